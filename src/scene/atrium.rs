//! A procedural atrium: the Sponza-scale scene for performance measurements.
//!
//! A rectangular courtyard surrounded by arcades on two floors — columns (a square plinth, a
//! turned base, a shaft with a slight entasis, a flared capital and a square abacus) carrying
//! round arches — gallery floor slabs, outer walls, a roof with an opening over the
//! courtyard, and cloth banners hanging into the courtyard from the upper gallery. About
//! 300 000 triangles in five materials with procedural textures (stone, floor tiles, plaster,
//! red and blue cloth), written as OBJ + MTL + PNG + a scene TOML by
//! `voxgi generate atrium --out DIR` (`tools/atrium` writes `assets/generated/atrium/`, the
//! files `assets/scenes/atrium.toml` loads).
//!
//! Everything is a function of the constants below: no random generator, no clock, no map
//! iteration order, so two runs write the same bytes (the tests check it). Closed solids
//! (plinths, column parts, arch bays, slabs, walls) are watertight and wound outward; the
//! banners are open sheets, two-sided as geometry (a front and a back sheet 5 mm apart,
//! since the renderer draws without back-face culling and coincident sheets would fight in
//! the depth test).

use glam::{Vec2, Vec3};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Half extents of the courtyard (the column lines), meters: x across, z along.
const COURT_HALF_X_M: f32 = 6.0;
const COURT_HALF_Z_M: f32 = 12.0;
/// Distance between column centers along the arcades, meters.
const BAY_M: f32 = 3.0;
/// Outer walls: the inner face's half extents and the thickness, meters.
const WALL_HALF_X_M: f32 = 9.0;
const WALL_HALF_Z_M: f32 = 15.0;
const WALL_THICK_M: f32 = 0.4;
/// Depth of the arcade walls (across the column line) and of the slabs, meters.
const ARCADE_DEPTH_M: f32 = 0.6;
const SLAB_THICK_M: f32 = 0.3;
/// Segments around a column and along its shaft.
const COLUMN_SEGMENTS: u32 = 48;
const SHAFT_RINGS: u32 = 32;
/// Segments of an arch's half circle.
const ARC_SEGMENTS: u32 = 48;
/// Banner grid (across, down) and size, meters.
const BANNER_GRID: (u32, u32) = (24, 64);
const BANNER_SIZE_M: (f32, f32) = (1.6, 3.4);
/// Texture tile size in meters (a texture spans this many meters of wall or floor).
const TILE_M: f32 = 2.0;
/// Texture resolution, texels per side.
const TEXTURE_TEXELS: u32 = 256;

/// One storey of the arcade: where its columns stand and where its arcade wall ends.
struct Storey {
    floor_y_m: f32,
    /// Height of the column (plinth to abacus top) = the arches' springing line.
    column_m: f32,
    /// Top of the arcade wall above the arches.
    top_y_m: f32,
    /// Shaft radius at its foot, meters.
    shaft_radius_m: f32,
}

const STOREYS: [Storey; 2] = [
    Storey {
        floor_y_m: 0.0,
        column_m: 3.2,
        top_y_m: 5.0,
        shaft_radius_m: 0.22,
    },
    Storey {
        floor_y_m: 5.0 + SLAB_THICK_M,
        column_m: 2.6,
        top_y_m: 9.5,
        shaft_radius_m: 0.18,
    },
];

/// The surfaces' materials, in the order the MTL file lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum AtriumMaterial {
    Stone,
    Tiles,
    Plaster,
    ClothRed,
    ClothBlue,
}

impl AtriumMaterial {
    pub const ALL: [AtriumMaterial; 5] = [
        Self::Stone,
        Self::Tiles,
        Self::Plaster,
        Self::ClothRed,
        Self::ClothBlue,
    ];

    /// The MTL name, also the stem of its texture file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Stone => "stone",
            Self::Tiles => "tiles",
            Self::Plaster => "plaster",
            Self::ClothRed => "cloth_red",
            Self::ClothBlue => "cloth_blue",
        }
    }

    /// The cloth's dye (linear RGB); other materials' colors are in [`texel`].
    fn dye(self) -> Vec3 {
        match self {
            Self::ClothRed => Vec3::new(0.50, 0.08, 0.06),
            _ => Vec3::new(0.07, 0.11, 0.45),
        }
    }

    /// The texture's mean albedo (linear RGB) over its texel centers, written
    /// as `Kd` so that a reader without textures sees about the surface's average color.
    pub fn mean_albedo(self) -> Vec3 {
        let n = TEXTURE_TEXELS;
        let sum: Vec3 = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
                texel(self, x / n as f32, y / n as f32)
            })
            .sum();
        sum / (n * n) as f32
    }
}

/// One triangle: per corner the indices of its position, texture coordinate and normal
/// (OBJ's `f p/t/n`, 0-based here), its material and the solid it belongs to.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    pub corners: [[u32; 3]; 3],
    pub material: AtriumMaterial,
    pub solid: u32,
}

/// The generated geometry, in memory (what the OBJ file holds).
#[derive(Default)]
pub struct AtriumModel {
    pub positions: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub normals: Vec<Vec3>,
    pub faces: Vec<Face>,
    /// Per solid: `true` when it is closed (watertight, wound outward), `false` for sheets.
    pub solid_closed: Vec<bool>,
}

/// A corner under construction: position, texture coordinate and normal indices.
type Corner = [u32; 3];

impl AtriumModel {
    fn begin_solid(&mut self, closed: bool) -> u32 {
        self.solid_closed.push(closed);
        self.solid_closed.len() as u32 - 1
    }

    fn pos(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        self.positions.len() as u32 - 1
    }

    fn uv(&mut self, uv: Vec2) -> u32 {
        self.uvs.push(uv);
        self.uvs.len() as u32 - 1
    }

    fn nrm(&mut self, n: Vec3) -> u32 {
        self.normals.push(n.normalize());
        self.normals.len() as u32 - 1
    }

    fn tri(&mut self, material: AtriumMaterial, corners: [Corner; 3]) {
        let solid = self.solid_closed.len() as u32 - 1;
        self.faces.push(Face {
            corners,
            material,
            solid,
        });
    }

    /// Two triangles `a b c`, `a c d` (counter-clockwise seen from outside).
    fn quad(&mut self, material: AtriumMaterial, [a, b, c, d]: [Corner; 4]) {
        self.tri(material, [a, b, c]);
        self.tri(material, [a, c, d]);
    }

    /// Reverses the winding of the faces of `solid` when they enclose a negative volume: the
    /// shapes wind their faces consistently in their own frame (along, up, across), which is
    /// left-handed for some directions; the normals are set from the geometry and need no
    /// change. (The tests check that every closed solid is consistently wound; a flip of a
    /// whole solid cannot hide one inconsistent face.)
    fn orient_outward(&mut self, solid: u32) {
        if self.signed_volume_m3(solid) < 0.0 {
            for f in self.faces.iter_mut().filter(|f| f.solid == solid) {
                f.corners.swap(1, 2);
            }
        }
    }

    /// The volume a closed solid encloses, by the divergence theorem: the sum over its
    /// triangles of det(a, b, c) / 6; positive when wound outward (counter-clockwise seen
    /// from outside).
    pub fn signed_volume_m3(&self, solid: u32) -> f32 {
        self.faces
            .iter()
            .filter(|f| f.solid == solid)
            .map(|f| {
                let [a, b, c] = f.corners.map(|k| self.positions[k[0] as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// An axis-aligned box, a closed solid; texture coordinates are planar, one tile per
    /// [`TILE_M`] meters.
    fn add_box(&mut self, min: Vec3, max: Vec3, material: AtriumMaterial) {
        let solid = self.begin_solid(true);
        let corner = |i: usize| {
            Vec3::new(
                if i & 1 != 0 { max.x } else { min.x },
                if i & 2 != 0 { max.y } else { min.y },
                if i & 4 != 0 { max.z } else { min.z },
            )
        };
        let p: Vec<u32> = (0..8).map(|i| self.pos(corner(i))).collect();
        // Each face: its normal and its four corners (bit indices: x 1, y 2, z 4),
        // counter-clockwise seen from outside.
        let faces: [(Vec3, [usize; 4]); 6] = [
            (Vec3::NEG_X, [0, 4, 6, 2]),
            (Vec3::X, [1, 3, 7, 5]),
            (Vec3::NEG_Y, [0, 1, 5, 4]),
            (Vec3::Y, [2, 6, 7, 3]),
            (Vec3::NEG_Z, [0, 2, 3, 1]),
            (Vec3::Z, [4, 5, 7, 6]),
        ];
        for (n, idx) in faces {
            let ni = self.nrm(n);
            let corners = idx.map(|i| {
                let t = self.uv(planar_uv(corner(i), n));
                [p[i], t, ni]
            });
            self.quad(material, corners);
        }
        self.orient_outward(solid);
    }

    /// A surface of revolution around the vertical axis through `center` (y = 0 there),
    /// closed by flat caps: `profile` lists (radius, height) from bottom to top, radii > 0.
    fn add_lathe(&mut self, center: Vec3, profile: &[(f32, f32)], material: AtriumMaterial) {
        let solid = self.begin_solid(true);
        let segs = COLUMN_SEGMENTS as usize;
        let angle = |j: usize| j as f32 / segs as f32 * std::f32::consts::TAU;
        let mut rings: Vec<Vec<u32>> = Vec::with_capacity(profile.len());
        let mut ring_normals: Vec<Vec<u32>> = Vec::with_capacity(profile.len());
        for (i, &(r, y)) in profile.iter().enumerate() {
            // The profile's tangent by central differences; the outward normal in the (r, y)
            // plane is (dy, -dr).
            let (r0, y0) = profile[i.saturating_sub(1)];
            let (r1, y1) = profile[(i + 1).min(profile.len() - 1)];
            let (dr, dy) = (r1 - r0, y1 - y0);
            let mut ring = Vec::with_capacity(segs);
            let mut normals = Vec::with_capacity(segs);
            for j in 0..segs {
                let (s, c) = angle(j).sin_cos();
                ring.push(self.pos(center + Vec3::new(r * c, y, r * s)));
                normals.push(self.nrm(Vec3::new(dy * c, -dr, dy * s)));
            }
            rings.push(ring);
            ring_normals.push(normals);
        }
        // Side quads; u runs once around (the seam gets its own texture coordinates, the
        // positions are shared so that the solid stays closed).
        let circumference_m = |r: f32| std::f32::consts::TAU * r;
        for i in 0..profile.len() - 1 {
            for j in 0..segs {
                let j1 = (j + 1) % segs;
                let uv = |m: &mut Self, ii: usize, jj: usize| {
                    let (r, y) = profile[ii];
                    let u = jj as f32 / segs as f32 * circumference_m(r).max(0.5) / TILE_M;
                    m.uv(Vec2::new(u, y / TILE_M))
                };
                // Counter-clockwise seen from outside: up first, then around (angle grows from
                // +x toward +z).
                let corners = [(i, j, j), (i + 1, j, j), (i + 1, j1, j + 1), (i, j1, j + 1)]
                    .map(|(ii, jj, ju)| [rings[ii][jj], uv(self, ii, ju), ring_normals[ii][jj]]);
                self.quad(material, corners);
            }
        }
        // Caps: fans around the axis.
        for (ring_i, n) in [(0, Vec3::NEG_Y), (profile.len() - 1, Vec3::Y)] {
            let (r, y) = profile[ring_i];
            let c = self.pos(center + Vec3::Y * y);
            let ni = self.nrm(n);
            let ct = self.uv(Vec2::splat(0.5));
            for j in 0..segs {
                let j1 = (j + 1) % segs;
                let rim = |m: &mut Self, jj: usize| {
                    let (s, co) = angle(jj).sin_cos();
                    m.uv(Vec2::new(0.5 + r * co / TILE_M, 0.5 + r * s / TILE_M))
                };
                let (ta, tb) = (rim(self, j), rim(self, j1));
                let (a, b) = ([rings[ring_i][j], ta, ni], [rings[ring_i][j1], tb, ni]);
                // Seen from below (the bottom cap), the angle runs clockwise.
                let tri = if n.y < 0.0 {
                    [[c, ct, ni], a, b]
                } else {
                    [[c, ct, ni], b, a]
                };
                self.tri(material, tri);
            }
        }
        self.orient_outward(solid);
    }

    /// One arch bay between two column centers: a wall `ARCADE_DEPTH_M` deep from the
    /// springing line `spring_y_m` to `top_y_m`, with a half-circle opening of radius
    /// `radius_m` centered between the columns. `origin` is the first column's center at the
    /// springing height, `along` the unit direction to the next column, `length_m` their
    /// distance. A closed solid: faces front and back, the underside (piers and intrados),
    /// the top and both ends.
    fn add_arch_bay(
        &mut self,
        origin: Vec3,
        along: Vec3,
        length_m: f32,
        top_m: f32,
        radius_m: f32,
    ) {
        let solid = self.begin_solid(true);
        let across = along.cross(Vec3::Y).normalize();
        let half_d = ARCADE_DEPTH_M / 2.0;
        // The underside's profile in (s along, y above the springing line), left to right.
        let mid = length_m / 2.0;
        let mut profile = vec![Vec2::new(0.0, 0.0)];
        for k in 0..=ARC_SEGMENTS {
            let theta = std::f32::consts::PI * (1.0 - k as f32 / ARC_SEGMENTS as f32);
            profile.push(Vec2::new(
                mid + radius_m * theta.cos(),
                radius_m * theta.sin(),
            ));
        }
        profile.push(Vec2::new(length_m, 0.0));
        let at = |s: f32, y: f32, t: f32| origin + along * s + Vec3::Y * y + across * t;
        let world_y = origin.y;
        // Positions: per profile point, bottom front/back and top front/back.
        let ids: Vec<[u32; 4]> = profile
            .iter()
            .map(|p| {
                [
                    self.pos(at(p.x, p.y, half_d)),
                    self.pos(at(p.x, p.y, -half_d)),
                    self.pos(at(p.x, top_m, half_d)),
                    self.pos(at(p.x, top_m, -half_d)),
                ]
            })
            .collect();
        let n_front = self.nrm(across);
        let n_back = self.nrm(-across);
        let n_top = self.nrm(Vec3::Y);
        let mat = AtriumMaterial::Stone;
        for k in 0..profile.len() - 1 {
            let (p0, p1) = (profile[k], profile[k + 1]);
            let (a, b) = (ids[k], ids[k + 1]);
            // Front and back: the strip from the underside up to the top.
            for (side, n) in [(0usize, n_front), (1, n_back)] {
                let uv = |m: &mut Self, s: f32, y: f32| m.uv(Vec2::new(s, world_y + y) / TILE_M);
                let mut corners = [
                    [a[side], uv(self, p0.x, p0.y), n],
                    [b[side], uv(self, p1.x, p1.y), n],
                    [b[side + 2], uv(self, p1.x, top_m), n],
                    [a[side + 2], uv(self, p0.x, top_m), n],
                ];
                // Counter-clockwise seen from the front; the back is seen from behind.
                if side == 1 {
                    corners.reverse();
                }
                self.quad(mat, corners);
            }
            // Underside: its normal points down and toward the opening's center.
            let d = p1 - p0;
            let n2 = Vec2::new(d.y, -d.x).normalize();
            let n_under = self.nrm(along * n2.x + Vec3::Y * n2.y);
            let uv = |m: &mut Self, s: f32, t: f32| m.uv(Vec2::new(s, t) / TILE_M);
            let corners = [
                [a[0], uv(self, p0.x, half_d), n_under],
                [a[1], uv(self, p0.x, -half_d), n_under],
                [b[1], uv(self, p1.x, -half_d), n_under],
                [b[0], uv(self, p1.x, half_d), n_under],
            ];
            self.quad(mat, corners);
            // Top, split at the same abscissae so that its edges meet the front's.
            let corners = [
                [a[2], uv(self, p0.x, half_d), n_top],
                [b[2], uv(self, p1.x, half_d), n_top],
                [b[3], uv(self, p1.x, -half_d), n_top],
                [a[3], uv(self, p0.x, -half_d), n_top],
            ];
            self.quad(mat, corners);
        }
        for (k, n) in [(0, -along), (profile.len() - 1, along)] {
            let ni = self.nrm(n);
            let i = ids[k];
            let uv = |m: &mut Self, t: f32, y: f32| m.uv(Vec2::new(t, world_y + y) / TILE_M);
            let mut corners = [
                [i[0], uv(self, half_d, 0.0), ni],
                [i[1], uv(self, -half_d, 0.0), ni],
                [i[3], uv(self, -half_d, top_m), ni],
                [i[2], uv(self, half_d, top_m), ni],
            ];
            // Counter-clockwise seen from +along; the first end is seen from -along.
            if k == 0 {
                corners.reverse();
            }
            self.quad(mat, corners);
        }
        self.orient_outward(solid);
    }

    /// A column standing at `base` (the floor point of its axis): a square plinth, a turned
    /// base, a shaft with a slight entasis, a flared capital and a square abacus, whose top is
    /// `height_m` above `base`.
    fn add_column(&mut self, base: Vec3, height_m: f32, shaft_r: f32) {
        let plinth_h = 0.18;
        let plinth_half = shaft_r + 0.14;
        self.add_box(
            base + Vec3::new(-plinth_half, 0.0, -plinth_half),
            base + Vec3::new(plinth_half, plinth_h, plinth_half),
            AtriumMaterial::Stone,
        );
        // Turned base: a torus-like bulge over the plinth (a half circle in profile).
        let torus_r = 0.07;
        let base_profile: Vec<(f32, f32)> = (0..=8)
            .map(|k| {
                let a = std::f32::consts::PI * (k as f32 / 8.0 - 0.5);
                (
                    shaft_r + torus_r * a.cos() + 0.01,
                    plinth_h + torus_r * (1.0 + a.sin()),
                )
            })
            .collect();
        self.add_lathe(base, &base_profile, AtriumMaterial::Stone);
        // Shaft from the base's top to the capital, radius shrinking by 15 % with a gentle
        // swell (entasis) a third of the way up.
        let abacus_h = 0.12;
        let capital_h = 0.35;
        let shaft_y0 = plinth_h + 2.0 * torus_r;
        let shaft_y1 = height_m - abacus_h - capital_h;
        let shaft: Vec<(f32, f32)> = (0..=SHAFT_RINGS)
            .map(|k| {
                let t = k as f32 / SHAFT_RINGS as f32;
                let swell = 0.02 * (std::f32::consts::PI * t).sin() * (1.0 - t);
                (
                    shaft_r * (1.0 - 0.15 * t + swell),
                    shaft_y0 + t * (shaft_y1 - shaft_y0),
                )
            })
            .collect();
        self.add_lathe(base, &shaft, AtriumMaterial::Stone);
        // Capital: a neck ring, then a quarter-round flare out to the abacus.
        let top_r = shaft_r * 0.85;
        let capital: Vec<(f32, f32)> = (0..=12)
            .map(|k| {
                let t = k as f32 / 12.0;
                let flare = 1.0 - (1.0 - t * t).sqrt();
                (top_r + 0.02 + flare * 0.16, shaft_y1 + t * capital_h)
            })
            .collect();
        self.add_lathe(base, &capital, AtriumMaterial::Stone);
        let abacus_half = top_r + 0.2;
        self.add_box(
            base + Vec3::new(-abacus_half, height_m - abacus_h, -abacus_half),
            base + Vec3::new(abacus_half, height_m, abacus_half),
            AtriumMaterial::Stone,
        );
    }

    /// A banner hanging from `top_center`, facing `facing` (horizontal), gently curved: a
    /// bulge along its length and a slow ripple across. Two open sheets, front and back, 5 mm
    /// apart with opposite windings and normals.
    fn add_banner(&mut self, top_center: Vec3, facing: Vec3, material: AtriumMaterial) {
        let (nu, nv) = BANNER_GRID;
        let (w, h) = BANNER_SIZE_M;
        let across = Vec3::Y.cross(facing).normalize();
        let point = |u: f32, v: f32| {
            let bulge = 0.12 * (std::f32::consts::PI * v).sin() * v;
            let ripple = 0.04 * (std::f32::consts::TAU * 1.5 * u).sin() * v;
            top_center + across * (u - 0.5) * w - Vec3::Y * v * h + facing * (bulge + ripple)
        };
        let grid = |i: u32, j: u32| point(i as f32 / nu as f32, j as f32 / nv as f32);
        let normal = |i: u32, j: u32| {
            // Central differences of the surface (one-sided at the borders).
            let du = grid((i + 1).min(nu), j) - grid(i.saturating_sub(1), j);
            let dv = grid(i, (j + 1).min(nv)) - grid(i, j.saturating_sub(1));
            let n = dv.cross(du).normalize();
            if n.dot(facing) < 0.0 {
                -n
            } else {
                n
            }
        };
        for side in [1.0f32, -1.0] {
            self.begin_solid(false);
            let base_p = self.positions.len() as u32;
            let base_n = self.normals.len() as u32;
            let base_t = self.uvs.len() as u32;
            for j in 0..=nv {
                for i in 0..=nu {
                    let n = normal(i, j) * side;
                    self.pos(grid(i, j) + n * 0.0025);
                    self.nrm(n);
                    self.uv(Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32));
                }
            }
            let idx = |i: u32, j: u32| j * (nu + 1) + i;
            for j in 0..nv {
                for i in 0..nu {
                    let c = |k: u32| [base_p + k, base_t + k, base_n + k];
                    let q = [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)];
                    // Counter-clockwise seen from the side the sheet's normals point to.
                    let q = if side > 0.0 {
                        [q[0], q[3], q[2], q[1]]
                    } else {
                        q
                    };
                    self.quad(material, q.map(c));
                }
            }
        }
    }
}

/// Planar texture coordinates of a point on a face with normal `n` (axis-aligned).
fn planar_uv(p: Vec3, n: Vec3) -> Vec2 {
    let uv = if n.x.abs() > 0.5 {
        Vec2::new(p.z, p.y)
    } else if n.y.abs() > 0.5 {
        Vec2::new(p.x, p.z)
    } else {
        Vec2::new(p.x, p.y)
    };
    uv / TILE_M
}

/// The column positions of one storey: every [`BAY_M`] along the courtyard's perimeter
/// (corners once), and the arcades as (start column, direction, number of bays).
fn arcade_lines() -> Vec<(Vec3, Vec3, u32)> {
    let bays_x = (2.0 * COURT_HALF_X_M / BAY_M).round() as u32;
    let bays_z = (2.0 * COURT_HALF_Z_M / BAY_M).round() as u32;
    let (hx, hz) = (COURT_HALF_X_M, COURT_HALF_Z_M);
    vec![
        (Vec3::new(-hx, 0.0, -hz), Vec3::Z, bays_z),
        (Vec3::new(hx, 0.0, -hz), Vec3::Z, bays_z),
        (Vec3::new(-hx, 0.0, -hz), Vec3::X, bays_x),
        (Vec3::new(-hx, 0.0, hz), Vec3::X, bays_x),
    ]
}

/// Builds the whole atrium in memory.
pub fn build() -> AtriumModel {
    let mut m = AtriumModel::default();
    let (wx, wz, t) = (WALL_HALF_X_M, WALL_HALF_Z_M, WALL_THICK_M);
    let top_y = STOREYS[1].top_y_m;
    // Ground floor, under the whole building.
    m.add_box(
        Vec3::new(-wx - t, -SLAB_THICK_M, -wz - t),
        Vec3::new(wx + t, 0.0, wz + t),
        AtriumMaterial::Tiles,
    );
    // Outer walls: the long ones full length, the short ones between them.
    for sx in [-1.0f32, 1.0] {
        let x0 = if sx > 0.0 { wx } else { -wx - t };
        m.add_box(
            Vec3::new(x0, 0.0, -wz - t),
            Vec3::new(x0 + t, top_y + SLAB_THICK_M, wz + t),
            AtriumMaterial::Plaster,
        );
        let z0 = if sx > 0.0 { wz } else { -wz - t };
        m.add_box(
            Vec3::new(-wx, 0.0, z0),
            Vec3::new(wx, top_y + SLAB_THICK_M, z0 + t),
            AtriumMaterial::Plaster,
        );
    }
    // Gallery floor and roof: rings between the walls and the arcades' inner faces, the
    // courtyard open (the roof's opening lets the sun in).
    let inner_x = COURT_HALF_X_M - ARCADE_DEPTH_M / 2.0;
    let inner_z = COURT_HALF_Z_M - ARCADE_DEPTH_M / 2.0;
    for (y0, material) in [
        (STOREYS[0].top_y_m, AtriumMaterial::Tiles),
        (top_y, AtriumMaterial::Plaster),
    ] {
        let y1 = y0 + SLAB_THICK_M;
        for s in [-1.0f32, 1.0] {
            let (xa, xb) = if s > 0.0 {
                (inner_x, wx)
            } else {
                (-wx, -inner_x)
            };
            m.add_box(Vec3::new(xa, y0, -wz), Vec3::new(xb, y1, wz), material);
            let (za, zb) = if s > 0.0 {
                (inner_z, wz)
            } else {
                (-wz, -inner_z)
            };
            m.add_box(
                Vec3::new(-inner_x, y0, za),
                Vec3::new(inner_x, y1, zb),
                material,
            );
        }
    }
    // Columns and arches on both floors.
    for storey in &STOREYS {
        let radius_m = BAY_M / 2.0 - storey.shaft_radius_m * 0.85 - 0.2;
        for (start, dir, bays) in arcade_lines() {
            let floor = start + Vec3::Y * storey.floor_y_m;
            for k in 0..=bays {
                let is_corner = k == 0 || k == bays;
                // Corner columns belong to the long (z) arcades only.
                if !(is_corner && dir == Vec3::X) {
                    m.add_column(
                        floor + dir * (k as f32 * BAY_M),
                        storey.column_m,
                        storey.shaft_radius_m,
                    );
                }
                if k < bays {
                    let spring = floor + dir * (k as f32 * BAY_M) + Vec3::Y * storey.column_m;
                    let top = storey.top_y_m - storey.floor_y_m - storey.column_m;
                    m.add_arch_bay(spring, dir, BAY_M, top, radius_m);
                }
            }
        }
    }
    // Banners: hanging into the courtyard from the upper gallery's floor edge, in front of
    // every second bay of the long arcades, red and blue alternating.
    let bays_z = (2.0 * COURT_HALF_Z_M / BAY_M).round() as u32;
    let hang_y = STOREYS[1].floor_y_m - SLAB_THICK_M - 0.1;
    for (i, k) in (1..bays_z).step_by(2).enumerate() {
        let z = -COURT_HALF_Z_M + (k as f32 + 0.5) * BAY_M;
        for s in [-1.0f32, 1.0] {
            let x = s * (COURT_HALF_X_M - ARCADE_DEPTH_M / 2.0 - 0.35);
            let material = if (i + (s > 0.0) as usize).is_multiple_of(2) {
                AtriumMaterial::ClothRed
            } else {
                AtriumMaterial::ClothBlue
            };
            m.add_banner(Vec3::new(x, hang_y, z), Vec3::new(-s, 0.0, 0.0), material);
        }
    }
    m
}

/// The OBJ text of the model: positions, texture coordinates, normals, then the faces
/// grouped by material (`usemtl`), one `o` per material.
pub fn obj_text(m: &AtriumModel, mtl_name: &str) -> String {
    let mut s = String::with_capacity(m.positions.len() * 40 + m.faces.len() * 40);
    let _ = writeln!(
        s,
        "# voxgi procedural atrium ({} triangles); written by `voxgi generate atrium`",
        m.faces.len()
    );
    let _ = writeln!(s, "mtllib {mtl_name}");
    for p in &m.positions {
        let _ = writeln!(s, "v {:.5} {:.5} {:.5}", p.x, p.y, p.z);
    }
    for t in &m.uvs {
        let _ = writeln!(s, "vt {:.5} {:.5}", t.x, t.y);
    }
    for n in &m.normals {
        let _ = writeln!(s, "vn {:.5} {:.5} {:.5}", n.x, n.y, n.z);
    }
    for material in AtriumMaterial::ALL {
        let _ = writeln!(s, "o {}\nusemtl {}", material.name(), material.name());
        for f in m.faces.iter().filter(|f| f.material == material) {
            let c = f
                .corners
                .map(|[p, t, n]| format!("{}/{}/{}", p + 1, t + 1, n + 1));
            let _ = writeln!(s, "f {} {} {}", c[0], c[1], c[2]);
        }
    }
    s
}

/// The MTL text: Lambert materials with their texture (`map_Kd`) and the texture's mean as
/// `Kd`.
pub fn mtl_text() -> String {
    let mut s = String::from("# voxgi procedural atrium materials\n");
    for material in AtriumMaterial::ALL {
        let kd = material.mean_albedo();
        let _ = writeln!(
            s,
            "newmtl {0}\nKd {1:.3} {2:.3} {3:.3}\nKs 0 0 0\nmap_Kd {0}.png\n",
            material.name(),
            kd.x,
            kd.y,
            kd.z
        );
    }
    s
}

/// The scene file for the atrium mesh at `mesh_path` (relative to the scene file).
/// `assets/scenes/atrium.toml` is this text with `../generated/atrium/atrium.obj`.
pub fn scene_toml(mesh_path: &str) -> String {
    format!(
        r#"# The procedural atrium (issue 16): a courtyard with two floors of arcades, banners and a
# roof opening, about 300 000 triangles. Its mesh and textures are generated: run `tools/atrium`
# (or `voxgi generate atrium --out DIR`), which writes them (and this file) deterministically.

[camera]
position = [0.0, 1.7, -11.0]
target = [0.0, 3.5, 4.0]
fov_y_deg = 60.0
near = 0.05
far = 80.0

# The sun, through the roof opening: 6 W/m^2 on a surface facing it.
[[lights]]
kind = "directional"
direction = [0.35, -1.0, 0.25]
irradiance_w_m2 = [6.0, 5.6, 4.8]

# A lamp in the lower gallery (x = -7.5 m, under the gallery floor at y = 5 m):
# E = 4 / 3^2 = 0.44 W/m^2 at the floor below it.
[[lights]]
kind = "point"
position = [-7.5, 3.0, 0.0]
intensity_w_sr = [4.0, 3.2, 2.2]

# A spot in the upper gallery aimed down across the courtyard.
[[lights]]
kind = "spot"
position = [7.5, 8.5, -6.0]
direction = [-0.8, -0.6, 0.3]
intensity_w_sr = [20.0, 18.0, 15.0]
cutoff_deg = 35.0
beam_deg = 25.0

[[objects]]
name = "atrium"
mesh = "{mesh_path}"

[gi]
radius_m = 8.0

# A walk for `voxgi profile --camera-path` and `voxgi bench camera-path`: into the courtyard,
# turning to the lower gallery's lamp, then up to the upper gallery's spot, then to the far end.
[camera_path]
keyframes = [
    {{ time_s = 0.0, position = [0.0, 1.7, -11.0], look_at = [0.0, 3.5, 4.0] }},
    {{ time_s = 2.0, position = [-2.0, 1.7, -4.0], look_at = [-7.5, 2.5, 0.0] }},
    {{ time_s = 4.0, position = [2.0, 1.7, 3.0], look_at = [7.5, 6.0, -4.0] }},
    {{ time_s = 5.0, position = [0.0, 1.7, 8.0], look_at = [0.0, 4.0, 14.0] }},
]
"#
    )
}

/// The generated files, in the order [`write`] writes them.
pub const FILES: [&str; 8] = [
    "atrium.obj",
    "atrium.mtl",
    "atrium.toml",
    "stone.png",
    "tiles.png",
    "plaster.png",
    "cloth_red.png",
    "cloth_blue.png",
];

/// Failure to write the generated files.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    #[error("{}: cannot write the generated file: {source}; check that the directory is writable", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: cannot encode the texture: {source}", path.display())]
    Png {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
}

/// Writes the atrium (OBJ, MTL, scene TOML, textures) into `dir`, creating it; returns the
/// number of triangles.
pub fn write(dir: &Path) -> Result<usize, GenerateError> {
    let write_err = |path: PathBuf| move |source| GenerateError::Write { path, source };
    std::fs::create_dir_all(dir).map_err(write_err(dir.to_path_buf()))?;
    let model = build();
    let put = |name: &str, text: String| {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(write_err(path))
    };
    put("atrium.obj", obj_text(&model, "atrium.mtl"))?;
    put("atrium.mtl", mtl_text())?;
    put("atrium.toml", scene_toml("atrium.obj"))?;
    for material in AtriumMaterial::ALL {
        let path = dir.join(format!("{}.png", material.name()));
        texture(material)
            .save_with_format(&path, image::ImageFormat::Png)
            .map_err(|source| GenerateError::Png { path, source })?;
    }
    Ok(model.faces.len())
}

/// A 32-bit integer hash (Wang/Jenkins style mix) of a lattice point and a seed.
fn hash(x: i32, y: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_215.0
}

/// Tileable value noise in [0, 1] with `period` lattice cells across the texture.
fn value_noise(u: f32, v: f32, period: i32, seed: u32) -> f32 {
    let (x, y) = (u * period as f32, v * period as f32);
    let (x0, y0) = (x.floor() as i32, y.floor() as i32);
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let at = |i: i32, j: i32| hash(i.rem_euclid(period), j.rem_euclid(period), seed);
    let (sx, sy) = (smooth(fx), smooth(fy));
    let top = at(x0, y0) + (at(x0 + 1, y0) - at(x0, y0)) * sx;
    let bottom = at(x0, y0 + 1) + (at(x0 + 1, y0 + 1) - at(x0, y0 + 1)) * sx;
    top + (bottom - top) * sy
}

/// Four octaves of [`value_noise`], in [0, 1].
fn fbm(u: f32, v: f32, seed: u32) -> f32 {
    (0..4i32)
        .map(|o| value_noise(u, v, 4 << o, seed + o as u32) * 0.5f32.powi(o + 1))
        .sum::<f32>()
        / (1.0 - 0.5f32.powi(4))
}

/// The linear albedo of a texture at (u, v) in [0, 1)².
fn texel(material: AtriumMaterial, u: f32, v: f32) -> Vec3 {
    let n = fbm(u, v, material as u32 * 17 + 3);
    match material {
        // Ashlar: rows of blocks, every other row shifted by half a block, thin mortar joints.
        AtriumMaterial::Stone => {
            let row = (v * 4.0).floor();
            let bu = u * 2.0 + 0.5 * (row % 2.0);
            let joint = (v * 4.0).fract() < 0.03 || bu.fract() < 0.015;
            let block_tint = 0.9 + 0.2 * hash(bu.floor() as i32, row as i32, 7);
            if joint {
                Vec3::new(0.35, 0.33, 0.30)
            } else {
                Vec3::new(0.62, 0.55, 0.44) * block_tint * (0.8 + 0.4 * n)
            }
        }
        // Terracotta and cream tiles in a checkerboard, grey grout.
        AtriumMaterial::Tiles => {
            let (tu, tv) = (u * 4.0, v * 4.0);
            if tu.fract() < 0.03 || tv.fract() < 0.03 {
                Vec3::splat(0.3)
            } else if (tu.floor() as i32 + tv.floor() as i32) % 2 == 0 {
                Vec3::new(0.55, 0.27, 0.16) * (0.85 + 0.3 * n)
            } else {
                Vec3::new(0.70, 0.62, 0.48) * (0.85 + 0.3 * n)
            }
        }
        AtriumMaterial::Plaster => Vec3::new(0.66, 0.63, 0.56) * (0.88 + 0.24 * n),
        // Plain weave (alternating warp and weft threads) with a gold band near the hem.
        AtriumMaterial::ClothRed | AtriumMaterial::ClothBlue => {
            let base = material.dye();
            let (x, y) = ((u * 128.0) as i32, (v * 128.0) as i32);
            let weave = if (x + y) % 2 == 0 { 1.08 } else { 0.92 };
            let band = (v * 8.0).fract();
            if (0.80..0.88).contains(&band) {
                Vec3::new(0.60, 0.45, 0.12) * weave
            } else {
                base * weave * (0.9 + 0.2 * n)
            }
        }
    }
}

/// The texture of a material, 8-bit sRGB.
pub fn texture(material: AtriumMaterial) -> image::RgbImage {
    let size = TEXTURE_TEXELS;
    image::RgbImage::from_fn(size, size, |x, y| {
        let c = texel(
            material,
            (x as f32 + 0.5) / size as f32,
            (y as f32 + 0.5) / size as f32,
        );
        image::Rgb(
            c.to_array()
                .map(|l| (linear_to_srgb(l.clamp(0.0, 1.0)) * 255.0).round() as u8),
        )
    })
}

fn linear_to_srgb(l: f32) -> f32 {
    if l <= 0.003_130_8 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests;
