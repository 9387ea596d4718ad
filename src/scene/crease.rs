//! Vertex normals for OBJ meshes without `vn` lines, as modelling tools make them: a triangle
//! is smoothed with its neighbours around a vertex only where they belong together, by
//! smoothing group (`s 1`, `s off`) when the file has groups, else by a crease angle between
//! the face normals. A vertex whose corners get different normals is split, so flat faces stay
//! flat (a cube gets 24 vertices) and curved meshes keep shared vertices.

use glam::Vec3;
use std::collections::HashMap;

/// The default crease angle, degrees: faces meeting at more than this stay sharp.
pub const DEFAULT_CREASE_DEG: f32 = 60.0;

/// How the faces around a vertex are grouped into one smooth normal.
#[derive(Clone, Copy, Debug)]
pub enum Smoothing<'a> {
    /// One smoothing group per triangle (0: `s off`, the triangle is flat): triangles are
    /// smoothed with the neighbours of their own nonzero group.
    Groups(&'a [u32]),
    /// Neighbours whose face normals differ by at most this angle (degrees) are smoothed.
    CreaseDeg(f32),
}

/// A mesh with its vertices split where their corners' normals differ.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitMesh {
    /// For each new vertex, the input vertex it copies (position, uv).
    pub source: Vec<u32>,
    /// Unit normal of each new vertex.
    pub normals: Vec<Vec3>,
    /// The triangles over the new vertices.
    pub indices: Vec<u32>,
}

/// Splits the vertices of the triangles `indices` over `positions` by `smoothing`. Each
/// corner's normal is the area-weighted sum of the face normals of the triangles at its vertex
/// that are smoothed with its own triangle (itself included); corners of a vertex with equal
/// normals share one output vertex.
pub fn split_normals(positions: &[Vec3], indices: &[u32], smoothing: Smoothing<'_>) -> SplitMesh {
    let tris = indices.len() / 3;
    let corner = |t: usize, c: usize| indices[3 * t + c] as usize;
    // Area-weighted (twice the area) and unit face normals; a degenerate triangle has 0.
    let area_n: Vec<Vec3> = (0..tris)
        .map(|t| {
            let p = |c| positions.get(corner(t, c)).copied().unwrap_or(Vec3::ZERO);
            let n = (p(1) - p(0)).cross(p(2) - p(0));
            if n.is_finite() {
                n
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let unit: Vec<Vec3> = area_n.iter().map(|n| n.normalize_or_zero()).collect();
    let incident = incident_triangles(positions.len(), indices);
    let crease_cos = match smoothing {
        Smoothing::CreaseDeg(deg) => deg.clamp(0.0, 180.0).to_radians().cos(),
        Smoothing::Groups(_) => 1.0,
    };
    let smooth_with = |t: usize, g: usize| -> bool {
        t == g
            || match smoothing {
                Smoothing::Groups(groups) => {
                    let (a, b) = (group_of(groups, t), group_of(groups, g));
                    a != 0 && a == b
                }
                // A small tolerance keeps coplanar neighbours together despite rounding.
                Smoothing::CreaseDeg(_) => unit[t].dot(unit[g]) >= crease_cos - 1e-6,
            }
    };
    let mut out = SplitMesh {
        source: Vec::new(),
        normals: Vec::new(),
        indices: Vec::with_capacity(indices.len()),
    };
    let mut seen: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
    for t in 0..tris {
        for c in 0..3 {
            let v = corner(t, c);
            let around = incident.get(v).map_or(&[][..], |a| a.as_slice());
            let sum: Vec3 = around
                .iter()
                .filter(|&&g| smooth_with(t, g as usize))
                .map(|&g| area_n[g as usize])
                .sum();
            let n = first_unit([
                sum,
                area_n[t],
                around.iter().map(|&g| area_n[g as usize]).sum(),
            ]);
            let key = (v as u32, n.to_array().map(f32::to_bits));
            let index = *seen.entry(key).or_insert_with(|| {
                out.source.push(v as u32);
                out.normals.push(n);
                out.source.len() as u32 - 1
            });
            out.indices.push(index);
        }
    }
    out
}

/// The smoothing group of triangle `t` (0, flat, where the list is short).
fn group_of(groups: &[u32], t: usize) -> u32 {
    groups.get(t).copied().unwrap_or(0)
}

/// The first of `candidates` with a direction, normalized; +Y where none has one (as
/// `area_weighted_normals` does for a vertex of degenerate triangles only).
fn first_unit(candidates: [Vec3; 3]) -> Vec3 {
    candidates
        .into_iter()
        .map(Vec3::normalize_or_zero)
        .find(|u| *u != Vec3::ZERO)
        .unwrap_or(Vec3::Y)
}

/// For each vertex, the triangles that use it, in triangle order (each once).
fn incident_triangles(vertices: usize, indices: &[u32]) -> Vec<Vec<u32>> {
    let mut around = vec![Vec::new(); vertices];
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        for &v in tri {
            if let Some(list) = around.get_mut(v as usize) {
                if list.last() != Some(&(t as u32)) {
                    list.push(t as u32);
                }
            }
        }
    }
    around
}

/// The smoothing group of every face of an OBJ file's text, in file order, each repeated
/// once per triangle its polygon is split into (n − 2): `s off` and `s 0` give 0 (flat),
/// `s N` gives N, faces before any `s` line 0. `None` where the file has no `s` line.
pub fn obj_smoothing_groups(text: &str) -> Option<Vec<u32>> {
    let mut any = false;
    let mut group = 0u32;
    let mut per_triangle = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("s") => {
                any = true;
                group = match words.next() {
                    Some("off") | None => 0,
                    Some(n) => n.parse().unwrap_or(0),
                };
            }
            Some("f") => {
                let corners = words.count();
                per_triangle.extend(std::iter::repeat_n(group, corners.saturating_sub(2)));
            }
            _ => {}
        }
    }
    any.then_some(per_triangle)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube: 8 shared corners, 12 triangles, outward winding.
    fn cube() -> (Vec<Vec3>, Vec<u32>) {
        let p = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        #[rustfmt::skip]
        let quads = [
            [0, 2, 3, 1], [4, 5, 7, 6], // z = 0, z = 1
            [0, 1, 5, 4], [2, 6, 7, 3], // y = 0, y = 1
            [0, 4, 6, 2], [1, 3, 7, 5], // x = 0, x = 1
        ];
        let idx = quads
            .iter()
            .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
            .collect();
        (p, idx)
    }

    /// A UV sphere of `rings` × `segments` quads with shared vertices (poles shared too).
    fn sphere(rings: u32, segments: u32) -> (Vec<Vec3>, Vec<u32>) {
        let mut p = vec![Vec3::Y];
        for r in 1..rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..segments {
                let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
                p.push(Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ));
            }
        }
        p.push(Vec3::NEG_Y);
        let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
        let last = p.len() as u32 - 1;
        let mut idx = Vec::new();
        for s in 0..segments {
            idx.extend([0, ring(1, s + 1), ring(1, s)]);
            idx.extend([last, ring(rings - 1, s), ring(rings - 1, s + 1)]);
            for r in 1..rings - 1 {
                let (a, b, c, d) = (
                    ring(r, s),
                    ring(r, s + 1),
                    ring(r + 1, s + 1),
                    ring(r + 1, s),
                );
                idx.extend([a, b, c, a, c, d]);
            }
        }
        (p, idx)
    }

    #[test]
    fn a_cube_gets_24_vertices_with_its_face_normals() {
        let (p, idx) = cube();
        let s = split_normals(&p, &idx, Smoothing::CreaseDeg(DEFAULT_CREASE_DEG));
        assert_eq!(s.normals.len(), 24, "8 corners × 3 faces");
        assert_eq!(s.indices.len(), idx.len());
        for tri in s.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| p[s.source[tri[k] as usize] as usize]);
            let face = (b - a).cross(c - a).normalize();
            for &i in tri {
                assert!(s.normals[i as usize].dot(face) > 1.0 - 1e-6, "a flat face");
            }
        }
        // Above 90° every corner is smooth again: one vertex per corner, the diagonal normal.
        let smooth = split_normals(&p, &idx, Smoothing::CreaseDeg(91.0));
        assert_eq!(smooth.normals.len(), 8);
    }

    #[test]
    fn a_fine_sphere_keeps_its_shared_vertices() {
        let (p, idx) = sphere(24, 48);
        let s = split_normals(&p, &idx, Smoothing::CreaseDeg(DEFAULT_CREASE_DEG));
        assert_eq!(s.normals.len(), p.len(), "no vertex split");
        for (n, &v) in s.normals.iter().zip(&s.source) {
            // Every normal close to the radial direction (the faces are 7.5° apart).
            assert!(n.dot(p[v as usize]) > 0.99, "{n} at {}", p[v as usize]);
        }
    }

    #[test]
    fn smoothing_groups_decide_instead_of_the_angle() {
        let (p, idx) = cube();
        // One group: smooth all around (8 vertices) although the faces meet at 90°.
        let one = vec![1; 12];
        assert_eq!(
            split_normals(&p, &idx, Smoothing::Groups(&one))
                .normals
                .len(),
            8
        );
        // `s off`: flat.
        let off = vec![0; 12];
        assert_eq!(
            split_normals(&p, &idx, Smoothing::Groups(&off))
                .normals
                .len(),
            24
        );
    }

    #[test]
    fn smoothing_groups_are_read_per_triangle() {
        let text = "v 0 0 0\nf 1 2 3\ns 1\nf 1 2 3 4\ns off\nf 1 2 3 4 5\ns 2\nf 1 2 3\n";
        assert_eq!(obj_smoothing_groups(text), Some(vec![0, 1, 1, 0, 0, 0, 2]));
        assert_eq!(obj_smoothing_groups("v 0 0 0\nf 1 2 3\n"), None);
    }
}
