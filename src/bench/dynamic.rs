//! `voxgi bench dynamic` (`bench_dynamic`): a static scene voxelized once, with N animated
//! objects voxelized again every frame (Thiedemann 2010 §8.2: Fig. 41 puts 3 and 9 animated
//! horses into a pre-voxelized Sibenik, Fig. 42 left does it with the normal and material
//! volumes too). Here the static scene is the Cornell walls with 16 Stanford bunnies on the
//! floor, and the animated objects are bunnies flying on a circle through the box, each a
//! quarter-turn apart. Per voxelizer and N, the GPU time per frame of the bit passes (the
//! static bits' copy, the animated objects' voxelization, the store and the OR hierarchy),
//! of the attribute volumes (the path tracer reads them; the hemisphere method with light maps
//! needs the bits alone) and of the whole frame.

use super::BenchError;
use crate::gi::{GiMethod, GiSettings};
use crate::render::RenderSettings;
use crate::scene::{Scene, Voxelizer};
use crate::stats::median;
use crate::vk::{Context, PassTiming};
use serde::Serialize;

/// What `voxgi bench dynamic` measures.
#[derive(Clone, Debug)]
pub struct DynamicBenchDesc {
    /// Numbers of animated objects (Thiedemann's 3 and 9, and 0 for the static scene alone).
    pub animated: Vec<u32>,
    /// Frame width and height.
    pub size: u32,
    /// Measured frames, each at a later scene time (every object moves in every frame).
    pub frames: usize,
    /// Frames before the measured ones.
    pub warmup: usize,
}

impl Default for DynamicBenchDesc {
    fn default() -> Self {
        Self {
            animated: vec![0, 3, 9],
            size: 128,
            frames: 8,
            warmup: 2,
        }
    }
}

/// One voxelizer, method and number of animated objects.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicBenchRow {
    pub voxelizer: &'static str,
    /// `hemisphere` (the bits alone) or `pathtrace` (bits and attribute volumes).
    pub method: &'static str,
    pub animated: u32,
    /// Triangles of the animated objects.
    pub animated_triangles: usize,
    /// Median per frame: the bit passes (`voxel_copy_static`, `voxelize_triangles` or
    /// `voxelize_atlas`, `voxel_store`, `voxel_mip_*`).
    pub bits_ms: f64,
    /// Median per frame: the attribute volumes' passes (`voxelize_attributes*`,
    /// `voxelize_atlas_volumes`, `voxelize_atlas_resolve`).
    pub attributes_ms: f64,
    pub frame_ms: f64,
}

/// The rows of one run, with the device's name.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicBenchReport {
    pub device: String,
    pub static_triangles: usize,
    pub rows: Vec<DynamicBenchRow>,
}

/// Bunnies along each side of the static grid on the floor.
const STATIC_PER_SIDE: u32 = 4;
/// Seconds per turn of an animated bunny's circle; frame k is at k·FRAME_S.
const TURN_S: f32 = 2.0;
const FRAME_S: f32 = 0.05;

/// The static scene and `animated` bunnies on a circle of radius 0.15 m at mid-height, each
/// `TURN_S / animated` behind the previous and turning about y as it goes; keyframes every
/// quarter turn (the animation interpolates between them), looping.
pub fn dynamic_scene(scenes_dir: &std::path::Path, animated: u32) -> Result<Scene, BenchError> {
    // bunny.obj spans x [-4.96, 4.95], y [0, 9.65], z [-3.73, 3.81] (cornell_bunny.toml).
    let cell_m = 0.54 / STATIC_PER_SIDE as f32;
    let scale = 0.9 * 0.5 * cell_m / 6.26;
    let mut toml = String::from(super::scenes::CORNELL_SPOT_TOML);
    for i in 0..STATIC_PER_SIDE * STATIC_PER_SIDE {
        let (a, b) = (i % STATIC_PER_SIDE, i / STATIC_PER_SIDE);
        toml += &format!(
            "\n[[objects]]\nname = \"static_{i}\"\nmesh = \"../meshes/bunny.obj\"\n\
             translate = [{}, 0.001, {}]\nrotate_deg = [0.0, {}, 0.0]\nscale = {scale}\n\
             material = {{ albedo = [0.73, 0.73, 0.73] }}\n",
            0.005 + (a as f32 + 0.5) * cell_m,
            0.01 + (b as f32 + 0.5) * cell_m,
            (40 * i) % 360
        );
    }
    let centre = [0.278f32, 0.22, 0.28];
    for k in 0..animated {
        toml += &format!(
            "\n[[objects]]\nname = \"animated_{k}\"\nmesh = \"../meshes/bunny.obj\"\n\
             scale = {scale}\nmaterial = {{ albedo = [0.8, 0.5, 0.3] }}\n\n\
             [objects.animation]\nloop = true\n"
        );
        let phase = k as f32 / animated.max(1) as f32;
        for q in 0..=4 {
            let turn = phase + q as f32 / 4.0;
            let angle = turn * std::f32::consts::TAU;
            toml += &format!(
                "\n[[objects.animation.keyframes]]\ntime_s = {}\ntranslate = [{}, {}, {}]\n\
                 rotate_deg = [0.0, {}, 0.0]\n",
                q as f32 * TURN_S / 4.0,
                centre[0] + 0.15 * angle.cos(),
                centre[1] + 0.05 * (k % 3) as f32,
                centre[2] + 0.15 * angle.sin(),
                -turn * 360.0
            );
        }
    }
    Ok(Scene::from_toml_str(
        &toml,
        std::path::Path::new("<dynamic-objects scene>"),
        scenes_dir,
    )?)
}

/// Whether a pass sets the bits or their hierarchy.
fn is_bit_pass(name: &str) -> bool {
    matches!(
        name,
        "voxel_copy_static" | "voxelize_triangles" | "voxelize_atlas" | "voxel_store"
    ) || name.starts_with("voxel_mip")
}

/// Whether a pass writes the attribute volumes.
fn is_attribute_pass(name: &str) -> bool {
    name.starts_with("voxelize_attributes")
        || name == "voxelize_atlas_volumes"
        || name == "voxelize_atlas_resolve"
}

fn sum_ms(frame: &[PassTiming], pick: fn(&str) -> bool) -> f64 {
    // A fold from +0: `sum` of no passes is -0.
    frame
        .iter()
        .filter(|t| pick(&t.name))
        .fold(0.0, |a, t| a + t.gpu_ms)
}

/// Runs every voxelizer × method × number of animated objects (see the module docs).
pub fn bench_dynamic(
    ctx: &Context,
    desc: &DynamicBenchDesc,
) -> Result<DynamicBenchReport, BenchError> {
    let scenes_dir = crate::assets::find(std::path::Path::new("assets/scenes"));
    let triangles = |s: &Scene, animated: bool| -> usize {
        s.objects
            .iter()
            .filter(|o| o.animation.is_some() == animated)
            .filter_map(|o| s.meshes.get(o.mesh))
            .map(|m| m.indices.len() / 3)
            .sum()
    };
    let mut rows = Vec::new();
    let mut static_triangles = 0;
    for &n in &desc.animated {
        let scene = dynamic_scene(&scenes_dir, n)?;
        static_triangles = triangles(&scene, false);
        for (voxelizer, vname) in [
            (Voxelizer::Triangle, "triangle"),
            (Voxelizer::Atlas, "atlas"),
        ] {
            for (method, mname) in [
                (GiMethod::Hemisphere, "hemisphere"),
                (GiMethod::Pathtrace, "pathtrace"),
            ] {
                let mut voxels = scene.voxel_settings();
                voxels.voxelizer = voxelizer;
                let settings = RenderSettings {
                    width: desc.size,
                    height: desc.size,
                    voxels: Some(voxels),
                    gi: GiSettings {
                        method,
                        rays: 1,
                        ..Default::default()
                    },
                    ..Default::default()
                };
                let frames = run_animated(ctx, &scene, settings, desc)?;
                let med = |pick: fn(&str) -> bool| {
                    median(&frames.iter().map(|f| sum_ms(f, pick)).collect::<Vec<_>>())
                };
                rows.push(DynamicBenchRow {
                    voxelizer: vname,
                    method: mname,
                    animated: n,
                    animated_triangles: triangles(&scene, true),
                    bits_ms: med(is_bit_pass),
                    attributes_ms: med(is_attribute_pass),
                    frame_ms: med(|_| true),
                });
            }
        }
    }
    Ok(DynamicBenchReport {
        device: ctx.info.name.clone(),
        static_triangles,
        rows,
    })
}

/// The per-pass timings of `desc.frames` frames after `desc.warmup`, the scene's time
/// advancing by `FRAME_S` every frame.
fn run_animated(
    ctx: &Context,
    scene: &Scene,
    settings: RenderSettings,
    desc: &DynamicBenchDesc,
) -> Result<Vec<Vec<PassTiming>>, BenchError> {
    let run = crate::render::profile_steps(
        ctx,
        scene,
        &settings,
        desc.frames,
        desc.warmup,
        |frame, _, time_s| *time_s = frame as f32 * FRAME_S,
    )?;
    Ok(run.frames)
}

impl DynamicBenchReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "Animated objects re-voxelized every frame over a static scene ({} static \
             triangles) on {}; GPU ms per frame, medians\n\
             voxelizer  method      animated  triangles    bits ms  attributes ms   frame ms\n",
            self.static_triangles, self.device
        );
        for r in &self.rows {
            s += &format!(
                "{:<10} {:<11} {:>8} {:>10} {:>10.3} {:>14.3} {:>10.3}\n",
                r.voxelizer,
                r.method,
                r.animated,
                r.animated_triangles,
                r.bits_ms,
                r.attributes_ms,
                r.frame_ms
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene has the 16 static bunnies and the animated ones, which move between any two
    /// frames the benchmark measures (so each frame re-voxelizes them).
    #[test]
    fn the_animated_bunnies_move_every_frame() {
        let dir = crate::assets::find(std::path::Path::new("assets/scenes"));
        let scene = dynamic_scene(&dir, 3).expect("scene builds");
        let animated: Vec<_> = scene
            .objects
            .iter()
            .filter(|o| o.animation.is_some())
            .collect();
        assert_eq!(animated.len(), 3);
        assert_eq!(scene.objects.len(), 1 + 16 + 3);
        for o in animated {
            let a = o.transform_at(0.0);
            let b = o.transform_at(FRAME_S);
            assert_ne!(a, b, "{} does not move in a frame", o.name);
        }
    }
}
