//! `pick` (`glsl/pick.{vert,frag}`) and `pick_readback`: which object is under a clicked
//! pixel, found on the GPU through the frame's graph.
//!
//! A click arms the passes for the frame slot about to be recorded (a [`SlotCondition`]: in
//! every other frame they record nothing). `pick` draws the camera's draw lists with the
//! frame's own view-projection into a 1×1 `R32_UINT` target (plus depth) that covers exactly
//! the clicked pixel (a pick matrix), writing each draw's object index + 1; `pick_readback`
//! copies that texel into the slot's window of a host-visible buffer. The viewer reads it when
//! the slot comes round again, after the frame loop waited for the slot's fence (two frames
//! later), as the timestamps are read: the CPU never waits for the GPU for a pick. Only the
//! viewer declares these passes; a headless render has none of them.

use crate::graph::{Access, Load, RenderGraph, Shader, SlotCondition};
use crate::render::{gpu::GpuVertex, SceneInputs};
use crate::vk::{
    vk, Buffer, BufferDesc, Context, GraphicsPipeline, GraphicsPipelineDesc, ImageDesc,
    MemoryLocation, VkError, MAX_FRAMES_IN_FLIGHT,
};
use std::cell::Cell;
use std::rc::Rc;
use std::sync::Arc;

/// Push constants of `pick.vert` / `pick.frag`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuPickPush {
    model: [f32; 16],
    /// The pixel's centre in NDC (xy) and the frame's size in pixels (zw).
    pixel: [f32; 4],
    /// Object index + 1.
    object: u32,
    _pad: [u32; 3],
}

crate::push_constants!(GpuPickPush {
    model,
    pixel,
    object,
    _pad
});

/// Bytes between the frame slots' result windows.
const SLOT_STRIDE: u64 = 256;

/// A pick the GPU answered: the object drawn at `pixel` (`None`: background).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Picked {
    pub pixel: (u32, u32),
    pub object: Option<usize>,
}

pub struct PickPass {
    pipeline: GraphicsPipeline,
    /// One `u32` per frame slot, `SLOT_STRIDE` apart.
    result: Buffer,
    /// Open in the slots whose frame picks.
    gate: Arc<SlotCondition>,
    /// The push constants' `pixel` of the frame being recorded.
    pixel: Rc<Cell<[f32; 4]>>,
    /// Per slot, the pixel its last recorded frame picked at.
    pending: [Option<(u32, u32)>; MAX_FRAMES_IN_FLIGHT],
}

impl PickPass {
    pub fn new(ctx: &Context) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline(&GraphicsPipelineDesc {
            vertex: "pick.vert".into(),
            geometry: None,
            fragment: "pick.frag".into(),
            push: crate::vk::PushLayout::of::<GpuPickPush>(),
            vertex_stride: std::mem::size_of::<GpuVertex>() as u32,
            vertex_attributes: vec![(
                vk::Format::R32G32B32_SFLOAT,
                std::mem::offset_of!(GpuVertex, position) as u32,
            )],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![vk::Format::R32_UINT],
            depth_format: Some(vk::Format::D32_SFLOAT),
            depth_test: true,
            depth_write: true,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: Vec::new(),
        })?;
        let result = ctx.create_buffer(&BufferDesc {
            name: "pick result".into(),
            size_bytes: SLOT_STRIDE * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?;
        let gate = Arc::new(SlotCondition::default());
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            gate.set(slot, false);
        }
        Ok(Self {
            pipeline,
            result,
            gate,
            pixel: Rc::new(Cell::new([0.0; 4])),
            pending: [None; MAX_FRAMES_IN_FLIGHT],
        })
    }

    /// Declares `pick` and `pick_readback` over the scene the renderer imported into `g`.
    pub fn declare(&self, g: &mut RenderGraph, scene: &SceneInputs) {
        let id = g.create_image(ImageDesc::new_2d("pick object", vk::Format::R32_UINT, 1, 1));
        let depth = g.create_image(ImageDesc::new_2d(
            "pick depth",
            vk::Format::D32_SFLOAT,
            1,
            1,
        ));
        let result = g.import_buffer_per_slot(&self.result, SLOT_STRIDE, 4, Access::HostRead);
        let pipe = *self.pipeline;
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let pixel = self.pixel.clone();
        g.add_pass("pick")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Vertex))
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .color(id, Load::Clear([0.0; 4]))
            .depth(depth, Load::ClearDepth(1.0))
            .when(Some(self.gate.clone()))
            .record(move |ctx| {
                ctx.begin_rendering();
                ctx.bind(&pipe);
                ctx.bind_vertex_buffer(vertices);
                ctx.bind_index_buffer(indices);
                if let Ok(lists) = draws.read() {
                    for d in lists.camera.iter().chain(&lists.transparent) {
                        let push = GpuPickPush {
                            model: d.model.to_cols_array(),
                            pixel: pixel.get(),
                            object: d.object as u32 + 1,
                            _pad: [0; 3],
                        };
                        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                        ctx.cmd
                            .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    }
                }
                ctx.cmd.end_rendering();
            });
        g.add_pass("pick_readback")
            .read(id, Access::TransferRead)
            .write(result, Access::TransferWrite)
            .when(Some(self.gate.clone()))
            .record(move |ctx| {
                let b = ctx.buffer(result);
                let one = vk::Extent3D {
                    width: 1,
                    height: 1,
                    depth: 1,
                };
                ctx.cmd
                    .copy_image_to_buffer_at(ctx.image(id).raw, one, 0, 1, b.raw, b.offset);
            });
    }

    /// The answer of the pick recorded in `slot` when that frame was last recorded, if it
    /// picked (call after the slot's fence, before [`Self::arm`]).
    pub fn collect(&mut self, slot: usize) -> Option<Picked> {
        let pixel = self.pending.get_mut(slot)?.take()?;
        let at = slot * SLOT_STRIDE as usize;
        let id = self
            .result
            .mapped()
            .and_then(|m| m.get(at..at + 4))
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        Some(Picked {
            pixel,
            object: id.checked_sub(1).map(|i| i as usize),
        })
    }

    /// Makes the frame about to be recorded in `slot` pick at `pixel` of a `size` frame
    /// (`None`: it records no pick).
    pub fn arm(&mut self, slot: usize, pixel: Option<(u32, u32)>, size: (u32, u32)) {
        self.gate.set(slot, pixel.is_some());
        if let Some(p) = self.pending.get_mut(slot) {
            *p = pixel;
        }
        if let Some((x, y)) = pixel {
            self.pixel.set(pick_constants((x, y), size));
        }
    }

    /// Forgets picks in flight (their graph is gone: the answer would not come).
    pub fn forget(&mut self) {
        self.pending = [None; MAX_FRAMES_IN_FLIGHT];
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            self.gate.set(slot, false);
        }
    }
}

/// `pick.vert`'s `pixel`: the centre of pixel (x, y) of a `w`×`h` frame in NDC, and the size.
fn pick_constants((x, y): (u32, u32), (w, h): (u32, u32)) -> [f32; 4] {
    let (w, h) = (w.max(1) as f32, h.max(1) as f32);
    [
        (x as f32 + 0.5) / w * 2.0 - 1.0,
        (y as f32 + 0.5) / h * 2.0 - 1.0,
        w,
        h,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pick matrix maps the clicked pixel's footprint onto [-1, 1]² and its centre to 0,
    /// whatever the clip-space w.
    #[test]
    fn the_clicked_pixel_fills_the_target() {
        let (size, px) = ((64, 48), (10, 40));
        let [cx, cy, w, h] = pick_constants(px, size);
        let ndc_of = |x: f32, y: f32| ((x / 64.0) * 2.0 - 1.0, (y / 48.0) * 2.0 - 1.0);
        let pick = |(nx, ny): (f32, f32), clip_w: f32| {
            let (x, y) = (nx * clip_w, ny * clip_w);
            (
                ((x - cx * clip_w) * w) / clip_w,
                ((y - cy * clip_w) * h) / clip_w,
            )
        };
        for clip_w in [0.1, 1.0, 7.5] {
            let lo = pick(ndc_of(10.0, 40.0), clip_w);
            let hi = pick(ndc_of(11.0, 41.0), clip_w);
            let mid = pick(ndc_of(10.5, 40.5), clip_w);
            assert!(
                (lo.0 + 1.0).abs() < 1e-4 && (lo.1 + 1.0).abs() < 1e-4,
                "{lo:?}"
            );
            assert!(
                (hi.0 - 1.0).abs() < 1e-4 && (hi.1 - 1.0).abs() < 1e-4,
                "{hi:?}"
            );
            assert!(mid.0.abs() < 1e-4 && mid.1.abs() < 1e-4, "{mid:?}");
        }
    }
}
