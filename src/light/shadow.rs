//! Shadow views: the projections the shadow pass renders and the shading pass looks up.
//!
//! Every view is one layer of a single depth array. Only the views a scene needs exist: a
//! point light adds six cube faces (or two paraboloid hemispheres), a spot light one
//! perspective map, a directional light one orthographic map; no lights, no shadow views.
//!
//! Directional lights may add cascades for the camera's direct light ([`cascade_views`]):
//! orthographic maps fitted to slices of the view frustum, after every light's own views.

use crate::scene::aabb_visible;
use crate::scene::{look_to, perspective, Aabb, Light, Scene};
use crate::scene::{PointShadow, ShadowSettings};
use glam::camera::rh::proj::directx;
use glam::{Mat4, Vec3};

/// The projection of a shadow view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowProjection {
    Perspective,
    Orthographic,
    /// `view_proj` is the rigid world → hemisphere frame (light at the origin, +z the
    /// hemisphere's axis); the paraboloid map itself is applied per vertex in the shaders.
    Paraboloid,
}

impl ShadowProjection {
    /// `GpuShadowView::params.y` (glsl/include/frame.glsl).
    pub fn gpu_code(self) -> f32 {
        match self {
            Self::Perspective => 0.0,
            Self::Orthographic => 1.0,
            Self::Paraboloid => 2.0,
        }
    }
}

/// One layer of the shadow array.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowView {
    pub view_proj: Mat4,
    /// World size of a texel per meter of view depth (perspective), in meters (ortho), or in
    /// radians at the hemisphere's axis (paraboloid; times 1 + cos of the angle elsewhere).
    pub texel_footprint: f32,
    pub projection: ShadowProjection,
    /// The view's axis (the direction a cube face or paraboloid hemisphere looks).
    pub axis: Vec3,
    pub near: f32,
    pub far: f32,
    /// Index of the light in `scene.lights`.
    pub light: usize,
    /// A cascade's far split, meters of camera view depth (`GpuShadowView::axis.w`); 0 for
    /// other views.
    pub split_far_m: f32,
}

impl ShadowView {
    /// False only when no part of `aabb` can land in this view (conservative).
    pub fn may_see(&self, aabb: &Aabb) -> bool {
        match self.projection {
            // The hemisphere is the half-space in front of the light; the paraboloid covers
            // all of it, so only boxes entirely behind are culled.
            ShadowProjection::Paraboloid => {
                !aabb.is_empty()
                    && (0..8).any(|i| {
                        let c = Vec3::new(
                            if i & 1 == 0 { aabb.min.x } else { aabb.max.x },
                            if i & 2 == 0 { aabb.min.y } else { aabb.max.y },
                            if i & 4 == 0 { aabb.min.z } else { aabb.max.z },
                        );
                        self.view_proj.transform_point3(c).z >= 0.0
                    })
            }
            _ => aabb_visible(&self.view_proj, aabb),
        }
    }
}

/// Which views belong to a light: `count` consecutive views starting at `first`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightShadows {
    pub first: u32,
    pub count: u32,
}

/// Perspective projection into Vulkan clip space (y down, depth 0..1), as the camera's.
fn perspective_vk(fov_y: f32, near: f32, far: f32) -> Mat4 {
    let mut p = perspective(fov_y, 1.0, near, far);
    p.y_axis.y = -p.y_axis.y;
    p
}

/// An up vector that is not parallel to `dir`.
/// `proj` with its output y negated (Vulkan's framebuffer y points down): the y row of the
/// matrix, scale and translation.
pub(super) fn flip_y(mut proj: Mat4) -> Mat4 {
    proj.x_axis.y = -proj.x_axis.y;
    proj.y_axis.y = -proj.y_axis.y;
    proj.z_axis.y = -proj.z_axis.y;
    proj.w_axis.y = -proj.w_axis.y;
    proj
}

pub(super) fn up_for(dir: Vec3) -> Vec3 {
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

/// The two paraboloid hemispheres (+y and −y) of a light at `position`, light index `li`,
/// appended to `views`.
fn paraboloid_pair(position: Vec3, aabb: &Aabb, res: f32, li: usize, views: &mut Vec<ShadowView>) {
    let (near, far) = depth_range(position, aabb);
    // Hemisphere frames share x and y, so a PCF tap past one rim (|uv| > 1) is the other
    // map's uv / |uv|^2 (glsl/include/shadow.glsl).
    for axis in [Vec3::Y, Vec3::NEG_Y] {
        let rot = Mat4::from_cols(
            Vec3::X.extend(0.0),
            Vec3::Z.extend(0.0),
            axis.extend(0.0),
            glam::Vec4::W,
        )
        .transpose();
        views.push(ShadowView {
            view_proj: rot * Mat4::from_translation(-position),
            // uv = d.xy / (1 + d.z) is conformal (stereographic) with |duv/dangle| =
            // 1 / (1 + d.z); a texel spans 2 / res in uv.
            texel_footprint: 2.0 / res,
            projection: ShadowProjection::Paraboloid,
            axis,
            near,
            far,
            light: li,
            split_far_m: 0.0,
        });
    }
}

/// The shadow views of every light of `scene` at time `t_s`, area lights sampled into
/// elements (`super::area::frame_lights`): `per_light` indexes that sampled list.
pub fn shadow_views(
    scene: &Scene,
    t_s: f32,
    settings: &ShadowSettings,
) -> (Vec<ShadowView>, Vec<LightShadows>) {
    let aabb = scene.aabb_at(t_s);
    let res = settings.resolution.max(1) as f32;
    // Texels of margin for the PCF kernel on each side of a view.
    let pcf_texels = settings.pcf_radius as f32 + 1.0;
    let mut views = Vec::new();
    let mut per_light = Vec::new();
    let lights = super::area::frame_lights(&scene.lights, settings);
    for (li, light) in lights.iter().enumerate() {
        let first = views.len() as u32;
        match *light {
            Light::Element {
                position, normal, ..
            } => views.push(element_view(position, normal, &aabb, res, li)),
            Light::Rectangle { .. } => {
                unreachable!("frame_lights replaced rectangles by elements")
            }
            // Whole spheres (PCSS, `super::area::frame_lights`): two hemispheres from the
            // centre, as a point light's paraboloid maps.
            Light::Sphere { position, .. } => paraboloid_pair(position, &aabb, res, li, &mut views),
            Light::Spot {
                position,
                direction,
                cutoff_deg,
                ..
            } => views.push(spot_view(
                position, direction, cutoff_deg, &aabb, res, pcf_texels, li,
            )),
            Light::Point { position, .. }
                if settings.point_technique == PointShadow::DualParaboloid =>
            {
                paraboloid_pair(position, &aabb, res, li, &mut views)
            }
            Light::Point { position, .. } => {
                cube_views(position, &aabb, res, pcf_texels, li, &mut views)
            }
            Light::Directional { direction, .. } => {
                views.push(directional_view(direction, &aabb, res, pcf_texels, li))
            }
        }
        per_light.push(LightShadows {
            first,
            count: views.len() as u32 - first,
        });
    }
    (views, per_light)
}

/// One paraboloid hemisphere around the normal of an area light's element at `position`,
/// light index `li`: the element emits nothing behind itself (glsl/include/shadow.glsl treats
/// taps past its rim as lit).
fn element_view(position: Vec3, normal: Vec3, aabb: &Aabb, res: f32, li: usize) -> ShadowView {
    let (near, far) = depth_range(position, aabb);
    let t = up_for(normal).cross(normal).normalize();
    let b = normal.cross(t);
    let rot = Mat4::from_cols(
        t.extend(0.0),
        b.extend(0.0),
        normal.extend(0.0),
        glam::Vec4::W,
    )
    .transpose();
    ShadowView {
        view_proj: rot * Mat4::from_translation(-position),
        texel_footprint: 2.0 / res,
        projection: ShadowProjection::Paraboloid,
        axis: normal,
        near,
        far,
        light: li,
        split_far_m: 0.0,
    }
}

/// The perspective view of a spot light at `position` (light index `li`) along `direction`,
/// covering its cone of half-angle `cutoff_deg` plus `pcf_texels` texels of PCF footprint at
/// resolution `res`.
fn spot_view(
    position: Vec3,
    direction: Vec3,
    cutoff_deg: f32,
    aabb: &Aabb,
    res: f32,
    pcf_texels: f32,
    li: usize,
) -> ShadowView {
    let (near, far) = depth_range(position, aabb);
    let half = (cutoff_deg.to_radians() * (1.0 + 2.0 * pcf_texels / res)).min(1.55);
    let proj = perspective_vk(2.0 * half, near, far);
    let view = look_to(position, direction, up_for(direction));
    ShadowView {
        view_proj: proj * view,
        texel_footprint: 2.0 * half.tan() / res,
        projection: ShadowProjection::Perspective,
        axis: direction,
        near,
        far,
        light: li,
        split_far_m: 0.0,
    }
}

/// The six cube-face views of a point light at `position`, light index `li`, appended to
/// `views`: each slightly wider than 90 degrees so the PCF kernel (`pcf_texels` texels of
/// margin) never leaves a face.
fn cube_views(
    position: Vec3,
    aabb: &Aabb,
    res: f32,
    pcf_texels: f32,
    li: usize,
    views: &mut Vec<ShadowView>,
) {
    let (near, far) = depth_range(position, aabb);
    let half = (1.0 + 2.0 * pcf_texels / res).atan();
    let proj = perspective_vk(2.0 * half, near, far);
    for axis in [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ] {
        let view = look_to(position, axis, up_for(axis));
        views.push(ShadowView {
            view_proj: proj * view,
            texel_footprint: 2.0 * half.tan() / res,
            projection: ShadowProjection::Perspective,
            axis,
            near,
            far,
            light: li,
            split_far_m: 0.0,
        });
    }
}

/// The orthographic view of a directional light along `direction`, light index `li`, fitted
/// to the scene box plus a texel of margin per PCF tap (`pcf_texels`) on each side.
fn directional_view(
    direction: Vec3,
    aabb: &Aabb,
    res: f32,
    pcf_texels: f32,
    li: usize,
) -> ShadowView {
    let center = aabb.center();
    let radius = (aabb.extent().length() * 0.5).max(1e-6);
    let eye = center - direction * radius * 2.0;
    let view = look_to(eye, direction, up_for(direction));
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
    let size = (hi.x - lo.x).max(hi.y - lo.y).max(1e-6);
    let margin = size * pcf_texels / res;
    let (near, far) = ((-hi.z - margin).max(0.0), -lo.z + margin);
    let proj = directx::orthographic(
        lo.x - margin,
        lo.x - margin + size + 2.0 * margin,
        lo.y - margin,
        lo.y - margin + size + 2.0 * margin,
        near,
        far,
    );
    // Vulkan's y points down: negate the whole y row (scale and offset), so the window stays
    // where it was fitted (negating the scale alone mirrors an off-centre window about y = 0).
    let proj = flip_y(proj);
    ShadowView {
        view_proj: proj * view,
        texel_footprint: (size + 2.0 * margin) / res,
        projection: ShadowProjection::Orthographic,
        axis: direction,
        near,
        far,
        light: li,
        split_far_m: 0.0,
    }
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

    fn paraboloid_uv(view: &ShadowView, p: Vec3) -> glam::Vec2 {
        let d = view.view_proj.transform_point3(p);
        glam::Vec2::new(d.x, d.y) / (d.length() + d.z)
    }

    #[test]
    fn paraboloid_hemispheres_cover_the_scene_and_meet_at_the_rim() {
        let scene = builtin("cornell-point").expect("cornell-point");
        let settings = ShadowSettings {
            point_technique: PointShadow::DualParaboloid,
            ..Default::default()
        };
        let (views, per_light) = shadow_views(&scene, 0.0, &settings);
        assert_eq!(
            views.len(),
            2,
            "a paraboloid point light has two hemispheres"
        );
        assert_eq!(per_light, vec![LightShadows { first: 0, count: 2 }]);
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
            // Picked by the sign along the axis, as shadow.glsl does.
            let (v, other) = if d.dot(views[0].axis) >= 0.0 {
                (&views[0], &views[1])
            } else {
                (&views[1], &views[0])
            };
            let uv = paraboloid_uv(v, p);
            assert!(uv.length() <= 1.0 + 1e-5, "point {p} -> {uv}");
            assert!(d.length() <= v.far && v.may_see(&Aabb { min: p, max: p }));
            // Past the rim, the other hemisphere holds the same direction at uv / |uv|^2.
            if uv.length() > 0.5 {
                let back = paraboloid_uv(other, p);
                let inv = back / back.length_squared();
                assert!((inv - uv).length() < 1e-3 * uv.length(), "{uv} vs {inv}");
            }
        }
        let below = Aabb {
            min: light - Vec3::new(1.0, 2.0, 1.0),
            max: light - Vec3::new(-1.0, 1.0, -1.0),
        };
        assert!(!views[0].may_see(&below) && views[1].may_see(&below));
    }

    #[test]
    fn directional_map_covers_the_scene_at_any_scale() {
        // Off the world origin too: the map's window is then off the light space's origin.
        for (scale, offset) in [
            (1e-3f32, Vec3::ZERO),
            (1.0, Vec3::ZERO),
            (1e3, Vec3::ZERO),
            (1.0, Vec3::new(5.0, 3.0, -4.0)),
        ] {
            let mut scene = builtin("cornell").expect("cornell");
            scene.lights = vec![Light::Directional {
                direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
                irradiance_w_m2: Vec3::ONE,
            }];
            for o in &mut scene.objects {
                o.transform.scale *= scale;
                o.transform.translate = o.transform.translate * scale + offset;
            }
            let (views, _) = shadow_views(&scene, 0.0, &ShadowSettings::default());
            let aabb = scene.aabb_at(0.0);
            let corners = (0..8).map(|i| {
                Vec3::select(
                    glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                    aabb.max,
                    aabb.min,
                )
            });
            for p in corners.chain([aabb.center()]) {
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
