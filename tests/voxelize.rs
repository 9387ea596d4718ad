//! The GPU triangle voxelizer and OR mip chain against the CPU reference, bit for bit: the
//! Cornell box, the bunny scene, and random triangle soups (degenerate, tiny, huge, off-grid),
//! with one and two depth layers and every depth axis. Validation is on; any message fails.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::graph::run_once;
use voxgi::graph::RenderGraph;
use voxgi::vk::Context;
use voxgi::voxel::coverage::{scene_coverage, Coverage};
use voxgi::voxel::gpu::{
    add_store_and_mip_passes, add_voxelize_passes, column_bytes, scene_triangles, voxelize_static,
    ColumnBase, GpuVoxelGrid, TriangleBuffer, VoxelPipelines, VOXELIZE_GROUP_SIZE,
};
use voxgi::voxel::voxelize::{voxelize_scene, voxelize_triangles};
use voxgi::voxel::{Axis, BitGrid, BitHierarchy, GridDesc, VoxelGrid};

/// Every level of the GPU hierarchy, cropped to the CPU sizes. Panics if the power-of-two
/// padding of the image holds any bit.
fn gpu_levels(
    ctx: &Context,
    grid: &VoxelGrid,
    static_tris: &[[Vec3; 3]],
    dynamic_tris: &[[Vec3; 3]],
) -> Vec<BitGrid> {
    gpu_levels_with(ctx, VOXELIZE_GROUP_SIZE, grid, static_tris, dynamic_tris)
}

/// [`gpu_levels`] with `group_size` invocations per triangle.
fn gpu_levels_with(
    ctx: &Context,
    group_size: u32,
    grid: &VoxelGrid,
    static_tris: &[[Vec3; 3]],
    dynamic_tris: &[[Vec3; 3]],
) -> Vec<BitGrid> {
    gpu_levels_covered(
        ctx,
        group_size,
        grid,
        (static_tris, &[]),
        (dynamic_tris, &[]),
    )
}

/// [`gpu_levels_with`] with each set's triangle coverage (opacity below 1).
fn gpu_levels_covered(
    ctx: &Context,
    group_size: u32,
    grid: &VoxelGrid,
    (static_tris, static_coverage): (&[[Vec3; 3]], &[Coverage]),
    (dynamic_tris, dynamic_coverage): (&[[Vec3; 3]], &[Coverage]),
) -> Vec<BitGrid> {
    let pipes = VoxelPipelines::with_group_size(ctx, group_size).expect("voxel pipelines");
    let voxels = GpuVoxelGrid::new(ctx, grid).expect("voxel image");
    let st = TriangleBuffer::upload_covered(ctx, "static triangles", static_tris, static_coverage)
        .expect("upload");
    let dy =
        TriangleBuffer::upload_covered(ctx, "dynamic triangles", dynamic_tris, dynamic_coverage)
            .expect("upload");
    // Static geometry voxelized once; the frame copies it and inserts the dynamic triangles.
    let static_columns = voxelize_static(ctx, &pipes, grid, &st).expect("static voxelization");

    let readback = common::VoxelReadback::new(ctx, grid, voxels.mip_levels());

    let mut g = RenderGraph::new();
    let image = voxels.import(&mut g);
    let columns = g.create_buffer("voxel column buffer", column_bytes(grid));
    add_voxelize_passes(
        &mut g,
        &pipes,
        grid,
        columns,
        ColumnBase::Copy(&static_columns),
        &[&dy],
    );
    add_store_and_mip_passes(&mut g, &pipes, &voxels, columns, image);
    readback.add_pass(&mut g, image);
    let timings = run_once(ctx, g).expect("voxel graph runs");
    let names: Vec<&str> = timings.iter().map(|t| t.name.as_str()).collect();
    assert!(names.contains(&"voxel_store"), "{names:?}");
    readback.levels(grid)
}

/// Voxel positions where two grids differ (at most `max`), and the total count.
fn diff(a: &BitGrid, b: &BitGrid, max: usize) -> (u64, Vec<(u32, u32, u32)>) {
    assert_eq!(a.dims(), b.dims());
    let (mut n, mut first) = (0, Vec::new());
    for y in 0..a.res_y() {
        for x in 0..a.res_x() {
            for k in 0..a.depth() {
                if a.get(x, y, k) != b.get(x, y, k) {
                    n += 1;
                    if first.len() < max {
                        first.push((x, y, k));
                    }
                }
            }
        }
    }
    (n, first)
}

/// GPU (static split from dynamic at `split`) == CPU, at every hierarchy level.
fn check(what: &str, grid: &VoxelGrid, tris: &[[Vec3; 3]], split: usize) {
    check_with(what, VOXELIZE_GROUP_SIZE, grid, tris, split);
}

/// [`check`] with `group_size` invocations per triangle.
fn check_with(what: &str, group_size: u32, grid: &VoxelGrid, tris: &[[Vec3; 3]], split: usize) {
    let ctx = common::context();
    let mut cpu = BitGrid::for_grid(grid);
    voxelize_triangles(grid, &mut cpu, tris).expect("cpu voxelization");
    let gpu = gpu_levels_with(&ctx, group_size, grid, &tris[..split], &tris[split..]);
    let (n, first) = diff(&gpu[0], &cpu, 8);
    assert_eq!(
        n,
        0,
        "{what}: {n} of {} reference voxels differ (GPU has {}), first at {first:?}",
        cpu.count_ones(),
        gpu[0].count_ones()
    );
    let h = BitHierarchy::build(cpu.clone());
    assert_eq!(gpu.len() as u32, h.level_count(), "{what}: mip count");
    for (l, level) in gpu.iter().enumerate() {
        assert!(
            level == h.level(l as u32),
            "{what}: mip level {l} differs from the CPU OR hierarchy"
        );
    }
    assert!(cpu.count_ones() > 0, "{what}: the test voxelizes something");
    common::assert_no_validation_messages(&ctx);
}

fn scene(path: &str) -> voxgi::scene::Scene {
    if path == "cornell" {
        return voxgi::scene::load_scene_arg(None).expect("built-in cornell");
    }
    voxgi::scene::Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
        .expect("scene loads")
}

fn check_scene(name: &str, layers: u32, max_res_xy: u32) {
    check_scene_with(name, VOXELIZE_GROUP_SIZE, layers, max_res_xy);
}

fn check_scene_with(name: &str, group_size: u32, layers: u32, max_res_xy: u32) {
    let s = scene(name);
    let aabb = s.aabb_at(0.0);
    let grid = VoxelGrid::around(
        aabb.min,
        aabb.max,
        &GridDesc {
            layers,
            max_res_xy,
            ..Default::default()
        },
    )
    .expect("grid");
    let mut tris = scene_triangles(&s, 0.0, false);
    let split = tris.len();
    tris.extend(scene_triangles(&s, 0.0, true));
    // Split the static objects in two so the copy-then-insert path is exercised too.
    check_with(
        &format!("{name} {}x{}x{}", grid.res_x(), grid.res_y(), grid.depth()),
        group_size,
        &grid,
        &tris,
        split / 2,
    );
}

/// Panes of opacity 0, 0.5 (one pane, and three overlapping) and none: the GPU voxelizer
/// takes the same coverage decisions as the CPU reference (`voxelize_scene` reads the
/// materials' opacity itself, the GPU gets `scene_coverage` with the triangles), a pane of
/// opacity 0 sets no voxel, and one of opacity 0.5 sets a fraction of its voxels.
#[test]
fn transparent_panes_gpu_equals_cpu() {
    let mut counts = Vec::new();
    for name in [
        "assets/scenes/cornell_ceiling_spot.toml",
        "assets/scenes/cornell_pane_clear.toml",
        "assets/scenes/cornell_pane.toml",
        "assets/scenes/transparency.toml",
    ] {
        let s = scene(name);
        let aabb = s.aabb_at(0.0);
        let desc = GridDesc {
            layers: 1,
            max_res_xy: 128,
            ..Default::default()
        };
        let grid = VoxelGrid::around(aabb.min, aabb.max, &desc).expect("grid");
        let mut cpu = BitGrid::for_grid(&grid);
        voxelize_scene(&grid, &mut cpu, &s, 0.0).expect("cpu voxelization");
        let tris = scene_triangles(&s, 0.0, false);
        let coverage = scene_coverage(&s, 0.0, false);
        assert_eq!(tris.len(), coverage.len());
        // The last object (a pane) as the dynamic set: both upload paths carry coverage.
        let split = tris.len() - 2;
        let ctx = common::context();
        let gpu = gpu_levels_covered(
            &ctx,
            VOXELIZE_GROUP_SIZE,
            &grid,
            (&tris[..split], &coverage[..split]),
            (&tris[split..], &coverage[split..]),
        );
        let (n, first) = diff(&gpu[0], &cpu, 8);
        assert_eq!(n, 0, "{name}: {n} voxels differ, first at {first:?}");
        common::assert_no_validation_messages(&ctx);
        counts.push(cpu.count_ones());
    }
    // The pane is 0.5 m square in a grid of 0.5488 / 128 m voxels (the box's height is its
    // shortest side, the depth axis): about (0.5 / 0.0043)² = 13,500 voxels when opaque.
    let (none, clear, half) = (counts[0], counts[1], counts[2]);
    assert_eq!(clear, none, "a pane of opacity 0 sets no voxel");
    let p = 1.0 - f64::from(Coverage::new("pane", 0.5).transparency);
    let pane = (half - none) as f64;
    assert!(
        pane > 0.8 * p * 13_000.0 && pane < 1.2 * p * 14_000.0,
        "{pane} pane voxels, p = {p}"
    );
}

#[test]
fn cornell_box_gpu_equals_cpu_one_layer() {
    check_scene("cornell", 1, 128);
}

#[test]
fn cornell_box_gpu_equals_cpu_two_layers() {
    check_scene("cornell", 2, 96);
}

#[test]
fn bunny_scene_gpu_equals_cpu_one_layer() {
    check_scene("assets/scenes/cornell_bunny.toml", 1, 100);
}

#[test]
fn bunny_scene_gpu_equals_cpu_two_layers() {
    check_scene("assets/scenes/cornell_bunny.toml", 2, 256);
}

// Lavapipe (llvmpipe's gallivm) ends every loop of a shader invocation once 65,535 loop
// iterations have run in it, all loops together (LP_MAX_TGSI_LOOP_ITERATIONS), silently. A
// triangle whose columns and depth range give one invocation more iterations than that lost
// its later columns: the bunny box's ceiling at group size 8 (10,082 voxels missing), and a
// steep triangle across a large grid even at the default group size. The voxelizer now splits
// such triangles over more workgroups.

#[test]
fn bunny_scene_two_layers_at_group_size_8() {
    check_scene_with("assets/scenes/cornell_bunny.toml", 8, 2, 256);
}

#[test]
fn steep_triangles_across_a_large_grid_at_every_group_size() {
    // Nearly parallel to the depth axis (no plane bound: every column walks all 256 depths)
    // and diagonal across 256x256 columns: 65,536 columns x 256 depths, far beyond one
    // invocation's 65,535 loop iterations at group size 64, let alone 8.
    let grid =
        VoxelGrid::from_box(Vec3::ZERO, Vec3::ONE, Some(Axis::Z), 256, 256, 2).expect("grid");
    let tris = vec![
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.02),
            Vec3::new(0.02, 0.0, 1.0),
        ],
        [
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 0.98),
            Vec3::new(0.97, 0.0, 0.0),
        ],
    ];
    for group_size in [VOXELIZE_GROUP_SIZE, 8, 1] {
        check_with(
            &format!("steep, group size {group_size}"),
            group_size,
            &grid,
            &tris,
            1,
        );
    }
}

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn point(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        lo + (hi - lo) * Vec3::new(self.next(), self.next(), self.next())
    }
}

/// Random triangles in world space around the box `[min, max]`: ordinary, on voxel
/// boundaries, degenerate (points, segments, slivers), tiny, huge and outside.
fn soup(rng: &mut Lcg, grid: &VoxelGrid, n: usize) -> Vec<[Vec3; 3]> {
    let (min, max) = (grid.world_min(), grid.world_max());
    let size = max - min;
    let voxel = grid.voxel_size_m().max_element();
    let (lo, hi) = (min - 0.2 * size, max + 0.2 * size);
    let mut out = Vec::new();
    for i in 0..n {
        let a = rng.point(lo, hi);
        let tri = match i % 9 {
            0 | 1 => [a, rng.point(lo, hi), rng.point(lo, hi)],
            // Small triangles of a few voxels.
            2 => [0; 3].map(|_| a + (rng.point(Vec3::ZERO, Vec3::ONE) - 0.5) * 3.0 * voxel),
            // Tiny: far below a voxel.
            3 => [0; 3].map(|_| a + (rng.point(Vec3::ZERO, Vec3::ONE) - 0.5) * 1e-4 * voxel),
            // A point and a segment.
            4 => [a, a, a],
            5 => {
                let b = rng.point(lo, hi);
                [a, b, 0.5 * (a + b)]
            }
            // A sliver.
            6 => {
                let b = rng.point(lo, hi);
                [a, b, 0.5 * (a + b) + Vec3::splat(1e-6 * voxel)]
            }
            // Huge, through the grid.
            7 => [0; 3].map(|_| a + (rng.point(Vec3::ZERO, Vec3::ONE) - 0.5) * 1e3 * size),
            // Vertices snapped to voxel corners (boundary planes).
            _ => [0; 3].map(|_| {
                let v = grid.world_to_voxel(rng.point(min, max)).round();
                grid.voxel_to_world(v)
            }),
        };
        out.push(tri);
    }
    out
}

#[test]
fn random_soups_gpu_equal_cpu() {
    let mut rng = Lcg(42);
    let cases = [
        (Axis::Z, 37, 53, 1),
        (Axis::X, 64, 16, 2),
        (Axis::Y, 5, 3, 1),
        (Axis::Z, 1, 1, 2),
    ];
    for (axis, rx, ry, layers) in cases {
        let grid = VoxelGrid::from_box(
            Vec3::new(-1.3, 0.2, 4.0),
            Vec3::new(0.9, 2.7, 5.1),
            Some(axis),
            rx,
            ry,
            layers,
        )
        .expect("grid");
        let tris = soup(&mut rng, &grid, 300);
        check(
            &format!("soup {axis:?} {rx}x{ry}x{}", grid.depth()),
            &grid,
            &tris,
            120,
        );
    }
}

#[test]
fn millimeter_and_kilometer_copies_voxelize_to_the_same_bits() {
    // The grid follows the scene's box, so a scaled copy of a scene lands on the same voxels:
    // the bunny box at 1/1024, 1e-3, 1e3 and 1024 times its size sets exactly the bits of the
    // unit-scale scene (measured: 0 of 81,382 voxels differ at every scale).
    let ctx = common::context();
    let s = scene("assets/scenes/cornell_bunny.toml");
    let base: Vec<[Vec3; 3]> = scene_triangles(&s, 0.0, false);
    let aabb = s.aabb_at(0.0);
    let bits_at = |scale: f32| {
        let grid = VoxelGrid::around(
            aabb.min * scale,
            aabb.max * scale,
            &GridDesc {
                max_res_xy: 128,
                ..Default::default()
            },
        )
        .expect("grid");
        let tris: Vec<[Vec3; 3]> = base.iter().map(|t| t.map(|v| v * scale)).collect();
        gpu_levels(&ctx, &grid, &tris, &[]).swap_remove(0)
    };
    let unit = bits_at(1.0);
    assert!(unit.count_ones() > 10_000);
    for scale in [1.0 / 1024.0, 1e-3, 1e3, 1024.0] {
        let (n, first) = diff(&unit, &bits_at(scale), 5);
        assert_eq!(n, 0, "scale {scale}: {n} voxels differ, e.g. {first:?}");
    }
    common::assert_no_validation_messages(&ctx);
}
