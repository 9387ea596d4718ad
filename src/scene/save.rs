//! Writing edits back into a scene file: the viewer's moved objects, edited, added and removed
//! lights, camera, recorded camera path and frame settings (`[gi]`, `[post]`, `[shadow]`, by
//! their key tables), with everything else of the file kept as written
//! (other keys, comments, order, formatting: the text is edited with `toml_edit`, not
//! re-serialized).
//!
//! Values are written so that loading the file gives back exactly the scene the editor holds:
//! floats in their shortest round-trip form, positions in world coordinates (the scene's local
//! origin added in f64, as [`super::Camera::toml_table`] does). [`reload_light`] and
//! [`Placement::transform`] run a value through the very checks the loader runs: the editor
//! applies an edit only as the file will give it back, and refuses one the loader would refuse
//! with the loader's message.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use toml_edit::{value, Array, ArrayOfTables, DocumentMut, Item, Table, TableLike, Value};

use super::camera::Camera;
use super::camera_path::CameraPath;
use super::desc::{self, Check, LightDesc};
use super::light::Light;
use super::object::Transform;
use super::schema::Settings;
use super::{GiSettings, PostTable, SceneError, ShadowSettings};

/// Why a scene could not be saved. Each says what to do.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    #[error("cannot save: the scene `{0}` is built in and has no file; start the viewer with `--save PATH` to write it to PATH")]
    NoFile(String),
    #[error("cannot save into {}: {reason}; fix the file or save elsewhere with `--save PATH`", file.display())]
    Syntax { file: PathBuf, reason: String },
    #[error("cannot save into {}: it has {found} `[[{table}]]` entries but the scene loaded {expected}; the file changed since it was loaded, save elsewhere with `--save PATH`", file.display())]
    Mismatch {
        file: PathBuf,
        table: &'static str,
        found: usize,
        expected: usize,
    },
    #[error("cannot write {}: {reason}; check that the folder exists and is writable", path.display())]
    Write { path: PathBuf, reason: String },
    /// An edited value the loader refuses (the editor checks each edit, so this means a bug).
    #[error(transparent)]
    Scene(#[from] SceneError),
}

/// What became of one of the scene's lights.
#[derive(Clone, Debug, PartialEq)]
pub enum LightEdit {
    /// The `[[lights]]` table at this index, unchanged.
    Keep(usize),
    /// The table at this index, with the light's keys set to these values (its comments and
    /// position in the file kept).
    Changed(usize, Light),
    /// A new table at the end.
    Added(Light),
}

/// Edits to write into a scene file (see [`apply_edits`]).
#[derive(Clone, Debug, Default)]
pub struct SceneEdits {
    /// The scene's local origin ([`super::Scene::origin_m`]), added back to every position.
    pub origin_m: DVec3,
    /// Per `[[objects]]` table: the transform keys to set (an empty placement leaves it).
    pub transforms: Vec<Placement>,
    /// The lights in their new order, `None` to leave the `[[lights]]` tables as written.
    pub lights: Option<Vec<LightEdit>>,
    /// The camera to write into `[camera]` (position, `forward`, up; `target` goes), `None`
    /// to leave it.
    pub camera: Option<Camera>,
    /// A recorded flight replacing `[camera_path]`.
    pub camera_path: Option<CameraPath>,
    /// The folder relative `mesh` and `obj_sequence` paths were resolved against, when the
    /// file is saved into another folder: they are written as absolute paths then.
    pub relocate_from: Option<PathBuf>,
    /// The frame settings to write into `[gi]`, `[post]` and `[shadow]`, `None` to leave them.
    pub settings: Option<FrameTables>,
}

/// The settings of a frame's `[gi]`, `[post]` and `[shadow]` tables, as a save writes them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTables {
    pub gi: GiSettings,
    pub post: PostTable,
    pub shadow: ShadowSettings,
}

/// Writes `s` into the table `S::TABLE` of `doc` key by key, so that the file loads back as
/// `s`: a key the file gives is set where its value differs (keeping its place and comment;
/// an unset value removes it), a key it leaves out is added where `s` differs from the
/// default. A table without keys is not added.
fn write_settings<S: Settings>(doc: &mut DocumentMut, s: &S, file: &Path) -> Result<(), SaveError> {
    let default = S::default();
    let existed = doc.contains_key(S::TABLE);
    let table = doc
        .entry(S::TABLE)
        .or_insert_with(|| Item::Table(Table::new()))
        .as_table_like_mut()
        .ok_or_else(|| SaveError::Syntax {
            file: file.to_path_buf(),
            reason: format!("its `{}` is not a table", S::TABLE),
        })?;
    for k in S::keys() {
        let v = (k.get)(s);
        // The value as the file writes it, read as the loader reads it.
        let written = table.get(k.name()).and_then(Item::as_value).map(|old| {
            let mut old = old.clone();
            old.decor_mut().clear();
            toml::from_str::<toml::Table>(&format!("v = {old}"))
                .ok()
                .and_then(|t| t.get("v").cloned())
        });
        let same = match &written {
            Some(Some(old)) => k.kind.from_toml(k.path, old).ok() == Some(v),
            Some(None) => false,
            None => v == (k.get)(&default),
        };
        if same {
            continue;
        }
        match k.kind.to_toml(v) {
            None => {
                table.remove(k.name());
            }
            Some(t) => {
                let text = t.to_string();
                let value = text.parse::<Value>().map_err(|e| SaveError::Syntax {
                    file: file.to_path_buf(),
                    reason: format!("`{}` = {text}: {e}", k.path),
                })?;
                set(table, k.name(), value);
            }
        }
    }
    if table.is_empty() && !existed {
        doc.remove(S::TABLE);
    }
    Ok(())
}

/// A float as the shortest decimal that reads back as the same f32 (-0 as 0).
fn float(x: f32) -> f64 {
    let x = if x == 0.0 { 0.0 } else { x };
    format!("{x:?}").parse().unwrap_or(f64::from(x))
}

fn array(v: impl IntoIterator<Item = f64>) -> Value {
    Value::Array(v.into_iter().collect::<Array>())
}

fn vec3_value(v: Vec3) -> Value {
    array(v.to_array().map(float))
}

/// A local position in world coordinates (the loader subtracts `origin` in f64 and rounds to
/// f32, which gives the local f32 back exactly).
fn point_value(origin: DVec3, v: Vec3) -> Value {
    let c = |o: f64, l: f32| o + float(l);
    array([c(origin.x, v.x), c(origin.y, v.y), c(origin.z, v.z)])
}

/// The keys of `light`'s `[[lights]]` table, in the order the scene format lists them; `None`
/// for a sample of an area light (never part of a scene).
pub fn light_keys(light: &Light, origin: DVec3) -> Option<Vec<(&'static str, Value)>> {
    let kind = |k: &str| ("kind", Value::from(k));
    Some(match *light {
        Light::Point {
            position,
            intensity_w_sr,
        } => vec![
            kind("point"),
            ("position", point_value(origin, position)),
            ("intensity_w_sr", vec3_value(intensity_w_sr)),
        ],
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => vec![
            kind("spot"),
            ("position", point_value(origin, position)),
            ("direction", vec3_value(direction)),
            ("intensity_w_sr", vec3_value(intensity_w_sr)),
            ("cutoff_deg", Value::from(float(cutoff_deg))),
            ("beam_deg", Value::from(float(beam_deg))),
        ],
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => vec![
            kind("directional"),
            ("direction", vec3_value(direction)),
            ("irradiance_w_m2", vec3_value(irradiance_w_m2)),
        ],
        Light::Sphere {
            position,
            radius_m,
            radiance_w_sr_m2,
            samples,
        } => vec![
            kind("sphere"),
            ("position", point_value(origin, position)),
            ("radiance_w_sr_m2", vec3_value(radiance_w_sr_m2)),
            ("radius_m", Value::from(float(radius_m))),
            ("samples", Value::from(i64::from(samples))),
        ],
        Light::Rectangle {
            position,
            normal,
            width_axis,
            width_m,
            height_m,
            radiance_w_sr_m2,
            samples,
        } => vec![
            kind("rectangle"),
            ("position", point_value(origin, position)),
            ("radiance_w_sr_m2", vec3_value(radiance_w_sr_m2)),
            ("normal", vec3_value(normal)),
            ("width_m", Value::from(float(width_m))),
            ("height_m", Value::from(float(height_m))),
            ("width_axis", vec3_value(width_axis)),
            ("samples", Value::from(i64::from(samples))),
        ],
        Light::Element { .. } => return None,
    })
}

/// `light` as a new `[[lights]]` table.
fn light_table(light: &Light, origin: DVec3) -> Option<Table> {
    let mut t = Table::new();
    for (k, v) in light_keys(light, origin)? {
        t.insert(k, value(v));
    }
    Some(t)
}

/// `light` as the scene file gives it back: its table read through the loader's checks.
/// `file` and `field` (e.g. `lights[2]`) name it in an error, which is the loader's.
pub fn reload_light(
    light: &Light,
    origin: DVec3,
    file: &Path,
    field: &str,
) -> Result<Light, SceneError> {
    let invalid = |problem: &str| SceneError::InvalidValue {
        file: file.to_path_buf(),
        field: field.to_string(),
        problem: problem.to_string(),
    };
    let table = light_table(light, origin)
        .ok_or_else(|| invalid("an area light's sample is not a scene light"))?;
    let mut doc = DocumentMut::new();
    for (k, v) in table.iter() {
        doc.insert(k, v.clone());
    }
    let text = doc.to_string();
    let d: LightDesc = toml::from_str(&text).map_err(|e| invalid(e.message()))?;
    desc::build_light(&Check { file, origin }, field, &d)
}

/// The transform keys of an `[[objects]]` table the editor changed; `None` keeps the key as
/// the file has it (so an object only moved keeps its stated rotation to the last bit). The
/// rotation is kept as its `rotate_deg` Euler angles, which the editor's fields show and the
/// file stores: a rotation's Euler angles computed back need not give the same quaternion to
/// the last bit, stated angles do.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Placement {
    pub translate: Option<Vec3>,
    /// About X first, then Y, then Z (world axes), degrees.
    pub rotate_deg: Option<Vec3>,
    pub scale: Option<Vec3>,
}

impl Placement {
    /// Whether it changes nothing.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// The keys it sets.
    pub fn keys(&self, origin: DVec3) -> Vec<(&'static str, Value)> {
        let mut out = Vec::new();
        if let Some(t) = self.translate {
            out.push(("translate", point_value(origin, t)));
        }
        if let Some(r) = self.rotate_deg {
            out.push(("rotate_deg", vec3_value(r)));
        }
        if let Some(s) = self.scale {
            let v = if s.x == s.y && s.y == s.z {
                Value::from(float(s.x))
            } else {
                vec3_value(s)
            };
            out.push(("scale", v));
        }
        out
    }

    /// The transform the scene file gives with [`Self::keys`] set over `base` (the object's
    /// transform as loaded), through the loader's checks (`file` and `field`, e.g.
    /// `objects[2]`, name a refused value): what the editor shows is what the saved file
    /// renders.
    pub fn transform(
        &self,
        base: &Transform,
        origin: DVec3,
        file: &Path,
        field: &str,
    ) -> Result<Transform, SceneError> {
        let f3 = |v: &Value| -> [f64; 3] {
            let mut out = [f64::NAN; 3];
            if let Some(a) = v.as_array() {
                for (o, x) in out.iter_mut().zip(a.iter()) {
                    *o = x.as_float().unwrap_or(f64::NAN);
                }
            }
            out
        };
        let (mut translate, mut rotate, mut scale) = (None, None, None);
        for (k, v) in self.keys(origin) {
            match k {
                "translate" => translate = Some(f3(&v)),
                "rotate_deg" => rotate = Some(f3(&v).map(|x| x as f32)),
                _ => {
                    scale = Some(match v.as_float() {
                        Some(s) => desc::ScalarOrVec3::Scalar(s as f32),
                        None => desc::ScalarOrVec3::Vec3(f3(&v).map(|x| x as f32)),
                    })
                }
            }
        }
        desc::build_transform(
            &Check { file, origin },
            field,
            translate,
            rotate,
            scale,
            base,
        )
    }
}

/// The entries of an array of tables (`[[name]]`) or of an inline array of tables
/// (`name = [{…}]`), for editing in place; empty without the key.
fn entries<'a>(doc: &'a mut DocumentMut, name: &str) -> Vec<&'a mut dyn TableLike> {
    match doc.get_mut(name) {
        Some(Item::ArrayOfTables(a)) => a.iter_mut().map(|t| t as &mut dyn TableLike).collect(),
        Some(Item::Value(Value::Array(a))) => a
            .iter_mut()
            .filter_map(|v| v.as_inline_table_mut())
            .map(|t| t as &mut dyn TableLike)
            .collect(),
        _ => Vec::new(),
    }
}

/// The entries as owned tables (an inline table becomes a `[[name]]` table).
fn owned_entries(doc: &DocumentMut, name: &str) -> Vec<Table> {
    match doc.get(name) {
        Some(Item::ArrayOfTables(a)) => a.iter().cloned().collect(),
        Some(Item::Value(Value::Array(a))) => a
            .iter()
            .filter_map(|v| v.as_inline_table())
            .map(|t| t.clone().into_table())
            .collect(),
        _ => Vec::new(),
    }
}

fn set(t: &mut dyn TableLike, key: &str, v: Value) {
    match t.get_mut(key) {
        // Keeps the key's place and the comment after it.
        Some(Item::Value(old)) => {
            let decor = old.decor().clone();
            *old = v;
            *old.decor_mut() = decor;
        }
        _ => {
            t.insert(key, value(v));
        }
    }
}

fn absolute(dir: &Path, relative: &str) -> String {
    let p = dir.join(relative);
    let p = if p.is_absolute() {
        p
    } else {
        std::env::current_dir().map(|c| c.join(&p)).unwrap_or(p)
    };
    p.to_string_lossy().into_owned()
}

/// `text` (the scene file `file` as written) with `edits` applied. Untouched tables keep their
/// text byte for byte.
pub fn apply_edits(text: &str, file: &Path, edits: &SceneEdits) -> Result<String, SaveError> {
    let mut doc: DocumentMut =
        text.parse()
            .map_err(|e: toml_edit::TomlError| SaveError::Syntax {
                file: file.to_path_buf(),
                reason: e.to_string().trim().replace('\n', " "),
            })?;
    let origin = edits.origin_m;
    let mut objects = entries(&mut doc, "objects");
    if objects.len() != edits.transforms.len() {
        return Err(SaveError::Mismatch {
            file: file.to_path_buf(),
            table: "objects",
            found: objects.len(),
            expected: edits.transforms.len(),
        });
    }
    for (t, edit) in objects.iter_mut().zip(&edits.transforms) {
        for (k, v) in edit.keys(origin) {
            set(*t, k, v);
        }
        if let Some(dir) = &edits.relocate_from {
            if let Some(m) = t.get("mesh").and_then(Item::as_str).map(str::to_owned) {
                set(*t, "mesh", Value::from(absolute(dir, &m)));
            }
            let seq = t
                .get_mut("animation")
                .and_then(Item::as_table_like_mut)
                .filter(|a| a.contains_key("obj_sequence"));
            if let Some(a) = seq {
                if let Some(s) = a
                    .get("obj_sequence")
                    .and_then(Item::as_str)
                    .map(str::to_owned)
                {
                    set(a, "obj_sequence", Value::from(absolute(dir, &s)));
                }
            }
        }
    }
    if let Some(lights) = &edits.lights {
        let old = owned_entries(&doc, "lights");
        let mut out = ArrayOfTables::new();
        for edit in lights {
            let (index, light) = match edit {
                LightEdit::Keep(i) => (Some(*i), None),
                LightEdit::Changed(i, l) => (Some(*i), Some(l)),
                LightEdit::Added(l) => (None, Some(l)),
            };
            let mut table = match index {
                Some(i) => old.get(i).cloned().ok_or(SaveError::Mismatch {
                    file: file.to_path_buf(),
                    table: "lights",
                    found: old.len(),
                    expected: i + 1,
                })?,
                None => Table::new(),
            };
            if let Some(l) = light {
                let keys = light_keys(l, origin).ok_or_else(|| SceneError::InvalidValue {
                    file: file.to_path_buf(),
                    field: "lights".into(),
                    problem: "an area light's sample is not a scene light".into(),
                })?;
                // Another kind's keys would be refused on load.
                let own: Vec<&str> = keys.iter().map(|(k, _)| *k).collect();
                let stale: Vec<String> = table
                    .iter()
                    .map(|(k, _)| k.to_string())
                    .filter(|k| !own.contains(&k.as_str()))
                    .collect();
                for k in stale {
                    table.remove(&k);
                }
                for (k, v) in keys {
                    set(&mut table, k, v);
                }
            }
            out.push(table);
        }
        if out.is_empty() {
            doc.remove("lights");
        } else {
            doc.insert("lights", Item::ArrayOfTables(out));
        }
    }
    if let Some(c) = &edits.camera {
        let cam = doc
            .get_mut("camera")
            .and_then(Item::as_table_like_mut)
            .ok_or_else(|| SaveError::Syntax {
                file: file.to_path_buf(),
                reason: "it has no [camera] table".into(),
            })?;
        cam.remove("target");
        set(cam, "position", point_value(origin, c.position));
        set(cam, "forward", vec3_value(c.forward));
        set(cam, "up", vec3_value(c.up));
    }
    if let Some(path) = &edits.camera_path {
        let table: DocumentMut =
            path.toml_table(origin)
                .parse()
                .map_err(|e: toml_edit::TomlError| SaveError::Syntax {
                    file: file.to_path_buf(),
                    reason: format!("the recorded camera path: {e}"),
                })?;
        if let Some(item) = table.get("camera_path") {
            doc.insert("camera_path", item.clone());
        }
    }
    if let Some(t) = &edits.settings {
        write_settings(&mut doc, &t.gi, file)?;
        write_settings(&mut doc, &t.post, file)?;
        write_settings(&mut doc, &t.shadow, file)?;
    }
    Ok(doc.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{builtin, Scene};

    const FILE: &str = "edited.toml";

    fn load(text: &str) -> Scene {
        Scene::from_toml_str(text, Path::new(FILE), Path::new("."))
            .unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    fn cornell_text() -> &'static str {
        include_str!("../../assets/scenes/cornell.toml")
    }

    fn keep_all(s: &Scene) -> SceneEdits {
        SceneEdits {
            origin_m: s.origin_m,
            transforms: vec![Placement::default(); s.objects.len()],
            ..Default::default()
        }
    }

    #[test]
    fn no_edits_keep_the_file_byte_for_byte() {
        let s = load(cornell_text());
        let mut e = keep_all(&s);
        e.lights = Some(vec![LightEdit::Keep(0)]);
        assert_eq!(
            apply_edits(cornell_text(), Path::new(FILE), &e).expect("saves"),
            cornell_text()
        );
    }

    #[test]
    fn a_moved_rotated_scaled_object_loads_back_exactly_and_comments_stay() {
        let s = load(cornell_text());
        let p = Placement {
            translate: Some(s.objects[2].transform.translate + Vec3::new(0.05, 0.0, -0.03)),
            rotate_deg: Some(Vec3::new(10.0, 33.3, -5.0)),
            scale: Some(Vec3::new(1.0, 0.75, 1.0)),
        };
        let t = p
            .transform(
                &s.objects[2].transform,
                s.origin_m,
                Path::new(FILE),
                "objects[2]",
            )
            .expect("valid");
        let mut e = keep_all(&s);
        e.transforms[2] = p;
        let text = apply_edits(cornell_text(), Path::new(FILE), &e).expect("saves");
        let back = load(&text);
        assert_eq!(back.objects[2].transform, t, "{text}");
        assert_eq!(back.objects[..2], s.objects[..2]);
        assert!(
            text.contains("# Floor, ceiling and back wall white"),
            "{text}"
        );
        assert!(text.contains("rotate_deg = ["), "{text}");
    }

    #[test]
    fn a_placement_loads_back_exactly_far_from_the_origin() {
        // Far out the loader subtracts the origin in f64: the local f32 values come back.
        let text = "[camera]\nposition = [512, 1, -260]\ntarget = [512, 1, -256]\n\
                    fov_y_deg = 40\n[[objects]]\nbuiltin = \"cube\"\n\
                    translate = [512, 0, -256]\nrotate_deg = [0.0, 33.3, 0.0] # turned\n";
        let s = load(text);
        assert_eq!(s.origin_m, DVec3::new(512.0, 0.0, -256.0));
        let base = s.objects[0].transform;
        // Only moved: the stated rotation stays as written, and so does its comment.
        let p = Placement {
            translate: Some(Vec3::new(0.1, -3.25, 7.0)),
            ..Default::default()
        };
        let t = p
            .transform(&base, s.origin_m, Path::new(FILE), "o")
            .expect("valid");
        assert_eq!(
            (t.translate, t.rotation),
            (Vec3::new(0.1, -3.25, 7.0), base.rotation)
        );
        let mut e = keep_all(&s);
        e.transforms[0] = p;
        let out = apply_edits(text, Path::new(FILE), &e).expect("saves");
        assert_eq!(load(&out).objects[0].transform, t, "{out}");
        assert!(out.contains("translate = [512.1, -3.25, -249.0]"), "{out}");
        assert!(
            out.contains("rotate_deg = [0.0, 33.3, 0.0] # turned"),
            "{out}"
        );
        // Stated Euler angles reload to the same rotation, and give R = Rz·Ry·Rx back.
        let turned = Placement {
            rotate_deg: Some(crate::scene::euler_xyz_deg(
                crate::scene::rotation_from_euler_xyz_deg(Vec3::new(30.0, 45.0, 10.0)),
            )),
            ..p
        };
        let t = turned
            .transform(&base, s.origin_m, Path::new(FILE), "o")
            .expect("valid");
        e.transforms[0] = turned;
        let out = apply_edits(text, Path::new(FILE), &e).expect("saves");
        assert_eq!(load(&out).objects[0].transform, t, "{out}");
        let want = crate::scene::rotation_from_euler_xyz_deg(Vec3::new(30.0, 45.0, 10.0));
        assert!(t.rotation.angle_between(want) < 1e-3);
    }

    #[test]
    fn lights_are_edited_added_and_removed_keeping_the_others() {
        let text = format!(
            "{}\n# the fill light\n[[lights]]\nkind = \"point\"  # small\nposition = [0.1, 0.4, 0.2]\nintensity_w_sr = 0.25\n",
            cornell_text()
        );
        let s = load(&text);
        assert_eq!(s.lights.len(), 2);
        let moved = match s.lights[1] {
            Light::Point { intensity_w_sr, .. } => Light::Point {
                position: Vec3::new(0.3, 0.45, 0.25),
                intensity_w_sr,
            },
            other => panic!("{other:?}"),
        };
        let added = Light::Rectangle {
            position: Vec3::new(0.278, 0.54, 0.28),
            normal: Vec3::NEG_Y,
            width_axis: Vec3::X,
            width_m: 0.1,
            height_m: 0.2,
            radiance_w_sr_m2: Vec3::new(4.0, 3.5, 3.0),
            samples: 4,
        };
        let mut e = keep_all(&s);
        // The spot goes; the point light moves; a rectangle light comes.
        e.lights = Some(vec![LightEdit::Changed(1, moved), LightEdit::Added(added)]);
        let out = apply_edits(&text, Path::new(FILE), &e).expect("saves");
        let back = load(&out);
        assert_eq!(back.lights, vec![moved, added], "{out}");
        assert!(
            out.contains("# the fill light") && out.contains("# small"),
            "{out}"
        );
        // Every light removed: the table goes.
        e.lights = Some(Vec::new());
        let none = apply_edits(&text, Path::new(FILE), &e).expect("saves");
        assert!(!none.contains("[[lights]]"), "{none}");
    }

    #[test]
    fn every_light_kind_reloads_as_itself() {
        let origin = DVec3::new(0.0, 256.0, 0.0);
        let lights = [
            Light::Point {
                position: Vec3::new(0.1, 0.2, 0.3),
                intensity_w_sr: Vec3::new(1.0, 0.5, 0.25),
            },
            Light::Spot {
                position: Vec3::new(0.1, 0.2, 0.3),
                direction: Vec3::new(0.0, -1.0, 0.0),
                intensity_w_sr: Vec3::ONE,
                cutoff_deg: 35.0,
                beam_deg: 12.5,
            },
            Light::Directional {
                direction: Vec3::new(0.6, -0.8, 0.0),
                irradiance_w_m2: Vec3::splat(2.0),
            },
            Light::Sphere {
                position: Vec3::new(-1.0, 2.0, 0.5),
                radius_m: 0.05,
                radiance_w_sr_m2: Vec3::splat(10.0),
                samples: 8,
            },
        ];
        for l in lights {
            let back = reload_light(&l, origin, Path::new(FILE), "lights[0]").expect("valid");
            assert_eq!(back, l);
        }
        // A value the loader refuses is refused with its message, naming the field.
        let bad = Light::Spot {
            position: Vec3::ZERO,
            direction: Vec3::NEG_Y,
            intensity_w_sr: Vec3::ONE,
            cutoff_deg: 95.0,
            beam_deg: 10.0,
        };
        let err = reload_light(&bad, origin, Path::new(FILE), "lights[3]")
            .expect_err("cutoff beyond 90")
            .to_string();
        assert!(err.contains("lights[3].cutoff_deg"), "{err}");
    }

    #[test]
    fn the_camera_and_a_recorded_path_are_written_in_world_coordinates() {
        let s = load(cornell_text());
        let mut cam = s.camera;
        cam.position = Vec3::new(0.3, 0.2, -0.5);
        cam.forward = Vec3::new(0.0, 0.6, 0.8);
        let path = CameraPath::through_cameras(&[s.camera, cam], 2.0).expect("a path");
        let mut e = keep_all(&s);
        e.camera = Some(cam);
        e.camera_path = Some(path.clone());
        let out = apply_edits(cornell_text(), Path::new(FILE), &e).expect("saves");
        let back = load(&out);
        assert_eq!(back.camera.position, cam.position);
        assert!(back.camera.forward.distance(cam.forward) < 1e-6);
        assert!(!out.contains("target ="), "{out}");
        assert_eq!(back.camera_path.map(|p| p.keys().len()), Some(2));
    }

    #[test]
    fn a_file_that_changed_since_loading_is_not_overwritten() {
        let s = builtin("cornell").expect("cornell");
        let mut e = keep_all(&s);
        e.transforms.push(Placement::default());
        let err = apply_edits(cornell_text(), Path::new(FILE), &e).expect_err("4 vs 3");
        assert!(err.to_string().contains("3 `[[objects]]`"), "{err}");
        let err = apply_edits("[camera", Path::new(FILE), &e).expect_err("syntax");
        assert!(err.to_string().contains(FILE), "{err}");
    }

    /// The frame's `[gi]`, `[post]` and `[shadow]` settings as `load` gives them.
    fn frame_tables(s: &Scene) -> FrameTables {
        use crate::scene::schema::resolve;
        FrameTables {
            gi: resolve(&[&s.gi]),
            post: resolve(&[&s.post]),
            shadow: resolve(&[&s.shadow]),
        }
    }

    #[test]
    fn frame_settings_are_written_into_gi_post_and_shadow_and_load_back() {
        use crate::scene::{AutoExposure, Bounces, GiMethod, SaoSettings, TaaSettings};
        let text = format!("{}\n[gi]\nrays = 4 # few\nradius_m = 2\n", cornell_text());
        let s = load(&text);
        let mut t = frame_tables(&s);
        assert_eq!(t.gi.rays, 4);
        t.gi.method = GiMethod::Pathtrace;
        t.gi.rays = 8;
        t.gi.radius_m = None;
        t.gi.bounces = Bounces::Unbounded;
        t.gi.vpl.pattern = [2, 3];
        t.gi.sao = Some(SaoSettings {
            taps: 8,
            ..Default::default()
        });
        t.post.post.taa = Some(TaaSettings {
            frames: 4,
            ..Default::default()
        });
        t.post.post.auto_exposure = Some(AutoExposure {
            key: 0.3,
            adaptation: 0.1,
        });
        t.post.post.bloom = Some(0.3);
        t.post.tonemap.operator = crate::scene::ToneOperator::Drago;
        t.post.tonemap.exposure = 0.1;
        t.shadow.auto_resolution = true;
        t.shadow.cascades = 2;
        t.shadow.area_samples = Some(4);
        t.shadow.bias_texels = 0.3;
        let mut e = keep_all(&s);
        e.settings = Some(t);
        let out = apply_edits(&text, Path::new(FILE), &e).expect("saves");
        let back = load(&out);
        assert_eq!(frame_tables(&back), t, "{out}");
        // A key set again keeps its comment; an unset value leaves the file.
        assert!(out.contains("rays = 8 # few"), "{out}");
        assert!(!out.contains("radius_m"), "{out}");
        assert!(out.contains("[post]") && out.contains("[shadow]"), "{out}");
        // Saving the same settings again changes nothing.
        let mut again = keep_all(&back);
        again.settings = Some(t);
        assert_eq!(
            apply_edits(&out, Path::new(FILE), &again).expect("saves"),
            out
        );
    }

    /// Every key of every table, set to a value other than the file's, is written and loads
    /// back (a new row is covered without an edit here); the defaults write nothing.
    #[test]
    fn every_frame_key_saves_and_loads_back() {
        use crate::scene::schema::{other_value, Settings};
        fn each<S: Settings>(table: fn(&mut FrameTables) -> &mut S) {
            let s = load(cornell_text());
            let base = frame_tables(&s);
            for k in S::keys() {
                let mut t = base;
                let v = other_value(k, table(&mut t));
                (k.set)(table(&mut t), v);
                let mut e = keep_all(&s);
                e.settings = Some(t);
                let out = apply_edits(cornell_text(), Path::new(FILE), &e).expect("saves");
                assert_eq!(frame_tables(&load(&out)), t, "{}: {out}", k.path);
            }
            let mut e = keep_all(&s);
            e.settings = Some(base);
            let out = apply_edits(cornell_text(), Path::new(FILE), &e).expect("saves");
            assert_eq!(out, cornell_text());
        }
        each::<GiSettings>(|t| &mut t.gi);
        each::<PostTable>(|t| &mut t.post);
        each::<ShadowSettings>(|t| &mut t.shadow);
    }

    #[test]
    fn relative_mesh_paths_become_absolute_when_saving_elsewhere() {
        let text = "[camera]\nposition = [0, 0, -1]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                    [[objects]]\nmesh = \"meshes/a.obj\"\n";
        let e = SceneEdits {
            transforms: vec![Placement::default()],
            relocate_from: Some(PathBuf::from("/data/scenes")),
            ..Default::default()
        };
        let out = apply_edits(text, Path::new(FILE), &e).expect("saves");
        assert!(
            out.contains("mesh = \"/data/scenes/meshes/a.obj\""),
            "{out}"
        );
    }
}
