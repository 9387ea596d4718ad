//! `tools/gpu-run --local` (the rehearsal of the prepared GPU run) runs every step on this
//! machine's Vulkan and writes its summary, so the script a lent GPU machine runs cannot rot:
//! a renamed flag, a removed command or an output the summary cannot read fails here first.
//! The scene lists are cut to Cornell (and the textured `cornell_pbr` for validation) to keep
//! the suite short; the steps are the device run's.

use std::path::Path;
use std::process::Command;

#[test]
fn the_gpu_run_rehearsal_runs_every_step_and_summarizes_them() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dest = std::env::temp_dir().join(format!("voxgi-gpu-run-{}", std::process::id()));
    let out = Command::new(root.join("tools/gpu-run"))
        .arg("--local")
        .arg(&dest)
        .env("VOXGI_BIN", env!("CARGO_BIN_EXE_voxgi"))
        .env(
            "GPU_RUN_VALIDATE_SCENES",
            "cornell assets/scenes/cornell_pbr.toml",
        )
        .env("GPU_RUN_PROFILE_SCENES", "cornell")
        .env("GPU_RUN_SWEEP_SCENES", "cornell")
        .env(
            "GPU_RUN_REAL_SCENES",
            "assets/scenes/cornell_original.toml:32",
        )
        .current_dir(root)
        .output()
        .expect("runs tools/gpu-run");
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "tools/gpu-run --local failed:\n{log}");

    // Every step ran (none skipped by the deadline) and exited 0.
    let steps = std::fs::read_to_string(dest.join("work/results/steps.tsv")).expect("steps.tsv");
    let rows: Vec<Vec<&str>> = steps.lines().map(|l| l.split('\t').collect()).collect();
    for name in [
        "devices",
        "validate_cornell_none",
        "validate_cornell_pbr_ssgi",
        "validate_cornell_hemisphere-temporal",
        "validate_cornell_pathtrace-temporal",
        "profile_cornell_none",
        "profile_cornell_ssgi",
        "profile_cornell_hemisphere-4",
        "profile_cornell_pathtrace-1x2",
        "profile_cornell_vpl-16",
        "profile_cornell_vpl-16-splat",
        "profile_cornell_stereo-multiview",
        "bench_traverse",
        "bench_ssgi",
        "bench_voxelize_sweep",
        "bench_voxelize",
        "sweep",
        "sweep_real_cornell_original",
    ] {
        let row = rows
            .iter()
            .find(|r| r[0] == name)
            .unwrap_or_else(|| panic!("step {name} missing:\n{steps}"));
        assert_eq!(row[1], "0", "step {name}:\n{steps}\n{log}");
    }

    // The summary read the profiles: a frame time for each configuration and the targets'
    // table, and the validation line counts all twelve renders (5 methods on 2 scenes, and
    // the two temporal methods on Cornell).
    let summary = std::fs::read_to_string(dest.join("summary.md")).expect("summary.md");
    assert!(summary.contains("12 of 12 renders"), "{summary}");
    for config in ["none", "ssgi", "hemisphere-4", "pathtrace-1x2", "vpl-16"] {
        let row = summary
            .lines()
            .find(|l| l.starts_with(&format!("| {config} | ")))
            .unwrap_or_else(|| panic!("no frame-time row for {config}:\n{summary}"));
        let ms: f64 = row
            .split('|')
            .nth(2)
            .unwrap()
            .trim()
            .parse()
            .unwrap_or(-1.0);
        assert!(ms > 0.0, "{config}: {row}");
    }
    assert!(summary.contains("## Targets"), "{summary}");
    assert!(dest.join("results.tar.gz").exists());
    let _ = std::fs::remove_dir_all(&dest);
}
