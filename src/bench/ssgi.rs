//! The screen-space GI's scalability table (`voxgi bench ssgi`), after Oetke 2017 §6.4
//! (Fig. 4.8): every combination of the depth/normal mip filter (fast, voting), the GI
//! resolution (full, half, quarter, eighth) and the samples per texel and level, each with the
//! GPU time of every `ssgi_*` stage and of the whole frame (median, min and max over the
//! profiled frames, as `voxgi profile` measures them) and the error of its image against the
//! scene's reference (relMSE, FLIP).
//!
//! A stage is a pass family: `ssgi_mip[1]`, `ssgi_mip[2]`, … are summed per frame into
//! `ssgi_mip` before the statistics are taken, and `ssgi` is the sum of all of them (the
//! thesis's "GI" column; its "MIP" column is `ssgi_mip`). Times are never compared in tests:
//! the report prints them side by side from one run.

use super::BenchError;
use crate::eval::HdrImage;
use crate::gi::{GiMethod, SsgiMips, SsgiResolution};
use crate::render::{profile_scene, render_image, RenderSettings};
use crate::scene::Scene;
use crate::stats::median;
use crate::vk::{Context, PassTiming};
use clap::ValueEnum;
use serde::Serialize;

/// What `voxgi bench ssgi` measures.
#[derive(Clone, Debug)]
pub struct SsgiBenchDesc {
    pub mips: Vec<SsgiMips>,
    pub resolutions: Vec<SsgiResolution>,
    /// Samples per texel and level.
    pub samples: Vec<u32>,
    /// Image width and height in pixels.
    pub size: u32,
    /// Profiled frames per configuration (after `warmup`).
    pub frames: usize,
    pub warmup: usize,
    /// Frames the scored image runs (feedback bounces and the temporal blend settle over
    /// them; `--gi-frames`).
    pub gi_frames: u32,
}

impl Default for SsgiBenchDesc {
    /// The thesis's grid (Fig. 4.8: fast/voting × resolution × 16–256 samples) at 128².
    fn default() -> Self {
        Self {
            mips: vec![SsgiMips::Fast, SsgiMips::Voting],
            resolutions: vec![
                SsgiResolution::Full,
                SsgiResolution::Half,
                SsgiResolution::Quarter,
                SsgiResolution::Eighth,
            ],
            samples: vec![16, 32, 64, 128, 256],
            size: 128,
            frames: 20,
            warmup: 3,
            gi_frames: 8,
        }
    }
}

/// Median, min and max of a per-frame time, ms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Span {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

impl Span {
    /// The statistics of per-frame sums (`sums` not empty).
    fn of(sums: &[f64]) -> Span {
        Span {
            median_ms: median(sums),
            min_ms: sums.iter().copied().fold(f64::INFINITY, f64::min),
            max_ms: sums.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// One stage (pass family) of a configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageTime {
    /// The pass name without its `[k]` index, e.g. `ssgi_gather`.
    pub stage: String,
    #[serde(flatten)]
    pub time: Span,
}

/// One configuration: its settings, times and errors.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SsgiBenchRow {
    /// 1-based, in the table's order.
    pub number: usize,
    pub mips: String,
    pub resolution: String,
    pub samples: u32,
    /// The `ssgi_*` stages in execution order.
    pub stages: Vec<StageTime>,
    /// All `ssgi_*` passes of a frame.
    pub ssgi: Span,
    /// The whole frame (every pass).
    pub frame: Span,
    pub rel_mse: f64,
    pub flip: f64,
}

/// The report of `voxgi bench ssgi`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SsgiBenchReport {
    pub device: String,
    pub scene: String,
    pub size: u32,
    pub frames: usize,
    pub warmup: usize,
    pub gi_frames: u32,
    /// The error of direct light alone against the same reference, for scale.
    pub direct_rel_mse: f64,
    pub direct_flip: f64,
    pub rows: Vec<SsgiBenchRow>,
}

/// A value enum's name as its flag spells it.
fn name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |p| p.get_name().to_owned())
}

/// The stage a pass belongs to (`ssgi_mip[2]` → `ssgi_mip`), `None` for non-ssgi passes.
fn stage_of(pass: &str) -> Option<&str> {
    pass.starts_with("ssgi_")
        .then(|| pass.split('[').next().unwrap_or(pass))
}

/// Per-stage, ssgi and frame statistics of profiled frames (each a list of pass timings).
fn stage_times(frames: &[Vec<PassTiming>]) -> (Vec<StageTime>, Span, Span) {
    let mut names: Vec<String> = Vec::new();
    for t in frames.iter().flatten() {
        if let Some(s) = stage_of(&t.name) {
            if !names.iter().any(|n| n == s) {
                names.push(s.to_owned());
            }
        }
    }
    let sums = |keep: &dyn Fn(&str) -> bool| -> Vec<f64> {
        frames
            .iter()
            .map(|f| {
                f.iter()
                    .filter(|t| keep(&t.name))
                    .map(|t| t.gpu_ms)
                    .sum::<f64>()
                    + 0.0
            })
            .collect()
    };
    let stages = names
        .iter()
        .map(|n| StageTime {
            stage: n.clone(),
            time: Span::of(&sums(&|p| stage_of(p) == Some(n.as_str()))),
        })
        .collect();
    let ssgi = Span::of(&sums(&|p| stage_of(p).is_some()));
    let frame = Span::of(&sums(&|_| true));
    (stages, ssgi, frame)
}

/// The reference `<name>_gi.exr` in `dir`, box-filtered to `size`² (`size` must divide its
/// square size).
pub fn load_reference(
    dir: &std::path::Path,
    name: &str,
    size: u32,
) -> Result<HdrImage, BenchError> {
    let path = crate::assets::find(&dir.join(format!("{name}_gi.exr")));
    if !path.exists() {
        return Err(BenchError::NoReference { path });
    }
    let full = HdrImage::load(&path)?;
    if size == 0 || full.width != full.height || full.width % size != 0 {
        return Err(BenchError::ReferenceSize {
            size,
            width: full.width,
            height: full.height,
            path,
        });
    }
    Ok(super::sweep::downsample(&full, full.width / size))
}

/// Runs the grid on `scene` (whose `[gi]` table gives the settings the grid leaves alone)
/// and scores each image against `reference` (already at `desc.size`).
pub fn bench_ssgi(
    ctx: &Context,
    scene: &Scene,
    scene_name: &str,
    reference: &HdrImage,
    desc: &SsgiBenchDesc,
) -> Result<SsgiBenchReport, BenchError> {
    let base = crate::scene::resolve_gi(&scene.gi, &Default::default());
    let settings = |gi: crate::gi::GiSettings| RenderSettings {
        width: desc.size,
        height: desc.size,
        gi,
        ..Default::default()
    };
    let direct = render_image(
        ctx,
        scene,
        &settings(crate::gi::GiSettings {
            method: GiMethod::None,
            sao: None,
            ..base
        }),
    )?;
    let direct = crate::eval::compare(reference, &direct.hdr, None)?;
    let mut rows = Vec::new();
    for &mips in &desc.mips {
        for &resolution in &desc.resolutions {
            for &samples in &desc.samples {
                let s = settings(crate::gi::GiSettings {
                    method: GiMethod::Ssgi,
                    accumulate_frames: desc.gi_frames,
                    ssgi: crate::gi::SsgiSettings {
                        mips,
                        resolution,
                        samples,
                        ..base.ssgi
                    },
                    ..base
                });
                crate::render::check_render_settings(&s)?;
                let run = profile_scene(ctx, scene, &s, desc.frames.max(1), desc.warmup)?;
                let image = render_image(ctx, scene, &s)?;
                let m = crate::eval::compare(reference, &image.hdr, None)?;
                let (stages, ssgi, frame) = stage_times(&run.frames);
                rows.push(SsgiBenchRow {
                    number: rows.len() + 1,
                    mips: name(&mips),
                    resolution: name(&resolution),
                    samples,
                    stages,
                    ssgi,
                    frame,
                    rel_mse: m.rel_mse,
                    flip: m.flip_mean,
                });
            }
        }
    }
    Ok(SsgiBenchReport {
        device: ctx.info.name.clone(),
        scene: scene_name.to_owned(),
        size: desc.size,
        frames: desc.frames.max(1),
        warmup: desc.warmup,
        gi_frames: desc.gi_frames,
        direct_rel_mse: direct.rel_mse,
        direct_flip: direct.flip_mean,
        rows,
    })
}

impl SsgiBenchReport {
    /// The stages of all rows, in first-seen order (a scene with glossy materials adds the
    /// reflection passes).
    fn stage_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for s in self.rows.iter().flat_map(|r| &r.stages) {
            if !names.contains(&s.stage) {
                names.push(s.stage.clone());
            }
        }
        names
    }

    fn stage_median(row: &SsgiBenchRow, stage: &str) -> Option<f64> {
        row.stages
            .iter()
            .find(|s| s.stage == stage)
            .map(|s| s.time.median_ms)
    }

    /// The table: a row per configuration, the median ms of each stage, the ssgi and frame
    /// medians with their [min, max], and the errors.
    pub fn table(&self) -> String {
        let stages = self.stage_names();
        let mut s = format!(
            "Screen-space GI scalability (Oetke 2017 Fig. 4.8) on {}: {}, {}², GPU ms per frame \
             (median of {} frames after {} warm-up; [min, max]), error of the image after {} \
             frames against the reference (direct light alone: relMSE {:.4}, FLIP {:.4})\n",
            self.device,
            self.scene,
            self.size,
            self.frames,
            self.warmup,
            self.gi_frames,
            self.direct_rel_mse,
            self.direct_flip
        );
        s += &format!("{:>3} {:<7} {:<8} {:>7}", "#", "mips", "res", "samples");
        for st in &stages {
            s += &format!(" {:>14}", st);
        }
        s += &format!(
            " {:>26} {:>26} {:>8} {:>7}\n",
            "ssgi ms", "frame ms", "relMSE", "FLIP"
        );
        for r in &self.rows {
            s += &format!(
                "{:>3} {:<7} {:<8} {:>7}",
                r.number, r.mips, r.resolution, r.samples
            );
            for st in &stages {
                match Self::stage_median(r, st) {
                    Some(v) => s += &format!(" {v:>14.3}"),
                    None => s += &format!(" {:>14}", "-"),
                }
            }
            let span = |t: &Span| format!("{:.2} [{:.2}, {:.2}]", t.median_ms, t.min_ms, t.max_ms);
            s += &format!(
                " {:>26} {:>26} {:>8.4} {:>7.4}\n",
                span(&r.ssgi),
                span(&r.frame),
                r.rel_mse,
                r.flip
            );
        }
        s
    }

    /// One CSV line per configuration: settings, each stage's and the ssgi and frame
    /// median/min/max, the errors.
    pub fn csv(&self) -> String {
        let stages = self.stage_names();
        let mut s = String::from("number,scene,size,mips,resolution,samples");
        for st in stages.iter().map(String::as_str).chain(["ssgi", "frame"]) {
            s += &format!(",{st}_median_ms,{st}_min_ms,{st}_max_ms");
        }
        s += ",rel_mse,flip,device\n";
        for r in &self.rows {
            s += &format!(
                "{},{},{},{},{},{}",
                r.number, self.scene, self.size, r.mips, r.resolution, r.samples
            );
            let spans = stages
                .iter()
                .map(|st| r.stages.iter().find(|x| &x.stage == st).map(|x| x.time))
                .chain([Some(r.ssgi), Some(r.frame)]);
            for t in spans {
                match t {
                    Some(t) => s += &format!(",{},{},{}", t.median_ms, t.min_ms, t.max_ms),
                    None => s += ",,,",
                }
            }
            s += &format!(
                ",{},{},{}\n",
                r.rel_mse,
                r.flip,
                self.device.replace(',', ";")
            );
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
    fn stages_sum_their_levels_per_frame_and_leave_other_passes_out() {
        let frames = vec![
            vec![
                t("gbuffer", 5.0),
                t("ssgi_input", 1.0),
                t("ssgi_mip[1]", 2.0),
                t("ssgi_mip[2]", 1.0),
                t("ssgi_gather[2]", 4.0),
                t("ssgi_gather[1]", 6.0),
                t("tonemap", 1.0),
            ],
            vec![
                t("gbuffer", 7.0),
                t("ssgi_input", 3.0),
                t("ssgi_mip[1]", 1.0),
                t("ssgi_mip[2]", 1.0),
                t("ssgi_gather[2]", 2.0),
                t("ssgi_gather[1]", 2.0),
                t("tonemap", 1.0),
            ],
            vec![
                t("gbuffer", 6.0),
                t("ssgi_input", 2.0),
                t("ssgi_mip[1]", 1.0),
                t("ssgi_mip[2]", 0.5),
                t("ssgi_gather[2]", 3.0),
                t("ssgi_gather[1]", 3.0),
                t("tonemap", 1.0),
            ],
        ];
        let (stages, ssgi, frame) = stage_times(&frames);
        let names: Vec<&str> = stages.iter().map(|s| s.stage.as_str()).collect();
        assert_eq!(names, ["ssgi_input", "ssgi_mip", "ssgi_gather"]);
        // ssgi_mip per frame: 3, 2, 1.5.
        assert_eq!(
            stages[1].time,
            Span {
                median_ms: 2.0,
                min_ms: 1.5,
                max_ms: 3.0
            }
        );
        // ssgi per frame: 14, 9, 9.5; the frame adds gbuffer and tonemap: 20, 17, 16.5.
        assert_eq!((ssgi.median_ms, ssgi.min_ms, ssgi.max_ms), (9.5, 9.0, 14.0));
        assert_eq!(
            (frame.median_ms, frame.min_ms, frame.max_ms),
            (17.0, 16.5, 20.0)
        );
    }

    #[test]
    fn table_and_csv_list_every_row_and_stage() {
        let span = |m| Span {
            median_ms: m,
            min_ms: m - 0.5,
            max_ms: m + 0.5,
        };
        let row = |number, mips: &str, stages: &[(&str, f64)]| SsgiBenchRow {
            number,
            mips: mips.into(),
            resolution: "half".into(),
            samples: 16,
            stages: stages
                .iter()
                .map(|&(s, m)| StageTime {
                    stage: s.into(),
                    time: span(m),
                })
                .collect(),
            ssgi: span(3.0),
            frame: span(10.0),
            rel_mse: 0.25,
            flip: 0.5,
        };
        let report = SsgiBenchReport {
            device: "dev, 1".into(),
            scene: "cornell".into(),
            size: 64,
            frames: 5,
            warmup: 1,
            gi_frames: 2,
            direct_rel_mse: 0.4,
            direct_flip: 0.7,
            rows: vec![
                row(1, "fast", &[("ssgi_input", 1.0), ("ssgi_mip", 2.0)]),
                row(2, "voting", &[("ssgi_input", 1.5), ("ssgi_reflect", 4.0)]),
            ],
        };
        let table = report.table();
        assert!(
            table.contains("ssgi_reflect") && table.contains("voting"),
            "{table}"
        );
        assert!(table.contains("3.00 [2.50, 3.50]"), "{table}");
        let csv = report.csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3, "{csv}");
        let columns = lines[0].split(',').count();
        assert!(
            lines.iter().all(|l| l.split(',').count() == columns),
            "{csv}"
        );
        // A stage a row does not have is empty, not zero.
        assert!(lines[1].contains(",,,"), "{csv}");
        assert!(lines[2].ends_with("0.25,0.5,dev; 1"), "{csv}");
    }
}
