//! The frame's graph: the world-space passes once, then per eye direct light, indirect
//! light, transparency, post-processing and tone mapping, or a debug view instead.

use super::*;
use oit::OitVoxelInputs;

/// What a frame's eyes share: declared by the first eye's passes, reused by the second.
#[derive(Default)]
struct SharedByEyes {
    light_maps: Option<LightMaps>,
    gi: Option<crate::gi::GiWorld>,
    direct_emitters: Option<direct_emitters::DirectEmittersWorld>,
}

impl Renderer {
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
        let direct = match (&self.direct_emitters, voxel_image) {
            (Some(pass), Some(voxels)) => {
                let world = *shared.direct_emitters.get_or_insert_with(|| pass.import(g));
                pass.declare(g, scene, gbuffer, direct, voxels, world, (w, h))
            }
            _ => direct,
        };
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
                        motion: gbuffer.motion,
                        specular: gbuffer.specular,
                        materials: scene.materials,
                        materials_pbr: scene.materials_pbr,
                        environment_map: scene.environment_map,
                        environment_cdf: scene.environment_cdf,
                        environment_sampler: scene.environment_sampler,
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
            Some(oit) => {
                // The GI method's voxels, ray masks and what its rays read at hits, for the
                // fragments' indirect light (declared above by the first eye).
                let voxels = voxel_image.zip(shared.gi).map(|(voxels, world)| {
                    let r = world.ray_inputs();
                    OitVoxelInputs {
                        voxels,
                        lut: r.lut,
                        attributes: r.attributes,
                        light_maps: shared.light_maps,
                        radiance_volume: r.radiance_volume,
                        vpls: r.vpls,
                    }
                });
                let world = (gbuffer.depth, shadow_map);
                oit.declare(g, scene, world, radiance, (w, h), voxels)
            }
            None => radiance,
        };
        let (radiance, exposure) = post.declare_hdr(g, radiance, gbuffer.depth, gbuffer.motion);
        // TAA upsampling resolves into a larger image: tone mapping follows it.
        let ldr = self.tonemap.declare(
            g,
            radiance,
            exposure,
            s.tonemap,
            post.upsampled().unwrap_or((w, h)),
        );
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
}
