//! Temporal stability of the GI methods (`voxgi bench flicker`): a light moves along a path,
//! each method renders every step, and its frame-to-frame change is compared with that of a
//! converged path tracer along the same path. Flicker — the VPL method's named weakness
//! (Thiedemann 2010, §7.5) — is the part of a method's change the converged images do not
//! have.
//!
//! Each step is a fresh render (as a viewer's frame after the light moved: accumulation
//! restarts, VPLs are regenerated). The direct light is the same pass in every method, so its
//! change cancels in the excess; what remains is the indirect light's error changing from frame
//! to frame.

use super::temporal::{light_path_scenes, reference_settings, render_path};
use super::BenchError;
use crate::eval::HdrImage;
use crate::gi::{Bounces, GiMethod, GiSettings};
use crate::render::RenderSettings;
use crate::scene::Scene;
use crate::vk::Context;
use serde::Serialize;

/// What [`bench_flicker`] runs.
#[derive(Clone, Debug)]
pub struct FlickerBenchDesc {
    /// Positions of the light along its path (frames).
    pub steps: u32,
    /// Image width and height in pixels.
    pub size: u32,
    /// Radius of the light's circular path, as a fraction of the scene's diagonal.
    pub path_radius_fraction: f32,
    /// Frames the reference path tracer accumulates at each step.
    pub reference_frames: u32,
    /// The methods compared, by name, with their settings.
    pub methods: Vec<(String, GiSettings)>,
}

impl Default for FlickerBenchDesc {
    fn default() -> Self {
        Self {
            steps: 8,
            size: 96,
            path_radius_fraction: 0.08,
            reference_frames: 32,
            methods: default_methods(),
        }
    }
}

/// The ladder at its interactive settings: direct only, hemisphere sampling (4 rays), VPLs
/// (defaults), and one path-tracer frame (4 rays, what the viewer shows while things move).
pub fn default_methods() -> Vec<(String, GiSettings)> {
    let with = |method, rays| GiSettings {
        method,
        rays,
        bounces: Bounces::Unbounded,
        ..GiSettings::default()
    };
    vec![
        ("direct".into(), with(GiMethod::None, 4)),
        ("hemisphere 4 rays".into(), with(GiMethod::Hemisphere, 4)),
        ("vpl".into(), with(GiMethod::Vpl, 4)),
        ("pathtrace 1 frame".into(), with(GiMethod::Pathtrace, 4)),
    ]
}

/// One method's row.
#[derive(Clone, Debug, Serialize)]
pub struct FlickerRow {
    pub method: String,
    /// Mean over steps of mean |I_k − I_{k−1}| / mean R_k (pixels and channels).
    pub change: f64,
    /// Mean over steps of mean |(I_k − I_{k−1}) − (R_k − R_{k−1})| / mean R_k: the change the
    /// converged images do not have.
    pub flicker: f64,
    /// Mean relMSE against the step's reference.
    pub rel_mse: f64,
    /// Median GPU ms of a frame's passes over the steps.
    pub frame_ms: f64,
}

/// What [`bench_flicker`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct FlickerReport {
    pub scene: String,
    pub steps: u32,
    pub size: u32,
    pub reference_frames: u32,
    /// The reference's own mean relative change per step.
    pub reference_change: f64,
    pub rows: Vec<FlickerRow>,
}

impl FlickerReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "Flicker along a light path: {} ({} steps, {}², reference: path tracer x {} frames, \
             its own change {:.4})\n",
            self.scene, self.steps, self.size, self.reference_frames, self.reference_change
        );
        s += &format!(
            "{:<22} {:>9} {:>9} {:>9} {:>10}\n",
            "method", "change", "flicker", "relMSE", "frame ms"
        );
        for r in &self.rows {
            s += &format!(
                "{:<22} {:>9.4} {:>9.4} {:>9.4} {:>10.1}\n",
                r.method, r.change, r.flicker, r.rel_mse, r.frame_ms
            );
        }
        s
    }
}

/// Mean over pixels and channels of |a − b|, or of |(a − b) − (c − d)| with `refs`.
fn mean_abs_change(a: &HdrImage, b: &HdrImage, refs: Option<(&HdrImage, &HdrImage)>) -> f64 {
    let n = a.data.len().max(1) as f64 * 3.0;
    let sum: f64 = (0..a.data.len())
        .flat_map(|i| (0..3).map(move |c| (i, c)))
        .map(|(i, c)| {
            let d = f64::from(a.data[i][c]) - f64::from(b.data[i][c]);
            let r = refs.map_or(0.0, |(ra, rb)| {
                f64::from(ra.data[i][c]) - f64::from(rb.data[i][c])
            });
            (d - r).abs()
        })
        .sum();
    sum / n
}

fn mean_value(a: &HdrImage) -> f64 {
    let n = a.data.len().max(1) as f64 * 3.0;
    a.data
        .iter()
        .map(|p| p.iter().map(|&v| f64::from(v)).sum::<f64>())
        .sum::<f64>()
        / n
}

/// `(change, flicker)` of a method's frames against the reference's, both relative to the
/// reference's mean (see [`FlickerRow`]).
pub fn change_and_flicker(frames: &[HdrImage], reference: &[HdrImage]) -> (f64, f64) {
    let steps = frames.len().min(reference.len());
    if steps < 2 {
        return (0.0, 0.0);
    }
    let (mut change, mut flicker) = (0.0, 0.0);
    for k in 1..steps {
        let scale = mean_value(&reference[k]).max(f64::MIN_POSITIVE);
        change += mean_abs_change(&frames[k], &frames[k - 1], None) / scale;
        let refs = Some((&reference[k], &reference[k - 1]));
        flicker += mean_abs_change(&frames[k], &frames[k - 1], refs) / scale;
    }
    let n = (steps - 1) as f64;
    (change / n, flicker / n)
}

/// Renders the path with every method and the reference; see the module doc.
pub fn bench_flicker(
    ctx: &Context,
    scene: &Scene,
    scene_name: &str,
    desc: &FlickerBenchDesc,
) -> Result<FlickerReport, BenchError> {
    let steps = light_path_scenes(scene, desc.steps, desc.path_radius_fraction)
        .ok_or(BenchError::NoMovableLight)?;
    let base = RenderSettings {
        width: desc.size,
        height: desc.size,
        ..RenderSettings::default()
    };
    let with_gi = |gi: GiSettings| RenderSettings { gi, ..base.clone() };
    let (reference, _) = render_path(
        ctx,
        &steps,
        &reference_settings(&base, desc.reference_frames),
    )?;
    let mut rows = Vec::new();
    for (name, gi) in &desc.methods {
        let (frames, frame_ms) = render_path(ctx, &steps, &with_gi(*gi))?;
        let (change, flicker) = change_and_flicker(&frames, &reference);
        let mut rel_mse = 0.0;
        for (r, f) in reference.iter().zip(&frames) {
            rel_mse += crate::eval::compare(r, f, None)?.rel_mse;
        }
        rows.push(FlickerRow {
            method: name.clone(),
            change,
            flicker,
            rel_mse: rel_mse / frames.len().max(1) as f64,
            frame_ms,
        });
    }
    // The reference against itself: its plain change (its flicker is 0 by construction).
    let (reference_change, _) = change_and_flicker(&reference, &reference);
    Ok(FlickerReport {
        scene: scene_name.to_owned(),
        steps: steps.len() as u32,
        size: desc.size,
        reference_frames: desc.reference_frames,
        reference_change,
        rows,
    })
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

    /// Frames that change exactly as the reference does have no flicker, whatever their
    /// constant bias; a frame sequence alternating ±a around the reference has flicker 2a/mean
    /// (each step's difference is ±2a off the reference's difference).
    #[test]
    fn flicker_is_the_change_the_reference_does_not_have() {
        let reference: Vec<HdrImage> = (0..4).map(|k| image(&[1.0 + k as f32; 4])).collect();
        let biased: Vec<HdrImage> = (0..4).map(|k| image(&[0.5 + k as f32; 4])).collect();
        let (change, flicker) = change_and_flicker(&biased, &reference);
        assert!(flicker.abs() < 1e-12, "{flicker}");
        assert!(change > 0.0);

        let a = 0.1_f32;
        let noisy: Vec<HdrImage> = (0..4)
            .map(|k| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                image(&[1.0 + k as f32 + sign * a; 4])
            })
            .collect();
        let (_, flicker) = change_and_flicker(&noisy, &reference);
        // Steps k = 1..3 with reference means 2, 3, 4: (2a/2 + 2a/3 + 2a/4) / 3.
        let expected = f64::from(2.0 * a) * (1.0 / 2.0 + 1.0 / 3.0 + 1.0 / 4.0) / 3.0;
        assert!((flicker - expected).abs() < 1e-6, "{flicker} vs {expected}");
    }
}
