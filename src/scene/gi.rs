//! The `[gi]` table of a scene file: the scene's layer of the indirect-light settings, which
//! the command line's layer overrides (the keys are [`GiSettings::keys`]).

use super::gi_settings::GiSettings;
use super::schema::Layer;

/// The indirect-light settings of a frame: the built-in defaults ([`GiSettings::default`]),
/// under what the scene file's `[gi]` table gives, under the values given on the command line.
pub fn resolve_gi(scene: &Layer, cli: &Layer) -> GiSettings {
    super::schema::resolve(&[scene, cli])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::schema::key;
    use crate::scene::{Bounces, GiMethod};

    /// A layer from `(path, text)` pairs, read as `--set` reads them.
    fn layer(values: &[(&str, &str)]) -> Layer {
        let mut l = Layer::default();
        for (path, text) in values {
            let k = key::<GiSettings>(path).expect(path);
            l.set(k.path, k.kind.parse_checked(path, text).expect(text));
        }
        l
    }

    #[test]
    fn flags_override_the_scene_which_overrides_the_defaults() {
        let d = GiSettings::default();
        // Nothing given anywhere: the built-in defaults.
        assert_eq!(resolve_gi(&Layer::default(), &Layer::default()), d);
        let scene = layer(&[
            ("gi.method", "pathtrace"),
            ("gi.rays", "4"),
            ("gi.bounces", "3"),
            ("gi.radius_m", "2"),
            ("gi.filter_radius", "0"),
        ]);
        let s = resolve_gi(&scene, &Layer::default());
        assert_eq!(
            (s.method, s.rays, s.bounces, s.radius_m, s.filter_radius),
            (GiMethod::Pathtrace, 4, Bounces::Fixed(3), Some(2.0), 0)
        );
        // Values the scene does not give keep their defaults.
        assert_eq!(
            (s.filter_passes, s.normal_offset_voxels, s.accumulate_frames),
            (d.filter_passes, d.normal_offset_voxels, d.accumulate_frames)
        );
        let cli = layer(&[
            ("gi.method", "hemisphere"),
            ("gi.rays", "32"),
            ("gi.filter_passes", "5"),
        ]);
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
        let off = layer(&[("gi.method", "none")]);
        assert_eq!(resolve_gi(&scene, &off).method, GiMethod::None);
    }

    #[test]
    fn sao_keys_switch_and_tune_the_estimator() {
        let on = |values: &[(&str, &str)]| resolve_gi(&layer(values), &Layer::default()).sao;
        let d = crate::scene::SaoSettings::default();
        // Values without the switch leave SAO off (the default); the switch alone takes the
        // thesis's constants.
        assert_eq!(on(&[("gi.sao_radius_m", "1")]), None);
        assert_eq!(on(&[("gi.sao", "true")]), Some(d));
        // A flag turns off what the scene turns on, and the scene's values survive a flag
        // that only switches it on.
        let scene = layer(&[("gi.sao", "true"), ("gi.sao_radius_m", "0.5")]);
        assert_eq!(resolve_gi(&scene, &layer(&[("gi.sao", "off")])).sao, None);
        let s = resolve_gi(&scene, &layer(&[("gi.sao", "on")]))
            .sao
            .expect("on");
        assert_eq!((s.radius_m, s.bias), (0.5, d.bias));
        // The scene's values without its switch, switched on by a flag.
        let values = layer(&[("gi.sao_radius_m", "0.25")]);
        let s = resolve_gi(&values, &layer(&[("gi.sao", "on")])).sao;
        assert_eq!(s.map(|s| s.radius_m), Some(0.25));
    }

    #[test]
    fn every_key_reads_and_writes_its_own_field() {
        // SAO's values are kept only where SAO is on.
        crate::scene::schema::assert_every_key_reads_and_writes_its_own_field::<GiSettings>(
            &layer(&[("gi.sao", "true")]),
        );
    }
}
