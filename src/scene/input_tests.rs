//! Bad input files: OBJ indices out of range, empty and non-UTF-8 files, MTL values out of
//! range, textures that are huge, empty, 16-bit, grayscale or truncated, binary garbage as a
//! scene; and a fuzz-style test feeding mutated OBJ, MTL and scene files to the loader.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::*;

const SCENE: &str = "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
                     [[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 1.0\n\
                     [[objects]]\nmesh = \"m.obj\"\n";
const TEXTURED_OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                            vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\n";

/// A fresh directory under the system's temporary directory, removed on drop.
struct Dir(PathBuf);

impl Dir {
    fn new(tag: &str) -> Dir {
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("voxgi_input_{tag}_{}_{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Dir(dir)
    }

    fn write(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, bytes).expect("write");
        p
    }

    /// Writes `scene.toml` (the default [`SCENE`]) with `m.obj` = `obj` and loads it.
    fn load_obj(&self, obj: impl AsRef<[u8]>) -> Result<Scene, SceneError> {
        self.write("m.obj", obj);
        Scene::load(self.write("scene.toml", SCENE))
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn obj_face_index_zero_and_texture_or_normal_indices_out_of_range_name_the_line() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
    for (face, element, index) in [
        ("f 0 1 2", "vertex", 0),
        ("f 1/2 2/1 3/1", "texture coordinate", 2),
        ("f 1//1 2//5 3//1", "normal", 5),
        ("f 1//1 2//1 3//-2", "normal", -2),
    ] {
        let dir = Dir::new("faces");
        let e = dir.load_obj(format!("{tri}{face}\n")).expect_err(face);
        match &e {
            SceneError::FaceIndexOutOfRange {
                line,
                element: el,
                index: i,
                ..
            } => assert_eq!((*line, *el, *i), (6, element, index), "{e}"),
            _ => panic!("{face}: {e}"),
        }
        assert!(e.to_string().contains("m.obj"), "{e}");
    }
}

#[test]
fn empty_and_non_utf8_obj_files_are_errors_naming_the_file() {
    let dir = Dir::new("empty");
    let e = dir.load_obj("").expect_err("empty OBJ");
    assert!(
        e.to_string().contains("m.obj") && e.to_string().contains("no faces"),
        "{e}"
    );
    let e = dir
        .load_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\xff\xfe\n")
        .expect_err("non-UTF-8 OBJ");
    assert!(e.to_string().contains("m.obj"), "{e}");
}

#[test]
fn mtl_out_of_range_numbers_clamp() {
    // MTL files come from other tools: out-of-range reflectances, dissolves and exponents
    // load clamped (with a warning naming the file, line and key), unlike a scene file's.
    let dir = Dir::new("mtl");
    dir.write(
        "m.mtl",
        "newmtl a\nKd -1 0.5 0.25\nKs 2 0 0\nNs -5\nd 1.5\n\
         newmtl b\nKd 1.02 0.5 0.5\nNs 30\nd -0.5\n",
    );
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
               usemtl a\nf 1 2 3\nusemtl b\nf 2 4 3\n";
    let s = dir.load_obj(obj).expect("loads");
    let m = |i: usize| &s.materials[s.objects[0].materials[i]];
    assert_eq!(m(0).albedo, glam::Vec3::new(0.0, 0.5, 0.25));
    assert_eq!(m(0).specular, glam::Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(m(0).shininess, 0.0);
    assert_eq!(m(0).opacity, 1.0);
    assert_eq!(m(1).albedo, glam::Vec3::new(1.0, 0.5, 0.5));
    assert_eq!(m(1).shininess, 30.0);
    assert_eq!(m(1).opacity, 0.0);
}

#[test]
fn mtl_non_finite_numbers_are_errors_naming_file_line_and_key() {
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    for (line, key) in [
        ("Kd -1 2 nan", "Kd"),
        ("Ks nan 0 0", "Ks"),
        ("Ke 0 inf 0", "Ke"),
        ("Ka 0 0 -inf", "Ka"),
        ("Tf nan 1 1", "Tf"),
        ("Ns nan", "Ns"),
        ("d inf", "d"),
        ("Tr nan", "Tr"),
        ("Ni nan", "Ni"),
        ("Pr nan", "Pr"),
    ] {
        let dir = Dir::new("mtl-nan");
        dir.write("m.mtl", format!("newmtl a\nKd 0.5 0.5 0.5\n{line}\n"));
        let e = dir.load_obj(obj).expect_err(line);
        let msg = e.to_string();
        assert!(
            matches!(e, SceneError::MalformedObj { kind: "MTL", .. }),
            "{line}: {msg}"
        );
        for part in ["m.mtl", "line 3", key] {
            assert!(msg.contains(part), "{line}: `{part}` missing from: {msg}");
        }
    }
}

/// Loads the textured triangle whose `map_Kd` is `tex.png` with `png`'s bytes.
fn load_texture(dir: &Dir, png: &[u8]) -> Result<Scene, SceneError> {
    dir.write("m.mtl", "newmtl a\nKd 1 1 1\nmap_Kd tex.png\n");
    dir.write("tex.png", png);
    dir.load_obj(TEXTURED_OBJ)
}

fn png_bytes<P: image::Pixel<Subpixel = S> + image::PixelWithColorType, S: image::Primitive>(
    img: &image::ImageBuffer<P, Vec<S>>,
) -> Vec<u8>
where
    [S]: image::EncodableLayout,
{
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("encode PNG");
    out.into_inner()
}

#[test]
fn sixteen_bit_and_grayscale_textures_load_as_rgba8() {
    let dir = Dir::new("tex16");
    let rgb16 = image::ImageBuffer::from_pixel(2, 2, image::Rgb([65535u16, 0, 32896]));
    let s = load_texture(&dir, &png_bytes(&rgb16)).expect("16-bit PNG loads");
    // 16 → 8 bits: v * 255 / 65535, rounded (32896 → 128).
    assert_eq!(&s.textures[0].rgba8[..4], &[255, 0, 128, 255]);
    let dir = Dir::new("texgray");
    let gray = image::GrayImage::from_pixel(3, 1, image::Luma([77]));
    let s = load_texture(&dir, &png_bytes(&gray)).expect("grayscale PNG loads");
    assert_eq!((s.textures[0].width, s.textures[0].height), (3, 1));
    assert_eq!(&s.textures[0].rgba8[..4], &[77, 77, 77, 255]);
}

/// `img` encoded as `format`.
fn encoded(img: &image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, format).expect("encode");
    out.into_inner()
}

#[test]
fn jpeg_tga_bmp_and_hdr_textures_load_whatever_their_extension_says() {
    // A flat colour survives JPEG's 8×8 DCT nearly exactly: every block is its DC term, so
    // the only error is the quantization of one coefficient and the YCbCr round trip
    // (a few levels of 255); the lossless formats must return it exactly.
    let rgb = image::DynamicImage::ImageRgb8(image::RgbImage::from_pixel(
        16,
        16,
        image::Rgb([200, 120, 40]),
    ));
    let cases = [
        ("tex.jpg", image::ImageFormat::Jpeg, 3),
        // Sponza's textures are named `*.JPG`.
        ("tex.JPG", image::ImageFormat::Jpeg, 3),
        ("tex.tga", image::ImageFormat::Tga, 0),
        ("tex.bmp", image::ImageFormat::Bmp, 0),
        // The extension says PNG, the bytes are a JPEG: the bytes decide.
        ("tex.png", image::ImageFormat::Jpeg, 3),
    ];
    for (name, format, tolerance) in cases {
        let dir = Dir::new("texformats");
        dir.write("m.mtl", format!("newmtl a\nKd 1 1 1\nmap_Kd {name}\n"));
        dir.write(name, encoded(&rgb, format));
        let s = dir
            .load_obj(TEXTURED_OBJ)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let t = &s.textures[0];
        assert_eq!((t.width, t.height), (16, 16), "{name}");
        for (got, want) in t.rgba8[..4].iter().zip([200u8, 120, 40, 255]) {
            assert!(
                got.abs_diff(want) <= tolerance,
                "{name}: {:?}",
                &t.rgba8[..4]
            );
        }
    }
    // Radiance .hdr: linear floats, converted to 8 bits like a 16-bit PNG (clamped to 1).
    let hdr = image::DynamicImage::ImageRgb32F(image::Rgb32FImage::from_pixel(
        4,
        4,
        image::Rgb([0.5, 2.0, 0.0]),
    ));
    let dir = Dir::new("texhdr");
    dir.write("m.mtl", "newmtl a\nKd 1 1 1\nmap_Kd tex.hdr\n");
    dir.write("tex.hdr", encoded(&hdr, image::ImageFormat::Hdr));
    let s = dir.load_obj(TEXTURED_OBJ).expect("HDR texture loads");
    let px = &s.textures[0].rgba8[..4];
    assert!(
        px[0].abs_diff(128) <= 1 && px[1] == 255 && px[2] == 0,
        "{px:?}"
    );
}

#[test]
fn a_texture_in_no_known_format_is_an_error_naming_the_file() {
    let dir = Dir::new("texunknown");
    dir.write("m.mtl", "newmtl a\nKd 1 1 1\nmap_Kd tex.jpg\n");
    dir.write("tex.jpg", b"this is not an image at all, just text");
    let e = dir.load_obj(TEXTURED_OBJ).expect_err("text as a texture");
    assert!(
        matches!(e, SceneError::TextureDecode { .. }) && e.to_string().contains("tex.jpg"),
        "{e}"
    );
}

#[test]
fn huge_empty_and_truncated_textures_are_errors_naming_the_file() {
    // One texel wider than the largest image the renderer uploads; grayscale keeps it small.
    let huge = image::GrayImage::new(super::obj::MAX_TEXTURE_SIDE + 1, 1);
    let dir = Dir::new("texhuge");
    let e = load_texture(&dir, &png_bytes(&huge)).expect_err("huge texture");
    assert!(
        matches!(e, SceneError::TextureDecode { .. })
            && e.to_string().contains("16385×1")
            && e.to_string().contains("downscale"),
        "{e}"
    );
    // A 0×0 PNG: its header (IHDR) says width = height = 0.
    let mut empty = png_bytes(&image::GrayImage::new(1, 1));
    empty[16..24].copy_from_slice(&[0; 8]);
    let dir = Dir::new("texempty");
    let e = load_texture(&dir, &empty).expect_err("0×0 texture");
    assert!(matches!(e, SceneError::TextureDecode { .. }), "{e}");
    let whole = png_bytes(&image::RgbImage::from_pixel(64, 64, image::Rgb([1, 2, 3])));
    let dir = Dir::new("textrunc");
    let e = load_texture(&dir, &whole[..whole.len() / 2]).expect_err("truncated texture");
    assert!(
        matches!(e, SceneError::TextureDecode { .. }) && e.to_string().contains("tex.png"),
        "{e}"
    );
}

#[test]
fn a_scene_file_of_binary_garbage_is_an_error_naming_it() {
    let dir = Dir::new("garbage");
    let bytes: Vec<u8> = (0..512u32).map(|i| (i * 167 + 13) as u8).collect();
    let path = dir.write("garbage.toml", &bytes);
    let e = Scene::load(&path).expect_err("garbage");
    assert!(e.to_string().contains("garbage.toml"), "{e}");
}

/// xorshift64*: a tiny deterministic generator, so that a failing case can be replayed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens the mutations insert: the formats' keywords, separators and awkward numbers.
const TOKENS: &[&str] = &[
    "v ",
    "vt ",
    "vn ",
    "f ",
    "/",
    "//",
    "-1",
    "0",
    "1",
    "3",
    "nan",
    "inf",
    "-0",
    "1e39",
    "99999999999",
    "mtllib m.mtl",
    "usemtl a",
    "newmtl a",
    "Kd ",
    "Ks ",
    "Ns ",
    "d ",
    "map_Kd ",
    "map_bump -bm 2 ",
    "norm ",
    "s 1",
    "g x",
    "o y",
    "#",
    " ",
    "\n",
    "\\\n",
    "\t",
    "[",
    "]",
    "=",
    "\"",
    "[[objects]]",
    "[[lights]]",
    "[gi]",
    "mesh = ",
    "kind = ",
    "é",
    "\u{0}",
];

/// `seed` changed by a few random edits: byte flips, deletions, duplications and inserted
/// tokens or raw bytes.
fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(8) {
        let at = rng.below(b.len() + 1);
        match rng.below(5) {
            0 if !b.is_empty() => {
                let i = at.min(b.len() - 1);
                b[i] ^= 1 << rng.below(8);
            }
            1 => {
                let end = (at + rng.below(16)).min(b.len());
                b.drain(at..end);
            }
            2 => {
                let end = (at + rng.below(32)).min(b.len());
                let copy = b[at..end].to_vec();
                b.splice(at..at, copy);
            }
            3 => {
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes().to_vec();
                b.splice(at..at, t);
            }
            _ => {
                let raw: Vec<u8> = (0..rng.below(8)).map(|_| rng.next() as u8).collect();
                b.splice(at..at, raw);
            }
        }
    }
    b
}

#[test]
fn mutated_obj_mtl_and_scene_files_load_or_fail_never_panic() {
    // 300 cases × 3 files run in about a second; the seed fixes them, so a failure replays.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mtl = "newmtl a\nKd 0.5 0.5 0.5\nKs 0.1 0.1 0.1\nNs 10\nd 1\n";
    let dir = Dir::new("fuzz");
    for case in 0..300 {
        // Mostly one file mutated at a time, so the others let the loader reach it.
        let which = rng.below(4);
        let pick = |rng: &mut Rng, k: usize, seed: &str| {
            if which == k || which == 3 {
                mutate(rng, seed.as_bytes())
            } else {
                seed.as_bytes().to_vec()
            }
        };
        let obj = pick(&mut rng, 0, TEXTURED_OBJ);
        let mtl = pick(&mut rng, 1, mtl);
        let scene = pick(&mut rng, 2, SCENE);
        dir.write("m.obj", &obj);
        dir.write("m.mtl", &mtl);
        let path = dir.write("scene.toml", &scene);
        let loaded = std::panic::catch_unwind(|| Scene::load(&path));
        let show = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
        match loaded {
            Ok(Ok(s)) => {
                // What loads is usable: every index points into the scene.
                for o in &s.objects {
                    assert!(o.mesh < s.meshes.len(), "case {case}");
                    assert!(o.materials.iter().all(|&m| m < s.materials.len()));
                }
                for m in &s.meshes {
                    let n = m.positions.len() as u32;
                    assert!(m.indices.iter().all(|&i| i < n), "case {case}");
                    assert!(m.positions.iter().all(|p| p.is_finite()), "case {case}");
                }
            }
            Ok(Err(e)) => assert!(!e.to_string().is_empty()),
            Err(_) => panic!(
                "case {case} panicked:\n--- OBJ\n{}\n--- MTL\n{}\n--- scene\n{}",
                show(&obj),
                show(&mtl),
                show(&scene)
            ),
        }
    }
}

#[test]
fn arbitrary_bytes_as_obj_mtl_or_scene_never_panic() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let dir = Dir::new("bytes");
    for case in 0..100 {
        let bytes: Vec<u8> = (0..rng.below(400)).map(|_| rng.next() as u8).collect();
        let (obj, mtl, scene) = match case % 3 {
            0 => (
                bytes.clone(),
                b"newmtl a\n".to_vec(),
                SCENE.as_bytes().to_vec(),
            ),
            1 => (
                TEXTURED_OBJ.as_bytes().to_vec(),
                bytes.clone(),
                SCENE.as_bytes().to_vec(),
            ),
            _ => (
                TEXTURED_OBJ.as_bytes().to_vec(),
                b"newmtl a\n".to_vec(),
                bytes.clone(),
            ),
        };
        dir.write("m.obj", &obj);
        dir.write("m.mtl", &mtl);
        let path = dir.write("scene.toml", &scene);
        let r = std::panic::catch_unwind(|| Scene::load(&path));
        assert!(r.is_ok(), "case {case} panicked on {bytes:?}");
    }
}

/// A scene with one area light given by `light` (TOML lines after `kind`).
fn area_scene(light: &str) -> String {
    format!(
        "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
         [[lights]]\n{light}\n[[objects]]\nbuiltin = \"quad\"\n"
    )
}

#[test]
fn area_lights_load_and_bad_values_name_the_file_and_key() {
    let dir = Dir::new("area");
    let load = |light: &str| Scene::load(dir.write("area.toml", area_scene(light)));
    let s = load(
        "kind = \"rectangle\"\nposition = [0, 2, 0]\nnormal = [0, -2, 0]\nwidth_m = 0.5\n\
         height_m = 0.25\nradiance_w_sr_m2 = [1, 2, 3]",
    )
    .expect("rectangle");
    let Light::Rectangle {
        normal,
        width_axis,
        samples,
        ..
    } = s.lights[0]
    else {
        panic!("not a rectangle: {:?}", s.lights[0]);
    };
    assert_eq!(normal, glam::Vec3::NEG_Y);
    assert!(width_axis.dot(normal).abs() < 1e-6 && (width_axis.length() - 1.0).abs() < 1e-6);
    assert_eq!(samples, desc::DEFAULT_AREA_SAMPLES);
    let s = load("kind = \"sphere\"\nposition = [0, 2, 0]\nradius_m = 0.1\nradiance_w_sr_m2 = 4\nsamples = 8")
        .expect("sphere");
    assert!(matches!(s.lights[0], Light::Sphere { radius_m, samples: 8, .. } if radius_m == 0.1));
    // (light lines, key the error must name, words it must say)
    let sphere = "kind = \"sphere\"\nposition = [0, 2, 0]\nradiance_w_sr_m2 = 1";
    let rect =
        "kind = \"rectangle\"\nposition = [0, 2, 0]\nnormal = [0, -1, 0]\nradiance_w_sr_m2 = 1";
    let cases = [
        (format!("{sphere}\nradius_m = 0"), "radius_m", "meters > 0"),
        (format!("{sphere}\nradius_m = -1"), "radius_m", "meters > 0"),
        (format!("{sphere}\nradius_m = nan"), "radius_m", "radius_m"),
        (sphere.to_string(), "radius_m", "needs `radius_m`"),
        (
            format!("{sphere}\nradius_m = 1\nwidth_m = 1"),
            "width_m",
            "does not apply",
        ),
        (
            format!("{sphere}\nradius_m = 1\nsamples = 0"),
            "samples",
            "[1, 64]",
        ),
        (
            format!("{sphere}\nradius_m = 1\nsamples = 65"),
            "samples",
            "[1, 64]",
        ),
        (
            format!("{rect}\nwidth_m = 1\nheight_m = 0"),
            "height_m",
            "meters > 0",
        ),
        (
            format!("{rect}\nwidth_m = inf\nheight_m = 1"),
            "width_m",
            "width_m",
        ),
        (
            format!("{rect}\nheight_m = 1"),
            "width_m",
            "needs `width_m`",
        ),
        (
            format!("{rect}\nwidth_m = 1\nheight_m = 1\nwidth_axis = [0, 2, 0]"),
            "width_axis",
            "parallel",
        ),
        (
            "kind = \"rectangle\"\nposition = [0, 2, 0]\nnormal = [0, 0, 0]\nwidth_m = 1\n\
             height_m = 1\nradiance_w_sr_m2 = 1"
                .to_owned(),
            "normal",
            "normal",
        ),
        (
            "kind = \"sphere\"\nposition = [0, 2, 0]\nradius_m = 1\nradiance_w_sr_m2 = -1"
                .to_owned(),
            "radiance_w_sr_m2",
            "negative",
        ),
        (
            "kind = \"sphere\"\nposition = [0, 2, 0]\nradius_m = 1\nradiance_w_sr_m2 = [1, nan, 1]"
                .to_owned(),
            "radiance_w_sr_m2",
            "radiance_w_sr_m2",
        ),
        (
            format!("{sphere}\nradius_m = 1\nintensity_w_sr = 1"),
            "intensity_w_sr",
            "does not apply",
        ),
        (
            "kind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 1\nradius_m = 1".to_owned(),
            "radius_m",
            "does not apply",
        ),
    ];
    for (light, key, words) in cases {
        let e = load(&light).expect_err(&light).to_string();
        assert!(
            e.contains("area.toml") && e.contains(key) && e.contains(words),
            "{light}\n-> {e}"
        );
    }
}

#[test]
fn an_obj_file_alone_is_a_scene_framed_and_lit_by_the_default_sun() {
    // `voxgi render model.obj` once read the OBJ as TOML ("TOML syntax error ... mtllib").
    // Like a glTF alone, it is one object, framed by a camera and lit by the default sun.
    let dir = Dir::new("obj-alone");
    dir.write("m.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    let path = dir.write(
        "Model.OBJ",
        "mtllib m.mtl\nv 0 0 0\nv 2 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    );
    let s = Scene::load(&path).expect("an OBJ alone loads");
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.materials[s.objects[0].materials[0]].albedo.x, 0.8);
    assert!(
        matches!(
            s.lights.as_slice(),
            [crate::scene::Light::Directional { .. }]
        ),
        "{:?}",
        s.lights
    );
    // The framing camera looks at the model's bounds from the front.
    let centre = (s.aabb_at(0.0).min + s.aabb_at(0.0).max) * 0.5;
    let to_centre = (centre - s.camera.position).normalize();
    assert!(to_centre.dot(s.camera.forward) > 0.99, "{:?}", s.camera);
    // A file that is not OBJ by its extension is still a TOML scene file, with TOML's errors.
    let toml = dir.write("m.toml", "mtllib m.mtl\n");
    let e = Scene::load(&toml).expect_err("not TOML");
    assert!(e.to_string().contains("TOML"), "{e}");
}
