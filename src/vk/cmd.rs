//! `Cmd`: the safe command-recording surface a pass's closure receives.
//!
//! Passes never call ash; they bind pipelines, push descriptors by (set, binding), and draw or
//! dispatch through this type. Barriers are recorded only by the render graph's executor.

use super::pipeline::{Bindable, Descriptor};
use super::Context;
use ash::vk;
use std::ffi::CString;

/// One color or depth attachment of a dynamic-rendering pass.
#[derive(Clone, Copy)]
pub struct Attachment {
    pub view: vk::ImageView,
    /// `Some` clears on load, `None` keeps the contents.
    pub clear: Option<vk::ClearValue>,
    /// A depth attachment tested but never written: read-only layout, nothing stored.
    pub read_only: bool,
}

/// A command buffer in the recording state, with the context it belongs to.
pub struct Cmd<'a> {
    pub(crate) ctx: &'a Context,
    pub(crate) raw: vk::CommandBuffer,
}

impl<'a> Cmd<'a> {
    /// # Invariant
    /// `raw` must be a primary command buffer of `ctx.device` in the recording state for the
    /// lifetime of the returned value.
    pub(crate) fn new(ctx: &'a Context, raw: vk::CommandBuffer) -> Self {
        Self { ctx, raw }
    }

    pub fn raw(&self) -> vk::CommandBuffer {
        self.raw
    }

    pub fn context(&self) -> &Context {
        self.ctx
    }

    pub(crate) fn barriers(
        &self,
        images: &[vk::ImageMemoryBarrier2],
        buffers: &[vk::BufferMemoryBarrier2],
    ) {
        if images.is_empty() && buffers.is_empty() {
            return;
        }
        let dep = vk::DependencyInfo::default()
            .image_memory_barriers(images)
            .buffer_memory_barriers(buffers);
        // SAFETY: Cmd invariant (recording); barrier handles are live resources of the graph.
        unsafe { self.ctx.device.cmd_pipeline_barrier2(self.raw, &dep) };
    }

    pub fn begin_label(&self, name: &str, color: [f32; 4]) {
        let Some(du) = &self.ctx.debug_utils else {
            return;
        };
        let Ok(cname) = CString::new(name) else {
            return;
        };
        let label = vk::DebugUtilsLabelEXT::default()
            .label_name(&cname)
            .color(color);
        // SAFETY: Cmd invariant.
        unsafe { du.cmd_begin_debug_utils_label(self.raw, &label) };
    }

    pub fn end_label(&self) {
        let Some(du) = &self.ctx.debug_utils else {
            return;
        };
        // SAFETY: Cmd invariant; paired with begin_label by the executor.
        unsafe { du.cmd_end_debug_utils_label(self.raw) };
    }

    pub(crate) fn write_timestamp(&self, pool: vk::QueryPool, query: u32, end: bool) {
        let stage = if end {
            vk::PipelineStageFlags2::ALL_COMMANDS
        } else {
            vk::PipelineStageFlags2::NONE
        };
        // SAFETY: Cmd invariant; the query was reset at the start of this command buffer.
        unsafe {
            self.ctx
                .device
                .cmd_write_timestamp2(self.raw, stage, pool, query)
        };
    }

    pub(crate) fn reset_queries(&self, pool: vk::QueryPool, first: u32, count: u32) {
        // SAFETY: Cmd invariant; outside any rendering instance.
        unsafe {
            self.ctx
                .device
                .cmd_reset_query_pool(self.raw, pool, first, count)
        };
    }

    /// Begins dynamic rendering over `extent` and sets a full viewport and scissor.
    pub fn begin_rendering(
        &self,
        extent: vk::Extent2D,
        colors: &[Attachment],
        depth: Option<Attachment>,
    ) {
        self.begin_rendering_layers(extent, (1, 0), colors, depth);
    }

    /// Begins layered dynamic rendering (a geometry shader picks `gl_Layer`) into array views.
    /// `view_mask` ≠ 0 renders with multiview: each set bit is a view drawn into the
    /// attachments' layer of that index (`gl_ViewIndex` in the shaders), and `layers` is
    /// ignored (Vulkan 1.1 multiview, core).
    pub fn begin_rendering_layers(
        &self,
        extent: vk::Extent2D,
        (layers, view_mask): (u32, u32),
        colors: &[Attachment],
        depth: Option<Attachment>,
    ) {
        let color_infos: Vec<vk::RenderingAttachmentInfo> = colors
            .iter()
            .map(|a| attachment_info(a, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL))
            .collect();
        let depth_info =
            depth.map(|a| attachment_info(&a, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL));
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent,
        };
        let mut info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(layers.max(1))
            .view_mask(view_mask)
            .color_attachments(&color_infos);
        if let Some(d) = depth_info.as_ref() {
            info = info.depth_attachment(d);
        }
        self.begin_rendering_info(&info, extent);
    }

    /// Begins dynamic rendering without attachments (e.g. voxelization writes storage images
    /// only), over `extent` with `layers` layers.
    pub fn begin_rendering_no_attachments(&self, extent: vk::Extent2D, layers: u32) {
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent,
        };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(layers.max(1));
        self.begin_rendering_info(&info, extent);
    }

    fn begin_rendering_info(&self, info: &vk::RenderingInfo, extent: vk::Extent2D) {
        let viewport = [vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        }];
        let scissor = [vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent,
        }];
        // SAFETY: Cmd invariant; attachment views are live and in the layouts the graph set.
        unsafe {
            self.ctx.device.cmd_begin_rendering(self.raw, info);
            self.ctx.device.cmd_set_viewport(self.raw, 0, &viewport);
            self.ctx.device.cmd_set_scissor(self.raw, 0, &scissor);
        }
    }

    pub fn end_rendering(&self) {
        // SAFETY: Cmd invariant; paired with begin_rendering.
        unsafe { self.ctx.device.cmd_end_rendering(self.raw) };
    }

    /// Binds a pipeline and pushes its descriptor set 0.
    pub fn bind(&self, pipeline: &impl Bindable, descriptors: &[Descriptor]) {
        let (bind_point, raw, _) = pipeline.bind_info();
        // SAFETY: Cmd invariant; the pipeline is live.
        unsafe { self.ctx.device.cmd_bind_pipeline(self.raw, bind_point, raw) };
        self.push_descriptors(pipeline, descriptors);
    }

    /// Pushes descriptors of set 0 of `pipeline` (e.g. a per-draw texture) without rebinding.
    pub fn push_descriptors(&self, pipeline: &impl Bindable, descriptors: &[Descriptor]) {
        if descriptors.is_empty() {
            return;
        }
        debug_assert!(
            descriptors.iter().all(|d| pipeline
                .interface()
                .bindings
                .get(&d.binding())
                .is_some_and(|r| super::descriptor_type(r.kind) == d.descriptor_type())),
            "descriptors {:?} do not fit the bindings `{}` declares: {:?}",
            descriptors
                .iter()
                .map(|d| (d.binding(), d.descriptor_type()))
                .collect::<Vec<_>>(),
            pipeline.interface().name,
            pipeline
                .interface()
                .bindings
                .values()
                .map(|r| (r.binding, r.kind))
                .collect::<Vec<_>>()
        );
        let (bind_point, _, layout) = pipeline.bind_info();
        let mut image_infos: Vec<[vk::DescriptorImageInfo; 1]> =
            Vec::with_capacity(descriptors.len());
        let mut buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            Vec::with_capacity(descriptors.len());
        for d in descriptors {
            match *d {
                Descriptor::SampledImage { view, sampler, .. } => {
                    image_infos.push([vk::DescriptorImageInfo {
                        sampler,
                        image_view: view,
                        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    }])
                }
                Descriptor::StorageImage { view, .. } => {
                    image_infos.push([vk::DescriptorImageInfo {
                        sampler: vk::Sampler::null(),
                        image_view: view,
                        image_layout: vk::ImageLayout::GENERAL,
                    }])
                }
                Descriptor::StorageBuffer {
                    buffer,
                    offset,
                    range,
                    ..
                }
                | Descriptor::UniformBuffer {
                    buffer,
                    offset,
                    range,
                    ..
                } => buffer_infos.push([vk::DescriptorBufferInfo {
                    buffer,
                    offset,
                    range,
                }]),
            }
        }
        let (mut ii, mut bi) = (0, 0);
        let writes: Vec<vk::WriteDescriptorSet> = descriptors
            .iter()
            .map(|d| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_binding(d.binding())
                    .descriptor_type(d.descriptor_type());
                match d {
                    Descriptor::SampledImage { .. } | Descriptor::StorageImage { .. } => {
                        ii += 1;
                        w.image_info(&image_infos[ii - 1])
                    }
                    _ => {
                        bi += 1;
                        w.buffer_info(&buffer_infos[bi - 1])
                    }
                }
            })
            .collect();
        // SAFETY: Cmd invariant; the layout's set 0 was created with the PUSH_DESCRIPTOR flag;
        // the infos outlive the call.
        unsafe {
            self.ctx
                .push_descriptor
                .cmd_push_descriptor_set(self.raw, bind_point, layout, 0, &writes)
        };
    }

    /// Push constants for the pipeline last bound (all stages). Pushes the bytes the shaders'
    /// block covers: a Rust struct may end in padding the block does not have (its layout was
    /// checked against the block when the pipeline was created).
    pub fn push_constants(&self, pipeline: &impl Bindable, bytes: &[u8]) {
        let (_, _, layout) = pipeline.bind_info();
        let size = (pipeline.push_bytes() as usize).min(bytes.len());
        if size == 0 {
            return;
        }
        // SAFETY: Cmd invariant; the layout declares a push-constant range of ALL stages of
        // `push_bytes()` bytes, and `size` does not exceed it.
        unsafe {
            self.ctx.device.cmd_push_constants(
                self.raw,
                layout,
                vk::ShaderStageFlags::ALL,
                0,
                &bytes[..size],
            )
        };
    }

    pub fn dispatch(&self, x: u32, y: u32, z: u32) {
        // SAFETY: Cmd invariant; a compute pipeline is bound.
        unsafe { self.ctx.device.cmd_dispatch(self.raw, x, y, z) };
    }

    pub fn draw(&self, vertices: u32, instances: u32) {
        // SAFETY: Cmd invariant; inside rendering with a graphics pipeline bound.
        unsafe {
            self.ctx
                .device
                .cmd_draw(self.raw, vertices, instances, 0, 0)
        };
    }

    pub fn draw_indexed(&self, indices: u32, first_index: u32, vertex_offset: i32) {
        self.draw_indexed_instanced(indices, 1, first_index, vertex_offset);
    }

    /// An indexed draw of `instances` instances (`gl_InstanceIndex` 0 to `instances` − 1).
    pub fn draw_indexed_instanced(
        &self,
        indices: u32,
        instances: u32,
        first_index: u32,
        vertex_offset: i32,
    ) {
        // SAFETY: Cmd invariant; index buffer bound.
        unsafe {
            self.ctx.device.cmd_draw_indexed(
                self.raw,
                indices,
                instances,
                first_index,
                vertex_offset,
                0,
            )
        };
    }

    pub fn bind_vertex_buffer(&self, buffer: vk::Buffer) {
        // SAFETY: Cmd invariant; buffer is live with VERTEX_BUFFER usage.
        unsafe {
            self.ctx
                .device
                .cmd_bind_vertex_buffers(self.raw, 0, &[buffer], &[0])
        };
    }

    pub fn bind_index_buffer(&self, buffer: vk::Buffer) {
        // SAFETY: Cmd invariant; buffer is live with INDEX_BUFFER usage.
        unsafe {
            self.ctx
                .device
                .cmd_bind_index_buffer(self.raw, buffer, 0, vk::IndexType::UINT32)
        };
    }

    /// Copies mip `mip` (all layers) of a color image in TRANSFER_SRC layout into a buffer,
    /// tightly packed, layer after layer.
    pub fn copy_image_to_buffer(
        &self,
        image: vk::Image,
        extent: vk::Extent3D,
        mip: u32,
        layers: u32,
        buffer: vk::Buffer,
    ) {
        self.copy_image_to_buffer_at(image, extent, mip, layers, buffer, 0);
    }

    /// [`Self::copy_image_to_buffer`] to `offset_bytes` into the buffer (a frame slot's window
    /// of a buffer imported per slot; a multiple of the texel size).
    pub fn copy_image_to_buffer_at(
        &self,
        image: vk::Image,
        extent: vk::Extent3D,
        mip: u32,
        layers: u32,
        buffer: vk::Buffer,
        offset_bytes: u64,
    ) {
        let region = [color_mip_copy(extent, mip, layers, offset_bytes)];
        // SAFETY: Cmd invariant; the graph put the image in TRANSFER_SRC_OPTIMAL; the buffer is
        // large enough past the offset (checked by the caller's read-back size).
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                self.raw,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer,
                &region,
            )
        };
    }

    /// Copies a whole buffer into an image (TRANSFER_DST layout), mip `mip`, all layers.
    pub fn copy_buffer_to_image(
        &self,
        buffer: vk::Buffer,
        image: vk::Image,
        extent: vk::Extent3D,
        mip: u32,
        layers: u32,
    ) {
        let region = [color_mip_copy(extent, mip, layers, 0)];
        // SAFETY: Cmd invariant; the graph put the image in TRANSFER_DST_OPTIMAL.
        unsafe {
            self.ctx.device.cmd_copy_buffer_to_image(
                self.raw,
                buffer,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
            )
        };
    }

    /// Copies mip 0, layer 0 of a color image (TRANSFER_SRC layout) into another of the same
    /// format and extent (TRANSFER_DST layout).
    pub fn copy_image(&self, src: vk::Image, dst: vk::Image, extent: vk::Extent3D) {
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = [vk::ImageCopy {
            src_subresource: layers,
            src_offset: vk::Offset3D::default(),
            dst_subresource: layers,
            dst_offset: vk::Offset3D::default(),
            extent,
        }];
        // SAFETY: Cmd invariant; the graph put `src` in TRANSFER_SRC_OPTIMAL and `dst` in
        // TRANSFER_DST_OPTIMAL; the caller passes images of one format holding `extent`.
        unsafe {
            self.ctx.device.cmd_copy_image(
                self.raw,
                src,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
            )
        };
    }

    pub fn copy_buffer(&self, src: vk::Buffer, dst: vk::Buffer, size_bytes: u64) {
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: size_bytes,
        }];
        // SAFETY: Cmd invariant; both buffers hold at least size_bytes.
        unsafe { self.ctx.device.cmd_copy_buffer(self.raw, src, dst, &region) };
    }

    /// Clears mips and layers of a color image in TRANSFER_DST layout.
    pub fn clear_color_image(
        &self,
        image: vk::Image,
        value: vk::ClearColorValue,
        mips: u32,
        layers: u32,
    ) {
        let range = [vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: mips,
            base_array_layer: 0,
            layer_count: layers,
        }];
        // SAFETY: Cmd invariant; the graph put the image in TRANSFER_DST_OPTIMAL.
        unsafe {
            self.ctx.device.cmd_clear_color_image(
                self.raw,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &value,
                &range,
            )
        };
    }

    /// Copies mip 0 of `src` (TRANSFER_SRC layout) onto `dst_rect` of `dst` (TRANSFER_DST
    /// layout), scaling with `filter` and converting between formats (e.g. RGBA → BGRA).
    pub fn blit_image(
        &self,
        src: vk::Image,
        src_extent: vk::Extent2D,
        dst: vk::Image,
        dst_rect: vk::Rect2D,
        filter: vk::Filter,
    ) {
        let corner = |o: vk::Offset2D, e: vk::Extent2D| vk::Offset3D {
            x: o.x + e.width as i32,
            y: o.y + e.height as i32,
            z: 1,
        };
        let origin = vk::Offset2D { x: 0, y: 0 };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = [vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), corner(origin, src_extent)],
            dst_subresource: layers,
            dst_offsets: [
                vk::Offset3D {
                    x: dst_rect.offset.x,
                    y: dst_rect.offset.y,
                    z: 0,
                },
                corner(dst_rect.offset, dst_rect.extent),
            ],
        }];
        // SAFETY: Cmd invariant; the graph put src in TRANSFER_SRC_OPTIMAL and dst in
        // TRANSFER_DST_OPTIMAL; both are color images whose formats support blits.
        unsafe {
            self.ctx.device.cmd_blit_image(
                self.raw,
                src,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &region,
                filter,
            )
        };
    }

    /// Restricts drawing to `rect` (inside a rendering instance).
    pub fn set_scissor(&self, rect: vk::Rect2D) {
        // SAFETY: Cmd invariant; the bound pipeline has a dynamic scissor.
        unsafe { self.ctx.device.cmd_set_scissor(self.raw, 0, &[rect]) };
    }

    pub fn fill_buffer(&self, buffer: vk::Buffer, value: u32) {
        // SAFETY: Cmd invariant; whole-size fill of a TRANSFER_DST buffer.
        unsafe {
            self.ctx
                .device
                .cmd_fill_buffer(self.raw, buffer, 0, vk::WHOLE_SIZE, value)
        };
    }
}

fn attachment_info(
    a: &Attachment,
    layout: vk::ImageLayout,
) -> vk::RenderingAttachmentInfo<'static> {
    let (layout, store) = match a.read_only {
        true => (
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
            vk::AttachmentStoreOp::NONE,
        ),
        false => (layout, vk::AttachmentStoreOp::STORE),
    };
    let mut info = vk::RenderingAttachmentInfo::default()
        .image_view(a.view)
        .image_layout(layout)
        .store_op(store);
    info = match a.clear {
        Some(c) => info.load_op(vk::AttachmentLoadOp::CLEAR).clear_value(c),
        None => info.load_op(vk::AttachmentLoadOp::LOAD),
    };
    info
}

/// A copy between a tightly packed buffer (from `offset_bytes`) and mip `mip`, layers
/// `0..layers`, of a color image of mip extent `extent`.
fn color_mip_copy(
    extent: vk::Extent3D,
    mip: u32,
    layers: u32,
    offset_bytes: u64,
) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: offset_bytes,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: mip,
            base_array_layer: 0,
            layer_count: layers,
        },
        image_offset: vk::Offset3D::default(),
        image_extent: extent,
    }
}
