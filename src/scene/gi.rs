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
    use crate::scene::schema::{key, Settings, Value};
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

    /// Every key writes its own field and reads it back: a value other than the default's
    /// set through the key comes back from the settings, and no other key's value changes.
    #[test]
    fn every_key_reads_and_writes_its_own_field() {
        let d = GiSettings::default();
        for k in GiSettings::keys() {
            let other = match (k.kind, (k.get)(&d)) {
                (crate::scene::schema::Kind::Choice(_), Value::Choice(i)) => {
                    Value::Choice(usize::from(i == 0))
                }
                (_, Value::Count(n)) => Value::Count(if n == 2 { 3 } else { 2 }),
                (_, Value::Number(_) | Value::Unset) => Value::Number(0.375),
                (_, Value::Bool(b)) => Value::Bool(!b),
                (_, Value::Pair([n, m])) => Value::Pair([n + 1, m + 2]),
                (_, Value::Word | Value::Choice(_)) => Value::Count(2),
            };
            // SAO's values are kept only where SAO is on.
            let mut l = layer(&[("gi.sao", "true")]);
            l.set(k.path, other);
            let s = resolve_gi(&l, &Layer::default());
            assert_eq!((k.get)(&s), other, "{}", k.path);
            for j in GiSettings::keys().iter().filter(|j| j.path != k.path) {
                let base = resolve_gi(&layer(&[("gi.sao", "true")]), &Layer::default());
                assert_eq!((j.get)(&s), (j.get)(&base), "{} moved {}", k.path, j.path);
            }
        }
    }

    #[test]
    fn key_paths_are_unique_and_name_their_table() {
        let paths = crate::scene::schema::paths::<GiSettings>();
        let mut unique = paths.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), paths.len());
        assert!(paths.iter().all(|p| p.starts_with("gi.")), "{paths:?}");
    }
}
