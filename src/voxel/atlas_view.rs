//! The atlas debug view (`voxgi render --debug atlas [--object NAME_OR_INDEX]`): one object's
//! automatic atlas ([`super::atlas`]) as the atlas voxelizer renders it.
//!
//! Each frame declares `atlas_positions` (the voxelizer's own pass, into a transient position
//! atlas) and `atlas_debug` (`glsl/atlas_debug.comp`), which draws the atlas from the image's
//! top-left corner at the largest integer zoom that fits (or every n-th texel of an atlas
//! larger than the image). Colors: a valid texel's model-space position normalized to the
//! mesh's box (r, g, b = x, y, z), invalid texels black, pixels past the atlas dark gray.
//! The value image holds `(1 valid / 0 invalid, texel x, texel y)` inside the atlas and
//! `-1` past it, so a read-back counts the GPU's valid texels exactly (zoom ≥ 1).
//!
//! Texels are sized for the grid the scene would be voxelized into (the view's
//! [`super::gpu::VoxelSettings`]), like the voxelizer's, but no voxel pass runs.

use super::atlas::{texel_size_for_voxel, AtlasCache, MeshAtlas};
use super::gpu::GpuVoxelError;
use super::gpu_atlas::{
    add_atlas_positions_pass, atlas_frames, gpu_atlas_triangles, AtlasPipelines,
};
use super::VoxelGrid;
use crate::eval::HdrImage;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::scene::{NoSuchObject, Scene};
use crate::vk::{vk, Buffer, ComputePipeline, Context, VkError};
use glam::Vec3;
use std::sync::Arc;

/// Push constants of `atlas_debug.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuAtlasDebugPush {
    /// Atlas width and height in texels; texel = pixel · den / num: num, den.
    pub atlas_zoom: [u32; 4],
    /// The mesh's model-space box: minimum corner, and 1 / extent (0 on flat axes).
    pub box_min: [f32; 4],
    pub box_scale: [f32; 4],
}

crate::push_constants!(GpuAtlasDebugPush {
    atlas_zoom,
    box_min,
    box_scale
});

/// `(num, den)` mapping image pixels to atlas texels (`texel = pixel · den / num`): the largest
/// integer zoom at which a `atlas` atlas fits into `image` pixels, else the smallest integer
/// reduction.
pub fn atlas_zoom(atlas: (u32, u32), image: (u32, u32)) -> (u32, u32) {
    let (aw, ah) = (atlas.0.max(1), atlas.1.max(1));
    let (w, h) = (image.0.max(1), image.1.max(1));
    let zoom = (w / aw).min(h / ah);
    if zoom >= 1 {
        (zoom, 1)
    } else {
        (1, aw.div_ceil(w).max(ah.div_ceil(h)))
    }
}

/// The atlas of object `index` for voxels of `grid`, as the atlas voxelizer builds it.
pub fn object_atlas(
    scene: &Scene,
    t_s: f32,
    grid: &VoxelGrid,
    index: usize,
    cache: &mut AtlasCache,
) -> Result<Arc<MeshAtlas>, GpuVoxelError> {
    let object = scene
        .objects
        .get(index)
        .ok_or_else(|| NoSuchObject::new(scene, &index.to_string()))?;
    // One atlas for all frames of an OBJ sequence, as AtlasScene builds it.
    let no_atlas = || GpuVoxelError::NoAtlas {
        object: object.name.clone(),
    };
    let frames: Vec<&crate::scene::Mesh> = atlas_frames(scene, object)
        .map_err(|_| no_atlas())?
        .iter()
        .filter_map(|&m| scene.meshes.get(m))
        .collect();
    let mesh = frames.first().ok_or_else(no_atlas)?;
    let positions: Vec<&[Vec3]> = frames.iter().map(|m| m.positions.as_slice()).collect();
    let texel_m = texel_size_for_voxel(grid.voxel_size_m().min_element());
    let scale = object.transform_components_at(t_s).scale;
    Ok(cache.get_sequence(&mesh.name, &positions, &mesh.indices, scale, texel_m)?)
}

/// The atlas view's pipelines, the object's atlas triangles and its push constants.
pub struct AtlasViewPass {
    atlas_pipelines: AtlasPipelines,
    pipeline: ComputePipeline,
    sampler: crate::vk::Sampler,
    triangles: Buffer,
    triangle_count: u32,
    atlas: Arc<MeshAtlas>,
    object: String,
    box_min: Vec3,
    box_scale: Vec3,
}

impl AtlasViewPass {
    /// The atlas of `scene`'s object `index` at `t_s`, texels sized for `grid`.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        grid: &VoxelGrid,
        index: usize,
    ) -> Result<Self, GpuVoxelError> {
        let atlas = object_atlas(scene, t_s, grid, index, &mut AtlasCache::default())?;
        // object_atlas found both; a sequence shows its frame at t_s.
        let (Some(object), Some(mesh)) = (
            scene.objects.get(index),
            scene
                .objects
                .get(index)
                .and_then(|o| scene.meshes.get(o.mesh_at(t_s))),
        ) else {
            return Err(NoSuchObject::new(scene, &index.to_string()).into());
        };
        let tris = gpu_atlas_triangles(&atlas, &mesh.positions, &mesh.indices);
        let lo = mesh.positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = mesh
            .positions
            .iter()
            .fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let extent = hi - lo;
        let box_scale = Vec3::select(extent.cmpgt(Vec3::ZERO), extent.recip(), Vec3::ZERO);
        let atlas_pipelines = AtlasPipelines::new(ctx)?;
        let parts = (|| -> Result<_, VkError> {
            let pipeline = ctx.compute_pipeline(
                "atlas_debug.comp",
                crate::vk::PushLayout::of::<GpuAtlasDebugPush>(),
                &[],
            )?;
            let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
            let bytes: &[u8] = if tris.is_empty() {
                &[0; std::mem::size_of::<super::gpu_atlas::GpuAtlasTriangle>()]
            } else {
                bytemuck::cast_slice(&tris)
            };
            let b = ctx.upload_buffer(
                "atlas view triangles",
                bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?;
            Ok((pipeline, sampler, b))
        })();
        let (pipeline, sampler, triangles) = parts?;
        Ok(Self {
            atlas_pipelines,
            pipeline,
            sampler,
            triangles,
            triangle_count: tris.len() as u32,
            atlas,
            object: object.name.clone(),
            box_min: lo,
            box_scale,
        })
    }

    /// The atlas shown.
    pub fn atlas(&self) -> &MeshAtlas {
        &self.atlas
    }

    /// Declares `atlas_positions` and `atlas_debug`, writing `value` (`RGBA32F`) and `color`
    /// (`RGBA8`), both `extent` pixels.
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        value: ImageHandle,
        color: ImageHandle,
        extent: (u32, u32),
    ) {
        let read = Access::StorageRead(Shader::Graphics);
        let tris = g.import_buffer(&self.triangles, read);
        let size = (self.atlas.width.max(1), self.atlas.height.max(1));
        let atlas =
            add_atlas_positions_pass(g, &self.atlas_pipelines, tris, self.triangle_count, size);
        let (num, den) = atlas_zoom(size, extent);
        let push = GpuAtlasDebugPush {
            atlas_zoom: [size.0, size.1, num, den],
            box_min: self.box_min.extend(0.0).to_array(),
            box_scale: self.box_scale.extend(0.0).to_array(),
        };
        let (pipe, sampler) = (*self.pipeline, self.sampler.raw);
        let c = Shader::Compute;
        g.add_pass("atlas_debug")
            .pipeline(&pipe)
            .bind_sampled(0, atlas, sampler, c)
            .bind(1, value, Access::StorageWrite(c))
            .bind(2, color, Access::StorageWrite(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd
                    .dispatch(extent.0.div_ceil(8), extent.1.div_ceil(8), 1);
            });
    }

    /// A few lines for the CLI: which atlas, and its coverage as the GPU drew it.
    pub fn describe(&self, value: &HdrImage) -> String {
        let cov = atlas_coverage(value);
        let a = &self.atlas;
        let cpu: usize = (0..a.triangles.len()).map(|t| a.texels(t).len()).sum();
        format!(
            "atlas view: object '{}', {}x{} texels of {:.2} mm, {} triangles; {} valid texels \
             shown ({:.1}% of those shown; the CPU coverage rule gives {cpu}); colors = \
             model-space position in the mesh's box, black = invalid",
            self.object,
            a.width,
            a.height,
            a.texel_m * 1e3,
            a.triangles.len(),
            cov.valid,
            100.0 * cov.valid as f64 / cov.shown.max(1) as f64,
        )
    }
}

/// Distinct atlas texels an atlas-view value image shows, and how many of them are valid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AtlasCoverage {
    pub shown: usize,
    pub valid: usize,
}

/// The distinct texels of an atlas view's value image (see the module doc).
pub fn atlas_coverage(value: &HdrImage) -> AtlasCoverage {
    let mut seen = std::collections::HashMap::new();
    for p in &value.data {
        if p[0] >= 0.0 {
            seen.insert((p[1] as u32, p[2] as u32), p[0] > 0.5);
        }
    }
    AtlasCoverage {
        shown: seen.len(),
        valid: seen.values().filter(|&&v| v).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_layout_matches_the_shader() {
        crate::vk::check_push_against(
            &["atlas_debug.comp"],
            crate::vk::PushLayout::of::<GpuAtlasDebugPush>(),
        )
        .unwrap();
    }

    #[test]
    fn the_atlas_is_zoomed_by_whole_factors() {
        assert_eq!(atlas_zoom((100, 50), (320, 240)), (3, 1));
        assert_eq!(atlas_zoom((100, 50), (100, 50)), (1, 1));
        // Larger than the image: every den-th texel, so the whole atlas still shows.
        let (num, den) = atlas_zoom((700, 300), (256, 256));
        assert_eq!((num, den), (1, 3));
        assert!(255 * den / num >= 700 - den);
        assert_eq!(atlas_zoom((0, 0), (0, 0)), (1, 1));
    }
}
