//! Frames in flight: per-frame command buffers, fences, and timestamp query pools.
//!
//! Timestamps of a frame are read when its slot comes around again, after its fence has
//! signalled, so reading never stalls the GPU (docs/ARCHITECTURE.md, "The path of
//! a frame").

use super::release::{Garbage, ReleaseQueue};
use super::{Cmd, Context, VkError};
use ash::vk;
use std::sync::Arc;

pub const MAX_FRAMES_IN_FLIGHT: usize = 2;

/// Records a begin/end timestamp pair per pass into one query pool.
pub struct TimestampRecorder {
    pool: vk::QueryPool,
    capacity_pairs: u32,
    names: Vec<String>,
}

impl TimestampRecorder {
    /// Starts a scope for `name`; returns its index, or `None` when the pool is full.
    pub fn begin(&mut self, cmd: &Cmd, name: &str) -> Option<u32> {
        let idx = self.names.len() as u32;
        if idx >= self.capacity_pairs {
            return None;
        }
        self.names.push(name.to_owned());
        cmd.write_timestamp(self.pool, 2 * idx, false);
        Some(idx)
    }

    pub fn end(&mut self, cmd: &Cmd, idx: Option<u32>) {
        if let Some(i) = idx {
            cmd.write_timestamp(self.pool, 2 * i + 1, true);
        }
    }
}

pub struct FrameSlot {
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    pub timestamps: TimestampRecorder,
    /// Serial (see `release.rs`) of the slot's submission not yet waited for, if any.
    submitted: Option<u64>,
}

/// The ring of frames in flight. Waiting for a slot's fence tells the context's release queue
/// that the slot's frame completed, which destroys the objects dropped while it was in flight.
/// Dropping the loop releases its command pools, fences and query pools the same way.
pub struct FrameLoop {
    slots: Vec<FrameSlot>,
    current: usize,
    frame_index: u64,
    release: Arc<ReleaseQueue>,
}

impl Drop for FrameLoop {
    fn drop(&mut self) {
        let items = self
            .slots
            .iter()
            .flat_map(|slot| {
                [
                    Garbage::QueryPool(slot.timestamps.pool),
                    Garbage::Fence(slot.fence),
                    Garbage::CommandPool(slot.pool),
                ]
            })
            .collect();
        self.release.release(items);
    }
}

/// Frames in flight at one moment ([`FrameLoop::in_flight`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InFlight {
    /// Submitted, completion not yet seen by the loop.
    pub submitted: usize,
    /// Of those, still running on the device.
    pub running: usize,
}

/// GPU milliseconds of one pass in one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    pub name: String,
    pub gpu_ms: f64,
}

impl FrameLoop {
    pub fn new(ctx: &Context, frames_in_flight: usize, max_passes: u32) -> Result<Self, VkError> {
        let mut frames = Self {
            slots: Vec::new(),
            current: 0,
            frame_index: 0,
            release: Arc::clone(&ctx.release),
        };
        for i in 0..frames_in_flight.clamp(1, MAX_FRAMES_IN_FLIGHT) {
            let slot = Self::new_slot(ctx, i, max_passes)?;
            frames.slots.push(slot);
        }
        Ok(frames)
    }

    /// The objects of slot `i`; what was made before a failure is destroyed here.
    fn new_slot(ctx: &Context, i: usize, max_passes: u32) -> Result<FrameSlot, VkError> {
        let mut made = Vec::new();
        let result = Self::make_slot(ctx, i, max_passes, &mut made);
        if result.is_err() {
            ctx.release.release(made);
        }
        result
    }

    fn make_slot(
        ctx: &Context,
        i: usize,
        max_passes: u32,
        made: &mut Vec<Garbage>,
    ) -> Result<FrameSlot, VkError> {
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device; the loop releases all objects below when it drops.
        let pool = unsafe { ctx.device.create_command_pool(&pool_info, None) }
            .map_err(VkError::vk("create a frame command pool"))?;
        made.push(Garbage::CommandPool(pool));
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: pool is live.
        let cmd = unsafe { ctx.device.allocate_command_buffers(&alloc) }
            .map_err(VkError::vk("allocate a frame command buffer"))?[0];
        let fence_info = vk::FenceCreateInfo::default();
        // SAFETY: valid device.
        let fence = unsafe { ctx.device.create_fence(&fence_info, None) }
            .map_err(VkError::vk("create a frame fence"))?;
        made.push(Garbage::Fence(fence));
        let query_info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2 * max_passes.max(1));
        // SAFETY: valid device.
        let query_pool = unsafe { ctx.device.create_query_pool(&query_info, None) }
            .map_err(VkError::vk("create a timestamp query pool"))?;
        made.push(Garbage::QueryPool(query_pool));
        // SAFETY: hostQueryReset is enabled; the pool is not in use.
        unsafe {
            ctx.device
                .reset_query_pool(query_pool, 0, 2 * max_passes.max(1))
        };
        ctx.set_name(cmd, &format!("frame slot {i}"));
        Ok(FrameSlot {
            pool,
            cmd,
            fence,
            timestamps: TimestampRecorder {
                pool: query_pool,
                capacity_pairs: max_passes.max(1),
                names: Vec::new(),
            },
            submitted: None,
        })
    }

    /// Index of the slot the next `begin` uses.
    pub fn current_slot(&self) -> usize {
        self.current
    }

    /// Frames submitted so far.
    pub fn frame_index(&self) -> u64 {
        self.frame_index
    }

    /// Waits for the current slot's previous frame, reads its pass timings, and starts
    /// recording. Returns the slot index, a recorder, and the finished frame's timings.
    pub fn begin<'a>(
        &'a mut self,
        ctx: &'a Context,
    ) -> Result<(usize, Cmd<'a>, &'a mut TimestampRecorder, Vec<PassTiming>), VkError> {
        let slot_index = self.current;
        let slot = &mut self.slots[slot_index];
        let mut timings = Vec::new();
        if slot.submitted.is_some() {
            wait_for_slot(ctx, slot)?;
            timings = read_timings(ctx, &slot.timestamps)?;
        }
        // SAFETY: the slot's previous submission has completed (fence waited above).
        unsafe {
            ctx.device
                .reset_command_pool(slot.pool, vk::CommandPoolResetFlags::empty())
                .map_err(VkError::vk("reset a frame command pool"))?;
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            ctx.device
                .begin_command_buffer(slot.cmd, &begin)
                .map_err(VkError::vk("begin a frame command buffer"))?;
        }
        let cmd = Cmd::new(ctx, slot.cmd);
        let ts = &mut slot.timestamps;
        cmd.reset_queries(ts.pool, 0, 2 * ts.capacity_pairs);
        ts.names.clear();
        Ok((slot_index, cmd, ts, timings))
    }

    /// Ends the current slot's command buffer and submits it, waiting on and signalling the
    /// given semaphores (a swapchain's; none when headless).
    pub fn submit(
        &mut self,
        ctx: &Context,
        wait: &[(vk::Semaphore, vk::PipelineStageFlags2)],
        signal: &[vk::Semaphore],
    ) -> Result<(), VkError> {
        let slot = &mut self.slots[self.current];
        let waits: Vec<vk::SemaphoreSubmitInfo> = wait
            .iter()
            .map(|&(s, stage)| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(s)
                    .stage_mask(stage)
            })
            .collect();
        let signals: Vec<vk::SemaphoreSubmitInfo> = signal
            .iter()
            .map(|&s| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(s)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            })
            .collect();
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(slot.cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        // SAFETY: the command buffer is recording (begun in `begin`).
        unsafe { ctx.device.end_command_buffer(slot.cmd) }
            .map_err(VkError::vk("end a frame command buffer"))?;
        let serial = ctx.release.next_submission();
        // SAFETY: the command buffer is executable; the fence is unsignalled.
        unsafe { ctx.device.queue_submit2(ctx.queue, &submit, slot.fence) }
            .map_err(VkError::vk("submit a frame"))?;
        slot.submitted = Some(serial);
        self.current = (self.current + 1) % self.slots.len();
        self.frame_index += 1;
        Ok(())
    }

    /// The frames in flight: those submitted whose completion the loop has not seen yet (it
    /// waits for a slot only when the slot comes round again), and of those the ones still
    /// running now (fence not signalled).
    pub fn in_flight(&self, ctx: &Context) -> Result<InFlight, VkError> {
        let mut n = InFlight::default();
        for slot in self.slots.iter().filter(|s| s.submitted.is_some()) {
            n.submitted += 1;
            // SAFETY: the fence belongs to this device and is not being destroyed.
            let done = unsafe { ctx.device.get_fence_status(slot.fence) }
                .map_err(VkError::vk("query a frame fence"))?;
            n.running += usize::from(!done);
        }
        Ok(n)
    }

    /// Waits for every submitted frame and returns their timings, oldest first.
    pub fn finish(&mut self, ctx: &Context) -> Result<Vec<Vec<PassTiming>>, VkError> {
        let mut all = Vec::new();
        let n = self.slots.len();
        for k in 0..n {
            let slot = &mut self.slots[(self.current + k) % n];
            if slot.submitted.is_some() {
                wait_for_slot(ctx, slot)?;
                all.push(read_timings(ctx, &slot.timestamps)?);
            }
        }
        Ok(all)
    }
}

/// Waits for the slot's submitted frame, resets its fence, and tells the release queue the
/// frame (and every earlier submission) completed.
fn wait_for_slot(ctx: &Context, slot: &mut FrameSlot) -> Result<(), VkError> {
    // SAFETY: the fence belongs to this device and was submitted with the slot's last frame.
    unsafe {
        ctx.device
            .wait_for_fences(&[slot.fence], true, u64::MAX)
            .map_err(VkError::vk("wait for a frame"))?;
        ctx.device
            .reset_fences(&[slot.fence])
            .map_err(VkError::vk("reset a frame fence"))?;
    }
    if let Some(serial) = slot.submitted.take() {
        ctx.release.mark_completed(serial);
    }
    Ok(())
}

fn read_timings(ctx: &Context, ts: &TimestampRecorder) -> Result<Vec<PassTiming>, VkError> {
    let n = ts.names.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut data = vec![0u64; 2 * n];
    // SAFETY: the frame that wrote these queries has completed (its fence was waited for), so
    // the results are available without WAIT; data holds 2n u64 values.
    unsafe {
        ctx.device
            .get_query_pool_results(ts.pool, 0, &mut data, vk::QueryResultFlags::TYPE_64)
            .map_err(VkError::vk("read timestamps"))?;
    }
    let bits = ctx.info.timestamp_valid_bits;
    let mask = if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    };
    let period = f64::from(ctx.info.timestamp_period_ns);
    Ok(ts
        .names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let (a, b) = (data[2 * i] & mask, data[2 * i + 1] & mask);
            let ticks = b.wrapping_sub(a) & mask;
            PassTiming {
                name: name.clone(),
                gpu_ms: ticks as f64 * period * 1e-6,
            }
        })
        .collect())
}
