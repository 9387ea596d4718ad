//! The viewer panel's controls for settings keys. Each control reads and writes its setting by
//! key path through the schema ([`crate::scene::schema`]), as `--set` and scene files do: the
//! panel names a setting the way they do and never offers a value they refuse (a slider's
//! span is cut to the key's range).

use crate::scene::schema::{self, Key, Kind, Settings, Value};

/// The key `path` of the table `S`. A path the panel names is part of the code, not of the
/// input: one missing from the table is a programming error, which debug builds (and the
/// tests drawing every panel section) report.
fn key<S: Settings>(path: &str) -> Option<&'static Key<S>> {
    let k = schema::key::<S>(path);
    debug_assert!(
        k.is_some(),
        "the panel names `{path}`, which is no key of its table"
    );
    k
}

/// Writes `v` to the key `path` of `s`, as `--set` and scene files write it (a path missing
/// from the table writes nothing; see [`key`]).
pub fn set_key<S: Settings>(s: &mut S, path: &str, v: Value) {
    if let Some(k) = key::<S>(path) {
        (k.set)(s, v);
    }
}

/// The key `path` of `s` (a boolean, or a stage that is on unless `false`) as a checkbox
/// labelled `text`.
pub fn key_checkbox<S: Settings>(
    ui: &mut egui::Ui,
    s: &mut S,
    path: &str,
    text: &str,
) -> egui::Response {
    let mut on = key::<S>(path).is_some_and(|k| (k.get)(s) != Value::Bool(false));
    let r = ui.checkbox(&mut on, text);
    if r.changed() {
        set_key(s, path, Value::Bool(on));
    }
    r
}

/// A checkbox labelled `text` that is ticked while the key `path` of `s` holds a value of the
/// kind of `on` (a number, a count, the key's word) and writes `on` when ticked, `off` when
/// cleared: `gi.radius_m` is a length or unset, `gi.bounces` a count or `unbounded`. Returns
/// whether it is ticked.
pub fn key_switch<S: Settings>(
    ui: &mut egui::Ui,
    s: &mut S,
    path: &str,
    text: &str,
    (on, off): (Value, Value),
) -> bool {
    let Some(k) = key::<S>(path) else {
        return false;
    };
    let mut ticked = std::mem::discriminant(&(k.get)(s)) == std::mem::discriminant(&on);
    if ui.checkbox(&mut ticked, text).changed() {
        (k.set)(s, if ticked { on } else { off });
    }
    ticked
}

/// A slider for the count or number key `path` of `s` over `lo..=hi` cut to the key's range
/// (so the panel never offers what flags and scene files refuse), labelled `text`. A key that
/// is unset (or holds its word) shows no slider.
pub fn key_slider<S: Settings>(
    ui: &mut egui::Ui,
    s: &mut S,
    path: &str,
    (lo, hi): (f64, f64),
    logarithmic: bool,
    text: &str,
) {
    let Some(k) = key::<S>(path) else {
        return;
    };
    match (k.kind, (k.get)(s)) {
        (Kind::Count(l) | Kind::CountOr(l, ..) | Kind::OptCount(l, _), Value::Count(mut n)) => {
            let slider = egui::Slider::new(&mut n, l.slider(lo as u32, hi as u32))
                .logarithmic(logarithmic)
                .text(text);
            if ui.add(slider).changed() {
                (k.set)(s, Value::Count(n));
            }
        }
        (Kind::Number(l) | Kind::OptNumber(l, _) | Kind::Switch(l, _), Value::Number(mut x)) => {
            let slider = egui::Slider::new(&mut x, l.slider(lo as f32, hi as f32))
                .logarithmic(logarithmic)
                .text(text);
            if ui.add(slider).changed() {
                (k.set)(s, Value::Number(x));
            }
        }
        _ => {}
    }
}

/// One slider per side of the pair key `path` of `s` (`gi.vpl_pattern`: N×M), over `lo..=hi`
/// cut to the key's range, labelled `texts`.
pub fn key_pair_sliders<S: Settings>(
    ui: &mut egui::Ui,
    s: &mut S,
    path: &str,
    (lo, hi): (u32, u32),
    texts: [&str; 2],
) {
    let Some(k) = key::<S>(path) else {
        return;
    };
    let (Kind::Pair(l), Value::Pair(mut pair)) = (k.kind, (k.get)(s)) else {
        return;
    };
    let mut changed = false;
    for (side, text) in pair.iter_mut().zip(texts) {
        changed |= ui
            .add(egui::Slider::new(side, l.slider(lo, hi)).text(text))
            .changed();
    }
    if changed {
        (k.set)(s, Value::Pair(pair));
    }
}

/// The choice key `path` of `s` as a combo box labelled `text`, listing the key's values by
/// the names flags and scene files give them.
pub fn key_choice<S: Settings>(ui: &mut egui::Ui, s: &mut S, path: &str, text: &str) {
    let Some(k) = key::<S>(path) else {
        return;
    };
    let (Kind::Choice(choices), Value::Choice(current)) = (k.kind, (k.get)(s)) else {
        return;
    };
    let names: Vec<String> = choices().iter().map(|c| c.get_name().to_owned()).collect();
    let mut chosen = current;
    egui::ComboBox::from_label(text)
        .selected_text(names.get(current).map_or("", String::as_str))
        .show_ui(ui, |ui| {
            for (i, name) in names.iter().enumerate() {
                ui.selectable_value(&mut chosen, i, name);
            }
        });
    if chosen != current {
        (k.set)(s, Value::Choice(chosen));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gi::{GiMethod, GiSettings};

    /// Draws every GI method's panel section (headless) with its switches both ways: each
    /// path it names must be a `[gi]` key (see [`key`]), and the values it shows read back
    /// through the schema unchanged.
    #[test]
    fn every_method_panel_names_gi_keys() {
        let ctx = egui::Context::default();
        for &method in GiMethod::ALL {
            for limited in [false, true] {
                let mut gi = GiSettings {
                    method,
                    radius_m: limited.then_some(2.0),
                    ..Default::default()
                };
                let before = gi;
                let mut out = ctx.run_ui(egui::RawInput::default(), |root| {
                    egui::CentralPanel::default().show(root, |ui| {
                        (method.spec().panel)(ui, &mut gi, Some(3));
                    });
                });
                out.textures_delta.clear();
                assert_eq!(
                    gi, before,
                    "{method:?}: drawing its panel changed a setting"
                );
            }
        }
    }

    /// `set_key` writes a field as `--set` does: a count, an optional number and its unset.
    #[test]
    fn set_key_writes_through_the_schema() {
        let mut gi = GiSettings::default();
        set_key(&mut gi, "gi.rays", Value::Count(7));
        assert_eq!(gi.rays, 7);
        set_key(&mut gi, "gi.radius_m", Value::Number(0.5));
        assert_eq!(gi.radius_m, Some(0.5));
        set_key(&mut gi, "gi.radius_m", Value::Unset);
        assert_eq!(gi.radius_m, None);
    }
}
