//! The temporal measures of `voxgi sweep` (and the light path `voxgi bench flicker` shares):
//!
//! - **Flicker along a light path**: the scene's first positional light moves along a circle
//!   in `steps` fresh renders, as a viewer's frame after the light moved (accumulation
//!   restarts, VPLs are regenerated); a method's flicker is the part of its frame-to-frame
//!   change that a converged path tracer's images along the same path do not have
//!   ([`super::change_and_flicker`]). Flicker is the VPLs' named weakness (Thiedemann 2010,
//!   §7.5).
//! - **Lag after a light switches off**: one renderer renders the scene until its image is
//!   done, the first light is switched off, and the renderer goes on frame by frame — what a
//!   method keeps between frames (the screen-space feedback and history, TAA's history, Oetke
//!   2017 §4.5 and §7.5) carries over, as in the viewer. With W the image before the switch,
//!   F a fresh render with the light off and I_k the k-th frame after it, the residual
//!   r_k = mean|I_k − F| / mean|W − F| is the fraction of the change still missing
//!   ([`residuals`]). The ghost is r_1, the lag the first k with r_k ≤ [`SETTLED`].

use super::change_and_flicker;
use crate::eval::HdrImage;
use crate::gi::{Bounces, GiMethod, GiSettings};
use crate::render::{frames_to_image, render_image, render_sequence, RenderError, RenderSettings};
use crate::scene::{Light, Scene};
use crate::vk::Context;
use glam::Vec3;

/// The residual below which a switch counts as done: 5% of the change still missing.
pub const SETTLED: f64 = 0.05;

/// What the temporal measures run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalDesc {
    /// Positions of the light along its path; 0 turns the flicker measure off.
    pub steps: u32,
    /// Frames the reference path tracer accumulates at each step.
    pub reference_frames: u32,
    /// Radius of the light's circular path, as a fraction of the scene's diagonal.
    pub path_radius_fraction: f32,
    /// Frames rendered after the switch before giving up on it settling; 0 turns the lag
    /// measure off.
    pub lag_max_frames: u32,
}

impl Default for TemporalDesc {
    fn default() -> Self {
        Self {
            steps: 4,
            reference_frames: 16,
            path_radius_fraction: 0.08,
            lag_max_frames: 32,
        }
    }
}

/// The scenes along the light path and the converged reference at each.
pub struct LightPath {
    pub scenes: Vec<Scene>,
    pub reference: Vec<HdrImage>,
}

/// The first point or spot light moved to step `k` of `steps` on a horizontal circle of
/// `radius_m` around its position; other lights stay.
pub fn scene_at_step(scene: &Scene, k: u32, steps: u32, radius_m: f32) -> Scene {
    let mut s = scene.clone();
    let angle = std::f32::consts::TAU * k as f32 / steps.max(1) as f32;
    let offset = Vec3::new(angle.cos() - 1.0, 0.0, angle.sin()) * radius_m;
    if let Some(light) = s.lights.iter_mut().find(|l| l.position().is_some()) {
        match light {
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Sphere { position, .. }
            | Light::Rectangle { position, .. }
            | Light::Element { position, .. } => *position += offset,
            Light::Directional { .. } => {}
        }
    }
    s
}

/// The scenes of a closed light path of `steps` (at least 2) positions; `None` when the
/// scene has no light with a position.
pub fn light_path_scenes(scene: &Scene, steps: u32, radius_fraction: f32) -> Option<Vec<Scene>> {
    scene.lights.iter().find(|l| l.position().is_some())?;
    let radius_m = scene.aabb_at(0.0).extent().length() * radius_fraction;
    let steps = steps.max(2);
    Some(
        (0..steps)
            .map(|k| scene_at_step(scene, k, steps, radius_m))
            .collect(),
    )
}

/// The converged reference of the temporal measures: the path tracer, unbounded, 4 rays,
/// `frames` accumulated.
pub fn reference_settings(base: &RenderSettings, frames: u32) -> RenderSettings {
    RenderSettings {
        gi: GiSettings {
            method: GiMethod::Pathtrace,
            rays: 4,
            bounces: Bounces::Unbounded,
            accumulate_frames: frames.max(1),
            ..GiSettings::default()
        },
        ..base.clone()
    }
}

/// Each scene rendered fresh with `settings`, and the median GPU ms of a frame's passes.
pub fn render_path(
    ctx: &Context,
    scenes: &[Scene],
    settings: &RenderSettings,
) -> Result<(Vec<HdrImage>, f64), RenderError> {
    let mut images = Vec::with_capacity(scenes.len());
    let mut ms = Vec::with_capacity(scenes.len());
    for s in scenes {
        let out = render_image(ctx, s, settings)?;
        ms.push(out.timings.iter().map(|t| t.gpu_ms).sum::<f64>());
        images.push(out.hdr);
    }
    Ok((images, crate::stats::median(&ms)))
}

/// The light path of `scene` with its references at `base`'s size; `None` without a light
/// that can move or with `desc.steps == 0`.
pub fn light_path(
    ctx: &Context,
    scene: &Scene,
    base: &RenderSettings,
    desc: &TemporalDesc,
) -> Result<Option<LightPath>, RenderError> {
    if desc.steps == 0 {
        return Ok(None);
    }
    let Some(scenes) = light_path_scenes(scene, desc.steps, desc.path_radius_fraction) else {
        return Ok(None);
    };
    let (reference, _) = render_path(
        ctx,
        &scenes,
        &reference_settings(base, desc.reference_frames),
    )?;
    Ok(Some(LightPath { scenes, reference }))
}

/// The flicker of `settings` along `path` ([`super::FlickerRow::flicker`]).
pub fn path_flicker(
    ctx: &Context,
    path: &LightPath,
    settings: &RenderSettings,
) -> Result<f64, RenderError> {
    let (frames, _) = render_path(ctx, &path.scenes, settings)?;
    Ok(change_and_flicker(&frames, &path.reference).1)
}

/// `scene` with its first light's power set to zero; `None` without lights.
pub fn first_light_off(scene: &Scene) -> Option<Scene> {
    let mut s = scene.clone();
    match s.lights.first_mut()? {
        Light::Point { intensity_w_sr, .. }
        | Light::Spot { intensity_w_sr, .. }
        | Light::Element { intensity_w_sr, .. } => *intensity_w_sr = Vec3::ZERO,
        Light::Directional {
            irradiance_w_m2, ..
        } => *irradiance_w_m2 = Vec3::ZERO,
        Light::Sphere {
            radiance_w_sr_m2, ..
        }
        | Light::Rectangle {
            radiance_w_sr_m2, ..
        } => *radiance_w_sr_m2 = Vec3::ZERO,
    }
    Some(s)
}

/// Mean over pixels and channels of |a − b|.
fn mean_abs_diff(a: &HdrImage, b: &HdrImage) -> f64 {
    let n = (a.data.len().max(1) * 3) as f64;
    a.data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).abs()))
        .sum::<f64>()
        / n
}

/// r_k = mean|I_k − F| / mean|W − F| for each frame I_k after the switch (see the module
/// doc); `None` when the switch changes nothing visible (mean|W − F| below 1e-6 of W's mean
/// absolute value, or zero).
pub fn residuals(warm: &HdrImage, after: &[HdrImage], fresh: &HdrImage) -> Option<Vec<f64>> {
    let change = mean_abs_diff(warm, fresh);
    let black = HdrImage {
        width: warm.width,
        height: warm.height,
        data: vec![[0.0; 3]; warm.data.len()],
    };
    if change <= 1e-6 * mean_abs_diff(warm, &black) || change == 0.0 {
        return None;
    }
    Some(
        after
            .iter()
            .map(|f| mean_abs_diff(f, fresh) / change)
            .collect(),
    )
}

/// The first frame (1-based) whose residual is at most `threshold`; `None` if none is.
pub fn settle_frame(residuals: &[f64], threshold: f64) -> Option<u32> {
    residuals
        .iter()
        .position(|&r| r <= threshold)
        .map(|k| k as u32 + 1)
}

/// What [`lag_after_switch_off`] measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lag {
    /// r_1: the fraction of the switch the first frame after it still misses.
    pub ghost: f64,
    /// Frames until r_k ≤ [`SETTLED`]; `None`: not within the frames rendered.
    pub frames: Option<u32>,
}

/// The ghost and lag of `settings` when the scene's first light switches off (see the module
/// doc); `None` without lights, with `max_frames == 0`, or when the light changes nothing
/// visible.
pub fn lag_after_switch_off(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    max_frames: u32,
) -> Result<Option<Lag>, RenderError> {
    let Some(off) = first_light_off(scene) else {
        return Ok(None);
    };
    if max_frames == 0 {
        return Ok(None);
    }
    let fresh = render_image(ctx, &off, settings)?.hdr;
    // Frame by frame, stopping once settled: render the switch in chunks so that a method
    // without history costs a few frames, not `max_frames`.
    let warm_frames = frames_to_image(settings);
    let mut after: Vec<Scene> = Vec::new();
    let mut chunk = 1usize;
    loop {
        let n = (after.len() + chunk).min(max_frames as usize);
        after.resize(n, off.clone());
        let seq = render_sequence(ctx, scene, settings, warm_frames, &after)?;
        let Some(r) = residuals(&seq.warm, &seq.frames, &fresh) else {
            return Ok(None);
        };
        let frames = settle_frame(&r, SETTLED);
        if frames.is_some() || n == max_frames as usize {
            return Ok(Some(Lag {
                ghost: r[0],
                frames,
            }));
        }
        chunk *= 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> HdrImage {
        HdrImage {
            width: values.len() as u32,
            height: 1,
            data: values.iter().map(|&v| [v; 3]).collect(),
        }
    }

    /// A history blended with weight τ keeps τ^k of the old image k frames after the switch:
    /// I_k = F + τ^k (W − F), so r_k = τ^k exactly, and the lag is the first k with
    /// τ^k ≤ 0.05, ⌈ln 0.05 / ln τ⌉ (29 for τ = 0.9).
    #[test]
    fn an_exponential_history_has_the_closed_form_lag() {
        let (w, f) = (image(&[2.0, 4.0, 1.0]), image(&[1.0, 1.0, 0.5]));
        let tau = 0.9_f64;
        let after: Vec<HdrImage> = (1..=40)
            .map(|k| {
                let t = tau.powi(k) as f32;
                HdrImage {
                    data: w
                        .data
                        .iter()
                        .zip(&f.data)
                        .map(|(a, b)| [0, 1, 2].map(|c| b[c] + t * (a[c] - b[c])))
                        .collect(),
                    ..w.clone()
                }
            })
            .collect();
        let r = residuals(&w, &after, &f).expect("the switch changes the image");
        for (k, rk) in r.iter().enumerate() {
            assert!((rk - tau.powi(k as i32 + 1)).abs() < 1e-6, "{k}: {rk}");
        }
        let expected = (SETTLED.ln() / tau.ln()).ceil() as u32;
        assert_eq!(expected, 29);
        assert_eq!(settle_frame(&r, SETTLED), Some(expected));
    }

    #[test]
    fn a_switch_without_history_settles_at_once_and_an_invisible_one_is_not_measured() {
        let (w, f) = (image(&[2.0, 4.0]), image(&[1.0, 1.0]));
        let r = residuals(&w, std::slice::from_ref(&f), &f).expect("visible");
        assert_eq!(r, vec![0.0]);
        assert_eq!(settle_frame(&r, SETTLED), Some(1));
        assert_eq!(residuals(&w, std::slice::from_ref(&w), &w), None);
        assert_eq!(settle_frame(&[0.5, 0.2], SETTLED), None);
    }

    #[test]
    fn switching_off_zeroes_only_the_first_light() {
        let scene = crate::scene::builtin("cornell").expect("cornell is built in");
        let off = first_light_off(&scene).expect("cornell has a light");
        assert_eq!(off.lights.len(), scene.lights.len());
        match off.lights[0] {
            Light::Point { intensity_w_sr, .. } | Light::Spot { intensity_w_sr, .. } => {
                assert_eq!(intensity_w_sr, Vec3::ZERO)
            }
            ref l => panic!("cornell's light is a point or spot light: {l:?}"),
        }
        assert_eq!(off.lights[1..], scene.lights[1..]);
    }

    #[test]
    fn the_light_path_is_a_closed_circle_starting_at_the_light() {
        let scene = crate::scene::builtin("cornell").expect("cornell is built in");
        let p0 = scene.lights[0]
            .position()
            .expect("cornell's light has a position");
        let at = |k| {
            scene_at_step(&scene, k, 8, 0.2).lights[0]
                .position()
                .unwrap()
        };
        assert!((at(0) - p0).length() < 1e-6);
        // The circle of radius r through p0 has its center at p0 − (r, 0, 0).
        for k in 0..8 {
            let center = p0 - Vec3::new(0.2, 0.0, 0.0);
            assert!(((at(k) - center).length() - 0.2).abs() < 1e-5);
            assert_eq!(at(k).y, p0.y);
        }
    }
}
