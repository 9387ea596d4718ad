//! Export of a [`Scene`] to a Mitsuba 3 scene (XML plus PLY meshes), so that reference images
//! can be rendered from exactly the geometry, materials, lights and camera voxgi draws
//! (`tools/reference` renders the result; `assets/references/README.md` lists the settings).
//!
//! What is written to `out_dir`:
//! - `scene.xml`: camera, lights, materials and one `ply` shape per (object, submesh) pair,
//!   because a Mitsuba shape carries one BSDF while a voxgi object has one material per
//!   submesh. The file declares `<default>`s for `spp`, `max_depth` and `seed`, which
//!   `mitsuba -D spp=…` or `mi.load_file(path, spp=…)` override.
//! - `meshes/*.ply`: binary little-endian PLY in **world space** at the requested time (the
//!   XML needs no shape transforms), with vertex normals and, where the mesh has them, uvs.
//! - `textures/*`: albedo maps used by exported materials.
//!
//! Conventions, checked against Mitsuba 3 (`src/sensors/perspective.cpp`,
//! `src/emitters/spot.cpp`, `src/core/transform.cpp`):
//! - Camera: `perspective` with `fov_axis = "y"` and voxgi's vertical FOV, placed with
//!   `lookat(position, position + forward, up)`. Mitsuba's look-at puts camera +x at
//!   `cross(up, forward)`, which its sensor maps to the image's *left*; voxgi's right-handed
//!   view does the same, so images are not mirrored (the Cornell box's red wall at x = 0.55 m
//!   is on the left in both).
//! - Orthographic camera: `orthographic` (`src/sensors/orthographic.cpp`, its
//!   `orthographic_projection` in `include/mitsuba/render/sensor.h`), whose local window is
//!   x ∈ [−1, 1], y ∈ [−1/aspect, 1/aspect] (aspect = width / height) on the near plane, so
//!   `to_world` scales x and y by s = ortho height × aspect / 2 (width 2s = height × aspect,
//!   height 2s / aspect = ortho height) before the same look-at; z stays 1 so that the clip
//!   distances stay meters.
//! - Film: `hdrfilm` with a `box` reconstruction filter, so a pixel is the average radiance
//!   over its area, like a supersampled rasterizer.
//! - Lights: `point` `intensity` (W/sr), `spot` `intensity` (on-axis W/sr) with
//!   `cutoff_angle` / `beam_width` in degrees (falloff linear in angle, as
//!   [`crate::scene::spot_falloff`]), `directional` `irradiance` (W/m²).
//! - Materials: every BSDF is wrapped in `twosided`, since voxgi shades by the vertex normal
//!   and Mitsuba's one-sided BSDFs would turn back faces black. Lambert is `diffuse`.
//!   Mitsuba 3 has no Phong BSDF: a material with a specular lobe becomes a `blendbsdf` of
//!   `diffuse` and a Beckmann `roughconductor` (perfect reflector, F = 1), which is an
//!   approximation and is reported in [`ExportReport::warnings`].
//! - Environment: `constant` with `radiance`, or `envmap` with the decoded map written as
//!   `textures/environment.exr` (linear RGB, exactly the texels voxgi samples), its `scale`,
//!   and `to_world` a rotation about +Y by `rotation_deg`; voxgi's equirectangular mapping is
//!   Mitsuba's (`crate::scene::environment`). A sky is `sunsky` with the same `turbidity`,
//!   `albedo`, `sky_scale` and `sun_direction`, `sun_scale` 0 (the sun is the directional
//!   light, exported as above) and `to_world` a −90° turn about +X (its +Z up to voxgi's +Y);
//!   Mitsuba evaluates the model itself, so the reference does not see voxgi's bake.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec2, Vec3};

use crate::imaging::srgb_decode;
use crate::scene::{AlphaMap, AlphaMode, Environment, Light, Material, Mesh, Scene, TextureData};

/// Samples per pixel written as the XML's `spp` default. The sampler is `independent`, which
/// takes any count as given (Mitsuba's stratified samplers round it to a grid) and whose
/// renders with different seeds are independent estimates, so their difference measures noise.
pub const DEFAULT_SPP: u32 = 256;
/// Path depth written as the XML's `max_depth` default: Mitsuba counts the camera ray as the
/// first segment, so 2 is direct light only; 64 is full GI for all practical purposes (Russian
/// roulette ends nearly every path long before).
pub const DEFAULT_MAX_DEPTH: u32 = 64;

/// What [`export_mitsuba`] wrote, and what it could not represent exactly.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExportReport {
    /// The scene file, `out_dir/scene.xml`.
    pub xml_path: PathBuf,
    /// Every mesh and texture file written, in the order the XML references them.
    pub files: Vec<PathBuf>,
    /// Number of `<shape>` entries (one per non-empty object submesh).
    pub shape_count: usize,
    /// Triangles written over all meshes.
    pub triangle_count: usize,
    /// Approximations and omissions, one sentence each (empty when the export is exact).
    pub warnings: Vec<String>,
}

/// Errors of [`export_mitsuba`]. The scene was validated on load, so these are about the
/// output: sizes and the file system.
#[derive(Debug, thiserror::Error)]
pub enum MitsubaExportError {
    #[error(
        "cannot export a {width}x{height} image for Mitsuba: width and height must both be at \
         least 1 pixel"
    )]
    EmptyImage { width: u32, height: u32 },

    #[error("could not write {} for the Mitsuba export: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    #[error("could not encode texture {} for the Mitsuba export: {source}", path.display())]
    Texture {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
}

/// Writes `out_dir/scene.xml` and its meshes and textures for `scene` at `time_s`, rendering
/// a `width` x `height` image. Existing files of the same names are overwritten; other files in
/// `out_dir` are left alone.
pub fn export_mitsuba(
    scene: &Scene,
    time_s: f32,
    width: u32,
    height: u32,
    out_dir: &Path,
) -> Result<ExportReport, MitsubaExportError> {
    if width == 0 || height == 0 {
        return Err(MitsubaExportError::EmptyImage { width, height });
    }
    create_dir(out_dir)?;
    let mut report = ExportReport {
        xml_path: out_dir.join("scene.xml"),
        ..ExportReport::default()
    };

    let mut xml = String::new();
    xml.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let source = match &scene.source {
        Some(p) => p.display().to_string(),
        None => "a built-in scene".to_owned(),
    };
    let _ = writeln!(
        xml,
        "<!-- Exported by voxgi from {} at t = {time_s} s. Meters, linear RGB; meshes are in \
         world space. Override the defaults with mitsuba -D spp=N, or \
         mi.load_file(path, spp=N, max_depth=D, seed=S). -->",
        comment_text(&source)
    );
    xml.push_str("<scene version=\"3.0.0\">\n");
    if scene.origin_m != glam::DVec3::ZERO {
        // Mitsuba computes in f32 too: the export keeps voxgi's local coordinates, which
        // stay precise, and says where they are.
        let o = scene.origin_m;
        let _ = writeln!(
            xml,
            "    <!-- Local coordinates: voxgi moved this scene's origin to world \
             ({}, {}, {}) m (a floating origin); add it for world positions. -->",
            o.x, o.y, o.z
        );
    }
    let _ = writeln!(xml, "    <default name=\"spp\" value=\"{DEFAULT_SPP}\"/>");
    let _ = writeln!(
        xml,
        "    <default name=\"max_depth\" value=\"{DEFAULT_MAX_DEPTH}\"/>"
    );
    xml.push_str("    <default name=\"seed\" value=\"0\"/>\n\n");
    xml.push_str(
        "    <!-- max_depth counts path segments from the camera: 2 = direct light only. -->\n",
    );
    // A `mask` (opacity below 1, an alpha map) must pass the light of delta emitters (spot,
    // point, directional) through its open part, as voxgi's shadow maps do. Mitsuba's `path`
    // traces its shadow rays with an occlusion test that stops at any surface, so a cutout
    // under a sun would cast a solid shadow; `volpath` evaluates null-BSDF transmission along
    // shadow rays and does not count passing through a mask as a bounce (without media it is
    // otherwise the same path tracer). Scenes without masks keep `path`.
    let integrator = if scene.has_transparency() || scene.has_alpha_maps() {
        "volpath"
    } else {
        "path"
    };
    let _ = writeln!(xml, "    <integrator type=\"{integrator}\">");
    xml.push_str("        <integer name=\"max_depth\" value=\"$max_depth\"/>\n");
    xml.push_str("    </integrator>\n\n");

    write_sensor(&mut xml, scene, width, height);
    write_lights(&mut xml, scene, &mut report);
    write_environment(&mut xml, scene, out_dir, &mut report)?;
    write_materials_and_shapes(&mut xml, scene, time_s, out_dir, &mut report)?;
    xml.push_str("</scene>\n");

    write_file(&report.xml_path, xml.as_bytes())?;
    Ok(report)
}

fn write_sensor(xml: &mut String, scene: &Scene, width: u32, height: u32) {
    let cam = &scene.camera;
    let target = cam.position + cam.forward;
    let scale = if cam.is_orthographic() {
        // The window's half width (see the module's conventions).
        let s = cam.ortho_height_m * width as f32 / height.max(1) as f32 * 0.5;
        xml.push_str("    <sensor type=\"orthographic\">\n");
        let _ = writeln!(
            xml,
            "        <!-- a view {} m high and {} m wide: Mitsuba's 2 × 2/aspect window scaled by {s} -->",
            cam.ortho_height_m,
            2.0 * s
        );
        format!("<scale x=\"{s}\" y=\"{s}\" z=\"1\"/>\n            ")
    } else {
        xml.push_str("    <sensor type=\"perspective\">\n");
        xml.push_str("        <string name=\"fov_axis\" value=\"y\"/>\n");
        let _ = writeln!(
            xml,
            "        <float name=\"fov\" value=\"{}\"/>",
            cam.fov_y_deg
        );
        String::new()
    };
    let _ = writeln!(
        xml,
        "        <float name=\"near_clip\" value=\"{}\"/>",
        cam.near
    );
    let _ = writeln!(
        xml,
        "        <float name=\"far_clip\" value=\"{}\"/>",
        cam.far
    );
    let _ = writeln!(
        xml,
        "        <transform name=\"to_world\">\n            {scale}<lookat origin=\"{}\" \
         target=\"{}\" up=\"{}\"/>\n        </transform>",
        vec3(cam.position),
        vec3(target),
        vec3(cam.up)
    );
    xml.push_str("        <sampler type=\"independent\">\n");
    xml.push_str("            <integer name=\"sample_count\" value=\"$spp\"/>\n");
    xml.push_str("            <integer name=\"seed\" value=\"$seed\"/>\n");
    xml.push_str("        </sampler>\n");
    xml.push_str("        <film type=\"hdrfilm\">\n");
    let _ = writeln!(
        xml,
        "            <integer name=\"width\" value=\"{width}\"/>"
    );
    let _ = writeln!(
        xml,
        "            <integer name=\"height\" value=\"{height}\"/>"
    );
    xml.push_str("            <string name=\"pixel_format\" value=\"rgb\"/>\n");
    xml.push_str("            <string name=\"component_format\" value=\"float32\"/>\n");
    xml.push_str("            <rfilter type=\"box\"/>\n");
    xml.push_str("        </film>\n");
    xml.push_str("    </sensor>\n\n");
}

fn write_lights(xml: &mut String, scene: &Scene, report: &mut ExportReport) {
    if scene.lights.is_empty() && !scene.has_emission() && scene.environment.is_none() {
        report.warnings.push(
            "the scene has no lights and no emitters: the Mitsuba image will be black".to_owned(),
        );
    }
    for light in &scene.lights {
        match *light {
            Light::Point {
                position,
                intensity_w_sr,
            } => {
                xml.push_str("    <emitter type=\"point\">\n");
                let _ = writeln!(
                    xml,
                    "        <point name=\"position\" value=\"{}\"/>",
                    vec3(position)
                );
                let _ = writeln!(
                    xml,
                    "        <rgb name=\"intensity\" value=\"{}\"/>",
                    vec3(intensity_w_sr)
                );
                xml.push_str("    </emitter>\n\n");
            }
            Light::Spot {
                position,
                direction,
                intensity_w_sr,
                cutoff_deg,
                beam_deg,
            } => {
                // The cone is symmetric about its axis, so any up that is not parallel works.
                let up = if direction.y.abs() > 0.9 {
                    Vec3::Z
                } else {
                    Vec3::Y
                };
                xml.push_str("    <emitter type=\"spot\">\n");
                let _ = writeln!(
                    xml,
                    "        <rgb name=\"intensity\" value=\"{}\"/>",
                    vec3(intensity_w_sr)
                );
                let _ = writeln!(
                    xml,
                    "        <float name=\"cutoff_angle\" value=\"{cutoff_deg}\"/>"
                );
                let _ = writeln!(
                    xml,
                    "        <float name=\"beam_width\" value=\"{beam_deg}\"/>"
                );
                let _ = writeln!(
                    xml,
                    "        <transform name=\"to_world\">\n            <lookat origin=\"{}\" \
                     target=\"{}\" up=\"{}\"/>\n        </transform>",
                    vec3(position),
                    vec3(position + direction),
                    vec3(up)
                );
                xml.push_str("    </emitter>\n\n");
            }
            Light::Directional {
                direction,
                irradiance_w_m2,
            } => {
                xml.push_str("    <emitter type=\"directional\">\n");
                let _ = writeln!(
                    xml,
                    "        <vector name=\"direction\" value=\"{}\"/>",
                    vec3(direction)
                );
                let _ = writeln!(
                    xml,
                    "        <rgb name=\"irradiance\" value=\"{}\"/>",
                    vec3(irradiance_w_m2)
                );
                xml.push_str("    </emitter>\n\n");
            }
            Light::Sphere {
                position,
                radius_m,
                radiance_w_sr_m2,
                ..
            } => {
                xml.push_str("    <shape type=\"sphere\">\n");
                let _ = writeln!(
                    xml,
                    "        <point name=\"center\" value=\"{}\"/>\n        <float \
                     name=\"radius\" value=\"{radius_m}\"/>",
                    vec3(position)
                );
                write_area_emitter(xml, radiance_w_sr_m2);
            }
            Light::Rectangle {
                position,
                normal,
                width_axis,
                width_m,
                height_m,
                radiance_w_sr_m2,
                ..
            } => {
                // Mitsuba's rectangle spans [-1, 1]² in z = 0 and emits along +z: the columns
                // of to_world are the half edges and the normal, then the centre.
                let cols = [
                    width_axis * (0.5 * width_m),
                    normal.cross(width_axis) * (0.5 * height_m),
                    normal,
                    position,
                ];
                let rows: Vec<String> = (0..3)
                    .map(|r| {
                        let row: Vec<String> = cols.iter().map(|c| c[r].to_string()).collect();
                        row.join(" ")
                    })
                    .collect();
                xml.push_str("    <shape type=\"rectangle\">\n");
                let _ = writeln!(
                    xml,
                    "        <transform name=\"to_world\">\n            <matrix value=\"{} \
                     0 0 0 1\"/>\n        </transform>",
                    rows.join(" ")
                );
                write_area_emitter(xml, radiance_w_sr_m2);
            }
            Light::Element { .. } => report.warnings.push(
                "an area-light sample has no Mitsuba equivalent and was left out; export the \
                 area light itself"
                    .to_owned(),
            ),
        }
    }
}

/// The end of an area light's shape: its emitter, and a black BSDF, since voxgi's lights are
/// not surfaces that reflect light.
fn write_area_emitter(xml: &mut String, radiance: Vec3) {
    let _ = writeln!(
        xml,
        "        <emitter type=\"area\">\n            <rgb name=\"radiance\" value=\"{}\"/>\n        \
         </emitter>\n        <bsdf type=\"diffuse\">\n            <rgb name=\"reflectance\" \
         value=\"0, 0, 0\"/>\n        </bsdf>\n    </shape>\n",
        vec3(radiance)
    );
}

/// One world-space mesh piece: the vertices and triangles of one object submesh.
struct Piece {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<Vec2>>,
    indices: Vec<u32>,
}

fn write_materials_and_shapes(
    xml: &mut String,
    scene: &Scene,
    time_s: f32,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<(), MitsubaExportError> {
    let mesh_dir = out_dir.join("meshes");
    create_dir(&mesh_dir)?;
    // Materials are written once, on first use, so the XML holds only drawn ones.
    let mut written = vec![false; scene.materials.len()];
    let mut warned_phong = false;

    for (oi, object) in scene.objects.iter().enumerate() {
        let Some(mesh) = scene.meshes.get(object.mesh_at(time_s)) else {
            report.warnings.push(format!(
                "object `{}` names a missing mesh and was skipped",
                object.name
            ));
            continue;
        };
        let model = object.transform_at(time_s);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material_index = object.materials.get(si).copied().unwrap_or(sub.material);
            let Some(material) = scene.materials.get(material_index) else {
                report.warnings.push(format!(
                    "object `{}` submesh {si} names a missing material and was skipped",
                    object.name
                ));
                continue;
            };
            let piece = world_piece(mesh, sub.first_index, sub.index_count, model);
            if piece.indices.is_empty() {
                continue;
            }
            let material_id = format!("mat{material_index}");
            if let Some(seen) = written.get_mut(material_index) {
                if !*seen {
                    *seen = true;
                    write_material(
                        xml,
                        scene,
                        material,
                        &material_id,
                        out_dir,
                        report,
                        &mut warned_phong,
                    )?;
                }
            }

            let stem = format!("{oi:02}_{}_{si}", file_safe(&object.name));
            let rel = format!("meshes/{stem}.ply");
            let path = out_dir.join(&rel);
            let comment = format!(
                "voxgi object {} submesh {si}, world space at t = {time_s} s",
                file_safe(&object.name)
            );
            write_file(&path, &ply_bytes(&piece, &comment))?;
            report.files.push(path);
            report.shape_count += 1;
            report.triangle_count += piece.indices.len() / 3;

            // Emission leaves the side the normals point to, as voxgi's G-buffer shows it.
            let emitter = if material.is_emissive() {
                format!(
                    "        <emitter type=\"area\">\n            {}\n        </emitter>\n",
                    radiance_xml(scene, material, out_dir, report)?
                )
            } else {
                String::new()
            };
            let _ = writeln!(
                xml,
                "    <shape type=\"ply\" id=\"{stem}\">\n        <string name=\"filename\" \
                 value=\"{rel}\"/>\n        <ref id=\"{material_id}\"/>\n{emitter}    </shape>\n"
            );
        }
    }
    Ok(())
}

/// The triangles `[first, first + count)` of `mesh` with only the vertices they use,
/// transformed by `model` (normals by its inverse transpose).
fn world_piece(mesh: &Mesh, first: u32, count: u32, model: glam::Mat4) -> Piece {
    let normal_matrix = Mat3::from_mat4(model).inverse().transpose();
    // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners so
    // the winding still agrees with the normals.
    let mirrored = Mat3::from_mat4(model).determinant() < 0.0;
    let range = (first as usize)..(first as usize).saturating_add(count as usize);
    let source = mesh.indices.get(range).unwrap_or(&[]);

    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut piece = Piece {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: mesh.uvs.as_ref().map(|_| Vec::new()),
        indices: Vec::with_capacity(source.len()),
    };
    for tri in source.chunks_exact(3) {
        let corners = if mirrored {
            [tri[0], tri[2], tri[1]]
        } else {
            [tri[0], tri[1], tri[2]]
        };
        // Indices were validated on load; a stray one drops its triangle rather than panic.
        if corners
            .iter()
            .any(|&i| mesh.positions.get(i as usize).is_none())
        {
            continue;
        }
        for i in corners {
            let slot = &mut remap[i as usize];
            if *slot == u32::MAX {
                *slot = piece.positions.len() as u32;
                let p = mesh.positions[i as usize];
                piece.positions.push(model.transform_point3(p));
                let n = mesh.normals.get(i as usize).copied().unwrap_or(Vec3::Y);
                let n = (normal_matrix * n).normalize_or_zero();
                piece
                    .normals
                    .push(if n == Vec3::ZERO { Vec3::Y } else { n });
                if let (Some(out), Some(uvs)) = (piece.uvs.as_mut(), mesh.uvs.as_ref()) {
                    let uv = uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO);
                    // voxgi keeps OBJ's v-up convention; Mitsuba's bitmap lookup has v = 0 at
                    // the top row (its own OBJ loader flips v the same way).
                    out.push(Vec2::new(uv.x, 1.0 - uv.y));
                }
            }
            piece.indices.push(*slot);
        }
    }
    piece
}

/// Binary little-endian PLY with float x y z nx ny nz [u v] and int triangle indices.
fn ply_bytes(piece: &Piece, comment: &str) -> Vec<u8> {
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    let _ = writeln!(header, "comment {comment}");
    let _ = writeln!(header, "element vertex {}", piece.positions.len());
    for name in ["x", "y", "z", "nx", "ny", "nz"] {
        let _ = writeln!(header, "property float {name}");
    }
    if piece.uvs.is_some() {
        header.push_str("property float u\nproperty float v\n");
    }
    let _ = writeln!(header, "element face {}", piece.indices.len() / 3);
    header.push_str("property list uchar int vertex_indices\nend_header\n");

    let floats_per_vertex = if piece.uvs.is_some() { 8 } else { 6 };
    let mut out = Vec::with_capacity(
        header.len() + piece.positions.len() * floats_per_vertex * 4 + piece.indices.len() / 3 * 13,
    );
    out.extend_from_slice(header.as_bytes());
    for (i, (p, n)) in piece.positions.iter().zip(&piece.normals).enumerate() {
        for v in p.to_array().into_iter().chain(n.to_array()) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        if let Some(uv) = piece.uvs.as_ref().and_then(|uvs| uvs.get(i)) {
            out.extend_from_slice(&uv.x.to_le_bytes());
            out.extend_from_slice(&uv.y.to_le_bytes());
        }
    }
    for tri in piece.indices.chunks_exact(3) {
        out.push(3);
        for &i in tri {
            // Vertex counts of voxgi meshes are far below i32::MAX.
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    out
}

/// Beckmann roughness matching a normalized Phong lobe cosⁿα about the mirror direction: the
/// half vector turns by about half the angle, so the lobe is Blinn-Phong with exponent ≈ 4n,
/// and Blinn-Phong n' corresponds to Beckmann α = sqrt(2 / (n' + 2)) (Walter et al.,
/// "Microfacet models for refraction through rough surfaces", EGSR 2007, section 5.2).
pub fn phong_to_beckmann_alpha(shininess: f32) -> f32 {
    (2.0 / (4.0 * shininess.max(0.0) + 2.0)).sqrt()
}

/// Writes `material` as the BSDF `id`. A material of opacity below 1 (MTL `d`) is a `mask`
/// around it: Mitsuba's mask passes a ray straight through with probability 1 − opacity, the
/// expectation of voxgi's hashed coverage in the G-buffer, the shadow maps and the voxels. A
/// material with an alpha map is a `mask` whose opacity is a bitmap ([`alpha_texture_xml`]).
fn write_material(
    xml: &mut String,
    scene: &Scene,
    material: &Material,
    id: &str,
    out_dir: &Path,
    report: &mut ExportReport,
    warned_phong: &mut bool,
) -> Result<(), MitsubaExportError> {
    if material.is_opaque() && material.alpha_map.is_none() {
        return write_opaque_material(xml, scene, material, id, out_dir, report, warned_phong);
    }
    let mut inner = String::new();
    write_opaque_material(
        &mut inner,
        scene,
        material,
        &format!("{id}_opaque"),
        out_dir,
        report,
        warned_phong,
    )?;
    let map = material
        .alpha_map
        .and_then(|a| scene.textures.get(a.texture).map(|data| (a, data)));
    let opacity = match map {
        Some((a, data)) => alpha_texture_xml(data, a, material.opacity, out_dir, report)?,
        None => format!("<float name=\"opacity\" value=\"{}\"/>", material.opacity),
    };
    let _ = writeln!(
        xml,
        "    <bsdf type=\"mask\" id=\"{id}\">\n        {opacity}"
    );
    for line in inner.trim_end().lines() {
        let _ = writeln!(xml, "    {line}");
    }
    let _ = writeln!(xml, "    </bsdf>\n");
    Ok(())
}

fn write_opaque_material(
    xml: &mut String,
    scene: &Scene,
    material: &Material,
    id: &str,
    out_dir: &Path,
    report: &mut ExportReport,
    warned_phong: &mut bool,
) -> Result<(), MitsubaExportError> {
    if material.bump_texture.is_some() {
        report.warnings.push(format!(
            "material `{}` has a bump or normal map, which is not exported",
            material.name
        ));
    }
    let texture = material
        .albedo_texture
        .and_then(|t| scene.textures.get(t).map(|data| (t, data)));

    let _ = writeln!(xml, "    <!-- {} -->", comment_text(&material.name));
    let _ = writeln!(xml, "    <bsdf type=\"twosided\" id=\"{id}\">");
    if let Some(ggx) = material.ggx {
        write_ggx(xml, scene, material, ggx, texture, out_dir, report)?;
    } else if material.is_lambert() {
        let reflectance = albedo_xml(
            texture,
            "reflectance",
            material.albedo,
            1.0,
            out_dir,
            report,
        )?;
        let _ = writeln!(
            xml,
            "        <bsdf type=\"diffuse\">\n            {reflectance}\n        </bsdf>"
        );
    } else {
        if !*warned_phong {
            *warned_phong = true;
            report.warnings.push(
                "Mitsuba 3 has no Phong BSDF: Phong materials are exported as a blendbsdf of \
                 diffuse and a Beckmann roughconductor (F = 1, alpha = sqrt(2 / (4n + 2))), \
                 which matches the lobe's width and albedo only approximately"
                    .to_owned(),
            );
        }
        // blendbsdf computes (1 - w)·diffuse + w·specular, so each part is scaled up by the
        // inverse of its weight; with ρ + ρs <= 1 neither scaled reflectance exceeds 1.
        let diffuse_max = match texture {
            Some(_) => 1.0,
            None => material.albedo.max_element(),
        };
        let specular_max = material.specular.max_element();
        let specular_bsdf = |reflectance: Vec3| {
            [
                "<bsdf type=\"roughconductor\">".to_owned(),
                "    <string name=\"distribution\" value=\"beckmann\"/>".to_owned(),
                format!(
                    "    <float name=\"alpha\" value=\"{}\"/>",
                    phong_to_beckmann_alpha(material.shininess)
                ),
                "    <string name=\"material\" value=\"none\"/>".to_owned(),
                format!(
                    "    <rgb name=\"specular_reflectance\" value=\"{}\"/>",
                    vec3(reflectance)
                ),
                "</bsdf>".to_owned(),
            ]
        };
        if diffuse_max <= 0.0 {
            // No diffuse part (an MTL metal: `Kd 0 0 0`, `Ks 1 1 1`): the lobe alone. A blend
            // would weigh the diffuse by 1 − w = 0 and scale it by 1 / 0, writing NaN.
            let _ = writeln!(
                xml,
                "        <!-- normalized Phong, specular {}, shininess {}, no diffuse part -->",
                vec3(material.specular),
                material.shininess
            );
            for line in specular_bsdf(material.specular) {
                let _ = writeln!(xml, "        {line}");
            }
            let _ = writeln!(xml, "    </bsdf>\n");
            return Ok(());
        }
        let weight = specular_max / (diffuse_max + specular_max);
        let diffuse_scale = 1.0 / (1.0 - weight);
        let reflectance = albedo_xml(
            texture,
            "reflectance",
            material.albedo,
            diffuse_scale,
            out_dir,
            report,
        )?;
        let _ = writeln!(
            xml,
            "        <!-- normalized Phong, specular {}, shininess {} -->",
            vec3(material.specular),
            material.shininess
        );
        let _ = writeln!(xml, "        <bsdf type=\"blendbsdf\">");
        let _ = writeln!(
            xml,
            "            <float name=\"weight\" value=\"{weight}\"/>"
        );
        let _ = writeln!(
            xml,
            "            <bsdf type=\"diffuse\">\n                {reflectance}\n            </bsdf>"
        );
        for line in specular_bsdf(material.specular / weight) {
            let _ = writeln!(xml, "            {line}");
        }
        let _ = writeln!(xml, "        </bsdf>");
    }
    let _ = writeln!(xml, "    </bsdf>\n");
    Ok(())
}

/// A GGX metal/roughness material as Mitsuba 3's `principled` BSDF (α = roughness², GGX with
/// the exact separable Smith G, Schlick Fresnel on the base color for its metallic part). A pure
/// metal (metallic 1) is exact: `principled` then has only that specular lobe. Below 1 the
/// match is approximate (`principled`'s diffuse part is Disney's with retro-reflection, and its
/// dielectric Fresnel is exact rather than Schlick), which the report says.
fn write_ggx(
    xml: &mut String,
    scene: &Scene,
    material: &Material,
    ggx: crate::scene::Ggx,
    texture: Option<(usize, &crate::scene::TextureData)>,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<(), MitsubaExportError> {
    // With a `map_Pm` the mean is below 1 exactly when some texel is not fully metal.
    let metallic = material
        .voxel_ggx(&scene.textures)
        .map_or(ggx.metallic, |g| g.metallic);
    if metallic < 1.0 {
        report.warnings.push(format!(
            "material `{}` is a GGX dielectric (metallic {metallic}{}): exported as Mitsuba's \
             principled BSDF, whose diffuse lobe (Disney, with retro-reflection) and exact \
             dielectric Fresnel match voxgi's Fresnel-weighted Lambert and Schlick only \
             approximately",
            material.name,
            if material.pbr_maps.metallic.is_some() {
                ", the mean of its map"
            } else {
                ""
            }
        ));
    }
    let base = albedo_xml(texture, "base_color", material.albedo, 1.0, out_dir, report)?;
    let _ = writeln!(
        xml,
        "        <!-- GGX metal/roughness, alpha = roughness^2 = {} -->",
        ggx.roughness * ggx.roughness
    );
    let _ = writeln!(xml, "        <bsdf type=\"principled\">");
    let _ = writeln!(xml, "            {base}");
    // `map_Pr` / `map_Pm` replace the constants per texel, as in the G-buffer.
    for (name, map, constant) in [
        ("roughness", material.pbr_maps.roughness, ggx.roughness),
        ("metallic", material.pbr_maps.metallic, ggx.metallic),
    ] {
        let param = match map.and_then(|t| scene.textures.get(t).map(|data| (t, data))) {
            Some((t, data)) => scalar_texture_xml(data, t, name, out_dir, report)?,
            None => format!("<float name=\"{name}\" value=\"{constant}\"/>"),
        };
        let _ = writeln!(xml, "            {param}");
    }
    // specular 0.5 is η = 1.5, F0 = 0.04, the dielectric F0 of voxgi's metal/roughness model.
    let _ = writeln!(xml, "            <float name=\"specular\" value=\"0.5\"/>");
    let _ = writeln!(xml, "        </bsdf>");
    Ok(())
}

/// An area emitter's `radiance`: `Ke`, or with `map_Ke` a bitmap of the map's linear color
/// times `Ke` (Mitsuba's area emitter takes a texture for its radiance).
fn radiance_xml(
    scene: &Scene,
    material: &Material,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<String, MitsubaExportError> {
    let map = material.pbr_maps.emission;
    Ok(
        match map.and_then(|t| scene.textures.get(t).map(|data| (t, data))) {
            Some((t, data)) => {
                texture_xml(data, t, "radiance", material.emission, out_dir, report)?
            }
            None => format!(
                "<rgb name=\"radiance\" value=\"{}\"/>",
                vec3(material.emission)
            ),
        },
    )
}

/// Writes the opacity of an alpha map as an 8-bit grey PNG and returns the `opacity` bitmap
/// that reads it raw. A cutout is baked to `opacity` where the texel's alpha passes the cutoff
/// and 0 elsewhere, read with nearest filtering: voxgi thresholds the bilinear alpha, and
/// between two texels on either side of the cutoff the threshold falls near their shared
/// edge (exactly there for alphas symmetric about it, such as a 0/255 checker at 0.5), where
/// the nearest lookup switches. A blend map is `opacity` × alpha, read bilinearly as voxgi
/// does.
fn alpha_texture_xml(
    data: &TextureData,
    map: AlphaMap,
    opacity: f32,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<String, MitsubaExportError> {
    create_dir(&out_dir.join("textures"))?;
    let pixels = (data.width as usize) * (data.height as usize);
    let rgba = data.rgba8.get(..pixels * 4).unwrap_or(&[]);
    let to_u8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let (values, rel, filter): (Vec<u8>, String, &str) = match map.mode {
        AlphaMode::Cutout(c) => (
            rgba.chunks_exact(4)
                .map(|p| {
                    to_u8(if f32::from(p[3]) / 255.0 >= c {
                        opacity
                    } else {
                        0.0
                    })
                })
                .collect(),
            format!("textures/tex{}_cutout{c}_x{opacity}.png", map.texture),
            "nearest",
        ),
        AlphaMode::Blend => (
            rgba.chunks_exact(4)
                .map(|p| to_u8(opacity * f32::from(p[3]) / 255.0))
                .collect(),
            format!("textures/tex{}_alpha_x{opacity}.png", map.texture),
            "bilinear",
        ),
    };
    let path = out_dir.join(&rel);
    match image::GrayImage::from_raw(data.width, data.height, values)
        .map(|img| img.save_with_format(&path, image::ImageFormat::Png))
    {
        Some(Ok(())) => {}
        Some(Err(source)) => return Err(MitsubaExportError::Texture { path, source }),
        None => {
            report.warnings.push(format!(
                "texture {} has fewer bytes than its size says; opacity {opacity} is used \
                 instead of its alpha",
                data.path.display()
            ));
            return Ok(format!("<float name=\"opacity\" value=\"{opacity}\"/>"));
        }
    }
    report.files.push(path);
    Ok(format!(
        "<texture type=\"bitmap\" name=\"opacity\">\n            <string \
         name=\"filename\" value=\"{rel}\"/>\n            <boolean name=\"raw\" \
         value=\"true\"/>\n            <string name=\"filter_type\" value=\"{filter}\"/>\n        \
         </texture>"
    ))
}

/// Writes the first channel of the linear (data) map `index` as an 8-bit grey PNG and returns
/// the `<texture>` element named `name` that reads it raw (no sRGB decoding), so Mitsuba sees
/// the same values in [0, 1] that the G-buffer samples.
fn scalar_texture_xml(
    data: &TextureData,
    index: usize,
    name: &str,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<String, MitsubaExportError> {
    create_dir(&out_dir.join("textures"))?;
    let pixels = (data.width as usize) * (data.height as usize);
    let rgba = data.rgba8.get(..pixels * 4).unwrap_or(&[]);
    let first: Vec<u8> = rgba.chunks_exact(4).map(|p| p[0]).collect();
    let rel = format!("textures/tex{index}_r.png");
    let path = out_dir.join(&rel);
    match image::GrayImage::from_raw(data.width, data.height, first)
        .map(|img| img.save_with_format(&path, image::ImageFormat::Png))
    {
        Some(Ok(())) => {}
        Some(Err(source)) => return Err(MitsubaExportError::Texture { path, source }),
        None => {
            report.warnings.push(format!(
                "texture {} has fewer bytes than its size says; {name} 1 is used instead",
                data.path.display()
            ));
            return Ok(format!("<float name=\"{name}\" value=\"1\"/>"));
        }
    }
    report.files.push(path);
    Ok(format!(
        "<texture type=\"bitmap\" name=\"{name}\">\n                <string \
         name=\"filename\" value=\"{rel}\"/>\n                <boolean name=\"raw\" \
         value=\"true\"/>\n            </texture>"
    ))
}

/// A BSDF's colour parameter `name`: the albedo `texture` (index and data) where the material
/// has one, else the constant `albedo`, either times `scale`.
fn albedo_xml(
    texture: Option<(usize, &TextureData)>,
    name: &str,
    albedo: Vec3,
    scale: f32,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<String, MitsubaExportError> {
    match texture {
        Some((t, data)) => texture_xml(data, t, name, Vec3::splat(scale), out_dir, report),
        None => Ok(format!(
            "<rgb name=\"{name}\" value=\"{}\"/>",
            vec3(albedo * scale)
        )),
    }
}

/// Writes texture `index` and returns the `<texture>` element named `name` that reads it.
/// Unscaled color maps are copied as sRGB PNG (Mitsuba linearizes 8-bit files); scaled or
/// linear ones are linearized, scaled per channel and written as float EXR, since a PNG cannot
/// hold values above 1.
fn texture_xml(
    data: &TextureData,
    index: usize,
    name: &str,
    scale: Vec3,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<String, MitsubaExportError> {
    create_dir(&out_dir.join("textures"))?;
    let pixels = (data.width as usize) * (data.height as usize);
    let rgba = data.rgba8.get(..pixels * 4).unwrap_or(&[]);
    let rgb = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]);
    let decode = |c: u8| {
        let v = f32::from(c) / 255.0;
        if data.srgb {
            srgb_decode(v)
        } else {
            v
        }
    };
    let (rel, result) = if scale == Vec3::ONE && data.srgb {
        let rel = format!("textures/tex{index}.png");
        let path = out_dir.join(&rel);
        let result = image::RgbImage::from_raw(data.width, data.height, rgb.collect())
            .map(|img| img.save_with_format(&path, image::ImageFormat::Png));
        (rel, result)
    } else {
        let rel = if scale.x == scale.y && scale.y == scale.z {
            format!("textures/tex{index}_x{}.exr", scale.x)
        } else {
            format!(
                "textures/tex{index}_x{}_{}_{}.exr",
                scale.x, scale.y, scale.z
            )
        };
        let path = out_dir.join(&rel);
        let linear: Vec<f32> = rgb
            .enumerate()
            .map(|(i, c)| decode(c) * scale[i % 3])
            .collect();
        let result = image::Rgb32FImage::from_raw(data.width, data.height, linear)
            .map(|img| img.save_with_format(&path, image::ImageFormat::OpenExr));
        (rel, result)
    };
    let path = out_dir.join(&rel);
    match result {
        Some(Ok(())) => {}
        Some(Err(source)) => return Err(MitsubaExportError::Texture { path, source }),
        None => {
            report.warnings.push(format!(
                "texture {} has fewer bytes than its size says; the material's color is \
                 used instead",
                data.path.display()
            ));
            return Ok(format!("<rgb name=\"{name}\" value=\"0.5, 0.5, 0.5\"/>"));
        }
    }
    report.files.push(path);
    Ok(format!(
        "<texture type=\"bitmap\" name=\"{name}\">\n                <string \
         name=\"filename\" value=\"{rel}\"/>\n            </texture>"
    ))
}

fn vec3(v: Vec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

/// A name reduced to `[A-Za-z0-9_-]`, usable in file names and XML ids.
fn file_safe(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "object".to_owned()
    } else {
        s
    }
}

/// Text safe inside an XML comment (which must not contain `--`).
fn comment_text(s: &str) -> String {
    s.replace("--", "- -")
}

/// The `[environment]` table as Mitsuba's `constant`, `envmap` or `sunsky` emitter.
fn write_environment(
    xml: &mut String,
    scene: &Scene,
    out_dir: &Path,
    report: &mut ExportReport,
) -> Result<(), MitsubaExportError> {
    match &scene.environment {
        None => {}
        Some(Environment::Constant { radiance }) => {
            let _ = writeln!(
                xml,
                "    <emitter type=\"constant\">\n        <rgb name=\"radiance\" value=\"{}\"/>\n    \
                 </emitter>\n",
                vec3(*radiance)
            );
        }
        Some(Environment::Sky { sky, .. }) => {
            // The sky's +Z up turned to +Y: rotate(x, −90°) takes (0, 0, 1) to (0, 1, 0). The
            // sun direction is given in world space (Mitsuba turns it by the inverse).
            let _ = writeln!(
                xml,
                "    <!-- voxgi's [environment] sky: Hosek-Wilkie without the sun's disk; the sun \
                 is the directional light -->\n    <emitter type=\"sunsky\">\n        \
                 <vector name=\"sun_direction\" value=\"{}\"/>\n        \
                 <float name=\"turbidity\" value=\"{}\"/>\n        \
                 <rgb name=\"albedo\" value=\"{}\"/>\n        \
                 <float name=\"sun_scale\" value=\"0\"/>\n        \
                 <float name=\"sky_scale\" value=\"{}\"/>\n        \
                 <transform name=\"to_world\">\n            <rotate x=\"1\" angle=\"-90\"/>\n        \
                 </transform>\n    </emitter>\n",
                vec3(sky.toward_sun),
                sky.turbidity,
                vec3(sky.ground_albedo),
                sky.scale
            );
        }
        Some(Environment::Map(m)) => {
            let dir = out_dir.join("textures");
            create_dir(&dir)?;
            let path = dir.join("environment.exr");
            let rgb: Vec<f32> = m
                .texels
                .chunks_exact(4)
                .flat_map(|t| [t[0], t[1], t[2]])
                .collect();
            image::Rgb32FImage::from_raw(m.width, m.height, rgb)
                .map(|img| img.save_with_format(&path, image::ImageFormat::OpenExr))
                .unwrap_or(Ok(()))
                .map_err(|source| MitsubaExportError::Texture {
                    path: path.clone(),
                    source,
                })?;
            report.files.push(path);
            let _ = writeln!(
                xml,
                "    <!-- voxgi's [environment] map {} -->\n    <emitter type=\"envmap\">\n        \
                 <string name=\"filename\" value=\"textures/environment.exr\"/>\n        \
                 <float name=\"scale\" value=\"{}\"/>\n        <transform name=\"to_world\">\n            \
                 <rotate y=\"1\" angle=\"{}\"/>\n        </transform>\n    </emitter>\n",
                comment_text(&m.path.display().to_string()),
                m.scale,
                m.rotation_deg
            );
        }
    }
    Ok(())
}

fn create_dir(path: &Path) -> Result<(), MitsubaExportError> {
    std::fs::create_dir_all(path).map_err(|source| MitsubaExportError::Io {
        path: path.to_owned(),
        source,
    })
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), MitsubaExportError> {
    std::fs::write(path, bytes).map_err(|source| MitsubaExportError::Io {
        path: path.to_owned(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::scene::builtin;

    /// A fresh directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(tag: &str) -> TempDir {
            static N: AtomicUsize = AtomicUsize::new(0);
            let n = N.fetch_add(1, Ordering::Relaxed);
            let dir = std::env::temp_dir()
                .join(format!("voxgi_mitsuba_{tag}_{}_{n}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            TempDir(dir)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// The numbers in attribute `attr` of the first element that starts with `element`.
    fn numbers(xml: &str, element: &str, attr: &str) -> Vec<f32> {
        let start = xml.find(element).unwrap_or_else(|| panic!("no {element}"));
        let rest = &xml[start..];
        let rest = &rest[..rest.find('>').unwrap()];
        let key = format!("{attr}=\"");
        let v = &rest[rest
            .find(&key)
            .unwrap_or_else(|| panic!("no {attr} in {rest}"))
            + key.len()..];
        let v = &v[..v.find('"').unwrap()];
        v.split(',').map(|s| s.trim().parse().unwrap()).collect()
    }

    /// [`numbers`] of every `element` in document order, concatenated.
    fn all_numbers(xml: &str, element: &str, attr: &str) -> Vec<f32> {
        xml.match_indices(element)
            .flat_map(|(i, _)| numbers(&xml[i..], element, attr))
            .collect()
    }

    fn close(a: &[f32], b: &[f32]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
    }

    /// Asserts that [`numbers`] of `element`'s `attr` are `want` (to 1e-5).
    #[track_caller]
    fn assert_numbers(xml: &str, element: &str, attr: &str, want: &[f32]) {
        let got = numbers(xml, element, attr);
        assert!(
            close(&got, want),
            "{element} {attr}: {got:?}, want {want:?}"
        );
    }

    /// Asserts that [`all_numbers`] of `element`'s `attr` are `want` (to 1e-5).
    #[track_caller]
    fn assert_all_numbers(xml: &str, element: &str, attr: &str, want: &[f32]) {
        let got = all_numbers(xml, element, attr);
        assert!(
            close(&got, want),
            "every {element} {attr}: {got:?}, want {want:?}"
        );
    }

    /// Parses a PLY written by [`ply_bytes`]: (vertex count, face count, world positions).
    fn read_ply(path: &Path) -> (usize, usize, Vec<Vec3>) {
        let bytes = std::fs::read(path).unwrap();
        let end = b"end_header\n";
        let split = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        let header = std::str::from_utf8(&bytes[..split]).unwrap();
        let count = |elem: &str| -> usize {
            let line = header
                .lines()
                .find(|l| l.starts_with(&format!("element {elem} ")))
                .unwrap();
            line.rsplit(' ').next().unwrap().parse().unwrap()
        };
        let (nv, nf) = (count("vertex"), count("face"));
        let floats = header
            .lines()
            .filter(|l| l.starts_with("property float"))
            .count();
        let body = &bytes[split..];
        assert_eq!(body.len(), nv * floats * 4 + nf * 13, "{}", path.display());
        let f = |k: usize| f32::from_le_bytes(body[k * 4..k * 4 + 4].try_into().unwrap());
        let positions = (0..nv)
            .map(|i| Vec3::new(f(i * floats), f(i * floats + 1), f(i * floats + 2)))
            .collect();
        (nv, nf, positions)
    }

    #[test]
    fn cornell_xml_has_camera_light_and_shapes() {
        let scene = builtin("cornell").unwrap();
        let dir = TempDir::new("cornell");
        let report = export_mitsuba(&scene, 0.0, 256, 192, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);

        // Camera: vertical FOV, look-at from the published position towards +z.
        assert!(xml.contains("<string name=\"fov_axis\" value=\"y\"/>"));
        assert_numbers(&xml, "<float name=\"fov\"", "value", &[39.3]);
        assert_numbers(&xml, "<float name=\"near_clip\"", "value", &[0.01]);
        assert_numbers(&xml, "<float name=\"far_clip\"", "value", &[10.0]);
        let cam = &xml[xml.find("<sensor").unwrap()..];
        assert_numbers(cam, "<lookat", "origin", &[0.278, 0.273, -0.8]);
        assert_numbers(cam, "<lookat", "target", &[0.278, 0.273, 0.2]);
        assert_numbers(cam, "<lookat", "up", &[0.0, 1.0, 0.0]);
        assert!(xml.contains("<integer name=\"width\" value=\"256\"/>"));
        assert!(xml.contains("<integer name=\"height\" value=\"192\"/>"));
        assert!(xml.contains("<rfilter type=\"box\"/>"));
        assert!(xml.contains("<default name=\"spp\""));
        assert!(xml.contains("value=\"$spp\"") && xml.contains("value=\"$max_depth\""));

        // The spot light: intensity, angles, and a look-at straight down.
        let spot = &xml[xml.find("<emitter type=\"spot\">").unwrap()..];
        assert_numbers(spot, "<rgb name=\"intensity\"", "value", &[1.0, 1.0, 1.0]);
        assert_numbers(spot, "<float name=\"cutoff_angle\"", "value", &[50.0]);
        assert_numbers(spot, "<float name=\"beam_width\"", "value", &[40.0]);
        assert_numbers(spot, "<lookat", "origin", &[0.278, 0.54, 0.2796]);
        assert_numbers(spot, "<lookat", "target", &[0.278, -0.46, 0.2796]);

        // One shape per object submesh, each referencing a BSDF defined before it.
        let expected_shapes: usize = scene
            .objects
            .iter()
            .map(|o| scene.meshes[o.mesh].submeshes.len())
            .sum();
        assert_eq!(report.shape_count, expected_shapes);
        assert_eq!(xml.matches("<shape type=\"ply\"").count(), expected_shapes);
        assert_eq!(report.triangle_count, scene.triangle_count_at(0.0));
        // Red (0.63, 0.065, 0.05) and green walls as diffuse reflectances.
        assert!(xml.contains("value=\"0.63, 0.065, 0.05\""));
        assert!(xml.contains("value=\"0.14, 0.45, 0.091\""));
        assert_eq!(xml.matches("<bsdf type=\"diffuse\">").count(), 3);
    }

    /// The orthographic sensor: Mitsuba's mapping of a world point to the film, written out
    /// from its sources (`lookat`: columns left = cross(up, d), up' = cross(d, left), d,
    /// origin; `orthographic_projection`: sample = (0.5 − x/2, 0.5 − aspect·y/2) of the local
    /// point after `to_world`'s scale), lands every point on the pixel voxgi's projection
    /// puts it on, at any depth.
    #[test]
    fn orthographic_sensor_matches_voxgis_projection() {
        let mut scene = builtin("cornell").unwrap();
        scene.camera.projection = crate::scene::Projection::Orthographic;
        scene.camera.ortho_height_m = 0.6;
        let (w, h) = (256u32, 192u32);
        let dir = TempDir::new("ortho");
        let report = export_mitsuba(&scene, 0.0, w, h, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        let cam = &xml[xml.find("<sensor").unwrap()..];
        assert!(cam.starts_with("<sensor type=\"orthographic\">"), "{cam}");
        assert!(!cam[..cam.find("</sensor>").unwrap()].contains("fov"));
        let scale = numbers(cam, "<scale", "x");
        assert_eq!(scale, numbers(cam, "<scale", "y"));
        assert_eq!(numbers(cam, "<scale", "z"), [1.0]);
        let s = scale[0];
        let v = |a: &str| Vec3::from_slice(&numbers(cam, "<lookat", a));
        let (origin, target, up) = (v("origin"), v("target"), v("up"));
        let d = (target - origin).normalize();
        let left = up.cross(d).normalize();
        let up2 = d.cross(left);
        let aspect = w as f32 / h as f32;
        let vp = scene.camera.view_proj(aspect);
        for p in [
            Vec3::new(0.278, 0.273, 0.0),
            Vec3::new(0.1, 0.5, 0.4),
            Vec3::new(0.5, 0.05, 2.0),
        ] {
            let (xc, yc) = ((p - origin).dot(left) / s, (p - origin).dot(up2) / s);
            let mitsuba = Vec2::new(
                (0.5 - 0.5 * xc) * w as f32,
                (0.5 - 0.5 * aspect * yc) * h as f32,
            );
            let ndc = vp.project_point3(p);
            let voxgi = Vec2::new(
                (ndc.x + 1.0) * 0.5 * w as f32,
                (ndc.y + 1.0) * 0.5 * h as f32,
            );
            assert!(
                (mitsuba - voxgi).length() < 1e-3,
                "{p}: {mitsuba} vs {voxgi}"
            );
        }
    }

    #[test]
    fn mesh_files_hold_every_vertex_and_triangle() {
        let scene = builtin("cornell").unwrap();
        let dir = TempDir::new("meshes");
        let report = export_mitsuba(&scene, 0.0, 64, 64, &dir.0).unwrap();
        assert_eq!(report.files.len(), report.shape_count);
        let mut triangles = 0;
        let mut shape = 0;
        for object in &scene.objects {
            let mesh = &scene.meshes[object.mesh];
            for sub in &mesh.submeshes {
                let (nv, nf, _) = read_ply(&report.files[shape]);
                let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
                let mut used: Vec<u32> = mesh.indices[range].to_vec();
                used.sort_unstable();
                used.dedup();
                assert_eq!(nf, sub.index_count as usize / 3);
                assert_eq!(nv, used.len());
                triangles += nf;
                shape += 1;
            }
        }
        assert_eq!(triangles, scene.triangle_count_at(0.0));
    }

    const CAMERA: &str = "[camera]\nposition = [0, 1, -3]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n";

    /// An MTL metal as OBJ exporters write it (`Kd 0 0 0`, `Ks 1 1 1`, no `Ns`, so shininess 0:
    /// the brass of Bitterli's staircase, the Modern Hall's chrome): no diffuse part, so the
    /// lobe alone. A blend would scale the empty diffuse part by 1 / (1 − w) = 1 / 0 and write
    /// NaN, which Mitsuba renders as NaN in every pixel.
    #[test]
    fn a_phong_material_without_diffuse_exports_the_lobe_alone_and_every_number_is_finite() {
        let text = format!(
            "{CAMERA}[[lights]]\nkind = \"directional\"\ndirection = [0, -1, 0]\n\
             irradiance_w_m2 = [2, 2, 2]\n[[objects]]\nbuiltin = \"sphere\"\n\
             material = {{ albedo = [0, 0, 0], specular = [1, 1, 1], shininess = 0.0 }}\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("phong_metal");
        let report = export_mitsuba(&scene, 0.0, 32, 32, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        assert!(!xml.contains("blendbsdf"), "{xml}");
        let ks = numbers(&xml, "<rgb name=\"specular_reflectance\"", "value");
        assert!(close(&ks, &[1.0, 1.0, 1.0]), "{ks:?}");
        // Every number the exporter wrote in a `value` attribute is finite.
        for part in xml.split("value=\"").skip(1) {
            let v = &part[..part.find('"').unwrap()];
            for n in v.split(',') {
                if let Ok(x) = n.trim().parse::<f64>() {
                    assert!(x.is_finite(), "non-finite {v} in the export");
                }
            }
        }
        assert!(!xml.to_lowercase().contains("nan"), "{xml}");
    }

    #[test]
    fn a_material_below_full_opacity_is_a_mask_around_its_bsdf() {
        let text = format!(
            "{CAMERA}[[lights]]\nkind = \"directional\"\ndirection = [0, -1, 0]\n\
             irradiance_w_m2 = [2, 2, 2]\n[[objects]]\nbuiltin = \"quad\"\n\
             material = {{ albedo = [0.5, 0.5, 0.5], opacity = 0.25 }}\n\
             [[objects]]\nbuiltin = \"cube\"\nmaterial = {{ albedo = [0.5, 0.5, 0.5] }}\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("mask");
        let report = export_mitsuba(&scene, 0.0, 32, 32, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        // One mask (the quad's), holding the opacity and the twosided diffuse BSDF.
        assert_eq!(xml.matches("<bsdf type=\"mask\"").count(), 1, "{xml}");
        let mask = &xml[xml.find("<bsdf type=\"mask\"").unwrap()..];
        let opacity = numbers(mask, "<float name=\"opacity\"", "value");
        assert!(close(&opacity, &[0.25]), "{opacity:?}");
        let inner = mask.find("<bsdf type=\"twosided\"").unwrap();
        assert!(inner < mask.find("</bsdf>\n\n").unwrap(), "{mask}");
        assert!(report.warnings.iter().all(|w| !w.contains("opaque")));
    }

    #[test]
    fn phong_material_is_approximated_with_a_warning() {
        let text = format!(
            "{CAMERA}[[lights]]\nkind = \"directional\"\ndirection = [0, -1, 0]\n\
             irradiance_w_m2 = [2, 2, 2]\n[[objects]]\nbuiltin = \"sphere\"\n\
             material = {{ albedo = [0.2, 0.3, 0.6], specular = [0.3, 0.3, 0.3], \
             shininess = 60.0 }}\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("phong");
        let report = export_mitsuba(&scene, 0.0, 32, 32, &dir.0).unwrap();
        assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
        assert!(report.warnings[0].contains("Phong"));
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        assert!(xml.contains("<bsdf type=\"blendbsdf\">"));
        // w = 0.3 / (0.6 + 0.3); the scaled parts give back ρ and ρs.
        let w = numbers(&xml, "<float name=\"weight\"", "value")[0];
        assert!((w - 1.0 / 3.0).abs() < 1e-6);
        let kd = numbers(&xml, "<rgb name=\"reflectance\"", "value");
        let ks = numbers(&xml, "<rgb name=\"specular_reflectance\"", "value");
        assert!(close(
            &kd.iter().map(|v| v * (1.0 - w)).collect::<Vec<_>>(),
            &[0.2, 0.3, 0.6]
        ));
        assert!(close(
            &ks.iter().map(|v| v * w).collect::<Vec<_>>(),
            &[0.3, 0.3, 0.3]
        ));
        let alpha = numbers(&xml, "<float name=\"alpha\"", "value")[0];
        assert!((alpha - phong_to_beckmann_alpha(60.0)).abs() < 1e-6);
        // Directional light with its irradiance.
        assert_numbers(
            &xml,
            "<vector name=\"direction\"",
            "value",
            &[0.0, -1.0, 0.0],
        );
        assert_numbers(&xml, "<rgb name=\"irradiance\"", "value", &[2.0, 2.0, 2.0]);
    }

    #[test]
    fn environments_are_exported_as_constant_and_envmap() {
        // A constant sky: Mitsuba's `constant` emitter with the radiance, and no warning about
        // a black image although there are no lights.
        let text = format!(
            "{CAMERA}[[objects]]\nbuiltin = \"quad\"\n\
             [environment]\nkind = \"constant\"\nradiance = [0.5, 1, 2]\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("constant-sky");
        let report = export_mitsuba(&scene, 0.0, 16, 16, &dir.0).unwrap();
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        let constant = &xml[xml.find("<emitter type=\"constant\">").unwrap()..];
        assert_numbers(
            constant,
            "<rgb name=\"radiance\"",
            "value",
            &[0.5, 1.0, 2.0],
        );

        // A map: its texels written as EXR beside the XML (read back equal), its scale and
        // its rotation about +Y.
        let maps = TempDir::new("sky-map");
        let texels: Vec<f32> = (0..8 * 4 * 3).map(|i| i as f32 * 0.25).collect();
        image::Rgb32FImage::from_raw(8, 4, texels.clone())
            .unwrap()
            .save_with_format(maps.0.join("sky.exr"), image::ImageFormat::OpenExr)
            .unwrap();
        let text = format!(
            "{CAMERA}[[objects]]\nbuiltin = \"quad\"\n\
             [environment]\nkind = \"map\"\nfile = \"sky.exr\"\nrotation_deg = 30\nscale = 1.5\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), &maps.0).unwrap();
        let dir = TempDir::new("map-sky");
        let report = export_mitsuba(&scene, 0.0, 16, 16, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        let envmap = &xml[xml.find("<emitter type=\"envmap\">").unwrap()..];
        assert!(envmap.contains("<string name=\"filename\" value=\"textures/environment.exr\"/>"));
        assert_numbers(envmap, "<float name=\"scale\"", "value", &[1.5]);
        assert_numbers(envmap, "<rotate y=\"1\"", "angle", &[30.0]);
        let written = image::open(dir.0.join("textures/environment.exr"))
            .unwrap()
            .into_rgb32f();
        assert_eq!(written.dimensions(), (8, 4));
        assert_eq!(written.into_raw(), texels);

        // A sky: `sunsky` with the model's parameters, the sun toward the directional light's
        // source (its direction reversed), no sun disk, and the directional light itself.
        let text = format!(
            "{CAMERA}[[objects]]\nbuiltin = \"quad\"\n\
             [[lights]]\nkind = \"directional\"\ndirection = [0, -1, -1]\nirradiance_w_m2 = 3\n\
             [environment]\nkind = \"sky\"\nturbidity = 4\nground_albedo = [0.1, 0.2, 0.3]\n\
             scale = 0.5\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("analytic-sky");
        let report = export_mitsuba(&scene, 0.0, 16, 16, &dir.0).unwrap();
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        let sunsky = &xml[xml.find("<emitter type=\"sunsky\">").unwrap()..];
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert_numbers(
            sunsky,
            "<vector name=\"sun_direction\"",
            "value",
            &[0.0, h, h],
        );
        assert_numbers(sunsky, "<float name=\"turbidity\"", "value", &[4.0]);
        assert_numbers(sunsky, "<rgb name=\"albedo\"", "value", &[0.1, 0.2, 0.3]);
        assert_numbers(sunsky, "<float name=\"sun_scale\"", "value", &[0.0]);
        assert_numbers(sunsky, "<float name=\"sky_scale\"", "value", &[0.5]);
        assert_numbers(sunsky, "<rotate x=\"1\"", "angle", &[-90.0]);
        assert!(xml.contains("<emitter type=\"directional\">"));
    }

    #[test]
    fn ggx_materials_and_emitters_are_exported() {
        // A copper metal sphere (exact as principled, no warning), a GGX dielectric cube
        // (approximate, one warning) and an emissive Lambert quad (an area emitter with the
        // same radiance); the Lambert quad stays diffuse.
        let text = format!(
            "{CAMERA}[[objects]]\nbuiltin = \"sphere\"\n\
             material = {{ albedo = [0.95, 0.64, 0.54], roughness = 0.3, metallic = 1.0 }}\n\
             [[objects]]\nbuiltin = \"cube\"\ntranslate = [2, 0, 0]\n\
             material = {{ albedo = 0.5, roughness = 0.8 }}\n\
             [[objects]]\nbuiltin = \"quad\"\ntranslate = [0, 2, 0]\n\
             material = {{ albedo = 0.7, emission_w_sr_m2 = [4, 3, 2] }}\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let dir = TempDir::new("ggx");
        let report = export_mitsuba(&scene, 0.0, 32, 32, &dir.0).unwrap();
        assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
        assert!(report.warnings[0].contains("GGX dielectric"));
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        assert_eq!(xml.matches("<bsdf type=\"principled\">").count(), 2);
        assert_all_numbers(
            &xml,
            "<rgb name=\"base_color\"",
            "value",
            &[0.95, 0.64, 0.54, 0.5, 0.5, 0.5],
        );
        assert_all_numbers(&xml, "<float name=\"roughness\"", "value", &[0.3, 0.8]);
        assert_all_numbers(&xml, "<float name=\"metallic\"", "value", &[1.0, 0.0]);
        assert_all_numbers(&xml, "<float name=\"specular\"", "value", &[0.5, 0.5]);
        assert_eq!(xml.matches("<bsdf type=\"diffuse\">").count(), 1);
        // One area emitter, inside the quad's shape, with the radiance.
        assert_eq!(xml.matches("<emitter type=\"area\">").count(), 1);
        let quad = &xml[xml.find("<shape type=\"ply\" id=\"02_").unwrap()..];
        let quad = &quad[..quad.find("</shape>").unwrap()];
        assert!(quad.contains("<emitter type=\"area\">"), "{quad}");
        assert_numbers(quad, "<rgb name=\"radiance\"", "value", &[4.0, 3.0, 2.0]);
    }

    /// The file name of the first `<string name="filename"` after `from` in `xml`.
    fn filename_after<'a>(xml: &'a str, from: &str) -> &'a str {
        let rest = &xml[xml.find(from).unwrap()..];
        let key = "name=\"filename\" value=\"";
        let rest = &rest[rest.find(key).unwrap() + key.len()..];
        &rest[..rest.find('"').unwrap()]
    }

    #[test]
    fn pbr_maps_are_exported_as_bitmaps() {
        // A GGX emitter whose roughness, metalness and emission come from maps: roughness and
        // metalness become raw (linear) grey bitmaps of the maps' first channel, the area
        // radiance a float bitmap of the decoded map times Ke.
        let text = format!(
            "{CAMERA}[[objects]]\nbuiltin = \"quad\"\n\
             material = {{ albedo = 0.5, roughness = 0.3, metallic = 1.0, \
             emission_w_sr_m2 = [2, 4, 6] }}\n"
        );
        let mut scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let texels = |a: [u8; 3], b: [u8; 3], srgb| {
            let rgba8 = [a, b]
                .iter()
                .flat_map(|c| [c[0], c[1], c[2], 255])
                .collect();
            TextureData::new("two".into(), 2, 1, rgba8, srgb)
        };
        scene.textures = vec![
            texels([10, 99, 99], [200, 0, 0], false),
            texels([255, 1, 2], [0, 3, 4], false),
            texels([255, 0, 128], [0, 255, 64], true),
        ];
        let m = scene.objects[0].materials[0];
        scene.materials[m].pbr_maps = crate::scene::PbrMaps {
            roughness: Some(0),
            metallic: Some(1),
            emission: Some(2),
        };
        let dir = TempDir::new("pbrmaps");
        let report = export_mitsuba(&scene, 0.0, 32, 32, &dir.0).unwrap();
        // The metalness map (texels 1 and 0, mean 0.5) is partly dielectric: approximate.
        assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
        assert!(report.warnings[0].contains("metallic 0.5, the mean of its map"));
        let xml = std::fs::read_to_string(&report.xml_path).unwrap();
        // The maps replace the constants.
        assert!(!xml.contains("<float name=\"roughness\""), "{xml}");
        assert!(!xml.contains("<float name=\"metallic\""), "{xml}");
        assert!(!xml.contains("<rgb name=\"radiance\""), "{xml}");
        for (name, first_channel) in [("roughness", [10u8, 200]), ("metallic", [255, 0])] {
            let element = format!("<texture type=\"bitmap\" name=\"{name}\">");
            let at = xml
                .find(&element)
                .unwrap_or_else(|| panic!("no {name} bitmap: {xml}"));
            let body = &xml[at..at + xml[at..].find("</texture>").unwrap()];
            assert!(
                body.contains("<boolean name=\"raw\" value=\"true\"/>"),
                "{body}"
            );
            let file = dir.0.join(filename_after(&xml, &element));
            let img = image::open(&file).unwrap().into_luma8();
            assert_eq!(img.into_raw(), first_channel, "{name}");
        }
        // The radiance bitmap sits in the quad's emitter; its texels are the decoded sRGB map
        // times Ke: srgb_decode(1) = 1, srgb_decode(0) = 0, srgb_decode(128/255) and
        // srgb_decode(64/255) by the sRGB transfer function.
        let shape = &xml[xml.find("<shape type=\"ply\"").unwrap()..];
        let shape = &shape[..shape.find("</shape>").unwrap()];
        let element = "<texture type=\"bitmap\" name=\"radiance\">";
        assert!(shape.contains(element), "{shape}");
        let file = dir.0.join(filename_after(shape, element));
        let exr = image::open(&file).unwrap().into_rgb32f().into_raw();
        let d = |c: f32| srgb_decode(c / 255.0);
        let want = [2.0, 0.0, 6.0 * d(128.0), 0.0, 4.0, 6.0 * d(64.0)];
        assert!(close(&exr, &want), "{exr:?}");
        assert!(report.files.contains(&file));
    }

    #[test]
    fn meshes_are_in_world_space_at_the_given_time() {
        let text = format!(
            "{CAMERA}[[lights]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity_w_sr = 2.0\n\
             [[objects]]\nbuiltin = \"cube\"\ntranslate = [1, 2, 3]\nscale = 0.5\n\
             [objects.animation]\nloop = false\nkeyframes = [\n\
             {{ time_s = 0.0, translate = [0, 0, 0] }},\n\
             {{ time_s = 2.0, translate = [2, 0, 0], scale = [1, 2, -1] }},\n]\n"
        );
        let scene = Scene::from_toml_str(&text, Path::new("<test>"), Path::new(".")).unwrap();
        let xml_point = |xml: &str| numbers(xml, "<point name=\"position\"", "value");
        for t in [0.0, 1.0, 2.0] {
            let dir = TempDir::new("world");
            let report = export_mitsuba(&scene, t, 16, 16, &dir.0).unwrap();
            let xml = std::fs::read_to_string(&report.xml_path).unwrap();
            assert!(close(&xml_point(&xml), &[0.0, 2.0, 0.0]));
            assert_numbers(&xml, "<rgb name=\"intensity\"", "value", &[2.0; 3]);
            let (nv, nf, positions) = read_ply(&report.files[0]);
            assert_eq!((nv, nf), (24, 12));
            let bounds = crate::scene::Aabb::from_points(&positions);
            let expected = scene.objects[0].aabb_at(t);
            assert!(
                (bounds.min - expected.min).length() < 1e-5
                    && (bounds.max - expected.max).length() < 1e-5,
                "t = {t}: {bounds:?} vs {expected:?}"
            );
        }
    }

    #[test]
    fn mirroring_transform_keeps_winding_consistent_with_normals() {
        let scene = builtin("cornell").unwrap();
        let mesh = &scene.meshes[scene.objects[1].mesh];
        let mirror = glam::Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let piece = world_piece(mesh, 0, mesh.indices.len() as u32, mirror);
        for tri in piece.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| piece.positions[tri[k] as usize]);
            let face = (b - a).cross(c - a);
            assert!(face.dot(piece.normals[tri[0] as usize]) > 0.0);
        }
    }

    #[test]
    fn zero_sized_image_is_an_error() {
        let scene = builtin("cornell").unwrap();
        let dir = TempDir::new("empty");
        let err = export_mitsuba(&scene, 0.0, 0, 16, &dir.0).unwrap_err();
        assert!(matches!(err, MitsubaExportError::EmptyImage { .. }));
        assert!(err.to_string().contains("at least 1 pixel"));
    }
}
