//! `--gi vpl`: virtual point lights (Thiedemann 2010, Ch. 7). VPLs are generated from the
//! reflective light maps by a 2D Halton sequence (§7.2, `glsl/gi_vpl_generate.comp`), further
//! bounces by one voxel ray per VPL with albedo and normal from the attribute volumes
//! (`glsl/gi_vpl_bounce.comp`), and the frame is shaded with interleaved sampling (§7.3.2): an
//! N×M pattern of VPL sets, each pixel block with its own set, voxel visibility per VPL–pixel
//! pair (`glsl/gi_vpl_gather.comp`); the geometry-aware filter then removes the pattern.
//! Emissive surfaces and area lights, which the light maps do not see, send VPLs of their own
//! (`gi_vpl_emit`, [`super::gi_vpl_emit`]).

pub use crate::scene::vpl_settings::{
    VplNormalize, VplSettings, VplShading, VplSpotSampling, VplVisibility,
};

use super::gi_common::GiShared;
pub use super::gi_common::GpuVplGeneratePush;
use super::gi_vpl_emit::GiVplEmit;
use super::{GiInputs, GiMethodPasses, GiOutput, GiSettings, GiTarget, Overlay};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PipelineHandle, PushLayout, VkError};
use bytemuck::{Pod, Zeroable};

/// One VPL (`GpuVpl` in `glsl/include/vpl.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVpl {
    /// xyz world position (m); w 1 valid, 0 invalid.
    pub position: [f32; 4],
    /// xyz unit normal of the sender.
    pub normal: [f32; 4],
    /// rgb the diffuse part's flux Φ_VPL (W); w the bounce.
    pub flux: [f32; 4],
    /// Glossy senders: xyz the unit direction toward the incident light, w the Phong exponent
    /// or the GGX roughness.
    pub lobe: [f32; 4],
    /// Glossy senders: rgb Phong ρ_s or GGX F0; w the lobe kind (1 Phong, 2 GGX, 0 Lambert).
    pub specular: [f32; 4],
    /// Glossy senders: rgb the incident flux Φ_in (W).
    pub incident: [f32; 4],
}

crate::gpu_struct!(GpuVpl {
    position,
    normal,
    flux,
    lobe,
    specular,
    incident
});

/// Push constants of `gi_vpl_gather`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVplGatherPush {
    pub world_to_voxel: [f32; 16],
    pub dims: [i32; 4],
    /// N, M, VPLs per row, visibility (1 voxel test, 0 none).
    pub pattern: [u32; 4],
    /// Start level, max iterations.
    pub trace: [u32; 2],
    pub d_min_m2: f32,
    pub voxel_diagonal_m: f32,
    /// Normal offset, ray offset k₂, its clamp (voxel diagonals).
    pub offsets: [f32; 3],
    /// `gi_vpl_splat`: the row index of the VPL this pass adds.
    pub splat_vpl: u32,
}

crate::push_constants!(GpuVplGatherPush {
    world_to_voxel,
    dims,
    pattern,
    trace,
    d_min_m2,
    voxel_diagonal_m,
    offsets,
    splat_vpl
});

// Also a buffer's contents: `oit_gather_vpl.frag` reads the gather's parameters from one (its
// push constants hold the draw).
crate::gpu_struct!(GpuVplGatherPush {
    world_to_voxel,
    dims,
    pattern,
    trace,
    d_min_m2,
    voxel_diagonal_m,
    offsets,
    splat_vpl
});

/// Push constants of `gi_vpl_points` (the debug view).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVplPointsPush {
    pub count: u32,
    pub radiance_w: f32,
}

crate::push_constants!(GpuVplPointsPush { count, radiance_w });

/// The sizes of the VPL buffer: `sets` rows of `bounces × lights × per_set` VPLs, then
/// `sources` source VPLs (`glsl/include/vpl.glsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VplLayout {
    pub sets: u32,
    /// The lights with reflective maps, plus one slot for the emitters when there are any.
    pub lights: u32,
    pub per_set: u32,
    pub bounces: u32,
    /// Source VPLs on emissive surfaces per row: `per_set` when the scene has emissive
    /// surfaces, else 0.
    pub sources: u32,
}

impl VplLayout {
    /// VPLs in one row (one set).
    pub fn row(&self) -> u32 {
        self.bounces * self.lights * self.per_set + self.sources
    }

    /// VPLs generated per bounce (one invocation each).
    pub fn per_bounce(&self) -> u32 {
        self.sets * self.lights * self.per_set
    }

    /// The buffer's size in bytes (at least one VPL).
    pub fn size_bytes(&self) -> u64 {
        (u64::from(self.sets) * u64::from(self.row())).max(1) * std::mem::size_of::<GpuVpl>() as u64
    }
}

/// The VPL method's pipelines and constants.
pub struct VplPasses {
    generate: ComputePipeline,
    bounce: Option<ComputePipeline>,
    gather: ComputePipeline,
    /// VPLs from emissive surfaces and area lights, in scenes that have them.
    emit: Option<GiVplEmit>,
    /// The debug view's pipeline, when it is on.
    points: Option<ComputePipeline>,
    layout: VplLayout,
    generate_push: GpuVplGeneratePush,
    /// Frames of history under temporal accumulation (`gi.temporal_frames`), 1 without: each
    /// set's block of the Halton sequence holds K points per history frame.
    history_frames: u32,
    gather_push: GpuVplGatherPush,
    shading: VplShading,
}

impl VplPasses {
    pub fn new(
        ctx: &Context,
        settings: &GiSettings,
        target: &GiTarget<'_>,
    ) -> Result<Self, VkError> {
        let v = settings.vpl;
        let grid = target.grid;
        let ext = grid.extent_voxels();
        let levels = crate::voxel::bits::mip_count(grid.res_x(), grid.res_y());
        let dims = [ext.x as i32, ext.y as i32, ext.z as i32, levels as i32 - 1];
        let world_to_voxel = grid.world_to_voxel_matrix().to_cols_array();
        let bounces = v.bounces.clamp(1, VplSettings::MAX_BOUNCES);
        let per_set = v.per_set.max(1);
        // Glossy hits of the bounces and emitter rays read the material volume, which the
        // assembly creates for the VPLs in scenes with Phong or GGX materials.
        let lobes = !target.scene.is_all_lambert();
        let emit = GiVplEmit::new(
            ctx,
            target.scene,
            target.time_s,
            per_set,
            lobes,
            settings.voxel_map_texels,
        )?;
        // Area lights have no reflective maps: the emitter slot carries their VPLs.
        let map_lights = target.scene.lights.iter().filter(|l| !l.is_area()).count() as u32;
        let layout = VplLayout {
            sets: v.pattern[0].max(1) * v.pattern[1].max(1),
            lights: map_lights + u32::from(emit.is_some()),
            per_set,
            bounces,
            sources: if emit.as_ref().is_some_and(|e| e.has_surfaces) {
                per_set
            } else {
                0
            },
        };
        let diagonal_m = grid.voxel_diagonal_m();
        let scene_diagonal_m = target.scene.aabb_at(target.time_s).extent().length();
        let generate_push = GpuVplGeneratePush {
            world_to_voxel,
            dims,
            counts: [layout.sets, layout.lights, layout.per_set, layout.bounces],
            trace: [
                settings.start_level,
                settings.max_iterations,
                0,
                target.shadow_resolution,
            ],
            params: [
                settings.normal_offset_voxels,
                diagonal_m,
                settings.radius_m.unwrap_or(scene_diagonal_m),
                0.0,
            ],
        };
        let gather_push = GpuVplGatherPush {
            world_to_voxel,
            dims,
            pattern: [
                v.pattern[0].max(1),
                v.pattern[1].max(1),
                layout.row(),
                u32::from(v.visibility == VplVisibility::Voxel),
            ],
            trace: [settings.start_level, settings.max_iterations],
            d_min_m2: (v.d_min_voxels * diagonal_m).powi(2),
            voxel_diagonal_m: diagonal_m,
            offsets: [
                settings.normal_offset_voxels,
                settings.ray_offset_voxels,
                settings.ray_offset_max_voxels,
            ],
            splat_vpl: 0,
        };
        // The two generation options are specialization constants (NORMALIZE_VALID,
        // SPOT_DISK): the push block has one spare float, and a change of either rebuilds the
        // passes anyway.
        let generate = ctx.compute_pipeline(
            "gi_vpl_generate.comp",
            PushLayout::of::<GpuVplGeneratePush>(),
            &crate::spec_constants![
                NORMALIZE_VALID = v.normalize == VplNormalize::Valid,
                SPOT_DISK = v.spot_sampling == VplSpotSampling::Disk,
                SOURCE_VPLS = layout.sources,
                HAS_GGX = target.scene.has_ggx(),
            ],
        )?;
        let shader = match v.shading {
            VplShading::Gather => "gi_vpl_gather.comp",
            VplShading::Splat => "gi_vpl_splat.comp",
        };
        // Glossy receivers: GGX pixels' whole BRDF (HAS_GGX) and the roughness floor of
        // Phong and GGX pixels (MIN_ROUGHNESS, a float; the push block is full at 128 bytes).
        let gather = ctx.compute_pipeline(
            shader,
            PushLayout::of::<GpuVplGatherPush>(),
            &crate::spec_constants![
                HAS_PHONG = target.has_phong,
                HAS_GGX = target.scene.has_ggx(),
                MIN_ROUGHNESS = v.min_roughness,
            ],
        )?;
        let points = v
            .show
            .then(|| {
                ctx.compute_pipeline(
                    "gi_vpl_points.comp",
                    PushLayout::of::<GpuVplPointsPush>(),
                    &[],
                )
            })
            .transpose()?;
        // Bounces after the first read the attribute volumes `GiPasses` keeps for them
        // (`GiPasses::needs_attribute_volumes`).
        let bounce = (bounces > 1)
            .then(|| {
                ctx.compute_pipeline(
                    "gi_vpl_bounce.comp",
                    PushLayout::of::<GpuVplGeneratePush>(),
                    &crate::spec_constants![SOURCE_VPLS = layout.sources, HAS_LOBES = lobes],
                )
            })
            .transpose()?;
        Ok(Self {
            generate,
            bounce,
            gather,
            emit,
            points,
            layout,
            generate_push,
            history_frames: if target.temporal {
                settings.temporal_frames.clamp(1, 4096)
            } else {
                1
            },
            gather_push,
            shading: v.shading,
        })
    }

    /// The buffer layout (sets, lights, VPLs per set, bounces).
    pub fn layout(&self) -> VplLayout {
        self.layout
    }

    /// Declares generation, bounces and the interleaved gather; returns the indirect
    /// irradiance (radiance for Phong and GGX pixels), unfiltered, and the VPL buffer (for
    /// [`VplPasses::add_points`]).
    fn add_vpl_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        shared: &GiShared,
    ) -> (ImageHandle, BufferHandle) {
        let (lut, sampler) = (shared.lut, shared.sampler);
        // `GiPasses::add_eye_passes` declares the VPLs first, once for both stereo eyes.
        let vpls = match shared.world.buffer {
            Some(vpls) => vpls,
            None => self.add_vpls(g, i, shared),
        };
        (self.add_gather(g, i, (lut, sampler), vpls), vpls)
    }

    /// Generates the VPLs (and their bounces): view-independent, shared by stereo eyes.
    fn add_vpls(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> BufferHandle {
        let (lut, sampler) = (shared.lut, shared.sampler);
        let vpls = g.create_buffer("vpls", self.layout.size_bytes());
        let push = self.frame_push(shared);
        self.add_generate(g, i, vpls, sampler, push.clone());
        // The assembly writes the attribute volumes when the scene has emitters.
        if let (Some(emit), Some(v)) = (&self.emit, shared.attributes) {
            let invocations = self.layout.sets * self.layout.per_set;
            // Without a material volume (all-Lambert scenes) the shader never reads it.
            let volumes = (v.albedo, v.normal, v.material.unwrap_or(v.albedo));
            emit.add_pass(
                g,
                push.clone(),
                invocations,
                (i.voxels, lut),
                volumes,
                vpls,
                sampler,
            );
        }
        if let (Some(pipe), Some(v)) = (self.bounce.as_deref().copied(), shared.attributes) {
            let volumes = (v.albedo, v.normal, v.material.unwrap_or(v.albedo));
            for b in 1..self.layout.bounces {
                self.add_bounce(
                    g,
                    (pipe, b),
                    i,
                    (lut, sampler),
                    volumes,
                    (vpls, push.clone()),
                );
            }
        }
        vpls
    }

    fn groups_1d(&self) -> u32 {
        self.layout.per_bounce().div_ceil(64).max(1)
    }

    /// The generating passes' push constants at record time: under temporal accumulation
    /// each set's frames continue its block of the Halton sequence where the last frame
    /// stopped (`halton_point` in `glsl/include/vpl.glsl`: T history frames and this frame's
    /// index modulo T, packed as T << 16 | f), so that N frames of K VPLs are the N·K that one
    /// frame of N·K would take; without, T = 1 and f = 0, the blocks of one frame.
    fn frame_push(&self, shared: &GiShared) -> impl Fn() -> GpuVplGeneratePush + Clone + 'static {
        let base = self.generate_push;
        let frame = shared.frame_index();
        let t = self.history_frames;
        move || {
            let packed = (t << 16) | (frame() % t);
            let mut push = base;
            push.params[3] = f32::from_bits(packed);
            push
        }
    }

    fn add_generate(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        vpls: BufferHandle,
        s: vk::Sampler,
        push: impl Fn() -> GpuVplGeneratePush + 'static,
    ) {
        let c = Shader::Compute;
        let pipe = *self.generate;
        let groups = self.groups_1d();
        g.add_pass("gi_vpl_generate")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.rlm_radiance, s, c)
            .bind_sampled(2, i.rlm_position, s, c)
            .bind_sampled(3, i.rlm_normal, s, c)
            .bind(4, vpls, Access::StorageWrite(c))
            .bind(5, i.materials, Access::StorageRead(c))
            .bind(6, i.materials_pbr, Access::StorageRead(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push()));
                ctx.cmd.dispatch(groups, 1, 1);
            });
    }

    fn add_bounce(
        &self,
        g: &mut RenderGraph,
        (pipe, bounce): (PipelineHandle, u32),
        i: &GiInputs,
        (lut, s): (BufferHandle, vk::Sampler),
        (albedo, normal, material): (ImageHandle, ImageHandle, ImageHandle),
        (vpls, push): (BufferHandle, impl Fn() -> GpuVplGeneratePush + 'static),
    ) {
        let c = Shader::Compute;
        let groups = self.groups_1d();
        g.add_pass(&format!("gi_vpl_bounce[{bounce}]"))
            .pipeline(&pipe)
            .bind_sampled(0, i.voxels, s, c)
            .bind(1, lut, Access::StorageRead(c))
            .bind_sampled(2, albedo, s, c)
            .bind_sampled(3, normal, s, c)
            .bind(4, vpls, Access::StorageReadWrite(c))
            .bind_sampled(5, material, s, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                let mut push = push();
                push.trace[2] = bounce;
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups, 1, 1);
            });
    }

    fn add_gather(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        (lut, s): (BufferHandle, vk::Sampler),
        vpls: BufferHandle,
    ) -> ImageHandle {
        let (w, h) = (i.width, i.height);
        let irradiance = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let c = Shader::Compute;
        let pipe = *self.gather;
        let push = self.gather_push;
        // The split frame: N×M blocks of ceil(W/N)×ceil(H/M) pixels (gi_vpl_gather.comp).
        let [n, m] = [push.pattern[0], push.pattern[1]];
        let groups = (
            (w.div_ceil(n) * n).div_ceil(8),
            (h.div_ceil(m) * m).div_ceil(8),
        );
        let specular = i.specular.unwrap_or(i.albedo);
        // Splatting: one pass per VPL of a row, the first writing, the others adding.
        let passes = match self.shading {
            VplShading::Gather => {
                vec![("gi_vpl_gather".to_string(), push, Access::StorageWrite(c))]
            }
            VplShading::Splat => (0..push.pattern[2].max(1))
                .map(|k| {
                    let access = if k == 0 {
                        Access::StorageWrite(c)
                    } else {
                        Access::StorageReadWrite(c)
                    };
                    let p = GpuVplGatherPush {
                        splat_vpl: k,
                        ..push
                    };
                    (format!("gi_vpl_splat[{k}]"), p, access)
                })
                .collect(),
        };
        for (name, push, access) in passes {
            g.add_pass(&name)
                .pipeline(&pipe)
                .bind(0, i.frame, Access::StorageRead(c))
                .bind_sampled(1, i.normal, s, c)
                .bind_sampled(2, i.depth, s, c)
                .bind_sampled(3, i.voxels, s, c)
                .bind(4, lut, Access::StorageRead(c))
                .bind(5, vpls, Access::StorageRead(c))
                .bind(6, irradiance, access)
                .bind_sampled(7, specular, s, c)
                .bind_sampled(8, i.albedo, s, c)
                .record(move |ctx| {
                    ctx.bind(&pipe);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd.dispatch(groups.0, groups.1, 1);
                });
        }
        irradiance
    }
}

impl GiMethodPasses for VplPasses {
    fn update_scene(&mut self, scene: &crate::scene::Scene, t_s: f32) {
        if let Some(emit) = &mut self.emit {
            emit.update(scene, t_s);
        }
    }

    fn write_slot(&mut self, slot: usize) {
        if let Some(emit) = &mut self.emit {
            emit.write_slot(slot);
        }
    }

    /// Transparent layers gather every set with the opaque pixels' parameters
    /// (`oit_gather_vpl.frag`).
    fn layer_params(&self) -> Option<super::LayerParams> {
        Some(super::LayerParams::Vpls(self.gather_push))
    }

    fn add_world_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        shared: &GiShared,
    ) -> super::MethodWorld {
        super::MethodWorld {
            image: None,
            buffer: Some(self.add_vpls(g, i, shared)),
        }
    }

    fn add_passes(&self, g: &mut RenderGraph, i: &GiInputs, shared: &GiShared) -> GiOutput {
        let (indirect, vpls) = self.add_vpl_passes(g, i, shared);
        // The debug view draws the VPLs over the lit image, after the filter and composite.
        let overlay = self.points.as_deref().copied().map(|pipe| {
            let (layout, i, sampler) = (self.layout, *i, shared.sampler);
            Box::new(move |g: &mut RenderGraph, lit: ImageHandle| {
                add_points(g, pipe, layout, &i, vpls, lit, sampler)
            }) as Overlay
        });
        GiOutput { indirect, overlay }
    }
}

/// The debug view (`gi_vpl_points`): draws every VPL as a dot into `radiance` (the lit image).
fn add_points(
    g: &mut RenderGraph,
    pipe: PipelineHandle,
    layout: VplLayout,
    i: &GiInputs,
    vpls: BufferHandle,
    radiance: ImageHandle,
    s: vk::Sampler,
) {
    let count = layout.sets * layout.row();
    // Bright enough to saturate any tone map over the Cornell box's radiance (~1).
    let push = GpuVplPointsPush {
        count,
        radiance_w: 100.0,
    };
    let c = Shader::Compute;
    g.add_pass("gi_vpl_points")
        .pipeline(&pipe)
        .bind(0, i.frame, Access::StorageRead(c))
        .bind_sampled(1, i.depth, s, c)
        .bind(2, vpls, Access::StorageRead(c))
        .bind(3, radiance, Access::StorageReadWrite(c))
        .record(move |ctx| {
            ctx.bind(&pipe);
            ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
            ctx.cmd.dispatch(count.div_ceil(64).max(1), 1, 1);
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_fit_and_match_glsl() {
        assert_eq!(std::mem::size_of::<GpuVplGeneratePush>(), 128);
        assert_eq!(std::mem::size_of::<GpuVplGatherPush>(), 128);
        assert_eq!(std::mem::offset_of!(GpuVplGatherPush, d_min_m2), 104);
        assert_eq!(std::mem::size_of::<GpuVpl>(), 96);
    }

    /// Every pass that reads or writes the VPL buffer lays out `GpuVpl` as the Rust struct.
    #[test]
    fn vpl_struct_matches_every_shader() {
        for shader in [
            "gi_vpl_generate.comp",
            "gi_vpl_bounce.comp",
            "gi_vpl_emit.comp",
            "gi_vpl_gather.comp",
            "gi_vpl_splat.comp",
            "gi_vpl_points.comp",
            "oit_gather_vpl.frag",
        ] {
            crate::vk::check_struct_against::<GpuVpl>(&[shader], "GpuVpl")
                .unwrap_or_else(|e| panic!("{shader}: {e}"));
        }
    }

    #[test]
    fn buffer_rows_hold_every_bounce_of_every_light() {
        let l = VplLayout {
            sets: 16,
            lights: 2,
            per_set: 8,
            bounces: 2,
            sources: 0,
        };
        assert_eq!(l.row(), 32);
        assert_eq!(l.per_bounce(), 256);
        assert_eq!(l.size_bytes(), 16 * 32 * 96);
        let none = VplLayout { lights: 0, ..l };
        assert_eq!(none.size_bytes(), 96, "never an empty buffer");
        // Emissive surfaces: K source VPLs end each row.
        let emissive = VplLayout { sources: 8, ..l };
        assert_eq!(emissive.row(), 40);
        assert_eq!(emissive.size_bytes(), 16 * 40 * 96);
    }
}
