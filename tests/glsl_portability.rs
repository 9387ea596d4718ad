//! GLSL that lavapipe forgives and a GPU driver does not, checked in the source because the
//! suite runs on lavapipe only.
//!
//! `pow(x, y)` is undefined for x = 0 and y <= 0 (GLSL 4.50 §8.2). Lavapipe returns 1 for
//! pow(0, 0); NVIDIA computes exp2(y log2 x) and returns NaN, and 0 · NaN is NaN. Twice a Phong
//! exponent of 0 (an MTL metal without `Ns`) met a zero cosine this way and turned pixels
//! NaN on an H200 only: once in the Phong BRDF (all surfaces of any scene with a Phong
//! material), once in the Phong lobe's pdf of the path tracer's emitter sampling (the Modern
//! Hall's path tracer, 4,780 NaN pixels at 320×180). Both now go through `phong_cos_power`
//! (glsl/include/brdf.glsl), which returns 0 for a cosine <= 0. This test keeps every Phong
//! exponent there, unless the base is held above 0 (`max(x, 1e-30)`).

use std::path::{Path, PathBuf};

fn glsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            glsl_files(&p, out);
        } else if p.extension().is_some_and(|x| {
            ["glsl", "comp", "frag", "vert", "geom"].contains(&x.to_str().unwrap_or(""))
        }) {
            out.push(p);
        }
    }
}

/// The base and exponent of each `pow(` call on `line` (split at the call's top-level comma),
/// or `None` for a call that does not close on the line.
fn pow_calls(line: &str) -> Vec<Option<(String, String)>> {
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(i) = rest.find("pow(") {
        // `pow(` inside another name (e.g. `phong_cos_pow(`) is not a call of pow.
        let before = rest[..i].chars().last();
        let call = &rest[i + 4..];
        rest = call;
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let (mut depth, mut comma, mut end) = (0i32, None, None);
        for (k, ch) in call.char_indices() {
            match ch {
                '(' => depth += 1,
                ')' if depth == 0 => {
                    end = Some(k);
                    break;
                }
                ')' => depth -= 1,
                ',' if depth == 0 => comma = Some(k),
                _ => {}
            }
        }
        out.push(match (comma, end) {
            (Some(c), Some(e)) => Some((
                call[..c].trim().to_owned(),
                call[c + 1..e].trim().to_owned(),
            )),
            _ => None,
        });
    }
    out
}

/// Whether an exponent names a Phong exponent: the lobe's parameter, a shininess or an
/// exponent variable.
/// Whether a base is kept above 0: `max(x, c)` with a literal c > 0.
fn is_positive_base(b: &str) -> bool {
    b.strip_prefix("max(")
        .and_then(|r| r.strip_suffix(')'))
        .and_then(|r| r.rsplit_once(','))
        .and_then(|(_, c)| c.trim().parse::<f64>().ok())
        .is_some_and(|c| c > 0.0)
}

fn is_phong_exponent(e: &str) -> bool {
    e.split(|c: char| !c.is_alphanumeric() && c != '_')
        .any(|t| {
            ["param", "shininess", "exponent", "ns"].contains(&t.to_ascii_lowercase().as_str())
        })
}

#[test]
fn every_phong_exponent_goes_through_phong_cos_power() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
    let mut files = Vec::new();
    glsl_files(&root, &mut files);
    assert!(files.len() > 20, "found only {} GLSL files", files.len());
    let mut bad = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("readable");
        let mut in_guard = false;
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            if code.contains("float phong_cos_power(") {
                in_guard = true;
            }
            for (b, e) in pow_calls(code).into_iter().flatten() {
                if is_phong_exponent(&e) && !is_positive_base(&b) && !in_guard {
                    bad.push(format!("{}:{}: {}", f.display(), n + 1, line.trim()));
                }
            }
            if in_guard && code.trim() == "}" {
                in_guard = false;
            }
        }
    }
    assert!(
        bad.is_empty(),
        "pow() with a Phong exponent outside phong_cos_power (NaN on NVIDIA for a zero \
         cosine and exponent 0):\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_check_finds_a_phong_exponent_and_passes_constants() {
    let call = |b: &str, e: &str| Some((b.to_owned(), e.to_owned()));
    assert_eq!(
        pow_calls("x = (m.param + 1.0) * pow(max(c, 0.0), m.param);"),
        vec![call("max(c, 0.0)", "m.param")]
    );
    assert!(!is_positive_base("max(c, 0.0)"));
    assert!(is_positive_base("max(u.x, 1e-30)"));
    assert!(is_phong_exponent("m.param"));
    assert!(is_phong_exponent("shininess"));
    assert!(!is_phong_exponent("5.0"));
    assert!(!is_phong_exponent("vec3(1.0 / 2.4)"));
    assert!(!is_phong_exponent("pc.contrast"));
    assert_eq!(
        pow_calls("float w = pow(max(dot(a, b), 0.0), 16.0);"),
        vec![call("max(dot(a, b), 0.0)", "16.0")]
    );
}
