//! What the GI ray passes share (`glsl/include/gi_common.glsl`): their push constants and the
//! declaration of their common bindings.

use super::{GiInputs, GiSettings, GiTarget};
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::Bounces;
use crate::vk::{vk, PipelineHandle};
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::AtomicU32;
use std::sync::Arc;

/// Push constants of the GI passes (`GiPush` in `glsl/include/gi_common.glsl`, checked against
/// it by name, offset and size when each pipeline is created).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuGiPush {
    pub world_to_voxel: [f32; 16],
    /// Voxels along x, y and depth.
    pub dims: [i32; 3],
    /// The highest mip level of the hierarchy.
    pub max_level: i32,
    /// Ray length.
    pub radius_m: f32,
    /// Self-intersection offset along the normal, k₁ (Thiedemann 2010 §5.3.1).
    pub normal_offset_voxels: f32,
    /// Light-map hit tolerance (plus the map texel's footprint).
    pub hit_tolerance_voxels: f32,
    pub voxel_diagonal_m: f32,
    /// Rays per pixel.
    pub rays: u32,
    /// Mip level the traversal starts at.
    pub start_level: u32,
    /// Traversal steps before a ray gives up.
    pub max_iterations: u32,
    /// Seed of the per-pixel rotation; the path tracer puts the frames accumulated before the
    /// one it records here (its sample index).
    pub seed: u32,
    /// Light-map texel footprint scale: shadow-map resolution over light-map resolution.
    pub light_map_scale: f32,
    /// Path-tracer bounces, 0 for unbounded (`bounces_push_value`).
    pub bounces: u32,
    /// Self-intersection offset along the ray, k₂ · h / (d·n) (Thiedemann 2010 §5.3.1).
    pub ray_offset_voxels: f32,
    /// The clamp of that offset.
    pub ray_offset_max_voxels: f32,
}

crate::push_constants!(GpuGiPush {
    world_to_voxel,
    dims,
    max_level,
    radius_m,
    normal_offset_voxels,
    hit_tolerance_voxels,
    voxel_diagonal_m,
    rays,
    start_level,
    max_iterations,
    seed,
    light_map_scale,
    bounces,
    ray_offset_voxels,
    ray_offset_max_voxels,
});

// Also a buffer's contents: `oit_gather_indirect.frag` reads the path tracer's parameters
// from one (its push constants hold the draw).
crate::gpu_struct!(GpuGiPush {
    world_to_voxel,
    dims,
    max_level,
    radius_m,
    normal_offset_voxels,
    hit_tolerance_voxels,
    voxel_diagonal_m,
    rays,
    start_level,
    max_iterations,
    seed,
    light_map_scale,
    bounces,
    ray_offset_voxels,
    ray_offset_max_voxels,
});

impl GpuGiPush {
    /// The push constants of `settings` on `target`'s grid; the ray length defaults to the
    /// scene's diagonal (unbounded in practice).
    pub fn new(settings: &GiSettings, target: &GiTarget<'_>) -> Self {
        let grid = target.grid;
        let scene_diagonal_m = target.scene.aabb_at(target.time_s).extent().length();
        let ext = grid.extent_voxels();
        let levels = crate::voxel::bits::mip_count(grid.res_x(), grid.res_y());
        Self {
            world_to_voxel: grid.world_to_voxel_matrix().to_cols_array(),
            dims: [ext.x as i32, ext.y as i32, ext.z as i32],
            max_level: levels as i32 - 1,
            radius_m: settings.radius_m.unwrap_or(scene_diagonal_m),
            normal_offset_voxels: settings.normal_offset_voxels,
            hit_tolerance_voxels: settings.hit_tolerance_voxels,
            voxel_diagonal_m: grid.voxel_diagonal_m(),
            rays: settings.rays,
            start_level: settings.start_level,
            max_iterations: settings.max_iterations,
            seed: settings.seed,
            light_map_scale: target.shadow_resolution as f32
                / settings.light_map_resolution.max(1) as f32,
            bounces: bounces_push_value(settings.bounces),
            ray_offset_voxels: settings.ray_offset_voxels,
            ray_offset_max_voxels: settings.ray_offset_max_voxels,
        }
    }
}

/// `GpuGiPush::bounces`: the count (clamped to [1, [`Bounces::MAX`]]), or 0 for unbounded.
pub fn bounces_push_value(b: Bounces) -> u32 {
    match b {
        Bounces::Fixed(n) => n.clamp(1, Bounces::MAX),
        Bounces::Unbounded => 0,
    }
}

/// What every GI method's passes get from the assembly (`GiPasses`) in a frame.
pub struct GiShared {
    /// The ray-mask lookup table (binding 4 of the ray passes).
    pub lut: BufferHandle,
    pub sampler: vk::Sampler,
    pub push: GpuGiPush,
    /// Frames accumulated since the last restart, counting the one being recorded.
    pub frames: Arc<AtomicU32>,
    /// Under temporal accumulation (`gi.temporal`): frames recorded so far, counting the one
    /// being recorded, by which the sample pattern advances ([`GiShared::seed`]).
    pub sample_index: Option<Arc<AtomicU32>>,
    /// The albedo, normal and (scenes with emitters) emission volumes, already written this
    /// frame, for the methods that read them ([`super::GiPasses::needs_attribute_volumes`]).
    pub attributes: Option<crate::voxel::attributes::AttributeHandles>,
    /// The stereo eye whose passes are declared (0: left or mono, 1: right): selects the
    /// method's per-eye history.
    pub eye: u32,
    /// What the method's view-independent passes produced this frame
    /// ([`super::GiMethodPasses::add_world_passes`]), shared by both stereo eyes.
    pub world: super::MethodWorld,
}

impl GiShared {
    /// The push constants' seed at record time: `push.seed`, advanced by the frame's index
    /// under temporal accumulation (so that frames sample other directions and their mean
    /// converges), fixed otherwise.
    pub fn seed(&self) -> impl Fn() -> u32 + 'static {
        let base = self.push.seed;
        let index = self.frame_index();
        move || base.wrapping_add(index())
    }

    /// At record time, the frame's index under temporal accumulation (0 for the first frame
    /// since the history was reset), 0 otherwise.
    pub fn frame_index(&self) -> impl Fn() -> u32 + Clone + 'static {
        let index = self.sample_index.clone();
        move || match &index {
            // Counting the frame being recorded: the first frame samples as an accumulating
            // path tracer's first frame does.
            Some(i) => i.load(std::sync::atomic::Ordering::SeqCst).wrapping_sub(1),
            None => 0,
        }
    }
}

/// Declares one of the GI ray passes (`gi_hemisphere`, `gi_hemisphere_volume`,
/// `gi_pathtrace`): they share the frame, G-buffer, voxel and ray-mask inputs (bindings 0-4)
/// and the specular and albedo images (9, 10), and the environment map (15; the albedo image
/// where the scene has none, which the shaders then never read); `own` are the pass's further sampled images by
/// binding, `out` its output image at binding 8, `buffers` its storage buffers (read) by
/// binding, and `push` its push constants at record time.
#[allow(clippy::too_many_arguments)]
pub fn add_ray_pass(
    g: &mut RenderGraph,
    name: &str,
    pipe: PipelineHandle,
    i: &GiInputs,
    shared: &GiShared,
    own: &[(u32, ImageHandle)],
    (out, out_access): (ImageHandle, Access),
    buffers: &[(u32, BufferHandle)],
    push: impl Fn() -> GpuGiPush + 'static,
) {
    let c = Shader::Compute;
    let sampler = shared.sampler;
    let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
    // Without Phong materials the shaders never read their specular binding; albedo fills it.
    let specular = i.specular.unwrap_or(i.albedo);
    let mut pass = g
        .add_pass(name)
        .pipeline(&pipe)
        .bind(0, i.frame, Access::StorageRead(c))
        .bind_sampled(1, i.normal, sampler, c)
        .bind_sampled(2, i.depth, sampler, c)
        .bind_sampled(3, i.voxels, sampler, c)
        .bind(4, shared.lut, Access::StorageRead(c))
        .bind(8, out, out_access)
        .bind_sampled(9, specular, sampler, c)
        .bind_sampled(10, i.albedo, sampler, c)
        .bind_sampled(
            15,
            i.environment_map.unwrap_or(i.albedo),
            i.environment_sampler,
            c,
        );
    for &(b, h) in own {
        pass = pass.bind_sampled(b, h, sampler, c);
    }
    for &(b, buffer) in buffers {
        pass = pass.bind(b, buffer, Access::StorageRead(c));
    }
    pass.record(move |ctx| {
        ctx.bind(&pipe);
        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push()));
        ctx.cmd.dispatch(groups.0, groups.1, 1);
    });
}

/// Push constants of `gi_vpl_generate` and `gi_vpl_bounce` (`glsl/include/vpl.glsl`), and of
/// `gi_vpl_emit`, which generates the emitters' VPLs the same way.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The block must fit the 128 bytes every Vulkan device accepts, and every GI shader
    /// declares it with the Rust names, offsets and sizes (what creating a pipeline checks).
    #[test]
    fn push_constants_fit_and_match_glsl() {
        assert_eq!(
            std::mem::size_of::<GpuGiPush>(),
            128,
            "the Vulkan minimum push-constant size"
        );
        for shader in [
            "gi_hemisphere.comp",
            "gi_hemisphere_emission.comp",
            "gi_hemisphere_volume.comp",
            "gi_pathtrace.comp",
            "gi_radiance_volume.comp",
        ] {
            crate::vk::check_push_against(&[shader], crate::vk::PushLayout::of::<GpuGiPush>())
                .unwrap_or_else(|e| panic!("{shader}: {e}"));
        }
    }

    #[test]
    fn bounces_encode_as_before_the_unbounded_setting() {
        for n in [1, 2, 3, 8, Bounces::MAX] {
            assert_eq!(bounces_push_value(Bounces::Fixed(n)), n);
        }
        assert_eq!(bounces_push_value(Bounces::Fixed(Bounces::MAX + 1)), 64);
        assert_eq!(bounces_push_value(Bounces::Unbounded), 0);
    }
}
