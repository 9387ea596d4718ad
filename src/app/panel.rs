//! The side panel: per-pass GPU timings, light, tone-mapping, shadow and global-illumination
//! controls, screenshot.

use crate::gi::{GiMethod, GiSettings};
use crate::light::ShadowSettings;
use crate::post::{ToneMap, ToneOperator};
use crate::vk::PassTiming;
use crate::voxel::debug_view::DebugView;
use std::collections::VecDeque;

/// Per-pass GPU times of the last frames; the panel shows medians (robust to hiccups).
#[derive(Debug)]
pub struct TimingStats {
    frames: VecDeque<Vec<PassTiming>>,
    capacity: usize,
}

impl TimingStats {
    pub fn new(capacity: usize) -> Self {
        Self {
            frames: VecDeque::with_capacity(capacity),
            capacity: capacity.max(1),
        }
    }

    /// Adds one finished frame's timings (frames without timings are skipped).
    pub fn push(&mut self, frame: Vec<PassTiming>) {
        if frame.is_empty() {
            return;
        }
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        self.frames.push_back(frame);
    }

    /// Forgets every frame (after the graph changed: its passes may differ).
    pub fn clear(&mut self) {
        self.frames.clear();
    }

    /// (pass, median ms) in the order of the latest frame, over the frames that ran the pass.
    pub fn medians(&self) -> Vec<(String, f64)> {
        let Some(latest) = self.frames.back() else {
            return Vec::new();
        };
        latest
            .iter()
            .map(|t| {
                let mut v: Vec<f64> = self
                    .frames
                    .iter()
                    .flat_map(|f| f.iter().filter(|p| p.name == t.name).map(|p| p.gpu_ms))
                    .collect();
                v.sort_by(f64::total_cmp);
                (t.name.clone(), median_sorted(&v))
            })
            .collect()
    }
}

fn median_sorted(v: &[f64]) -> f64 {
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// What the panel edits. The viewer compares it with the renderer's settings each frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    pub tonemap: ToneMap,
    pub shadow: ShadowSettings,
    /// Indirect light; a change needs a new renderer, which the viewer makes once no pointer
    /// button is down (not while a slider is being dragged).
    pub gi: GiSettings,
    /// Per light, a factor on the scene file's intensity.
    pub light_scale: Vec<f32>,
    pub speed_m_s: f32,
    /// Scene time (keyframed objects and dynamic voxels follow it) and whether it runs.
    pub time_s: f32,
    pub animate: bool,
    /// A voxel debug view instead of the lit image (a change needs a new renderer).
    pub debug: Option<DebugView>,
    /// The object whose atlas the atlas view shows (index into the scene's objects).
    pub atlas_object: usize,
    /// Set by the button (or F12); the viewer clears it after saving.
    pub screenshot: bool,
}

/// Read-only facts the panel shows.
pub struct PanelInfo<'a> {
    pub device: &'a str,
    pub extent_px: (u32, u32),
    pub frame_ms: f32,
    pub light_names: &'a [String],
    /// The scene's objects, for the atlas view's picker.
    pub object_names: &'a [String],
    pub status: &'a str,
    /// Frames the indirect light has accumulated (`None`: GI off).
    pub gi_frames: Option<u32>,
}

const GI_METHODS: [(GiMethod, &str); 3] = [
    (GiMethod::None, "none"),
    (GiMethod::Hemisphere, "hemisphere"),
    (GiMethod::Pathtrace, "pathtrace"),
];

fn gi_method_name(m: GiMethod) -> &'static str {
    GI_METHODS
        .iter()
        .find(|(g, _)| *g == m)
        .map_or("?", |(_, n)| n)
}

const SHADOW_RESOLUTIONS: [u32; 5] = [256, 512, 1024, 2048, 4096];
const OPERATORS: [ToneOperator; 4] = [
    ToneOperator::Linear,
    ToneOperator::Logarithmic,
    ToneOperator::Drago,
    ToneOperator::Filmic,
];

/// Draws the panel; returns its width in points.
pub fn draw(ctx: &egui::Context, c: &mut Controls, stats: &TimingStats, info: &PanelInfo) -> f32 {
    let panel = egui::SidePanel::left("voxgi panel")
        .resizable(false)
        .default_width(240.0)
        .show(ctx, |ui| {
            ui.heading("voxgi");
            ui.label(format!(
                "{} · {}×{} · {:.1} ms/frame",
                info.device, info.extent_px.0, info.extent_px.1, info.frame_ms
            ));
            ui.label("WASD move · Q/E down/up · right mouse look · wheel speed · F12 screenshot");
            ui.separator();

            egui::CollapsingHeader::new("GPU time per pass (median)")
                .default_open(true)
                .show(ui, |ui| {
                    let medians = stats.medians();
                    egui::Grid::new("timings").striped(true).show(ui, |ui| {
                        for (name, ms) in &medians {
                            ui.label(name);
                            ui.label(format!("{ms:8.3} ms"));
                            ui.end_row();
                        }
                        ui.strong("total");
                        ui.strong(format!(
                            "{:8.3} ms",
                            medians.iter().map(|(_, ms)| ms).sum::<f64>()
                        ));
                        ui.end_row();
                    });
                });

            egui::CollapsingHeader::new("Camera")
                .default_open(true)
                .show(ui, |ui| {
                    ui.add(
                        egui::Slider::new(&mut c.speed_m_s, 0.01..=100.0)
                            .logarithmic(true)
                            .text("speed m/s"),
                    );
                    ui.horizontal(|ui| {
                        ui.checkbox(&mut c.animate, "animate");
                        ui.label(format!("t = {:.2} s", c.time_s));
                    });
                });

            egui::CollapsingHeader::new("Lights")
                .default_open(true)
                .show(ui, |ui| {
                    for (i, s) in c.light_scale.iter_mut().enumerate() {
                        let name = info.light_names.get(i).map_or("light", |n| n.as_str());
                        ui.add(
                            egui::Slider::new(s, 0.0..=100.0)
                                .logarithmic(true)
                                .text(format!("{name} ×")),
                        );
                    }
                });

            egui::CollapsingHeader::new("Tone mapping")
                .default_open(true)
                .show(ui, |ui| {
                    egui::ComboBox::from_label("operator")
                        .selected_text(format!("{:?}", c.tonemap.operator))
                        .show_ui(ui, |ui| {
                            for op in OPERATORS {
                                ui.selectable_value(&mut c.tonemap.operator, op, format!("{op:?}"));
                            }
                        });
                    ui.add(
                        egui::Slider::new(&mut c.tonemap.exposure, 0.001..=1000.0)
                            .logarithmic(true)
                            .text("exposure"),
                    );
                    ui.add(
                        egui::Slider::new(&mut c.tonemap.white, 0.01..=100.0)
                            .logarithmic(true)
                            .text("white"),
                    );
                });

            egui::CollapsingHeader::new("Shadows")
                .default_open(true)
                .show(ui, |ui| {
                    egui::ComboBox::from_label("resolution")
                        .selected_text(format!("{}²", c.shadow.resolution))
                        .show_ui(ui, |ui| {
                            for r in SHADOW_RESOLUTIONS {
                                ui.selectable_value(&mut c.shadow.resolution, r, format!("{r}²"));
                            }
                        });
                    ui.add(egui::Slider::new(&mut c.shadow.pcf_radius, 0..=4).text("PCF radius"));
                    ui.add(
                        egui::Slider::new(&mut c.shadow.bias_texels, 0.0..=8.0).text("bias texels"),
                    );
                    ui.add(
                        egui::Slider::new(&mut c.shadow.slope_bias_texels, 0.0..=8.0)
                            .text("slope bias"),
                    );
                    ui.add(
                        egui::Slider::new(&mut c.shadow.normal_offset_texels, 0.0..=8.0)
                            .text("normal offset"),
                    );
                });

            egui::CollapsingHeader::new("Global illumination")
                .default_open(true)
                .show(ui, |ui| gi_controls(ui, &mut c.gi, info.gi_frames));

            egui::CollapsingHeader::new("View")
                .default_open(false)
                .show(ui, |ui| {
                    egui::ComboBox::from_label("image")
                        .selected_text(debug_name(c.debug))
                        .show_ui(ui, |ui| {
                            for v in VIEWS {
                                ui.selectable_value(&mut c.debug, v, debug_name(v));
                            }
                        });
                    if c.debug == Some(DebugView::Atlas) {
                        let name = |i: usize| info.object_names.get(i).map_or("?", |n| n.as_str());
                        egui::ComboBox::from_label("object")
                            .selected_text(name(c.atlas_object))
                            .show_ui(ui, |ui| {
                                for i in 0..info.object_names.len() {
                                    ui.selectable_value(&mut c.atlas_object, i, name(i));
                                }
                            });
                    }
                });

            ui.separator();
            if ui.button("Screenshot (F12)").clicked() {
                c.screenshot = true;
            }
            if !info.status.is_empty() {
                ui.label(info.status);
            }
        });
    panel.response.rect.width()
}

/// The "View" combo's entries: the lit image, then every debug view.
const VIEWS: [Option<DebugView>; 6] = [
    None,
    Some(DebugView::Voxels),
    Some(DebugView::Steps),
    Some(DebugView::Level),
    Some(DebugView::Albedo),
    Some(DebugView::Atlas),
];

/// Name of a debug view in the panel.
fn debug_name(v: Option<DebugView>) -> &'static str {
    match v {
        None => "lit",
        Some(DebugView::Voxels) => "voxels",
        Some(DebugView::Steps) => "traversal steps",
        Some(DebugView::Level) => "hierarchy level",
        Some(DebugView::Albedo) => "albedo",
        Some(DebugView::Atlas) => "object atlas",
    }
}

/// The GI method and its parameters; what does not apply to the method is hidden.
fn gi_controls(ui: &mut egui::Ui, gi: &mut GiSettings, frames: Option<u32>) {
    egui::ComboBox::from_label("method")
        .selected_text(gi_method_name(gi.method))
        .show_ui(ui, |ui| {
            for (m, name) in GI_METHODS {
                ui.selectable_value(&mut gi.method, m, name);
            }
        });
    if gi.method == GiMethod::None {
        ui.label("direct light only");
        return;
    }
    ui.add(
        egui::Slider::new(&mut gi.rays, 1..=256)
            .logarithmic(true)
            .text("rays / pixel"),
    );
    if gi.method == GiMethod::Pathtrace {
        ui.add(egui::Slider::new(&mut gi.bounces, 1..=8).text("bounces"));
    }
    let mut limited = gi.radius_m.is_some();
    ui.checkbox(&mut limited, "limit ray length");
    match (limited, gi.radius_m) {
        (true, None) => gi.radius_m = Some(1.0),
        (false, Some(_)) => gi.radius_m = None,
        _ => {}
    }
    if let Some(r) = &mut gi.radius_m {
        ui.add(
            egui::Slider::new(r, 0.01..=100.0)
                .logarithmic(true)
                .text("radius m"),
        );
    }
    ui.add(egui::Slider::new(&mut gi.filter_radius, 0..=16).text("filter radius"));
    ui.add(egui::Slider::new(&mut gi.filter_passes, 0..=8).text("filter passes"));
    ui.add(egui::Slider::new(&mut gi.normal_offset_voxels, 0.0..=4.0).text("normal offset k1"));
    ui.add(egui::Slider::new(&mut gi.ray_offset_voxels, 0.0..=2.0).text("ray offset k2"));
    ui.add(egui::Slider::new(&mut gi.start_level, 0..=8).text("start level"));
    ui.add(
        egui::Slider::new(&mut gi.max_iterations, 16..=4096)
            .logarithmic(true)
            .text("max iterations"),
    );
    if gi.method == GiMethod::Pathtrace {
        match frames {
            Some(n) => ui.label(format!("accumulated frames: {n}")),
            None => ui.label("accumulated frames: –"),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_combo_offers_every_debug_view_once() {
        use clap::ValueEnum;
        for v in DebugView::value_variants() {
            let n = VIEWS.iter().filter(|&&e| e == Some(*v)).count();
            assert_eq!(n, 1, "{v:?} appears {n} times in the panel's View combo");
        }
        let names: std::collections::HashSet<_> = VIEWS.iter().map(|&v| debug_name(v)).collect();
        assert_eq!(names.len(), VIEWS.len(), "entries share a name");
    }

    fn frame(values: &[(&str, f64)]) -> Vec<PassTiming> {
        values
            .iter()
            .map(|&(n, ms)| PassTiming {
                name: n.into(),
                gpu_ms: ms,
            })
            .collect()
    }

    #[test]
    fn medians_follow_latest_order_and_ignore_outliers() {
        let mut s = TimingStats::new(3);
        assert!(s.medians().is_empty());
        s.push(frame(&[("a", 100.0), ("b", 1.0)]));
        s.push(Vec::new());
        s.push(frame(&[("a", 2.0), ("b", 2.0)]));
        s.push(frame(&[("b", 3.0), ("a", 3.0)]));
        assert_eq!(
            s.medians(),
            vec![("b".to_string(), 2.0), ("a".to_string(), 3.0)]
        );
        // Capacity 3: the 100 ms frame drops out once a fourth arrives.
        s.push(frame(&[("a", 4.0)]));
        assert_eq!(s.medians(), vec![("a".to_string(), 3.0)]);
        s.clear();
        assert!(s.medians().is_empty());
    }

    #[test]
    fn even_count_median_averages() {
        assert_eq!(median_sorted(&[1.0, 2.0, 4.0, 8.0]), 3.0);
        assert_eq!(median_sorted(&[]), 0.0);
    }
}
