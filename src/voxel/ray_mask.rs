//! Bit-mask look-up tables of the ray test and the voxelizer.
//!
//! - Ray masks (Thiedemann 2010, §5.3.2, Fig. 16): entry `(a, b)` has the bits `min(a,b)..=max(a,b)` of
//!   one 128-voxel column set, so one fetch turns the depth range a ray segment covers inside
//!   a column into a mask to AND with the column. The thesis XORs two 1D masks; that gives
//!   the range only for *prefix* masks, and the range must be inclusive at both ends (a
//!   segment that enters voxel a and leaves through voxel b touches both), hence
//!   `prefix(max) ^ prefix(min) | single(min)`.
//! - Single-bit masks (thesis §4.3.1, Fig. 12): entry k has only bit k set; the splatting
//!   voxelizer ORs it into the column.
//! - March masks (thesis §6.4.1, Fig. 26): the 1-bit mask is the single-bit mask; the "thick" 3-bit mask
//!   of entry k covers `k−1..=k+1` clamped to the column (Nichols et al. 2010).
//!
//! Depth indices here are local to one layer (`0..128`); see [`super`] for the convention.

use super::bits::Column;
use super::COLUMN_BITS;

/// Mask with bits `0..=k` set (`k` clamped to 127).
#[inline]
pub fn prefix_mask(k: u32) -> Column {
    let k = k.min(COLUMN_BITS - 1);
    let mut m = [0u32; 4];
    let mut ch = 0u32;
    while ch < 4 {
        let lo = ch * 32;
        m[ch as usize] = if k >= lo + 31 {
            u32::MAX
        } else if k >= lo {
            // Bits 0..=(k − lo); k − lo ≤ 30 here so the shift cannot overflow.
            (2u32 << (k - lo)) - 1
        } else {
            0
        };
        ch += 1;
    }
    m
}

/// Mask with only bit `k` set (`k` clamped to 127).
#[inline]
pub fn single_bit(k: u32) -> Column {
    let k = k.min(COLUMN_BITS - 1);
    let mut m = [0u32; 4];
    m[(k / 32) as usize] = 1 << (k % 32);
    m
}

/// Mask with bits `min(k0,k1)..=max(k0,k1)` set (indices clamped to 127): the value of the
/// ray-mask LUT at `(k0, k1)`.
#[inline]
pub fn column_mask(k0: u32, k1: u32) -> Column {
    let (lo, hi) = (k0.min(k1), k0.max(k1));
    let (p_hi, p_lo, s_lo) = (prefix_mask(hi), prefix_mask(lo), single_bit(lo));
    [
        (p_hi[0] ^ p_lo[0]) | s_lo[0],
        (p_hi[1] ^ p_lo[1]) | s_lo[1],
        (p_hi[2] ^ p_lo[2]) | s_lo[2],
        (p_hi[3] ^ p_lo[3]) | s_lo[3],
    ]
}

/// The thick 3-bit march mask around `k`: bits `k−1..=k+1` within the column.
#[inline]
pub fn march3_mask(k: u32) -> Column {
    let k = k.min(COLUMN_BITS - 1);
    column_mask(k.saturating_sub(1), k + 1)
}

/// The 128×128 ray-mask LUT as uploaded to a `R32G32B32A32_UINT` 128×128 2D image:
/// texel `(x = a, y = b)` at index `b·128 + a`. The table is symmetric.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RayMaskLut {
    entries: Vec<Column>,
}

impl Default for RayMaskLut {
    fn default() -> Self {
        Self::new()
    }
}

impl RayMaskLut {
    pub fn new() -> Self {
        let n = COLUMN_BITS;
        let mut entries = Vec::with_capacity((n * n) as usize);
        for b in 0..n {
            for a in 0..n {
                entries.push(column_mask(a, b));
            }
        }
        Self { entries }
    }

    /// Entry `(a, b)`, indices clamped to 127.
    #[inline]
    pub fn get(&self, a: u32, b: u32) -> Column {
        let (a, b) = (a.min(COLUMN_BITS - 1), b.min(COLUMN_BITS - 1));
        self.entries[(b * COLUMN_BITS + a) as usize]
    }

    pub fn entries(&self) -> &[Column] {
        &self.entries
    }

    /// Upload bytes (little-endian RGBA u32 per texel, rows of 128 texels).
    pub fn to_gpu_bytes(&self) -> Vec<u8> {
        self.entries
            .iter()
            .flat_map(|c| c.iter().flat_map(|w| w.to_le_bytes()))
            .collect()
    }
}

/// A 128-entry 1D LUT of columns (`R32G32B32A32_UINT`, 128×1), e.g. the single-bit LUT of the
/// splatting voxelizer or the 3-bit march LUT.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnLut1d {
    entries: Vec<Column>,
}

impl ColumnLut1d {
    /// Single-bit LUT: entry k = bit k (thesis §4.3.1, Fig. 12).
    pub fn single_bit() -> Self {
        Self {
            entries: (0..COLUMN_BITS).map(single_bit).collect(),
        }
    }

    /// 3-bit march LUT: entry k = bits k−1..=k+1 clamped (thesis §6.4.1).
    pub fn march3() -> Self {
        Self {
            entries: (0..COLUMN_BITS).map(march3_mask).collect(),
        }
    }

    /// Entry `k`, clamped to 127.
    #[inline]
    pub fn get(&self, k: u32) -> Column {
        self.entries[k.min(COLUMN_BITS - 1) as usize]
    }

    pub fn entries(&self) -> &[Column] {
        &self.entries
    }

    /// Upload bytes (little-endian RGBA u32 per texel).
    pub fn to_gpu_bytes(&self) -> Vec<u8> {
        self.entries
            .iter()
            .flat_map(|c| c.iter().flat_map(|w| w.to_le_bytes()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive_range(lo: u32, hi: u32) -> Column {
        let mut m = [0u32; 4];
        for k in lo..=hi {
            m[(k / 32) as usize] |= 1 << (k % 32);
        }
        m
    }

    #[test]
    fn lut_matches_naive_ranges() {
        let lut = RayMaskLut::new();
        for a in 0..128 {
            for b in 0..128 {
                let want = naive_range(a.min(b), a.max(b));
                assert_eq!(lut.get(a, b), want, "({a},{b})");
                assert_eq!(column_mask(a, b), want);
            }
        }
        assert_eq!(prefix_mask(127), [u32::MAX; 4]);
        assert_eq!(prefix_mask(31), [u32::MAX, 0, 0, 0]);
        assert_eq!(prefix_mask(0), [1, 0, 0, 0]);
        assert_eq!(column_mask(500, 500), single_bit(127));
        assert_eq!(lut.to_gpu_bytes().len(), 128 * 128 * 16);
        // Texel (a=0, b=1) at index 128: bits 0..=1 → first byte 0b11.
        assert_eq!(lut.to_gpu_bytes()[128 * 16], 0b11);
    }

    #[test]
    fn one_dimensional_luts() {
        let single = ColumnLut1d::single_bit();
        let thick = ColumnLut1d::march3();
        for k in 0..128 {
            assert_eq!(single.get(k), naive_range(k, k));
            assert_eq!(
                thick.get(k),
                naive_range(k.saturating_sub(1), (k + 1).min(127))
            );
        }
        assert_eq!(single.to_gpu_bytes()[16 * 33 + 4], 0b10);
    }
}
