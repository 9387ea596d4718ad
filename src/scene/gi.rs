//! The `[gi]` table of a scene file: the scene's defaults of the indirect-light settings,
//! which command-line flags override.

use super::gi_settings::{Bounces, GiMethod, GiSettings};

/// Indirect-light settings given by a scene file's `[gi]` table or by command-line flags;
/// `None`: not given there. See [`resolve_gi`] for the precedence.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GiOverrides {
    pub method: Option<GiMethod>,
    /// Rays per pixel.
    pub rays: Option<u32>,
    /// Path-tracer bounces.
    pub bounces: Option<Bounces>,
    /// Ray length in meters.
    pub radius_m: Option<f32>,
    pub normal_offset_voxels: Option<f32>,
    pub ray_offset_voxels: Option<f32>,
    pub filter_radius: Option<u32>,
    pub filter_passes: Option<u32>,
    pub light_map_resolution: Option<u32>,
    /// Frames a headless path-tracer render accumulates.
    pub accumulate_frames: Option<u32>,
    /// The VPL method's parameters.
    pub vpl: crate::scene::vpl_settings::VplOverrides,
    /// The screen-space GI's parameters.
    pub ssgi: super::gi_settings::SsgiOverrides,
    /// Modified SAO multiplied into the indirect light (Oetke 2017 §2.5).
    pub sao: super::gi_settings::SaoOverrides,
}

impl GiOverrides {
    /// Nothing given.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// Field by field: `self`'s value where given, else `fallback`'s.
    pub fn or(self, fallback: GiOverrides) -> GiOverrides {
        GiOverrides {
            method: self.method.or(fallback.method),
            rays: self.rays.or(fallback.rays),
            bounces: self.bounces.or(fallback.bounces),
            radius_m: self.radius_m.or(fallback.radius_m),
            normal_offset_voxels: self.normal_offset_voxels.or(fallback.normal_offset_voxels),
            ray_offset_voxels: self.ray_offset_voxels.or(fallback.ray_offset_voxels),
            filter_radius: self.filter_radius.or(fallback.filter_radius),
            filter_passes: self.filter_passes.or(fallback.filter_passes),
            light_map_resolution: self.light_map_resolution.or(fallback.light_map_resolution),
            accumulate_frames: self.accumulate_frames.or(fallback.accumulate_frames),
            vpl: self.vpl.or(fallback.vpl),
            ssgi: self.ssgi.or(fallback.ssgi),
            sao: self.sao.or(fallback.sao),
        }
    }

    /// `base` with the given values replaced.
    pub fn apply(&self, base: GiSettings) -> GiSettings {
        GiSettings {
            method: self.method.unwrap_or(base.method),
            rays: self.rays.unwrap_or(base.rays),
            bounces: self.bounces.unwrap_or(base.bounces),
            radius_m: self.radius_m.or(base.radius_m),
            normal_offset_voxels: self
                .normal_offset_voxels
                .unwrap_or(base.normal_offset_voxels),
            ray_offset_voxels: self.ray_offset_voxels.unwrap_or(base.ray_offset_voxels),
            filter_radius: self.filter_radius.unwrap_or(base.filter_radius),
            filter_passes: self.filter_passes.unwrap_or(base.filter_passes),
            light_map_resolution: self
                .light_map_resolution
                .unwrap_or(base.light_map_resolution),
            accumulate_frames: self.accumulate_frames.unwrap_or(base.accumulate_frames),
            vpl: self.vpl.apply(base.vpl),
            ssgi: self.ssgi.apply(base.ssgi),
            sao: self.sao.apply(base.sao),
            ..base
        }
    }
}

/// The indirect-light settings of a frame: the built-in defaults ([`GiSettings::default`]),
/// replaced by what the scene file's `[gi]` table gives, replaced by the flags given on the
/// command line.
pub fn resolve_gi(scene: &GiOverrides, cli: &GiOverrides) -> GiSettings {
    cli.or(*scene).apply(GiSettings::default())
}

/// A scene file's `bounces`: an integer count or the string `"unbounded"`; `Err` holds what
/// was expected, for the error naming the field.
pub(crate) fn bounces_from_toml(v: &toml::Value) -> Result<Bounces, String> {
    let parsed = match v {
        toml::Value::Integer(n) => Bounces::fixed(*n),
        toml::Value::String(s) if s == Bounces::UNBOUNDED_NAME => Some(Bounces::Unbounded),
        _ => None,
    };
    parsed.ok_or_else(|| format!("{v}; expected path-tracer bounces, {}", Bounces::expected()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_override_the_scene_which_overrides_the_defaults() {
        let d = GiSettings::default();
        // Nothing given anywhere: the built-in defaults.
        assert_eq!(
            resolve_gi(&GiOverrides::default(), &GiOverrides::default()),
            d
        );
        let scene = GiOverrides {
            method: Some(GiMethod::Pathtrace),
            rays: Some(4),
            bounces: Some(Bounces::Fixed(3)),
            radius_m: Some(2.0),
            filter_radius: Some(0),
            ..Default::default()
        };
        let s = resolve_gi(&scene, &GiOverrides::default());
        assert_eq!(
            (s.method, s.rays, s.bounces, s.radius_m, s.filter_radius),
            (GiMethod::Pathtrace, 4, Bounces::Fixed(3), Some(2.0), 0)
        );
        // Values the scene does not give keep their defaults.
        assert_eq!(
            (s.filter_passes, s.normal_offset_voxels, s.accumulate_frames),
            (d.filter_passes, d.normal_offset_voxels, d.accumulate_frames)
        );
        let cli = GiOverrides {
            method: Some(GiMethod::Hemisphere),
            rays: Some(32),
            filter_passes: Some(5),
            ..Default::default()
        };
        let s = resolve_gi(&scene, &cli);
        // Flags win; the scene fills in what the flags leave out; defaults the rest.
        assert_eq!(
            (s.method, s.rays, s.filter_passes),
            (GiMethod::Hemisphere, 32, 5)
        );
        assert_eq!(
            (s.bounces, s.radius_m, s.filter_radius),
            (Bounces::Fixed(3), Some(2.0), 0)
        );
        assert_eq!(
            (s.light_map_resolution, s.seed, s.max_iterations),
            (d.light_map_resolution, d.seed, d.max_iterations)
        );
        // A flag can switch GI off that the scene switches on.
        let off = GiOverrides {
            method: Some(GiMethod::None),
            ..Default::default()
        };
        assert_eq!(resolve_gi(&scene, &off).method, GiMethod::None);
    }

    #[test]
    fn sao_keys_switch_and_tune_the_estimator() {
        let on = |o: crate::scene::SaoOverrides| {
            resolve_gi(
                &GiOverrides {
                    sao: o,
                    ..Default::default()
                },
                &GiOverrides::default(),
            )
            .sao
        };
        let d = crate::scene::SaoSettings::default();
        // Values without the switch leave SAO off (the default); the switch alone takes the
        // thesis's constants.
        assert_eq!(
            on(crate::scene::SaoOverrides {
                radius_m: Some(1.0),
                ..Default::default()
            }),
            None
        );
        assert_eq!(
            on(crate::scene::SaoOverrides {
                enabled: Some(true),
                ..Default::default()
            }),
            Some(d)
        );
        // A flag turns off what the scene turns on, and the scene's values survive a flag
        // that only switches it on.
        let scene = GiOverrides {
            sao: crate::scene::SaoOverrides {
                enabled: Some(true),
                radius_m: Some(0.5),
                ..Default::default()
            },
            ..Default::default()
        };
        let flag = |enabled| GiOverrides {
            sao: crate::scene::SaoOverrides {
                enabled: Some(enabled),
                ..Default::default()
            },
            ..Default::default()
        };
        assert_eq!(resolve_gi(&scene, &flag(false)).sao, None);
        let s = resolve_gi(&scene, &flag(true)).sao.expect("on");
        assert_eq!((s.radius_m, s.bias), (0.5, d.bias));
    }

    #[test]
    fn every_field_is_merged() {
        let all = GiOverrides {
            method: Some(GiMethod::Hemisphere),
            rays: Some(1),
            bounces: Some(Bounces::Unbounded),
            radius_m: Some(0.5),
            normal_offset_voxels: Some(0.25),
            ray_offset_voxels: Some(0.75),
            filter_radius: Some(7),
            filter_passes: Some(9),
            light_map_resolution: Some(64),
            accumulate_frames: Some(11),
            vpl: crate::scene::vpl_settings::VplOverrides {
                per_set: Some(3),
                pattern: Some([2, 5]),
                bounces: Some(1),
                d_min_voxels: Some(0.5),
                min_roughness: Some(0.45),
                visibility: Some(crate::scene::vpl_settings::VplVisibility::None),
                normalize: Some(crate::scene::vpl_settings::VplNormalize::Valid),
                spot_sampling: Some(crate::scene::vpl_settings::VplSpotSampling::Disk),
            },
            ssgi: crate::scene::SsgiOverrides {
                resolution: Some(crate::scene::SsgiResolution::Eighth),
                samples: Some(5),
                mips: Some(crate::scene::SsgiMips::Fast),
                feedback: Some(false),
                feedback_max_w_m2: Some(3.5),
                history_weight: Some(0.25),
                ssr: Some(false),
                ssr_rays: Some(crate::scene::SsrRays::Lobe),
            },
            sao: crate::scene::SaoOverrides {
                enabled: Some(true),
                radius_m: Some(0.7),
                bias: Some(0.02),
                contrast: Some(3.0),
                epsilon_m2: Some(0.5),
            },
        };
        assert!(!all.is_empty() && GiOverrides::default().is_empty());
        assert_eq!(GiOverrides::default().or(all), all);
        assert_eq!(all.or(GiOverrides::default()), all);
        let s = resolve_gi(&GiOverrides::default(), &all);
        let back = GiOverrides {
            method: Some(s.method),
            rays: Some(s.rays),
            bounces: Some(s.bounces),
            radius_m: s.radius_m,
            normal_offset_voxels: Some(s.normal_offset_voxels),
            ray_offset_voxels: Some(s.ray_offset_voxels),
            filter_radius: Some(s.filter_radius),
            filter_passes: Some(s.filter_passes),
            light_map_resolution: Some(s.light_map_resolution),
            accumulate_frames: Some(s.accumulate_frames),
            vpl: crate::scene::vpl_settings::VplOverrides {
                per_set: Some(s.vpl.per_set),
                pattern: Some(s.vpl.pattern),
                bounces: Some(s.vpl.bounces),
                d_min_voxels: Some(s.vpl.d_min_voxels),
                min_roughness: Some(s.vpl.min_roughness),
                visibility: Some(s.vpl.visibility),
                normalize: Some(s.vpl.normalize),
                spot_sampling: Some(s.vpl.spot_sampling),
            },
            ssgi: crate::scene::SsgiOverrides {
                resolution: Some(s.ssgi.resolution),
                samples: Some(s.ssgi.samples),
                mips: Some(s.ssgi.mips),
                feedback: Some(s.ssgi.feedback),
                feedback_max_w_m2: Some(s.ssgi.feedback_max_w_m2),
                history_weight: Some(s.ssgi.history_weight),
                ssr: Some(s.ssgi.ssr),
                ssr_rays: Some(s.ssgi.ssr_rays),
            },
            sao: s.sao.map_or_else(
                || crate::scene::SaoOverrides {
                    enabled: Some(false),
                    ..Default::default()
                },
                |a| crate::scene::SaoOverrides {
                    enabled: Some(true),
                    radius_m: Some(a.radius_m),
                    bias: Some(a.bias),
                    contrast: Some(a.contrast),
                    epsilon_m2: Some(a.epsilon_m2),
                },
            ),
        };
        assert_eq!(back, all);
    }
}
