//! Area lights as sums of sub-lights: the "brute force" soft shadow that converges (Dachsbacher
//! 2014, part 3, soft shadows: sample the light's surface, render one shadow map per sample,
//! average). Each sample is a [`Light::Element`], a small patch of the emitter's surface with
//! its own shadow view (one paraboloid hemisphere around its normal).
//!
//! Why the weights are exact in the limit. A surface emitter of radiance L gives a receiver at
//! x (normal n) the irradiance E(x) = ∫_A L·V(x, y)·cos θ_y·cos θ_x / |x − y|² dA_y, θ_y
//! measured from the emitter's normal at y and cos θ_y clamped at 0 (one-sided surfaces).
//! Splitting A into S cells of area A_i and taking one point y_i per cell gives
//! E ≈ Σ_i (L·A_i)·max(cos θ_i, 0)·V(x, y_i)·cos θ_x / |x − y_i|²: a point light at y_i with
//! the intensity I_i(θ) = L·A_i·max(cos θ, 0), exactly what `Light::Element` is. The error
//! vanishes as the cells shrink (midpoint rule), so S → ∞ converges to the area light.
//!  - Rectangle (w × h, normal n): a grid of nx × ny cells, their centres as samples, A_i =
//!    w·h/S. nx is the divisor of S that makes the cells closest to square.
//!  - Sphere (radius R): the emitter is the whole sphere surface, each element facing outward,
//!    A_i = 4πR²/S, at S points of a Fibonacci spiral (equal areas, low discrepancy). A
//!    receiver outside the sphere sees exactly the elements whose normal faces it — max(cos θ,
//!    0) > 0 — so the sum needs no separate visibility of the sphere itself; about half the
//!    elements light any one receiver, which is the cost of fixed shadow views (a disk facing
//!    the receiver would need one per receiver). Far away the sum is L·πR²/d², the sphere's
//!    exact irradiance (∫ max(n·w, 0) dA = πR²).

use crate::scene::Light;
use crate::scene::{AreaShadow, ShadowSettings};
use glam::Vec3;

/// The lights a frame renders with `settings`: [`sample_lights`], except that with
/// `--area-shadows pcss` a rectangle is one element at its centre carrying the whole
/// L·w·h (exact far away) and its size √(w·h) for PCSS (Fernando 2005; Oetke 2017 §4.3;
/// glsl/include/shadow.glsl). Spheres stay sampled: their emission faces every way, which one
/// element cannot carry.
pub fn frame_lights(lights: &[Light], settings: &ShadowSettings) -> Vec<Light> {
    if settings.area_technique == AreaShadow::Sampled {
        return sample_lights(lights, settings.area_samples);
    }
    let mut out = Vec::with_capacity(lights.len());
    for light in lights {
        match *light {
            Light::Rectangle {
                position,
                normal,
                width_m,
                height_m,
                radiance_w_sr_m2,
                ..
            } => out.push(Light::Element {
                position,
                normal,
                intensity_w_sr: radiance_w_sr_m2 * (width_m * height_m),
                pcss_size_m: (width_m * height_m).sqrt(),
            }),
            // A sphere stays whole: a uniform emitter at its centre, shadowed by two
            // paraboloid hemispheres, its PCSS size the diameter (`super::shadow`,
            // `render::gpu_light`).
            Light::Sphere { .. } => out.push(*light),
            other => out.extend(sample_lights(&[other], settings.area_samples)),
        }
    }
    out
}

/// The lights a frame renders: `lights` with every sphere and rectangle replaced by its
/// samples (`samples` when given, else the light's own count). Other lights stay as they are,
/// in order.
pub fn sample_lights(lights: &[Light], samples: Option<u32>) -> Vec<Light> {
    let mut out = Vec::with_capacity(lights.len());
    for light in lights {
        match *light {
            Light::Sphere {
                position,
                radius_m,
                radiance_w_sr_m2,
                samples: own,
            } => {
                let s = samples.unwrap_or(own).max(1);
                let area_m2 = 4.0 * std::f32::consts::PI * radius_m * radius_m / s as f32;
                out.extend(fibonacci_sphere(s).map(|normal| Light::Element {
                    position: position + normal * radius_m,
                    normal,
                    intensity_w_sr: radiance_w_sr_m2 * area_m2,
                    pcss_size_m: 0.0,
                }));
            }
            Light::Rectangle {
                position,
                normal,
                width_axis,
                width_m,
                height_m,
                radiance_w_sr_m2,
                samples: own,
            } => {
                let s = samples.unwrap_or(own).max(1);
                let height_axis = normal.cross(width_axis);
                let area_m2 = width_m * height_m / s as f32;
                let (nx, ny) = grid_for(s, width_m / height_m);
                for j in 0..ny {
                    for i in 0..nx {
                        let u = (i as f32 + 0.5) / nx as f32 - 0.5;
                        let v = (j as f32 + 0.5) / ny as f32 - 0.5;
                        out.push(Light::Element {
                            position: position
                                + width_axis * (u * width_m)
                                + height_axis * (v * height_m),
                            normal,
                            intensity_w_sr: radiance_w_sr_m2 * area_m2,
                            pcss_size_m: 0.0,
                        });
                    }
                }
            }
            other => out.push(other),
        }
    }
    out
}

/// Grid of `s` cells over a rectangle of width / height `aspect`: (nx, ny), nx·ny = s, with
/// the divisor nx that makes a cell's aspect (aspect·ny/nx) closest to 1 in log scale.
pub fn grid_for(s: u32, aspect: f32) -> (u32, u32) {
    let s = s.max(1);
    (1..=s)
        .filter(|nx| s.is_multiple_of(*nx))
        .map(|nx| (nx, s / nx))
        .min_by(|a, b| {
            let err = |(nx, ny): (u32, u32)| (aspect * ny as f32 / nx as f32).ln().abs();
            err(*a).total_cmp(&err(*b))
        })
        .unwrap_or((1, s))
}

/// `s` unit directions of equal-area cells on the sphere: a Fibonacci spiral, z = 1 − (2i+1)/s
/// (uniform in z, hence in area, Archimedes), the azimuth turned by the golden angle.
fn fibonacci_sphere(s: u32) -> impl Iterator<Item = Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    (0..s).map(move |i| {
        let z = 1.0 - (2.0 * i as f32 + 1.0) / s as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * i as f32;
        // y up, so the first samples are at the top of the sphere.
        Vec3::new(r * phi.cos(), z, r * phi.sin())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Irradiance at `x` (normal `n`) from sampled lights, unshadowed.
    fn irradiance(lights: &[Light], x: Vec3, n: Vec3) -> f32 {
        lights
            .iter()
            .map(|l| match *l {
                Light::Element {
                    position,
                    normal,
                    intensity_w_sr,
                    ..
                } => {
                    let d = x - position;
                    let w = d.normalize();
                    intensity_w_sr.x * normal.dot(w).max(0.0) * n.dot(-w).max(0.0)
                        / d.length_squared()
                }
                _ => unreachable!("only samples"),
            })
            .sum()
    }

    #[test]
    fn sphere_samples_converge_to_the_exact_irradiance() {
        // A sphere of radiance L seen from distance D on the normal: E = π L (R/D)² (the
        // solid-angle formula π L sin²α with sin α = R/D).
        let (r, d, l) = (0.5f32, 3.0f32, 2.0f32);
        let sphere = Light::Sphere {
            position: Vec3::ZERO,
            radius_m: r,
            radiance_w_sr_m2: Vec3::splat(l),
            samples: 1,
        };
        let exact = std::f32::consts::PI * l * (r / d).powi(2);
        let mut last = f32::INFINITY;
        for s in [16, 64, 256, 4096] {
            let lights = sample_lights(&[sphere], Some(s));
            assert_eq!(lights.len(), s as usize);
            // A direction off the spiral's axis, the receiver facing the sphere.
            let dir = Vec3::new(0.3, -1.0, 0.1).normalize();
            let err = (irradiance(&lights, dir * d, -dir) - exact).abs() / exact;
            assert!(
                err <= last.max(0.02),
                "{s} samples: error {err} after {last}"
            );
            last = err;
        }
        assert!(last < 2e-3, "4096 samples: relative error {last}");
    }

    #[test]
    fn rectangle_samples_tile_the_rectangle() {
        let rect = Light::Rectangle {
            position: Vec3::new(0.0, 2.0, 0.0),
            normal: Vec3::NEG_Y,
            width_axis: Vec3::X,
            width_m: 0.8,
            height_m: 0.2,
            radiance_w_sr_m2: Vec3::splat(5.0),
            samples: 8,
        };
        let lights = sample_lights(&[rect], None);
        assert_eq!(grid_for(8, 4.0), (4, 2), "cells 0.2 x 0.1 m");
        assert_eq!(lights.len(), 8);
        let mut total = 0.0;
        for l in &lights {
            let Light::Element {
                position,
                normal,
                intensity_w_sr,
                ..
            } = *l
            else {
                unreachable!("only samples")
            };
            assert_eq!(normal, Vec3::NEG_Y);
            assert!((position.y - 2.0).abs() < 1e-6);
            assert!(position.x.abs() < 0.4 && position.z.abs() < 0.1);
            total += intensity_w_sr.x;
        }
        // Σ L·A_i = L·w·h.
        assert!((total - 5.0 * 0.8 * 0.2).abs() < 1e-5);
        // Far along the normal, the rectangle is a Lambertian patch: E = L·A / D².
        let e = irradiance(&lights, Vec3::new(0.0, -98.0, 0.0), Vec3::Y);
        assert!((e - 5.0 * 0.16 / 1e4).abs() < 1e-4 * e);
    }
}
