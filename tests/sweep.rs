//! `voxgi sweep` end to end at 32², and `voxgi tune` on what it wrote: the rows, their
//! survival across runs (`--resume`), the files, and the errors that name the bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn voxgi(args: &[&str]) -> Output {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("voxgi-xdg");
        let _ = std::fs::create_dir_all(&dir);
        std::env::set_var("XDG_RUNTIME_DIR", dir);
    }
    Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .args(args)
        .output()
        .expect("voxgi runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn sweep(dir: &Path, extra: &[&str]) -> Output {
    let dir = dir.to_string_lossy().into_owned();
    let mut args = vec![
        "--validate",
        "sweep",
        "cornell",
        "--size",
        "32",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--out",
        &dir,
    ];
    args.extend_from_slice(extra);
    voxgi(&args)
}

fn rows(dir: &Path) -> Vec<voxgi::bench::sweep::SweepRow> {
    voxgi::bench::sweep::read_csv(&dir.join("sweep.csv")).expect("the CSV reads back")
}

#[test]
fn a_sweep_writes_its_rows_resumes_and_feeds_tune() {
    let dir = out_dir("resume");
    let first = sweep(&dir, &["--methods", "none"]);
    assert!(first.status.success(), "{}", text(&first.stderr));
    assert_eq!(rows(&dir).len(), 1);
    // A second run into the same folder must say --resume, and then adds only the new row.
    let again = sweep(
        &dir,
        &["--methods", "none,hemisphere", "--grid", "gi-rays=2"],
    );
    assert!(!again.status.success());
    assert!(
        text(&again.stderr).contains("--resume"),
        "{}",
        text(&again.stderr)
    );
    let resumed = sweep(
        &dir,
        &[
            "--methods",
            "none,hemisphere",
            "--grid",
            "gi-rays=2",
            "--resume",
        ],
    );
    assert!(resumed.status.success(), "{}", text(&resumed.stderr));
    let r = rows(&dir);
    let configs: Vec<&str> = r.iter().map(|r| r.config.as_str()).collect();
    assert_eq!(configs, ["none", "hemisphere gi-rays=2"]);
    // Direct light alone misses the indirect light the reference has; hemisphere sampling
    // adds it (tests/gi.rs asserts the same at 256²).
    assert!(r[1].rel_mse < r[0].rel_mse, "{r:?}");
    for row in &r {
        assert!(row.frame_median_ms > 0.0 && row.image_ms >= row.frame_median_ms);
        assert!(row.frame_min_ms <= row.frame_median_ms && row.frame_median_ms <= row.frame_max_ms);
        assert!(row.gi_median_ms <= row.frame_median_ms && row.transient_bytes > 0);
        assert!((0.0..=1.0).contains(&row.flip) && (-1.0..=1.0).contains(&row.ssim));
        assert_eq!(row.size, 32);
    }
    assert_eq!(r[0].gi_median_ms, 0.0, "direct light runs no GI pass");
    assert!(r[1].gi_median_ms > 0.0);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep.json")).expect("json"))
            .expect("parses");
    assert_eq!(json.as_array().map(Vec::len), Some(2));
    let svg = std::fs::read_to_string(dir.join("cornell_pareto.svg")).expect("the plot");
    assert!(svg.starts_with("<svg") && svg.matches("<circle").count() >= 2);

    // tune: a budget between the two rows' times picks the faster; an ample one the more
    // accurate, printed as a `[gi]` table.
    let dir_s = dir.to_string_lossy().into_owned();
    let (fast, slow) = match r[0].image_ms < r[1].image_ms {
        true => (&r[0], &r[1]),
        false => (&r[1], &r[0]),
    };
    let tune = |budget: f64| {
        voxgi(&[
            "tune",
            "cornell",
            "--budget-ms",
            &budget.to_string(),
            "--from",
            &dir_s,
        ])
    };
    let ample = tune(slow.image_ms.max(fast.image_ms) * 2.0);
    assert!(ample.status.success(), "{}", text(&ample.stderr));
    let table = text(&ample.stdout);
    let parsed: toml::Table = toml::from_str(&table).expect("the output is TOML");
    assert_eq!(
        parsed["gi"]["method"].as_str(),
        Some("hemisphere"),
        "{table}"
    );
    assert_eq!(parsed["gi"]["rays"].as_integer(), Some(2), "{table}");
    if slow.image_ms > fast.image_ms {
        let tight = tune((fast.image_ms + slow.image_ms) / 2.0);
        let parsed: toml::Table = toml::from_str(&text(&tight.stdout)).expect("TOML");
        assert_eq!(parsed["gi"]["method"].as_str(), Some(fast.method.as_str()));
    }
    let none = tune(fast.image_ms / 4.0);
    assert!(!none.status.success());
    assert!(
        text(&none.stderr).contains("fastest"),
        "{}",
        text(&none.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_sweep_input_is_refused_before_any_row() {
    let dir = out_dir("errors");
    for (extra, says) in [
        (&["--grid", "gi-rays"][..], "KEY=V1"),
        (&["--grid", "rayz=2"], "unknown key `rayz`"),
        (
            &["--methods", "hemisphere", "--grid", "gi-rays=0"],
            "gi-rays=0",
        ),
        (&["--methods", "segi"], "--methods segi"),
    ] {
        let out = sweep(&dir, extra);
        let stderr = text(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(says),
            "{extra:?}: {stderr}"
        );
        assert!(!dir.join("sweep.csv").exists(), "{extra:?} wrote a CSV");
    }
    let dir_s = dir.to_string_lossy().into_owned();
    let out = voxgi(&["sweep", "cornell", "--size", "48", "--out", &dir_s]);
    assert!(
        text(&out.stderr).contains("--size 48"),
        "{}",
        text(&out.stderr)
    );
    // A scene without a reference says how to make one.
    let out = voxgi(&["sweep", "assets/scenes/cornell_mover.toml", "--out", &dir_s]);
    assert!(
        text(&out.stderr).contains("tools/reference"),
        "{}",
        text(&out.stderr)
    );
    assert!(!dir.exists(), "nothing written");
}
