//! OBJ/MTL loading (through `tobj`), textures (through `image`), and the store that
//! deduplicates meshes, materials and textures while a scene is built.

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::crease::{obj_smoothing_groups, split_normals, Smoothing};
use super::error::SceneError;
use super::material::{AlphaMap, AlphaMode, BumpKind, Ggx, Material, PbrMaps, TextureData};
use super::mesh::{area_weighted_normals, builtin_shape, BuiltinMaterial, Mesh, SubMesh};

/// Meshes, materials and textures of a scene under construction.
#[derive(Default)]
pub(crate) struct AssetStore {
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureData>,
    /// OBJ path → mesh, so objects sharing a file share the mesh.
    /// Loaded OBJ meshes by path and crease angle (its bits).
    obj_meshes: HashMap<(PathBuf, u32), usize>,
    builtin_meshes: HashMap<String, usize>,
    /// (OBJ directory, MTL material name) → material.
    mtl_materials: HashMap<(PathBuf, String), usize>,
    builtin_materials: HashMap<BuiltinMaterial, usize>,
    /// (path, sRGB) → texture, `None` when missing (warned once).
    textures_by_path: HashMap<(PathBuf, bool), Option<usize>>,
    /// Loaded glTF files by path and crease angle (its bits), so objects sharing a file share
    /// its mesh ([`super::gltf`]).
    pub(super) gltf_files: HashMap<(PathBuf, u32), super::gltf_asset::GltfAsset>,
    /// Textures made from glTF images (a channel split off, a factor baked in), by glTF file
    /// and a key naming the image and what was made of it.
    pub(super) gltf_textures: HashMap<(PathBuf, String), usize>,
    /// glTF materials by (file, material index; `None` for the default material).
    pub(super) gltf_materials: HashMap<(PathBuf, Option<usize>), usize>,
}

impl AssetStore {
    pub fn builtin_material(&mut self, m: BuiltinMaterial) -> usize {
        if let Some(&i) = self.builtin_materials.get(&m) {
            return i;
        }
        let i = self.materials.len();
        self.materials.push(Material::lambert(
            format!("builtin:{}", m.name()),
            m.albedo(),
        ));
        self.builtin_materials.insert(m, i);
        i
    }

    /// The mesh for `builtin = NAME`, or `None` if there is no such shape.
    pub fn builtin_mesh(&mut self, name: &str) -> Option<usize> {
        if let Some(&i) = self.builtin_meshes.get(name) {
            return Some(i);
        }
        let shape = builtin_shape(name)?;
        let submeshes = shape
            .parts
            .iter()
            .map(|&(first_index, index_count, m)| SubMesh {
                first_index,
                index_count,
                material: self.builtin_material(m),
            })
            .collect();
        let mut mesh = Mesh {
            name: format!("builtin:{name}"),
            positions: shape.positions,
            normals: shape.normals,
            uvs: Some(shape.uvs),
            indices: shape.indices,
            submeshes,
            aabb: super::mesh::Aabb::EMPTY,
        };
        mesh.update_aabb();
        let i = self.meshes.len();
        self.meshes.push(mesh);
        self.builtin_meshes.insert(name.to_string(), i);
        Some(i)
    }

    /// Loads (once) the OBJ at `path`; `referenced_by` names the scene field, for messages.
    /// `crease_deg`: the crease angle for files without normals and smoothing groups
    /// ([`super::crease`]).
    pub fn obj_mesh(
        &mut self,
        path: &Path,
        what: &'static str,
        referenced_by: &str,
        crease_deg: f32,
    ) -> Result<usize, SceneError> {
        let key = (path.to_path_buf(), crease_deg.to_bits());
        if let Some(&i) = self.obj_meshes.get(&key) {
            return Ok(i);
        }
        let mesh = self.load_obj(path, what, referenced_by, crease_deg)?;
        let i = self.meshes.len();
        self.meshes.push(mesh);
        self.obj_meshes.insert(key, i);
        Ok(i)
    }

    fn load_obj(
        &mut self,
        path: &Path,
        what: &'static str,
        referenced_by: &str,
        crease_deg: f32,
    ) -> Result<Mesh, SceneError> {
        let text = read_text(path, what, Some(referenced_by))?;
        prescan_obj(path, &text)?;
        let groups = obj_smoothing_groups(&text);

        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let ObjContents {
            models,
            materials,
            mtl_files,
        } = load_obj_models(path, &dir, &text)?;
        let material_ids = materials
            .iter()
            .map(|m| {
                // tobj only reports materials of MTL files that were read.
                let mtl = mtl_files.get(&m.name).map_or(path, PathBuf::as_path);
                self.register_mtl_material(&dir, m, path, mtl)
            })
            .collect::<Result<Vec<_>, _>>()?;

        let mut mesh = Mesh {
            name: path.display().to_string(),
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: None,
            indices: Vec::new(),
            submeshes: Vec::new(),
            aabb: super::mesh::Aabb::EMPTY,
        };
        let any_uvs = models.iter().any(|m| !m.mesh.texcoords.is_empty());
        let triangles: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
        let groups = groups.filter(|g| {
            let ok = g.len() == triangles;
            if !ok {
                log::warn!(
                    "{}: {} triangles in the `f` lines, {triangles} loaded; smoothing groups \
                     ignored, normals by the {crease_deg}° crease angle",
                    path.display(),
                    g.len()
                );
            }
            ok
        });
        let mut first_triangle = 0;
        let mut uvs = any_uvs.then(Vec::new);
        for model in &models {
            let m = &model.mesh;
            let model_groups = groups.as_ref().map(|g| {
                let t = m.indices.len() / 3;
                &g[first_triangle..first_triangle + t]
            });
            first_triangle += m.indices.len() / 3;
            if m.indices.is_empty() {
                continue;
            }
            // No normals in the file: by smoothing group or crease angle, splitting vertices
            // where their corners' normals differ.
            let split;
            let m = if m.normals.len() == m.positions.len() {
                m
            } else {
                let smoothing =
                    model_groups.map_or(Smoothing::CreaseDeg(crease_deg), Smoothing::Groups);
                split = split_model(m, smoothing);
                &split
            };
            let material = match m.material_id.and_then(|id| material_ids.get(id)) {
                Some(&id) => id,
                None => self.builtin_material(BuiltinMaterial::Default),
            };
            append_model(&mut mesh, uvs.as_mut(), m, material);
        }
        if mesh.indices.is_empty() {
            return Err(SceneError::MalformedObj {
                file: path.to_path_buf(),
                kind: "OBJ",
                line: None,
                message: "the file contains no faces (`f` lines)".into(),
            });
        }
        mesh.uvs = uvs;
        mesh.update_aabb();
        Ok(mesh)
    }

    fn register_mtl_material(
        &mut self,
        dir: &Path,
        m: &tobj::Material,
        obj: &Path,
        mtl: &Path,
    ) -> Result<usize, SceneError> {
        let key = (dir.to_path_buf(), m.name.clone());
        if let Some(&i) = self.mtl_materials.get(&key) {
            return Ok(i);
        }
        let field = |f: &str| format!("{}: material `{}` {f}", obj.display(), m.name);
        let rgb = |v: Option<[f32; 3]>, default: Vec3| {
            v.map(Vec3::from_array)
                .filter(|c| c.is_finite())
                .unwrap_or(default)
                .max(Vec3::ZERO)
        };
        let albedo_texture = match texture_file(m.diffuse_texture.as_deref()) {
            Some(t) => self.texture(&dir.join(t), true, &field("map_Kd"), false)?,
            None => None,
        };
        let mut bump_kind = BumpKind::Height;
        let mut bump_texture = match texture_file(m.normal_texture.as_deref()) {
            Some(t) => self.texture(&dir.join(t), false, &field("map_bump"), false)?,
            None => None,
        };
        if let Some(t) = texture_file(m.unknown_param.get("norm").map(String::as_str)) {
            if let Some(i) = self.texture(&dir.join(t), false, &field("norm"), false)? {
                bump_texture = Some(i);
                bump_kind = BumpKind::TangentNormal;
            }
        }
        let finite_or = |v: Option<f32>, d: f32| v.filter(|x| x.is_finite()).unwrap_or(d);
        let alpha_map = match texture_file(m.dissolve_texture.as_deref()) {
            Some(t) => self
                .texture(&dir.join(t), false, &field("map_d"), false)?
                .map(|mask| self.merge_alpha_map(mask, albedo_texture)),
            None => None,
        };
        // The merged copy carries the albedo too (AlphaMap's invariant).
        let albedo_texture = match (albedo_texture, alpha_map) {
            (Some(_), Some(a)) => Some(a.texture),
            (t, _) => t,
        };
        // The PBR extension's maps: roughness and metalness linear, emission sRGB. A missing
        // one is an error naming the MTL file: these maps are new enough that a broken path is
        // a mistake in the scene at hand, not an old download (unlike `map_Kd` above).
        let pbr_field = |key: &str| {
            format!(
                "{}: material `{}` {key} (loaded by {})",
                mtl.display(),
                m.name,
                obj.display()
            )
        };
        let pbr_maps = PbrMaps {
            roughness: self.mtl_pbr_map(dir, m, "map_Pr", false, &pbr_field)?,
            metallic: self.mtl_pbr_map(dir, m, "map_Pm", false, &pbr_field)?,
            emission: self.mtl_pbr_map(dir, m, "map_Ke", true, &pbr_field)?,
        };
        let pbr = |key: &str| {
            m.unknown_param
                .get(key)
                .and_then(|v| v.trim().parse::<f32>().ok())
        };
        // prescan_mtl already rejected values outside [0, 1]. A map alone makes the material
        // GGX too (the map replaces the constant).
        let ggx = match (pbr("Pr"), pbr("Pm")) {
            (None, None) if pbr_maps.roughness.is_none() && pbr_maps.metallic.is_none() => None,
            (r, metal) => Some(Ggx {
                roughness: r.unwrap_or(1.0),
                metallic: metal.unwrap_or(0.0),
            }),
        };
        // `map_Ke` scales `Ke`, which is 1 when the MTL gives only the map.
        let ke_default = if pbr_maps.emission.is_some() {
            Vec3::ONE
        } else {
            Vec3::ZERO
        };
        let specular = rgb(m.specular, Vec3::ZERO).min(Vec3::ONE);
        let shininess = finite_or(m.shininess, 0.0).max(0.0);
        if ggx.is_none() {
            warn_flat_phong(&field("Ks"), specular, shininess, m.shininess.is_some());
        }
        let material = Material {
            ggx,
            pbr_maps,
            emission: rgb(m.emissive, ke_default),
            name: m.name.clone(),
            // prescan_mtl warned about reflectances outside [0, 1].
            albedo: rgb(m.diffuse, BuiltinMaterial::Default.albedo()).min(Vec3::ONE),
            specular,
            shininess,
            albedo_texture,
            bump_texture,
            bump_kind,
            bump_scale: bump_multiplier(m.normal_texture.as_deref()),
            opacity: finite_or(m.dissolve, 1.0).clamp(0.0, 1.0),
            alpha_map,
        };
        let i = self.materials.len();
        self.materials.push(material);
        self.mtl_materials.insert(key, i);
        Ok(i)
    }

    /// The PBR extension's map `key` of MTL material `m` (textures under `dir`), `None` where
    /// the material has none; `srgb` for colour (emission), else a linear map of one value per
    /// texel. `referenced_by` names the key for messages.
    fn mtl_pbr_map(
        &mut self,
        dir: &Path,
        m: &tobj::Material,
        key: &str,
        srgb: bool,
        referenced_by: &dyn Fn(&str) -> String,
    ) -> Result<Option<usize>, SceneError> {
        let Some(t) = texture_file(m.unknown_param.get(key).map(String::as_str)) else {
            return Ok(None);
        };
        let path = dir.join(t);
        let i = self.texture(&path, srgb, &referenced_by(key), true)?;
        // Roughness and metalness are one value per texel: a map whose channels differ is most
        // likely packed, and its first channel the wrong quantity.
        let packed = if srgb {
            None
        } else {
            i.and_then(|i| self.textures.get(i))
                .and_then(first_coloured_texel)
        };
        match packed {
            Some((x, y, rgb)) => Err(SceneError::TextureChannels {
                file: path,
                key: key.to_string(),
                x,
                y,
                rgb,
                referenced_by: referenced_by(key),
            }),
            None => Ok(i),
        }
    }

    /// An MTL `map_d` (texture `mask`) as a cutout at 0.5, the usual reading of a dissolve map
    /// in the OBJ tools that export foliage (Blender's, tinyobjloader's users): a texel is
    /// kept where its value is at least one half. The value is the mask's alpha when some texel
    /// of it is not opaque (an RGBA cutout image), else its first channel (a grey mask, as the
    /// MTL specification's scalar `map_d`). The passes read the alpha of the draw's texture, so
    /// with a `map_Kd` the mask becomes the alpha of a copy of it (the mask sampled at the
    /// nearest texel where the sizes differ), and without one a copy of the mask whose alpha
    /// holds the value (the material keeps its constant `Kd`).
    fn merge_alpha_map(&mut self, mask: usize, albedo: Option<usize>) -> AlphaMap {
        let Some(mask_data) = self.textures.get(mask) else {
            return AlphaMap {
                texture: mask,
                mode: AlphaMode::Cutout(0.5),
            };
        };
        let has_alpha = mask_data.rgba8.chunks_exact(4).any(|p| p[3] < 255);
        let channel = if has_alpha { 3 } else { 0 };
        let (mw, mh) = (mask_data.width.max(1), mask_data.height.max(1));
        let value = |x: u32, y: u32| {
            mask_data
                .rgba8
                .get(((y.min(mh - 1) * mw + x.min(mw - 1)) * 4 + channel) as usize)
                .copied()
                .unwrap_or(255)
        };
        let base = albedo
            .and_then(|a| self.textures.get(a))
            .unwrap_or(mask_data);
        let (w, h) = (base.width.max(1), base.height.max(1));
        let mut rgba8 = base.rgba8.clone();
        for (i, p) in rgba8.chunks_exact_mut(4).enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            // Nearest texel of the mask at the same texture coordinates (texel centres).
            let mx = ((u64::from(x) * 2 + 1) * u64::from(mw) / (2 * u64::from(w))) as u32;
            let my = ((u64::from(y) * 2 + 1) * u64::from(mh) / (2 * u64::from(h))) as u32;
            p[3] = value(mx, my);
        }
        let mut path = base.path.clone().into_os_string();
        path.push(format!("+map_d:{}", mask_data.path.display()));
        let merged = TextureData::new(path.into(), base.width, base.height, rgba8, base.srgb);
        let texture = self.textures.len();
        self.textures.push(merged);
        AlphaMap {
            texture,
            mode: AlphaMode::Cutout(0.5),
        }
    }

    /// Loads a texture once. A missing file is an error when `required` (the MTL PBR maps),
    /// else a warning that gives `None` (the material's color is used instead, as common OBJ
    /// downloads name textures by paths on their author's machine); a file that exists but
    /// cannot be decoded is always an error.
    pub fn texture(
        &mut self,
        path: &Path,
        srgb: bool,
        referenced_by: &str,
        required: bool,
    ) -> Result<Option<usize>, SceneError> {
        let missing = || SceneError::TextureMissing {
            file: path.to_path_buf(),
            referenced_by: referenced_by.to_string(),
        };
        let key = (path.to_path_buf(), srgb);
        if let Some(&i) = self.textures_by_path.get(&key) {
            return if i.is_none() && required {
                Err(missing())
            } else {
                Ok(i)
            };
        }
        if required && !path.is_file() {
            return Err(missing());
        }
        if !path.is_file() {
            log::warn!(
                "{}: texture not found (referenced by {referenced_by}); using the material's \
                 color instead. Fix the path in the MTL file (relative to the OBJ's directory).",
                path.display()
            );
            self.textures_by_path.insert(key, None);
            return Ok(None);
        }
        let decode_error = |message: String| SceneError::TextureDecode {
            file: path.to_path_buf(),
            message,
            referenced_by: referenced_by.to_string(),
        };
        check_texture_size(path).map_err(decode_error)?;
        // The format comes from the file's first bytes, not its extension: real scenes ship
        // `.JPG`, `.jpeg` and textures whose extension lies.
        let img = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| decode_error(e.to_string()))?
            .decode()
            .map_err(|e| decode_error(e.to_string()))?;
        let rgba = img.to_rgba8();
        let i = self.textures.len();
        let (width, height) = rgba.dimensions();
        self.textures.push(TextureData::new(
            path.to_path_buf(),
            width,
            height,
            rgba.into_raw(),
            srgb,
        ));
        self.textures_by_path.insert(key, Some(i));
        Ok(Some(i))
    }
}

/// The largest texture side voxgi uploads: the `maxImageDimension2D` every Vulkan 1.3 desktop
/// driver offers (lavapipe's included).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Reads only the header of a texture file and refuses an empty image or one larger than
/// [`MAX_TEXTURE_SIDE`], before decoding allocates its texels.
fn check_texture_size(path: &Path) -> Result<(), String> {
    let (w, h) = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| e.to_string())?
        .into_dimensions()
        .map_err(|e| e.to_string())?;
    check_texture_side(w, h)
}

/// Decodes an image held in memory (a glTF image embedded in a buffer or a `data:` URI) to
/// RGBA8, refusing the sizes [`check_texture_size`] refuses before decoding; the message says
/// what is wrong.
pub(crate) fn decode_image_bytes(bytes: &[u8]) -> Result<image::RgbaImage, String> {
    let reader = || {
        image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    check_texture_side(w, h)?;
    Ok(reader()?.decode().map_err(|e| e.to_string())?.to_rgba8())
}

/// Decodes an image file to RGBA8 as [`AssetStore::texture`] does (size checked first, the
/// format from the file's first bytes).
pub(crate) fn decode_image_file(path: &Path) -> Result<image::RgbaImage, String> {
    check_texture_size(path)?;
    Ok(image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| e.to_string())?
        .to_rgba8())
}

fn check_texture_side(w: u32, h: u32) -> Result<(), String> {
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!(
            "the image is {w}×{h} texels; expected 1 to {MAX_TEXTURE_SIDE} texels per side \
             (downscale it, e.g. to 4096×4096)"
        ));
    }
    Ok(())
}

/// The first texel of `t` whose channels differ (x, y and its RGB), `None` for a grey texture.
fn first_coloured_texel(t: &TextureData) -> Option<(u32, u32, [u8; 3])> {
    t.rgba8
        .chunks_exact(4)
        .position(|c| c[0] != c[1] || c[0] != c[2])
        .map(|p| {
            (
                p as u32 % t.width,
                p as u32 / t.width,
                [0, 1, 2].map(|k| t.rgba8[4 * p + k]),
            )
        })
}

/// Warns about a Phong material (`field` names it) with `Ks` but exponent 0.
///
/// Normalized Phong at n = 0 is (n + 2)/(2π) cos⁰ = Ks/π toward every direction: a white
/// diffuse layer on top of Kd, not a highlight. OBJ exports write `Ks` without `Ns` (the brass
/// of Bitterli's staircase: `Kd 0`, `Ks 1`), so say what it renders as.
fn warn_flat_phong(field: &str, specular: Vec3, shininess: f32, has_ns: bool) {
    if specular.max_element() > 0.0 && shininess == 0.0 {
        log::warn!(
            "{}: Ks {} {} {} with {}: a Phong lobe of exponent 0 reflects Ks/π in every \
             direction, a white diffuse layer rather than a highlight; give the material \
             `Ns` (a highlight's exponent, e.g. 10 to 1000) or remove `Ks`",
            field,
            specular.x,
            specular.y,
            specular.z,
            if has_ns { "Ns 0" } else { "no Ns" }
        );
    }
}

/// What an OBJ file and its MTL libraries hold.
struct ObjContents {
    models: Vec<tobj::Model>,
    materials: Vec<tobj::Material>,
    /// The MTL file defining each material, by name, for messages naming the MTL file.
    mtl_files: HashMap<String, PathBuf>,
}

/// A parsed OBJ's models and its MTL materials. A missing MTL file is a warning (its materials
/// fall back to the default); a malformed one, or a malformed OBJ, is an error.
fn load_obj_models(path: &Path, dir: &Path, text: &str) -> Result<ObjContents, SceneError> {
    // MTL problems found by tobj's callback: (path, missing?, message).
    let mtl_problems: RefCell<Vec<(PathBuf, bool, String)>> = RefCell::new(Vec::new());
    let mtl_files: RefCell<HashMap<String, PathBuf>> = RefCell::new(HashMap::new());
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let loaded = guarded(|| {
        tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &options, |mtl| {
            load_mtl_library(path, dir, mtl, &mtl_problems, &mtl_files)
        })
    })
    .unwrap_or(Err(tobj::LoadError::GenericFailure));
    let (models, materials) = loaded.map_err(|e| SceneError::MalformedObj {
        file: path.to_path_buf(),
        kind: "OBJ",
        line: None,
        message: e.to_string(),
    })?;
    for (mtl_path, missing, message) in mtl_problems.into_inner() {
        if missing {
            log::warn!(
                "{}: material library {} not found; its materials fall back to the \
                 default gray (0.5). Put the MTL next to the OBJ or remove the `mtllib` line.",
                path.display(),
                mtl_path.display()
            );
        } else {
            let kind = if mtl_path == path { "OBJ" } else { "MTL" };
            return Err(SceneError::MalformedObj {
                file: mtl_path,
                kind,
                line: None,
                message,
            });
        }
    }
    // tobj reports MTL errors here too; ours were already handled above.
    let materials = materials.unwrap_or_default();
    Ok(ObjContents {
        models,
        materials,
        mtl_files: mtl_files.into_inner(),
    })
}

/// tobj's MTL callback for the OBJ at `obj` (in `dir`): reads the library `mtl`, recording
/// its problems in `problems` (path, missing?, message) and the file of each material it
/// defines in `files`. A library that cannot be used is empty, so faces using its materials
/// get the default material.
fn load_mtl_library(
    obj: &Path,
    dir: &Path,
    mtl: &Path,
    problems: &RefCell<Vec<(PathBuf, bool, String)>>,
    files: &RefCell<HashMap<String, PathBuf>>,
) -> tobj::MTLLoadResult {
    let mtl_path = dir.join(mtl);
    match std::fs::read_to_string(&mtl_path) {
        Ok(mtl_text) => {
            if let Err((line, message)) = prescan_mtl(&mtl_text, &mtl_path) {
                problems.borrow_mut().push((
                    mtl_path.clone(),
                    false,
                    format!("line {line}: {message}"),
                ));
                return Ok((Vec::new(), Default::default()));
            }
            for name in mtl_material_names(&mtl_text) {
                files.borrow_mut().insert(name, mtl_path.clone());
            }
            let r = guarded(|| tobj::load_mtl_buf(&mut Cursor::new(mtl_text.as_bytes())))
                .unwrap_or(Err(tobj::LoadError::GenericFailure));
            if let Err(e) = &r {
                problems
                    .borrow_mut()
                    .push((mtl_path.clone(), false, e.to_string()));
            }
            r
        }
        Err(_) if mtl_path.is_dir() => {
            // `mtllib` with no name (or a folder's): say so on the OBJ's side, not as a
            // malformed MTL "Is a directory" (found by fuzz_tests).
            problems.borrow_mut().push((
                obj.to_path_buf(),
                false,
                format!(
                    "`mtllib {}` names the folder {}, not an MTL file; name the .mtl file or \
                     remove the line",
                    mtl.display(),
                    mtl_path.display()
                ),
            ));
            Ok((Vec::new(), Default::default()))
        }
        Err(e) => {
            let missing = e.kind() == std::io::ErrorKind::NotFound;
            problems
                .borrow_mut()
                .push((mtl_path.clone(), missing, e.to_string()));
            Ok((Vec::new(), Default::default()))
        }
    }
}

/// Appends one tobj model to `mesh` as a submesh of `material`, with the file's normals (the
/// area-weighted ones where a normal is zero or missing; a triangle wound against its normals
/// is rewound, [`super::mesh::orient_to_normals`]), and its texture coordinates to `uvs` when some model of the file has them (zeros for a
/// model without).
fn append_model(mesh: &mut Mesh, uvs: Option<&mut Vec<Vec2>>, m: &tobj::Mesh, material: usize) {
    let n = m.positions.len() / 3;
    let base = mesh.positions.len();
    let positions: Vec<Vec3> = m
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let computed = area_weighted_normals(&positions, &m.indices);
    let normals: Vec<Vec3> = if m.normals.len() == 3 * n {
        m.normals
            .chunks_exact(3)
            .zip(&computed)
            .map(|(v, c)| {
                // A zero-length normal in the file falls back to the computed one.
                let u = Vec3::new(v[0], v[1], v[2]).normalize_or_zero();
                if u == Vec3::ZERO {
                    *c
                } else {
                    u
                }
            })
            .collect()
    } else {
        computed
    };
    if let Some(uvs) = uvs {
        if m.texcoords.len() == 2 * n {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        } else {
            uvs.resize(uvs.len() + n, Vec2::ZERO);
        }
    }
    // The file's normals are the front; a winding that disagrees is rewound to them.
    let mut indices = m.indices.clone();
    let rewound = super::mesh::orient_to_normals(&positions, &normals, &mut indices);
    if rewound > 0 {
        log::debug!(
            "{}: {rewound} triangles rewound to face their vertex normals",
            mesh.name
        );
    }
    let first_index = mesh.indices.len() as u32;
    mesh.indices
        .extend(indices.iter().map(|&i| i + base as u32));
    mesh.positions.extend(positions);
    mesh.normals.extend(normals);
    mesh.submeshes.push(SubMesh {
        first_index,
        index_count: m.indices.len() as u32,
        material,
    });
}

/// `m` with its vertices split and normals set by `smoothing` ([`split_normals`]).
fn split_model(m: &tobj::Mesh, smoothing: Smoothing<'_>) -> tobj::Mesh {
    let positions: Vec<Vec3> = m
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let s = split_normals(&positions, &m.indices, smoothing);
    let gather = |data: &[f32], k: usize| -> Vec<f32> {
        if data.len() != k * positions.len() {
            return Vec::new();
        }
        s.source
            .iter()
            .flat_map(|&v| data[k * v as usize..k * (v as usize + 1)].iter().copied())
            .collect()
    };
    tobj::Mesh {
        positions: gather(&m.positions, 3),
        texcoords: gather(&m.texcoords, 2),
        normals: s.normals.iter().flat_map(|n| n.to_array()).collect(),
        indices: s.indices,
        material_id: m.material_id,
        ..Default::default()
    }
}

/// Runs a tobj call, turning a panic inside tobj (it unwraps in a few places on malformed
/// input) into `None` so a bad file cannot crash the renderer.
fn guarded<T>(f: impl FnOnce() -> T) -> Option<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok()
}

/// Checks the MTL statements tobj would panic on or report without a line, and the numbers
/// voxgi reads (`mtl` names the file in warnings). Returns (line, message) of the first error.
///
/// - `Ka`, `Kd`, `Ks`, `Ke` need three numbers, `Ns`, `d`, `Tr`, `Ni`, `Pr`, `Pm` one; a
///   non-finite number (`nan`, `inf`) there or in `Tf` is an error naming the line and the key.
/// - Out-of-range numbers that an exporter plausibly wrote (`Kd 1.02`, `Ks 2`, `d 1.5`,
///   `Ns -1`) are clamped with a warning naming the file, line and key: MTL files come from
///   other tools, and the rest of such a file is usually fine. (A scene file is written for
///   voxgi, so there the same values are errors.) `Kd`, `Ks`, `d`, `Tr` clamp to [0, 1],
///   `Ns` to >= 0.
/// - Emission (`Ke`) must not be negative, and `Pr` and `Pm` must lie in [0, 1]: errors, as
///   these keys are new enough that a wrong value is a mistake in the file at hand.
fn prescan_mtl(text: &str, mtl: &Path) -> Result<(), (usize, String)> {
    for (i, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("");
        let mut toks = l.split_whitespace();
        let Some(kw) = toks.next() else { continue };
        let nums: Vec<&str> = toks.collect();
        let parsed: Vec<Option<f32>> = nums.iter().map(|t| t.parse::<f32>().ok()).collect();
        let non_finite = |n: usize| parsed.iter().take(n).flatten().any(|v| !v.is_finite());
        let warn_clamp = |range: &str| {
            log::warn!(
                "{}:{}: `{}`: {kw} outside {range}; clamped to {range}",
                mtl.display(),
                i + 1,
                raw.trim()
            )
        };
        if kw == "Tf" && non_finite(3) {
            // Transmission filter: not used, but never a NaN.
            return Err((
                i + 1,
                format!("`{}`: Tf has a non-finite number", raw.trim()),
            ));
        } else if matches!(kw, "Ka" | "Kd" | "Ks" | "Ke") {
            if nums.len() < 3 || parsed.iter().take(3).any(Option::is_none) {
                return Err((
                    i + 1,
                    format!("`{}`: expected `{kw} r g b` with three numbers", raw.trim()),
                ));
            }
            if non_finite(3) {
                return Err((
                    i + 1,
                    format!(
                        "`{}`: {kw} has a non-finite number; expected three finite numbers",
                        raw.trim()
                    ),
                ));
            }
            let v = parsed.iter().take(3).flatten();
            if kw == "Ke" && v.clone().any(|&v| v < 0.0) {
                return Err((
                    i + 1,
                    format!(
                        "`{}`: Ke is emitted radiance in W/(m²·sr); expected three finite \
                         numbers >= 0",
                        raw.trim()
                    ),
                ));
            }
            if matches!(kw, "Kd" | "Ks") && v.clone().any(|&v| !(0.0..=1.0).contains(&v)) {
                warn_clamp("[0, 1]");
            }
        } else if matches!(kw, "Ns" | "d" | "Tr" | "Ni" | "Pr" | "Pm") {
            let v = match parsed.as_slice() {
                [Some(v)] if v.is_finite() => Some(*v),
                _ => None,
            };
            if matches!(kw, "Pr" | "Pm") && !v.is_some_and(|v| (0.0..=1.0).contains(&v)) {
                let what = if kw == "Pr" { "roughness" } else { "metalness" };
                return Err((
                    i + 1,
                    format!(
                        "`{}`: {kw} is the GGX {what}; expected one number in [0, 1]",
                        raw.trim()
                    ),
                ));
            }
            let Some(v) = v else {
                return Err((
                    i + 1,
                    format!("`{}`: expected `{kw}` and one finite number", raw.trim()),
                ));
            };
            if matches!(kw, "d" | "Tr") && !(0.0..=1.0).contains(&v) {
                warn_clamp("[0, 1]");
            }
            if kw == "Ns" && v < 0.0 {
                warn_clamp("[0, ∞)");
            }
        }
    }
    Ok(())
}

/// The file name in an MTL map statement, skipping options such as `-bm 0.5`.
/// The `-bm X` option of a bump-map statement (1 when absent or not a finite number).
fn bump_multiplier(s: Option<&str>) -> f32 {
    let Some(s) = s else { return 1.0 };
    let mut words = s.split_whitespace();
    while let Some(w) = words.next() {
        if w == "-bm" {
            return words
                .next()
                .and_then(|v| v.parse::<f32>().ok())
                .filter(|v| v.is_finite())
                .unwrap_or(1.0);
        }
    }
    1.0
}

/// Whether `path` names a Wavefront OBJ file (by its extension, any case): `voxgi render x.obj`
/// loads it as a scene of its own instead of reading it as TOML.
pub fn is_obj_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

fn texture_file(s: Option<&str>) -> Option<String> {
    let s = s?.trim();
    if s.is_empty() {
        return None;
    }
    let name = if s.starts_with('-') {
        s.split_whitespace().last()?
    } else {
        s
    };
    Some(name.replace('\\', "/"))
}

/// The names of the materials an MTL file defines (its `newmtl` lines, trimmed as tobj does).
fn mtl_material_names(mtl_text: &str) -> impl Iterator<Item = String> + '_ {
    mtl_text.lines().filter_map(|line| {
        let rest = line.trim_start().strip_prefix("newmtl")?;
        (rest.is_empty() || rest.starts_with(char::is_whitespace)).then(|| rest.trim().to_owned())
    })
}

/// Reads a whole file; a missing file becomes [`SceneError::NotFound`].
pub(crate) fn read_bytes(
    path: &Path,
    what: &'static str,
    referenced_by: Option<&str>,
) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|e| read_error(e, path, what, referenced_by))
}

fn read_error(
    e: std::io::Error,
    path: &Path,
    what: &'static str,
    referenced_by: Option<&str>,
) -> SceneError {
    if e.kind() == std::io::ErrorKind::NotFound {
        SceneError::NotFound {
            file: path.to_path_buf(),
            what,
            referenced_by: referenced_by.map(str::to_string),
        }
    } else {
        SceneError::Io {
            file: path.to_path_buf(),
            what,
            source: e,
        }
    }
}

/// Reads a whole text file; a missing file becomes [`SceneError::NotFound`].
pub(crate) fn read_text(
    path: &Path,
    what: &'static str,
    referenced_by: Option<&str>,
) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|e| read_error(e, path, what, referenced_by))
}

/// Checks what tobj does not report with a line number: unparsable or non-finite numbers in
/// `v`/`vt`/`vn` lines, and face indices out of range.
fn prescan_obj(path: &Path, text: &str) -> Result<(), SceneError> {
    let keyword = |l: &str| l.split_whitespace().next().map(str::to_string);
    let mut totals = [0usize; 3];
    for l in text.lines() {
        match keyword(l).as_deref() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let malformed = |line: usize, message: String| SceneError::MalformedObj {
        file: path.to_path_buf(),
        kind: "OBJ",
        line: Some(line),
        message,
    };
    let mut counts = [0usize; 3];
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let l = raw.split('#').next().unwrap_or("");
        let mut toks = l.split_whitespace();
        let Some(kw) = toks.next() else { continue };
        let (slot, min, element) = match kw {
            "v" => (0, 3, "vertex position"),
            "vt" => (1, 1, "texture coordinate"),
            "vn" => (2, 3, "vertex normal"),
            "f" => {
                let verts: Vec<&str> = toks.collect();
                if verts.len() < 3 {
                    return Err(malformed(
                        line_no,
                        format!("face with {} vertices; expected at least 3", verts.len()),
                    ));
                }
                for v in verts {
                    if v.split('/').count() > 3 {
                        return Err(malformed(
                            line_no,
                            format!("bad face vertex `{v}`; expected v, v/vt, v//vn or v/vt/vn"),
                        ));
                    }
                    for (k, part) in v.split('/').enumerate() {
                        if part.is_empty() {
                            // `v//vn` leaves the texture coordinate out.
                            if k == 0 {
                                return Err(malformed(line_no, format!("bad face vertex `{v}`")));
                            }
                            continue;
                        }
                        let idx: i64 = part.parse().map_err(|_| {
                            malformed(line_no, format!("bad face index `{part}` in `{v}`"))
                        })?;
                        let element = ["vertex", "texture coordinate", "normal"][k];
                        let resolved = if idx > 0 {
                            (idx as u64 <= totals[k] as u64).then_some(())
                        } else if idx < 0 {
                            (idx.unsigned_abs() <= counts[k] as u64).then_some(())
                        } else {
                            None
                        };
                        if resolved.is_none() {
                            return Err(SceneError::FaceIndexOutOfRange {
                                file: path.to_path_buf(),
                                line: line_no,
                                element,
                                index: idx,
                                count: if idx < 0 { counts[k] } else { totals[k] },
                            });
                        }
                    }
                }
                continue;
            }
            _ => continue,
        };
        let mut n = 0;
        let mut w = 1.0;
        for t in toks {
            let x: f32 = t.parse().map_err(|_| {
                malformed(
                    line_no,
                    format!("`{t}` is not a number in a `{kw}` line (`{}`)", raw.trim()),
                )
            })?;
            if !x.is_finite() {
                return Err(SceneError::NonFiniteVertex {
                    file: path.to_path_buf(),
                    line: line_no,
                    element,
                });
            }
            n += 1;
            if n == 4 {
                w = x;
            }
        }
        // `v x y z w`: tobj divides by w (with colors, `v x y z r g b`, there is no w).
        if kw == "v" && n == 4 && w == 0.0 {
            return Err(malformed(line_no, "vertex with w = 0".to_string()));
        }
        if n < min {
            return Err(malformed(
                line_no,
                format!("`{kw}` line with {n} numbers; expected at least {min}"),
            ));
        }
        counts[slot] += 1;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prescan_reports_lines() {
        let p = Path::new("x.obj");
        let ok = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 -1//-1\n";
        assert!(prescan_obj(p, ok).is_ok());
        let e = prescan_obj(p, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
        assert!(
            matches!(e, Err(SceneError::NonFiniteVertex { line: 3, .. })),
            "{e:?}"
        );
        let e = prescan_obj(p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
        assert!(
            matches!(
                e,
                Err(SceneError::FaceIndexOutOfRange {
                    line: 4,
                    index: 4,
                    count: 3,
                    ..
                })
            ),
            "{e:?}"
        );
        let e = prescan_obj(p, "v 0 0 0\nf 1 -2 1\n");
        assert!(matches!(
            e,
            Err(SceneError::FaceIndexOutOfRange { line: 2, .. })
        ));
        let e = prescan_obj(p, "v 0 0\n");
        assert!(matches!(
            e,
            Err(SceneError::MalformedObj { line: Some(1), .. })
        ));
        let e = prescan_obj(p, "v 0 0 1e39\n");
        assert!(matches!(e, Err(SceneError::NonFiniteVertex { .. })));
    }

    #[test]
    fn bump_multiplier_is_read_from_the_options() {
        assert_eq!(bump_multiplier(Some("-bm 0.5 a.png")), 0.5);
        assert_eq!(bump_multiplier(Some("a.png")), 1.0);
        assert_eq!(bump_multiplier(Some("-bm nan a.png")), 1.0);
        assert_eq!(bump_multiplier(None), 1.0);
    }

    #[test]
    fn texture_file_skips_options() {
        assert_eq!(
            texture_file(Some("-bm 0.5 a\\b.png")),
            Some("a/b.png".into())
        );
        assert_eq!(texture_file(Some("  ")), None);
        assert_eq!(texture_file(Some("tex.png")), Some("tex.png".into()));
    }
}
