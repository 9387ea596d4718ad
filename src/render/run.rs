//! Running the frame headless: one frame (or a path tracer's accumulation) to images, or many
//! frames for per-pass GPU timings.

use super::{RenderError, Renderer};
use crate::eval::HdrImage;
use crate::graph::GraphExecutor;
use crate::scene::{CameraPath, Scene};
use crate::vk::{Context, PassTiming, MAX_FRAMES_IN_FLIGHT};

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
    /// The transparency lists' counters (`None`: the frame had none).
    pub oit: Option<super::OitStats>,
    /// What `--shadow-resolution auto` picked (`None`: a fixed resolution).
    pub auto_shadow: Option<super::shadow_texels::AutoShadowResolution>,
}

impl RenderOutput {
    /// The graph facts and statistics of this output, with empty images and timings.
    pub(super) fn clone_facts(&self) -> Self {
        Self {
            hdr: crate::eval::HdrImage {
                width: 0,
                height: 0,
                data: Vec::new(),
            },
            ldr: Vec::new(),
            timings: Vec::new(),
            live_passes: self.live_passes.clone(),
            transient_bytes: self.transient_bytes,
            debug_description: self.debug_description.clone(),
            oit: self.oit,
            auto_shadow: self.auto_shadow,
        }
    }
}

/// Renders one frame of `scene` headless.
pub fn render_image(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
) -> Result<RenderOutput, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    render_frames(ctx, &mut renderer)
}

/// Renders the frame `renderer` is prepared for: one frame, or the path tracer's
/// accumulation or TAA's frames (the longer); reads back its images.
pub(super) fn render_frames(
    ctx: &Context,
    renderer: &mut Renderer,
) -> Result<RenderOutput, RenderError> {
    let frames = frames_to_image(&renderer.settings);
    let (timings, live_passes, transient_bytes) = run_frames(ctx, renderer, frames)?;
    let hdr = renderer.hdr_image();
    let ldr = renderer.ldr_pixels();
    let debug_description = renderer.debug_description(&hdr);
    Ok(RenderOutput {
        hdr,
        ldr,
        timings,
        live_passes,
        transient_bytes,
        debug_description,
        oit: renderer.oit_stats(),
        auto_shadow: renderer.auto_shadow_resolution(),
    })
}

/// Frames a headless render runs for its image: the path tracer (and every method under
/// temporal accumulation) converges over frames,
/// screen-space GI adds a bounce per frame by feedback, TAA converges over jittered frames;
/// everything else is done in one.
pub fn frames_to_image(settings: &super::RenderSettings) -> usize {
    let accumulates = settings.gi.method.spec().accumulates;
    let gi_frames = if accumulates || crate::gi::GiPasses::temporal_on(&settings.gi) {
        settings.gi.accumulate_frames.max(1) as usize
    } else {
        1
    };
    let taa_frames = settings.post.taa.map_or(1, |t| t.frames.max(1) as usize);
    gi_frames.max(taa_frames)
}

/// What [`render_sequence`] saw.
pub struct SequenceOutput {
    /// The image after the warm-up frames of the first scene.
    pub warm: HdrImage,
    /// The image of each following frame, one per scene of `then`.
    pub frames: Vec<HdrImage>,
}

/// Renders `warm` frames of `scene`, then one frame of each scene of `then` with the same
/// renderer, as the viewer does when something changes: what a method keeps from frame to
/// frame (accumulation, feedback, TAA and SSGI histories) carries over, and
/// [`Renderer::prepare`] decides what restarts. Only the camera and the lights of the later
/// scenes are read (their objects must be those of `scene`).
pub fn render_sequence(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    warm: usize,
    then: &[Scene],
) -> Result<SequenceOutput, RenderError> {
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    // Each run waits for its frames, so the read-back holds the last one.
    crate::graph::run_frames(ctx, &exec, warm.max(1), 0, |slot| {
        renderer.write_frame(slot)
    })?;
    let warm = renderer.hdr_image();
    let mut frames = Vec::with_capacity(then.len());
    for next in then {
        renderer.prepare(next)?;
        crate::graph::run_frames(ctx, &exec, 1, 0, |slot| renderer.write_frame(slot))?;
        frames.push(renderer.hdr_image());
    }
    Ok(SequenceOutput { warm, frames })
}

/// Renders one frame of `scene` at each animation time of `times_s` with one renderer, as
/// the viewer does while the scene plays: moving objects follow the times (through
/// [`Renderer::prepare`]) while TAA, GI accumulation and histories carry over. Returns the
/// image of every frame.
pub fn render_animation(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    times_s: &[f32],
) -> Result<Vec<HdrImage>, RenderError> {
    Ok(render_flight(ctx, scene, settings, times_s, None)?.images)
}

/// What [`render_flight`] saw: each frame's image and the GPU ms of its passes.
pub struct Flight {
    pub images: Vec<HdrImage>,
    pub gpu_ms: Vec<f64>,
}

/// [`render_animation`] with the camera also flown along `path` at the same times, as a
/// viewer's user flies it while the scene plays (for `voxgi bench camera-path`). Without a
/// path it is [`render_animation`].
pub fn render_flight(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    times_s: &[f32],
    path: Option<&CameraPath>,
) -> Result<Flight, RenderError> {
    let mut settings = settings.clone();
    settings.time_s = times_s.first().copied().unwrap_or(settings.time_s);
    let mut flown = scene.clone();
    let fly = |flown: &mut Scene, t_s: f32| {
        if let Some(p) = path {
            flown.camera = p.camera_at(&scene.camera, t_s);
        }
    };
    fly(&mut flown, settings.time_s);
    let mut renderer = Renderer::new(ctx, &flown, settings)?;
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let mut images = Vec::with_capacity(times_s.len());
    let mut gpu_ms = Vec::with_capacity(times_s.len());
    for &t_s in times_s {
        renderer.settings.time_s = t_s;
        fly(&mut flown, t_s);
        renderer.prepare(&flown)?;
        // Each run waits for its frame, so the read-back holds it.
        let timings =
            crate::graph::run_frames(ctx, &exec, 1, 0, |slot| renderer.write_frame(slot))?;
        gpu_ms.push(timings.iter().flatten().map(|t| t.gpu_ms).sum());
        images.push(renderer.hdr_image());
    }
    Ok(Flight { images, gpu_ms })
}

type FrameFacts = (Vec<PassTiming>, Vec<String>, (u64, u64));

/// Runs `frames` frames; returns the last frame's timings and graph facts.
fn run_frames(
    ctx: &Context,
    renderer: &mut Renderer,
    frames: usize,
) -> Result<FrameFacts, RenderError> {
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let timings =
        crate::graph::run_frames(ctx, &exec, frames, 0, |slot| renderer.write_frame(slot));
    let c = exec.compiled();
    let live = c.order.iter().map(|&p| c.pass_names[p].clone()).collect();
    let bytes = (c.memory.peak_aliased_bytes, c.memory.unaliased_bytes);
    let last = timings?.into_iter().last().unwrap_or_default();
    Ok((last, live, bytes))
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
    /// What `--shadow-resolution auto` picked (`None`: a fixed resolution).
    pub auto_shadow: Option<super::shadow_texels::AutoShadowResolution>,
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
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let frames = crate::graph::run_frames(ctx, &exec, warmup + frames, warmup, |slot| {
        renderer.write_frame(slot)
    })?;
    Ok(profile_run(&exec, &renderer, frames))
}

/// Like [`profile_scene`], with the camera flown along `path` (for `voxgi profile
/// --camera-path`): the warm-up frames look from the path's start, measured frame k from the
/// k-th of `frames` times evenly spaced over it (first and last key included). The camera
/// moves through [`Renderer::prepare`] before each frame, as the viewer's does; the scene's
/// animation time stays `settings.time_s`.
pub fn profile_camera_path(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    path: &CameraPath,
    frames: usize,
    warmup: usize,
) -> Result<ProfileRun, RenderError> {
    let times_s = path.even_times_s(frames);
    let start_s = path.time_range_s().0;
    profile_steps(ctx, scene, settings, frames, warmup, |frame, shown, _| {
        let t_s = frame
            .checked_sub(warmup)
            .and_then(|k| times_s.get(k).copied())
            .unwrap_or(start_s);
        shown.camera = path.camera_at(&scene.camera, t_s);
    })
}

/// Like [`profile_scene`], with `step(k, scene, time_s)` setting what frame k (warm-up
/// frames first, from 0) shows before it is prepared: the camera and lights of its copy of
/// `scene`, and the animation time. Each frame goes through [`Renderer::prepare`], as the
/// viewer's do (`profile --camera-path`, `bench dynamic`).
pub fn profile_steps(
    ctx: &Context,
    scene: &Scene,
    settings: &super::RenderSettings,
    frames: usize,
    warmup: usize,
    mut step: impl FnMut(usize, &mut Scene, &mut f32),
) -> Result<ProfileRun, RenderError> {
    let mut shown = scene.clone();
    let mut renderer = Renderer::new(ctx, scene, settings.clone())?;
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)?;
    let mut frame = 0usize;
    let mut failed = None;
    let measured = crate::graph::run_frames(ctx, &exec, warmup + frames, warmup, |slot| {
        step(frame, &mut shown, &mut renderer.settings.time_s);
        frame += 1;
        match renderer.prepare(&shown) {
            Ok(()) => renderer.write_frame(slot),
            Err(e) => {
                failed.get_or_insert(e);
            }
        }
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    Ok(profile_run(&exec, &renderer, measured))
}

/// The compiled graph's facts and the renderer's setup timings around measured `frames`.
pub(super) fn profile_run(
    exec: &GraphExecutor,
    renderer: &Renderer,
    frames: Vec<Vec<PassTiming>>,
) -> ProfileRun {
    let c = exec.compiled();
    ProfileRun {
        frames,
        live_passes: c.order.iter().map(|&p| c.pass_names[p].clone()).collect(),
        culled_passes: c.culled.iter().map(|&p| c.pass_names[p].clone()).collect(),
        transient_memory: c.memory,
        setup: renderer.setup_timings(),
        auto_shadow: renderer.auto_shadow_resolution(),
    }
}
