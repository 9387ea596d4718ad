//! Shadow views: the projections the shadow pass renders and the shading pass looks up.
//!
//! Every view is one layer of a single depth array. Only the views a scene needs exist: a
//! point light adds six cube faces, a spot light one perspective map, a directional light one
//! orthographic map; no lights, no shadow views.

use crate::scene::{Aabb, Light, Scene};
use glam::{Mat4, Vec3};

/// Shadow parameters (exposed in the CLI and the viewer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Width and height of every shadow-map layer, texels.
    pub resolution: u32,
    /// PCF kernel radius in texels ((2r+1)² taps).
    pub pcf_radius: u32,
    /// Constant depth bias, in shadow-map texels (scale-free).
    pub bias_texels: f32,
    /// Slope-scaled bias: texels per unit of tan(theta).
    pub slope_bias_texels: f32,
    /// Normal offset of the lookup position, in texels (times sin(theta)).
    pub normal_offset_texels: f32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            resolution: 1024,
            pcf_radius: 1,
            bias_texels: 1.0,
            slope_bias_texels: 1.0,
            normal_offset_texels: 1.0,
        }
    }
}

/// One layer of the shadow array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    pub view_proj: Mat4,
    /// World size of a texel per meter of view depth (perspective) or in meters (ortho).
    pub texel_footprint: f32,
    pub orthographic: bool,
    pub near: f32,
    pub far: f32,
    /// Index of the light in `scene.lights`.
    pub light: usize,
}

/// Which views belong to a light: `count` consecutive views starting at `first`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightShadows {
    pub first: u32,
    pub count: u32,
}

/// Perspective projection into Vulkan clip space (y down, depth 0..1), as the camera's.
fn perspective_vk(fov_y: f32, near: f32, far: f32) -> Mat4 {
    let mut p = Mat4::perspective_rh(fov_y, 1.0, near, far);
    p.y_axis.y = -p.y_axis.y;
    p
}

/// An up vector that is not parallel to `dir`.
fn up_for(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    }
}

/// Near and far planes of a perspective view from `origin` that contains the scene box.
fn depth_range(origin: Vec3, aabb: &Aabb) -> (f32, f32) {
    let mut far = 0.0f32;
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { aabb.min.x } else { aabb.max.x },
            if i & 2 == 0 { aabb.min.y } else { aabb.max.y },
            if i & 4 == 0 { aabb.min.z } else { aabb.max.z },
        );
        far = far.max((c - origin).length());
    }
    let far = (far * 1.01).max(1e-6);
    // Depth is compared linearly in meters, so a small near plane costs little precision.
    (far * 1e-4, far)
}

/// The shadow views of every light of `scene` at time `t_s`.
pub fn shadow_views(
    scene: &Scene,
    t_s: f32,
    settings: &ShadowSettings,
) -> (Vec<ShadowView>, Vec<LightShadows>) {
    let aabb = scene.aabb_at(t_s);
    let res = settings.resolution.max(1) as f32;
    let mut views = Vec::new();
    let mut per_light = Vec::new();
    for (li, light) in scene.lights.iter().enumerate() {
        let first = views.len() as u32;
        match *light {
            Light::Spot {
                position,
                direction,
                cutoff_deg,
                ..
            } => {
                let (near, far) = depth_range(position, &aabb);
                // The cone plus the PCF footprint.
                let half = (cutoff_deg.to_radians()
                    * (1.0 + 2.0 * (settings.pcf_radius as f32 + 1.0) / res))
                    .min(1.55);
                let proj = perspective_vk(2.0 * half, near, far);
                let view = Mat4::look_to_rh(position, direction, up_for(direction));
                views.push(ShadowView {
                    view_proj: proj * view,
                    texel_footprint: 2.0 * half.tan() / res,
                    orthographic: false,
                    near,
                    far,
                    light: li,
                });
            }
            Light::Point { position, .. } => {
                let (near, far) = depth_range(position, &aabb);
                // Slightly wider than 90 degrees so the PCF kernel never leaves a face.
                let half = (1.0 + 2.0 * (settings.pcf_radius as f32 + 1.0) / res).atan();
                let proj = perspective_vk(2.0 * half, near, far);
                for axis in [
                    Vec3::X,
                    Vec3::NEG_X,
                    Vec3::Y,
                    Vec3::NEG_Y,
                    Vec3::Z,
                    Vec3::NEG_Z,
                ] {
                    let view = Mat4::look_to_rh(position, axis, up_for(axis));
                    views.push(ShadowView {
                        view_proj: proj * view,
                        texel_footprint: 2.0 * half.tan() / res,
                        orthographic: false,
                        near,
                        far,
                        light: li,
                    });
                }
            }
            Light::Directional { direction, .. } => {
                let center = aabb.center();
                let radius = (aabb.extent().length() * 0.5).max(1e-6);
                let eye = center - direction * radius * 2.0;
                let view = Mat4::look_to_rh(eye, direction, up_for(direction));
                let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                for i in 0..8 {
                    let c = Vec3::new(
                        if i & 1 == 0 { aabb.min.x } else { aabb.max.x },
                        if i & 2 == 0 { aabb.min.y } else { aabb.max.y },
                        if i & 4 == 0 { aabb.min.z } else { aabb.max.z },
                    );
                    let v = view.transform_point3(c);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                // A texel of margin per PCF tap on each side.
                let size = (hi.x - lo.x).max(hi.y - lo.y).max(1e-6);
                let margin = size * (settings.pcf_radius as f32 + 1.0) / res;
                let (near, far) = ((-hi.z - margin).max(0.0), -lo.z + margin);
                let mut proj = Mat4::orthographic_rh(
                    lo.x - margin,
                    lo.x - margin + size + 2.0 * margin,
                    lo.y - margin,
                    lo.y - margin + size + 2.0 * margin,
                    near,
                    far,
                );
                proj.y_axis.y = -proj.y_axis.y;
                views.push(ShadowView {
                    view_proj: proj * view,
                    texel_footprint: (size + 2.0 * margin) / res,
                    orthographic: true,
                    near,
                    far,
                    light: li,
                });
            }
        }
        per_light.push(LightShadows {
            first,
            count: views.len() as u32 - first,
        });
    }
    (views, per_light)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;

    fn ndc(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        c.truncate() / c.w
    }

    #[test]
    fn only_the_views_a_scene_needs() {
        let spot = builtin("cornell").expect("cornell");
        let (v, l) = shadow_views(&spot, 0.0, &ShadowSettings::default());
        assert_eq!(
            v.len(),
            1,
            "one spot light, one perspective map, no cube faces"
        );
        assert_eq!(l, vec![LightShadows { first: 0, count: 1 }]);
        let point = builtin("cornell-point").expect("cornell-point");
        let (v, _) = shadow_views(&point, 0.0, &ShadowSettings::default());
        assert_eq!(v.len(), 6, "a point light has six cube faces");
    }

    #[test]
    fn every_scene_point_lands_inside_its_cube_face() {
        let scene = builtin("cornell-point").expect("cornell-point");
        let (views, _) = shadow_views(&scene, 0.0, &ShadowSettings::default());
        let light = scene.lights[0].position().expect("point light");
        let aabb = scene.aabb_at(0.0);
        for i in 0..1000 {
            let u = Vec3::new(
                (i % 10) as f32 / 9.0,
                ((i / 10) % 10) as f32 / 9.0,
                (i / 100) as f32 / 9.0,
            );
            let p = aabb.min + (aabb.max - aabb.min) * u;
            let d = p - light;
            if d.length() < 1e-3 {
                continue;
            }
            let a = d.abs();
            let face = if a.x >= a.y && a.x >= a.z {
                if d.x > 0.0 {
                    0
                } else {
                    1
                }
            } else if a.y >= a.z {
                if d.y > 0.0 {
                    2
                } else {
                    3
                }
            } else if d.z > 0.0 {
                4
            } else {
                5
            };
            let q = ndc(views[face].view_proj, p);
            assert!(
                q.x.abs() <= 1.0 && q.y.abs() <= 1.0 && (0.0..=1.0).contains(&q.z),
                "point {p} face {face} -> {q}"
            );
        }
    }

    #[test]
    fn directional_map_covers_the_scene_at_any_scale() {
        for scale in [1e-3f32, 1.0, 1e3] {
            let mut scene = builtin("cornell").expect("cornell");
            scene.lights = vec![Light::Directional {
                direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
                irradiance_w_m2: Vec3::ONE,
            }];
            for o in &mut scene.objects {
                o.transform.scale *= scale;
                o.transform.translate *= scale;
            }
            let (views, _) = shadow_views(&scene, 0.0, &ShadowSettings::default());
            let aabb = scene.aabb_at(0.0);
            for p in [aabb.min, aabb.max, aabb.center()] {
                let q = ndc(views[0].view_proj, p);
                assert!(
                    q.x.abs() <= 1.0 && q.y.abs() <= 1.0 && (0.0..=1.0).contains(&q.z),
                    "scale {scale}: {p} -> {q}"
                );
                assert!(q.is_finite());
            }
        }
    }
}
