//! CPU copy of the binary column image and its OR mip hierarchy (Thiedemann 2010, §4.3.1, §5.2).
//!
//! A [`Column`] is one `R32G32B32A32_UINT` texel: 128 voxels of one layer, `[R, G, B, A]`,
//! bit `k mod 32` of channel `(k mod 128) / 32`, least significant = nearest.
//!
//! # Odd sizes
//! Level ℓ has `ceil(res / 2^ℓ)` texels per axis (down to 1×1), and texel `(x, y)` of level ℓ
//! ORs the texels `2x..=2x+1, 2y..=2y+1` of level ℓ−1 that exist. Its footprint at level 0 is
//! therefore always the aligned block `[x·2^ℓ, (x+1)·2^ℓ) ∩ [0, res)`, which is what the
//! traversal's column boxes assume. For power-of-two sizes this equals Vulkan's mip chain
//! (`max(1, res >> ℓ)`); for other sizes Vulkan's floor-sized mips drop the last odd
//! row/column, so a GPU hierarchy of a non-power-of-two grid needs its own per-level images
//! (or a power-of-two grid).

use super::{VoxelError, VoxelGrid, COLUMN_BITS};

/// One column of 128 voxels: `[R, G, B, A]`, R = front (nearest 32 voxels).
pub type Column = [u32; 4];

/// The empty column.
pub const EMPTY_COLUMN: Column = [0; 4];

/// `(layer, channel, bit)` of depth index `k` (the convention of [`super`]).
#[inline]
pub fn bit_location(k: u32) -> (u32, u32, u32) {
    (k / COLUMN_BITS, (k % COLUMN_BITS) / 32, k % 32)
}

#[inline]
pub fn col_and(a: Column, b: Column) -> Column {
    [a[0] & b[0], a[1] & b[1], a[2] & b[2], a[3] & b[3]]
}

#[inline]
pub fn col_or(a: Column, b: Column) -> Column {
    [a[0] | b[0], a[1] | b[1], a[2] | b[2], a[3] | b[3]]
}

#[inline]
pub fn col_is_empty(a: Column) -> bool {
    (a[0] | a[1] | a[2] | a[3]) == 0
}

/// Lowest set bit index (0..128) of a column, i.e. the nearest voxel (GLSL `findLSB` on the
/// first non-zero channel, thesis §5.3.4 "rear" trick mirrored for our bit order).
#[inline]
pub fn col_lowest_bit(a: Column) -> Option<u32> {
    let mut ch = 0;
    while ch < 4 {
        if a[ch] != 0 {
            return Some(ch as u32 * 32 + a[ch].trailing_zeros());
        }
        ch += 1;
    }
    None
}

/// Highest set bit index (0..128) of a column, i.e. the farthest voxel (GLSL `findMSB`).
#[inline]
pub fn col_highest_bit(a: Column) -> Option<u32> {
    let mut ch = 4;
    while ch > 0 {
        ch -= 1;
        if a[ch] != 0 {
            return Some(ch as u32 * 32 + 31 - a[ch].leading_zeros());
        }
    }
    None
}

/// CPU copy of the binary column image: `res_x × res_y` texels × `layers` array layers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitGrid {
    res_x: u32,
    res_y: u32,
    layers: u32,
    /// Layer-major, then row y, then x — the tightly packed read-back order of a 2D array image.
    data: Vec<Column>,
}

impl BitGrid {
    /// Empty grid. Sizes of 0 are bumped to 1 so every grid has at least one column.
    pub fn new(res_x: u32, res_y: u32, layers: u32) -> Self {
        let (res_x, res_y, layers) = (res_x.max(1), res_y.max(1), layers.max(1));
        Self {
            res_x,
            res_y,
            layers,
            data: vec![EMPTY_COLUMN; res_x as usize * res_y as usize * layers as usize],
        }
    }

    /// Empty grid matching `grid`'s resolution.
    pub fn for_grid(grid: &VoxelGrid) -> Self {
        Self::new(grid.res_x(), grid.res_y(), grid.layers())
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
    /// `(res_x, res_y, layers)`.
    pub fn dims(&self) -> (u32, u32, u32) {
        (self.res_x, self.res_y, self.layers)
    }

    #[inline]
    fn index(&self, x: u32, y: u32, layer: u32) -> usize {
        debug_assert!(x < self.res_x && y < self.res_y && layer < self.layers);
        ((layer as usize * self.res_y as usize) + y as usize) * self.res_x as usize + x as usize
    }

    /// Whether `(x, y, k)` is inside the grid.
    #[inline]
    pub fn contains(&self, x: u32, y: u32, k: u32) -> bool {
        x < self.res_x && y < self.res_y && k < self.depth()
    }

    /// Voxel occupancy; voxels outside the grid read as empty.
    #[inline]
    pub fn get(&self, x: u32, y: u32, k: u32) -> bool {
        if !self.contains(x, y, k) {
            return false;
        }
        let (layer, ch, bit) = bit_location(k);
        (self.data[self.index(x, y, layer)][ch as usize] >> bit) & 1 != 0
    }

    /// Sets a voxel; voxels outside the grid are ignored (clipped).
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, k: u32) {
        if !self.contains(x, y, k) {
            return;
        }
        let (layer, ch, bit) = bit_location(k);
        let i = self.index(x, y, layer);
        self.data[i][ch as usize] |= 1 << bit;
    }

    /// Clears a voxel; voxels outside the grid are ignored.
    pub fn clear_voxel(&mut self, x: u32, y: u32, k: u32) {
        if !self.contains(x, y, k) {
            return;
        }
        let (layer, ch, bit) = bit_location(k);
        let i = self.index(x, y, layer);
        self.data[i][ch as usize] &= !(1 << bit);
    }

    /// One texel (128 voxels of `layer`); out-of-range reads as empty like a GPU
    /// `texelFetch` with robust access.
    #[inline]
    pub fn column(&self, x: u32, y: u32, layer: u32) -> Column {
        if x < self.res_x && y < self.res_y && layer < self.layers {
            self.data[self.index(x, y, layer)]
        } else {
            EMPTY_COLUMN
        }
    }

    /// Mutable texel. Panics outside the grid (caller bug).
    pub fn column_mut(&mut self, x: u32, y: u32, layer: u32) -> &mut Column {
        assert!(x < self.res_x && y < self.res_y && layer < self.layers);
        let i = self.index(x, y, layer);
        &mut self.data[i]
    }

    /// All texels, layer-major, then row, then x.
    pub fn columns(&self) -> &[Column] {
        &self.data
    }

    /// Number of set voxels.
    pub fn count_ones(&self) -> u64 {
        self.data
            .iter()
            .flat_map(|c| c.iter())
            .map(|w| u64::from(w.count_ones()))
            .sum()
    }

    /// Parses a tightly packed read-back of mip 0 of the `R32G32B32A32_UINT` array image
    /// (all layers; layer-major, then row y, then x; little-endian u32 R, G, B, A).
    pub fn from_gpu_bytes(
        res_x: u32,
        res_y: u32,
        layers: u32,
        bytes: &[u8],
    ) -> Result<Self, VoxelError> {
        let mut grid = Self::new(res_x, res_y, layers);
        let expected = grid.data.len() * 16;
        if bytes.len() != expected || (res_x, res_y, layers) != grid.dims() {
            return Err(VoxelError::ByteSizeMismatch {
                got: bytes.len(),
                expected,
                res_x,
                res_y,
                layers,
            });
        }
        for (col, texel) in grid.data.iter_mut().zip(bytes.chunks_exact(16)) {
            for (w, b) in col.iter_mut().zip(texel.chunks_exact(4)) {
                *w = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
        }
        Ok(grid)
    }

    /// Bytes to upload into mip 0 of the `R32G32B32A32_UINT` array image (inverse of
    /// [`Self::from_gpu_bytes`]).
    pub fn to_gpu_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.data.len() * 16);
        for col in &self.data {
            for w in col {
                out.extend_from_slice(&w.to_le_bytes());
            }
        }
        out
    }
}

/// The OR mip hierarchy over a [`BitGrid`] (thesis §5.2): level 0 is the grid itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitHierarchy {
    levels: Vec<BitGrid>,
}

/// Texels per axis at mip `level` (ceil; see the module doc on odd sizes).
#[inline]
pub fn mip_extent(res: u32, level: u32) -> u32 {
    if level >= 32 {
        return 1;
    }
    // (res + 2^ℓ − 1) >> ℓ without overflow for res near u32::MAX.
    ((u64::from(res) + (1u64 << level) - 1) >> level) as u32
}

/// Number of mip levels down to 1×1: `1 + ceil(log2(max(res_x, res_y)))`.
pub fn mip_count(res_x: u32, res_y: u32) -> u32 {
    let m = res_x.max(res_y).max(1);
    1 + (32 - (m - 1).leading_zeros())
}

impl BitHierarchy {
    /// Builds all levels by 2×2 OR reduction.
    pub fn build(base: BitGrid) -> Self {
        let count = mip_count(base.res_x, base.res_y);
        let mut levels = Vec::with_capacity(count as usize);
        levels.push(base);
        for _ in 1..count {
            let fine = &levels[levels.len() - 1];
            let (w, h) = (mip_extent(fine.res_x, 1), mip_extent(fine.res_y, 1));
            let mut coarse = BitGrid::new(w, h, fine.layers);
            for layer in 0..fine.layers {
                for y in 0..h {
                    for x in 0..w {
                        // `column` reads outside the finer level as empty: the clamp for odd sizes.
                        let c = col_or(
                            col_or(
                                fine.column(2 * x, 2 * y, layer),
                                fine.column(2 * x + 1, 2 * y, layer),
                            ),
                            col_or(
                                fine.column(2 * x, 2 * y + 1, layer),
                                fine.column(2 * x + 1, 2 * y + 1, layer),
                            ),
                        );
                        *coarse.column_mut(x, y, layer) = c;
                    }
                }
            }
            levels.push(coarse);
        }
        Self { levels }
    }

    /// Number of levels (≥ 1).
    pub fn level_count(&self) -> u32 {
        self.levels.len() as u32
    }

    /// Index of the 1×1 level.
    pub fn max_level(&self) -> u32 {
        self.level_count() - 1
    }

    /// Level `l`, clamped to the coarsest.
    pub fn level(&self, l: u32) -> &BitGrid {
        &self.levels[(l as usize).min(self.levels.len() - 1)]
    }

    /// Level 0.
    pub fn base(&self) -> &BitGrid {
        &self.levels[0]
    }

    /// Texel of level `l`; out of range reads as empty.
    #[inline]
    pub fn texel(&self, l: u32, x: u32, y: u32, layer: u32) -> Column {
        self.level(l).column(x, y, layer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn bit_convention() {
        assert_eq!(bit_location(0), (0, 0, 0));
        assert_eq!(bit_location(31), (0, 0, 31));
        assert_eq!(bit_location(32), (0, 1, 0));
        assert_eq!(bit_location(127), (0, 3, 31));
        assert_eq!(bit_location(128), (1, 0, 0));
        assert_eq!(bit_location(200), (1, 2, 8));
        let mut g = BitGrid::new(3, 2, 2);
        g.set(2, 1, 0);
        assert_eq!(g.column(2, 1, 0), [1, 0, 0, 0]);
        g.set(2, 1, 127);
        assert_eq!(g.column(2, 1, 0), [1, 0, 0, 0x8000_0000]);
        g.set(0, 0, 161);
        assert_eq!(g.column(0, 0, 1), [0, 2, 0, 0]);
        assert!(g.get(0, 0, 161) && !g.get(0, 0, 160) && !g.get(0, 0, 33));
        // Outside reads empty, writes are clipped.
        g.set(3, 0, 0);
        g.set(0, 0, 256);
        assert!(!g.get(3, 0, 0) && !g.get(0, 0, 256));
        assert_eq!(g.count_ones(), 3);
        g.clear_voxel(2, 1, 0);
        assert_eq!(g.count_ones(), 2);
    }

    #[test]
    fn gpu_byte_layout() {
        let mut g = BitGrid::new(2, 3, 2);
        // Layer 1, row 2, x 1 is the last texel; bit 0 of R is its first byte.
        g.set(1, 2, 128);
        let bytes = g.to_gpu_bytes();
        assert_eq!(bytes.len(), 2 * 3 * 2 * 16);
        let last = ((3 + 2) * 2 + 1) * 16; // ((layer·res_y + y)·res_x + x)·16
        assert_eq!(bytes[last], 1);
        assert_eq!(bytes.iter().map(|b| b.count_ones()).sum::<u32>(), 1);
        // k = 32·c + 8 sets byte 4c + 1 of the texel: channels in RGBA order, little endian.
        let mut h = BitGrid::new(1, 1, 1);
        h.set(0, 0, 32 * 2 + 8);
        assert_eq!(h.to_gpu_bytes()[9], 1);
        assert!(matches!(
            BitGrid::from_gpu_bytes(2, 3, 2, &bytes[1..]),
            Err(VoxelError::ByteSizeMismatch { .. })
        ));
    }

    #[test]
    fn lowest_highest_bits() {
        assert_eq!(col_lowest_bit([0, 0, 0, 0]), None);
        assert_eq!(col_highest_bit([0, 0, 0, 0]), None);
        assert_eq!(col_lowest_bit([0, 0b1100, 0, 1]), Some(34));
        assert_eq!(col_highest_bit([0, 0b1100, 0, 1]), Some(96));
        assert_eq!(col_highest_bit([u32::MAX, 0, 0, 0]), Some(31));
    }

    #[test]
    fn mip_sizes() {
        assert_eq!(mip_count(1, 1), 1);
        assert_eq!(mip_count(2, 1), 2);
        assert_eq!(mip_count(128, 128), 8);
        assert_eq!(mip_count(5, 3), 4); // 5×3, 3×2, 2×1, 1×1
        assert_eq!(mip_extent(5, 1), 3);
        assert_eq!(mip_extent(5, 3), 1);
        assert_eq!(mip_extent(u32::MAX, 1), 1 << 31);
        let h = BitHierarchy::build(BitGrid::new(5, 3, 1));
        assert_eq!(h.level_count(), 4);
        assert_eq!(h.level(3).dims(), (1, 1, 1));
        assert_eq!(h.level(99).dims(), (1, 1, 1));
    }

    fn arb_grid() -> impl Strategy<Value = BitGrid> {
        (1u32..20, 1u32..20, 1u32..3).prop_flat_map(|(w, h, l)| {
            let n = (w * h * l) as usize;
            // Sparse words so coarse levels are not all full.
            proptest::collection::vec(
                prop_oneof![3 => Just(0u32), 1 => any::<u32>().prop_map(|v| v & (v >> 7) & (v >> 13))],
                n * 4,
            )
            .prop_map(move |words| {
                let mut g = BitGrid::new(w, h, l);
                for (i, c) in g.data.iter_mut().enumerate() {
                    c.copy_from_slice(&words[i * 4..i * 4 + 4]);
                }
                g
            })
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn gpu_bytes_round_trip(g in arb_grid()) {
            let (w, h, l) = g.dims();
            let back = BitGrid::from_gpu_bytes(w, h, l, &g.to_gpu_bytes()).unwrap();
            prop_assert_eq!(back, g);
        }

        #[test]
        fn set_get_round_trip(g in arb_grid()) {
            let mut copy = BitGrid::new(g.res_x, g.res_y, g.layers);
            for y in 0..g.res_y {
                for x in 0..g.res_x {
                    for k in 0..g.depth() {
                        if g.get(x, y, k) {
                            copy.set(x, y, k);
                        }
                    }
                }
            }
            prop_assert_eq!(copy, g);
        }

        #[test]
        fn hierarchy_is_or_of_footprint(g in arb_grid()) {
            let h = BitHierarchy::build(g.clone());
            prop_assert_eq!(h.level(h.max_level()).dims(), (1, 1, g.layers));
            for l in 0..h.level_count() {
                let lv = h.level(l);
                prop_assert_eq!(lv.res_x, mip_extent(g.res_x, l));
                prop_assert_eq!(lv.res_y, mip_extent(g.res_y, l));
                for layer in 0..g.layers {
                    for y in 0..lv.res_y {
                        for x in 0..lv.res_x {
                            // Reference: OR over the aligned level-0 footprint.
                            let mut want = EMPTY_COLUMN;
                            for y0 in (y << l)..((y + 1) << l).min(g.res_y) {
                                for x0 in (x << l)..((x + 1) << l).min(g.res_x) {
                                    want = col_or(want, g.column(x0, y0, layer));
                                }
                            }
                            prop_assert_eq!(lv.column(x, y, layer), want);
                        }
                    }
                }
            }
        }
    }
}
