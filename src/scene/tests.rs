//! Scene loading tests: the asset scenes, every user error, OBJ details, and a fuzz test.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use proptest::prelude::*;

use super::*;

fn asset(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(rel)
}

/// A fresh directory under the system temp dir, unique per test and process.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("voxgi_scene_{tag}_{}_{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).unwrap();
        }
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const CAMERA: &str = "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n";
const LIGHT: &str = "[[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 1.0\n";
const CUBE: &str = "[[objects]]\nbuiltin = \"cube\"\n";
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// Writes `scene.toml` with `text` (plus `files`) and loads it; returns the error and the
/// scene path.
fn load_err(text: &str, files: &[(&str, &str)]) -> (SceneError, PathBuf) {
    let dir = TempDir::new("err");
    for (name, content) in files {
        dir.write(name, content);
    }
    let path = dir.write("scene.toml", text);
    match Scene::load(&path) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => (e, path),
    }
}

fn load_ok(text: &str, files: &[(&str, &str)]) -> Scene {
    let dir = TempDir::new("ok");
    for (name, content) in files {
        dir.write(name, content);
    }
    let path = dir.write("scene.toml", text);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The message names the file and contains each of `parts`.
fn assert_msg(e: &SceneError, file: &Path, parts: &[&str]) {
    let msg = e.to_string();
    assert!(
        msg.contains(&file.display().to_string()),
        "message does not name {}: {msg}",
        file.display()
    );
    for p in parts {
        assert!(msg.contains(p), "message lacks `{p}`: {msg}");
    }
}

// ---- asset and built-in scenes -------------------------------------------------------------

#[test]
fn transparency_key_picks_the_mode_and_names_itself_when_wrong() {
    let camera =
        "[camera]\nposition = [0.0, 0.0, -1.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n";
    let object = "[[objects]]\nbuiltin = \"quad\"\n";
    let with = |key: &str| format!("{key}\n{camera}{object}");
    assert_eq!(load_ok(&with(""), &[]).transparency, None);
    let hashed = load_ok(&with("transparency = \"hashed\""), &[]);
    assert_eq!(
        hashed.transparency,
        Some(crate::scene::Transparency::Hashed)
    );
    let oit = load_ok(&with("transparency = \"oit\""), &[]);
    assert_eq!(oit.transparency, Some(crate::scene::Transparency::Oit));
    let (e, path) = load_err(&with("transparency = \"sorted\""), &[]);
    assert_msg(
        &e,
        &path,
        &["transparency", "sorted", "\"oit\" or \"hashed\""],
    );
}

#[test]
fn asset_cornell_loads() {
    let s = Scene::load(asset("scenes/cornell.toml")).unwrap();
    assert_eq!(s.objects.len(), 3);
    assert!(s.source.is_some());
}

#[test]
fn asset_cornell_bunny_sits_on_the_floor() {
    let s = Scene::load(asset("scenes/cornell_bunny.toml")).unwrap();
    let bunny = s.objects.iter().find(|o| o.name == "bunny").unwrap();
    let b = bunny.aabb_at(0.0);
    assert!(b.min.y.abs() < 1e-3, "{b:?}");
    assert!((b.extent().y - 0.2).abs() < 0.005, "{b:?}");
    // Inside the box.
    assert!(b.min.x > 0.0 && b.max.x < 0.55 && b.min.z > 0.0 && b.max.z < 0.559);
    let mesh = &s.meshes[bunny.mesh];
    // The OBJ has no normals: computed, unit length, mostly pointing away from the center.
    assert_eq!(mesh.normals.len(), mesh.positions.len());
    assert!(mesh.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
    let c = mesh.aabb.center();
    let outward = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .filter(|(p, n)| n.dot(**p - c) > 0.0)
        .count();
    assert!(outward * 10 > mesh.positions.len() * 8, "{outward}");
    assert!(s.is_all_lambert());
}

#[test]
fn asset_point_light_loads() {
    let s = Scene::load(asset("scenes/point_light.toml")).unwrap();
    assert!(s.has_point_lights());
    assert!(!s.has_spot_lights());
    assert!(!s.is_all_lambert(), "the ball is Phong");
    assert!(s.has_dynamic_objects() && s.has_animation());
    // The orbiter moves, so the scene bounds change over time but stay finite.
    let orbiter = s.objects.iter().find(|o| o.name == "orbiter").unwrap();
    assert_ne!(orbiter.aabb_at(0.0), orbiter.aabb_at(1.0));
    assert_eq!(
        orbiter.aabb_at(0.0),
        orbiter.aabb_at(4.0),
        "loops after 4 s"
    );
    assert!(s.aabb_at(1.3).min.is_finite() && s.aabb_at(1.3).max.is_finite());
}

#[test]
fn doc_example_follows_the_schema() {
    // The module doc's example uses every key; it must parse (its files need not exist).
    let src = include_str!("mod.rs");
    let start = src.find("```toml").unwrap() + "```toml".len();
    let end = start + src[start..].find("//! ```").unwrap();
    let toml: String = src[start..end]
        .lines()
        .map(|l| l.trim_start().trim_start_matches("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .collect::<Vec<_>>()
        .join("\n");
    let d = desc::parse(&toml, Path::new("doc")).unwrap_or_else(|e| panic!("{e}\n{toml}"));
    assert_eq!(d.objects.len(), 2);
    assert_eq!(d.lights.len(), 3);
    assert!(d.gi.is_some_and(|g| g
        .values
        .iter()
        .any(|(k, v)| k.path == "gi.method" && v.as_str() == Some("pathtrace"))));
}

// ---- error cases -----------------------------------------------------------------------------

#[test]
fn missing_scene_file() {
    let p = std::env::temp_dir().join("voxgi_no_such_scene.toml");
    let e = Scene::load(&p).unwrap_err();
    assert!(matches!(e, SceneError::NotFound { .. }), "{e}");
    assert_msg(&e, &p, &["scene file not found"]);
}

#[test]
fn missing_obj_file() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"meshes/nope.obj\"\n");
    let (e, scene) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::NotFound { .. }), "{e}");
    assert_msg(
        &e,
        &scene,
        &["nope.obj", "objects[0].mesh", "OBJ mesh not found"],
    );
}

#[test]
fn toml_syntax_error_has_line_and_column() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nbuiltin = \"cube\nscale = 2\n");
    let (e, scene) = load_err(&text, &[]);
    let SceneError::TomlSyntax { line, col, .. } = e else {
        panic!("{e}")
    };
    assert_eq!(line, 10);
    assert!(col > 1);
    assert_msg(&e, &scene, &[":10:", "TOML syntax error"]);
}

#[test]
fn unknown_key_is_named() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nbuiltin = \"cube\"\nscal = 2\n");
    let (e, scene) = load_err(&text, &[]);
    let SceneError::UnknownKey { line, ref key, .. } = e else {
        panic!("{e}")
    };
    assert_eq!((line, key.as_str()), (11, "scal"));
    assert_msg(&e, &scene, &["unknown key `scal`", "`scale`", ":11:"]);
    // Also in nested tables.
    let text = format!("{CAMERA}{LIGHT}{CUBE}material = {{ albedo = 0.5, glossiness = 0.2 }}\n");
    let (e, _) = load_err(&text, &[]);
    assert!(
        matches!(e, SceneError::UnknownKey { ref key, .. } if key == "glossiness"),
        "{e}"
    );
}

#[test]
fn wrong_type_is_a_schema_error() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nbuiltin = \"cube\"\nscale = \"big\"\n");
    let (e, scene) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::Schema { line: 11, .. }), "{e}");
    assert_msg(&e, &scene, &["a number or an array of 3 numbers"]);
    let text = format!("{CAMERA}[[lights]]\nkind = \"area\"\n{CUBE}");
    let (e, _) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::Schema { .. }), "{e}");
    assert!(e.to_string().contains("spot"), "{e}");
}

#[test]
fn nan_and_inf_are_rejected() {
    for (text, field) in [
        (
            format!("{CAMERA}{LIGHT}{CUBE}translate = [0, nan, 0]\n"),
            "objects[0].translate[1]",
        ),
        (
            format!("{CAMERA}[[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = inf\n{CUBE}"),
            "lights[0].intensity_w_sr[0]",
        ),
        (
            CAMERA.replace("fov_y_deg = 40", "fov_y_deg = nan") + LIGHT + CUBE,
            "camera.fov_y_deg",
        ),
        (
            CAMERA.replace("[0, 1, -3]", "[0, 1, -inf]") + LIGHT + CUBE,
            "camera.position[2]",
        ),
    ] {
        let (e, scene) = load_err(&text, &[]);
        assert!(matches!(e, SceneError::NonFinite { .. }), "{e}");
        assert_msg(&e, &scene, &[field, "finite"]);
    }
}

#[test]
fn zero_length_direction() {
    let text = format!(
        "{CAMERA}[[lights]]\nkind = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, 0, 0]\nintensity_w_sr = 1\n{CUBE}"
    );
    let (e, scene) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::ZeroLengthDirection { .. }), "{e}");
    assert_msg(&e, &scene, &["lights[0].direction", "zero length"]);
    let text = CAMERA.replace("target = [0, 0, 0]", "forward = [0, 0, 0]") + LIGHT + CUBE;
    let (e, _) = load_err(&text, &[]);
    assert!(
        matches!(e, SceneError::ZeroLengthDirection { ref field, .. } if field == "camera.forward")
    );
}

#[test]
fn camera_toml_table_round_trips() {
    let scene = load_ok(&format!("{CAMERA}{LIGHT}{CUBE}"), &[]);
    let mut cam = scene.camera;
    cam.position = Vec3::new(0.1, -2.5e-3, 1.0 / 3.0);
    cam.forward = Vec3::new(0.3, -0.2, 0.9).normalize();
    let text = format!("{}{LIGHT}{CUBE}", cam.toml_table(glam::DVec3::ZERO));
    assert_eq!(load_ok(&text, &[]).camera, cam, "{text}");
}

#[test]
fn orthographic_camera_loads_and_round_trips() {
    let text = CAMERA.replace(
        "fov_y_deg = 40",
        "projection = \"orthographic\"\northo_height_m = 2.5",
    ) + LIGHT
        + CUBE;
    let scene = load_ok(&text, &[]);
    let mut cam = scene.camera;
    assert_eq!(
        (cam.projection, cam.ortho_height_m, cam.fov_y_deg),
        (crate::scene::Projection::Orthographic, 2.5, 40.0)
    );
    // A direction that survives the file's normalization exactly (as in the test above).
    cam.forward = Vec3::new(0.3, -0.2, 0.9).normalize();
    let text = format!("{}{LIGHT}{CUBE}", cam.toml_table(glam::DVec3::ZERO));
    assert_eq!(load_ok(&text, &[]).camera, cam, "{text}");
    // A perspective camera without a height gets the view's height at the depth of the
    // scene's centre: the unit cube at the origin, 3.16 m along the view from (0, 1, -3).
    let scene = load_ok(&format!("{CAMERA}{LIGHT}{CUBE}"), &[]);
    let depth = 10f32.sqrt();
    let expected = 2.0 * depth * 20f32.to_radians().tan();
    assert!(
        (scene.camera.ortho_height_m - expected).abs() < 1e-4,
        "{} vs {expected}",
        scene.camera.ortho_height_m
    );
}

#[test]
fn bad_camera() {
    for (from, to, field) in [
        ("fov_y_deg = 40", "fov_y_deg = 0", "camera.fov_y_deg"),
        ("fov_y_deg = 40", "fov_y_deg = -10", "camera.fov_y_deg"),
        ("fov_y_deg = 40", "fov_y_deg = 180", "camera.fov_y_deg"),
        (
            "fov_y_deg = 40",
            "fov_y_deg = 40\nnear = 1\nfar = 1",
            "camera.far",
        ),
        (
            "fov_y_deg = 40",
            "fov_y_deg = 40\nnear = 2\nfar = 1",
            "camera.far",
        ),
        ("fov_y_deg = 40", "fov_y_deg = 40\nnear = 0", "camera.near"),
        ("target = [0, 0, 0]", "target = [0, 1, -3]", "camera.target"),
        ("target = [0, 0, 0]", "forward = [0, 1, 0]", "camera.up"),
        ("target = [0, 0, 0]", "", "camera"),
        (
            "fov_y_deg = 40",
            "fov_y_deg = 40\nprojection = \"isometric\"",
            "camera.projection",
        ),
        (
            "fov_y_deg = 40",
            "projection = \"orthographic\"",
            "camera.ortho_height_m",
        ),
        ("fov_y_deg = 40", "ortho_height_m = 1", "camera.fov_y_deg"),
        (
            "fov_y_deg = 40",
            "fov_y_deg = 40\northo_height_m = 0",
            "camera.ortho_height_m",
        ),
        (
            "fov_y_deg = 40",
            "projection = \"orthographic\"\northo_height_m = -2",
            "camera.ortho_height_m",
        ),
        (
            "fov_y_deg = 40",
            "projection = \"orthographic\"\northo_height_m = nan",
            "camera.ortho_height_m",
        ),
    ] {
        let text = CAMERA.replace(from, to) + LIGHT + CUBE;
        let (e, scene) = load_err(&text, &[]);
        assert!(
            matches!(e, SceneError::InvalidCamera { field: ref f, .. } if f == field),
            "{to}: {e}"
        );
        assert_msg(&e, &scene, &[field]);
    }
}

#[test]
fn negative_intensity() {
    let text = format!(
        "{CAMERA}[[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = [1, -0.5, 1]\n{CUBE}"
    );
    let (e, scene) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::NegativeIntensity { .. }), "{e}");
    assert_msg(&e, &scene, &["lights[0].intensity_w_sr[1]", "-0.5", ">= 0"]);
    let text = format!(
        "{CAMERA}[[lights]]\nkind = \"directional\"\ndirection = [0, -1, 0]\nirradiance_w_m2 = -1\n{CUBE}"
    );
    let (e, _) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::NegativeIntensity { .. }), "{e}");
}

#[test]
fn light_fields_must_fit_the_kind() {
    for (light, field) in [
        ("kind = \"spot\"\nposition = [0, 2, 0]\nintensity_w_sr = 1", "lights[0].direction"),
        ("kind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 1\ncutoff_deg = 10", "lights[0].cutoff_deg"),
        ("kind = \"directional\"\ndirection = [0, -1, 0]\nintensity_w_sr = 1", "lights[0].irradiance_w_m2"),
        ("kind = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity_w_sr = 1\ncutoff_deg = 10\nbeam_deg = 20", "lights[0].beam_deg"),
        ("kind = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity_w_sr = 1\ncutoff_deg = 95", "lights[0].cutoff_deg"),
    ] {
        let text = format!("{CAMERA}[[lights]]\n{light}\n{CUBE}");
        let (e, scene) = load_err(&text, &[]);
        assert!(matches!(e, SceneError::InvalidValue { .. }), "{e}");
        assert_msg(&e, &scene, &[field]);
    }
}

#[test]
fn spot_defaults_follow_mitsuba() {
    let text = format!(
        "{CAMERA}[[lights]]\nkind = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -2, 0]\nintensity_w_sr = 1\n{CUBE}"
    );
    let s = load_ok(&text, &[]);
    let Light::Spot {
        cutoff_deg,
        beam_deg,
        direction,
        ..
    } = s.lights[0]
    else {
        panic!()
    };
    assert_eq!((cutoff_deg, beam_deg), (20.0, 15.0));
    assert_eq!(direction, -Vec3::Y);
}

#[test]
fn empty_scene() {
    let (e, scene) = load_err(&format!("{CAMERA}{LIGHT}"), &[]);
    assert!(matches!(e, SceneError::EmptyScene { .. }), "{e}");
    assert_msg(&e, &scene, &["no objects", "[[objects]]"]);
}

#[test]
fn object_errors() {
    for (obj, field) in [
        ("builtin = \"teapot\"", "objects[0].builtin"),
        ("builtin = \"cube\"\nmesh = \"a.obj\"", "objects[0].builtin"),
        ("name = \"x\"", "objects[0]"),
        ("builtin = \"cube\"\nscale = [1, 0, 1]", "objects[0].scale"),
        (
            "builtin = \"cube\"\nmaterial = { albedo = 1.5 }",
            "objects[0].material.albedo",
        ),
        (
            "builtin = \"cube\"\nmaterial = { shininess = -1 }",
            "objects[0].material.shininess",
        ),
        (
            "builtin = \"cube\"\ndynamic = false\nanimation = { keyframes = [{ time_s = 0 }] }",
            "objects[0].dynamic",
        ),
        (
            "builtin = \"cube\"\nanimation = { keyframes = [{ time_s = 1 }, { time_s = 1 }] }",
            "objects[0].animation.keyframes[1].time_s",
        ),
        (
            "builtin = \"cube\"\nanimation = { keyframes = [] }",
            "objects[0].animation.keyframes",
        ),
        (
            "builtin = \"cube\"\nanimation = { loop = true }",
            "objects[0].animation",
        ),
        (
            "animation = { obj_sequence = \"f.obj\", frames = 2 }",
            "objects[0].animation.obj_sequence",
        ),
        (
            "animation = { obj_sequence = \"f{}.obj\", frames = 0 }",
            "objects[0].animation.frames",
        ),
    ] {
        let text = format!("{CAMERA}{LIGHT}[[objects]]\n{obj}\n");
        let (e, scene) = load_err(&text, &[]);
        assert!(matches!(e, SceneError::InvalidValue { .. }), "{obj}: {e}");
        assert_msg(&e, &scene, &[field]);
    }
}

// ---- OBJ files -----------------------------------------------------------------------------

#[test]
fn malformed_obj_names_the_file() {
    // tobj rejects this one itself (no line known).
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nusemtl\n";
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let (e, scene) = load_err(&text, &[("m.obj", obj)]);
    assert!(
        matches!(e, SceneError::MalformedObj { kind: "OBJ", .. }),
        "{e}"
    );
    assert_msg(&e, &scene.with_file_name("m.obj"), &["malformed OBJ"]);
    // Caught before tobj, with a line.
    let (e, scene) = load_err(&text, &[("m.obj", "v 0 0\n")]);
    assert!(
        matches!(e, SceneError::MalformedObj { line: Some(1), .. }),
        "{e}"
    );
    assert_msg(&e, &scene.with_file_name("m.obj"), &["m.obj:1"]);
    // No faces at all.
    let (e, _) = load_err(&text, &[("m.obj", "v 0 0 0\n")]);
    assert!(matches!(e, SceneError::MalformedObj { .. }), "{e}");
}

#[test]
fn malformed_mtl_names_the_mtl_file() {
    let obj = format!("mtllib m.mtl\nusemtl a\n{TRIANGLE_OBJ}");
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let (e, scene) = load_err(&text, &[("m.obj", &obj), ("m.mtl", "newmtl a\nKd 1 2\n")]);
    assert!(
        matches!(e, SceneError::MalformedObj { kind: "MTL", .. }),
        "{e}"
    );
    assert_msg(&e, &scene.with_file_name("m.mtl"), &["line 2", "Kd r g b"]);
}

#[test]
fn face_index_out_of_range() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n";
    let (e, scene) = load_err(&text, &[("m.obj", obj)]);
    assert!(
        matches!(
            e,
            SceneError::FaceIndexOutOfRange {
                line: 5,
                index: 7,
                count: 3,
                ..
            }
        ),
        "{e}"
    );
    assert_msg(&e, &scene.with_file_name("m.obj"), &["m.obj:5", "vertex 7"]);
}

#[test]
fn nan_vertex_is_rejected() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let obj = "v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n";
    let (e, scene) = load_err(&text, &[("m.obj", obj)]);
    assert!(
        matches!(e, SceneError::NonFiniteVertex { line: 2, .. }),
        "{e}"
    );
    assert_msg(
        &e,
        &scene.with_file_name("m.obj"),
        &["m.obj:2", "non-finite"],
    );
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 inf 1\nf 1//1 2//1 3//1\n";
    let (e, _) = load_err(&text, &[("m.obj", obj)]);
    assert!(
        matches!(e, SceneError::NonFiniteVertex { line: 4, .. }),
        "{e}"
    );
}

#[test]
fn obj_normals_computed_or_taken() {
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let s = load_ok(&text, &[("m.obj", TRIANGLE_OBJ)]);
    let m = &s.meshes[s.objects[0].mesh];
    assert_eq!(m.positions.len(), 3);
    assert!(m.normals.iter().all(|n| n.abs_diff_eq(Vec3::Z, 1e-6)));
    assert!(m.uvs.is_none());
    // Given normals are normalized and used as they are.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 2 0\nvt 0 0\nf 1/1/1 2/1/1 3/1/1\n";
    let s = load_ok(&text, &[("m.obj", obj)]);
    let m = &s.meshes[s.objects[0].mesh];
    assert!(m.normals.iter().all(|n| n.abs_diff_eq(Vec3::Y, 1e-6)));
    assert_eq!(m.uvs.as_ref().map(Vec::len), Some(3));
    // Without an MTL, the default material.
    assert_eq!(
        s.materials[s.objects[0].materials[0]].albedo,
        Vec3::splat(0.5)
    );
}

#[test]
fn mtl_materials_textures_and_missing_texture() {
    let dir = TempDir::new("tex");
    let img = image::RgbaImage::from_pixel(2, 3, image::Rgba([10, 20, 30, 255]));
    img.save(dir.0.join("albedo.png")).unwrap();
    dir.write(
        "m.mtl",
        "newmtl shiny\nKd 0.2 0.4 0.6\nKs 0.3 0.3 0.3\nNs 50\nd 0.5\nmap_Kd albedo.png\n\
         newmtl lost\nKd 0.1 0.2 0.3\nmap_Kd missing.png\nmap_bump missing_bump.png\n",
    );
    dir.write(
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl shiny\nf 1 2 3\nusemtl lost\nf 2 4 3\n",
    );
    let scene = dir.write(
        "scene.toml",
        &format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n[[objects]]\nmesh = \"m.obj\"\nmaterial = {{ albedo = 0.9 }}\n"),
    );
    let s = Scene::load(&scene).unwrap();
    // Both objects share the mesh.
    assert_eq!(s.meshes.len(), 1);
    let m = &s.meshes[0];
    assert_eq!(m.submeshes.len(), 2);
    let shiny = &s.materials[s.objects[0].materials[0]];
    assert_eq!(shiny.albedo, Vec3::new(0.2, 0.4, 0.6));
    assert_eq!((shiny.shininess, shiny.opacity), (50.0, 0.5));
    assert!(!shiny.is_lambert());
    let t = &s.textures[shiny.albedo_texture.unwrap()];
    assert_eq!((t.width, t.height, t.srgb, t.rgba8.len()), (2, 3, true, 24));
    assert_eq!(&t.rgba8[..4], &[10, 20, 30, 255]);
    // Missing textures: a warning, and the color stays.
    let lost = &s.materials[s.objects[0].materials[1]];
    assert_eq!(lost.albedo_texture, None);
    assert_eq!(lost.bump_texture, None);
    assert_eq!(lost.albedo, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(s.textures.len(), 1);
    // The override replaces the albedo (and drops the albedo map) but keeps the rest.
    let o = &s.materials[s.objects[1].materials[0]];
    assert_eq!(
        (o.albedo, o.albedo_texture, o.shininess),
        (Vec3::splat(0.9), None, 50.0)
    );
    assert!(!s.is_all_lambert() && s.has_albedo_textures() && s.has_transparency());
}

#[test]
fn undecodable_texture_is_an_error() {
    let obj = format!("mtllib m.mtl\nusemtl a\n{TRIANGLE_OBJ}");
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let (e, scene) = load_err(
        &text,
        &[
            ("m.obj", &obj),
            ("m.mtl", "newmtl a\nmap_Kd bad.png\n"),
            ("bad.png", "not a png"),
        ],
    );
    assert!(matches!(e, SceneError::TextureDecode { .. }), "{e}");
    assert_msg(&e, &scene.with_file_name("bad.png"), &["map_Kd"]);
}

#[test]
fn missing_mtl_is_a_warning() {
    let obj = format!("mtllib gone.mtl\nusemtl a\n{TRIANGLE_OBJ}");
    let text = format!("{CAMERA}{LIGHT}[[objects]]\nmesh = \"m.obj\"\n");
    let s = load_ok(&text, &[("m.obj", &obj)]);
    assert_eq!(
        s.materials[s.objects[0].materials[0]].albedo,
        Vec3::splat(0.5)
    );
}

#[test]
fn obj_sequence_frames() {
    let frame = |z: f32| format!("v 0 0 {z}\nv 1 0 {z}\nv 0 1 {z}\nf 1 2 3\n");
    let (f1, f2, f3) = (frame(0.0), frame(1.0), frame(2.0));
    let text = format!(
        "{CAMERA}{LIGHT}[[objects]]\nanimation = {{ obj_sequence = \"anim/f_{{:02}}.obj\", frames = 3, fps = 2.0, first_frame = 1 }}\n"
    );
    let s = load_ok(
        &text,
        &[
            ("anim/f_01.obj", &f1),
            ("anim/f_02.obj", &f2),
            ("anim/f_03.obj", &f3),
        ],
    );
    let o = &s.objects[0];
    assert!(o.dynamic);
    assert_eq!(s.meshes.len(), 3);
    let z_at = |t: f32| s.meshes[o.mesh_at(t)].positions[0].z;
    assert_eq!(
        (z_at(0.0), z_at(0.6), z_at(1.2), z_at(1.6)),
        (0.0, 1.0, 2.0, 0.0)
    );
    assert_eq!(o.aabb_at(1.2).min.z, 2.0);
    // A frame with another topology.
    let bad = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    let (e, scene) = load_err(
        &text,
        &[
            ("anim/f_01.obj", &f1),
            ("anim/f_02.obj", bad),
            ("anim/f_03.obj", &f3),
        ],
    );
    assert!(matches!(e, SceneError::SequenceTopology { .. }), "{e}");
    let frame2 = scene.with_file_name("anim").join("f_02.obj");
    assert_msg(&e, &frame2, &["f_01.obj", "4 vertices instead of 3"]);
    // A missing frame.
    let (e, _) = load_err(&text, &[("anim/f_01.obj", &f1)]);
    assert!(
        matches!(e, SceneError::NotFound { ref file, .. } if file.ends_with("f_02.obj")),
        "{e}"
    );
}

#[test]
fn keyframes_inherit_the_object_transform() {
    let text = format!(
        "{CAMERA}{LIGHT}[[objects]]\nbuiltin = \"cube\"\ntranslate = [0, 5, 0]\nscale = 2\n\
         animation = {{ loop = false, keyframes = [{{ time_s = 0, translate = [0, 0, 0] }}, {{ time_s = 1, translate = [2, 0, 0] }}] }}\n"
    );
    let s = load_ok(&text, &[]);
    let b = s.aabb_at(0.5);
    // Scale 2 kept from the object; translation interpolated.
    assert!(b.min.abs_diff_eq(Vec3::new(0.0, -1.0, -1.0), 1e-5), "{b:?}");
    assert!(b.max.abs_diff_eq(Vec3::new(2.0, 1.0, 1.0), 1e-5), "{b:?}");
    assert!(s.has_dynamic_objects());
}

/// The `[voxel]` table sets the grid a renderer voxelizes with, and refuses what its flags
/// refuse, naming the file and the key.
#[test]
fn voxel_table_sets_the_grid() {
    use crate::scene::{VoxelSettings, Voxelizer};
    let text = format!(
        "{CAMERA}{LIGHT}{CUBE}[voxel]\nresolution = 256\nlayers = 2\nvoxelizer = \"atlas\"\n\
         revoxelize = true\n"
    );
    let s = load_ok(&text, &[]);
    assert_eq!(
        s.voxel_settings(),
        VoxelSettings {
            max_res_xy: 256,
            layers: 2,
            revoxelize_static: true,
            voxelizer: Voxelizer::Atlas,
        }
    );
    assert!(s.gi.is_empty(), "no [gi] table: nothing given");
    let s = load_ok(&format!("{CAMERA}{LIGHT}{CUBE}"), &[]);
    assert_eq!(s.voxel_settings(), VoxelSettings::default());
    for (line, field, expected) in [
        ("resolution = 0", "voxel.resolution", "[1, 16384]"),
        ("layers = 65", "voxel.layers", "[1, 64]"),
        ("voxelizer = \"splat\"", "voxel.voxelizer", "triangle"),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[voxel]\n{line}\n");
        let (e, scene) = load_err(&text, &[]);
        assert!(
            matches!(e, SceneError::InvalidValue { field: ref f, .. } if f == field),
            "{line}: {e}"
        );
        assert_msg(&e, &scene, &[&format!("`{field}`"), expected]);
    }
    let (e, _) = load_err(&format!("{CAMERA}{LIGHT}{CUBE}[voxel]\nsize = 3\n"), &[]);
    assert!(e.to_string().contains("resolution"), "{e}");
}

// ---- the [gi] table ------------------------------------------------------------------------

#[test]
fn gi_table_parses_every_key() {
    let text = format!(
        "{CAMERA}{LIGHT}{CUBE}[gi]\nmethod = \"pathtrace\"\nrays = 8\nbounces = 3\n\
         radius_m = 1.5\nnormal_offset_voxels = 0.5\nray_offset_voxels = 2\n\
         filter_radius = 0\nfilter_passes = 1\nlight_map_resolution = 128\n\
         accumulate_frames = 64\nvpls = 4\nvpl_pattern = [2, 3]\nvpl_bounces = 1\n\
         vpl_d_min_voxels = 2.5\nvpl_min_roughness = 0.3\nvpl_visibility = \"none\"\n\
         vpl_normalize = \"valid\"\nvpl_spot_sampling = \"disk\"\nssgi_resolution = \"quarter\"\n\
         ssgi_samples = 12\nssgi_mips = \"fast\"\nssgi_feedback = false\n\
         ssgi_feedback_max_w_m2 = 5.5\nssgi_history_weight = 0.5\nssr = false\n\
         ssr_rays = \"lobe\"\n\
         sao = true\nsao_radius_m = 0.6\nsao_bias = 0.02\nsao_contrast = 3\nsao_epsilon_m2 = 0.5\n"
    );
    let s = load_ok(&text, &[]);
    use crate::scene::vpl_settings::{VplNormalize, VplSpotSampling};
    let d = GiSettings::default();
    let want = GiSettings {
        method: crate::scene::GiMethod::Pathtrace,
        rays: 8,
        bounces: crate::scene::Bounces::Fixed(3),
        radius_m: Some(1.5),
        normal_offset_voxels: 0.5,
        ray_offset_voxels: 2.0,
        filter_radius: 0,
        filter_passes: 1,
        light_map_resolution: 128,
        accumulate_frames: 64,
        vpl: crate::scene::VplSettings {
            per_set: 4,
            pattern: [2, 3],
            bounces: 1,
            d_min_voxels: 2.5,
            min_roughness: 0.3,
            visibility: crate::scene::VplVisibility::None,
            normalize: VplNormalize::Valid,
            spot_sampling: VplSpotSampling::Disk,
            ..d.vpl
        },
        ssgi: crate::scene::SsgiSettings {
            resolution: crate::scene::SsgiResolution::Quarter,
            samples: 12,
            mips: crate::scene::SsgiMips::Fast,
            feedback: false,
            feedback_max_w_m2: 5.5,
            history_weight: 0.5,
            ssr: false,
            ssr_rays: crate::scene::SsrRays::Lobe,
        },
        sao: Some(crate::scene::SaoSettings {
            radius_m: 0.6,
            bias: 0.02,
            contrast: 3.0,
            epsilon_m2: 0.5,
            ..Default::default()
        }),
        ..d
    };
    assert_eq!(resolve_gi(&s.gi, &schema::Layer::default()), want);
    // Every key the table names is in the scene's layer, and nothing else.
    assert_eq!(s.gi.iter().count(), 31);
    // Partial tables give only what they name; the rest stays the defaults'.
    for (method, m) in [
        ("none", crate::scene::GiMethod::None),
        ("hemisphere", crate::scene::GiMethod::Hemisphere),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\nmethod = \"{method}\"\n");
        let s = load_ok(&text, &[]);
        assert_eq!(
            s.gi.iter().map(|(k, _)| k).collect::<Vec<_>>(),
            ["gi.method"]
        );
        assert_eq!(
            resolve_gi(&s.gi, &schema::Layer::default()),
            GiSettings { method: m, ..d }
        );
    }
    // Bounces: a count up to the safety cap, or unbounded (Russian roulette).
    for (value, b) in [
        ("1", crate::scene::Bounces::Fixed(1)),
        ("64", crate::scene::Bounces::Fixed(64)),
        ("\"unbounded\"", crate::scene::Bounces::Unbounded),
    ] {
        let s = load_ok(
            &format!("{CAMERA}{LIGHT}{CUBE}[gi]\nbounces = {value}\n"),
            &[],
        );
        let gi = resolve_gi(&s.gi, &schema::Layer::default());
        assert_eq!(gi.bounces, b, "{value}");
    }
    let s = load_ok(&format!("{CAMERA}{LIGHT}{CUBE}[gi]\nrays = 4\n"), &[]);
    let settings = resolve_gi(&s.gi, &schema::Layer::default());
    assert_eq!(settings.rays, 4);
    assert_eq!(settings.method, crate::scene::GiMethod::None);
}

#[test]
fn gi_unknown_method_names_file_field_and_choices() {
    let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\nmethod = \"photons\"\n");
    let (e, scene) = load_err(&text, &[]);
    assert!(
        matches!(e, SceneError::InvalidValue { ref field, .. } if field == "gi.method"),
        "{e}"
    );
    assert_msg(
        &e,
        &scene,
        &[
            "`gi.method`",
            "\"photons\"",
            "\"none\"",
            "\"hemisphere\"",
            "\"pathtrace\"",
            "\"vpl\"",
        ],
    );
}

#[test]
fn gi_out_of_range_values_name_the_field() {
    for (line, field, expected) in [
        (
            "rays = -4",
            "gi.rays",
            "-4; expected rays per pixel, an integer in [1, 4096]",
        ),
        ("rays = 0", "gi.rays", "[1, 4096]"),
        ("bounces = 0", "gi.bounces", "path-tracer bounces"),
        ("bounces = 65", "gi.bounces", "[1, 64] or \"unbounded\""),
        (
            "bounces = \"inf\"",
            "gi.bounces",
            "\"inf\"; expected path-tracer bounces",
        ),
        (
            "bounces = 2.5",
            "gi.bounces",
            "\"unbounded\" (Russian roulette)",
        ),
        ("bounces = true", "gi.bounces", "true; expected"),
        ("filter_radius = -1", "gi.filter_radius", "[0, 64]"),
        ("filter_passes = 100", "gi.filter_passes", "[0, 16]"),
        (
            "light_map_resolution = 4",
            "gi.light_map_resolution",
            "[16, 8192]",
        ),
        (
            "accumulate_frames = 0",
            "gi.accumulate_frames",
            "frames to accumulate",
        ),
        ("radius_m = 0", "gi.radius_m", "in (0, "),
        ("radius_m = -2.5", "gi.radius_m", "a ray length in meters"),
        (
            "normal_offset_voxels = -1",
            "gi.normal_offset_voxels",
            "in [0, ",
        ),
        (
            "ray_offset_voxels = -0.5",
            "gi.ray_offset_voxels",
            "in [0, ",
        ),
        (
            "vpls = 0",
            "gi.vpls",
            "VPLs per set and light, an integer in [1, 1024]",
        ),
        ("vpl_pattern = [4, 17]", "gi.vpl_pattern", "[1, 16]"),
        ("vpl_bounces = 9", "gi.vpl_bounces", "[1, 8]"),
        ("vpl_d_min_voxels = -1", "gi.vpl_d_min_voxels", "in [0, "),
        (
            "vpl_min_roughness = 1.5",
            "gi.vpl_min_roughness",
            "a roughness, a finite number in [0, 1]",
        ),
        (
            "vpl_visibility = \"rays\"",
            "gi.vpl_visibility",
            "\"voxel\" or \"none\"",
        ),
        (
            "vpl_normalize = \"some\"",
            "gi.vpl_normalize",
            "\"all\" or \"valid\"",
        ),
        (
            "vpl_spot_sampling = \"cone\"",
            "gi.vpl_spot_sampling",
            "\"solid-angle\" or \"disk\"",
        ),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\n{line}\n");
        let (e, scene) = load_err(&text, &[]);
        assert!(
            matches!(e, SceneError::InvalidValue { field: ref f, .. } if f == field),
            "{line}: {e}"
        );
        assert_msg(&e, &scene, &[&format!("`{field}`"), expected]);
    }
    let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\nradius_m = nan\n");
    let (e, scene) = load_err(&text, &[]);
    assert!(
        matches!(e, SceneError::NonFinite { ref field, .. } if field == "gi.radius_m"),
        "{e}"
    );
    assert_msg(&e, &scene, &["`gi.radius_m`", "finite"]);
}

#[test]
fn gi_unknown_key_and_wrong_type_are_named() {
    let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\nmethod = \"hemisphere\"\nraays = 4\n");
    let (e, scene) = load_err(&text, &[]);
    let SceneError::UnknownKey { line, ref key, .. } = e else {
        panic!("{e}")
    };
    assert_eq!((line, key.as_str()), (13, "raays"));
    assert_msg(
        &e,
        &scene,
        &[
            "unknown key `raays`",
            "`rays`",
            "`accumulate_frames`",
            ":13:",
        ],
    );
    let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\nrays = \"many\"\n");
    let (e, scene) = load_err(&text, &[]);
    assert!(matches!(e, SceneError::Schema { line: 12, .. }), "{e}");
    assert_msg(&e, &scene, &["rays = \"many\""]);
}

// ---- fuzzing -------------------------------------------------------------------------------

/// Lines a scene file may contain, with numbers to be filled in.
const FRAGMENTS: &[&str] = &[
    "[camera]",
    "position = [{}, {}, {}]",
    "target = [{}, {}, {}]",
    "forward = [{}, {}, {}]",
    "up = [{}, {}, {}]",
    "fov_y_deg = {}",
    "near = {}",
    "far = {}",
    "[[lights]]",
    "kind = \"point\"",
    "kind = \"spot\"",
    "kind = \"directional\"",
    "direction = [{}, {}, {}]",
    "intensity_w_sr = {}",
    "irradiance_w_m2 = [{}, {}, {}]",
    "cutoff_deg = {}",
    "beam_deg = {}",
    "[[objects]]",
    "builtin = \"cube\"",
    "builtin = \"sphere\"",
    "builtin = \"cornell_walls\"",
    "mesh = \"nowhere.obj\"",
    "translate = [{}, {}, {}]",
    "rotate_deg = [{}, {}, {}]",
    "scale = {}",
    "material = { albedo = {}, specular = {}, shininess = {} }",
    "dynamic = true",
    "animation = { keyframes = [{ time_s = {}, translate = [{}, {}, {}] }, { time_s = {}, scale = {} }] }",
    "animation = { obj_sequence = \"f{}.obj\", frames = 3 }",
    "[voxel]",
    "x = {}",
    "[gi]",
    "method = \"pathtrace\"",
    "rays = {}",
    "radius_m = {}",
    "= = [",
    "\"",
];

const NUMBERS: &[&str] = &[
    "0", "1", "-1", "0.5", "1e30", "-1e30", "1e-30", "nan", "inf", "-inf", "180", "90", "1e6",
    "\"s\"", "[1, 2]",
];

fn fill(fragment: &str, numbers: &[usize]) -> String {
    let mut out = String::new();
    let mut k = 0;
    for (i, part) in fragment.split("{}").enumerate() {
        if i > 0 {
            out.push_str(NUMBERS[numbers[k % numbers.len()] % NUMBERS.len()]);
            k += 1;
        }
        out.push_str(part);
    }
    out
}

/// What a loaded scene promises: finite numbers, unit directions, finite matrices.
fn check_invariants(s: &Scene) {
    let c = &s.camera;
    assert!(c.position.is_finite() && c.forward.is_normalized() && c.up.is_normalized());
    assert!(c.view_proj(16.0 / 9.0).is_finite());
    for l in &s.lights {
        match *l {
            Light::Point {
                position,
                intensity_w_sr,
            } => {
                assert!(position.is_finite() && intensity_w_sr.min_element() >= 0.0);
            }
            Light::Spot {
                direction,
                cutoff_deg,
                beam_deg,
                ..
            } => {
                assert!(direction.is_normalized() && beam_deg <= cutoff_deg);
            }
            Light::Directional { direction, .. } => assert!(direction.is_normalized()),
            Light::Sphere {
                position,
                radius_m,
                radiance_w_sr_m2,
                samples,
            } => {
                assert!(position.is_finite() && radius_m > 0.0 && radius_m.is_finite());
                assert!(radiance_w_sr_m2.is_finite() && radiance_w_sr_m2.min_element() >= 0.0);
                assert!((1..=64).contains(&samples));
            }
            Light::Rectangle {
                normal,
                width_axis,
                width_m,
                height_m,
                radiance_w_sr_m2,
                ..
            } => {
                assert!(normal.is_normalized() && width_axis.is_normalized());
                assert!(normal.dot(width_axis).abs() < 1e-3);
                assert!(width_m > 0.0 && height_m > 0.0 && width_m.is_finite());
                assert!(radiance_w_sr_m2.is_finite() && radiance_w_sr_m2.min_element() >= 0.0);
            }
            Light::Element { .. } => panic!("scene files never make area-light samples"),
        }
    }
    for o in &s.objects {
        assert!(o.mesh < s.meshes.len());
        assert!(o.materials.iter().all(|&m| m < s.materials.len()));
        for t in [0.0, 0.37, 5.0, -3.0] {
            assert!(!o.transform_at(t).is_nan());
            let _ = o.mesh_at(t);
        }
    }
}

/// Keys of a light and of an object, each a line with numbers to be filled in.
const LIGHT_KEYS: &[&str] = &[
    "position = [{}, {}, {}]",
    "direction = [{}, {}, {}]",
    "intensity_w_sr = [{}, {}, {}]",
    "irradiance_w_m2 = {}",
    "cutoff_deg = {}",
    "beam_deg = {}",
    "radiance_w_sr_m2 = [{}, {}, {}]",
    "radius_m = {}",
    "normal = [{}, {}, {}]",
    "width_m = {}",
    "height_m = {}",
    "samples = {}",
];
const LIGHT_KINDS: &[&str] = &["point", "spot", "directional", "sphere", "rectangle"];
const OBJECT_KEYS: &[&str] = &[
    "translate = [{}, {}, {}]",
    "rotate_deg = [{}, {}, {}]",
    "scale = {}",
    "material = { albedo = {}, specular = {}, shininess = {}, opacity = {} }",
    "dynamic = true",
    "animation = { loop = false, keyframes = [{ time_s = {}, translate = [{}, {}, {}] }, { time_s = {}, scale = {}, rotate_deg = [{}, 0, {}] }] }",
];
const BUILTINS: &[&str] = &[
    "cube",
    "quad",
    "sphere",
    "cornell_walls",
    "cornell_tall_block",
];
/// Mostly valid numbers, so that many generated scenes load and get their invariants checked.
const GOOD_NUMBERS: &[&str] = &["1", "0.5", "0.1", "0.7", "2", "30", "1e-6", "1e6", "0"];

fn fill_from(fragment: &str, numbers: &[usize], table: &[&str]) -> String {
    let mut out = String::new();
    let mut k = 0;
    for (i, part) in fragment.split("{}").enumerate() {
        if i > 0 {
            out.push_str(table[numbers[k % numbers.len()] % table.len()]);
            k += 1;
        }
        out.push_str(part);
    }
    out
}

type Entity = (usize, Vec<bool>, Vec<usize>);

fn entity() -> impl Strategy<Value = Entity> {
    (
        0..8usize,
        prop::collection::vec(any::<bool>(), LIGHT_KEYS.len()),
        prop::collection::vec(
            prop_oneof![
                20 => 0..GOOD_NUMBERS.len(),
                1 => GOOD_NUMBERS.len()..GOOD_NUMBERS.len() + NUMBERS.len(),
            ],
            1..24,
        ),
    )
}

/// Numbers index GOOD_NUMBERS first, then NUMBERS (the bad ones included).
fn pick(i: usize) -> &'static str {
    GOOD_NUMBERS
        .get(i)
        .copied()
        .unwrap_or_else(|| NUMBERS[(i - GOOD_NUMBERS.len()) % NUMBERS.len()])
}

fn structured_scene(cam: &[usize], lights: &[Entity], objects: &[Entity]) -> String {
    let table: Vec<&str> = (0..GOOD_NUMBERS.len() + NUMBERS.len()).map(pick).collect();
    // Camera numbers: cam[i] is 0 for the valid value most of the time.
    let cam_value = |i: usize, good: &'static str| if cam[i] == 0 { good } else { pick(cam[i]) };
    let mut t = format!(
        "[camera]\nposition = [0, {}, -2]\nforward = [0, {}, 1]\nfov_y_deg = {}\nnear = {}\nfar = {}\n",
        cam_value(0, "1"),
        cam_value(1, "0"),
        cam_value(2, "40"),
        cam_value(3, "0.01"),
        cam_value(4, "100"),
    );
    for (kind, mask, nums) in lights {
        let kind = kind % LIGHT_KINDS.len();
        t.push_str(&format!("[[lights]]\nkind = \"{}\"\n", LIGHT_KINDS[kind]));
        // The keys each kind needs, plus (rarely) one it must not have.
        let needed: &[usize] = match kind {
            0 => &[0, 2],
            1 => &[0, 1, 2],
            2 => &[1, 3],
            3 => &[0, 6, 7],
            _ => &[0, 6, 8, 9, 10],
        };
        for (i, key) in LIGHT_KEYS.iter().enumerate() {
            let optional = kind == 1 && i >= 4 && mask[i];
            let intruder = mask.iter().all(|m| *m) && !needed.contains(&i);
            if needed.contains(&i) || optional || intruder {
                t.push_str(&fill_from(key, nums, &table));
                t.push('\n');
            }
        }
    }
    for (b, mask, nums) in objects {
        t.push_str(&format!(
            "[[objects]]\nbuiltin = \"{}\"\n",
            BUILTINS[b % BUILTINS.len()]
        ));
        for (key, on) in OBJECT_KEYS.iter().zip(mask) {
            if *on {
                t.push_str(&fill_from(key, nums, &table));
                t.push('\n');
            }
        }
    }
    t
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,300}") {
        let _ = Scene::from_toml_str(&text, Path::new("fuzz.toml"), &std::env::temp_dir());
    }

    #[test]
    fn scene_like_text_never_panics(
        lines in prop::collection::vec((0..FRAGMENTS.len(), prop::collection::vec(0..NUMBERS.len(), 1..8)), 0..24)
    ) {
        let mut text = String::from("[camera]\nposition = [0, 0, -1]\nforward = [0, 0, 1]\nfov_y_deg = 40\n");
        for (f, nums) in &lines {
            text.push_str(&fill(FRAGMENTS[*f], nums));
            text.push('\n');
        }
        if let Ok(s) = Scene::from_toml_str(&text, Path::new("fuzz.toml"), &std::env::temp_dir()) {
            check_invariants(&s);
        }
    }

    #[test]
    fn structured_scenes_load_or_fail_cleanly(
        cam in prop::collection::vec(prop_oneof![8 => Just(0usize), 1 => 0..GOOD_NUMBERS.len() + NUMBERS.len()], 5),
        lights in prop::collection::vec(entity(), 0..4),
        objects in prop::collection::vec(entity(), 0..4),
    ) {
        let text = structured_scene(&cam, &lights, &objects);
        match Scene::from_toml_str(&text, Path::new("fuzz.toml"), &std::env::temp_dir()) {
            Ok(s) => {
                check_invariants(&s);
                let b = s.aabb_at(0.5);
                prop_assert!(b.min.is_finite() && b.max.is_finite(), "{:?}", b);
            }
            // Every error names the file.
            Err(e) => prop_assert!(e.to_string().contains("fuzz.toml"), "{}", e),
        }
    }
}

// ---- [camera_path] --------------------------------------------------------------------------

#[test]
fn asset_cornell_mover_has_a_camera_path_starting_at_its_camera() {
    let s = Scene::load(asset("scenes/cornell_mover.toml")).unwrap();
    let p = s.camera_path.as_ref().expect("a [camera_path] table");
    assert_eq!(p.keys().len(), 4);
    // The first key repeats `[camera]`, so a replay starts from the usual view.
    let c = p.camera_at(&s.camera, p.time_range_s().0);
    assert!(c.position.abs_diff_eq(s.camera.position, 1e-6));
    assert!(c.forward.abs_diff_eq(s.camera.forward, 1e-6));
}

#[test]
fn camera_path_round_trips_through_its_toml_table() {
    let text = format!(
        "{CAMERA}{LIGHT}{CUBE}[camera_path]\nkeyframes = [\n\
         {{ time_s = 0.5, position = [0, 1, -3], look_at = [0, 0, 0] }},\n\
         {{ time_s = 1.5, position = [1, 1, -2], direction = [-0.1, -0.3, 1], fov_y_deg = 55 }},\n\
         {{ time_s = 4, position = [2, 0.5, 0], look_at = [0, 0.2, 0] }},\n]\n"
    );
    let s = load_ok(&text, &[]);
    let p = s.camera_path.clone().unwrap();
    let again = load_ok(
        &format!("{CAMERA}{LIGHT}{CUBE}{}", p.toml_table(glam::DVec3::ZERO)),
        &[],
    );
    let q = again.camera_path.unwrap();
    // Times, positions and fields of view print exactly; a written direction is normalized
    // again on loading, which may move its last bit.
    assert_eq!((q.up(), q.keys().len()), (p.up(), p.keys().len()));
    for (a, b) in p.keys().iter().zip(q.keys()) {
        assert_eq!(
            (a.time_s, a.position, a.fov_y_deg),
            (b.time_s, b.position, b.fov_y_deg)
        );
        assert!(a.forward.abs_diff_eq(b.forward, 1e-6), "{a:?} vs {b:?}");
    }
}

#[test]
fn camera_path_errors_name_the_file_and_key() {
    let path = |keys: &str| format!("{CAMERA}{LIGHT}{CUBE}[camera_path]\nkeyframes = [{keys}]\n");
    let key = |t: &str, extra: &str| format!("{{ time_s = {t}, position = [0, 1, -3]{extra} }},");
    let look = ", look_at = [0, 0, 0]";
    let cases: Vec<(String, &[&str])> = vec![
        (
            path(&key("0", look)),
            &["camera_path.keyframes", "at least 2"],
        ),
        (
            path(&(key("1", look) + &key("0.5", look))),
            &["camera_path.keyframes[1].time_s", "strictly increasing"],
        ),
        (
            path(&(key("nan", look) + &key("1", look))),
            &["camera_path.keyframes[0].time_s"],
        ),
        (
            path(&(key("0", look) + &key("1", ""))),
            &["camera_path.keyframes[1].look_at", "neither"],
        ),
        (
            path(&(key("0", look) + &key("1", ", look_at = [0, 1, -3]"))),
            &[
                "camera_path.keyframes[1].look_at",
                "equals the key's position",
            ],
        ),
        (
            path(&(key("0", look) + &key("1", ", direction = [0, 0, 0]"))),
            &["camera_path.keyframes[1].direction"],
        ),
        (
            path(&(key("0", look) + &key("1", ", direction = [0, 1, 0]"))),
            &["camera_path.keyframes[1].direction", "parallel to up"],
        ),
        (
            path(&(key("0", look) + &key("1", &format!("{look}, fov_y_deg = 0")))),
            &["camera_path.keyframes[1].fov_y_deg", "(0, 180)"],
        ),
    ];
    for (text, parts) in cases {
        let (e, file) = load_err(&text, &[]);
        assert_msg(&e, &file, parts);
    }
}

/// A scene 10 km out is rebased at load (a floating origin): positions are subtracted from
/// the local origin in f64, so 10 000.3 m keeps its 0.3 m to f32 precision near 16 m
/// (ulp 1.9e-6 m) instead of ulp(10 km) ≈ 1 mm; a scene near 0 is not moved at all.
#[test]
fn far_scenes_are_rebased_to_a_local_origin_in_f64() {
    let text = |x: f64| {
        format!(
            "[camera]\nposition = [{x}, 1, -3]\ntarget = [{x}, 0, 0]\nfov_y_deg = 40\n\
             [[lights]]\nkind = \"point\"\nposition = [{}, 2, 0]\nintensity_w_sr = 1.0\n\
             [[objects]]\nbuiltin = \"cube\"\ntranslate = [{}, 0, 0]\n",
            x + 0.3,
            x + 0.3
        )
    };
    let near = load_ok(&text(0.0), &[]);
    assert_eq!(near.origin_m, glam::DVec3::ZERO);
    assert_eq!(near.objects[0].transform.translate.x, 0.3f32);
    let far = load_ok(&text(10_000.0), &[]);
    // Centre of x ∈ [10 000, 10 000.3] rounded to 256 m: 39 × 256 = 9984 m.
    assert_eq!(far.origin_m, glam::DVec3::new(9984.0, 0.0, 0.0));
    assert_eq!(far.objects[0].transform.translate.x, 16.3f32);
    assert_eq!(far.camera.position.x, 16.0f32);
    let Light::Point { position, .. } = far.lights[0] else {
        panic!("a point light")
    };
    assert_eq!(position.x, 16.3f32);
    // World positions come back by adding the origin in f64.
    let world = far.origin_m + far.objects[0].transform.translate.as_dvec3();
    assert!((world.x - 10_000.3).abs() < 1e-6, "{world}");
}

#[test]
fn shadow_table_gives_cascades_and_names_bad_values() {
    let s = load_ok(
        &format!("{CAMERA}{LIGHT}{CUBE}[shadow]\ncascades = 3\ncascade_lambda = 0.75\n"),
        &[],
    );
    use schema::Value;
    assert_eq!(s.shadow.get("shadow.cascades"), Some(Value::Count(3)));
    assert_eq!(
        s.shadow.get("shadow.cascade_lambda"),
        Some(Value::Number(0.75))
    );
    let s = load_ok(&format!("{CAMERA}{LIGHT}{CUBE}"), &[]);
    assert!(s.shadow.is_empty());
    // The flags' other values are scene keys too.
    let s = load_ok(
        &format!(
            "{CAMERA}{LIGHT}{CUBE}[shadow]
resolution = \"auto\"
pcf_radius = 2
\
             point_shadows = \"paraboloid\"
area_samples = 4
area_shadows = \"pcss\"
"
        ),
        &[],
    );
    let t: ShadowSettings = schema::resolve(&[&s.shadow]);
    assert!(t.auto_resolution);
    assert_eq!(
        (
            t.pcf_radius,
            t.point_technique,
            t.area_samples,
            t.area_technique
        ),
        (2, PointShadow::DualParaboloid, Some(4), AreaShadow::Pcss)
    );
    for (line, field, expected) in [
        (
            "resolution = 8",
            "shadow.resolution",
            "[16, 8192] or \"auto\"",
        ),
        ("resolution = \"big\"", "shadow.resolution", "\"auto\""),
        ("pcf_radius = 9", "shadow.pcf_radius", "[0, 8]"),
        ("area_samples = 65", "shadow.area_samples", "[1, 64]"),
        ("cascades = 0", "shadow.cascades", "an integer in [1, 8]"),
        ("cascades = -2", "shadow.cascades", "[1, 8]"),
        ("cascades = 9", "shadow.cascades", "[1, 8]"),
        ("cascade_lambda = 1.5", "shadow.cascade_lambda", "[0, 1]"),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[shadow]\n{line}\n");
        let (e, scene) = load_err(&text, &[]);
        assert!(
            matches!(e, SceneError::InvalidValue { field: ref f, .. } if f == field),
            "{line}: {e}"
        );
        assert_msg(&e, &scene, &[&format!("`{field}`"), expected]);
    }
}

/// The screen-space keys refuse what their flags refuse, naming the file and the key.
#[test]
fn gi_screen_space_keys_refuse_bad_values() {
    for (table, field, says) in [
        (
            "ssgi_mips = \"median\"",
            "gi.ssgi_mips",
            "\"voting\" or \"fast\"",
        ),
        (
            "ssr_rays = \"cone\"",
            "gi.ssr_rays",
            "\"mirror\" or \"lobe\"",
        ),
        (
            "ssgi_history_weight = 1.0",
            "gi.ssgi_history_weight",
            "0.99",
        ),
        (
            "ssgi_feedback_max_w_m2 = 0.0",
            "gi.ssgi_feedback_max_w_m2",
            "W/m²",
        ),
        (
            "ssgi_feedback_max_w_m2 = nan",
            "gi.ssgi_feedback_max_w_m2",
            "",
        ),
        ("ssr = \"yes\"", "ssr", "bool"),
        ("sao_radius_m = 0", "gi.sao_radius_m", "(0, 1000000]"),
        ("sao_bias = -0.5", "gi.sao_bias", "an SAO bias in meters"),
        ("sao_contrast = 65", "gi.sao_contrast", "[0, 64]"),
        ("sao_epsilon_m2 = inf", "gi.sao_epsilon_m2", ""),
        ("sao = 1", "sao", "bool"),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[gi]\n{table}\n");
        let (e, _) = load_err(&text, &[]);
        let msg = e.to_string();
        assert!(msg.contains(field) && msg.contains(says), "{table}: {msg}");
        assert!(msg.contains("scene.toml"), "{table}: {msg}");
    }
}

// ---- the [post] table ----------------------------------------------------------------------

#[test]
fn post_table_parses_every_key() {
    use crate::scene::schema::Value;
    use crate::scene::{AutoExposure, PostTable, TaaSettings, ToneOperator};
    let text = format!(
        "{CAMERA}{LIGHT}{CUBE}[post]\ntaa = true\ntaa_history_weight = 0.8\ntaa_frames = 8\n\
         auto_exposure = 0.25\nexposure_adaptation = 0.5\nbloom = 0.05\nfxaa = true\n\
         dither = false\ntonemap = \"drago\"\nexposure = 2\n"
    );
    let t: PostTable = schema::resolve(&[&load_ok(&text, &[]).post]);
    assert_eq!(
        t.post.taa,
        Some(TaaSettings {
            history_weight: 0.8,
            frames: 8,
            ..Default::default()
        })
    );
    assert_eq!(
        t.post.auto_exposure,
        Some(AutoExposure {
            key: 0.25,
            adaptation: 0.5
        })
    );
    assert_eq!((t.post.bloom, t.post.fxaa), (Some(0.05), true));
    assert_eq!(
        (t.tonemap.operator, t.tonemap.exposure, t.tonemap.dither),
        (ToneOperator::Drago, 2.0, false)
    );
    // `true` turns auto exposure on with its default key; `false` turns a stage off.
    let s = load_ok(
        &format!("{CAMERA}{LIGHT}{CUBE}[post]\nauto_exposure = true\nbloom = false\n"),
        &[],
    );
    assert_eq!(s.post.get("post.auto_exposure"), Some(Value::Bool(true)));
    assert_eq!(s.post.get("post.bloom"), Some(Value::Bool(false)));
    let t: PostTable = schema::resolve(&[&s.post]);
    assert_eq!(
        (t.post.auto_exposure, t.post.bloom),
        (Some(AutoExposure::default()), None)
    );
    assert!(load_ok(&format!("{CAMERA}{LIGHT}{CUBE}"), &[])
        .post
        .is_empty());
    use clap::ValueEnum as _;
    for &op in ToneOperator::value_variants() {
        // The names are the flag's.
        let name = op.to_possible_value().expect("named").get_name().to_owned();
        let s = load_ok(
            &format!("{CAMERA}{LIGHT}{CUBE}[post]\ntonemap = \"{name}\"\n"),
            &[],
        );
        let t: PostTable = schema::resolve(&[&s.post]);
        assert_eq!(t.tonemap.operator, op, "{name}");
    }
}

/// The `[post]` keys refuse what their flags refuse, naming the file and the key.
#[test]
fn post_keys_refuse_bad_values() {
    for (line, field, says) in [
        (
            "taa_history_weight = 1.0",
            "post.taa_history_weight",
            "[0, 0.999]",
        ),
        ("taa_frames = 0", "post.taa_frames", "[1, 4096]"),
        ("taa_frames = -3", "post.taa_frames", "[1, 4096]"),
        ("auto_exposure = 0", "post.auto_exposure", "(0, 1000]"),
        (
            "auto_exposure = \"bright\"",
            "post.auto_exposure",
            "true (the default) or false",
        ),
        (
            "exposure_adaptation = 0",
            "post.exposure_adaptation",
            "(0, 1]",
        ),
        ("bloom = 1.5", "post.bloom", "[0, 1]"),
        ("bloom = true", "post.bloom", "a number or false (off)"),
        ("tonemap = \"reinhard\"", "post.tonemap", "\"filmic\""),
        ("exposure = 0", "post.exposure", "(0, 1000000]"),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[post]\n{line}\n");
        let (e, scene) = load_err(&text, &[]);
        assert!(
            matches!(e, SceneError::InvalidValue { field: ref f, .. } if f == field),
            "{line}: {e}"
        );
        assert_msg(&e, &scene, &[&format!("`{field}`"), says]);
    }
    for (line, says) in [
        ("fxaa = \"yes\"", "bool"),
        ("taa_jitter = 2", "taa_jitter"),
        ("exposure = nan", "`post.exposure` is NaN"),
    ] {
        let text = format!("{CAMERA}{LIGHT}{CUBE}[post]\n{line}\n");
        let (e, scene) = load_err(&text, &[]);
        let msg = e.to_string();
        assert!(
            msg.contains(says) && msg.contains(&scene.display().to_string()),
            "{line}: {msg}"
        );
    }
}
