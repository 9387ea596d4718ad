//! `voxgi render` on a glTF file, end to end through the built binary: a `.glb` alone renders
//! to a PNG of the asked size with something lit in it, and a malformed `.glb` fails with an
//! error that names the file, without a panic.

mod common;

use std::path::PathBuf;

use common::voxgi;

fn temp_file(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("voxgi-cli-gltf-{}-{name}", std::process::id()))
}

#[test]
fn render_writes_a_png_of_a_glb() {
    let glb = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cutout.glb");
    let png = temp_file("cutout.png");
    let _ = std::fs::remove_file(&png);
    let (glb, png_arg) = (glb.to_string_lossy(), png.to_string_lossy());
    let out = voxgi(&[
        "render", &glb, "-o", &png_arg, "--width", "48", "--height", "24",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "render failed:\n{stderr}");
    let img = image::open(&png).expect("a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (48, 24));
    // The sunlit floor fills most of the view: far from black.
    let bright = img
        .pixels()
        .filter(|p| p[0].max(p[1]).max(p[2]) > 32)
        .count();
    assert!(
        bright > img.pixels().count() / 2,
        "{bright} of {} pixels above 32",
        img.pixels().count()
    );
    let _ = std::fs::remove_file(&png);
}

#[test]
fn a_malformed_glb_fails_naming_the_file() {
    let glb = temp_file("broken.glb");
    // A GLB header whose JSON chunk runs past the end of the file.
    let mut bytes = Vec::new();
    for word in [0x4654_6C67u32, 2, 40, 100, 0x4E4F_534A] {
        bytes.extend(word.to_le_bytes());
    }
    bytes.extend(b"{\"asset\":");
    std::fs::write(&glb, &bytes).expect("write");
    let png = temp_file("broken.png");
    let (glb_arg, png_arg) = (glb.to_string_lossy(), png.to_string_lossy());
    let out = voxgi(&[
        "render", &glb_arg, "-o", &png_arg, "--width", "32", "--height", "32",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a broken .glb rendered:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let name = glb
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    assert!(
        stderr.contains(name.as_ref()),
        "the error does not name the file:\n{stderr}"
    );
    assert!(!png.exists(), "no image for a failed render");
    let _ = std::fs::remove_file(&glb);
}
