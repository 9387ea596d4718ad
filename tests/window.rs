//! The viewer in a real window (CI: `xvfb-run -a cargo test`). Runs `voxgi --validate view` as
//! a scripted run: frames, a resize halfway, a screenshot of the last frame; the command fails
//! on any validation message. Without a display the test fails with the hint, never passes.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create a scratch directory");
    dir
}

fn voxgi(args: &[&str]) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_voxgi"));
    cmd.args(args);
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        cmd.env("XDG_RUNTIME_DIR", scratch_dir("xdg"));
    }
    cmd.output().expect("run the voxgi binary")
}

fn require_display() {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        panic!(
            "no display for the window test: run it under Xvfb, `xvfb-run -a cargo test` \
             (Debian/Ubuntu: apt-get install xvfb)"
        );
    }
}

fn assert_success(out: &std::process::Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

fn load(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
        .to_rgba8()
}

#[test]
fn viewer_renders_resizes_and_screenshots_without_validation_messages() {
    require_display();
    let dir = scratch_dir("window");
    let shot = dir.join("shot.png");
    let out = voxgi(&[
        "--validate",
        "view",
        "--width",
        "320",
        "--height",
        "240",
        "--frames",
        "12",
        "--resize",
        "640x360",
        "--screenshot",
        shot.to_str().expect("utf-8 path"),
    ]);
    // Exit code 0 means: no validation message, screenshot written.
    assert_success(&out, "voxgi --validate view");
    let img = load(&shot);
    // The last frame was rendered after the resize reached the swapchain; the scene fills the
    // window right of the panel.
    let (w, h) = img.dimensions();
    assert_eq!(h, 360, "the screenshot is {w}x{h}");
    assert!((300..640).contains(&w), "the screenshot is {w}x{h}");

    let mut sum = 0.0f64;
    let mut colors = std::collections::HashSet::new();
    for p in img.pixels() {
        let [r, g, b, _] = p.0;
        sum += (0.2126 * f64::from(r) + 0.7152 * f64::from(g) + 0.0722 * f64::from(b)) / 255.0;
        colors.insert([r, g, b]);
    }
    let mean = sum / f64::from(img.width() * img.height());
    assert!(
        mean > 0.05,
        "the screenshot is nearly black (mean luma {mean:.4})"
    );
    assert!(
        colors.len() > 2,
        "the screenshot has {} colors",
        colors.len()
    );

    // With the camera untouched, the viewer shows exactly what `voxgi render` writes.
    let reference = dir.join("render.png");
    let out = voxgi(&[
        "--validate",
        "render",
        "--width",
        &w.to_string(),
        "--height",
        &h.to_string(),
        "-o",
        reference.to_str().expect("utf-8 path"),
    ]);
    assert_success(&out, "voxgi --validate render");
    let reference = load(&reference);
    let max_diff = img
        .pixels()
        .zip(reference.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| a.0[c].abs_diff(b.0[c])))
        .max()
        .unwrap_or(0);
    assert!(
        max_diff <= 1,
        "the viewer's frame differs from `voxgi render` by up to {max_diff}/255"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
