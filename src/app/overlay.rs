//! Draws egui's output over the swapchain image as the render-graph pass `egui` (the graph
//! derives its barriers). The font atlas is a persistent image, uploaded between frames when
//! egui changes it (the first frame, new glyphs), like any other texture.

use crate::graph::{Access, ImageHandle, Load, RenderGraph, Shader};
use crate::vk::{
    vk, Buffer, BufferDesc, Context, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc,
    MemoryLocation, VkError, MAX_FRAMES_IN_FLIGHT,
};
use bytemuck::{Pod, Zeroable};
use std::cell::RefCell;
use std::rc::Rc;

/// Push constants of `egui.vert`: the screen size in egui points.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuEguiPush {
    screen_size_points: [f32; 2],
}

crate::push_constants!(GpuEguiPush { screen_size_points });

/// One egui vertex as `glsl/egui.vert` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuEguiVertex {
    pub pos_points: [f32; 2],
    pub uv: [f32; 2],
    /// sRGB-encoded, premultiplied RGBA.
    pub color: [u8; 4],
}

/// Vertices and indices one frame slot may hold; larger UIs are cut (with a warning).
const MAX_VERTICES: u64 = 1 << 16;
const MAX_INDICES: u64 = 3 << 16;
const ATLAS_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// One indexed draw with its scissor, offsets relative to the slot's region.
#[derive(Clone, Copy, Debug)]
struct MeshDraw {
    scissor: vk::Rect2D,
    first_index: u32,
    index_count: u32,
    vertex_offset: i32,
}

#[derive(Debug, Default)]
struct FrameDraws {
    screen_size_points: [f32; 2],
    draws: Vec<MeshDraw>,
}

/// The font atlas: a CPU copy (egui sends partial updates) and its GPU image.
struct Atlas {
    width: usize,
    height: usize,
    pixels: Vec<[u8; 4]>,
    image: Image,
}

pub struct Overlay {
    pipeline: GraphicsPipeline,
    sampler: crate::vk::Sampler,
    vertices: Buffer,
    indices: Buffer,
    atlas: Option<Atlas>,
    /// Per frame slot, what `egui` draws.
    frames: Rc<RefCell<Vec<FrameDraws>>>,
    warned_overflow: bool,
}

impl Overlay {
    pub fn new(ctx: &Context, target_format: vk::Format) -> Result<Self, VkError> {
        let pipeline = ctx.graphics_pipeline_premultiplied(&GraphicsPipelineDesc {
            vertex: "egui.vert".into(),
            geometry: None,
            fragment: "egui.frag".into(),
            push: crate::vk::PushLayout::of::<GpuEguiPush>(),
            vertex_stride: std::mem::size_of::<GpuEguiVertex>() as u32,
            vertex_attributes: vec![
                (vk::Format::R32G32_SFLOAT, 0),
                (vk::Format::R32G32_SFLOAT, 8),
                (vk::Format::R8G8B8A8_UNORM, 16),
            ],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![target_format],
            depth_format: None,
            depth_test: false,
            depth_write: false,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: vec![],
        })?;
        let sampler = ctx.create_sampler(vk::Filter::LINEAR, false)?;
        let slots = MAX_FRAMES_IN_FLIGHT as u64;
        let vertices = ctx.create_buffer(&BufferDesc {
            name: "egui vertices".into(),
            size_bytes: slots * MAX_VERTICES * std::mem::size_of::<GpuEguiVertex>() as u64,
            usage: vk::BufferUsageFlags::VERTEX_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let indices = ctx.create_buffer(&BufferDesc {
            name: "egui indices".into(),
            size_bytes: slots * MAX_INDICES * 4,
            usage: vk::BufferUsageFlags::INDEX_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        Ok(Self {
            pipeline,
            sampler,
            vertices,
            indices,
            atlas: None,
            frames: Rc::new(RefCell::new(
                (0..MAX_FRAMES_IN_FLIGHT)
                    .map(|_| FrameDraws::default())
                    .collect(),
            )),
            warned_overflow: false,
        })
    }

    /// Whether the atlas exists (egui's first frame creates it); the graph needs it.
    pub fn ready(&self) -> bool {
        self.atlas.is_some()
    }

    /// Applies egui's texture changes and empties `delta` (egui asserts that a dropped delta
    /// is empty, an error here included). Returns `true` when the atlas image was (re)created,
    /// which needs a new graph. Waits for the device when the atlas changed (rare: the first
    /// frame and new glyphs), because frames in flight may still sample it.
    pub fn update_textures(
        &mut self,
        ctx: &Context,
        delta: &mut egui::TexturesDelta,
    ) -> Result<bool, VkError> {
        let set = std::mem::take(&mut delta.set);
        delta.free.clear();
        let mut recreated = false;
        let mut changed = false;
        // egui lists a texture's changes in order: a whole image, then patches of it.
        let atlas_deltas = set.into_iter().filter_map(|(id, ds)| {
            if id == egui::TextureId::default() {
                return Some(ds);
            }
            log::warn!("egui texture {id:?} ignored: the viewer draws the font atlas only");
            None
        });
        for d in atlas_deltas.flatten() {
            let (w, h) = (d.image.width(), d.image.height());
            // egui hands every texture, the font atlas too, as premultiplied sRGBA.
            let egui::ImageData::Color(c) = &d.image;
            let pixels: Vec<[u8; 4]> = c.pixels.iter().map(|p| p.to_array()).collect();
            match d.pos {
                None => {
                    if self
                        .atlas
                        .as_ref()
                        .is_none_or(|a| (a.width, a.height) != (w, h))
                    {
                        // The old atlas is released once the frames that sample it completed.
                        self.atlas = Some(create_atlas(ctx, w, h)?);
                        recreated = true;
                    }
                    if let Some(a) = &mut self.atlas {
                        a.pixels = pixels;
                    }
                }
                Some([x0, y0]) => {
                    let Some(a) = &mut self.atlas else { continue };
                    for y in 0..h.min(a.height.saturating_sub(y0)) {
                        for x in 0..w.min(a.width.saturating_sub(x0)) {
                            a.pixels[(y0 + y) * a.width + x0 + x] = pixels[y * w + x];
                        }
                    }
                }
            }
            changed = true;
        }
        if changed {
            ctx.wait_idle()?;
            if let Some(a) = &self.atlas {
                // The graph imports the atlas in this layout (Access::Sampled).
                ctx.write_image(
                    &a.image,
                    bytemuck::cast_slice(&a.pixels),
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                )?;
            }
        }
        Ok(recreated)
    }

    /// Writes the meshes of frame slot `slot` (after the slot's fence was waited for).
    pub fn write_frame(
        &mut self,
        slot: usize,
        primitives: &[egui::ClippedPrimitive],
        pixels_per_point: f32,
        extent: vk::Extent2D,
    ) {
        let vertex_base = slot as u64 * MAX_VERTICES;
        let index_base = slot as u64 * MAX_INDICES;
        let vsize = std::mem::size_of::<GpuEguiVertex>();
        let mut draws = Vec::new();
        let (mut nv, mut ni) = (0u64, 0u64);
        for p in primitives {
            let egui::epaint::Primitive::Mesh(mesh) = &p.primitive else {
                continue;
            };
            if mesh.indices.is_empty() {
                continue;
            }
            if nv + mesh.vertices.len() as u64 > MAX_VERTICES
                || ni + mesh.indices.len() as u64 > MAX_INDICES
            {
                if !self.warned_overflow {
                    log::warn!("the UI has more triangles than the overlay holds; some are cut");
                    self.warned_overflow = true;
                }
                break;
            }
            let Some(scissor) = scissor(p.clip_rect, pixels_per_point, extent) else {
                continue;
            };
            let verts: Vec<GpuEguiVertex> = mesh
                .vertices
                .iter()
                .map(|v| GpuEguiVertex {
                    pos_points: [v.pos.x, v.pos.y],
                    uv: [v.uv.x, v.uv.y],
                    color: v.color.to_array(),
                })
                .collect();
            if let Some(m) = self.vertices.mapped_mut() {
                let at = ((vertex_base + nv) as usize) * vsize;
                m[at..at + verts.len() * vsize].copy_from_slice(bytemuck::cast_slice(&verts));
            }
            if let Some(m) = self.indices.mapped_mut() {
                let at = ((index_base + ni) as usize) * 4;
                m[at..at + mesh.indices.len() * 4]
                    .copy_from_slice(bytemuck::cast_slice(&mesh.indices));
            }
            draws.push(MeshDraw {
                scissor,
                first_index: (index_base + ni) as u32,
                index_count: mesh.indices.len() as u32,
                vertex_offset: (vertex_base + nv) as i32,
            });
            nv += mesh.vertices.len() as u64;
            ni += mesh.indices.len() as u64;
        }
        if let Some(f) = self.frames.borrow_mut().get_mut(slot) {
            f.screen_size_points = [
                extent.width as f32 / pixels_per_point,
                extent.height as f32 / pixels_per_point,
            ];
            f.draws = draws;
        }
    }

    /// Declares `egui`, drawing over `target`. Call when [`Self::ready`].
    pub fn declare(&self, g: &mut RenderGraph, target: ImageHandle) {
        let Some(atlas) = &self.atlas else { return };
        let image = g.import_image(&atlas.image, Access::Sampled(Shader::Fragment));
        let vertices = g.import_buffer(&self.vertices, Access::VertexBuffer);
        let indices = g.import_buffer(&self.indices, Access::IndexBuffer);
        let (pipe, sampler, frames) = (*self.pipeline, self.sampler.raw, self.frames.clone());
        g.add_pass("egui")
            .pipeline(&pipe)
            .bind_sampled(0, image, sampler, Shader::Fragment)
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .color(target, Load::Keep)
            .record(move |ctx| {
                let frames = frames.borrow();
                let Some(f) = frames.get(ctx.slot) else {
                    return;
                };
                ctx.begin_rendering();
                ctx.bind(&pipe);
                ctx.cmd.push_constants(
                    &pipe,
                    bytemuck::bytes_of(&GpuEguiPush {
                        screen_size_points: f.screen_size_points,
                    }),
                );
                ctx.bind_vertex_buffer(vertices);
                ctx.bind_index_buffer(indices);
                for d in &f.draws {
                    ctx.cmd.set_scissor(d.scissor);
                    ctx.cmd
                        .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                }
                ctx.cmd.end_rendering();
            });
    }
}

fn create_atlas(ctx: &Context, width: usize, height: usize) -> Result<Atlas, VkError> {
    let image = ctx.create_image(
        &ImageDesc::new_2d("egui atlas", ATLAS_FORMAT, width as u32, height as u32)
            .with_usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    Ok(Atlas {
        width,
        height,
        pixels: vec![[0; 4]; width * height],
        image,
    })
}

/// The clip rectangle in pixels, inside the target; `None` when empty.
fn scissor(clip: egui::Rect, pixels_per_point: f32, extent: vk::Extent2D) -> Option<vk::Rect2D> {
    let to_px = |v: f32, max: u32| (v * pixels_per_point).round().clamp(0.0, max as f32) as u32;
    let x0 = to_px(clip.min.x, extent.width);
    let y0 = to_px(clip.min.y, extent.height);
    let x1 = to_px(clip.max.x, extent.width);
    let y1 = to_px(clip.max.y, extent.height);
    (x1 > x0 && y1 > y0).then_some(vk::Rect2D {
        offset: vk::Offset2D {
            x: x0 as i32,
            y: y0 as i32,
        },
        extent: vk::Extent2D {
            width: x1 - x0,
            height: y1 - y0,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_layout_matches_egui_vert() {
        assert_eq!(std::mem::size_of::<GpuEguiVertex>(), 20);
        assert_eq!(std::mem::offset_of!(GpuEguiVertex, uv), 8);
        assert_eq!(std::mem::offset_of!(GpuEguiVertex, color), 16);
    }

    #[test]
    fn scissor_is_clamped_and_empty_clips_are_skipped() {
        let e = vk::Extent2D {
            width: 100,
            height: 50,
        };
        let r = egui::Rect::from_min_max(egui::pos2(-10.0, 5.0), egui::pos2(200.0, 20.0));
        let s = scissor(r, 2.0, e).expect("non-empty");
        assert_eq!((s.offset.x, s.offset.y), (0, 10));
        assert_eq!((s.extent.width, s.extent.height), (100, 30));
        let outside = egui::Rect::from_min_max(egui::pos2(60.0, 0.0), egui::pos2(80.0, 10.0));
        assert!(scissor(outside, 2.0, e).is_none());
    }
}
