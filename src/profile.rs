//! Per-pass GPU timing statistics over many frames (median, min, max), as a table and JSON.

use crate::stats::median;
use crate::vk::PassTiming;
use serde::Serialize;

/// Statistics of one pass over the measured frames.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassStats {
    pub name: String,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub samples: usize,
}

/// A one-time pass run before the first frame, outside the frame graph (atlas building,
/// static voxelization); runs of the same pass (one per atlas) are summed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SetupStats {
    pub name: String,
    pub total_ms: f64,
    pub runs: usize,
}

/// A profiling run: per-pass statistics, in execution order, plus the frame sum, and the
/// one-time setup passes apart from them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileReport {
    pub device: String,
    pub frames: usize,
    pub warmup_frames: usize,
    pub passes: Vec<PassStats>,
    /// Median over frames of the sum of all pass times.
    pub frame_median_ms: f64,
    /// One-time passes before the first frame, in order of first run; not in the frame sum.
    pub setup: Vec<SetupStats>,
    /// Free-form facts about the run (resolution, transient memory, culled passes...).
    pub notes: Vec<(String, String)>,
}

impl ProfileReport {
    /// Aggregates per-frame timings (each frame a list in execution order), keeping the order
    /// in which pass names first appear.
    pub fn from_frames(device: &str, frames: &[Vec<PassTiming>], warmup_frames: usize) -> Self {
        let mut names: Vec<String> = Vec::new();
        for f in frames {
            for t in f {
                if !names.contains(&t.name) {
                    names.push(t.name.clone());
                }
            }
        }
        let passes = names
            .iter()
            .map(|name| {
                let samples: Vec<f64> = frames
                    .iter()
                    .flat_map(|f| f.iter().filter(|t| &t.name == name).map(|t| t.gpu_ms))
                    .collect();
                PassStats {
                    name: name.clone(),
                    median_ms: median(&samples),
                    min_ms: samples.iter().copied().fold(f64::INFINITY, f64::min),
                    max_ms: samples.iter().copied().fold(0.0, f64::max),
                    samples: samples.len(),
                }
            })
            .collect();
        let totals: Vec<f64> = frames
            .iter()
            .map(|f| f.iter().map(|t| t.gpu_ms).sum())
            .collect();
        Self {
            device: device.to_owned(),
            frames: frames.len(),
            warmup_frames,
            passes,
            frame_median_ms: median(&totals),
            setup: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// Adds the one-time passes (`timings` in execution order), summing repeated names.
    pub fn with_setup(mut self, timings: &[PassTiming]) -> Self {
        for t in timings {
            match self.setup.iter_mut().find(|s| s.name == t.name) {
                Some(s) => {
                    s.total_ms += t.gpu_ms;
                    s.runs += 1;
                }
                None => self.setup.push(SetupStats {
                    name: t.name.clone(),
                    total_ms: t.gpu_ms,
                    runs: 1,
                }),
            }
        }
        self
    }

    /// A fixed-width table for terminals.
    pub fn table(&self) -> String {
        let width = self
            .passes
            .iter()
            .map(|p| p.name.len())
            .chain(self.setup.iter().map(|p| p.name.len()))
            .max()
            .unwrap_or(4)
            .max(11);
        let mut s = format!(
            "GPU time per pass on {} ({} frames after {} warm-up)\n",
            self.device, self.frames, self.warmup_frames
        );
        s += &format!(
            "{:<width$}  {:>10}  {:>10}  {:>10}\n",
            "pass", "median ms", "min ms", "max ms"
        );
        for p in &self.passes {
            s += &format!(
                "{:<width$}  {:>10.4}  {:>10.4}  {:>10.4}\n",
                p.name, p.median_ms, p.min_ms, p.max_ms
            );
        }
        s += &format!("{:<width$}  {:>10.4}\n", "frame", self.frame_median_ms);
        if !self.setup.is_empty() {
            s += "\nsetup (once, before the first frame; not in the frame sum)\n";
            s += &format!("{:<width$}  {:>10}  {:>10}\n", "pass", "total ms", "runs");
            for p in &self.setup {
                s += &format!("{:<width$}  {:>10.4}  {:>10}\n", p.name, p.total_ms, p.runs);
            }
            let total: f64 = self.setup.iter().map(|p| p.total_ms).sum();
            s += &format!("{:<width$}  {:>10.4}\n\n", "setup total", total);
        }
        for (k, v) in &self.notes {
            s += &format!("{k}: {v}\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(name: &str, ms: f64) -> PassTiming {
        PassTiming {
            name: name.into(),
            gpu_ms: ms,
        }
    }

    #[test]
    fn report_aggregates_per_pass_in_order() {
        let frames = vec![
            vec![t("a", 1.0), t("b", 10.0)],
            vec![t("a", 3.0), t("b", 30.0)],
            vec![t("a", 2.0), t("b", 20.0)],
        ];
        let r = ProfileReport::from_frames("dev", &frames, 2);
        assert_eq!(r.passes.len(), 2);
        assert_eq!(r.passes[0].name, "a");
        assert_eq!(
            (
                r.passes[0].median_ms,
                r.passes[0].min_ms,
                r.passes[0].max_ms
            ),
            (2.0, 1.0, 3.0)
        );
        assert_eq!(r.passes[1].median_ms, 20.0);
        assert_eq!(r.frame_median_ms, 22.0);
        let table = r.table();
        assert!(table.contains("a") && table.contains("20.0000"));
        let json = serde_json::to_string(&r).expect("serializes");
        assert!(json.contains("\"median_ms\":2.0"));
        assert!(
            !table.contains("setup"),
            "no setup section without setup passes"
        );
    }

    #[test]
    fn setup_passes_are_listed_apart_from_the_frame() {
        let frames = vec![vec![t("a", 1.0)], vec![t("a", 3.0)]];
        let setup = [
            t("atlas_positions", 4.0),
            t("atlas_points", 1.0),
            t("atlas_positions", 2.0),
            t("voxel_store", 0.5),
        ];
        let r = ProfileReport::from_frames("dev", &frames, 0).with_setup(&setup);
        // Two atlases: one row each pass, runs summed, first-run order.
        let names: Vec<&str> = r.setup.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["atlas_positions", "atlas_points", "voxel_store"]);
        assert_eq!((r.setup[0].total_ms, r.setup[0].runs), (6.0, 2));
        assert_eq!(r.frame_median_ms, 2.0, "setup is not in the frame sum");
        assert_eq!(r.passes.len(), 1);
        let table = r.table();
        let lines: Vec<&str> = table.lines().collect();
        let frame = lines
            .iter()
            .position(|l| l.starts_with("frame"))
            .expect("frame line");
        let header = lines
            .iter()
            .position(|l| l.starts_with("setup (once"))
            .expect("setup section");
        assert!(
            header > frame,
            "the setup section follows the frame passes:\n{table}"
        );
        let row = |name: &str| lines.iter().position(|l| l.starts_with(name));
        for name in names {
            assert!(
                row(name).is_some_and(|i| i > header),
                "{name} under setup:\n{table}"
            );
        }
        assert!(lines[row("atlas_positions").unwrap_or(0)].contains("6.0000"));
        let total = lines
            .iter()
            .find(|l| l.starts_with("setup total"))
            .expect("total");
        assert!(total.contains("7.5000"), "{total}");
        let json = serde_json::to_string(&r).expect("serializes");
        assert!(
            json.contains("\"setup\":[{\"name\":\"atlas_positions\""),
            "{json}"
        );
    }
}
