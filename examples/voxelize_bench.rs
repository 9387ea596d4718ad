//! Voxelization GPU time versus x,y resolution (D = 128) and scene: the triangle voxelizer,
//! its column store and the OR mip chain, each timed by the render graph's timestamps.
//! Not a test; prints a table of medians.
//!
//! `cargo run --release --example voxelize_bench [-- REPS [GROUP_SIZES...]]`

use anyhow::Result;
use glam::Vec3;
use std::path::Path;
use voxgi::graph::run_once;
use voxgi::graph::RenderGraph;
use voxgi::scene::Scene;
use voxgi::stats::median;
use voxgi::vk::{Context, ContextDesc};
use voxgi::voxel::gpu::{
    add_store_and_mip_passes, add_voxelize_passes, column_bytes, scene_triangles, ColumnBase,
    GpuVoxelGrid, TriangleBuffer, VoxelPipelines, VOXELIZE_GROUP_SIZE,
};
use voxgi::voxel::VoxelGrid;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let reps: usize = args.first().map(|a| a.parse()).transpose()?.unwrap_or(9);
    let groups: Vec<u32> = if args.len() > 1 {
        args[1..]
            .iter()
            .map(|a| a.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![VOXELIZE_GROUP_SIZE]
    };
    let ctx = Context::new(&ContextDesc::default())?;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scenes = [
        ("cornell", voxgi::scene::load_scene_arg(None)?),
        (
            "bunny-in-box",
            Scene::load(root.join("assets/scenes/cornell_bunny.toml"))?,
        ),
    ];
    println!("device: {}", ctx.info.name);
    println!(
        "{:<13} {:>5} {:>6} {:>9} {:>12} {:>10} {:>10}",
        "scene", "group", "res", "triangles", "voxelize ms", "store ms", "mips ms"
    );
    for (name, scene) in &scenes {
        let mut tris = scene_triangles(scene, 0.0, false);
        tris.extend(scene_triangles(scene, 0.0, true));
        let aabb = scene.aabb_at(0.0);
        let pad = Vec3::splat(0.01 * aabb.extent().max_element());
        for &group in &groups {
            let pipes = VoxelPipelines::with_group_size(&ctx, group)?;
            let buf = TriangleBuffer::upload(&ctx, "triangles", &tris)?;
            for res in [64, 128, 256, 512] {
                let grid = VoxelGrid::from_box(aabb.min - pad, aabb.max + pad, None, res, res, 1)?;
                let voxels = GpuVoxelGrid::new(&ctx, &grid)?;
                let (mut vox, mut store, mut mips) = (Vec::new(), Vec::new(), Vec::new());
                for _ in 0..reps {
                    let mut g = RenderGraph::new();
                    let image = voxels.import(&mut g);
                    let columns = g.create_buffer("voxel column buffer", column_bytes(&grid));
                    add_voxelize_passes(&mut g, &pipes, &grid, columns, ColumnBase::Clear, &[&buf]);
                    add_store_and_mip_passes(&mut g, &pipes, &voxels, columns, image);
                    let t = run_once(&ctx, g)?;
                    let sum = |f: &dyn Fn(&str) -> bool| {
                        t.iter()
                            .filter(|p| f(&p.name))
                            .map(|p| p.gpu_ms)
                            .sum::<f64>()
                    };
                    vox.push(sum(&|n| n == "voxelize_triangles"));
                    store.push(sum(&|n| n == "voxel_store"));
                    mips.push(sum(&|n| n.starts_with("voxel_mip_")));
                }
                println!(
                    "{:<13} {:>5} {:>6} {:>9} {:>12.3} {:>10.3} {:>10.3}",
                    name,
                    group,
                    format!("{res}²"),
                    tris.len(),
                    median(&vox),
                    median(&store),
                    median(&mips)
                );
            }
        }
    }
    Ok(())
}
