//! The post-processing settings: plain data at the bottom, so that scene files (`[post]`
//! tables), the command line and the viewer's panel share them with `crate::post`, which
//! re-exports them. The `[post]` keys are declared once, in [`PostTable::keys`]'s table
//! (`scene::schema`).

use super::schema::{
    choices, flag, toggle, FieldValue, Flag, FlagStyle, Key, Kind, Settings, Value,
};

/// Tone-mapping operator of `glsl/tonemap.comp`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
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
    /// TAA upsampling into this size, larger than the frame: the viewer's dynamic resolution
    /// with `post.upscale = "taa"` (`post::taa`). The TAA pass resolves the jittered frame
    /// into a history of this size, and the stages after it run at this size. `None`: TAA,
    /// where on, at the frame's size. No scene key or flag sets it.
    pub upsample_to: Option<(u32, u32)>,
}

impl PostSettings {
    /// Whether the G-buffer draws motion vectors: only for a scene with moving objects
    /// (`moving`) under TAA that asks for them.
    pub fn motion_vectors(&self, moving: bool) -> bool {
        moving && self.taa.is_some_and(|t| t.motion_vectors)
    }
}

/// The viewer's dynamic resolution (`docs/design/dynamic-resolution.md`): the scene renders
/// at an internal scale of the window chosen to hold a GPU frame-time budget, upscaled to the
/// window, and refines to the full size when the camera stops. Only the viewer reads it; a
/// headless render is always at its full size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicResolution {
    /// The GPU time a frame may take, ms; 0 turns dynamic resolution off (always full size).
    pub frame_budget_ms: f32,
    /// The smallest internal scale (per axis) the viewer goes down to.
    pub min_scale: f32,
    /// Still frames after which the viewer renders at the full size again; 0: never.
    pub refine_frames: u32,
    /// The viewer's GI follows the scale (`app::dynres::ScaleController::gi`): temporal
    /// accumulation on unless the scene or a flag sets `gi.temporal`, and
    /// [`MOVING_GI_RAYS`] per pixel while the scale is below full.
    pub dynamic_gi: bool,
    /// How the internal frame reaches the window's size while scaled.
    pub upscale: Upscale,
}

/// How the viewer upscales its internal frame to the window under dynamic resolution
/// (`post.upscale`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Upscale {
    /// The tone-mapped frame, blitted with a bilinear filter. The default: on lavapipe TAA
    /// upsampling into a 969×720 area costs 205 ms (the pass) and 58 ms (tone mapping at that
    /// size) per frame, more than twice the 100 ms budget, against 13 ms for the blit.
    #[default]
    Bilinear,
    /// TAA upsampling: each frame renders with a sub-pixel jitter and the TAA pass blends its
    /// samples, by their distance to each window pixel's centre, into a history of the
    /// window's size (Karis 2014; the FSR 2 reconstruction), so a still or slow camera
    /// gains the detail of the full size over the frames. Its passes run at the window's
    /// size: for a GPU that has the time.
    Taa,
}

/// GI rays per pixel the viewer traces while its scale is below full (`post.dynamic_gi`):
/// with temporal accumulation one ray per pixel and frame converges over the frames (the
/// issue's "1–2 rays per pixel per frame"), and the path tracer's cost is linear in its rays,
/// so this is the largest saving after the scale itself.
pub const MOVING_GI_RAYS: u32 = 1;

impl DynamicResolution {
    /// Whether the viewer scales at all.
    pub fn on(&self) -> bool {
        self.frame_budget_ms > 0.0
    }
}

impl Default for DynamicResolution {
    /// 100 ms: the point of the default is a viewer that answers on any device, a software
    /// rasterizer included (lavapipe on two cores takes 8.9 s for the default path-traced
    /// 1280×720 frame); a GPU that draws the full frame within it is never scaled. A scale of
    /// 1/8 (160×90 of 1280×720) is the floor: below it the upscaled image no longer shows
    /// the scene's shapes. 30 still frames (a few seconds on lavapipe) before refining:
    /// long enough not to refine between two key presses.
    fn default() -> Self {
        Self {
            frame_budget_ms: 100.0,
            min_scale: 0.125,
            refine_frames: 30,
            dynamic_gi: true,
            upscale: Upscale::Bilinear,
        }
    }
}

/// The `[post]` table's settings: the stages around tone mapping, the tone map and the
/// viewer's dynamic resolution. Apart because a frame keeps them apart: a new tone map only
/// needs a new frame graph, a new stage a new renderer, and the dynamic resolution is the
/// viewer's alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostTable {
    pub post: PostSettings,
    pub tonemap: ToneMap,
    pub dynres: DynamicResolution,
}

/// A stage's value (`taa $f` of [`TaaSettings`], `auto_exposure $f` of [`AutoExposure`]),
/// written into the stage, which it switches on with the defaults for the others; the stage's
/// switch, written after its values, switches it off again where it is not on (as `gi.sao`
/// does for SAO's values).
macro_rules! key {
    ($path:literal, $kind:expr, $doc:literal, $flag:expr, stage $stage:ident $f:ident) => {
        crate::settings_key!(PostTable; $path, $kind, $doc, $flag,
            get |s: &PostTable| FieldValue::to_value(&s.post.$stage.unwrap_or_default().$f),
            set |s: &mut PostTable, v| {
                if let Some(x) = FieldValue::from_value(v) {
                    s.post.$stage.get_or_insert_with(Default::default).$f = x;
                }
            })
    };
    ($($t:tt)*) => {
        crate::settings_key!(PostTable; $($t)*)
    };
}

use range::*;

/// Every `[post]` key: the scene file's key, the path `--set` and the panel use, its range,
/// its flag and its field.
static POST_KEYS: [Key<PostTable>; 16] = [
    key!("post.taa_history_weight", Kind::Number(TAA_HISTORY_WEIGHT),
        "TAA history weight α: each frame keeps α of the reprojected history",
        flag("taa-history-weight", "ALPHA"), stage taa history_weight),
    key!("post.taa_frames", Kind::Count(TAA_FRAMES),
        "Frames a headless render with TAA runs; the viewer blends one per frame and has no \
         count",
        flag("taa-frames", "N"), stage taa frames),
    // After the TAA values.
    key!("post.taa", Kind::Bool,
    "Temporal anti-aliasing: Halton(2,3) sub-pixel jitter, reprojected and clipped history \
     (a headless render runs --taa-frames frames); `--taa off` turns off the scene's",
    toggle("taa"),
    get |s: &PostTable| Value::Bool(s.post.taa.is_some()),
    set |s: &mut PostTable, v| if let Value::Bool(on) = v {
        s.post.taa = on.then(|| s.post.taa.unwrap_or_default());
    }),
    key!("post.exposure_adaptation", Kind::Number(EXPOSURE_ADAPTATION),
        "Auto exposure: fraction of the way (in log exposure) to the target per frame",
        flag("exposure-adaptation", "F"), stage auto_exposure adaptation),
    // After the adaptation.
    key!("post.auto_exposure", Kind::Switch(AUTO_EXPOSURE_KEY, true),
    "Auto exposure: exposure = KEY / log-average luminance (KEY 0.18 when left out), \
     adapted over frames; --exposure then multiplies it as a compensation; `off` turns off \
     the scene's",
    Some(Flag { long: "auto-exposure", value_name: "KEY|off", style: FlagStyle::OptionalValue }),
    get |s: &PostTable| s.post.auto_exposure.map_or(Value::Bool(false), |a| Value::Number(a.key)),
    set |s: &mut PostTable, v| match v {
        Value::Number(key) => {
            s.post.auto_exposure = Some(AutoExposure { key, ..s.post.auto_exposure.unwrap_or_default() });
        }
        Value::Bool(on) => s.post.auto_exposure = on.then(|| s.post.auto_exposure.unwrap_or_default()),
        _ => {}
    }),
    key!("post.bloom", Kind::Switch(BLOOM_STRENGTH, false),
    "Bloom: moves the share STRENGTH of the radiance into a wide blur (energy-conserving, \
     no threshold); `off` turns off the scene's",
    flag("bloom", "STRENGTH|off"),
    get |s: &PostTable| s.post.bloom.map_or(Value::Bool(false), Value::Number),
    set |s: &mut PostTable, v| match v {
        Value::Number(x) => s.post.bloom = Some(x),
        Value::Bool(false) => s.post.bloom = None,
        _ => {}
    }),
    key!(
        "post.fxaa",
        Kind::Bool,
        "FXAA on the tone-mapped image",
        toggle("fxaa"),
        post.fxaa
    ),
    key!(
        "post.dither",
        Kind::Bool,
        "Triangular dither of ±1/255 before the 8-bit quantization (no banding on gradients)",
        toggle("dither"),
        tonemap.dither
    ),
    key!("post.tonemap", Kind::Choice(choices::<ToneOperator>), "Tone-mapping operator",
        flag("tonemap", "TONEMAP"), choice ToneOperator, tonemap.operator),
    key!(
        "post.exposure",
        Kind::Number(EXPOSURE),
        "Exposure factor before tone mapping (a compensation with auto exposure)",
        flag("exposure", "E"),
        tonemap.exposure
    ),
    key!(
        "post.white",
        Kind::Number(WHITE),
        "Luminance (after exposure) the logarithmic and Drago operators map to display white",
        flag("tonemap-white", "L"),
        tonemap.white
    ),
    key!(
        "post.frame_budget_ms",
        Kind::Number(FRAME_BUDGET_MS),
        "The viewer's GPU frame-time budget, ms: it renders at a reduced internal resolution \
         (upscaled to the window) to hold it, and refines when the camera stops; 0 turns \
         dynamic resolution off. Headless renders are always full size",
        flag("frame-budget-ms", "MS"),
        dynres.frame_budget_ms
    ),
    key!(
        "post.min_scale",
        Kind::Number(MIN_SCALE),
        "The viewer's smallest internal resolution under dynamic resolution, as a fraction \
         of the window's (per axis; used in steps of 1/8)",
        None,
        dynres.min_scale
    ),
    key!(
        "post.refine_frames",
        Kind::Count(REFINE_FRAMES),
        "Still frames after which the viewer under dynamic resolution renders at the full \
         size again; 0: never",
        None,
        dynres.refine_frames
    ),
    key!(
        "post.dynamic_gi",
        Kind::Bool,
        "The viewer's GI follows dynamic resolution: temporal accumulation on unless the scene \
         or a flag sets gi.temporal, and 1 GI ray per pixel while the scale is below full (the \
         scene's count when refined); false keeps the scene's GI settings. Headless renders \
         are not affected",
        None,
        dynres.dynamic_gi
    ),
    key!("post.upscale", Kind::Choice(choices::<Upscale>),
        "How the viewer upscales its reduced internal resolution to the window: bilinear (a \
         filtered blit of each frame) or taa (jittered frames resolved into a history of the \
         window's size, which regains detail while the camera is still or slow, at the cost \
         of a TAA pass and tone mapping at the window's size)",
        None, choice Upscale, dynres.upscale),
];

impl Settings for PostTable {
    const TABLE: &'static str = "post";
    fn keys() -> &'static [Key<Self>] {
        &POST_KEYS
    }
}

/// The ranges of the `[post]` keys (and their flags), which [`PostTable::keys`] gives each
/// key; the panel's sliders are cut to them.
pub mod range {
    use crate::limits::Limit;

    /// Exposure multiplies the radiance before tone mapping; 0 would be black, NaN garbage.
    pub const EXPOSURE: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--exposure",
            Some("post.exposure"),
            "an exposure factor",
            0.0,
            1e6,
        )
    };
    /// TAA history weight α in [0, 0.999]: 1 would never let the current frame in.
    pub const TAA_HISTORY_WEIGHT: Limit<f32> = Limit::new(
        "--taa-history-weight",
        Some("post.taa_history_weight"),
        "a TAA history weight",
        0.0,
        0.999,
    );
    /// Frames of a headless TAA render.
    pub const TAA_FRAMES: Limit<u32> = Limit::new(
        "--taa-frames",
        Some("post.taa_frames"),
        "a number of TAA frames",
        1,
        4096,
    );
    /// Auto exposure's key value (the display luminance of the log-average scene luminance).
    pub const AUTO_EXPOSURE_KEY: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--auto-exposure",
            Some("post.auto_exposure"),
            "an auto exposure key value",
            0.0,
            1e3,
        )
    };
    /// Auto exposure's adaptation per frame: 0 would never adapt, 1 jumps at once.
    pub const EXPOSURE_ADAPTATION: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--exposure-adaptation",
            Some("post.exposure_adaptation"),
            "an adaptation fraction per frame",
            0.0,
            1.0,
        )
    };
    /// The logarithmic operators divide by log(1 + white): positive (`glsl/tonemap.comp`
    /// clamps it to 1e-6 for the same reason), at most the exposure's range.
    pub const WHITE: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--tonemap-white",
            Some("post.white"),
            "a white luminance",
            0.0,
            1e6,
        )
    };
    /// The viewer's frame budget: 0 is off; up to a minute a frame (beyond it the budget
    /// holds nothing anyway).
    pub const FRAME_BUDGET_MS: Limit<f32> = Limit::new(
        "--frame-budget-ms",
        Some("post.frame_budget_ms"),
        "a frame budget in ms",
        0.0,
        60_000.0,
    );
    /// The smallest internal scale: the viewer's steps are eighths, so 1/8 is the least.
    pub const MIN_SCALE: Limit<f32> = Limit::new(
        "--set post.min_scale",
        Some("post.min_scale"),
        "a scale of the window's size",
        0.125,
        1.0,
    );
    /// Still frames before refining (0: never).
    pub const REFINE_FRAMES: Limit<u32> = Limit::new(
        "--set post.refine_frames",
        Some("post.refine_frames"),
        "a number of frames",
        0,
        100_000,
    );
    /// Bloom strength: the share of the radiance moved into the blur.
    pub const BLOOM_STRENGTH: Limit<f32> = Limit::new(
        "--bloom",
        Some("post.bloom"),
        "a bloom strength (share of the radiance)",
        0.0,
        1.0,
    );
}
