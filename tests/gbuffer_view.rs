//! The G-buffer debug views (`voxgi render --debug gbuffer-albedo|gbuffer-normal|
//! gbuffer-distance`) against an independent CPU ray cast: for every pixel, the camera ray
//! through its center is intersected with every scene triangle (Möller and Trumbore 1997), and
//! the view must show the nearest hit's material albedo, its normal and its distance. No
//! voxelization runs, and the lit passes are culled. Validation and synchronization
//! validation on.

mod common;

use glam::Vec3;
use voxgi::render::{render_image, RenderOutput, RenderSettings};
use voxgi::scene::{builtin, Scene};
use voxgi::voxel::debug_view::{DebugSettings, DebugView};

const SIZE: u32 = 64;

fn render(scene: &Scene, view: DebugView) -> RenderOutput {
    let ctx = common::context();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        debug: Some(DebugSettings {
            view,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = render_image(&ctx, scene, &settings).expect("renders the G-buffer view");
    common::assert_no_validation_messages(&ctx);
    // The cached shadow maps are drawn per layer, `shadow_depth[v]`.
    let live = |name: &str| {
        out.live_passes
            .iter()
            .any(|p| p == name || p.starts_with(&format!("{name}[")))
    };
    assert!(
        live("gbuffer_view") && live("gbuffer"),
        "{:?}",
        out.live_passes
    );
    for culled in ["deferred_direct", "tonemap", "shadow_depth", "voxel_debug"] {
        assert!(!live(culled), "{culled} runs: {:?}", out.live_passes);
    }
    assert!(
        !out.live_passes.iter().any(|p| p.starts_with("voxelize")),
        "a G-buffer view voxelizes: {:?}",
        out.live_passes
    );
    out
}

/// The nearest hit of the camera ray through the center of pixel (x, y): distance (m),
/// geometric unit normal, material index.
struct Hit {
    distance_m: f32,
    normal: Vec3,
    material: usize,
}

fn cast(scene: &Scene, x: u32, y: u32) -> Option<Hit> {
    let (near, far) = common::pixel_ray_points(scene, x, y, SIZE);
    let origin = scene.camera.position;
    let dir = (far - near).normalize();
    let mut best: Option<Hit> = None;
    for object in &scene.objects {
        let mesh = &scene.meshes[object.mesh_at(0.0)];
        let model = object.transform_at(0.0);
        for (si, sub) in mesh.submeshes.iter().enumerate() {
            let material = object.materials.get(si).copied().unwrap_or(sub.material);
            let tris = &mesh.indices
                [sub.first_index as usize..(sub.first_index + sub.index_count) as usize];
            for t in tris.chunks_exact(3) {
                let [a, b, c] =
                    [t[0], t[1], t[2]].map(|i| model.transform_point3(mesh.positions[i as usize]));
                // Möller–Trumbore.
                let (e1, e2) = (b - a, c - a);
                let p = dir.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-12 {
                    continue;
                }
                let s = origin - a;
                let u = s.dot(p) / det;
                let q = s.cross(e1);
                let v = dir.dot(q) / det;
                let d = e2.dot(q) / det;
                if u < 0.0 || v < 0.0 || u + v > 1.0 || d <= 0.0 {
                    continue;
                }
                if best.as_ref().is_none_or(|h| d < h.distance_m) {
                    best = Some(Hit {
                        distance_m: d,
                        normal: e1.cross(e2).normalize(),
                        material,
                    });
                }
            }
        }
    }
    best
}

/// Only a pixel whose center lies within float rounding (~1e-5 pixel) of a triangle edge can
/// see the other triangle on the GPU than on the CPU (rasterization samples pixel centers with
/// its own tie rules): a vanishing share. Measured on lavapipe: 0 of 4096 in each view. The
/// bound (1%, 41 pixels) leaves room for another driver's rounding while a wrong channel,
/// which disagrees on nearly every pixel, fails.
const MAX_DISAGREEING_SHARE: f64 = 0.01;

fn check(view: DebugView, agrees: impl Fn(&Hit, [f32; 3]) -> bool) {
    let scene = builtin("cornell").expect("built-in scene");
    let out = render(&scene, view);
    let mut disagree = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let value = out.hdr.data[(y * SIZE + x) as usize];
            let ok = match cast(&scene, x, y) {
                Some(hit) => agrees(&hit, value),
                None => value == [0.0; 3],
            };
            disagree += usize::from(!ok);
        }
    }
    let share = disagree as f64 / f64::from(SIZE * SIZE);
    assert!(
        share <= MAX_DISAGREEING_SHARE,
        "{view:?}: {disagree} of {} pixels disagree with the CPU ray cast",
        SIZE * SIZE
    );
}

#[test]
fn albedo_view_shows_the_hit_material() {
    let scene = builtin("cornell").expect("built-in scene");
    // RGBA16F holds albedo to 2^-11 relative (< 5e-4 for albedo <= 1).
    check(DebugView::GbufferAlbedo, |hit, v| {
        let a = scene.materials[hit.material].albedo;
        (Vec3::from(v) - a).abs().max_element() < 1e-3
    });
}

#[test]
fn normal_view_shows_the_hit_normal() {
    // The Cornell box is made of flat faces, so the interpolated vertex normal is the face
    // normal up to its orientation; RGBA16F stores each component to 2^-11.
    check(DebugView::GbufferNormal, |hit, v| {
        Vec3::from(v).dot(hit.normal).abs() > 0.999
    });
}

#[test]
fn distance_view_shows_the_hit_distance() {
    // D32 depth near 1 has an ulp of 6e-8; with the perspective z = f(d - n) / (d (f - n)),
    // dz/dd ≈ n / d², so the reconstructed distance is good to about 6e-8·d²/n: under 1e-4 m
    // for d < 1.5 m and n ≥ 0.01 m. The bound adds margin for the float inverse projection.
    check(DebugView::GbufferDistance, |hit, v| {
        (v[0] - hit.distance_m).abs() < 1e-3 * hit.distance_m.max(1.0)
    });
}
