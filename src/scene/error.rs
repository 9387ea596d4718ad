//! Errors a scene file, an OBJ/MTL file or a built-in scene can cause.
//!
//! Every variant names the file it is about and the field (`lights[1].direction`) or the line
//! (`line 12`) where the problem is, says what was expected, and says what to do. They are
//! meant to be printed as they are, e.g. by `main.rs` through `anyhow`.

use std::path::{Path, PathBuf};

/// What to do about a missing file: a file under `generated/NAME/` is written by a
/// generator (`tools/NAME`, e.g. `tools/atrium`) and is not committed, so run it; any other
/// path is probably wrong.
fn not_found_advice(file: &Path) -> String {
    let parts: Vec<_> = file.components().map(|c| c.as_os_str()).collect();
    let generator = parts
        .windows(3)
        .find(|w| w[0] == "generated")
        .and_then(|w| w[1].to_str());
    match generator {
        Some(name) => format!(
            "this file is generated, not committed: run `tools/{name}` (or `voxgi generate \
             {name} --out DIR`) to write it"
        ),
        None => "check the path (paths in a scene file are relative to the scene file's \
                 directory)"
            .to_string(),
    }
}

/// Something wrong with a scene the user gave us.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file the scene needs (the scene itself, an OBJ mesh, a frame of an OBJ sequence)
    /// does not exist. Missing textures and MTL files are only warnings.
    #[error(
        "{}: {what} not found{}; {}",
        file.display(),
        referenced_by.as_ref().map(|r| format!(" (referenced by {r})")).unwrap_or_default(),
        not_found_advice(file)
    )]
    NotFound {
        file: PathBuf,
        /// "scene file", "OBJ mesh", "OBJ sequence frame"…
        what: &'static str,
        /// `scene.toml: objects[2].mesh`, when another file referenced it.
        referenced_by: Option<String>,
    },

    /// Any other I/O error while reading a file.
    #[error("{}: cannot read {what}: {source}; check that the file is readable", file.display())]
    Io {
        file: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },

    /// The text is not valid TOML.
    #[error(
        "{}:{line}:{col}: TOML syntax error: {message}{}; fix the syntax at that position",
        file.display(),
        show_source_line(source_line)
    )]
    TomlSyntax {
        file: PathBuf,
        line: usize,
        col: usize,
        message: String,
        source_line: String,
    },

    /// A key the scene format does not know (often a typo).
    #[error(
        "{}:{line}:{col}: unknown key `{key}`{}; expected one of {expected}; remove the key or \
         fix its spelling (see the format in `voxgi::scene` docs)",
        file.display(),
        show_source_line(source_line)
    )]
    UnknownKey {
        file: PathBuf,
        line: usize,
        col: usize,
        key: String,
        expected: String,
        source_line: String,
    },

    /// Valid TOML, but a value has the wrong type or shape, or a required key is missing.
    #[error(
        "{}:{line}:{col}: {message}{}; see the format in `voxgi::scene` docs",
        file.display(),
        show_source_line(source_line)
    )]
    Schema {
        file: PathBuf,
        line: usize,
        col: usize,
        message: String,
        source_line: String,
    },

    /// NaN or infinity in a numeric field of the scene file.
    #[error(
        "{}: `{field}` is {value}; expected a finite number; replace it with a finite value",
        file.display()
    )]
    NonFinite {
        file: PathBuf,
        field: String,
        value: f32,
    },

    /// A direction (or `up`, or camera target minus position) of length zero.
    #[error(
        "{}: `{field}` has zero length; expected a non-zero direction vector, e.g. [0, -1, 0]",
        file.display()
    )]
    ZeroLengthDirection { file: PathBuf, field: String },

    /// Camera parameters that do not describe a projection (fov, near/far, up ∥ forward).
    #[error("{}: `{field}`: {problem}", file.display())]
    InvalidCamera {
        file: PathBuf,
        field: String,
        problem: String,
    },

    /// A light intensity or irradiance below zero.
    #[error(
        "{}: `{field}` = {value} is negative; light intensities are W/sr (point, spot) or W/m² \
         (directional) and must be >= 0; use 0 to switch a channel off",
        file.display()
    )]
    NegativeIntensity {
        file: PathBuf,
        field: String,
        value: f32,
    },

    /// A value out of its allowed range, or two fields that contradict each other, or a field
    /// required by another one (e.g. `direction` for a spot light).
    #[error("{}: `{field}`: {problem}", file.display())]
    InvalidValue {
        file: PathBuf,
        field: String,
        problem: String,
    },

    /// The scene has no `[[objects]]`.
    #[error(
        "{}: the scene has no objects; add at least one `[[objects]]` table with `mesh = \
         \"path.obj\"` or `builtin = \"cube\"`",
        file.display()
    )]
    EmptyScene { file: PathBuf },

    /// The OBJ (or MTL) file could not be parsed.
    #[error(
        "{}{}: malformed {kind}: {message}; fix or re-export the file",
        file.display(),
        line.map(|l| format!(":{l}")).unwrap_or_default()
    )]
    MalformedObj {
        file: PathBuf,
        /// "OBJ" or "MTL".
        kind: &'static str,
        line: Option<usize>,
        message: String,
    },

    /// A face refers to a vertex, texture coordinate or normal that does not exist.
    #[error(
        "{}:{line}: face refers to {element} {index}, but only {count} are defined before \
         this line; fix the face indices (OBJ indices start at 1, negative ones count back)",
        file.display()
    )]
    FaceIndexOutOfRange {
        file: PathBuf,
        line: usize,
        /// "vertex", "texture coordinate" or "normal".
        element: &'static str,
        index: i64,
        count: usize,
    },

    /// NaN or infinity in a vertex position, normal or texture coordinate.
    #[error(
        "{}:{line}: {element} has a non-finite component (NaN or infinity); expected finite \
         numbers; fix the exporter or remove the vertex",
        file.display()
    )]
    NonFiniteVertex {
        file: PathBuf,
        line: usize,
        element: &'static str,
    },

    /// A frame of an OBJ sequence whose topology differs from the first frame.
    #[error(
        "{}: OBJ sequence frame differs in topology from the first frame {} ({problem}); \
         every frame must have the same faces, vertex count and materials; re-export the \
         sequence with a fixed topology (referenced by {referenced_by})",
        file.display(),
        first_frame.display()
    )]
    SequenceTopology {
        file: PathBuf,
        first_frame: PathBuf,
        problem: String,
        referenced_by: String,
    },

    /// A texture that must exist (an MTL PBR map) is missing.
    #[error(
        "{}: texture not found (referenced by {referenced_by}); fix the path in the MTL file \
         (relative to the OBJ's directory) or remove the key",
        file.display()
    )]
    TextureMissing {
        file: PathBuf,
        referenced_by: String,
    },

    /// A texture exists but cannot be decoded.
    #[error(
        "{}: cannot decode texture: {message}; convert it to PNG or EXR (referenced by \
         {referenced_by})",
        file.display()
    )]
    TextureDecode {
        file: PathBuf,
        message: String,
        referenced_by: String,
    },

    /// A one-channel map (`map_Pr`, `map_Pm`) whose color channels differ: its first channel
    /// would be read silently, which for a packed texture is the wrong quantity.
    #[error(
        "{}: {key} reads one value per texel from the first channel, but this map's red, green \
         and blue differ (texel ({x}, {y}) is {rgb:?}), as in a packed occlusion/roughness/\
         metalness texture; save the channel that holds the {key} values as a grey image \
         (referenced by {referenced_by})",
        file.display()
    )]
    TextureChannels {
        file: PathBuf,
        key: String,
        x: u32,
        y: u32,
        rgb: [u8; 3],
        referenced_by: String,
    },

    /// A glTF file that cannot be read as glTF 2.0 (bad JSON or GLB framing, a document the
    /// glTF schema rejects, a node tree with a cycle, a camera without a projection).
    #[error("{}: malformed glTF: {message}; fix or re-export the file", file.display())]
    GltfMalformed { file: PathBuf, message: String },

    /// A glTF buffer that is missing, cannot be decoded, or is shorter than the file declares
    /// (or than a bufferView needs).
    #[error(
        "{}: glTF buffer {buffer}{}: {problem}; put the buffer next to the glTF file (its URI is \
         relative to it) or re-export as a self-contained .glb",
        file.display(),
        uri.as_ref().map(|u| format!(" (`{u}`)")).unwrap_or_default()
    )]
    GltfBuffer {
        file: PathBuf,
        buffer: usize,
        uri: Option<String>,
        problem: String,
    },

    /// A glTF accessor that reads outside its bufferView, has a type voxgi cannot use for its
    /// attribute, or (indices) points past the vertices.
    #[error(
        "{}: glTF accessor {accessor} ({what}): {problem}; the file is corrupt or truncated, \
         re-export it",
        file.display()
    )]
    GltfAccessor {
        file: PathBuf,
        accessor: usize,
        /// "POSITION of mesh `x` primitive 0", …
        what: String,
        problem: String,
    },

    /// The glTF requires an extension voxgi does not implement.
    #[error(
        "{}: the glTF requires extension {extension}, which voxgi does not support (supported: \
         {supported}); re-export without it (e.g. without Draco or meshopt compression, \
         texture transforms or quantized vertices)",
        file.display()
    )]
    GltfExtension {
        file: PathBuf,
        extension: String,
        supported: String,
    },

    /// A glTF primitive that is not made of triangles.
    #[error(
        "{}: glTF mesh `{mesh}` primitive {primitive} draws {mode}; voxgi draws triangles \
         only (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN); remove the primitive or convert it \
         to faces",
        file.display()
    )]
    GltfPrimitiveMode {
        file: PathBuf,
        mesh: String,
        primitive: usize,
        mode: &'static str,
    },

    /// An image a glTF material uses that does not exist (or whose data cannot be found).
    #[error(
        "{}: glTF image {image}{} not found (used by {referenced_by}); put the image next to \
         the glTF file (its URI is relative to it) or re-export as a self-contained .glb",
        file.display(),
        uri.as_ref().map(|u| format!(" (`{u}`)")).unwrap_or_default()
    )]
    GltfImageMissing {
        file: PathBuf,
        image: usize,
        uri: Option<String>,
        referenced_by: String,
    },
}

fn show_source_line(line: &str) -> String {
    if line.trim().is_empty() {
        String::new()
    } else {
        format!(" (in `{}`)", line.trim())
    }
}

/// `file: field` as used in "referenced by" clauses.
pub(crate) fn field_ref(file: &Path, field: &str) -> String {
    format!("{}: {field}", file.display())
}

/// 1-based line and column of byte offset `pos` in `text`, and the text of that line.
pub(crate) fn line_col(text: &str, pos: usize) -> (usize, usize, String) {
    let pos = pos.min(text.len());
    // Step back to a char boundary so slicing cannot panic on a span inside a multi-byte char.
    let mut p = pos;
    while p > 0 && !text.is_char_boundary(p) {
        p -= 1;
    }
    let before = &text[..p];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map(|i| i + 1).unwrap_or(0);
    let col = before[line_start..].chars().count() + 1;
    let line_text = text[line_start..].lines().next().unwrap_or("").to_string();
    (line, col, line_text)
}

/// Converts a `toml` error into a [`SceneError`], keeping the line and column.
pub(crate) fn from_toml_error(
    file: &Path,
    text: &str,
    err: &toml::de::Error,
    syntax: bool,
) -> SceneError {
    let (line, col, source_line) =
        err.span()
            .map(|s| line_col(text, s.start))
            .unwrap_or((0, 0, String::new()));
    let message = err.message().trim().replace('\n', "; ");
    let file = file.to_path_buf();
    if syntax {
        return SceneError::TomlSyntax {
            file,
            line,
            col,
            message,
            source_line,
        };
    }
    // serde's wording: "unknown field `foo`, expected one of `a`, `b`" (or "expected `a`").
    if let Some(rest) = message.strip_prefix("unknown field `") {
        if let Some((key, tail)) = rest.split_once('`') {
            let expected = tail
                .trim_start_matches(',')
                .trim()
                .trim_start_matches("expected one of")
                .trim_start_matches("expected")
                .trim()
                .to_string();
            let expected = if expected.is_empty() {
                "no keys here".to_string()
            } else {
                expected
            };
            return SceneError::UnknownKey {
                file,
                line,
                col,
                key: key.to_string(),
                expected,
                source_line,
            };
        }
    }
    SceneError::Schema {
        file,
        line,
        col,
        message,
        source_line,
    }
}

impl SceneError {
    /// A short, stable name of the variant, for logs and tests.
    pub fn kind(&self) -> &'static str {
        match self {
            SceneError::NotFound { .. } => "not-found",
            SceneError::Io { .. } => "io",
            SceneError::TomlSyntax { .. } => "toml-syntax",
            SceneError::UnknownKey { .. } => "unknown-key",
            SceneError::Schema { .. } => "schema",
            SceneError::NonFinite { .. } => "non-finite",
            SceneError::ZeroLengthDirection { .. } => "zero-length-direction",
            SceneError::InvalidCamera { .. } => "invalid-camera",
            SceneError::NegativeIntensity { .. } => "negative-intensity",
            SceneError::InvalidValue { .. } => "invalid-value",
            SceneError::EmptyScene { .. } => "empty-scene",
            SceneError::MalformedObj { .. } => "malformed-obj",
            SceneError::FaceIndexOutOfRange { .. } => "face-index-out-of-range",
            SceneError::NonFiniteVertex { .. } => "non-finite-vertex",
            SceneError::SequenceTopology { .. } => "sequence-topology",
            SceneError::TextureMissing { .. } => "texture-missing",
            SceneError::TextureDecode { .. } => "texture-decode",
            SceneError::TextureChannels { .. } => "texture-channels",
            SceneError::GltfMalformed { .. } => "gltf-malformed",
            SceneError::GltfBuffer { .. } => "gltf-buffer",
            SceneError::GltfAccessor { .. } => "gltf-accessor",
            SceneError::GltfExtension { .. } => "gltf-extension",
            SceneError::GltfPrimitiveMode { .. } => "gltf-primitive-mode",
            SceneError::GltfImageMissing { .. } => "gltf-image-missing",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A message is one sentence: the `\` continuations of its source lines drop their
    /// indentation, so no run of spaces is left inside it.
    #[test]
    fn the_packed_map_message_reads_as_one_sentence() {
        let e = SceneError::TextureChannels {
            file: PathBuf::from("orm.png"),
            key: "map_Pr".into(),
            x: 3,
            y: 4,
            rgb: [10, 200, 30],
            referenced_by: "material 'metal' in scene.mtl".into(),
        };
        let text = e.to_string();
        assert!(
            text.starts_with("orm.png: map_Pr reads one value"),
            "{text}"
        );
        assert!(text.contains("roughness/metalness"), "{text}");
        assert!(!text.contains("  "), "{text}");
    }
}
