//! The scene camera: a pinhole with a vertical field of view.

use glam::{Mat4, Vec3};

/// A validated pinhole camera. `forward` and `up` are unit length and not parallel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Meters, world space.
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit up hint (not necessarily orthogonal to `forward`).
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180). Mitsuba's `perspective` sensor takes
    /// `fov` along `fov_axis` (default "x"); use [`Camera::fov_x_deg`] when exporting.
    pub fov_y_deg: f32,
    /// Near and far plane distances in meters, 0 < near < far.
    pub near: f32,
    pub far: f32,
}

impl Camera {
    /// World → view (right-handed; the camera looks down -Z in view space, +X right, +Y up).
    pub fn view(&self) -> Mat4 {
        Mat4::look_to_rh(self.position, self.forward, self.up)
    }

    /// View → Vulkan clip space: y points down in framebuffer space, depth 0 at `near` and 1 at
    /// `far` (no reversed Z). `aspect` is width / height; a non-positive or non-finite aspect
    /// (a minimized window) is treated as 1 so the matrix never holds NaN.
    pub fn proj(&self, aspect: f32) -> Mat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let mut p = Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, self.near, self.far);
        // glam's perspective_rh already maps depth to [0, 1]; Vulkan's y axis points down.
        p.y_axis.y = -p.y_axis.y;
        p
    }

    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.proj(aspect) * self.view()
    }

    /// The world points where the ray through the center of pixel (x, y) of a
    /// `width`×`height` image meets the near (NDC z = 0) and far (z = 1) planes.
    pub fn pixel_ray_points(&self, x: u32, y: u32, width: u32, height: u32) -> (Vec3, Vec3) {
        let inv = self.view_proj(width as f32 / height as f32).inverse();
        let ndc = |z: f32| {
            let p = inv
                * glam::Vec4::new(
                    (x as f32 + 0.5) / width as f32 * 2.0 - 1.0,
                    (y as f32 + 0.5) / height as f32 * 2.0 - 1.0,
                    z,
                    1.0,
                );
            p.truncate() / p.w
        };
        (ndc(0.0), ndc(1.0))
    }

    /// Horizontal field of view in degrees for a given aspect (width / height), as Mitsuba's
    /// `fov` with `fov_axis = "x"` expects it.
    pub fn fov_x_deg(&self, aspect: f32) -> f32 {
        let half = (self.fov_y_deg.to_radians() * 0.5).tan() * aspect;
        2.0 * half.atan().to_degrees()
    }

    /// The camera as a scene file's `[camera]` table, exact (floats print in their shortest
    /// round-trip form), so a pose found in the viewer can be pasted into a scene.
    pub fn toml_table(&self) -> String {
        let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
        format!(
            "[camera]\nposition = {}\nforward = {}\nup = {}\nfov_y_deg = {:?}\nnear = {:?}\nfar = {:?}\n",
            v(self.position),
            v(self.forward),
            v(self.up),
            self.fov_y_deg,
            self.near,
            self.far
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell_cam() -> Camera {
        Camera {
            position: Vec3::new(0.278, 0.273, -0.8),
            forward: Vec3::Z,
            up: Vec3::Y,
            fov_y_deg: 39.3,
            near: 0.01,
            far: 100.0,
        }
    }

    #[test]
    fn vulkan_clip_conventions() {
        let c = cornell_cam();
        let vp = c.view_proj(1.0);
        let ndc = |p: Vec3| vp.project_point3(p);
        // Depth 0 at near, 1 at far.
        let near = ndc(c.position + c.forward * c.near);
        let far = ndc(c.position + c.forward * c.far);
        assert!(
            near.z.abs() < 1e-5 && (far.z - 1.0).abs() < 1e-4,
            "{near} {far}"
        );
        // A point above the axis lands in the upper half: negative y in Vulkan.
        let above = ndc(c.position + Vec3::new(0.0, 0.1, 1.0));
        assert!(above.y < 0.0);
        // Right-handed world, looking +z with y up: +x is on the left of the image, so the
        // red wall (x ≈ 0.55) appears on the left as in the published photographs.
        let red = ndc(Vec3::new(0.55, 0.273, 0.5));
        assert!(red.x < 0.0);
        // The top edge of the frustum is at fov_y / 2.
        let t = (c.fov_y_deg.to_radians() / 2.0).tan();
        let edge = ndc(c.position + Vec3::new(0.0, t, 1.0));
        assert!((edge.y + 1.0).abs() < 1e-4, "{edge}");
    }

    #[test]
    fn degenerate_aspect_gives_finite_matrix() {
        let c = cornell_cam();
        for a in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(c.proj(a).is_finite());
        }
    }

    #[test]
    fn fov_x_for_square_and_wide() {
        let c = cornell_cam();
        assert!((c.fov_x_deg(1.0) - 39.3).abs() < 1e-4);
        assert!(c.fov_x_deg(2.0) > 39.3 * 1.5);
    }
}
