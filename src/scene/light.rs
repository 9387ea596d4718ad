//! Lights. Units and spot falloff follow Mitsuba 3 (`point`, `spot`, `directional` emitters;
//! `sphere` and `rectangle` shapes with `area` emitters), so a scene exported to Mitsuba renders
//! the same image.

use glam::Vec3;

/// A validated light. Directions are unit length; intensities are finite and >= 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light: irradiance E = I cosθ / d².
    Point {
        position: Vec3,
        /// Radiant intensity, W/sr, linear RGB (Mitsuba `intensity`).
        intensity_w_sr: Vec3,
    },
    /// Spot light: a point light masked by [`spot_falloff`].
    Spot {
        position: Vec3,
        /// Unit axis of the cone (the direction light travels).
        direction: Vec3,
        /// On-axis radiant intensity, W/sr.
        intensity_w_sr: Vec3,
        /// Half-angle of the whole cone, degrees (Mitsuba `cutoff_angle`).
        cutoff_deg: f32,
        /// Half-angle of the full-intensity core, degrees, <= cutoff (Mitsuba `beam_width`).
        beam_deg: f32,
    },
    /// Distant light: irradiance on a surface facing it, E⊥ in W/m².
    Directional {
        /// Unit direction the light travels (Mitsuba `direction`), e.g. [0, -1, 0] from above.
        direction: Vec3,
        irradiance_w_m2: Vec3,
    },
    /// Spherical area light: every point of the sphere emits `radiance_w_sr_m2` outward
    /// (Mitsuba `sphere` shape with an `area` emitter). Not drawn by the camera.
    Sphere {
        position: Vec3,
        radius_m: f32,
        /// Emitted radiance L, W/(m²·sr), linear RGB.
        radiance_w_sr_m2: Vec3,
        /// Sub-lights it is rendered with (`crate::light::area`), unless `--area-samples`.
        samples: u32,
    },
    /// One-sided rectangular area light emitting `radiance_w_sr_m2` along `normal` (Mitsuba
    /// `rectangle` shape with an `area` emitter). Not drawn by the camera.
    Rectangle {
        position: Vec3,
        /// Unit normal: the side that emits.
        normal: Vec3,
        /// Unit direction of the `width_m` edges, perpendicular to `normal`; the `height_m`
        /// edges run along `normal × width_axis`.
        width_axis: Vec3,
        width_m: f32,
        height_m: f32,
        radiance_w_sr_m2: Vec3,
        samples: u32,
    },
    /// One sample of an area light (made by `crate::light::area::sample_lights`, never by a
    /// scene file): a surface element of area A at `position` emitting radiance L along its
    /// `normal`, i.e. the intensity I(θ) = L·A·max(cos θ, 0) with θ measured from the normal.
    Element {
        position: Vec3,
        normal: Vec3,
        /// L·A, W/sr: the intensity along the normal.
        intensity_w_sr: Vec3,
        /// 0 for a sample of `--area-shadows sampled`; with `pcss`, the element stands for
        /// the whole light and this is the light's size s (m) that sizes the penumbra.
        pcss_size_m: f32,
    },
}

impl Light {
    pub fn is_point(&self) -> bool {
        matches!(self, Light::Point { .. })
    }
    pub fn is_spot(&self) -> bool {
        matches!(self, Light::Spot { .. })
    }
    pub fn is_directional(&self) -> bool {
        matches!(self, Light::Directional { .. })
    }
    /// A sphere or rectangle light (rendered as [`Light::Element`] samples).
    pub fn is_area(&self) -> bool {
        matches!(self, Light::Sphere { .. } | Light::Rectangle { .. })
    }

    /// Position for point and spot lights.
    pub fn position(&self) -> Option<Vec3> {
        match self {
            Light::Point { position, .. }
            | Light::Spot { position, .. }
            | Light::Sphere { position, .. }
            | Light::Rectangle { position, .. }
            | Light::Element { position, .. } => Some(*position),
            Light::Directional { .. } => None,
        }
    }
}

/// Multiplies every emitted quantity of `light` by `s` (the viewer's light sliders).
pub fn scaled(light: &Light, s: f32) -> Light {
    let mut l = *light;
    match &mut l {
        Light::Point { intensity_w_sr, .. }
        | Light::Spot { intensity_w_sr, .. }
        | Light::Element { intensity_w_sr, .. } => *intensity_w_sr *= s,
        Light::Directional {
            irradiance_w_m2, ..
        } => *irradiance_w_m2 *= s,
        Light::Sphere {
            radiance_w_sr_m2, ..
        }
        | Light::Rectangle {
            radiance_w_sr_m2, ..
        } => *radiance_w_sr_m2 *= s,
    }
    l
}

/// Spot falloff of Mitsuba 3 (`src/emitters/spot.cpp`, `falloff_curve`): 1 inside the beam,
/// falling linearly *in angle* to 0 at the cutoff. `cos_theta` is the cosine between the
/// spot axis and the direction to the lit point.
pub fn spot_falloff(cos_theta: f32, cutoff_deg: f32, beam_deg: f32) -> f32 {
    let theta = cos_theta.clamp(-1.0, 1.0).acos();
    let cutoff = cutoff_deg.to_radians();
    let beam = beam_deg.to_radians();
    if theta >= cutoff {
        0.0
    } else if theta <= beam {
        1.0
    } else {
        // cutoff > theta > beam here, so the denominator is positive.
        (cutoff - theta) / (cutoff - beam)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_matches_mitsuba_shape() {
        let f = |deg: f32| spot_falloff(deg.to_radians().cos(), 30.0, 20.0);
        assert_eq!(f(0.0), 1.0);
        assert_eq!(f(19.0), 1.0);
        assert!((f(25.0) - 0.5).abs() < 1e-3);
        assert_eq!(f(31.0), 0.0);
        assert_eq!(f(180.0), 0.0);
        // beam == cutoff: a hard edge, never NaN.
        assert!(spot_falloff(0.9, 20.0, 20.0).is_finite());
    }
}
