//! Construction of a [`Renderer`]: the checks before anything is allocated, then the scene
//! on the GPU and the passes the scene and settings ask for.

use super::*;

impl Renderer {
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        Self::new_with(ctx, scene, settings, None)
    }

    /// A renderer of both eyes of `rig` in one frame (`scene.camera` is the centre between
    /// the eyes): world-space passes run once, the G-buffer draws both eyes into two-layer
    /// images (one Vulkan multiview pass with `multiview`, else one pass per eye), and every
    /// screen-space pass runs per eye on its layer ([`stereo::multiview_blocker`] says which
    /// scenes and settings cannot; `multiview` needs the device feature).
    pub fn new_stereo(
        ctx: &Context,
        scene: &Scene,
        settings: RenderSettings,
        rig: crate::scene::StereoRig,
        multiview: bool,
    ) -> Result<Self, RenderError> {
        let path = match multiview {
            true => StereoPath::Multiview,
            false => StereoPath::OneFrame,
        };
        if let Some(why) = stereo::multiview_blocker(ctx, path, scene, &settings) {
            return Err(RenderError::MultiviewUnavailable(why));
        }
        Self::new_with(ctx, scene, settings, Some((rig, multiview)))
    }

    fn new_with(
        ctx: &Context,
        scene: &Scene,
        settings: RenderSettings,
        rig: Option<(crate::scene::StereoRig, bool)>,
    ) -> Result<Self, RenderError> {
        let (settings, auto_shadow) = match settings.shadow.auto_resolution {
            true => {
                let (s, pick) = shadow_texels::resolve_auto_resolution(ctx, scene, &settings)?;
                (s, Some(pick))
            }
            false => (settings, None),
        };
        check_render_settings(&settings)?;
        check_device_limits(&settings, ctx.info.max_image_dimension_2d)?;
        let lights = frame_lights(&scene.lights, &settings.shadow).len();
        if lights > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights));
        }
        if scene.objects.is_empty() {
            return Err(RenderError::EmptyScene);
        }
        // An error half-way (a voxel grid that does not fit, a debug level beyond the
        // hierarchy, …) drops what was made so far, which releases it.
        let mut r = Self::create(ctx, scene, &settings, rig)?;
        r.auto_shadow = auto_shadow;
        if r.pre_exposure.k != 0 {
            log::info!(
                "half-float radiance is stored pre-exposed by 2^{} (the scene's brightest \
                 source is outside 2^-14 to 2^14)",
                -r.pre_exposure.k
            );
        }
        for warning in crate::scene::pre_exposure::unrepresentable_emission(scene, r.pre_exposure) {
            log::warn!("{warning}");
        }
        r.prepare(scene)?;
        r.check_transient_memory(ctx)?;
        Ok(r)
    }

    /// Refuses a frame whose transients (G-buffer, radiance, indirect light, post chain:
    /// the graph's arenas, one set per frame in flight) cannot fit beside what is allocated
    /// now, before the executor allocates them.
    fn check_transient_memory(&self, ctx: &Context) -> Result<(), RenderError> {
        memory::check_fits(
            ctx,
            &frame_subject(&self.settings),
            FRAME_FLAGS,
            &self.transient_needs(ctx)?,
            ctx.allocated_bytes(),
        )
    }

    /// Refuses a `size` for this renderer's frame that cannot fit the device, before
    /// anything of that size is made (the viewer asks before it resizes to a window): the
    /// frame-sized resources a renderer of that size holds, its graph's transient arenas
    /// per frame in flight and `extra` (what the caller makes of that size, such as a
    /// window's swapchain images), together beside everything allocated now. That counts
    /// the present size's frame too, which a resize frees: near the limit it refuses a
    /// size that would just fit.
    pub fn check_frame_size(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        (width, height): (u32, u32),
        extra: &[memory::MemoryNeed],
    ) -> Result<(), RenderError> {
        let sized = RenderSettings {
            width,
            height,
            ..self.settings.clone()
        };
        let current = std::mem::replace(&mut self.settings, sized.clone());
        let transients = self.transient_needs(ctx);
        self.settings = current;
        let gi_on = sized.gi.method != crate::gi::GiMethod::None && sized.debug.is_none();
        let eyes = if self.stereo.is_some() { 2 } else { 1 };
        let mut needs = super::preflight::frame_memory_needs(ctx, scene, &sized, gi_on, eyes);
        needs.extend(transients?);
        needs.extend_from_slice(extra);
        memory::check_fits(
            ctx,
            &frame_subject(&sized),
            FRAME_FLAGS,
            &needs,
            ctx.allocated_bytes(),
        )
    }

    /// The graph's transient arenas (one set per frame in flight) and cached images at the
    /// renderer's settings.
    fn transient_needs(&self, ctx: &Context) -> Result<Vec<memory::MemoryNeed>, RenderError> {
        let graph = self.graph();
        let arenas = crate::graph::transient_arenas(ctx, &graph)?;
        let slots = crate::vk::MAX_FRAMES_IN_FLIGHT;
        // The cached shadow and light maps: once, shared by the slots.
        let cached = crate::graph::cached_image_sizes(ctx, &graph)?;
        let cached = cached.into_iter().map(|(name, bytes)| memory::MemoryNeed {
            name,
            bytes,
            is_buffer: false,
        });
        let needs: Vec<_> = (0..slots)
            .flat_map(|s| {
                arenas
                    .iter()
                    .enumerate()
                    .map(move |(i, a)| memory::MemoryNeed {
                        name: format!("graph arena {i} (slot {s})"),
                        bytes: a.size_bytes,
                        is_buffer: false,
                    })
            })
            .chain(cached)
            .collect();
        Ok(needs)
    }

    /// Creates the frame's resources and passes (see [`Renderer::new`]), in this order: the
    /// plan and its checks, the read-back buffers and the scene, the passes of the lit frame,
    /// the debug views, the voxels, indirect light, transparency (whose layers may trace the GI
    /// method's rays), and the voxel views.
    fn create(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        rig: Option<(crate::scene::StereoRig, bool)>,
    ) -> Result<Self, RenderError> {
        let plan = FramePlan::new(ctx, scene, settings, rig)?;
        let [hdr_desc, ldr_desc] = readback_descs((settings.width, settings.height));
        let readback_hdr = ctx.create_buffer(&hdr_desc)?;
        let readback_ldr = ctx.create_buffer(&ldr_desc)?;
        let mut scene_gpu = SceneGpu::new(ctx, scene, settings.time_s)?;
        if rig.is_some() {
            scene_gpu.enable_right_eye(ctx)?;
        }
        scene_gpu.split_transparent = plan.oit_on;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let lit = LitPasses::new(ctx, scene, settings, &plan, sampler.raw)?;
        scene_gpu.motion = lit.motion;
        let (gbuffer_view, shadow_texels) = debug_views(ctx, scene, settings, sampler.raw)?;
        let mut voxels = plan
            .voxel_settings
            .as_ref()
            .map(|v| crate::voxel::frame::VoxelFrame::new(ctx, scene, settings.time_s, v))
            .transpose()?;
        let gi = match plan.gi_on {
            true => Some(gi_passes(ctx, scene, settings, &plan, &mut voxels)?),
            false => None,
        };
        let oit = plan
            .oit_on
            .then(|| {
                let materials = (
                    plan.has_phong,
                    scene.has_ggx(),
                    scene.has_albedo_textures(),
                    scene.has_alpha_maps(),
                );
                // The GI method's rays from the transparent fragments, if it gives them any.
                let indirect = gi
                    .as_ref()
                    .and_then(|(gi, _)| gi.transparent_indirect(scene))
                    .map(|(params, kind)| {
                        let variant = oit::LayerVariant {
                            kind,
                            emission: scene.has_emission(),
                            environment: crate::scene::Environment::shader_kind(
                                scene.environment.as_ref(),
                            ),
                        };
                        (params, variant)
                    });
                let nodes = settings.oit_nodes_per_pixel;
                oit::OitPasses::new(ctx, materials, nodes, sampler.raw, indirect)
            })
            .transpose()?;
        let direct_emitters = match (plan.direct_light, voxels.as_ref()) {
            (Some(light), Some(v)) => Some(direct_emitters::DirectEmittersPass::new(
                ctx,
                light,
                &crate::gi::GiTarget {
                    scene,
                    eyes: plan.eyes,
                    time_s: settings.time_s,
                    grid: &v.voxels.grid,
                    shadow_resolution: settings.shadow.resolution,
                    size: (settings.width, settings.height),
                    has_phong: plan.has_phong,
                    motion: false,
                    temporal: false,
                    atlas_attributes: false,
                    cache: settings.shadow.cache,
                },
                &settings.gi,
                (settings.shadow.direct_samples, settings.post.taa.is_some()),
                sampler.raw,
            )?),
            _ => None,
        };
        let atlas_view = atlas_view(ctx, scene, settings)?;
        let voxel_debug = voxel_debug(ctx, scene, settings, &plan, &mut voxels)?;
        Ok(Renderer {
            settings: settings.clone(),
            scene: scene_gpu,
            readback_hdr,
            readback_ldr,
            shadow_depth: lit.shadow_depth,
            gbuffer: lit.gbuffer,
            deferred: lit.deferred,
            direct_emitters,
            tonemap: lit.tonemap,
            post: lit.post,
            has_phong: plan.has_phong,
            shadow_view_count: 0,
            cascade_view_capacity: 0,
            frame_data: GpuFrame::zeroed(),
            pre_exposure: crate::scene::PreExposure::of_scene(scene),
            prev_view_proj: None,
            voxels,
            gi,
            voxel_debug,
            atlas_view,
            gbuffer_view,
            oit,
            shadow_texels,
            auto_shadow: None,
            stereo: rig
                .map(|(rig, _)| {
                    stereo::OnePass::new(ctx, rig, settings, sampler.raw, scene.has_animation())
                })
                .transpose()?,
            sampler,
            moving: scene
                .objects
                .iter()
                .map(|o| o.dynamic || o.is_animated())
                .collect(),
        })
    }
}

/// What a frame needs, decided from the scene and settings before anything is created, and
/// checked to fit the device.
struct FramePlan {
    eyes: u32,
    views: gbuffer::GbufferViews,
    has_phong: bool,
    /// An indirect-light method is on (and no debug view replaces the lit image).
    gi_on: bool,
    /// The GI method reads voxels and light maps.
    gi_voxels: bool,
    /// A debug view shows the voxels.
    voxel_view_on: bool,
    /// The emitters' and the environment's direct light with voxel visibility
    /// (`direct_emitters::sampled_light`), in scenes with them where no GI method brings it.
    direct_light: Option<direct_emitters::SampledLight>,
    /// The voxelization, when a GI method, the sampled direct light or a debug view needs one.
    voxel_settings: Option<crate::voxel::gpu::VoxelSettings>,
    /// Transparent surfaces go to the linked lists instead of the G-buffer.
    oit_on: bool,
}

impl FramePlan {
    fn new(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        rig: Option<(crate::scene::StereoRig, bool)>,
    ) -> Result<Self, RenderError> {
        let eyes = if rig.is_some() { 2 } else { 1 };
        let views = match rig {
            None => gbuffer::GbufferViews::Mono,
            Some((_, false)) => gbuffer::GbufferViews::PerEye,
            Some((_, true)) => gbuffer::GbufferViews::Multiview,
        };
        // A debug view replaces the lit image, so nothing would read the indirect light (and
        // the albedo view declares the attribute passes the GI methods would declare again).
        let gi_on = settings.gi.method != crate::gi::GiMethod::None && settings.debug.is_none();
        // Screen-space GI reads only the frame: no voxels, no light maps.
        let gi_voxels = gi_on && settings.gi.method.needs_voxels();
        check_setting_combination(settings)?;
        check_projection(&scene.camera, settings, rig.is_some())?;
        let voxel_view_on = settings.debug.is_some_and(|d| d.view.shows_voxels());
        // A debug view replaces the lit image: no direct light to add to.
        let direct_light = match settings.debug {
            None => direct_emitters::sampled_light(settings.gi.method, scene),
            Some(_) => None,
        };
        // What needs voxels and the frame names no voxel settings gets the scene's `[voxel]`.
        let voxel_settings = settings
            .voxels
            .or(needs_voxels(settings, scene).then(|| scene.voxel_settings()));
        if let Some(v) = &voxel_settings {
            check_voxel_memory(ctx, scene, settings, v)?;
        }
        check_frame_memory(ctx, scene, settings, gi_on, eyes)?;
        // A debug view shows the G-buffer, so it keeps the transparent surfaces' hashed
        // coverage.
        let oit_on = settings.transparency == crate::scene::Transparency::Oit
            && scene.has_transparency()
            && settings.debug.is_none();
        Ok(Self {
            eyes,
            views,
            has_phong: scene.has_phong(),
            gi_on,
            gi_voxels,
            direct_light,
            voxel_view_on,
            voxel_settings,
            oit_on,
        })
    }
}

/// The passes of the lit frame: shadow maps, G-buffer, direct light, tone mapping and
/// post-processing.
struct LitPasses {
    shadow_depth: ShadowDepthPass,
    gbuffer: GbufferPass,
    deferred: DeferredDirectPass,
    tonemap: TonemapPass,
    post: crate::post::PostPasses,
    /// The G-buffer writes motion vectors.
    motion: bool,
}

impl LitPasses {
    fn new(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        plan: &FramePlan,
        sampler: vk::Sampler,
    ) -> Result<Self, RenderError> {
        // Paraboloid maps write their depth per fragment, which costs the other maps their
        // early depth test: only scenes that have them pay for it.
        let paraboloid = (settings.shadow.point_technique == PointShadow::DualParaboloid
            && scene
                .lights
                .iter()
                .any(|l| matches!(l, Light::Point { .. })))
            || scene.lights.iter().any(Light::is_area);
        let shadow_depth = ShadowDepthPass::new(
            ctx,
            paraboloid,
            scene.has_transparency(),
            scene.has_alpha_maps(),
            settings.shadow.cache,
        )?;
        let features = GbufferFeatures {
            phong: plan.has_phong,
            ggx: scene.has_ggx(),
            emission: scene.has_emission(),
            textures: scene.has_albedo_textures(),
            bump: scene.has_bump_maps(),
            dissolve: scene.has_transparency() && !plan.oit_on,
            pbr_maps: scene.has_pbr_maps(),
            motion: motion_vectors(scene, settings),
            alpha_maps: scene.has_alpha_maps(),
        };
        let gbuffer = GbufferPass::new(ctx, features, plan.views)?;
        let deferred = DeferredDirectPass::new(
            ctx,
            (features.phong, features.ggx, features.emission),
            crate::scene::Environment::shader_kind(scene.environment.as_ref()),
            sampler,
        )?;
        let tonemap = TonemapPass::new(ctx, sampler)?;
        // A debug view replaces the lit image: no post passes, and no TAA jitter.
        let post = match settings.debug {
            None => crate::post::PostPasses::new(
                ctx,
                &settings.post,
                (settings.width, settings.height),
                sampler,
                scene.has_animation(),
            )?,
            Some(_) => crate::post::PostPasses::default(),
        };
        Ok(Self {
            shadow_depth,
            gbuffer,
            deferred,
            tonemap,
            post,
            motion: features.motion,
        })
    }
}

/// The debug views of the G-buffer and of the shadow maps' texel density, when
/// `settings.debug` asks for one.
#[allow(clippy::type_complexity)]
/// Whether a renderer of `settings` for `scene` voxelizes the scene when `settings.voxels`
/// does not ask it to: a voxel GI method, the emitters' or the environment's direct light
/// with voxel visibility (what the method does not bring itself), or a voxel debug view.
pub fn needs_voxels(settings: &RenderSettings, scene: &Scene) -> bool {
    // A debug view replaces the lit image: neither the indirect nor the direct light is made.
    let lit = settings.debug.is_none();
    let gi_voxels = lit && settings.gi.method.needs_voxels();
    let direct_light = lit && direct_emitters::sampled_light(settings.gi.method, scene).is_some();
    gi_voxels || direct_light || settings.debug.is_some_and(|d| d.view.shows_voxels())
}

fn debug_views(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    sampler: vk::Sampler,
) -> Result<
    (
        Option<gbuffer_view::GbufferViewPass>,
        Option<shadow_texels::ShadowTexelsPass>,
    ),
    RenderError,
> {
    let mut gbuffer_view = None;
    if let Some(channel) = settings.debug.and_then(|d| gbuffer_view::channel(d.view)) {
        // The distance view draws the farthest point of the scene's box black.
        let b = scene.aabb_at(settings.time_s);
        let far_m =
            scene.camera.position.distance((b.min + b.max) * 0.5) + 0.5 * (b.max - b.min).length();
        gbuffer_view = Some(gbuffer_view::GbufferViewPass::new(
            ctx, sampler, channel, far_m,
        )?);
    }
    let shadow_texels = settings
        .debug
        .and_then(|d| match d.view {
            crate::voxel::debug_view::DebugView::ShadowTexels => Some(true),
            crate::voxel::debug_view::DebugView::ShadowTexelsPerspective => Some(false),
            _ => None,
        })
        .map(|projective| {
            shadow_texels::ShadowTexelsPass::new(
                ctx,
                sampler,
                &scene.camera,
                settings.height,
                projective,
            )
        })
        .transpose()?;
    Ok((gbuffer_view, shadow_texels))
}

/// The indirect-light passes and, for the methods that read them, the light-map pass.
fn gi_passes(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    plan: &FramePlan,
    voxels: &mut Option<crate::voxel::frame::VoxelFrame>,
) -> Result<(crate::gi::GiPasses, Option<LightMapPass>), RenderError> {
    // With the atlas voxelizer its points write the volumes (Thiedemann 2010, §4.3.2).
    let atlas_attributes = match voxels.as_mut() {
        Some(v) => {
            crate::gi::GiPasses::needs_attribute_volumes(&settings.gi, scene)
                && v.enable_attribute_volumes(
                    ctx,
                    scene,
                    crate::gi::GiPasses::value_volumes(&settings.gi, scene),
                )?
        }
        None => false,
    };
    // Screen-space GI has no voxels; its push constants still describe the grid the voxel
    // methods would use (computed on the CPU, nothing allocated).
    let cpu_grid;
    let grid = match voxels.as_ref() {
        Some(v) => &v.voxels.grid,
        None => {
            cpu_grid = scene
                .voxel_settings()
                .grid_for(scene, settings.time_s)
                .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
            &cpu_grid
        }
    };
    let passes = crate::gi::GiPasses::new(
        ctx,
        settings.gi,
        &crate::gi::GiTarget {
            scene,
            eyes: plan.eyes,
            time_s: settings.time_s,
            grid,
            shadow_resolution: settings.shadow.resolution,
            size: (settings.width, settings.height),
            has_phong: plan.has_phong,
            motion: motion_vectors(scene, settings),
            temporal: crate::gi::GiPasses::temporal_on(&settings.gi),
            atlas_attributes,
            cache: settings.shadow.cache,
        },
    )?;
    let light_map = plan
        .gi_voxels
        .then(|| {
            LightMapPass::new(
                ctx,
                scene.has_transparency(),
                scene.has_ggx(),
                settings.gi.method.spec().reads_area_light_maps,
                (
                    LightMapPass::scene_has_maps(scene),
                    scene.has_alpha_maps(),
                    settings.shadow.cache,
                ),
            )
        })
        .transpose()?;
    Ok((passes, light_map))
}

/// The atlas debug view, which needs only the grid's voxel size, not a voxelization.
fn atlas_view(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
) -> Result<Option<crate::voxel::atlas_view::AtlasViewPass>, RenderError> {
    let Some(d) = settings
        .debug
        .filter(|d| d.view == crate::voxel::debug_view::DebugView::Atlas)
    else {
        return Ok(None);
    };
    let grid = settings
        .voxels
        .unwrap_or_else(|| scene.voxel_settings())
        .grid_for(scene, settings.time_s)
        .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
    Ok(Some(crate::voxel::atlas_view::AtlasViewPass::new(
        ctx,
        scene,
        settings.time_s,
        &grid,
        d.object,
    )?))
}

/// The debug view of the voxels, when one is asked for.
fn voxel_debug(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    plan: &FramePlan,
    voxels: &mut Option<crate::voxel::frame::VoxelFrame>,
) -> Result<Option<crate::voxel::debug_view::VoxelDebugPass>, RenderError> {
    let (Some(d), Some(v)) = (&settings.debug, voxels.as_mut()) else {
        return Ok(None);
    };
    if !plan.voxel_view_on {
        return Ok(None);
    }
    // With the atlas voxelizer its points write the albedo the view shows.
    if d.view == crate::voxel::debug_view::DebugView::Albedo {
        v.enable_attribute_volumes(
            ctx,
            scene,
            crate::voxel::attributes::ValueVolumes::albedo_only(scene),
        )?;
    }
    Ok(Some(crate::voxel::debug_view::VoxelDebugPass::new(
        ctx,
        scene,
        settings.time_s,
        settings.width as f32 / settings.height as f32,
        d,
        v,
    )?))
}

/// Whether the G-buffer writes motion vectors: for moving objects under TAA or temporal GI
/// accumulation (a debug view has neither).
fn motion_vectors(scene: &Scene, settings: &RenderSettings) -> bool {
    let moving = scene.has_animation();
    settings.debug.is_none()
        && (settings.post.motion_vectors(moving)
            || (moving && crate::gi::GiPasses::temporal_on(&settings.gi)))
}
