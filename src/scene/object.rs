//! Scene objects: a mesh instance with a transform, optionally animated.

use glam::{Mat4, Quat, Vec3, Vec4};

use super::mesh::Aabb;

/// Translation, rotation and scale; the model matrix is T·R·S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translate: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform {
            translate: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

impl Transform {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translate)
    }

    /// Linear interpolation of translation and scale, spherical of rotation (along the shorter
    /// arc, so keyframes more than 180° apart need a key in between).
    pub fn interpolate(&self, other: &Transform, u: f32) -> Transform {
        Transform {
            translate: self.translate.lerp_monotonic(other.translate, u),
            rotation: slerp(self.rotation, other.rotation, u).normalize(),
            scale: self.scale.lerp_monotonic(other.scale, u),
        }
    }
}

/// Spherical interpolation from `a` to `b` along the shorter arc. Keys closer than 3.6°
/// (|a·b| > 0.9995) are interpolated linearly and normalized: glam 0.25's `slerp` threshold
/// (glam 0.34's is 1 − ε), so that animations keep, bit for bit, the rotations their
/// renders were measured with.
fn slerp(a: Quat, b: Quat, u: f32) -> Quat {
    let d = a.dot(b);
    if d.abs() <= 0.9995 {
        return a.slerp(b, u);
    }
    let b = if d < 0.0 { -b } else { b };
    Quat::from_vec4(Vec4::from(a).lerp_monotonic(Vec4::from(b), u)).normalize()
}

/// Rotation from `rotate_deg = [x, y, z]`: about world X first, then Y, then Z
/// (R = Rz·Ry·Rx, Blender's "XYZ Euler").
pub fn rotation_from_euler_xyz_deg(deg: Vec3) -> Quat {
    let r = deg * (std::f32::consts::PI / 180.0);
    (Quat::from_rotation_z(r.z) * Quat::from_rotation_y(r.y) * Quat::from_rotation_x(r.x))
        .normalize()
}

/// The `rotate_deg = [x, y, z]` of a rotation: the inverse of [`rotation_from_euler_xyz_deg`]
/// (for R = Rz·Ry·Rx, glam's `EulerRot::ZYX` yields the angles z, y, x). Within ±90° of y
/// the angles are unique; at y = ±90° (gimbal lock) one of the equivalent triples.
pub fn euler_xyz_deg(q: Quat) -> Vec3 {
    let (z, y, x) = q.normalize().to_euler(glam::EulerRot::ZYX);
    Vec3::new(x, y, z) * (180.0 / std::f32::consts::PI)
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    pub time_s: f32,
    pub transform: Transform,
}

/// How an object moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Animation {
    /// A keyframed path; times strictly increasing (validated).
    Keyframes {
        keyframes: Vec<Keyframe>,
        looping: bool,
    },
    /// One mesh per frame, all with the same topology (validated): the vertex count, indices
    /// and submeshes of every frame equal those of the first.
    ObjSequence {
        /// Indices into [`super::Scene::meshes`], one per frame.
        meshes: Vec<usize>,
        /// Object-space bounds of each frame's mesh.
        frame_aabbs: Vec<Aabb>,
        fps: f32,
        looping: bool,
    },
}

/// An instance of a mesh in the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    pub name: String,
    /// Index into [`super::Scene::meshes`]; the first frame for OBJ sequences.
    pub mesh: usize,
    /// Material of each submesh of the mesh (indices into [`super::Scene::materials`]), after
    /// the object's `material` override. All frames of a sequence share the submesh layout.
    pub materials: Vec<usize>,
    /// The transform when not animated by keyframes.
    pub transform: Transform,
    /// Moves (or may be moved by the user) after load, so it must be re-voxelized per frame.
    pub dynamic: bool,
    pub animation: Option<Animation>,
    /// Object-space bounds of `mesh`.
    pub local_aabb: Aabb,
}

impl Object {
    /// Model matrix at time `t_s` (seconds). A non-finite time is treated as 0.
    pub fn transform_at(&self, t_s: f32) -> Mat4 {
        self.transform_components_at(t_s).matrix()
    }

    /// Translation, rotation and scale at time `t_s`.
    pub fn transform_components_at(&self, t_s: f32) -> Transform {
        match &self.animation {
            Some(Animation::Keyframes { keyframes, looping }) => {
                sample_keyframes(keyframes, *looping, t_s).unwrap_or(self.transform)
            }
            _ => self.transform,
        }
    }

    /// Index into [`super::Scene::meshes`] of the mesh to draw at `t_s`.
    pub fn mesh_at(&self, t_s: f32) -> usize {
        match &self.animation {
            Some(Animation::ObjSequence {
                meshes,
                fps,
                looping,
                ..
            }) => sequence_frame(meshes.len(), *fps, *looping, t_s)
                .and_then(|i| meshes.get(i).copied())
                .unwrap_or(self.mesh),
            _ => self.mesh,
        }
    }

    /// World-space bounds at `t_s` (the 8 corners of the mesh's box, transformed).
    pub fn aabb_at(&self, t_s: f32) -> Aabb {
        let local = match &self.animation {
            Some(Animation::ObjSequence {
                frame_aabbs,
                fps,
                looping,
                ..
            }) => sequence_frame(frame_aabbs.len(), *fps, *looping, t_s)
                .and_then(|i| frame_aabbs.get(i).copied())
                .unwrap_or(self.local_aabb),
            _ => self.local_aabb,
        };
        local.transformed(&self.transform_at(t_s))
    }

    pub fn is_animated(&self) -> bool {
        self.animation.is_some()
    }
}

/// The transform at `t_s`; before the first key it holds the first, after the last it holds
/// the last, unless `looping`, when time wraps over [first key, last key].
fn sample_keyframes(keys: &[Keyframe], looping: bool, t_s: f32) -> Option<Transform> {
    let first = keys.first()?;
    let last = keys.last()?;
    let (t0, t1) = (first.time_s, last.time_s);
    let t = if !t_s.is_finite() {
        t0
    } else if looping && t1 > t0 {
        t0 + (t_s - t0).rem_euclid(t1 - t0)
    } else {
        t_s.clamp(t0, t1.max(t0))
    };
    // First key strictly after t; the segment is [i-1, i].
    let i = keys.partition_point(|k| k.time_s <= t);
    if i == 0 {
        return Some(first.transform);
    }
    if i >= keys.len() {
        return Some(last.transform);
    }
    let (a, b) = (&keys[i - 1], &keys[i]);
    let span = b.time_s - a.time_s;
    let u = if span > 0.0 {
        ((t - a.time_s) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    Some(a.transform.interpolate(&b.transform, u))
}

/// Frame index at `t_s` for `count` frames at `fps`.
fn sequence_frame(count: usize, fps: f32, looping: bool, t_s: f32) -> Option<usize> {
    if count == 0 {
        return None;
    }
    let t = if t_s.is_finite() { t_s } else { 0.0 };
    // f64 and a saturating cast keep huge times from overflowing.
    let f = (f64::from(t) * f64::from(fps)).floor();
    let n = count as f64;
    let f = if looping {
        f.rem_euclid(n)
    } else {
        f.clamp(0.0, n - 1.0)
    };
    Some((f as usize).min(count - 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(t: f32, x: f32, yaw_deg: f32, s: f32) -> Keyframe {
        Keyframe {
            time_s: t,
            transform: Transform {
                translate: Vec3::new(x, 0.0, 0.0),
                rotation: rotation_from_euler_xyz_deg(Vec3::new(0.0, yaw_deg, 0.0)),
                scale: Vec3::splat(s),
            },
        }
    }

    fn animated(looping: bool) -> Object {
        Object {
            name: "a".into(),
            mesh: 0,
            materials: vec![0],
            transform: Transform::default(),
            dynamic: true,
            animation: Some(Animation::Keyframes {
                keyframes: vec![key(0.0, 0.0, 0.0, 1.0), key(2.0, 4.0, 90.0, 3.0)],
                looping,
            }),
            local_aabb: Aabb {
                min: Vec3::splat(-0.5),
                max: Vec3::splat(0.5),
            },
        }
    }

    #[test]
    fn keyframes_interpolate() {
        let o = animated(false);
        let mid = o.transform_components_at(1.0);
        assert!((mid.translate - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
        assert!((mid.scale - Vec3::splat(2.0)).length() < 1e-6);
        let expected = rotation_from_euler_xyz_deg(Vec3::new(0.0, 45.0, 0.0));
        assert!(mid.rotation.angle_between(expected) < 1e-4);
        // Clamped outside the key range.
        assert_eq!(o.transform_components_at(-5.0).translate, Vec3::ZERO);
        assert_eq!(
            o.transform_components_at(10.0).translate,
            Vec3::new(4.0, 0.0, 0.0)
        );
        assert_eq!(o.transform_components_at(f32::NAN).translate, Vec3::ZERO);
    }

    #[test]
    fn keyframes_loop() {
        let o = animated(true);
        let a = o.transform_components_at(0.5).translate;
        let b = o.transform_components_at(2.5).translate;
        let c = o.transform_components_at(-1.5).translate;
        assert!((a - b).length() < 1e-5 && (a - c).length() < 1e-5);
    }

    #[test]
    fn aabb_follows_animation() {
        let o = animated(false);
        let b = o.aabb_at(2.0);
        // Scale 3, 90° about Y (a cube stays a cube), translated by 4 in x.
        assert!(
            (b.min - Vec3::new(2.5, -1.5, -1.5)).length() < 1e-4,
            "{b:?}"
        );
        assert!((b.max - Vec3::new(5.5, 1.5, 1.5)).length() < 1e-4, "{b:?}");
    }

    #[test]
    fn euler_angles_invert_the_rotation() {
        for deg in [
            Vec3::new(30.0, 45.0, 10.0),
            Vec3::new(-120.0, -60.0, 170.0),
            Vec3::new(0.0, 0.0, 90.0),
        ] {
            let back = euler_xyz_deg(rotation_from_euler_xyz_deg(deg));
            assert!((back - deg).abs().max_element() < 1e-3, "{deg} -> {back}");
        }
    }

    #[test]
    fn euler_order_is_x_then_y_then_z() {
        let q = rotation_from_euler_xyz_deg(Vec3::new(90.0, 90.0, 0.0));
        // X first: +Y → +Z; then Y: +Z → +X.
        assert!((q * Vec3::Y - Vec3::X).length() < 1e-5);
    }

    #[test]
    fn sequence_frames() {
        assert_eq!(sequence_frame(24, 24.0, true, 0.0), Some(0));
        assert_eq!(sequence_frame(24, 24.0, true, 0.5), Some(12));
        assert_eq!(sequence_frame(24, 24.0, true, 1.0), Some(0));
        assert_eq!(sequence_frame(24, 24.0, true, -0.01), Some(23));
        assert_eq!(sequence_frame(24, 24.0, false, 5.0), Some(23));
        assert_eq!(sequence_frame(24, 24.0, false, -5.0), Some(0));
        // Huge times neither overflow nor leave the range.
        assert!(sequence_frame(24, 24.0, true, f32::MAX).is_some_and(|f| f < 24));
        assert_eq!(sequence_frame(24, 24.0, false, f32::MAX), Some(23));
        assert_eq!(sequence_frame(0, 24.0, true, 1.0), None);
    }
}
