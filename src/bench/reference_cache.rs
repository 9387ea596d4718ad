//! References in the sweep's loop (`voxgi sweep --make-references`): a scene without a
//! committed reference gets one from Mitsuba 3 (`export-mitsuba` + `tools/reference`), cached
//! under a key that is a hash of what Mitsuba renders — the exported XML, meshes and textures
//! (so the scene file, its meshes, MTL and textures, as they reach the export) — and of the
//! reference settings and the reference script. A changed scene gets a new reference; an
//! unchanged one is reused.
//!
//! Hashing the export rather than the scene's source files covers built-in scenes (no file),
//! materials set in the scene file and everything the loader reads, with no list of inputs to
//! keep in step with the scene format.

use std::path::{Path, PathBuf};

/// The Mitsuba settings of a made reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSettings {
    /// Image width and height in pixels.
    pub size: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Path segments from the camera (64: full GI, see `export::mitsuba::DEFAULT_MAX_DEPTH`).
    pub max_depth: u32,
    pub seed: u32,
}

impl ReferenceSettings {
    /// The settings as hashed and as written next to the cached image.
    pub fn text(&self) -> String {
        format!(
            "size={} spp={} max_depth={} seed={}",
            self.size, self.spp, self.max_depth, self.seed
        )
    }
}

/// Errors of making a reference, each saying what to do.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("--make-references needs Mitsuba 3: {reason}. Run `tools/reference --help` once from the repository root (it installs the pinned Mitsuba into .venv; python3-venv comes with tools/setup), or leave out --make-references and pass scenes that have a reference")]
    NoMitsuba { reason: String },
    #[error(
        "the reference of {scene} failed: `{command}` exited with {status}; its output is above"
    )]
    Render {
        scene: String,
        command: String,
        status: String,
    },
}

/// FNV-1a, 128 bits: a cache key, not a defence against crafted collisions.
#[derive(Clone, Copy)]
struct Fnv128(u128);

impl Fnv128 {
    const OFFSET: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    const PRIME: u128 = 0x0000_0000_0100_0000_0000_0000_0000_013b;

    fn new() -> Self {
        Self(Self::OFFSET)
    }

    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u128::from(x);
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }

    /// A length-prefixed field, so that ("ab", "c") and ("a", "bc") differ.
    fn field(&mut self, b: &[u8]) {
        self.bytes(&(b.len() as u64).to_le_bytes());
        self.bytes(b);
    }
}

/// The cache key of named inputs (relative path, contents) and settings: the same inputs in
/// any order give the same key; a changed byte, name or setting gives another.
pub fn content_key(files: &[(String, Vec<u8>)], settings: &ReferenceSettings) -> String {
    let mut sorted: Vec<&(String, Vec<u8>)> = files.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let mut h = Fnv128::new();
    h.field(settings.text().as_bytes());
    for (name, bytes) in sorted {
        h.field(name.as_bytes());
        h.field(bytes);
    }
    format!("{:032x}", h.0)
}

/// The export's first comment names the scene file's path; a moved but unchanged scene keeps
/// its key, so that line is left out of the hash.
fn without_source_comment(xml: &[u8]) -> Vec<u8> {
    let text = String::from_utf8_lossy(xml);
    text.lines()
        .filter(|l| !l.trim_start().starts_with("<!-- Exported by voxgi from"))
        .collect::<Vec<_>>()
        .join("\n")
        .into_bytes()
}

/// Every file under `dir` as (path relative to `dir` with `/` separators, contents).
fn files_under(dir: &Path) -> Result<Vec<(String, Vec<u8>)>, ReferenceError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| ReferenceError::Io { path, source }
    };
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).map_err(io(&d))? {
            let path = entry.map_err(io(&d))?.path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let rel = path
                .strip_prefix(dir)
                .unwrap_or(&path)
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join("/");
            let bytes = std::fs::read(&path).map_err(io(&path))?;
            out.push((rel, bytes));
        }
    }
    Ok(out)
}

/// The key of a Mitsuba export in `export_dir` (written by `export-mitsuba` into an empty
/// folder) rendered with `settings` by the reference script `tool` (its bytes count: a new
/// renderer version or script gives new references).
pub fn export_key(
    export_dir: &Path,
    settings: &ReferenceSettings,
    tool: &[(String, Vec<u8>)],
) -> Result<String, ReferenceError> {
    let mut files = files_under(export_dir)?;
    for (name, bytes) in &mut files {
        if name == "scene.xml" {
            *bytes = without_source_comment(bytes);
        }
    }
    files.extend(tool.iter().map(|(n, b)| (format!("tool:{n}"), b.clone())));
    Ok(content_key(&files, settings))
}

/// Where the reference of scene `name` with `key` is cached.
pub fn cached_path(cache_dir: &Path, name: &str, key: &str) -> PathBuf {
    cache_dir.join(format!("{name}-{key}_gi.exr"))
}

/// The default cache folder: `$XDG_CACHE_HOME/voxgi/references`, else
/// `~/.cache/voxgi/references`, else `out/references`.
pub fn default_cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")));
    base.map_or_else(
        || PathBuf::from("out/references"),
        |b| b.join("voxgi/references"),
    )
}

/// The reference script `tool` (`tools/reference`) and the Python renderer beside it, as
/// hashed inputs; a clear error when the script is missing.
pub fn tool_files(tool: &Path) -> Result<Vec<(String, Vec<u8>)>, ReferenceError> {
    let mut out = Vec::new();
    for path in [tool.to_owned(), tool.with_extension("py")] {
        let bytes = std::fs::read(&path).map_err(|e| ReferenceError::NoMitsuba {
            reason: format!("cannot read {} ({e})", path.display()),
        })?;
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        out.push((name, bytes));
    }
    Ok(out)
}

/// The Python of the repository's `.venv` (the folder above `tools/`), if Mitsuba imports
/// in it; else why not.
pub fn mitsuba_python(tool: &Path) -> Result<PathBuf, ReferenceError> {
    let root = tool
        .parent()
        .and_then(Path::parent)
        .map_or_else(|| PathBuf::from("."), Path::to_owned);
    let python = root.join(".venv/bin/python");
    if !python.exists() {
        return Err(ReferenceError::NoMitsuba {
            reason: format!("{} does not exist", python.display()),
        });
    }
    let ok = std::process::Command::new(&python)
        .args(["-c", "import mitsuba, numpy"])
        .output()
        .map_err(|e| ReferenceError::NoMitsuba {
            reason: format!("{} does not run ({e})", python.display()),
        })?;
    if !ok.status.success() {
        return Err(ReferenceError::NoMitsuba {
            reason: format!("{} cannot import mitsuba", python.display()),
        });
    }
    Ok(python)
}

/// Renders `export_dir` with `tool` into `out` (the script's per-pass progress goes to the
/// terminal), through a temporary file so that an interrupted render leaves no reference.
pub fn render_reference(
    tool: &Path,
    scene: &str,
    export_dir: &Path,
    settings: &ReferenceSettings,
    out: &Path,
) -> Result<(), ReferenceError> {
    let partial = out.with_extension("partial.exr");
    let args = [
        export_dir.to_string_lossy().into_owned(),
        partial.to_string_lossy().into_owned(),
        "--spp".into(),
        settings.spp.to_string(),
        "--max-depth".into(),
        settings.max_depth.to_string(),
        "--seed".into(),
        settings.seed.to_string(),
        "--float32".into(),
    ];
    let command = format!("{} {}", tool.display(), args.join(" "));
    // The script's output (progress per pass) goes to stderr, leaving stdout to the rows.
    let status = std::process::Command::new(tool)
        .args(&args)
        .stdout(std::io::stderr())
        .status()
        .map_err(|source| ReferenceError::Io {
            path: tool.to_owned(),
            source,
        })?;
    if !status.success() {
        return Err(ReferenceError::Render {
            scene: scene.to_owned(),
            command,
            status: status.to_string(),
        });
    }
    std::fs::rename(&partial, out).map_err(|source| ReferenceError::Io {
        path: out.to_owned(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: ReferenceSettings = ReferenceSettings {
        size: 64,
        spp: 16,
        max_depth: 64,
        seed: 0,
    };

    #[test]
    fn the_key_follows_the_content_not_the_order() {
        let a = vec![("a".to_owned(), b"xyz".to_vec()), ("b".into(), vec![1, 2])];
        let b = vec![a[1].clone(), a[0].clone()];
        assert_eq!(content_key(&a, &S), content_key(&b, &S));
        let touched = vec![a[0].clone(), ("b".into(), vec![1, 3])];
        assert_ne!(content_key(&a, &S), content_key(&touched, &S));
        let renamed = vec![a[0].clone(), ("c".into(), vec![1, 2])];
        assert_ne!(content_key(&a, &S), content_key(&renamed, &S));
        // Moving bytes across the field boundary changes the key (length prefixes).
        let moved = vec![
            ("a".to_owned(), b"xy".to_vec()),
            ("b".into(), vec![b'z', 1, 2]),
        ];
        assert_ne!(content_key(&a, &S), content_key(&moved, &S));
        let more_spp = ReferenceSettings { spp: 17, ..S };
        assert_ne!(content_key(&a, &S), content_key(&a, &more_spp));
        assert_eq!(content_key(&a, &S).len(), 32);
    }

    #[test]
    fn the_source_comment_is_left_out() {
        let x = b"<?xml?>\n<!-- Exported by voxgi from /a/b.toml at t = 0 s. -->\n<scene/>";
        let y = b"<?xml?>\n<!-- Exported by voxgi from /c/d.toml at t = 0 s. -->\n<scene/>";
        assert_eq!(without_source_comment(x), without_source_comment(y));
        assert_ne!(
            without_source_comment(x),
            without_source_comment(b"<?xml?>\n<scene2/>")
        );
    }
}
