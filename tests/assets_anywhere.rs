//! The project's files are found from any directory: the binary run from an empty temporary
//! directory renders the built-in scene, renders a scene file given by its path in the
//! project, and compares against `assets/references/cornell_gi.exr`; a reference that exists
//! nowhere is an error naming the flag that points at the folder.

mod common;

use std::path::PathBuf;
use std::process::Output;

fn empty_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi-anywhere-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn voxgi_in(dir: &PathBuf, args: &[&str]) -> Output {
    common::voxgi_with(args, |c| {
        c.current_dir(dir);
    })
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn renders_from_another_directory() {
    let dir = empty_dir("render");
    for (scene, png) in [
        ("cornell", "builtin.png"),
        ("assets/scenes/cornell_bunny.toml", "bunny.png"),
    ] {
        let o = voxgi_in(
            &dir,
            &[
                "--validate",
                "render",
                scene,
                "--gi",
                "none",
                "--width",
                "32",
                "--height",
                "32",
                "-o",
                png,
            ],
        );
        assert!(o.status.success(), "{scene}: {}", text(&o));
        let size = std::fs::metadata(dir.join(png))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(size > 0, "{scene}: no {png} written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn reads_the_references_from_another_directory() {
    let dir = empty_dir("compare");
    let reference = "assets/references/cornell_gi.exr";
    let o = voxgi_in(&dir, &["compare", reference, reference, "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("rel_mse"), "{out}");

    // A folder that has no reference: the sweep names the flag that points at one.
    let o = voxgi_in(
        &dir,
        &[
            "sweep",
            "cornell",
            "--references",
            "nowhere",
            "--out",
            "sweep",
        ],
    );
    assert!(!o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("--references"), "{}", text(&o));
    let _ = std::fs::remove_dir_all(&dir);
}
