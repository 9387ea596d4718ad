//! The shadow settings: plain data at the bottom, so that scene files (`[shadow]` tables), the
//! command line and the viewer's panel share them with the shadow views (`crate::light`, which
//! re-exports them) and the area lights' sampling. The `[shadow]` keys are declared once, in
//! [`ShadowSettings::keys`]'s table (`scene::schema`).

use super::schema::{choices, flag, Flag, FlagStyle, Key, Kind, Settings, Value};

/// How point lights are shadowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PointShadow {
    /// Six perspective cube faces.
    #[default]
    Cube,
    /// Two paraboloid hemispheres around ±Y (Brabec et al. 2002):
    /// a third of the layers and draws; each triangle's curved image is covered exactly, by a
    /// ray-triangle test per texel (see `shadow_depth.geom`).
    #[value(name = "paraboloid")]
    DualParaboloid,
}

/// How area lights (spheres, rectangles) are shadowed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum AreaShadow {
    /// S sampled sub-lights, one shadow view each, averaged: converges to the exact soft
    /// shadow as S grows (Dachsbacher 2014's brute force).
    #[default]
    Sampled,
    /// Rectangles as one view at their centre with percentage-closer soft shadows (blocker
    /// search, penumbra estimate, rotated-Poisson PCF; Fernando 2005, Oetke 2017 §4.3); spheres
    /// stay sampled.
    Pcss,
}

/// Shadow parameters (exposed in the CLI and the viewer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Width and height of every shadow-map layer, texels.
    pub resolution: u32,
    /// PCF kernel radius in texels ((2r+1)² taps).
    pub pcf_radius: u32,
    /// Constant depth bias, in shadow-map texels (scale-free), on top of the depth format's
    /// own rounding, which the shader adds.
    pub bias_texels: f32,
    /// Cap of the slope-scaled depth bias, in texels. Against self-shadowing the shader needs
    /// (r + 1/2) sqrt(2) tan(beta) texels of depth at most (beta: the normal's angle to the
    /// depth axis), unbounded at grazing angles; it spends a slope bias up to this cap and
    /// covers the rest with a normal offset of at most (r + 1/2) sqrt(2) texels
    /// (glsl/include/shadow.glsl explains the trade: bias hides occluders, offset moves edges).
    pub slope_bias_texels: f32,
    /// Normal offset of the lookup position on top of the one the PCF kernel needs, in texels
    /// (times sin(beta)); 0 is enough for planar receivers at any angle.
    pub normal_offset_texels: f32,
    /// Cube or dual-paraboloid maps for point lights.
    pub point_technique: PointShadow,
    /// Sub-lights per area light (`--area-samples`), instead of each light's own `samples`.
    pub area_samples: Option<u32>,
    /// Sampled sub-lights or PCSS for area lights (`--area-shadows`).
    pub area_technique: AreaShadow,
    /// Cascades per directional light for the camera's direct light: 1 is the single
    /// whole-scene map alone; N ≥ 2 adds N orthographic maps fitted to slices of the view
    /// frustum (`light::cascade`).
    pub cascades: u32,
    /// Blend λ of logarithmic (1) and uniform (0) splits (Zhang et al. 2006).
    pub cascade_lambda: f32,
    /// Snap each cascade's window to whole texels of a grid fixed in light space, so that its
    /// texels do not slide over the scene when the camera moves (off only to measure that).
    pub cascade_snap: bool,
    /// `--shadow-resolution auto`: [`Self::resolution`] is picked when a renderer is created,
    /// from a probe frame of the shadow-texel view (`render::shadow_texels`).
    pub auto_resolution: bool,
    /// Keep the light-space passes' results (shadow maps, light maps) from frame to frame
    /// and render them again only when their lights, views or drawn geometry change
    /// (`graph::Cache`); off (`--no-cache`) renders them every frame, to measure the two.
    pub cache: bool,
    /// Samples per pixel of the emissive triangles' and the environment's direct light, with
    /// voxel visibility (`render::direct_emitters`; when no GI method brings that light).
    pub direct_samples: u32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            resolution: 1024,
            pcf_radius: 1,
            bias_texels: 1.0,
            slope_bias_texels: 3.0,
            normal_offset_texels: 0.0,
            point_technique: PointShadow::Cube,
            area_samples: None,
            area_technique: AreaShadow::Sampled,
            cascades: DEFAULT_CASCADES,
            cascade_lambda: 0.5,
            cascade_snap: true,
            auto_resolution: false,
            cache: true,
            direct_samples: 8,
        }
    }
}

/// Cascades per directional light by default.
pub const DEFAULT_CASCADES: u32 = 4;

/// The word of `--shadow-resolution auto` (and a scene's `resolution = "auto"`).
pub const AUTO_RESOLUTION_NAME: &str = "auto";

macro_rules! key {
    ($($t:tt)*) => {
        crate::settings_key!(ShadowSettings; $($t)*)
    };
}

use range::*;

/// Every `[shadow]` key: the scene file's key, the path `--set` and the panel use, its range,
/// its flag and its field.
static SHADOW_KEYS: [Key<ShadowSettings>; 13] = [
    key!("shadow.resolution",
    Kind::CountOr(SHADOW_RESOLUTION, AUTO_RESOLUTION_NAME,
        "(the smallest power of two that keeps the shadow texel under a pixel)"),
    "Shadow-map resolution: texels per side, or `auto`: the smallest power of two that \
     keeps the shadow texel under a pixel on 95% of the lit pixels of the view (picked from \
     one probe frame of `--debug shadow-texels` when the renderer is made)",
    flag("shadow-resolution", "TEXELS|auto"),
    get |s: &ShadowSettings| if s.auto_resolution {
        Value::Word
    } else {
        Value::Count(s.resolution)
    },
    set |s: &mut ShadowSettings, v| match v {
        Value::Count(n) => (s.resolution, s.auto_resolution) = (n, false),
        // The probe frame sets its own resolution (`render::shadow_texels`).
        Value::Word => s.auto_resolution = true,
        _ => {}
    }),
    key!(
        "shadow.pcf_radius",
        Kind::Count(PCF_RADIUS),
        "PCF radius in texels",
        flag("pcf-radius", "PCF_RADIUS"),
        pcf_radius
    ),
    key!(
        "shadow.bias_texels",
        Kind::Number(BIAS_TEXELS),
        "Constant depth bias in shadow-map texels",
        None,
        bias_texels
    ),
    key!(
        "shadow.slope_bias_texels",
        Kind::Number(SLOPE_BIAS_TEXELS),
        "Cap of the slope-scaled depth bias in texels (a normal offset covers the rest)",
        None,
        slope_bias_texels
    ),
    key!(
        "shadow.normal_offset_texels",
        Kind::Number(NORMAL_OFFSET_TEXELS),
        "Normal offset of the shadow lookup in texels, on top of the PCF kernel's",
        None,
        normal_offset_texels
    ),
    key!(
        "shadow.cascades",
        Kind::Count(SHADOW_CASCADES),
        "Shadow cascades per directional light for the camera's direct light (1: one map for \
         the whole scene)",
        flag("shadow-cascades", "N"),
        cascades
    ),
    key!(
        "shadow.cascade_lambda",
        Kind::Number(SHADOW_CASCADE_LAMBDA),
        "Cascade splits: blend of logarithmic (1) and uniform (0) splits (Zhang et al. 2006)",
        flag("shadow-cascade-lambda", "LAMBDA"),
        cascade_lambda
    ),
    key!(
        "shadow.cascade_snap",
        Kind::Bool,
        "Snap each cascade's window to whole texels fixed in light space (no crawling edges \
         when the camera moves)",
        None,
        cascade_snap
    ),
    key!("shadow.point_shadows", Kind::Choice(choices::<PointShadow>),
        "Shadow maps of point lights: six cube faces or two paraboloid hemispheres",
        flag("point-shadows", "POINT_SHADOWS"), choice PointShadow, point_technique),
    key!(
        "shadow.area_samples",
        Kind::OptCount(
            crate::limits::AREA_SAMPLES,
            "each light's `samples` key (16 without it)"
        ),
        "Sub-lights (one shadow view each) per sphere or rectangle light, for every area light",
        flag("area-samples", "S"),
        area_samples
    ),
    key!("shadow.area_shadows", Kind::Choice(choices::<AreaShadow>),
        "Soft shadows of area lights: S sampled sub-lights (converges) or PCSS for rectangles \
         (one shadow view each; spheres stay sampled)",
        flag("area-shadows", "AREA_SHADOWS"), choice AreaShadow, area_technique),
    key!(
        "shadow.cache",
        Kind::Bool,
        "Keep shadow maps and light maps from frame to frame, rendered again only when their \
         lights, views or the geometry in them change; the flag renders them every frame",
        Some(Flag {
            long: "no-cache",
            value_name: "",
            style: FlagStyle::SetsFalse
        }),
        cache
    ),
    key!(
        "shadow.direct_samples",
        Kind::Count(DIRECT_SAMPLES),
        "Samples per pixel of the emissive meshes' and the environment's direct light, with \
         voxel visibility (under --gi none; --gi ssgi and vpl: the environment's only)",
        flag("direct-samples", "K"),
        direct_samples
    ),
];

impl Settings for ShadowSettings {
    const TABLE: &'static str = "shadow";
    fn keys() -> &'static [Key<Self>] {
        &SHADOW_KEYS
    }
}

/// The ranges of the `[shadow]` keys (and their flags), which [`ShadowSettings::keys`] gives
/// each key; the panel's sliders are cut to them.
pub mod range {
    use crate::limits::Limit;

    pub const SHADOW_RESOLUTION: Limit<u32> = Limit::new(
        "--shadow-resolution",
        Some("shadow.resolution"),
        "texels per side of a shadow map",
        16,
        8192,
    );
    /// Light samples and environment directions per pixel of `direct_emitters`, each a voxel
    /// ray: 1024 is past where a 320×180 frame takes seconds on a CPU device.
    pub const DIRECT_SAMPLES: Limit<u32> = Limit::new(
        "--direct-samples",
        Some("shadow.direct_samples"),
        "direct-light samples per pixel",
        1,
        1024,
    );
    /// The deferred pass filters (2r+1)² shadow-map taps per view.
    pub const PCF_RADIUS: Limit<u32> = Limit::new(
        "--pcf-radius",
        Some("shadow.pcf_radius"),
        "a PCF radius in texels",
        0,
        8,
    );
    /// Cascades per directional light (`light::cascade`; 1: the whole-scene map alone). Eight
    /// keeps a frame of several suns under the 64 shadow views.
    pub const SHADOW_CASCADES: Limit<u32> = Limit::new(
        "--shadow-cascades",
        Some("shadow.cascades"),
        "a number of shadow cascades per directional light",
        1,
        8,
    );
    /// Zhang et al. 2006's blend of logarithmic (1) and uniform (0) cascade splits.
    pub const SHADOW_CASCADE_LAMBDA: Limit<f32> = Limit::new(
        "--shadow-cascade-lambda",
        Some("shadow.cascade_lambda"),
        "a blend of logarithmic (1) and uniform (0) splits",
        0.0,
        1.0,
    );
    /// The depth bias in texels: the self-shadowing it must cover is at most the PCF kernel's
    /// reach, (r + 1/2)·sqrt(2)·tan β texels, and the largest kernel (r = 8) at β = 75° needs
    /// about 45; 64 keeps every useful value (the panel offers 0–8) and refuses typos.
    pub const BIAS_TEXELS: Limit<f32> = Limit::new(
        "--set shadow.bias_texels",
        Some("shadow.bias_texels"),
        "a depth bias in texels",
        0.0,
        64.0,
    );
    /// The slope bias's cap, in texels (as [`BIAS_TEXELS`]).
    pub const SLOPE_BIAS_TEXELS: Limit<f32> = Limit::new(
        "--set shadow.slope_bias_texels",
        Some("shadow.slope_bias_texels"),
        "a slope-bias cap in texels",
        0.0,
        64.0,
    );
    /// The extra normal offset, in texels (as [`BIAS_TEXELS`]).
    pub const NORMAL_OFFSET_TEXELS: Limit<f32> = Limit::new(
        "--set shadow.normal_offset_texels",
        Some("shadow.normal_offset_texels"),
        "a normal offset in texels",
        0.0,
        64.0,
    );
}
