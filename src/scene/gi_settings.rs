//! The indirect-light settings: which GI method a frame uses and its parameters. Plain data
//! (no GPU), here at the bottom so that scene files (`[gi]` tables), the command line
//! and the viewer's panel share them with the GI passes (`crate::gi`, which re-exports them).
//! The `[gi]` keys are declared once, in [`GiSettings::keys`]'s table (`scene::schema`).

use super::schema::{
    choices, flag, toggle, FieldValue, Flag, FlagStyle, Key, Kind, Settings, Value,
};

/// A GI method of the speed/accuracy ladder. Only the names live here, at the bottom, so that
/// settings can hold one; what a method does and needs is its spec (`crate::gi::MethodSpec`),
/// in the file named after it in `gi/method/`, found by `GiMethod::spec`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum GiMethod {
    /// Direct light only.
    #[default]
    None,
    Hemisphere,
    Pathtrace,
    Vpl,
    Ssgi,
}

impl GiMethod {
    /// Every method, in the order the panel, the `G` key and `--help` list them.
    pub const ALL: &'static [GiMethod] = &[
        GiMethod::None,
        GiMethod::Hemisphere,
        GiMethod::Pathtrace,
        GiMethod::Vpl,
        GiMethod::Ssgi,
    ];
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
    /// Which spatial filter smooths the indirect light.
    pub filter: GiFilterKind,
    /// Filter radius in pixels (0: off) and number of passes: the geometry-aware filter's
    /// h+v pass pairs, or SVGF's à-trous iterations (radius unused there, except 0: off).
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
    /// Path tracer: next-event estimation toward the scene's emissive triangles at every path
    /// vertex, picked by power, combined with the BSDF-sampled rays' emitter hits by multiple
    /// importance sampling (`gi::emitters`); the hemisphere method's radiance volume samples
    /// them at every voxel too, for the light the voxel reflects. Scenes without emissive
    /// triangles are the same either way.
    pub emitter_sampling: bool,
    /// Direct light of an environment map (`direct_emitters`) and the path tracer: draw a
    /// share α of the directions from the map's luminance (`scene::environment::EnvironmentCdf`,
    /// α per map from how concentrated its power is, 0 to 1/2), combined with the cosine and
    /// lobe samples by the balance heuristic; `false` samples the map by the cosine and lobe
    /// samples alone. Scenes without a map (or with a constant) are the same either way.
    pub env_sampling: bool,
    /// The voxel volumes sample the MTL texture maps (`map_Kd` in the albedo volume, `map_Ke`
    /// in the emission volume, `map_Pr` / `map_Pm` in the material volume) per texel at the
    /// surface in each voxel (`voxel::maps`), and the VPL emitter rays take `map_Ke`'s texel at
    /// their points; `false` gives the volumes `Kd` and each map's mean per material and the
    /// emitter rays the mean, kept for comparisons. Scenes without such
    /// maps are the same either way. (The reflective light maps sample `map_Kd` / `map_Pm`
    /// like the G-buffer either way.)
    pub voxel_map_texels: bool,
    /// Frames a headless render accumulates (path tracer, and every method under `temporal`;
    /// the viewer accumulates while still).
    pub accumulate_frames: u32,
    /// Temporal accumulation (`gi::gi_temporal`): the voxel methods' indirect light is
    /// reprojected from the previous frames with the camera and the motion vectors, blended
    /// with this frame's, and the sample pattern advances every frame; disoccluded pixels
    /// start over, a light change starts every pixel over.
    pub temporal: bool,
    /// The longest history a pixel keeps under `temporal` (frames): up to it a still pixel
    /// holds the plain mean of its frames, after it an exponential mean of about twice as
    /// many.
    pub temporal_frames: u32,
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
    /// N: taps on the spiral per pixel (Oetke 2017 Eq. 2.20, N = 16): fewer are faster and
    /// noisier before the blur.
    pub taps: u32,
    /// Show the AO term (grey, 1 = unoccluded) instead of the lit image (`--debug sao`).
    pub view: bool,
}

impl SaoSettings {
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
            taps: 16,
            view: false,
        }
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

/// The spatial filter of the indirect light (`crate::gi`, before the composite).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum GiFilterKind {
    /// The geometry-aware filter (Herzog et al. 2010, Thiedemann 2010 §8.6.1): a separable
    /// joint bilateral blur by distance, normal and tangent plane.
    #[default]
    Geometric,
    /// Spatiotemporal variance-guided filtering (Schied et al. 2017 §4.4): an à-trous wavelet
    /// filter of 5×5 taps at spacing 2^i, its luminance weight guided by a variance
    /// estimate that each iteration filters along.
    Svgf,
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
            filter: GiFilterKind::Geometric,
            filter_radius: 4,
            filter_passes: 2,
            seed: 0,
            bounces: Bounces::Fixed(2),
            pathtrace_lobes: true,
            emitter_sampling: true,
            env_sampling: true,
            voxel_map_texels: true,
            accumulate_frames: 1,
            temporal: false,
            temporal_frames: 64,
            radiance_source: RadianceSource::Maps,
            vpl: super::VplSettings::default(),
            sao: None,
            ssgi: SsgiSettings::default(),
        }
    }
}

/// An SAO value ([`GiSettings::sao`]'s field `$f`), written into the estimator's settings,
/// which it switches on with the defaults for the others; `gi.sao`, written after every
/// value, switches it off again where it is not on. So values without the switch leave SAO
/// off, and a layer that only switches it on keeps the values of the layers below.
macro_rules! key {
    ($path:literal, $kind:expr, $doc:literal, $flag:expr, sao $f:ident) => {
        crate::settings_key!(GiSettings; $path, $kind, $doc, $flag,
            get |s: &GiSettings| FieldValue::to_value(&s.sao.unwrap_or_default().$f),
            set |s: &mut GiSettings, v| {
                if let Some(x) = FieldValue::from_value(v) {
                    s.sao.get_or_insert_with(SaoSettings::default).$f = x;
                }
            })
    };
    ($($t:tt)*) => {
        crate::settings_key!(GiSettings; $($t)*)
    };
}

use range::*;

/// Every `[gi]` key: the scene file's key, the path `--set`, the sweep's grid and the panel
/// use, its range, its flag and its field.
static GI_KEYS: [Key<GiSettings>; 41] = [
    key!("gi.method", Kind::Choice(choices::<GiMethod>),
        "Indirect-light method (none: direct light only)",
        flag("gi", "METHOD"), choice GiMethod, method),
    key!(
        "gi.rays",
        Kind::Count(GI_RAYS),
        "GI rays per pixel",
        flag("gi-rays", "N"),
        rays
    ),
    key!(
        "gi.bounces",
        Kind::CountOr(GI_BOUNCES, Bounces::UNBOUNDED_NAME, "(Russian roulette)"),
        "Path-tracer bounces, or `unbounded`: 3 bounces, then Russian roulette ends each path \
         (unbiased; capped at 64)",
        flag("gi-bounces", "B"),
        bounces
    ),
    key!(
        "gi.emitter_sampling",
        Kind::Bool,
        "Path tracer: sample emissive triangles by power at every path vertex (next-event \
         estimation, MIS with the BSDF rays); radiance volume: at every voxel, for the light \
         its rays' hits reflect; off: emitters are found only by the rays",
        toggle("emitter-sampling"),
        emitter_sampling
    ),
    key!(
        "gi.env_sampling",
        Kind::Bool,
        "Environment map's direct light and path tracer: draw a share of the directions \
         from the map's luminance (by how concentrated its power is: half for a sun, none \
         for a sky as smooth as a constant), combined with the cosine and lobe samples by \
         MIS; off: the map is found only by cosine and lobe samples",
        toggle("env-sampling"),
        env_sampling
    ),
    key!(
        "gi.radius_m",
        Kind::OptNumber(GI_RADIUS_M, "the scene's diagonal"),
        "GI ray length in meters",
        flag("gi-radius", "M"),
        radius_m
    ),
    key!(
        "gi.normal_offset_voxels",
        Kind::Number(GI_NORMAL_OFFSET),
        "Self-intersection offset along the normal, in voxel diagonals (thesis k1)",
        flag("gi-normal-offset", "K1"),
        normal_offset_voxels
    ),
    key!(
        "gi.ray_offset_voxels",
        Kind::Number(GI_RAY_OFFSET),
        "Self-intersection offset along the ray, in voxel diagonals over cos (thesis k2)",
        flag("gi-ray-offset", "K2"),
        ray_offset_voxels
    ),
    key!("gi.filter", Kind::Choice(choices::<GiFilterKind>),
        "The indirect light's spatial filter: the geometry-aware joint bilateral blur \
         (Thiedemann 2010), or SVGF's variance-guided à-trous wavelet (Schied et al. 2017)",
        flag("gi-filter", "FILTER"), choice GiFilterKind, filter),
    key!(
        "gi.filter_radius",
        Kind::Count(GI_FILTER_RADIUS),
        "Filter radius in pixels, 0: off (SVGF: only 0 counts; its footprint grows with its \
         passes)",
        flag("gi-filter-radius", "R"),
        filter_radius
    ),
    key!(
        "gi.filter_passes",
        Kind::Count(GI_FILTER_PASSES),
        "Filter passes: the geometry-aware filter's horizontal + vertical pairs, or SVGF's \
         à-trous iterations (taps 2^i pixels apart; 5 reach 62 pixels)",
        flag("gi-filter-passes", "P"),
        filter_passes
    ),
    key!(
        "gi.light_map_resolution",
        Kind::Count(LIGHT_MAP_RESOLUTION),
        "Reflective light-map resolution per light view",
        flag("light-map-resolution", "L"),
        light_map_resolution
    ),
    key!(
        "gi.accumulate_frames",
        Kind::Count(GI_FRAMES),
        "Frames a headless render accumulates (the path tracer, and every method under \
         `gi.temporal`)",
        flag("gi-frames", "F"),
        accumulate_frames
    ),
    key!(
        "gi.temporal",
        Kind::Bool,
        "Temporal accumulation of the voxel methods' indirect light: reprojected by camera and \
         motion vectors, disocclusions rejected by depth and normal, the sample pattern \
         advanced every frame, the filter stepping back as the variance of the mean falls",
        toggle("gi-temporal"),
        temporal
    ),
    key!(
        "gi.temporal_frames",
        Kind::Count(GI_TEMPORAL_FRAMES),
        "`gi.temporal`: the longest history a pixel keeps, in frames",
        flag("gi-temporal-frames", "N"),
        temporal_frames
    ),
    key!("gi.radiance_source", Kind::Choice(choices::<RadianceSource>),
        "Where hemisphere sampling reads the radiance at ray hits: reflective light maps or a \
         direct-radiance voxel volume",
        flag("gi-radiance", "SOURCE"), choice RadianceSource, radiance_source),
    key!(
        "gi.start_level",
        Kind::Count(GI_START_LEVEL),
        "Hierarchy level GI rays start their traversal at (Thiedemann 2010, §5.3.2)",
        flag("gi-start-level", "LEVEL"),
        start_level
    ),
    key!(
        "gi.max_iterations",
        Kind::Count(GI_MAX_ITERATIONS),
        "Iteration cap of GI rays' hierarchical traversal (too low shows as missing indirect \
         shadows, thesis Fig. 46)",
        flag("gi-max-iterations", "N"),
        max_iterations
    ),
    key!(
        "gi.vpls",
        Kind::Count(VPLS),
        "`--gi vpl`: VPLs per interleaving set and light (thesis §7.2)",
        flag("vpls", "K"),
        vpl.per_set
    ),
    key!(
        "gi.vpl_pattern",
        Kind::Pair(VPL_PATTERN_SIDE),
        "`--gi vpl`: interleaved-sampling pattern NxM, N·M VPL sets (thesis §7.3.2)",
        flag("vpl-pattern", "NxM"),
        vpl.pattern
    ),
    key!(
        "gi.vpl_bounces",
        Kind::Count(VPL_BOUNCES),
        "`--gi vpl`: VPL bounces: 1 reflects the lights' direct light once, 2 adds one voxel \
         ray per VPL (thesis §7.2)",
        flag("vpl-bounces", "B"),
        vpl.bounces
    ),
    key!(
        "gi.vpl_d_min_voxels",
        Kind::Number(VPL_D_MIN),
        "`--gi vpl`: d_min of E = I cos cos / (d_min + d²) (thesis §7.3) as a distance in voxel \
         diagonals h: d_min = (D · h)²",
        flag("vpl-d-min", "D"),
        vpl.d_min_voxels
    ),
    key!(
        "gi.vpl_min_roughness",
        Kind::Number(VPL_MIN_ROUGHNESS),
        "`--gi vpl`: the roughness floor of glossy receivers: GGX pixels are shaded with \
         roughness max(r, R) toward the VPLs, Phong exponents capped at 2/R⁴ − 2",
        flag("vpl-min-roughness", "R"),
        vpl.min_roughness
    ),
    key!("gi.vpl_visibility", Kind::Choice(choices::<super::VplVisibility>),
        "`--gi vpl`: visibility per VPL and pixel: the voxel segment test, or none (v = 1)",
        flag("vpl-visibility", "V"), choice super::VplVisibility, vpl.visibility),
    key!("gi.vpl_normalize", Kind::Choice(choices::<super::vpl_settings::VplNormalize>),
        "`--gi vpl`: divide a light's flux among all K samples of its emission domain \
         (unbiased) or among the valid ones only (the thesis's renormalization)",
        flag("vpl-normalize", "N"),
        choice super::vpl_settings::VplNormalize, vpl.normalize),
    key!("gi.vpl_spot_sampling", Kind::Choice(choices::<super::vpl_settings::VplSpotSampling>),
        "`--gi vpl`: spot VPL directions uniform in solid angle on the cone, or uniform in the \
         disk of the spot's image plane (thesis §7.2)",
        flag("vpl-spot-sampling", "S"),
        choice super::vpl_settings::VplSpotSampling, vpl.spot_sampling),
    key!("gi.vpl_shading", Kind::Choice(choices::<super::VplShading>),
        "`--gi vpl`: shade by one gather loop per pixel, or by one additive pass per VPL (the \
         thesis's splatting)",
        flag("vpl-shading", "S"), choice super::VplShading, vpl.shading),
    key!("gi.ssgi_resolution", Kind::Choice(choices::<SsgiResolution>),
        "`--gi ssgi`: the internal GI resolution, the frame's divided by 1, 2, 4 or 8",
        flag("ssgi-resolution", "R"), choice SsgiResolution, ssgi.resolution),
    key!(
        "gi.ssgi_samples",
        Kind::Count(SSGI_SAMPLES),
        "`--gi ssgi`: samples per texel and pyramid level",
        flag("ssgi-samples", "N"),
        ssgi.samples
    ),
    key!("gi.ssgi_mips", Kind::Choice(choices::<SsgiMips>),
        "`--gi ssgi`: how depth and normal mips pick a texel: the voting filter or the nearest \
         child (fast)",
        flag("ssgi-mips", "M"), choice SsgiMips, ssgi.mips),
    key!(
        "gi.ssgi_feedback",
        Kind::Bool,
        "`--gi ssgi`: feed the previous frame's indirect light back (one more bounce per \
         frame); the flag turns it off",
        Some(Flag {
            long: "ssgi-no-feedback",
            value_name: "",
            style: FlagStyle::SetsFalse
        }),
        ssgi.feedback
    ),
    key!(
        "gi.ssgi_feedback_max_w_m2",
        Kind::Number(SSGI_FEEDBACK_MAX),
        "`--gi ssgi`: clamp of the fed-back irradiance in W/m²",
        flag("ssgi-feedback-max", "E"),
        ssgi.feedback_max_w_m2
    ),
    key!(
        "gi.ssgi_history_weight",
        Kind::Number(SSGI_HISTORY_WEIGHT),
        "`--gi ssgi`: τ of the temporal blend with the reprojected history, 0 (off) to 0.99",
        flag("ssgi-history-weight", "TAU"),
        ssgi.history_weight
    ),
    key!(
        "gi.ssr",
        Kind::Bool,
        "`--gi ssgi`: screen-space reflection rays on Phong and GGX materials (on), or only \
         the diffuse fallback (off)",
        toggle("ssr"),
        ssgi.ssr
    ),
    key!("gi.ssr_rays", Kind::Choice(choices::<SsrRays>),
        "`--gi ssgi`: reflection rays along the mirror direction, the lobe's width read as a \
         coarser colour mip (mirror), or one lobe sample per pixel and frame averaged by the \
         history (lobe)",
        flag("ssr-rays", "RAYS"), choice SsrRays, ssgi.ssr_rays),
    key!("gi.sao_radius_m", Kind::Number(SAO_RADIUS_M),
        "SAO: sample radius r in meters",
        flag("sao-radius", "M"), sao radius_m),
    key!("gi.sao_bias", Kind::Number(SAO_BIAS), "SAO: bias β in meters of v·n",
        flag("sao-bias", "M"), sao bias),
    key!("gi.sao_contrast", Kind::Number(SAO_CONTRAST), "SAO: contrast k, the AO term's exponent",
        flag("sao-contrast", "K"), sao contrast),
    key!("gi.sao_epsilon_m2", Kind::Number(SAO_EPSILON), "SAO: ε of v·v + ε in m²",
        flag("sao-epsilon", "M2"), sao epsilon_m2),
    key!("gi.sao_taps", Kind::Count(SAO_TAPS),
        "SAO: taps on the spiral per pixel (fewer: faster and noisier)",
        flag("sao-taps", "N"), sao taps),
    // After the SAO values (see the `sao` arm of `key!`).
    key!("gi.sao", Kind::Bool,
    "Modified SAO (Oetke 2017 §2.5) at half resolution, multiplied into the indirect light \
     (needs a --gi method: direct light is not darkened)",
    toggle("sao"),
    get |s: &GiSettings| Value::Bool(s.sao.is_some()),
    set |s: &mut GiSettings, v| match v {
            Value::Bool(false) => s.sao = None,
            Value::Bool(true) => s.sao = Some(s.sao.unwrap_or_default()),
        _ => {}
    }),
];

impl Settings for GiSettings {
    const TABLE: &'static str = "gi";
    fn keys() -> &'static [Key<Self>] {
        &GI_KEYS
    }
}

impl FieldValue for Bounces {
    fn to_value(&self) -> Value {
        match self {
            Bounces::Fixed(n) => Value::Count(*n),
            Bounces::Unbounded => Value::Word,
        }
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::Count(n) => Some(Bounces::Fixed(n)),
            Value::Word => Some(Bounces::Unbounded),
            _ => None,
        }
    }
}

/// The ranges of the `[gi]` keys (and their flags), which [`GiSettings::keys`] gives each key;
/// the panel's sliders are cut to them.
pub mod range {
    use crate::limits::Limit;

    pub const GI_RAYS: Limit<u32> =
        Limit::new("--gi-rays", Some("gi.rays"), "rays per pixel", 1, 4096);

    /// SAO (Oetke 2017 §2.5): the world-space sample radius r.
    pub const SAO_RADIUS_M: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--sao-radius",
            Some("gi.sao_radius_m"),
            "an SAO radius in meters",
            0.0,
            1e6,
        )
    };

    /// SAO bias β, in meters of v·n (v the tap offset, n the normal).
    pub const SAO_BIAS: Limit<f32> = Limit::new(
        "--sao-bias",
        Some("gi.sao_bias"),
        "an SAO bias in meters",
        0.0,
        1e6,
    );

    /// SAO contrast k, the exponent of the AO term.
    pub const SAO_CONTRAST: Limit<f32> = Limit::new(
        "--sao-contrast",
        Some("gi.sao_contrast"),
        "an SAO contrast exponent",
        0.0,
        64.0,
    );

    /// SAO ε of the denominator v·v + ε, in m² (positive: keeps a tap at the centre finite).
    pub const SAO_EPSILON: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--sao-epsilon",
            Some("gi.sao_epsilon_m2"),
            "an SAO epsilon in square meters",
            0.0,
            1e6,
        )
    };

    pub const GI_RADIUS_M: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--gi-radius",
            Some("gi.radius_m"),
            "a ray length in meters",
            0.0,
            1e9,
        )
    };

    pub const GI_NORMAL_OFFSET: Limit<f32> = Limit::new(
        "--gi-normal-offset",
        Some("gi.normal_offset_voxels"),
        "an offset along the normal in voxel diagonals",
        0.0,
        1e3,
    );

    pub const GI_RAY_OFFSET: Limit<f32> = Limit::new(
        "--gi-ray-offset",
        Some("gi.ray_offset_voxels"),
        "an offset along the ray in voxel diagonals",
        0.0,
        1e3,
    );

    pub const GI_FILTER_RADIUS: Limit<u32> = Limit::new(
        "--gi-filter-radius",
        Some("gi.filter_radius"),
        "a filter radius in pixels (0: off)",
        0,
        64,
    );

    pub const GI_FILTER_PASSES: Limit<u32> = Limit::new(
        "--gi-filter-passes",
        Some("gi.filter_passes"),
        "a number of filter passes",
        0,
        16,
    );

    pub const GI_FRAMES: Limit<u32> = Limit::new(
        "--gi-frames",
        Some("gi.accumulate_frames"),
        "frames to accumulate",
        1,
        1 << 20,
    );

    /// One frame is no accumulation; 4096 frames at 60 Hz is over a minute of history.
    pub const GI_TEMPORAL_FRAMES: Limit<u32> = Limit::new(
        "--gi-temporal-frames",
        Some("gi.temporal_frames"),
        "frames of history",
        1,
        4096,
    );

    pub const LIGHT_MAP_RESOLUTION: Limit<u32> = Limit::new(
        "--light-map-resolution",
        Some("gi.light_map_resolution"),
        "texels per side of a light map",
        16,
        8192,
    );

    /// Traversal starts at most at the top of a 16384² hierarchy (log2 16384 = 14).
    pub const GI_START_LEVEL: Limit<u32> = Limit::new(
        "--gi-start-level",
        None,
        "a hierarchy level to start traversal at",
        0,
        14,
    );

    pub const GI_MAX_ITERATIONS: Limit<u32> = Limit::new(
        "--gi-max-iterations",
        None,
        "a traversal iteration cap",
        1,
        1 << 20,
    );

    /// `--gi vpl`'s values (Thiedemann 2010, Ch. 7): VPLs per set and light, the interleaving
    /// pattern's sides, bounces (each adds one voxel ray per VPL), d_min in voxel diagonals.
    pub const VPLS: Limit<u32> =
        Limit::new("--vpls", Some("gi.vpls"), "VPLs per set and light", 1, 1024);

    pub const VPL_PATTERN_SIDE: Limit<u32> = Limit::new(
        "--vpl-pattern",
        Some("gi.vpl_pattern"),
        "a side of the interleaving pattern",
        1,
        16,
    );

    pub const VPL_BOUNCES: Limit<u32> =
        Limit::new("--vpl-bounces", Some("gi.vpl_bounces"), "VPL bounces", 1, 8);

    pub const VPL_D_MIN: Limit<f32> = Limit::new(
        "--vpl-d-min",
        Some("gi.vpl_d_min_voxels"),
        "d_min in voxel diagonals",
        0.0,
        1e6,
    );

    /// `--gi vpl`: the roughness floor of glossy receivers (perceptual GGX roughness; Phong
    /// exponents are capped at the matching 2/r⁴ − 2), which bounds the peak of a receiver's lobe
    /// toward a VPL as d_min bounds 1/d² (`glsl/include/gi_vpl_gather_body.glsl`).
    pub const VPL_MIN_ROUGHNESS: Limit<f32> = Limit::new(
        "--vpl-min-roughness",
        Some("gi.vpl_min_roughness"),
        "a roughness",
        0.0,
        1.0,
    );

    /// `--gi ssgi`: samples per texel and pyramid level (Oetke 2017 §5.2: 8–256 in the GUI).
    pub const SSGI_SAMPLES: Limit<u32> = Limit::new(
        "--ssgi-samples",
        Some("gi.ssgi_samples"),
        "screen-space GI samples per texel and level",
        1,
        1024,
    );

    /// `--gi ssgi`: the clamp of the fed-back irradiance (Oetke 2017 §5.1: 20).
    pub const SSGI_FEEDBACK_MAX: Limit<f32> = Limit {
        min_exclusive: true,
        ..Limit::new(
            "--ssgi-feedback-max",
            Some("gi.ssgi_feedback_max_w_m2"),
            "a fed-back irradiance clamp in W/m²",
            0.0,
            1e9,
        )
    };

    /// `--gi ssgi`: τ of the temporal blend (below 1: the history must fade).
    pub const SSGI_HISTORY_WEIGHT: Limit<f32> = Limit::new(
        "--ssgi-history-weight",
        Some("gi.ssgi_history_weight"),
        "a history weight",
        0.0,
        0.99,
    );

    /// SAO taps per pixel around the thesis's 16 (Oetke 2017 Eq. 2.20); the cap bounds the
    /// shader's per-pixel loop.
    pub const SAO_TAPS: Limit<u32> = Limit::new(
        "--sao-taps",
        Some("gi.sao_taps"),
        "SAO taps per pixel",
        1,
        256,
    );

    /// Path-tracer bounces: a fixed count up to the safety cap (or `"unbounded"`).
    pub const GI_BOUNCES: Limit<u32> = Limit::new(
        "--gi-bounces",
        Some("gi.bounces"),
        "path-tracer bounces",
        1,
        super::Bounces::MAX,
    );
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
