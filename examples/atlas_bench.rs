//! Atlas versus triangle voxelizer on lavapipe: per-voxelization GPU time at 64², 128², 256²
//! (D = 128) for the Cornell box and the bunny scene, and the thesis's claim that the atlas
//! cost follows the occupied voxels rather than the triangle count (a cube tessellated 1×
//! and 16×). Atlas times are the per-frame `voxelize_atlas` splat of rigid objects; the
//! one-time atlas packing (CPU) and `atlas_positions` + `atlas_points` (GPU) are listed
//! separately. Not a test; prints medians.
//!
//! `cargo run --release --example atlas_bench [-- REPS]`

use anyhow::Result;
use glam::Vec3;
use std::path::Path;
use std::time::Instant;
use voxgi::bench::tessellated_cube;
use voxgi::graph::run_once;
use voxgi::graph::RenderGraph;
use voxgi::scene::Scene;
use voxgi::stats::median;
use voxgi::vk::{Context, ContextDesc};
use voxgi::voxel::atlas::{build_atlas, texel_size_for_voxel, AtlasCache};
use voxgi::voxel::gpu::{
    add_voxelize_passes, column_bytes, ColumnBase, TriangleBuffer, VoxelPipelines,
};
use voxgi::voxel::gpu_atlas::{
    add_voxelize_atlas_pass, render_atlas_points, AtlasInstance, AtlasPipelines, AtlasScene,
};
use voxgi::voxel::VoxelGrid;

/// Median GPU ms of pass `name` over `reps` runs of the graph `build` declares.
fn time_pass(
    ctx: &Context,
    reps: usize,
    name: &str,
    build: &dyn Fn(&mut RenderGraph),
) -> Result<f64> {
    let mut ms = Vec::new();
    for _ in 0..reps {
        let mut g = RenderGraph::new();
        build(&mut g);
        let t = run_once(ctx, g)?;
        ms.push(t.iter().filter(|p| p.name == name).map(|p| p.gpu_ms).sum());
    }
    Ok(median(&ms))
}

fn main() -> Result<()> {
    let reps: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(7);
    let ctx = Context::new(&ContextDesc::default())?;
    let tri_pipes = VoxelPipelines::new(&ctx)?;
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
        "{:<13} {:>5} {:>9} {:>9} {:>8} {:>5} {:>5} {:>8} {:>9} {:>8} {:>9}",
        "scene",
        "res",
        "triangles",
        "points",
        "texels",
        "fill",
        "cells",
        "pack ms",
        "build ms",
        "tri ms",
        "atlas ms"
    );
    for (name, scene) in &scenes {
        let mut tris = voxgi::voxel::gpu::scene_triangles(scene, 0.0, false);
        tris.extend(voxgi::voxel::gpu::scene_triangles(scene, 0.0, true));
        let buf = TriangleBuffer::upload(&ctx, "triangles", &tris)?;
        let aabb = scene.aabb_at(0.0);
        let pad = Vec3::splat(0.01 * aabb.extent().max_element());
        for res in [64, 128, 256] {
            let grid = VoxelGrid::from_box(aabb.min - pad, aabb.max + pad, None, res, res, 1)?;
            let t0 = Instant::now();
            let mut cache = AtlasCache::default();
            let texel_m = texel_size_for_voxel(grid.voxel_size_m().min_element());
            let (mut texels, mut tri_area, mut cell_area) = (0u64, 0.0, 0.0);
            for o in &scene.objects {
                let m = &scene.meshes[o.mesh];
                let a = cache.get(
                    &m.name,
                    &m.positions,
                    &m.indices,
                    o.transform.scale,
                    texel_m,
                )?;
                let n = u64::from(a.width) * u64::from(a.height);
                texels += n;
                tri_area += a.area_efficiency() * n as f64;
                cell_area += a.cell_efficiency() * n as f64;
            }
            let pack_ms = t0.elapsed().as_secs_f64() * 1e3;
            let t1 = Instant::now();
            let atlas = AtlasScene::new(&ctx, scene, 0.0, &grid, &mut cache)?;
            let build_ms = t1.elapsed().as_secs_f64() * 1e3;
            let size = column_bytes(&grid);
            let tri_ms = time_pass(&ctx, reps, "voxelize_triangles", &|g| {
                let c = g.create_buffer("columns", size);
                add_voxelize_passes(g, &tri_pipes, &grid, c, ColumnBase::Clear, &[&buf]);
                g.mark_output(c);
            })?;
            let atlas_ms = time_pass(&ctx, reps, "voxelize_atlas", &|g| {
                let c = g.create_buffer("columns", size);
                add_voxelize_passes(g, &tri_pipes, &grid, c, ColumnBase::Clear, &[]);
                atlas.add_pass(g, &grid, c, true, true, None);
                g.mark_output(c);
            })?;
            println!(
                "{:<13} {:>5} {:>9} {:>9} {:>8} {:>5.2} {:>5.2} {:>8.1} {:>9.1} {:>8.3} {:>9.3}",
                name,
                format!("{res}²"),
                tris.len(),
                atlas.point_count(),
                texels,
                tri_area / texels as f64,
                cell_area / texels as f64,
                pack_ms,
                build_ms,
                tri_ms,
                atlas_ms
            );
        }
    }

    // Same surface, 1× and 16× the triangles, at 128².
    let pipes = AtlasPipelines::new(&ctx)?;
    println!("\ncube (same surface), 128²×128:");
    println!(
        "{:>6} {:>9} {:>9} {:>8} {:>5} {:>5} {:>9} {:>11}",
        "tess", "triangles", "points", "texels", "fill", "cells", "tri ms", "atlas ms"
    );
    let grid = VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, None, 128, 128, 1)?;
    let size = column_bytes(&grid);
    for n in [1, 4] {
        let (pos, idx) = tessellated_cube(n);
        let tris: Vec<[Vec3; 3]> = idx
            .chunks_exact(3)
            .map(|t| [0, 1, 2].map(|k| pos[t[k] as usize]))
            .collect();
        let buf = TriangleBuffer::upload(&ctx, "triangles", &tris)?;
        let texel_m = texel_size_for_voxel(grid.voxel_size_m().min_element());
        let atlas = build_atlas("cube", &pos, &idx, Vec3::ONE, texel_m)?;
        let points = render_atlas_points(&ctx, &pipes, &atlas, &pos, &idx)?;
        let tri_ms = time_pass(&ctx, reps, "voxelize_triangles", &|g| {
            let c = g.create_buffer("columns", size);
            add_voxelize_passes(g, &tri_pipes, &grid, c, ColumnBase::Clear, &[&buf]);
            g.mark_output(c);
        })?;
        let atlas_ms = time_pass(&ctx, reps, "voxelize_atlas", &|g| {
            let c = g.create_buffer("columns", size);
            add_voxelize_passes(g, &tri_pipes, &grid, c, ColumnBase::Clear, &[]);
            let inst = [AtlasInstance::rigid(&points, glam::Mat4::IDENTITY)];
            add_voxelize_atlas_pass(g, &pipes, &grid, c, &inst, None);
            g.mark_output(c);
        })?;
        println!(
            "{:>6} {:>9} {:>9} {:>8} {:>5.2} {:>5.2} {:>9.3} {:>11.3}",
            format!("{}×", n * n),
            tris.len(),
            points.count,
            atlas.width * atlas.height,
            atlas.area_efficiency(),
            atlas.cell_efficiency(),
            tri_ms,
            atlas_ms
        );
    }
    Ok(())
}
