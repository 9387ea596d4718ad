//! glTF 2.0 import (`.gltf` with external or `data:` buffers, `.glb`), through the `gltf`
//! crate without its `import` feature: buffers and images are resolved here, and images are
//! decoded by our own `image` crate, as OBJ textures are.
//!
//! A file becomes one [`Mesh`] (the default scene's node tree flattened: every node transform
//! baked into the positions and normals), its materials, its `KHR_lights_punctual` lights and
//! its first camera. What is read and how, the unit conversion and what is ignored are listed
//! in `docs/gltf.md`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use base64::Engine;
use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::khr_lights_punctual::Kind as LightKind;
use gltf::mesh::Mode;

use super::camera::{Camera, Projection};
use super::crease::{split_normals, Smoothing};
use super::error::SceneError;
pub(crate) use super::gltf_asset::{GltfAsset, GltfCamera, GltfProjection};
use super::light::Light;
use super::material::{AlphaMap, AlphaMode, BumpKind, Ggx, Material, PbrMaps, TextureData};
use super::mesh::{Aabb, Mesh, SubMesh};
use super::obj::{decode_image_bytes, decode_image_file, read_bytes, AssetStore};

/// Lumens per watt of the photometric-to-radiometric conversion: 683 lm/W, the luminous
/// efficacy of monochromatic 555 nm light that defines the candela (SI brochure, 9th ed.,
/// 2019, §2.3.1). glTF gives point and spot intensities in candela (lm/sr) and directional
/// ones in lux (lm/m²); voxgi's lights are radiometric, so 683 cd = 1 W/sr and 683 lx =
/// 1 W/m², as three.js and Blender's glTF importer also convert (a white light of 683 cd is
/// treated as if it were all 555 nm, the usual convention for RGB renderers).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// The `extensionsRequired` entries voxgi implements; any other is an error.
pub const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 2] =
    ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

impl GltfCamera {
    /// The voxgi camera this glTF camera becomes under the object transform `model`.
    /// Distances (near, far, the orthographic height) scale with the transform's scale along
    /// the camera's up axis.
    pub fn to_camera(self, model: Mat4) -> Camera {
        let m = model * self.world;
        let position = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up_scaled = m.transform_vector3(Vec3::Y);
        let s = up_scaled.length();
        // Orthogonal to `forward` (a sheared matrix could tilt it).
        let up = (up_scaled - forward * up_scaled.dot(forward)).normalize_or_zero();
        let (projection, fov_y_deg, near, far, ortho) = match self.projection {
            GltfProjection::Perspective {
                yfov_rad,
                znear,
                zfar,
            } => {
                // An infinite projection gets a far plane 10⁶ near planes away (the depth
                // buffer keeps precision up to far/near ≈ 10⁷, `desc::build_camera`).
                let far = zfar.unwrap_or(znear * 1e6);
                (
                    Projection::Perspective,
                    yfov_rad.to_degrees(),
                    znear,
                    far,
                    f32::NAN,
                )
            }
            GltfProjection::Orthographic { ymag, znear, zfar } => (
                Projection::Orthographic,
                super::camera::DEFAULT_ORTHO_FOV_Y_DEG,
                znear,
                zfar,
                2.0 * ymag * s,
            ),
        };
        Camera {
            position,
            forward,
            up,
            fov_y_deg,
            near: near * s,
            far: far * s,
            shift_x_tan: 0.0,
            projection,
            ortho_height_m: ortho,
        }
    }
}

/// A `KHR_lights_punctual` light as a voxgi light at the node whose world matrix is `world`
/// (the light shines down its node's −Z). `color` × `intensity` is candela (point, spot) or
/// lux (directional), divided by [`LUMENS_PER_WATT`]. The spot cone keeps its angles: the
/// outer cone becomes the cutoff, the inner cone the full-intensity beam (voxgi's falloff
/// between them is Mitsuba's, not glTF's suggested smooth step). The light's `range` is
/// ignored: voxgi's lights fall off as 1/d² without a cut-off.
pub(crate) fn punctual_light(kind: LightKind, color: Vec3, intensity: f32, world: Mat4) -> Light {
    let radiometric = color.max(Vec3::ZERO) * intensity.max(0.0) / LUMENS_PER_WATT;
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(-Vec3::Z)
        .try_normalize()
        .unwrap_or(-Vec3::Y);
    match kind {
        LightKind::Directional => Light::Directional {
            direction,
            irradiance_w_m2: radiometric,
        },
        LightKind::Point => Light::Point {
            position,
            intensity_w_sr: radiometric,
        },
        LightKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            // voxgi's cone is (0°, 90°) and its beam (0°, cutoff]; glTF allows an outer angle
            // of π/2 and an inner one of 0.
            let cutoff_deg = outer_cone_angle.to_degrees().clamp(0.01, 89.9);
            let beam_deg = inner_cone_angle.to_degrees().clamp(0.01, cutoff_deg);
            Light::Spot {
                position,
                direction,
                intensity_w_sr: radiometric,
                cutoff_deg,
                beam_deg,
            }
        }
    }
}

impl AssetStore {
    /// Loads (once) the glTF file at `path`; `referenced_by` names the scene field, for
    /// messages. `crease_deg`: the crease angle of primitives without normals
    /// ([`super::crease`]).
    pub fn gltf(
        &mut self,
        path: &Path,
        referenced_by: &str,
        crease_deg: f32,
    ) -> Result<GltfAsset, SceneError> {
        let key = (path.to_path_buf(), crease_deg.to_bits());
        if let Some(a) = self.gltf_files.get(&key) {
            return Ok(a.clone());
        }
        let bytes = read_bytes(path, "glTF file", Some(referenced_by))?;
        let loader = Loader::new(path, &bytes)?;
        // The checks above keep the `gltf` crate's readers within their slices; this guard
        // is for what they miss, so that a bad file cannot crash the renderer.
        let asset = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            loader.load(self, crease_deg)
        }))
        .unwrap_or_else(|_| {
            Err(SceneError::GltfMalformed {
                file: path.to_path_buf(),
                message: "the glTF reader failed on this file".into(),
            })
        })?;
        self.gltf_files.insert(key, asset.clone());
        Ok(asset)
    }
}

/// What a texture made from a glTF image holds.
#[derive(Clone, Copy, Debug, PartialEq)]
enum TexelUse {
    /// Color, sRGB-encoded, times a linear factor (base color, emission).
    Color(Vec3),
    /// One channel of a packed texture (1 = G roughness, 2 = B metalness) times a factor,
    /// stored grey and linear (what `map_Pr` / `map_Pm` read).
    Channel(usize, f32),
    /// A tangent-space normal map whose X and Y are scaled (`normalTexture.scale`).
    Normal(f32),
}

/// One glTF document with its buffers resolved.
struct Loader {
    file: PathBuf,
    dir: PathBuf,
    doc: gltf::Document,
    buffers: Vec<Vec<u8>>,
    /// Decoded images by index.
    images: HashMap<usize, Rc<image::RgbaImage>>,
}

impl Loader {
    fn new(file: &Path, bytes: &[u8]) -> Result<Loader, SceneError> {
        let malformed = |message: String| SceneError::GltfMalformed {
            file: file.to_path_buf(),
            message,
        };
        // Required extensions first: the schema check below would report them without a hint.
        let unchecked = gltf::Gltf::from_slice_without_validation(bytes)
            .map_err(|e| malformed(e.to_string()))?;
        if let Some(ext) = unchecked
            .extensions_required()
            .find(|e| !SUPPORTED_REQUIRED_EXTENSIONS.contains(e))
        {
            return Err(SceneError::GltfExtension {
                file: file.to_path_buf(),
                extension: ext.to_string(),
                supported: SUPPORTED_REQUIRED_EXTENSIONS.join(", "),
            });
        }
        // gltf-json 1.4's validation indexes the accessors by a primitive's POSITION before
        // checking that index, so an out-of-range one panics there (found by fuzz_tests):
        // check every attribute's accessor here first.
        let json = unchecked.document.as_json();
        for (m, mesh) in json.meshes.iter().enumerate() {
            for (p, primitive) in mesh.primitives.iter().enumerate() {
                for (semantic, accessor) in &primitive.attributes {
                    if accessor.value() >= json.accessors.len() {
                        let name = match semantic {
                            gltf::json::validation::Checked::Valid(s) => s.to_string(),
                            gltf::json::validation::Checked::Invalid => "?".to_string(),
                        };
                        return Err(malformed(format!(
                            "`meshes[{m}].primitives[{p}].attributes.{name}`: accessor {} \
                             does not exist (the file has {})",
                            accessor.value(),
                            json.accessors.len()
                        )));
                    }
                }
            }
        }
        let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| match e {
            gltf::Error::Validation(errors) => {
                let shown: Vec<String> = errors
                    .iter()
                    .take(4)
                    .map(|(path, e)| format!("`{path}`: {e}"))
                    .collect();
                let more = errors.len().saturating_sub(shown.len());
                malformed(format!(
                    "{}{}",
                    shown.join("; "),
                    if more > 0 {
                        format!(" (and {more} more)")
                    } else {
                        String::new()
                    }
                ))
            }
            e => malformed(e.to_string()),
        })?;
        let dir = file.parent().unwrap_or(Path::new(".")).to_path_buf();
        let mut loader = Loader {
            file: file.to_path_buf(),
            dir,
            doc: gltf.document,
            buffers: Vec::new(),
            images: HashMap::new(),
        };
        loader.buffers = loader.resolve_buffers(gltf.blob)?;
        loader.check_views()?;
        Ok(loader)
    }

    /// Each buffer's bytes: the GLB's BIN chunk, a `data:` URI or a file beside the glTF;
    /// never shorter than its declared `byteLength`.
    fn resolve_buffers(&self, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>, SceneError> {
        let mut out = Vec::new();
        for b in self.doc.buffers() {
            let error = |uri: Option<&str>, problem: String| SceneError::GltfBuffer {
                file: self.file.clone(),
                buffer: b.index(),
                uri: uri.map(|u| short_uri(u).to_string()),
                problem,
            };
            let (data, uri) = match b.source() {
                gltf::buffer::Source::Bin => (
                    blob.take().ok_or_else(|| {
                        error(
                            None,
                            "the buffer has no URI, so it is the GLB's binary chunk, but the \
                             file has none"
                                .into(),
                        )
                    })?,
                    None,
                ),
                gltf::buffer::Source::Uri(uri) => {
                    let data = match data_uri(uri) {
                        Some(d) => d.map_err(|e| error(Some(uri), e))?,
                        None => {
                            let path = self.dir.join(percent_decode(uri));
                            std::fs::read(&path).map_err(|e| {
                                error(Some(uri), format!("cannot read {}: {e}", path.display()))
                            })?
                        }
                    };
                    (data, Some(uri))
                }
            };
            if data.len() < b.length() {
                return Err(error(
                    uri,
                    format!(
                        "{} bytes, but the file declares byteLength {}",
                        data.len(),
                        b.length()
                    ),
                ));
            }
            out.push(data);
        }
        Ok(out)
    }

    /// Every bufferView lies inside its buffer.
    fn check_views(&self) -> Result<(), SceneError> {
        for v in self.doc.views() {
            let b = v.buffer();
            let len = self.buffers.get(b.index()).map_or(0, Vec::len);
            let end = v.offset().checked_add(v.length());
            if end.is_none_or(|e| e > len) {
                return Err(SceneError::GltfBuffer {
                    file: self.file.clone(),
                    buffer: b.index(),
                    uri: None,
                    problem: format!(
                        "bufferView {} covers bytes {}..{}, but the buffer has {len} bytes",
                        v.index(),
                        v.offset(),
                        v.offset().saturating_add(v.length())
                    ),
                });
            }
        }
        Ok(())
    }

    fn malformed(&self, message: impl Into<String>) -> SceneError {
        SceneError::GltfMalformed {
            file: self.file.clone(),
            message: message.into(),
        }
    }

    /// Checks that `accessor` can be read as `what` in place: a bufferView, no sparse
    /// storage, at least one element, every element inside the view, and (for the float
    /// attributes) the component type voxgi reads.
    fn check_accessor(
        &self,
        accessor: &gltf::Accessor<'_>,
        what: &str,
        float_vec3: bool,
    ) -> Result<(), SceneError> {
        let error = |problem: String| SceneError::GltfAccessor {
            file: self.file.clone(),
            accessor: accessor.index(),
            what: what.to_string(),
            problem,
        };
        if accessor.sparse().is_some() {
            return Err(error(
                "sparse accessors are not supported; re-export without sparse storage".into(),
            ));
        }
        let Some(view) = accessor.view() else {
            return Err(error(
                "the accessor has no bufferView (all zeros), which is not a mesh".into(),
            ));
        };
        if float_vec3
            && (accessor.data_type() != gltf::accessor::DataType::F32
                || accessor.dimensions() != gltf::accessor::Dimensions::Vec3)
        {
            return Err(error(format!(
                "{:?} {:?}; expected float VEC3 (quantized vertices need \
                 KHR_mesh_quantization, which voxgi does not support)",
                accessor.data_type(),
                accessor.dimensions()
            )));
        }
        let count = accessor.count();
        if count == 0 {
            return Err(error("count is 0; expected at least 1 element".into()));
        }
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size);
        let end = (count as u64 - 1)
            .checked_mul(stride as u64)
            .and_then(|x| x.checked_add((accessor.offset() + size) as u64));
        if end.is_none_or(|e| e > view.length() as u64) {
            return Err(error(format!(
                "{count} elements of {size} bytes (stride {stride}) from byte {} need {} \
                 bytes, but bufferView {} has {}",
                accessor.offset(),
                end.map_or("more than 2⁶⁴".to_string(), |e| e.to_string()),
                view.index(),
                view.length()
            )));
        }
        Ok(())
    }

    fn load(mut self, store: &mut AssetStore, crease_deg: f32) -> Result<GltfAsset, SceneError> {
        let scene = self
            .doc
            .default_scene()
            .or_else(|| self.doc.scenes().next())
            .ok_or_else(|| self.malformed("the file has no scene; export with a scene"))?;
        // The node tree flattened, depth first in file order: (node index, world matrix).
        let mut nodes: Vec<(usize, Mat4)> = Vec::new();
        let mut seen = vec![false; self.doc.nodes().len()];
        let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
            scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
        stack.reverse();
        while let Some((node, parent)) = stack.pop() {
            let i = node.index();
            if std::mem::replace(&mut seen[i], true) {
                return Err(self.malformed(format!(
                    "node {i} is reached twice (a cycle, or a node with two parents); glTF \
                     nodes form trees"
                )));
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if !world.is_finite() {
                return Err(self.malformed(format!("node {i} has a non-finite transform")));
            }
            nodes.push((i, world));
            let first_child = stack.len();
            stack.extend(node.children().map(|c| (c, world)));
            stack[first_child..].reverse();
        }

        let mut mesh = Mesh {
            name: self.file.display().to_string(),
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: None,
            indices: Vec::new(),
            submeshes: Vec::new(),
            aabb: Aabb::EMPTY,
        };
        let mut uvs: Vec<Vec2> = Vec::new();
        let mut any_uvs = false;
        let mut lights = Vec::new();
        let mut camera = None;
        let doc = self.doc.clone();
        for &(i, world) in &nodes {
            let Some(node) = doc.nodes().nth(i) else {
                continue;
            };
            if let Some(l) = node.light() {
                lights.push(punctual_light(
                    l.kind(),
                    Vec3::from_array(l.color()),
                    l.intensity(),
                    world,
                ));
            }
            if let (None, Some(c)) = (camera, node.camera()) {
                camera = Some(self.camera(&c, world)?);
            }
            let Some(m) = node.mesh() else { continue };
            for p in m.primitives() {
                let Some(part) = self.primitive(store, &m, &p, world, crease_deg)? else {
                    continue;
                };
                let base = mesh.positions.len() as u32;
                let first_index = mesh.indices.len() as u32;
                mesh.indices.extend(part.indices.iter().map(|&k| k + base));
                mesh.positions.extend(&part.positions);
                mesh.normals.extend(&part.normals);
                match part.uvs {
                    Some(u) => {
                        if !any_uvs {
                            uvs.resize(mesh.positions.len() - part.positions.len(), Vec2::ZERO);
                            any_uvs = true;
                        }
                        uvs.extend(u);
                    }
                    None if any_uvs => uvs.resize(mesh.positions.len(), Vec2::ZERO),
                    None => {}
                }
                mesh.submeshes.push(SubMesh {
                    first_index,
                    index_count: part.indices.len() as u32,
                    material: part.material,
                });
            }
        }
        if mesh.indices.is_empty() {
            return Err(self.malformed(
                "the default scene draws no triangles (no node with a mesh of triangles)",
            ));
        }
        if any_uvs {
            mesh.uvs = Some(uvs);
        }
        mesh.update_aabb();
        let index = store.meshes.len();
        store.meshes.push(mesh);
        Ok(GltfAsset {
            mesh: index,
            lights,
            camera,
        })
    }

    fn camera(&self, c: &gltf::Camera<'_>, world: Mat4) -> Result<GltfCamera, SceneError> {
        let bad = |what: String| {
            self.malformed(format!(
                "camera {}: {what}; expected finite values with 0 < znear < zfar",
                c.index()
            ))
        };
        let projection = match c.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let (yfov, znear, zfar) = (p.yfov(), p.znear(), p.zfar());
                if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                    return Err(bad(format!("yfov {yfov} is not in (0, π)")));
                }
                if !(znear > 0.0 && znear.is_finite())
                    || zfar.is_some_and(|f| f.is_nan() || f <= znear)
                {
                    return Err(bad(format!("znear {znear}, zfar {zfar:?}")));
                }
                GltfProjection::Perspective {
                    yfov_rad: yfov,
                    znear,
                    zfar: zfar.filter(|f| f.is_finite()),
                }
            }
            gltf::camera::Projection::Orthographic(o) => {
                let (ymag, znear, zfar) = (o.ymag(), o.znear(), o.zfar());
                if !(ymag.abs() > 0.0 && ymag.is_finite()) {
                    return Err(bad(format!("ymag {ymag}")));
                }
                // glTF allows znear = 0 for orthographic cameras; voxgi's near must be > 0.
                let znear = znear.max(zfar * 1e-6);
                if !(zfar > znear && zfar.is_finite()) {
                    return Err(bad(format!("znear {znear}, zfar {zfar}")));
                }
                GltfProjection::Orthographic {
                    ymag: ymag.abs(),
                    znear,
                    zfar,
                }
            }
        };
        Ok(GltfCamera { world, projection })
    }

    /// One primitive in world space, or `None` when it draws nothing (an alpha-masked
    /// material whose constant alpha is below its cutoff).
    fn primitive(
        &mut self,
        store: &mut AssetStore,
        m: &gltf::Mesh<'_>,
        p: &gltf::Primitive<'_>,
        world: Mat4,
        crease_deg: f32,
    ) -> Result<Option<Part>, SceneError> {
        let mesh_name = m
            .name()
            .map_or_else(|| m.index().to_string(), str::to_string);
        let mode = match p.mode() {
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => p.mode(),
            other => {
                return Err(SceneError::GltfPrimitiveMode {
                    file: self.file.clone(),
                    mesh: mesh_name,
                    primitive: p.index(),
                    mode: match other {
                        Mode::Points => "POINTS",
                        Mode::Lines => "LINES",
                        Mode::LineLoop => "LINE_LOOP",
                        _ => "LINE_STRIP",
                    },
                })
            }
        };
        let material = self.material(store, &p.material())?;
        let Some(material) = material else {
            return Ok(None);
        };
        let local = self.read_primitive(&mesh_name, p)?;
        let indices = triangles(mode, &local.vertex_indices);
        Ok(Some(local.into_world(indices, world, crease_deg, material)))
    }

    /// The vertex attributes and indices of primitive `p` of mesh `mesh_name`, checked: finite
    /// positions, indices within the vertices, and one normal and texture coordinate (where
    /// given) per vertex.
    fn read_primitive(
        &self,
        mesh_name: &str,
        p: &gltf::Primitive<'_>,
    ) -> Result<LocalPrimitive, SceneError> {
        let attr = |a: &str| format!("{a} of mesh `{mesh_name}` primitive {}", p.index());
        let positions_acc = p.get(&gltf::Semantic::Positions).ok_or_else(|| {
            self.malformed(format!(
                "mesh `{mesh_name}` primitive {} has no POSITION attribute",
                p.index()
            ))
        })?;
        self.check_accessor(&positions_acc, &attr("POSITION"), true)?;
        let normals_acc = p.get(&gltf::Semantic::Normals);
        if let Some(a) = &normals_acc {
            self.check_accessor(a, &attr("NORMAL"), true)?;
        }
        let uv_acc = p.get(&gltf::Semantic::TexCoords(0));
        if let Some(a) = &uv_acc {
            self.check_accessor(a, &attr("TEXCOORD_0"), false)?;
        }
        if let Some(a) = p.indices() {
            self.check_accessor(&a, &attr("indices"), false)?;
        }
        let buffers = &self.buffers;
        let reader = p.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let read_failed = |what: &str| self.malformed(format!("cannot read {}", attr(what)));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| read_failed("POSITION"))?
            .map(Vec3::from_array)
            .collect();
        if let Some(k) = positions.iter().position(|v| !v.is_finite()) {
            return Err(SceneError::GltfAccessor {
                file: self.file.clone(),
                accessor: positions_acc.index(),
                what: attr("POSITION"),
                problem: format!("vertex {k} is not finite (NaN or infinity)"),
            });
        }
        let n = positions.len();
        let normals: Option<Vec<Vec3>> = match normals_acc {
            Some(_) => Some(
                reader
                    .read_normals()
                    .ok_or_else(|| read_failed("NORMAL"))?
                    .map(Vec3::from_array)
                    .collect(),
            ),
            None => None,
        };
        let uvs: Option<Vec<Vec2>> = match uv_acc {
            Some(_) => Some(
                reader
                    .read_tex_coords(0)
                    .ok_or_else(|| read_failed("TEXCOORD_0"))?
                    .into_f32()
                    // glTF's v runs down the image, voxgi's (OBJ's) up.
                    .map(|[u, v]| Vec2::new(u, 1.0 - v))
                    .collect(),
            ),
            None => None,
        };
        let vertex_indices: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = vertex_indices.iter().find(|&&k| k as usize >= n) {
            return Err(SceneError::GltfAccessor {
                file: self.file.clone(),
                accessor: p.indices().map_or(positions_acc.index(), |a| a.index()),
                what: attr("indices"),
                problem: format!("index {bad} points past the {n} vertices"),
            });
        }
        if normals.as_ref().is_some_and(|v| v.len() != n)
            || uvs.as_ref().is_some_and(|v| v.len() != n)
        {
            return Err(self.malformed(format!(
                "mesh `{mesh_name}` primitive {}: its attributes have different counts",
                p.index()
            )));
        }
        Ok(LocalPrimitive {
            positions,
            normals,
            uvs,
            vertex_indices,
        })
    }

    /// The store's material for a glTF material (made once per file and index), or `None`
    /// for an alpha-masked material whose constant alpha is below its cutoff (it draws
    /// nothing).
    fn material(
        &mut self,
        store: &mut AssetStore,
        m: &gltf::Material<'_>,
    ) -> Result<Option<usize>, SceneError> {
        let pbr = m.pbr_metallic_roughness();
        let factor = pbr.base_color_factor();
        let alpha = factor[3].clamp(0.0, 1.0);
        let cutoff = m.alpha_cutoff().unwrap_or(0.5);
        if m.alpha_mode() == gltf::material::AlphaMode::Mask && alpha < cutoff {
            return Ok(None);
        }
        let key = (self.file.clone(), m.index());
        if let Some(&i) = store.gltf_materials.get(&key) {
            return Ok(Some(i));
        }
        let name = match (m.name(), m.index()) {
            (Some(n), _) => n.to_string(),
            (None, Some(i)) => format!("material{i}"),
            (None, None) => "default".to_string(),
        };
        let file = self.file.display().to_string();
        let used_by = |slot: &str| format!("{file}: material `{name}` {slot}");
        let finite = |v: f32, d: f32| if v.is_finite() { v } else { d };
        let base = Vec3::new(factor[0], factor[1], factor[2]).clamp(Vec3::ZERO, Vec3::ONE);
        let roughness = finite(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0);
        let metallic = finite(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0);
        warn_tex_coord(
            &self.file,
            &name,
            [
                pbr.base_color_texture().map(|t| t.tex_coord()),
                pbr.metallic_roughness_texture().map(|t| t.tex_coord()),
                m.normal_texture().map(|t| t.tex_coord()),
                m.emissive_texture().map(|t| t.tex_coord()),
            ],
        );
        let albedo_texture = match pbr.base_color_texture() {
            Some(t) => Some(self.texture(
                store,
                &t.texture().source(),
                TexelUse::Color(base),
                &used_by("baseColorTexture"),
            )?),
            None => None,
        };
        let alpha_map = alpha_map(
            m.alpha_mode(),
            alpha,
            cutoff,
            albedo_texture.and_then(|t| store.textures.get(t).map(|d| (t, d))),
        );
        let pbr_maps = match pbr.metallic_roughness_texture() {
            Some(t) => {
                let image = t.texture().source();
                let what = used_by("metallicRoughnessTexture");
                PbrMaps {
                    roughness: Some(self.texture(
                        store,
                        &image,
                        TexelUse::Channel(1, roughness),
                        &what,
                    )?),
                    metallic: Some(self.texture(
                        store,
                        &image,
                        TexelUse::Channel(2, metallic),
                        &what,
                    )?),
                    emission: None,
                }
            }
            None => PbrMaps::default(),
        };
        let bump_texture = match m.normal_texture() {
            Some(t) => {
                let scale = finite(t.scale(), 1.0);
                Some(self.texture(
                    store,
                    &t.texture().source(),
                    TexelUse::Normal(scale),
                    &used_by("normalTexture"),
                )?)
            }
            None => None,
        };
        let strength = finite(m.emissive_strength().unwrap_or(1.0), 1.0).max(0.0);
        let emission = Vec3::from_array(m.emissive_factor()).max(Vec3::ZERO) * strength;
        let emission = if emission.is_finite() {
            emission
        } else {
            Vec3::ZERO
        };
        let emission_map = match m.emissive_texture() {
            Some(t) if emission.max_element() > 0.0 => Some(self.texture(
                store,
                &t.texture().source(),
                TexelUse::Color(Vec3::ONE),
                &used_by("emissiveTexture"),
            )?),
            _ => None,
        };
        let opacity = match m.alpha_mode() {
            gltf::material::AlphaMode::Blend => alpha,
            _ => 1.0,
        };
        let material = Material {
            name,
            albedo: base,
            specular: Vec3::ZERO,
            shininess: 0.0,
            albedo_texture,
            bump_texture,
            bump_kind: BumpKind::TangentNormal,
            bump_scale: 1.0,
            opacity,
            ggx: Some(Ggx {
                roughness,
                metallic,
            }),
            emission,
            pbr_maps: PbrMaps {
                emission: emission_map,
                ..pbr_maps
            },
            alpha_map,
        };
        let i = store.materials.len();
        store.materials.push(material);
        store.gltf_materials.insert(key, i);
        Ok(Some(i))
    }

    /// The decoded RGBA8 texels of image `image`.
    fn rgba(
        &mut self,
        image: &gltf::Image<'_>,
        used_by: &str,
    ) -> Result<Rc<image::RgbaImage>, SceneError> {
        if let Some(i) = self.images.get(&image.index()) {
            return Ok(Rc::clone(i));
        }
        let (label, decoded) = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let bytes = self
                    .buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.get(view.offset()..view.offset() + view.length()))
                    .ok_or_else(|| self.image_missing(image, None, used_by))?;
                (self.image_label(image), decode_image_bytes(bytes))
            }
            gltf::image::Source::Uri { uri, .. } => match data_uri(uri) {
                Some(bytes) => {
                    let bytes = bytes.map_err(|e| SceneError::TextureDecode {
                        file: self.image_label(image),
                        message: e,
                        referenced_by: used_by.to_string(),
                    })?;
                    (self.image_label(image), decode_image_bytes(&bytes))
                }
                None => {
                    let path = self.dir.join(percent_decode(uri));
                    if !path.is_file() {
                        return Err(self.image_missing(image, Some(uri), used_by));
                    }
                    let decoded = decode_image_file(&path);
                    (path, decoded)
                }
            },
        };
        let rgba = Rc::new(decoded.map_err(|message| SceneError::TextureDecode {
            file: label,
            message,
            referenced_by: used_by.to_string(),
        })?);
        self.images.insert(image.index(), Rc::clone(&rgba));
        Ok(rgba)
    }

    fn image_missing(
        &self,
        image: &gltf::Image<'_>,
        uri: Option<&str>,
        used_by: &str,
    ) -> SceneError {
        SceneError::GltfImageMissing {
            file: self.file.clone(),
            image: image.index(),
            uri: uri.map(|u| short_uri(u).to_string()),
            referenced_by: used_by.to_string(),
        }
    }

    /// The path a texture from `image` is known by: its file for an external image, else
    /// `FILE#imageN`.
    fn image_label(&self, image: &gltf::Image<'_>) -> PathBuf {
        match image.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                self.dir.join(percent_decode(uri))
            }
            _ => PathBuf::from(format!("{}#image{}", self.file.display(), image.index())),
        }
    }

    /// The store's texture holding `image` as `texel_use` (made once per file, image and use).
    /// An external image used as it is goes through [`AssetStore::texture`], as OBJ textures.
    fn texture(
        &mut self,
        store: &mut AssetStore,
        image: &gltf::Image<'_>,
        texel_use: TexelUse,
        used_by: &str,
    ) -> Result<usize, SceneError> {
        let label = self.image_label(image);
        let plain_srgb = match texel_use {
            TexelUse::Color(f) => (f == Vec3::ONE).then_some(true),
            TexelUse::Normal(s) => (s == 1.0).then_some(false),
            TexelUse::Channel(..) => None,
        };
        if let (Some(srgb), gltf::image::Source::Uri { uri, .. }) = (plain_srgb, image.source()) {
            if !uri.starts_with("data:") {
                if !label.is_file() {
                    return Err(self.image_missing(image, Some(uri), used_by));
                }
                if let Some(i) = store.texture(&label, srgb, used_by, true)? {
                    return Ok(i);
                }
            }
        }
        let key = (
            self.file.clone(),
            format!("image{}:{texel_use:?}", image.index()),
        );
        if let Some(&i) = store.gltf_textures.get(&key) {
            return Ok(i);
        }
        let rgba = self.rgba(image, used_by)?;
        let (width, height) = rgba.dimensions();
        let mut texels = rgba.as_raw().clone();
        let srgb = matches!(texel_use, TexelUse::Color(_));
        convert_texels(&mut texels, texel_use);
        let i = store.textures.len();
        store
            .textures
            .push(TextureData::new(label, width, height, texels, srgb));
        store.gltf_textures.insert(key, i);
        Ok(i)
    }
}

/// The per-texel alpha of a material whose base colour texture is `texture` (index and
/// texels), under glTF 2.0 §3.9.4: the alpha is `baseColorFactor`'s alpha (`factor_alpha`)
/// times the texel's. `MASK` keeps a texel where that product is at least `cutoff`, so the
/// texture's own alpha is compared with cutoff / factor alpha (the caller has dropped
/// primitives whose factor alpha is below the cutoff, so the quotient is at most 1); `BLEND`
/// multiplies the texel's alpha into the material's opacity in the shaders. `None` for
/// `OPAQUE`, without a texture, for a texture whose texels are all opaque (nothing to test, so
/// the material costs the passes nothing), and for a cutoff of 0 (every texel passes).
fn alpha_map(
    mode: gltf::material::AlphaMode,
    factor_alpha: f32,
    cutoff: f32,
    texture: Option<(usize, &TextureData)>,
) -> Option<AlphaMap> {
    let (index, data) = texture?;
    if data.rgba8.chunks_exact(4).all(|p| p[3] == 255) {
        return None;
    }
    let mode = match mode {
        gltf::material::AlphaMode::Opaque => return None,
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        gltf::material::AlphaMode::Mask => {
            let c = if factor_alpha > 0.0 {
                (cutoff / factor_alpha).min(1.0)
            } else {
                0.0
            };
            if c.is_nan() || c <= 0.0 {
                return None;
            }
            AlphaMode::Cutout(c)
        }
    };
    Some(AlphaMap {
        texture: index,
        mode,
    })
}

/// A primitive's triangles in world space.
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<Vec2>>,
    indices: Vec<u32>,
    material: usize,
}

/// A primitive's attributes as the file gives them, in its mesh's space.
struct LocalPrimitive {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    /// The primitive's indices (or `0..n` without an index accessor), before triangulation.
    vertex_indices: Vec<u32>,
}

impl LocalPrimitive {
    /// The primitive as triangles `indices` in world space (`world` its node's transform), as
    /// a part drawn with `material`. Without normals in the file, they are made by the
    /// `crease_deg` crease angle.
    fn into_world(
        self,
        mut indices: Vec<u32>,
        world: Mat4,
        crease_deg: f32,
        material: usize,
    ) -> Part {
        // A mirroring transform turns the winding around (glTF 2.0 §3.7.4: the front face
        // is counter-clockwise after the node transform).
        if world.determinant() < 0.0 {
            for t in indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        let world_positions: Vec<Vec3> = self
            .positions
            .iter()
            .map(|&v| world.transform_point3(v))
            .collect();
        let normal_matrix = inverse_transpose(Mat3::from_mat4(world));
        let uvs = self.uvs;
        let (positions, normals, uvs, indices) = match self.normals {
            Some(local) => {
                let computed = super::mesh::area_weighted_normals(&world_positions, &indices);
                let normals = local
                    .iter()
                    .zip(&computed)
                    .map(|(&v, &c)| {
                        // A zero or non-finite normal falls back to the computed one.
                        (normal_matrix * v).try_normalize().unwrap_or(c)
                    })
                    .collect::<Vec<_>>();
                // The normals are the front, as for OBJ files: a triangle wound against
                // them is rewound ([`super::mesh::orient_to_normals`]).
                super::mesh::orient_to_normals(&world_positions, &normals, &mut indices);
                (world_positions, normals, uvs, indices)
            }
            None => {
                // glTF asks for flat normals here (§3.7.2.1); voxgi smooths across edges
                // below the crease angle, as for OBJ files without normals.
                let s = split_normals(&world_positions, &indices, Smoothing::CreaseDeg(crease_deg));
                let gather = |k: &u32| world_positions[*k as usize];
                let uvs = uvs.map(|u| s.source.iter().map(|&k| u[k as usize]).collect());
                (
                    s.source.iter().map(gather).collect(),
                    s.normals,
                    uvs,
                    s.indices,
                )
            }
        };
        Part {
            positions,
            normals,
            uvs,
            indices,
            material,
        }
    }
}

/// Rewrites RGBA8 texels for `texel_use` (glTF 2.0 §3.9: base color and emission are
/// sRGB-encoded and multiplied by their factors; metalness is B and roughness G of the
/// packed texture, times their factors; a normal map's X and Y are scaled by `scale`).
fn convert_texels(texels: &mut [u8], texel_use: TexelUse) {
    let to_u8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    for t in texels.chunks_exact_mut(4) {
        match texel_use {
            TexelUse::Color(f) => {
                if f != Vec3::ONE {
                    for (c, k) in t.iter_mut().zip(f.to_array()) {
                        let linear = crate::imaging::srgb_decode(f32::from(*c) / 255.0) * k;
                        *c = to_u8(crate::imaging::srgb_encode(linear));
                    }
                }
            }
            TexelUse::Channel(channel, factor) => {
                let v = to_u8(f32::from(t[channel]) / 255.0 * factor);
                t.copy_from_slice(&[v, v, v, 255]);
            }
            TexelUse::Normal(scale) => {
                let n = Vec3::new(t[0].into(), t[1].into(), t[2].into()) / 127.5 - Vec3::ONE;
                let n = (n * Vec3::new(scale, scale, 1.0))
                    .try_normalize()
                    .unwrap_or(Vec3::Z);
                for (c, v) in t.iter_mut().zip(n.to_array()) {
                    *c = to_u8(v * 0.5 + 0.5);
                }
            }
        }
    }
}

/// Triangle list of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive (glTF 2.0
/// §3.7.2.1; strips alternate their winding so every triangle keeps its orientation).
fn triangles(mode: Mode, ix: &[u32]) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => (0..ix.len().saturating_sub(2))
            .flat_map(|i| {
                if i % 2 == 0 {
                    [ix[i], ix[i + 1], ix[i + 2]]
                } else {
                    [ix[i + 1], ix[i], ix[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..ix.len().saturating_sub(1))
            .flat_map(|i| [ix[i], ix[i + 1], ix[0]])
            .collect(),
        _ => ix[..ix.len() / 3 * 3].to_vec(),
    }
}

/// The normals' transform of a linear map `m`: its inverse transpose, the cofactors over the
/// determinant z·(x×y). glam's `Mat3::inverse` takes the determinant as x·(y×z), which rounds
/// differently; this order keeps glTF normals bit for bit what the renders were measured with.
fn inverse_transpose(m: Mat3) -> Mat3 {
    let (c0, c1, c2) = (
        m.y_axis.cross(m.z_axis),
        m.z_axis.cross(m.x_axis),
        m.x_axis.cross(m.y_axis),
    );
    let inv_det = 1.0 / m.z_axis.dot(c2);
    Mat3::from_cols(c0 * inv_det, c1 * inv_det, c2 * inv_det)
}

fn warn_tex_coord(file: &Path, material: &str, sets: [Option<u32>; 4]) {
    if sets.iter().flatten().any(|&s| s != 0) {
        log::warn!(
            "{}: material `{material}` samples a texture with TEXCOORD_1 or higher; voxgi \
             reads TEXCOORD_0 only, so that texture is mapped by TEXCOORD_0",
            file.display()
        );
    }
}

/// The bytes of a `data:` URI (base64 or percent-encoded), `None` for any other URI.
fn data_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
    let rest = uri.strip_prefix("data:")?;
    let Some((meta, data)) = rest.split_once(',') else {
        return Some(Err("a `data:` URI without a comma".into()));
    };
    Some(if meta.ends_with(";base64") {
        base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| format!("its base64 data cannot be decoded: {e}"))
    } else {
        Ok(percent_decode(data).into_bytes())
    })
}

/// `%XX` escapes of a URI decoded (glTF URIs are RFC 3986 references; file names with spaces
/// are written `%20`). An escape that is not two hex digits stays as it is.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |k: usize| b.get(k).and_then(|c| (*c as char).to_digit(16));
        match (b[i], hex(i + 1), hex(i + 2)) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// A URI for messages: a `data:` URI cut after its media type.
fn short_uri(uri: &str) -> &str {
    if uri.starts_with("data:") {
        uri.split(',').next().unwrap_or(uri)
    } else {
        uri
    }
}

/// True for paths voxgi reads as glTF (`.gltf`, `.glb`, any case).
pub fn is_gltf_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}
