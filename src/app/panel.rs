//! The side panel: per-pass GPU timings, light, post-processing (tone mapping included),
//! shadow and global-illumination controls, screenshot.

use crate::gi::{GiMethod, GiSettings};
use crate::light::ShadowSettings;
use crate::panel_keys::{key_checkbox, key_choice, key_slider, key_switch, set_key};
use crate::post::{ToneMap, ToneOperator};
use crate::scene::schema::{self, Value};
use crate::scene::PostTable;
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
        let frame = merge_shadow_layers(frame);
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
                let v: Vec<f64> = self
                    .frames
                    .iter()
                    .flat_map(|f| f.iter().filter(|p| p.name == t.name).map(|p| p.gpu_ms))
                    .collect();
                (t.name.clone(), crate::stats::median(&v))
            })
            .collect()
    }
}

/// Pass families ([`super::frame_graph::family`]) the table shows as one row, their sum: the
/// cached shadow maps record one pass per layer (`shadow_depth[v]`, one per shadow view: six
/// per point light), shown as one `shadow_depth` row, as an uncached frame names it, so that a
/// scene with many lights does not push the panel's other sections off screen. (The
/// frame-time graph groups every family.)
const SUMMED_FAMILIES: &[&str] = &["shadow_depth"];

/// `frame` with the members of each of [`SUMMED_FAMILIES`] summed into one row named for the
/// family, where the first of them stood.
fn merge_shadow_layers(frame: Vec<PassTiming>) -> Vec<PassTiming> {
    let mut out: Vec<PassTiming> = Vec::with_capacity(frame.len());
    for t in frame {
        let family = super::frame_graph::family(&t.name);
        if family != t.name && SUMMED_FAMILIES.contains(&family) {
            match out.iter_mut().find(|r| r.name == family) {
                Some(row) => row.gpu_ms += t.gpu_ms,
                None => out.push(PassTiming {
                    name: family.to_string(),
                    gpu_ms: t.gpu_ms,
                }),
            }
        } else {
            out.push(t);
        }
    }
    out
}

/// What the panel edits. The viewer compares it with the renderer's settings each frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    pub tonemap: ToneMap,
    /// TAA, auto exposure, bloom, FXAA; a change needs a new renderer (applied like `gi`).
    pub post: crate::post::PostSettings,
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
    /// Set by the "Add camera keyframe" button; the viewer records the camera and clears it.
    pub add_keyframe: bool,
    /// The time budget of "best within budget", ms (GPU time to the image, as the sweep
    /// measured it on its device).
    pub budget_ms: f32,
    /// Set by the "Best within budget" button; the viewer applies the sweep's choice.
    pub tune: bool,
    /// Dynamic resolution: the frame budget, the smallest scale, when to refine.
    pub dynres: crate::scene::DynamicResolution,
    /// Stereo packing and parallax (`app/stereo.rs`); turning it on or off, or another
    /// path, needs a new renderer (applied like `gi`).
    pub stereo: super::stereo::StereoControls,
    /// The camera's projection (checkbox, `O` key) and orthographic view height; the viewer
    /// refuses a switch the frame cannot render and says why.
    pub projection: crate::scene::Projection,
    pub ortho_height_m: f32,
    /// The "Open scene" section: the scene shown and another to open (`app/open.rs`).
    pub open: super::open::OpenControls,
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
    /// The stereo path that runs, or why it fell back (`None`: mono).
    pub stereo: Option<&'a str>,
    /// Per-pass GPU times of the last frames, for the frame-time graph.
    pub history: &'a super::frame_graph::FrameHistory,
    /// The size the scene renders at and its scale of the scene's area, eighths (dynamic
    /// resolution; 8: full size).
    pub internal: (u32, u32),
    pub scale_steps: u32,
    /// The GI settings the renderer runs (with dynamic resolution's ray count).
    pub gi: Option<crate::gi::GiSettings>,
}

const SHADOW_RESOLUTIONS: [u32; 5] = [256, 512, 1024, 2048, 4096];
const OPERATORS: [ToneOperator; 4] = [
    ToneOperator::Linear,
    ToneOperator::Logarithmic,
    ToneOperator::Drago,
    ToneOperator::Filmic,
];

/// Where the GPU-time table's text landed in the last drawn frame, in points: the viewer logs
/// it at the end of a scripted run so that tests can check the table's geometry.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelLayout {
    /// The whole side panel.
    pub panel: egui::Rect,
    /// Per pass, then the total.
    pub rows: Vec<TableRow>,
    /// The frame-time graph.
    pub graph: super::frame_graph::GraphLayout,
    /// The panel's vertical scrolling (its contents are taller than a short window).
    pub scroll: ScrollLayout,
    /// Controls the window tests click, where this frame drew them.
    pub spots: Vec<Spot>,
}

/// A control's name and where it was drawn, in points.
pub type Spot = (String, egui::Rect);

/// Where the panel's scroll area stands, in points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScrollLayout {
    /// How far the contents are scrolled down.
    pub offset: f32,
    /// The height of all the contents.
    pub content_height: f32,
    /// The visible part of the scroll area.
    pub view: egui::Rect,
    /// The "Screenshot" button at the bottom of the contents, where this frame drew it.
    pub screenshot_button: egui::Rect,
}

impl ScrollLayout {
    /// The largest offset: the contents' bottom at the view's bottom.
    pub fn max_offset(&self) -> f32 {
        (self.content_height - self.view.height()).max(0.0)
    }
}

impl Default for ScrollLayout {
    fn default() -> Self {
        Self {
            offset: 0.0,
            content_height: 0.0,
            view: egui::Rect::NOTHING,
            screenshot_button: egui::Rect::NOTHING,
        }
    }
}

/// A row of the GPU-time table: the pass name, where its name and its time were drawn.
pub type TableRow = (String, egui::Rect, egui::Rect);

impl Default for PanelLayout {
    fn default() -> Self {
        Self {
            panel: egui::Rect::NOTHING,
            rows: Vec::new(),
            graph: Default::default(),
            scroll: Default::default(),
            spots: Vec::new(),
        }
    }
}

impl PanelLayout {
    /// One line of JSON; rectangles as `[min x, min y, max x, max y]`.
    pub fn to_json(&self) -> String {
        let r = |r: &egui::Rect| [r.min.x, r.min.y, r.max.x, r.max.y];
        let rows: Vec<_> = self
            .rows
            .iter()
            .map(|(name, n, t)| serde_json::json!({ "name": name, "name_rect": r(n), "time_rect": r(t) }))
            .collect();
        let g = &self.graph;
        let graph = serde_json::json!({
            "rect": g.rect.as_ref().map(r),
            "series": g.series.iter().map(|(name, ms)| serde_json::json!({ "name": name, "mean_ms": ms })).collect::<Vec<_>>(),
            "frames": g.frames,
            "scale_ms": g.scale_ms,
        });
        let s = &self.scroll;
        let scroll = serde_json::json!({
            "offset": s.offset,
            "content_height": s.content_height,
            "view": r(&s.view),
            "screenshot_button": r(&s.screenshot_button),
        });
        serde_json::json!({ "panel": r(&self.panel), "rows": rows, "graph": graph, "scroll": scroll })
            .to_string()
    }
}

/// The GPU-time table: pass names on the left, median milliseconds right-aligned in a column as
/// wide as the widest number, then the total. The name column takes what is left of the
/// panel's width; a longer name is elided with "…" and shows in full on hover (egui's
/// truncating label), so names never run into the numbers however narrow the panel. The table
/// ends at `right_x`. Returns (name, name text, time text) per row.
fn timing_table(ui: &mut egui::Ui, medians: &[(String, f64)], right_x: f32) -> Vec<TableRow> {
    let total: f64 = medians.iter().map(|(_, ms)| ms).sum();
    let rows: Vec<(egui::RichText, egui::RichText)> = medians
        .iter()
        .map(|(name, ms)| (name.into(), format!("{ms:.3}").into()))
        .chain([(
            egui::RichText::new("total").strong(),
            egui::RichText::new(format!("{total:.3}")).strong(),
        )])
        .collect();
    // Monospace digits: right-aligned numbers with three decimals line up on the point.
    let font = egui::TextStyle::Monospace.resolve(ui.style());
    let color = ui.visuals().text_color();
    let time_w = rows.iter().fold(0.0f32, |w, (_, t)| {
        let text = t.text().to_owned();
        w.max(
            ui.fonts_mut(|f| f.layout_no_wrap(text, font.clone(), color))
                .size()
                .x,
        )
    });
    let gap = ui.spacing().item_spacing.x;
    // At least a few characters of each name, even in a panel too narrow for both columns
    // (the rows then widen the panel rather than overlap).
    let width = ui.available_width().min(right_x - ui.cursor().min.x);
    let name_w = (width - time_w - gap).max(3.0 * font.size);
    let size = egui::vec2(name_w + gap + time_w, ui.spacing().interact_size.y);
    let stripe = ui.visuals().faint_bg_color;
    let row = |ui: &mut egui::Ui, name: egui::RichText, time: egui::RichText, striped| {
        let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
        if striped {
            // Stripes lead the eye from a name to its number.
            ui.painter().rect_filled(rect, 2.0, stripe);
        }
        let name_cell = egui::Rect::from_min_size(rect.min, egui::vec2(name_w, size.y));
        let time_cell = egui::Rect::from_min_max(rect.max - egui::vec2(time_w, size.y), rect.max);
        let left = egui::Layout::left_to_right(egui::Align::Center);
        let right = egui::Layout::right_to_left(egui::Align::Center);
        let cell = |rect, layout| egui::UiBuilder::new().max_rect(rect).layout(layout);
        let n = ui
            .new_child(cell(name_cell, left))
            .add(egui::Label::new(name).truncate());
        let t = ui.new_child(cell(time_cell, right)).label(time.monospace());
        (n.rect, t.rect)
    };
    row(
        ui,
        egui::RichText::new("pass").weak(),
        egui::RichText::new("ms").weak(),
        false,
    );
    rows.into_iter()
        .enumerate()
        .map(|(i, (name, time))| {
            let label = name.text().to_owned();
            let (n, t) = row(ui, name, time, i % 2 == 0);
            (label, n, t)
        })
        .collect()
}

/// Draws the panel; returns where it and its GPU-time table landed. `edit_ui` draws the scene
/// editor's section (`app::edit::panel`).
pub fn draw(
    root: &mut egui::Ui,
    c: &mut Controls,
    stats: &TimingStats,
    info: &PanelInfo,
    edit_ui: &mut dyn FnMut(&mut egui::Ui),
) -> PanelLayout {
    let mut rows = Vec::new();
    let mut graph = Default::default();
    let mut scroll = ScrollLayout::default();
    let mut spots = Vec::new();
    // Exactly 240 points: a panel grows to fit what does not wrap (egui 0.37 lays out a
    // slider's label beside it, unwrapped: "cascade log/uniform λ" ends 310 points in), and a
    // wider panel would take the scene's width. What does not fit is clipped at the edge. In
    // a narrower window the panel takes the window's width: egui cuts an exact size to the
    // window but lays the contents out at least that wide, past the window's edge.
    let width = root.available_width().min(240.0);
    let panel = egui::Panel::left("voxgi panel")
        .resizable(false)
        .exact_size(width)
        .show(root, |ui| {
            // Taller than a short window: the contents scroll (wheel over the panel, or the
            // bar). The width stays the panel's, as without scrolling. No scrolling by
            // dragging the contents: a drag there is a slider's or a drag value's.
            let area = egui::ScrollArea::vertical()
                .auto_shrink([false, true])
                .scroll_source(egui::scroll_area::ScrollSource {
                    drag: egui::scroll_area::DragScroll::Never,
                    ..Default::default()
                })
                .show(ui, |ui| {
                    // The panel's inner right edge as this frame lays it out (within the window): a
                    // control wider than that (a collapsing header's title, a slider) widens the
                    // `Ui` as it is added, and the table would follow it off the window.
                    let right_x = ui.max_rect().right();
                    ui.heading("voxgi");
                    ui.label(format!(
                        "{} · {}×{} · {:.1} ms/frame",
                        info.device, info.extent_px.0, info.extent_px.1, info.frame_ms
                    ));
                    ui.label(format!(
                        "renders {}×{} (scale {}){}",
                        info.internal.0,
                        info.internal.1,
                        scale_name(info.scale_steps),
                        info.gi.map_or_else(String::new, |gi| gi_rays_note(&gi))
                    ));
                    ui.label(
                "WASD move · Q/E down/up · right mouse look · wheel speed · G next GI method · \
                 O orthographic · F12 screenshot",
            );
                    ui.separator();

                    egui::CollapsingHeader::new("GPU time per pass (median)")
                        .default_open(true)
                        .show(ui, |ui| {
                            rows = timing_table(ui, &stats.medians(), right_x);
                        });

                    egui::CollapsingHeader::new("GPU time per frame (stacked)")
                        .default_open(true)
                        .show(ui, |ui| {
                            let width = ui.available_width().min(right_x - ui.cursor().min.x);
                            graph = super::frame_graph::draw(ui, info.history, width);
                        });

                    egui::CollapsingHeader::new("Camera")
                        .default_open(true)
                        .show(ui, |ui| camera_controls(ui, c));
                    egui::CollapsingHeader::new("Lights")
                        .default_open(true)
                        .show(ui, |ui| light_controls(ui, c, info.light_names));

                    egui::CollapsingHeader::new("Edit scene")
                        .default_open(true)
                        .show(ui, |ui| edit_ui(ui));

                    egui::CollapsingHeader::new("Open scene")
                        .default_open(true)
                        .show(ui, |ui| {
                            super::open::panel_section(ui, &mut c.open, &mut spots)
                        });

                    egui::CollapsingHeader::new("Post-processing")
                        .default_open(true)
                        .show(ui, |ui| {
                            post_controls(ui, &mut c.post, &mut c.tonemap, &mut spots)
                        });

                    egui::CollapsingHeader::new("Shadows")
                        .default_open(true)
                        .show(ui, |ui| shadow_controls(ui, &mut c.shadow));

                    egui::CollapsingHeader::new("Dynamic resolution")
                        .default_open(false)
                        .show(ui, |ui| dynres_controls(ui, &mut c.dynres));

                    egui::CollapsingHeader::new("Global illumination")
                        .default_open(true)
                        .show(ui, |ui| {
                            gi_controls(ui, &mut c.gi, info.gi_frames);
                            budget_controls(ui, c);
                        });

                    let stereo = egui::CollapsingHeader::new("Stereo")
                        .default_open(c.stereo.mode.is_some())
                        .show(ui, |ui| {
                            super::stereo::panel_section(ui, &mut c.stereo, info.stereo, &mut spots)
                        });
                    spots.push(("stereo section".into(), stereo.header_response.rect));

                    egui::CollapsingHeader::new("View")
                        .default_open(false)
                        .show(ui, |ui| view_controls(ui, c, info.object_names));

                    ui.separator();
                    scroll.screenshot_button = footer(ui, c, info.status);
                });
            // Where the contents are drawn (past an end while rubber-banding).
            scroll.offset = area.state.unclamped_offset().y;
            scroll.content_height = area.content_size.y;
            scroll.view = area.inner_rect;
        });
    PanelLayout {
        panel: panel.response.rect,
        rows,
        graph,
        scroll,
        spots,
    }
}

/// The camera's speed, animation clock and projection.
fn camera_controls(ui: &mut egui::Ui, c: &mut Controls) {
    ui.add(
        egui::Slider::new(&mut c.speed_m_s, 0.01..=100.0)
            .logarithmic(true)
            .text("speed m/s"),
    );
    ui.horizontal(|ui| {
        ui.checkbox(&mut c.animate, "animate");
        ui.label(format!("t = {:.2} s", c.time_s));
    });
    projection_controls(ui, c);
}

/// One intensity scale per light, named as in the scene.
fn light_controls(ui: &mut egui::Ui, c: &mut Controls, light_names: &[String]) {
    for (i, s) in c.light_scale.iter_mut().enumerate() {
        let name = light_names.get(i).map_or("light", |n| n.as_str());
        ui.add(
            egui::Slider::new(s, 0.0..=100.0)
                .logarithmic(true)
                .text(format!("{name} ×")),
        );
    }
}

/// The debug image shown instead of the frame, and for the atlas view its object.
fn view_controls(ui: &mut egui::Ui, c: &mut Controls, object_names: &[String]) {
    egui::ComboBox::from_label("image")
        .selected_text(debug_name(c.debug))
        .show_ui(ui, |ui| {
            for v in VIEWS {
                ui.selectable_value(&mut c.debug, v, debug_name(v));
            }
        });
    if c.debug == Some(DebugView::Atlas) {
        let name = |i: usize| object_names.get(i).map_or("?", |n| n.as_str());
        egui::ComboBox::from_label("object")
            .selected_text(name(c.atlas_object))
            .show_ui(ui, |ui| {
                for i in 0..object_names.len() {
                    ui.selectable_value(&mut c.atlas_object, i, name(i));
                }
            });
    }
}

/// The screenshot and keyframe buttons and the status line; returns where the screenshot
/// button landed.
fn footer(ui: &mut egui::Ui, c: &mut Controls, status: &str) -> egui::Rect {
    let shot = ui.button("Screenshot (F12)");
    if shot.clicked() {
        c.screenshot = true;
    }
    if ui
        .button("Add camera keyframe")
        .on_hover_text("printed as a [camera_path] table on exit, keys 2 s apart")
        .clicked()
    {
        c.add_keyframe = true;
    }
    if !status.is_empty() {
        ui.label(status);
    }
    shot.rect
}

/// The projection switch (O) and the orthographic view's height (range from [`limits`]).
fn projection_controls(ui: &mut egui::Ui, c: &mut Controls) {
    use crate::scene::Projection;
    let mut ortho = c.projection == Projection::Orthographic;
    ui.checkbox(&mut ortho, "orthographic (O)")
        .on_hover_text("parallel projection: sizes do not shrink with distance");
    c.projection = match ortho {
        true => Projection::Orthographic,
        false => Projection::Perspective,
    };
    if ortho {
        ui.add(
            egui::Slider::new(
                &mut c.ortho_height_m,
                crate::limits::ORTHO_HEIGHT_M.slider(0.01, 1000.0),
            )
            .logarithmic(true)
            .text("view height m"),
        );
    }
}

/// The post-processing chain in its order (TAA, auto exposure, bloom, tone mapping, FXAA,
/// dither; ranges from [`limits`]). In the viewer every frame is one TAA frame (the
/// headless `--taa-frames` does not apply); TAA, auto exposure, bloom and FXAA switched or
/// changed make a new renderer, tone mapping and dither a new graph. Adds where the TAA
/// checkbox was drawn to `spots` ("post TAA").
fn post_controls(
    ui: &mut egui::Ui,
    p: &mut crate::post::PostSettings,
    tone: &mut ToneMap,
    spots: &mut Vec<Spot>,
) {
    let mut t = PostTable {
        post: *p,
        tonemap: *tone,
        ..Default::default()
    };
    let taa_box = key_checkbox(ui, &mut t, "post.taa", "TAA")
        .on_hover_text("temporal anti-aliasing: each frame jittered, blended with the history");
    spots.push(("post TAA".into(), taa_box.rect));
    if t.post.taa.is_some() {
        key_slider(
            ui,
            &mut t,
            "post.taa_history_weight",
            (0.0, 0.999),
            false,
            "TAA history weight",
        );
        if let Some(taa) = &mut t.post.taa {
            ui.checkbox(&mut taa.motion_vectors, "motion vectors")
                .on_hover_text(
                    "reproject moving objects with their own motion (scenes with animated objects)",
                );
        }
    }
    key_checkbox(ui, &mut t, "post.auto_exposure", "auto exposure");
    if t.post.auto_exposure.is_some() {
        key_slider(ui, &mut t, "post.auto_exposure", (0.01, 1.0), true, "key");
        key_slider(
            ui,
            &mut t,
            "post.exposure_adaptation",
            (0.001, 1.0),
            true,
            "adaptation / frame",
        );
    }
    let mut bloom = t.post.bloom.is_some();
    ui.checkbox(&mut bloom, "bloom");
    // Bloom has no "on" without a strength: the box starts it at 0.1.
    let on = schema::Value::Number(t.post.bloom.unwrap_or(0.1));
    set_key(
        &mut t,
        "post.bloom",
        if bloom { on } else { Value::Bool(false) },
    );
    if bloom {
        key_slider(
            ui,
            &mut t,
            "post.bloom",
            (0.0, 1.0),
            false,
            "bloom strength",
        );
    }
    egui::ComboBox::from_label("tone mapping")
        .selected_text(format!("{:?}", t.tonemap.operator))
        .show_ui(ui, |ui| {
            for op in OPERATORS {
                ui.selectable_value(&mut t.tonemap.operator, op, format!("{op:?}"));
            }
        });
    key_slider(
        ui,
        &mut t,
        "post.exposure",
        (0.001, 1000.0),
        true,
        "exposure",
    );
    key_slider(ui, &mut t, "post.white", (0.01, 100.0), true, "white");
    key_checkbox(ui, &mut t, "post.fxaa", "FXAA");
    key_checkbox(ui, &mut t, "post.dither", "dither");
    (*p, *tone) = (t.post, t.tonemap);
}

/// A scale in eighths as the panel shows it: `1`, `5/8`, `1/2`.
fn scale_name(steps: u32) -> String {
    let d = super::dynres::STEPS;
    match steps {
        s if s >= d => "1".into(),
        s if s % 4 == 0 => format!("{}/{}", s / 4, d / 4),
        s if s % 2 == 0 => format!("{}/{}", s / 2, d / 2),
        s => format!("{s}/{d}"),
    }
}

/// The GI's rays per pixel and whether they accumulate, after the scale in the panel's
/// header (dynamic resolution lowers the rays below the full size): ", 1 GI ray/px,
/// accumulated". Empty for methods that trace no rays per pixel.
fn gi_rays_note(gi: &crate::gi::GiSettings) -> String {
    if !gi.method.spec().sweep_keys.contains(&"gi.rays") {
        return String::new();
    }
    let plural = if gi.rays == 1 { "" } else { "s" };
    let accumulated = if crate::gi::GiPasses::temporal_on(gi) {
        ", accumulated"
    } else {
        ""
    };
    format!(", {} GI ray{plural}/px{accumulated}", gi.rays)
}

/// Dynamic resolution's settings, each the `[post]` key of its label.
fn dynres_controls(ui: &mut egui::Ui, d: &mut crate::scene::DynamicResolution) {
    let mut t = PostTable {
        dynres: *d,
        ..Default::default()
    };
    key_slider(
        ui,
        &mut t,
        "post.frame_budget_ms",
        (0.0, 1000.0),
        true,
        "frame budget (ms, 0 off)",
    );
    key_slider(
        ui,
        &mut t,
        "post.min_scale",
        (0.125, 1.0),
        false,
        "minimum scale",
    );
    key_slider(
        ui,
        &mut t,
        "post.refine_frames",
        (0.0, 600.0),
        false,
        "still frames to refine (0 never)",
    );
    key_checkbox(
        ui,
        &mut t,
        "post.dynamic_gi",
        "1 GI ray per pixel while scaled",
    );
    key_choice(ui, &mut t, "post.upscale", "upscale");
    *d = t.dynres;
}

/// The shadow controls; each is the `[shadow]` key of its label.
fn shadow_controls(ui: &mut egui::Ui, shadow: &mut ShadowSettings) {
    egui::ComboBox::from_label("resolution")
        .selected_text(format!("{}²", shadow.resolution))
        .show_ui(ui, |ui| {
            for r in SHADOW_RESOLUTIONS {
                let chosen = !shadow.auto_resolution && shadow.resolution == r;
                if ui.selectable_label(chosen, format!("{r}²")).clicked() {
                    set_key(shadow, "shadow.resolution", Value::Count(r));
                }
            }
        });
    key_checkbox(ui, shadow, "shadow.cache", "cache shadow and light maps");
    key_slider(
        ui,
        shadow,
        "shadow.direct_samples",
        (1.0, 64.0),
        true,
        "emitter / sky samples",
    );
    key_slider(
        ui,
        shadow,
        "shadow.pcf_radius",
        (0.0, 4.0),
        false,
        "PCF radius",
    );
    key_slider(
        ui,
        shadow,
        "shadow.cascades",
        (1.0, 8.0),
        false,
        "sun cascades",
    );
    key_slider(
        ui,
        shadow,
        "shadow.cascade_lambda",
        (0.0, 1.0),
        false,
        "cascade log/uniform λ",
    );
    key_slider(
        ui,
        shadow,
        "shadow.bias_texels",
        (0.0, 8.0),
        false,
        "bias texels",
    );
    key_slider(
        ui,
        shadow,
        "shadow.slope_bias_texels",
        (0.0, 8.0),
        false,
        "slope bias",
    );
    key_slider(
        ui,
        shadow,
        "shadow.normal_offset_texels",
        (0.0, 8.0),
        false,
        "normal offset",
    );
}

#[cfg(test)]
mod table_tests {
    use super::*;

    /// Pass names as the renderer's graphs name them, the longest ones included, with times
    /// from 0.1 ms to seconds (lavapipe's GI passes).
    const PASSES: [(&str, f64); 10] = [
        ("shadow_depth", 18.546),
        ("gbuffer", 3.25),
        ("voxelize_atlas_attributes", 250.125),
        ("voxelize_attributes_resolve", 1.0),
        ("gi_radiance_volume", 1234.5),
        ("gi_filter[0h]", 4.5),
        ("gi_filter[0v]", 0.125),
        ("deferred_direct", 12.0),
        ("tonemap", 0.75),
        ("egui", 0.25),
    ];

    /// Draws the panel in a headless egui context of the given size, as the viewer does each
    /// frame, then hovers `hover` (a point) if given; returns the layout of the last frame
    /// and the texts drawn in it, each with whether it was elided.
    fn draw_headless(
        size: egui::Vec2,
        hover: Option<egui::Pos2>,
    ) -> (PanelLayout, Vec<(String, bool)>) {
        draw_headless_scrolled(size, hover, 0.0)
    }

    /// [`draw_headless`], with the mouse wheel turned by `scroll_y` points (negative: down)
    /// over the hovered point in the fourth frame.
    fn draw_headless_scrolled(
        size: egui::Vec2,
        hover: Option<egui::Pos2>,
        scroll_y: f32,
    ) -> (PanelLayout, Vec<(String, bool)>) {
        let ctx = egui::Context::default();
        ctx.set_visuals(egui::Visuals::dark());
        let mut stats = TimingStats::new(2);
        let timings: Vec<PassTiming> = PASSES
            .iter()
            .map(|&(n, ms)| PassTiming {
                name: n.into(),
                gpu_ms: ms,
            })
            .collect();
        let mut history = super::super::frame_graph::FrameHistory::new(8);
        for _ in 0..5 {
            history.push(&timings);
        }
        stats.push(timings);
        let mut c = Controls {
            tonemap: ToneMap::default(),
            post: Default::default(),
            shadow: ShadowSettings::default(),
            gi: GiSettings::default(),
            light_scale: vec![1.0],
            speed_m_s: 1.0,
            time_s: 0.0,
            animate: false,
            debug: None,
            atlas_object: 0,
            screenshot: false,
            add_keyframe: false,
            budget_ms: 100.0,
            tune: false,
            dynres: Default::default(),
            stereo: super::super::stereo::StereoControls {
                mode: None,
                rig: Default::default(),
                path: Default::default(),
            },
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
            open: super::super::open::OpenControls::showing("cornell".into()),
        };
        let lights = ["point 0".to_string()];
        let info = PanelInfo {
            device: "llvmpipe (LLVM 15.0.7, 256 bits)",
            extent_px: (size.x as u32, size.y as u32),
            frame_ms: 16.7,
            light_names: &lights,
            object_names: &[],
            status: "",
            gi_frames: None,
            stereo: None,
            history: &history,
            internal: (size.x as u32, size.y as u32),
            scale_steps: 8,
            gi: None,
        };
        let mut layout = PanelLayout::default();
        let mut texts = Vec::new();
        // Panels and grids size themselves from earlier frames: draw a few, as the viewer
        // does, and hover (move, then hold still past the tooltip delay) in the last ones.
        for frame in 0..6 {
            let mut raw = egui::RawInput {
                screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
                time: Some(f64::from(frame)),
                ..Default::default()
            };
            if let (Some(p), 3) = (hover, frame) {
                raw.events.push(egui::Event::PointerMoved(p));
                if scroll_y != 0.0 {
                    raw.events.push(egui::Event::MouseWheel {
                        unit: egui::MouseWheelUnit::Point,
                        delta: egui::vec2(0.0, scroll_y),
                        phase: egui::TouchPhase::Move,
                        source: egui::MouseWheelSource::Unknown,
                        modifiers: egui::Modifiers::NONE,
                    });
                }
            }
            let mut out = ctx.run_ui(raw, |ui| {
                layout = draw(ui, &mut c, &stats, &info, &mut |_| {})
            });
            out.textures_delta.clear();
            texts = out
                .shapes
                .iter()
                .filter_map(|s| match &s.shape {
                    egui::Shape::Text(t) => Some((t.galley.text().to_string(), t.galley.elided)),
                    _ => None,
                })
                .collect();
        }
        (layout, texts)
    }

    /// The panel's contents as scrolled: the panel's width, the scroll area's whole height
    /// (what lies below a short window is reached by scrolling).
    fn contents(l: &PanelLayout) -> egui::Rect {
        let top = l.scroll.view.min.y - l.scroll.offset;
        egui::Rect::from_x_y_ranges(l.panel.x_range(), top..=top + l.scroll.content_height)
    }

    /// What is wrong with the table's geometry: a name overlapping its time, times not
    /// right-aligned to one edge, rows overlapping, a cell outside the panel's contents.
    fn table_faults(l: &PanelLayout) -> Vec<String> {
        let mut faults = Vec::new();
        let right = l.rows.first().map_or(0.0, |(_, _, t)| t.max.x);
        let mut above = f32::NEG_INFINITY;
        for (name, n, t) in &l.rows {
            if n.max.x > t.min.x {
                faults.push(format!("{name}: name {n:?} runs into time {t:?}"));
            }
            // Labels sit at fractional positions; a hundredth of a point is far below a pixel.
            if (t.max.x - right).abs() > 0.01 {
                faults.push(format!("{name}: time ends at x = {}, not {right}", t.max.x));
            }
            if n.min.y.min(t.min.y) < above {
                faults.push(format!("{name}: row overlaps the row above"));
            }
            above = n.max.y.max(t.max.y);
            for (what, r) in [("name", n), ("time", t)] {
                if !contents(l).contains_rect(*r) {
                    faults.push(format!(
                        "{name}: {what} {r:?} outside the panel's contents {:?}",
                        contents(l)
                    ));
                }
            }
        }
        faults
    }

    fn l_contains(panel: &egui::Rect, r: &egui::Rect) -> bool {
        panel.expand(0.01).contains_rect(*r)
    }

    #[test]
    fn timing_table_keeps_names_and_times_apart_at_any_window_size() {
        let mut faults = Vec::new();
        for (w, h) in [
            (1280.0, 720.0),
            (640.0, 480.0),
            (200.0, 480.0),
            (160.0, 420.0),
        ] {
            let (layout, _) = draw_headless(egui::vec2(w, h), None);
            let names: Vec<&str> = layout.rows.iter().map(|(n, ..)| n.as_str()).collect();
            let mut wanted: Vec<&str> = PASSES.iter().map(|(n, _)| *n).collect();
            wanted.push("total");
            assert_eq!(names, wanted, "rows of the table at {w}x{h}");
            faults.extend(
                table_faults(&layout)
                    .iter()
                    .map(|f| format!("{w}x{h}: {f}")),
            );
            // The frame-time graph: inside the panel, all five frames, the heaviest family
            // first and the two gi_filter passes as one.
            let g = &layout.graph;
            match g.rect {
                Some(r) if l_contains(&contents(&layout), &r) => {}
                r => faults.push(format!(
                    "{w}x{h}: graph {r:?} outside {:?}",
                    contents(&layout)
                )),
            }
            assert_eq!(g.frames, 5);
            assert_eq!(
                g.series.first().map(|(n, _)| n.as_str()),
                Some("gi_radiance_volume")
            );
            assert!(g
                .series
                .iter()
                .any(|(n, ms)| n == "gi_filter" && (ms - 4.625).abs() < 1e-4));
            // The tallest frame is the sum of PASSES, 1525.046 ms: the scale's next 1-2-5 step.
            assert_eq!(g.scale_ms, 2000.0);
            // A window narrower than the panel's widgets cuts the panel off: the table must
            // still be in view.
            for (name, n, t) in &layout.rows {
                if n.min.x < 0.0 || t.max.x > w {
                    faults.push(format!("{w}x{h}: {name}: {n:?} or {t:?} off the window"));
                }
            }
        }
        assert!(faults.is_empty(), "{}", faults.join("\n"));
    }

    /// In a window shorter than the panel's contents the panel scrolls: its last control is
    /// below the window at first and in view once the wheel turned far enough down, and the
    /// table (at the top) keeps names and times apart inside the panel.
    #[test]
    fn the_panel_scrolls_to_its_last_control_in_a_short_window() {
        let short = egui::vec2(240.0, 320.0);
        let (top, _) = draw_headless(short, None);
        let s = top.scroll;
        assert!(
            s.content_height > s.view.height() + 100.0,
            "contents {} points high in a {} point view: nothing to scroll",
            s.content_height,
            s.view.height()
        );
        assert!(s.view.min.y >= 0.0 && s.view.max.y <= short.y, "{s:?}");
        assert_eq!(s.offset, 0.0);
        assert!(
            s.screenshot_button.min.y > short.y,
            "the last control {:?} is in view without scrolling",
            s.screenshot_button
        );
        // Far more than the contents' height: the area stops at its bottom.
        let over_panel = Some(top.panel.center());
        let (bottom, _) = draw_headless_scrolled(short, over_panel, -10_000.0);
        let s = bottom.scroll;
        assert!(
            (s.offset - s.max_offset()).abs() < 0.5,
            "scrolled to {} of {}",
            s.offset,
            s.max_offset()
        );
        assert!(
            s.view.contains_rect(s.screenshot_button),
            "the last control {:?} is not in the view {:?} at the bottom",
            s.screenshot_button,
            s.view
        );
        let faults = table_faults(&top);
        assert!(faults.is_empty(), "{}", faults.join("\n"));
    }

    /// egui paints its own warnings into the UI in debug builds (tests included), e.g.
    /// "🔥 First use of widget ID …" / "Second use of …" where two widgets share an Id (two
    /// combo boxes with one label); none may show in the panel. The window is tall enough
    /// for every open section (shapes outside the view are culled).
    #[test]
    fn the_panel_shows_no_egui_warning() {
        let (_, texts) = draw_headless(egui::vec2(640.0, 2400.0), None);
        assert!(
            texts.iter().any(|(t, _)| t == "voxgi"),
            "the panel's heading is not among the texts: {texts:?}"
        );
        let warnings: Vec<&String> = texts
            .iter()
            .map(|(t, _)| t)
            .filter(|t| t.contains('🔥') || t.contains(" use of ") && t.contains(" ID "))
            .collect();
        assert!(warnings.is_empty(), "egui warns in the panel: {warnings:?}");
    }

    /// The panel keeps its 240 points in any window wider than that, whatever its contents
    /// (egui widens a panel to fit what does not wrap; the scene gets the rest).
    #[test]
    fn the_panel_is_240_points_wide() {
        for w in [320.0, 640.0, 1280.0] {
            let (layout, _) = draw_headless(egui::vec2(w, 480.0), None);
            assert_eq!(layout.panel.width(), 240.0, "at a {w} point wide window");
        }
    }

    #[test]
    fn long_pass_names_are_elided_and_shown_in_full_on_hover() {
        let long = "voxelize_attributes_resolve";
        // Tall enough for the whole table in view (its last rows end near 550 points), as
        // shapes outside the view are culled.
        let narrow = egui::vec2(200.0, 640.0);
        let (layout, texts) = draw_headless(narrow, None);
        let drawn =
            |texts: &[(String, bool)], elided| texts.iter().any(|(t, e)| t == long && *e == elided);
        assert!(drawn(&texts, true), "{long} is not elided at 200 points");
        assert!(
            !drawn(&texts, false),
            "{long} is drawn in full at 200 points"
        );
        assert!(
            texts.iter().any(|(t, e)| t == "egui" && !e),
            "a short name is elided"
        );
        let (_, name_rect, _) = layout
            .rows
            .iter()
            .find(|(n, ..)| n == long)
            .expect("the long name's row");
        let (_, hovered) = draw_headless(narrow, Some(name_rect.center()));
        assert!(
            drawn(&hovered, false),
            "hovering the elided {long} shows no tooltip with the full name"
        );
    }
}

/// The "View" combo's entries: the lit image, then every debug view.
const VIEWS: [Option<DebugView>; 11] = [
    None,
    Some(DebugView::Voxels),
    Some(DebugView::Steps),
    Some(DebugView::Level),
    Some(DebugView::Albedo),
    Some(DebugView::Atlas),
    Some(DebugView::GbufferAlbedo),
    Some(DebugView::GbufferNormal),
    Some(DebugView::GbufferDistance),
    Some(DebugView::ShadowTexels),
    Some(DebugView::ShadowTexelsPerspective),
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
        Some(DebugView::GbufferAlbedo) => "G-buffer albedo",
        Some(DebugView::GbufferNormal) => "G-buffer normal",
        Some(DebugView::GbufferDistance) => "G-buffer distance",
        Some(DebugView::ShadowTexels) => "shadow texels",
        Some(DebugView::ShadowTexelsPerspective) => "shadow texels, perspective part",
    }
}

/// "Best within budget": the most accurate GI configuration of the scene's sweep whose GPU
/// time to the image fits the budget (`voxgi tune`; the sweep folder is `voxgi view --sweep`).
fn budget_controls(ui: &mut egui::Ui, c: &mut Controls) {
    ui.horizontal(|ui| {
        ui.add(
            egui::DragValue::new(&mut c.budget_ms)
                .range(0.1..=1.0e6)
                .suffix(" ms"),
        );
        if ui.button("Best within budget").clicked() {
            c.tune = true;
        }
    });
}

/// The GI method, its own section ([`crate::gi::MethodSpec::panel`]) and the parameters the
/// methods share, each the `[gi]` key of its label; without indirect light, only the method's
/// section.
fn gi_controls(ui: &mut egui::Ui, gi: &mut GiSettings, frames: Option<u32>) {
    key_choice(ui, gi, "gi.method", "method");
    (gi.method.spec().panel)(ui, gi, frames);
    if gi.method == GiMethod::None {
        return;
    }
    let limited = (Value::Number(1.0), Value::Unset);
    if key_switch(ui, gi, "gi.radius_m", "limit ray length", limited) {
        key_slider(ui, gi, "gi.radius_m", (0.01, 100.0), true, "radius m");
    }
    key_choice(ui, gi, "gi.filter", "filter");
    key_slider(
        ui,
        gi,
        "gi.filter_radius",
        (0.0, 16.0),
        false,
        "filter radius",
    );
    key_slider(
        ui,
        gi,
        "gi.filter_passes",
        (0.0, 8.0),
        false,
        "filter passes",
    );
    key_slider(
        ui,
        gi,
        "gi.normal_offset_voxels",
        (0.0, 4.0),
        false,
        "normal offset k1",
    );
    key_slider(
        ui,
        gi,
        "gi.ray_offset_voxels",
        (0.0, 2.0),
        false,
        "ray offset k2",
    );
    key_slider(ui, gi, "gi.start_level", (0.0, 8.0), false, "start level");
    key_slider(
        ui,
        gi,
        "gi.max_iterations",
        (16.0, 4096.0),
        true,
        "max iterations",
    );
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
}
