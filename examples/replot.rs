//! Redraws the Pareto plots of a finished sweep from its sweep.csv, without measuring again:
//! `cargo run --example replot -- docs/sweep` writes `<scene>_pareto.{svg,png}` next to the
//! CSV, as `voxgi sweep` does at the end of a run.

use anyhow::Context;
use std::path::PathBuf;
use voxgi::bench::plot::{pareto_png, pareto_svg};
use voxgi::tune::{read_csv, SweepRow};

fn main() -> anyhow::Result<()> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .context("usage: cargo run --example replot -- SWEEP_DIR")?,
    );
    let rows = read_csv(&dir.join("sweep.csv"))?;
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.sort_unstable();
    scenes.dedup();
    for scene in scenes {
        let of: Vec<&SweepRow> = rows.iter().filter(|r| r.scene == scene).collect();
        let svg = dir.join(format!("{scene}_pareto.svg"));
        std::fs::write(&svg, pareto_svg(scene, &of)?)
            .with_context(|| format!("writing {}", svg.display()))?;
        let png = dir.join(format!("{scene}_pareto.png"));
        pareto_png(scene, &of)?
            .save(&png)
            .with_context(|| format!("writing {}", png.display()))?;
        println!("{} and {}", svg.display(), png.display());
    }
    Ok(())
}
