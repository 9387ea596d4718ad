//! Per-pass GPU timing statistics over many frames (median, min, max), as a table and JSON.

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

/// A profiling run: per-pass statistics, in execution order, plus the frame sum.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileReport {
    pub device: String,
    pub frames: usize,
    pub warmup_frames: usize,
    pub passes: Vec<PassStats>,
    /// Median over frames of the sum of all pass times.
    pub frame_median_ms: f64,
    /// Free-form facts about the run (resolution, transient memory, culled passes...).
    pub notes: Vec<(String, String)>,
}

/// Median of a sample set (mean of the two middle values for even counts); 0 when empty.
pub fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
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
            notes: Vec::new(),
        }
    }

    /// A fixed-width table for terminals.
    pub fn table(&self) -> String {
        let width = self
            .passes
            .iter()
            .map(|p| p.name.len())
            .max()
            .unwrap_or(4)
            .max(5);
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
    fn median_of_odd_and_even_sets() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[]), 0.0);
        assert_eq!(median(&[f64::NAN, 1.0]), 1.0);
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
    }
}
