//! Temporal accumulation along a camera path (`voxgi bench camera-path`): the camera flies the
//! scene's `[camera_path]` while the scene's animation plays at the same times, one frame per
//! step, as a viewer's user sees it. Each GI method renders the flight with and without
//! temporal accumulation (the same rays per frame, so about the same GPU ms: accumulation adds
//! one reprojection pass and a copy), and at a few frames along the way its image is scored
//! against Mitsuba 3's image of that frame (relMSE and FLIP).
//!
//! Against Mitsuba the error is the method's bias plus its noise. Beside it:
//! - **noise**: the relMSE of each scored frame against the method's own converged image of
//!   that frame (the same settings at `converged_rays` rays, `converged_frames` frames
//!   accumulated with the camera still: 512 rays per pixel by default, twice what a flight
//!   frame's longest history holds at the default 64 frames of 4 rays), which has the
//!   method's bias and little of its noise;
//! - **flicker**, at each scored frame: the change from the frame before, less what the
//!   method's own converged images of the same two frames change
//!   ([`super::change_and_flicker`]);
//! - **ghost and lag** after the first light switches off, with a still camera at the path's
//!   start ([`super::temporal::lag_after_switch_off`]): what the history keeps of a light
//!   that is gone.

use super::flicker::change_and_flicker;
use super::temporal::{lag_after_switch_off, Lag};
use super::BenchError;
use crate::eval::{compare, HdrImage};
use crate::gi::{GiFilterKind, GiMethod, GiSettings};
use crate::render::{render_flight, render_image, RenderSettings};
use crate::scene::{CameraPath, Scene};
use crate::vk::Context;
use serde::Serialize;

/// What [`bench_camera_path`] runs.
#[derive(Clone, Debug)]
pub struct CameraPathDesc {
    /// Image width and height in pixels.
    pub size: u32,
    /// Frames along the path (evenly spaced in time, first and last key included).
    pub frames: u32,
    /// Frames scored against the references, evenly spaced, the last frame included.
    pub scored: u32,
    /// The methods, each rendered with and without temporal accumulation.
    pub methods: Vec<GiMethod>,
    /// Rays per pixel and frame.
    pub rays: u32,
    /// The spatial filter and its passes (`None`: the method's default).
    pub filter: Option<(GiFilterKind, u32)>,
    /// Frames each method's converged images (of the noise and flicker measures) accumulate.
    pub converged_frames: u32,
    /// Rays per pixel and frame of those converged images.
    pub converged_rays: u32,
    /// Frames rendered after the light switch before giving up on it settling.
    pub lag_max_frames: u32,
}

impl Default for CameraPathDesc {
    fn default() -> Self {
        Self {
            size: 128,
            frames: 48,
            scored: 4,
            methods: vec![GiMethod::Hemisphere, GiMethod::Vpl, GiMethod::Pathtrace],
            rays: 4,
            filter: None,
            converged_frames: 32,
            converged_rays: 16,
            lag_max_frames: 32,
        }
    }
}

/// The frames of a flight of `frames` that are scored: `scored` of them, evenly spaced, the
/// last included (0-based, ascending, each at least 1 so that it has a frame before it).
pub fn scored_frames(frames: u32, scored: u32) -> Vec<usize> {
    let (frames, scored) = (
        frames.max(2) as usize,
        scored.clamp(1, frames.max(2) - 1) as usize,
    );
    (1..=scored)
        .map(|j| (j * frames / scored).saturating_sub(1).max(1))
        .collect()
}

/// The times of the flight's frames over the path.
pub fn flight_times(path: &CameraPath, frames: u32) -> Vec<f32> {
    path.even_times_s(frames.max(2) as usize)
}

/// `scene` seen from the path at `t_s` (the camera only: the animation time is the render's
/// `time_s`).
pub fn scene_at(scene: &Scene, path: &CameraPath, t_s: f32) -> Scene {
    let mut s = scene.clone();
    s.camera = path.camera_at(&scene.camera, t_s);
    s
}

/// One method, with or without temporal accumulation, along the path.
#[derive(Clone, Debug, Serialize)]
pub struct CameraPathRow {
    pub method: String,
    pub temporal: bool,
    /// Median GPU ms of a frame's passes along the flight.
    pub gpu_ms: f64,
    /// Mean relMSE of the scored frames against their references.
    pub rel_mse: f64,
    /// Mean FLIP of the scored frames against their references.
    pub flip: f64,
    /// relMSE of each scored frame.
    pub rel_mse_per_frame: Vec<f64>,
    /// Mean relMSE of the scored frames against the method's own converged images.
    pub noise: f64,
    /// That relMSE of each scored frame.
    pub noise_per_frame: Vec<f64>,
    /// Mean flicker of the scored frames (relative to the reference's mean value).
    pub flicker: f64,
    /// r_1 after the first light switches off (`None`: the switch changes nothing visible).
    pub ghost: Option<f64>,
    /// Frames until the switch settles (`None`: not within the frames rendered, or not
    /// measured).
    pub lag: Option<u32>,
}

/// What [`bench_camera_path`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct CameraPathReport {
    pub scene: String,
    pub size: u32,
    pub frames: u32,
    pub rays: u32,
    /// The spatial filter and its passes.
    pub filter: String,
    /// The scored frames (0-based) and their times on the path.
    pub scored: Vec<(usize, f32)>,
    pub reference: String,
    pub rows: Vec<CameraPathRow>,
}

impl CameraPathReport {
    /// The rows as a table, with each method's ratio of mean relMSE without to with temporal
    /// accumulation.
    pub fn table(&self) -> String {
        let mut s = format!(
            "camera path of {}: {}² px, {} frames, {} rays per pixel and frame, filter {}; scored frames {}; references: {}\n",
            self.scene,
            self.size,
            self.frames,
            self.rays,
            self.filter,
            self.scored
                .iter()
                .map(|(k, t)| format!("{k} ({t:.2} s)"))
                .collect::<Vec<_>>()
                .join(", "),
            self.reference
        );
        s += &format!(
            "{:<11} {:>8} {:>8} {:>9} {:>7} {:>9} {:>8} {:>6} {:>4}  relMSE per scored frame\n",
            "method", "temporal", "GPU ms", "relMSE", "FLIP", "noise", "flicker", "ghost", "lag"
        );
        for r in &self.rows {
            s += &format!(
                "{:<11} {:>8} {:>8.1} {:>9.5} {:>7.4} {:>9.6} {:>8.5} {:>6} {:>4}  {}\n",
                r.method,
                if r.temporal { "on" } else { "off" },
                r.gpu_ms,
                r.rel_mse,
                r.flip,
                r.noise,
                r.flicker,
                r.ghost.map_or("-".into(), |g| format!("{g:.3}")),
                r.lag.map_or("-".into(), |l| l.to_string()),
                r.rel_mse_per_frame
                    .iter()
                    .map(|e| format!("{e:.5}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
        for m in self.rows.iter().filter(|r| !r.temporal) {
            if let Some(on) = self
                .rows
                .iter()
                .find(|r| r.temporal && r.method == m.method)
            {
                let ratio = |a: f64, b: f64| a / b.max(f64::MIN_POSITIVE);
                s += &format!(
                    "{}: temporal accumulation divides the mean relMSE by {:.2}, the noise by {:.2} and the flicker by {:.2}, at {:.2}x the GPU ms\n",
                    m.method,
                    ratio(m.rel_mse, on.rel_mse),
                    ratio(m.noise, on.noise),
                    ratio(m.flicker, on.flicker),
                    ratio(on.gpu_ms, m.gpu_ms)
                );
            }
        }
        s
    }
}

/// The settings of `method` in the flight, with or without temporal accumulation: the
/// method's defaults at `rays` (and `desc.filter`), one frame per step (a moving camera
/// restarts the accumulation of a method without temporal history).
fn method_settings(
    base: &RenderSettings,
    desc: &CameraPathDesc,
    method: GiMethod,
    rays: u32,
    temporal: bool,
) -> RenderSettings {
    let defaults = GiSettings::default();
    let (filter, filter_passes) = desc
        .filter
        .unwrap_or((defaults.filter, defaults.filter_passes));
    RenderSettings {
        gi: GiSettings {
            method,
            rays,
            temporal,
            accumulate_frames: 1,
            filter,
            filter_passes,
            ..defaults
        },
        ..base.clone()
    }
}

/// Flies `path` through `scene` with every method of `desc`, with and without temporal
/// accumulation, and scores the frames of [`scored_frames`] against `references` (one per
/// scored frame, at `desc.size`², e.g. Mitsuba's images of [`scene_at`] those frames' times).
pub fn bench_camera_path(
    ctx: &Context,
    scene: &Scene,
    scene_name: &str,
    path: &CameraPath,
    desc: &CameraPathDesc,
    references: &[HdrImage],
    reference_name: &str,
) -> Result<CameraPathReport, BenchError> {
    let times = flight_times(path, desc.frames);
    let scored = scored_frames(desc.frames, desc.scored);
    let base = RenderSettings {
        width: desc.size,
        height: desc.size,
        ..RenderSettings::default()
    };
    let start = scene_at(scene, path, times[0]);
    let mut rows = Vec::new();
    for &method in &desc.methods {
        // The method's converged images at each scored frame and the one before it: a still
        // camera, `converged_frames` frames of temporal accumulation (the filter steps back
        // as they accumulate), so their noise is gone and their bias stays.
        let converged = |k: usize| -> Result<HdrImage, BenchError> {
            let settings = RenderSettings {
                time_s: times[k],
                gi: GiSettings {
                    accumulate_frames: desc.converged_frames.max(1),
                    ..method_settings(&base, desc, method, desc.converged_rays, true).gi
                },
                ..base.clone()
            };
            Ok(render_image(ctx, &scene_at(scene, path, times[k]), &settings)?.hdr)
        };
        let mut own = Vec::with_capacity(scored.len());
        for &k in &scored {
            own.push([converged(k - 1)?, converged(k)?]);
        }
        for temporal in [false, true] {
            let settings = method_settings(&base, desc, method, desc.rays, temporal);
            let flight = render_flight(ctx, scene, &settings, &times, Some(path))?;
            let mut rel_mse = Vec::with_capacity(scored.len());
            let mut noise = Vec::with_capacity(scored.len());
            let (mut flip, mut flicker) = (0.0, 0.0);
            for (j, &k) in scored.iter().enumerate() {
                let m = compare(&references[j], &flight.images[k], None)?;
                rel_mse.push(m.rel_mse);
                flip += m.flip_mean;
                noise.push(compare(&own[j][1], &flight.images[k], None)?.rel_mse);
                let pair = [flight.images[k - 1].clone(), flight.images[k].clone()];
                flicker += change_and_flicker(&pair, &own[j]).1;
            }
            let n = scored.len() as f64;
            let still = RenderSettings {
                time_s: times[0],
                ..settings.clone()
            };
            let lag = lag_after_switch_off(ctx, &start, &still, desc.lag_max_frames)?;
            eprintln!(
                "{} temporal {}: done",
                method.name(),
                if temporal { "on" } else { "off" }
            );
            rows.push(CameraPathRow {
                method: method.name().to_owned(),
                temporal,
                gpu_ms: crate::stats::median(&flight.gpu_ms),
                rel_mse: rel_mse.iter().sum::<f64>() / n,
                flip: flip / n,
                rel_mse_per_frame: rel_mse,
                noise: noise.iter().sum::<f64>() / n,
                noise_per_frame: noise,
                flicker: flicker / n,
                ghost: lag.map(|l: Lag| l.ghost),
                lag: lag.and_then(|l| l.frames),
            });
        }
    }
    Ok(CameraPathReport {
        scene: scene_name.to_owned(),
        size: desc.size,
        frames: desc.frames,
        rays: desc.rays,
        filter: {
            let gi = method_settings(&base, desc, GiMethod::Hemisphere, desc.rays, false).gi;
            format!("{:?} × {}", gi.filter, gi.filter_passes).to_lowercase()
        },
        scored: scored.iter().map(|&k| (k, times[k])).collect(),
        reference: reference_name.to_owned(),
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scored_frames_are_evenly_spaced_and_end_at_the_last() {
        assert_eq!(scored_frames(48, 4), vec![11, 23, 35, 47]);
        assert_eq!(scored_frames(8, 1), vec![7]);
        // Each scored frame has one before it, even for the shortest flight.
        assert_eq!(scored_frames(2, 4), vec![1]);
        assert_eq!(scored_frames(3, 2), vec![1, 2]);
    }
}
