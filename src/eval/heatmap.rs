//! Per-pixel error images written as PNG heatmaps.

use std::path::Path;

use super::EvalError;
use crate::imaging::image_io::save_rgb8_png;

/// The 256-entry magma colormap that FLIP itself uses for its error maps (dark purple for no
/// error, through red, to pale yellow for the largest). Perceptually uniform, so equal steps in
/// error read as equal steps in colour; taken from the `nv-flip` crate so our heatmaps match
/// the ones NVIDIA's FLIP tool writes.
pub fn magma_colormap() -> Vec<[u8; 3]> {
    nv_flip::magma_lut()
        .to_vec()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// Writes `errors` (row-major, one value per pixel, `width * height` values) as a PNG
/// coloured with [`magma_colormap`]. Values are expected in `[0, 1]` (FLIP's range) and are
/// clamped; scale other errors first, e.g. divide by their maximum.
pub fn write_heatmap(
    path: impl AsRef<Path>,
    errors: &[f32],
    width: u32,
    height: u32,
) -> Result<(), EvalError> {
    let path = path.as_ref();
    let expected = width as usize * height as usize;
    if errors.len() != expected {
        return Err(EvalError::LengthMismatch {
            what: format!("error map for {}", path.display()),
            actual: errors.len(),
            expected,
            width,
            height,
        });
    }
    let mut bad = errors.iter().enumerate().filter(|(_, e)| !e.is_finite());
    if let Some((first, _)) = bad.next() {
        let w = width.max(1) as usize;
        return Err(EvalError::NonFinite {
            what: format!("error map for {}", path.display()),
            count: 1 + bad.count(),
            x: (first % w) as u32,
            y: (first / w) as u32,
        });
    }
    let lut = magma_colormap();
    let last = lut.len().saturating_sub(1);
    let bytes: Vec<u8> = errors
        .iter()
        .flat_map(|&e| {
            // Finite and clamped, so the index is in 0..=last.
            let index = (e.clamp(0.0, 1.0) * last as f32 + 0.5) as usize;
            lut.get(index.min(last)).copied().unwrap_or([0, 0, 0])
        })
        .collect();
    save_rgb8_png(path, width, height, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magma_runs_dark_to_bright() {
        let lut = magma_colormap();
        assert_eq!(lut.len(), 256);
        let brightness = |c: [u8; 3]| c.iter().map(|&v| u32::from(v)).sum::<u32>();
        assert!(brightness(lut[0]) < 30, "{:?}", lut[0]);
        assert!(brightness(lut[255]) > 600, "{:?}", lut[255]);
    }

    #[test]
    fn heatmap_png_uses_colormap_ends() {
        let dir = std::env::temp_dir().join(format!("voxgi_eval_heat_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("heat.png");
        write_heatmap(&path, &[0.0, 1.0, 5.0, -1.0], 2, 2).unwrap();
        let png = image::open(&path).unwrap().into_rgb8();
        let lut = magma_colormap();
        assert_eq!(png.get_pixel(0, 0).0, lut[0]);
        assert_eq!(png.get_pixel(1, 0).0, lut[255]);
        assert_eq!(png.get_pixel(0, 1).0, lut[255]);
        assert_eq!(png.get_pixel(1, 1).0, lut[0]);

        let err = write_heatmap(&path, &[0.0; 3], 2, 2).unwrap_err();
        assert!(err.to_string().contains("2x2"), "{err}");
        let err = write_heatmap(&path, &[0.0, f32::NAN, 0.0, 0.0], 2, 2).unwrap_err();
        assert!(err.to_string().contains("(1, 0)"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
