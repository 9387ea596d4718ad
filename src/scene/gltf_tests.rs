//! glTF import: files written here (JSON + .bin, GLB, `data:` URIs), what they load as, and
//! the error each kind of bad input gives.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use serde_json::{json, Value};

use super::gltf::{punctual_light, LUMENS_PER_WATT};
use super::{AlphaMode, Light, Projection, Scene, SceneError};

/// A glTF document under construction: JSON plus one binary buffer.
struct Builder {
    json: Value,
    bin: Vec<u8>,
}

impl Builder {
    fn new() -> Builder {
        Builder {
            json: json!({
                "asset": { "version": "2.0" },
                "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                "scenes": [{ "nodes": [] }], "scene": 0,
            }),
            bin: Vec::new(),
        }
    }

    fn push(&mut self, key: &str, v: Value) -> usize {
        if self.json.get(key).is_none() {
            self.json[key] = json!([]);
        }
        let a = self.json[key].as_array_mut().expect("an array");
        a.push(v);
        a.len() - 1
    }

    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.push(
            "bufferViews",
            json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }),
        )
    }

    /// A float accessor of `ty` ("VEC3", "VEC2").
    fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let n = if ty == "VEC3" { 3 } else { 2 };
        let mut acc = json!({ "bufferView": view, "componentType": 5126, "count": data.len() / n, "type": ty });
        if ty == "VEC3" {
            let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
            for p in data.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.push("accessors", acc)
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": 5125, "count": data.len(), "type": "SCALAR" }),
        )
    }

    /// A mesh of one primitive and a root node holding it; returns the node.
    fn mesh_node(&mut self, primitive: Value, node: Value) -> usize {
        let mesh = self.push("meshes", json!({ "primitives": [primitive] }));
        let mut node = node;
        node["mesh"] = json!(mesh);
        self.node(node)
    }

    fn node(&mut self, node: Value) -> usize {
        let n = self.push("nodes", node);
        self.json["scenes"][0]["nodes"]
            .as_array_mut()
            .expect("scene nodes")
            .push(json!(n));
        n
    }

    /// The unit right triangle in the XY plane facing +Z, with normals and UVs.
    fn triangle(&mut self, material: Option<usize>, node: Value) -> usize {
        let pos = self.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
        let nrm = self.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
        let uv = self.floats(&[0., 1., 1., 1., 0., 0.], "VEC2");
        let ix = self.indices(&[0, 1, 2]);
        let mut p = json!({ "attributes": { "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv }, "indices": ix });
        if let Some(m) = material {
            p["material"] = json!(m);
        }
        self.mesh_node(p, node)
    }

    /// Writes `NAME.gltf` with `NAME.bin` beside it.
    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let mut json = self.json.clone();
        json["buffers"] = json!([{ "uri": format!("{name}.bin"), "byteLength": self.bin.len() }]);
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).expect("write bin");
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec_pretty(&json).expect("json")).expect("write");
        path
    }

    /// Writes `NAME.glb`: the JSON chunk and the buffer as its BIN chunk (glTF 2.0 §4.4).
    fn write_glb(&self, dir: &Path, name: &str) -> PathBuf {
        let mut json = self.json.clone();
        json["buffers"] = json!([{ "byteLength": self.bin.len() }]);
        let mut j = serde_json::to_vec(&json).expect("json");
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let mut b = self.bin.clone();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&((12 + 8 + j.len() + 8 + b.len()) as u32).to_le_bytes());
        out.extend_from_slice(&(j.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&j);
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
        let path = dir.join(format!("{name}.glb"));
        std::fs::write(&path, out).expect("write glb");
        path
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("voxgi-gltf-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn load(path: &Path) -> Scene {
    Scene::load(path).unwrap_or_else(|e| panic!("{e}"))
}

fn error(path: &Path) -> SceneError {
    match Scene::load(path) {
        Ok(_) => panic!("{} loaded, expected an error", path.display()),
        Err(e) => e,
    }
}

#[test]
fn a_triangle_loads_with_its_node_transform_material_and_flipped_uvs() {
    let dir = temp_dir("triangle");
    let mut b = Builder::new();
    let m = b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.25, 1.0, 1.0],
                "metallicFactor": 0.2, "roughnessFactor": 0.7 },
                "emissiveFactor": [1.0, 0.5, 0.0],
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } } }),
    );
    // Parent: translate (1, 2, 3); child: rotate 90° about Y, scale 2.
    let child = b.triangle(
        Some(m),
        json!({ "rotation": [0.0, 0.70710677, 0.0, 0.70710677], "scale": [2.0, 2.0, 2.0] }),
    );
    b.json["scenes"][0]["nodes"] = json!([]);
    b.node(json!({ "translation": [1.0, 2.0, 3.0], "children": [child] }));
    let s = load(&b.write(&dir, "tri"));
    let mesh = &s.meshes[s.objects[0].mesh];
    // (1, 0, 0) → scale 2 → rotated to (0, 0, −2) → + (1, 2, 3).
    assert!(
        mesh.positions[1].abs_diff_eq(Vec3::new(1.0, 2.0, 1.0), 1e-5),
        "{:?}",
        mesh.positions
    );
    // +Z rotated 90° about Y is +X.
    assert!(
        mesh.normals[0].abs_diff_eq(Vec3::X, 1e-5),
        "{:?}",
        mesh.normals
    );
    let uvs = mesh.uvs.as_ref().expect("uvs");
    assert_eq!(
        uvs[0],
        glam::Vec2::new(0.0, 0.0),
        "v flipped: glTF's v runs down"
    );
    let mat = &s.materials[mesh.submeshes[0].material];
    assert_eq!(mat.albedo, Vec3::new(0.5, 0.25, 1.0));
    let g = mat.ggx.expect("GGX");
    assert_eq!((g.roughness, g.metallic), (0.7, 0.2));
    assert_eq!(mat.emission, Vec3::new(4.0, 2.0, 0.0));
    assert!(mat.is_opaque());
}

#[test]
fn glb_and_data_uri_buffers_load_the_same_mesh() {
    let dir = temp_dir("glb");
    let mut b = Builder::new();
    b.triangle(None, json!({}));
    let from_glb = load(&b.write_glb(&dir, "tri"));
    let mut inline = b.json.clone();
    use base64::Engine;
    let data = base64::engine::general_purpose::STANDARD.encode(&b.bin);
    inline["buffers"] = json!([{ "uri": format!("data:application/octet-stream;base64,{data}"),
                                 "byteLength": b.bin.len() }]);
    let path = dir.join("inline.gltf");
    std::fs::write(&path, inline.to_string()).expect("write");
    let from_uri = load(&path);
    let (m1, m2) = (&from_glb.meshes[0], &from_uri.meshes[0]);
    assert_eq!(m1.positions, m2.positions);
    assert_eq!(m1.indices, vec![0, 1, 2]);
    // The default glTF material: white, metallic 1, roughness 1.
    let g = from_glb.materials[m1.submeshes[0].material]
        .ggx
        .expect("GGX");
    assert_eq!((g.roughness, g.metallic), (1.0, 1.0));
}

#[test]
fn an_image_in_a_glb_buffer_is_decoded_by_its_bytes() {
    let dir = temp_dir("glbimage");
    let texels = vec![255, 0, 0, 255, 0, 0, 255, 128];
    let mut png = Vec::new();
    image::RgbaImage::from_raw(2, 1, texels.clone())
        .expect("image")
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode");
    let mut b = Builder::new();
    let view = b.view(&png);
    // A wrong MIME type: the bytes decide.
    b.json["images"] = json!([{ "bufferView": view, "mimeType": "image/jpeg" }]);
    b.json["textures"] = json!([{ "source": 0 }]);
    let m = b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }),
    );
    b.triangle(Some(m), json!({}));
    let s = load(&b.write_glb(&dir, "img"));
    let t = &s.textures[s.materials[0].albedo_texture.expect("albedo map")];
    assert_eq!((t.width, t.height, &t.rgba8), (2, 1, &texels));
    assert!(t.srgb);
    assert!(
        t.path.to_string_lossy().ends_with("img.glb#image0"),
        "{:?}",
        t.path
    );
}

#[test]
fn bad_files_give_their_errors() {
    let dir = temp_dir("bad");
    let mut b = Builder::new();
    b.triangle(None, json!({}));
    let good = b.write(&dir, "good");
    assert!(Scene::load(&good).is_ok());

    // Missing .bin: the same file in a directory without it.
    std::fs::create_dir_all(dir.join("alone")).expect("dir");
    let nobin = dir.join("alone/nobin.gltf");
    std::fs::write(&nobin, std::fs::read(&good).expect("read")).expect("w");
    let e = error(&nobin);
    assert_eq!(e.kind(), "gltf-buffer", "{e}");
    assert!(e.to_string().contains("good.bin"), "{e}");

    // A buffer shorter than its byteLength.
    let p = b.write(&dir, "short");
    std::fs::write(dir.join("short.bin"), &b.bin[..b.bin.len() - 8]).expect("w");
    let e = error(&p);
    assert_eq!(e.kind(), "gltf-buffer", "{e}");
    assert!(e.to_string().contains("byteLength"), "{e}");

    // An accessor reading past its bufferView.
    let mut c = Builder::new();
    c.triangle(None, json!({}));
    c.json["accessors"][0]["count"] = json!(4);
    let e = error(&c.write(&dir, "acc"));
    assert_eq!(e.kind(), "gltf-accessor", "{e}");
    assert!(e.to_string().contains("POSITION"), "{e}");

    // An index past the vertices.
    let mut c = Builder::new();
    c.triangle(None, json!({}));
    let ix = c.indices(&[0, 1, 7]);
    c.json["meshes"][0]["primitives"][0]["indices"] = json!(ix);
    let e = error(&c.write(&dir, "index"));
    assert_eq!(e.kind(), "gltf-accessor", "{e}");
    assert!(e.to_string().contains("index 7"), "{e}");

    // A required extension voxgi lacks.
    let mut c = Builder::new();
    c.triangle(None, json!({}));
    c.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    c.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = error(&c.write(&dir, "ext"));
    assert_eq!(e.kind(), "gltf-extension", "{e}");
    assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");

    // Lines.
    let mut c = Builder::new();
    c.triangle(None, json!({}));
    c.json["meshes"][0]["primitives"][0]["mode"] = json!(1);
    let e = error(&c.write(&dir, "lines"));
    assert_eq!(e.kind(), "gltf-primitive-mode", "{e}");
    assert!(e.to_string().contains("LINES"), "{e}");

    // A missing image.
    let mut c = Builder::new();
    c.json["images"] = json!([{ "uri": "nowhere.png" }]);
    c.json["textures"] = json!([{ "source": 0 }]);
    let m = c.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }),
    );
    c.triangle(Some(m), json!({}));
    let e = error(&c.write(&dir, "img"));
    assert_eq!(e.kind(), "gltf-image-missing", "{e}");
    assert!(e.to_string().contains("nowhere.png"), "{e}");

    // Not glTF at all, and a node cycle.
    std::fs::write(dir.join("junk.glb"), b"glTF\x02\0\0\0junk").expect("w");
    assert_eq!(error(&dir.join("junk.glb")).kind(), "gltf-malformed");
    let mut c = Builder::new();
    c.triangle(None, json!({}));
    c.json["nodes"][0]["children"] = json!([0]);
    let e = error(&c.write(&dir, "cycle"));
    assert_eq!(e.kind(), "gltf-malformed", "{e}");
}

#[test]
fn punctual_lights_convert_candela_and_lux_at_683_lm_per_w() {
    use gltf::khr_lights_punctual::Kind;
    let at = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
    let p = punctual_light(Kind::Point, Vec3::ONE, 683.0, at);
    assert_eq!(
        p,
        Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity_w_sr: Vec3::ONE
        }
    );
    // A red 1366 lx sun pointing down its node's −Z, turned to point straight down.
    let down = Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let Light::Directional {
        direction,
        irradiance_w_m2,
    } = punctual_light(Kind::Directional, Vec3::new(1.0, 0.0, 0.0), 1366.0, down)
    else {
        panic!("directional")
    };
    assert!(direction.abs_diff_eq(-Vec3::Y, 1e-6), "{direction}");
    assert_eq!(irradiance_w_m2, Vec3::new(2.0, 0.0, 0.0));
    let Light::Spot {
        intensity_w_sr,
        cutoff_deg,
        beam_deg,
        ..
    } = punctual_light(
        Kind::Spot {
            inner_cone_angle: 0.25,
            outer_cone_angle: 0.5,
        },
        Vec3::ONE,
        LUMENS_PER_WATT * 3.0,
        Mat4::IDENTITY,
    )
    else {
        panic!("spot")
    };
    assert_eq!(intensity_w_sr, Vec3::splat(3.0));
    assert!((cutoff_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert!((beam_deg - 0.25f32.to_degrees()).abs() < 1e-4);
}

#[test]
fn a_gltf_alone_brings_its_lights_and_camera_or_a_sun_and_a_framing_camera() {
    let dir = temp_dir("alone");
    let mut b = Builder::new();
    b.triangle(None, json!({}));
    let bare = load(&b.write(&dir, "bare"));
    assert!(
        matches!(bare.lights[..], [Light::Directional { .. }]),
        "the default sun"
    );
    let bounds = bare.aabb_at(0.0);
    let to_center = (bounds.center() - bare.camera.position).normalize();
    assert!(to_center.dot(bare.camera.forward) > 0.999, "framed");

    b.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    b.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "intensity": 1366.0, "color": [1.0, 1.0, 1.0] } ] } });
    b.node(json!({ "translation": [0.0, 1.0, 0.0], "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    b.json["cameras"] = json!([{ "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.05, "zfar": 50.0 } }]);
    b.node(json!({ "translation": [0.0, 0.0, 4.0], "camera": 0 }));
    let lit = load(&b.write(&dir, "lit"));
    assert_eq!(
        lit.lights,
        vec![Light::Point {
            position: Vec3::Y,
            intensity_w_sr: Vec3::splat(2.0)
        }]
    );
    assert_eq!(lit.camera.position, Vec3::new(0.0, 0.0, 4.0));
    assert_eq!(lit.camera.forward, -Vec3::Z);
    assert!((lit.camera.fov_y_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert_eq!((lit.camera.near, lit.camera.far), (0.05, 50.0));

    // In a scene file without `[camera]`: the glTF's camera and light, moved by the object.
    let toml = "[[objects]]\nmesh = \"lit.gltf\"\ntranslate = [10.0, 0.0, 0.0]\n";
    let s = Scene::from_toml_str(toml, Path::new("s.toml"), &dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.camera.position, Vec3::new(10.0, 0.0, 4.0));
    assert!(
        matches!(s.lights[..], [Light::Point { position, .. }] if position == Vec3::new(10.0, 1.0, 0.0))
    );

    // An orthographic camera: its view is 2·ymag high.
    b.json["cameras"] = json!([{ "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 0.75, "znear": 0.0, "zfar": 10.0 } }]);
    let ortho = load(&b.write(&dir, "ortho"));
    assert_eq!(ortho.camera.projection, Projection::Orthographic);
    assert_eq!(ortho.camera.ortho_height_m, 1.5);
}

#[test]
fn textures_are_split_and_scaled_as_glsl_reads_them() {
    let dir = temp_dir("tex");
    // 2×1: texel 0 (R, G, B) = (10, 200, 50), texel 1 = (0, 100, 255).
    let packed =
        image::RgbaImage::from_raw(2, 1, vec![10, 200, 50, 255, 0, 100, 255, 255]).expect("image");
    packed.save(dir.join("mr.png")).expect("png");
    let white = image::RgbaImage::from_raw(1, 1, vec![255, 255, 255, 255]).expect("image");
    white.save(dir.join("base.png")).expect("png");
    let mut b = Builder::new();
    b.json["images"] = json!([{ "uri": "mr.png" }, { "uri": "base.png" }]);
    b.json["textures"] = json!([{ "source": 0 }, { "source": 1 }]);
    let m = b.push(
        "materials",
        json!({ "pbrMetallicRoughness": { "metallicRoughnessTexture": { "index": 0 },
                "roughnessFactor": 0.5, "metallicFactor": 1.0,
                "baseColorTexture": { "index": 1 }, "baseColorFactor": [0.5, 1.0, 1.0, 1.0] } }),
    );
    b.triangle(Some(m), json!({}));
    let s = load(&b.write(&dir, "tex"));
    let mat = &s.materials[s.meshes[0].submeshes[0].material];
    let r = &s.textures[mat.pbr_maps.roughness.expect("roughness map")];
    let metal = &s.textures[mat.pbr_maps.metallic.expect("metallic map")];
    // Roughness: G × 0.5, grey; metalness: B, grey; both linear.
    assert_eq!(r.rgba8, vec![100, 100, 100, 255, 50, 50, 50, 255]);
    assert_eq!(metal.rgba8, vec![50, 50, 50, 255, 255, 255, 255, 255]);
    assert!(!r.srgb && !metal.srgb);
    // The base color factor is baked into the (sRGB) texture: linear 0.5 is sRGB 188.
    let base = &s.textures[mat.albedo_texture.expect("albedo map")];
    assert!(base.srgb);
    assert_eq!(&base.rgba8[..3], &[188, 255, 255]);
}

#[test]
fn primitives_without_normals_follow_the_crease_rule() {
    let dir = temp_dir("crease");
    // Two triangles folded 90° along the X axis, sharing the edge: split at 60°, smooth at 120°.
    let mut b = Builder::new();
    let pos = b.floats(&[0., 0., 0., 1., 0., 0., 0., 0., -1., 0., 1., 0.], "VEC3");
    let ix = b.indices(&[0, 1, 2, 1, 0, 3]);
    b.mesh_node(
        json!({ "attributes": { "POSITION": pos }, "indices": ix }),
        json!({}),
    );
    b.write(&dir, "fold");
    for (crease, vertices) in [(60.0, 6), (120.0, 4)] {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
             [[objects]]\nmesh = \"fold.gltf\"\ncrease_deg = {crease}\n"
        );
        let s = Scene::from_toml_str(&toml, Path::new("s.toml"), &dir)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.meshes[0].positions.len(), vertices, "crease {crease}°");
    }
}

#[test]
fn alpha_modes_map_to_opacity_or_drop_the_primitive() {
    let dir = temp_dir("alpha");
    let mut b = Builder::new();
    let blend = b.push("materials", json!({ "alphaMode": "BLEND", "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.25] } }));
    let masked_out = b.push("materials", json!({ "alphaMode": "MASK", "alphaCutoff": 0.5, "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.25] } }));
    let masked_in = b.push("materials", json!({ "alphaMode": "MASK", "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.75] } }));
    b.triangle(Some(blend), json!({}));
    b.triangle(Some(masked_out), json!({ "translation": [0, 0, 1] }));
    b.triangle(Some(masked_in), json!({ "translation": [0, 0, 2] }));
    let s = load(&b.write(&dir, "alpha"));
    let subs = &s.meshes[0].submeshes;
    assert_eq!(subs.len(), 2, "the primitive below its cutoff is dropped");
    assert_eq!(s.materials[subs[0].material].opacity, 0.25);
    assert!(s.materials[subs[1].material].is_opaque());
}

#[test]
fn base_colour_alpha_becomes_a_cutout_or_a_blend_map() {
    let dir = temp_dir("alphamap");
    // 2×1: one opaque texel, one at alpha 64; and an all-opaque texture.
    let holes =
        image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 255, 255, 0, 0, 64]).expect("image");
    holes.save(dir.join("holes.png")).expect("png");
    let solid = image::RgbaImage::from_raw(1, 1, vec![255, 255, 255, 255]).expect("image");
    solid.save(dir.join("solid.png")).expect("png");
    let mut b = Builder::new();
    b.json["images"] = json!([{ "uri": "holes.png" }, { "uri": "solid.png" }]);
    b.json["textures"] = json!([{ "source": 0 }, { "source": 1 }]);
    let tex = |i: usize, alpha: f32| json!({ "baseColorTexture": { "index": i }, "baseColorFactor": [1, 1, 1, alpha] });
    let mask = b.push(
        "materials",
        json!({ "alphaMode": "MASK", "alphaCutoff": 0.5, "pbrMetallicRoughness": tex(0, 0.8) }),
    );
    let blend = b.push(
        "materials",
        json!({ "alphaMode": "BLEND", "pbrMetallicRoughness": tex(0, 0.5) }),
    );
    let solid_mask = b.push(
        "materials",
        json!({ "alphaMode": "MASK", "pbrMetallicRoughness": tex(1, 1.0) }),
    );
    let opaque = b.push("materials", json!({ "pbrMetallicRoughness": tex(0, 1.0) }));
    for (k, m) in [mask, blend, solid_mask, opaque].into_iter().enumerate() {
        b.triangle(Some(m), json!({ "translation": [0, 0, k] }));
    }
    let s = load(&b.write(&dir, "alphamap"));
    let mat = |k: usize| &s.materials[s.meshes[0].submeshes[k].material];
    // MASK: factor alpha × texel alpha ≥ 0.5 ⟺ texel alpha ≥ 0.5 / 0.8.
    let cut = mat(0).alpha_map.expect("a cutout");
    assert_eq!(cut.mode, AlphaMode::Cutout(0.5 / 0.8));
    assert_eq!(Some(cut.texture), mat(0).albedo_texture);
    assert!(mat(0).is_opaque());
    // Texel alphas 1 and 0.25 against 0.625: one of the two texels is open.
    assert_eq!(mat(0).coverage_opacity(&s.textures), 0.5);
    // BLEND: the factor is the opacity, the texel multiplies it; the mean alpha is
    // (255 + 64) / 510.
    assert_eq!(mat(1).alpha_map.map(|a| a.mode), Some(AlphaMode::Blend));
    assert_eq!(mat(1).opacity, 0.5);
    assert!(!mat(1).is_opaque());
    let mean = 0.5 * (255.0 + 64.0) / 510.0;
    assert!((mat(1).coverage_opacity(&s.textures) - mean).abs() < 1e-6);
    // An all-opaque texture needs no test, and OPAQUE ignores alpha.
    assert!(mat(2).alpha_map.is_none() && mat(3).alpha_map.is_none());
    assert!(mat(3).is_opaque());
}
