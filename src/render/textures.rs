//! Textures uploaded once as sampled images with the mip chains of
//! [`TextureData::mip_chain`] (box filter in linear space for sRGB data).

use crate::scene::TextureData;
use crate::vk::{vk, Context, Image, ImageDesc, VkError};

/// Uploads `tex` with its mip chain; sRGB textures use an sRGB format so sampling returns
/// linear values.
pub fn upload_texture(ctx: &Context, tex: &TextureData, name: &str) -> Result<Image, VkError> {
    let format = if tex.srgb {
        vk::Format::R8G8B8A8_SRGB
    } else {
        vk::Format::R8G8B8A8_UNORM
    };
    let desc = ImageDesc::new_2d(name, format, tex.width.max(1), tex.height.max(1));
    ctx.upload_image(&desc, &tex.mip_chain())
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
        let levels = tex.mip_chain();
        assert_eq!(levels.len(), 2);
        assert_eq!(levels[1].len(), 4);
        assert_eq!(levels[1][0], 188);
        assert_eq!(levels[1][3], 255);
        let odd = TextureData::new("odd".into(), 5, 3, vec![255; 60], false);
        let levels = odd.mip_chain();
        assert_eq!(
            levels.iter().map(Vec::len).collect::<Vec<_>>(),
            vec![60, 8, 4]
        );
    }
}
