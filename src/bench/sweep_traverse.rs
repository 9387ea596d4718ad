//! The ray-test comparison of `voxgi sweep` (`DIR/traverse.csv`, the `traverse` array of
//! `sweep.json`): per scene, ray radius and ray test, what `voxgi bench traverse` measures
//! ([`super::bench_radius`]) as one row each — the hierarchical test at its default start
//! level, the exact voxel walk and 1-bit and 3-bit marching at each sample count
//! (Thiedemann 2010, §9.3.1, §6.4.1). Plain data without a GPU: the rows, their resume keys
//! and the hierarchical test's speed-up over the cheapest marching at ≥ 99% agreement.

use super::sweep::CsvRow;
use super::traverse::{fewest_samples_at_99, RadiusResult};
use serde::{Deserialize, Serialize};

/// One ray test at one radius on one scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TraverseRow {
    /// The scene's name, as the GI rows name it.
    pub scene: String,
    /// Ray length in the thesis's test-box units (radius_m = r / 6 × the scene's largest
    /// extent).
    pub radius_box_units: f32,
    /// The same in meters (the `f32` the rays used, as its shortest decimal).
    pub radius_m: f64,
    /// `voxgi bench traverse`'s name of the test: `hierarchical`, `dda` (the exact walk),
    /// `march1xN`, `march3xN`.
    pub test: String,
    /// Marching samples per ray; empty for the hierarchical test and the exact walk.
    pub samples: Option<u32>,
    /// The voxel grid, `XxYxD`.
    pub grid: String,
    /// Side of the CPU-traced G-buffer the rays start from, in pixels.
    pub gbuffer: u32,
    /// Camera-visible surface points the rays start from, and the rays (points × rays per
    /// point).
    pub points: u32,
    pub rays: u32,
    /// Timed runs (after one untimed warm-up run when more than 1).
    pub repeats: u32,
    /// GPU ms of the test's pass over all rays: median, fastest and slowest run.
    pub gpu_median_ms: f64,
    pub gpu_min_ms: f64,
    pub gpu_max_ms: f64,
    /// Median CPU ms of the process per run (on lavapipe the work itself); empty where not
    /// measured.
    pub cpu_ms: Option<f64>,
    /// Mean steps per ray (the hierarchical test's loop iterations, the walk's voxels, the
    /// marching samples taken).
    pub steps_per_ray: f64,
    /// Share of rays this test reports a hit on.
    pub hit_fraction: f64,
    /// Share of rays whose hit/miss equals the exact walk's (the ground truth).
    pub exact_agreement: f64,
    /// Share of rays whose hit/miss equals the hierarchical test's in the same run.
    pub hierarchical_agreement: f64,
    /// This test's GPU ms over the hierarchical test's in the same run: how many times
    /// faster the hierarchical test is (1 on its own row).
    pub speedup: f64,
    /// The same in CPU ms; empty where not measured.
    pub cpu_speedup: Option<f64>,
    pub device: String,
}

/// The CSV's columns, in [`TraverseRow`]'s field order.
pub const TRAVERSE_CSV_COLUMNS: [&str; 21] = [
    "scene",
    "radius_box_units",
    "radius_m",
    "test",
    "samples",
    "grid",
    "gbuffer",
    "points",
    "rays",
    "repeats",
    "gpu_median_ms",
    "gpu_min_ms",
    "gpu_max_ms",
    "cpu_ms",
    "steps_per_ray",
    "hit_fraction",
    "exact_agreement",
    "hierarchical_agreement",
    "speedup",
    "cpu_speedup",
    "device",
];

impl CsvRow for TraverseRow {
    const COLUMNS: &'static [&'static str] = &TRAVERSE_CSV_COLUMNS;
    const TEXT_COLUMNS: &'static [&'static str] = &["scene", "test", "grid", "device"];
    const OTHER_HEADER: &'static str =
        "the header is not this version's traverse.csv header: start a new --out, or move \
         traverse.csv away to measure the ray tests again";
}

/// The name of the marching test with `bits` bits (1 or 3) and `samples` samples, as
/// `voxgi bench traverse` names it.
pub fn march_test(bits: u32, samples: u32) -> String {
    format!("march{bits}x{samples}")
}

/// The tests of one radius in the order the benchmark casts them: the hierarchical test, the
/// exact walk, then 1-bit and 3-bit marching at each of `samples`.
pub fn traverse_tests(samples: &[u32]) -> Vec<String> {
    let mut tests = vec!["hierarchical".to_owned(), "dda".to_owned()];
    for bits in [1, 3] {
        tests.extend(samples.iter().map(|&s| march_test(bits, s)));
    }
    tests
}

/// What a measured radius is, besides its results.
pub struct RadiusContext<'a> {
    pub scene: &'a str,
    pub grid: [u32; 3],
    pub gbuffer: u32,
    pub points: usize,
    pub repeats: u32,
    pub device: &'a str,
}

/// The rows of one measured radius, one per test the benchmark cast.
pub fn traverse_rows(c: &RadiusContext<'_>, r: &RadiusResult) -> Vec<TraverseRow> {
    // The benchmark casts the hierarchical test first: the reference of its run.
    let hier = r.methods.first();
    let (hier_gpu, hier_cpu) = (
        hier.map_or(f64::NAN, |m| m.gpu_ms),
        hier.and_then(|m| m.cpu_ms),
    );
    r.methods
        .iter()
        .map(|m| TraverseRow {
            scene: c.scene.to_owned(),
            radius_box_units: r.radius_box_units,
            radius_m: format!("{}", r.radius_m)
                .parse()
                .unwrap_or(f64::from(r.radius_m)),
            test: m.method.clone(),
            samples: m.samples,
            grid: format!("{}x{}x{}", c.grid[0], c.grid[1], c.grid[2]),
            gbuffer: c.gbuffer,
            points: c.points as u32,
            rays: r.rays as u32,
            repeats: c.repeats,
            gpu_median_ms: m.gpu_ms,
            gpu_min_ms: m.gpu_ms_min,
            gpu_max_ms: m.gpu_ms_max,
            cpu_ms: m.cpu_ms,
            steps_per_ray: m.mean_steps,
            hit_fraction: m.hit_fraction,
            exact_agreement: m.exact_agreement,
            hierarchical_agreement: m.agreement,
            speedup: m.gpu_ms / hier_gpu.max(1e-9),
            cpu_speedup: m.cpu_ms.zip(hier_cpu).map(|(a, h)| a / h.max(1e-9)),
            device: c.device.to_owned(),
        })
        .collect()
}

/// The hierarchical test against the cheapest marching that matches it: per scene, radius
/// and bit depth, the fewest samples whose hit/miss agrees with the hierarchical test on at
/// least 99% of the rays, and how many times faster the hierarchical test is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MarchAt99 {
    pub scene: String,
    pub radius_box_units: f32,
    /// 1 or 3.
    pub bits: u32,
    /// `None` when no sample count tried reaches 99%.
    pub samples: Option<u32>,
    /// That marching's GPU ms over the hierarchical test's in its run.
    pub speedup: Option<f64>,
    /// The same in CPU ms.
    pub cpu_speedup: Option<f64>,
}

/// [`MarchAt99`] for every scene, radius and bit depth of `rows` (in the rows' order), by the
/// benchmark's rule ([`fewest_samples_at_99`]).
pub fn march_at_99(rows: &[TraverseRow]) -> Vec<MarchAt99> {
    let mut keys: Vec<(&str, f32)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.scene.as_str(), r.radius_box_units)) {
            keys.push((&r.scene, r.radius_box_units));
        }
    }
    let mut out = Vec::new();
    for (scene, radius) in keys {
        let of: Vec<&TraverseRow> = rows
            .iter()
            .filter(|r| r.scene == scene && r.radius_box_units == radius)
            .collect();
        for bits in [1, 3] {
            let prefix = format!("march{bits}x");
            let marching = || of.iter().filter(|r| r.test.starts_with(&prefix));
            // Each row's speed-up is against the hierarchical test of its own run, so the
            // hierarchical time is 1 in those units.
            let pick = fewest_samples_at_99(
                marching().filter_map(|r| Some((r.samples?, r.hierarchical_agreement, r.speedup))),
                1.0,
            );
            let row = pick.and_then(|(s, _)| marching().find(|r| r.samples == Some(s)));
            out.push(MarchAt99 {
                scene: scene.to_owned(),
                radius_box_units: radius,
                bits,
                samples: pick.map(|(s, _)| s),
                speedup: pick.map(|(_, x)| x),
                cpu_speedup: row.and_then(|r| r.cpu_speedup),
            });
        }
    }
    out
}

/// The tests of `wanted` that `rows` lack at `scene` and `radius` (box units).
pub fn missing_tests<'a>(
    rows: &[TraverseRow],
    scene: &str,
    radius: f32,
    wanted: &'a [String],
) -> Vec<&'a String> {
    wanted
        .iter()
        .filter(|t| {
            !rows
                .iter()
                .any(|r| r.scene == scene && r.radius_box_units == radius && &&r.test == t)
        })
        .collect()
}

/// The settings the rays of a row were made with, as the flags that give them.
pub fn settings_text(gbuffer: u32, rays_per_point: u32, repeats: u32) -> String {
    format!(
        "--traverse-gbuffer {gbuffer} --traverse-rays {rays_per_point} --traverse-repeats {repeats}"
    )
}

/// The first row of `rows` measured with other settings than these, as its settings' text:
/// a resumed sweep must not mix rows of different rays or run counts.
pub fn other_settings(
    rows: &[TraverseRow],
    gbuffer: u32,
    rays_per_point: u32,
    repeats: u32,
) -> Option<String> {
    rows.iter()
        .find(|r| {
            r.gbuffer != gbuffer
                || u64::from(r.rays) != u64::from(r.points) * u64::from(rays_per_point)
                || r.repeats != repeats
        })
        .map(|r| {
            let per_point = r.rays.checked_div(r.points).unwrap_or(0);
            settings_text(r.gbuffer, per_point, r.repeats)
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::MethodResult;

    fn method(name: &str, gpu_ms: f64, agreement: f64) -> MethodResult {
        MethodResult {
            method: name.into(),
            samples: name.split_once('x').and_then(|(_, s)| s.parse().ok()),
            gpu_ms,
            gpu_ms_min: gpu_ms * 0.9,
            gpu_ms_max: gpu_ms * 1.2,
            cpu_ms: Some(gpu_ms * 2.0),
            rays_per_s: 1000.0 / gpu_ms,
            mean_steps: 10.0,
            hit_fraction: 0.5,
            agreement,
            exact_agreement: agreement,
        }
    }

    fn radius() -> RadiusResult {
        RadiusResult {
            radius_box_units: 4.0,
            radius_m: 0.25,
            rays: 1000,
            hit_fraction: 0.5,
            methods: vec![
                method("hierarchical", 2.0, 1.0),
                method("dda", 4.0, 1.0),
                method("march1x8", 1.0, 0.9),
                method("march1x64", 5.0, 0.995),
                method("march3x8", 1.5, 0.97),
                method("march3x64", 7.0, 0.98),
            ],
            march_steps_for_99: Some(64),
            speedup_at_99: Some(2.5),
            march3_steps_for_99: None,
            march3_speedup_at_99: None,
        }
    }

    #[test]
    fn a_radius_becomes_one_row_per_test_with_speed_ups_against_its_hierarchical_run() {
        let c = RadiusContext {
            scene: "cornell",
            grid: [128, 128, 128],
            gbuffer: 16,
            points: 250,
            repeats: 3,
            device: "llvmpipe, 256 bits",
        };
        let rows = traverse_rows(&c, &radius());
        let tests: Vec<&str> = rows.iter().map(|r| r.test.as_str()).collect();
        assert_eq!(tests, traverse_tests(&[8, 64]));
        assert_eq!(rows[0].speedup, 1.0);
        assert_eq!(rows[3].speedup, 2.5); // 5 ms / 2 ms
        assert_eq!(rows[3].cpu_speedup, Some(2.5)); // 10 ms / 4 ms
        assert_eq!((rows[0].samples, rows[5].samples), (None, Some(64)));
        assert_eq!(rows[0].grid, "128x128x128");
        for r in &rows {
            assert_eq!(TraverseRow::from_csv_line(&r.csv_line()), Ok(r.clone()));
        }
        // The summary picks what the benchmark picked: 1-bit x 64 at 2.5x, no 3-bit count.
        let at = march_at_99(&rows);
        assert_eq!(at.len(), 2);
        assert_eq!(
            (at[0].bits, at[0].samples, at[0].speedup),
            (1, Some(64), Some(2.5))
        );
        assert_eq!((at[1].bits, at[1].samples, at[1].speedup), (3, None, None));
        // Resume: everything there; one more sample count is missing at both bit depths.
        let wanted = traverse_tests(&[8, 64]);
        assert!(missing_tests(&rows, "cornell", 4.0, &wanted).is_empty());
        let wanted = traverse_tests(&[8, 16, 64]);
        let missing = missing_tests(&rows, "cornell", 4.0, &wanted);
        assert_eq!(missing, [&wanted[3], &wanted[6]]);
        assert_eq!(missing_tests(&rows, "cornell", 2.0, &wanted).len(), 8);
        // 1000 rays from 250 points: 4 per point.
        assert_eq!(other_settings(&rows, 16, 4, 3), None);
        let other = other_settings(&rows, 16, 8, 3);
        assert_eq!(other.as_deref(), Some(settings_text(16, 4, 3).as_str()));
        assert!(other_settings(&rows, 32, 4, 3).is_some());
        assert!(other_settings(&rows, 16, 4, 1).is_some());
    }
}
