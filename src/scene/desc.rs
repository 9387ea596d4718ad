//! The scene file as written (serde types) and its validation into a [`Scene`].

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use serde::Deserialize;

use super::camera::{Camera, Projection, DEFAULT_ORTHO_FOV_Y_DEG};
use super::camera_path::{CameraKey, CameraPath};
use super::environment::Environment;
use super::error::{field_ref, from_toml_error, SceneError};
use super::gi_settings::GiSettings;
use super::gltf::{is_gltf_path, GltfAsset};
use super::light::Light;
use super::mesh::{Aabb, BUILTIN_MESH_NAMES};
use super::obj::AssetStore;
use super::object::{rotation_from_euler_xyz_deg, Animation, Keyframe, Object, Transform};
use super::schema::{Layer, RawTable, Settings, TomlValueError};
use super::Scene;
use crate::limits;

/// A number or three numbers (`scale = 2` or `scale = [1, 2, 1]`; `albedo = 0.5`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(untagged, expecting = "expected a number or an array of 3 numbers")]
pub(crate) enum ScalarOrVec3 {
    Scalar(f32),
    Vec3([f32; 3]),
}

impl ScalarOrVec3 {
    fn to_array(self) -> [f32; 3] {
        match self {
            ScalarOrVec3::Scalar(s) => [s; 3],
            ScalarOrVec3::Vec3(v) => v,
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneDesc {
    /// Optional when an object's glTF file has a camera (the first one is used).
    pub camera: Option<CameraDesc>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    pub voxel: Option<RawTable<super::VoxelSettings>>,
    pub gi: Option<RawTable<GiSettings>>,
    pub shadow: Option<RawTable<super::ShadowSettings>>,
    pub post: Option<RawTable<super::PostTable>>,
    pub camera_path: Option<CameraPathDesc>,
    /// "oit" or "hashed" ([`super::Transparency`]).
    pub transparency: Option<String>,
    pub environment: Option<EnvironmentDesc>,
}

/// The `[environment]` table, checked by [`build_environment`].
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EnvironmentDesc {
    /// "constant", "map" or "sky" ([`super::environment::ENVIRONMENT_KINDS`]).
    pub kind: String,
    pub radiance: Option<ScalarOrVec3>,
    pub file: Option<String>,
    pub rotation_deg: Option<f32>,
    pub scale: Option<f32>,
    pub turbidity: Option<f32>,
    pub ground_albedo: Option<ScalarOrVec3>,
}

/// The `[camera_path]` table, checked by [`build_camera_path`].
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraPathDesc {
    pub up: Option<[f32; 3]>,
    pub keyframes: Vec<CameraKeyDesc>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraKeyDesc {
    pub time_s: f32,
    pub position: [f64; 3],
    pub look_at: Option<[f64; 3]>,
    pub direction: Option<[f32; 3]>,
    pub fov_y_deg: Option<f32>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraDesc {
    pub position: [f64; 3],
    pub target: Option<[f64; 3]>,
    pub forward: Option<[f32; 3]>,
    pub up: Option<[f32; 3]>,
    /// Required under perspective projection; under orthographic projection the viewer's
    /// switch back to perspective uses it (default [`DEFAULT_ORTHO_FOV_Y_DEG`]).
    pub fov_y_deg: Option<f32>,
    /// `"perspective"` (default) or `"orthographic"`.
    pub projection: Option<String>,
    /// The orthographic view's height in meters; required with `projection = "orthographic"`.
    pub ortho_height_m: Option<f32>,
    pub near: Option<f32>,
    pub far: Option<f32>,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(crate) enum LightKind {
    #[default]
    Point,
    Spot,
    Directional,
    Sphere,
    Rectangle,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightDesc {
    pub kind: LightKind,
    pub position: Option<[f64; 3]>,
    pub direction: Option<[f32; 3]>,
    pub intensity_w_sr: Option<ScalarOrVec3>,
    pub irradiance_w_m2: Option<ScalarOrVec3>,
    pub cutoff_deg: Option<f32>,
    pub beam_deg: Option<f32>,
    /// Area lights (`sphere`, `rectangle`): emitted radiance, W/(m²·sr).
    pub radiance_w_sr_m2: Option<ScalarOrVec3>,
    pub radius_m: Option<f32>,
    /// Rectangle: the emitting side, and the direction of its width edges.
    pub normal: Option<[f32; 3]>,
    pub width_axis: Option<[f32; 3]>,
    pub width_m: Option<f32>,
    pub height_m: Option<f32>,
    /// Sub-lights an area light is rendered with (`limits::AREA_SAMPLES`).
    pub samples: Option<i64>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObjectDesc {
    pub name: Option<String>,
    pub mesh: Option<String>,
    pub builtin: Option<String>,
    /// OBJ files without normals: faces meeting at more than this (degrees) stay sharp.
    pub crease_deg: Option<f32>,
    pub translate: Option<[f64; 3]>,
    pub rotate_deg: Option<[f32; 3]>,
    pub scale: Option<ScalarOrVec3>,
    pub material: Option<MaterialDesc>,
    pub dynamic: Option<bool>,
    pub animation: Option<AnimationDesc>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MaterialDesc {
    pub albedo: Option<ScalarOrVec3>,
    pub specular: Option<ScalarOrVec3>,
    pub shininess: Option<f32>,
    pub opacity: Option<f32>,
    /// GGX perceptual roughness in [0, 1] (α = roughness²); makes the material GGX.
    pub roughness: Option<f32>,
    /// GGX metalness in [0, 1]; makes the material GGX.
    pub metallic: Option<f32>,
    /// Emitted radiance, W/(m²·sr), >= 0.
    pub emission_w_sr_m2: Option<ScalarOrVec3>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AnimationDesc {
    pub keyframes: Option<Vec<KeyframeDesc>>,
    #[serde(rename = "loop")]
    pub looping: Option<bool>,
    pub obj_sequence: Option<String>,
    pub frames: Option<u32>,
    pub fps: Option<f32>,
    pub first_frame: Option<u32>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct KeyframeDesc {
    pub time_s: f32,
    pub translate: Option<[f64; 3]>,
    pub rotate_deg: Option<[f32; 3]>,
    pub scale: Option<ScalarOrVec3>,
}

/// Parses scene TOML; `file` is only used in messages.
pub(crate) fn parse(text: &str, file: &Path) -> Result<SceneDesc, SceneError> {
    // Parse as plain TOML first so syntax errors and schema errors get distinct variants.
    if let Err(e) = text.parse::<toml::Table>() {
        return Err(from_toml_error(file, text, &e, true));
    }
    toml::from_str::<SceneDesc>(text).map_err(|e| from_toml_error(file, text, &e, false))
}

/// The `[gi]` table of a TOML document (what `voxgi tune` prints), checked as a scene file's
/// `[gi]` table is: the same keys, ranges and messages; `file` names it in errors.
pub fn gi_table_layer(text: &str, file: &Path) -> Result<Layer, SceneError> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct OnlyGi {
        gi: Option<RawTable<GiSettings>>,
    }
    if let Err(e) = text.parse::<toml::Table>() {
        return Err(from_toml_error(file, text, &e, true));
    }
    let desc =
        toml::from_str::<OnlyGi>(text).map_err(|e| from_toml_error(file, text, &e, false))?;
    let ck = Check {
        file,
        origin: DVec3::ZERO,
    };
    desc.gi
        .map(|g| build_table(&ck, &g))
        .transpose()
        .map(Option::unwrap_or_default)
}

/// Coordinates beyond this (meters) are refused: 1e9 m keeps f64 differences exact to 1e-7 m.
const MAX_COORDINATE_M: f64 = 1e9;

/// The local origin's grid, meters: scenes within half of it of the world origin keep the
/// origin there (every such scene renders exactly as written); others are moved by a multiple
/// of it, so their local coordinates stay within half of it plus their own extent.
pub const ORIGIN_GRID_M: f64 = 256.0;

/// The scene's local origin in world coordinates: the centre of the positions it gives
/// (object translations, keyframes, camera, lights) rounded to [`ORIGIN_GRID_M`]. Everything
/// GPU-side is relative to it (a floating origin): f32 coordinates 10 km out have an ulp of
/// 1 mm, relative ones keep sub-micrometre precision. Values that fail their checks later are
/// left out here.
fn local_origin(desc: &SceneDesc) -> DVec3 {
    let mut points: Vec<[f64; 3]> = desc.camera.iter().map(|c| c.position).collect();
    points.extend(desc.lights.iter().filter_map(|l| l.position));
    for o in &desc.objects {
        points.push(o.translate.unwrap_or_default());
        let keys = o.animation.as_ref().and_then(|a| a.keyframes.as_ref());
        points.extend(keys.into_iter().flatten().filter_map(|k| k.translate));
    }
    let finite = points
        .iter()
        .map(|&p| DVec3::from_array(p))
        .filter(|p| p.is_finite() && p.abs().max_element() <= MAX_COORDINATE_M);
    let (min, max) = finite.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    if !min.is_finite() {
        return DVec3::ZERO;
    }
    ((min + max) * 0.5 / ORIGIN_GRID_M).round() * ORIGIN_GRID_M
}

/// Field-level checks, each error naming `file` and the field.
pub(crate) struct Check<'a> {
    pub(crate) file: &'a Path,
    /// The scene's local origin in world coordinates (see [`local_origin`]): subtracted in
    /// f64 from every position the file gives, before it becomes f32.
    pub(crate) origin: DVec3,
}

impl Check<'_> {
    fn invalid(&self, field: &str, problem: impl Into<String>) -> SceneError {
        SceneError::InvalidValue {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            problem: problem.into(),
        }
    }

    fn camera(&self, field: &str, problem: impl Into<String>) -> SceneError {
        SceneError::InvalidCamera {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            problem: problem.into(),
        }
    }

    fn scalar(&self, field: &str, v: f32) -> Result<f32, SceneError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SceneError::NonFinite {
                file: self.file.to_path_buf(),
                field: field.to_string(),
                value: v,
            })
        }
    }

    /// A world-space position from the file, made local: `v − origin` in f64, then f32, so a
    /// point 10 km out keeps the precision of one near the origin.
    fn point3(&self, field: &str, v: [f64; 3]) -> Result<Vec3, SceneError> {
        for (i, x) in v.iter().enumerate() {
            self.scalar(&format!("{field}[{i}]"), *x as f32)?;
            if x.abs() > MAX_COORDINATE_M {
                return Err(self.invalid(
                    &format!("{field}[{i}]"),
                    format!(
                        "{x} is not a coordinate voxgi can place; expected a finite number of \
                         meters within ±{MAX_COORDINATE_M:e}"
                    ),
                ));
            }
        }
        Ok((DVec3::from_array(v) - self.origin).as_vec3())
    }

    fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        for (i, x) in v.iter().enumerate() {
            self.scalar(&format!("{field}[{i}]"), *x)?;
        }
        Ok(Vec3::from_array(v))
    }

    fn direction(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v)?;
        // Rescale first so that a tiny but non-zero vector (1e-30) is still a direction.
        let scaled = v / v.abs().max_element().max(f32::MIN_POSITIVE);
        let n = scaled.normalize_or_zero();
        if v == Vec3::ZERO || n == Vec3::ZERO {
            return Err(SceneError::ZeroLengthDirection {
                file: self.file.to_path_buf(),
                field: field.to_string(),
            });
        }
        Ok(n)
    }

    fn intensity(&self, field: &str, v: ScalarOrVec3) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v.to_array())?;
        for (i, x) in v.to_array().iter().enumerate() {
            if *x < 0.0 {
                return Err(SceneError::NegativeIntensity {
                    file: self.file.to_path_buf(),
                    field: format!("{field}[{i}]"),
                    value: *x,
                });
            }
        }
        Ok(v)
    }

    /// An emitted radiance: finite and >= 0 in every channel.
    fn emission(&self, field: &str, v: ScalarOrVec3) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v.to_array())?;
        if v.min_element() < 0.0 {
            return Err(self.invalid(
                field,
                format!(
                    "emission {v} is negative; expected radiance in W/(m²·sr) >= 0 per channel \
                     (0 switches a channel off)"
                ),
            ));
        }
        Ok(v)
    }

    fn reflectance(&self, field: &str, v: ScalarOrVec3) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v.to_array())?;
        if v.min_element() < 0.0 || v.max_element() > 1.0 {
            return Err(self.invalid(
                field,
                format!(
                    "reflectance {v} outside [0, 1]; expected linear RGB reflectances in [0, 1] \
                     (values above 1 create energy)"
                ),
            ));
        }
        Ok(v)
    }

    fn scale(&self, field: &str, v: ScalarOrVec3) -> Result<Vec3, SceneError> {
        let v = self.vec3(field, v.to_array())?;
        if v.to_array().contains(&0.0) {
            return Err(self.invalid(
                field,
                format!("scale {v} has a zero component, which flattens the object; expected non-zero scale factors"),
            ));
        }
        Ok(v)
    }
}

/// Validates `desc` and loads everything it references. `file` names the scene in messages;
/// relative paths resolve against `base_dir`.
pub(crate) fn build(
    desc: SceneDesc,
    file: &Path,
    base_dir: &Path,
    source: Option<PathBuf>,
) -> Result<Scene, SceneError> {
    build_with(desc, file, base_dir, source, SceneFallbacks::default())
}

/// What a scene made from a glTF or OBJ file alone (`voxgi render x.glb`) gets that a scene
/// file does not: a camera framing the scene when the file has none, and a default sun when it
/// has no lights and nothing emits (see [`super::Scene::load_model`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SceneFallbacks {
    pub frame_camera: bool,
    pub default_sun: bool,
}

/// [`build`] with the fallbacks of a scene made from a glTF or OBJ file alone.
pub(crate) fn build_with(
    desc: SceneDesc,
    file: &Path,
    base_dir: &Path,
    source: Option<PathBuf>,
    fallbacks: SceneFallbacks,
) -> Result<Scene, SceneError> {
    let ck = Check {
        file,
        origin: local_origin(&desc),
    };
    let camera = desc
        .camera
        .as_ref()
        .map(|c| build_camera(&ck, c))
        .transpose()?;
    let gi = table_layer(&ck, desc.gi.as_ref())?;
    let transparency = desc
        .transparency
        .as_deref()
        .map(|t| build_transparency(&ck, t))
        .transpose()?;
    let shadow = table_layer(&ck, desc.shadow.as_ref())?;
    let voxel = table_layer(&ck, desc.voxel.as_ref())?;
    let post = table_layer(&ck, desc.post.as_ref())?;
    let mut lights = desc
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| build_light(&ck, &format!("lights[{i}]"), l))
        .collect::<Result<Vec<_>, _>>()?;
    if desc.objects.is_empty() {
        return Err(SceneError::EmptyScene {
            file: file.to_path_buf(),
        });
    }
    let mut store = AssetStore::default();
    let mut objects = Vec::with_capacity(desc.objects.len());
    let mut gltf_camera = None;
    for (i, o) in desc.objects.iter().enumerate() {
        let (object, gltf) = build_object(&ck, &format!("objects[{i}]"), o, base_dir, &mut store)?;
        if let Some(g) = gltf {
            // A glTF's lights and camera sit where the object puts the file at time 0.
            let model = object.transform_at(0.0);
            lights.extend(g.lights.iter().map(|l| transformed_light(*l, model)));
            if gltf_camera.is_none() {
                gltf_camera = g.camera.map(|c| c.to_camera(model));
            }
        }
        objects.push(object);
    }
    let camera = match (camera, gltf_camera) {
        (Some(c), _) => c,
        (None, Some(c)) => c,
        (None, None) if fallbacks.frame_camera => framing_camera(
            objects
                .iter()
                .fold(Aabb::EMPTY, |b, o| b.union(o.aabb_at(0.0))),
        ),
        (None, None) => {
            return Err(ck.camera(
                "camera",
                "the scene has no `[camera]` table (and no glTF object with a camera); add \
                 one with `position`, `target` and `fov_y_deg`",
            ))
        }
    };
    let camera_path = desc
        .camera_path
        .as_ref()
        .map(|p| build_camera_path(&ck, p, camera.up))
        .transpose()?;
    if fallbacks.default_sun
        && lights.is_empty()
        && !store.materials.iter().any(|m| m.is_emissive())
    {
        lights.push(default_sun());
        log::warn!(
            "{}: the glTF has no KHR_lights_punctual lights and nothing emits; it is lit by a \
             default sun ({} W/m² from above and in front). To light it yourself, write a scene \
             file with `[[objects]] mesh = \"{}\"` and `[[lights]]` tables",
            file.display(),
            DEFAULT_SUN_IRRADIANCE_W_M2,
            file.display()
        );
    }
    // After the lights (the glTF files' included): a sky takes its sun from them.
    let environment = desc
        .environment
        .as_ref()
        .map(|e| build_environment(&ck, e, base_dir, &lights))
        .transpose()?;
    let mut scene = Scene {
        origin_m: ck.origin,
        camera,
        camera_path,
        lights,
        objects,
        meshes: store.meshes,
        materials: store.materials,
        textures: store.textures,
        voxel,
        gi,
        transparency,
        shadow,
        post,
        environment,
        source,
    };
    if scene.camera.ortho_height_m.is_nan() {
        scene.camera.ortho_height_m = scene.default_ortho_height_m();
    }
    if scene.lights.is_empty() && !scene.has_emission() && scene.environment.is_none() {
        log::warn!(
            "{}: the scene has no lights, no emissive materials and no environment, so it will \
             render black; add a `[[lights]]` or an `[environment]` table",
            file.display()
        );
    }
    Ok(scene)
}

/// The `[environment]` table: a constant radiance or an equirectangular map (read here, so
/// that a missing or malformed file is an error naming the scene file and the key).
fn build_environment(
    ck: &Check<'_>,
    e: &EnvironmentDesc,
    base_dir: &Path,
    lights: &[super::Light],
) -> Result<Environment, SceneError> {
    use super::environment::ENVIRONMENT_KINDS;
    let only = |key: &str, present: bool, kind: &str| {
        if present {
            Err(ck.invalid(
                &format!("environment.{key}"),
                format!("`{key}` does not apply to kind = \"{kind}\"; remove it"),
            ))
        } else {
            Ok(())
        }
    };
    if e.kind == "constant" || e.kind == "map" {
        only("turbidity", e.turbidity.is_some(), e.kind.as_str())?;
        only("ground_albedo", e.ground_albedo.is_some(), e.kind.as_str())?;
    }
    match e.kind.as_str() {
        "constant" => {
            only("file", e.file.is_some(), "constant")?;
            only("rotation_deg", e.rotation_deg.is_some(), "constant")?;
            only("scale", e.scale.is_some(), "constant")?;
            let Some(radiance) = e.radiance else {
                return Err(ck.invalid(
                    "environment.radiance",
                    "missing; a constant environment needs `radiance = [r, g, b]` (W/(m²·sr), \
                     linear RGB, >= 0)",
                ));
            };
            let radiance = ck.emission("environment.radiance", radiance)?;
            Ok(Environment::Constant { radiance })
        }
        "map" => {
            only("radiance", e.radiance.is_some(), "map")?;
            map_environment(ck, e, base_dir)
        }
        "sky" => {
            only("radiance", e.radiance.is_some(), "sky")?;
            only("file", e.file.is_some(), "sky")?;
            only("rotation_deg", e.rotation_deg.is_some(), "sky")?;
            sky_environment(ck, e, lights)
        }
        other => Err(ck.invalid(
            "environment.kind",
            format!(
                "unknown kind \"{other}\"; use one of {}",
                ENVIRONMENT_KINDS
                    .iter()
                    .map(|k| format!("\"{k}\""))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )),
    }
}

/// `[environment] kind = "map"`: the equirectangular map `file` (relative to `base_dir`), read
/// here, so that a missing or malformed file is an error naming the scene file and the key.
fn map_environment(
    ck: &Check<'_>,
    e: &EnvironmentDesc,
    base_dir: &Path,
) -> Result<Environment, SceneError> {
    use super::environment::{read_map, EnvironmentMap, MapReadError};
    let Some(file) = &e.file else {
        return Err(ck.invalid(
            "environment.file",
            "missing; a map environment needs `file = \"sky.hdr\"` (an \
             equirectangular Radiance .hdr or OpenEXR image, 2:1, relative to the \
             scene file)",
        ));
    };
    let rotation_deg = ck.scalar("environment.rotation_deg", e.rotation_deg.unwrap_or(0.0))?;
    let scale = environment_scale(ck, e)?;
    let path = base_dir.join(file);
    let referenced_by = format!("{}: environment.file", ck.file.display());
    let (width, height, texels) = read_map(&path).map_err(|err| match err {
        MapReadError::NotFound => SceneError::NotFound {
            file: path.clone(),
            what: "environment map",
            referenced_by: Some(referenced_by.clone()),
        },
        MapReadError::Decode(message) => SceneError::TextureDecode {
            file: path.clone(),
            message,
            referenced_by: referenced_by.clone(),
        },
        MapReadError::NotTwoToOne { width, height } => ck.invalid(
            "environment.file",
            format!(
                "{} is {width}×{height} texels; an equirectangular map is twice as \
                 wide as high (e.g. 2048×1024): resample or crop it",
                path.display()
            ),
        ),
        MapReadError::NonFinite { x, y } => ck.invalid(
            "environment.file",
            format!(
                "{} has a NaN or infinite texel at ({x}, {y}); fix the image",
                path.display()
            ),
        ),
    })?;
    Ok(Environment::Map(EnvironmentMap {
        path,
        width,
        height,
        texels,
        rotation_deg,
        scale,
    }))
}

/// `[environment] kind = "sky"`: the Hosek-Wilkie sky, its sun toward the scene's directional
/// light (one of `lights`).
fn sky_environment(
    ck: &Check<'_>,
    e: &EnvironmentDesc,
    lights: &[super::Light],
) -> Result<Environment, SceneError> {
    let range = super::sky::TURBIDITY_RANGE;
    let turbidity = ck.scalar("environment.turbidity", e.turbidity.unwrap_or(3.0))?;
    if !range.contains(&turbidity) {
        return Err(ck.invalid(
            "environment.turbidity",
            format!(
                "{turbidity} is outside the model's {}..={} (2: clear, 3: a temperate \
                 day, 8-10: hazy); pick one inside",
                range.start(),
                range.end()
            ),
        ));
    }
    let ground_albedo = ck.reflectance(
        "environment.ground_albedo",
        e.ground_albedo.unwrap_or(ScalarOrVec3::Scalar(0.3)),
    )?;
    let scale = environment_scale(ck, e)?;
    let Some(toward_sun) = lights.iter().find_map(|l| match l {
        super::Light::Directional { direction, .. } => Some(-*direction),
        _ => None,
    }) else {
        return Err(ck.invalid(
            "environment.kind",
            "a sky takes its sun from the scene's directional light, and the scene has \
             none; add `[[lights]] kind = \"directional\"` with the sun's `direction` \
             and `irradiance_w_m2` (or use kind = \"constant\" or \"map\")",
        ));
    };
    let sky = super::sky::SkyParams {
        turbidity,
        ground_albedo,
        scale,
        toward_sun,
    };
    let map = super::sky::bake(&sky);
    Ok(Environment::Sky { sky, map })
}

/// `environment.scale`, a factor >= 0 (1 when not given).
fn environment_scale(ck: &Check<'_>, e: &EnvironmentDesc) -> Result<f32, SceneError> {
    let scale = ck.scalar("environment.scale", e.scale.unwrap_or(1.0))?;
    if scale < 0.0 {
        return Err(ck.invalid(
            "environment.scale",
            format!("{scale} is negative; use a factor >= 0"),
        ));
    }
    Ok(scale)
}

/// The `transparency` key: one of [`super::TRANSPARENCY_NAMES`].
fn build_transparency(ck: &Check<'_>, word: &str) -> Result<super::Transparency, SceneError> {
    super::TRANSPARENCY_NAMES
        .iter()
        .find(|(name, _)| *name == word)
        .map(|&(_, t)| t)
        .ok_or_else(|| {
            ck.invalid(
                "transparency",
                format!("\"{word}\" is not a transparency mode; expected \"oit\" or \"hashed\""),
            )
        })
}

/// Turns each key's `look_at` or `direction` into a unit direction, then lets
/// [`CameraPath::new`] check the path; every error names the file and the key.
fn build_camera_path(
    ck: &Check<'_>,
    p: &CameraPathDesc,
    camera_up: Vec3,
) -> Result<CameraPath, SceneError> {
    let up = match p.up {
        Some(u) => ck.direction("camera_path.up", u)?,
        None => camera_up,
    };
    let mut keys = Vec::with_capacity(p.keyframes.len());
    for (i, k) in p.keyframes.iter().enumerate() {
        let field = |f: &str| format!("camera_path.keyframes[{i}].{f}");
        let time_s = ck.scalar(&field("time_s"), k.time_s)?;
        let position = ck.point3(&field("position"), k.position)?;
        let forward = match (k.look_at, k.direction) {
            (Some(_), Some(_)) => {
                return Err(ck.camera(
                    &field("look_at"),
                    "both `look_at` and `direction` are given; keep one of them",
                ))
            }
            (None, None) => {
                return Err(ck.camera(
                    &field("look_at"),
                    "neither `look_at` nor `direction` is given; add `look_at = [x, y, z]` (a \
                     point, meters) or `direction = [x, y, z]`",
                ))
            }
            (Some(t), None) => {
                let d = ck.point3(&field("look_at"), t)? - position;
                d.try_normalize().ok_or_else(|| {
                    ck.camera(
                        &field("look_at"),
                        "the point equals the key's position; move it or use `direction`",
                    )
                })?
            }
            (None, Some(d)) => ck.direction(&field("direction"), d)?,
        };
        let fov_y_deg = k
            .fov_y_deg
            .map(|f| ck.scalar(&field("fov_y_deg"), f))
            .transpose()?;
        keys.push(CameraKey {
            time_s,
            position,
            forward,
            fov_y_deg,
        });
    }
    CameraPath::new(keys, up).map_err(|e| ck.camera(&e.field, e.problem))
}

fn build_camera(ck: &Check<'_>, c: &CameraDesc) -> Result<Camera, SceneError> {
    let position = ck.point3("camera.position", c.position)?;
    let forward =
        match (c.target, c.forward) {
            (Some(_), Some(_)) => {
                return Err(ck.camera(
                    "camera.target",
                    "both `target` and `forward` are given; keep one of them",
                ))
            }
            (None, None) => return Err(ck.camera(
                "camera",
                "neither `target` nor `forward` is given; add `target = [x, y, z]` (a point to \
                 look at, meters) or `forward = [x, y, z]` (a direction)",
            )),
            (Some(t), None) => {
                let t = ck.point3("camera.target", t)?;
                let d = t - position;
                if d.length_squared() == 0.0 || d.normalize_or_zero() == Vec3::ZERO {
                    return Err(ck.camera(
                        "camera.target",
                        "the target equals the camera position; move the target or use `forward`",
                    ));
                }
                d.normalize()
            }
            (None, Some(f)) => ck.direction("camera.forward", f)?,
        };
    let up = match c.up {
        Some(u) => ck.direction("camera.up", u)?,
        None => Vec3::Y,
    };
    if forward.cross(up).length() < 1e-4 {
        return Err(ck.camera(
            "camera.up",
            format!(
                "up {up} is parallel to the viewing direction {forward}; expected an up vector \
                 that is not parallel to it, e.g. [0, 0, 1] when looking straight down"
            ),
        ));
    }
    let projection = match c.projection.as_deref() {
        None => Projection::Perspective,
        Some(word) => [Projection::Perspective, Projection::Orthographic]
            .into_iter()
            .find(|p| p.name() == word)
            .ok_or_else(|| {
                ck.camera(
                    "camera.projection",
                    format!(
                        "\"{word}\" is not a projection; expected \"perspective\" or \
                         \"orthographic\""
                    ),
                )
            })?,
    };
    let fov = match (c.fov_y_deg, projection) {
        (Some(f), _) => ck.scalar("camera.fov_y_deg", f)?,
        (None, Projection::Orthographic) => DEFAULT_ORTHO_FOV_Y_DEG,
        (None, Projection::Perspective) => {
            return Err(ck.camera(
                "camera.fov_y_deg",
                "a perspective camera needs its vertical field of view; add e.g. \
                 `fov_y_deg = 39.3` (or `projection = \"orthographic\"` with `ortho_height_m`)",
            ))
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(ck.camera(
            "camera.fov_y_deg",
            format!(
                "{fov} is not a vertical field of view; expected degrees in (0, 180), e.g. 39.3"
            ),
        ));
    }
    let limit = &limits::ORTHO_HEIGHT_M;
    let ortho_height_m = match c.ortho_height_m {
        Some(h) => Some(
            limit
                .check_as("camera.ortho_height_m", h)
                .map_err(|e| ck.camera("camera.ortho_height_m", limit_message(&e)))?,
        ),
        None if projection == Projection::Orthographic => {
            return Err(ck.camera(
                "camera.ortho_height_m",
                "an orthographic camera needs the height of its view; add e.g. \
                 `ortho_height_m = 1.2` (meters)",
            ))
        }
        None => None,
    };
    let near = ck.scalar("camera.near", c.near.unwrap_or(0.01))?;
    let far = ck.scalar("camera.far", c.far.unwrap_or(100.0))?;
    if near <= 0.0 {
        return Err(ck.camera(
            "camera.near",
            format!("near = {near}; expected a positive distance in meters, e.g. 0.01"),
        ));
    }
    if far <= near {
        return Err(ck.camera(
            "camera.far",
            format!("far = {far} is not beyond near = {near}; expected near < far"),
        ));
    }
    if far / near > 1e7 {
        log::warn!(
            "{}: camera far/near = {:.0e} loses depth precision; raise `near` or lower `far`",
            ck.file.display(),
            far / near
        );
    }
    Ok(Camera {
        position,
        forward,
        up,
        fov_y_deg: fov,
        near,
        far,
        shift_x_tan: 0.0,
        projection,
        // Resolved by `build` once the scene's bounds are known (see
        // `Scene::default_ortho_height_m`); NaN never survives it.
        ortho_height_m: ortho_height_m.unwrap_or(f32::NAN),
    })
}

/// The layer of an optional settings table, empty where the scene has none.
fn table_layer<S: Settings>(ck: &Check<'_>, t: Option<&RawTable<S>>) -> Result<Layer, SceneError> {
    t.map(|t| build_table(ck, t))
        .transpose()
        .map(Option::unwrap_or_default)
}

/// Checks a settings table's values against their keys' ranges (those of the flags), each
/// error naming the file and the key path.
fn build_table<S: Settings>(ck: &Check<'_>, t: &RawTable<S>) -> Result<Layer, SceneError> {
    let mut layer = Layer::default();
    for (k, v) in &t.values {
        let value = k.kind.from_toml(k.path, v).map_err(|e| match e {
            TomlValueError::NonFinite(value) => SceneError::NonFinite {
                file: ck.file.to_path_buf(),
                field: k.path.to_owned(),
                value,
            },
            TomlValueError::Invalid(problem) => ck.invalid(k.path, problem),
        })?;
        layer.set(k.path, value);
    }
    Ok(layer)
}

/// An object's `crease_deg`: in [0, 180], default 60.
fn crease_angle(ck: &Check<'_>, field: &str, v: Option<f32>) -> Result<f32, SceneError> {
    let deg = ck.scalar(field, v.unwrap_or(super::crease::DEFAULT_CREASE_DEG))?;
    if (0.0..=180.0).contains(&deg) {
        Ok(deg)
    } else {
        Err(ck.invalid(
            field,
            format!("{deg} is not an angle between faces; expected degrees in [0, 180]"),
        ))
    }
}

/// A limit's message without the key, which the scene error puts in front itself.
fn limit_message(e: &limits::LimitError) -> String {
    format!("{}; expected {}", e.value, e.expected)
}

pub(crate) fn build_light(ck: &Check<'_>, field: &str, l: &LightDesc) -> Result<Light, SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let kind_name = match l.kind {
        LightKind::Point => "point",
        LightKind::Spot => "spot",
        LightKind::Directional => "directional",
        LightKind::Sphere | LightKind::Rectangle => return build_area_light(ck, field, l),
    };
    let require = |name: &str, present: bool, example: &str| {
        if present {
            Ok(())
        } else {
            Err(ck.invalid(
                &f(name),
                format!("a {kind_name} light needs `{name}`; add e.g. `{name} = {example}`"),
            ))
        }
    };
    let forbid = |name: &str, present: bool| {
        if present {
            Err(ck.invalid(
                &f(name),
                format!("`{name}` does not apply to a {kind_name} light; remove it"),
            ))
        } else {
            Ok(())
        }
    };
    match l.kind {
        LightKind::Point | LightKind::Spot => {
            require("position", l.position.is_some(), "[0, 1, 0]")?;
            require("intensity_w_sr", l.intensity_w_sr.is_some(), "[1, 1, 1]")?;
            forbid("irradiance_w_m2", l.irradiance_w_m2.is_some())?;
        }
        LightKind::Directional => {
            require("direction", l.direction.is_some(), "[0, -1, 0]")?;
            require("irradiance_w_m2", l.irradiance_w_m2.is_some(), "[1, 1, 1]")?;
            forbid("position", l.position.is_some())?;
            forbid("intensity_w_sr", l.intensity_w_sr.is_some())?;
        }
        LightKind::Sphere | LightKind::Rectangle => unreachable!("handled above"),
    }
    for (name, present) in area_keys(l) {
        forbid(name, present)?;
    }
    if l.kind != LightKind::Spot {
        forbid("cutoff_deg", l.cutoff_deg.is_some())?;
        forbid("beam_deg", l.beam_deg.is_some())?;
    }
    if l.kind == LightKind::Point {
        forbid("direction", l.direction.is_some())?;
    }
    if l.kind == LightKind::Spot {
        require("direction", l.direction.is_some(), "[0, -1, 0]")?;
    }
    let position = l
        .position
        .map(|p| ck.point3(&f("position"), p))
        .transpose()?;
    let direction = l
        .direction
        .map(|d| ck.direction(&f("direction"), d))
        .transpose()?;
    let intensity = l
        .intensity_w_sr
        .map(|v| ck.intensity(&f("intensity_w_sr"), v))
        .transpose()?;
    let irradiance = l
        .irradiance_w_m2
        .map(|v| ck.intensity(&f("irradiance_w_m2"), v))
        .transpose()?;
    // `require` above guarantees the kind's fields are present.
    let missing = |name: &str| ck.invalid(&f(name), "missing");
    Ok(match l.kind {
        LightKind::Point => Light::Point {
            position: position.ok_or_else(|| missing("position"))?,
            intensity_w_sr: intensity.ok_or_else(|| missing("intensity_w_sr"))?,
        },
        LightKind::Spot => {
            // Mitsuba 3's defaults: cutoff_angle 20°, beam_width 3/4 of the cutoff.
            let cutoff = ck.scalar(&f("cutoff_deg"), l.cutoff_deg.unwrap_or(20.0))?;
            if !(cutoff > 0.0 && cutoff < 90.0) {
                return Err(ck.invalid(
                    &f("cutoff_deg"),
                    format!(
                        "{cutoff} is not a cone half-angle; expected degrees in (0, 90) (use a \
                         point light for wider cones)"
                    ),
                ));
            }
            let beam = ck.scalar(&f("beam_deg"), l.beam_deg.unwrap_or(0.75 * cutoff))?;
            if !(beam > 0.0 && beam <= cutoff) {
                return Err(ck.invalid(
                    &f("beam_deg"),
                    format!("{beam} is not in (0, cutoff_deg = {cutoff}]; the full-intensity core must lie inside the cone"),
                ));
            }
            Light::Spot {
                position: position.ok_or_else(|| missing("position"))?,
                direction: direction.ok_or_else(|| missing("direction"))?,
                intensity_w_sr: intensity.ok_or_else(|| missing("intensity_w_sr"))?,
                cutoff_deg: cutoff,
                beam_deg: beam,
            }
        }
        LightKind::Directional => Light::Directional {
            direction: direction.ok_or_else(|| missing("direction"))?,
            irradiance_w_m2: irradiance.ok_or_else(|| missing("irradiance_w_m2"))?,
        },
        LightKind::Sphere | LightKind::Rectangle => unreachable!("handled above"),
    })
}

/// The keys only area lights take, and whether `l` has each.
fn area_keys(l: &LightDesc) -> [(&'static str, bool); 7] {
    [
        ("radiance_w_sr_m2", l.radiance_w_sr_m2.is_some()),
        ("radius_m", l.radius_m.is_some()),
        ("normal", l.normal.is_some()),
        ("width_axis", l.width_axis.is_some()),
        ("width_m", l.width_m.is_some()),
        ("height_m", l.height_m.is_some()),
        ("samples", l.samples.is_some()),
    ]
}

/// Sub-lights of an area light without a `samples` key.
pub const DEFAULT_AREA_SAMPLES: u32 = 16;

/// A `sphere` or `rectangle` light: position, radiance (finite, >= 0), sizes (finite, > 0)
/// and, for rectangles, a normal and the width edges' direction (default: the world axis
/// `cross(up, normal)` with up = +Y, or +Z when the normal is vertical).
fn build_area_light(ck: &Check<'_>, field: &str, l: &LightDesc) -> Result<Light, SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let sphere = l.kind == LightKind::Sphere;
    let kind_name = if sphere { "sphere" } else { "rectangle" };
    let example = |name: &str| match name {
        "position" => "[0, 1, 0]",
        "radiance_w_sr_m2" => "[10, 10, 10]",
        "normal" => "[0, -1, 0]",
        _ => "0.25",
    };
    let needs = |name: &str, present: bool| {
        if present {
            Ok(())
        } else {
            Err(ck.invalid(
                &f(name),
                format!(
                    "a {kind_name} light needs `{name}`; add e.g. `{name} = {}`",
                    example(name)
                ),
            ))
        }
    };
    let forbid = |name: &str, present: bool| {
        if present {
            Err(ck.invalid(
                &f(name),
                format!("`{name}` does not apply to a {kind_name} light; remove it"),
            ))
        } else {
            Ok(())
        }
    };
    forbid("direction", l.direction.is_some())?;
    forbid("intensity_w_sr", l.intensity_w_sr.is_some())?;
    forbid("irradiance_w_m2", l.irradiance_w_m2.is_some())?;
    forbid("cutoff_deg", l.cutoff_deg.is_some())?;
    forbid("beam_deg", l.beam_deg.is_some())?;
    needs("position", l.position.is_some())?;
    needs("radiance_w_sr_m2", l.radiance_w_sr_m2.is_some())?;
    if sphere {
        needs("radius_m", l.radius_m.is_some())?;
        for (name, present) in [
            ("normal", l.normal.is_some()),
            ("width_axis", l.width_axis.is_some()),
            ("width_m", l.width_m.is_some()),
            ("height_m", l.height_m.is_some()),
        ] {
            forbid(name, present)?;
        }
    } else {
        forbid("radius_m", l.radius_m.is_some())?;
        for (name, present) in [
            ("normal", l.normal.is_some()),
            ("width_m", l.width_m.is_some()),
            ("height_m", l.height_m.is_some()),
        ] {
            needs(name, present)?;
        }
    }
    let length = |name: &str, v: Option<f32>| -> Result<f32, SceneError> {
        let v = ck.scalar(&f(name), v.unwrap_or(0.0))?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(ck.invalid(&f(name), format!("{v} is not a size; expected meters > 0")))
        }
    };
    let position = ck.point3(&f("position"), l.position.unwrap_or_default())?;
    let radiance = ck.emission(
        &f("radiance_w_sr_m2"),
        l.radiance_w_sr_m2.unwrap_or(ScalarOrVec3::Scalar(0.0)),
    )?;
    let samples = match l.samples {
        Some(v) => limits::AREA_SAMPLES
            .check_as(&f("samples"), v)
            .map_err(|e| ck.invalid(&f("samples"), limit_message(&e)))?,
        None => DEFAULT_AREA_SAMPLES,
    };
    if sphere {
        return Ok(Light::Sphere {
            position,
            radius_m: length("radius_m", l.radius_m)?,
            radiance_w_sr_m2: radiance,
            samples,
        });
    }
    let normal = ck.direction(&f("normal"), l.normal.unwrap_or_default())?;
    let axis = match l.width_axis {
        Some(a) => ck.direction(&f("width_axis"), a)?,
        None => {
            let up = if normal.y.abs() > 0.99 {
                Vec3::Z
            } else {
                Vec3::Y
            };
            up.cross(normal)
        }
    };
    // The part of the axis in the rectangle's plane.
    let width_axis = (axis - normal * axis.dot(normal)).normalize_or_zero();
    if width_axis.length_squared() < 0.5 || axis.dot(normal).abs() > 0.999 {
        return Err(ck.invalid(
            &f("width_axis"),
            "is parallel to `normal`; give a direction in the rectangle's plane",
        ));
    }
    Ok(Light::Rectangle {
        position,
        normal,
        width_axis,
        width_m: length("width_m", l.width_m)?,
        height_m: length("height_m", l.height_m)?,
        radiance_w_sr_m2: radiance,
        samples,
    })
}

pub(crate) fn build_transform(
    ck: &Check<'_>,
    field: &str,
    translate: Option<[f64; 3]>,
    rotate_deg: Option<[f32; 3]>,
    scale: Option<ScalarOrVec3>,
    base: &Transform,
) -> Result<Transform, SceneError> {
    Ok(Transform {
        translate: match translate {
            Some(t) => ck.point3(&format!("{field}.translate"), t)?,
            None => base.translate,
        },
        rotation: match rotate_deg {
            Some(r) => rotation_from_euler_xyz_deg(ck.vec3(&format!("{field}.rotate_deg"), r)?),
            None => base.rotation,
        },
        scale: match scale {
            Some(s) => ck.scale(&format!("{field}.scale"), s)?,
            None => base.scale,
        },
    })
}

/// The irradiance of [`default_sun`]: π W/m², so a white Lambert surface facing it reflects a
/// radiance of 1 W/(m²·sr), mid-range for the default tone mapping.
const DEFAULT_SUN_IRRADIANCE_W_M2: f32 = std::f32::consts::PI;

/// The light of a glTF scene rendered alone that has no lights and no emission: a directional
/// light from above, in front (+Z, the side glTF models face) and a little to the side, so
/// that the faces a default camera sees are lit at different angles.
fn default_sun() -> Light {
    Light::Directional {
        direction: Vec3::new(-0.3, -1.0, -0.5).normalize(),
        irradiance_w_m2: Vec3::splat(DEFAULT_SUN_IRRADIANCE_W_M2),
    }
}

/// A camera looking at `bounds` from the front (+Z) and a little above, 45° vertical field of
/// view, far enough away that the bounding sphere fits the view.
fn framing_camera(bounds: Aabb) -> Camera {
    let center = if bounds.is_empty() {
        Vec3::ZERO
    } else {
        bounds.center()
    };
    let radius = (bounds.extent().length() * 0.5).max(1e-3);
    let fov_y_deg: f32 = 45.0;
    let distance = radius / (0.5 * fov_y_deg.to_radians()).sin() * 1.05;
    let forward = -Vec3::new(0.0, 0.3, 1.0).normalize();
    Camera {
        position: center - forward * distance,
        forward,
        up: Vec3::Y,
        fov_y_deg,
        near: (distance - radius).max(distance * 1e-3),
        far: distance + 2.0 * radius,
        shift_x_tan: 0.0,
        projection: super::camera::Projection::Perspective,
        ortho_height_m: f32::NAN,
    }
}

/// `l` moved by the object transform `model` (directions renormalized).
fn transformed_light(l: Light, model: glam::Mat4) -> Light {
    let dir = |d: Vec3| model.transform_vector3(d).try_normalize().unwrap_or(d);
    match l {
        Light::Point {
            position,
            intensity_w_sr,
        } => Light::Point {
            position: model.transform_point3(position),
            intensity_w_sr,
        },
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => Light::Spot {
            position: model.transform_point3(position),
            direction: dir(direction),
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        },
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => Light::Directional {
            direction: dir(direction),
            irradiance_w_m2,
        },
        other => other,
    }
}

/// An object and, for a glTF mesh, what else the file gives (lights, camera).
fn build_object(
    ck: &Check<'_>,
    field: &str,
    o: &ObjectDesc,
    base_dir: &Path,
    store: &mut AssetStore,
) -> Result<(Object, Option<GltfAsset>), SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let transform = build_transform(
        ck,
        field,
        o.translate,
        o.rotate_deg,
        o.scale,
        // No `translate`: the object stays at the world origin, −origin locally.
        &Transform {
            translate: ck.point3(&f("translate"), [0.0; 3])?,
            ..Transform::default()
        },
    )?;
    let sequence = o.animation.as_ref().and_then(|a| a.obj_sequence.as_ref());
    let mut gltf = None;
    if o.crease_deg.is_some() && o.mesh.is_none() {
        return Err(ck.invalid(
            &f("crease_deg"),
            "`crease_deg` sets the normals of an OBJ `mesh`; remove it here",
        ));
    }
    let (mesh, default_name) = match (&o.mesh, &o.builtin) {
        (Some(_), Some(_)) => {
            return Err(ck.invalid(
                &f("builtin"),
                "both `mesh` and `builtin` are given; keep one of them",
            ))
        }
        (None, None) if sequence.is_none() => {
            return Err(ck.invalid(
                field,
                format!(
                    "the object has no geometry; add `mesh = \"file.obj\"` (relative to the \
                     scene file) or `builtin = \"NAME\"` with NAME one of {BUILTIN_MESH_NAMES:?}"
                ),
            ))
        }
        (None, None) => (None, String::new()),
        (Some(_), None) if sequence.is_some() => {
            return Err(ck.invalid(
                &f("mesh"),
                "an object animated by `obj_sequence` takes its meshes from the sequence; \
                 remove `mesh`",
            ))
        }
        (Some(m), None) => {
            let path = base_dir.join(m);
            let name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| m.clone());
            let crease_deg = crease_angle(ck, &f("crease_deg"), o.crease_deg)?;
            let referenced_by = field_ref(ck.file, &f("mesh"));
            let idx = if is_gltf_path(&path) {
                let asset = store.gltf(&path, &referenced_by, crease_deg)?;
                let idx = asset.mesh;
                gltf = Some(asset);
                idx
            } else {
                store.obj_mesh(&path, "OBJ mesh", &referenced_by, crease_deg)?
            };
            (Some(idx), name)
        }
        (None, Some(b)) => match store.builtin_mesh(b) {
            Some(idx) => (Some(idx), b.clone()),
            None => {
                return Err(ck.invalid(
                    &f("builtin"),
                    format!("unknown built-in mesh `{b}`; expected one of {BUILTIN_MESH_NAMES:?}"),
                ))
            }
        },
    };
    let name = o.name.clone().unwrap_or_else(|| default_name.clone());

    let animation = match &o.animation {
        None => None,
        Some(a) => Some(build_animation(
            ck,
            &f("animation"),
            a,
            &transform,
            base_dir,
            store,
        )?),
    };
    let mesh = match (&animation, mesh) {
        (Some(Animation::ObjSequence { meshes, .. }), _) => meshes.first().copied(),
        (_, m) => m,
    }
    .ok_or_else(|| ck.invalid(field, "the object has no mesh"))?;
    let name = if name.is_empty() {
        format!("object{}", field.trim_start_matches("objects"))
    } else {
        name
    };

    let dynamic = match (o.dynamic, animation.is_some()) {
        (Some(false), true) => {
            return Err(ck.invalid(
                &f("dynamic"),
                "an animated object is dynamic; remove `dynamic = false` or the animation",
            ))
        }
        (d, animated) => d.unwrap_or(animated),
    };

    let submesh_materials: Vec<usize> = store
        .meshes
        .get(mesh)
        .map(|m| m.submeshes.iter().map(|s| s.material).collect())
        .unwrap_or_default();
    let materials = match &o.material {
        None => submesh_materials,
        Some(md) => apply_override(ck, &f("material"), md, &name, &submesh_materials, store)?,
    };
    let local_aabb = store
        .meshes
        .get(mesh)
        .map(|m| m.aabb)
        .unwrap_or(Aabb::EMPTY);
    Ok((
        Object {
            name,
            mesh,
            materials,
            transform,
            dynamic,
            animation,
            local_aabb,
        },
        gltf,
    ))
}

/// Derives one material per distinct submesh material with the override's fields replaced.
fn apply_override(
    ck: &Check<'_>,
    field: &str,
    md: &MaterialDesc,
    object: &str,
    submesh_materials: &[usize],
    store: &mut AssetStore,
) -> Result<Vec<usize>, SceneError> {
    let albedo = md
        .albedo
        .map(|a| ck.reflectance(&format!("{field}.albedo"), a))
        .transpose()?;
    let specular = md
        .specular
        .map(|s| ck.reflectance(&format!("{field}.specular"), s))
        .transpose()?;
    let shininess = md
        .shininess
        .map(|s| ck.scalar(&format!("{field}.shininess"), s))
        .transpose()?;
    if let Some(s) = shininess {
        if s < 0.0 {
            return Err(ck.invalid(
                &format!("{field}.shininess"),
                format!("{s} is negative; expected a Phong exponent >= 0"),
            ));
        }
    }
    let opacity = md
        .opacity
        .map(|s| ck.scalar(&format!("{field}.opacity"), s))
        .transpose()?;
    if let Some(o) = opacity {
        if !(0.0..=1.0).contains(&o) {
            return Err(ck.invalid(
                &format!("{field}.opacity"),
                format!("{o} is outside [0, 1]; 1 is opaque"),
            ));
        }
    }
    let unit = |name: &str, v: Option<f32>| -> Result<Option<f32>, SceneError> {
        let field = format!("{field}.{name}");
        match v.map(|x| ck.scalar(&field, x)).transpose()? {
            Some(x) if !(0.0..=1.0).contains(&x) => Err(ck.invalid(
                &field,
                format!("{x} is outside [0, 1]; expected a value in [0, 1]"),
            )),
            x => Ok(x),
        }
    };
    let roughness = unit("roughness", md.roughness)?;
    let metallic = unit("metallic", md.metallic)?;
    if (roughness.is_some() || metallic.is_some())
        && (md.specular.is_some() || md.shininess.is_some())
    {
        return Err(ck.invalid(
            field,
            "sets both Phong (`specular`, `shininess`) and GGX (`roughness`, `metallic`) \
             fields; a material is one or the other, remove one pair",
        ));
    }
    let emission = md
        .emission_w_sr_m2
        .map(|e| ck.emission(&format!("{field}.emission_w_sr_m2"), e))
        .transpose()?;
    let mut derived: Vec<(usize, usize)> = Vec::new();
    let mut out = Vec::with_capacity(submesh_materials.len());
    for &m in submesh_materials {
        if let Some(&(_, d)) = derived.iter().find(|(src, _)| *src == m) {
            out.push(d);
            continue;
        }
        let Some(base) = store.materials.get(m) else {
            out.push(m);
            continue;
        };
        let mut mat = base.clone();
        mat.name = format!("{object}:{}", base.name);
        if let Some(a) = albedo {
            mat.albedo = a;
            mat.albedo_texture = None;
        }
        if let Some(s) = specular {
            mat.specular = s;
        }
        if let Some(n) = shininess {
            mat.shininess = n;
        }
        if let Some(o) = opacity {
            mat.opacity = o;
        }
        if md.specular.is_some() || md.shininess.is_some() {
            // A Phong override turns a GGX material (MTL `Pr`/`Pm`) into Phong.
            mat.ggx = None;
        }
        if roughness.is_some() || metallic.is_some() {
            let base = mat.ggx.unwrap_or(crate::scene::Ggx {
                roughness: 1.0,
                metallic: 0.0,
            });
            mat.ggx = Some(crate::scene::Ggx {
                roughness: roughness.unwrap_or(base.roughness),
                metallic: metallic.unwrap_or(base.metallic),
            });
        }
        // A constant override drops the MTL map it replaces, as `albedo` drops `map_Kd`.
        if roughness.is_some() {
            mat.pbr_maps.roughness = None;
        }
        if metallic.is_some() {
            mat.pbr_maps.metallic = None;
        }
        if let Some(e) = emission {
            mat.emission = e;
            mat.pbr_maps.emission = None;
        }
        if mat.ggx.is_none() && (mat.albedo + mat.specular).max_element() > 1.0 {
            log::warn!(
                "{}: {field}: albedo + specular exceeds 1 in some channel, so the material \
                 reflects more energy than it receives; lower one of them",
                ck.file.display()
            );
        }
        let d = store.materials.len();
        store.materials.push(mat);
        derived.push((m, d));
        out.push(d);
    }
    Ok(out)
}

fn build_animation(
    ck: &Check<'_>,
    field: &str,
    a: &AnimationDesc,
    base: &Transform,
    base_dir: &Path,
    store: &mut AssetStore,
) -> Result<Animation, SceneError> {
    let f = |name: &str| format!("{field}.{name}");
    let looping = a.looping.unwrap_or(true);
    match (&a.keyframes, &a.obj_sequence) {
        (Some(_), Some(_)) => Err(ck.invalid(
            field,
            "both `keyframes` and `obj_sequence` are given; an animation is one or the other",
        )),
        (None, None) => Err(ck.invalid(
            field,
            "expected `keyframes = [{ time_s = 0.0, translate = [...] }, ...]` or \
             `obj_sequence = \"anim/frame_{:03}.obj\"` with `frames` and `fps`",
        )),
        (Some(keys), None) => {
            for name in ["frames", "fps", "first_frame"] {
                let present = match name {
                    "frames" => a.frames.is_some(),
                    "fps" => a.fps.is_some(),
                    _ => a.first_frame.is_some(),
                };
                if present {
                    return Err(ck.invalid(
                        &f(name),
                        format!("`{name}` belongs to `obj_sequence` animations; remove it"),
                    ));
                }
            }
            if keys.is_empty() {
                return Err(ck.invalid(&f("keyframes"), "no keyframes; add at least one"));
            }
            let mut keyframes = Vec::with_capacity(keys.len());
            for (i, k) in keys.iter().enumerate() {
                let kf = f(&format!("keyframes[{i}]"));
                let time_s = ck.scalar(&format!("{kf}.time_s"), k.time_s)?;
                if let Some(prev) = keyframes.last().map(|p: &Keyframe| p.time_s) {
                    if time_s <= prev {
                        return Err(ck.invalid(
                            &format!("{kf}.time_s"),
                            format!(
                                "{time_s} s is not after the previous keyframe ({prev} s); \
                                 expected strictly increasing times"
                            ),
                        ));
                    }
                }
                let transform = build_transform(ck, &kf, k.translate, k.rotate_deg, k.scale, base)?;
                keyframes.push(Keyframe { time_s, transform });
            }
            Ok(Animation::Keyframes { keyframes, looping })
        }
        (None, Some(pattern)) => {
            let frames = a.frames.ok_or_else(|| {
                ck.invalid(
                    &f("frames"),
                    "an `obj_sequence` needs `frames = N` (N >= 1)",
                )
            })?;
            if frames == 0 {
                return Err(ck.invalid(&f("frames"), "0 frames; expected at least 1"));
            }
            let fps = ck.scalar(&f("fps"), a.fps.unwrap_or(24.0))?;
            if fps <= 0.0 {
                return Err(ck.invalid(&f("fps"), format!("{fps}; expected frames per second > 0")));
            }
            let first = a.first_frame.unwrap_or(0);
            let seq_field = f("obj_sequence");
            let referenced_by = field_ref(ck.file, &seq_field);
            let mut meshes = Vec::with_capacity(frames as usize);
            let mut frame_aabbs = Vec::with_capacity(frames as usize);
            let mut first_path = PathBuf::new();
            for n in 0..frames {
                let number = first.checked_add(n).ok_or_else(|| {
                    ck.invalid(&f("first_frame"), "first_frame + frames overflows")
                })?;
                let name = format_frame(pattern, number).ok_or_else(|| {
                    ck.invalid(
                        &seq_field,
                        format!(
                            "`{pattern}` has no frame-number placeholder; expected `{{}}` or \
                             `{{:0N}}` (zero-padded to N digits), e.g. \"anim/frame_{{:03}}.obj\""
                        ),
                    )
                })?;
                let path = base_dir.join(&name);
                // Every frame smooth (crease 180°) so that no frame splits other vertices
                // than the first: the frames must keep one topology.
                let idx = store.obj_mesh(&path, "OBJ sequence frame", &referenced_by, 180.0)?;
                if let Some(&m0) = meshes.first() {
                    check_same_topology(store, m0, idx, &path, &first_path, &referenced_by)?;
                } else {
                    first_path = path.clone();
                }
                meshes.push(idx);
                frame_aabbs.push(store.meshes.get(idx).map(|m| m.aabb).unwrap_or(Aabb::EMPTY));
            }
            if a.fps.is_none() {
                log::info!(
                    "{}: {field}: no `fps` given, playing at 24 frames per second",
                    ck.file.display()
                );
            }
            Ok(Animation::ObjSequence {
                meshes,
                frame_aabbs,
                fps,
                looping,
            })
        }
    }
}

fn check_same_topology(
    store: &AssetStore,
    first: usize,
    other: usize,
    path: &Path,
    first_path: &Path,
    referenced_by: &str,
) -> Result<(), SceneError> {
    let (Some(a), Some(b)) = (store.meshes.get(first), store.meshes.get(other)) else {
        return Ok(());
    };
    let problem = if a.positions.len() != b.positions.len() {
        Some(format!(
            "{} vertices instead of {}",
            b.positions.len(),
            a.positions.len()
        ))
    } else if a.indices != b.indices {
        Some(format!(
            "different faces ({} triangles, first has {})",
            b.triangle_count(),
            a.triangle_count()
        ))
    } else if a.submeshes != b.submeshes {
        Some("different material groups".to_string())
    } else if a.uvs.is_some() != b.uvs.is_some() {
        Some("texture coordinates present in one frame only".to_string())
    } else {
        None
    };
    match problem {
        None => Ok(()),
        Some(problem) => Err(SceneError::SequenceTopology {
            file: path.to_path_buf(),
            first_frame: first_path.to_path_buf(),
            problem,
            referenced_by: referenced_by.to_string(),
        }),
    }
}

/// Replaces the first `{}` or `{:0N}` / `{:N}` in `pattern` by `n` (zero-padded to N digits).
pub(crate) fn format_frame(pattern: &str, n: u32) -> Option<String> {
    let start = pattern.find('{')?;
    let end = start + pattern[start..].find('}')?;
    let spec = &pattern[start + 1..end];
    let width = match spec {
        "" => 0,
        s => s.strip_prefix(':')?.parse::<usize>().ok()?,
    };
    // Widths beyond 32 digits are typos; refuse rather than allocate.
    if width > 32 {
        return None;
    }
    Some(format!(
        "{}{:0width$}{}",
        &pattern[..start],
        n,
        &pattern[end + 1..],
        width = width
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        assert_eq!(format_frame("f_{:03}.obj", 7).as_deref(), Some("f_007.obj"));
        assert_eq!(format_frame("f_{}.obj", 12).as_deref(), Some("f_12.obj"));
        assert_eq!(
            format_frame("f_{:4}.obj", 12).as_deref(),
            Some("f_0012.obj")
        );
        assert_eq!(format_frame("f.obj", 1), None);
        assert_eq!(format_frame("f_{x}.obj", 1), None);
        assert_eq!(format_frame("f_{:999}.obj", 1), None);
    }
}
