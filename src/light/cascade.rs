//! Cascaded shadow maps for directional lights (Dachsbacher 2014, part 3, A.5: split the view
//! frustum along its depth and give each slice its own orthographic map).
//!
//! - **Splits**: the practical split scheme of Zhang et al. 2006, a blend λ of logarithmic and
//!   uniform splits over the camera's depth range ([`cascade_splits`]).
//! - **Fit**: each cascade's map is a square around the bounding sphere of its frustum slice,
//!   whose size depends only on the slice's depths and the field of view, not on where the
//!   camera looks, so a turning camera does not change the texel size.
//! - **Snapping**: the map's window moves in whole texels of a grid fixed in light space
//!   (the light's rotation only, no translation), so scene points keep their texel while the
//!   camera moves and shadow edges do not swim.
//! - **Blending**: cascade i+1 also covers the last [`CASCADE_BLEND`] of cascade i's depth
//!   range, over which `glsl/include/shadow.glsl` (`cascade_visibility`) fades from one to the
//!   other; past the last split the light's whole-scene map takes over with the same fade.
//!
//! Depth along the light still spans the whole scene, so every caster is in every cascade.
//! Only the camera's direct light (`deferred_direct`) reads the cascades: the reflective light
//! maps, the VPLs and the path tracer keep the light's single whole-scene map.

use super::shadow::{ShadowProjection, ShadowView};
use crate::scene::ShadowSettings;
use crate::scene::{look_to, Aabb, Camera, Light, Projection};
use glam::camera::rh::proj::directx;
use glam::Vec3;

/// Share of each cascade's depth range (from the previous split, or from 0 for the first) at
/// its far end over which it fades into the next one. Mirrored by `CASCADE_BLEND` in
/// `glsl/include/shadow.glsl`.
pub const CASCADE_BLEND: f32 = 0.1;

/// The far split distances C_1..C_N (meters of view depth) of `count` cascades over
/// [`near_m`, `far_m`], after Zhang et al. 2006:
/// C_i = λ·n·(f/n)^(i/N) + (1 − λ)·(n + (f − n)·i/N).
/// λ = 1 is the logarithmic scheme (constant ratio of texel to pixel size along the view,
/// the ideal for a perspective camera), λ = 0 the uniform one; C_N = f.
pub fn cascade_splits(near_m: f32, far_m: f32, count: u32, lambda: f32) -> Vec<f32> {
    let (n, f) = (f64::from(near_m), f64::from(far_m));
    let count = count.max(1);
    (1..=count)
        .map(|i| {
            let t = f64::from(i) / f64::from(count);
            let log = n * (f / n).powf(t);
            let uniform = n + (f - n) * t;
            (f64::from(lambda) * log + (1.0 - f64::from(lambda)) * uniform) as f32
        })
        .collect()
}

/// The depth band [start, end] of view depth that cascade `i` of `splits` must cover: its own
/// slice plus the blend band at the end of the previous cascade.
pub fn cascade_slice(near_m: f32, splits: &[f32], i: usize) -> (f32, f32) {
    let start = match i {
        0 => near_m,
        _ => splits[i - 1] - blend_band_m(splits, i - 1),
    };
    (start, splits[i])
}

/// Width of the blend band at the far end of cascade `i` (meters of view depth).
pub fn blend_band_m(splits: &[f32], i: usize) -> f32 {
    let prev = if i == 0 { 0.0 } else { splits[i - 1] };
    CASCADE_BLEND * (splits[i] - prev)
}

/// The depth range the cascades split: the camera's near plane to the nearer of its far
/// plane and the farthest the scene's bounding sphere reaches, the latter rounded up to a
/// power of 2^(1/4) so that the splits (and with them the texel sizes) change only at those
/// steps while the camera moves, not with every move.
pub fn cascade_range(camera: &Camera, scene_aabb: &Aabb) -> (f32, f32) {
    let radius = 0.5 * scene_aabb.extent().length();
    let reach = (camera.position.distance(scene_aabb.center()) + radius).max(camera.near * 2.0);
    let quantized = 2f32.powf((reach.log2() * 4.0).ceil() / 4.0);
    let far = quantized.min(camera.far).max(camera.near * 1.001);
    (camera.near, far)
}

/// Depth of the center (along the view axis) and radius of the bounding sphere of the
/// perspective frustum slice between view depths `d0` and `d1`, whose corners lie
/// `k` = √(tan²(fov_x/2) + tan²(fov_y/2)) times their depth off the axis. The sphere through
/// both corner rings has its center at c = (d0 + d1)(1 + k²)/2; when that lies beyond d1 the far
/// ring alone bounds the slice (c = d1, radius k·d1).
pub fn slice_sphere(d0: f32, d1: f32, k: f32) -> (f32, f32) {
    let c = (0.5 * (d0 + d1) * (1.0 + k * k)).min(d1);
    let radius = ((c - d0) * (c - d0) + (k * d0) * (k * d0))
        .max((d1 - c) * (d1 - c) + (k * d1) * (k * d1))
        .sqrt();
    (c, radius)
}

/// Depth of the center and radius of the bounding sphere of the orthographic view's slice
/// between view depths `d0` and `d1`: a box whose cross-section (the view, `half_diagonal`
/// from its axis to a corner) does not change with depth, bounded by the sphere at its middle
/// through its eight corners.
pub fn ortho_slice_sphere(d0: f32, d1: f32, half_diagonal: f32) -> (f32, f32) {
    let half_depth = 0.5 * (d1 - d0);
    (
        0.5 * (d0 + d1),
        (half_depth * half_depth + half_diagonal * half_diagonal).sqrt(),
    )
}

/// Texels kept free at each side of a cascade's window: the lookup's normal offset (at most
/// (r + 1/2)√2 texels plus the extra offset, `glsl/include/shadow.glsl`), the PCF taps
/// (r + 1) and the snapping's rounding (1/2, taken as 1).
fn margin_texels(settings: &ShadowSettings) -> f32 {
    let r = settings.pcf_radius as f32;
    ((r + 0.5) * std::f32::consts::SQRT_2 + settings.normal_offset_texels).ceil() + r + 2.0
}

/// The cascade views of every directional light among `lights` (the frame's light list, area
/// lights already sampled) for `camera` at `aspect`: `(light index, views)`, nothing when
/// `settings.cascades` < 2. `scene_aabb` bounds the casters at the frame's time.
///
/// `whole_texel_m(i)` is the texel footprint of light i's whole-scene map. A cascade whose
/// texel is not finer than that map's only costs (a camera whose far slices are wider than the
/// scene, as in a large hall seen from inside): the cascades from the first such one on are
/// dropped, so the last one kept fades into the whole-scene map, and a light whose first
/// cascade is already no finer keeps none.
pub fn cascade_views(
    lights: &[Light],
    camera: &Camera,
    aspect: f32,
    scene_aabb: &Aabb,
    settings: &ShadowSettings,
    whole_texel_m: impl Fn(usize) -> f32,
) -> Vec<(usize, Vec<ShadowView>)> {
    if settings.cascades < 2 {
        return Vec::new();
    }
    let (near, far) = cascade_range(camera, scene_aabb);
    let splits = cascade_splits(near, far, settings.cascades, settings.cascade_lambda);
    let tan_y = (0.5 * camera.fov_y_deg.to_radians()).tan();
    let aspect = if aspect.is_finite() && aspect > 0.0 {
        aspect
    } else {
        1.0
    };
    let tan_x = tan_y * aspect + camera.shift_x_tan.abs();
    let k = (tan_x * tan_x + tan_y * tan_y).sqrt();
    // Orthographic: the slice is a box whose cross-section is the whole view at every depth.
    let half_diagonal = 0.5 * camera.ortho_height_m * (aspect * aspect + 1.0).sqrt();
    let forward = camera.forward.normalize_or_zero();
    let mut out = Vec::new();
    for (li, light) in lights.iter().enumerate() {
        let Light::Directional { direction, .. } = *light else {
            continue;
        };
        let whole = whole_texel_m(li);
        let views: Vec<ShadowView> = (0..splits.len())
            .map(|i| {
                let (d0, d1) = cascade_slice(near, &splits, i);
                let (c, radius) = match camera.projection {
                    Projection::Perspective => slice_sphere(d0, d1, k),
                    Projection::Orthographic => ortho_slice_sphere(d0, d1, half_diagonal),
                };
                let center = camera.position + forward * c;
                let mut v = fitted_view(direction, center, radius, scene_aabb, settings);
                v.light = li;
                v.split_far_m = d1;
                v
            })
            .take_while(|v| v.texel_footprint < whole)
            .collect();
        if !views.is_empty() {
            out.push((li, views));
        }
    }
    out
}

/// An orthographic view along `direction` whose square window holds the sphere (`center`,
/// `radius`) with [`margin_texels`] to spare, snapped to whole texels when
/// `settings.cascade_snap`, and whose depth range holds all of `scene_aabb`.
pub fn fitted_view(
    direction: Vec3,
    center: Vec3,
    radius: f32,
    scene_aabb: &Aabb,
    settings: &ShadowSettings,
) -> ShadowView {
    let res = settings.resolution.max(1) as f32;
    // The light's rotation about the world origin: a grid fixed in the world for snapping.
    let view = look_to(Vec3::ZERO, direction, super::shadow::up_for(direction));
    let usable = (res - 2.0 * margin_texels(settings)).max(0.5 * res);
    let texel = (2.0 * radius / usable).max(f32::MIN_POSITIVE);
    let half = 0.5 * res * texel;
    let c = view.transform_point3(center);
    let snap = |x: f32| {
        if settings.cascade_snap {
            (x / texel).round() * texel
        } else {
            x
        }
    };
    let (cx, cy) = (snap(c.x), snap(c.y));
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for i in 0..8 {
        let p = Vec3::new(
            if i & 1 == 0 {
                scene_aabb.min.x
            } else {
                scene_aabb.max.x
            },
            if i & 2 == 0 {
                scene_aabb.min.y
            } else {
                scene_aabb.max.y
            },
            if i & 4 == 0 {
                scene_aabb.min.z
            } else {
                scene_aabb.max.z
            },
        );
        let z = view.transform_point3(p).z;
        lo = lo.min(z);
        hi = hi.max(z);
    }
    // The view looks down -z; a few texels of depth margin as the whole-scene map has.
    let z_margin = texel * margin_texels(settings) + 1e-6 * (hi - lo).abs().max(1.0);
    let (near, far) = (-hi - z_margin, -lo + z_margin);
    let proj = super::shadow::flip_y(directx::orthographic(
        cx - half,
        cx + half,
        cy - half,
        cy + half,
        near,
        far,
    ));
    ShadowView {
        view_proj: proj * view,
        texel_footprint: texel,
        projection: ShadowProjection::Orthographic,
        axis: direction,
        near,
        far,
        light: 0,
        split_far_m: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_match_the_closed_forms_of_both_schemes() {
        // n = 1, f = 16, N = 4. Logarithmic: n (f/n)^(i/4) = 2, 4, 8, 16. Uniform: 1 + 15 i/4
        // = 4.75, 8.5, 12.25, 16. λ = 1/2: their means 3.375, 6.25, 10.125, 16.
        let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
        let log = cascade_splits(1.0, 16.0, 4, 1.0);
        assert!(close(&log, &[2.0, 4.0, 8.0, 16.0]), "{log:?}");
        let uni = cascade_splits(1.0, 16.0, 4, 0.0);
        assert!(close(&uni, &[4.75, 8.5, 12.25, 16.0]), "{uni:?}");
        let half = cascade_splits(1.0, 16.0, 4, 0.5);
        assert!(close(&half, &[3.375, 6.25, 10.125, 16.0]), "{half:?}");
        // One cascade is the whole range.
        assert_eq!(cascade_splits(0.1, 50.0, 1, 0.3), vec![50.0]);
    }

    #[test]
    fn the_shader_blends_over_the_same_band() {
        let glsl = include_str!("../../glsl/include/shadow.glsl");
        assert!(
            glsl.contains(&format!("#define CASCADE_BLEND {CASCADE_BLEND:?}")),
            "glsl/include/shadow.glsl must define CASCADE_BLEND {CASCADE_BLEND:?}"
        );
    }

    #[test]
    fn the_slice_sphere_holds_the_slice_corners_and_is_tight() {
        for &(d0, d1, k) in &[(0.1f32, 1.0f32, 0.5f32), (1.0, 1.5, 1.2), (3.0, 40.0, 0.3)] {
            let (c, r) = slice_sphere(d0, d1, k);
            // Corners at depth d lie k·d off the axis: distance² (d - c)² + (k d)².
            let dist = |d: f32| ((d - c) * (d - c) + (k * d) * (k * d)).sqrt();
            assert!(dist(d0) <= r * (1.0 + 1e-5) && dist(d1) <= r * (1.0 + 1e-5));
            // Tight: some corner ring lies on the sphere.
            assert!(
                (dist(d0).max(dist(d1)) - r).abs() < 1e-4 * r,
                "{d0} {d1} {k}"
            );
        }
    }

    /// Under orthographic projection each cascade's map holds the whole box of its slice: the
    /// view's rectangle (ortho height × aspect) at both ends of the slice's depth band, and
    /// the texel stays the same size for slices of equal depth.
    #[test]
    fn orthographic_cascades_hold_their_slice_boxes() {
        let settings = ShadowSettings {
            cascade_lambda: 0.0,
            ..ShadowSettings::default()
        };
        let aabb = Aabb {
            min: Vec3::splat(-20.0),
            max: Vec3::splat(20.0),
        };
        let (h, aspect) = (6.0, 1.5);
        let camera = Camera {
            position: Vec3::new(1.0, 2.0, -25.0),
            forward: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            near: 0.1,
            far: 200.0,
            shift_x_tan: 0.0,
            projection: Projection::Orthographic,
            ortho_height_m: h,
        };
        let sun = [Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
            irradiance_w_m2: Vec3::ONE,
        }];
        let sets = cascade_views(&sun, &camera, aspect, &aabb, &settings, |_| f32::MAX);
        let views = &sets[0].1;
        assert_eq!(views.len(), settings.cascades as usize);
        let (near, far) = cascade_range(&camera, &aabb);
        let splits = cascade_splits(near, far, settings.cascades, 0.0);
        let right = camera.right();
        for (i, v) in views.iter().enumerate() {
            let (d0, d1) = cascade_slice(near, &splits, i);
            for corner in 0..8 {
                let d = if corner & 1 == 0 { d0 } else { d1 };
                let sx = if corner & 2 == 0 { -0.5 } else { 0.5 };
                let sy = if corner & 4 == 0 { -0.5 } else { 0.5 };
                let p = camera.position
                    + camera.forward * d
                    + right * (sx * h * aspect)
                    + camera.up * (sy * h);
                let ndc = v.view_proj.project_point3(p);
                assert!(
                    ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0 && (0.0..=1.0).contains(&ndc.z),
                    "cascade {i} misses {p}: {ndc}"
                );
            }
        }
        // Uniform splits of equal depth after the first: the same sphere, the same texel.
        let t = |i: usize| views[i].texel_footprint;
        assert!((t(2) - t(3)).abs() < 1e-5 * t(2), "{} {}", t(2), t(3));
    }

    /// Slices grow with depth, and so do their texels; against a whole-scene map whose texel
    /// lies between those of cascades 2 and 3, cascades 3 and 4 go, and against one finer than
    /// the first cascade's, all of them.
    #[test]
    fn cascades_no_finer_than_the_whole_map_are_dropped() {
        let settings = ShadowSettings::default();
        let aabb = Aabb {
            min: Vec3::splat(-50.0),
            max: Vec3::splat(50.0),
        };
        let camera = Camera {
            position: Vec3::ZERO,
            forward: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            near: 0.1,
            far: 200.0,
            shift_x_tan: 0.0,
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
        };
        let sun = [Light::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance_w_m2: Vec3::ONE,
        }];
        let all = cascade_views(&sun, &camera, 1.0, &aabb, &settings, |_| f32::INFINITY);
        assert_eq!(all.len(), 1);
        let texels: Vec<f32> = all[0].1.iter().map(|v| v.texel_footprint).collect();
        assert_eq!(texels.len(), settings.cascades as usize);
        assert!(texels.windows(2).all(|w| w[0] < w[1]), "{texels:?}");
        let between = 0.5 * (texels[1] + texels[2]);
        let capped = cascade_views(&sun, &camera, 1.0, &aabb, &settings, |_| between);
        let kept: Vec<f32> = capped[0].1.iter().map(|v| v.texel_footprint).collect();
        assert_eq!(kept, texels[..2]);
        let none = cascade_views(&sun, &camera, 1.0, &aabb, &settings, |_| texels[0]);
        assert!(none.is_empty());
    }

    #[test]
    fn snapping_moves_the_window_in_whole_texels() {
        let settings = ShadowSettings::default();
        let aabb = Aabb {
            min: Vec3::splat(-10.0),
            max: Vec3::splat(10.0),
        };
        let dir = Vec3::new(0.3, -1.0, 0.2).normalize();
        let a = fitted_view(dir, Vec3::new(0.1, 0.0, 0.3), 2.0, &aabb, &settings);
        // A world point maps to the same texel coordinate (up to rounding) wherever the
        // window's sphere moves, since the window moves in whole texels.
        let p = Vec3::new(0.7, 0.2, -0.4);
        let res = settings.resolution as f32;
        let texel_coord = |v: &ShadowView| {
            let q = v.view_proj.project_point3(p);
            (q.truncate() * 0.5 + 0.5) * res
        };
        for step in 1..20 {
            let c = Vec3::new(0.1 + 0.0123 * step as f32, 0.0, 0.3 - 0.007 * step as f32);
            let b = fitted_view(dir, c, 2.0, &aabb, &settings);
            let d = texel_coord(&b) - texel_coord(&a);
            let frac = (d - d.round()).abs();
            assert!(frac.max_element() < 1e-2, "step {step}: {d}");
        }
    }
}
