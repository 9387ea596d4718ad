//! Running the frame headless: one frame (or a path tracer's accumulation) to images, or many
//! frames for per-pass GPU timings.

use super::{RenderError, Renderer};
use crate::eval::HdrImage;
use crate::graph::GraphExecutor;
use crate::scene::Scene;
use crate::vk::{Context, FrameLoop, PassTiming, MAX_FRAMES_IN_FLIGHT};

/// The result of [`render_image`].
pub struct RenderOutput {
    pub hdr: HdrImage,
    /// Tone-mapped sRGB RGBA8.
    pub ldr: Vec<u8>,
    pub timings: Vec<PassTiming>,
    /// Compiled-graph facts: live passes, culled passes, transient bytes aliased / not.
    pub live_passes: Vec<String>,
    pub transient_bytes: (u64, u64),
    /// A debug view's description ([`Renderer::debug_description`]).
    pub debug_description: Option<String>,
}

/// Renders one frame of `scene` headless.
pub fn render_image(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
) -> Result<RenderOutput, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    // The path tracer converges over frames; everything else is done in one.
    let frames = match settings.gi.method {
        crate::gi::GiMethod::Pathtrace => settings.gi.accumulate_frames.max(1) as usize,
        _ => 1,
    };
    let result = run_frames(ctx, &mut renderer, frames);
    let out = result.map(|timings| {
        let hdr = renderer.hdr_image();
        let ldr = renderer.ldr_pixels();
        let description = renderer.debug_description(&hdr);
        (hdr, ldr, (timings, description))
    });
    let (exec_facts, out) = match out {
        Ok((hdr, ldr, ((timings, live, bytes), description))) => {
            (Some((live, bytes)), Ok((hdr, ldr, timings, description)))
        }
        Err(e) => (None, Err(e)),
    };
    renderer.destroy(ctx);
    let (hdr, ldr, timings, debug_description) = out?;
    let (live_passes, transient_bytes) = exec_facts.unwrap_or_default();
    Ok(RenderOutput {
        hdr,
        ldr,
        timings,
        live_passes,
        transient_bytes,
        debug_description,
    })
}

type FrameFacts = (Vec<PassTiming>, Vec<String>, (u64, u64));

/// Runs `frames` frames; returns the last frame's timings and graph facts.
fn run_frames(
    ctx: &Context,
    renderer: &mut Renderer,
    frames: usize,
) -> Result<FrameFacts, RenderError> {
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let result = (|| -> Result<FrameFacts, RenderError> {
        let mut frame_loop = FrameLoop::new(
            ctx,
            MAX_FRAMES_IN_FLIGHT,
            exec.compiled().order.len() as u32,
        )?;
        let mut last = Vec::new();
        let run = (|| -> Result<(), RenderError> {
            for _ in 0..frames {
                let slot = frame_loop.current_slot();
                // begin() waits for the slot's fence before the frame constants are rewritten.
                let (slot_b, cmd, ts, done) = frame_loop.begin(ctx)?;
                debug_assert_eq!(slot, slot_b);
                if !done.is_empty() {
                    last = done;
                }
                renderer.write_frame(slot);
                exec.record(&cmd, slot, ts);
                frame_loop.submit(ctx, &[], &[])?;
            }
            Ok(())
        })();
        let finished = frame_loop.finish(ctx);
        frame_loop.destroy(ctx);
        run?;
        if let Some(t) = finished?.into_iter().last() {
            last = t;
        }
        let c = exec.compiled();
        let live = c.order.iter().map(|&p| c.pass_names[p].clone()).collect();
        Ok((
            last,
            live,
            (c.memory.peak_aliased_bytes, c.memory.unaliased_bytes),
        ))
    })();
    let _ = ctx.wait_idle();
    exec.destroy(ctx);
    result
}

/// What [`profile_scene`] measured.
pub struct ProfileRun {
    /// Per measured frame, the timings of each pass in order.
    pub frames: Vec<Vec<PassTiming>>,
    pub live_passes: Vec<String>,
    pub culled_passes: Vec<String>,
    /// Transient memory with and without aliasing.
    pub transient_memory: crate::graph::MemoryStats,
    /// One-time passes submitted before the first frame, outside the frame graph.
    pub setup: Vec<PassTiming>,
}

/// Per-pass GPU timing over many frames of a scene (for `voxgi profile`).
pub fn profile_scene(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    frames: usize,
    warmup: usize,
) -> Result<ProfileRun, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    let result = (|| {
        let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
        let r = (|| -> Result<Vec<Vec<PassTiming>>, RenderError> {
            let mut frame_loop = FrameLoop::new(
                ctx,
                MAX_FRAMES_IN_FLIGHT,
                exec.compiled().order.len() as u32,
            )?;
            let mut measured = Vec::new();
            let run = (|| -> Result<(), RenderError> {
                for i in 0..warmup + frames {
                    let slot = frame_loop.current_slot();
                    let (_, cmd, ts, done) = frame_loop.begin(ctx)?;
                    if i >= warmup + MAX_FRAMES_IN_FLIGHT && !done.is_empty() {
                        measured.push(done);
                    }
                    renderer.write_frame(slot);
                    exec.record(&cmd, slot, ts);
                    frame_loop.submit(ctx, &[], &[])?;
                }
                Ok(())
            })();
            let finished = frame_loop.finish(ctx);
            frame_loop.destroy(ctx);
            run?;
            measured.extend(finished?.into_iter().filter(|t| !t.is_empty()));
            Ok(measured)
        })();
        let _ = ctx.wait_idle();
        let c = exec.compiled();
        let live = c.order.iter().map(|&p| c.pass_names[p].clone()).collect();
        let culled = c.culled.iter().map(|&p| c.pass_names[p].clone()).collect();
        let memory = c.memory;
        exec.destroy(ctx);
        r.map(|frames| ProfileRun {
            frames,
            live_passes: live,
            culled_passes: culled,
            transient_memory: memory,
            setup: renderer.setup_timings(),
        })
    })();
    renderer.destroy(ctx);
    result
}
