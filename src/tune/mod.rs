//! The sweep's results and the tuner: one row per measured configuration ([`SweepRow`]), the
//! CSV files they are kept in (appended row by row, so that an interrupted sweep keeps what
//! it measured), and the tuner's choice within a time budget ([`tune`], [`tune_from_dir`]).
//!
//! Plain data without a GPU, below both its users: `bench::sweep` (which measures and writes
//! the rows) and the viewer (whose "best within budget" reads them), neither of which may use
//! the other.

mod csv;

pub use csv::{read_rows, CsvAppender, CsvRow};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Errors of the sweep's CSV files and of the tuner's choice, each naming what to fix.
#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{} line {line}: {reason}; is it a CSV written by `voxgi sweep`?", path.display())]
    Csv {
        path: PathBuf,
        line: usize,
        reason: String,
    },
    #[error("{}: no rows of scene {scene} (it has: {}); run `voxgi sweep {scene} --out DIR` first", path.display(), have.join(", "))]
    NoScene {
        scene: String,
        path: PathBuf,
        have: Vec<String>,
    },
    #[error("no configuration of {scene} fits in {budget_ms} ms; the fastest, `{fastest}`, takes {fastest_ms:.3} ms")]
    OverBudget {
        scene: String,
        budget_ms: f64,
        fastest: String,
        fastest_ms: f64,
    },
    #[error("--budget-ms {0}: expected a positive number of milliseconds")]
    Budget(f64),
}

/// What the sweep measured of one configuration on one scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// The scene's name: a built-in's name, else the file's stem (its reference's prefix).
    pub scene: String,
    /// The configuration's label (`bench::sweep::Config::label`).
    pub config: String,
    pub method: String,
    /// Image width and height in pixels.
    pub size: u32,
    /// Profiled frames (after warm-up).
    pub frames: u32,
    /// GPU ms per frame of the GI passes (voxelization, light maps, `gi_*`): median, min, max.
    pub gi_median_ms: f64,
    pub gi_min_ms: f64,
    pub gi_max_ms: f64,
    /// GPU ms per frame of all passes.
    pub frame_median_ms: f64,
    pub frame_min_ms: f64,
    pub frame_max_ms: f64,
    /// Frames the scored image accumulates (the path tracer's `gi-frames`, else 1).
    pub accumulate_frames: u32,
    /// GPU ms to the scored image: `frame_median_ms` × `accumulate_frames`.
    pub image_ms: f64,
    /// Transient GPU memory of the frame graph (aliased), bytes.
    pub transient_bytes: u64,
    pub rel_mse: f64,
    pub flip: f64,
    pub psnr_db: f64,
    pub ssim: f64,
    pub device: String,
    /// The configuration's settings as an inline TOML document of scene tables: the
    /// resolved `[gi]` table and the `[shadow]` and `[post]` keys its grid set
    /// (`{ gi = { … }, shadow = { … } }`, what `voxgi tune` prints). A row of an older
    /// sweep holds the `[gi]` table alone (`{ method = …, … }`); [`tables_text`] reads both.
    pub gi_toml: String,
    /// Flicker along the light path (`bench::temporal`); empty when not measured (no
    /// light that can move, or `--temporal-steps 0`).
    pub flicker: Option<f64>,
    /// The fraction of a light's switch-off the first frame after it still misses
    /// (`bench::temporal::Lag::ghost`); empty when not measured.
    pub ghost: Option<f64>,
    /// Frames until the switch-off is 95% done; empty when not measured or not done within
    /// `--lag-frames` (then `ghost` is set).
    pub lag_frames: Option<u32>,
}

/// The CSV's columns, in [`SweepRow`]'s field order.
pub const CSV_COLUMNS: [&str; 23] = [
    "scene",
    "config",
    "method",
    "size",
    "frames",
    "gi_median_ms",
    "gi_min_ms",
    "gi_max_ms",
    "frame_median_ms",
    "frame_min_ms",
    "frame_max_ms",
    "accumulate_frames",
    "image_ms",
    "transient_bytes",
    "rel_mse",
    "flip",
    "psnr_db",
    "ssim",
    "device",
    "gi_toml",
    "flicker",
    "ghost",
    "lag_frames",
];

const TEXT_COLUMNS: [&str; 5] = ["scene", "config", "method", "device", "gi_toml"];

impl CsvRow for SweepRow {
    const COLUMNS: &'static [&'static str] = &CSV_COLUMNS;
    const TEXT_COLUMNS: &'static [&'static str] = &TEXT_COLUMNS;
    const OTHER_HEADER: &'static str =
        "the header is not this version's sweep header (an older sweep lacks the temporal \
         columns: start a new --out)";
}

/// The CSV header line of [`SweepRow`]s.
pub fn csv_header() -> String {
    SweepRow::csv_header()
}

/// Reads a sweep's CSV (header and rows).
pub fn read_csv(path: &Path) -> Result<Vec<SweepRow>, TuneError> {
    read_rows(path)
}

/// The most accurate row (least relMSE; of equals the faster) of `scene` whose time to the
/// image fits in `budget_ms`.
pub fn tune<'a>(
    rows: &'a [SweepRow],
    scene: &str,
    budget_ms: f64,
    path: &Path,
) -> Result<&'a SweepRow, TuneError> {
    if !(budget_ms > 0.0 && budget_ms.is_finite()) {
        return Err(TuneError::Budget(budget_ms));
    }
    let of_scene: Vec<&SweepRow> = rows.iter().filter(|r| r.scene == scene).collect();
    if of_scene.is_empty() {
        let mut have: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
        have.dedup();
        return Err(TuneError::NoScene {
            scene: scene.to_owned(),
            path: path.to_owned(),
            have,
        });
    }
    let best = of_scene
        .iter()
        .filter(|r| r.image_ms <= budget_ms && r.rel_mse.is_finite())
        .min_by(|a, b| {
            a.rel_mse
                .total_cmp(&b.rel_mse)
                .then(a.image_ms.total_cmp(&b.image_ms))
        });
    let fastest = of_scene
        .iter()
        .min_by(|a, b| a.image_ms.total_cmp(&b.image_ms));
    match (best, fastest) {
        (Some(r), _) => Ok(r),
        (None, fastest) => Err(TuneError::OverBudget {
            scene: scene.to_owned(),
            budget_ms,
            fastest: fastest.map_or_else(String::new, |f| f.config.clone()),
            fastest_ms: fastest.map_or(f64::NAN, |f| f.image_ms),
        }),
    }
}

/// A row's settings as scene tables (`gi`, and `shadow` or `post` when its grid set their
/// keys). The column of an older sweep is the `[gi]` table itself; its keys are `[gi]`'s,
/// none of which is a table named `gi`, so the two forms are told apart by that key.
fn row_tables(row: &SweepRow) -> Result<toml::Table, String> {
    let doc: toml::Table =
        toml::from_str(&format!("v = {}", row.gi_toml)).map_err(|e| e.to_string())?;
    let v = match doc.get("v") {
        Some(toml::Value::Table(t)) => t.clone(),
        _ => return Err("not an inline table".into()),
    };
    Ok(match v.get("gi") {
        Some(toml::Value::Table(_)) => v,
        _ => toml::Table::from_iter([("gi".to_owned(), toml::Value::Table(v))]),
    })
}

/// A row's settings as a scene file writes them: its `[gi]` table, then its `[post]` and
/// `[shadow]` keys when its grid set some (what `voxgi tune` prints).
pub fn tables_text(row: &SweepRow) -> Result<String, String> {
    toml::to_string(&row_tables(row)?).map_err(|e| e.to_string())
}

/// A row's `[gi]` table alone as a scene file writes it.
pub fn gi_table_text(row: &SweepRow) -> Result<String, String> {
    let mut tables = row_tables(row)?;
    tables.retain(|k, _| k == "gi");
    toml::to_string(&tables).map_err(|e| e.to_string())
}

/// What `voxgi tune` and the viewer's "best within budget" choose from the sweep in `dir`
/// (its sweep.csv): the most accurate row of `scene` within `budget_ms` ([`tune`]), its
/// settings as text ([`tables_text`]: `[gi]`, and `[shadow]`/`[post]` keys its grid set),
/// and its `[gi]` table read back as a scene file's `[gi]` would be.
pub fn tune_from_dir(
    dir: &Path,
    scene: &str,
    budget_ms: f64,
) -> Result<(SweepRow, String, crate::scene::schema::Layer), TuneError> {
    let csv = dir.join("sweep.csv");
    if !csv.exists() {
        return Err(TuneError::Io {
            path: csv,
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no sweep here; run `voxgi sweep SCENE --out DIR` and pass DIR",
            ),
        });
    }
    let rows = read_csv(&csv)?;
    let row = tune(&rows, scene, budget_ms, &csv)?.clone();
    let bad = |reason: String| TuneError::Csv {
        path: csv.clone(),
        line: 0,
        reason: format!("the gi_toml of `{}`: {reason}", row.config),
    };
    let table = tables_text(&row).map_err(bad)?;
    let gi = gi_table_text(&row).map_err(bad)?;
    let layer = crate::scene::gi_table_layer(&gi, &csv).map_err(|e| bad(e.to_string()))?;
    Ok((row, table, layer))
}

/// A row for the tests of the tuner and the sweep: the hemisphere method with `ms` rays.
#[cfg(test)]
pub(crate) fn sample_row(scene: &str, config: &str, ms: f64, rel_mse: f64) -> SweepRow {
    SweepRow {
        scene: scene.into(),
        config: config.into(),
        method: config.split(' ').next().unwrap_or("").into(),
        size: 32,
        frames: 5,
        gi_median_ms: ms / 2.0,
        gi_min_ms: ms / 3.0,
        gi_max_ms: ms,
        frame_median_ms: ms,
        frame_min_ms: ms,
        frame_max_ms: ms,
        accumulate_frames: 1,
        image_ms: ms,
        transient_bytes: 1 << 20,
        rel_mse,
        flip: 0.1,
        psnr_db: 30.0,
        ssim: 0.9,
        device: "a, \"quoted\" device".into(),
        gi_toml: format!(
            "{{ method = \"hemisphere\", rays = {} }}",
            (ms as u32).max(1)
        ),
        // One measured, one not settled, so the round trip sees numbers and empties.
        flicker: Some(0.0125),
        ghost: Some(0.5),
        lag_frames: None,
    }
}

#[cfg(test)]
mod tests {
    use super::sample_row as row;
    use super::*;
    use crate::gi::GiMethod;

    #[test]
    fn rows_survive_the_csv_round_trip() {
        let r = row("cornell", "hemisphere gi-rays=4", 1.25, 0.0123);
        assert_eq!(SweepRow::from_csv_line(&r.csv_line()), Ok(r.clone()));
        let dir = std::env::temp_dir().join(format!("voxgi-sweep-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("sweep.csv");
        let _ = std::fs::remove_file(&path);
        CsvAppender::open(&path)
            .and_then(|mut a| a.append(&r))
            .expect("writes");
        let r2 = SweepRow {
            flicker: None,
            ghost: None,
            lag_frames: Some(3),
            ..row("cornell", "none", 0.5, 0.2)
        };
        assert!(r2.csv_line().ends_with(",,,3"), "{}", r2.csv_line());
        CsvAppender::open(&path)
            .and_then(|mut a| a.append(&r2))
            .expect("appends without a second header");
        assert_eq!(read_csv(&path).expect("reads"), vec![r, r2]);
        std::fs::write(&path, "a,b\n").expect("write");
        let e = read_csv(&path).expect_err("not a sweep").to_string();
        assert!(e.contains("header"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// What the viewer's "best within budget" and `voxgi tune` read: the row within the budget,
    /// its `[gi]` table and that table as the scene file's settings layer; a folder without a sweep is an
    /// error naming its sweep.csv.
    #[test]
    fn tune_from_dir_reads_the_sweep_and_its_gi_table() {
        let dir = std::env::temp_dir().join(format!("voxgi-tune-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        let e = tune_from_dir(&dir, "cornell", 10.0).expect_err("no sweep yet");
        assert!(e.to_string().contains("sweep.csv"), "{e}");
        let mut csv = CsvAppender::open(&dir.join("sweep.csv")).expect("opens");
        for r in [
            row("cornell", "none", 1.0, 0.5),
            row("cornell", "hemisphere gi-rays=4", 4.0, 0.05),
            row("cornell", "hemisphere gi-rays=16", 16.0, 0.02),
        ] {
            csv.append(&r).expect("appends");
        }
        let (r, table, layer) = tune_from_dir(&dir, "cornell", 5.0).expect("tunes");
        assert_eq!(r.config, "hemisphere gi-rays=4");
        assert!(table.starts_with("[gi]\n"), "{table}");
        // `row` stores rays = its ms (4 here) in the resolved settings.
        let s = crate::scene::resolve_gi(&layer, &Default::default());
        assert_eq!((s.method, s.rays), (GiMethod::Hemisphere, 4));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn tune_takes_the_most_accurate_row_within_the_budget() {
        let rows = [
            row("cornell", "none", 1.0, 0.5),
            row("cornell", "hemisphere gi-rays=4", 4.0, 0.05),
            row("cornell", "hemisphere gi-rays=16", 12.0, 0.02),
            row("cornell", "pathtrace gi-frames=8", 40.0, 0.01),
            row("box", "pathtrace gi-frames=8", 2.0, 0.0),
        ];
        let p = Path::new("sweep.csv");
        let pick = |ms| tune(&rows, "cornell", ms, p).map(|r| r.config.as_str());
        assert!(pick(0.5).is_err());
        assert_eq!(pick(1.0).ok(), Some("none"));
        assert_eq!(pick(11.9).ok(), Some("hemisphere gi-rays=4"));
        assert_eq!(pick(12.0).ok(), Some("hemisphere gi-rays=16"));
        assert_eq!(pick(1e9).ok(), Some("pathtrace gi-frames=8"));
        let e = tune(&rows, "sponza", 10.0, p)
            .expect_err("no rows")
            .to_string();
        assert!(e.contains("cornell, box"), "{e}");
        assert!(tune(&rows, "cornell", -1.0, p).is_err());
    }
}
