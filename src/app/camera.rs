//! Fly camera: WASD moves, Q/E go down/up, the mouse looks around while the right button is
//! held, the wheel changes the speed. Plain math, tested without a window.

use crate::scene::Camera;
use glam::Vec3;

/// Largest pitch magnitude: looking straight up or down would make `forward` parallel to the
/// up hint, which the camera forbids.
const MAX_PITCH_RAD: f32 = 1.55;

/// Which movement keys are held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MoveKeys {
    pub forward: bool,
    pub back: bool,
    pub left: bool,
    pub right: bool,
    pub up: bool,
    pub down: bool,
    /// Move four times faster.
    pub fast: bool,
}

/// Position plus yaw/pitch; turns into a scene [`Camera`] keeping its lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    pub position: Vec3,
    /// Radians about +Y; 0 looks along +Z.
    pub yaw_rad: f32,
    /// Radians above the horizon.
    pub pitch_rad: f32,
    pub speed_m_s: f32,
    /// Radians per pixel of mouse motion.
    pub look_rad_per_px: f32,
}

impl FlyCamera {
    /// Starts where `camera` is, looking where it looks; the speed crosses `scene_size_m` in
    /// about four seconds.
    pub fn from_camera(camera: &Camera, scene_size_m: f32) -> Self {
        let f = camera.forward.normalize_or_zero();
        let size = if scene_size_m.is_finite() && scene_size_m > 0.0 {
            scene_size_m
        } else {
            1.0
        };
        Self {
            position: camera.position,
            yaw_rad: f.x.atan2(f.z),
            pitch_rad: f
                .y
                .clamp(-1.0, 1.0)
                .asin()
                .clamp(-MAX_PITCH_RAD, MAX_PITCH_RAD),
            speed_m_s: size / 4.0,
            look_rad_per_px: 0.004,
        }
    }

    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw_rad.sin_cos();
        let (sp, cp) = self.pitch_rad.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Screen-right in world space (right-handed, y up: forward × up).
    pub fn right(&self) -> Vec3 {
        self.forward().cross(Vec3::Y).normalize_or_zero()
    }

    /// Turns by a mouse motion of (`dx`, `dy`) pixels (x right, y down).
    pub fn look(&mut self, dx: f32, dy: f32) {
        if !(dx.is_finite() && dy.is_finite()) {
            return;
        }
        self.yaw_rad = (self.yaw_rad - dx * self.look_rad_per_px) % std::f32::consts::TAU;
        self.pitch_rad =
            (self.pitch_rad - dy * self.look_rad_per_px).clamp(-MAX_PITCH_RAD, MAX_PITCH_RAD);
    }

    /// Moves for `dt_s` seconds with `keys` held.
    pub fn advance(&mut self, keys: MoveKeys, dt_s: f32) {
        let axis = |pos: bool, neg: bool| f32::from(u8::from(pos)) - f32::from(u8::from(neg));
        let dir = self.forward() * axis(keys.forward, keys.back)
            + self.right() * axis(keys.right, keys.left)
            + Vec3::Y * axis(keys.up, keys.down);
        let speed = self.speed_m_s * if keys.fast { 4.0 } else { 1.0 };
        let dt = if dt_s.is_finite() {
            dt_s.clamp(0.0, 0.25)
        } else {
            0.0
        };
        self.position += dir.normalize_or_zero() * speed * dt;
    }

    /// Scales the speed by 1.2 per wheel notch (positive = faster).
    pub fn scroll_speed(&mut self, notches: f32) {
        if notches.is_finite() {
            self.speed_m_s = (self.speed_m_s * 1.2f32.powf(notches)).clamp(1e-3, 1e4);
        }
    }

    /// `lens` with this camera's position and orientation.
    pub fn apply(&self, lens: &Camera) -> Camera {
        Camera {
            position: self.position,
            forward: self.forward(),
            up: Vec3::Y,
            ..*lens
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(forward: Vec3) -> Camera {
        Camera {
            position: Vec3::new(1.0, 2.0, 3.0),
            forward,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            near: 0.01,
            far: 100.0,
            shift_x_tan: 0.0,
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
        }
    }

    #[test]
    fn starts_where_the_scene_camera_looks() {
        for f in [Vec3::Z, Vec3::X, Vec3::new(-1.0, -0.5, 0.3).normalize()] {
            let fly = FlyCamera::from_camera(&cam(f), 2.0);
            assert!((fly.forward() - f).length() < 1e-5, "{f} {}", fly.forward());
            let c = fly.apply(&cam(f));
            assert_eq!(c.position, Vec3::new(1.0, 2.0, 3.0));
            assert_eq!(c.fov_y_deg, 40.0);
        }
    }

    #[test]
    fn keys_move_along_view_axes() {
        let mut fly = FlyCamera::from_camera(&cam(Vec3::Z), 4.0);
        let start = fly.position;
        let keys = MoveKeys {
            forward: true,
            ..Default::default()
        };
        fly.advance(keys, 0.2);
        assert!((fly.position - start - Vec3::Z * 0.2).length() < 1e-5);
        // Looking +Z with y up, screen-right is -X (see scene::camera's conventions).
        let mut fly = FlyCamera::from_camera(&cam(Vec3::Z), 4.0);
        fly.advance(
            MoveKeys {
                right: true,
                up: true,
                ..Default::default()
            },
            0.1,
        );
        let d = fly.position - start;
        assert!(d.x < 0.0 && d.y > 0.0 && d.z.abs() < 1e-6, "{d}");
    }

    #[test]
    fn mouse_right_turns_right_and_pitch_is_clamped() {
        let mut fly = FlyCamera::from_camera(&cam(Vec3::Z), 1.0);
        let right = fly.right();
        fly.look(50.0, 0.0);
        assert!(fly.forward().dot(right) > 0.1);
        fly.look(0.0, -1e6);
        assert!(fly.pitch_rad <= MAX_PITCH_RAD);
        assert!(fly.forward().cross(Vec3::Y).length() > 1e-3);
        fly.look(f32::NAN, 1.0);
        assert!(fly.forward().is_finite());
    }

    #[test]
    fn huge_or_bad_time_steps_are_bounded() {
        let mut fly = FlyCamera::from_camera(&cam(Vec3::Z), 4.0);
        let start = fly.position;
        let keys = MoveKeys {
            forward: true,
            ..Default::default()
        };
        fly.advance(keys, f32::INFINITY);
        fly.advance(keys, 100.0);
        assert!((fly.position - start).length() <= 0.25 + 1e-5);
        fly.scroll_speed(1e9);
        assert!(fly.speed_m_s <= 1e4);
    }
}
