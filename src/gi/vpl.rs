//! `--gi vpl`: virtual point lights (Thiedemann 2010, Ch. 7). VPLs are generated from the
//! reflective light maps by a 2D Halton sequence (§7.2, `glsl/gi_vpl_generate.comp`), further
//! bounces by one voxel ray per VPL with albedo and normal from the attribute volumes
//! (`glsl/gi_vpl_bounce.comp`), and the frame is shaded with interleaved sampling (§7.3.2): an
//! N×M pattern of VPL sets, each pixel block with its own set, voxel visibility per VPL–pixel
//! pair (`glsl/gi_vpl_gather.comp`); the geometry-aware filter then removes the pattern.

use super::{GiInputs, GiSettings, GiTarget};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, ComputePipeline, Context, ImageDesc, PushLayout, VkError};
use crate::voxel::attributes::TriangleAttributeVolumes;
use bytemuck::{Pod, Zeroable};

/// Visibility of a VPL from a receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplVisibility {
    /// The voxel segment test with offsets at both ends (thesis §5.3, §7.3).
    #[default]
    Voxel,
    /// Every VPL is visible (v = 1): the cost and the error of visibility, measured.
    None,
}

/// How the frame is shaded with the VPLs (Thiedemann 2010, §7.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum VplShading {
    /// One pass, every VPL of the pixel's set in a loop.
    #[default]
    Gather,
    /// One pass per VPL of a row, each adding its light to the image (the thesis's additive
    /// splatting, there with blending).
    Splat,
}

/// Parameters of the VPL method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VplSettings {
    /// VPLs per interleaving set and light (K).
    pub per_set: u32,
    /// Interleaving pattern N×M: N·M sets, each shading one pixel of every N×M tile.
    pub pattern: [u32; 2],
    /// d_min of E = I cosθ_VPL cosθ_P / (d_min + d²) (thesis §7.3), which bounds the
    /// singularity of a VPL next to a receiver, as a distance in voxel diagonals h:
    /// d_min = (d_min_voxels · h)² m². Relative to the grid, so that a scene renders the same
    /// in millimeters or kilometers (tests/extremes.rs).
    pub d_min_voxels: f32,
    pub visibility: VplVisibility,
    /// VPL generations: 1 = the lights' direct light reflected once, 2 adds one voxel ray per
    /// VPL (the thesis's maximum), up to [`VplSettings::MAX_BOUNCES`].
    pub bounces: u32,
    pub shading: VplShading,
    /// Debug view: draw every VPL as a dot over the lit image (`gi_vpl_points`).
    pub show: bool,
}

impl VplSettings {
    /// The most VPLs per set and light, and the largest pattern side.
    pub const MAX_PER_SET: u32 = 1024;
    pub const MAX_PATTERN: u32 = 16;
    /// The most VPL bounces (each adds one ray per VPL and a row segment).
    pub const MAX_BOUNCES: u32 = 8;
}

impl Default for VplSettings {
    fn default() -> Self {
        Self {
            per_set: 16,
            pattern: [4, 4],
            d_min_voxels: 8.0,
            visibility: VplVisibility::Voxel,
            bounces: 2,
            shading: VplShading::Gather,
            show: false,
        }
    }
}

/// VPL settings given by a scene's `[gi]` table or by flags; `None`: not given there
/// (see [`crate::scene::resolve_gi`] for the precedence).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VplOverrides {
    pub per_set: Option<u32>,
    pub pattern: Option<[u32; 2]>,
    pub bounces: Option<u32>,
    pub d_min_voxels: Option<f32>,
    pub visibility: Option<VplVisibility>,
}

impl VplOverrides {
    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: VplOverrides) -> VplOverrides {
        VplOverrides {
            per_set: self.per_set.or(fallback.per_set),
            pattern: self.pattern.or(fallback.pattern),
            bounces: self.bounces.or(fallback.bounces),
            d_min_voxels: self.d_min_voxels.or(fallback.d_min_voxels),
            visibility: self.visibility.or(fallback.visibility),
        }
    }

    /// `base` with the given values replaced.
    pub fn apply(&self, base: VplSettings) -> VplSettings {
        VplSettings {
            per_set: self.per_set.unwrap_or(base.per_set),
            pattern: self.pattern.unwrap_or(base.pattern),
            bounces: self.bounces.unwrap_or(base.bounces),
            d_min_voxels: self.d_min_voxels.unwrap_or(base.d_min_voxels),
            visibility: self.visibility.unwrap_or(base.visibility),
            shading: base.shading,
            show: base.show,
        }
    }
}

/// The names of [`VplVisibility`] in scene files and on the command line.
pub const VISIBILITY_NAMES: [(&str, VplVisibility); 2] = [
    ("voxel", VplVisibility::Voxel),
    ("none", VplVisibility::None),
];

/// Parses `--vpl-pattern NxM` (e.g. `4x4`).
pub fn parse_pattern(s: &str) -> Result<[u32; 2], String> {
    let bad = || {
        format!(
            "expected NxM with N and M in [1, {}], e.g. 4x4",
            VplSettings::MAX_PATTERN
        )
    };
    let (a, b) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let n: u32 = a.trim().parse().map_err(|_| bad())?;
    let m: u32 = b.trim().parse().map_err(|_| bad())?;
    let ok = |v: u32| (1..=VplSettings::MAX_PATTERN).contains(&v);
    if ok(n) && ok(m) {
        Ok([n, m])
    } else {
        Err(bad())
    }
}

/// One VPL (`GpuVpl` in `glsl/include/vpl.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVpl {
    /// xyz world position (m); w 1 valid, 0 invalid.
    pub position: [f32; 4],
    /// xyz unit normal of the sender.
    pub normal: [f32; 4],
    /// rgb diffusely reflected flux Φ_VPL (W); w the bounce.
    pub flux: [f32; 4],
    /// Phong senders: xyz the incident light's mirror direction, w the shininess.
    pub lobe: [f32; 4],
    /// Phong senders: rgb ρ_s Φ_in (W).
    pub specular: [f32; 4],
}

/// Push constants of `gi_vpl_generate` and `gi_vpl_bounce` (`glsl/include/vpl.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVplGeneratePush {
    pub world_to_voxel: [f32; 16],
    /// Voxels x, y, depth; w the top hierarchy level.
    pub dims: [i32; 4],
    /// Sets, lights, VPLs per set and light, bounces.
    pub counts: [u32; 4],
    /// Start level, max iterations, this pass's bounce, shadow-map resolution.
    pub trace: [u32; 4],
    /// Normal offset (voxel diagonals), voxel diagonal (m), ray length (m), unused.
    pub params: [f32; 4],
}

crate::push_constants!(GpuVplGeneratePush {
    world_to_voxel,
    dims,
    counts,
    trace,
    params
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

/// Push constants of `gi_vpl_points` (the debug view).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVplPointsPush {
    pub count: u32,
    pub radiance_w: f32,
}

crate::push_constants!(GpuVplPointsPush { count, radiance_w });

/// The sizes of the VPL buffer: `sets` rows of `bounces × lights × per_set` VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VplLayout {
    pub sets: u32,
    pub lights: u32,
    pub per_set: u32,
    pub bounces: u32,
}

impl VplLayout {
    /// VPLs in one row (one set).
    pub fn row(&self) -> u32 {
        self.bounces * self.lights * self.per_set
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
    /// The debug view's pipeline, when it is on.
    points: Option<ComputePipeline>,
    /// Albedo and normal volumes for bounces after the first.
    volumes: Option<TriangleAttributeVolumes>,
    layout: VplLayout,
    generate_push: GpuVplGeneratePush,
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
        let layout = VplLayout {
            sets: v.pattern[0].max(1) * v.pattern[1].max(1),
            lights: target.scene.lights.len() as u32,
            per_set: v.per_set.max(1),
            bounces,
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
        let generate = ctx.compute_pipeline(
            "gi_vpl_generate.comp",
            PushLayout::of::<GpuVplGeneratePush>(),
            &[],
        )?;
        let shader = match v.shading {
            VplShading::Gather => "gi_vpl_gather.comp",
            VplShading::Splat => "gi_vpl_splat.comp",
        };
        let gather = ctx.compute_pipeline(
            shader,
            PushLayout::of::<GpuVplGatherPush>(),
            &[(0, u32::from(target.has_phong))],
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
        let (bounce, volumes) = if bounces > 1 {
            let p = ctx.compute_pipeline(
                "gi_vpl_bounce.comp",
                PushLayout::of::<GpuVplGeneratePush>(),
                &[],
            )?;
            let vols = TriangleAttributeVolumes::new(
                ctx,
                target.scene,
                target.time_s,
                grid,
                target.atlas_attributes,
            )?;
            (Some(p), Some(vols))
        } else {
            (None, None)
        };
        Ok(Self {
            generate,
            bounce,
            gather,
            points,
            volumes,
            layout,
            generate_push,
            gather_push,
            shading: v.shading,
        })
    }

    /// The buffer layout (sets, lights, VPLs per set, bounces).
    pub fn layout(&self) -> VplLayout {
        self.layout
    }

    /// Moving objects: rewrites the attribute volumes; returns whether they changed.
    pub fn update(&mut self, t_s: f32, slot: usize) -> bool {
        self.volumes.as_mut().is_some_and(|v| v.update(t_s, slot))
    }

    /// Declares generation, bounces and the interleaved gather; returns the indirect
    /// irradiance (radiance for Phong pixels), unfiltered, and the VPL buffer (for
    /// [`VplPasses::add_points`]). `atlas_attributes` declares the atlas voxelizer's part of
    /// the attribute volumes.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        (lut, sampler): (BufferHandle, vk::Sampler),
        atlas_attributes: impl FnOnce(&mut RenderGraph, ImageHandle, ImageHandle),
    ) -> (ImageHandle, BufferHandle) {
        let vpls = g.create_buffer("vpls", self.layout.size_bytes());
        self.add_generate(g, i, vpls, sampler);
        if let (Some(pipe), Some(volumes)) = (self.bounce, &self.volumes) {
            let (albedo, normal) = volumes.add_passes(g, atlas_attributes);
            for b in 1..self.layout.bounces {
                self.add_bounce(g, (pipe, b), i, (lut, sampler), (albedo, normal), vpls);
            }
        }
        (self.add_gather(g, i, (lut, sampler), vpls), vpls)
    }

    /// The debug view, when on: draws the VPLs into `radiance` (the lit image).
    pub fn add_points(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        vpls: BufferHandle,
        radiance: ImageHandle,
        s: vk::Sampler,
    ) {
        let Some(pipe) = self.points else {
            return;
        };
        let count = self.layout.sets * self.layout.row();
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

    fn groups_1d(&self) -> u32 {
        self.layout.per_bounce().div_ceil(64).max(1)
    }

    fn add_generate(&self, g: &mut RenderGraph, i: &GiInputs, vpls: BufferHandle, s: vk::Sampler) {
        let c = Shader::Compute;
        let pipe = self.generate;
        let push = self.generate_push;
        let groups = self.groups_1d();
        g.add_pass("gi_vpl_generate")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.rlm_radiance, s, c)
            .bind_sampled(2, i.rlm_position, s, c)
            .bind_sampled(3, i.rlm_normal, s, c)
            .bind(4, vpls, Access::StorageWrite(c))
            .bind(5, i.materials, Access::StorageRead(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(groups, 1, 1);
            });
    }

    fn add_bounce(
        &self,
        g: &mut RenderGraph,
        (pipe, bounce): (ComputePipeline, u32),
        i: &GiInputs,
        (lut, s): (BufferHandle, vk::Sampler),
        (albedo, normal): (ImageHandle, ImageHandle),
        vpls: BufferHandle,
    ) {
        let c = Shader::Compute;
        let mut push = self.generate_push;
        push.trace[2] = bounce;
        let groups = self.groups_1d();
        g.add_pass(&format!("gi_vpl_bounce[{bounce}]"))
            .pipeline(&pipe)
            .bind_sampled(0, i.voxels, s, c)
            .bind(1, lut, Access::StorageRead(c))
            .bind_sampled(2, albedo, s, c)
            .bind_sampled(3, normal, s, c)
            .bind(4, vpls, Access::StorageReadWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
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
        let pipe = self.gather;
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

    pub fn destroy(self, ctx: &Context) {
        ctx.destroy_compute_pipeline(self.generate);
        ctx.destroy_compute_pipeline(self.gather);
        if let Some(p) = self.points {
            ctx.destroy_compute_pipeline(p);
        }
        if let Some(p) = self.bounce {
            ctx.destroy_compute_pipeline(p);
        }
        if let Some(v) = self.volumes {
            v.destroy(ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_fit_and_match_glsl() {
        assert_eq!(std::mem::size_of::<GpuVplGeneratePush>(), 128);
        assert_eq!(std::mem::size_of::<GpuVplGatherPush>(), 128);
        assert_eq!(std::mem::offset_of!(GpuVplGatherPush, d_min_m2), 104);
        assert_eq!(std::mem::size_of::<GpuVpl>(), 80);
    }

    #[test]
    fn pattern_parses_and_rejects() {
        assert_eq!(parse_pattern("4x4"), Ok([4, 4]));
        assert_eq!(parse_pattern("8X2"), Ok([8, 2]));
        for bad in ["4", "0x4", "4x17", "ax4", "", "4x4x4"] {
            let e = parse_pattern(bad).expect_err(bad);
            assert!(e.contains("NxM") && e.contains("[1, 16]"), "{bad}: {e}");
        }
    }

    #[test]
    fn buffer_rows_hold_every_bounce_of_every_light() {
        let l = VplLayout {
            sets: 16,
            lights: 2,
            per_set: 8,
            bounces: 2,
        };
        assert_eq!(l.row(), 32);
        assert_eq!(l.per_bounce(), 256);
        assert_eq!(l.size_bytes(), 16 * 32 * 80);
        let none = VplLayout { lights: 0, ..l };
        assert_eq!(none.size_bytes(), 80, "never an empty buffer");
    }
}
