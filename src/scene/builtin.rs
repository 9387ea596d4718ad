//! Built-in scenes, available without any file (`voxgi view` with no arguments).
//!
//! They are defined as TOML (`assets/scenes/cornell.toml`, embedded with `include_str!`) and
//! go through the same parser and validation as scene files: one format, one code path, and
//! the file doubles as an example users can copy. Variants are TOML text too (cornell.toml
//! with a table added or replaced), so that the viewer can save an edited built-in scene.

use std::path::Path;

use super::desc;
use super::{Scene, SceneError};

/// The scene used when none is given.
pub const DEFAULT_SCENE: &str = "cornell";

const CORNELL_TOML: &str = include_str!("../../assets/scenes/cornell.toml");

/// The `[gi]` table of the built-in `cornell` (not in `cornell.toml`, which scene files copy
/// and extend with tables of their own): the default render shows indirect light. The path
/// tracer with unbounded paths is unbiased; 4 rays × 2 frames, smoothed by a filter of radius
/// 8 pixels, render 512² in about 9 s on lavapipe (2 cores; 1 s with `--gi none`). At 256²
/// against the Mitsuba reference: relMSE 0.013, FLIP 0.112 (2 rays × 1 frame: 0.022, 0.169,
/// with visible blotches; radius 4 instead of 8 at 2 rays: 0.032).
const CORNELL_GI_TOML: &str = "
# The built-in scene's indirect light: the unbiased path tracer, 4 rays x 2 frames, filtered.
[gi]
method = \"pathtrace\"
rays = 4
accumulate_frames = 2
bounces = \"unbounded\"
filter_radius = 8
";

/// The `[gi]` layer of the built-in default scene: the GI a scene that names no method renders
/// with, under its own `[gi]` keys and the command line's (the command line applies it:
/// `cli::args`), so that loading one's own scene into a GI renderer shows indirect light.
pub fn default_gi_layer() -> super::schema::Layer {
    static LAYER: std::sync::OnceLock<super::schema::Layer> = std::sync::OnceLock::new();
    LAYER
        .get_or_init(|| builtin(DEFAULT_SCENE).map(|s| s.gi).unwrap_or_default())
        .clone()
}

/// The light of `cornell-point`: 1 W/sr at 0.25 m below the ceiling, E = 1 / 0.5² = 4 W/m² at
/// the floor's center.
const CORNELL_POINT_LIGHT_TOML: &str = "
# A point light 0.25 m below the ceiling: E = 1 / 0.5^2 = 4 W/m^2 at the floor's center.
[[lights]]
kind = \"point\"
position = [0.278, 0.5, 0.2796]
intensity_w_sr = [1.0, 1.0, 1.0]
";

/// The TOML text of a built-in scene (what `voxgi view --save` edits for a scene without a
/// file), or `None` for an unknown name. [`builtin`] loads exactly this text.
pub fn builtin_toml(name: &str) -> Option<String> {
    match name {
        "cornell" => Some(format!("{CORNELL_TOML}{CORNELL_GI_TOML}")),
        "cornell-point" => {
            // cornell.toml with its spot light replaced by the point light.
            let mut doc: toml_edit::DocumentMut = CORNELL_TOML.parse().ok()?;
            let light: toml_edit::DocumentMut = CORNELL_POINT_LIGHT_TOML.parse().ok()?;
            doc.insert("lights", light.get("lights")?.clone());
            Some(doc.to_string())
        }
        _ => None,
    }
}

/// Names accepted by [`builtin`].
pub fn builtin_names() -> &'static [&'static str] {
    &["cornell", "cornell-point"]
}

/// A built-in scene by name, or `None` for an unknown name.
///
/// The embedded scenes are checked by the tests, so they always load; should one ever fail,
/// the error is logged and `None` returned rather than panicking.
pub fn builtin(name: &str) -> Option<Scene> {
    match try_builtin(name)? {
        Ok(scene) => Some(scene),
        Err(e) => {
            log::error!("built-in scene `{name}` is broken (a bug in voxgi): {e}");
            None
        }
    }
}

fn try_builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    let origin = format!("<built-in scene {name}>");
    let origin = Path::new(&origin);
    let text = builtin_toml(name)?;
    // Built-in scenes reference only built-in meshes, so the base directory is unused.
    Some(desc::parse(&text, origin).and_then(|d| desc::build(d, origin, Path::new("."), None)))
}

/// A scene from a command-line argument: a built-in name (`cornell`, ...), a path to a TOML
/// scene file, or the default scene when `None`.
pub fn load_scene_arg(arg: Option<&str>) -> Result<Scene, SceneError> {
    let name = arg.unwrap_or(DEFAULT_SCENE);
    if let Some(result) = try_builtin(name) {
        return result;
    }
    Scene::load(crate::assets::find(Path::new(name)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Light;
    use glam::Vec3;

    #[test]
    fn every_builtin_loads() {
        for name in builtin_names() {
            let r = try_builtin(name);
            assert!(matches!(r, Some(Ok(_))), "{name}: {r:?}");
        }
        assert!(builtin("nope").is_none());
        assert!(builtin(DEFAULT_SCENE).is_some());
    }

    #[test]
    fn cornell_matches_the_published_box() {
        let s = builtin("cornell").unwrap_or_else(|| panic!("cornell"));
        let b = s.aabb_at(0.0);
        assert!((b.min - Vec3::ZERO).length() < 1e-6, "{b:?}");
        assert!(
            (b.max - Vec3::new(0.556, 0.5488, 0.5592)).length() < 1e-6,
            "{b:?}"
        );
        assert_eq!(s.objects.len(), 3);
        assert!(s.is_all_lambert());
        assert!(!s.has_point_lights() && s.has_spot_lights());
        assert!(!s.has_dynamic_objects());
        let fov = 2.0 * (0.0125f32 / 0.035).atan().to_degrees();
        assert!((s.camera.fov_y_deg - fov).abs() < 0.05);
        assert_eq!(s.camera.forward, Vec3::Z);
        // Three wall colors plus nothing else.
        assert_eq!(s.materials.len(), 3);
        let Light::Spot {
            position,
            direction,
            intensity_w_sr,
            ..
        } = s.lights[0]
        else {
            panic!("expected a spot light")
        };
        assert_eq!(direction, -Vec3::Y);
        // The irradiance stated in cornell.toml.
        let e = intensity_w_sr.x / (position.y * position.y);
        assert!((e - 3.43).abs() < 0.01, "{e}");
        // 5 walls + 2 × 5 block faces, two triangles each.
        assert_eq!(s.triangle_count_at(0.0), 30);
    }

    #[test]
    fn the_default_scene_renders_indirect_light_unless_switched_off() {
        use crate::scene::resolve_gi;
        use crate::scene::schema::{Layer, Value};
        use crate::scene::{Bounces, GiMethod};
        let s = builtin(DEFAULT_SCENE).unwrap_or_else(|| panic!("{DEFAULT_SCENE}"));
        let gi = resolve_gi(&s.gi, &Layer::default());
        assert_eq!(
            (gi.method, gi.bounces, gi.rays, gi.filter_radius),
            (GiMethod::Pathtrace, Bounces::Unbounded, 4, 8)
        );
        let mut off = Layer::default();
        off.set("gi.method", Value::Choice(0));
        assert_eq!(resolve_gi(&s.gi, &off).method, GiMethod::None);
    }

    #[test]
    fn cornell_point_has_a_point_light() {
        let s = builtin("cornell-point").unwrap_or_else(|| panic!("cornell-point"));
        assert!(s.has_point_lights() && !s.has_spot_lights());
        assert_eq!(s.lights.len(), 1);
    }
}
