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
use crate::scene::schema::{Key, Settings};
use crate::scene::{PostTable, ShadowSettings, VoxelSettings};
pub use crate::tune::{
    csv_header, gi_table_text, read_csv, read_rows, tables_text, tune, tune_from_dir, CsvAppender,
    CsvRow, SweepRow, CSV_COLUMNS,
};
use clap::ValueEnum;
use std::path::PathBuf;

/// Errors of the sweep's inputs and files, each naming what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("--grid {spec}: {reason}")]
    Grid { spec: String, reason: String },
    #[error("--methods {value}: unknown method; expected a comma-separated list of none, hemisphere, pathtrace, vpl")]
    Method { value: String },
    #[error("configuration `{config}`: {message}")]
    Flag { config: String, message: String },
    #[error("scene {scene}: no reference image {}; point --references at the folder that has it, render one with tools/reference (see assets/references/README.md) or leave the scene out", path.display())]
    NoReference { scene: String, path: PathBuf },
    #[error("--size {size}: the reference {} is {width}x{height}; --size, the renders' width, must divide its width so that the height scales by the same whole factor (e.g. 32, 64, 128 or 256 for a 256² reference, 32 or 64 for 320x180) or be a multiple of the width (512 for a 256² reference)", path.display())]
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
    #[error(transparent)]
    Reference(#[from] super::reference_cache::ReferenceError),
    #[error(transparent)]
    Tune(#[from] crate::tune::TuneError),
}

/// One `--grid KEY=V1,V2,…`: a `[gi]` key (one of the methods'
/// [`crate::gi::MethodSpec::sweep_keys`]) or any `[shadow]`, `[post]` or `[voxel]` key, and
/// the values it takes.
#[derive(Clone, Debug, PartialEq)]
pub struct GridAxis {
    /// The key path.
    pub key: &'static str,
    /// The key as the grid named it (its path or its flag's alias), for the configuration's
    /// label, so that a sweep resumed with the same `--grid` finds its rows.
    pub name: String,
    pub values: Vec<String>,
}

impl GridAxis {
    /// Whether the axis changes `method`'s renders: a `[gi]` key those methods whose spec
    /// lists it, a `[shadow]`, `[post]` or `[voxel]` key every method (direct light and tone
    /// mapping are in every image, and the emitters' direct light has voxel visibility).
    pub fn applies_to(&self, method: GiMethod) -> bool {
        !is_gi_key(self.key) || method.spec().sweep_keys.contains(&self.key)
    }
}

/// Whether `path` is a `[gi]` key path.
fn is_gi_key(path: &str) -> bool {
    path.split_once('.')
        .is_some_and(|(table, _)| table == GiSettings::TABLE)
}

/// The key of `S` that `name` names: its path or its flag without `--`.
fn named<S: Settings>(name: &str) -> Option<&'static Key<S>> {
    S::keys()
        .iter()
        .find(|k| k.path == name || k.flag.is_some_and(|f| f.long == name))
}

/// The grid key `name` names: one of the methods' `[gi]` sweep keys or any key of the
/// `[shadow]`, `[post]` and `[voxel]` schemas, by its path or its flag without `--`.
fn grid_key(name: &str) -> Option<&'static str> {
    named::<GiSettings>(name)
        .map(|k| k.path)
        .filter(|p| GiMethod::sweep_keys().contains(p))
        .or_else(|| named::<ShadowSettings>(name).map(|k| k.path))
        .or_else(|| named::<PostTable>(name).map(|k| k.path))
        .or_else(|| named::<VoxelSettings>(name).map(|k| k.path))
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
        let known = GiMethod::sweep_keys();
        err(format!(
            "unknown key `{name}`; expected one of {}, or a `[shadow]`, `[post]` or `[voxel]` key path \
             (`voxgi render --help` lists them under --set), or a flag's name (e.g. gi-rays, \
             direct-samples, bloom)",
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
    m.name().to_owned()
}

/// The `--methods` of `voxgi sweep` when none are given: those whose spec says
/// [`crate::gi::MethodSpec::swept_by_default`].
pub fn default_sweep_methods() -> String {
    let names: Vec<&str> = GiMethod::ALL
        .iter()
        .filter(|m| m.spec().swept_by_default)
        .map(|m| m.name())
        .collect();
    names.join(",")
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

/// Every method with the cartesian product of the grid axes that apply to it
/// ([`GridAxis::applies_to`]; a method no axis applies to is one configuration).
pub fn configs(methods: &[GiMethod], grid: &[GridAxis]) -> Vec<Config> {
    let mut out = Vec::new();
    for &method in methods {
        let axes: Vec<&GridAxis> = grid.iter().filter(|a| a.applies_to(method)).collect();
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

/// The resolved GI settings as a scene's `[gi]` table: every key of the schema
/// ([`GiSettings::keys`]; an unset ray length left out).
pub fn gi_table(s: &GiSettings) -> toml::Table {
    crate::scene::schema::table(s)
}

/// [`gi_table`] as a one-line inline table, for the CSV.
pub fn gi_inline(s: &GiSettings) -> String {
    toml::Value::Table(gi_table(s)).to_string()
}

/// The configuration's settings as the CSV's `gi_toml` column holds them: an inline TOML
/// document of scene tables, the resolved `[gi]` table and the `[shadow]`, `[post]` and `[voxel]` keys
/// the grid set (`{ gi = { … }, shadow = { direct_samples = 4 } }`), which `voxgi tune`
/// prints ([`tables_text`]).
pub fn settings_inline(gi: &GiSettings, config: &Config) -> String {
    let mut doc = toml::Table::new();
    doc.insert(GiSettings::TABLE.into(), toml::Value::Table(gi_table(gi)));
    for v in config.values.iter().filter(|v| !is_gi_key(v.key)) {
        let (Some((table, name)), Some(value)) = (v.key.split_once('.'), grid_toml(v)) else {
            continue;
        };
        if let Some(t) = doc
            .entry(table)
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
        {
            t.insert(name.to_owned(), value);
        }
    }
    toml::Value::Table(doc).to_string()
}

/// A `[shadow]`, `[post]` or `[voxel]` grid value as a scene file writes it. `None` for a value its key
/// does not read, which no row has: a configuration's values are parsed as its flags before
/// it is measured (`cli::sweep`'s `job`); and for an unset number, which a table leaves out.
fn grid_toml(v: &GridValue) -> Option<toml::Value> {
    fn of<S: Settings>(v: &GridValue) -> Option<toml::Value> {
        let k = crate::scene::schema::key::<S>(v.key)?;
        k.kind.to_toml(k.kind.parse(&v.value).ok()?)
    }
    of::<ShadowSettings>(v)
        .or_else(|| of::<PostTable>(v))
        .or_else(|| of::<VoxelSettings>(v))
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
        for k in GiMethod::sweep_keys() {
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

    use crate::tune::sample_row as row;

    #[test]
    fn every_shadow_and_post_key_is_a_grid_key_by_path_and_flag() {
        fn each<S: Settings>() -> usize {
            for k in S::keys() {
                let by_path = parse_grid(&format!("{}=1", k.path)).expect(k.path);
                assert_eq!((by_path.key, by_path.name.as_str()), (k.path, k.path));
                if let Some(f) = k.flag {
                    let by_flag = parse_grid(&format!("--{}=1", f.long)).expect(f.long);
                    assert_eq!((by_flag.key, by_flag.name.as_str()), (k.path, f.long));
                }
            }
            S::keys().len()
        }
        assert!(each::<ShadowSettings>() > 0 && each::<PostTable>() > 0);
        assert!(each::<VoxelSettings>() > 0);
        let e = parse_grid("shadow.direct_sample=1")
            .expect_err("no such key")
            .to_string();
        assert!(e.contains("unknown key `shadow.direct_sample`"), "{e}");
        // A `[gi]` key no method sweeps stays refused: its axis would multiply nothing.
        let unswept = GiSettings::keys()
            .iter()
            .find(|k| !GiMethod::sweep_keys().contains(&k.path) && k.path != "gi.method")
            .expect("a [gi] key outside the sweep keys");
        assert!(parse_grid(&format!("{}=1", unswept.path)).is_err());
    }

    #[test]
    fn shadow_and_post_axes_apply_to_every_method() {
        let grid = [
            parse_grid("gi-rays=4,16").expect("rays"),
            parse_grid("shadow.direct_samples=1,4").expect("direct"),
            parse_grid("tonemap=linear,filmic,drago").expect("tonemap"),
        ];
        let c = configs(&[GiMethod::None, GiMethod::Hemisphere], &grid);
        let count = |m| c.iter().filter(|c| c.method == m).count();
        // none: direct 2 × tonemap 3; hemisphere: rays 2 × direct 2 × tonemap 3.
        assert_eq!([GiMethod::None, GiMethod::Hemisphere].map(count), [6, 12]);
        assert!(grid[1].applies_to(GiMethod::None) && !grid[0].applies_to(GiMethod::None));
        let h = c
            .iter()
            .find(|c| c.method == GiMethod::Hemisphere)
            .expect("hemisphere");
        assert_eq!(
            h.label(),
            "hemisphere gi-rays=4 shadow.direct_samples=1 tonemap=linear"
        );
        assert_eq!(
            h.argv(),
            [
                "--gi",
                "hemisphere",
                "--set",
                "gi.rays=4",
                "--set",
                "shadow.direct_samples=1",
                "--set",
                "post.tonemap=linear"
            ]
        );
        // Every label differs, so a resumed sweep tells each configuration's row apart.
        let mut labels: Vec<String> = c.iter().map(Config::label).collect();
        labels.sort();
        labels.dedup();
        assert_eq!(labels.len(), c.len());
    }

    #[test]
    fn tune_prints_the_shadow_and_post_keys_of_the_configuration() {
        let grid = [
            parse_grid("direct-samples=4").expect("direct"),
            parse_grid("post.tonemap=drago").expect("tonemap"),
            parse_grid("bloom=0.25").expect("bloom"),
        ];
        let c = &configs(&[GiMethod::None], &grid)[0];
        let gi = GiSettings {
            method: GiMethod::None,
            ..GiSettings::default()
        };
        let r = SweepRow {
            gi_toml: settings_inline(&gi, c),
            ..row("cornell", &c.label(), 1.0, 0.1)
        };
        let text = tables_text(&r).expect("prints");
        assert!(text.starts_with("[gi]\n"), "{text}");
        assert!(
            text.contains("[post]\nbloom = 0.25\ntonemap = \"drago\"\n"),
            "{text}"
        );
        assert!(text.contains("[shadow]\ndirect_samples = 4\n"), "{text}");
        // The `[gi]` table alone is what the viewer applies.
        let gi_only = gi_table_text(&r).expect("gi");
        assert!(gi_only.starts_with("[gi]\n") && !gi_only.contains("[shadow]"));
        // Pasted into a scene, the tables give back the swept values.
        let base = include_str!("../../assets/scenes/cornell.toml");
        assert!(!base.contains("[gi]") && !base.contains("[shadow]") && !base.contains("[post]"));
        let scene = crate::scene::Scene::from_toml_str(
            &format!("{base}\n{text}"),
            std::path::Path::new("tuned.toml"),
            std::path::Path::new("assets/scenes"),
        )
        .expect("the scene with the tuned tables loads");
        let shadow: ShadowSettings = crate::scene::schema::resolve(&[&scene.shadow]);
        assert_eq!(shadow.direct_samples, 4);
        let post: PostTable = crate::scene::schema::resolve(&[&scene.post]);
        for (path, text) in [("post.tonemap", "drago"), ("post.bloom", "0.25")] {
            let k = crate::scene::schema::key::<PostTable>(path).expect(path);
            assert_eq!(Ok((k.get)(&post)), k.kind.parse(text), "{path}");
        }
        // An older sweep's column, the `[gi]` table alone, prints as before.
        let old = SweepRow {
            gi_toml: gi_inline(&gi),
            ..r.clone()
        };
        assert_eq!(tables_text(&old), gi_table_text(&r));
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
            std::path::Path::new("tuned.toml"),
            std::path::Path::new("assets/scenes"),
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
}
