//! Post-processing: tone mapping (and, with the GI methods, geometry-aware filtering), and the
//! packing of a stereo pair.

mod stereo_pack;
mod tonemap;

pub use stereo_pack::{GpuStereoPackPush, Rows3, StereoMode, StereoPackPass};
pub use tonemap::{GpuTonemapPush, TonemapPass};

use serde::{Deserialize, Serialize};

/// Tone-mapping operator of `glsl/tonemap.comp`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum ToneOperator {
    /// Exposure, then clamp.
    Linear,
    /// log(1 + L) / log(1 + white).
    Logarithmic,
    /// Drago et al. 2003, adaptive logarithmic.
    Drago,
    /// ACES filmic fit (Narkowicz 2015).
    #[default]
    Filmic,
}

impl ToneOperator {
    pub fn shader_id(self) -> u32 {
        match self {
            ToneOperator::Linear => 0,
            ToneOperator::Logarithmic => 1,
            ToneOperator::Drago => 2,
            ToneOperator::Filmic => 3,
        }
    }
}

/// Tone-mapping parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    pub operator: ToneOperator,
    /// Multiplies radiance before the operator.
    pub exposure: f32,
    /// Luminance (after exposure) mapped to display white by the logarithmic operators.
    pub white: f32,
    /// Drago's bias b in [0.5, 1].
    pub drago_bias: f32,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self {
            operator: ToneOperator::Filmic,
            exposure: 1.0,
            white: 1.0,
            drago_bias: 0.85,
        }
    }
}
