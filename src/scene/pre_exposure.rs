//! The per-scene pre-exposure of radiance stored in half floats (Lagarde and de Rousiers 2014,
//! "Moving Frostbite to Physically Based Rendering", §5.1: radiance is multiplied by an
//! exposure before it reaches a 16-bit float target, and by its inverse where it is read).
//!
//! Half floats hold 2^-14 to 65,504 at full precision (IEEE 754-2008 binary16), but a user may
//! write emission from 1e-6 to 1e9 W/(m²·sr), as for light intensities. Every image or buffer
//! that stores radiance as half floats (the G-buffer's emission, the voxel emission sums and
//! volume, the screen-space reflections' lit colour, the transparency lists' lit colour)
//! therefore stores radiance × 2^-k, and every reader multiplies by 2^k, in f32. The scale is
//! a power of two, so both products are exact while the values stay in the normal range: a
//! render at k ≠ 0 equals the render at k = 0 scaled, and at k = 0 — every scene whose
//! brightest source lies in [`NEUTRAL_BAND`] — the multiplications by 1 change no bit.
//!
//! `k` is chosen once per scene from its brightest source ([`brightest_source`]), so that it
//! lands in [1, 2) outside [`NEUTRAL_BAND`]: 2^15 of headroom for sums of fragments and for lit values above the
//! sources, and 2^14 below it before half floats lose precision (subnormals).

use super::{Environment, Light, Scene};

/// The dimmest and the brightest source (max channel) for which `k` stays 0: half floats'
/// normal range, less 2^2 of headroom at the top for the voxelizer's sums of a few fragments
/// per voxel. Every scene in `assets/scenes` lies within (the brightest source is the
/// 16,000 W/(m²·sr) sphere light of `sponza_authors`), so each stores its radiance unscaled.
pub const NEUTRAL_BAND: (f32, f32) = (1.0 / 16384.0, 16384.0);

/// The largest |k|: 2^±k must be a normal f32 (2^-126 to 2^127), with room for the values the
/// scale multiplies.
const MAX_EXPONENT: i32 = 100;

/// A scene's pre-exposure: half-float images hold radiance × [`Self::store_scale`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PreExposure {
    /// The power of two: stored = radiance × 2^-k.
    pub k: i32,
}

impl PreExposure {
    /// No scaling (k = 0).
    pub const NEUTRAL: PreExposure = PreExposure { k: 0 };

    /// The pre-exposure for a scene whose brightest source is `brightest` (W/sr, W/m² or
    /// W/(m²·sr), see [`brightest_source`]): k = 0 within [`NEUTRAL_BAND`] (and for a scene
    /// without sources), else the binary exponent of `brightest`, so that brightest × 2^-k
    /// lies in [1, 2).
    pub fn for_brightest(brightest: f32) -> PreExposure {
        let (low, high) = NEUTRAL_BAND;
        if !brightest.is_finite() || brightest <= 0.0 || (low..=high).contains(&brightest) {
            return PreExposure::NEUTRAL;
        }
        // floor(log2(x)) read from the exponent bits is exact, where log2 may round up just
        // below a power of two; a subnormal `brightest` has the smallest exponent, which the
        // clamp covers.
        let exponent = ((brightest.to_bits() >> 23) & 0xff) as i32 - 127;
        PreExposure {
            k: exponent.clamp(-MAX_EXPONENT, MAX_EXPONENT),
        }
    }

    /// The pre-exposure of `scene` ([`Self::for_brightest`] of [`brightest_source`]).
    pub fn of_scene(scene: &Scene) -> PreExposure {
        PreExposure::for_brightest(brightest_source(scene))
    }

    /// 2^-k: what a writer of a half-float radiance image multiplies by.
    pub fn store_scale(self) -> f32 {
        pow2(-self.k)
    }

    /// 2^k: what a reader of a half-float radiance image multiplies by.
    pub fn read_scale(self) -> f32 {
        pow2(self.k)
    }

    /// `GpuFrame::radiance_scale`: x the store scale, y the read scale (`frame.glsl`).
    pub fn frame_constants(self) -> [f32; 4] {
        [self.store_scale(), self.read_scale(), 0.0, 0.0]
    }
}

/// 2^e for |e| ≤ 126, built from its exponent bits (exact, no libm rounding).
fn pow2(e: i32) -> f32 {
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// The largest value (max over RGB) of any source in `scene`: material emission (W/(m²·sr)),
/// area-light radiance (W/(m²·sr)), point and spot intensity (W/sr), directional irradiance
/// (W/m²) and the environment's radiance (the constant, or the map's brightest texel × scale).
/// The units differ; each is the radiance of what it lights at about 1 m (a point light of
/// I W/sr gives a white surface 1 m away the radiance I/π), which is what the half-float
/// images hold, so one maximum serves them all.
pub fn brightest_source(scene: &Scene) -> f32 {
    let max3 = |v: glam::Vec3| v.max_element();
    let materials = scene.materials.iter().map(|m| max3(m.emission));
    let lights = scene.lights.iter().map(|l| {
        max3(match *l {
            Light::Point { intensity_w_sr, .. }
            | Light::Spot { intensity_w_sr, .. }
            | Light::Element { intensity_w_sr, .. } => intensity_w_sr,
            Light::Directional {
                irradiance_w_m2, ..
            } => irradiance_w_m2,
            Light::Sphere {
                radiance_w_sr_m2, ..
            }
            | Light::Rectangle {
                radiance_w_sr_m2, ..
            } => radiance_w_sr_m2,
        })
    });
    let environment = scene.environment.iter().map(|e| match e {
        Environment::Constant { radiance } => max3(*radiance),
        Environment::Map(map) | Environment::Sky { map, .. } => {
            let texel = map
                .texels
                .chunks_exact(4)
                .flat_map(|t| t[..3].iter().copied())
                .fold(0.0f32, f32::max);
            texel * map.scale
        }
    });
    materials
        .chain(lights)
        .chain(environment)
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max)
}

/// The smallest normal and the largest finite half float (IEEE 754-2008 binary16).
pub const HALF_RANGE: (f32, f32) = (1.0 / 16384.0, 65504.0);

/// One warning per material whose emission half floats cannot hold at the pre-exposure `p`:
/// a non-zero channel that, times 2^-k, falls below the normal range (it keeps fewer than
/// 11 significant bits, or none) or above 65,504 (clipped). Only scenes whose sources span
/// more than about 2^29, or pass 2^100, have any.
pub fn unrepresentable_emission(scene: &Scene, p: PreExposure) -> Vec<String> {
    let (low, high) = HALF_RANGE;
    let range = (low * p.read_scale(), high * p.read_scale());
    scene
        .materials
        .iter()
        .filter_map(|m| {
            let channels = m.emission.to_array();
            let lit = || channels.iter().filter(|&&c| c > 0.0);
            let dim = lit().any(|&c| c < range.0);
            let bright = lit().any(|&c| c > range.1);
            (dim || bright).then(|| {
                format!(
                    "material '{}': its emission {:?} W/(m²·sr) is outside the {:e} to {:e} \
                     that half-float images hold at this scene's pre-exposure 2^{} (set by its \
                     brightest source, {:e}), so it renders {}; keep the scene's sources \
                     within about 2^29 of each other",
                    m.name,
                    channels,
                    range.0,
                    range.1,
                    -p.k,
                    brightest_source(scene),
                    if bright {
                        "clipped"
                    } else {
                        "with less precision, or black"
                    },
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_are_exact_inverse_powers_of_two() {
        for k in -MAX_EXPONENT..=MAX_EXPONENT {
            let p = PreExposure { k };
            assert_eq!(p.store_scale(), 2f32.powi(-k), "k {k}");
            assert_eq!(p.read_scale(), 2f32.powi(k), "k {k}");
            assert_eq!(p.store_scale() * p.read_scale(), 1.0, "k {k}");
        }
    }

    /// Inside the band nothing is scaled (every scene in assets/ stores its radiance as it is);
    /// outside it the brightest source is stored in [1, 2), in range with room for sums.
    #[test]
    fn k_is_zero_in_the_band_and_puts_the_brightest_in_one_to_two_outside() {
        for b in [
            0.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            1.0 / 16384.0,
            0.5,
            1.0,
            16000.0,
            16384.0,
        ] {
            assert_eq!(PreExposure::for_brightest(b), PreExposure::NEUTRAL, "{b}");
        }
        for b in [
            1e-30, 1e-9, 1e-6, 6.1e-5, 16384.01, 65504.0, 65536.0, 1e6, 1e9, 1e30,
        ] {
            let p = PreExposure::for_brightest(b);
            let stored = b * p.store_scale();
            assert!(
                (1.0..2.0).contains(&stored),
                "{b}: k {} stores {stored}",
                p.k
            );
        }
        // Just below a power of two log2 rounds up in f32; the exponent bits do not.
        let below = f32::from_bits(1048576f32.to_bits() - 1);
        assert_eq!(PreExposure::for_brightest(below).k, 19);
        assert_eq!(PreExposure::for_brightest(f32::MAX).k, MAX_EXPONENT);
        assert_eq!(PreExposure::for_brightest(1e-45).k, -MAX_EXPONENT);
    }

    /// Every scene shipped in assets/scenes keeps k = 0, so its renders stay bit for bit
    /// those of the renderer before the pre-exposure existed.
    #[test]
    fn every_shipped_scene_is_neutral() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        let mut checked = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            // The atrium's meshes are generated (tools/atrium), not committed.
            let scene = match Scene::load(&path) {
                Err(e) if e.to_string().contains("this file is generated") => continue,
                loaded => loaded.unwrap_or_else(|e| panic!("{}: {e}", path.display())),
            };
            let b = brightest_source(&scene);
            assert_eq!(
                PreExposure::of_scene(&scene),
                PreExposure::NEUTRAL,
                "{}: brightest source {b}",
                path.display()
            );
            checked += 1;
        }
        assert!(checked >= 19, "only {checked} scenes in {}", dir.display());
    }

    /// A scene with a 1e6 and a 1e-3 emitter (2^29.9 apart): k = 19 stores the bright one
    /// as 1.9 and the dim one as 1.9e-9, below the half floats' 6.1e-5; only the dim one is
    /// named. In the band no material is.
    #[test]
    fn emission_half_floats_cannot_hold_is_named() {
        let mut scene = crate::scene::builtin("cornell").unwrap();
        assert!(unrepresentable_emission(&scene, PreExposure::of_scene(&scene)).is_empty());
        let mut emitter = |name: &str, e: f32| {
            let mut m = scene.materials[0].clone();
            m.name = name.into();
            m.emission = glam::Vec3::splat(e);
            scene.materials.push(m);
        };
        emitter("sun disk", 1e6);
        emitter("night light", 1e-3);
        let p = PreExposure::of_scene(&scene);
        assert_eq!(p.k, 19);
        let warnings = unrepresentable_emission(&scene, p);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("'night light'"), "{}", warnings[0]);
        assert!(warnings[0].contains("2^-19"), "{}", warnings[0]);
        // One sentence: its source lines are joined without their indentation.
        assert!(!warnings[0].contains("  "), "{}", warnings[0]);
    }
}
