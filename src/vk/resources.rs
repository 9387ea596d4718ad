//! Persistent buffers and images, allocated with gpu-allocator; staging upload and read-back.
//! Buffers, images and arenas release themselves when dropped (see `release.rs`).

use super::release::{allocation_key, Garbage, ReleaseQueue};
use super::{Context, VkError};
use ash::vk;
use ash::vk::Handle;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
pub use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Plain creation data of a buffer.
#[derive(Clone, Debug)]
pub struct BufferDesc {
    pub name: String,
    pub size_bytes: u64,
    pub usage: vk::BufferUsageFlags,
    pub location: MemoryLocation,
}

/// A buffer with its memory (its own allocation, or a place in a graph arena). Dropping it
/// releases both once the GPU is done with them.
pub struct Buffer {
    pub raw: vk::Buffer,
    pub desc: BufferDesc,
    allocation: Option<Allocation>,
    release: Arc<ReleaseQueue>,
}

impl Drop for Buffer {
    fn drop(&mut self) {
        let mut items = vec![Garbage::Buffer(self.raw)];
        items.extend(self.allocation.take().map(Garbage::Allocation));
        self.release.release(items);
    }
}

impl Buffer {
    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }
    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut()?.mapped_slice_mut()
    }
}

/// Plain creation data of an image. `depth > 1` makes a 3D image; `layers > 1` a 2D array.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageDesc {
    pub name: String,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub depth: u32,
    pub layers: u32,
    pub mip_levels: u32,
    pub usage: vk::ImageUsageFlags,
    /// View as an array even with one layer (shaders declare `*Array` samplers).
    pub array: bool,
    /// Also create one 2D view per layer ([`Image::layer_views`]): a pass can then read or
    /// write one layer as a plain 2D image (a stereo eye of a two-layer multiview target).
    pub layer_views: bool,
}

impl ImageDesc {
    pub fn new_2d(name: &str, format: vk::Format, width: u32, height: u32) -> Self {
        Self {
            name: name.to_owned(),
            format,
            width,
            height,
            depth: 1,
            layers: 1,
            mip_levels: 1,
            usage: vk::ImageUsageFlags::empty(),
            array: false,
            layer_views: false,
        }
    }
    /// An array image of `layers` layers, viewed as an array even when `layers` is 1.
    pub fn with_layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self.array = true;
        self
    }
    pub fn with_mips(mut self, mip_levels: u32) -> Self {
        self.mip_levels = mip_levels;
        self
    }
    pub fn with_depth(mut self, depth: u32) -> Self {
        self.depth = depth;
        self
    }
    pub fn with_usage(mut self, usage: vk::ImageUsageFlags) -> Self {
        self.usage = usage;
        self
    }
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.format)
    }
    pub fn image_type(&self) -> vk::ImageType {
        if self.depth > 1 {
            vk::ImageType::TYPE_3D
        } else {
            vk::ImageType::TYPE_2D
        }
    }
    pub fn view_type(&self) -> vk::ImageViewType {
        if self.depth > 1 {
            vk::ImageViewType::TYPE_3D
        } else if self.layers > 1 || self.array {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        }
    }
    pub fn create_info(&self) -> vk::ImageCreateInfo<'static> {
        vk::ImageCreateInfo::default()
            .image_type(self.image_type())
            .format(self.format)
            .extent(vk::Extent3D {
                width: self.width,
                height: self.height,
                depth: self.depth,
            })
            .mip_levels(self.mip_levels)
            .array_layers(self.layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(self.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
    }
}

pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => {
            vk::ImageAspectFlags::DEPTH
        }
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// An image with a view of all its mips and layers, plus optional per-mip views. Dropping it
/// releases the views, the image (unless a swapchain owns it) and its memory once the GPU is
/// done with them.
pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    /// One view per mip level (all layers), for storage writes into a single level.
    pub mip_views: Vec<vk::ImageView>,
    /// One 2D view per layer (all mips), when `desc.layer_views` asks for them.
    pub layer_views: Vec<vk::ImageView>,
    pub desc: ImageDesc,
    backing: Backing,
    release: Arc<ReleaseQueue>,
}

/// Who owns an [`Image`]'s `raw` handle and memory.
enum Backing {
    /// The image and its allocation from the context's allocator.
    Allocated(Option<Allocation>),
    /// The image, bound at a place in memory someone else owns (a graph arena).
    Placed,
    /// Only the views: the image belongs to a swapchain.
    ViewsOnly,
}

impl Drop for Image {
    fn drop(&mut self) {
        let mut items: Vec<Garbage> = self
            .mip_views
            .drain(..)
            .chain(self.layer_views.drain(..))
            .map(Garbage::ImageView)
            .collect();
        items.push(Garbage::ImageView(self.view));
        match &mut self.backing {
            Backing::Allocated(allocation) => {
                items.push(Garbage::Image(self.raw));
                items.extend(allocation.take().map(Garbage::Allocation));
            }
            Backing::Placed => items.push(Garbage::Image(self.raw)),
            Backing::ViewsOnly => {}
        }
        self.release.release(items);
    }
}

/// A block of device memory that the render graph places transient resources in. Released
/// on drop; drop the resources placed in it first (they are destroyed in drop order).
pub struct Arena {
    pub raw: vk::DeviceMemory,
    release: Arc<ReleaseQueue>,
}

impl Drop for Arena {
    fn drop(&mut self) {
        self.release.release(vec![Garbage::Memory(self.raw)]);
    }
}

impl Context {
    pub fn create_buffer(&self, desc: &BufferDesc) -> Result<Buffer, VkError> {
        if desc.size_bytes == 0 {
            return Err(VkError::Invalid(format!(
                "buffer `{}` has size 0",
                desc.name
            )));
        }
        let info = vk::BufferCreateInfo::default()
            .size(desc.size_bytes)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let raw = unsafe { self.device.create_buffer(&info, None) }
            .map_err(VkError::vk("create a buffer"))?;
        // SAFETY: raw was just created on this device.
        let requirements = unsafe { self.device.get_buffer_memory_requirements(raw) };
        let allocation = self.allocate(&desc.name, requirements, desc.location, true);
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: raw is unused.
                unsafe { self.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        // SAFETY: memory and offset come from an allocation that satisfies `requirements`.
        let bound = unsafe {
            self.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        };
        // From here on the buffer releases itself (also on the error below).
        let buffer = Buffer {
            raw,
            desc: desc.clone(),
            allocation: Some(allocation),
            release: Arc::clone(&self.release),
        };
        bound.map_err(VkError::vk("bind buffer memory"))?;
        self.set_name(raw, &desc.name);
        Ok(buffer)
    }

    pub fn create_image(&self, desc: &ImageDesc) -> Result<Image, VkError> {
        // SAFETY: valid device and create info.
        let raw = unsafe { self.device.create_image(&desc.create_info(), None) }
            .map_err(VkError::vk("create an image"))?;
        // SAFETY: raw was just created on this device.
        let requirements = unsafe { self.device.get_image_memory_requirements(raw) };
        let allocation =
            match self.allocate(&desc.name, requirements, MemoryLocation::GpuOnly, false) {
                Ok(a) => a,
                Err(e) => {
                    // SAFETY: raw is unused.
                    unsafe { self.device.destroy_image(raw, None) };
                    return Err(e);
                }
            };
        // SAFETY: allocation satisfies `requirements`.
        let bound = unsafe {
            self.device
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        };
        if let Err(e) = bound {
            // SAFETY: raw is unused.
            unsafe { self.device.destroy_image(raw, None) };
            self.release.free(allocation);
            return Err(VkError::vk("bind image memory")(e));
        }
        self.image_with_views(raw, desc, Backing::Allocated(Some(allocation)))
    }

    /// Wraps an image owned by a swapchain: the [`Image`] owns only its views.
    pub(super) fn wrap_swapchain_image(
        &self,
        raw: vk::Image,
        desc: &ImageDesc,
    ) -> Result<Image, VkError> {
        self.image_with_views(raw, desc, Backing::ViewsOnly)
    }

    /// Names `raw`, creates its views, and makes the [`Image`] that releases them (and, per
    /// `backing`, the image and its memory), also when creating a view fails.
    fn image_with_views(
        &self,
        raw: vk::Image,
        desc: &ImageDesc,
        backing: Backing,
    ) -> Result<Image, VkError> {
        self.set_name(raw, &desc.name);
        let mut image = Image {
            raw,
            view: vk::ImageView::null(),
            mip_views: Vec::new(),
            layer_views: Vec::new(),
            desc: desc.clone(),
            backing,
            release: Arc::clone(&self.release),
        };
        self.create_views(&mut image)?;
        Ok(image)
    }

    /// Creates the views of `image`. When one fails, the views made so far are released with
    /// `image` (destroying the null handle left in `view` is a no-op).
    fn create_views(&self, image: &mut Image) -> Result<(), VkError> {
        let (raw, desc) = (image.raw, image.desc.clone());
        let make_view = |view_type, (base_mip, mips): (u32, u32), (base_layer, layers)| {
            let info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(view_type)
                .format(desc.format)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: desc.aspect(),
                    base_mip_level: base_mip,
                    level_count: mips,
                    base_array_layer: base_layer,
                    layer_count: layers,
                });
            // SAFETY: raw is a live image of this device with a compatible format; the range
            // lies within its mips and layers.
            unsafe { self.device.create_image_view(&info, None) }
                .map_err(VkError::vk("create an image view"))
        };
        let make = |base_mip: u32, mips: u32| {
            make_view(desc.view_type(), (base_mip, mips), (0, desc.layers))
        };
        image.view = make(0, desc.mip_levels)?;
        if desc.mip_levels > 1 {
            for m in 0..desc.mip_levels {
                let view = make(m, 1)?;
                image.mip_views.push(view);
            }
        }
        if desc.layer_views && desc.depth == 1 {
            for l in 0..desc.layers {
                let view = make_view(vk::ImageViewType::TYPE_2D, (0, desc.mip_levels), (l, 1))?;
                image.layer_views.push(view);
            }
        }
        Ok(())
    }

    fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> Result<Allocation, VkError> {
        self.check_allocation_size(name, requirements.size)?;
        let mut alloc = self
            .release
            .allocator
            .lock()
            .map_err(|_| VkError::Allocation("allocator lock poisoned".into()))?;
        let alloc = alloc
            .as_mut()
            .ok_or_else(|| VkError::Allocation("the context is being destroyed".into()))?;
        let allocation = alloc
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| VkError::Allocation(format!("`{name}`: {e}")))?;
        self.release
            .live_allocations
            .insert(allocation_key(&allocation), name, allocation.size());
        Ok(allocation)
    }

    /// Creates a device-local buffer filled with `data` (staging copy, waits for completion).
    pub fn upload_buffer(
        &self,
        name: &str,
        data: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer, VkError> {
        let mut staging = self.create_buffer(&BufferDesc {
            name: format!("{name} (staging)"),
            size_bytes: data.len().max(4) as u64,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        })?;
        if let Some(m) = staging.mapped_mut() {
            m[..data.len()].copy_from_slice(data);
        }
        let dst = self.create_buffer(&BufferDesc {
            name: name.to_owned(),
            size_bytes: data.len().max(4) as u64,
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuOnly,
        })?;
        let result = self.one_time_submit(|device, cmd| {
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: data.len().max(4) as u64,
            }];
            // SAFETY: both buffers are live and large enough; cmd is recording.
            unsafe { device.cmd_copy_buffer(cmd, staging.raw, dst.raw, &region) };
        });
        drop(staging);
        result?;
        Ok(dst)
    }

    /// Creates an image (with `TRANSFER_DST` added to its usage) cleared to zero in `layout`:
    /// a history or table a render graph imports in that resting state. Waits.
    pub fn create_zeroed_image(
        &self,
        desc: &ImageDesc,
        layout: vk::ImageLayout,
    ) -> Result<Image, VkError> {
        let desc = desc
            .clone()
            .with_usage(desc.usage | vk::ImageUsageFlags::TRANSFER_DST);
        let image = self.create_image(&desc)?;
        self.clear_new_image(&image, vk::ClearColorValue { float32: [0.0; 4] }, layout)?;
        Ok(image)
    }

    /// Clears every mip and layer of a freshly created color image and leaves it in `layout`,
    /// so a render graph can import it in a resting state with that layout (imported images
    /// are assumed to be in their resting state before the first frame). Waits.
    pub fn clear_new_image(
        &self,
        image: &Image,
        value: vk::ClearColorValue,
        layout: vk::ImageLayout,
    ) -> Result<(), VkError> {
        let range = vk::ImageSubresourceRange {
            aspect_mask: image.desc.aspect(),
            base_mip_level: 0,
            level_count: image.desc.mip_levels,
            base_array_layer: 0,
            layer_count: image.desc.layers,
        };
        let barrier = |old, new, src_stage, src_access, dst_stage, dst_access| {
            [vk::ImageMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(dst_stage)
                .dst_access_mask(dst_access)
                .old_layout(old)
                .new_layout(new)
                .image(image.raw)
                .subresource_range(range)]
        };
        let to_dst = barrier(
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::PipelineStageFlags2::NONE,
            vk::AccessFlags2::NONE,
            vk::PipelineStageFlags2::CLEAR,
            vk::AccessFlags2::TRANSFER_WRITE,
        );
        let to_final = barrier(
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            layout,
            vk::PipelineStageFlags2::CLEAR,
            vk::AccessFlags2::TRANSFER_WRITE,
            vk::PipelineStageFlags2::ALL_COMMANDS,
            vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
        );
        self.one_time_submit(|device, cmd| {
            let dep = vk::DependencyInfo::default().image_memory_barriers(&to_dst);
            let dep_final = vk::DependencyInfo::default().image_memory_barriers(&to_final);
            // SAFETY: cmd is recording; the image is live and unused by any pending work
            // (it was just created); the range covers the whole image.
            unsafe {
                device.cmd_pipeline_barrier2(cmd, &dep);
                device.cmd_clear_color_image(
                    cmd,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &value,
                    &[range],
                );
                device.cmd_pipeline_barrier2(cmd, &dep_final);
            }
        })
    }

    /// Creates an image and moves it from UNDEFINED to `layout` without touching its
    /// contents: a render graph's cached image, which imports it in a resting state with that
    /// layout and renders it before any read (its cache starts invalid). Waits.
    pub fn create_image_in_layout(
        &self,
        desc: &ImageDesc,
        layout: vk::ImageLayout,
    ) -> Result<Image, VkError> {
        let image = self.create_image(desc)?;
        let range = vk::ImageSubresourceRange {
            aspect_mask: desc.aspect(),
            base_mip_level: 0,
            level_count: desc.mip_levels,
            base_array_layer: 0,
            layer_count: desc.layers,
        };
        let to_layout = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::NONE)
            .src_access_mask(vk::AccessFlags2::NONE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(layout)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(range)];
        self.one_time_submit(|device, cmd| {
            let dep = vk::DependencyInfo::default().image_memory_barriers(&to_layout);
            // SAFETY: cmd is recording; the image is live and unused by any pending work
            // (it was just created); the range covers the whole image.
            unsafe { device.cmd_pipeline_barrier2(cmd, &dep) };
        })?;
        Ok(image)
    }

    /// Fills mip 0 (all layers) of `image` with `data` (tightly packed texels) and leaves it
    /// in `layout_after`; see [`Context::write_image_levels`].
    pub fn write_image(
        &self,
        image: &Image,
        data: &[u8],
        layout_after: vk::ImageLayout,
    ) -> Result<(), VkError> {
        self.write_image_levels(image, &[data], layout_after)
    }

    /// Fills mips `0..levels.len()` (all layers) of `image` with tightly packed texels through
    /// a staging buffer and leaves them in `layout_after`; waits for completion. Like
    /// [`Context::upload_buffer`], this happens outside the render graph, between frames: the
    /// previous contents are discarded, so the image may be in any layout, but no frame in
    /// flight may use it (wait for the device first).
    pub fn write_image_levels(
        &self,
        image: &Image,
        levels: &[&[u8]],
        layout_after: vk::ImageLayout,
    ) -> Result<(), VkError> {
        let total: usize = levels.iter().map(|l| l.len()).sum();
        let mut staging = self.create_buffer(&BufferDesc {
            name: format!("{} (staging)", image.desc.name),
            size_bytes: total.max(4) as u64,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            location: MemoryLocation::CpuToGpu,
        })?;
        let desc = &image.desc;
        let mut regions = Vec::with_capacity(levels.len());
        if let Some(m) = staging.mapped_mut() {
            let mut offset = 0usize;
            for (level, data) in levels.iter().enumerate() {
                m[offset..offset + data.len()].copy_from_slice(data);
                regions.push(vk::BufferImageCopy {
                    buffer_offset: offset as u64,
                    buffer_row_length: 0,
                    buffer_image_height: 0,
                    image_subresource: vk::ImageSubresourceLayers {
                        aspect_mask: desc.aspect(),
                        mip_level: level as u32,
                        base_array_layer: 0,
                        layer_count: desc.layers,
                    },
                    image_offset: vk::Offset3D::default(),
                    image_extent: vk::Extent3D {
                        width: (desc.width >> level).max(1),
                        height: (desc.height >> level).max(1),
                        depth: (desc.depth >> level).max(1),
                    },
                });
                offset += data.len();
            }
        }
        let range = vk::ImageSubresourceRange {
            aspect_mask: desc.aspect(),
            base_mip_level: 0,
            level_count: levels.len().max(1) as u32,
            base_array_layer: 0,
            layer_count: desc.layers,
        };
        let to_dst = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_stage_mask(vk::PipelineStageFlags2::COPY)
            .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(range)];
        let to_final = [vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ)
            .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .new_layout(layout_after)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(range)];
        let result = self.one_time_submit(|device, cmd| {
            // SAFETY: cmd is recording; image and staging are live; every region lies inside
            // the staging buffer and the image's mip levels.
            unsafe {
                device.cmd_pipeline_barrier2(
                    cmd,
                    &vk::DependencyInfo::default().image_memory_barriers(&to_dst),
                );
                device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &regions,
                );
                device.cmd_pipeline_barrier2(
                    cmd,
                    &vk::DependencyInfo::default().image_memory_barriers(&to_final),
                );
            }
        });
        drop(staging);
        result
    }

    /// Records `f` into a fresh command buffer, submits it, and waits. Ends with a full
    /// memory barrier so that later submissions see the writes: uploads happen outside the
    /// render graph, before the frame that first uses the resource.
    pub fn one_time_submit(
        &self,
        f: impl FnOnce(&ash::Device, vk::CommandBuffer),
    ) -> Result<(), VkError> {
        let pool = self
            .upload_pool
            .lock()
            .map_err(|_| VkError::Invalid("upload pool lock poisoned".into()))?;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: pool is valid and externally synchronized by the mutex.
        let cmd = unsafe { self.device.allocate_command_buffers(&info) }
            .map_err(VkError::vk("allocate an upload command buffer"))?[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: cmd is a fresh primary command buffer.
        unsafe { self.device.begin_command_buffer(cmd, &begin) }
            .map_err(VkError::vk("begin an upload command buffer"))?;
        f(&self.device, cmd);
        let barrier = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        let dep = vk::DependencyInfo::default().memory_barriers(&barrier);
        // SAFETY: cmd is recording.
        unsafe {
            self.device.cmd_pipeline_barrier2(cmd, &dep);
            self.device.end_command_buffer(cmd)
        }
        .map_err(VkError::vk("end an upload command buffer"))?;
        let fence_info = vk::FenceCreateInfo::default();
        // SAFETY: valid device.
        let fence = unsafe { self.device.create_fence(&fence_info, None) }
            .map_err(VkError::vk("create a fence"))?;
        let cmds = [cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        let serial = self.release.next_submission();
        // SAFETY: queue access is serialized by holding the upload-pool lock; cmd is executable.
        let result = unsafe {
            self.device
                .queue_submit(self.queue, &submit, fence)
                .and_then(|_| self.device.wait_for_fences(&[fence], true, u64::MAX))
        };
        if result.is_ok() {
            self.release.mark_completed(serial);
        }
        // SAFETY: the fence was waited for (or submission failed), so cmd is not pending.
        unsafe {
            self.device.destroy_fence(fence, None);
            self.device.free_command_buffers(*pool, &cmds);
        }
        result.map_err(VkError::vk("submit an upload"))
    }
}

/// Raw memory for the render graph's transient arenas (the graph places resources in it).
impl Context {
    /// Memory requirements of an image that is not created yet (Vulkan 1.3 core query).
    pub fn image_requirements(&self, desc: &ImageDesc) -> vk::MemoryRequirements {
        let info = desc.create_info();
        let query = vk::DeviceImageMemoryRequirements::default().create_info(&info);
        let mut out = vk::MemoryRequirements2::default();
        // SAFETY: info is a valid create info; out is a plain output struct.
        unsafe {
            self.device
                .get_device_image_memory_requirements(&query, &mut out)
        };
        out.memory_requirements
    }

    /// Memory requirements of a buffer that is not created yet.
    pub fn buffer_requirements(
        &self,
        size_bytes: u64,
        usage: vk::BufferUsageFlags,
    ) -> vk::MemoryRequirements {
        let info = vk::BufferCreateInfo::default()
            .size(size_bytes.max(1))
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let query = vk::DeviceBufferMemoryRequirements::default().create_info(&info);
        let mut out = vk::MemoryRequirements2::default();
        // SAFETY: info is a valid create info; out is a plain output struct.
        unsafe {
            self.device
                .get_device_buffer_memory_requirements(&query, &mut out)
        };
        out.memory_requirements
    }

    /// The first device-local memory type among `type_bits` (any type if none is local).
    pub fn device_local_type(&self, type_bits: u32) -> Option<u32> {
        let props = self.memory_properties();
        let types = &props.memory_types[..props.memory_type_count as usize];
        let pick = |want: vk::MemoryPropertyFlags| {
            types
                .iter()
                .enumerate()
                .find(|(i, t)| type_bits & (1 << i) != 0 && t.property_flags.contains(want))
                .map(|(i, _)| i as u32)
        };
        pick(vk::MemoryPropertyFlags::DEVICE_LOCAL)
            .or_else(|| pick(vk::MemoryPropertyFlags::empty()))
    }

    /// Refuses one allocation larger than `maxMemoryAllocationSize` before the driver sees it
    /// (the renderer checks its sizes earlier, naming the flags; this is the last guard).
    fn check_allocation_size(&self, name: &str, size_bytes: u64) -> Result<(), VkError> {
        let max = self.info.max_memory_allocation_bytes;
        if size_bytes > max {
            return Err(VkError::Allocation(format!(
                "`{name}` needs {size_bytes} bytes in one allocation, more than this device \
                 allocates at once (maxMemoryAllocationSize {max} bytes)"
            )));
        }
        Ok(())
    }

    pub fn allocate_arena(
        &self,
        memory_type: u32,
        size_bytes: u64,
        name: &str,
    ) -> Result<Arena, VkError> {
        self.check_allocation_size(name, size_bytes)?;
        let info = vk::MemoryAllocateInfo::default()
            .allocation_size(size_bytes.max(1))
            .memory_type_index(memory_type);
        // SAFETY: valid device; memory_type comes from device_local_type.
        let memory = unsafe { self.device.allocate_memory(&info, None) }.map_err(|e| {
            VkError::Allocation(format!(
                "transient arena `{name}` of {size_bytes} bytes: {e}"
            ))
        })?;
        self.set_name(memory, name);
        self.release
            .live_allocations
            .insert((memory.as_raw(), u64::MAX), name, size_bytes.max(1));
        Ok(Arena {
            raw: memory,
            release: Arc::clone(&self.release),
        })
    }

    /// Creates an image bound at `offset` in `memory` (the graph checked size and alignment).
    pub fn create_image_in(
        &self,
        desc: &ImageDesc,
        memory: &Arena,
        offset: u64,
    ) -> Result<Image, VkError> {
        // SAFETY: valid create info.
        let raw = unsafe { self.device.create_image(&desc.create_info(), None) }
            .map_err(VkError::vk("create a transient image"))?;
        // SAFETY: the graph placed [offset, offset+size) inside memory with the required alignment.
        if let Err(e) = unsafe { self.device.bind_image_memory(raw, memory.raw, offset) } {
            // SAFETY: raw is unused.
            unsafe { self.device.destroy_image(raw, None) };
            return Err(VkError::vk("bind a transient image")(e));
        }
        self.image_with_views(raw, desc, Backing::Placed)
    }

    /// Creates a buffer bound at `offset` in `memory`.
    pub fn create_buffer_in(
        &self,
        desc: &BufferDesc,
        memory: &Arena,
        offset: u64,
    ) -> Result<Buffer, VkError> {
        let info = vk::BufferCreateInfo::default()
            .size(desc.size_bytes.max(1))
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid create info.
        let raw = unsafe { self.device.create_buffer(&info, None) }
            .map_err(VkError::vk("create a transient buffer"))?;
        let buffer = Buffer {
            raw,
            desc: desc.clone(),
            allocation: None,
            release: Arc::clone(&self.release),
        };
        // SAFETY: as for create_image_in.
        unsafe { self.device.bind_buffer_memory(raw, memory.raw, offset) }
            .map_err(VkError::vk("bind a transient buffer"))?;
        self.set_name(raw, &desc.name);
        Ok(buffer)
    }
}

impl Context {
    /// Creates a sampled image from tightly packed texel data per mip level (level 0 first)
    /// and leaves it in SHADER_READ_ONLY_OPTIMAL. A one-time upload outside the render graph:
    /// the image is persistent and the graph imports it in that state.
    pub fn upload_image(&self, desc: &ImageDesc, levels: &[Vec<u8>]) -> Result<Image, VkError> {
        let mut desc = desc.clone();
        desc.mip_levels = levels.len().max(1) as u32;
        desc.usage |= vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let image = self.create_image(&desc)?;
        let slices: Vec<&[u8]> = levels.iter().map(Vec::as_slice).collect();
        self.write_image_levels(&image, &slices, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)?;
        Ok(image)
    }
}
