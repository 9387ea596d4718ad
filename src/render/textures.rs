//! Albedo textures: mip chains built on the CPU (box filter in linear space for sRGB data)
//! and uploaded once as sampled images.

use crate::eval::{srgb_decode, srgb_encode};
use crate::scene::TextureData;
use crate::vk::{vk, Context, Image, ImageDesc, VkError};

/// RGBA8 mip chain of `tex` down to 1×1; level 0 is the texture itself.
pub fn mip_chain(tex: &TextureData) -> Vec<Vec<u8>> {
    let (mut w, mut h) = (tex.width.max(1), tex.height.max(1));
    let mut levels = vec![tex.rgba8.clone()];
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let prev = &levels[levels.len() - 1];
        let mut next = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                for c in 0..4 {
                    let mut sum = 0.0f32;
                    let mut n = 0.0f32;
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                        let v = f32::from(prev[((sy * w + sx) * 4 + c) as usize]) / 255.0;
                        // Average light, not encoded values: decode sRGB color channels first.
                        sum += if tex.srgb && c < 3 { srgb_decode(v) } else { v };
                        n += 1.0;
                    }
                    let avg = sum / n;
                    let enc = if tex.srgb && c < 3 {
                        srgb_encode(avg)
                    } else {
                        avg
                    };
                    next[((y * nw + x) * 4 + c) as usize] =
                        (enc.clamp(0.0, 1.0) * 255.0).round() as u8;
                }
            }
        }
        levels.push(next);
        (w, h) = (nw, nh);
    }
    levels
}

/// Uploads `tex` with its mip chain; sRGB textures use an sRGB format so sampling returns
/// linear values.
pub fn upload_texture(ctx: &Context, tex: &TextureData, name: &str) -> Result<Image, VkError> {
    let format = if tex.srgb {
        vk::Format::R8G8B8A8_SRGB
    } else {
        vk::Format::R8G8B8A8_UNORM
    };
    let desc = ImageDesc::new_2d(name, format, tex.width.max(1), tex.height.max(1));
    ctx.upload_image(&desc, &mip_chain(tex))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_chain_halves_down_to_one_texel_and_averages_light() {
        // 2x2 black/white checker: its 1x1 mip is mid-grey in *light* (sRGB 188), not 128.
        let tex = TextureData::new(
            "checker".into(),
            2,
            2,
            vec![
                0, 0, 0, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 255,
            ],
            true,
        );
        let levels = mip_chain(&tex);
        assert_eq!(levels.len(), 2);
        assert_eq!(levels[1].len(), 4);
        assert_eq!(levels[1][0], 188);
        assert_eq!(levels[1][3], 255);
        let odd = TextureData::new("odd".into(), 5, 3, vec![255; 60], false);
        let levels = mip_chain(&odd);
        assert_eq!(
            levels.iter().map(Vec::len).collect::<Vec<_>>(),
            vec![60, 8, 4]
        );
    }
}
