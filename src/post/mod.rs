//! Post-processing: temporal anti-aliasing, tone mapping, and the packing of a stereo pair.
//! Every stage but tone mapping is off by default, and then has no pass.

mod stereo_pack;
pub mod taa;
mod tonemap;

pub use stereo_pack::{GpuStereoPackPush, Rows3, StereoMode, StereoPackPass};
pub use taa::{GpuTaaPush, TaaPass};
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

/// Temporal anti-aliasing (`--taa`; Oetke 2017 §4.5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaaSettings {
    /// α: the weight of the reprojected history in each frame's blend (the current frame
    /// gets 1 − α, or 1/(n+1) while only n < 1/(1 − α) frames are in the history).
    pub history_weight: f32,
    /// Frames a headless render runs (jittered), so a still image is anti-aliased.
    pub frames: u32,
}

impl Default for TaaSettings {
    fn default() -> Self {
        Self {
            history_weight: 0.9,
            frames: 16,
        }
    }
}

/// The post-processing stages around tone mapping; all off by default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostSettings {
    pub taa: Option<TaaSettings>,
}

/// The post-processing passes the settings ask for (none by default), around `tonemap`.
#[derive(Default)]
pub struct PostPasses {
    taa: Option<TaaPass>,
}

impl PostPasses {
    /// Creates the passes `settings` turn on for a `size` frame; `sampler` is nearest.
    pub fn new(
        ctx: &crate::vk::Context,
        settings: &PostSettings,
        size: (u32, u32),
        sampler: crate::vk::vk::Sampler,
    ) -> Result<Self, crate::vk::VkError> {
        let taa = settings
            .taa
            .map(|t| TaaPass::new(ctx, t, size, sampler))
            .transpose()?;
        Ok(Self { taa })
    }

    /// Starts a frame rendered with the un-jittered `view_proj`; returns the view-projection
    /// the frame renders with (jittered with TAA, else `view_proj` itself).
    pub fn begin_frame(&self, view_proj: glam::Mat4) -> glam::Mat4 {
        match &self.taa {
            Some(taa) => taa.begin_frame(view_proj),
            None => view_proj,
        }
    }

    /// Whether frames are jittered (TAA on).
    pub fn jitters(&self) -> bool {
        self.taa.is_some()
    }

    /// Declares the stages on linear radiance (TAA); returns the radiance to tone-map.
    pub fn declare_hdr(
        &self,
        g: &mut crate::graph::RenderGraph,
        radiance: crate::graph::ImageHandle,
        depth: crate::graph::ImageHandle,
    ) -> crate::graph::ImageHandle {
        match &self.taa {
            Some(taa) => taa.declare(g, radiance, depth),
            None => radiance,
        }
    }

    pub fn destroy(self, ctx: &crate::vk::Context) {
        if let Some(p) = self.taa {
            p.destroy(ctx);
        }
    }
}
