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

pub use crate::scene::{AutoExposure, PostSettings, TaaSettings, ToneMap, ToneOperator};

/// The post-processing passes the settings ask for (none by default), around `tonemap`.
#[derive(Default)]
pub struct PostPasses {
    taa: Option<TaaPass>,
    exposure: Option<ExposurePass>,
    bloom: Option<BloomPass>,
    fxaa: Option<FxaaPass>,
    /// The size the stages after TAA run at: the frame's, or TAA upsampling's.
    size: (u32, u32),
    /// TAA upsampling's size (`PostSettings::upsample_to`, when larger than the frame).
    upsampled: Option<(u32, u32)>,
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
        // Upsampling is a TAA pass (with TAA's defaults where TAA is not on) whose output is
        // larger than the frame; every stage after it runs at its size.
        self.upsampled = settings.upsample_to.filter(|&out| out != size);
        let out = self.upsampled.unwrap_or(size);
        let taa = match self.upsampled {
            Some(_) => Some(settings.taa.unwrap_or_default()),
            None => settings.taa,
        };
        self.taa = taa
            .map(|t| TaaPass::new(ctx, t, size, out, sampler, motion))
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
        self.size = out;
        Ok(())
    }

    /// TAA upsampling's size, when the stages from TAA on run larger than the frame.
    pub fn upsampled(&self) -> Option<(u32, u32)> {
        self.upsampled
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
