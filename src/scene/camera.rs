//! The scene camera: a pinhole with a vertical field of view, or an orthographic view of a
//! given height.

use glam::camera::rh::{proj::directx, view};
use glam::Vec4;
use glam::{Mat4, Vec3};

/// World → view for an eye at `eye` looking along `dir` with the up hint `up` (right-handed:
/// -Z forward, +X right, +Y up). `dir` need not be unit: it is normalized here, because glam's
/// `look_to_mat4` takes it as unit and a scene's or a light's direction is unit only to rounding.
pub fn look_to(eye: Vec3, dir: Vec3, up: Vec3) -> Mat4 {
    view::look_to_mat4(eye, dir.normalize(), up)
}

/// Right-handed perspective projection (vertical field of view `fov_y_rad`, `aspect` = width /
/// height), depth 0 at `near` and 1 at `far`, y up. The depth terms are far / (near − far) and
/// that times near, as glam 0.25's `perspective_rh` had them: glam's `directx::perspective`
/// rounds −far · 1/(far − near) instead, one ulp off in half the cases, and every depth and
/// reprojection would move with it.
pub fn perspective(fov_y_rad: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let (sin, cos) = (0.5 * fov_y_rad).sin_cos();
    let h = cos / sin;
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(h / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

/// How the camera projects: through a pinhole (`fov_y_deg`) or along parallel rays
/// (`ortho_height_m`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Projection {
    /// A pinhole: rays through the camera's position, the vertical field of view `fov_y_deg`.
    #[default]
    Perspective,
    /// Parallel rays along `forward` from the plane through the camera's position, the view
    /// `ortho_height_m` meters high: an object's size on screen does not depend on its distance.
    Orthographic,
}

impl Projection {
    /// The scene file's word (`[camera] projection`), also the flag's.
    pub fn name(self) -> &'static str {
        match self {
            Projection::Perspective => "perspective",
            Projection::Orthographic => "orthographic",
        }
    }
}

/// A validated camera. `forward` and `up` are unit length and not parallel.
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
    /// Horizontal off-axis shift of the frustum: the tangent (x / distance, view space) of the
    /// direction the image center looks along. 0 for a symmetric frustum; a stereo eye's
    /// asymmetric frustum ([`Camera::eye`]) has ±e / (2c). Not stored in scene files.
    /// Perspective only.
    pub shift_x_tan: f32,
    pub projection: Projection,
    /// Height in meters of the orthographic view (its width is height × aspect), > 0. Kept
    /// under perspective projection too, for a switch to orthographic (the viewer's toggle,
    /// `--projection`).
    pub ortho_height_m: f32,
}

impl Camera {
    /// World → view (right-handed; the camera looks down -Z in view space, +X right, +Y up).
    pub fn view(&self) -> Mat4 {
        look_to(self.position, self.forward, self.up)
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
        if self.is_orthographic() {
            // x, y scale by 2 / (width, height), depth linear from 0 at near to 1 at far, w = 1.
            let (hw, hh) = (
                0.5 * self.ortho_height_m * aspect,
                0.5 * self.ortho_height_m,
            );
            let mut p = directx::orthographic(-hw, hw, -hh, hh, self.near, self.far);
            p.y_axis.y = -p.y_axis.y;
            return p;
        }
        let mut p = perspective(self.fov_y_deg.to_radians(), aspect, self.near, self.far);
        // `perspective` already maps depth to [0, 1]; Vulkan's y axis points down.
        p.y_axis.y = -p.y_axis.y;
        // Off-axis: x_ndc = P00 (x_v / d - shift) with d = -z_v, so clip x gains P00 shift z_v.
        p.z_axis.x += p.x_axis.x * self.shift_x_tan;
        p
    }

    pub fn is_orthographic(&self) -> bool {
        self.projection == Projection::Orthographic
    }

    /// Pixels per meter of a surface facing the camera at view depth `depth_m`, in an image
    /// `height_px` pixels high: height / (2 tan(fov_y/2) · depth) through a pinhole, height /
    /// ortho height (any depth) under orthographic projection.
    pub fn px_per_m(&self, height_px: u32, depth_m: f32) -> f32 {
        match self.projection {
            Projection::Perspective => {
                height_px as f32 / (2.0 * (0.5 * self.fov_y_deg.to_radians()).tan() * depth_m)
            }
            Projection::Orthographic => height_px as f32 / self.ortho_height_m,
        }
    }

    /// The height of the perspective view at view depth `depth_m`, 2·d·tan(fov_y/2): an
    /// orthographic view of this height shows the plane at that depth as this camera does.
    pub fn view_height_at(&self, depth_m: f32) -> f32 {
        2.0 * depth_m * (0.5 * self.fov_y_deg.to_radians()).tan()
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

    /// The unit vector to the right of the image (view-space +X) in world space.
    pub fn right(&self) -> Vec3 {
        self.forward.cross(self.up).normalize()
    }

    /// One eye of a stereo pair with parallel axes and asymmetric (off-axis) frusta: the eye
    /// sits `separation_m / 2` to the side of this camera along [`Camera::right`], looks along
    /// the same `forward`, and its frustum is shifted toward the center so that both eyes' image
    /// windows coincide on the plane at `convergence_m` (zero disparity there). Any stereo
    /// text derives the same pair, e.g. Bourke 1999, "Calculating stereo pairs".
    ///
    /// With the eye at lateral offset ±e/2 and the shift ∓e/(2c) in tangent units, a point at
    /// lateral offset X and distance z projects to x_ndc = P00 ((X ∓ e/2) / z ± e/(2c)) with
    /// P00 = 1 / (aspect · tan(fov_y / 2)); right minus left is the disparity
    /// [`StereoRig::disparity_px`].
    pub fn eye(&self, rig: StereoRig, eye: Eye) -> Camera {
        let sign = match eye {
            Eye::Left => -1.0,
            Eye::Right => 1.0,
        };
        let half_e = 0.5 * rig.separation_m;
        Camera {
            position: self.position + self.right() * (sign * half_e),
            shift_x_tan: self.shift_x_tan - sign * half_e / rig.convergence_m,
            ..*self
        }
    }

    /// The camera as a scene file's `[camera]` table, exact (floats print in their shortest
    /// round-trip form), so a pose found in the viewer can be pasted into a scene.
    /// `origin_m` is the scene's local origin ([`super::Scene::origin_m`]): the position is
    /// written in world coordinates, like the scene file that gave it.
    pub fn toml_table(&self, origin_m: glam::DVec3) -> String {
        let v = |v: Vec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
        let projection = match self.projection {
            Projection::Perspective => "",
            Projection::Orthographic => "projection = \"orthographic\"\n",
        };
        let ortho = format!("{projection}ortho_height_m = {:?}\n", self.ortho_height_m);
        format!(
            "[camera]\nposition = {}\nforward = {}\nup = {}\nfov_y_deg = {:?}\n{ortho}near = {:?}\nfar = {:?}\n",
            world_toml(origin_m, self.position),
            v(self.forward),
            v(self.up),
            self.fov_y_deg,
            self.near,
            self.far
        )
    }
}

/// A local position as a TOML array in world coordinates: each f32 component at its shortest
/// round-trip value, plus the origin in f64 (unchanged text for a scene at the origin).
pub fn world_toml(origin_m: glam::DVec3, local: Vec3) -> String {
    let c = |o: f64, l: f32| {
        if o == 0.0 {
            format!("{l:?}")
        } else {
            format!(
                "{:?}",
                o + format!("{l:?}").parse::<f64>().unwrap_or(f64::from(l))
            )
        }
    };
    format!(
        "[{}, {}, {}]",
        c(origin_m.x, local.x),
        c(origin_m.y, local.y),
        c(origin_m.z, local.z)
    )
}

/// Which eye of a stereo pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Eye {
    Left,
    Right,
}

/// Parallax control of a stereo pair: the eyes' distance and the distance of the plane that
/// appears on the screen (nearer points come out of it, farther ones go behind).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoRig {
    /// Interocular distance e in meters, > 0 (a human's is about 0.065).
    pub separation_m: f32,
    /// Convergence (zero-parallax) distance c in meters along `forward`, > 0.
    pub convergence_m: f32,
}

impl Default for StereoRig {
    fn default() -> Self {
        Self {
            separation_m: 0.065,
            convergence_m: 2.0,
        }
    }
}

impl StereoRig {
    /// Horizontal screen disparity x_right − x_left in pixels of a point at distance `z_m`
    /// (along `forward`), for an image `width` pixels wide with focal length
    /// f = P00 · width / 2 = height / (2 tan(fov_y / 2)) pixels:
    ///
    /// d = f · e · (1/c − 1/z) = (f e / c) · (1 − c / z)
    ///
    /// (from [`Camera::eye`]: the lateral offsets ∓e/2 give f·(∓e/2)/z, the shifts ±e/(2c)
    /// give f·(±e/2)/c; the difference is independent of the point's lateral position). Zero
    /// at z = c, negative (crossed, in front of the screen) for z < c, approaching f e / c as
    /// z → ∞.
    pub fn disparity_px(&self, camera: &Camera, height: u32, z_m: f32) -> f32 {
        let f_px = height as f32 / (2.0 * (camera.fov_y_deg.to_radians() * 0.5).tan());
        let (e, c) = (self.separation_m, self.convergence_m);
        f_px * e / c * (1.0 - c / z_m)
    }
}

/// The field of view an orthographic camera without `fov_y_deg` switches to (the viewer's
/// toggle, `--projection perspective`).
pub(crate) const DEFAULT_ORTHO_FOV_Y_DEG: f32 = 40.0;

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
            shift_x_tan: 0.0,
            projection: Projection::Perspective,
            ortho_height_m: 1.0,
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
        let o = ortho_cam(0.8);
        for a in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(o.proj(a).is_finite());
        }
    }

    fn ortho_cam(height_m: f32) -> Camera {
        Camera {
            projection: Projection::Orthographic,
            ortho_height_m: height_m,
            ..cornell_cam()
        }
    }

    #[test]
    fn orthographic_sizes_do_not_depend_on_depth() {
        // A view h meters high maps y_v = ±h/2 to the image's top and bottom edges and x_v =
        // ±h·aspect/2 to its sides, at every depth; depth is linear, 0 at near and 1 at far.
        let (h, aspect) = (0.8, 1.5);
        let c = ortho_cam(h);
        let vp = c.view_proj(aspect);
        for z in [c.near, 0.5, 3.0, c.far] {
            let centre = c.position + c.forward * z;
            let top = vp.project_point3(centre + Vec3::Y * (0.5 * h));
            // +x of the world is the image's left (see vulkan_clip_conventions).
            let side = vp.project_point3(centre - Vec3::X * (0.5 * h * aspect));
            assert!((top.y + 1.0).abs() < 1e-5, "{top}");
            assert!((side.x - 1.0).abs() < 1e-5, "{side}");
            let expected_depth = (z - c.near) / (c.far - c.near);
            assert!((top.z - expected_depth).abs() < 1e-5, "{top} at {z}");
        }
        // The pixel scale is height / h at any depth.
        assert_eq!(c.px_per_m(128, 0.3), c.px_per_m(128, 30.0));
        assert!((c.px_per_m(128, 1.0) - 160.0).abs() < 1e-3);
        // The perspective scale at depth d is that of the orthographic view of the
        // perspective view's height there.
        let p = cornell_cam();
        let d = 2.5;
        let matched = ortho_cam(p.view_height_at(d));
        assert!((p.px_per_m(128, d) - matched.px_per_m(128, d)).abs() < 1e-3);
    }

    #[test]
    fn orthographic_rays_are_parallel_to_forward() {
        let c = ortho_cam(2.0);
        for (x, y) in [(0, 0), (63, 10), (127, 127)] {
            let (a, b) = c.pixel_ray_points(x, y, 128, 128);
            assert!(((b - a).normalize() - c.forward).length() < 1e-4, "{a} {b}");
            // The ray starts on the near plane.
            assert!(((a - c.position).dot(c.forward) - c.near).abs() < 1e-4);
        }
    }

    #[test]
    fn the_camera_table_keeps_the_projection() {
        let o = ortho_cam(0.75);
        let t = o.toml_table(glam::DVec3::ZERO);
        assert!(
            t.contains("projection = \"orthographic\"\northo_height_m = 0.75\n"),
            "{t}"
        );
        let p = cornell_cam().toml_table(glam::DVec3::ZERO);
        assert!(
            !p.contains("projection") && p.contains("ortho_height_m = 1.0\n"),
            "{p}"
        );
    }

    #[test]
    fn fov_x_for_square_and_wide() {
        let c = cornell_cam();
        assert!((c.fov_x_deg(1.0) - 39.3).abs() < 1e-4);
        assert!(c.fov_x_deg(2.0) > 39.3 * 1.5);
    }

    /// Pixel x (continuous, 0 at the left edge) where `camera` sees `p` in a w×h image.
    fn pixel_x(camera: &Camera, p: Vec3, w: u32, h: u32) -> f32 {
        let ndc = camera.view_proj(w as f32 / h as f32).project_point3(p);
        (ndc.x + 1.0) * 0.5 * w as f32
    }

    #[test]
    fn eyes_are_parallel_and_separated_along_right() {
        let c = cornell_cam();
        let rig = StereoRig {
            separation_m: 0.1,
            convergence_m: 1.5,
        };
        let (l, r) = (c.eye(rig, Eye::Left), c.eye(rig, Eye::Right));
        assert_eq!((l.forward, r.forward), (c.forward, c.forward));
        assert!((r.position - l.position - c.right() * 0.1).length() < 1e-6);
        assert!(((l.position + r.position) * 0.5 - c.position).length() < 1e-6);
    }

    #[test]
    fn disparity_matches_the_closed_form() {
        let c = cornell_cam();
        let rig = StereoRig {
            separation_m: 0.08,
            convergence_m: 1.2,
        };
        let (l, r) = (c.eye(rig, Eye::Left), c.eye(rig, Eye::Right));
        let (w, h) = (160, 120);
        for z in [0.3, 0.7, 1.2, 2.0, 9.0] {
            // Off the axis in x and y: disparity must not depend on the lateral position.
            for lateral in [-0.2, 0.0, 0.15] {
                let p = c.position + c.forward * z + c.right() * lateral + c.up * 0.05;
                let d = pixel_x(&r, p, w, h) - pixel_x(&l, p, w, h);
                let expected = rig.disparity_px(&c, h, z);
                assert!((d - expected).abs() < 1e-3, "z {z}: {d} vs {expected}");
            }
        }
        // Zero parallax exactly at the convergence distance; crossed (negative) nearer.
        assert_eq!(rig.disparity_px(&c, h, 1.2), 0.0);
        assert!(rig.disparity_px(&c, h, 0.5) < 0.0 && rig.disparity_px(&c, h, 3.0) > 0.0);
    }

    #[test]
    fn eye_frusta_share_the_window_at_the_convergence_plane() {
        let c = cornell_cam();
        let rig = StereoRig::default();
        let aspect = 1.5;
        let t = (c.fov_y_deg.to_radians() / 2.0).tan();
        // The corners of the centre camera's window at distance c land on both eyes' corners.
        for (sx, sy) in [(-1.0, -1.0), (1.0, 1.0), (1.0, -1.0)] {
            let p = c.position
                + c.forward * rig.convergence_m
                + c.right() * (sx * t * aspect * rig.convergence_m)
                + Vec3::Y * (sy * t * rig.convergence_m);
            for eye in [Eye::Left, Eye::Right] {
                let ndc = c.eye(rig, eye).view_proj(aspect).project_point3(p);
                assert!(
                    (ndc.x - sx).abs() < 1e-4 && (ndc.y + sy).abs() < 1e-4,
                    "{ndc}"
                );
            }
        }
    }
}
