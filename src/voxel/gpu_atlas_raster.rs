//! The thesis's binary atlas voxelization as a raster pass (Thiedemann 2010, §4.3.1):
//! the atlas points drawn as `POINT_LIST` into the `R32G32B32A32_UINT` column image, each
//! fragment writing the single-bit LUT entry of its depth and `logicOp OR` merging the bits.
//! The renderer uses the compute twin `voxelize_atlas` (atomicOr into the column buffer that
//! the triangle voxelizer shares, see [`super::gpu_atlas`]); this pass exists to measure the
//! thesis's way against it (`voxgi bench voxelize`) and sets the same bits: both find a
//! point's voxel with `atlas_voxel.glsl`.
//!
//! # Pass (named after its GLSL stem)
//! - `voxelize_atlas_bits` (graphics): vertex pulling from the point buffer, the geometry
//!   shader picks the layer of the point's 128-voxel depth chunk (`k / 128`), the fragment
//!   shader reads the single-bit LUT ([`super::ray_mask::ColumnLut1d::single_bit`]).

use super::gpu::{image_extent, COLUMN_FORMAT};
use super::gpu_atlas::{AtlasInstance, GpuAtlasVoxelizePush, ImportedInstance, COVERAGE_BINDING};
use super::ray_mask::ColumnLut1d;
use super::VoxelGrid;
use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{vk, Buffer, Context, GraphicsPipeline, GraphicsPipelineDesc, VkError};

/// The raster pipeline and its single-bit LUT.
pub struct AtlasRasterBits {
    pipe: GraphicsPipeline,
    lut: Buffer,
}

impl AtlasRasterBits {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let mut desc = GraphicsPipelineDesc::fullscreen(
            "voxelize_atlas_bits.vert",
            "voxelize_atlas_bits.frag",
            COLUMN_FORMAT,
        );
        desc.geometry = Some("voxelize_atlas_bits.geom".into());
        desc.topology = vk::PrimitiveTopology::POINT_LIST;
        desc.push = crate::vk::PushLayout::of::<GpuAtlasVoxelizePush>();
        desc.logic_op = Some(vk::LogicOp::OR);
        let pipe = ctx.graphics_pipeline(&desc)?;
        let lut = ctx.upload_buffer(
            "single-bit lut",
            &ColumnLut1d::single_bit().to_gpu_bytes(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Self { pipe, lut })
    }

    /// Declares `voxelize_atlas_bits`: clears `image` (a 2D array of [`COLUMN_FORMAT`] with
    /// [`image_extent`] texels and one layer per 128 voxels of depth) and ORs every
    /// instance's points into it, one draw per point-list chunk.
    pub fn add_pass(
        &self,
        g: &mut RenderGraph,
        grid: &VoxelGrid,
        image: ImageHandle,
        instances: &[AtlasInstance],
    ) {
        let read = Access::StorageRead(Shader::Graphics);
        let lut = g.import_buffer(&self.lut, read);
        let sets: Vec<ImportedInstance> =
            instances.iter().filter_map(|i| i.import(g, read)).collect();
        let chunks: Vec<_> = sets.iter().flat_map(ImportedInstance::handles).collect();
        let coverage: Vec<_> = sets
            .iter()
            .flat_map(ImportedInstance::coverage_handles)
            .collect();
        let (pipe, grid) = (*self.pipe, *grid);
        let (w, h) = image_extent(&grid);
        // Cleared on load, so the logic op reads only what this pass wrote; the image is the
        // whole (padded) grid, so the viewport maps columns to texels 1:1.
        g.add_pass("voxelize_atlas_bits")
            .pipeline(&pipe)
            .bind_one_of(0, chunks, read)
            .bind(1, lut, read)
            .bind_one_of(COVERAGE_BINDING, coverage, read)
            .color(image, Load::Clear([0.0; 4]))
            .record(move |ctx| {
                ctx.begin_rendering();
                for inst in &sets {
                    let (chunks, model, coverage) = inst.at(ctx.slot);
                    for &(points, count) in chunks {
                        if count == 0 {
                            continue;
                        }
                        let push = GpuAtlasVoxelizePush::new(&grid, model, (w, h), count)
                            .with_coverage(coverage.is_some());
                        let cov = coverage.unwrap_or(points);
                        ctx.bind_with(&pipe, &[(0, points), (COVERAGE_BINDING, cov)]);
                        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                        ctx.cmd.draw(count, 1);
                    }
                }
                ctx.cmd.end_rendering();
            });
    }
}
