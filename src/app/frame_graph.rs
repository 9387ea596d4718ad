//! The panel's frame-time graph: per pass family, the GPU time of each of the last frames as
//! stacked areas (the heaviest families coloured and named, the rest grouped as "other"),
//! drawn with egui's painter from the timings the viewer reads back for the table.
//!
//! [`FrameHistory`] is the bookkeeping (a bounded ring of frames; plain data, unit-tested);
//! [`draw`] paints it.

use crate::vk::PassTiming;
use std::collections::{HashMap, VecDeque};

/// Frames the graph spans: about 5 s at 60 frames per second (longer where frames are slower).
pub const HISTORY_FRAMES: usize = 300;
/// Families drawn in their own colour; the rest are summed into "other".
pub const NAMED_SERIES: usize = 6;
/// The grouped rest's name.
pub const OTHER: &str = "other";

/// The family a pass belongs to: its name before the first `[` (`bloom_down[3]` and
/// `ssgi_gather[0]` group with their siblings, `sao_blur[h]` with `sao_blur[v]`, a right
/// eye's `gbuffer [R]` with the left eye's), trimmed.
pub fn family(pass: &str) -> &str {
    pass.split('[').next().unwrap_or(pass).trim_end()
}

/// Per-family GPU times of the last [`HISTORY_FRAMES`] frames, oldest first.
#[derive(Debug)]
pub struct FrameHistory {
    /// Per frame: (family, ms) in the frame's order, each family once.
    frames: VecDeque<Vec<(String, f32)>>,
    capacity: usize,
}

/// What [`draw`] paints: per series (name, ms per frame, oldest first), heaviest first, then
/// "other" when any pass is grouped; per frame the series sum to the frame's total.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stacked {
    pub series: Vec<(String, Vec<f32>)>,
    /// Sum over every pass, per frame.
    pub totals: Vec<f32>,
}

impl FrameHistory {
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            frames: VecDeque::with_capacity(capacity),
            capacity,
        }
    }

    /// Adds one finished frame's timings, dropping the oldest frame when full (frames without
    /// timings, e.g. the first after a new graph, are skipped).
    pub fn push(&mut self, frame: &[PassTiming]) {
        if frame.is_empty() {
            return;
        }
        let mut families: Vec<(String, f32)> = Vec::new();
        for t in frame {
            let f = family(&t.name);
            match families.iter_mut().find(|(n, _)| n == f) {
                Some((_, ms)) => *ms += t.gpu_ms as f32,
                None => families.push((f.to_owned(), t.gpu_ms as f32)),
            }
        }
        if self.frames.len() == self.capacity {
            self.frames.pop_front();
        }
        self.frames.push_back(families);
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The stacked series: the `named` families with the largest mean over the window (a
    /// family that ran in only some frames counts 0 in the others), heaviest first, then
    /// "other", the sum of the rest, when there is a rest. Families no frame in the window
    /// ran are gone: after a GI switch the old method's passes leave the graph as its frames
    /// age out.
    pub fn stacked(&self, named: usize) -> Stacked {
        let mut sums: HashMap<&str, f32> = HashMap::new();
        let mut order: Vec<&str> = Vec::new();
        for frame in &self.frames {
            for (name, ms) in frame {
                let sum = sums.entry(name.as_str()).or_insert_with(|| {
                    order.push(name.as_str());
                    0.0
                });
                *sum += ms;
            }
        }
        // Heaviest first; ties keep the order of first appearance (a stable sort).
        order.sort_by(|a, b| sums[b].total_cmp(&sums[a]));
        let (top, rest) = order.split_at(order.len().min(named));
        let totals: Vec<f32> = self
            .frames
            .iter()
            .map(|f| f.iter().map(|(_, ms)| ms).sum())
            .collect();
        let mut series: Vec<(String, Vec<f32>)> = top
            .iter()
            .map(|&name| {
                let values = self
                    .frames
                    .iter()
                    .map(|f| f.iter().find(|(n, _)| n == name).map_or(0.0, |(_, ms)| *ms))
                    .collect();
                (name.to_owned(), values)
            })
            .collect();
        if !rest.is_empty() {
            let values = self
                .frames
                .iter()
                .map(|f| {
                    f.iter()
                        .filter(|(n, _)| rest.contains(&n.as_str()))
                        .map(|(_, ms)| ms)
                        .sum()
                })
                .collect();
            series.push((OTHER.to_owned(), values));
        }
        Stacked { series, totals }
    }
}

/// A colour per family that does not change when the ranking does: the hue from a hash of the
/// name (FNV-1a) spaced by the golden angle; "other" is grey.
pub fn series_color(name: &str) -> egui::Color32 {
    if name == OTHER {
        return egui::Color32::from_gray(120);
    }
    let hash = name.bytes().fold(0x811c_9dc5u32, |h, b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    });
    let hue = (hash % 97) as f32 * 0.618_034 % 1.0;
    egui::ecolor::Hsva::new(hue, 0.65, 0.85, 1.0).into()
}

/// The smallest of 1, 2, 5 × 10^k ms at or above `ms`: the graph's top line.
pub fn nice_ceiling(ms: f32) -> f32 {
    if ms.is_nan() || ms <= 0.0 || ms.is_infinite() {
        return 1.0;
    }
    let decade = 10f32.powf(ms.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&v| v >= ms * (1.0 - 1e-6))
        .unwrap_or(10.0 * decade)
}

/// Where the graph landed and what it showed, for the scripted runs' layout dump.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GraphLayout {
    pub rect: Option<egui::Rect>,
    /// The series drawn, heaviest first, with their mean ms over the window.
    pub series: Vec<(String, f32)>,
    pub frames: usize,
    /// The top line's value, ms.
    pub scale_ms: f32,
}

/// Paints the stacked graph `width` points wide (newest frame at the right edge), its scale
/// and a legend with each series' mean.
pub fn draw(ui: &mut egui::Ui, history: &FrameHistory, width: f32) -> GraphLayout {
    if history.is_empty() {
        ui.weak("no GPU timings yet");
        return GraphLayout::default();
    }
    let stacked = history.stacked(NAMED_SERIES);
    let n = history.len();
    let peak = stacked.totals.iter().copied().fold(0.0f32, f32::max);
    let scale_ms = nice_ceiling(peak);
    let size = egui::vec2(width.max(1.0), 72.0);
    let (rect, _) = ui.allocate_exact_size(size, egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, ui.visuals().extreme_bg_color);
    // One column per frame slot of the full window, so the graph does not stretch while it
    // fills; the newest frame at the right.
    let column = rect.width() / history.capacity as f32;
    let y_of = |ms: f32| rect.bottom() - (ms / scale_ms).clamp(0.0, 1.0) * rect.height();
    for i in 0..n {
        let x1 = rect.right() - (n - 1 - i) as f32 * column;
        let x0 = x1 - column;
        let mut base = 0.0;
        for (name, values) in &stacked.series {
            let top = base + values[i];
            if values[i] > 0.0 {
                let r = egui::Rect::from_x_y_ranges(x0..=x1, y_of(top)..=y_of(base));
                painter.rect_filled(r, 0.0, series_color(name));
            }
            base = top;
        }
    }
    let text = ui.visuals().text_color();
    let font = egui::TextStyle::Small.resolve(ui.style());
    painter.text(
        rect.left_top() + egui::vec2(2.0, 1.0),
        egui::Align2::LEFT_TOP,
        format!("{scale_ms} ms"),
        font,
        text,
    );
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len().max(1) as f32;
    let series: Vec<(String, f32)> = stacked
        .series
        .iter()
        .map(|(name, v)| (name.clone(), mean(v)))
        .collect();
    for (name, ms) in &series {
        ui.horizontal(|ui| {
            let (swatch, _) = ui.allocate_exact_size(egui::vec2(10.0, 10.0), egui::Sense::hover());
            ui.painter().rect_filled(swatch, 1.0, series_color(name));
            ui.label(egui::RichText::new(format!("{name} {ms:.2}")).small());
        });
    }
    GraphLayout {
        rect: Some(rect),
        series,
        frames: n,
        scale_ms,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(values: &[(&str, f64)]) -> Vec<PassTiming> {
        values
            .iter()
            .map(|&(name, gpu_ms)| PassTiming {
                name: name.into(),
                gpu_ms,
            })
            .collect()
    }

    #[test]
    fn the_history_is_bounded_and_keeps_the_newest_frames() {
        let mut h = FrameHistory::new(4);
        for i in 0..10 {
            h.push(&frame(&[("gbuffer", f64::from(i))]));
            assert_eq!(h.len(), (i as usize + 1).min(4));
        }
        // Empty frames (no timings read back) are not frames.
        h.push(&[]);
        assert_eq!(h.len(), 4);
        let s = h.stacked(NAMED_SERIES);
        assert_eq!(s.series, vec![("gbuffer".into(), vec![6.0, 7.0, 8.0, 9.0])]);
    }

    #[test]
    fn stacked_series_sum_to_the_frame_totals() {
        let mut h = FrameHistory::new(8);
        let passes = [
            "shadow_depth",
            "gbuffer",
            "deferred_direct",
            "bloom_down[1]",
            "bloom_down[2]",
            "gi_hemisphere",
            "gi_filter[h]",
            "gi_filter[v]",
            "tonemap",
            "egui",
        ];
        for f in 0..8 {
            let values: Vec<(&str, f64)> = passes
                .iter()
                .enumerate()
                .map(|(i, &p)| (p, 0.125 * ((i * 7 + f * 3) % 11) as f64))
                .collect();
            h.push(&frame(&values));
        }
        for named in [0, 1, 3, NAMED_SERIES, 20] {
            let s = h.stacked(named);
            // Ten passes in eight families: bloom_down[*] and gi_filter[*] are one each.
            let families = 8;
            assert_eq!(
                s.series.len(),
                named.min(families) + usize::from(named < families)
            );
            for (i, total) in s.totals.iter().enumerate() {
                let sum: f32 = s.series.iter().map(|(_, v)| v[i]).sum();
                assert!((sum - total).abs() < 1e-5, "{named} named, frame {i}");
            }
            // Heaviest first (by the window's sum), "other" last.
            let sums: Vec<f32> = s.series.iter().map(|(_, v)| v.iter().sum()).collect();
            let named_sums = &sums[..named.min(families)];
            assert!(named_sums.windows(2).all(|w| w[0] >= w[1]), "{sums:?}");
            if named < families {
                assert_eq!(s.series.last().map(|(n, _)| n.as_str()), Some(OTHER));
            }
        }
        // The totals are the frames' sums of every pass.
        let s = h.stacked(2);
        let first: f32 = passes
            .iter()
            .enumerate()
            .map(|(i, _)| 0.125 * ((i * 7) % 11) as f32)
            .sum();
        assert!((s.totals[0] - first).abs() < 1e-5);
    }

    #[test]
    fn passes_appear_and_leave_with_a_gi_switch() {
        let mut h = FrameHistory::new(3);
        let vpl = frame(&[("gbuffer", 1.0), ("gi_vpl_gather", 5.0)]);
        let path = frame(&[("gbuffer", 1.0), ("gi_pathtrace", 2.0)]);
        for _ in 0..3 {
            h.push(&vpl);
        }
        h.push(&path);
        let s = h.stacked(NAMED_SERIES);
        let names: Vec<&str> = s.series.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["gi_vpl_gather", "gbuffer", "gi_pathtrace"]);
        // The frames without a pass show 0 for it, the others its time.
        assert_eq!(s.series[0].1, [5.0, 5.0, 0.0]);
        assert_eq!(s.series[2].1, [0.0, 0.0, 2.0]);
        assert_eq!(s.totals, [6.0, 6.0, 3.0]);
        // Once the window holds only the new method's frames, the old passes are gone.
        h.push(&path);
        h.push(&path);
        let names: Vec<String> = h
            .stacked(NAMED_SERIES)
            .series
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(names, ["gi_pathtrace", "gbuffer"]);
    }

    #[test]
    fn families_group_indexed_passes_and_eyes() {
        assert_eq!(family("bloom_down[3]"), "bloom_down");
        assert_eq!(family("sao_blur[h]"), "sao_blur");
        assert_eq!(family("gbuffer [R]"), "gbuffer");
        assert_eq!(family("tonemap"), "tonemap");
    }

    #[test]
    fn the_scale_is_one_two_or_five_times_a_power_of_ten() {
        for (ms, top) in [
            (0.7, 1.0),
            (1.0, 1.0),
            (1.01, 2.0),
            (3.2, 5.0),
            (16.7, 20.0),
            (51.0, 100.0),
            (0.0, 1.0),
        ] {
            assert!(
                (nice_ceiling(ms) - top).abs() < 1e-4,
                "{ms}: {}",
                nice_ceiling(ms)
            );
        }
        assert_eq!(nice_ceiling(f32::NAN), 1.0);
    }

    #[test]
    fn colours_are_stable_and_other_is_grey() {
        assert_eq!(series_color("gbuffer"), series_color("gbuffer"));
        assert_ne!(series_color("gbuffer"), series_color("tonemap"));
        assert_eq!(series_color(OTHER), egui::Color32::from_gray(120));
    }
}
