//! Automatic injective texture atlases for the thesis's atlas voxelizer (Thiedemann 2010,
//! §4.2–§4.3.1), generated here instead of by hand in Blender.
//!
//! # Layout
//! Every triangle gets its own rectangular *cell*. Inside it the triangle is laid out
//! **isometrically** (its longest edge along +u, scaled by `1 / texel_m` texels per meter,
//! after the object's scale), so atlas area is proportional to world area and a distance in
//! the atlas is a distance on the surface. The cell is the triangle's bounding box rounded up
//! to whole texels plus a [`PAD_TEXELS`] gutter on every side; cells are integer rectangles
//! packed by shelves (tallest first), so they never overlap.
//!
//! # Which texels a triangle owns (the coverage rule, shared with `atlas_positions.frag`)
//! Texel `(i, j)` of a cell belongs to its triangle iff the distance from the texel centre
//! `(i + ½, j + ½)` to the triangle is at most [`COVER_RADIUS_TEXELS`] = √2/2 (the texel's
//! circumscribed disk touches the triangle): conservative, so thin and tiny triangles own at
//! least one texel. Such a texel's sample is the *closest point of the triangle* to its
//! centre, so every sample lies on the surface. A centre within √2/2 of a triangle whose
//! box starts one texel into the cell is itself inside the cell: the one-texel gutter keeps
//! texel sets disjoint.
//!
//! # Resolution (no holes)
//! Let `h` be the texel's world size. For any point `P` of a triangle, the texel containing
//! `P` has its centre `C` within `h·√2/2` of `P`, so it is owned, and its sample
//! `Q = proj(C)` satisfies `|Q − P| ≤ |C − P| ≤ h·√2/2` (projection onto a convex set is
//! non-expansive and `proj(P) = P`). The samples are thus an `ε`-net of the surface with
//! `ε = h·√2/2`. A voxel of edge `v` gets a sample whenever the surface inside it contains a
//! disk of radius `ε`. With [`texel_size_for_voxel`] `h = v/2`, `ε ≈ 0.35 v`: every voxel the
//! surface crosses with more than a thin corner or edge clip is hit; only voxels that the
//! conservative (touching) reference adds for grazing contact can be missed. (The thesis's
//! hand-tuned 384² atlas for 128³ voxels is the same order.)
//!
//! Measured (`examples/atlas_bench.rs`, texels of v/2): ~4.2 valid texels per CPU voxel;
//! h = v/√2 halves the points (and was 2–4× faster on lavapipe) but drops the Cornell recall
//! against the conservative reference from 0.985 to 0.975, too close to the
//! required 0.97 (`tests/atlas.rs`, `MIN_RECALL`).
//!
//! # Packing efficiency (measured, `examples/atlas_bench.rs`)
//! Shelf packing of the cells leaves 4–19% of the atlas empty (cells cover 0.81 of the
//! Cornell atlases, 0.90 of the bunny's, 0.96 of a 16×-tessellated cube's); the triangles
//! themselves fill 0.37–0.43, because a triangle covers at most half its bounding box and
//! the one-texel gutter dominates tiny triangles. Valid texels (triangles plus their
//! √2/2-texel rim) are ~41% of the atlas. Fine for a position atlas that is rendered once
//! and then read only through its compacted point list.
//!
//! # OBJ sequences (one atlas for all frames)
//! The thesis shares one atlas across an OBJ sequence whose vertex order is identical and
//! whose deformation is moderate (§4.2.1), and notes that a growing triangle makes
//! holes (§4.4). [`build_sequence_atlas`] removes that limit: each triangle is laid out
//! isometrically from the frame where its area is largest, then scaled by
//! `s = max(1, max_f σ_f)`, where `σ_f` is the largest singular value of the affine map from
//! the layout (texels) to frame `f`'s triangle (texels). The map from the scaled layout,
//! `A_f / s`, then lengthens no atlas distance, so the argument of "Resolution" holds in
//! every frame: the texel containing a point's preimage has its sample within
//! `σ_f/s · √2/2 ≤ √2/2` texels of the point, i.e. within `h·√2/2` meters. Cost: atlas area grows by `s²` for triangles that
//! stretch in different directions in different frames; a triangle that only grows or only
//! shrinks keeps `s = 1` (its largest frame dominates every other frame).
//! Triangles of zero area in every frame (segments) are laid out along their longest frame
//! and scaled by the largest edge-length ratio instead.
//!
//! # Cache
//! [`AtlasCache`] keeps built atlases in memory (per renderer, not on disk), keyed by mesh
//! content, object scale and texel size, so a static mesh is packed once per run and objects
//! that share a mesh share its atlas.

use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

/// Gutter around each triangle's box, in texels.
pub const PAD_TEXELS: u32 = 1;

/// A texel belongs to a triangle when its centre is this close to it (texels): √2/2.
pub const COVER_RADIUS_TEXELS: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Texel world size for voxels of edge `voxel_m` (see the module doc: `ε = h·√2/2 ≈ 0.35 v`).
pub fn texel_size_for_voxel(voxel_m: f32) -> f32 {
    voxel_m * 0.5
}

/// Errors of atlas generation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AtlasError {
    #[error(
        "atlas texel size {0} m is not a positive finite number; the voxel grid is degenerate"
    )]
    BadTexelSize(f32),
    #[error("mesh '{mesh}' needs a {width}×{height} atlas, above the {max}-texel limit; use fewer voxels (--voxel-res) or --voxelizer triangle")]
    TooLarge {
        mesh: String,
        width: u32,
        height: u32,
        max: u32,
    },
    #[error("mesh '{mesh}': triangle {triangle} has a vertex index out of range or a non-finite position; fix the mesh")]
    BadTriangle { mesh: String, triangle: usize },
    #[error("OBJ sequence '{mesh}' has no frames; give `frames = N` with N >= 1")]
    NoFrames { mesh: String },
}

/// One triangle's place in the atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasTriangle {
    /// The three vertices in atlas texel coordinates (continuous; texel `(i, j)` spans
    /// `[i, i+1) × [j, j+1)`), in the mesh's vertex order.
    pub uv: [Vec2; 3],
    /// Cell `(x, y, width, height)` in texels: the triangle owns texels only inside it.
    pub cell: [u32; 4],
}

/// An injective atlas of one mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAtlas {
    pub width: u32,
    pub height: u32,
    /// World size of a texel (meters, after the object's scale).
    pub texel_m: f32,
    /// One entry per mesh triangle, in index order.
    pub triangles: Vec<AtlasTriangle>,
}

impl MeshAtlas {
    /// Sum of the triangles' atlas areas over the atlas area (packing efficiency).
    pub fn area_efficiency(&self) -> f64 {
        let tri: f64 = self
            .triangles
            .iter()
            .map(|t| f64::from(tri_area_2d(t.uv)))
            .sum();
        tri / (f64::from(self.width) * f64::from(self.height)).max(1.0)
    }

    /// Share of the atlas that the cells (boxes plus gutters) cover.
    pub fn cell_efficiency(&self) -> f64 {
        let cells: f64 = self
            .triangles
            .iter()
            .map(|t| f64::from(t.cell[2]) * f64::from(t.cell[3]))
            .sum();
        cells / (f64::from(self.width) * f64::from(self.height)).max(1.0)
    }

    /// Texels that triangle `t` owns (the coverage rule of the module doc), row-major.
    pub fn texels(&self, t: usize) -> Vec<(u32, u32)> {
        let Some(tri) = self.triangles.get(t) else {
            return Vec::new();
        };
        let [x, y, w, h] = tri.cell;
        let mut out = Vec::new();
        for j in y..y + h {
            for i in x..x + w {
                let c = Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                let (q, _) = closest_point(tri.uv, c);
                if q.distance(c) <= COVER_RADIUS_TEXELS {
                    out.push((i, j));
                }
            }
        }
        out
    }
}

fn tri_area_2d(p: [Vec2; 3]) -> f32 {
    0.5 * (p[1] - p[0]).perp_dot(p[2] - p[0]).abs()
}

/// Closest point of triangle `p` to `c`, with its barycentric coordinates. Handles
/// degenerate triangles (segments, points). Mirrors `closest_on_triangle` in
/// `atlas_positions.frag`.
pub fn closest_point(p: [Vec2; 3], c: Vec2) -> (Vec2, [f32; 3]) {
    let area2 = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    if area2.abs() > 1e-12 {
        let l0 = (p[1] - c).perp_dot(p[2] - c) / area2;
        let l1 = (p[2] - c).perp_dot(p[0] - c) / area2;
        let l2 = 1.0 - l0 - l1;
        if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
            return (c, [l0, l1, l2]);
        }
    }
    let mut best = (p[0], [1.0, 0.0, 0.0]);
    let mut best_d = f32::INFINITY;
    for e in 0..3 {
        let (a, b) = (p[e], p[(e + 1) % 3]);
        let ab = b - a;
        let len2 = ab.length_squared();
        let s = if len2 > 0.0 {
            ((c - a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = a + ab * s;
        let d = q.distance_squared(c);
        if d < best_d {
            best_d = d;
            let mut bary = [0.0; 3];
            bary[e] = 1.0 - s;
            bary[(e + 1) % 3] = s;
            best = (q, bary);
        }
    }
    best
}

/// Largest atlas side accepted (lavapipe and every desktop GPU support 8192² images).
pub const MAX_ATLAS_SIDE: u32 = 8192;

/// Builds the atlas of a mesh (`positions` in model space, `scale` the object's scale)
/// with texels of `texel_m` meters.
pub fn build_atlas(
    name: &str,
    positions: &[Vec3],
    indices: &[u32],
    scale: Vec3,
    texel_m: f32,
) -> Result<MeshAtlas, AtlasError> {
    build_sequence_atlas(name, &[positions], indices, scale, texel_m)
}

/// Builds one atlas shared by every frame of an OBJ sequence (`frames[f]` = frame `f`'s
/// model-space positions, all indexed by `indices`): no frame gets holes (module doc,
/// "OBJ sequences"). With one frame this is the isometric atlas of [`build_atlas`].
pub fn build_sequence_atlas(
    name: &str,
    frames: &[&[Vec3]],
    indices: &[u32],
    scale: Vec3,
    texel_m: f32,
) -> Result<MeshAtlas, AtlasError> {
    if !(texel_m.is_finite() && texel_m > 0.0) {
        return Err(AtlasError::BadTexelSize(texel_m));
    }
    if frames.is_empty() {
        return Err(AtlasError::NoFrames {
            mesh: name.to_owned(),
        });
    }
    let inv = 1.0 / texel_m;
    // Per triangle: layout (texels) with its box at the origin.
    let mut local = Vec::with_capacity(indices.len() / 3);
    let mut per_frame = vec![[Vec3::ZERO; 3]; frames.len()];
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        let bad = || AtlasError::BadTriangle {
            mesh: name.to_owned(),
            triangle: t,
        };
        for (positions, v) in frames.iter().zip(per_frame.iter_mut()) {
            for (k, &i) in tri.iter().enumerate() {
                let p = *positions.get(i as usize).ok_or_else(bad)? * scale * inv;
                if !p.is_finite() {
                    return Err(bad());
                }
                v[k] = p;
            }
        }
        local.push(layout_sequence_triangle(&per_frame));
    }
    // Cells, packed by shelves, tallest first.
    let size = |uv: &[Vec2; 3]| {
        let hi = uv[0].max(uv[1]).max(uv[2]);
        (
            hi.x.ceil() as u32 + 2 * PAD_TEXELS,
            hi.y.ceil() as u32 + 2 * PAD_TEXELS,
        )
    };
    let sizes: Vec<(u32, u32)> = local.iter().map(size).collect();
    let total: u64 = sizes
        .iter()
        .map(|&(w, h)| u64::from(w) * u64::from(h))
        .sum();
    let widest = sizes.iter().map(|s| s.0).max().unwrap_or(1);
    let width = ((total as f64).sqrt().ceil() as u32).max(widest).max(1);
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(sizes[i].1), std::cmp::Reverse(sizes[i].0)));
    let mut cells = vec![[0u32; 4]; sizes.len()];
    let (mut x, mut y, mut shelf_h) = (0u32, 0u32, 0u32);
    for &i in &order {
        let (w, h) = sizes[i];
        if x + w > width {
            y += shelf_h;
            x = 0;
            shelf_h = 0;
        }
        cells[i] = [x, y, w, h];
        x += w;
        shelf_h = shelf_h.max(h);
    }
    let height = (y + shelf_h).max(1);
    if width > MAX_ATLAS_SIDE || height > MAX_ATLAS_SIDE {
        return Err(AtlasError::TooLarge {
            mesh: name.to_owned(),
            width,
            height,
            max: MAX_ATLAS_SIDE,
        });
    }
    let triangles = local
        .iter()
        .zip(&cells)
        .map(|(uv, &cell)| {
            let o = Vec2::new((cell[0] + PAD_TEXELS) as f32, (cell[1] + PAD_TEXELS) as f32);
            AtlasTriangle {
                uv: uv.map(|p| p + o),
                cell,
            }
        })
        .collect();
    Ok(MeshAtlas {
        width,
        height,
        texel_m,
        triangles,
    })
}

/// Lays out one triangle of a sequence (`v[f]` = its vertices in frame `f`, in texels):
/// isometric from the frame of largest area, scaled so that no frame's map from the layout
/// stretches by more than 1 (module doc, "OBJ sequences").
fn layout_sequence_triangle(v: &[[Vec3; 3]]) -> [Vec2; 3] {
    let area = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).length();
    let longest = |t: &[Vec3; 3]| {
        (0..3)
            .map(|e| t[e].distance(t[(e + 1) % 3]))
            .fold(0.0f32, f32::max)
    };
    // Largest area first, then the longest edge (all-degenerate triangles).
    let Some(reference) = v.iter().max_by(|a, b| {
        (area(a), longest(a))
            .partial_cmp(&(area(b), longest(b)))
            .unwrap_or(std::cmp::Ordering::Equal)
    }) else {
        return [Vec2::ZERO; 3];
    };
    let layout = layout_triangle(*reference);
    if v.len() == 1 {
        // Isometric by construction: σ = 1.
        return layout;
    }
    let s = v
        .iter()
        .map(|f| max_stretch(layout, f))
        .fold(1.0f32, f32::max);
    layout.map(|p| p * s)
}

/// The largest singular value of the affine map taking the 2D triangle `uv` to the 3D
/// triangle `p` (how much it lengthens an atlas distance at most). For a degenerate `uv`
/// (a segment) the largest edge-length ratio, the stretch along the segment.
pub fn max_stretch(uv: [Vec2; 3], p: &[Vec3; 3]) -> f32 {
    let (e1, e2) = ((uv[1] - uv[0]).as_dvec2(), (uv[2] - uv[0]).as_dvec2());
    let (f1, f2) = ((p[1] - p[0]).as_dvec3(), (p[2] - p[0]).as_dvec3());
    let det = e1.perp_dot(e2);
    let scale2 = e1.length_squared().max(e2.length_squared());
    if det.abs() > 1e-9 * scale2 && scale2 > 0.0 {
        // J = [f1 f2]·[e1 e2]⁻¹, columns j1 = J·x̂, j2 = J·ŷ.
        let j1 = (f1 * e2.y - f2 * e1.y) / det;
        let j2 = (f2 * e1.x - f1 * e2.x) / det;
        let (a, b, c) = (j1.length_squared(), j1.dot(j2), j2.length_squared());
        // Largest eigenvalue of JᵀJ = [[a, b], [b, c]].
        let lambda = 0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt();
        return lambda.sqrt() as f32;
    }
    (0..3)
        .filter_map(|e| {
            let l2 = uv[e].distance(uv[(e + 1) % 3]);
            let l3 = p[e].distance(p[(e + 1) % 3]);
            (l2 > 0.0).then(|| l3 / l2)
        })
        .fold(1.0f32, f32::max)
}

/// Lays out a 3D triangle isometrically in 2D: longest edge along +u, third vertex above,
/// box at the origin.
fn layout_triangle(v: [Vec3; 3]) -> [Vec2; 3] {
    let lens = [0, 1, 2].map(|e| v[e].distance_squared(v[(e + 1) % 3]));
    let e = if lens[0] >= lens[1] && lens[0] >= lens[2] {
        0
    } else if lens[1] >= lens[2] {
        1
    } else {
        2
    };
    let (ia, ib, ic) = (e, (e + 1) % 3, (e + 2) % 3);
    let ab = v[ib] - v[ia];
    let len = ab.length();
    let mut out = [Vec2::ZERO; 3];
    if len > 0.0 {
        let ux = ab / len;
        let ac = v[ic] - v[ia];
        let cx = ac.dot(ux);
        let cy = (ac - ux * cx).length();
        out[ib] = Vec2::new(len, 0.0);
        out[ic] = Vec2::new(cx, cy);
    }
    let lo = out[0].min(out[1]).min(out[2]);
    out.map(|p| p - lo)
}

/// Built atlases, in memory, keyed by mesh content, scale and texel size (see module doc).
#[derive(Default)]
pub struct AtlasCache {
    atlases: HashMap<u64, Arc<MeshAtlas>>,
    /// How many atlases were packed (cache misses), for tests and logs.
    pub packed: u32,
}

impl AtlasCache {
    /// The atlas of a mesh, packed on first use.
    pub fn get(
        &mut self,
        name: &str,
        positions: &[Vec3],
        indices: &[u32],
        scale: Vec3,
        texel_m: f32,
    ) -> Result<Arc<MeshAtlas>, AtlasError> {
        self.get_sequence(name, &[positions], indices, scale, texel_m)
    }

    /// The shared atlas of an OBJ sequence's frames ([`build_sequence_atlas`]), packed on
    /// first use; one frame is the atlas of [`Self::get`].
    pub fn get_sequence(
        &mut self,
        name: &str,
        frames: &[&[Vec3]],
        indices: &[u32],
        scale: Vec3,
        texel_m: f32,
    ) -> Result<Arc<MeshAtlas>, AtlasError> {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        frames.len().hash(&mut h);
        for positions in frames {
            positions.len().hash(&mut h);
            for p in *positions {
                p.to_array().map(f32::to_bits).hash(&mut h);
            }
        }
        indices.hash(&mut h);
        scale.to_array().map(f32::to_bits).hash(&mut h);
        texel_m.to_bits().hash(&mut h);
        let key = h.finish();
        if let Some(a) = self.atlases.get(&key) {
            return Ok(a.clone());
        }
        let atlas = Arc::new(build_sequence_atlas(name, frames, indices, scale, texel_m)?);
        self.packed += 1;
        self.atlases.insert(key, atlas.clone());
        Ok(atlas)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn random_soup(n: usize, seed: u64) -> (Vec<Vec3>, Vec<u32>) {
        let mut s = seed;
        let mut r = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut pos = Vec::new();
        for i in 0..n {
            let base = Vec3::new(r(), r(), r()) * 4.0;
            // Mix of ordinary, tiny, sliver and degenerate triangles.
            let size = [0.3, 0.002, 0.05][i % 3];
            let a = base;
            let b = base + Vec3::new(r(), r(), r()) * size;
            let c = match i % 7 {
                0 => a,                  // degenerate: segment
                1 => a + (b - a) * 0.5,  // collinear
                2 => b + Vec3::X * 1e-4, // sliver
                _ => base + Vec3::new(r(), r(), r()) * size,
            };
            pos.extend([a, b, c]);
        }
        let idx = (0..pos.len() as u32).collect();
        (pos, idx)
    }

    fn check_invariants(atlas: &MeshAtlas, pos: &[Vec3], idx: &[u32], scale: Vec3) {
        let mut seen = HashSet::new();
        for t in 0..atlas.triangles.len() {
            let texels = atlas.texels(t);
            assert!(!texels.is_empty(), "triangle {t} owns no texel");
            for px in texels {
                assert!(px.0 < atlas.width && px.1 < atlas.height);
                assert!(seen.insert(px), "texel {px:?} owned twice (triangle {t})");
            }
            // Density: atlas edge lengths are world lengths / texel_m (isometric layout).
            let tri = &atlas.triangles[t];
            for e in 0..3 {
                let w =
                    (pos[idx[3 * t + e] as usize] - pos[idx[3 * t + (e + 1) % 3] as usize]) * scale;
                let a = tri.uv[e].distance(tri.uv[(e + 1) % 3]) * atlas.texel_m;
                assert!(
                    (a - w.length()).abs() <= 1e-3 * (1.0 + w.length()),
                    "triangle {t} edge {e}: atlas {a} m vs world {} m",
                    w.length()
                );
            }
        }
    }

    #[test]
    fn soup_texel_sets_are_disjoint_and_nonempty() {
        let (pos, idx) = random_soup(600, 7);
        let scale = Vec3::new(1.0, 2.0, 0.5);
        let atlas = build_atlas("soup", &pos, &idx, scale, 0.01).expect("atlas");
        check_invariants(&atlas, &pos, &idx, scale);
    }

    #[test]
    fn cornell_atlas_meets_the_density_bound() {
        let scene = crate::scene::load_scene_arg(None).expect("cornell");
        let voxel_m = 1.0 / 64.0;
        let texel_m = texel_size_for_voxel(voxel_m);
        // Hole-free bound of the module doc: ε = h·√2/2 ≤ 0.36 v.
        assert!(texel_m * std::f32::consts::FRAC_1_SQRT_2 <= 0.36 * voxel_m);
        for o in &scene.objects {
            let m = &scene.meshes[o.mesh];
            let s = o.transform.scale;
            let atlas = build_atlas(&m.name, &m.positions, &m.indices, s, texel_m).expect("atlas");
            check_invariants(&atlas, &m.positions, &m.indices, s);
            assert!(atlas.cell_efficiency() > 0.5, "{}", atlas.cell_efficiency());
        }
    }

    #[test]
    fn cache_packs_each_mesh_once() {
        let (pos, idx) = random_soup(50, 3);
        let mut cache = AtlasCache::default();
        let a = cache.get("a", &pos, &idx, Vec3::ONE, 0.01).expect("atlas");
        let b = cache.get("a", &pos, &idx, Vec3::ONE, 0.01).expect("atlas");
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(cache.packed, 1);
        cache
            .get("a", &pos, &idx, Vec3::splat(2.0), 0.01)
            .expect("atlas");
        assert_eq!(cache.packed, 2);
    }

    /// Frame `f`'s 3D sample of every texel triangle `t` owns: the closest triangle point to
    /// the texel centre (barycentric in the atlas) carried to that frame's vertices.
    fn frame_samples(atlas: &MeshAtlas, t: usize, p: [Vec3; 3]) -> Vec<Vec3> {
        let uv = atlas.triangles[t].uv;
        atlas
            .texels(t)
            .into_iter()
            .map(|(i, j)| {
                let (_, b) = closest_point(uv, Vec2::new(i as f32 + 0.5, j as f32 + 0.5));
                p[0] * b[0] + p[1] * b[1] + p[2] * b[2]
            })
            .collect()
    }

    /// The largest distance from a point of any triangle of any frame to the nearest of
    /// that frame's samples of the triangle (dense barycentric grid of points).
    fn worst_gap(atlas: &MeshAtlas, frames: &[Vec<Vec3>], idx: &[u32]) -> f32 {
        let mut worst = 0.0f32;
        for positions in frames {
            for (t, tri) in idx.chunks_exact(3).enumerate() {
                let p = [0, 1, 2].map(|k| positions[tri[k] as usize]);
                let samples = frame_samples(atlas, t, p);
                const N: u32 = 40;
                for i in 0..=N {
                    for j in 0..=N - i {
                        let (b1, b2) = (i as f32 / N as f32, j as f32 / N as f32);
                        let q = p[0] + (p[1] - p[0]) * b1 + (p[2] - p[0]) * b2;
                        let d = samples
                            .iter()
                            .map(|s| s.distance(q))
                            .fold(f32::INFINITY, f32::min);
                        worst = worst.max(d);
                    }
                }
            }
        }
        worst
    }

    /// A unit quad (two triangles) scaled by `(sx, sy)` in its plane, tilted out of the
    /// axes so no layout is trivially axis-aligned.
    fn quad_frame(sx: f32, sy: f32) -> Vec<Vec3> {
        let tilt = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.4, 0.3, 0.2);
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .map(|(x, y)| tilt * Vec3::new(x * sx, y * sy, 0.0) * 0.1)
            .to_vec()
    }

    #[test]
    fn sequence_atlas_has_no_holes_in_any_frame() {
        let idx = [0u32, 1, 2, 0, 2, 3];
        let voxel_m = 1.0 / 64.0;
        let texel_m = texel_size_for_voxel(voxel_m);
        // The density test's hole-free bound: every surface point within h·√2/2 of a sample.
        let bound = texel_m * std::f32::consts::FRAC_1_SQRT_2;
        assert!(bound <= 0.36 * voxel_m);
        let sequences: [(&str, Vec<Vec<Vec3>>); 2] = [
            // Stretched 1x -> 3x along one axis over the frames.
            (
                "stretch",
                (0..5)
                    .map(|f| quad_frame(1.0 + 0.5 * f as f32, 1.0))
                    .collect(),
            ),
            // Stretched along x, then along y: no frame dominates the others, so the
            // layout must be scaled (s = 1.5 from the 2x2 frame).
            (
                "cross",
                [(1.0, 1.0), (3.0, 1.0), (1.0, 3.0), (2.0, 2.0)]
                    .map(|(x, y)| quad_frame(x, y))
                    .to_vec(),
            ),
        ];
        for (name, frames) in &sequences {
            let refs: Vec<&[Vec3]> = frames.iter().map(Vec::as_slice).collect();
            let atlas = build_sequence_atlas(name, &refs, &idx, Vec3::ONE, texel_m).expect("atlas");
            let gap = worst_gap(&atlas, frames, &idx);
            println!(
                "{name}: worst gap {gap} m, bound {bound} m, {}x{} texels",
                atlas.width, atlas.height
            );
            // 1e-4 relative: f32 rounding of the samples.
            assert!(gap <= bound * 1.0001, "{name}: gap {gap} > {bound}");
            // Texel sets stay disjoint and non-empty.
            let mut seen = HashSet::new();
            for t in 0..atlas.triangles.len() {
                let texels = atlas.texels(t);
                assert!(!texels.is_empty());
                assert!(texels.into_iter().all(|px| seen.insert(px)));
            }
            // The same frames through a one-frame atlas of frame 0 (the thesis's shared
            // atlas, laid out once) leave holes: the test can tell the two apart.
            let naive = build_atlas(name, &frames[0], &idx, Vec3::ONE, texel_m).expect("atlas");
            let naive_gap = worst_gap(&naive, frames, &idx);
            assert!(
                naive_gap > 1.5 * bound,
                "{name}: frame-0 atlas gap {naive_gap} unexpectedly within {bound}"
            );
        }
    }

    #[test]
    fn max_stretch_is_the_largest_singular_value() {
        let uv = [Vec2::ZERO, Vec2::new(2.0, 0.0), Vec2::new(0.0, 1.0)];
        // (u, v) -> (3u, 0.5v, 0): σ = 3.
        let p = [
            Vec3::ZERO,
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(0.0, 0.5, 0.0),
        ];
        assert!((max_stretch(uv, &p) - 3.0).abs() < 1e-5);
        // A rotation is isometric.
        let r = glam::Quat::from_rotation_y(0.7);
        let q = uv.map(|u| r * u.extend(0.0));
        assert!((max_stretch(uv, &q) - 1.0).abs() < 1e-5);
        // Degenerate layout: the edge ratio.
        let seg = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.5, 0.0)];
        let ps = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        assert!((max_stretch(seg, &ps) - 2.0).abs() < 1e-5);
    }

    #[test]
    fn one_frame_sequence_equals_the_mesh_atlas() {
        let (pos, idx) = random_soup(60, 11);
        let a = build_atlas("a", &pos, &idx, Vec3::ONE, 0.01).expect("atlas");
        let b = build_sequence_atlas("a", &[&pos], &idx, Vec3::ONE, 0.01).expect("atlas");
        assert_eq!(a, b);
        assert_eq!(
            build_sequence_atlas("a", &[], &idx, Vec3::ONE, 0.01),
            Err(AtlasError::NoFrames { mesh: "a".into() })
        );
    }

    #[test]
    fn closest_point_handles_degenerate_triangles() {
        let seg = [Vec2::ZERO, Vec2::new(2.0, 0.0), Vec2::new(1.0, 0.0)];
        let (q, b) = closest_point(seg, Vec2::new(1.5, 1.0));
        assert!((q - Vec2::new(1.5, 0.0)).length() < 1e-6);
        assert!((b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let pt = [Vec2::ONE; 3];
        assert_eq!(closest_point(pt, Vec2::ZERO).0, Vec2::ONE);
    }

    #[test]
    fn bad_input_is_reported() {
        assert_eq!(
            build_atlas("m", &[Vec3::ZERO], &[0, 0, 1], Vec3::ONE, 0.1),
            Err(AtlasError::BadTriangle {
                mesh: "m".into(),
                triangle: 0
            })
        );
        assert!(build_atlas("m", &[], &[], Vec3::ONE, 0.0).is_err());
    }
}
