//! Triangle meshes, bounding boxes, and the procedural meshes scene files can name with
//! `builtin = "…"`.

use glam::{Mat4, Vec2, Vec3};

/// Axis-aligned bounding box. An empty box has `min > max` (see [`Aabb::EMPTY`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The box that contains nothing; the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.including(*p))
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn including(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Edge lengths; zero for an empty box.
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// The box around the transformed box (its 8 corners): conservative under rotation.
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let mut out = Aabb::EMPTY;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out = out.including(m.transform_point3(c));
        }
        out
    }
}

/// A range of a mesh's index buffer drawn with one material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SubMesh {
    /// First index (into [`Mesh::indices`]).
    pub first_index: u32,
    pub index_count: u32,
    /// Index into [`super::Scene::materials`], before any per-object override
    /// (see [`super::Object::materials`]).
    pub material: usize,
}

/// An indexed triangle mesh in object space. Positions, normals and uvs share one index.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// The OBJ path or `builtin:NAME`; for logs and the UI.
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position: from the OBJ, or area-weighted when the OBJ has none.
    pub normals: Vec<Vec3>,
    /// Texture coordinates (OBJ convention: v up), one per position, if the file has them.
    pub uvs: Option<Vec<Vec2>>,
    /// Three per triangle, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
    pub submeshes: Vec<SubMesh>,
    /// Object-space bounds of `positions`.
    pub aabb: Aabb,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Recomputes [`Mesh::aabb`] from the positions.
    pub(crate) fn update_aabb(&mut self) {
        self.aabb = Aabb::from_points(&self.positions);
    }
}

/// Area-weighted vertex normals: each triangle adds its unnormalized cross product (whose
/// length is twice its area) to its three vertices, so large faces dominate and degenerate
/// (zero-area) triangles contribute nothing. A vertex touched by no non-degenerate triangle
/// gets +Y rather than NaN.
pub fn area_weighted_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let (Some(pa), Some(pb), Some(pc)) = (positions.get(a), positions.get(b), positions.get(c))
        else {
            continue;
        };
        let n = (*pb - *pa).cross(*pc - *pa);
        if !n.is_finite() {
            continue;
        }
        acc[a] += n;
        acc[b] += n;
        acc[c] += n;
    }
    acc.into_iter()
        .map(|n| {
            let u = n.normalize_or_zero();
            if u == Vec3::ZERO {
                Vec3::Y
            } else {
                u
            }
        })
        .collect()
}

/// Rewinds every triangle whose winding disagrees with its vertex normals (the face normal
/// (b − a) × (c − a) points away from n_a + n_b + n_c) by swapping its last two indices, so
/// that [`Mesh::indices`]' "counter-clockwise seen from the front" holds for files whose
/// normals and winding disagree; returns how many it rewound. The normals decide because they
/// are what the G-buffer shades, what emission leaves from (docs/ARCHITECTURE.md, "Units") and
/// what Mitsuba 3's area emitter takes as its front when it renders voxgi's export; the
/// consumers of the winding alone (the emitter list's e₁ × e₂, the voxel normal volume) then
/// agree with them. Flattened scenes keep the winding of mirroring transforms while
/// transforming the normals correctly: two of the Modern Hall's four window emitters (39% of
/// its emitted power) are such triangles and lit the outside of the building before
/// (docs/measurements/real-scenes.md, "Where the Modern Hall's light went"). Swapping b and c
/// keeps each vertex's normal and texture coordinates; the G-buffer's tangent frame comes from
/// screen-space derivatives, which the winding does not enter. Degenerate triangles, normals
/// that cancel, and indices out of range are left alone.
pub fn orient_to_normals(positions: &[Vec3], normals: &[Vec3], indices: &mut [u32]) -> usize {
    let mut rewound = 0;
    for tri in indices.chunks_exact_mut(3) {
        let at = |k: usize| {
            let i = tri[k] as usize;
            positions.get(i).copied().zip(normals.get(i).copied())
        };
        let (Some((a, na)), Some((b, nb)), Some((c, nc))) = (at(0), at(1), at(2)) else {
            continue;
        };
        if (b - a).cross(c - a).dot(na + nb + nc) < 0.0 {
            tri.swap(1, 2);
            rewound += 1;
        }
    }
    rewound
}

/// The order in which to read a triangle's corners after transforming them by `model` so
/// that the world-space winding keeps the front [`orient_to_normals`] gave it: reversed
/// (0, 2, 1) where `model` mirrors (a negative determinant, e.g. `scale = [-1, 1, 1]`), whose
/// normals, transformed by the inverse transpose, still point to the front while the
/// transformed positions turn the winding around.
pub fn corner_order(model: &Mat4) -> [usize; 3] {
    if glam::Mat3::from_mat4(*model).determinant() < 0.0 {
        [0, 2, 1]
    } else {
        [0, 1, 2]
    }
}

/// Names accepted by `builtin = "…"` in `[[objects]]`.
pub const BUILTIN_MESH_NAMES: &[&str] = &[
    "cube",
    "quad",
    "sphere",
    "cornell_walls",
    "cornell_short_block",
    "cornell_tall_block",
];

/// A procedural mesh before its materials are registered in a scene: each part is a
/// submesh with its own material.
pub(crate) struct ShapeParts {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
    /// (first index, count, material) with material a [`BuiltinMaterial`].
    pub parts: Vec<(u32, u32, BuiltinMaterial)>,
}

/// Materials of the procedural meshes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum BuiltinMaterial {
    /// Mitsuba's default `diffuse` reflectance (0.5), so exported scenes match.
    Default,
    CornellWhite,
    CornellRed,
    CornellGreen,
}

impl BuiltinMaterial {
    pub fn name(self) -> &'static str {
        match self {
            BuiltinMaterial::Default => "default",
            BuiltinMaterial::CornellWhite => "cornell_white",
            BuiltinMaterial::CornellRed => "cornell_red",
            BuiltinMaterial::CornellGreen => "cornell_green",
        }
    }

    /// Lambert reflectance (linear RGB). The Cornell values are those of the widely used
    /// Cornell-box scene files (white 0.73, red (0.63, 0.065, 0.05), green (0.14, 0.45, 0.091)).
    pub fn albedo(self) -> Vec3 {
        match self {
            BuiltinMaterial::Default => Vec3::splat(0.5),
            BuiltinMaterial::CornellWhite => Vec3::splat(0.73),
            BuiltinMaterial::CornellRed => Vec3::new(0.63, 0.065, 0.05),
            BuiltinMaterial::CornellGreen => Vec3::new(0.14, 0.45, 0.091),
        }
    }
}

pub(crate) fn builtin_shape(name: &str) -> Option<ShapeParts> {
    match name {
        "cube" => Some(cube()),
        "quad" => Some(quad()),
        "sphere" => Some(sphere(48, 24)),
        "cornell_walls" => Some(cornell_walls()),
        "cornell_short_block" => Some(cornell_block(&CORNELL_SHORT_BLOCK_MM)),
        "cornell_tall_block" => Some(cornell_block(&CORNELL_TALL_BLOCK_MM)),
        _ => None,
    }
}

/// Builds flat-shaded quads (each quad: 4 corners counter-clockwise seen from the front).
struct QuadBuilder {
    shape: ShapeParts,
}

impl QuadBuilder {
    fn new() -> Self {
        QuadBuilder {
            shape: ShapeParts {
                positions: Vec::new(),
                normals: Vec::new(),
                uvs: Vec::new(),
                indices: Vec::new(),
                parts: Vec::new(),
            },
        }
    }

    fn quad(&mut self, c: [Vec3; 4], material: BuiltinMaterial) {
        let s = &mut self.shape;
        let base = s.positions.len() as u32;
        // Sum of the two triangles' cross products: robust for slightly non-planar quads
        // (the published Cornell walls are not exactly planar).
        let n = ((c[1] - c[0]).cross(c[2] - c[0]) + (c[2] - c[0]).cross(c[3] - c[0]))
            .normalize_or_zero();
        for (i, p) in c.iter().enumerate() {
            s.positions.push(*p);
            s.normals.push(n);
            s.uvs.push(
                [
                    Vec2::new(0.0, 0.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(0.0, 1.0),
                ][i],
            );
        }
        let first = s.indices.len() as u32;
        s.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        match s.parts.last_mut() {
            Some(last) if last.2 == material && last.0 + last.1 == first => last.1 += 6,
            _ => s.parts.push((first, 6, material)),
        }
    }
}

/// Unit cube centered at the origin (edges 1 m), outward normals.
fn cube() -> ShapeParts {
    let mut b = QuadBuilder::new();
    let h = 0.5;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array({
                let mut a = [0.0; 3];
                a[axis] = sign;
                a
            });
            // Two tangents with t × s = n, so the corners run counter-clockwise around n.
            let t = Vec3::from_array({
                let mut a = [0.0; 3];
                a[(axis + 1) % 3] = 1.0;
                a
            });
            let s = n.cross(t);
            let c = n * h;
            b.quad(
                [
                    c - t * h - s * h,
                    c + t * h - s * h,
                    c + t * h + s * h,
                    c - t * h + s * h,
                ],
                BuiltinMaterial::Default,
            );
        }
    }
    b.shape
}

/// Unit square in the XZ plane centered at the origin, facing +Y.
fn quad() -> ShapeParts {
    let mut b = QuadBuilder::new();
    b.quad(
        [
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, -0.5),
            Vec3::new(-0.5, 0.0, -0.5),
        ],
        BuiltinMaterial::Default,
    );
    b.shape
}

/// UV sphere of radius 0.5 centered at the origin (diameter 1 m, like the cube).
fn sphere(segments: u32, rings: u32) -> ShapeParts {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let theta = v * std::f32::consts::PI;
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            let phi = u * std::f32::consts::TAU;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(0.5 * n);
            normals.push(n);
            uvs.push(Vec2::new(u, 1.0 - v));
        }
    }
    let mut indices = Vec::new();
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            // Counter-clockwise seen from outside; skip the degenerate triangles at the poles.
            if r != 0 {
                indices.extend_from_slice(&[a, b, a + 1]);
            }
            if r != rings - 1 {
                indices.extend_from_slice(&[a + 1, b, b + 1]);
            }
        }
    }
    let count = indices.len() as u32;
    ShapeParts {
        positions,
        normals,
        uvs,
        indices,
        parts: vec![(0, count, BuiltinMaterial::Default)],
    }
}

/// Cornell box geometry, in millimeters, from the measurements published at
/// <https://www.graphics.cornell.edu/online/box/data.html>. Right-handed, y up, the camera at
/// negative z looking +z. Each quad is listed as published; the published order is already
/// counter-clockwise seen from inside the box (walls) and from outside (blocks).
const CORNELL_FLOOR_MM: [[f32; 3]; 4] = [
    [552.8, 0.0, 0.0],
    [0.0, 0.0, 0.0],
    [0.0, 0.0, 559.2],
    [549.6, 0.0, 559.2],
];
const CORNELL_CEILING_MM: [[f32; 3]; 4] = [
    [556.0, 548.8, 0.0],
    [556.0, 548.8, 559.2],
    [0.0, 548.8, 559.2],
    [0.0, 548.8, 0.0],
];
const CORNELL_BACK_MM: [[f32; 3]; 4] = [
    [549.6, 0.0, 559.2],
    [0.0, 0.0, 559.2],
    [0.0, 548.8, 559.2],
    [556.0, 548.8, 559.2],
];
/// Green; x ≈ 0 appears on the right of the published camera.
const CORNELL_RIGHT_MM: [[f32; 3]; 4] = [
    [0.0, 0.0, 559.2],
    [0.0, 0.0, 0.0],
    [0.0, 548.8, 0.0],
    [0.0, 548.8, 559.2],
];
/// Red.
const CORNELL_LEFT_MM: [[f32; 3]; 4] = [
    [552.8, 0.0, 0.0],
    [549.6, 0.0, 559.2],
    [556.0, 548.8, 559.2],
    [556.0, 548.8, 0.0],
];
const CORNELL_SHORT_BLOCK_MM: [[[f32; 3]; 4]; 5] = [
    [
        [130.0, 165.0, 65.0],
        [82.0, 165.0, 225.0],
        [240.0, 165.0, 272.0],
        [290.0, 165.0, 114.0],
    ],
    [
        [290.0, 0.0, 114.0],
        [290.0, 165.0, 114.0],
        [240.0, 165.0, 272.0],
        [240.0, 0.0, 272.0],
    ],
    [
        [130.0, 0.0, 65.0],
        [130.0, 165.0, 65.0],
        [290.0, 165.0, 114.0],
        [290.0, 0.0, 114.0],
    ],
    [
        [82.0, 0.0, 225.0],
        [82.0, 165.0, 225.0],
        [130.0, 165.0, 65.0],
        [130.0, 0.0, 65.0],
    ],
    [
        [240.0, 0.0, 272.0],
        [240.0, 165.0, 272.0],
        [82.0, 165.0, 225.0],
        [82.0, 0.0, 225.0],
    ],
];
const CORNELL_TALL_BLOCK_MM: [[[f32; 3]; 4]; 5] = [
    [
        [423.0, 330.0, 247.0],
        [265.0, 330.0, 296.0],
        [314.0, 330.0, 456.0],
        [472.0, 330.0, 406.0],
    ],
    [
        [423.0, 0.0, 247.0],
        [423.0, 330.0, 247.0],
        [472.0, 330.0, 406.0],
        [472.0, 0.0, 406.0],
    ],
    [
        [472.0, 0.0, 406.0],
        [472.0, 330.0, 406.0],
        [314.0, 330.0, 456.0],
        [314.0, 0.0, 456.0],
    ],
    [
        [314.0, 0.0, 456.0],
        [314.0, 330.0, 456.0],
        [265.0, 330.0, 296.0],
        [265.0, 0.0, 296.0],
    ],
    [
        [265.0, 0.0, 296.0],
        [265.0, 330.0, 296.0],
        [423.0, 330.0, 247.0],
        [423.0, 0.0, 247.0],
    ],
];

fn mm_to_m(q: &[[f32; 3]; 4]) -> [Vec3; 4] {
    q.map(|p| Vec3::from_array(p) / 1000.0)
}

/// Floor, ceiling, back, left (red) and right (green) walls, in meters, facing into the box.
/// The front is open; there is no area light (voxgi lights the box with a spot or point light).
fn cornell_walls() -> ShapeParts {
    let mut b = QuadBuilder::new();
    b.quad(mm_to_m(&CORNELL_FLOOR_MM), BuiltinMaterial::CornellWhite);
    b.quad(mm_to_m(&CORNELL_CEILING_MM), BuiltinMaterial::CornellWhite);
    b.quad(mm_to_m(&CORNELL_BACK_MM), BuiltinMaterial::CornellWhite);
    b.quad(mm_to_m(&CORNELL_LEFT_MM), BuiltinMaterial::CornellRed);
    b.quad(mm_to_m(&CORNELL_RIGHT_MM), BuiltinMaterial::CornellGreen);
    b.shape
}

/// A block (top and four sides; it stands on the floor, so no bottom), in meters.
fn cornell_block(quads: &[[[f32; 3]; 4]; 5]) -> ShapeParts {
    let mut b = QuadBuilder::new();
    for q in quads {
        b.quad(mm_to_m(q), BuiltinMaterial::CornellWhite);
    }
    b.shape
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_of_a_known_triangle() {
        // Right triangle in the XY plane, counter-clockwise seen from +Z.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let n = area_weighted_normals(&p, &[0, 1, 2]);
        for v in n {
            assert!((v - Vec3::Z).length() < 1e-6, "{v}");
        }
        // Clockwise: -Z.
        let n = area_weighted_normals(&p, &[0, 2, 1]);
        assert!((n[0] + Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn triangles_are_rewound_to_face_their_vertex_normals() {
        // Counter-clockwise seen from +Z, so the face normal is +Z.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(5.0, 5.0, 0.0)];
        // Normals toward -Z: the triangle is rewound to (0, 2, 1), whose face normal is -Z.
        let mut idx = [0, 1, 2];
        assert_eq!(orient_to_normals(&p, &[-Vec3::Z; 4], &mut idx), 1);
        assert_eq!(idx, [0, 2, 1]);
        let face = (p[2] - p[0]).cross(p[1] - p[0]);
        assert!(face.dot(-Vec3::Z) > 0.0);
        // Agreeing normals, normals that cancel (sum zero), a degenerate triangle and an index
        // out of range are left alone.
        let mut idx = [0, 1, 2];
        assert_eq!(orient_to_normals(&p, &[Vec3::Z; 4], &mut idx), 0);
        assert_eq!(idx, [0, 1, 2]);
        let cancel = [Vec3::Z, -Vec3::Z, Vec3::ZERO, Vec3::ZERO];
        let mut idx = [0, 1, 2, 0, 0, 1, 0, 1, 9];
        assert_eq!(orient_to_normals(&p, &cancel, &mut idx), 0);
        assert_eq!(idx, [0, 1, 2, 0, 0, 1, 0, 1, 9]);
        // Only the disagreeing triangle of two changes.
        let mut idx = [0, 1, 2, 1, 3, 2];
        let n = [Vec3::Z, Vec3::Z, Vec3::Z, -Vec3::Z];
        // (1, 3, 2): face normal ((5,5,0)-(1,0,0)) x ((0,1,0)-(1,0,0)) = +Z, normals sum +2Z: kept.
        assert_eq!(orient_to_normals(&p, &n, &mut idx), 0);
        let n = [-Vec3::Z, -Vec3::Z, -Vec3::Z, Vec3::Z];
        // Now the first sums to -3Z (rewound), the second to -Z (rewound too).
        assert_eq!(orient_to_normals(&p, &n, &mut idx), 2);
        assert_eq!(idx, [0, 2, 1, 1, 2, 3]);
    }

    #[test]
    fn mirroring_transforms_reverse_the_corner_order() {
        assert_eq!(corner_order(&Mat4::IDENTITY), [0, 1, 2]);
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        assert_eq!(corner_order(&mirror), [0, 2, 1]);
        // Two mirrors are a rotation.
        assert_eq!(
            corner_order(&Mat4::from_scale(Vec3::new(-1.0, -2.0, 1.0))),
            [0, 1, 2]
        );
        // The reversed order keeps the face normal where the normals point: +Z in object
        // space stays the front after x is mirrored (normals by the inverse transpose: +Z).
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y].map(|v| mirror.transform_point3(v));
        let [a, b, c] = corner_order(&mirror).map(|k| p[k]);
        assert!((b - a).cross(c - a).z > 0.0);
    }

    #[test]
    fn normals_are_area_weighted() {
        // Vertex 0 shared by a big triangle facing +Z and a small one facing +X.
        let p = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
            Vec3::new(0.0, 0.0, 0.1),
        ];
        let n = area_weighted_normals(&p, &[0, 1, 2, 0, 3, 4]);
        // Weights: area 2 (+Z) vs 0.005 (+X).
        let expected = Vec3::new(0.01, 0.0, 4.0).normalize();
        assert!((n[0] - expected).length() < 1e-5, "{}", n[0]);
    }

    #[test]
    fn degenerate_triangles_give_no_nan() {
        let p = [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let n = area_weighted_normals(&p, &[0, 1, 2]);
        assert!(n
            .iter()
            .all(|v| v.is_finite() && (v.length() - 1.0).abs() < 1e-6));
    }

    #[test]
    fn aabb_union_and_transform() {
        let a = Aabb::from_points(&[Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 3.0)]);
        assert_eq!(a.extent(), Vec3::new(2.0, 2.0, 3.0));
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.union(a), a);
        let m = Mat4::from_translation(Vec3::new(10.0, 0.0, 0.0))
            * Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let t = a.transformed(&m);
        // Rotating +90° about Y maps x → -z and z → x.
        assert!(
            (t.min - Vec3::new(10.0, 0.0, -1.0)).length() < 1e-5,
            "{:?}",
            t
        );
        assert!(
            (t.max - Vec3::new(13.0, 2.0, 1.0)).length() < 1e-5,
            "{:?}",
            t
        );
    }

    fn check_closed_outward(shape: &ShapeParts) {
        let center = Aabb::from_points(&shape.positions).center();
        for tri in shape.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|i| shape.positions[tri[i] as usize]);
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            assert!(n.dot(centroid - center) > 0.0, "inward triangle {tri:?}");
        }
    }

    #[test]
    fn cube_and_sphere_face_outward() {
        check_closed_outward(&cube());
        check_closed_outward(&sphere(16, 8));
        let s = cube();
        for (p, n) in s.positions.iter().zip(&s.normals) {
            assert!(n.dot(*p) > 0.0);
        }
    }

    #[test]
    fn quad_faces_up() {
        let q = quad();
        let [a, b, c] = [0, 1, 2].map(|i| q.positions[q.indices[i] as usize]);
        assert!((b - a).cross(c - a).normalize().abs_diff_eq(Vec3::Y, 1e-6));
    }

    #[test]
    fn cornell_walls_face_into_the_box_and_blocks_face_out() {
        let walls = cornell_walls();
        let center = Vec3::new(0.278, 0.274, 0.280);
        for tri in walls.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|i| walls.positions[tri[i] as usize]);
            let geo = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            assert!(geo.dot(center - centroid) > 0.0, "wall triangle faces out");
        }
        for (p, n) in walls.positions.iter().zip(&walls.normals) {
            assert!(n.dot(center - *p) > 0.0);
        }
        check_closed_outward(&cornell_block(&CORNELL_SHORT_BLOCK_MM));
        check_closed_outward(&cornell_block(&CORNELL_TALL_BLOCK_MM));
        // The red wall is at x ≈ 0.55 m, the green one at x = 0.
        let red = walls
            .parts
            .iter()
            .find(|p| p.2 == BuiltinMaterial::CornellRed);
        let red = red.map(|p| walls.positions[walls.indices[p.0 as usize] as usize]);
        assert!(red.is_some_and(|p| p.x > 0.5));
    }
}
