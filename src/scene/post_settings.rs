//! The post-processing settings a scene's `[post]` table gives (plain data, at the bottom so
//! that scene files, the command line and the viewer share them with `crate::post`, which
//! re-exports [`ToneOperator`] and applies [`PostOverrides`]).

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

    /// The names a scene file's `tonemap` takes (those of `--tonemap`).
    pub const NAMES: [(&'static str, ToneOperator); 4] = [
        ("linear", ToneOperator::Linear),
        ("logarithmic", ToneOperator::Logarithmic),
        ("drago", ToneOperator::Drago),
        ("filmic", ToneOperator::Filmic),
    ];
}

/// A post stage switched off, or on with its parameter (`None`: the stage's default): auto
/// exposure's key (`--auto-exposure [KEY|off]`, `auto_exposure = true | KEY | false`) and
/// bloom's strength (`--bloom STRENGTH|off`, `bloom = STRENGTH | false`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stage {
    Off,
    On(Option<f32>),
}

/// Post-processing settings given by a scene file's `[post]` table or by the command line's
/// flags; `None`: not given there. The flags override the table, which overrides the
/// defaults (`crate::post::apply_overrides`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostOverrides {
    /// TAA on or off (`taa`, `--taa [on|off]`).
    pub taa: Option<bool>,
    pub taa_history_weight: Option<f32>,
    pub taa_frames: Option<u32>,
    pub auto_exposure: Option<Stage>,
    pub exposure_adaptation: Option<f32>,
    pub bloom: Option<Stage>,
    pub fxaa: Option<bool>,
    pub dither: Option<bool>,
    pub tonemap: Option<ToneOperator>,
    /// The exposure factor (a compensation with auto exposure).
    pub exposure: Option<f32>,
}

impl PostOverrides {
    /// Nothing given.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: PostOverrides) -> PostOverrides {
        PostOverrides {
            taa: self.taa.or(fallback.taa),
            taa_history_weight: self.taa_history_weight.or(fallback.taa_history_weight),
            taa_frames: self.taa_frames.or(fallback.taa_frames),
            auto_exposure: stage_or(self.auto_exposure, fallback.auto_exposure),
            exposure_adaptation: self.exposure_adaptation.or(fallback.exposure_adaptation),
            bloom: stage_or(self.bloom, fallback.bloom),
            fxaa: self.fxaa.or(fallback.fxaa),
            dither: self.dither.or(fallback.dither),
            tonemap: self.tonemap.or(fallback.tonemap),
            exposure: self.exposure.or(fallback.exposure),
        }
    }
}

/// `a` where given, else `b`; a stage switched on without its value (`--auto-exposure` alone)
/// keeps `b`'s value when `b` has one.
fn stage_or(a: Option<Stage>, b: Option<Stage>) -> Option<Stage> {
    match (a, b) {
        (Some(Stage::On(None)), Some(Stage::On(Some(v)))) => Some(Stage::On(Some(v))),
        (a, b) => a.or(b),
    }
}
