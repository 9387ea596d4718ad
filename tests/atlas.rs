//! The atlas voxelizer (automatic atlases, `atlas_positions` → `atlas_points` →
//! `voxelize_atlas`) against the exact CPU triangle voxelizer on the Cornell box and the
//! bunny scene. Validation is on; any message fails.
//!
//! # What is asserted, and why
//! - **Precision** (atlas voxels that the CPU sets): every atlas sample is a point of a
//!   triangle, so its voxel touches the triangle and lies in the conservative CPU set; only
//!   f32 rounding of a sample that lies exactly on a voxel face can move it into the
//!   neighbour. Asserted: every atlas voxel is in the CPU set dilated by one voxel (3×3×3),
//!   and the undilated precision is ≥ 0.999.
//! - **Recall** (CPU voxels the atlas sets): point samples cannot reach voxels the surface
//!   only grazes (the reference counts touching boxes, `voxelize.rs`). With texels of half a
//!   voxel (`atlas::texel_size_for_voxel`, ε ≈ 0.35 voxel) the measured recall is
//!   0.985–0.992 (Cornell 128³ 0.9852, 256²×128 0.9907, 256²×256 0.9858; bunny 128³ 0.9899,
//!   256²×128 0.9916; printed
//!   by the tests). Asserted: issue 4's bound [`MIN_RECALL`] = 0.97.

mod common;

use glam::Vec3;
use std::path::Path;
use voxgi::graph::{readback_buffer, run_once};
use voxgi::graph::{Access, RenderGraph};
use voxgi::vk::Context;
use voxgi::voxel::atlas::AtlasCache;
use voxgi::voxel::gpu::{
    add_voxelize_passes, column_bytes, image_extent, scene_triangles, ColumnBase, VoxelPipelines,
};
use voxgi::voxel::gpu_atlas::{device_chunk_bytes, AtlasScene};
use voxgi::voxel::voxelize::voxelize_triangles;
use voxgi::voxel::{BitGrid, GridDesc, VoxelGrid};

/// Lower bound on recall against the conservative CPU set (see the module doc).
const MIN_RECALL: f64 = 0.97;

fn scene(path: &str) -> voxgi::scene::Scene {
    if path == "cornell" {
        return voxgi::scene::load_scene_arg(None).expect("built-in cornell");
    }
    voxgi::scene::Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join(path))
        .expect("scene loads")
}

/// The atlas voxelization of `s` at time 0, read back from the column buffer.
fn atlas_bits(ctx: &Context, grid: &VoxelGrid, s: &voxgi::scene::Scene) -> (BitGrid, u64) {
    let (bits, points, _) = atlas_bits_chunked(ctx, grid, s, device_chunk_bytes(ctx));
    (bits, points)
}

/// [`atlas_bits`] with point-list chunks of at most `chunk_bytes`; also returns how many
/// chunks the lists took.
fn atlas_bits_chunked(
    ctx: &Context,
    grid: &VoxelGrid,
    s: &voxgi::scene::Scene,
    chunk_bytes: u64,
) -> (BitGrid, u64, usize) {
    let tri_pipes = VoxelPipelines::new(ctx).expect("voxel pipelines");
    let mut cache = AtlasCache::default();
    let atlas =
        AtlasScene::new_chunked(ctx, s, 0.0, grid, &mut cache, chunk_bytes).expect("atlas scene");
    for list in atlas.lists() {
        let counted: u64 = list.chunks.iter().map(|c| u64::from(c.count)).sum();
        assert_eq!(counted, list.count, "the chunks hold the whole list");
        for c in &list.chunks {
            assert!(
                u64::from(c.count) * 16 <= chunk_bytes,
                "a chunk over the limit"
            );
        }
    }
    let size = column_bytes(grid);
    let readback = readback_buffer(ctx, "atlas voxels readback", size).expect("readback");
    let mut g = RenderGraph::new();
    let columns = g.create_buffer("voxel column buffer", size);
    add_voxelize_passes(&mut g, &tri_pipes, grid, columns, ColumnBase::Clear, &[]);
    atlas.add_pass(&mut g, grid, columns, true, true, None);
    let out = g.import_buffer(&readback, Access::HostRead);
    g.add_pass("atlas_readback")
        .read(columns, Access::TransferRead)
        .write(out, Access::TransferWrite)
        .record(move |ctx| {
            ctx.cmd
                .copy_buffer(ctx.buffer(columns).raw, ctx.buffer(out).raw, size)
        });
    let timings = run_once(ctx, g).expect("atlas graph runs");
    assert!(timings.iter().any(|t| t.name == "voxelize_atlas"));
    let (w, h) = image_extent(grid);
    let full = BitGrid::from_gpu_bytes(
        w,
        h,
        grid.layers(),
        &readback.mapped().expect("host-visible")[..size as usize],
    )
    .expect("read-back size");
    let mut bits = BitGrid::for_grid(grid);
    for layer in 0..grid.layers() {
        for y in 0..grid.res_y() {
            for x in 0..grid.res_x() {
                *bits.column_mut(x, y, layer) = full.column(x, y, layer);
            }
        }
    }
    let points = atlas.point_count();
    let chunks = atlas.lists().iter().map(|l| l.chunks.len()).sum();
    (bits, points, chunks)
}

/// The albedo and normal volumes (`RGBA8` and `RGBA8_SNORM` bytes) that
/// `voxelize_atlas_volumes` + `voxelize_atlas_resolve` write for `s` at time 0, with
/// point-list chunks of at most `chunk_bytes`.
fn atlas_volumes_chunked(
    ctx: &Context,
    grid: &VoxelGrid,
    s: &voxgi::scene::Scene,
    chunk_bytes: u64,
) -> [Vec<u8>; 2] {
    use voxgi::voxel::gpu_atlas_volumes::{AtlasVolumes, AttributeVolumes};
    let mut cache = AtlasCache::default();
    let atlas =
        AtlasScene::new_chunked(ctx, s, 0.0, grid, &mut cache, chunk_bytes).expect("atlas scene");
    let splat =
        AtlasVolumes::new(ctx, &atlas, s, grid, false, Default::default()).expect("atlas volumes");
    let volumes = AttributeVolumes::new(ctx, grid).expect("attribute volumes");
    let ext = grid.extent_voxels();
    let size = u64::from(ext.x * ext.y * ext.z) * 4;
    let outs = [
        readback_buffer(ctx, "albedo readback", size).expect("readback"),
        readback_buffer(ctx, "normal readback", size).expect("readback"),
    ];
    let mut g = RenderGraph::new();
    let (albedo, normal) = volumes.import(&mut g);
    let handles = voxgi::voxel::attributes::AttributeHandles {
        albedo,
        normal,
        emission: None,
        material: None,
    };
    splat.add_passes(&mut g, (&atlas, grid), &handles, true, None);
    let out = outs
        .each_ref()
        .map(|b| g.import_buffer(b, Access::HostRead));
    g.add_pass("volume_readback")
        .read(albedo, Access::TransferRead)
        .read(normal, Access::TransferRead)
        .write(out[0], Access::TransferWrite)
        .write(out[1], Access::TransferWrite)
        .record(move |ctx| {
            let extent = voxgi::vk::vk::Extent3D {
                width: ext.x,
                height: ext.y,
                depth: ext.z,
            };
            for (img, buf) in [(albedo, out[0]), (normal, out[1])] {
                ctx.cmd
                    .copy_image_to_buffer(ctx.image(img).raw, extent, 0, 1, ctx.buffer(buf).raw);
            }
        });
    let timings = run_once(ctx, g).expect("volume graph runs");
    assert!(timings.iter().any(|t| t.name == "voxelize_atlas_volumes"));
    let bytes = outs
        .each_ref()
        .map(|b| b.mapped().expect("host-visible")[..size as usize].to_vec());
    bytes
}

/// `(recall, precision, precision against the CPU set dilated by one voxel)`.
fn compare(cpu: &BitGrid, gpu: &BitGrid) -> (f64, f64, f64) {
    let (rx, ry, d) = (cpu.res_x(), cpu.res_y(), cpu.depth());
    let (mut both, mut near) = (0u64, 0u64);
    for k in 0..d {
        for y in 0..ry {
            for x in 0..rx {
                if !gpu.get(x, y, k) {
                    continue;
                }
                if cpu.get(x, y, k) {
                    both += 1;
                    near += 1;
                    continue;
                }
                let mut found = false;
                for (dx, dy, dk) in itertools_product() {
                    let (nx, ny, nk) = (x as i64 + dx, y as i64 + dy, k as i64 + dk);
                    if nx >= 0
                        && ny >= 0
                        && nk >= 0
                        && cpu.contains(nx as u32, ny as u32, nk as u32)
                        && cpu.get(nx as u32, ny as u32, nk as u32)
                    {
                        found = true;
                    }
                }
                near += u64::from(found);
            }
        }
    }
    let n_gpu = gpu.count_ones().max(1) as f64;
    (
        both as f64 / cpu.count_ones().max(1) as f64,
        both as f64 / n_gpu,
        near as f64 / n_gpu,
    )
}

fn itertools_product() -> impl Iterator<Item = (i64, i64, i64)> {
    (-1..=1).flat_map(|a| (-1..=1).flat_map(move |b| (-1..=1).map(move |c| (a, b, c))))
}

/// Near-cubic voxels, at most `max_res_xy` columns a side.
fn check(name: &str, max_res_xy: u32, layers: u32) {
    let aabb = scene(name).aabb_at(0.0);
    let desc = GridDesc {
        layers,
        max_res_xy,
        ..Default::default()
    };
    check_grid(
        name,
        &VoxelGrid::around(aabb.min, aabb.max, &desc).expect("grid"),
    );
}

/// `res`² columns of 128 voxels (flat voxels), as in the 256²×128.
fn check_flat(name: &str, res: u32) {
    let aabb = scene(name).aabb_at(0.0);
    let pad = Vec3::splat(0.01 * aabb.extent().max_element());
    let grid =
        VoxelGrid::from_box(aabb.min - pad, aabb.max + pad, None, res, res, 1).expect("grid");
    check_grid(name, &grid);
}

fn check_grid(name: &str, grid: &VoxelGrid) {
    let ctx = common::context();
    let s = scene(name);
    let grid = *grid;
    let mut tris: Vec<[Vec3; 3]> = scene_triangles(&s, 0.0, false);
    tris.extend(scene_triangles(&s, 0.0, true));
    let mut cpu = BitGrid::for_grid(&grid);
    voxelize_triangles(&grid, &mut cpu, &tris).expect("cpu voxelization");
    let (gpu, points) = atlas_bits(&ctx, &grid, &s);
    let (recall, precision, near) = compare(&cpu, &gpu);
    println!(
        "{name} {}x{}x{}: {} triangles, {points} points, cpu {} voxels, atlas {} voxels, \
         recall {recall:.4}, precision {precision:.5}, precision (dilated) {near:.5}",
        grid.res_x(),
        grid.res_y(),
        grid.depth(),
        tris.len(),
        cpu.count_ones(),
        gpu.count_ones(),
    );
    assert_eq!(
        near, 1.0,
        "an atlas voxel is farther than one voxel from the surface"
    );
    assert!(precision >= 0.999, "precision {precision}");
    assert!(recall >= MIN_RECALL, "recall {recall} < {MIN_RECALL}");
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn cornell_box_atlas_vs_cpu_128() {
    check("cornell", 128, 1);
}

/// Point lists and `atlas_points` scratch past the device's storage-buffer range (at 512²:
/// Cornell's scratch, the dense-bunnies list) are split into chunks; here 256 KiB chunks
/// (and 256 KiB scratch bands) stand in for the limit at 128³, where one chunk holds each
/// list. The chunked lists set exactly the same bits (`voxelize_atlas`, a dispatch per
/// chunk) and write exactly the same volumes (`voxelize_atlas_volumes`, a draw per chunk,
/// blending in the same order).
#[test]
fn chunked_point_lists_voxelize_like_whole_ones_on_the_cornell_box() {
    const CHUNK_BYTES: u64 = 1 << 18;
    let ctx = common::context();
    let s = scene("cornell");
    let aabb = s.aabb_at(0.0);
    let desc = GridDesc {
        layers: 1,
        max_res_xy: 128,
        ..Default::default()
    };
    let grid = VoxelGrid::around(aabb.min, aabb.max, &desc).expect("grid");
    let (whole, points, whole_chunks) =
        atlas_bits_chunked(&ctx, &grid, &s, device_chunk_bytes(&ctx));
    let (chunked, chunked_points, chunks) = atlas_bits_chunked(&ctx, &grid, &s, CHUNK_BYTES);
    println!(
        "cornell 128: {points} points, {whole_chunks} chunks at the device limit, {chunks} \
         of {CHUNK_BYTES} bytes; {} voxels",
        whole.count_ones()
    );
    assert_eq!(chunked_points, points, "chunking loses no point");
    assert!(
        chunks as u64 >= points * 16 / CHUNK_BYTES,
        "{chunks} chunks for {points} points"
    );
    assert!(chunks > whole_chunks, "the small limit splits the lists");
    assert!(whole.count_ones() > 10_000, "{} voxels", whole.count_ones());
    assert!(
        whole == chunked,
        "chunked bits differ from the whole lists'"
    );

    let [albedo, normal] = atlas_volumes_chunked(&ctx, &grid, &s, device_chunk_bytes(&ctx));
    let [c_albedo, c_normal] = atlas_volumes_chunked(&ctx, &grid, &s, CHUNK_BYTES);
    let occupied = albedo.chunks_exact(4).filter(|t| t[3] == 255).count();
    assert!(occupied > 10_000, "{occupied} voxels with albedo");
    let differ = |a: &[u8], b: &[u8]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    assert_eq!(differ(&albedo, &c_albedo), 0, "chunked albedo differs");
    assert_eq!(differ(&normal, &c_normal), 0, "chunked normals differ");

    // The raster bit pass (`voxelize_atlas_bits`, a draw per chunk) against the compute
    // one, both chunked: with the equality above, it too matches the whole lists.
    use voxgi::bench::{bench_voxelize_atlas_chunked, VoxelizeBenchDesc};
    let desc = VoxelizeBenchDesc {
        resolution: 128,
        layers: 1,
        repeats: 1,
    };
    let r = bench_voxelize_atlas_chunked(&ctx, &s, &desc, CHUNK_BYTES).expect("bench runs");
    assert_eq!(r.voxels, whole.count_ones(), "raster bench grid differs");
    assert_eq!(
        r.differing_words, 0,
        "chunked raster and compute bits differ"
    );
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn bunny_scene_atlas_vs_cpu_128() {
    check("assets/scenes/cornell_bunny.toml", 128, 1);
}

#[test]
fn cornell_box_atlas_vs_cpu_256x256x128() {
    check_flat("cornell", 256);
}

#[test]
fn cornell_box_atlas_vs_cpu_256_two_layers() {
    check("cornell", 256, 2);
}

#[test]
fn bunny_scene_atlas_vs_cpu_256x256x128() {
    check_flat("assets/scenes/cornell_bunny.toml", 256);
}

/// The renderer's `VoxelFrame` with `--voxelizer atlas`: static walls voxelized once, the
/// rigid mover's atlas points transformed per frame; each frame's mip 0 against the CPU.
#[test]
fn voxel_frame_atlas_follows_a_moving_object() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let s = common::animated_scene();
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        ..Default::default()
    };
    let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
    assert!(frame.has_frame_passes());
    let grid = frame.voxels.grid;
    let (w, h) = image_extent(&grid);
    let size = column_bytes(&grid);
    let readback = readback_buffer(&ctx, "voxel readback", size).expect("readback");
    for t in [0.0, 0.5, 1.0] {
        assert!(frame.update(t, 0).expect("update"), "the mover moved");
        let mut g = RenderGraph::new();
        let image = frame.add_passes(&mut g);
        let out = g.import_buffer(&readback, Access::HostRead);
        g.add_pass("voxel_readback")
            .read(image, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(move |ctx| {
                let extent = voxgi::vk::vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                };
                ctx.cmd.copy_image_to_buffer(
                    ctx.image(image).raw,
                    extent,
                    0,
                    1,
                    ctx.buffer(out).raw,
                )
            });
        let timings = run_once(&ctx, g).expect("frame runs");
        let names: Vec<_> = timings.iter().map(|t| t.name.as_str()).collect();
        assert!(names.contains(&"voxel_copy_static"), "{names:?}");
        assert!(names.contains(&"voxelize_atlas"), "{names:?}");
        assert!(!names.contains(&"voxelize_triangles"), "{names:?}");
        let full = BitGrid::from_gpu_bytes(
            w,
            h,
            1,
            &readback.mapped().expect("mapped")[..size as usize],
        )
        .expect("size");
        let mut gpu = BitGrid::for_grid(&grid);
        for y in 0..grid.res_y() {
            for x in 0..grid.res_x() {
                *gpu.column_mut(x, y, 0) = full.column(x, y, 0);
            }
        }
        let mut cpu = BitGrid::for_grid(&grid);
        voxgi::voxel::voxelize_scene(&grid, &mut cpu, &s, t).expect("cpu");
        let (recall, precision, near) = compare(&cpu, &gpu);
        println!("t = {t}: recall {recall:.4}, precision {precision:.5}");
        assert_eq!(near, 1.0);
        assert!(recall >= MIN_RECALL, "t = {t}: recall {recall}");
    }
    // Nothing moves after t = 1: no re-voxelization.
    assert!(!frame.update(1.0, 0).expect("update"));
    assert!(!frame.update(2.0, 0).expect("update"));
    common::assert_no_validation_messages(&ctx);
}

#[test]
fn profile_lists_the_one_time_atlas_passes_apart_from_the_frame() {
    // Three objects, three atlases, each rendered and compacted once by a one-time submit
    // before the first frame; the frames never run them.
    let ctx = common::context();
    let s = scene("cornell");
    let settings = voxgi::render::RenderSettings {
        width: 64,
        height: 64,
        voxels: Some(voxgi::voxel::gpu::VoxelSettings {
            max_res_xy: 64,
            voxelizer: voxgi::voxel::gpu::Voxelizer::Atlas,
            ..Default::default()
        }),
        ..Default::default()
    };
    let run = voxgi::render::profile_scene(&ctx, &s, &settings, 2, 1).expect("profiles");
    common::assert_no_validation_messages(&ctx);
    let runs = |name: &str| run.setup.iter().filter(|t| t.name == name).count();
    assert_eq!(runs("atlas_positions"), 3, "{:?}", run.setup);
    assert_eq!(runs("atlas_points"), 3);
    // Nothing moves: the static grid is voxelized once too.
    assert_eq!(runs("voxelize_atlas"), 1);
    assert!(run
        .setup
        .iter()
        .all(|t| t.gpu_ms.is_finite() && t.gpu_ms >= 0.0));
    assert!(!run.frames.is_empty());
    for frame in &run.frames {
        for t in frame {
            assert!(
                !t.name.starts_with("atlas_") && t.name != "voxelize_atlas",
                "{} runs per frame",
                t.name
            );
        }
    }
    let report = voxgi::profile::ProfileReport::from_frames("lavapipe", &run.frames, 1)
        .with_setup(&run.setup);
    let table = report.table();
    let section = table.find("setup (once").expect("a setup section");
    let positions = table
        .find("atlas_positions")
        .expect("atlas_positions listed");
    assert!(positions > section, "{table}");
    let row = table.lines().find(|l| l.starts_with("atlas_positions"));
    assert!(row.is_some_and(|r| r.trim_end().ends_with('3')), "{table}");
}

#[test]
fn voxelize_bench_prints_every_scene_resolution_and_tessellation() {
    let ctx = common::context();
    let desc = voxgi::bench::VoxelizeSweepDesc {
        reps: 1,
        resolutions: vec![16, 24],
        tessellations: vec![1, 4],
    };
    let report = voxgi::bench::bench_voxelize_sweep(&ctx, &desc).expect("bench runs");
    common::assert_no_validation_messages(&ctx);
    let names: Vec<(&str, u32)> = report
        .rows
        .iter()
        .map(|r| (r.scene.as_str(), r.resolution))
        .collect();
    assert_eq!(
        names,
        [
            ("cornell", 16),
            ("cornell", 24),
            ("bunny-in-box", 16),
            ("bunny-in-box", 24),
            ("dense-bunnies", 16),
            ("dense-bunnies", 24),
            ("cube 1x", 128),
            ("cube 16x", 128),
        ]
    );
    for r in &report.rows {
        let a = r.atlas.as_ref().expect("small atlases fit every device");
        assert!(r.voxels > 0 && a.points > 0 && r.triangle_ms > 0.0, "{r:?}");
    }
    // The same surface sets the same voxels however it is tessellated, and the atlas splats
    // about as many points (its cost follows the surface, not the triangles).
    let (c1, c16) = (&report.rows[6], &report.rows[7]);
    assert_eq!(c16.triangles, 16 * c1.triangles);
    assert_eq!(c1.voxels, c16.voxels);
    let points = |r: &voxgi::bench::VoxelizeSweepRow| r.atlas.as_ref().map_or(0, |a| a.points);
    let ratio = points(c16) as f64 / points(c1) as f64;
    assert!((0.8..1.25).contains(&ratio), "points 16x / 1x = {ratio}");
    let table = report.table();
    for (scene, res) in names {
        let row = format!("{scene:<14} {:>5}", format!("{res}²"));
        assert!(table.contains(&row), "no row {row:?}:\n{table}");
    }
    assert!(table.contains("atlas/tri"), "{table}");
}

/// The voxel frame's bits (mip 0) and attribute volumes after one frame in slot 0.
struct Volumes {
    bits: BitGrid,
    albedo: Vec<[u8; 4]>,
    normal: Vec<[i8; 4]>,
}

fn run_volume_frame(
    ctx: &Context,
    frame: &voxgi::voxel::frame::VoxelFrame,
    volumes: &voxgi::voxel::gpu_atlas_volumes::AttributeVolumes,
) -> (Volumes, Vec<String>) {
    let grid = frame.voxels.grid;
    let ext = grid.extent_voxels();
    let size = u64::from(ext.x * ext.y * ext.z) * 4;
    let bits = common::VoxelReadback::new(ctx, &grid, 1);
    let outs = [
        readback_buffer(ctx, "albedo readback", size).expect("readback"),
        readback_buffer(ctx, "normal readback", size).expect("readback"),
    ];
    let mut g = RenderGraph::new();
    let image = frame.add_passes(&mut g);
    let (albedo, normal) = volumes.import(&mut g);
    let handles = voxgi::voxel::attributes::AttributeHandles {
        albedo,
        normal,
        emission: None,
        material: None,
    };
    frame.add_attribute_passes(&mut g, &handles);
    bits.add_pass(&mut g, image);
    let out = outs
        .each_ref()
        .map(|b| g.import_buffer(b, Access::HostRead));
    g.add_pass("volume_readback")
        .read(albedo, Access::TransferRead)
        .read(normal, Access::TransferRead)
        .write(out[0], Access::TransferWrite)
        .write(out[1], Access::TransferWrite)
        .record(move |ctx| {
            let extent = voxgi::vk::vk::Extent3D {
                width: ext.x,
                height: ext.y,
                depth: ext.z,
            };
            for (img, buf) in [(albedo, out[0]), (normal, out[1])] {
                ctx.cmd
                    .copy_image_to_buffer(ctx.image(img).raw, extent, 0, 1, ctx.buffer(buf).raw);
            }
        });
    let timings = run_once(ctx, g).expect("frame runs");
    let names = timings.into_iter().map(|t| t.name).collect();
    let texels = |b: &voxgi::vk::Buffer| -> Vec<[u8; 4]> {
        b.mapped().expect("mapped")[..size as usize]
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    };
    let v = Volumes {
        bits: bits.levels(&grid).remove(0),
        albedo: texels(&outs[0]),
        normal: texels(&outs[1])
            .into_iter()
            .map(|t| t.map(|c| c as i8))
            .collect(),
    };
    (v, names)
}

/// Congruence (docs/design/voxels.md): a voxel has an attribute (albedo alpha 1, a unit normal
/// or a cancelled one) exactly where its bit is set, and nothing elsewhere.
fn assert_congruent(v: &Volumes, grid: &VoxelGrid, what: &str) -> usize {
    let ext = grid.extent_voxels();
    let (mut set, mut mismatches) = (0, Vec::new());
    for k in 0..ext.z {
        for y in 0..ext.y {
            for x in 0..ext.x {
                let i = ((k * ext.y + y) * ext.x + x) as usize;
                let bit = v.bits.get(x, y, k);
                let a = v.albedo[i];
                assert!(
                    a[3] == 0 || a[3] == 255,
                    "{what}: alpha {} at {x},{y},{k}",
                    a[3]
                );
                if bit != (a[3] == 255) {
                    mismatches.push((x, y, k, bit, a));
                }
                if !bit {
                    assert_eq!(
                        v.normal[i], [0; 4],
                        "{what}: normal in empty voxel {x},{y},{k}"
                    );
                }
                set += usize::from(bit);
            }
        }
    }
    assert!(
        mismatches.is_empty(),
        "{what}: {} of {set} voxels differ (bit, albedo), first: {:?}",
        mismatches.len(),
        &mismatches[..mismatches.len().min(8)]
    );
    assert!(set > 1000, "{what}: only {set} voxels set");
    set
}

/// `--voxelizer atlas` with a volume GI method: the layered pass `voxelize_atlas_volumes`
/// writes albedo and normal volumes congruent with the bits; on the Cornell box's red wall
/// the albedo is the wall's material and the normal points into the box.
#[test]
fn atlas_volumes_match_the_bits_and_the_red_wall() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::gpu_atlas_volumes::AttributeVolumes;
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let s = scene("cornell");
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        ..Default::default()
    };
    let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
    assert!(!frame.has_attribute_volumes(), "created only on request");
    assert!(frame
        .enable_attribute_volumes(&ctx, &s, Default::default())
        .expect("volumes"));
    let grid = frame.voxels.grid;
    let volumes = AttributeVolumes::new(&ctx, &grid).expect("volumes");
    let (v, names) = run_volume_frame(&ctx, &frame, &volumes);
    // Static scene: the statics were splatted once at enable time; the frame only resolves.
    assert!(
        names.iter().any(|n| n == "voxelize_atlas_resolve"),
        "{names:?}"
    );
    assert!(
        !names.iter().any(|n| n == "voxelize_atlas_volumes"),
        "{names:?}"
    );
    let set = assert_congruent(&v, &grid, "cornell");
    println!("cornell: {set} voxels, congruent");

    // The red wall: every voxel around the centroids of its triangles.
    let red = s
        .materials
        .iter()
        .position(|m| m.albedo.x > 2.0 * m.albedo.y && m.albedo.x > 2.0 * m.albedo.z)
        .expect("a red material");
    let center = s.aabb_at(0.0).center();
    let ext = grid.extent_voxels();
    let mut checked = 0;
    for o in &s.objects {
        let mesh = &s.meshes[o.mesh];
        let model = o.transform_at(0.0);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            if o.materials.get(si).copied().unwrap_or(sub.material) != red {
                continue;
            }
            let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
            for t in mesh.indices[range].chunks_exact(3) {
                let p = [0, 1, 2].map(|j| model.transform_point3(mesh.positions[t[j] as usize]));
                // Interior points (barycentrics >= 0.2): their 3x3x3 neighbourhoods stay
                // off the adjacent walls.
                let interior = (2..=6).flat_map(|i| (2..=6).map(move |j| (i, j)));
                let samples = interior.filter(|&(i, j)| i + j <= 8).map(|(i, j)| {
                    let (b1, b2) = (i as f32 / 10.0, j as f32 / 10.0);
                    p[0] + (p[1] - p[0]) * b1 + (p[2] - p[0]) * b2
                });
                for c in samples {
                    let inward = (center - c).normalize();
                    let vc = grid.world_to_voxel(c).floor().as_ivec3();
                    for d in itertools_product() {
                        let q = vc + glam::IVec3::new(d.0 as i32, d.1 as i32, d.2 as i32);
                        if q.min_element() < 0 || q.cmpge(ext.as_ivec3()).any() {
                            continue;
                        }
                        let (x, y, k) = (q.x as u32, q.y as u32, q.z as u32);
                        if !v.bits.get(x, y, k) {
                            continue;
                        }
                        let i = ((k * ext.y + y) * ext.x + x) as usize;
                        let a =
                            Vec3::from_array(v.albedo[i].map(f32::from)[..3].try_into().unwrap())
                                / 255.0;
                        let want = s.materials[red].albedo;
                        assert!(
                            (a - want).abs().max_element() <= 2.0 / 255.0,
                            "red wall voxel {q}: albedo {a} != {want}"
                        );
                        let n = Vec3::new(
                            f32::from(v.normal[i][0]),
                            f32::from(v.normal[i][1]),
                            f32::from(v.normal[i][2]),
                        ) / 127.0;
                        assert!((n.length() - 1.0).abs() < 0.02, "unit normal {n} at {q}");
                        let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
                        assert!(
                            n.dot(face) > 0.99,
                            "normal {n} != face normal {face} at {q}"
                        );
                        assert!(
                            n.dot(inward) > 0.0,
                            "normal {n} points out of the box at {q}"
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    println!("red wall: {checked} voxels checked");
    assert!(checked > 0, "no red-wall voxel found");
    common::assert_no_validation_messages(&ctx);
}

/// The moving cube of `cornell_mover.toml`: static walls splatted once, the mover per frame;
/// the volumes follow it (voxels it leaves are cleared) and stay congruent with the bits.
#[test]
fn atlas_volumes_follow_a_moving_object() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::gpu_atlas_volumes::AttributeVolumes;
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let s = common::animated_scene();
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        ..Default::default()
    };
    let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
    assert!(frame
        .enable_attribute_volumes(&ctx, &s, Default::default())
        .expect("volumes"));
    let grid = frame.voxels.grid;
    let volumes = AttributeVolumes::new(&ctx, &grid).expect("volumes");
    let mut counts = Vec::new();
    for t in [0.0, 0.5, 1.0] {
        assert!(frame.update(t, 0).expect("update"), "the mover moved");
        assert!(frame.attributes_moved());
        let (v, names) = run_volume_frame(&ctx, &frame, &volumes);
        assert!(
            names.iter().any(|n| n == "voxelize_atlas_volumes"),
            "{names:?}"
        );
        counts.push(assert_congruent(&v, &grid, &format!("t = {t}")));
    }
    println!("voxels set per frame: {counts:?}");
    assert!(!frame.update(1.0, 0).expect("update"));
    assert!(!frame.attributes_moved());
    common::assert_no_validation_messages(&ctx);
}

/// The thesis's raster bit pass (`voxelize_atlas_bits`: single-bit LUT, logicOp OR, layer =
/// depth chunk) sets exactly the bits of the compute pass `voxelize_atlas`, one and two
/// depth layers (`voxgi bench voxelize` runs the same comparison with timings).
#[test]
fn raster_atlas_bits_equal_compute_atlas_bits() {
    use voxgi::bench::{bench_voxelize_atlas, VoxelizeBenchDesc};
    let ctx = common::context();
    // The three panes of opacity 0.5: the raster twin drops the points the compute pass drops.
    for (path, layers) in [
        ("cornell", 1),
        ("assets/scenes/cornell_bunny.toml", 2),
        ("assets/scenes/transparency.toml", 1),
    ] {
        let desc = VoxelizeBenchDesc {
            resolution: 128,
            layers,
            repeats: 1,
        };
        let r = bench_voxelize_atlas(&ctx, &scene(path), &desc).expect("bench runs");
        print!("{}", r.table());
        assert!(r.voxels > 10_000, "{path}: {} voxels", r.voxels);
        assert_eq!(
            r.differing_words, 0,
            "{path}: raster and compute bits differ"
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// An OBJ sequence of 5 frames (1 fps, not looping) over a static floor: a wavy 12×6-quad
/// sheet that stretches from 1× to 3× along x, written to a temp dir.
fn sequence_scene(tag: &str) -> voxgi::scene::Scene {
    let dir = std::env::temp_dir().join(format!("voxgi-atlas-seq-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (nu, nv) = (12u32, 6u32);
    for f in 0..5 {
        let half_x = 0.5 * (1.0 + 0.5 * f as f32);
        let mut obj = String::new();
        for j in 0..=nv {
            for i in 0..=nu {
                let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
                // The wave keeps the y range of every frame, so the t = 0 grid holds them all.
                let y = 0.55 + 0.2 * (std::f32::consts::TAU * u).sin() * (0.5 + v);
                obj += &format!("v {} {y} {}\n", (2.0 * u - 1.0) * half_x, v - 0.5);
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let a = j * (nu + 1) + i + 1;
                let (b, c, d) = (a + 1, a + nu + 2, a + nu + 1);
                obj += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
            }
        }
        std::fs::write(dir.join(format!("sheet_{f}.obj")), obj).expect("obj frame");
    }
    let toml = "[camera]\nposition = [0.0, 3.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov_y_deg = 60.0\nnear = 0.05\nfar = 10.0\n\
        [[objects]]\nname = \"floor\"\nbuiltin = \"quad\"\nscale = [4.0, 1.0, 4.0]\n\
        [[objects]]\nname = \"sheet\"\nmaterial = { albedo = [0.8, 0.3, 0.2] }\n\
        [objects.animation]\nobj_sequence = \"sheet_{}.obj\"\nframes = 5\nfps = 1.0\nloop = false\n";
    voxgi::scene::Scene::from_toml_str(toml, Path::new("<sequence>"), &dir).expect("parses")
}

/// Times of the sequence tests and the frame each shows.
const SEQUENCE_TIMES: [(f32, usize); 4] = [(0.0, 0), (1.5, 1), (2.5, 2), (4.2, 4)];

/// Issue 4: an OBJ sequence whose frames share topology shares one atlas. With
/// `--voxelizer atlas` no triangle pass runs; at every frame the bits match the CPU
/// reference of that frame as closely as the rigid atlas tests do.
#[test]
fn voxel_frame_atlas_follows_an_obj_sequence() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let s = sequence_scene("bits");
    let sheet = s.objects.iter().find(|o| o.name == "sheet").expect("sheet");
    assert!(voxgi::voxel::gpu_atlas::uses_atlas(&s, sheet));
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        ..Default::default()
    };
    let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
    assert!(frame.has_frame_passes());
    // The floor's atlas and one for the whole sequence; a point list per sequence frame.
    assert_eq!(frame.atlases_packed(), 2);
    assert_eq!(frame.atlas_point_lists(), 1 + 5);
    let grid = frame.voxels.grid;
    let bits = common::VoxelReadback::new(&ctx, &grid, 1);
    let mut seen = Vec::new();
    for (t, f) in SEQUENCE_TIMES {
        assert_eq!(
            s.objects[1].mesh_at(t),
            s.meshes.len() - 5 + f,
            "frame at {t}"
        );
        assert!(frame.update(t, 0).expect("update"), "frame {f} is new");
        let mut g = RenderGraph::new();
        let image = frame.add_passes(&mut g);
        bits.add_pass(&mut g, image);
        let timings = run_once(&ctx, g).expect("frame runs");
        let names: Vec<_> = timings.iter().map(|t| t.name.as_str()).collect();
        assert!(names.contains(&"voxelize_atlas"), "{names:?}");
        assert!(!names.contains(&"voxelize_triangles"), "{names:?}");
        let gpu = bits.levels(&grid).remove(0);
        let mut cpu = BitGrid::for_grid(&grid);
        voxgi::voxel::voxelize_scene(&grid, &mut cpu, &s, t).expect("cpu");
        let (recall, precision, near) = compare(&cpu, &gpu);
        println!(
            "sequence frame {f} (t = {t}): cpu {} voxels, atlas {} voxels, recall {recall:.4}, \
             precision {precision:.5}, precision (dilated) {near:.5}",
            cpu.count_ones(),
            gpu.count_ones()
        );
        assert_eq!(near, 1.0, "frame {f}: an atlas voxel is off the surface");
        assert!(precision >= 0.999, "frame {f}: precision {precision}");
        assert!(recall >= MIN_RECALL, "frame {f}: recall {recall}");
        seen.push(gpu);
    }
    // The frames differ (the sheet stretches), so a stale point list would have failed.
    assert!(seen.windows(2).all(|w| w[0] != w[1]));
    // Same frame (not looping, past the end): nothing re-voxelizes; still one atlas.
    assert!(!frame.update(4.7, 0).expect("update"));
    assert_eq!(frame.atlases_packed(), 2);
    common::assert_no_validation_messages(&ctx);
}

/// The attribute volumes of an OBJ sequence follow its frames and stay congruent with the
/// bits (the layered pass splats the slot's frame list with that frame's triangles).
#[test]
fn atlas_volumes_follow_an_obj_sequence() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::gpu_atlas_volumes::AttributeVolumes;
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let s = sequence_scene("volumes");
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        ..Default::default()
    };
    let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
    assert!(frame
        .enable_attribute_volumes(&ctx, &s, Default::default())
        .expect("volumes"));
    let grid = frame.voxels.grid;
    let volumes = AttributeVolumes::new(&ctx, &grid).expect("volumes");
    let mut counts = Vec::new();
    for (t, _) in SEQUENCE_TIMES {
        assert!(frame.update(t, 0).expect("update"));
        assert!(
            frame.attributes_moved(),
            "a new frame changes the attributes"
        );
        let (v, names) = run_volume_frame(&ctx, &frame, &volumes);
        assert!(
            names.iter().any(|n| n == "voxelize_atlas_volumes"),
            "{names:?}"
        );
        counts.push(assert_congruent(&v, &grid, &format!("t = {t}")));
    }
    println!("sequence voxels set per frame: {counts:?}");
    assert!(counts.windows(2).any(|w| w[0] != w[1]), "{counts:?}");
    assert_eq!(frame.atlases_packed(), 2);
    common::assert_no_validation_messages(&ctx);
}

/// `cornell_pane.toml` with the pane's opacity `opacity` (the pane is object "pane").
fn pane_scene(opacity: f32) -> voxgi::scene::Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let text = std::fs::read_to_string(dir.join("cornell_pane.toml")).expect("scene file");
    let line = "opacity = 0.5 }";
    assert_eq!(
        text.matches(line).count(),
        1,
        "cornell_pane.toml's pane material"
    );
    let toml = text.replace(line, &format!("opacity = {opacity:?} }}"));
    voxgi::scene::Scene::from_toml_str(&toml, Path::new("<pane>"), &dir).expect("scene parses")
}

/// Opacity in the atlas voxelizer (docs/design/transparency.md): a pane's points set their
/// voxels where the triangle voxelizer's stochastic coverage keeps them. Exactly: the atlas
/// bits of the box with a pane of opacity α are the bits of the box without it, united with
/// the opaque pane's atlas voxels that `Coverage::covers` keeps for the pane's object (the
/// same points, so the same voxels; the rule is the CPU twin of the shaders' test). So a pane
/// of opacity 0 sets nothing and one of opacity 1 everything it did before; a moving pane
/// (a dynamic instance) sets the voxels the static one sets.
#[test]
fn atlas_panes_keep_the_voxels_their_coverage_keeps() {
    use voxgi::voxel::coverage::Coverage;
    let ctx = common::context();
    let box_only = scene("assets/scenes/cornell_ceiling_spot.toml");
    let aabb = box_only.aabb_at(0.0);
    let desc = GridDesc {
        layers: 1,
        max_res_xy: 128,
        ..Default::default()
    };
    let grid = VoxelGrid::around(aabb.min, aabb.max, &desc).expect("grid");
    let (none, _) = atlas_bits(&ctx, &grid, &box_only);
    let (opaque, _) = atlas_bits(&ctx, &grid, &pane_scene(1.0));
    let mut pane_voxels = 0u64;
    for opacity in [0.0f32, 0.5, 0.9] {
        let (bits, _) = atlas_bits(&ctx, &grid, &pane_scene(opacity));
        let rule = Coverage::new("pane", opacity);
        let (mut differ, mut kept) = (0u64, 0u64);
        for k in 0..grid.depth() {
            for y in 0..grid.res_y() {
                for x in 0..grid.res_x() {
                    let pane = opaque.get(x, y, k)
                        && !none.get(x, y, k)
                        && rule.covers(glam::UVec3::new(x, y, k));
                    kept += u64::from(pane);
                    differ += u64::from(bits.get(x, y, k) != (none.get(x, y, k) || pane));
                }
            }
        }
        println!("pane of opacity {opacity}: {kept} voxels kept");
        assert_eq!(differ, 0, "opacity {opacity}: {differ} voxels differ");
        // A moving pane (a dynamic instance, its own coverage) takes the same decisions.
        let mut moving = pane_scene(opacity);
        for o in moving.objects.iter_mut().filter(|o| o.name == "pane") {
            o.dynamic = true;
        }
        let (dynamic_bits, _) = atlas_bits(&ctx, &grid, &moving);
        assert!(
            dynamic_bits == bits,
            "opacity {opacity}: the moving pane sets other voxels"
        );
        if opacity == 0.0 {
            assert_eq!(kept, 0, "a pane of opacity 0 sets no voxel");
        } else {
            pane_voxels = pane_voxels.max(kept);
        }
    }
    // The pane (0.5 m square, voxels of 0.5488 / 128 m): thousands of voxels, so the rule
    // kept some of them in every decision above.
    assert!(pane_voxels > 5_000, "{pane_voxels} pane voxels");
    common::assert_no_validation_messages(&ctx);
}

/// The attribute volumes drop the points the bits drop: with the pane of opacity 0.5 the
/// atlas voxelizer's albedo and normal volumes are congruent with its bits (a voxel has an
/// attribute exactly where its bit is set), and the box without a pane and with a pane of
/// opacity 0 set the same voxels.
#[test]
fn atlas_volumes_drop_the_points_the_coverage_drops() {
    use voxgi::voxel::gpu::{VoxelSettings, Voxelizer};
    use voxgi::voxel::gpu_atlas_volumes::AttributeVolumes;
    use voxgi::voxel::VoxelFrame;
    let ctx = common::context();
    let settings = VoxelSettings {
        voxelizer: Voxelizer::Atlas,
        max_res_xy: 128,
        ..Default::default()
    };
    let mut sets = Vec::new();
    for (what, s) in [
        ("no pane", scene("assets/scenes/cornell_ceiling_spot.toml")),
        ("pane of opacity 0", pane_scene(0.0)),
        ("pane of opacity 0.5", pane_scene(0.5)),
    ] {
        let mut frame = VoxelFrame::new(&ctx, &s, 0.0, &settings).expect("voxel frame");
        assert!(frame
            .enable_attribute_volumes(&ctx, &s, Default::default())
            .expect("volumes"));
        let volumes = AttributeVolumes::new(&ctx, &frame.voxels.grid).expect("volumes");
        let (v, _) = run_volume_frame(&ctx, &frame, &volumes);
        sets.push(assert_congruent(&v, &frame.voxels.grid, what));
    }
    common::assert_no_validation_messages(&ctx);
    println!("voxels set: no pane, clear pane, half pane {sets:?}");
    assert_eq!(sets[0], sets[1], "a pane of opacity 0 sets no voxel");
    assert!(sets[2] > sets[0], "the pane of opacity 0.5 sets some");
}
