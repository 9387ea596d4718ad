//! The generated atrium (`voxgi::scene::atrium`) as a scene: it loads, renders one small
//! frame with validation clean and is lit, and without its generated files the error says
//! which tool writes them.

mod common;

use std::path::{Path, PathBuf};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::{atrium, Scene, SceneError};

/// A fresh directory under the system's temporary directory, per test and process.
fn temp_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("voxgi-{name}-{}", std::process::id()))
}

#[test]
fn generated_atrium_loads_and_renders_validation_clean() {
    let dir = temp_dir("atrium-render");
    let triangles = atrium::write(&dir).expect("writes the atrium");
    let scene = Scene::load(dir.join("atrium.toml")).expect("loads");
    let loaded: usize = scene.meshes.iter().map(|m| m.indices.len() / 3).sum();
    assert_eq!(
        loaded, triangles,
        "the OBJ loader reads every generated triangle"
    );
    // Five materials, each with its texture.
    assert_eq!(
        scene
            .materials
            .iter()
            .filter(|m| m.albedo_texture.is_some())
            .count(),
        5
    );

    let settings = RenderSettings {
        width: 64,
        height: 64,
        ..Default::default()
    };
    let ctx = common::context();
    let out = render_image(&ctx, &scene, &settings).expect("renders");
    common::assert_no_validation_messages(&ctx);
    // The camera stands in the courtyard under the roof opening: the sunlit floor and
    // arcades fill most of the view (the sky, above the opening, is black). Require a lit
    // image, not a black one: at least a quarter of the pixels have radiance.
    let lit = out
        .hdr
        .data
        .iter()
        .filter(|p| p[0] + p[1] + p[2] > 1e-3)
        .count();
    assert!(lit * 4 > 64 * 64, "only {lit} of 4096 pixels are lit");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_generated_files_name_the_generator() {
    // The committed scene file, read from a directory without `generated/`.
    let root = temp_dir("atrium-missing");
    let scenes = root.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    let text = atrium::scene_toml("../generated/atrium/atrium.obj");
    let path = scenes.join("atrium.toml");
    let err = Scene::from_toml_str(&text, &path, &scenes).expect_err("no generated files");
    assert!(matches!(err, SceneError::NotFound { .. }), "{err}");
    let message = err.to_string();
    assert!(message.contains("run `tools/atrium`"), "{message}");
    assert!(!Path::new(&root.join("generated")).exists());
    std::fs::remove_dir_all(&root).unwrap();
}
