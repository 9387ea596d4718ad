//! Device memory a frame and its voxel grid need, counted before anything is allocated, so
//! that a size that cannot fit the device is an error naming the flag to lower instead of a
//! failure inside the driver.
//!
//! Two limits apply: one allocation may not exceed `maxMemoryAllocationSize`
//! (`VkPhysicalDeviceMaintenance3Properties`, Vulkan 1.1), and everything together may not
//! exceed the device-local heap. Sizes come from the device's own memory requirements
//! (`vkGetDeviceImageMemoryRequirements` / `…BufferMemoryRequirements`) of the very
//! descriptors the renderer creates: the read-back buffers, the frame-sized histories (TAA,
//! path tracer, SSGI), the voxel column image and buffer, and the graph's transient arenas
//! (G-buffer, direct and indirect radiance, post chain), one set per frame in flight.

use super::RenderError;
pub use crate::graph::texel_bytes_of;
use crate::vk::{BufferDesc, Context, ImageDesc};

const GIB: f64 = (1u64 << 30) as f64;

/// One resource (or arena) and the bytes the device asks for it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryNeed {
    pub name: String,
    pub bytes: u64,
    /// A buffer, also bounded by `maxBufferSize`.
    pub is_buffer: bool,
}

impl MemoryNeed {
    /// The device's size of an image that is not created yet, never less than its texels
    /// (a driver may report a size wrapped at 32 bits for images beyond what it can create).
    pub fn image(ctx: &Context, desc: &ImageDesc) -> Self {
        Self {
            name: desc.name.clone(),
            bytes: ctx.image_requirements(desc).size.max(texel_bytes_of(desc)),
            is_buffer: false,
        }
    }

    /// The device's size of a buffer that is not created yet, never less than its size.
    pub fn buffer(ctx: &Context, desc: &BufferDesc) -> Self {
        Self {
            name: desc.name.clone(),
            bytes: ctx
                .buffer_requirements(desc.size_bytes, desc.usage)
                .size
                .max(desc.size_bytes),
            is_buffer: true,
        }
    }
}

/// Which device limit a set of resources exceeds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MemoryLimit {
    /// One allocation (named) is larger than `maxMemoryAllocationSize` (or a buffer than
    /// `maxBufferSize`).
    OneAllocation(String),
    /// All of them together (plus what is already allocated) exceed the device-local heap.
    Heap,
}

/// A frame or voxel grid that does not fit the device: what, the flags that size it, the
/// bytes needed against the bytes available under the limit it breaks.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.message())]
pub struct MemoryError {
    /// What was being sized, e.g. "the 16384×16384 frame".
    pub subject: String,
    /// The flags (and scene keys) that size it, e.g. "--width/--height".
    pub flags: &'static str,
    pub limit: MemoryLimit,
    pub need_bytes: u64,
    pub available_bytes: u64,
    /// What the device already held when this was sized (the voxel grid's volumes, shadow
    /// and light maps, created before the frame's transients).
    pub held_bytes: u64,
}

impl MemoryError {
    fn message(&self) -> String {
        let (need, have) = (
            self.need_bytes as f64 / GIB,
            self.available_bytes as f64 / GIB,
        );
        match &self.limit {
            MemoryLimit::OneAllocation(name) => format!(
                "{}: `{name}` needs {need:.2} GiB ({} bytes) in one allocation, more than this \
                 device allocates at once ({have:.2} GiB, {} bytes: maxMemoryAllocationSize, \
                 for buffers also maxBufferSize): lower {}",
                self.subject, self.need_bytes, self.available_bytes, self.flags
            ),
            MemoryLimit::Heap => {
                let mut m = format!(
                    "{} needs {need:.2} GiB ({} bytes) of device memory, more than is left of \
                     this device's largest device-local heap ({have:.2} GiB, {} bytes): lower {}",
                    self.subject, self.need_bytes, self.available_bytes, self.flags
                );
                // When what exists already holds most of the heap, lowering the subject's own
                // flags may not be enough: say so, and what sizes the rest.
                if self.held_bytes > self.need_bytes {
                    m += &format!(
                        "; {:.2} GiB of the heap is held already by what was made before it (the \
                         voxel grid and its volumes, shadow and light maps): a smaller grid \
                         (--voxels, --voxel-layers, the scene's `[voxel]` table) or smaller shadow \
                         maps (--shadow-resolution) leave more",
                        self.held_bytes as f64 / GIB
                    );
                }
                m
            }
        }
    }
}

/// Checks `needs` against the device: each against `maxMemoryAllocationSize`, their sum
/// against the device-local heap less `already_bytes` (what the context holds now).
pub fn check_fits(
    ctx: &Context,
    subject: &str,
    flags: &'static str,
    needs: &[MemoryNeed],
    already_bytes: u64,
) -> Result<(), RenderError> {
    let error = |limit, need_bytes, available_bytes| {
        RenderError::OutOfDeviceMemory(MemoryError {
            subject: subject.to_owned(),
            flags,
            limit,
            need_bytes,
            available_bytes,
            held_bytes: already_bytes,
        })
    };
    let max_one = |n: &MemoryNeed| match n.is_buffer {
        true => ctx
            .info
            .max_memory_allocation_bytes
            .min(ctx.info.max_buffer_bytes),
        false => ctx.info.max_memory_allocation_bytes,
    };
    if let Some(n) = needs.iter().find(|n| n.bytes > max_one(n)) {
        return Err(error(
            MemoryLimit::OneAllocation(n.name.clone()),
            n.bytes,
            max_one(n),
        ));
    }
    let total: u64 = needs.iter().fold(0u64, |s, n| s.saturating_add(n.bytes));
    let left = ctx
        .info
        .device_local_heap_bytes
        .saturating_sub(already_bytes);
    if total > left {
        return Err(error(MemoryLimit::Heap, total, left));
    }
    Ok(())
}
