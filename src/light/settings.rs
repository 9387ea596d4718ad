//! The shadow settings the CLI, the scene file and the viewer set: plain data that the shadow
//! views (`shadow`) and the area lights' sampling (`area`) both read.

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
    /// Cascades per directional light for the camera's direct light (`--shadow-cascades`,
    /// scene key `shadow.cascades`): 1 is the single whole-scene map alone; N ≥ 2 adds N
    /// orthographic maps fitted to slices of the view frustum (see [`super::cascade::cascade_views`]).
    pub cascades: u32,
    /// Blend λ of logarithmic (1) and uniform (0) splits (Zhang et al. 2006;
    /// `--shadow-cascade-lambda`, scene key `shadow.cascade_lambda`).
    pub cascade_lambda: f32,
    /// Snap each cascade's window to whole texels of a grid fixed in light space, so that its
    /// texels do not slide over the scene when the camera moves (off only to measure that).
    pub cascade_snap: bool,
    /// `--shadow-resolution auto`: [`Self::resolution`] is picked when a renderer is created,
    /// from a probe frame of the shadow-texel view (`render::shadow_texels`).
    pub auto_resolution: bool,
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
        }
    }
}

/// Cascades per directional light by default.
pub const DEFAULT_CASCADES: u32 = 4;
