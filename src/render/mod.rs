//! The frame of voxgi: shadow maps → G-buffer → deferred direct light → (indirect light) →
//! tone mapping, with read-back of the linear HDR radiance and the tone-mapped image.
//!
//! Each pass lives in the file named after its shader (`shadow_depth.rs` for
//! `glsl/shadow_depth.*`, …) with its pipeline, push constants and declaration; [`Renderer`]
//! owns them and the scene on the GPU ([`SceneGpu`]) and assembles the frame in
//! [`Renderer::declare`]. [`render_image`] and [`profile_scene`] run frames headless.

mod deferred_direct;
mod gbuffer;
mod gbuffer_view;
pub mod gpu;
mod light_map;
pub mod memory;
mod multiview;
mod oit;
mod oit_clear;
mod oit_gather;
mod oit_resolve;
mod run;
mod scene_gpu;
mod settings_check;
mod shadow_depth;
pub mod shadow_texels;
mod stereo;
mod textures;

pub use gbuffer::Gbuffer;
pub use light_map::LightMaps;
pub use multiview::{MesaVersion, MultiviewDefect, RIGHT_EYE_SUFFIX};
pub use oit::{OitStats, DEFAULT_NODES_PER_PIXEL as OIT_DEFAULT_NODES_PER_PIXEL};
pub use oit_resolve::MAX_LAYERS as OIT_MAX_LAYERS;
pub use run::{
    frames_to_image, profile_camera_path, profile_scene, render_animation, render_image,
    render_sequence, ProfileRun, RenderOutput, SequenceOutput,
};
pub use scene_gpu::{Draw, DrawLists, SceneGpu, SceneInputs};
pub use settings_check::{check_device_limits, check_render_settings};
pub use stereo::{
    declare_pair as declare_stereo_pair, default_convergence_m,
    default_path as default_stereo_path, eye_scene, multiview_blocker, pack as stereo_pack,
    prepare_pair as prepare_stereo_pair, profile_stereo, render_stereo, StereoOutput, StereoPath,
    StereoProfile, StereoRenderers, StereoSettings, PROFILE_ROUND_FRAMES,
};

use crate::eval::HdrImage;
use crate::graph::{Access, GraphError, ImageHandle, RenderGraph};
use crate::light::{area::frame_lights, shadow_views, PointShadow, ShadowSettings};
use crate::post::{ToneMap, TonemapPass};
use crate::scene::{Light, Scene};
use crate::vk::{
    vk, Buffer, BufferDesc, Context, ImageDesc, MemoryLocation, PassTiming, Sampler, VkError,
};
use bytemuck::Zeroable;
use deferred_direct::DeferredDirectPass;
use gbuffer::{GbufferFeatures, GbufferPass};
use glam::Vec3;
use gpu::*;
use light_map::LightMapPass;
use shadow_depth::ShadowDepthPass;

const GBUFFER_COLOR: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
const HDR: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Errors of building or running a frame.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error("the scene has {0} lights (each area light counts its samples); voxgi renders at most {MAX_LIGHTS}: remove some or lower --area-samples / the lights' `samples`")]
    TooManyLights(usize),
    #[error("the scene's lights need {0} shadow-map views; at most {MAX_SHADOW_VIEWS} fit (a point light takes 6, or 2 with paraboloid shadows, an area light 1 per sample, a directional light 1 plus its cascades): remove some point lights, use --point-shadows paraboloid, lower --area-samples / the lights' `samples` or --shadow-cascades")]
    TooManyShadowViews(usize),
    /// A settings value out of its range ([`crate::limits`]), named by its flag.
    #[error(transparent)]
    Settings(#[from] crate::limits::LimitError),
    #[error("the scene has no geometry to render: add an object")]
    EmptyScene,
    #[error("SAO (--sao, or `sao = true` in the scene's [gi] table) darkens only indirect light, and --gi none has none: choose a --gi method (hemisphere, pathtrace, vpl, ssgi) or leave out --sao (--sao off turns the scene's off)")]
    SaoWithoutGi,
    #[error(transparent)]
    Voxel(#[from] crate::voxel::gpu::GpuVoxelError),
    /// A frame size or voxel grid that does not fit the device, found before allocating.
    #[error(transparent)]
    OutOfDeviceMemory(memory::MemoryError),
    /// A one-frame stereo renderer was asked for where it cannot run (the reason).
    #[error("one-frame stereo cannot render this: {0}; use --stereo-path two-pass")]
    MultiviewUnavailable(String),
    /// An orthographic camera (`--projection orthographic`, the scene's `[camera]
    /// projection`, the viewer's toggle) with a feature built for a pinhole camera.
    #[error("{what} cannot render with an orthographic camera: {why}. Use --projection perspective (or `projection = \"perspective\"` in the scene's [camera] table), or {instead}")]
    Orthographic {
        what: &'static str,
        why: &'static str,
        instead: &'static str,
    },
}

/// Refuses what an orthographic camera cannot render: screen-space GI, whose patch areas
/// (Oetke 2017, Eq. 2.10: z² times a pinhole's texel solid angle), reflection march (linear in
/// 1/w) and history (clip w as depth) assume a pinhole camera, and stereo pairs, whose
/// off-axis frusta are a perspective concept.
/// `Renderer::new` and every `prepare` run it (the viewer switches projection per frame).
pub fn check_projection(
    camera: &crate::scene::Camera,
    settings: &RenderSettings,
    stereo: bool,
) -> Result<(), RenderError> {
    if !camera.is_orthographic() {
        return Ok(());
    }
    if stereo {
        return Err(RenderError::Orthographic {
            what: "--stereo",
            why: "a stereo pair's eyes are off-axis perspective frusta",
            instead: "leave out --stereo",
        });
    }
    if let Some(r) = settings.gi.method.spec().orthographic_blocker {
        if settings.debug.is_none() {
            return Err(RenderError::Orthographic {
                what: r.what,
                why: r.why,
                instead: r.instead,
            });
        }
    }
    Ok(())
}

/// Refuses a voxel grid that cannot fit the device, before anything is allocated: its column
/// image (all mips) and the column buffer of its mip 0.
fn check_voxel_memory(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    voxels: &crate::voxel::gpu::VoxelSettings,
) -> Result<(), RenderError> {
    let grid = voxels
        .grid_for(scene, settings.time_s)
        .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
    let image = crate::voxel::gpu::column_image_desc(&grid);
    let buffer = BufferDesc {
        name: "voxel column buffer".into(),
        size_bytes: crate::voxel::gpu::column_bytes(&grid),
        usage: vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuOnly,
    };
    memory::check_fits(
        ctx,
        &format!(
            "the voxel grid of {}×{} columns × {} layer(s)",
            grid.res_x(),
            grid.res_y(),
            grid.layers()
        ),
        "--voxels or --voxel-layers",
        &[
            memory::MemoryNeed::image(ctx, &image),
            memory::MemoryNeed::buffer(ctx, &buffer),
        ],
        ctx.allocated_bytes(),
    )
}

/// The read-back buffers of a `w`×`h` frame: linear RGBA32F radiance and RGBA8 LDR.
fn readback_descs((w, h): (u32, u32)) -> [BufferDesc; 2] {
    let pixels = u64::from(w) * u64::from(h);
    let desc = |name: &str, bytes_per_pixel: u64| BufferDesc {
        name: name.into(),
        size_bytes: pixels * bytes_per_pixel,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    };
    [desc("readback hdr", 16), desc("readback ldr", 4)]
}

/// What sizes a frame, for memory errors.
fn frame_subject(s: &RenderSettings) -> String {
    format!("the {}×{} frame", s.width, s.height)
}
const FRAME_FLAGS: &str = "--width/--height";

/// Refuses a frame whose persistent frame-sized resources (read-back buffers, the TAA, path
/// tracer and SSGI histories) cannot fit the device, before anything is allocated. The
/// transients are checked by [`check_transient_memory`] once the passes exist.
fn check_frame_memory(
    ctx: &Context,
    scene: &Scene,
    s: &RenderSettings,
    gi_on: bool,
    eyes: u32,
) -> Result<(), RenderError> {
    let size = (s.width, s.height);
    let mut needs: Vec<_> = readback_descs(size)
        .iter()
        .map(|d| memory::MemoryNeed::buffer(ctx, d))
        .collect();
    let mut images = Vec::new();
    for _ in 0..eyes.max(1) {
        per_eye_frame_images(scene, s, gi_on, &mut images);
    }
    if eyes > 1 {
        needs.extend(needs.clone());
    }
    needs.extend(images.iter().map(|d| memory::MemoryNeed::image(ctx, d)));
    memory::check_fits(
        ctx,
        &frame_subject(s),
        FRAME_FLAGS,
        &needs,
        ctx.allocated_bytes(),
    )
}

/// The persistent frame-sized images of one eye (TAA, path tracer and SSGI histories).
fn per_eye_frame_images(
    scene: &Scene,
    s: &RenderSettings,
    gi_on: bool,
    images: &mut Vec<ImageDesc>,
) {
    let size = (s.width, s.height);
    if s.debug.is_none() && s.post.taa.is_some() {
        images.push(crate::post::TaaPass::history_desc(size));
    }
    if gi_on {
        let glossy = scene.has_phong() || scene.has_ggx();
        images.extend(crate::gi::GiPasses::frame_image_descs(&s.gi, size, glossy));
    }
}

/// Whether `settings` combine at all, independent of scene and device: the combination a
/// renderer refuses (SAO without GI; every GI method renders with paraboloid point
/// shadows and with area lights). [`Renderer::new`] runs it first; `voxgi sweep` asks it to
/// leave such configurations out instead of failing on them.
pub fn check_setting_combination(settings: &RenderSettings) -> Result<(), RenderError> {
    use crate::gi::GiMethod;
    let gi_on = settings.gi.method != GiMethod::None && settings.debug.is_none();
    if !gi_on && settings.gi.sao.is_some() {
        return Err(RenderError::SaoWithoutGi);
    }
    Ok(())
}

/// Refuses lights a frame cannot hold: more than [`MAX_LIGHTS`] (an area light counts its
/// samples) or more than [`MAX_SHADOW_VIEWS`] shadow views with the directional lights'
/// cascades, the checks of [`Renderer::new`] and [`Renderer::prepare`]. The viewer's editor
/// asks before it adds a light.
pub fn check_lights(scene: &Scene, settings: &RenderSettings) -> Result<(), RenderError> {
    let lights = frame_lights(&scene.lights, &settings.shadow);
    if lights.len() > MAX_LIGHTS {
        return Err(RenderError::TooManyLights(lights.len()));
    }
    let (views, _) = shadow_views(scene, settings.time_s, &settings.shadow);
    let capacity = match settings.shadow.cascades {
        n if n >= 2 => n as usize * lights.iter().filter(|l| l.is_directional()).count(),
        _ => 0,
    };
    if views.len() + capacity > MAX_SHADOW_VIEWS {
        return Err(RenderError::TooManyShadowViews(views.len() + capacity));
    }
    Ok(())
}

/// What a frame renders.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Scene time (animation), seconds.
    pub time_s: f32,
    pub shadow: ShadowSettings,
    pub tonemap: ToneMap,
    /// Voxelize the scene every frame (`None`: direct light needs no voxels). Indirect light
    /// voxelizes with default settings when this is `None`.
    pub voxels: Option<crate::voxel::gpu::VoxelSettings>,
    /// Indirect light (method `None`: direct light only).
    pub gi: crate::gi::GiSettings,
    /// Show a voxel debug view instead of the lit image (voxelizes with the default
    /// [`crate::voxel::gpu::VoxelSettings`] when `voxels` is `None`).
    pub debug: Option<crate::voxel::debug_view::DebugSettings>,
    /// Post-processing around tone mapping (TAA, …); off by default.
    pub post: crate::post::PostSettings,
    /// How the camera view draws surfaces with d < 1 (only in scenes that have them).
    pub transparency: crate::scene::Transparency,
    /// Capacity of the transparency node buffer, in nodes per pixel on average
    /// ([`crate::limits::OIT_NODES_PER_PIXEL`]).
    pub oit_nodes_per_pixel: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            time_s: 0.0,
            shadow: ShadowSettings::default(),
            tonemap: ToneMap::default(),
            voxels: None,
            gi: crate::gi::GiSettings::default(),
            debug: None,
            post: Default::default(),
            transparency: Default::default(),
            oit_nodes_per_pixel: oit::DEFAULT_NODES_PER_PIXEL,
        }
    }
}

/// The images a declared frame produces.
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    /// Linear radiance, RGBA32F.
    pub radiance: ImageHandle,
    /// Tone-mapped, sRGB-encoded values in RGBA8 UNORM.
    pub ldr: ImageHandle,
}

/// A scene on the GPU with the passes of its frame.
pub struct Renderer {
    pub settings: RenderSettings,
    scene: SceneGpu,
    readback_hdr: Buffer,
    readback_ldr: Buffer,
    /// Nearest-neighbour sampler of the G-buffer, shadow maps and radiance. Held to keep it
    /// alive: the passes were given its raw handle.
    #[allow(dead_code)]
    sampler: Sampler,
    shadow_depth: ShadowDepthPass,
    gbuffer: GbufferPass,
    deferred: DeferredDirectPass,
    tonemap: TonemapPass,
    post: crate::post::PostPasses,
    has_phong: bool,
    /// The lights' own shadow views (the light maps have one layer each).
    shadow_view_count: u32,
    /// Shadow-array layers kept for the directional lights' cascades, after the lights' own
    /// views: the cascade count × the directional lights (a frame may use fewer).
    cascade_view_capacity: u32,
    frame_data: GpuFrame,
    /// The scene's pre-exposure of half-float radiance, fixed when the renderer is made (the
    /// voxelizers scale their emission with the same one).
    pre_exposure: crate::scene::PreExposure,
    /// The un-jittered view-projection of the last frame written (motion vectors only).
    prev_view_proj: Option<glam::Mat4>,
    voxels: Option<crate::voxel::frame::VoxelFrame>,
    /// Indirect-light passes and the light-map pass (for the voxel methods), when a GI method
    /// is on.
    gi: Option<(crate::gi::GiPasses, Option<LightMapPass>)>,
    voxel_debug: Option<crate::voxel::debug_view::VoxelDebugPass>,
    atlas_view: Option<crate::voxel::atlas_view::AtlasViewPass>,
    gbuffer_view: Option<gbuffer_view::GbufferViewPass>,
    /// The transparency lists, in scenes with d < 1 materials and `--transparency oit`.
    oit: Option<oit::OitPasses>,
    shadow_texels: Option<shadow_texels::ShadowTexelsPass>,
    /// What `--shadow-resolution auto` picked, when it was asked for.
    auto_shadow: Option<shadow_texels::AutoShadowResolution>,
    /// One-pass stereo: both eyes in one frame (`render/stereo.rs`); `frame_data`,
    /// `readback_*` and `post` are then the left eye's.
    stereo: Option<stereo::OnePass>,
    /// Per object, whether it was dynamic (or animated) when the renderer was made: only
    /// those move in the voxels.
    moving: Vec<bool>,
}

/// What a frame's eyes share: declared by the first eye's passes, reused by the second.
#[derive(Default)]
struct SharedByEyes {
    light_maps: Option<LightMaps>,
    gi: Option<crate::gi::GiWorld>,
}

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
        memory::check_fits(
            ctx,
            &frame_subject(&self.settings),
            FRAME_FLAGS,
            &needs,
            ctx.allocated_bytes(),
        )
    }

    /// Creates the frame's resources and passes (see [`Renderer::new`]).
    fn create(
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
        let has_phong = scene.has_phong();
        // A debug view replaces the lit image, so nothing would read the indirect light (and
        // the albedo view declares the attribute passes the GI methods would declare again).
        let gi_on = settings.gi.method != crate::gi::GiMethod::None && settings.debug.is_none();
        // Screen-space GI reads only the frame: no voxels, no light maps.
        let gi_voxels = gi_on && settings.gi.method.needs_voxels();
        check_setting_combination(settings)?;
        check_projection(&scene.camera, settings, rig.is_some())?;
        let voxel_view_on = settings.debug.is_some_and(|d| d.view.shows_voxels());
        let voxel_settings = settings
            .voxels
            .or(gi_voxels.then(Default::default))
            .or(voxel_view_on.then(Default::default));
        if let Some(v) = &voxel_settings {
            check_voxel_memory(ctx, scene, settings, v)?;
        }
        check_frame_memory(ctx, scene, settings, gi_on, eyes)?;
        let [hdr_desc, ldr_desc] = readback_descs((settings.width, settings.height));
        let readback_hdr = ctx.create_buffer(&hdr_desc)?;
        let readback_ldr = ctx.create_buffer(&ldr_desc)?;
        let mut scene_gpu = SceneGpu::new(ctx, scene, settings.time_s)?;
        if rig.is_some() {
            scene_gpu.enable_right_eye(ctx)?;
        }
        // Transparent surfaces go to the linked lists instead of the G-buffer (a debug view
        // shows the G-buffer, so it keeps their hashed coverage).
        let oit_on = settings.transparency == crate::scene::Transparency::Oit
            && scene.has_transparency()
            && settings.debug.is_none();
        scene_gpu.split_transparent = oit_on;
        // Paraboloid maps write their depth per fragment, which costs the other maps their
        // early depth test: only scenes that have them pay for it.
        let paraboloid = (settings.shadow.point_technique == PointShadow::DualParaboloid
            && scene
                .lights
                .iter()
                .any(|l| matches!(l, Light::Point { .. })))
            || scene.lights.iter().any(Light::is_area);
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let sampler_raw = sampler.raw;
        let shadow_depth = ShadowDepthPass::new(
            ctx,
            paraboloid,
            scene.has_transparency(),
            scene.has_alpha_maps(),
            settings.shadow.cache,
        )?;
        let features = GbufferFeatures {
            phong: has_phong,
            ggx: scene.has_ggx(),
            emission: scene.has_emission(),
            textures: scene.has_albedo_textures(),
            bump: scene.has_bump_maps(),
            dissolve: scene.has_transparency() && !oit_on,
            pbr_maps: scene.has_pbr_maps(),
            // Moving objects under TAA (a debug view has no TAA).
            motion: settings.debug.is_none() && settings.post.motion_vectors(scene.has_animation()),
            alpha_maps: scene.has_alpha_maps(),
        };
        scene_gpu.motion = features.motion;
        let gbuffer = GbufferPass::new(ctx, features, views)?;
        let deferred = DeferredDirectPass::new(
            ctx,
            (features.phong, features.ggx, features.emission),
            crate::scene::Environment::shader_kind(scene.environment.as_ref()),
            sampler.raw,
        )?;
        let oit = oit_on
            .then(|| {
                let materials = (
                    features.phong,
                    features.ggx,
                    features.textures,
                    features.alpha_maps,
                );
                oit::OitPasses::new(ctx, materials, settings.oit_nodes_per_pixel, sampler.raw)
            })
            .transpose()?;
        let tonemap = TonemapPass::new(ctx, sampler.raw)?;
        // A debug view replaces the lit image: no post passes, and no TAA jitter.
        let post = match settings.debug {
            None => crate::post::PostPasses::new(
                ctx,
                &settings.post,
                (settings.width, settings.height),
                sampler.raw,
                scene.has_animation(),
            )?,
            Some(_) => crate::post::PostPasses::default(),
        };
        // The atlas view only needs the grid's voxel size, not a voxelization; the G-buffer
        // views not even that.
        let atlas_view_on = settings
            .debug
            .is_some_and(|d| d.view == crate::voxel::debug_view::DebugView::Atlas);
        let mut gbuffer_view = None;
        if let Some(channel) = settings.debug.and_then(|d| gbuffer_view::channel(d.view)) {
            // The distance view draws the farthest point of the scene's box black.
            let b = scene.aabb_at(settings.time_s);
            let far_m = scene.camera.position.distance((b.min + b.max) * 0.5)
                + 0.5 * (b.max - b.min).length();
            gbuffer_view = Some(gbuffer_view::GbufferViewPass::new(
                ctx,
                sampler.raw,
                channel,
                far_m,
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
                    sampler.raw,
                    &scene.camera,
                    settings.height,
                    projective,
                )
            })
            .transpose()?;
        let mut voxels = None;
        if let Some(v) = &voxel_settings {
            voxels = Some(crate::voxel::frame::VoxelFrame::new(
                ctx,
                scene,
                settings.time_s,
                v,
            )?);
        }
        let mut gi = None;
        if gi_on {
            // With the atlas voxelizer its points write the volumes (Thiedemann 2010, §4.3.2).
            let atlas_attributes = match &mut voxels {
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
            // Screen-space GI has no voxels; its push constants still describe the grid the
            // voxel methods would use (computed on the CPU, nothing allocated).
            let cpu_grid;
            let grid = match &voxels {
                Some(v) => &v.voxels.grid,
                None => {
                    cpu_grid = crate::voxel::gpu::VoxelSettings::default()
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
                    eyes,
                    time_s: settings.time_s,
                    grid,
                    shadow_resolution: settings.shadow.resolution,
                    size: (settings.width, settings.height),
                    has_phong,
                    atlas_attributes,
                },
            )?;
            let light_map = gi_voxels
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
            gi = Some((passes, light_map));
        }
        let mut atlas_view = None;
        if let Some(d) = settings.debug.filter(|_| atlas_view_on) {
            let grid = settings
                .voxels
                .unwrap_or_default()
                .grid_for(scene, settings.time_s)
                .map_err(crate::voxel::gpu::GpuVoxelError::from)?;
            atlas_view = Some(crate::voxel::atlas_view::AtlasViewPass::new(
                ctx,
                scene,
                settings.time_s,
                &grid,
                d.object,
            )?);
        }
        let mut voxel_debug = None;
        if let (Some(d), Some(v)) = (&settings.debug, &mut voxels) {
            if voxel_view_on {
                // With the atlas voxelizer its points write the albedo the view shows.
                if d.view == crate::voxel::debug_view::DebugView::Albedo {
                    v.enable_attribute_volumes(
                        ctx,
                        scene,
                        crate::voxel::attributes::ValueVolumes::albedo_only(scene),
                    )?;
                }
                voxel_debug = Some(crate::voxel::debug_view::VoxelDebugPass::new(
                    ctx,
                    scene,
                    settings.time_s,
                    settings.width as f32 / settings.height as f32,
                    d,
                    v,
                )?);
            }
        }
        Ok(Renderer {
            settings: settings.clone(),
            scene: scene_gpu,
            readback_hdr,
            readback_ldr,
            sampler,
            shadow_depth,
            gbuffer,
            deferred,
            tonemap,
            post,
            has_phong,
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
                    stereo::OnePass::new(ctx, rig, settings, sampler_raw, scene.has_animation())
                })
                .transpose()?,
            moving: scene
                .objects
                .iter()
                .map(|o| o.dynamic || o.is_animated())
                .collect(),
        })
    }

    /// What `--shadow-resolution auto` picked for this renderer (`None`: a fixed resolution).
    pub fn auto_shadow_resolution(&self) -> Option<shadow_texels::AutoShadowResolution> {
        self.auto_shadow
    }

    /// Whether moving object `object` (changing its transform in the scene given to
    /// [`Self::prepare`]) is drawn and voxelized where it goes: it was dynamic when the
    /// renderer was made, or nothing of the renderer depends on where static objects are
    /// (no voxels). Otherwise the object must be marked dynamic and a new renderer made (the
    /// static grid holds it where it was).
    pub fn can_move(&self, object: usize) -> bool {
        self.voxels.is_none() || self.moving.get(object).copied().unwrap_or(false)
    }

    /// Computes frame constants, shadow views and culled draw lists for the scene's camera and
    /// lights and `settings`. Call again after changing them (the viewer does, every frame);
    /// a new size, shadow resolution, cascade count or tone map also needs a new graph.
    /// Dynamic objects are drawn, and re-voxelized by [`Self::write_frame`], at their
    /// transform in `scene` (the viewer's editor moves them).
    ///
    /// A one-frame stereo renderer takes `scene.camera` as the centre between its eyes.
    pub fn prepare(&mut self, scene: &Scene) -> Result<(), RenderError> {
        check_projection(&scene.camera, &self.settings, self.stereo.is_some())?;
        let s = self.settings.clone();
        if let Some(v) = &mut self.voxels {
            v.follow_objects(scene);
        }
        if let Some((gi, _)) = &mut self.gi {
            gi.follow_objects(scene);
        }
        if let Some(pass) = &mut self.voxel_debug {
            pass.follow_objects(scene);
        }
        let eyes = self.stereo.as_ref().map(|st| {
            let eye = |e| scene.camera.eye(st.rig, e);
            (eye(crate::scene::Eye::Left), eye(crate::scene::Eye::Right))
        });
        // The camera of `frame_data`: the left eye's in a stereo frame.
        let camera = eyes.map_or(scene.camera, |(left, _)| left);
        let (mut views, per_light) = shadow_views(scene, s.time_s, &s.shadow);
        let lights = frame_lights(&scene.lights, &s.shadow);
        let aspect = s.width as f32 / s.height as f32;
        // The directional lights' cascades follow every light's own views (the light maps
        // draw only those): GpuLight::info.w = first cascade view | cascade count << 16.
        let base_views = views.len();
        let mut cascades_of = vec![0u32; lights.len()];
        let cascade_sets = crate::light::cascade::cascade_views(
            &lights,
            &camera,
            aspect,
            &scene.aabb_at(s.time_s),
            &s.shadow,
            |li| views[per_light[li].first as usize].texel_footprint,
        );
        for (li, set) in cascade_sets {
            cascades_of[li] = views.len() as u32 | (set.len() as u32) << 16;
            views.extend(set);
        }
        // The graph's shadow array holds every cascade the settings allow, so that a camera
        // whose far cascades are dropped (no finer than the whole-scene map) and later come
        // back needs no new graph.
        let capacity = match s.shadow.cascades {
            n if n >= 2 => n as usize * lights.iter().filter(|l| l.is_directional()).count(),
            _ => 0,
        };
        if base_views + capacity > MAX_SHADOW_VIEWS {
            return Err(RenderError::TooManyShadowViews(base_views + capacity));
        }
        let view_proj = camera.view_proj(aspect);
        let mut f = GpuFrame::zeroed();
        set_frame_camera(&mut f, &camera, aspect);
        f.environment = crate::scene::Environment::frame_constants(scene.environment.as_ref());
        f.radiance_scale = self.pre_exposure.frame_constants();
        f.counts = [lights.len() as u32, views.len() as u32, s.width, s.height];
        f.shadow = [
            s.shadow.bias_texels,
            s.shadow.slope_bias_texels,
            s.shadow.normal_offset_texels,
            s.shadow.pcf_radius as f32,
        ];
        for (i, light) in lights.iter().enumerate() {
            f.lights[i] = gpu_light(light, per_light[i].first, per_light[i].count);
            f.lights[i].info[3] = cascades_of[i];
        }
        for (i, v) in views.iter().enumerate() {
            f.shadow_views[i] = GpuShadowView {
                view_proj: v.view_proj.to_cols_array(),
                params: [v.texel_footprint, v.projection.gpu_code(), v.near, v.far],
                axis: v.axis.extend(v.split_far_m).to_array(),
            };
        }
        // The right eye: the same constants seen from its camera.
        let mut right_changed = false;
        let mut view_projs = vec![view_proj];
        if let (Some(st), Some((_, right))) = (&mut self.stereo, eyes) {
            let mut fr = f;
            set_frame_camera(&mut fr, &right, aspect);
            right_changed = bytemuck::bytes_of(&fr) != bytemuck::bytes_of(&st.frame_right);
            st.frame_right = fr;
            view_projs.push(right.view_proj(aspect));
        }
        // Accumulated indirect light is valid only while camera, lights and settings stay.
        if let Some((gi, _)) = &mut self.gi {
            gi.update_scene(scene, s.time_s);
            if right_changed || bytemuck::bytes_of(&f) != bytemuck::bytes_of(&self.frame_data) {
                gi.reset();
            }
        }
        self.frame_data = f;
        self.shadow_view_count = base_views as u32;
        self.cascade_view_capacity = capacity as u32;
        let (own, cascades) = views.split_at(base_views);
        self.scene
            .update_draws(scene, s.time_s, &view_projs, (own, cascades));
        Ok(())
    }

    /// Writes the frame constants of frame slot `slot` (call after the slot's fence), and the
    /// dynamic objects' voxels at `settings.time_s`.
    pub fn write_frame(&mut self, slot: usize) {
        let mut attributes_moved = false;
        if let Some(v) = &mut self.voxels {
            if let Err(e) = v.update(self.settings.time_s, slot) {
                log::warn!("dynamic objects not re-voxelized: {e}");
            }
            attributes_moved = v.attributes_moved();
        }
        if let Some((gi, _)) = &mut self.gi {
            gi.update_dynamic(self.settings.time_s, slot);
            if attributes_moved {
                gi.reset();
            }
            gi.advance(slot);
        }
        if let Some(pass) = &mut self.voxel_debug {
            pass.update(self.settings.time_s, slot);
        }
        self.validate_caches(slot);
        // With TAA every frame renders with its own sub-pixel jitter; `frame_data` keeps the
        // un-jittered camera (what `prepare` compares to restart accumulation).
        let view_proj = glam::Mat4::from_cols_array(&self.frame_data.view_proj);
        let mut frame = jittered(self.frame_data, &mut self.post);
        let motion = self.scene.motion;
        if motion {
            // The previous frame written is the motion vectors' "before", camera and models.
            let prev = self.prev_view_proj.unwrap_or(view_proj);
            frame.prev_view_proj = prev.to_cols_array();
            self.prev_view_proj = Some(view_proj);
            self.scene.advance_motion();
        }
        self.scene.write_frame(slot, &frame);
        if let Some(st) = &mut self.stereo {
            // The right eye's own TAA history and jitter sequence.
            let right = st.jittered_right_frame(motion);
            self.scene.write_frame_right(slot, &right);
        }
    }

    /// Opens the cached light-space passes of slot `slot` where their inputs changed since
    /// they were last rendered (`graph::Cache`; nothing while `shadow.cache` is off).
    fn validate_caches(&self, slot: usize) {
        let Ok(draws) = self.scene.draws.read() else {
            return;
        };
        let layers = self.shadow_view_count + self.cascade_view_capacity;
        self.shadow_depth
            .validate(slot, &self.frame_data, &draws, layers);
        if let Some((_, Some(light_map))) = &self.gi {
            light_map.validate(slot, &self.frame_data, &draws);
        }
    }

    /// The caches of the light-space passes, by name (`shadow map V` per layer, `light
    /// maps`): how often each rendered and was reused (empty while `shadow.cache` is off).
    pub fn cache_counts(&self) -> Vec<(String, (u64, u64))> {
        let layers = self.shadow_view_count + self.cascade_view_capacity;
        let light_map = self.gi.as_ref().and_then(|(_, lm)| lm.as_ref());
        let light_map = light_map.and_then(|lm| lm.cache());
        self.shadow_depth
            .caches(layers)
            .iter()
            .chain(light_map)
            .map(|c| (c.name().to_owned(), c.counts()))
            .collect()
    }

    /// Frames the indirect light has accumulated since the last reset (`None`: GI off).
    pub fn gi_accumulated_frames(&self) -> Option<u32> {
        self.gi.as_ref().map(|(gi, _)| gi.accumulated_frames())
    }

    /// Number of culled camera draws and total draws (for statistics and tests).
    pub fn camera_draws(&self) -> (usize, usize) {
        let visible = self.scene.draws.read().map(|d| d.camera.len()).unwrap_or(0);
        (visible, self.scene.all_draws.len())
    }

    /// The transparency lists' counters of the last completed frame (`None`: no lists).
    pub fn oit_stats(&self) -> Option<OitStats> {
        self.oit.as_ref().map(oit::OitPasses::stats)
    }

    pub fn shadow_view_count(&self) -> u32 {
        self.shadow_view_count
    }

    pub fn has_phong(&self) -> bool {
        self.has_phong
    }

    /// Declares the frame with read-back of the radiance and the tone-mapped image (at the
    /// size given to [`Renderer::new`]).
    pub fn graph(&self) -> RenderGraph {
        let mut g = RenderGraph::new();
        let eyes = self.declare_eyes(&mut g);
        let readbacks = std::iter::once([&self.readback_hdr, &self.readback_ldr])
            .chain(self.stereo.as_ref().map(|st| st.readback_right.each_ref()));
        for (i, (images, [hdr, ldr])) in eyes.into_iter().zip(readbacks).enumerate() {
            g.set_pass_suffix(if i == 0 {
                ""
            } else {
                multiview::RIGHT_EYE_SUFFIX
            });
            let hdr_buf = g.import_buffer(hdr, Access::HostRead);
            let ldr_buf = g.import_buffer(ldr, Access::HostRead);
            crate::graph::add_readback(&mut g, "readback_hdr", images.radiance, hdr_buf);
            crate::graph::add_readback(&mut g, "readback_ldr", images.ldr, ldr_buf);
        }
        g
    }

    /// Declares the frame's passes into `g` at `settings`' size and returns the images it
    /// produces, for callers that add their own outputs (the viewer presents `ldr`). Nothing
    /// is an output yet: passes that feed nothing the caller adds are culled.
    ///
    /// A one-frame stereo renderer's frame has two such pairs: this returns the left eye's
    /// (see [`Renderer::declare_eyes`]).
    pub fn declare(&self, g: &mut RenderGraph) -> FrameImages {
        self.declare_with_scene(g).0
    }

    /// [`Self::declare`], also returning the scene's resources as imported into `g`, for
    /// passes the caller adds over the same scene (the viewer's `pick`).
    pub fn declare_with_scene(&self, g: &mut RenderGraph) -> (FrameImages, SceneInputs) {
        let (eyes, scene) = self.declare_eyes_with_scene(g);
        (eyes[0], scene)
    }

    /// Declares the frame: one [`FrameImages`], or, for a one-frame stereo renderer, the left
    /// and the right eye's. The world-space passes (shadow maps, voxels, light maps, the GI
    /// methods' VPLs and radiance volume) are declared once; the G-buffer draws both eyes
    /// into two-layer images (per eye, or in one multiview pass); every later pass runs per
    /// eye on its layer, the right eye's named with the suffix [`multiview::RIGHT_EYE_SUFFIX`].
    pub fn declare_eyes(&self, g: &mut RenderGraph) -> Vec<FrameImages> {
        self.declare_eyes_with_scene(g).0
    }

    /// [`Self::declare_eyes`], also returning the scene's resources as imported into `g`.
    fn declare_eyes_with_scene(&self, g: &mut RenderGraph) -> (Vec<FrameImages>, SceneInputs) {
        let s = &self.settings;
        let (w, h) = (s.width, s.height);
        let scene = self.scene.import(g);
        let views = self.shadow_view_count;
        let voxel_image = self.voxels.as_ref().map(|v| v.add_passes(g));
        let shadow_map = self.shadow_depth.declare(
            g,
            &scene,
            views + self.cascade_view_capacity,
            s.shadow.resolution,
        );
        let gbuffer = self.gbuffer.declare(g, &scene, w, h);
        let mut shared = SharedByEyes::default();
        let world = (shadow_map, voxel_image);
        let Some(st) = &self.stereo else {
            let images =
                self.declare_view(g, &scene, &gbuffer, world, (&self.post, 0), &mut shared);
            let images = self.declare_debug_view(g, &scene, &gbuffer, voxel_image, images);
            return (vec![images], scene);
        };
        let left = gbuffer.eye(g, 0);
        let right = gbuffer.eye(g, 1);
        let left = self.declare_view(g, &scene, &left, world, (&self.post, 0), &mut shared);
        // The right eye's passes read its frame constants.
        let mut scene_right = scene.clone();
        scene_right.frame = scene.frame_right.unwrap_or(scene.frame);
        g.set_pass_suffix(multiview::RIGHT_EYE_SUFFIX);
        let right = self.declare_view(
            g,
            &scene_right,
            &right,
            world,
            (&st.post_right, 1),
            &mut shared,
        );
        g.set_pass_suffix("");
        (vec![left, right], scene)
    }

    /// The passes of one view after the G-buffer: direct light, indirect light, transparency,
    /// post-processing and tone mapping. What the eyes of a stereo frame share is declared
    /// by the first and kept in `shared`.
    fn declare_view(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        (shadow_map, voxel_image): (ImageHandle, Option<ImageHandle>),
        (post, eye): (&crate::post::PostPasses, u32),
        shared: &mut SharedByEyes,
    ) -> FrameImages {
        let s = &self.settings;
        let (w, h) = (s.width, s.height);
        let views = self.shadow_view_count;
        let direct = self.deferred.declare(g, scene, gbuffer, shadow_map, (w, h));
        let radiance = match &self.gi {
            Some((gi, light_map)) if voxel_image.is_some() || light_map.is_none() => {
                // Screen-space GI reads neither voxels nor light maps (GiInputs::voxels).
                let maps = match (light_map, shared.light_maps) {
                    (Some(_), Some(maps)) => maps,
                    (Some(lm), None) => {
                        let maps = lm.declare(g, scene, views, gi.settings.light_map_resolution);
                        shared.light_maps = Some(maps);
                        maps
                    }
                    (None, _) => LightMaps {
                        radiance: direct,
                        position: direct,
                        normal: direct,
                    },
                };
                gi.add_eye_passes(
                    g,
                    &crate::gi::GiInputs {
                        frame: scene.frame,
                        albedo: gbuffer.albedo,
                        normal: gbuffer.normal,
                        depth: gbuffer.depth,
                        direct,
                        voxels: voxel_image.unwrap_or(gbuffer.depth),
                        rlm_radiance: maps.radiance,
                        rlm_position: maps.position,
                        rlm_normal: maps.normal,
                        shadow_map,
                        specular: gbuffer.specular,
                        materials: scene.materials,
                        materials_pbr: scene.materials_pbr,
                        environment_map: scene.environment_map,
                        environment_sampler: scene.texture_sampler,
                        width: w,
                        height: h,
                    },
                    self.voxels.as_ref(),
                    eye,
                    &mut shared.gi,
                )
            }
            _ => direct,
        };
        // Transparent layers over the lit opaque frame, before post-processing.
        let radiance = match &self.oit {
            Some(oit) => oit.declare(g, scene, (gbuffer.depth, shadow_map), radiance, (w, h)),
            None => radiance,
        };
        let (radiance, exposure) = post.declare_hdr(g, radiance, gbuffer.depth, gbuffer.motion);
        let ldr = self
            .tonemap
            .declare(g, radiance, exposure, s.tonemap, (w, h));
        let ldr = post.declare_ldr(g, ldr);
        FrameImages { radiance, ldr }
    }

    /// A debug view replaces the lit image `lit` (mono renderers only).
    fn declare_debug_view(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        gbuffer: &Gbuffer,
        voxel_image: Option<ImageHandle>,
        lit: FrameImages,
    ) -> FrameImages {
        let (w, h) = (self.settings.width, self.settings.height);
        let FrameImages { radiance, ldr } = lit;

        // A debug view replaces the lit image: the read-backs take its images, and the graph
        // culls deferred light, tone mapping, G-buffer and shadows, which nothing reads then.
        let (radiance, ldr) = match (&self.voxel_debug, &self.voxels, voxel_image) {
            _ if self.gbuffer_view.is_some() => match &self.gbuffer_view {
                Some(pass) => pass.declare(g, scene, gbuffer, (w, h)),
                None => (radiance, ldr),
            },
            _ if self.shadow_texels.is_some() => match &self.shadow_texels {
                Some(pass) => pass.declare(g, scene, gbuffer, (w, h)),
                None => (radiance, ldr),
            },
            _ if self.atlas_view.is_some() => {
                let value = g.create_image(ImageDesc::new_2d("atlas debug value", HDR, w, h));
                let color = g.create_image(ImageDesc::new_2d(
                    "atlas debug color",
                    vk::Format::R8G8B8A8_UNORM,
                    w,
                    h,
                ));
                if let Some(pass) = &self.atlas_view {
                    pass.add_passes(g, value, color, (w, h));
                }
                (value, color)
            }
            (Some(pass), Some(v), Some(image)) => {
                let value = g.create_image(ImageDesc::new_2d("voxel debug value", HDR, w, h));
                let color = g.create_image(ImageDesc::new_2d(
                    "voxel debug color",
                    vk::Format::R8G8B8A8_UNORM,
                    w,
                    h,
                ));
                pass.add_pass(g, v, image, value, color, (w, h));
                (value, color)
            }
            _ => (radiance, ldr),
        };

        FrameImages { radiance, ldr }
    }

    /// Linear radiance of the last completed frame.
    pub fn hdr_image(&self) -> HdrImage {
        hdr_from(
            &self.readback_hdr,
            (self.settings.width, self.settings.height),
        )
    }

    /// Tone-mapped sRGB RGBA8 pixels of the last completed frame.
    pub fn ldr_pixels(&self) -> Vec<u8> {
        ldr_from(
            &self.readback_ldr,
            (self.settings.width, self.settings.height),
        )
    }

    /// GPU times of the one-time passes the renderer submitted outside its frame graph
    /// (atlas building, static voxelization), in order.
    pub fn setup_timings(&self) -> Vec<PassTiming> {
        self.voxels
            .as_ref()
            .map(|v| v.setup_timings().to_vec())
            .unwrap_or_default()
    }

    /// What the debug view shows and measured in `value` (its value image), for the CLI.
    pub fn debug_description(&self, value: &HdrImage) -> Option<String> {
        if let Some(pass) = &self.gbuffer_view {
            return Some(pass.describe(value));
        }
        if self.shadow_texels.is_some() {
            return Some(shadow_texels::describe(value));
        }
        match (&self.atlas_view, &self.settings.debug) {
            (Some(pass), _) => Some(pass.describe(value)),
            (None, Some(d)) => Some(crate::voxel::debug_view::describe(d, value)),
            _ => None,
        }
    }
}

fn gpu_light(light: &Light, first_view: u32, views: u32) -> GpuLight {
    let v4 = |v: Vec3| [v.x, v.y, v.z, 0.0];
    match *light {
        Light::Point {
            position,
            intensity_w_sr,
        } => GpuLight {
            position: v4(position),
            intensity: v4(intensity_w_sr),
            info: [LIGHT_POINT, first_view, views, 0],
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => GpuLight {
            position: v4(position),
            direction: v4(direction),
            intensity: v4(intensity_w_sr),
            spot: [
                cutoff_deg.to_radians().cos(),
                cutoff_deg.to_radians(),
                beam_deg.to_radians(),
                0.0,
            ],
            info: [LIGHT_SPOT, first_view, views, 0],
        },
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => GpuLight {
            direction: v4(direction),
            intensity: v4(irradiance_w_m2),
            info: [LIGHT_DIRECTIONAL, first_view, views, 0],
            ..Default::default()
        },
        Light::Element {
            position,
            normal,
            intensity_w_sr,
            pcss_size_m,
        } => GpuLight {
            position: v4(position),
            direction: v4(normal),
            intensity: v4(intensity_w_sr),
            spot: [0.0, 0.0, 0.0, pcss_size_m],
            info: [LIGHT_ELEMENT, first_view, views, 0],
        },
        // A whole sphere (`--area-shadows pcss`): seen from any direction it is a disk of
        // area πR² and radiance L, so a point light of intensity I = L·πR² at its centre gives
        // exactly its irradiance E = π L (R/d)² cos θ wherever it is wholly above the
        // receiver's horizon; spot.w, its diameter, asks for PCSS (glsl/include/shadow.glsl).
        Light::Sphere {
            position,
            radius_m,
            radiance_w_sr_m2,
            ..
        } => GpuLight {
            position: v4(position),
            intensity: v4(radiance_w_sr_m2 * (std::f32::consts::PI * radius_m * radius_m)),
            spot: [0.0, 0.0, 0.0, 2.0 * radius_m],
            info: [LIGHT_POINT, first_view, views, 0],
            ..Default::default()
        },
        Light::Rectangle { .. } => {
            unreachable!("prepare renders rectangles as elements (frame_lights)")
        }
    }
}

/// The linear radiance in a read-back buffer of a `w`×`h` frame (black if unmapped).
fn hdr_from(buffer: &Buffer, (w, h): (u32, u32)) -> HdrImage {
    let data: Vec<[f32; 3]> = buffer
        .mapped()
        .map(|m| {
            bytemuck::cast_slice::<u8, [f32; 4]>(&m[..(w * h * 16) as usize])
                .iter()
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        })
        .unwrap_or_else(|| vec![[0.0; 3]; (w * h) as usize]);
    HdrImage {
        width: w,
        height: h,
        data,
    }
}

/// The tone-mapped sRGB RGBA8 pixels in a read-back buffer of a `w`×`h` frame.
fn ldr_from(buffer: &Buffer, (w, h): (u32, u32)) -> Vec<u8> {
    let n = (w * h * 4) as usize;
    buffer.mapped().map(|m| m[..n].to_vec()).unwrap_or_default()
}

/// With TAA every frame renders with its own sub-pixel jitter: `frame` (un-jittered, what
/// `prepare` compares to restart accumulation) moved by `post`'s next jitter.
fn jittered(mut frame: GpuFrame, post: &mut crate::post::PostPasses) -> GpuFrame {
    if post.jitters() {
        let view_proj = glam::Mat4::from_cols_array(&frame.view_proj);
        let jitter_ndc = post.begin_frame(view_proj);
        let jitter = crate::post::taa::jitter_matrix(jitter_ndc);
        // The inverse stays camera-relative (see `camera_relative_inverse`).
        let inv_relative = glam::Mat4::from_cols_array(&frame.inv_view_proj);
        frame.view_proj = (jitter * view_proj).to_cols_array();
        frame.inv_view_proj = (inv_relative * jitter.inverse()).to_cols_array();
        frame.jitter_ndc = [jitter_ndc.x, jitter_ndc.y, 0.0, 0.0];
    }
    frame
}

/// Sets the frame constants that depend on the camera: view-projection, its camera-relative
/// inverse, the camera position and its viewing direction with the projection.
fn set_frame_camera(f: &mut GpuFrame, camera: &crate::scene::Camera, aspect: f32) {
    f.view_proj = camera.view_proj(aspect).to_cols_array();
    f.inv_view_proj = camera_relative_inverse(camera, aspect).to_cols_array();
    f.camera_position = camera.position.extend(1.0).to_array();
    let ortho_height_m = if camera.is_orthographic() {
        camera.ortho_height_m
    } else {
        0.0
    };
    f.camera_forward = camera.forward.extend(ortho_height_m).to_array();
}

/// The inverse of the camera's view-projection with the camera moved to the origin:
/// `pixel_world_position` (glsl/include/frame.glsl) unprojects a pixel relative to the camera
/// with it and adds the camera's position, so that a scene far from the world origin keeps
/// f32 precision.
fn camera_relative_inverse(camera: &crate::scene::Camera, aspect: f32) -> glam::Mat4 {
    let mut relative = *camera;
    relative.position = glam::Vec3::ZERO;
    relative.view_proj(aspect).inverse()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lights a frame holds: 64 lights, 64 shadow views (a cube-shadowed point light takes
    /// 6, so 10 fit and 11 do not; with paraboloid shadows 2 each, 32 fit).
    #[test]
    fn check_lights_counts_lights_and_shadow_views() {
        let mut scene = crate::scene::builtin("cornell-point").expect("cornell-point");
        let point = scene.lights[0];
        let settings = RenderSettings::default();
        scene.lights = vec![point; 10];
        assert!(check_lights(&scene, &settings).is_ok());
        scene.lights.push(point);
        assert!(matches!(
            check_lights(&scene, &settings),
            Err(RenderError::TooManyShadowViews(66))
        ));
        let mut paraboloid = settings.clone();
        paraboloid.shadow.point_technique = PointShadow::DualParaboloid;
        assert!(check_lights(&scene, &paraboloid).is_ok());
        scene.lights = vec![point; 65];
        assert!(matches!(
            check_lights(&scene, &paraboloid),
            Err(RenderError::TooManyLights(65))
        ));
    }
}
