//! The data side of `voxgi sweep` and `voxgi tune`, plain Rust without a GPU: the grid of
//! configurations, one row per measured configuration, its CSV form (appended row by row so
//! that an interrupted sweep keeps what it measured), the Pareto front of error against time,
//! its SVG plot, and the tuner's choice within a time budget.
//!
//! The trade measured is the one of the method ladder (Thiedemann 2010, Ch. 6 hemisphere
//! sampling and path tracing, Ch. 7 VPLs): each row's time is the GPU time to the image it was
//! scored on — one frame, or the path tracer's accumulated frames.

use crate::gi::GiMethod;
use crate::gi::GiSettings;
use clap::ValueEnum;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Errors of the sweep's inputs and files, each naming what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("--grid {spec}: {reason}")]
    Grid { spec: String, reason: String },
    #[error("--methods {value}: unknown method; expected a comma-separated list of none, hemisphere, pathtrace, vpl")]
    Method { value: String },
    #[error("configuration `{config}`: {message}")]
    Flag { config: String, message: String },
    #[error("scene {scene}: no reference image {}; render one with tools/reference (see assets/references/README.md) or leave the scene out", path.display())]
    NoReference { scene: String, path: PathBuf },
    #[error("--size {size}: the reference {} is {width}x{height}; --size must divide it (e.g. 32, 64, 128, 256)", path.display())]
    Size {
        size: u32,
        width: u32,
        height: u32,
        path: PathBuf,
    },
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
    #[error("{} exists: pass --resume to skip the rows it has, or choose another --out", path.display())]
    Exists { path: PathBuf },
    #[error("{}: its rows were measured with {measured}, and this sweep asks for {given}; pass the same flags to resume it, or choose another --out", path.display())]
    TraverseSettings {
        path: PathBuf,
        measured: String,
        given: String,
    },
    #[error("no scene to sweep: none of the scenes has a reference in {}", dir.display())]
    NoScenes { dir: PathBuf },
    #[error("{}: no rows of scene {scene} (it has: {}); run `voxgi sweep {scene} --out DIR` first", path.display(), have.join(", "))]
    TuneNoScene {
        scene: String,
        path: PathBuf,
        have: Vec<String>,
    },
    #[error("no configuration of {scene} fits in {budget_ms} ms; the fastest, `{fastest}`, takes {fastest_ms:.3} ms")]
    TuneOverBudget {
        scene: String,
        budget_ms: f64,
        fastest: String,
        fastest_ms: f64,
    },
    #[error("--budget-ms {0}: expected a positive number of milliseconds")]
    Budget(f64),
    #[error(transparent)]
    Reference(#[from] super::reference_cache::ReferenceError),
}

/// The `[gi]` keys a grid may vary (by key path; their flags' names, without `--`, are
/// aliases) and the methods each one changes; a key is left out of the other methods'
/// configurations, so that no configuration is measured twice.
pub const GRID_KEYS: &[(&str, &[GiMethod])] = &[
    ("gi.rays", RAY_METHODS),
    ("gi.radius_m", RAY_METHODS),
    ("gi.normal_offset_voxels", GI_METHODS),
    ("gi.ray_offset_voxels", GI_METHODS),
    ("gi.filter_radius", FILTERED),
    ("gi.filter_passes", FILTERED),
    ("gi.start_level", GI_METHODS),
    ("gi.max_iterations", GI_METHODS),
    ("gi.light_map_resolution", GI_METHODS),
    ("gi.radiance_source", &[GiMethod::Hemisphere]),
    ("gi.bounces", &[GiMethod::Pathtrace]),
    (
        "gi.accumulate_frames",
        &[GiMethod::Pathtrace, GiMethod::Ssgi],
    ),
    ("gi.vpls", VPL),
    ("gi.vpl_pattern", VPL),
    ("gi.vpl_d_min_voxels", VPL),
    ("gi.vpl_bounces", VPL),
    ("gi.vpl_visibility", VPL),
    ("gi.vpl_normalize", VPL),
    ("gi.vpl_spot_sampling", VPL),
    ("gi.vpl_shading", VPL),
    ("gi.ssgi_resolution", SSGI),
    ("gi.ssgi_samples", SSGI),
    ("gi.ssgi_mips", SSGI),
    ("gi.ssr_rays", SSGI),
];

const GI_METHODS: &[GiMethod] = &[GiMethod::Hemisphere, GiMethod::Pathtrace, GiMethod::Vpl];
const RAY_METHODS: &[GiMethod] = &[GiMethod::Hemisphere, GiMethod::Pathtrace];
const VPL: &[GiMethod] = &[GiMethod::Vpl];
const SSGI: &[GiMethod] = &[GiMethod::Ssgi];
/// The methods whose output the shared geometry-aware filter smooths.
const FILTERED: &[GiMethod] = &[
    GiMethod::Hemisphere,
    GiMethod::Pathtrace,
    GiMethod::Vpl,
    GiMethod::Ssgi,
];

/// One `--grid KEY=V1,V2,…`: a `[gi]` key and the values it takes.
#[derive(Clone, Debug, PartialEq)]
pub struct GridAxis {
    /// The key path.
    pub key: &'static str,
    /// The key as the grid named it (its path or its flag's alias), for the configuration's
    /// label, so that a sweep resumed with the same `--grid` finds its rows.
    pub name: String,
    pub values: Vec<String>,
}

/// The grid key `name` names: a key path of [`GRID_KEYS`] or its flag without `--`.
fn grid_key(name: &str) -> Option<&'static str> {
    use crate::scene::schema::key;
    GRID_KEYS.iter().map(|(k, _)| *k).find(|k| {
        *k == name
            || key::<GiSettings>(k)
                .and_then(|k| k.flag)
                .is_some_and(|f| f.long == name)
    })
}

/// Parses `KEY=V1,V2,…`. The values are checked later, as flags of the configurations
/// ([`Config::argv`]), so that their errors are the flags' own.
pub fn parse_grid(spec: &str) -> Result<GridAxis, SweepError> {
    let err = |reason: String| SweepError::Grid {
        spec: spec.to_owned(),
        reason,
    };
    let (key, values) = spec
        .split_once('=')
        .ok_or_else(|| err("expected KEY=V1,V2,… (e.g. gi.rays=4,16)".into()))?;
    let name = key.trim().trim_start_matches("--");
    if name == "gi" || name == "gi.method" {
        return Err(err("the method is chosen by --methods, not --grid".into()));
    }
    let key = grid_key(name).ok_or_else(|| {
        let known: Vec<&str> = GRID_KEYS.iter().map(|(k, _)| *k).collect();
        err(format!(
            "unknown key `{name}`; expected one of {} (or their flags' names, e.g. gi-rays)",
            known.join(", ")
        ))
    })?;
    let values: Vec<String> = values.split(',').map(|v| v.trim().to_owned()).collect();
    if values.iter().any(String::is_empty) {
        return Err(err(format!("an empty value for {name}")));
    }
    Ok(GridAxis {
        key,
        name: name.to_owned(),
        values,
    })
}

/// Parses `--methods none,hemisphere,…`.
pub fn parse_methods(list: &str) -> Result<Vec<GiMethod>, SweepError> {
    let mut methods = Vec::new();
    for name in list.split(',').map(str::trim) {
        let m = GiMethod::from_str(name, true).map_err(|_| SweepError::Method {
            value: name.to_owned(),
        })?;
        if !methods.contains(&m) {
            methods.push(m);
        }
    }
    Ok(methods)
}

/// A method's name as `--gi` and a scene's `method` spell it.
pub fn method_name(m: GiMethod) -> String {
    m.to_possible_value()
        .map_or_else(|| format!("{m:?}"), |v| v.get_name().to_owned())
}

/// One value of a grid axis in a configuration: the key path, the name the grid gave it, the
/// value.
#[derive(Clone, Debug, PartialEq)]
pub struct GridValue {
    pub key: &'static str,
    pub name: String,
    pub value: String,
}

/// One configuration of the sweep: a method and the grid values that apply to it.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub method: GiMethod,
    pub values: Vec<GridValue>,
}

impl Config {
    /// `method key=value …`, the configuration's name in the CSV (each key as the grid
    /// named it).
    pub fn label(&self) -> String {
        let mut s = method_name(self.method);
        for v in &self.values {
            s += &format!(" {}={}", v.name, v.value);
        }
        s
    }

    /// The configuration as `voxgi render` flags: `--gi METHOD` and `--set KEY=VALUE`.
    pub fn argv(&self) -> Vec<String> {
        let mut a = vec!["--gi".to_owned(), method_name(self.method)];
        for v in &self.values {
            a.push("--set".to_owned());
            a.push(format!("{}={}", v.key, v.value));
        }
        a
    }
}

/// Every method with the cartesian product of the grid axes that apply to it (a method no
/// axis applies to is one configuration).
pub fn configs(methods: &[GiMethod], grid: &[GridAxis]) -> Vec<Config> {
    let mut out = Vec::new();
    for &method in methods {
        let axes: Vec<&GridAxis> = grid
            .iter()
            .filter(|a| {
                GRID_KEYS
                    .iter()
                    .any(|(k, ms)| *k == a.key && ms.contains(&method))
            })
            .collect();
        let mut partial: Vec<Vec<GridValue>> = vec![Vec::new()];
        for axis in axes {
            partial = partial
                .into_iter()
                .flat_map(|p| {
                    axis.values.iter().map(move |v| {
                        let mut q = p.clone();
                        q.push(GridValue {
                            key: axis.key,
                            name: axis.name.clone(),
                            value: v.clone(),
                        });
                        q
                    })
                })
                .collect();
        }
        out.extend(partial.into_iter().map(|values| Config { method, values }));
    }
    out
}

/// What the sweep measured of one configuration on one scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// The scene's name: a built-in's name, else the file's stem (its reference's prefix).
    pub scene: String,
    /// [`Config::label`].
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
    /// The resolved `[gi]` table as an inline TOML table (what `voxgi tune` prints).
    pub gi_toml: String,
    /// Flicker along the light path ([`super::temporal`]); empty when not measured (no
    /// light that can move, or `--temporal-steps 0`).
    pub flicker: Option<f64>,
    /// The fraction of a light's switch-off the first frame after it still misses
    /// ([`super::temporal::Lag::ghost`]); empty when not measured.
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

/// Quotes a CSV field when it holds a comma, a quote or a line break (RFC 4180).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// Splits one CSV line into fields (RFC 4180 quoting, no line breaks inside fields).
fn split_csv_line(line: &str) -> Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => fields.push(std::mem::take(&mut field)),
            _ => field.push(c),
        }
    }
    if quoted {
        return Err("an unclosed quote".into());
    }
    fields.push(field);
    Ok(fields)
}

/// A row type of the sweep's CSV files: its columns, in the struct's field order and named
/// as its serde fields, and which of them are text (the others are numbers, empty for
/// `None`).
pub trait CsvRow: Serialize + serde::de::DeserializeOwned {
    const COLUMNS: &'static [&'static str];
    const TEXT_COLUMNS: &'static [&'static str];
    /// What a header of another version means, for the error.
    const OTHER_HEADER: &'static str;

    /// The row as one CSV line (no line break).
    fn csv_line(&self) -> String {
        let value = serde_json::to_value(self).unwrap_or_default();
        Self::COLUMNS
            .iter()
            .map(|c| match &value[*c] {
                serde_json::Value::String(s) => csv_field(s),
                serde_json::Value::Null => String::new(),
                v => v.to_string(),
            })
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Parses a line written by [`CsvRow::csv_line`].
    fn from_csv_line(line: &str) -> Result<Self, String> {
        let fields = split_csv_line(line)?;
        if fields.len() != Self::COLUMNS.len() {
            return Err(format!(
                "{} fields, expected {}",
                fields.len(),
                Self::COLUMNS.len()
            ));
        }
        let mut map = serde_json::Map::new();
        for (c, f) in Self::COLUMNS.iter().zip(fields) {
            let v = if Self::TEXT_COLUMNS.contains(c) {
                serde_json::Value::String(f)
            } else if f.is_empty() {
                serde_json::Value::Null
            } else {
                serde_json::from_str(&f).map_err(|_| format!("{c} = `{f}` is not a number"))?
            };
            map.insert((*c).to_owned(), v);
        }
        serde_json::from_value(serde_json::Value::Object(map)).map_err(|e| e.to_string())
    }

    /// The CSV header line.
    fn csv_header() -> String {
        Self::COLUMNS.join(",")
    }
}

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
pub fn read_csv(path: &Path) -> Result<Vec<SweepRow>, SweepError> {
    read_rows(path)
}

/// Reads a CSV of `T` rows written by [`CsvAppender`] (header and rows).
pub fn read_rows<T: CsvRow>(path: &Path) -> Result<Vec<T>, SweepError> {
    let text = std::fs::read_to_string(path).map_err(|source| SweepError::Io {
        path: path.to_owned(),
        source,
    })?;
    let mut lines = text.lines().enumerate();
    let csv_err = |line: usize, reason: String| SweepError::Csv {
        path: path.to_owned(),
        line: line + 1,
        reason,
    };
    match lines.next() {
        Some((_, h)) if h.trim_end() == T::csv_header() => {}
        _ => return Err(csv_err(0, T::OTHER_HEADER.into())),
    }
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| T::from_csv_line(l.trim_end()).map_err(|e| csv_err(i, e)))
        .collect()
}

/// Appends `T` rows to a CSV file, writing the header first when the file is new; each row
/// is flushed as it is written, so an interrupted sweep keeps every finished row.
pub struct CsvAppender<T> {
    path: PathBuf,
    file: std::fs::File,
    rows: std::marker::PhantomData<fn(&T)>,
}

impl<T: CsvRow> CsvAppender<T> {
    pub fn open(path: &Path) -> Result<Self, SweepError> {
        let io = |source| SweepError::Io {
            path: path.to_owned(),
            source,
        };
        let new = !path.exists();
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(io)?;
        if new {
            writeln!(file, "{}", T::csv_header()).map_err(io)?;
        }
        Ok(Self {
            path: path.to_owned(),
            file,
            rows: std::marker::PhantomData,
        })
    }

    pub fn append(&mut self, row: &T) -> Result<(), SweepError> {
        writeln!(self.file, "{}", row.csv_line())
            .and_then(|()| self.file.sync_data())
            .map_err(|source| SweepError::Io {
                path: self.path.clone(),
                source,
            })
    }
}

/// Indices of the points on the Pareto front of (time, error), both smaller-is-better: no
/// other point is at most as slow and at most as wrong and better in one. Sorted by time
/// (then error); of equal points the first is kept. Points with a non-finite value are never
/// on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
            .then(a.cmp(&b))
    });
    // Along increasing time, a point is on the front when its error is below every error
    // seen so far.
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The most accurate row (least relMSE; of equals the faster) of `scene` whose time to the
/// image fits in `budget_ms`.
pub fn tune<'a>(
    rows: &'a [SweepRow],
    scene: &str,
    budget_ms: f64,
    path: &Path,
) -> Result<&'a SweepRow, SweepError> {
    if !(budget_ms > 0.0 && budget_ms.is_finite()) {
        return Err(SweepError::Budget(budget_ms));
    }
    let of_scene: Vec<&SweepRow> = rows.iter().filter(|r| r.scene == scene).collect();
    if of_scene.is_empty() {
        let mut have: Vec<String> = rows.iter().map(|r| r.scene.clone()).collect();
        have.dedup();
        return Err(SweepError::TuneNoScene {
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
        (None, fastest) => Err(SweepError::TuneOverBudget {
            scene: scene.to_owned(),
            budget_ms,
            fastest: fastest.map_or_else(String::new, |f| f.config.clone()),
            fastest_ms: fastest.map_or(f64::NAN, |f| f.image_ms),
        }),
    }
}

/// A row's `[gi]` table as a scene file writes it.
pub fn gi_table_text(row: &SweepRow) -> Result<String, String> {
    let doc: toml::Table =
        toml::from_str(&format!("gi = {}", row.gi_toml)).map_err(|e| e.to_string())?;
    toml::to_string(&doc).map_err(|e| e.to_string())
}

/// What `voxgi tune` and the viewer's "best within budget" choose from the sweep in `dir`
/// (its sweep.csv): the most accurate row of `scene` within `budget_ms` ([`tune`]), its
/// `[gi]` table as text, and that table read back as a scene file's `[gi]` would be.
pub fn tune_from_dir(
    dir: &Path,
    scene: &str,
    budget_ms: f64,
) -> Result<(SweepRow, String, crate::scene::schema::Layer), SweepError> {
    let csv = dir.join("sweep.csv");
    if !csv.exists() {
        return Err(SweepError::Io {
            path: csv,
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no sweep here; run `voxgi sweep SCENE --out DIR` and pass DIR",
            ),
        });
    }
    let rows = read_csv(&csv)?;
    let row = tune(&rows, scene, budget_ms, &csv)?.clone();
    let bad = |reason: String| SweepError::Csv {
        path: csv.clone(),
        line: 0,
        reason: format!("the gi_toml of `{}`: {reason}", row.config),
    };
    let table = gi_table_text(&row).map_err(bad)?;
    let layer = crate::scene::gi_table_layer(&table, &csv).map_err(|e| bad(e.to_string()))?;
    Ok((row, table, layer))
}

/// The resolved GI settings as a scene's `[gi]` table: every key of the schema
/// ([`GiSettings::keys`]; an unset ray length left out).
pub fn gi_table(s: &GiSettings) -> toml::Table {
    crate::scene::schema::table(s)
}

/// [`gi_table`] as a one-line inline table, for the CSV.
pub fn gi_inline(s: &GiSettings) -> String {
    toml::Value::Table(gi_table(s)).to_string()
}

/// A box-filtered copy of `img` `factor` times smaller in each direction (the reference
/// brought to the sweep's image size: each pixel the mean radiance over its footprint).
pub fn downsample(img: &crate::eval::HdrImage, factor: u32) -> crate::eval::HdrImage {
    let f = factor.max(1) as usize;
    let (w, h) = (img.width as usize / f, img.height as usize / f);
    let mut data = vec![[0.0f32; 3]; w * h];
    for (i, out) in data.iter_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let mut sum = [0.0f64; 3];
        for dy in 0..f {
            for dx in 0..f {
                let p = img.data[(y * f + dy) * img.width as usize + x * f + dx];
                for c in 0..3 {
                    sum[c] += f64::from(p[c]);
                }
            }
        }
        *out = sum.map(|s| (s / (f * f) as f64) as f32);
    }
    crate::eval::HdrImage {
        width: w as u32,
        height: h as u32,
        data,
    }
}

/// Colours of the methods in the plot.
fn method_colour(method: &str) -> &'static str {
    match method {
        "none" => "#7f7f7f",
        "hemisphere" => "#1f77b4",
        "pathtrace" => "#d62728",
        "vpl" => "#2ca02c",
        _ => "#9467bd",
    }
}

/// Escapes text for SVG.
fn xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The decades [10^lo, 10^hi] covering the positive values.
fn decades(values: impl Iterator<Item = f64>) -> (i32, i32) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0, 1);
    }
    let (l, h) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (l, h.max(l + 1))
}

/// The plot of relMSE (log) against GPU ms to the image (log) of one scene's rows: a dot
/// per configuration coloured by method (its label as the tooltip), the Pareto front as a
/// line through the configurations no other beats in both.
pub fn pareto_svg(scene: &str, rows: &[&SweepRow]) -> String {
    let (w, h, left, right, top, bottom) = (640.0, 420.0, 70.0, 150.0, 40.0, 50.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let (tx0, tx1) = decades(rows.iter().map(|r| r.image_ms));
    let (ey0, ey1) = decades(rows.iter().map(|r| r.rel_mse));
    let x = |ms: f64| left + (ms.max(1e-300).log10() - f64::from(tx0)) / f64::from(tx1 - tx0) * pw;
    let y =
        |e: f64| top + ph - (e.max(1e-300).log10() - f64::from(ey0)) / f64::from(ey1 - ey0) * ph;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         font-family=\"sans-serif\" font-size=\"12\">\n\
         <rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}: error vs GPU time \
         (log–log), Pareto front</text>\n",
        left + pw / 2.0,
        xml(scene)
    );
    for d in tx0..=tx1 {
        let px = x(10f64.powi(d));
        s += &format!(
            "<line x1=\"{px:.1}\" y1=\"{top}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\">1e{d}</text>\n",
            top + ph,
            top + ph + 16.0
        );
    }
    for d in ey0..=ey1 {
        let py = y(10f64.powi(d));
        s += &format!(
            "<line x1=\"{left}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#ddd\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{d}</text>\n",
            left + pw,
            left - 6.0,
            py + 4.0
        );
    }
    s += &format!(
        "<rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>\n\
         <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">GPU ms to the image</text>\n\
         <text x=\"16\" y=\"{:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 16 {:.1})\">relMSE</text>\n",
        left + pw / 2.0,
        h - 10.0,
        top + ph / 2.0,
        top + ph / 2.0
    );
    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.image_ms, r.rel_mse)).collect();
    let front = pareto_front(&points);
    let line: Vec<String> = front
        .iter()
        .map(|&i| format!("{:.1},{:.1}", x(points[i].0), y(points[i].1)))
        .collect();
    s += &format!(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"black\" stroke-width=\"1.5\"/>\n",
        line.join(" ")
    );
    for (i, r) in rows.iter().enumerate() {
        let on_front = front.contains(&i);
        s += &format!(
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{}\" fill=\"{}\" stroke=\"black\" \
             stroke-width=\"{}\"><title>{} — {:.3} ms, relMSE {:.4}</title></circle>\n",
            x(r.image_ms),
            y(r.rel_mse),
            if on_front { 5 } else { 4 },
            method_colour(&r.method),
            if on_front { 1.5 } else { 0.0 },
            xml(&r.config),
            r.image_ms,
            r.rel_mse
        );
    }
    let mut methods: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
    methods.dedup();
    methods.sort_unstable();
    methods.dedup();
    for (k, m) in methods.iter().enumerate() {
        let ly = top + 10.0 + 18.0 * k as f64;
        s += &format!(
            "<circle cx=\"{:.1}\" cy=\"{ly:.1}\" r=\"4\" fill=\"{}\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n",
            left + pw + 16.0,
            method_colour(m),
            left + pw + 26.0,
            ly + 4.0,
            xml(m)
        );
    }
    let ly = top + 10.0 + 18.0 * methods.len() as f64;
    s += &format!(
        "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"black\" stroke-width=\"1.5\"/>\
         <text x=\"{:.1}\" y=\"{:.1}\">Pareto front</text>\n</svg>\n",
        left + pw + 10.0,
        left + pw + 22.0,
        left + pw + 26.0,
        ly + 4.0
    );
    s
}

/// `#rrggbb` as RGB bytes (the plot's colours).
fn rgb(hex: &str) -> image::Rgb<u8> {
    let byte = |i: usize| u8::from_str_radix(hex.get(i..i + 2).unwrap_or("00"), 16).unwrap_or(0);
    image::Rgb([byte(1), byte(3), byte(5)])
}

/// A line of 1-pixel steps from (x0, y0) to (x1, y1), clipped to the image.
fn draw_line(img: &mut image::RgbImage, from: (f64, f64), to: (f64, f64), c: image::Rgb<u8>) {
    let steps = (to.0 - from.0)
        .abs()
        .max((to.1 - from.1).abs())
        .ceil()
        .max(1.0) as u32;
    for k in 0..=steps {
        let t = f64::from(k) / f64::from(steps);
        plot(
            img,
            from.0 + (to.0 - from.0) * t,
            from.1 + (to.1 - from.1) * t,
            c,
        );
    }
}

fn plot(img: &mut image::RgbImage, x: f64, y: f64, c: image::Rgb<u8>) {
    let (x, y) = (x.round(), y.round());
    if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}

/// A filled disc of radius `r` pixels.
fn draw_disc(img: &mut image::RgbImage, x: f64, y: f64, r: f64, c: image::Rgb<u8>) {
    let ri = r.ceil() as i32;
    for dy in -ri..=ri {
        for dx in -ri..=ri {
            if f64::from(dx * dx + dy * dy) <= r * r {
                plot(img, x + f64::from(dx), y + f64::from(dy), c);
            }
        }
    }
}

/// [`pareto_svg`]'s plot as a bitmap (the same axes, decade grid, front and dots; legend as
/// coloured dots in the SVG's order; no text — the SVG carries the labels).
pub fn pareto_png(rows: &[&SweepRow]) -> image::RgbImage {
    let (w, h, left, right, top, bottom) = (640u32, 420u32, 70.0, 150.0, 40.0, 50.0);
    let (pw, ph) = (f64::from(w) - left - right, f64::from(h) - top - bottom);
    let (tx0, tx1) = decades(rows.iter().map(|r| r.image_ms));
    let (ey0, ey1) = decades(rows.iter().map(|r| r.rel_mse));
    let x = |ms: f64| left + (ms.max(1e-300).log10() - f64::from(tx0)) / f64::from(tx1 - tx0) * pw;
    let y =
        |e: f64| top + ph - (e.max(1e-300).log10() - f64::from(ey0)) / f64::from(ey1 - ey0) * ph;
    let mut img = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    let grid = rgb("#dddddd");
    for d in tx0..=tx1 {
        let px = x(10f64.powi(d));
        draw_line(&mut img, (px, top), (px, top + ph), grid);
    }
    for d in ey0..=ey1 {
        let py = y(10f64.powi(d));
        draw_line(&mut img, (left, py), (left + pw, py), grid);
    }
    let black = image::Rgb([0, 0, 0]);
    let corners = [
        (left, top),
        (left + pw, top),
        (left + pw, top + ph),
        (left, top + ph),
    ];
    for k in 0..4 {
        draw_line(&mut img, corners[k], corners[(k + 1) % 4], black);
    }
    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.image_ms, r.rel_mse)).collect();
    let front = pareto_front(&points);
    for pair in front.windows(2) {
        let (a, b) = (points[pair[0]], points[pair[1]]);
        draw_line(&mut img, (x(a.0), y(a.1)), (x(b.0), y(b.1)), black);
    }
    for (i, r) in rows.iter().enumerate() {
        let (px, py) = (x(r.image_ms), y(r.rel_mse));
        if front.contains(&i) {
            draw_disc(&mut img, px, py, 6.0, black);
        }
        draw_disc(&mut img, px, py, 4.0, rgb(method_colour(&r.method)));
    }
    let mut methods: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
    methods.sort_unstable();
    methods.dedup();
    for (k, m) in methods.iter().enumerate() {
        let ly = top + 10.0 + 18.0 * k as f64;
        draw_disc(&mut img, left + pw + 16.0, ly, 4.0, rgb(method_colour(m)));
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pareto_front_keeps_what_nothing_beats_in_both() {
        // (time, error): 1 is beaten by 0 (slower, same error); 3 by 2 (slower, worse);
        // 4 is the fastest; 5 equals 0 and the first of equals is kept; 6 is NaN.
        let p = [
            (2.0, 0.5),
            (3.0, 0.5),
            (4.0, 0.1),
            (5.0, 0.2),
            (1.0, 0.9),
            (2.0, 0.5),
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&p), vec![4, 0, 2]);
        assert!(pareto_front(&[]).is_empty());
        // Every point of a strictly decreasing trade is on the front.
        let trade: Vec<(f64, f64)> = (1..=5).map(|k| (k as f64, 1.0 / k as f64)).collect();
        assert_eq!(pareto_front(&trade), vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn the_front_matches_a_brute_force_check() {
        // A deterministic scatter; the front by definition, pair by pair.
        let p: Vec<(f64, f64)> = (0..40u32)
            .map(|k| {
                let a = f64::from((k * 37 + 11) % 23) + 1.0;
                let b = f64::from((k * 53 + 7) % 19) + 1.0;
                (a, b)
            })
            .collect();
        let dominated = |i: usize| {
            (0..p.len())
                .any(|j| j != i && p[j].0 <= p[i].0 && p[j].1 <= p[i].1 && (p[j] != p[i] || j < i))
        };
        let mut brute: Vec<usize> = (0..p.len()).filter(|&i| !dominated(i)).collect();
        let mut front = pareto_front(&p);
        brute.sort_unstable();
        front.sort_unstable();
        assert_eq!(front, brute);
    }

    #[test]
    fn grid_specs_parse_or_name_the_problem() {
        let a = parse_grid("gi-rays=4, 16").expect("parses");
        assert_eq!(
            (a.key, a.name.as_str(), a.values),
            ("gi.rays", "gi-rays", vec!["4".into(), "16".into()])
        );
        // A key path and its flag's alias name the same key.
        assert_eq!(
            parse_grid("gi.vpl_pattern=2x2").map(|a| a.key).ok(),
            Some("gi.vpl_pattern")
        );
        assert_eq!(
            parse_grid("vpl-pattern=2x2").map(|a| a.key).ok(),
            Some("gi.vpl_pattern")
        );
        // Every grid key is a `[gi]` key.
        for (k, _) in GRID_KEYS {
            assert!(crate::scene::schema::key::<GiSettings>(k).is_some(), "{k}");
        }
        for (spec, says) in [
            ("gi-rays", "KEY=V1"),
            ("rays=4", "unknown key `rays`"),
            ("gi=vpl", "--methods"),
            ("gi.method=vpl", "--methods"),
            ("vpls=4,,8", "empty value"),
        ] {
            let e = parse_grid(spec).expect_err(spec).to_string();
            assert!(e.contains(spec) && e.contains(says), "{spec}: {e}");
        }
        assert!(parse_methods("vpl,none,vpl").is_ok_and(|m| m.len() == 2));
        let e = parse_methods("none,segi").expect_err("unknown").to_string();
        assert!(e.contains("segi"), "{e}");
    }

    #[test]
    fn grid_axes_apply_only_to_the_methods_they_change() {
        let grid = [
            parse_grid("gi-rays=4,16").expect("rays"),
            parse_grid("vpls=8,32").expect("vpls"),
            parse_grid("gi.accumulate_frames=1,4").expect("frames"),
        ];
        let c = configs(
            &[
                GiMethod::None,
                GiMethod::Hemisphere,
                GiMethod::Pathtrace,
                GiMethod::Vpl,
            ],
            &grid,
        );
        let count = |m| c.iter().filter(|c| c.method == m).count();
        // none: 1; hemisphere: rays 2; pathtrace: rays 2 × frames 2; vpl: vpls 2.
        assert_eq!(
            [
                GiMethod::None,
                GiMethod::Hemisphere,
                GiMethod::Pathtrace,
                GiMethod::Vpl
            ]
            .map(count),
            [1, 2, 4, 2]
        );
        let pt = c
            .iter()
            .find(|c| c.method == GiMethod::Pathtrace)
            .expect("pt");
        assert_eq!(pt.label(), "pathtrace gi-rays=4 gi.accumulate_frames=1");
        assert_eq!(
            pt.argv(),
            [
                "--gi",
                "pathtrace",
                "--set",
                "gi.rays=4",
                "--set",
                "gi.accumulate_frames=1"
            ]
        );
    }

    fn row(scene: &str, config: &str, ms: f64, rel_mse: f64) -> SweepRow {
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
            gi_toml: gi_inline(&GiSettings {
                method: GiMethod::Hemisphere,
                rays: (ms as u32).max(1),
                ..GiSettings::default()
            }),
            // One measured, one not settled, so the round trip sees numbers and empties.
            flicker: Some(0.0125),
            ghost: Some(0.5),
            lag_frames: None,
        }
    }

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
    /// its `[gi]` table and that table as scene-file overrides; a folder without a sweep is an
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

    #[test]
    fn the_tuned_table_is_a_scene_gi_table() {
        let settings = GiSettings {
            method: GiMethod::Vpl,
            rays: 8,
            radius_m: Some(0.1),
            bounces: crate::gi::Bounces::Unbounded,
            filter_radius: 3,
            vpl: crate::gi::vpl::VplSettings {
                per_set: 12,
                pattern: [2, 3],
                d_min_voxels: 0.3,
                visibility: crate::gi::vpl::VplVisibility::None,
                ..Default::default()
            },
            sao: Some(crate::gi::SaoSettings {
                radius_m: 0.6,
                contrast: 1.5,
                ..Default::default()
            }),
            ..GiSettings::default()
        };
        let r = SweepRow {
            gi_toml: gi_inline(&settings),
            ..row("cornell", "vpl", 1.0, 0.1)
        };
        let text = gi_table_text(&r).expect("prints");
        assert!(text.starts_with("[gi]\n"), "{text}");
        assert!(text.contains("radius_m = 0.1\n"), "{text}");
        assert!(text.contains("sao = true\nsao_bias = 0.04\n"), "{text}");
        // Pasted into a scene without `[gi]`, the table gives back every setting it holds.
        let base = include_str!("../../assets/scenes/cornell.toml");
        assert!(!base.contains("[gi]"));
        let scene = crate::scene::Scene::from_toml_str(
            &format!("{base}\n{text}"),
            Path::new("tuned.toml"),
            Path::new("assets/scenes"),
        )
        .expect("the scene with the tuned table loads");
        let back = crate::scene::resolve_gi(&scene.gi, &Default::default());
        assert_eq!(back, settings);
    }

    #[test]
    fn downsampling_averages_each_footprint() {
        let img = crate::eval::HdrImage {
            width: 4,
            height: 2,
            data: (0..8).map(|i| [i as f32, 1.0, 0.0]).collect(),
        };
        let d = downsample(&img, 2);
        // Footprints {0,1,4,5} and {2,3,6,7}: means 2.5 and 4.5.
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.data, vec![[2.5, 1.0, 0.0], [4.5, 1.0, 0.0]]);
    }

    #[test]
    fn the_plot_marks_the_front() {
        let rows = [
            row("cornell", "none", 1.0, 0.5),
            row("cornell", "hemisphere gi-rays=4", 4.0, 0.05),
            row("cornell", "hemisphere gi-rays=8", 8.0, 0.5),
        ];
        let refs: Vec<&SweepRow> = rows.iter().collect();
        let svg = pareto_svg("cornell <box>", &refs);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("cornell &lt;box&gt;"));
        // Two front points (bigger, outlined) and one beaten point.
        assert_eq!(svg.matches("r=\"5\"").count(), 2, "{svg}");
        assert_eq!(svg.matches("<title>").count(), 3);
    }

    #[test]
    fn the_bitmap_plot_draws_the_dots_where_the_svg_does() {
        let rows = [
            row("cornell", "none", 1.0, 0.5),
            row("cornell", "hemisphere gi-rays=4", 4.0, 0.05),
        ];
        let refs: Vec<&SweepRow> = rows.iter().collect();
        let img = pareto_png(&refs);
        assert_eq!(img.dimensions(), (640, 420));
        // Decades: ms 1e0..1e1, relMSE 1e-2..1e0 (decades()). The "none" dot at (1 ms, 0.5):
        // x = 70 + 0/1 * 420 = 70, y = 40 + 330 - (log10 0.5 + 2)/2 * 330 = 89.7.
        let none = img.get_pixel(70, 90);
        assert_eq!(*none, rgb(method_colour("none")));
        // The hemisphere dot at (4 ms, 0.05): x = 70 + log10 4 * 420 = 322.9,
        // y = 370 - (log10 0.05 + 2)/2 * 330 = 255.3.
        assert_eq!(*img.get_pixel(323, 255), rgb(method_colour("hemisphere")));
        // Both are on the front: a black ring around each, and white far from everything.
        assert_eq!(*img.get_pixel(323 + 5, 255), image::Rgb([0, 0, 0]));
        assert_eq!(*img.get_pixel(200, 100), image::Rgb([255, 255, 255]));
    }
}
