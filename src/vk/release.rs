//! GPU objects release themselves: every owning wrapper of this layer ([`Buffer`](super::Buffer),
//! [`Image`](super::Image), the pipelines, [`Sampler`](super::Sampler), …) holds a clone of the
//! context's [`ReleaseQueue`] and hands its raw handles to it when it drops. The queue destroys
//! them only once the GPU can no longer use them.
//!
//! Every queue submission takes the next serial number ([`ReleaseQueue::submitted`]); waiting
//! for a submission's fence marks that serial, and by Vulkan's submission order every earlier
//! one, complete ([`ReleaseQueue::completed`]). An object dropped while serial `s` is the
//! latest submission waits in the queue until `s` completed: the frame loop collects the
//! queue each time it waits for a frame slot, and [`Context::finish`](super::Context::finish)
//! (or the context's drop) waits for the device and destroys whatever is left before the
//! allocator and the device go. When nothing is in flight an object is destroyed at once, as
//! an explicit `destroy` after `wait_idle` did. (Deferred deletion per frame, as in kajiya's
//! and Granite's devices.)
//!
//! An object must be dropped only after the last command buffer that records it was submitted
//! (the natural order: owners outlive the frames they record). An object dropped after its
//! context was destroyed touches nothing: it is logged and leaked, and [`Context::finish`]
//! already reported its memory as never freed.

use ash::khr;
use ash::vk;
use ash::vk::Handle;
use gpu_allocator::vulkan::{Allocation, Allocator};
use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

/// A raw handle (or memory) waiting to be destroyed. Batches are destroyed in the order their
/// items were pushed (views before their image, an image before its memory, a swapchain before
/// its surface).
pub(super) enum Garbage {
    Buffer(vk::Buffer),
    Image(vk::Image),
    ImageView(vk::ImageView),
    /// Memory from the context's allocator.
    Allocation(Allocation),
    /// A dedicated `vkAllocateMemory` block (the graph's transient arenas).
    Memory(vk::DeviceMemory),
    Pipeline(vk::Pipeline),
    PipelineLayout(vk::PipelineLayout),
    DescriptorSetLayout(vk::DescriptorSetLayout),
    Sampler(vk::Sampler),
    ShaderModule(vk::ShaderModule),
    QueryPool(vk::QueryPool),
    Fence(vk::Fence),
    Semaphore(vk::Semaphore),
    CommandPool(vk::CommandPool),
    Swapchain(khr::swapchain::Device, vk::SwapchainKHR),
    Surface(khr::surface::Instance, vk::SurfaceKHR),
}

struct State {
    /// Serial of the latest submission known to have completed.
    completed: u64,
    /// Batches waiting for the submission serial they were tagged with, oldest first.
    pending: VecDeque<(u64, Vec<Garbage>)>,
    /// The device is destroyed (or about to be): nothing may be destroyed any more.
    closed: bool,
}

/// The context's release queue, shared (`Arc`) by every object that owns a Vulkan handle.
/// Owns the memory allocator and the table of live allocations, so that an object can free
/// its memory without a reference to the [`Context`](super::Context).
pub struct ReleaseQueue {
    device: ash::Device,
    pub(super) allocator: Mutex<Option<Allocator>>,
    pub(super) live_allocations: LiveAllocations,
    /// Serial of the latest queue submission (0: none yet).
    submitted: AtomicU64,
    state: Mutex<State>,
}

impl std::fmt::Debug for ReleaseQueue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReleaseQueue")
            .field("submitted", &self.submitted.load(Ordering::SeqCst))
            .finish_non_exhaustive()
    }
}

impl ReleaseQueue {
    pub(super) fn new(device: ash::Device, allocator: Allocator) -> Arc<Self> {
        Arc::new(Self {
            device,
            allocator: Mutex::new(Some(allocator)),
            live_allocations: LiveAllocations::default(),
            submitted: AtomicU64::new(0),
            state: Mutex::new(State {
                completed: 0,
                pending: VecDeque::new(),
                closed: false,
            }),
        })
    }

    fn state(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Takes the serial of a submission about to be made. Call right before `vkQueueSubmit*`
    /// (under the same external synchronization of the queue).
    pub(super) fn next_submission(&self) -> u64 {
        self.submitted.fetch_add(1, Ordering::SeqCst) + 1
    }

    /// Serial of the latest submission made.
    pub fn submitted(&self) -> u64 {
        self.submitted.load(Ordering::SeqCst)
    }

    /// Serial of the latest submission known to have completed.
    pub fn completed(&self) -> u64 {
        self.state().completed
    }

    /// Batches of dropped objects waiting for their submission to complete.
    pub fn pending(&self) -> usize {
        self.state().pending.len()
    }

    /// Records that submission `serial` (and so every earlier one: a fence's signal covers all
    /// work submitted before it on the queue) has completed, and destroys what waited for it.
    pub(super) fn mark_completed(&self, serial: u64) {
        let mut state = self.state();
        state.completed = state.completed.max(serial);
        self.collect(&mut state);
    }

    /// Hands `items` over for destruction once the latest submission made so far completed;
    /// destroys them now when it already has.
    pub(super) fn release(&self, items: Vec<Garbage>) {
        if items.is_empty() {
            return;
        }
        let tag = self.submitted();
        let mut state = self.state();
        if state.closed {
            drop(state);
            self.leak(items);
            return;
        }
        state.pending.push_back((tag, items));
        self.collect(&mut state);
    }

    /// Destroys every pending batch whose submission completed, oldest first.
    fn collect(&self, state: &mut State) {
        if state.closed {
            return;
        }
        while state
            .pending
            .front()
            .is_some_and(|(tag, _)| *tag <= state.completed)
        {
            if let Some((_, items)) = state.pending.pop_front() {
                self.destroy_all(items);
            }
        }
    }

    /// Destroys everything still pending and refuses any later release: the caller (the
    /// context's teardown) waited for the device, and destroys the allocator and the device
    /// next.
    pub(super) fn close(&self) {
        let mut state = self.state();
        state.completed = self.submitted();
        self.collect(&mut state);
        state.closed = true;
        if let Ok(mut alloc) = self.allocator.lock() {
            // Frees the allocator's memory blocks while the device is still alive.
            drop(alloc.take());
        }
    }

    /// An object outlived its context: nothing of its device may be touched any more.
    fn leak(&self, items: Vec<Garbage>) {
        log::error!(
            "{} Vulkan object(s) dropped after their context was destroyed: leaked (drop GPU \
             objects before Context::finish)",
            items.len()
        );
        // The allocations are only records of memory the destroyed device already took back.
        std::mem::forget(items);
    }

    fn destroy_all(&self, items: Vec<Garbage>) {
        for item in items {
            self.destroy(item);
        }
    }

    fn destroy(&self, item: Garbage) {
        let d = &self.device;
        // SAFETY: every submission that may use the object has completed (the release tag is
        // at most the completed serial, or the device was waited idle in `close`), the queue is
        // not closed, so the device is alive, and each handle was created on this device and is
        // destroyed exactly once (its owner gave it up on drop).
        unsafe {
            match item {
                Garbage::Buffer(b) => d.destroy_buffer(b, None),
                Garbage::Image(i) => d.destroy_image(i, None),
                Garbage::ImageView(v) => d.destroy_image_view(v, None),
                Garbage::Allocation(a) => self.free(a),
                Garbage::Memory(m) => {
                    self.live_allocations.remove((m.as_raw(), u64::MAX));
                    d.free_memory(m, None);
                }
                Garbage::Pipeline(p) => d.destroy_pipeline(p, None),
                Garbage::PipelineLayout(l) => d.destroy_pipeline_layout(l, None),
                Garbage::DescriptorSetLayout(l) => d.destroy_descriptor_set_layout(l, None),
                Garbage::Sampler(s) => d.destroy_sampler(s, None),
                Garbage::ShaderModule(m) => d.destroy_shader_module(m, None),
                Garbage::QueryPool(q) => d.destroy_query_pool(q, None),
                Garbage::Fence(f) => d.destroy_fence(f, None),
                Garbage::Semaphore(s) => d.destroy_semaphore(s, None),
                Garbage::CommandPool(p) => d.destroy_command_pool(p, None),
                Garbage::Swapchain(loader, s) => loader.destroy_swapchain(s, None),
                Garbage::Surface(loader, s) => loader.destroy_surface(s, None),
            }
        }
    }

    /// Returns an allocation to the allocator and drops it from the live table.
    pub(super) fn free(&self, allocation: Allocation) {
        self.live_allocations.remove(allocation_key(&allocation));
        if let Ok(mut alloc) = self.allocator.lock() {
            if let Some(alloc) = alloc.as_mut() {
                if let Err(e) = alloc.free(allocation) {
                    log::error!("freeing GPU memory failed: {e}");
                }
            }
        }
    }

    /// Waits for the device and destroys what waited for it (teardown of objects that must go
    /// before something outside the context, e.g. a swapchain before its window). Does nothing
    /// once the context is destroyed.
    pub(super) fn wait_idle(&self) {
        if self.state().closed {
            return;
        }
        let target = self.submitted();
        // SAFETY: the device is alive (the queue is not closed; `close` runs before the device
        // is destroyed, on the thread that owns the context).
        let _ = unsafe { self.device.device_wait_idle() };
        self.mark_completed(target);
    }
}

/// GPU memory handed out and not yet freed, keyed by (memory handle, offset), with the name
/// it was allocated under and its size: what [`Context::finish`] reports as leaked, and what
/// [`Context::allocated_bytes`] sums. gpu-allocator only logs its leaks at shutdown; this
/// table lets teardown fail on them instead.
#[derive(Debug, Default)]
pub struct LiveAllocations(Mutex<BTreeMap<(u64, u64), (String, u64)>>);

impl LiveAllocations {
    pub(super) fn insert(&self, key: (u64, u64), name: &str, size_bytes: u64) {
        if let Ok(mut m) = self.0.lock() {
            m.insert(key, (name.to_owned(), size_bytes));
        }
    }
    pub(super) fn remove(&self, key: (u64, u64)) {
        if let Ok(mut m) = self.0.lock() {
            m.remove(&key);
        }
    }
    /// The names of every allocation still alive, sorted.
    pub(super) fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .0
            .lock()
            .map(|m| m.values().map(|(name, _)| name.clone()).collect())
            .unwrap_or_default();
        names.sort();
        names
    }
    /// Bytes of every allocation still alive.
    pub(super) fn total_bytes(&self) -> u64 {
        self.0
            .lock()
            .map(|m| m.values().map(|(_, size)| size).sum())
            .unwrap_or(0)
    }
}

/// The key of an allocation in the context's table of live allocations.
pub(super) fn allocation_key(allocation: &Allocation) -> (u64, u64) {
    // SAFETY: only the handle's value is read, as a key; no memory is touched.
    let memory = unsafe { allocation.memory() };
    (memory.as_raw(), allocation.offset())
}
