//! Post-processing: temporal anti-aliasing, tone mapping, and the packing of a stereo pair.
//! Every stage but tone mapping is off by default, and then has no pass.

pub mod bloom;
pub mod exposure;
mod fxaa;
mod stereo_pack;
pub mod taa;
mod tonemap;

pub use bloom::{BloomPass, GpuBloomUpPush};
pub use exposure::{ExposurePass, GpuExposurePush};
pub use fxaa::FxaaPass;
pub use stereo_pack::{GpuStereoPackPush, Rows3, StereoMode, StereoPackPass};
pub use taa::{GpuTaaPush, TaaPass};
pub use tonemap::{GpuTonemapPush, TonemapPass};

pub use crate::scene::ToneOperator;

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
    /// Triangular dither of ±1/255 before the 8-bit quantization (`--dither`).
    pub dither: bool,
}

impl Default for ToneMap {
    fn default() -> Self {
        Self {
            operator: ToneOperator::Filmic,
            exposure: 1.0,
            white: 1.0,
            drago_bias: 0.85,
            dither: false,
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
    /// Reproject moving objects' pixels with their motion vectors (scenes with moving objects
    /// only; false reprojects them with the camera alone, for comparisons).
    pub motion_vectors: bool,
}

impl Default for TaaSettings {
    fn default() -> Self {
        Self {
            history_weight: 0.9,
            frames: 16,
            motion_vectors: true,
        }
    }
}

/// Auto exposure (`--auto-exposure KEY`; Reinhard et al. 2002 §3.1, Oetke 2017 §4.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoExposure {
    /// The key value a: the exposure is a / L̄, L̄ the log-average luminance.
    pub key: f32,
    /// Fraction of the way (in log exposure) towards the target covered per frame, in (0, 1].
    pub adaptation: f32,
}

impl Default for AutoExposure {
    fn default() -> Self {
        Self {
            key: 0.18,
            adaptation: 0.05,
        }
    }
}

/// The post-processing stages around tone mapping; all off by default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostSettings {
    pub taa: Option<TaaSettings>,
    /// Multiplies `--exposure` (which stays a compensation factor).
    pub auto_exposure: Option<AutoExposure>,
    /// Bloom strength s in [0, 1] (`--bloom`): the share of the radiance moved into the blur.
    pub bloom: Option<f32>,
    /// FXAA after tone mapping (`--fxaa`).
    pub fxaa: bool,
}

/// `post` and `tone` with the given values of `o` replaced (a scene's `[post]` table merged
/// with the flags: `flags.or(scene)`): a stage switched on keeps its parameters from `post` (the
/// defaults when `post` has it off), then takes the values given.
pub fn apply_overrides(
    o: &crate::scene::PostOverrides,
    post: PostSettings,
    tone: ToneMap,
) -> (PostSettings, ToneMap) {
    use crate::scene::Stage;
    let taa = match o.taa.unwrap_or(post.taa.is_some()) {
        false => None,
        true => {
            let b = post.taa.unwrap_or_default();
            Some(TaaSettings {
                history_weight: o.taa_history_weight.unwrap_or(b.history_weight),
                frames: o.taa_frames.unwrap_or(b.frames),
                ..b
            })
        }
    };
    let auto_exposure = match o.auto_exposure {
        Some(Stage::Off) => None,
        given => {
            let on = matches!(given, Some(Stage::On(_))) || post.auto_exposure.is_some();
            on.then(|| {
                let b = post.auto_exposure.unwrap_or_default();
                let key = match given {
                    Some(Stage::On(Some(k))) => k,
                    _ => b.key,
                };
                AutoExposure {
                    key,
                    adaptation: o.exposure_adaptation.unwrap_or(b.adaptation),
                }
            })
        }
    };
    let bloom = match o.bloom {
        Some(Stage::Off) => None,
        Some(Stage::On(Some(s))) => Some(s),
        Some(Stage::On(None)) | None => post.bloom,
    };
    let post = PostSettings {
        taa,
        auto_exposure,
        bloom,
        fxaa: o.fxaa.unwrap_or(post.fxaa),
    };
    let tone = ToneMap {
        operator: o.tonemap.unwrap_or(tone.operator),
        exposure: o.exposure.unwrap_or(tone.exposure),
        dither: o.dither.unwrap_or(tone.dither),
        ..tone
    };
    (post, tone)
}

impl PostSettings {
    /// Whether the G-buffer draws motion vectors: only for a scene with moving objects
    /// (`moving`) under TAA that asks for them.
    pub fn motion_vectors(&self, moving: bool) -> bool {
        moving && self.taa.is_some_and(|t| t.motion_vectors)
    }
}

/// The post-processing passes the settings ask for (none by default), around `tonemap`.
#[derive(Default)]
pub struct PostPasses {
    taa: Option<TaaPass>,
    exposure: Option<ExposurePass>,
    bloom: Option<BloomPass>,
    fxaa: Option<FxaaPass>,
    size: (u32, u32),
}

impl PostPasses {
    /// Creates the passes `settings` turn on for a `size` frame; `sampler` is nearest;
    /// `moving`: the scene has moving objects (TAA then reads motion vectors, when its
    /// settings ask for them: [`PostSettings::motion_vectors`]).
    pub fn new(
        ctx: &crate::vk::Context,
        settings: &PostSettings,
        size: (u32, u32),
        sampler: crate::vk::vk::Sampler,
        moving: bool,
    ) -> Result<Self, crate::vk::VkError> {
        let mut passes = Self::default();
        passes.create(ctx, settings, size, sampler, moving)?;
        Ok(passes)
    }

    fn create(
        &mut self,
        ctx: &crate::vk::Context,
        settings: &PostSettings,
        size: (u32, u32),
        sampler: crate::vk::vk::Sampler,
        moving: bool,
    ) -> Result<(), crate::vk::VkError> {
        let motion = settings.motion_vectors(moving);
        self.taa = settings
            .taa
            .map(|t| TaaPass::new(ctx, t, size, sampler, motion))
            .transpose()?;
        self.exposure = settings
            .auto_exposure
            .map(|a| ExposurePass::new(ctx, a, sampler))
            .transpose()?;
        self.bloom = settings
            .bloom
            .map(|s| BloomPass::new(ctx, s, sampler))
            .transpose()?;
        self.fxaa = settings.fxaa.then(|| FxaaPass::new(ctx)).transpose()?;
        self.size = size;
        Ok(())
    }

    /// Starts a frame whose un-jittered view-projection is `view_proj`; returns the frame's
    /// sub-pixel jitter in NDC units (zero without TAA; see [`taa::jitter_matrix`]).
    pub fn begin_frame(&self, view_proj: glam::Mat4) -> glam::Vec2 {
        match &self.taa {
            Some(taa) => taa.begin_frame(view_proj),
            None => glam::Vec2::ZERO,
        }
    }

    /// Whether frames are jittered (TAA on).
    pub fn jitters(&self) -> bool {
        self.taa.is_some()
    }

    /// Declares the stages on linear radiance (TAA, then auto exposure and bloom; `motion`: the
    /// G-buffer's motion vectors, where it has them); returns the
    /// radiance to tone-map and the exposure buffer `tonemap` reads (`None`: a fixed 1).
    pub fn declare_hdr(
        &self,
        g: &mut crate::graph::RenderGraph,
        radiance: crate::graph::ImageHandle,
        depth: crate::graph::ImageHandle,
        motion: Option<crate::graph::ImageHandle>,
    ) -> (
        crate::graph::ImageHandle,
        Option<crate::graph::BufferHandle>,
    ) {
        let radiance = match &self.taa {
            Some(taa) => taa.declare(g, radiance, depth, motion),
            None => radiance,
        };
        // The exposure is measured before bloom, which only moves light around.
        let exposure = self.exposure.as_ref().map(|e| e.declare(g, radiance));
        let radiance = match &self.bloom {
            Some(bloom) => bloom.declare(g, radiance, self.size),
            None => radiance,
        };
        (radiance, exposure)
    }

    /// Declares the stages on the tone-mapped image (FXAA); returns the final image.
    pub fn declare_ldr(
        &self,
        g: &mut crate::graph::RenderGraph,
        ldr: crate::graph::ImageHandle,
    ) -> crate::graph::ImageHandle {
        match &self.fxaa {
            Some(fxaa) => fxaa.declare(g, ldr, self.size),
            None => ldr,
        }
    }
}
