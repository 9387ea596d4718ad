//! A recorded camera flight: keyframes (time, position, viewing direction, optional field of
//! view) joined by a C1 spline, evaluated at any time. `voxgi profile --camera-path` replays it
//! so that timings are taken along the same flight every time.
//!
//! # The spline
//! Position, viewing direction and field of view each follow a Catmull-Rom spline in *time*:
//! the cubic Hermite curve through the keys whose tangent at key i is
//! m_i = (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1}) (one-sided, (p_1 − p_0) / (t_1 − t_0), at
//! the ends). For equally spaced keys this is the *uniform* Catmull-Rom spline; for unequal
//! spacing it is its non-uniform-knot generalization (a cardinal spline of tension 0), which
//! keeps the velocity continuous in seconds, not just in the segment parameter. It passes
//! through every key exactly and is C1 at the keys. The direction is the spline of the unit
//! key directions, normalized (smooth wherever the spline is not near zero; if it ever is, the
//! segment's normalized linear blend is used). Outside the keys' time range the path clamps
//! to the first or last key.

use glam::Vec3;

use super::Camera;

/// One keyframe of a [`CameraPath`], validated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    pub time_s: f32,
    /// Meters, world space.
    pub position: Vec3,
    /// Unit viewing direction (a `look_at` point is turned into the direction to it).
    pub forward: Vec3,
    /// Vertical field of view in degrees; `None` keeps the scene camera's.
    pub fov_y_deg: Option<f32>,
}

/// A camera path's problem: the field (`camera_path.keyframes[2].time_s`) and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPathError {
    pub field: String,
    pub problem: String,
}

/// A validated camera path: at least two keys, times finite and strictly increasing,
/// positions finite, directions unit length and not parallel to `up`.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    keys: Vec<CameraKey>,
    /// The up hint of every camera on the path.
    up: Vec3,
}

/// How far (|forward · up|) a key's direction may lean toward `up` before the view is
/// ill-defined: 0.9999 = cos 0.81°, i.e. |forward × up| >= 0.014.
const MAX_UP_ALIGNMENT: f32 = 0.9999;

impl CameraPath {
    /// Checks the keys (see [`CameraPath`]); `up` must be a finite non-zero vector.
    pub fn new(keys: Vec<CameraKey>, up: Vec3) -> Result<CameraPath, CameraPathError> {
        let err = |field: String, problem: String| CameraPathError { field, problem };
        if !up.is_finite() || up.length_squared() == 0.0 {
            return Err(err(
                "camera_path.up".into(),
                format!("{up} is not a direction; expected a finite non-zero vector"),
            ));
        }
        let up = up.normalize();
        if keys.len() < 2 {
            return Err(err(
                "camera_path.keyframes".into(),
                format!(
                    "{} keyframe(s); a path needs at least 2 (a start and an end)",
                    keys.len()
                ),
            ));
        }
        for (i, k) in keys.iter().enumerate() {
            let field = |f: &str| format!("camera_path.keyframes[{i}].{f}");
            if !k.time_s.is_finite() {
                return Err(err(field("time_s"), format!("{} is not finite", k.time_s)));
            }
            if i > 0 && k.time_s <= keys[i - 1].time_s {
                return Err(err(
                    field("time_s"),
                    format!(
                        "{} s is not after the previous keyframe's {} s; times must be \
                         strictly increasing",
                        k.time_s,
                        keys[i - 1].time_s
                    ),
                ));
            }
            if !k.position.is_finite() {
                return Err(err(
                    field("position"),
                    format!("{} is not finite", k.position),
                ));
            }
            let f = k.forward;
            if !f.is_finite() || (f.length() - 1.0).abs() > 1e-3 {
                return Err(err(
                    field("direction"),
                    format!("{f} is not a finite unit direction"),
                ));
            }
            if f.dot(up).abs() > MAX_UP_ALIGNMENT {
                return Err(err(
                    field("direction"),
                    format!(
                        "the viewing direction {f} is parallel to up {up}; set \
                         `camera_path.up` to an axis it does not point along"
                    ),
                ));
            }
            if let Some(fov) = k.fov_y_deg {
                if !(fov > 0.0 && fov < 180.0) {
                    return Err(err(
                        field("fov_y_deg"),
                        format!(
                            "{fov} is not a vertical field of view; expected degrees in (0, 180)"
                        ),
                    ));
                }
            }
        }
        Ok(CameraPath { keys, up })
    }

    /// A path through `cameras` (the viewer's recorded keyframes), `spacing_s` apart from
    /// t = 0, each key with its camera's field of view; `up` is the first camera's.
    pub fn through_cameras(
        cameras: &[Camera],
        spacing_s: f32,
    ) -> Result<CameraPath, CameraPathError> {
        let keys = cameras
            .iter()
            .enumerate()
            .map(|(i, c)| CameraKey {
                time_s: i as f32 * spacing_s,
                position: c.position,
                forward: c.forward,
                fov_y_deg: Some(c.fov_y_deg),
            })
            .collect();
        CameraPath::new(keys, cameras.first().map_or(Vec3::Y, |c| c.up))
    }

    pub fn keys(&self) -> &[CameraKey] {
        &self.keys
    }

    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// The first and last keys' times, seconds.
    pub fn time_range_s(&self) -> (f32, f32) {
        (self.keys[0].time_s, self.keys[self.keys.len() - 1].time_s)
    }

    /// `n` times evenly spaced over the path, first and last key included (one frame: the start).
    pub fn even_times_s(&self, n: usize) -> Vec<f32> {
        let (t0, t1) = self.time_range_s();
        (0..n)
            .map(|i| match n {
                1 => t0,
                _ => t0 + (t1 - t0) * i as f32 / (n - 1) as f32,
            })
            .collect()
    }

    /// The position at `t_s` (clamped to the keys' range), meters.
    pub fn position_at(&self, t_s: f32) -> Vec3 {
        self.hermite(t_s, |k| k.position)
    }

    /// The unit viewing direction at `t_s`.
    pub fn forward_at(&self, t_s: f32) -> Vec3 {
        let f = self.hermite(t_s, |k| k.forward);
        if f.length() > 1e-3 {
            return f.normalize();
        }
        // The spline nearly vanished (keys pointing almost opposite ways): blend linearly.
        let (i, u) = self.segment(t_s);
        let (a, b) = (self.keys[i].forward, self.keys[i + 1].forward);
        a.lerp_monotonic(b, u).try_normalize().unwrap_or(a)
    }

    /// The vertical field of view at `t_s`; keys without one take `default_deg`.
    pub fn fov_at(&self, t_s: f32, default_deg: f32) -> f32 {
        let fov = self.hermite(t_s, |k| Vec3::splat(k.fov_y_deg.unwrap_or(default_deg)));
        fov.x.clamp(1.0, 179.0)
    }

    /// `base` (near, far, …) moved to the path's pose at `t_s`.
    pub fn camera_at(&self, base: &Camera, t_s: f32) -> Camera {
        let forward = self.forward_at(t_s);
        // Between keys the direction may pass along `up`; pick another hint for that moment.
        let up = if forward.dot(self.up).abs() > MAX_UP_ALIGNMENT {
            self.up.any_orthonormal_vector()
        } else {
            self.up
        };
        Camera {
            position: self.position_at(t_s),
            forward,
            up,
            fov_y_deg: self.fov_at(t_s, base.fov_y_deg),
            ..*base
        }
    }

    /// The path as a scene file's `[camera_path]` table (exact float round trip), for pasting
    /// a recorded flight into a scene.
    /// Positions in world coordinates (`origin_m`: the scene's local origin).
    pub fn toml_table(&self, origin_m: glam::DVec3) -> String {
        let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
        let mut s = format!("[camera_path]\nup = {}\nkeyframes = [\n", v(self.up));
        for k in &self.keys {
            let fov = k
                .fov_y_deg
                .map(|f| format!(", fov_y_deg = {f:?}"))
                .unwrap_or_default();
            s += &format!(
                "    {{ time_s = {:?}, position = {}, direction = {}{fov} }},\n",
                k.time_s,
                super::camera::world_toml(origin_m, k.position),
                v(k.forward)
            );
        }
        s + "]\n"
    }

    /// The segment holding `t_s` (clamped) and the fraction u ∈ [0, 1] through it.
    fn segment(&self, t_s: f32) -> (usize, f32) {
        let (t0, t1) = self.time_range_s();
        let t = t_s.clamp(t0, t1);
        let last = self.keys.len() - 2;
        let i = self.keys[1..=last]
            .iter()
            .position(|k| t < k.time_s)
            .unwrap_or(last);
        let (a, b) = (self.keys[i].time_s, self.keys[i + 1].time_s);
        (i, ((t - a) / (b - a)).clamp(0.0, 1.0))
    }

    /// The Catmull-Rom tangent (per second) of `value` at key `i`.
    fn tangent(&self, i: usize, value: impl Fn(&CameraKey) -> Vec3) -> Vec3 {
        let lo = i.saturating_sub(1);
        let hi = (i + 1).min(self.keys.len() - 1);
        let (a, b) = (&self.keys[lo], &self.keys[hi]);
        (value(b) - value(a)) / (b.time_s - a.time_s)
    }

    /// The cubic Hermite spline of `value` with Catmull-Rom tangents, at `t_s` (clamped).
    fn hermite(&self, t_s: f32, value: impl Fn(&CameraKey) -> Vec3 + Copy) -> Vec3 {
        let (i, u) = self.segment(t_s);
        let (a, b) = (&self.keys[i], &self.keys[i + 1]);
        let dt = b.time_s - a.time_s;
        let (m0, m1) = (self.tangent(i, value) * dt, self.tangent(i + 1, value) * dt);
        let (u2, u3) = (u * u, u * u * u);
        let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
        let h10 = u3 - 2.0 * u2 + u;
        let h01 = -2.0 * u3 + 3.0 * u2;
        let h11 = u3 - u2;
        value(a) * h00 + m0 * h10 + value(b) * h01 + m1 * h11
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time_s: f32, position: Vec3, forward: Vec3) -> CameraKey {
        CameraKey {
            time_s,
            position,
            forward: forward.normalize(),
            fov_y_deg: None,
        }
    }

    /// Four keys with unequal spacing (1 s, 2 s, 0.5 s), turning and climbing.
    fn path() -> CameraPath {
        CameraPath::new(
            vec![
                key(0.0, Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)),
                CameraKey {
                    fov_y_deg: Some(50.0),
                    ..key(1.0, Vec3::new(1.0, 0.5, 0.0), Vec3::new(1.0, 0.0, 1.0))
                },
                key(3.0, Vec3::new(2.0, 0.5, 2.0), Vec3::new(1.0, -0.3, 0.0)),
                key(3.5, Vec3::new(1.5, 1.0, 3.0), Vec3::new(0.0, 0.2, -1.0)),
            ],
            Vec3::Y,
        )
        .unwrap()
    }

    #[test]
    fn passes_through_every_key_exactly() {
        let p = path();
        for k in p.keys() {
            // At u = 0 or 1 the Hermite basis is (1, 0, 0, 0) or (0, 0, 1, 0): exact up to
            // float rounding of the basis sum.
            assert!(p.position_at(k.time_s).abs_diff_eq(k.position, 1e-6));
            assert!(p.forward_at(k.time_s).abs_diff_eq(k.forward, 1e-6));
        }
        // The keys without a field of view take the default; the one with takes its own.
        assert!((p.fov_at(0.0, 40.0) - 40.0).abs() < 1e-5);
        assert!((p.fov_at(1.0, 40.0) - 50.0).abs() < 1e-5);
    }

    /// Central differences of the position on either side of each inner key: the one-sided
    /// derivatives agree (C1), and both equal the Catmull-Rom tangent
    /// (p_{i+1} − p_{i−1}) / (t_{i+1} − t_{i−1}). With h = 1e-3 s the cubic's truncation error
    /// is O(h) · |p''| ≈ 1e-3 · (a few m/s²) and the rounding error ≈ 1e-7 m / 1e-3 s, so 2e-2
    /// m/s separates "continuous" from a kink (which the linear interpolation of these keys
    /// would show as a jump of ≥ 0.5 m/s).
    #[test]
    fn velocity_is_continuous_at_keys() {
        let p = path();
        let h = 1e-3;
        for i in 1..p.keys().len() - 1 {
            let t = p.keys()[i].time_s;
            let left = (p.position_at(t) - p.position_at(t - h)) / h;
            let right = (p.position_at(t + h) - p.position_at(t)) / h;
            let (a, b) = (p.keys()[i - 1], p.keys()[i + 1]);
            let m = (b.position - a.position) / (b.time_s - a.time_s);
            assert!(left.abs_diff_eq(right, 2e-2), "key {i}: {left} vs {right}");
            assert!(left.abs_diff_eq(m, 2e-2), "key {i}: {left} vs tangent {m}");
            let fl = (p.forward_at(t) - p.forward_at(t - h)) / h;
            let fr = (p.forward_at(t + h) - p.forward_at(t)) / h;
            assert!(fl.abs_diff_eq(fr, 2e-2), "key {i} direction: {fl} vs {fr}");
        }
    }

    #[test]
    fn clamps_outside_the_time_range() {
        let p = path();
        let (first, last) = (p.keys()[0], p.keys()[3]);
        assert_eq!(p.position_at(-5.0), first.position);
        assert_eq!(p.position_at(100.0), last.position);
        assert_eq!(p.forward_at(f32::NEG_INFINITY), first.forward);
        assert_eq!(p.time_range_s(), (0.0, 3.5));
        assert_eq!(p.even_times_s(3), vec![0.0, 1.75, 3.5]);
        assert_eq!(p.even_times_s(1), vec![0.0]);
    }

    #[test]
    fn two_keys_are_a_straight_line_at_constant_speed() {
        // With one-sided end tangents (p1 − p0)/(t1 − t0) at both ends, the Hermite cubic of
        // two keys is exactly the linear interpolation: the midpoint in time is the midpoint.
        let p = CameraPath::new(
            vec![
                key(2.0, Vec3::ZERO, Vec3::Z),
                key(4.0, Vec3::new(2.0, 0.0, 0.0), Vec3::Z),
            ],
            Vec3::Y,
        )
        .unwrap();
        assert!(p
            .position_at(3.0)
            .abs_diff_eq(Vec3::new(1.0, 0.0, 0.0), 1e-6));
        assert!(p
            .position_at(2.5)
            .abs_diff_eq(Vec3::new(0.5, 0.0, 0.0), 1e-6));
    }

    #[test]
    fn camera_at_keeps_the_base_lens() {
        let p = path();
        let base = Camera {
            position: Vec3::ZERO,
            forward: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 39.3,
            near: 0.05,
            far: 7.0,
            shift_x_tan: 0.0,
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
        };
        let c = p.camera_at(&base, 1.0);
        assert_eq!((c.near, c.far), (0.05, 7.0));
        assert_eq!(c.fov_y_deg, 50.0);
        assert!(c.position.abs_diff_eq(Vec3::new(1.0, 0.5, 0.0), 1e-6));
        assert!(c.view().is_finite());
    }

    #[test]
    fn through_cameras_spaces_the_recorded_keys() {
        let cam = |x: f32| Camera {
            position: Vec3::new(x, 1.0, 0.0),
            forward: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 40.0 + x,
            near: 0.01,
            far: 10.0,
            shift_x_tan: 0.0,
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
        };
        let p = CameraPath::through_cameras(&[cam(0.0), cam(1.0), cam(3.0)], 2.0).unwrap();
        let times: Vec<f32> = p.keys().iter().map(|k| k.time_s).collect();
        assert_eq!(times, vec![0.0, 2.0, 4.0]);
        assert_eq!(p.camera_at(&cam(9.0), 4.0), cam(3.0));
        // One recorded key is not a path.
        assert!(CameraPath::through_cameras(&[cam(0.0)], 2.0).is_err());
    }

    #[test]
    fn errors_name_the_field() {
        let k = |t| key(t, Vec3::ZERO, Vec3::Z);
        let field = |r: Result<CameraPath, CameraPathError>| r.unwrap_err().field;
        assert_eq!(
            field(CameraPath::new(vec![k(0.0)], Vec3::Y)),
            "camera_path.keyframes"
        );
        assert_eq!(
            field(CameraPath::new(vec![k(1.0), k(0.5)], Vec3::Y)),
            "camera_path.keyframes[1].time_s"
        );
        assert_eq!(
            field(CameraPath::new(vec![k(0.0), k(0.0)], Vec3::Y)),
            "camera_path.keyframes[1].time_s"
        );
        assert_eq!(
            field(CameraPath::new(vec![k(f32::NAN), k(1.0)], Vec3::Y)),
            "camera_path.keyframes[0].time_s"
        );
        let nan_pos = CameraKey {
            position: Vec3::new(0.0, f32::NAN, 0.0),
            ..k(1.0)
        };
        assert_eq!(
            field(CameraPath::new(vec![k(0.0), nan_pos], Vec3::Y)),
            "camera_path.keyframes[1].position"
        );
        let looking_up = key(1.0, Vec3::ZERO, Vec3::Y);
        assert_eq!(
            field(CameraPath::new(vec![k(0.0), looking_up], Vec3::Y)),
            "camera_path.keyframes[1].direction"
        );
        let wide = CameraKey {
            fov_y_deg: Some(180.0),
            ..k(1.0)
        };
        assert_eq!(
            field(CameraPath::new(vec![k(0.0), wide], Vec3::Y)),
            "camera_path.keyframes[1].fov_y_deg"
        );
        assert_eq!(
            field(CameraPath::new(vec![k(0.0), k(1.0)], Vec3::ZERO)),
            "camera_path.up"
        );
    }

    #[test]
    fn toml_table_lists_every_key() {
        let p = path();
        let text = p.toml_table(glam::DVec3::ZERO);
        assert!(text.starts_with("[camera_path]\n"), "{text}");
        assert!(text.contains("fov_y_deg = 50.0"), "{text}");
        assert_eq!(text.matches("time_s").count(), 4, "{text}");
    }
}
