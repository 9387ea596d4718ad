//! The viewer's scene editor: select an object by clicking it (the GPU `pick` pass, see
//! [`super::pick`]) or a light by its marker, move, rotate and scale it with handles dragged in
//! the viewport or with the panel's fields, edit, add and remove lights, and save the scene
//! back to its TOML file ([`crate::scene::save`]). The panel section and the drawing over the
//! scene are in `edit_ui.rs`.
//!
//! - Every edit goes through the loader's checks ([`Placement::transform`], [`reload_light`]):
//!   the viewer shows exactly what the saved file renders, and a value the loader refuses is
//!   refused with the loader's message in the panel.
//! - An edited object becomes dynamic (`Object::dynamic`): the renderer draws it and
//!   re-voxelizes it where it is in each frame it moves (`Renderer::prepare` hands the
//!   transforms to the voxelizer, whose `SlotCondition` opens in the frames whose triangles
//!   changed, as for keyframed objects). A static object's voxels are baked into the static
//!   grid, so the first edit of one makes a new renderer with it dynamic (once per object;
//!   `Renderer::can_move`); without voxels none is needed.
//! - A new renderer is also made when the lights change in number or in shadow views (an
//!   added or removed light, an area light's samples: the shadow array and light tables have
//!   one size per renderer) and, once a drag or field edit ends, when the scene's bounds
//!   changed (the voxel grid and every GI parameter derived from the scene's size follow
//!   them, so the viewer matches a render of the saved file). A renderer that cannot be made
//!   (e.g. `TooManyLights`) undoes the edit and says why.
//! - Animated objects keep their keyframes: they are selectable but not editable.

use super::camera::FlyCamera;
use super::pick::Picked;
use crate::scene::save::{reload_light, Placement, SceneEdits};
use crate::scene::{Aabb, Camera, Light, Scene};
use glam::{Quat, Vec3};
use std::path::{Path, PathBuf};

/// What is selected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    Object(usize),
    Light(usize),
}

/// What the viewport's handles do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HandleMode {
    /// Along world X, Y, Z.
    #[default]
    Move,
    /// About world X, Y, Z through the object's centre.
    Rotate,
    /// Along the object's own axes, about its centre.
    Scale,
}

const AXES: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];
const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];
/// Handle length and how near a click must be to grab one, window pixels.
const HANDLE_PX: f32 = 60.0;
const GRAB_PX: f32 = 8.0;
/// Sub-lights of an area light added in the viewer (a file's default is 16; each is a shadow
/// view, so fewer keep the viewer responsive).
const NEW_AREA_SAMPLES: u32 = 8;

/// The kinds of light the panel adds.
pub const LIGHT_KINDS: [&str; 5] = ["point", "spot", "directional", "sphere", "rectangle"];

/// The scene's part of the window and the camera that renders it: maps between world points
/// and window pixels.
#[derive(Clone, Copy, Debug)]
pub struct ViewGeom {
    pub camera: Camera,
    /// Left, top, width, height of the scene in window pixels.
    pub rect_px: [f32; 4],
}

impl ViewGeom {
    fn aspect(&self) -> f32 {
        self.rect_px[2] / self.rect_px[3].max(1.0)
    }

    /// Window pixel of world point `p`, `None` behind the camera.
    pub fn project(&self, p: Vec3) -> Option<[f32; 2]> {
        let clip = self.camera.view_proj(self.aspect()) * p.extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let [x0, y0, w, h] = self.rect_px;
        Some([
            x0 + (clip.x / clip.w * 0.5 + 0.5) * w,
            y0 + (clip.y / clip.w * 0.5 + 0.5) * h,
        ])
    }

    /// The camera ray through window pixel `px`: origin and unit direction.
    pub fn ray(&self, px: [f32; 2]) -> (Vec3, Vec3) {
        let [x0, y0, w, h] = self.rect_px;
        let ndc = |z: f32| {
            let inv = self.camera.view_proj(self.aspect()).inverse();
            let p = inv
                * glam::Vec4::new(
                    (px[0] - x0) / w * 2.0 - 1.0,
                    (px[1] - y0) / h * 2.0 - 1.0,
                    z,
                    1.0,
                );
            p.truncate() / p.w
        };
        let (a, b) = (ndc(0.0), ndc(1.0));
        (a, (b - a).normalize_or_zero())
    }

    /// The frame pixel under window pixel `px`, `None` outside the scene.
    pub fn frame_pixel(&self, px: [f32; 2]) -> Option<(u32, u32)> {
        let [x0, y0, w, h] = self.rect_px;
        let (x, y) = (px[0] - x0, px[1] - y0);
        (x >= 0.0 && y >= 0.0 && x < w && y < h).then_some((x as u32, y as u32))
    }

    /// World length that spans `px` pixels at `p`'s distance.
    fn world_per_px(&self, p: Vec3) -> f32 {
        let d = (p - self.camera.position)
            .dot(self.camera.forward)
            .max(1e-4);
        d * 2.0 * (self.camera.fov_y_deg.to_radians() * 0.5).tan() / self.rect_px[3].max(1.0)
    }
}

/// The parameter t of the point of the line `o + t·a` nearest to the ray (`ro`, `rd`); `None`
/// when they are parallel.
fn axis_param(o: Vec3, a: Vec3, ro: Vec3, rd: Vec3) -> Option<f32> {
    // Closest points of two lines (e.g. Ericson 2005, §5.1.8).
    let w = o - ro;
    let (b, c, d, e) = (a.dot(rd), rd.dot(rd), a.dot(w), rd.dot(w));
    let denom = a.dot(a) * c - b * b;
    (denom.abs() > 1e-8 * c.max(1e-8)).then(|| (b * e - c * d) / denom)
}

/// Distance from `p` to the segment `a`–`b` (window pixels).
fn segment_distance(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f32 {
    let (p, a, b) = (
        glam::Vec2::from(p),
        glam::Vec2::from(a),
        glam::Vec2::from(b),
    );
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-6)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// A drag in progress.
#[derive(Clone, Copy, Debug)]
struct Drag {
    what: Selection,
    mode: HandleMode,
    axis: usize,
    /// The world direction dragged along (or rotated about).
    dir: Vec3,
    pivot: Vec3,
    /// The axis parameter (move, scale) or the plane vector (rotate) at the press.
    start_t: f32,
    start_v: Vec3,
    start_x_px: f32,
    start: Start,
}

#[derive(Clone, Copy, Debug)]
enum Start {
    /// The transform, the mesh's local centre and the placement at the press.
    Object(crate::scene::Transform, Vec3, Placement),
    Light(Light),
}

/// What changes the renderer's resources: the lights' kinds and samples (shadow views, light
/// tables), which objects move, the scene's bounds (voxel grid, GI scales).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneShape {
    lights: Vec<(std::mem::Discriminant<Light>, u32)>,
    bounds: Aabb,
}

impl SceneShape {
    pub fn of(scene: &Scene) -> Self {
        Self {
            lights: scene
                .lights
                .iter()
                .map(|l| {
                    let samples = match l {
                        Light::Sphere { samples, .. } | Light::Rectangle { samples, .. } => {
                            *samples
                        }
                        _ => 0,
                    };
                    (std::mem::discriminant(l), samples)
                })
                .collect(),
            bounds: edited_bounds(scene),
        }
    }

    pub fn same_lights(&self, other: &Self) -> bool {
        self.lights == other.lights
    }

    pub fn same_bounds(&self, other: &Self) -> bool {
        self.bounds == other.bounds
    }
}

/// A change the panel asks for; the viewer applies it after drawing the panel.
#[derive(Clone, Debug, PartialEq)]
pub enum EditAction {
    Select(Option<Selection>),
    Handle(HandleMode),
    Place(usize, Placement),
    SetLight(usize, Light),
    /// The kind the "Add light" button adds (index into [`LIGHT_KINDS`]).
    LightKind(usize),
    AddLight(usize),
    RemoveLight(usize),
    Save,
}

/// The editor's state.
pub struct Editor {
    pub selection: Option<Selection>,
    pub handle: HandleMode,
    drag: Option<Drag>,
    /// A click in the scene waiting for the GPU pick (frame pixel).
    pick_request: Option<(u32, u32)>,
    /// Per object, the transform keys edited.
    placements: Vec<Placement>,
    /// Per object, its transform as loaded (what unedited keys keep).
    loaded_transforms: Vec<crate::scene::Transform>,
    /// For each light of the scene, the `[[lights]]` table it came from (`None`: added).
    pub(super) light_origins: Vec<Option<usize>>,
    /// The lights as loaded.
    loaded_lights: Vec<Light>,
    /// The fly camera at the start: a moved camera is saved.
    start_camera: FlyCamera,
    /// The kind the panel's "Add" button adds (index into [`LIGHT_KINDS`]).
    pub new_light_kind: usize,
    /// The scene file, `None` for a built-in scene (then `builtin` names it).
    source: Option<PathBuf>,
    builtin: Option<String>,
    save_to: Option<PathBuf>,
    /// The last message for the panel.
    pub status: String,
}

impl Editor {
    pub fn new(
        scene: &Scene,
        fly: &FlyCamera,
        builtin: Option<String>,
        save_to: Option<PathBuf>,
    ) -> Self {
        Self {
            selection: None,
            handle: HandleMode::Move,
            drag: None,
            pick_request: None,
            placements: vec![Placement::default(); scene.objects.len()],
            loaded_transforms: scene.objects.iter().map(|o| o.transform).collect(),
            light_origins: (0..scene.lights.len()).map(Some).collect(),
            loaded_lights: scene.lights.clone(),
            start_camera: *fly,
            new_light_kind: 0,
            source: scene.source.clone(),
            builtin,
            save_to,
            status: String::new(),
        }
    }

    pub fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// The click waiting for the GPU, once.
    pub fn take_pick_request(&mut self) -> Option<(u32, u32)> {
        self.pick_request.take()
    }

    fn file_name(&self) -> PathBuf {
        self.source
            .clone()
            .or_else(|| {
                self.builtin
                    .as_ref()
                    .map(|b| PathBuf::from(format!("<{b}>")))
            })
            .unwrap_or_else(|| PathBuf::from("<scene>"))
    }

    /// The transform keys edited of object `i`.
    pub fn placement(&self, i: usize) -> Placement {
        self.placements.get(i).copied().unwrap_or_default()
    }

    /// The rotation of object `i` as the panel shows it: the edited angles, or the loaded
    /// rotation's (see [`crate::scene::euler_xyz_deg`]).
    pub(super) fn rotate_deg(&self, scene: &Scene, i: usize) -> Vec3 {
        self.placement(i).rotate_deg.unwrap_or_else(|| {
            scene.objects.get(i).map_or(Vec3::ZERO, |o| {
                crate::scene::euler_xyz_deg(o.transform.rotation)
            })
        })
    }

    /// The selected object's or light's handle centre.
    fn pivot(&self, scene: &Scene, time_s: f32) -> Option<Vec3> {
        match self.selection? {
            Selection::Object(i) => Some(scene.objects.get(i)?.aabb_at(time_s).center()),
            Selection::Light(i) => scene.lights.get(i)?.position(),
        }
    }

    /// The selection's handles in window pixels: (axis, world direction, start, end).
    pub(super) fn handles(
        &self,
        scene: &Scene,
        view: &ViewGeom,
        time_s: f32,
    ) -> Vec<(usize, Vec3, [f32; 2], [f32; 2])> {
        let Some(p) = self.pivot(scene, time_s) else {
            return Vec::new();
        };
        let Some(c) = view.project(p) else {
            return Vec::new();
        };
        let len = HANDLE_PX * view.world_per_px(p);
        let mode = match self.selection {
            Some(Selection::Light(_)) => HandleMode::Move,
            _ => self.handle,
        };
        let rotation = match self.selection {
            Some(Selection::Object(i)) => scene.objects.get(i).map(|o| o.transform.rotation),
            _ => None,
        }
        .unwrap_or(Quat::IDENTITY);
        (0..3)
            .filter_map(|k| {
                let dir = match mode {
                    HandleMode::Scale => rotation * AXES[k],
                    _ => AXES[k],
                };
                let tip = view.project(p + dir * len)?;
                Some((k, dir, c, tip))
            })
            .collect()
    }

    /// One line for the log: where the selection's handle tips are (window pixels).
    pub fn describe_handles(&self, scene: &Scene, view: &ViewGeom, time_s: f32) -> String {
        let parts: Vec<String> = self
            .handles(scene, view, time_s)
            .iter()
            .map(|(k, _, _, tip)| format!("{} [{:.1}, {:.1}]", AXIS_NAMES[*k], tip[0], tip[1]))
            .collect();
        format!(
            "{:?} handles (window px): {}",
            self.handle,
            parts.join(", ")
        )
    }

    /// A press of the left button at window pixel `px`: grabs a handle of the selection, or a
    /// light's marker, or asks the GPU which object is there. Returns whether it grabbed a
    /// handle (a drag starts).
    pub fn press(&mut self, px: [f32; 2], scene: &Scene, view: &ViewGeom, time_s: f32) -> bool {
        let Some(frame_px) = view.frame_pixel(px) else {
            return false;
        };
        let grabbed = self
            .handles(scene, view, time_s)
            .into_iter()
            .map(|(k, dir, a, b)| (segment_distance(px, a, b), k, dir))
            .filter(|(d, _, _)| *d <= GRAB_PX)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let (Some((_, axis, dir)), Some(what), Some(pivot)) =
            (grabbed, self.selection, self.pivot(scene, time_s))
        {
            let mode = match what {
                Selection::Light(_) => HandleMode::Move,
                Selection::Object(_) => self.handle,
            };
            let start = match what {
                Selection::Object(i) => match scene.objects.get(i) {
                    Some(o) if o.is_animated() => {
                        self.status = format!(
                            "\"{}\" is animated by keyframes: edit them in the scene file",
                            o.name
                        );
                        return false;
                    }
                    Some(o) => Start::Object(o.transform, o.local_aabb.center(), self.placement(i)),
                    None => return false,
                },
                Selection::Light(i) => match scene.lights.get(i) {
                    Some(l) => Start::Light(*l),
                    None => return false,
                },
            };
            let (ro, rd) = view.ray(px);
            let mut drag = Drag {
                what,
                mode,
                axis,
                dir,
                pivot,
                start_t: axis_param(pivot, dir, ro, rd).unwrap_or(0.0),
                start_v: Vec3::ZERO,
                start_x_px: px[0],
                start,
            };
            if mode == HandleMode::Rotate {
                drag.start_v = plane_vector(pivot, dir, ro, rd).unwrap_or(Vec3::ZERO);
            }
            self.drag = Some(drag);
            return true;
        }
        // A light's marker.
        let marker = scene
            .lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| Some((i, view.project(l.position()?)?)))
            .map(|(i, m)| (glam::Vec2::from(m).distance(px.into()), i))
            .filter(|(d, _)| *d <= GRAB_PX)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((_, i)) = marker {
            self.select(Some(Selection::Light(i)));
            return false;
        }
        self.pick_request = Some(frame_px);
        false
    }

    /// Follows the cursor during a drag; returns the edit to apply.
    pub fn drag_to(&mut self, px: [f32; 2], view: &ViewGeom) -> Option<EditAction> {
        let d = self.drag?;
        let (ro, rd) = view.ray(px);
        match (d.start, d.mode) {
            (Start::Light(l), _) => {
                let t = axis_param(d.pivot, d.dir, ro, rd)?;
                let mut l = l;
                move_light(&mut l, d.dir * (t - d.start_t));
                Some(EditAction::SetLight(index(d.what), l))
            }
            (Start::Object(t0, _, p0), HandleMode::Move) => {
                let t = axis_param(d.pivot, d.dir, ro, rd)?;
                let p = Placement {
                    translate: Some(t0.translate + d.dir * (t - d.start_t)),
                    ..p0
                };
                Some(EditAction::Place(index(d.what), p))
            }
            (Start::Object(t0, _, p0), HandleMode::Rotate) => {
                let angle = match plane_vector(d.pivot, d.dir, ro, rd) {
                    Some(v) if d.start_v != Vec3::ZERO && v != Vec3::ZERO => {
                        d.dir.dot(d.start_v.cross(v)).atan2(d.start_v.dot(v))
                    }
                    // The ring seen edge-on: the cursor's horizontal motion turns it.
                    _ => (px[0] - d.start_x_px) * 0.01,
                };
                let turn = Quat::from_axis_angle(d.dir, angle);
                let p = Placement {
                    rotate_deg: Some(crate::scene::euler_xyz_deg(turn * t0.rotation)),
                    // About the centre: the centre stays where it is.
                    translate: Some(d.pivot + turn * (t0.translate - d.pivot)),
                    ..p0
                };
                Some(EditAction::Place(index(d.what), p))
            }
            (Start::Object(t0, local_center, p0), HandleMode::Scale) => {
                let t = axis_param(d.pivot, d.dir, ro, rd)?;
                let f = if d.start_t.abs() > 1e-9 {
                    (t / d.start_t).clamp(0.01, 100.0)
                } else {
                    1.0
                };
                let mut scale = t0.scale;
                scale[d.axis] *= f;
                let p = Placement {
                    scale: Some(scale),
                    // About the centre: pivot = T + R (S ⊙ c) stays.
                    translate: Some(d.pivot - t0.rotation * (scale * local_center)),
                    ..p0
                };
                Some(EditAction::Place(index(d.what), p))
            }
        }
    }

    /// Ends a drag; returns whether one was in progress.
    pub fn release(&mut self) -> bool {
        self.drag.take().is_some()
    }

    pub fn select(&mut self, s: Option<Selection>) {
        self.selection = s;
        self.drag = None;
    }

    /// The GPU's answer to a click: selects the object there (or nothing).
    pub fn picked(&mut self, p: Picked) {
        self.select(p.object.map(Selection::Object));
    }

    /// Records that object `i` is now at `p` (already applied to the scene).
    pub fn placed(&mut self, i: usize, p: Placement) {
        if let Some(slot) = self.placements.get_mut(i) {
            *slot = p;
        }
    }

    pub fn light_added(&mut self) {
        self.light_origins.push(None);
    }

    pub fn light_removed(&mut self, i: usize) {
        if i < self.light_origins.len() {
            self.light_origins.remove(i);
        }
        self.selection = match self.selection {
            Some(Selection::Light(j)) if j == i => None,
            Some(Selection::Light(j)) if j > i => Some(Selection::Light(j - 1)),
            s => s,
        };
        self.drag = None;
    }

    /// The edits since loading, for [`crate::scene::save::apply_edits`].
    fn edits(
        &self,
        scene: &Scene,
        fly: &FlyCamera,
        camera: &Camera,
        keys: &[Camera],
    ) -> SceneEdits {
        let lights = scene
            .lights
            .iter()
            .zip(&self.light_origins)
            .map(|(l, origin)| match origin {
                Some(i) if self.loaded_lights.get(*i) == Some(l) => {
                    crate::scene::save::LightEdit::Keep(*i)
                }
                Some(i) => crate::scene::save::LightEdit::Changed(*i, *l),
                None => crate::scene::save::LightEdit::Added(*l),
            })
            .collect::<Vec<_>>();
        let untouched = lights.len() == self.loaded_lights.len()
            && lights
                .iter()
                .enumerate()
                .all(|(i, e)| *e == crate::scene::save::LightEdit::Keep(i));
        let moved = (fly.position, fly.yaw_rad, fly.pitch_rad)
            != (
                self.start_camera.position,
                self.start_camera.yaw_rad,
                self.start_camera.pitch_rad,
            );
        SceneEdits {
            origin_m: scene.origin_m,
            transforms: self.placements.clone(),
            lights: (!untouched).then_some(lights),
            camera: moved.then_some(*camera),
            camera_path: crate::scene::CameraPath::through_cameras(
                keys,
                super::RECORDED_KEY_SPACING_S,
            )
            .ok(),
            relocate_from: None,
            settings: None,
        }
    }

    /// Writes the scene with its edits to `--save PATH` or its own file; returns the path.
    pub fn save(
        &self,
        scene: &Scene,
        fly: &FlyCamera,
        camera: &Camera,
        keys: &[Camera],
        settings: crate::scene::save::FrameTables,
    ) -> Result<PathBuf, crate::scene::save::SaveError> {
        use crate::scene::save::SaveError;
        let target = match (&self.save_to, &self.source) {
            (Some(p), _) | (None, Some(p)) => p.clone(),
            (None, None) => {
                return Err(SaveError::NoFile(
                    self.builtin.clone().unwrap_or_else(|| "?".into()),
                ))
            }
        };
        let text = match (&self.source, &self.builtin) {
            (Some(src), _) => std::fs::read_to_string(src).map_err(|e| SaveError::Syntax {
                file: src.clone(),
                reason: format!("it cannot be read again ({e})"),
            })?,
            (None, Some(b)) => {
                crate::scene::builtin_toml(b).ok_or_else(|| SaveError::NoFile(b.clone()))?
            }
            (None, None) => return Err(SaveError::NoFile("?".into())),
        };
        let mut edits = self.edits(scene, fly, camera, keys);
        edits.settings = Some(settings);
        if let Some(src) = &self.source {
            let dir = |p: &Path| {
                let d = p.parent().unwrap_or(Path::new("."));
                let d = if d.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    d
                };
                d.canonicalize().unwrap_or_else(|_| d.to_path_buf())
            };
            if dir(src) != dir(&target) {
                edits.relocate_from = src.parent().map(Path::to_path_buf);
            }
        }
        let out = crate::scene::save::apply_edits(&text, &self.file_name(), &edits)?;
        std::fs::write(&target, out).map_err(|e| SaveError::Write {
            path: target.clone(),
            reason: e.to_string(),
        })?;
        Ok(target)
    }

    /// Checks `light` as the file would give it back (the loader's checks and message).
    pub fn checked_light(&self, scene: &Scene, i: usize, light: &Light) -> Result<Light, String> {
        reload_light(
            light,
            scene.origin_m,
            &self.file_name(),
            &format!("lights[{i}]"),
        )
        .map_err(|e| e.to_string())
    }

    /// Checks a placement as the file would give it back.
    pub fn checked_placement(
        &self,
        scene: &Scene,
        i: usize,
        p: &Placement,
    ) -> Result<crate::scene::Transform, String> {
        let base = self.loaded_transforms.get(i).copied().unwrap_or_default();
        p.transform(
            &base,
            scene.origin_m,
            &self.file_name(),
            &format!("objects[{i}]"),
        )
        .map_err(|e| e.to_string())
    }
}

fn index(s: Selection) -> usize {
    match s {
        Selection::Object(i) | Selection::Light(i) => i,
    }
}

/// The vector from `pivot` to where the ray meets the plane through `pivot` normal to `n`,
/// `None` when the ray runs (nearly) in the plane.
fn plane_vector(pivot: Vec3, n: Vec3, ro: Vec3, rd: Vec3) -> Option<Vec3> {
    let den = rd.dot(n);
    if den.abs() < 0.05 {
        return None;
    }
    let t = (pivot - ro).dot(n) / den;
    Some(ro + rd * t - pivot)
}

/// Moves a light's position by `delta` (lights without one do not move).
fn move_light(l: &mut Light, delta: Vec3) {
    match l {
        Light::Point { position, .. }
        | Light::Spot { position, .. }
        | Light::Sphere { position, .. }
        | Light::Rectangle { position, .. }
        | Light::Element { position, .. } => *position += delta,
        Light::Directional { .. } => {}
    }
}

/// A new light of kind `LIGHT_KINDS[kind]` for `scene`: a quarter of the scene's height above
/// its centre, facing down, bright enough for E = 2 W/m² at half the scene's diagonal
/// (I = E·d²; an area light's radiance L = I/A for the same on-axis intensity).
pub fn new_light(scene: &Scene, kind: usize, time_s: f32) -> Light {
    let b = scene.aabb_at(time_s);
    let (center, extent) = if b.is_empty() {
        (Vec3::ZERO, Vec3::ONE)
    } else {
        (b.center(), b.extent())
    };
    let position = center + Vec3::Y * (0.25 * extent.y);
    let d = (0.5 * extent.length()).max(1e-3);
    let intensity = Vec3::splat(2.0 * d * d);
    match LIGHT_KINDS.get(kind).copied().unwrap_or("point") {
        "spot" => Light::Spot {
            position,
            direction: Vec3::NEG_Y,
            intensity_w_sr: intensity,
            cutoff_deg: 40.0,
            beam_deg: 30.0,
        },
        "directional" => Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
            irradiance_w_m2: Vec3::splat(1.0),
        },
        "sphere" => {
            let r = 0.02 * 2.0 * d;
            Light::Sphere {
                position,
                radius_m: r,
                radiance_w_sr_m2: intensity / (std::f32::consts::PI * r * r),
                samples: NEW_AREA_SAMPLES,
            }
        }
        "rectangle" => {
            let s = 0.1 * 2.0 * d;
            Light::Rectangle {
                position,
                normal: Vec3::NEG_Y,
                width_axis: Vec3::X,
                width_m: s,
                height_m: s,
                radiance_w_sr_m2: intensity / (s * s),
                samples: NEW_AREA_SAMPLES,
            }
        }
        _ => Light::Point {
            position,
            intensity_w_sr: intensity,
        },
    }
}

/// The lights' state the viewer keeps, saved before a change that needs a new renderer and
/// restored when that renderer cannot be made.
pub struct LightBackup {
    base: Vec<Light>,
    scale: Vec<f32>,
    names: Vec<String>,
    origins: Vec<Option<usize>>,
    selection: Option<Selection>,
}

/// The panel's name of light `i`.
pub fn light_name(i: usize, l: &Light) -> String {
    let kind = match l {
        Light::Point { .. } => "point",
        Light::Spot { .. } => "spot",
        Light::Directional { .. } => "directional",
        Light::Sphere { .. } => "sphere",
        Light::Rectangle { .. } => "rectangle",
        Light::Element { .. } => "area sample",
    };
    format!("{kind} {i}")
}

/// The union of the bounds of the objects that do not move by themselves: what edits change
/// (keyframed objects move every frame without a new renderer).
pub fn edited_bounds(scene: &Scene) -> Aabb {
    scene
        .objects
        .iter()
        .filter(|o| !o.is_animated())
        .fold(Aabb::EMPTY, |b, o| b.union(o.aabb_at(0.0)))
}

impl super::Viewer {
    /// The scene's part of the window as the last frame drew it.
    pub(super) fn view_geom(&self) -> ViewGeom {
        ViewGeom {
            camera: self.scene.camera,
            rect_px: self.view_rect,
        }
    }

    /// Logs the selection and where its handles are (scripted tests click them).
    fn log_selection(&self) {
        let view = self.view_geom();
        let t = self.controls.time_s;
        match self.editor.selection {
            Some(Selection::Object(i)) => {
                if let Some(o) = self.scene.objects.get(i) {
                    let b = o.aabb_at(t);
                    log::info!(
                        "edit: selected object {i} \"{}\", bounds [{:.4}, {:.4}, {:.4}] - [{:.4}, {:.4}, {:.4}]; {}",
                        o.name,
                        b.min.x,
                        b.min.y,
                        b.min.z,
                        b.max.x,
                        b.max.y,
                        b.max.z,
                        self.editor.describe_handles(&self.scene, &view, t)
                    );
                }
            }
            Some(Selection::Light(i)) => {
                log::info!(
                    "edit: selected light {i} ({}); {}",
                    self.light_names.get(i).map_or("?", |n| n.as_str()),
                    self.editor.describe_handles(&self.scene, &view, t)
                );
            }
            None => log::info!("edit: selected nothing"),
        }
    }

    /// A press of the left mouse button over the scene (not taken by the panel).
    pub(super) fn edit_press(&mut self) {
        let Some((x, y)) = self.cursor else { return };
        let view = self.view_geom();
        let before = self.editor.selection;
        self.editor.press(
            [x as f32, y as f32],
            &self.scene,
            &view,
            self.controls.time_s,
        );
        if self.editor.selection != before {
            self.log_selection();
        }
    }

    /// The cursor moved: follows a drag.
    pub(super) fn edit_drag(&mut self) {
        let Some((x, y)) = self.cursor else { return };
        if !self.editor.dragging() {
            return;
        }
        let view = self.view_geom();
        if let Some(a) = self.editor.drag_to([x as f32, y as f32], &view) {
            self.apply_edit(a);
        }
    }

    pub(super) fn edit_release(&mut self) {
        if self.editor.release() {
            match self.editor.selection {
                Some(Selection::Object(i)) => {
                    if let Some(o) = self.scene.objects.get(i) {
                        let t = o.transform;
                        log::info!(
                            "edit: object {i} at translate {:?} rotate_deg {:?} scale {:?}",
                            t.translate.to_array(),
                            self.editor.rotate_deg(&self.scene, i).to_array(),
                            t.scale.to_array()
                        );
                    }
                }
                Some(Selection::Light(i)) => {
                    if let Some(l) = self.scene.lights.get(i) {
                        log::info!("edit: light {i} now {l:?}");
                    }
                }
                None => {}
            }
            self.log_selection();
        }
    }

    /// The GPU's answer to a click.
    pub(super) fn edit_picked(&mut self, p: Picked) {
        self.editor.picked(p);
        self.log_selection();
    }

    fn backup_lights(&mut self) {
        if self.light_backup.is_none() {
            self.light_backup = Some(LightBackup {
                base: self.base_lights.clone(),
                scale: self.controls.light_scale.clone(),
                names: self.light_names.clone(),
                origins: self.editor.light_origins.clone(),
                selection: self.editor.selection,
            });
        }
    }

    /// Puts the lights back as they were before the change a renderer could not be made for.
    pub(super) fn restore_lights(&mut self) {
        if let Some(b) = self.light_backup.take() {
            self.scene.lights = b.base.clone();
            self.base_lights = b.base;
            self.controls.light_scale = b.scale;
            self.light_names = b.names;
            self.editor.light_origins = b.origins;
            self.editor.select(b.selection);
        }
    }

    pub(super) fn light_change_done(&mut self) {
        self.light_backup = None;
    }

    /// Rechecks the lights after a change of their number or views; undoes it when a frame
    /// cannot hold them.
    fn check_light_change(&mut self, what: &str) -> bool {
        let settings = self.renderer.as_ref().map(|r| r.settings.clone());
        let ok = match settings.map(|s| crate::render::check_lights(&self.scene, &s)) {
            Some(Err(e)) => {
                self.editor.status = format!("{what} refused: {e}");
                log::warn!("{}", self.editor.status);
                self.restore_lights();
                false
            }
            _ => true,
        };
        if ok {
            self.light_names = self
                .base_lights
                .iter()
                .enumerate()
                .map(|(i, l)| light_name(i, l))
                .collect();
        }
        ok
    }

    /// Applies one edit to the scene (the renderer follows in the next frame).
    pub(super) fn apply_edit(&mut self, a: EditAction) {
        match a {
            EditAction::Select(s) => {
                self.editor.select(s);
                self.log_selection();
            }
            EditAction::Handle(m) => {
                self.editor.handle = m;
                self.log_selection();
            }
            EditAction::LightKind(k) => self.editor.new_light_kind = k,
            EditAction::Place(i, p) => {
                let Some(o) = self.scene.objects.get(i) else {
                    return;
                };
                if o.is_animated() {
                    return;
                }
                match self.editor.checked_placement(&self.scene, i, &p) {
                    Ok(t) => {
                        if let Some(o) = self.scene.objects.get_mut(i) {
                            o.transform = t;
                            o.dynamic = true;
                        }
                        self.editor.placed(i, p);
                        self.editor.status.clear();
                    }
                    Err(e) => self.editor.status = e,
                }
            }
            EditAction::SetLight(i, l) => {
                let shape_before = SceneShape::of(&self.scene);
                match self.editor.checked_light(&self.scene, i, &l) {
                    Ok(l) => {
                        self.backup_lights();
                        if let (Some(base), Some(s), Some(now)) = (
                            self.base_lights.get_mut(i),
                            self.controls.light_scale.get_mut(i),
                            self.scene.lights.get_mut(i),
                        ) {
                            *base = l;
                            *s = 1.0;
                            *now = l;
                        }
                        self.editor.status.clear();
                        if SceneShape::of(&self.scene).same_lights(&shape_before) {
                            self.light_backup = None;
                        } else {
                            self.check_light_change("the light's samples");
                        }
                    }
                    Err(e) => self.editor.status = e,
                }
            }
            EditAction::AddLight(k) => {
                self.editor.new_light_kind = k;
                let l = new_light(&self.scene, k, self.controls.time_s);
                let i = self.scene.lights.len();
                match self.editor.checked_light(&self.scene, i, &l) {
                    Ok(l) => {
                        self.backup_lights();
                        self.base_lights.push(l);
                        self.controls.light_scale.push(1.0);
                        self.scene.lights.push(l);
                        self.editor.light_added();
                        self.editor.select(Some(Selection::Light(i)));
                        if self.check_light_change("a new light") {
                            log::info!("edit: added light {i}: {l:?}");
                            self.log_selection();
                        }
                    }
                    Err(e) => self.editor.status = e,
                }
            }
            EditAction::RemoveLight(i) => {
                if i >= self.scene.lights.len() {
                    return;
                }
                self.backup_lights();
                self.base_lights.remove(i);
                self.controls.light_scale.remove(i);
                self.scene.lights.remove(i);
                self.editor.light_removed(i);
                if self.check_light_change("removing the light") {
                    log::info!("edit: removed light {i}");
                }
            }
            EditAction::Save => self.save_scene(),
        }
    }

    /// Writes the scene with its edits (Ctrl+S, the panel's button).
    pub(super) fn save_scene(&mut self) {
        let keys = self.report.camera_keys.clone();
        // The panel's frame settings, written into the scene's `[gi]`, `[post]` and `[shadow]`.
        let c = &self.controls;
        let settings = crate::scene::save::FrameTables {
            gi: c.gi,
            post: crate::scene::PostTable {
                post: c.post,
                tonemap: c.tonemap,
                dynres: c.dynres,
            },
            shadow: c.shadow,
        };
        match self
            .editor
            .save(&self.scene, &self.fly, &self.scene.camera, &keys, settings)
        {
            Ok(path) => {
                self.editor.status = format!("saved scene to {}", path.display());
                log::info!("{}", self.editor.status);
                self.report.saved.push(path);
            }
            Err(e) => {
                self.editor.status = e.to_string();
                log::warn!("{}", self.editor.status);
            }
        }
    }

    /// Whether the scene changed in a way the renderer was not made for (see [`SceneShape`]
    /// and `Renderer::can_move`): checked before each frame.
    pub(super) fn scene_needs_new_renderer(&self, editing: bool) -> bool {
        let (Some(r), Some(built)) = (&self.renderer, &self.scene_shape) else {
            return false;
        };
        let now = SceneShape::of(&self.scene);
        // Bounds are checked once no drag or field edit is in progress (one new renderer per
        // edit, not per frame of it).
        let bounds_changed = !editing && !now.same_bounds(built);
        let moves = self
            .scene
            .objects
            .iter()
            .enumerate()
            .any(|(i, o)| o.dynamic && !r.can_move(i));
        !now.same_lights(built) || bounds_changed || moves
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> (Scene, ViewGeom) {
        let s = crate::scene::builtin("cornell").expect("cornell");
        let v = ViewGeom {
            camera: s.camera,
            rect_px: [100.0, 0.0, 200.0, 150.0],
        };
        (s, v)
    }

    #[test]
    fn projection_and_ray_agree() {
        let (_, v) = view();
        let p = Vec3::new(0.2, 0.1, 0.3);
        let px = v.project(p).expect("in front");
        let (o, d) = v.ray(px);
        // The ray through p's pixel passes through p.
        let closest = o + d * (p - o).dot(d);
        assert!(closest.distance(p) < 1e-4, "{closest} vs {p}");
        assert_eq!(v.frame_pixel([99.0, 10.0]), None);
        assert_eq!(v.frame_pixel([100.5, 149.5]), Some((0, 149)));
    }

    #[test]
    fn dragging_the_x_handle_moves_along_x_only() {
        let (mut s, v) = view();
        let mut ed = Editor::new(&s, &FlyCamera::from_camera(&s.camera, 1.0), None, None);
        ed.select(Some(Selection::Object(2)));
        let handles = ed.handles(&s, &v, 0.0);
        let (_, _, _, tip) = handles[0];
        assert!(
            ed.press(tip, &s, &v, 0.0),
            "the x handle is grabbed at its tip"
        );
        let Some(EditAction::Place(2, p)) = ed.drag_to([tip[0] - 20.0, tip[1]], &v) else {
            panic!("a placement")
        };
        let t0 = s.objects[2].transform;
        let moved = p.translate.expect("a new translation") - t0.translate;
        // Only the key that changed is written: the file keeps the others.
        assert_eq!((p.rotate_deg, p.scale), (None, None));
        // The camera looks along +Z, so screen-left is world +X.
        assert!(moved.x > 0.0 && moved.y == 0.0 && moved.z == 0.0, "{moved}");
        s.objects[2].transform = ed.checked_placement(&s, 2, &p).expect("valid");
        assert!(ed.release());
    }

    #[test]
    fn rotating_and_scaling_keep_the_centre() {
        let (s, v) = view();
        let mut ed = Editor::new(&s, &FlyCamera::from_camera(&s.camera, 1.0), None, None);
        ed.select(Some(Selection::Object(2)));
        let center = s.objects[2].aabb_at(0.0).center();
        for mode in [HandleMode::Rotate, HandleMode::Scale] {
            ed.handle = mode;
            // The y handle: rotation about world Y, or scaling along the block's own y.
            let (_, _, _, tip) = ed.handles(&s, &v, 0.0)[1];
            assert!(ed.press(tip, &s, &v, 0.0));
            let Some(EditAction::Place(2, p)) = ed.drag_to([tip[0] + 15.0, tip[1] - 10.0], &v)
            else {
                panic!("{mode:?}: a placement")
            };
            ed.release();
            let t = ed.checked_placement(&s, 2, &p).expect("valid");
            let local = s.objects[2].local_aabb.center();
            let moved_center = t.translate + t.rotation * (t.scale * local);
            assert!(
                moved_center.distance(center) < 1e-4,
                "{mode:?}: centre {moved_center} vs {center}"
            );
            assert_ne!(t, s.objects[2].transform, "{mode:?} changed nothing");
        }
    }

    #[test]
    fn clicks_select_light_markers_or_ask_the_gpu() {
        let (s, v) = view();
        let mut ed = Editor::new(&s, &FlyCamera::from_camera(&s.camera, 1.0), None, None);
        let marker = v
            .project(s.lights[0].position().expect("spot"))
            .expect("visible");
        assert!(!ed.press(marker, &s, &v, 0.0));
        assert_eq!(ed.selection, Some(Selection::Light(0)));
        assert_eq!(ed.take_pick_request(), None);
        ed.select(None);
        assert!(!ed.press([200.0, 140.0], &s, &v, 0.0));
        assert_eq!(ed.take_pick_request(), Some((100, 140)));
        // Outside the scene (on the panel): nothing.
        assert!(!ed.press([50.0, 10.0], &s, &v, 0.0));
        assert_eq!(ed.take_pick_request(), None);
    }

    #[test]
    fn new_lights_pass_the_loaders_checks() {
        let (s, _) = view();
        let ed = Editor::new(&s, &FlyCamera::from_camera(&s.camera, 1.0), None, None);
        for k in 0..LIGHT_KINDS.len() {
            let l = new_light(&s, k, 0.0);
            let back = ed.checked_light(&s, 1, &l).expect("valid");
            assert!(back.is_point() || back.position() != Some(Vec3::ZERO));
        }
        // Point light: E at half the diagonal d is 2 W/m² (I = 2 d²).
        let Light::Point { intensity_w_sr, .. } = new_light(&s, 0, 0.0) else {
            panic!("a point light")
        };
        let d = 0.5 * s.aabb_at(0.0).extent().length();
        assert!((intensity_w_sr.x / (d * d) - 2.0).abs() < 1e-4);
    }
}
