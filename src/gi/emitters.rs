//! The emitter list of the path tracer's next-event estimation (`glsl/include/emitters.glsl`):
//! the scene's emissive triangles in world space, each with its power Φ = π·w·A (w the mean
//! of its emitted radiance's channels, `Material::voxel_emission`: `Ke` times the mean of
//! `map_Ke`; A its area), and the cumulative distribution of Φ, so that a path vertex picks a
//! triangle with probability Φ/ΣΦ and a point on it uniformly (Veach 1997, §9.2; Pharr, Jakob
//! and Humphreys 2016, §14.6 "light sampling by power"). The density of such a point per unit
//! area is then the same on every triangle of the same radiance,
//!
//!   p_A(y) = (Φ_t/ΣΦ) / A_t = w(L_t) / Σ_t w(L_t)·A_t,
//!
//! which is what lets a BSDF ray that hits an emitter in the voxels weigh itself against this
//! strategy without knowing its triangle: the emission volume holds L at the hit
//! ([`GpuEmitterHeader::inv_weighted_area`] is the denominator).
//!
//! Built on the CPU at renderer creation and rebuilt when `Renderer::prepare` sees the scene
//! change (an emissive object moved); each frame slot's window of a host-visible buffer gets
//! the current table. The row count never changes: a triangle that is black for now keeps its
//! row with zero weight. Scenes without emissive triangles have no table, no buffer and no
//! shader code for it (a specialization constant).

use super::gi_vpl_emit::{emissive_triangles, weight};
use crate::graph::{Access, BufferHandle, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{vk, Buffer, BufferDesc, Context, MemoryLocation, VkError, MAX_FRAMES_IN_FLIGHT};
use bytemuck::{Pod, Zeroable};

/// The table's first 16 bytes (`GpuEmitterHeader` in `glsl/include/emitters.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuEmitterHeader {
    /// Rows that follow.
    pub count: u32,
    /// 1 / Σ w(L_t)·A_t (1/(W/(m²·sr)·m²)); 0 when every triangle is black (nothing to pick).
    pub inv_weighted_area: f32,
    pub pad: [u32; 2],
}

crate::gpu_struct!(GpuEmitterHeader {
    count,
    inv_weighted_area,
    pad
});

/// One emissive triangle (`GpuEmissiveTriangle` in `glsl/include/emitters.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuEmissiveTriangle {
    /// A vertex (m); w the CDF of the power up to and including this row (the last is 1).
    pub origin: [f32; 4],
    /// The edges to the other two vertices (m); the emitting side is e1 × e2's. w of edge1:
    /// the probability of picking this row, Φ_t/ΣΦ.
    pub edge1: [f32; 4],
    pub edge2: [f32; 4],
    /// The emitted radiance L (W/(m²·sr)); w its area density p_A = w(L)/Σ w·A (1/m²).
    pub radiance: [f32; 4],
}

crate::gpu_struct!(GpuEmissiveTriangle {
    origin,
    edge1,
    edge2,
    radiance
});

/// The emitter list of `scene` at time `t_s`: its header and one row per emissive triangle;
/// no rows without emissive triangles. Degenerate and black triangles keep a row of zero
/// probability (the CDF does not rise over it).
pub fn emitter_list(scene: &Scene, t_s: f32) -> (GpuEmitterHeader, Vec<GpuEmissiveTriangle>) {
    // The means of the emission maps: the emission volume's texels vary over a triangle, but
    // the power of a row, and with it the pdf, is the triangle's (docs/design/emitter-sampling.md).
    let sources = emissive_triangles(scene, t_s, false);
    let weighted_area = |w: f32, a: f32| match w > 0.0 && a > 0.0 && (w * a).is_finite() {
        true => f64::from(w) * f64::from(a),
        false => 0.0,
    };
    let total: f64 = sources
        .iter()
        .map(|s| weighted_area(weight(s.radiance), s.area_m2))
        .sum();
    let inv_total = if total > 0.0 { 1.0 / total } else { 0.0 };
    let count = sources.len();
    let mut cdf = 0.0f64;
    let rows = sources
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let w = weight(s.radiance);
            let p = weighted_area(w, s.area_m2) * inv_total;
            cdf += p;
            let cdf = if i + 1 == count {
                1.0
            } else {
                cdf.min(1.0) as f32
            };
            let density = if p > 0.0 {
                f64::from(w) * inv_total
            } else {
                0.0
            };
            GpuEmissiveTriangle {
                origin: s.origin.extend(cdf).to_array(),
                edge1: s.edge1.extend(p as f32).to_array(),
                edge2: s.edge2.extend(0.0).to_array(),
                radiance: s.radiance.extend(density as f32).to_array(),
            }
        })
        .collect();
    let header = GpuEmitterHeader {
        count: count as u32,
        inv_weighted_area: inv_total as f32,
        pad: [0; 2],
    };
    (header, rows)
}

/// The table's bytes: the header, then the rows.
fn table_bytes(header: &GpuEmitterHeader, rows: &[GpuEmissiveTriangle]) -> Vec<u8> {
    let mut bytes = bytemuck::bytes_of(header).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(rows));
    bytes
}

/// The emitter list on the GPU: `MAX_FRAMES_IN_FLIGHT` windows of a host-visible buffer.
pub struct EmitterBuffer {
    buffer: Buffer,
    stride_bytes: u64,
    size_bytes: u64,
    /// The current table's bytes, its generation, and the generation each slot's window holds.
    table: Vec<u8>,
    generation: u64,
    written: [u64; MAX_FRAMES_IN_FLIGHT],
}

impl EmitterBuffer {
    /// `None` when `scene` has no emissive triangles.
    pub fn new(ctx: &Context, scene: &Scene, t_s: f32) -> Result<Option<Self>, VkError> {
        let (header, rows) = emitter_list(scene, t_s);
        if rows.is_empty() {
            return Ok(None);
        }
        let table = table_bytes(&header, &rows);
        let size_bytes = table.len() as u64;
        let stride_bytes = size_bytes.next_multiple_of(256);
        let buffer = ctx.create_buffer(&BufferDesc {
            name: "path tracer emitters".into(),
            size_bytes: stride_bytes * MAX_FRAMES_IN_FLIGHT as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            location: MemoryLocation::CpuToGpu,
        })?;
        let mut me = Self {
            buffer,
            stride_bytes,
            size_bytes,
            table,
            generation: 1,
            written: [0; MAX_FRAMES_IN_FLIGHT],
        };
        for slot in 0..MAX_FRAMES_IN_FLIGHT {
            me.write_slot(slot);
        }
        Ok(Some(me))
    }

    /// Rebuilds the table for `scene` at `t_s`; the frame slots get it as they are written. A
    /// scene with another number of emissive triangles than the buffer was made for keeps the
    /// old table, with a warning (a new renderer follows such a change).
    pub fn update(&mut self, scene: &Scene, t_s: f32) {
        let (header, rows) = emitter_list(scene, t_s);
        let table = table_bytes(&header, &rows);
        if table.len() as u64 != self.size_bytes {
            log::warn!(
                "path tracer emitters not updated: {} emissive triangles, the buffer holds {}",
                rows.len(),
                (self.size_bytes as usize - std::mem::size_of::<GpuEmitterHeader>())
                    / std::mem::size_of::<GpuEmissiveTriangle>()
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
        if let Some(m) = self.buffer.mapped_mut() {
            m[offset..offset + self.table.len()].copy_from_slice(&self.table);
            self.written[slot] = self.generation;
        }
    }

    /// The frame slot's window, read by the compute stage.
    pub fn import(&self, g: &mut RenderGraph) -> BufferHandle {
        g.import_buffer_per_slot(
            &self.buffer,
            self.stride_bytes,
            self.size_bytes,
            Access::StorageRead(Shader::Compute),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
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
    fn structs_match_glsl() {
        crate::vk::check_struct_against::<GpuEmissiveTriangle>(
            &["gi_pathtrace.comp"],
            "GpuEmissiveTriangle",
        )
        .expect("GpuEmissiveTriangle layout");
        crate::vk::check_struct_against::<GpuEmitterHeader>(
            &["gi_pathtrace.comp"],
            "GpuEmitterHeader",
        )
        .expect("GpuEmitterHeader layout");
    }

    const BASE: &str = r#"
[camera]
position = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[[objects]]
builtin = "quad"
"#;

    /// Two emissive quads, 1 m² of L = (2, 1, 0) (w = 1) and 4 m² (scale 2) of L = 3 (w = 3):
    /// powers π·1·1 and π·3·4, so the first quad's two triangles are picked with 1/13 in all
    /// and the second's with 12/13; the area density is w/Σw·A = 1/13 and 3/13 per m², the
    /// same on both triangles of a quad (a point picked by power is uniform over equal
    /// radiance). A scene without emitters has no rows.
    #[test]
    fn triangles_are_picked_by_power() {
        assert!(emitter_list(&scene(BASE), 0.0).1.is_empty());
        let s = scene(&format!(
            "{BASE}material = {{ albedo = 0.0, emission_w_sr_m2 = [2.0, 1.0, 0.0] }}\n\
             [[objects]]\nbuiltin = \"quad\"\nscale = 2.0\ntranslate = [0.0, 1.0, 0.0]\n\
             material = {{ albedo = 0.0, emission_w_sr_m2 = 3.0 }}\n"
        ));
        let (header, rows) = emitter_list(&s, 0.0);
        assert_eq!((header.count, rows.len()), (4, 4));
        assert!((header.inv_weighted_area - 1.0 / 13.0).abs() < 1e-7);
        let picks: Vec<f32> = rows.iter().map(|r| r.edge1[3]).collect();
        let expected = [0.5 / 13.0, 0.5 / 13.0, 6.0 / 13.0, 6.0 / 13.0];
        for (p, e) in picks.iter().zip(expected) {
            assert!((p - e).abs() < 1e-6, "{picks:?}");
        }
        assert!((rows[1].origin[3] - 1.0 / 13.0).abs() < 1e-6);
        assert_eq!(rows[3].origin[3], 1.0);
        for (r, density) in rows.iter().zip([1.0, 1.0, 3.0, 3.0]) {
            let area = 0.5
                * Vec3::from_slice(&r.edge1)
                    .cross(Vec3::from_slice(&r.edge2))
                    .length();
            // p_A = (pick probability) / area, the density the shader weighs with.
            assert!((r.edge1[3] / area - r.radiance[3]).abs() < 1e-6, "{r:?}");
            assert!((r.radiance[3] - density / 13.0).abs() < 1e-6, "{r:?}");
        }
    }
}
