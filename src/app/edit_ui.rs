//! The scene editor's egui parts: the panel's "Edit scene" section (fields of the selected
//! object or light, add, remove, save) and the selection, light markers and handles drawn over
//! the scene. They only read the editor's state and return [`EditAction`]s, which the viewer
//! applies (`edit.rs`).

use super::edit::{EditAction, Editor, HandleMode, Selection, ViewGeom, LIGHT_KINDS};
use crate::scene::{Light, Scene};
use glam::Vec3;

/// What the panel's editor section shows.
pub struct EditView<'a> {
    pub editor: &'a Editor,
    pub scene: &'a Scene,
    pub light_names: &'a [String],
}

/// Draws the selection (its bounds), the lights' markers and the handles over the scene.
pub fn paint(
    ctx: &egui::Context,
    ed: &Editor,
    scene: &Scene,
    view: &ViewGeom,
    time_s: f32,
    ppp: f32,
) {
    let painter = ctx.layer_painter(egui::LayerId::background());
    let pt = |p: [f32; 2]| egui::pos2(p[0] / ppp, p[1] / ppp);
    let colors = [
        egui::Color32::from_rgb(230, 70, 70),
        egui::Color32::from_rgb(80, 200, 80),
        egui::Color32::from_rgb(80, 120, 240),
    ];
    let yellow = egui::Color32::from_rgb(250, 210, 60);
    for (i, l) in scene.lights.iter().enumerate() {
        if let Some(m) = l.position().and_then(|p| view.project(p)) {
            let selected = ed.selection == Some(Selection::Light(i));
            let c = if selected {
                yellow
            } else {
                egui::Color32::WHITE
            };
            painter.circle_stroke(pt(m), 5.0, egui::Stroke::new(1.5, c));
        }
    }
    if let Some(Selection::Object(i)) = ed.selection {
        if let Some(o) = scene.objects.get(i) {
            let b = o.aabb_at(time_s);
            let corner = |k: usize| {
                Vec3::new(
                    if k & 1 == 0 { b.min.x } else { b.max.x },
                    if k & 2 == 0 { b.min.y } else { b.max.y },
                    if k & 4 == 0 { b.min.z } else { b.max.z },
                )
            };
            for k in 0..8 {
                for bit in [1, 2, 4] {
                    if k & bit == 0 {
                        if let (Some(a), Some(c)) =
                            (view.project(corner(k)), view.project(corner(k | bit)))
                        {
                            painter.line_segment([pt(a), pt(c)], egui::Stroke::new(1.0, yellow));
                        }
                    }
                }
            }
        }
    }
    for (k, _, a, b) in ed.handles(scene, view, time_s) {
        painter.line_segment([pt(a), pt(b)], egui::Stroke::new(3.0, colors[k]));
        let tip = match (ed.handle, ed.selection) {
            (HandleMode::Rotate, Some(Selection::Object(_))) => {
                egui::Shape::circle_stroke(pt(b), 5.0, egui::Stroke::new(2.0, colors[k]))
            }
            (HandleMode::Scale, Some(Selection::Object(_))) => egui::Shape::rect_filled(
                egui::Rect::from_center_size(pt(b), egui::vec2(8.0, 8.0)),
                0.0,
                colors[k],
            ),
            _ => egui::Shape::circle_filled(pt(b), 4.0, colors[k]),
        };
        painter.add(tip);
    }
}

/// What the panel's section asks for and where its selected object's position field is.
pub struct PanelOut {
    pub actions: Vec<EditAction>,
    /// The position's x field of the selected object, in points (scripted tests drag it).
    pub position_field: Option<egui::Rect>,
}

/// The panel's "Edit scene" section: the selection's fields, the lights, add/remove, save.
/// Returns the changes to apply.
pub fn panel(ui: &mut egui::Ui, v: &EditView) -> PanelOut {
    let mut out = Vec::new();
    let mut position_field = None;
    let ed = v.editor;
    ui.label(
        "Click selects (lights: their circles); drag a handle to edit. 1/2/3 move/rotate/scale, \
         Insert/Delete add/remove a light, Ctrl+S save.",
    );
    ui.horizontal(|ui| {
        for (m, name) in [
            (HandleMode::Move, "move (1)"),
            (HandleMode::Rotate, "rotate (2)"),
            (HandleMode::Scale, "scale (3)"),
        ] {
            if ui.selectable_label(ed.handle == m, name).clicked() {
                out.push(EditAction::Handle(m));
            }
        }
    });
    let names: Vec<&str> = v.scene.objects.iter().map(|o| o.name.as_str()).collect();
    let selected = match ed.selection {
        Some(Selection::Object(i)) => names.get(i).map_or("?".to_string(), |n| n.to_string()),
        Some(Selection::Light(i)) => v.light_names.get(i).cloned().unwrap_or_default(),
        None => "nothing".into(),
    };
    egui::ComboBox::from_label("selected")
        .width(120.0)
        .selected_text(selected)
        .show_ui(ui, |ui| {
            for (i, n) in names.iter().enumerate() {
                if ui
                    .selectable_label(ed.selection == Some(Selection::Object(i)), *n)
                    .clicked()
                {
                    out.push(EditAction::Select(Some(Selection::Object(i))));
                }
            }
            for (i, n) in v.light_names.iter().enumerate() {
                if ui
                    .selectable_label(ed.selection == Some(Selection::Light(i)), n.as_str())
                    .clicked()
                {
                    out.push(EditAction::Select(Some(Selection::Light(i))));
                }
            }
        });
    let speed = 0.005 * v.scene.aabb_at(0.0).extent().length().max(1e-3);
    match ed.selection {
        Some(Selection::Object(i)) => {
            if let Some(o) = v.scene.objects.get(i) {
                let b = o.aabb_at(0.0);
                ui.label(format!(
                    "bounds [{:.3}, {:.3}, {:.3}] – [{:.3}, {:.3}, {:.3}] m{}",
                    b.min.x,
                    b.min.y,
                    b.min.z,
                    b.max.x,
                    b.max.y,
                    b.max.z,
                    if o.dynamic { " · dynamic" } else { "" }
                ));
                if o.is_animated() {
                    ui.label("animated by keyframes: edit them in the scene file");
                } else {
                    // Each row sets only its key: the others keep the file's values.
                    let mut p = ed.placement(i);
                    let (mut t, mut r, mut sc) = (
                        o.transform.translate,
                        ed.rotate_deg(v.scene, i),
                        o.transform.scale,
                    );
                    let before = (t, r, sc);
                    position_field = Some(vec3_row(ui, "position m", &mut t, speed, None));
                    vec3_row(ui, "rotate °", &mut r, 0.5, None);
                    vec3_row(ui, "scale", &mut sc, 0.01, Some(1e-4..=1e4));
                    if t != before.0 {
                        p.translate = Some(t);
                    }
                    if r != before.1 {
                        p.rotate_deg = Some(r);
                    }
                    if sc != before.2 {
                        p.scale = Some(sc);
                    }
                    if (t, r, sc) != before {
                        out.push(EditAction::Place(i, p));
                    }
                }
            }
        }
        Some(Selection::Light(i)) => {
            if let Some(l) = v.scene.lights.get(i) {
                let mut e = *l;
                light_fields(ui, &mut e, speed);
                if e != *l {
                    out.push(EditAction::SetLight(i, e));
                }
                if ui.button("Remove light (Delete)").clicked() {
                    out.push(EditAction::RemoveLight(i));
                }
            }
        }
        None => {}
    }
    ui.horizontal(|ui| {
        let mut kind = ed.new_light_kind;
        egui::ComboBox::from_id_salt("new light kind")
            .width(90.0)
            .selected_text(LIGHT_KINDS.get(kind).copied().unwrap_or("point"))
            .show_ui(ui, |ui| {
                for (k, name) in LIGHT_KINDS.iter().enumerate() {
                    ui.selectable_value(&mut kind, k, *name);
                }
            });
        if ui.button("Add (Insert)").clicked() {
            out.push(EditAction::AddLight(kind));
        } else if kind != ed.new_light_kind {
            out.push(EditAction::LightKind(kind));
        }
    });
    if ui.button("Save scene (Ctrl+S)").clicked() {
        out.push(EditAction::Save);
    }
    if !ed.status.is_empty() {
        ui.label(&ed.status);
    }
    PanelOut {
        actions: out,
        position_field,
    }
}

/// Three drag values and a label; returns where the first (x) was drawn.
fn vec3_row(
    ui: &mut egui::Ui,
    label: &str,
    v: &mut Vec3,
    speed: f32,
    range: Option<std::ops::RangeInclusive<f32>>,
) -> egui::Rect {
    ui.horizontal(|ui| {
        let mut first = egui::Rect::NOTHING;
        for k in 0..3 {
            let mut d = egui::DragValue::new(&mut v[k]).speed(speed).max_decimals(4);
            if let Some(r) = &range {
                d = d.range(r.clone());
            }
            let rect = ui.add(d).rect;
            if k == 0 {
                first = rect;
            }
        }
        ui.label(label);
        first
    })
    .inner
}

/// A unit direction as azimuth (about +Y from +Z) and elevation, degrees.
fn direction_row(ui: &mut egui::Ui, label: &str, d: &mut Vec3) {
    let mut az = d.x.atan2(d.z).to_degrees();
    let mut el = d.y.clamp(-1.0, 1.0).asin().to_degrees();
    let (az0, el0) = (az, el);
    ui.horizontal(|ui| {
        ui.add(egui::DragValue::new(&mut az).speed(0.5).suffix("°"));
        ui.add(
            egui::DragValue::new(&mut el)
                .speed(0.5)
                .range(-90.0..=90.0)
                .suffix("°"),
        );
        ui.label(format!("{label} azimuth, elevation"));
    });
    if (az, el) != (az0, el0) {
        let (a, e) = (az.to_radians(), el.to_radians());
        *d = Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos());
    }
}

/// The fields of every kind of light (ranges as the scene format's checks).
fn light_fields(ui: &mut egui::Ui, l: &mut Light, speed: f32) {
    let nonneg = Some(0.0..=1e9);
    match l {
        Light::Point {
            position,
            intensity_w_sr,
        } => {
            vec3_row(ui, "position m", position, speed, None);
            vec3_row(ui, "intensity W/sr", intensity_w_sr, 0.01, nonneg);
        }
        Light::Spot {
            position,
            direction,
            intensity_w_sr,
            cutoff_deg,
            beam_deg,
        } => {
            vec3_row(ui, "position m", position, speed, None);
            direction_row(ui, "direction", direction);
            vec3_row(ui, "intensity W/sr", intensity_w_sr, 0.01, nonneg);
            ui.add(egui::Slider::new(cutoff_deg, 0.5..=89.5).text("cutoff °"));
            let max = *cutoff_deg;
            ui.add(egui::Slider::new(beam_deg, 0.1..=max).text("beam °"));
        }
        Light::Directional {
            direction,
            irradiance_w_m2,
        } => {
            direction_row(ui, "direction", direction);
            vec3_row(ui, "irradiance W/m²", irradiance_w_m2, 0.01, nonneg);
        }
        Light::Sphere {
            position,
            radius_m,
            radiance_w_sr_m2,
            samples,
        } => {
            vec3_row(ui, "position m", position, speed, None);
            ui.add(
                egui::DragValue::new(radius_m)
                    .speed(speed * 0.1)
                    .range(1e-5..=1e6)
                    .prefix("radius m "),
            );
            vec3_row(ui, "radiance W/(m²·sr)", radiance_w_sr_m2, 0.1, nonneg);
            samples_slider(ui, samples);
        }
        Light::Rectangle {
            position,
            normal,
            width_m,
            height_m,
            radiance_w_sr_m2,
            samples,
            ..
        } => {
            vec3_row(ui, "position m", position, speed, None);
            direction_row(ui, "normal", normal);
            ui.horizontal(|ui| {
                for (v, name) in [(width_m, "width m"), (height_m, "height m")] {
                    ui.add(
                        egui::DragValue::new(v)
                            .speed(speed * 0.1)
                            .range(1e-5..=1e6)
                            .prefix(format!("{name} ")),
                    );
                }
            });
            vec3_row(ui, "radiance W/(m²·sr)", radiance_w_sr_m2, 0.1, nonneg);
            samples_slider(ui, samples);
        }
        Light::Element { .. } => {}
    }
}

fn samples_slider(ui: &mut egui::Ui, samples: &mut u32) {
    let l = crate::limits::AREA_SAMPLES;
    ui.add(egui::Slider::new(samples, l.slider(1, 64)).text("samples (shadow views)"));
}
