//! Long runs (`voxgi bench soak`): each GI method renders many frames of a scene whose objects
//! move, through the one frame driver ([`crate::graph::run_frames`]), and every `every` frames
//! the process's resident memory, the GPU memory the context holds and the release queue's
//! backlog are recorded. A leak shows as a slope: bytes per 1000 frames, a least-squares line
//! through the samples after the first (the first is taken before any frame ran, while
//! first-use allocations are still to come). A benchmark, not a test: it reports, it does not
//! judge.

use super::BenchError;
use crate::gi::{GiMethod, GiSettings};
use crate::graph::GraphExecutor;
use crate::render::{RenderSettings, Renderer};
use crate::scene::Scene;
use crate::vk::{Context, MAX_FRAMES_IN_FLIGHT};
use serde::Serialize;
use std::time::Instant;

/// Frames per second of scene time: frame `i` shows the scene at `i / SOAK_FPS` seconds
/// (folded by [`soak_time_s`]).
pub const SOAK_FPS: f32 = 60.0;

/// What [`bench_soak`] runs.
#[derive(Clone, Debug)]
pub struct SoakBenchDesc {
    /// Frames per method.
    pub frames: usize,
    /// Frames between samples.
    pub every: usize,
    pub width: u32,
    pub height: u32,
    /// The methods, one run each, in order.
    pub methods: Vec<GiMethod>,
    /// Scene time turns back every `period_s` seconds (a triangle wave over
    /// `[0, period_s]`), so that keyframed objects keep moving however long the run is.
    pub period_s: f32,
}

impl Default for SoakBenchDesc {
    fn default() -> Self {
        Self {
            frames: 10_000,
            every: 500,
            width: 32,
            height: 32,
            methods: GiMethod::ALL.to_vec(),
            period_s: 1.0,
        }
    }
}

/// One sample of a run.
#[derive(Clone, Debug, Serialize)]
pub struct SoakSample {
    /// Frames submitted before the sample.
    pub frame: usize,
    /// Resident set size of the process (`None` where the platform does not say).
    pub rss_bytes: Option<u64>,
    /// GPU memory the context holds ([`Context::allocated_bytes`]).
    pub gpu_bytes: u64,
    /// Batches waiting in the release queue ([`Context::pending_releases`]).
    pub pending_releases: usize,
}

/// One method's run.
#[derive(Clone, Debug, Serialize)]
pub struct SoakRow {
    pub method: GiMethod,
    pub frames: usize,
    pub wall_s: f64,
    pub samples: Vec<SoakSample>,
    /// Least-squares slope of RSS over the samples after the first, bytes per 1000 frames.
    pub rss_slope_bytes_per_1000_frames: Option<f64>,
    /// The same for the context's GPU memory.
    pub gpu_slope_bytes_per_1000_frames: Option<f64>,
    /// GPU memory the context still holds once the method's renderer and graph are dropped
    /// (0 unless something outlives them).
    pub gpu_bytes_after_drop: u64,
}

/// What [`bench_soak`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct SoakReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub every: usize,
    pub rows: Vec<SoakRow>,
}

impl SoakReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "Soak: {} at {}x{}, a sample every {} frames; slopes over the samples after the \
             first\n",
            self.scene, self.width, self.height, self.every
        );
        s += &format!(
            "{:<11} {:>7} {:>8} {:>10} {:>10} {:>16} {:>10} {:>10} {:>16} {:>8} {:>11}\n",
            "method",
            "frames",
            "wall s",
            "RSS MiB",
            "RSS last",
            "RSS B/1k frames",
            "GPU MiB",
            "GPU last",
            "GPU B/1k frames",
            "pending",
            "GPU B left"
        );
        for r in &self.rows {
            let mib = |b: Option<u64>| b.map_or("n/a".to_owned(), |b| format!("{:.2}", mib(b)));
            let slope = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.0}"));
            let first = r.samples.get(1).or(r.samples.first());
            let last = r.samples.last();
            s += &format!(
                "{:<11} {:>7} {:>8.1} {:>10} {:>10} {:>16} {:>10} {:>10} {:>16} {:>8} {:>11}\n",
                format!("{:?}", r.method).to_lowercase(),
                r.frames,
                r.wall_s,
                mib(first.and_then(|x| x.rss_bytes)),
                mib(last.and_then(|x| x.rss_bytes)),
                slope(r.rss_slope_bytes_per_1000_frames),
                mib(first.map(|x| x.gpu_bytes)),
                mib(last.map(|x| x.gpu_bytes)),
                slope(r.gpu_slope_bytes_per_1000_frames),
                last.map_or(0, |x| x.pending_releases),
                r.gpu_bytes_after_drop,
            );
        }
        s += "(RSS/GPU MiB: at the second sample and the last; pending: release-queue batches \
              at the last sample; GPU B left: held after the method's renderer was dropped)\n";
        s
    }
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// Scene time of frame `frame`: `frame / SOAK_FPS` seconds folded into a triangle wave over
/// `[0, period_s]` (forward, then back), so objects keep moving in a run of any length.
pub fn soak_time_s(frame: usize, period_s: f32) -> f32 {
    let period_s = period_s.max(f32::MIN_POSITIVE);
    let t = (frame as f64 / f64::from(SOAK_FPS)) % (2.0 * f64::from(period_s));
    (f64::from(period_s) - (t - f64::from(period_s)).abs()) as f32
}

/// Resident set size of this process: `VmRSS` of `/proc/self/status` (the same count as
/// `/proc/self/statm`'s second field times the page size, without needing the page size).
/// `None` where there is no `/proc` (not Linux).
pub fn process_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Least-squares slope of `y` over `x`, per 1000 units of `x`; `None` with fewer than two
/// distinct `x`.
pub fn slope_per_1000(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mean_x = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mean_y = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    (sxx > 0.0).then(|| sxy / sxx * 1000.0)
}

fn sample(ctx: &Context, frame: usize) -> SoakSample {
    SoakSample {
        frame,
        rss_bytes: process_rss_bytes(),
        gpu_bytes: ctx.allocated_bytes(),
        pending_releases: ctx.pending_releases(),
    }
}

/// Runs every method of `desc` on `scene`; `progress` sees each sample as it is taken.
pub fn bench_soak(
    ctx: &Context,
    scene: &Scene,
    scene_name: &str,
    desc: &SoakBenchDesc,
    progress: &mut dyn FnMut(GiMethod, &SoakSample),
) -> Result<SoakReport, BenchError> {
    let mut rows = Vec::new();
    for &method in &desc.methods {
        rows.push(soak_method(ctx, scene, desc, method, progress)?);
    }
    Ok(SoakReport {
        scene: scene_name.to_owned(),
        width: desc.width,
        height: desc.height,
        every: desc.every.max(1),
        rows,
    })
}

/// One method's run: a renderer, its graph, and `desc.frames` frames with the scene time
/// advancing; samples before the first frame, every `desc.every` frames and after the last
/// (with the renderer alive), then the GPU memory left once it is dropped.
fn soak_method(
    ctx: &Context,
    scene: &Scene,
    desc: &SoakBenchDesc,
    method: GiMethod,
    progress: &mut dyn FnMut(GiMethod, &SoakSample),
) -> Result<SoakRow, BenchError> {
    let every = desc.every.max(1);
    let settings = RenderSettings {
        width: desc.width,
        height: desc.height,
        gi: GiSettings {
            method,
            ..GiSettings::default()
        },
        ..RenderSettings::default()
    };
    let start = Instant::now();
    let mut samples = Vec::new();
    {
        let mut renderer = Renderer::new(ctx, scene, settings)?;
        let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT)
            .map_err(crate::render::RenderError::from)?;
        let mut frame = 0;
        let mut failed = None;
        crate::graph::run_frames(ctx, &exec, desc.frames, desc.frames, |slot| {
            if frame % every == 0 {
                let s = sample(ctx, frame);
                progress(method, &s);
                samples.push(s);
            }
            renderer.settings.time_s = soak_time_s(frame, desc.period_s);
            if let Err(e) = renderer.prepare(scene) {
                failed.get_or_insert(e);
            }
            renderer.write_frame(slot);
            frame += 1;
        })?;
        if let Some(e) = failed {
            return Err(e.into());
        }
        // After the last frame (the GPU idle), the renderer still alive.
        let last = sample(ctx, desc.frames);
        progress(method, &last);
        samples.push(last);
    }
    // The renderer and its graph dropped: what they left behind.
    let gpu_bytes_after_drop = ctx.allocated_bytes();
    let wall_s = start.elapsed().as_secs_f64();
    let line = |value: &dyn Fn(&SoakSample) -> Option<u64>| {
        let points: Option<Vec<(f64, f64)>> = samples
            .iter()
            .skip(1)
            .map(|s| value(s).map(|v| (s.frame as f64, v as f64)))
            .collect();
        points.and_then(|p| slope_per_1000(&p))
    };
    Ok(SoakRow {
        method,
        frames: desc.frames,
        wall_s,
        rss_slope_bytes_per_1000_frames: line(&|s| s.rss_bytes),
        gpu_slope_bytes_per_1000_frames: line(&|s| Some(s.gpu_bytes)),
        samples,
        gpu_bytes_after_drop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = 3x + 7 has slope 3 per unit, 3000 per 1000; a constant has slope 0; one point or
    /// one x has none.
    #[test]
    fn the_slope_is_the_least_squares_line() {
        let line: Vec<(f64, f64)> = (0..5)
            .map(|i| (i as f64 * 500.0, 1500.0 * i as f64 + 7.0))
            .collect();
        assert!((slope_per_1000(&line).unwrap() - 3000.0).abs() < 1e-9);
        let flat: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 42.0)).collect();
        assert_eq!(slope_per_1000(&flat), Some(0.0));
        assert_eq!(slope_per_1000(&[(1.0, 2.0)]), None);
        assert_eq!(slope_per_1000(&[(1.0, 2.0), (1.0, 3.0)]), None);
    }

    /// The triangle wave starts at 0, reaches the period at `period × fps` frames and is back
    /// at 0 after twice that.
    #[test]
    fn scene_time_goes_forth_and_back() {
        let fps = SOAK_FPS as usize;
        assert_eq!(soak_time_s(0, 1.0), 0.0);
        assert!((soak_time_s(fps / 2, 1.0) - 0.5).abs() < 1e-6);
        assert!((soak_time_s(fps, 1.0) - 1.0).abs() < 1e-6);
        assert!((soak_time_s(fps * 3 / 2, 1.0) - 0.5).abs() < 1e-6);
        assert!(soak_time_s(2 * fps, 1.0).abs() < 1e-6);
    }

    #[test]
    fn rss_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(process_rss_bytes().is_some_and(|b| b > 0));
        }
    }
}
