//! The analytic sky of `[environment] kind = "sky"`: Hosek and Wilkie's skylight model
//! ("An Analytic Model for Full Spectral Sky-Dome Radiance", SIGGRAPH 2012), RGB version,
//! evaluated as Mitsuba 3's `sunsky` emitter evaluates it, so that a scene exported with a
//! `sunsky` emitter is an independent reference (same published tables, separate code).
//!
//! The sky is baked at load into an equirectangular map ([`bake`]) in the `envmap` convention
//! of [`super::environment`], so that every shader reads it through the existing map path
//! (`ENVIRONMENT_MAP`, bilinear lookup) and nothing on the GPU knows a sky from a map.
//!
//! The model gives the sky *without* the sun's disk; the sun is the scene's directional light,
//! a delta light whose irradiance the scene file sets (`irradiance_w_m2`), and the sky only
//! takes its direction from it. The export pairs Mitsuba's `sunsky` with `sun_scale = 0` and
//! voxgi's directional light as a `directional` emitter, so both renderers see the same sun.

use glam::{DVec3, Vec3};

// The table's parameters live with the environment that holds them, so that this module only
// reads the environment's types (never the other way round).
pub use super::environment::SkyParams;
use super::environment::{equirect_direction, EnvironmentMap};
use super::sky_data::{SKY_PARAMS_RGB, SKY_RAD_RGB};

/// Mitsuba 3's `MI_CIE_Y_NORMALIZATION` (`include/mitsuba/core/spectrum.h`), which its `sunsky`
/// emitter multiplies the RGB model's output by (the model's RGB tables are in units where the
/// CIE Y integral of an equal-energy spectrum is 106.75).
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;

/// The turbidities the tables hold: 1 to 10 (Hosek and Wilkie 2012, §5).
pub const TURBIDITY_RANGE: std::ops::RangeInclusive<f32> = 1.0..=10.0;

/// Width × height of the baked map: 0.7° per texel, fine enough for the circumsolar
/// brightening, whose narrowest term (the Mie lobe with `I` up to about 0.8) spans degrees.
pub const BAKE_WIDTH: u32 = 512;
pub const BAKE_HEIGHT: u32 = 256;

/// The model's parameters for one sun elevation, turbidity and ground albedo (Hosek and
/// Wilkie 2012, §5: the tables' Bézier control points interpolated in elevation, then linearly
/// in turbidity and albedo).
#[derive(Clone, Debug)]
pub struct SkyModel {
    /// A..I per channel.
    params: [[f64; 9]; 3],
    /// L_M per channel.
    radiance: [f64; 3],
    /// Unit direction toward the sun; `None` when it is below the horizon (the model has no
    /// night: the sky is black, as Mitsuba's `sunsky` makes it).
    toward_sun: Option<DVec3>,
    scale: f64,
}

impl SkyModel {
    pub fn new(sky: &SkyParams) -> Self {
        let sun = sky.toward_sun.as_dvec3().normalize();
        let elevation = sun.y.clamp(-1.0, 1.0).asin();
        // Bézier parameter: the control points are spaced in the cube root of the elevation
        // (Hosek and Wilkie 2012, §5; Mitsuba clamps it just below 1 the same way).
        let x = (elevation.max(0.0) / std::f64::consts::FRAC_PI_2)
            .cbrt()
            .min(1.0 - f64::EPSILON);
        let bernstein: [f64; 6] = std::array::from_fn(|i| {
            const BINOMIAL: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
            BINOMIAL[i] * x.powi(i as i32) * (1.0 - x).powi(5 - i as i32)
        });
        let t = (f64::from(sky.turbidity) - 1.0).clamp(0.0, 9.0);
        let t0 = (t.floor() as usize).min(8);
        let t_frac = t - t0 as f64;
        let mut params = [[0.0; 9]; 3];
        let mut radiance = [0.0; 3];
        for c in 0..3 {
            let albedo = f64::from(sky.ground_albedo[c]).clamp(0.0, 1.0);
            for (ti, wt) in [(t0, 1.0 - t_frac), (t0 + 1, t_frac)] {
                for (ai, wa) in [(0, 1.0 - albedo), (1, albedo)] {
                    for (k, wb) in bernstein.iter().enumerate() {
                        let w = wt * wa * wb;
                        if w == 0.0 {
                            continue;
                        }
                        // [turbidity][albedo][control point][channel](param)
                        let base = ((ti * 2 + ai) * 6 + k) * 3 + c;
                        radiance[c] += w * SKY_RAD_RGB[base];
                        for (p, v) in params[c].iter_mut().enumerate() {
                            *v += w * SKY_PARAMS_RGB[base * 9 + p];
                        }
                    }
                }
            }
        }
        Self {
            params,
            radiance,
            toward_sun: (elevation >= 0.0).then_some(sun),
            scale: f64::from(sky.scale),
        }
    }

    /// The sky's radiance (W/(m²·sr), linear RGB) arriving from unit direction `toward` (the
    /// direction a ray travels). Zero below the horizon and with the sun below it.
    pub fn radiance_toward(&self, toward: Vec3) -> Vec3 {
        let Some(sun) = self.toward_sun else {
            return Vec3::ZERO;
        };
        let d = toward.as_dvec3().normalize();
        let cos_theta = d.y;
        if cos_theta < 0.0 {
            return Vec3::ZERO;
        }
        let cos_gamma = d.dot(sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let mut out = [0.0f32; 3];
        for (c, o) in out.iter_mut().enumerate() {
            // Hosek and Wilkie 2012, eq. 9: F(θ, γ) = (1 + A e^{B/(cos θ + 0.01)}) ·
            // (C + D e^{Eγ} + F cos²γ + G χ(H, γ) + I cos^{1/2} θ), χ(H, γ) = (1 + cos²γ) /
            // (1 + H² − 2H cos γ)^{3/2}. The tables store I before H (as the authors' code and
            // Mitsuba read them).
            let [a, b, c_, d_, e, f, g, i_zenith, h_mie] = self.params[c];
            let chi = (1.0 + cos_gamma * cos_gamma)
                / (1.0 + h_mie * h_mie - 2.0 * h_mie * cos_gamma).powf(1.5);
            let f1 = 1.0 + a * (b / (cos_theta + 0.01)).exp();
            let f2 = c_
                + d_ * (e * gamma).exp()
                + f * cos_gamma * cos_gamma
                + g * chi
                + i_zenith * cos_theta.sqrt();
            *o = (f1 * f2 * self.radiance[c] * self.scale * CIE_Y_NORMALIZATION) as f32;
        }
        Vec3::from_array(out).max(Vec3::ZERO)
    }
}

/// The sky baked into a [`BAKE_WIDTH`] × [`BAKE_HEIGHT`] equirectangular map (rotation 0,
/// scale 1; each texel the radiance toward its center). The horizon falls on a row boundary,
/// so the lower half is black, as the model is.
pub fn bake(sky: &SkyParams) -> EnvironmentMap {
    let model = SkyModel::new(sky);
    let (w, h) = (BAKE_WIDTH, BAKE_HEIGHT);
    let mut texels = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let d = equirect_direction(
                (x as f32 + 0.5) / w as f32,
                (y as f32 + 0.5) / h as f32,
                0.0,
            );
            texels.extend(model.radiance_toward(d).extend(1.0).to_array());
        }
    }
    EnvironmentMap {
        path: std::path::PathBuf::from("(analytic sky)"),
        width: w,
        height: h,
        texels,
        rotation_deg: 0.0,
        scale: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's `sunsky` (scalar_rgb, `sun_scale` 0, `to_world` a −90° turn about +X so
    /// that its +Z up is voxgi's +Y) evaluated at these directions for a sun toward
    /// (0.5, 0.6, −0.3), turbidity 3.5 and albedo (0.2, 0.3, 0.4): `emitter.eval(si)` with
    /// `si.wi = −d`. The values are Mitsuba's output, printed to 6 digits.
    const MITSUBA: [([f32; 3], [f32; 3]); 6] = [
        ([0.0, 1.0, 0.0], [0.0269918, 0.0455555, 0.092993]),
        ([1.0, 0.1, 0.0], [0.176467, 0.240457, 0.321403]),
        ([0.0, 0.05, -1.0], [0.148372, 0.205074, 0.26525]),
        ([0.5, 0.6, -0.3], [0.241736, 0.266728, 0.283257]),
        ([-0.5, 0.6, 0.3], [0.0242219, 0.0499463, 0.106626]),
        ([0.3, 0.2, 0.8], [0.0674819, 0.118915, 0.205635]),
    ];

    fn probe_sky() -> SkyParams {
        SkyParams {
            turbidity: 3.5,
            ground_albedo: Vec3::new(0.2, 0.3, 0.4),
            scale: 1.0,
            toward_sun: Vec3::new(0.5, 0.6, -0.3).normalize(),
        }
    }

    #[test]
    fn sky_matches_mitsubas_sunsky() {
        let model = SkyModel::new(&probe_sky());
        for (d, want) in MITSUBA {
            let got = model.radiance_toward(Vec3::from_array(d).normalize());
            let want = Vec3::from_array(want);
            // Mitsuba evaluates in f32 and prints 6 significant digits: 1e-4 relative.
            let err = ((got - want).abs() / want).max_element();
            assert!(err < 1e-4, "{d:?}: voxgi {got}, Mitsuba {want} ({err:e})");
        }
        assert_eq!(
            model.radiance_toward(Vec3::new(0.0, -0.2, 1.0).normalize()),
            Vec3::ZERO
        );
    }

    #[test]
    fn sun_below_the_horizon_makes_a_black_sky() {
        let mut sky = probe_sky();
        sky.toward_sun = Vec3::new(0.5, -0.1, 0.0).normalize();
        let map = bake(&sky);
        assert!(map.texels.chunks_exact(4).all(|t| t[..3] == [0.0; 3]));
    }

    #[test]
    fn bake_follows_the_map_convention_and_scale() {
        let mut sky = probe_sky();
        sky.scale = 2.0;
        let map = bake(&sky);
        let model = SkyModel::new(&sky);
        let env = super::super::Environment::Sky { sky, map };
        // Texel centers: the map's nearest-texel lookup returns the model there exactly.
        for (u, v) in [(0.1, 0.2), (0.6, 0.45), (0.3, 0.05)] {
            let (x, y) = (
                (u * BAKE_WIDTH as f32).floor(),
                (v * BAKE_HEIGHT as f32).floor(),
            );
            let d = equirect_direction(
                (x + 0.5) / BAKE_WIDTH as f32,
                (y + 0.5) / BAKE_HEIGHT as f32,
                0.0,
            );
            let (a, b) = (env.radiance_toward(d), model.radiance_toward(d));
            assert!(
                (a - b).abs().max_element() <= 1e-6 * b.max_element(),
                "{a} {b}"
            );
            assert!(b.min_element() > 0.0);
        }
        // The lower half is black.
        let half = (BAKE_WIDTH * BAKE_HEIGHT / 2 * 4) as usize;
        let texels: &[f32] = env.map().map(|m| m.texels.as_slice()).unwrap_or(&[]);
        assert!(texels.len() == half * 2);
        assert!(texels[half..].iter().all(|&t| t == 0.0 || t == 1.0));
    }
}
