//! Debug views of the GPU voxel grid (`glsl/voxel_debug.comp`, pass `voxel_debug`): camera
//! rays cast through the column image's OR hierarchy with the GLSL traversal library.
//!
//! - [`DebugView::Voxels`]: hierarchical first hit, shaded by the entered face's normal
//!   (N·L with a fixed light over the camera's shoulder, edges darkened).
//! - [`DebugView::Steps`]: the traversal's loop iterations per pixel on a heat ramp (black 0 →
//!   red → yellow → white at `steps_scale`); the value image holds the raw counts.
//! - [`DebugView::Level`]: occupancy of one hierarchy level, walked exactly (blocks of
//!   2^ℓ × 2^ℓ voxels, one voxel deep).
//! - [`DebugView::Albedo`]: hierarchical first hit; the value image holds the albedo volume
//!   at the hit voxel (linear), the color image that albedo half shaded like the voxels
//!   view. Only this view creates the albedo volume ([`TriangleAttributeVolumes`]); the others bind
//!   a tiny placeholder in its slot. Its voxels are the triangle voxelizer's, so bits that
//!   only the atlas voxelizer sets show black.
//!
//! The pass writes an `RGBA32F` value image (shade, step count, occupancy or albedo: what
//! tests and `--exr` read) and the `RGBA8` color image the renderer reads back as its picture.

use super::attributes::{TriangleAttributeVolumes, ATTRIBUTE_VOLUME_STATE};
use super::frame::VoxelFrame;
use super::gpu::GpuVoxelError;
use super::ray_mask::RayMaskLut;
use super::traverse::TraversalParams;
use super::VoxelGrid;
use crate::eval::HdrImage;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{vk, Buffer, ComputePipeline, Context, Image, ImageDesc, VkError};
use glam::{Mat4, Vec3};

/// Which debug view a frame shows instead of the lit image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum DebugView {
    /// Ray-cast voxels shaded by their face normals.
    #[default]
    Voxels,
    /// Hierarchical traversal steps per pixel (heat ramp).
    Steps,
    /// Occupancy of one hierarchy level.
    Level,
    /// Ray-cast voxels colored by the albedo volume.
    Albedo,
    /// One object's position atlas (`--object`; see [`super::atlas_view`]).
    Atlas,
    /// The G-buffer's albedo (drawn by the renderer's `gbuffer_view` pass).
    GbufferAlbedo,
    /// The G-buffer's world-space normal, (n + 1) / 2 as color.
    GbufferNormal,
    /// The distance from the camera of the G-buffer's surface.
    GbufferDistance,
    /// Shadow aliasing: the predicted on-screen size in pixels of the shadow-map texel that
    /// shades each pixel (drawn by the renderer's `shadow_texels` pass).
    ShadowTexels,
    /// Its perspective part only, d_s·r_s/r_i: the aliasing a finer map removes, without the
    /// projective factor cos α_i / cos α_s, which is unbounded where light grazes a surface
    /// and which no resolution fixes (what `--shadow-resolution auto` sizes for).
    ShadowTexelsPerspective,
}

impl DebugView {
    fn shader_mode(self) -> u32 {
        match self {
            DebugView::Voxels => 0,
            DebugView::Steps => 1,
            DebugView::Level => 2,
            DebugView::Albedo => 3,
            // Drawn by `atlas_debug` (super::atlas_view) or the renderer's `gbuffer_view`,
            // never by `voxel_debug`.
            DebugView::Atlas
            | DebugView::GbufferAlbedo
            | DebugView::GbufferNormal
            | DebugView::GbufferDistance
            | DebugView::ShadowTexels
            | DebugView::ShadowTexelsPerspective => 0,
        }
    }

    /// Whether the view shows the voxel grid (and so needs a voxelization).
    pub fn shows_voxels(self) -> bool {
        matches!(
            self,
            DebugView::Voxels | DebugView::Steps | DebugView::Level | DebugView::Albedo
        )
    }
}

/// A debug view with its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DebugSettings {
    pub view: DebugView,
    /// Hierarchy level of [`DebugView::Level`].
    pub level: u32,
    /// Traversal parameters of the voxels and steps views.
    pub traversal: TraversalParams,
    /// Step count shown white by [`DebugView::Steps`].
    pub steps_scale: u32,
    /// Scene object index whose atlas [`DebugView::Atlas`] shows.
    pub object: usize,
}

impl Default for DebugSettings {
    fn default() -> Self {
        Self {
            view: DebugView::Voxels,
            level: 0,
            traversal: TraversalParams::default(),
            steps_scale: 64,
            object: 0,
        }
    }
}

/// Push constants of `voxel_debug.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVoxelDebugPush {
    /// Vulkan NDC (z 0 = near, 1 = far) → continuous voxel coordinates, column-major.
    pub ndc_to_voxel: [f32; 16],
    /// Voxels `(res_x, res_y, D)`, coarsest level.
    pub dims: [i32; 4],
    /// The view ([`DebugView::shader_mode`]).
    pub mode: u32,
    /// The hierarchy level the level view shows.
    pub level: u32,
    pub max_iterations: u32,
    pub start_level: u32,
    /// Unit light direction in voxel axes, steps at the top of the heat ramp.
    pub light: [f32; 4],
}

crate::push_constants!(GpuVoxelDebugPush {
    ndc_to_voxel,
    dims,
    mode,
    level,
    max_iterations,
    start_level,
    light
});

impl GpuVoxelDebugPush {
    /// `view_proj` is the camera's world → clip matrix; `light_dir` the world direction
    /// towards the light.
    pub fn new(
        grid: &VoxelGrid,
        levels: u32,
        view_proj: Mat4,
        light_dir: Vec3,
        s: &DebugSettings,
    ) -> Self {
        let ext = grid.extent_voxels();
        // The permutation of world axes into voxel axes (no scale): normals are axis-aligned.
        let light =
            (grid.dir_world_to_voxel(light_dir) / grid.voxels_per_meter()).normalize_or_zero();
        Self {
            ndc_to_voxel: (grid.world_to_voxel_matrix() * view_proj.inverse()).to_cols_array(),
            dims: [
                ext.x as i32,
                ext.y as i32,
                ext.z as i32,
                levels.saturating_sub(1) as i32,
            ],
            mode: s.view.shader_mode(),
            level: s.level,
            max_iterations: s.traversal.max_iterations,
            start_level: s.traversal.start_level,
            light: [light.x, light.y, light.z, s.steps_scale.max(1) as f32],
        }
    }
}

/// The pipeline, ray-mask LUT (uploaded once) and push constants of a debug view, and what
/// it samples as albedo: the albedo volume in the albedo view, else a placeholder.
pub struct VoxelDebugPass {
    pipeline: ComputePipeline,
    lut: Buffer,
    sampler: crate::vk::Sampler,
    push: GpuVoxelDebugPush,
    albedo: AlbedoSource,
}

/// Binding 4 of `voxel_debug.comp`.
enum AlbedoSource {
    Volumes(Box<TriangleAttributeVolumes>),
    /// 1×1×2, never read: the shader reads albedo in the albedo view only.
    Placeholder(Image),
}

impl VoxelDebugPass {
    /// The debug view of `frame`'s grid seen by `scene`'s camera (`aspect` = width / height),
    /// lit from over the camera's shoulder; the albedo view voxelizes `scene`'s albedo at
    /// `time_s`.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        aspect: f32,
        settings: &DebugSettings,
        frame: &VoxelFrame,
    ) -> Result<Self, GpuVoxelError> {
        let camera = &scene.camera;
        let levels = frame.voxels.mip_levels();
        if settings.level >= levels {
            return Err(GpuVoxelError::BadDebugLevel {
                level: settings.level,
                max: levels - 1,
            });
        }
        let right = camera.forward.cross(camera.up).normalize_or_zero();
        let up = right.cross(camera.forward);
        let light = -camera.forward + 0.6 * up - 0.4 * right;
        let push = GpuVoxelDebugPush::new(
            &frame.voxels.grid,
            levels,
            camera.view_proj(aspect),
            light,
            settings,
        );
        let albedo = AlbedoSource::new(ctx, scene, time_s, settings.view, frame)?;
        let (pipeline, lut, sampler) = Self::pipeline_parts(ctx)?;
        Ok(Self {
            pipeline,
            lut,
            sampler,
            push,
            albedo,
        })
    }

    /// For scenes with moving objects: rewrites the albedo volume of frame slot `slot` at
    /// `t_s` when they moved (albedo view only).
    pub fn update(&mut self, t_s: f32, slot: usize) {
        if let AlbedoSource::Volumes(v) = &mut self.albedo {
            v.update(t_s, slot);
        }
    }

    /// Takes the dynamic objects' transforms from `scene` (albedo view only).
    pub fn follow_objects(&mut self, scene: &crate::scene::Scene) {
        if let AlbedoSource::Volumes(v) = &mut self.albedo {
            v.follow_objects(scene);
        }
    }

    fn pipeline_parts(
        ctx: &Context,
    ) -> Result<(ComputePipeline, Buffer, crate::vk::Sampler), VkError> {
        let lut = ctx.upload_buffer(
            "ray mask lut",
            &RayMaskLut::new().to_gpu_bytes(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let pipeline = ctx.compute_pipeline(
            "voxel_debug.comp",
            crate::vk::PushLayout::of::<GpuVoxelDebugPush>(),
            &[],
        );
        let pipeline = pipeline?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        Ok((pipeline, lut, sampler))
    }

    /// Declares `voxel_debug`: reads the column image `columns` (every mip) and the albedo
    /// (after `voxelize_attributes` in the albedo view) and writes `value` (`RGBA32F`) and
    /// `color` (`RGBA8`), both `extent` pixels.
    pub fn add_pass(
        &self,
        g: &mut RenderGraph,
        frame: &VoxelFrame,
        columns: ImageHandle,
        value: ImageHandle,
        color: ImageHandle,
        extent: (u32, u32),
    ) {
        let push = self.push;
        debug_assert_eq!(push.dims[3] as u32 + 1, frame.voxels.mip_levels());
        let read = Access::StorageRead(Shader::Compute);
        let lut = g.import_buffer(&self.lut, read);
        let pipe = *self.pipeline;
        let sampler = self.sampler.raw;
        let albedo = match &self.albedo {
            AlbedoSource::Volumes(v) => {
                v.add_passes(g, |g, volumes| frame.add_attribute_passes(g, volumes))
                    .albedo
            }
            AlbedoSource::Placeholder(image) => g.import_image(image, ATTRIBUTE_VOLUME_STATE),
        };
        let c = Shader::Compute;
        g.add_pass("voxel_debug")
            .pipeline(&pipe)
            .bind_sampled(0, columns, sampler, c)
            .bind(1, lut, Access::StorageRead(c))
            .bind(2, value, Access::StorageWrite(c))
            .bind(3, color, Access::StorageWrite(c))
            .bind_sampled(4, albedo, sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd
                    .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), 1);
            });
    }
}

impl AlbedoSource {
    fn new(
        ctx: &Context,
        scene: &Scene,
        time_s: f32,
        view: DebugView,
        frame: &VoxelFrame,
    ) -> Result<Self, VkError> {
        if view == DebugView::Albedo {
            let grid = &frame.voxels.grid;
            return Ok(Self::Volumes(Box::new(TriangleAttributeVolumes::new(
                ctx,
                scene,
                time_s,
                grid,
                frame.has_attribute_volumes(),
                super::attributes::ValueVolumes::albedo_only(scene),
            )?)));
        }
        // Two texels deep: `ImageDesc` makes a 3D image (the shader's sampler3D) only for
        // depth > 1.
        let desc = ImageDesc::new_2d("albedo placeholder", vk::Format::R8G8B8A8_UNORM, 1, 1)
            .with_depth(2)
            .with_usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST);
        let image = ctx.create_image(&desc)?;
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        ctx.clear_new_image(&image, zero, ATTRIBUTE_VOLUME_STATE.info().layout)?;
        Ok(Self::Placeholder(image))
    }
}

/// What a debug view's value image says, pixel statistics for the CLI and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DebugStats {
    pub pixels: usize,
    /// Pixels whose ray hit a voxel.
    pub hits: usize,
    /// Steps view: rays the iteration cap ended.
    pub ran_out: usize,
    /// Steps view: mean and largest step count over every pixel.
    pub mean_steps: f64,
    pub max_steps: u32,
}

/// Statistics of the value image of a debug view (see the module doc for its channels).
pub fn debug_stats(view: DebugView, value: &HdrImage) -> DebugStats {
    let mut s = DebugStats {
        pixels: value.data.len(),
        ..Default::default()
    };
    let mut sum = 0.0;
    for p in &value.data {
        if view == DebugView::Steps {
            let steps = p[0].max(0.0) as u32;
            sum += f64::from(steps);
            s.max_steps = s.max_steps.max(steps);
            s.hits += usize::from(p[1] > 0.5);
            s.ran_out += usize::from(p[2] > 0.5);
        } else if view == DebugView::Atlas {
            s.hits += usize::from(p[0] > 0.5);
        } else if view == DebugView::Albedo {
            // Albedo: a hit on a black voxel reads as a miss.
            s.hits += usize::from(p.iter().any(|&c| c > 0.0));
        } else {
            s.hits += usize::from(p[0] > 0.0);
        }
    }
    s.mean_steps = if s.pixels > 0 {
        sum / s.pixels as f64
    } else {
        0.0
    };
    s
}

/// A few lines for the CLI: what the colors mean and what the view measured.
pub fn describe(settings: &DebugSettings, value: &HdrImage) -> String {
    let st = debug_stats(settings.view, value);
    let hit_share = 100.0 * st.hits as f64 / st.pixels.max(1) as f64;
    match settings.view {
        DebugView::Voxels => format!(
            "voxels view: {hit_share:.1}% of pixels hit a voxel (shade = N·L of the entered face)"
        ),
        DebugView::Steps => {
            let top = settings.steps_scale.max(1);
            format!(
                "steps view: heat ramp black = 0, red = {}, yellow = {}, white >= {top} steps\n\
                 steps per pixel: mean {:.2}, max {} (cap {}); {hit_share:.1}% hit, {} ran out",
                top / 3,
                2 * top / 3,
                st.mean_steps,
                st.max_steps,
                settings.traversal.max_iterations,
                st.ran_out
            )
        }
        DebugView::Albedo => format!(
            "albedo view: {hit_share:.1}% of pixels hit a voxel with albedo (color = albedo, half \
             shaded; the value image holds the albedo)"
        ),
        DebugView::Atlas => {
            let cov = super::atlas_view::atlas_coverage(value);
            format!(
                "atlas view: {} valid of {} texels shown (black = invalid)",
                cov.valid, cov.shown
            )
        }
        DebugView::Level => format!(
            "level {} view: blocks of {n}x{n}x1 voxels; {hit_share:.1}% of pixels hit",
            settings.level,
            n = 1u32 << settings.level.min(31)
        ),
        // Described by the renderer's `gbuffer_view` / `shadow_texels` pass.
        DebugView::GbufferAlbedo
        | DebugView::GbufferNormal
        | DebugView::GbufferDistance
        | DebugView::ShadowTexels
        | DebugView::ShadowTexelsPerspective => {
            format!("{:?} view", settings.view)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_layout_matches_the_shader() {
        crate::vk::check_push_against(
            &["voxel_debug.comp"],
            crate::vk::PushLayout::of::<GpuVoxelDebugPush>(),
        )
        .unwrap();
        // Within the 128 bytes of push constants every device offers.
        assert!(std::mem::size_of::<GpuVoxelDebugPush>() <= 128);
    }

    #[test]
    fn ndc_maps_into_voxel_space() {
        // A camera looking at the grid's center: the center pixel's ray passes through the
        // grid center, and the light direction is a unit vector.
        let grid = VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, None, 64, 64, 1).expect("grid");
        let view = glam::camera::rh::view::look_at_mat4(
            Vec3::new(0.5, 0.5, 3.0),
            Vec3::splat(0.5),
            Vec3::Y,
        );
        let proj = glam::camera::rh::proj::directx::perspective(1.0, 1.0, 0.1, 10.0);
        let push = GpuVoxelDebugPush::new(
            &grid,
            7,
            proj * view,
            Vec3::new(1.0, 2.0, 3.0),
            &DebugSettings::default(),
        );
        let m = Mat4::from_cols_array(&push.ndc_to_voxel);
        let a = m.project_point3(Vec3::new(0.0, 0.0, 0.0));
        let b = m.project_point3(Vec3::new(0.0, 0.0, 1.0));
        let center = grid.world_to_voxel(Vec3::splat(0.5));
        let d = (b - a).normalize();
        let closest = a + d * (center - a).dot(d);
        assert!((closest - center).length() < 1e-2, "{closest} vs {center}");
        assert!((Vec3::from_slice(&push.light[..3]).length() - 1.0).abs() < 1e-5);
        assert_eq!(push.dims, [64, 64, 128, 6]);
    }
}
