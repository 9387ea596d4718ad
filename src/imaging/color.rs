//! Colour helpers shared by the metrics, the image writers and tone mapping.

/// Relative luminance of a linear RGB triple with Rec.709 / sRGB primaries.
///
/// Weights from ITU-R BT.709-6, item 3.2 (Y = 0.2126 R + 0.7152 G + 0.0722 B).
/// Applied to sRGB-encoded values the same weights give luma Y' instead.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// Linear → sRGB transfer function (IEC 61966-2-1), one channel.
///
/// Does not clamp: callers that need a display value clamp to `[0, 1]` first. Negative input
/// stays on the linear segment; NaN passes through.
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB → linear transfer function (IEC 61966-2-1), one channel; inverse of [`srgb_encode`].
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → 8-bit sRGB code: clamp to `[0, 1]`, encode, round to nearest.
/// NaN maps to 0 (callers validate finiteness before this where it matters).
pub fn to_srgb8(linear: f32) -> u8 {
    let encoded = srgb_encode(linear.clamp(0.0, 1.0));
    // In [0, 255.5) after clamping, so the cast cannot saturate; `as` maps NaN to 0.
    (encoded * 255.0 + 0.5) as u8
}

/// Linear value → clamped display value in `[0, 1]` (sRGB-encoded).
pub(crate) fn display(linear: f32) -> f32 {
    srgb_encode(linear.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_and_hits_known_points() {
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-6, "x = {x}");
        }
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        // Middle grey: 18% reflectance encodes to about 0.4614.
        assert!((srgb_encode(0.18) - 0.4614).abs() < 1e-3);
        assert_eq!(to_srgb8(1.0), 255);
        assert_eq!(to_srgb8(2.0), 255);
        assert_eq!(to_srgb8(-1.0), 0);
        assert_eq!(to_srgb8(f32::NAN), 0);
    }

    #[test]
    fn luminance_weights_sum_to_one() {
        assert!((luminance([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-6);
        assert!((luminance([0.0, 1.0, 0.0]) - 0.7152).abs() < 1e-7);
    }
}
