//! The screen-space method's limitations (Oetke 2017 §7), measured on purpose-made scenes
//! (`voxgi bench ssgi-limits`): for each view, the indirect light in the image (the image
//! minus the direct-only image of the same view, averaged over the pixels and the three
//! channels) of `--gi ssgi` and of a voxel method, as a fraction of the Mitsuba reference's
//! (its full-GI image minus its direct-only image, `max_depth` 2).
//!
//! - **Off-screen light** (`assets/scenes/ssgi_offscreen.toml`): a spot lights a disk on a
//!   wall that lights the room indirectly; the camera turns away from it ([`OFFSCREEN_YAWS_DEG`]),
//!   the whole view measured. Screen-space GI gathers only what is on the screen: once the
//!   disk is out of view, no pixel has light to send and its indirect light is exactly 0.
//! - **Missing indirect shadows** (`assets/scenes/ssgi_occluder.toml`): a floor disk lit by a
//!   spot lights the back wall; a panel seen edge-on by the camera and the light (it covers no
//!   pixel, casts no direct shadow) blocks part of that light. Measured over
//!   [`occluder_region`] of the wall, with and without the panel: screen-space GI has no
//!   visibility term (§2.3) and sees no panel, so its two images are identical.
//!
//! Light leaking through thin walls, the third limitation named in the issue, has its own
//! benchmark (`voxgi bench leak`, [`super::leak`], `ssgi` among its methods).

use crate::eval::HdrImage;
use crate::gi::{GiMethod, GiSettings};
use crate::render::{render_image, RenderError, RenderSettings};
use crate::scene::{Scene, SceneError};
use crate::vk::Context;
use glam::Mat3;
use serde::Serialize;
use std::path::Path;

/// The off-screen scene's views: the camera turned right (towards +x, away from the lit
/// disk) by these angles. At 0° the disk is in view, at 10° and 20° it leaves the image's
/// edge, from 30° on no directly lit pixel is in view.
pub const OFFSCREEN_YAWS_DEG: [f32; 5] = [0.0, 10.0, 20.0, 30.0, 45.0];

/// The off-screen scene (embedded, so the benchmark runs from any directory).
pub fn offscreen_scene() -> Result<Scene, SceneError> {
    Scene::from_toml_str(
        include_str!("../../assets/scenes/ssgi_offscreen.toml"),
        Path::new("assets/scenes/ssgi_offscreen.toml"),
        Path::new("."),
    )
}

/// The occluder scene (embedded).
pub fn occluder_scene() -> Result<Scene, SceneError> {
    Scene::from_toml_str(
        include_str!("../../assets/scenes/ssgi_occluder.toml"),
        Path::new("assets/scenes/ssgi_occluder.toml"),
        Path::new("."),
    )
}

/// `scene` with its camera turned right by `deg` about the vertical axis (+y).
pub fn yawed(scene: &Scene, deg: f32) -> Scene {
    let mut s = scene.clone();
    s.camera.forward = Mat3::from_rotation_y(deg.to_radians()) * s.camera.forward;
    s
}

/// `scene` without its objects named `name`.
pub fn without_object(scene: &Scene, name: &str) -> Scene {
    let mut s = scene.clone();
    s.objects.retain(|o| o.name != name);
    s
}

/// The pixels of a `size`² view of the occluder scene whose camera ray meets the back wall
/// (z = 1) at |x| ≤ 0.4, y ≤ 1.2: the wall behind the panel, where its indirect shadow falls
/// (the camera at y = 1 looks down at the wall, so nothing in front hides that part).
pub fn occluder_region(scene: &Scene, size: u32) -> Vec<bool> {
    (0..size * size)
        .map(|i| {
            let (a, b) = scene
                .camera
                .pixel_ray_points(i % size, i / size, size, size);
            let d = b - a;
            if d.z <= 0.0 {
                return false;
            }
            let p = a + d * ((1.0 - a.z) / d.z);
            p.x.abs() <= 0.4 && (0.0..=1.2).contains(&p.y)
        })
        .collect()
}

/// The mean of `img − direct` over the pixels of `mask` (all pixels without one) and the
/// three channels: the indirect light in view, W/(m²·sr).
pub fn indirect_mean(img: &HdrImage, direct: &HdrImage, mask: Option<&[bool]>) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, (p, q)) in img.data.iter().zip(&direct.data).enumerate() {
        if mask.is_some_and(|m| !m.get(i).copied().unwrap_or(false)) {
            continue;
        }
        sum += (0..3).map(|c| f64::from(p[c] - q[c])).sum::<f64>();
        n += 3;
    }
    sum / n.max(1) as f64
}

/// The GI settings of a measured method: `frames` accumulated frames (feedback bounces for
/// `ssgi`), no geometry-aware filter (it would blur the indirect shadow).
pub fn method_settings(method: GiMethod, frames: u32) -> GiSettings {
    GiSettings {
        method,
        accumulate_frames: frames,
        filter_radius: 0,
        ..Default::default()
    }
}

/// Renders `scene` at `size`² with `gi` (direct only with `GiMethod::None`).
pub fn render(
    ctx: &Context,
    scene: &Scene,
    size: u32,
    gi: GiSettings,
) -> Result<HdrImage, RenderError> {
    let settings = RenderSettings {
        width: size,
        height: size,
        gi,
        ..Default::default()
    };
    Ok(render_image(ctx, scene, &settings)?.hdr)
}

/// One measured view: the indirect light of the reference and of each method (W/(m²·sr)
/// averaged over the measured pixels) and each method's fraction of the reference's.
#[derive(Clone, Debug, Serialize)]
pub struct LimitRow {
    pub case: String,
    pub view: String,
    pub reference: f64,
    /// (method, indirect light, fraction of the reference's)
    pub methods: Vec<(String, f64, f64)>,
}

/// The measured views.
#[derive(Clone, Debug, Serialize)]
pub struct LimitReport {
    pub size: u32,
    pub frames: u32,
    pub reference_spp: u32,
    pub rows: Vec<LimitRow>,
}

impl LimitReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "indirect light in view, W/(m² sr), and the fraction of Mitsuba's ({}², {} frames, \
             references {} spp)\n",
            self.size, self.frames, self.reference_spp
        );
        let names: Vec<&str> = self
            .rows
            .first()
            .map(|r| r.methods.iter().map(|m| m.0.as_str()).collect())
            .unwrap_or_default();
        s += &format!("{:<10} {:<16} {:>10}", "case", "view", "mitsuba");
        for n in &names {
            s += &format!(" {:>10} {:>8}", n, "fraction");
        }
        s += "\n";
        for r in &self.rows {
            s += &format!("{:<10} {:<16} {:>10.5}", r.case, r.view, r.reference);
            for (_, v, f) in &r.methods {
                s += &format!(" {v:>10.5} {f:>8.3}");
            }
            s += "\n";
        }
        s
    }
}

/// A measured case: its scene variants (label, scene) and the pixels measured.
pub struct LimitCase {
    pub case: &'static str,
    pub views: Vec<(String, Scene)>,
    pub mask: Option<Vec<bool>>,
}

/// The cases of the benchmark at `size`².
pub fn limit_cases(size: u32) -> Result<Vec<LimitCase>, SceneError> {
    let offscreen = offscreen_scene()?;
    let occluder = occluder_scene()?;
    Ok(vec![
        LimitCase {
            case: "offscreen",
            views: OFFSCREEN_YAWS_DEG
                .iter()
                .map(|&d| (format!("yaw {d}°"), yawed(&offscreen, d)))
                .collect(),
            mask: None,
        },
        LimitCase {
            case: "occluder",
            views: vec![
                ("with panel".into(), occluder.clone()),
                ("without panel".into(), without_object(&occluder, "panel")),
            ],
            mask: Some(occluder_region(&occluder, size)),
        },
    ])
}
