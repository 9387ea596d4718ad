//! The indirect-light settings: which GI method a frame uses and its parameters. Plain data
//! (no GPU), here at the bottom so that scene files (`[gi]` tables), the command line
//! and the viewer's panel share them with the GI passes (`crate::gi`, which re-exports them).

/// A GI method of the speed/accuracy ladder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum GiMethod {
    /// No indirect light.
    #[default]
    None,
    /// One bounce: N rays per pixel, radiance at hits from reflective light maps
    /// (Thiedemann 2010 §6.4.1).
    Hemisphere,
    /// B bounces with albedo and normal from voxel volumes and direct light at every hit from
    /// the shadow maps, accumulated over frames (Thiedemann 2010 §6.4.2).
    Pathtrace,
    /// Virtual point lights from the reflective light maps, B bounces, interleaved sampling
    /// with voxel visibility and the geometry-aware filter (Thiedemann 2010 Ch. 7).
    Vpl,
    /// Screen-space diffuse gathering over a depth/normal/colour pyramid, unlimited bounces by
    /// feedback over frames; no voxels (Oetke 2017 §2.3, §5.1–5.3).
    Ssgi,
}

impl GiMethod {
    /// Whether the method traces rays in the voxel grid (all but screen-space GI; `None`
    /// has no passes at all).
    pub fn needs_voxels(self) -> bool {
        !matches!(self, GiMethod::None | GiMethod::Ssgi)
    }
}

/// Parameters of the indirect-light passes (all exposed on the command line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GiSettings {
    pub method: GiMethod,
    /// Rays per pixel.
    pub rays: u32,
    /// Ray length in meters; `None`: the scene's diagonal (unbounded in practice).
    pub radius_m: Option<f32>,
    /// Self-intersection offset along the normal, in voxel diagonals (Thiedemann 2010
    /// §5.3.1, k₁).
    pub normal_offset_voxels: f32,
    /// Self-intersection offset along the ray, k₂ · h / (d·n) in voxel diagonals h, clamped
    /// to `ray_offset_max_voxels` (Thiedemann 2010 §5.3.1).
    pub ray_offset_voxels: f32,
    pub ray_offset_max_voxels: f32,
    /// Light-map hit tolerance, in voxel diagonals (plus the map texel's footprint).
    pub hit_tolerance_voxels: f32,
    pub start_level: u32,
    pub max_iterations: u32,
    /// Reflective light-map resolution per view (the thesis used 256²).
    pub light_map_resolution: u32,
    /// Geometry-aware filter radius in pixels (0: off) and number of h+v passes.
    pub filter_radius: u32,
    pub filter_passes: u32,
    /// Seed of the per-pixel rotation (vary per frame to accumulate).
    pub seed: u32,
    /// Path-tracer bounces: a fixed count, or unbounded by Russian roulette.
    pub bounces: Bounces,
    /// Path tracer: sample the Phong and GGX lobes at every bounce (a material volume, in
    /// scenes with such materials); `false` makes later bounces Lambert with the base color
    /// (no material volume), kept for comparisons.
    pub pathtrace_lobes: bool,
    /// The voxel volumes sample the MTL texture maps (`map_Kd` in the albedo volume, `map_Ke`
    /// in the emission volume, `map_Pr` / `map_Pm` in the material volume) per texel at the
    /// surface in each voxel (`voxel::maps`), and the VPL emitter rays take `map_Ke`'s texel at
    /// their points; `false` gives the volumes `Kd` and each map's mean per material and the
    /// emitter rays the mean, kept for comparisons. Scenes without such
    /// maps are the same either way. (The reflective light maps sample `map_Kd` / `map_Pm`
    /// like the G-buffer either way.)
    pub voxel_map_texels: bool,
    /// Frames a headless render accumulates (path tracer; the viewer accumulates while still).
    pub accumulate_frames: u32,
    /// Where the hemisphere method reads the radiance at ray hits.
    pub radiance_source: RadianceSource,
    /// The VPL method's parameters.
    pub vpl: super::VplSettings,
    /// Modified SAO multiplied into the indirect light (`None`: no SAO passes).
    pub sao: Option<SaoSettings>,
    /// The screen-space GI's parameters (`GiMethod::Ssgi`).
    pub ssgi: SsgiSettings,
}

/// Screen-space GI (Oetke 2017 §5.1–5.3): the internal resolution, samples and pyramid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsgiSettings {
    /// The GI resolution, the finest level gathered (thesis: about 960×500 at any output
    /// size, i.e. half at 1080p).
    pub resolution: SsgiResolution,
    /// Samples per texel and level (thesis: 128; visible noise below 32–64).
    pub samples: u32,
    /// How the depth and normal mips choose their texel.
    pub mips: SsgiMips,
    /// Feed the previous frame's indirect light back into the lit colour (one more bounce per
    /// frame, Oetke 2017 §2.3).
    pub feedback: bool,
    /// The clamp of the fed-back irradiance, W/m² (Oetke 2017 §5.1 clamps at 20).
    pub feedback_max_w_m2: f32,
    /// τ of the temporal blend E = mix(E_new, E_history, τ·w) (Oetke 2017 §5.1: 0.1–0.98,
    /// 0.85–0.98 at high frame rates); 0 turns the accumulation off.
    pub history_weight: f32,
    /// Screen-space reflections (Oetke 2017 §5.4) where the scene has Phong or GGX
    /// materials; without such materials nothing is allocated either way.
    pub ssr: bool,
    /// The reflection rays' directions: the mirror direction with the lobe's width read as a
    /// coarser colour mip, or one lobe sample per pixel and frame (`--ssr-rays`).
    pub ssr_rays: SsrRays,
}

impl Default for SsgiSettings {
    fn default() -> Self {
        Self {
            resolution: SsgiResolution::Half,
            samples: 64,
            mips: SsgiMips::Voting,
            feedback: true,
            feedback_max_w_m2: 20.0,
            history_weight: 0.9,
            ssr: true,
            ssr_rays: SsrRays::Mirror,
        }
    }
}

/// `--ssr-rays`: how screen-space reflection rays choose their direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SsrRays {
    /// One ray along the mirror direction; the lobe's width picks the colour pyramid's level
    /// at the hit (Oetke 2017 §5.4): deterministic, blurs only where the ray hits.
    #[default]
    Mirror,
    /// One ray per pixel and frame importance-sampled from the pixel's lobe (GGX visible
    /// normals, Heitz 2018; Phong cosⁿ), read at the colour's finest level and averaged by
    /// the history: converges to the lobe's reflection over frames. Lobes narrower than a
    /// pixel keep the mirror ray.
    Lobe,
}

impl SsrRays {
    /// The names the scene file's `ssr_rays` (and `--ssr-rays`) take.
    pub const NAMES: [(&'static str, SsrRays); 2] =
        [("mirror", SsrRays::Mirror), ("lobe", SsrRays::Lobe)];
}

/// `--ssr on|off`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SsrMode {
    /// Reflection rays where the scene has Phong or GGX materials.
    #[default]
    On,
    /// The diffuse fallback only (the image before reflection rays).
    Off,
}

/// Scalable Ambient Obscurance as modified by Oetke 2017 §2.5 (after McGuire et al. 2012):
/// the estimator's constants, with the thesis's values as defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SaoSettings {
    /// r: world-space sample radius, meters (thesis: 1.8).
    pub radius_m: f32,
    /// β: bias subtracted from v·n, meters (thesis: 0.04).
    pub bias: f32,
    /// k: the contrast exponent of the AO term (thesis: 2).
    pub contrast: f32,
    /// ε in the denominator v·v + ε, m² (thesis: 0.01).
    pub epsilon_m2: f32,
    /// Show the AO term (grey, 1 = unoccluded) instead of the lit image (`--debug sao`).
    pub view: bool,
}

impl SaoSettings {
    /// Taps on the spiral (Oetke 2017 Eq. 2.20, N = 16).
    pub const TAPS: u32 = 16;
    /// Spiral turns τ (7, as the thesis's code uses).
    pub const SPIRAL_TURNS: f32 = 7.0;
}

impl Default for SaoSettings {
    fn default() -> Self {
        Self {
            radius_m: 1.8,
            bias: 0.04,
            contrast: 2.0,
            epsilon_m2: 0.01,
            view: false,
        }
    }
}

/// SAO settings given by a scene's `[gi]` table (`sao`, `sao_radius_m`, `sao_bias`,
/// `sao_contrast`, `sao_epsilon_m2`) or by the `--sao*` flags; `None`: not given there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SaoOverrides {
    /// SAO on or off (`sao = true`, `--sao [on|off]`).
    pub enabled: Option<bool>,
    pub radius_m: Option<f32>,
    pub bias: Option<f32>,
    pub contrast: Option<f32>,
    pub epsilon_m2: Option<f32>,
}

impl SaoOverrides {
    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: SaoOverrides) -> SaoOverrides {
        SaoOverrides {
            enabled: self.enabled.or(fallback.enabled),
            radius_m: self.radius_m.or(fallback.radius_m),
            bias: self.bias.or(fallback.bias),
            contrast: self.contrast.or(fallback.contrast),
            epsilon_m2: self.epsilon_m2.or(fallback.epsilon_m2),
        }
    }

    /// Whether a value of the estimator (not the switch) is given.
    pub fn has_values(&self) -> bool {
        SaoOverrides {
            enabled: None,
            ..*self
        } != SaoOverrides::default()
    }

    /// `base` with the given values replaced: off when `enabled` says so (or when it is not
    /// given and `base` is off), else `base`'s values (the defaults when `base` is off) with
    /// the given ones replaced.
    pub fn apply(&self, base: Option<SaoSettings>) -> Option<SaoSettings> {
        if !self.enabled.unwrap_or(base.is_some()) {
            return None;
        }
        let b = base.unwrap_or_default();
        Some(SaoSettings {
            radius_m: self.radius_m.unwrap_or(b.radius_m),
            bias: self.bias.unwrap_or(b.bias),
            contrast: self.contrast.unwrap_or(b.contrast),
            epsilon_m2: self.epsilon_m2.unwrap_or(b.epsilon_m2),
            view: b.view,
        })
    }
}

/// The screen-space GI's internal resolution: the frame's divided by a power of two.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum SsgiResolution {
    Full,
    #[default]
    Half,
    Quarter,
    Eighth,
}

impl SsgiResolution {
    /// The names a scene file's `ssgi_resolution` takes (those of the flag).
    pub const NAMES: [(&'static str, SsgiResolution); 4] = [
        ("full", SsgiResolution::Full),
        ("half", SsgiResolution::Half),
        ("quarter", SsgiResolution::Quarter),
        ("eighth", SsgiResolution::Eighth),
    ];

    /// The frame's size over the GI resolution's.
    pub fn divisor(self) -> u32 {
        match self {
            SsgiResolution::Full => 1,
            SsgiResolution::Half => 2,
            SsgiResolution::Quarter => 4,
            SsgiResolution::Eighth => 8,
        }
    }
}

/// How the screen-space GI's depth and normal mips pick the texel of each 2×2 block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum SsgiMips {
    /// SHR10's voting filter as Oetke 2017 §5.3 approximates it (temporally stable).
    #[default]
    Voting,
    /// The first non-sky child (the thesis's fast nearest-neighbour blit).
    Fast,
}

impl SsgiMips {
    /// The names the scene file's `ssgi_mips` (and `--ssgi-mips`) take.
    pub const NAMES: [(&'static str, SsgiMips); 2] =
        [("voting", SsgiMips::Voting), ("fast", SsgiMips::Fast)];
}

/// Screen-space GI settings given by a scene's `[gi]` table or by flags; `None`: not given
/// there (see [`crate::scene::resolve_gi`] for the precedence).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SsgiOverrides {
    pub resolution: Option<SsgiResolution>,
    pub samples: Option<u32>,
    pub mips: Option<SsgiMips>,
    pub feedback: Option<bool>,
    pub feedback_max_w_m2: Option<f32>,
    pub history_weight: Option<f32>,
    pub ssr: Option<bool>,
    pub ssr_rays: Option<SsrRays>,
}

impl SsgiOverrides {
    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: SsgiOverrides) -> SsgiOverrides {
        SsgiOverrides {
            resolution: self.resolution.or(fallback.resolution),
            samples: self.samples.or(fallback.samples),
            mips: self.mips.or(fallback.mips),
            feedback: self.feedback.or(fallback.feedback),
            feedback_max_w_m2: self.feedback_max_w_m2.or(fallback.feedback_max_w_m2),
            history_weight: self.history_weight.or(fallback.history_weight),
            ssr: self.ssr.or(fallback.ssr),
            ssr_rays: self.ssr_rays.or(fallback.ssr_rays),
        }
    }

    /// `base` with the given values replaced.
    pub fn apply(&self, base: SsgiSettings) -> SsgiSettings {
        SsgiSettings {
            resolution: self.resolution.unwrap_or(base.resolution),
            samples: self.samples.unwrap_or(base.samples),
            mips: self.mips.unwrap_or(base.mips),
            feedback: self.feedback.unwrap_or(base.feedback),
            feedback_max_w_m2: self.feedback_max_w_m2.unwrap_or(base.feedback_max_w_m2),
            history_weight: self.history_weight.unwrap_or(base.history_weight),
            ssr: self.ssr.unwrap_or(base.ssr),
            ssr_rays: self.ssr_rays.unwrap_or(base.ssr_rays),
        }
    }
}

/// How long the path tracer's paths are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounces {
    /// Exactly this many bounces (1..=[`Bounces::MAX`]): biased low by the light of the
    /// bounces left out.
    Fixed(u32),
    /// [`Bounces::ROULETTE_AFTER`] bounces, then Russian roulette: unbiased but for the
    /// safety cap of [`Bounces::MAX`] bounces (see `glsl/gi_pathtrace.comp` for its bound).
    Unbounded,
}

impl Bounces {
    /// The most bounces a path takes: the largest fixed count and the safety cap of the
    /// unbounded setting (`MAX_PATH_BOUNCES` in `glsl/gi_pathtrace.comp`).
    pub const MAX: u32 = 64;
    /// Bounces an unbounded path always takes before Russian roulette may end it
    /// (`ROULETTE_AFTER` in `glsl/gi_pathtrace.comp`).
    pub const ROULETTE_AFTER: u32 = 3;
    /// The spelling of [`Bounces::Unbounded`] on the command line and in scene files.
    pub const UNBOUNDED_NAME: &'static str = "unbounded";

    /// What a flag or scene value must be, for error messages.
    pub fn expected() -> String {
        format!(
            "an integer in [1, {}] or \"{}\" (Russian roulette)",
            Self::MAX,
            Self::UNBOUNDED_NAME
        )
    }

    /// A fixed count checked against [1, MAX].
    pub fn fixed(n: i64) -> Option<Bounces> {
        (1..=i64::from(Self::MAX))
            .contains(&n)
            .then_some(Bounces::Fixed(n as u32))
    }
}

impl std::fmt::Display for Bounces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Bounces::Fixed(n) => write!(f, "{n}"),
            Bounces::Unbounded => f.write_str(Self::UNBOUNDED_NAME),
        }
    }
}

/// Parses `--gi-bounces`: a count or `unbounded` (clap names the flag in its error).
impl std::str::FromStr for Bounces {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == Self::UNBOUNDED_NAME {
            return Ok(Bounces::Unbounded);
        }
        s.parse::<i64>()
            .ok()
            .and_then(Bounces::fixed)
            .ok_or_else(|| format!("expected {}", Bounces::expected()))
    }
}

/// Where hemisphere sampling reads the radiance leaving a hit surface (Thiedemann 2010 §6.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum RadianceSource {
    /// Reflective light maps rendered per shadow view (radiance, position, normal).
    #[default]
    Maps,
    /// A direct-radiance voxel volume congruent with the bits (its diffuse part; a glossy
    /// sender's lobe is evaluated at the hit from the material volume).
    Volume,
}

impl Default for GiSettings {
    fn default() -> Self {
        Self {
            method: GiMethod::None,
            rays: 16,
            radius_m: None,
            normal_offset_voxels: 1.0,
            ray_offset_voxels: 0.0,
            ray_offset_max_voxels: 4.0,
            hit_tolerance_voxels: 1.5,
            start_level: 1,
            max_iterations: 1024,
            light_map_resolution: 256,
            filter_radius: 4,
            filter_passes: 2,
            seed: 0,
            bounces: Bounces::Fixed(2),
            pathtrace_lobes: true,
            voxel_map_texels: true,
            accumulate_frames: 1,
            radiance_source: RadianceSource::Maps,
            vpl: super::VplSettings::default(),
            sao: None,
            ssgi: SsgiSettings::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounces_parse_and_print() {
        use std::str::FromStr;
        for n in [1, 2, 3, 8, Bounces::MAX] {
            let b = Bounces::from_str(&n.to_string());
            assert_eq!(b, Ok(Bounces::Fixed(n)));
        }
        assert_eq!(Bounces::from_str("unbounded"), Ok(Bounces::Unbounded));
        for b in [Bounces::Fixed(5), Bounces::Unbounded] {
            assert_eq!(Bounces::from_str(&b.to_string()), Ok(b), "round trip");
        }
        for bad in ["0", "65", "-1", "inf", "Unbounded", "", "2.5"] {
            let e = Bounces::from_str(bad).expect_err(bad);
            assert!(
                e.contains("[1, 64]") && e.contains("\"unbounded\""),
                "{bad}: {e}"
            );
        }
    }
}
