//! Bounded fuzzing of the model loaders (#32): arbitrary bytes, and valid files mutated line by
//! line or byte by byte, fed to the OBJ, MTL and glTF paths through `Scene::load`, as a user's
//! file reaches them. Every case must load or fail with an error that names a file the case
//! wrote; none may panic or hang. (The scene-file TOML has its own properties in `tests.rs`.)
//! Failures proptest finds are kept in `proptest-regressions/scene/fuzz_tests.txt` and replayed
//! first on every run; commit that file with the fix.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use proptest::prelude::*;

use super::Scene;

/// A fresh directory per case (proptest runs cases one after another within a test, but the
/// tests run in parallel).
fn case_dir(tag: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("voxgi_fuzz_{tag}_{}_{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Loads `file` in `dir`; an error must name one of `names`. Removes the directory.
fn load_or_named_error(dir: &Path, file: &str, names: &[&str]) -> Result<(), TestCaseError> {
    let result = Scene::load(dir.join(file));
    let _ = std::fs::remove_dir_all(dir);
    match result {
        Ok(scene) => {
            let b = scene.aabb_at(0.0);
            prop_assert!(
                scene.objects.is_empty() || (b.min.is_finite() && b.max.is_finite()),
                "{b:?}"
            );
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                names.iter().any(|n| msg.contains(n)),
                "the error names none of {names:?}: {msg}"
            );
        }
    }
    Ok(())
}

const MTL: &str = "newmtl a\nKd 0.8 0.2 0.2\nKs 0.1 0.1 0.1\nNs 20\n\
                   newmtl b\nKd 0.5 0.5 0.5\nKe 1 1 1\nd 0.5\n";
const OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                   vn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\nusemtl b\nf 2 4 3\n";

/// OBJ statements with numbers and indices in and out of range.
const OBJ_LINES: &[&str] = &[
    "v {} {} {}",
    "v {} {}",
    "vt {} {}",
    "vn {} {} {}",
    "f {} {} {}",
    "f {}/{}/{} {}/{}/{} {}/{}/{}",
    "f {}//{} {}//{} {}//{}",
    "f {} {} {} {}",
    "f {}",
    "usemtl a",
    "usemtl missing",
    "mtllib m.mtl",
    "mtllib nowhere.mtl",
    "o obj{}",
    "g grp",
    "s {}",
    "l {} {}",
    "# comment {}",
    "",
];

/// MTL statements, including texture maps that do not exist.
const MTL_LINES: &[&str] = &[
    "newmtl a",
    "newmtl b",
    "Kd {} {} {}",
    "Ks {} {} {}",
    "Ka {} {} {}",
    "Ke {} {} {}",
    "Tf {} {} {}",
    "Ns {}",
    "d {}",
    "Tr {}",
    "Ni {}",
    "Pr {}",
    "Pm {}",
    "illum {}",
    "map_Kd missing.png",
    "map_Pr missing.png",
    "map_Ke -bm {} missing.png",
    "bump -bm {} missing.png",
    "map_d missing.png",
    "Kd {}",
];

const NUMBERS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "4",
    "-1",
    "-4",
    "0.5",
    "1e30",
    "-1e30",
    "1e-30",
    "nan",
    "inf",
    "-inf",
    "99999999999",
    "x",
    "",
    "1.5.2",
    "3/",
    "/",
];

fn fill(template: &str, picks: &[usize]) -> String {
    let mut out = String::new();
    let mut k = 0;
    let mut rest = template;
    while let Some(i) = rest.find("{}") {
        out.push_str(&rest[..i]);
        out.push_str(NUMBERS[picks[k % picks.len()] % NUMBERS.len()]);
        k += 1;
        rest = &rest[i + 2..];
    }
    out.push_str(rest);
    out
}

fn lines_from(vocabulary: &'static [&'static str]) -> impl Strategy<Value = String> {
    prop::collection::vec(
        (
            0..vocabulary.len(),
            prop::collection::vec(0..NUMBERS.len(), 1..10),
        ),
        0..30,
    )
    .prop_map(move |lines| {
        lines
            .iter()
            .map(|(l, picks)| fill(vocabulary[*l], picks) + "\n")
            .collect()
    })
}

/// A valid file's bytes with some bytes replaced, some removed, and maybe cut short.
fn mutated(valid: &'static [u8]) -> impl Strategy<Value = Vec<u8>> {
    (
        prop::collection::vec((0..valid.len(), any::<u8>()), 0..8),
        prop::collection::vec(0..valid.len(), 0..4),
        prop_oneof![3 => Just(None), 1 => (0..=valid.len()).prop_map(Some)],
    )
        .prop_map(move |(flips, removals, cut)| {
            let mut b = valid.to_vec();
            for (i, v) in flips {
                b[i] = v;
            }
            for i in removals {
                if i < b.len() {
                    b.remove(i);
                }
            }
            if let Some(n) = cut {
                b.truncate(n.min(b.len()));
            }
            b
        })
}

/// A one-triangle glTF whose buffer is a `data:` URI (positions only, 36 bytes).
fn gltf_json(count: &str, offset: &str, component: &str, extra: &str) -> String {
    let positions: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let data = base64_encode(&positions);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0{extra}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{data}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":{offset},"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":{component},"count":{count},"type":"VEC3",
"min":[0,0,0],"max":[1,1,0]}}]}}"#
    )
}

fn base64_encode(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

const GLTF_COUNTS: &[&str] = &["3", "0", "1", "4", "1000000", "4294967295", "-1"];
const GLTF_OFFSETS: &[&str] = &["0", "4", "36", "40", "4294967295", "-4"];
const GLTF_COMPONENTS: &[&str] = &["5126", "5125", "5121", "1", "\"x\""];
const GLTF_EXTRAS: &[&str] = &[
    "",
    r#","translation":[1e39,0,0]"#,
    r#","scale":[0,0,0]"#,
    r#","matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]"#,
    r#","children":[0]"#,
    r#","children":[7]"#,
    r#","rotation":[0,0,0,0]"#,
    r#","camera":3"#,
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_as_obj_load_or_fail_naming_the_file(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let dir = case_dir("obj_bytes");
        std::fs::write(dir.join("m.obj"), &bytes).expect("write");
        std::fs::write(dir.join("m.mtl"), MTL).expect("write");
        load_or_named_error(&dir, "m.obj", &["m.obj", "m.mtl"])?;
    }

    #[test]
    fn obj_statements_load_or_fail_naming_the_file(text in lines_from(OBJ_LINES)) {
        let dir = case_dir("obj_lines");
        std::fs::write(dir.join("m.obj"), format!("mtllib m.mtl\n{text}")).expect("write");
        std::fs::write(dir.join("m.mtl"), MTL).expect("write");
        load_or_named_error(&dir, "m.obj", &["m.obj", "m.mtl", "nowhere.mtl"])?;
    }

    #[test]
    fn mtl_statements_load_or_fail_naming_the_file(text in lines_from(MTL_LINES)) {
        let dir = case_dir("mtl_lines");
        std::fs::write(dir.join("m.obj"), OBJ).expect("write");
        std::fs::write(dir.join("m.mtl"), text).expect("write");
        load_or_named_error(&dir, "m.obj", &["m.obj", "m.mtl", "missing.png"])?;
    }

    #[test]
    fn mutated_obj_and_mtl_load_or_fail_naming_the_file(
        obj in mutated(OBJ.as_bytes()),
        mtl in mutated(MTL.as_bytes()),
    ) {
        let dir = case_dir("obj_mutated");
        std::fs::write(dir.join("m.obj"), obj).expect("write");
        std::fs::write(dir.join("m.mtl"), mtl).expect("write");
        load_or_named_error(&dir, "m.obj", &["m.obj", "m.mtl", ".mtl"])?;
    }

    #[test]
    fn arbitrary_bytes_as_glb_load_or_fail_naming_the_file(
        bytes in prop::collection::vec(any::<u8>(), 0..300),
        magic in any::<bool>(),
    ) {
        // Half the cases start like a GLB, so the parser gets past the magic number.
        let mut b = if magic { b"glTF\x02\0\0\0".to_vec() } else { Vec::new() };
        b.extend_from_slice(&bytes);
        let dir = case_dir("glb_bytes");
        std::fs::write(dir.join("m.glb"), &b).expect("write");
        load_or_named_error(&dir, "m.glb", &["m.glb"])?;
    }

    #[test]
    fn gltf_accessors_and_nodes_load_or_fail_naming_the_file(
        count in 0..GLTF_COUNTS.len(),
        offset in 0..GLTF_OFFSETS.len(),
        component in 0..GLTF_COMPONENTS.len(),
        extra in 0..GLTF_EXTRAS.len(),
    ) {
        let json = gltf_json(GLTF_COUNTS[count], GLTF_OFFSETS[offset], GLTF_COMPONENTS[component], GLTF_EXTRAS[extra]);
        let dir = case_dir("gltf_fields");
        std::fs::write(dir.join("m.gltf"), json).expect("write");
        load_or_named_error(&dir, "m.gltf", &["m.gltf"])?;
    }

    #[test]
    fn mutated_gltf_loads_or_fails_naming_the_file(json in mutated(VALID_GLTF.as_bytes())) {
        let dir = case_dir("gltf_mutated");
        std::fs::write(dir.join("m.gltf"), json).expect("write");
        load_or_named_error(&dir, "m.gltf", &["m.gltf"])?;
    }
}

/// [`gltf_json`] with valid fields, as a constant for [`mutated`].
static VALID_GLTF: std::sync::LazyLock<String> =
    std::sync::LazyLock::new(|| gltf_json("3", "0", "5126", ""));

#[test]
fn the_unmutated_files_load() {
    // The properties above mutate these; they must be valid to begin with.
    let dir = case_dir("valid");
    std::fs::write(dir.join("m.obj"), OBJ).expect("write");
    std::fs::write(dir.join("m.mtl"), MTL).expect("write");
    std::fs::write(dir.join("m.gltf"), VALID_GLTF.as_str()).expect("write");
    let obj = Scene::load(dir.join("m.obj")).expect("the OBJ loads");
    assert_eq!(obj.objects.len(), 1);
    let gltf = Scene::load(dir.join("m.gltf")).expect("the glTF loads");
    assert_eq!(gltf.objects.len(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}
