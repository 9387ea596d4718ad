//! `gi_vpl_emit`: VPLs from emitters — emissive triangles and area lights (spheres,
//! rectangles) — for `--gi vpl`. The reflective light maps see only what point, spot and
//! directional lights see, so emitters need their own VPL paths: a point on an emitter
//! sampled by emitted power, a source VPL there (emissive surfaces only: an area light's
//! direct light is `deferred_direct`'s), and one cosine-distributed voxel ray to the first hit,
//! whose VPL the bounce passes continue. The estimator and its flux are derived in
//! `glsl/gi_vpl_emit.comp`; this file builds the emitter table it samples ([`emitter_table`]).
//!
//! An emissive triangle with an emission map (`map_Ke`) is picked by `Ke` × the map's mean (its
//! row's weight) but emits the map's texel at the sampled point, a point resampled from 8
//! uniform candidates in proportion to the map: the row carries the triangle's texture
//! coordinates and map, and the pass reads the map from a buffer of linear half-float texels
//! ([`crate::voxel::maps::VoxelMaps`], only in scenes with such maps and with
//! `GiSettings::voxel_map_texels`; the estimator stays unbiased, see the shader).
//!
//! The table is rebuilt when `Renderer::prepare` sees the emitters change (a light switched
//! off or scaled, an emissive object moved) and written into the frame slots' windows of a
//! host-visible buffer, one row per potential emitter: an emitter that is black for now keeps
//! its row with zero weight, so the table's length, and the graph, never change.

use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::{Light, Scene};
use crate::vk::{
    vk, Buffer, BufferDesc, ComputePipeline, Context, MemoryLocation, PushLayout, VkError,
    MAX_FRAMES_IN_FLIGHT,
};
use crate::voxel::maps::{MapUse, VoxelMaps};
use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::gi_common::GpuVplGeneratePush;

/// `GpuEmitter::origin.w` of an emissive triangle (origin, edges; face normal e1 × e2).
pub const EMITTER_TRIANGLE: f32 = 0.0;
/// Of a rectangle light (origin a corner, edges; normal e1 × e2, one-sided).
pub const EMITTER_RECTANGLE: f32 = 1.0;
/// Of a sphere light (origin the centre, `edge1[0]` the radius; emits outward everywhere).
pub const EMITTER_SPHERE: f32 = 2.0;

/// One emitter of the table (`GpuEmitter` in `glsl/gi_vpl_emit.comp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuEmitter {
    /// xyz (m); w the kind (`EMITTER_*`).
    pub origin: [f32; 4],
    /// xyz (m); a sphere's radius in x.
    pub edge1: [f32; 4],
    /// xyz (m).
    pub edge2: [f32; 4],
    /// rgb π·W·L/w (W): the flux one power-sampled point carries, times the samples per set
    /// (with an emission map L = `Ke`, which the shader multiplies by the map's texel at the
    /// point); w the CDF of the power up to and including this emitter (the last is 1).
    pub flux: [f32; 4],
    /// A triangle's texture coordinates at its origin (xy) and at origin + edge1 (zw).
    pub uv01: [f32; 4],
    /// At origin + edge2 (xy); z unused; w the emission map's texture index as `i32` bits (-1:
    /// none).
    pub uv2_map: [f32; 4],
}

crate::gpu_struct!(GpuEmitter {
    origin,
    edge1,
    edge2,
    flux,
    uv01,
    uv2_map
});

/// An emitter before normalization: kind, origin, edges, radiance L (W/(m²·sr); with an
/// emission map its mean over the map, the weight of the power sampling), area (m²).
pub(super) struct Source {
    kind: f32,
    pub(super) origin: Vec3,
    pub(super) edge1: Vec3,
    pub(super) edge2: Vec3,
    pub(super) radiance: Vec3,
    pub(super) area_m2: f32,
    /// An emission map sampled per texel: its texture index, `Ke` (what the map's texel
    /// multiplies) and the texture coordinates at origin, origin + edge1, origin + edge2.
    map: Option<(usize, Vec3, [Vec2; 3])>,
}

/// The weight w of a radiance in the power sampling: the mean of its channels (positive
/// whenever any channel is, unlike a luminance of a pure colour that could round to 0).
pub(super) fn weight(radiance: Vec3) -> f32 {
    (radiance.x + radiance.y + radiance.z) / 3.0
}

/// Every emitter of `scene` at time `t_s`: its emissive triangles (weighed by
/// `Material::voxel_emission`, `Ke` × the mean of `map_Ke`; with `per_texel` a triangle with
/// an emission map carries it, [`GpuEmitter::uv2_map`]) and its sphere and rectangle lights,
/// sampled by power w·A; empty without emitters. Degenerate and black emitters keep a row of
/// zero weight (never picked: the CDF does not rise over it) and zero flux; when all are
/// black, every row has zero flux.
pub fn emitter_table(scene: &Scene, t_s: f32, per_texel: bool) -> Vec<GpuEmitter> {
    let mut sources = emissive_triangles(scene, t_s, per_texel);
    sources.extend(scene.lights.iter().filter_map(area_light_source));
    let power = |s: &Source| match s.area_m2 > 0.0 && weight(s.radiance) > 0.0 {
        true => f64::from(weight(s.radiance) * s.area_m2),
        false => 0.0,
    };
    let total: f64 = sources.iter().map(power).sum();
    let mut cdf = 0.0f64;
    let count = sources.len();
    sources
        .into_iter()
        .enumerate()
        .map(|(i, s)| {
            let p = power(&s);
            cdf += match total > 0.0 {
                true => p / total,
                false => 1.0 / count as f64,
            };
            // π·W·L/w: one sample's estimate of the whole emitted flux (the shader's step 2);
            // with a map the shader multiplies π·W·Ke/w by the texel at the point.
            let emitted = s.map.map_or(s.radiance, |(_, ke, _)| ke);
            let flux = match p > 0.0 {
                true => emitted * (PI * total as f32 / weight(s.radiance)),
                false => Vec3::ZERO,
            };
            let cdf = if i + 1 == count { 1.0 } else { cdf as f32 };
            let (map, uv) = s.map.map_or((-1, [Vec2::ZERO; 3]), |(t, _, uv)| {
                (i32::try_from(t).unwrap_or(-1), uv)
            });
            GpuEmitter {
                origin: s.origin.extend(s.kind).to_array(),
                edge1: s.edge1.extend(0.0).to_array(),
                edge2: s.edge2.extend(0.0).to_array(),
                flux: flux.extend(cdf).to_array(),
                uv01: [uv[0].x, uv[0].y, uv[1].x, uv[1].y],
                uv2_map: [uv[2].x, uv[2].y, 0.0, f32::from_bits(map as u32)],
            }
        })
        .collect()
}

/// The scene's emissive triangles in world space at `t_s` (with `per_texel`, their emission
/// maps).
pub(super) fn emissive_triangles(scene: &Scene, t_s: f32, per_texel: bool) -> Vec<Source> {
    let mut out = Vec::new();
    for object in &scene.objects {
        let Some(mesh) = scene.meshes.get(object.mesh_at(t_s)) else {
            continue;
        };
        let m = object.transform_at(t_s);
        // The emitting side is e1 x e2's: a mirroring transform reads the corners reversed.
        let order = crate::scene::corner_order(&m);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let Some(mat) = scene.materials.get(material) else {
                continue;
            };
            let radiance = mat.voxel_emission(&scene.textures);
            if radiance == Vec3::ZERO {
                continue;
            }
            let map = mat.pbr_maps.emission.filter(|_| per_texel);
            let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
            for t in mesh.indices[range].chunks_exact(3) {
                let [a, b, c] = order.map(|k| m.transform_point3(mesh.positions[t[k] as usize]));
                let uv = order.map(|k| {
                    mesh.uvs
                        .as_ref()
                        .and_then(|uvs| uvs.get(t[k] as usize).copied())
                        .unwrap_or(Vec2::ZERO)
                });
                out.push(Source {
                    kind: EMITTER_TRIANGLE,
                    origin: a,
                    edge1: b - a,
                    edge2: c - a,
                    radiance,
                    area_m2: 0.5 * (b - a).cross(c - a).length(),
                    map: map.map(|t| (t, mat.emission, uv)),
                });
            }
        }
    }
    out
}

/// A sphere or rectangle light as an emitter; other lights have reflective maps instead.
fn area_light_source(light: &Light) -> Option<Source> {
    match *light {
        Light::Sphere {
            position,
            radius_m,
            radiance_w_sr_m2,
            ..
        } => Some(Source {
            kind: EMITTER_SPHERE,
            origin: position,
            edge1: Vec3::new(radius_m, 0.0, 0.0),
            edge2: Vec3::ZERO,
            radiance: radiance_w_sr_m2,
            area_m2: 4.0 * PI * radius_m * radius_m,
            map: None,
        }),
        Light::Rectangle {
            position,
            normal,
            width_axis,
            width_m,
            height_m,
            radiance_w_sr_m2,
            ..
        } => {
            // normal × width_axis is the height axis, so width × height = the normal.
            let (e1, e2) = (width_axis * width_m, normal.cross(width_axis) * height_m);
            Some(Source {
                kind: EMITTER_RECTANGLE,
                origin: position - 0.5 * (e1 + e2),
                edge1: e1,
                edge2: e2,
                radiance: radiance_w_sr_m2,
                area_m2: width_m * height_m,
                map: None,
            })
        }
        _ => None,
    }
}

/// The pass and its table.
pub struct GiVplEmit {
    pipeline: ComputePipeline,
    /// `MAX_FRAMES_IN_FLIGHT` windows of `rows` emitters, `stride_bytes` apart.
    emitters: Buffer,
    rows: usize,
    stride_bytes: u64,
    /// The current table, its generation, and the generation each slot's window holds.
    table: Vec<GpuEmitter>,
    generation: u64,
    written: [u64; MAX_FRAMES_IN_FLIGHT],
    /// Emissive triangles are in the table: each row ends with K source VPLs.
    pub has_surfaces: bool,
    /// The rows carry their emission maps ([`emitter_table`]'s `per_texel`).
    per_texel: bool,
    /// The emission maps the pass samples, in scenes whose emitters have them (with
    /// `per_texel`).
    maps: Option<VoxelMaps>,
}

impl GiVplEmit {
    /// `None` when `scene` has no emitters. `source_vpls`: the specialization constant of the
    /// row layout (`SOURCE_VPLS` in `glsl/include/vpl.glsl`), K when the table has emissive
    /// triangles. `lobes`: the scene has Phong or GGX materials, and the pass reads the
    /// material volume at its rays' hits (specialization constant 3). `per_texel`: emissive
    /// triangles emit their emission map's texel at the sampled point
    /// (`GiSettings::voxel_map_texels`; specialization constant 4 where one has a map).
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        per_set: u32,
        lobes: bool,
        per_texel: bool,
    ) -> Result<Option<Self>, VkError> {
        let table = emitter_table(scene, t_s, per_texel);
        if table.is_empty() {
            return Ok(None);
        }
        let has_surfaces = table.iter().any(|e| e.origin[3] == EMITTER_TRIANGLE);
        let used = MapUse::new(scene, true, false, per_texel);
        let maps = VoxelMaps::new(
            ctx,
            scene,
            MapUse {
                emission: used.emission,
                ..MapUse::default()
            },
        )?;
        let pipeline = ctx.compute_pipeline(
            "gi_vpl_emit.comp",
            PushLayout::of::<GpuVplGeneratePush>(),
            &crate::spec_constants![
                SOURCE_VPLS = if has_surfaces { per_set } else { 0 },
                HAS_LOBES = lobes,
                HAS_MAPS = maps.is_some(),
            ],
        )?;
        let bytes = std::mem::size_of_val(table.as_slice()) as u64;
        let stride_bytes = bytes.next_multiple_of(256);
        let emitters = ctx.create_buffer(&BufferDesc {
            name: "vpl emitters".into(),
            size_bytes: stride_bytes * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let mut pass = Self {
            pipeline,
            emitters,
            rows: table.len(),
            stride_bytes,
            table,
            generation: 1,
            written: [0; MAX_FRAMES_IN_FLIGHT],
            has_surfaces,
            per_texel,
            maps,
        };
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            pass.write_slot(slot);
        }
        Ok(Some(pass))
    }

    /// Rebuilds the table for `scene` at `t_s`; the frame slots get it as they are written.
    /// A scene whose emitters are not those the pass was made for (another row count) keeps
    /// the old table, with a warning.
    pub fn update(&mut self, scene: &Scene, t_s: f32) {
        let table = emitter_table(scene, t_s, self.per_texel);
        if table.len() != self.rows {
            log::warn!(
                "VPL emitters not updated: {} rows, the pass was made for {}",
                table.len(),
                self.rows
            );
        } else if table != self.table {
            self.table = table;
            self.generation += 1;
        }
    }

    /// Writes the current table into frame slot `slot`'s window (after the slot's fence), if
    /// that window holds an older one.
    pub fn write_slot(&mut self, slot: usize) {
        if self.written[slot] == self.generation {
            return;
        }
        let offset = slot * self.stride_bytes as usize;
        let bytes: &[u8] = bytemuck::cast_slice(&self.table);
        if let Some(m) = self.emitters.mapped_mut() {
            m[offset..offset + bytes.len()].copy_from_slice(bytes);
            self.written[slot] = self.generation;
        }
    }

    /// Declares the pass: writes the emitter slot's bounce-0 VPLs and the source VPLs of
    /// `vpls` (after `gi_vpl_generate`, before the bounces); `invocations` = sets × K.
    #[allow(clippy::too_many_arguments)]
    pub fn add_pass(
        &self,
        g: &mut RenderGraph,
        push: impl Fn() -> GpuVplGeneratePush + 'static,
        invocations: u32,
        (voxels, lut): (ImageHandle, BufferHandle),
        (albedo, normal, material): (ImageHandle, ImageHandle, ImageHandle),
        vpls: BufferHandle,
        s: vk::Sampler,
    ) {
        let c = Shader::Compute;
        let pipe = *self.pipeline;
        let emitters = g.import_buffer_per_slot(
            &self.emitters,
            self.stride_bytes,
            std::mem::size_of::<GpuEmitter>() as u64 * self.rows as u64,
            Access::StorageRead(c),
        );
        // Without emission maps the shader never reads them: the table stands in.
        let (texels, table) = self.maps.as_ref().map_or((emitters, emitters), |m| {
            m.import(g, Access::StorageRead(c))
        });
        g.add_pass("gi_vpl_emit")
            .pipeline(&pipe)
            .bind_sampled(0, voxels, s, c)
            .bind(1, lut, Access::StorageRead(c))
            .bind_sampled(2, albedo, s, c)
            .bind_sampled(3, normal, s, c)
            .bind(4, vpls, Access::StorageReadWrite(c))
            .bind(5, emitters, Access::StorageRead(c))
            .bind_sampled(6, material, s, c)
            .bind(7, texels, Access::StorageRead(c))
            .bind(8, table, Access::StorageRead(c))
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push()));
                ctx.cmd.dispatch(invocations.div_ceil(64).max(1), 1, 1);
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(toml: &str) -> Scene {
        Scene::from_toml_str(
            toml,
            Path::new("<test>"),
            Path::new(env!("CARGO_MANIFEST_DIR")),
        )
        .expect("parses")
    }

    #[test]
    fn emitter_struct_matches_glsl() {
        crate::vk::check_struct_against::<GpuEmitter>(&["gi_vpl_emit.comp"], "GpuEmitter")
            .expect("GpuEmitter layout");
    }

    /// A 2 m × 0.5 m rectangle of L = 3 and a sphere of radius 0.5 and L = 1 (both grey):
    /// powers w·A = 3 and π, so the CDF is 3 / (3 + π) then 1, and every sample carries the
    /// whole flux π·(3 + π)·L/w = π (3 + π) (grey: L/w = 1), the sum of π L A over both.
    #[test]
    fn area_lights_are_sampled_by_power() {
        let s = scene(
            r#"
[camera]
position = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[[objects]]
builtin = "quad"
[[lights]]
kind = "rectangle"
position = [0.0, 2.0, 0.0]
normal = [0.0, -1.0, 0.0]
width_axis = [1.0, 0.0, 0.0]
width_m = 2.0
height_m = 0.5
radiance_w_sr_m2 = 3.0
[[lights]]
kind = "sphere"
position = [1.0, 1.0, 1.0]
radius_m = 0.5
radiance_w_sr_m2 = 1.0
"#,
        );
        let t = emitter_table(&s, 0.0, true);
        assert_eq!(t.len(), 2);
        let total = 3.0 + PI;
        assert!((t[0].flux[3] - 3.0 / total).abs() < 1e-6, "{t:?}");
        assert_eq!(t[1].flux[3], 1.0);
        for e in &t {
            assert!((e.flux[0] - PI * total).abs() < 1e-4, "{e:?}");
        }
        // The rectangle's corner and edges: the normal e1 × e2 is the light's.
        let (e1, e2) = (Vec3::from_slice(&t[0].edge1), Vec3::from_slice(&t[0].edge2));
        assert!((e1.cross(e2).normalize() - Vec3::NEG_Y).length() < 1e-6);
        assert!((e1.cross(e2).length() - 1.0).abs() < 1e-6, "area 2 × 0.5");
        let centre = Vec3::from_slice(&t[0].origin) + 0.5 * (e1 + e2);
        assert!((centre - Vec3::new(0.0, 2.0, 0.0)).length() < 1e-6);
        assert_eq!(t[0].origin[3], EMITTER_RECTANGLE);
        assert_eq!(t[1].origin[3], EMITTER_SPHERE);
    }

    /// An emissive quad is two triangles of half its area each, facing where its normals do;
    /// a scene without emitters has an empty table (no pass, no buffer).
    #[test]
    fn emissive_triangles_face_their_normals() {
        let base = r#"
[camera]
position = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[[objects]]
builtin = "quad"
"#;
        assert!(emitter_table(&scene(base), 0.0, true).is_empty());
        let s = scene(&format!(
            "{base}material = {{ albedo = 0.0, emission_w_sr_m2 = [2.0, 1.0, 0.0] }}\n"
        ));
        let t = emitter_table(&s, 0.0, true);
        assert_eq!(t.len(), 2);
        for e in &t {
            let (e1, e2) = (Vec3::from_slice(&e.edge1), Vec3::from_slice(&e.edge2));
            // The built-in quad lies in y = 0 with normals +y, 1 m × 1 m.
            assert!(
                (e1.cross(e2).normalize() - Vec3::Y).length() < 1e-6,
                "{e:?}"
            );
            assert!((0.5 * e1.cross(e2).length() - 0.5).abs() < 1e-6);
            // w = 1, W = 1 (m²): π·W·L/w = π·(2, 1, 0).
            assert!(
                (Vec3::from_slice(&e.flux[..3]) - PI * Vec3::new(2.0, 1.0, 0.0)).length() < 1e-5
            );
        }
        assert!((t[0].flux[3] - 0.5).abs() < 1e-6);
    }

    /// An emission map: the rows keep the weight `Ke` × the map's mean but carry π·W·Ke/w, the
    /// map and the triangle's texture coordinates, for the shader to multiply by the texel at
    /// its point; without `per_texel` they carry the mean's flux and no map.
    #[test]
    fn emission_map_rows_carry_ke_and_the_map() {
        let mut s = scene(
            r#"
[camera]
position = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[[objects]]
builtin = "quad"
material = { albedo = 0.0, emission_w_sr_m2 = [4.0, 2.0, 0.0] }
"#,
        );
        // Linear texels 1 and 0: the map's mean is 1/2, so L̄ = (2, 1, 0), w = 1, W = 1 m².
        let rgba8 = [255, 255, 255, 255, 0, 0, 0, 255].to_vec();
        s.textures = vec![crate::scene::TextureData::new(
            "glow".into(),
            2,
            1,
            rgba8,
            false,
        )];
        let m = s.objects[0].materials[0];
        s.materials[m].pbr_maps.emission = Some(0);
        let texel = emitter_table(&s, 0.0, true);
        let mean = emitter_table(&s, 0.0, false);
        for (e, f) in texel.iter().zip(&mean) {
            // The selection is the same table either way.
            assert_eq!(e.flux[3], f.flux[3]);
            // π·W·Ke/w = π·(4, 2, 0) with the map, π·W·L̄/w = π·(2, 1, 0) without.
            let flux = |r: &GpuEmitter| Vec3::from_slice(&r.flux[..3]);
            assert!(
                (flux(e) - PI * Vec3::new(4.0, 2.0, 0.0)).length() < 1e-5,
                "{e:?}"
            );
            assert!(
                (flux(f) - PI * Vec3::new(2.0, 1.0, 0.0)).length() < 1e-5,
                "{f:?}"
            );
            assert_eq!(e.uv2_map[3].to_bits(), 0);
            assert_eq!(f.uv2_map[3].to_bits(), u32::MAX);
        }
        // The built-in quad's texture coordinates span [0, 1]².
        let uvs: Vec<f32> = texel
            .iter()
            .flat_map(|e| {
                [
                    e.uv01[0],
                    e.uv01[1],
                    e.uv01[2],
                    e.uv01[3],
                    e.uv2_map[0],
                    e.uv2_map[1],
                ]
            })
            .collect();
        assert!(uvs.iter().all(|u| (0.0..=1.0).contains(u)), "{uvs:?}");
        assert!(uvs.contains(&1.0) && uvs.contains(&0.0), "{uvs:?}");
    }
}
