//! Grid placement: the world box, the voxel camera axis and the world→voxel transforms.
//!
//! The voxel camera is orthographic and looks along the box's shortest axis (Thiedemann 2010, §4.5), so
//! the fixed 128·L depth voxels go where the scene is thinnest and x,y resolution is free.
//! Its frame `(u, v, w)` is a cyclic permutation of the world axes (a proper rotation, no
//! mirror): looking along +Z gives `(X, Y, Z)`, along +X gives `(Y, Z, X)`, along +Y gives
//! `(Z, X, Y)`. Depth `w` grows from the near plane at the box's minimum corner.

use glam::{Mat3, Mat4, UVec3, Vec3};

use super::{VoxelError, COLUMN_BITS};

/// Largest accepted x/y resolution (Vulkan guarantees `maxImageDimension2D` ≥ 4096; common
/// desktop GPUs allow 16384).
pub const MAX_RES_XY: u32 = crate::limits::VOXELS.max;
/// Largest accepted number of 128-voxel layers (depth 8192).
pub const MAX_LAYERS: u32 = crate::limits::VOXEL_LAYERS.max;

/// World axis the voxel camera looks along (its depth axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// World axis index (0 = X).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// How [`VoxelGrid::around`] places a grid around a scene box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridDesc {
    /// Number of 128-voxel depth layers; depth `D = 128 · layers`.
    pub layers: u32,
    /// Cap on the x/y resolution. Voxels stay cubic unless the cap is hit.
    pub max_res_xy: u32,
    /// Padding on every side as a fraction of the box's longest edge, so geometry on the box
    /// faces is not clipped by rounding.
    pub pad_fraction: f32,
    /// Additional padding on every side, in voxels.
    pub pad_voxels: f32,
}

impl Default for GridDesc {
    fn default() -> Self {
        Self {
            layers: 1,
            max_res_xy: 512,
            pad_fraction: 0.01,
            pad_voxels: 1.0,
        }
    }
}

/// Placement of the binary voxel grid in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelGrid {
    min: Vec3,
    max: Vec3,
    axis: Axis,
    res_x: u32,
    res_y: u32,
    layers: u32,
}

/// World vector → voxel-camera frame `(u, v, w)` (a cyclic axis permutation).
fn to_frame(axis: Axis, p: Vec3) -> Vec3 {
    match axis {
        Axis::Z => p,
        Axis::X => Vec3::new(p.y, p.z, p.x),
        Axis::Y => Vec3::new(p.z, p.x, p.y),
    }
}

/// Inverse of [`to_frame`].
fn from_frame(axis: Axis, q: Vec3) -> Vec3 {
    match axis {
        Axis::Z => q,
        Axis::X => Vec3::new(q.z, q.x, q.y),
        Axis::Y => Vec3::new(q.y, q.z, q.x),
    }
}

fn check_box(min: Vec3, max: Vec3) -> Result<(), VoxelError> {
    if !(min.is_finite() && max.is_finite()) {
        return Err(VoxelError::NonFiniteBox { min, max });
    }
    if min.cmpgt(max).any() {
        return Err(VoxelError::EmptyBox { min, max });
    }
    Ok(())
}

/// Shortest axis of `size`; ties prefer Z, then Y, then X so a cube keeps the usual
/// "look down Z" camera.
fn shortest_axis(size: Vec3) -> Axis {
    if size.z <= size.x && size.z <= size.y {
        Axis::Z
    } else if size.y <= size.x {
        Axis::Y
    } else {
        Axis::X
    }
}

impl VoxelGrid {
    /// Grid around a scene box `[min, max]` (world meters), padded per `desc`, looking along the
    /// shortest padded axis, with near-cubic voxels.
    ///
    /// A flat box (a floor, a single quad) would give paper-thin voxels; the depth extent is
    /// therefore grown until cubic voxels fit within `desc.max_res_xy`.
    pub fn around(min: Vec3, max: Vec3, desc: &GridDesc) -> Result<Self, VoxelError> {
        check_box(min, max)?;
        check_res(1, 1, desc.layers, desc.max_res_xy)?;
        for (what, value) in [
            ("pad_fraction", desc.pad_fraction),
            ("pad_voxels", desc.pad_voxels),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(VoxelError::BadPadding { what, value });
            }
        }
        let size = max - min;
        let longest = size.max_element();
        if longest <= 0.0 {
            return Err(VoxelError::ZeroExtent { axis: 0, min, max });
        }
        let depth = (COLUMN_BITS * desc.layers) as f32;
        // Padding by whole voxels needs the voxel size, which depends on the padding; solve
        // `ext' = ext + 2·pad_voxels·ext'/D` for the depth axis in closed form. Keep at least
        // a quarter of the depth for the scene.
        let pad_voxels = desc.pad_voxels.min(depth * 0.375);
        let center = 0.5 * (min + max);
        let mut half = 0.5 * size + Vec3::splat(desc.pad_fraction * longest);
        let axis = shortest_axis(half);
        let d = axis.index();
        let longest_half = half.max_element();
        // Cubic voxels need res_xy = extent / (depth_extent / D) ≤ max_res_xy.
        half[d] = half[d].max(longest_half * depth / desc.max_res_xy as f32);
        half[d] /= 1.0 - 2.0 * pad_voxels / depth;
        let edge = 2.0 * half[d] / depth;
        let mut res = [0u32; 2];
        let frame_axes = match axis {
            Axis::Z => [0, 1],
            Axis::X => [1, 2],
            Axis::Y => [2, 0],
        };
        for (r, &a) in res.iter_mut().zip(frame_axes.iter()) {
            let want = 2.0 * (half[a] + pad_voxels * edge);
            let n = (want / edge).ceil().clamp(1.0, desc.max_res_xy as f32) as u32;
            // Grow to exactly n cubic voxels unless the cap forced fewer.
            half[a] = (0.5 * n as f32 * edge).max(0.5 * want);
            *r = n;
        }
        let grid = Self::from_box(
            center - half,
            center + half,
            Some(axis),
            res[0],
            res[1],
            desc.layers,
        )?;
        log::debug!(
            "voxel grid around [{min}, {max}]: axis {axis:?}, {}×{}×{}, voxel {} m",
            grid.res_x,
            grid.res_y,
            grid.depth(),
            grid.voxel_size_m()
        );
        Ok(grid)
    }

    /// Grid on a user box. `axis = None` picks the box's shortest axis (thesis §4.5).
    pub fn from_box(
        min: Vec3,
        max: Vec3,
        axis: Option<Axis>,
        res_x: u32,
        res_y: u32,
        layers: u32,
    ) -> Result<Self, VoxelError> {
        check_box(min, max)?;
        check_res(res_x, res_y, layers, MAX_RES_XY)?;
        let size = max - min;
        for a in 0..3 {
            // `min + size == min` catches boxes too thin for f32 to resolve, not only zero.
            if size[a] <= 0.0 || min[a] + size[a] * 1e-3 == min[a] {
                return Err(VoxelError::ZeroExtent { axis: a, min, max });
            }
        }
        Ok(Self {
            min,
            max,
            axis: axis.unwrap_or_else(|| shortest_axis(size)),
            res_x,
            res_y,
            layers,
        })
    }

    pub fn world_min(&self) -> Vec3 {
        self.min
    }
    pub fn world_max(&self) -> Vec3 {
        self.max
    }
    /// World axis the voxel camera looks along.
    pub fn axis(&self) -> Axis {
        self.axis
    }
    pub fn res_x(&self) -> u32 {
        self.res_x
    }
    pub fn res_y(&self) -> u32 {
        self.res_y
    }
    pub fn layers(&self) -> u32 {
        self.layers
    }
    /// Depth resolution `D = 128 · layers`.
    pub fn depth(&self) -> u32 {
        COLUMN_BITS * self.layers
    }
    /// `(res_x, res_y, D)`.
    pub fn extent_voxels(&self) -> UVec3 {
        UVec3::new(self.res_x, self.res_y, self.depth())
    }

    /// Box extent in the voxel-camera frame `(u, v, w)`, meters.
    fn frame_extent_m(&self) -> Vec3 {
        to_frame(self.axis, self.max - self.min)
    }

    /// Voxel edge lengths in meters, in voxel axis order `(x, y, depth)`.
    pub fn voxel_size_m(&self) -> Vec3 {
        self.frame_extent_m() / self.extent_voxels().as_vec3()
    }

    /// Length of a voxel's space diagonal in meters: the self-intersection offset unit of
    /// thesis §5.3.1.
    pub fn voxel_diagonal_m(&self) -> f32 {
        self.voxel_size_m().length()
    }

    /// World point → continuous voxel coordinates (`[0,res_x) × [0,res_y) × [0,D)` inside).
    /// Computed directly rather than through the 4×4 matrix to keep f32 precision for large
    /// world coordinates.
    pub fn world_to_voxel(&self, p: Vec3) -> Vec3 {
        to_frame(self.axis, p - self.min) * self.voxels_per_meter()
    }

    /// Voxels per meter in voxel axis order `(x, y, depth)`: the scale of
    /// [`Self::world_to_voxel`]. The GPU voxelizer receives this exact f32 vector and repeats
    /// `to_frame(p − min) · scale`, so both sides round identically.
    pub fn voxels_per_meter(&self) -> Vec3 {
        self.extent_voxels().as_vec3() / self.frame_extent_m()
    }

    /// Continuous voxel coordinates → world point.
    pub fn voxel_to_world(&self, v: Vec3) -> Vec3 {
        self.min
            + from_frame(
                self.axis,
                v * (self.frame_extent_m() / self.extent_voxels().as_vec3()),
            )
    }

    /// World direction → voxel-space direction (the linear part of [`Self::world_to_voxel`]),
    /// so that `world_to_voxel(o + t·d) = world_to_voxel(o) + t·dir_world_to_voxel(d)`.
    pub fn dir_world_to_voxel(&self, d: Vec3) -> Vec3 {
        to_frame(self.axis, d) * (self.extent_voxels().as_vec3() / self.frame_extent_m())
    }

    /// Voxel-space direction → world direction.
    pub fn dir_voxel_to_world(&self, d: Vec3) -> Vec3 {
        from_frame(
            self.axis,
            d * (self.frame_extent_m() / self.extent_voxels().as_vec3()),
        )
    }

    /// View matrix V of the voxel camera: eye at the box's minimum corner, looking along +w
    /// (depth), rows = the permuted world axes. A rotation (det +1), not a mirror.
    pub fn view_matrix(&self) -> Mat4 {
        let rot = Mat3::from_cols(
            to_frame(self.axis, Vec3::X),
            to_frame(self.axis, Vec3::Y),
            to_frame(self.axis, Vec3::Z),
        );
        Mat4::from_mat3(rot) * Mat4::from_translation(-self.min)
    }

    /// Orthographic projection P: the view-space box `[0,e_u]×[0,e_v]×[0,e_w]` → GL NDC
    /// `[-1,1]³`, near plane (w = 0) → −1 (thesis §5.3.2 uses GL conventions).
    pub fn projection_matrix(&self) -> Mat4 {
        let e = self.frame_extent_m();
        Mat4::from_translation(Vec3::splat(-1.0)) * Mat4::from_scale(2.0 / e)
    }

    /// The thesis's unit-cube matrix `M = T(½,½,½)·S(½,½,½)·P·V` (§5.3.2): world → `[0,1]³`,
    /// directly a texture coordinate, depth 0 at the near plane.
    pub fn world_to_unit(&self) -> Mat4 {
        Mat4::from_translation(Vec3::splat(0.5))
            * Mat4::from_scale(Vec3::splat(0.5))
            * self.projection_matrix()
            * self.view_matrix()
    }

    /// World → continuous voxel coordinates as a matrix (`S(res_x, res_y, D) · M`).
    pub fn world_to_voxel_matrix(&self) -> Mat4 {
        Mat4::from_scale(self.extent_voxels().as_vec3()) * self.world_to_unit()
    }

    /// World → Vulkan clip space for rasterizing into the column image: x,y ∈ [−1,1] with
    /// NDC y = −1 at texel row 0 (Vulkan's viewport maps −1 to the top row), z ∈ `[0,1]` from
    /// near to far. Equals `(2u−1, 2v−1, w)` of [`Self::world_to_unit`].
    pub fn world_to_clip_vk(&self) -> Mat4 {
        Mat4::from_translation(Vec3::new(-1.0, -1.0, 0.0))
            * Mat4::from_scale(Vec3::new(2.0, 2.0, 1.0))
            * self.world_to_unit()
    }
}

fn check_res(res_x: u32, res_y: u32, layers: u32, max_xy: u32) -> Result<(), VoxelError> {
    let ok_xy = |r: u32| (1..=MAX_RES_XY).contains(&r) && r <= max_xy;
    if !(ok_xy(res_x) && ok_xy(res_y) && (1..=MAX_LAYERS).contains(&layers) && max_xy >= 1) {
        return Err(VoxelError::BadResolution {
            res_x,
            res_y,
            layers,
            max: max_xy.min(MAX_RES_XY),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn picks_shortest_axis_and_cubic_voxels() {
        // Sponza-like box: Y is shortest.
        let g = VoxelGrid::around(
            Vec3::new(-15.0, 0.0, -9.0),
            Vec3::new(15.0, 12.0, 9.0),
            &GridDesc::default(),
        )
        .unwrap();
        assert_eq!(g.axis(), Axis::Y);
        assert_eq!(g.depth(), 128);
        let s = g.voxel_size_m();
        assert!(s.max_element() / s.min_element() < 1.001, "{s}");
        // Padding keeps the scene inside.
        let lo = g.world_to_voxel(Vec3::new(-15.0, 0.0, -9.0));
        let hi = g.world_to_voxel(Vec3::new(15.0, 12.0, 9.0));
        for v in [lo, hi] {
            assert!(v.cmpge(Vec3::splat(1.0)).all());
            assert!(v.cmplt(g.extent_voxels().as_vec3() - 1.0).all(), "{v}");
        }
    }

    #[test]
    fn flat_box_gets_cubic_voxels_within_cap() {
        let desc = GridDesc {
            max_res_xy: 256,
            ..GridDesc::default()
        };
        let g =
            VoxelGrid::around(Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 10.0, 0.0), &desc).unwrap();
        assert_eq!(g.axis(), Axis::Z);
        assert!(g.res_x() <= 256 && g.res_y() <= 256);
        let s = g.voxel_size_m();
        assert!(s.max_element() / s.min_element() < 1.02, "{s}");
    }

    #[test]
    fn rejects_bad_boxes() {
        let nan = Vec3::new(f32::NAN, 0.0, 0.0);
        let inf = Vec3::new(0.0, f32::INFINITY, 0.0);
        let d = GridDesc::default();
        assert!(matches!(
            VoxelGrid::around(nan, Vec3::ONE, &d),
            Err(VoxelError::NonFiniteBox { .. })
        ));
        assert!(matches!(
            VoxelGrid::around(Vec3::ZERO, inf, &d),
            Err(VoxelError::NonFiniteBox { .. })
        ));
        assert!(matches!(
            VoxelGrid::around(Vec3::ONE, Vec3::ZERO, &d),
            Err(VoxelError::EmptyBox { .. })
        ));
        assert!(matches!(
            VoxelGrid::around(Vec3::ONE, Vec3::ONE, &d),
            Err(VoxelError::ZeroExtent { .. })
        ));
        assert!(matches!(
            VoxelGrid::from_box(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), None, 4, 4, 1),
            Err(VoxelError::ZeroExtent { axis: 1, .. })
        ));
        assert!(matches!(
            VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, None, 0, 4, 1),
            Err(VoxelError::BadResolution { .. })
        ));
        assert!(matches!(
            VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, None, 4, 4, 0),
            Err(VoxelError::BadResolution { .. })
        ));
        let bad_pad = GridDesc {
            pad_fraction: f32::NAN,
            ..d
        };
        assert!(matches!(
            VoxelGrid::around(Vec3::ZERO, Vec3::ONE, &bad_pad),
            Err(VoxelError::BadPadding { .. })
        ));
    }

    #[test]
    fn matrices_match_direct_transform_for_every_axis() {
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let g = VoxelGrid::from_box(
                Vec3::new(-1.0, 2.0, 3.0),
                Vec3::new(3.0, 4.0, 11.0),
                Some(axis),
                32,
                16,
                2,
            )
            .unwrap();
            assert!((Mat3::from_mat4(g.view_matrix()).determinant() - 1.0).abs() < 1e-6);
            for p in [
                Vec3::new(-1.0, 2.0, 3.0),
                Vec3::new(3.0, 4.0, 11.0),
                Vec3::new(0.3, 2.7, 9.1),
            ] {
                let direct = g.world_to_voxel(p);
                let m = g.world_to_voxel_matrix().transform_point3(p);
                assert!(close(direct, m, 1e-3), "{axis:?} {direct} {m}");
                assert!(close(g.voxel_to_world(direct), p, 1e-5));
                let unit = g.world_to_unit().transform_point3(p);
                assert!(close(unit * g.extent_voxels().as_vec3(), direct, 1e-3));
                let clip = g.world_to_clip_vk().transform_point3(p);
                assert!(close(
                    clip,
                    Vec3::new(2.0 * unit.x - 1.0, 2.0 * unit.y - 1.0, unit.z),
                    1e-5
                ));
            }
            // Box corners map to the voxel box corners; depth 0 is the near plane at min.
            assert!(close(g.world_to_voxel(g.world_min()), Vec3::ZERO, 1e-5));
            assert!(close(
                g.world_to_voxel(g.world_max()),
                g.extent_voxels().as_vec3(),
                1e-3
            ));
            // Depth grows along +axis.
            let mut step = Vec3::ZERO;
            step[axis.index()] = 1.0;
            assert!(g.dir_world_to_voxel(step).z > 0.0);
            let d = Vec3::new(0.3, -0.2, 0.9);
            assert!(close(
                g.dir_voxel_to_world(g.dir_world_to_voxel(d)),
                d,
                1e-6
            ));
        }
    }

    #[test]
    fn voxel_size_and_diagonal() {
        let g = VoxelGrid::from_box(
            Vec3::ZERO,
            Vec3::new(2.0, 4.0, 1.28),
            Some(Axis::Z),
            200,
            400,
            1,
        )
        .unwrap();
        assert!(close(g.voxel_size_m(), Vec3::splat(0.01), 1e-7));
        assert!((g.voxel_diagonal_m() - 0.01 * 3f32.sqrt()).abs() < 1e-6);
    }
}
