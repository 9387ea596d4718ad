//! Temporal anti-aliasing (`--taa`, `glsl/taa.comp`): a static view converges towards the
//! supersampled image, and the reprojected history of a moving camera shows the previous
//! frame's world-anchored content at the new pixels. Validation on, across frames.

mod common;

use glam::{Mat4, Vec2, Vec3, Vec4};
use voxgi::graph::{add_readback, readback_buffer, run_frames, Access, RenderGraph, Shader};
use voxgi::post::{PostSettings, TaaPass, TaaSettings};
use voxgi::render::{render_image, RenderSettings};
use voxgi::scene::load_scene_arg;
use voxgi::vk::{vk, ImageDesc};

/// Mean absolute difference of two equally sized radiance images, over all channels.
fn mean_abs_diff(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| f64::from((p[c] - q[c]).abs())))
        .sum();
    sum / (3 * a.len()) as f64
}

/// `img` (`w`×`h`) averaged over `k`×`k` blocks: the box-filtered pixel footprint.
fn downsample(img: &[[f32; 3]], w: usize, k: usize) -> Vec<[f32; 3]> {
    let (ow, oh) = (w / k, img.len() / w / k);
    let mut out = vec![[0.0f32; 3]; ow * oh];
    for (i, o) in out.iter_mut().enumerate() {
        let (x, y) = (i % ow, i / ow);
        for dy in 0..k {
            for dx in 0..k {
                let p = img[(y * k + dy) * w + x * k + dx];
                for c in 0..3 {
                    o[c] += p[c] / (k * k) as f32;
                }
            }
        }
    }
    out
}

/// The Cornell box's silhouettes and shadow edges, 64² with direct light. Without TAA each
/// pixel samples its centre only, so an edge pixel is all one side or the other: its error
/// against the box-filtered 4×4-supersampled render is up to half the edge's contrast. TAA
/// averages 16 stratified Halton(2,3) positions over the footprint (the plain mean of the
/// first 1/(1 − α) = 10 frames, then exponential), which estimates the same box filter: the
/// edge error must fall. A stratified estimate of a straight edge's coverage with n samples
/// errs by O(1/n); 10 evenly averaged frames already should cut the error at least in half,
/// and interior pixels (identical in both) dilute neither measure differently.
#[test]
fn static_view_converges_towards_the_supersampled_image() {
    let scene = load_scene_arg(Some("cornell")).expect("scene");
    let ctx = common::context();
    let size = 64;
    let render = |s: u32, taa: Option<TaaSettings>| {
        let settings = RenderSettings {
            width: s,
            height: s,
            post: PostSettings {
                taa,
                ..Default::default()
            },
            ..Default::default()
        };
        render_image(&ctx, &scene, &settings).expect("renders").hdr
    };
    let reference = downsample(&render(4 * size, None).data, 4 * size as usize, 4);
    let plain = render(size, None);
    let taa = render(size, Some(TaaSettings::default()));
    common::assert_no_validation_messages(&ctx);
    let e_plain = mean_abs_diff(&plain.data, &reference);
    let e_taa = mean_abs_diff(&taa.data, &reference);
    println!("mean |error| against 4×4 supersampling: no TAA {e_plain:.5}, TAA {e_taa:.5}");
    assert!(e_plain > 0.0, "the test scene has edges to anti-alias");
    assert!(
        e_taa < 0.5 * e_plain,
        "TAA error {e_taa:.5} is not below half the aliased error {e_plain:.5}"
    );
}

const W: u32 = 48;
const H: u32 = 32;

/// Radiance painted on the plane z = 0: linear in world x and y, so the image of a moving
/// camera is known everywhere (≈0.06 per pixel at the test's distance, per channel), and
/// positive over the whole view.
fn paint(p: Vec3) -> [f32; 3] {
    [3.0 + 0.5 * p.x, 3.0 + 0.5 * p.y, 3.0 - 0.25 * (p.x + p.y)]
}

/// Where the ray through NDC `ndc` of `view_proj` meets the plane z = 0, and its depth.
fn plane_hit(view_proj: Mat4, ndc: Vec2) -> (Vec3, f32) {
    let inv = view_proj.inverse();
    let a = inv.project_point3(ndc.extend(0.0));
    let b = inv.project_point3(ndc.extend(1.0));
    let t = a.z / (a.z - b.z);
    let p = a + (b - a) * t;
    let clip = view_proj * Vec4::new(p.x, p.y, p.z, 1.0);
    (p, clip.z / clip.w)
}

fn pixel_ndc(x: u32, y: u32) -> Vec2 {
    Vec2::new(
        (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
        (y as f32 + 0.5) / H as f32 * 2.0 - 1.0,
    )
}

fn camera(eye: Vec3) -> Mat4 {
    let mut proj = Mat4::perspective_rh(50f32.to_radians(), W as f32 / H as f32, 0.1, 100.0);
    proj.y_axis.y = -proj.y_axis.y;
    proj * Mat4::look_at_rh(eye, Vec3::new(0.2, 0.1, 0.0), Vec3::Y)
}

/// The reprojection test, on the pass itself: frame 1 (no history) stores the painted
/// plane seen by camera 1 as the history; frame 2 moves the camera (≈ 4 pixels of parallax
/// and a turn) and gives the pass the depth of the plane seen by the jittered camera 2 and a
/// current frame of saturated primaries (every 3×3 neighbourhood's YCoCg box then holds the
/// history, so clipping keeps it). The history weight α = 0.99 after 120 frames makes the blend
/// 0.99 · history + 0.01 · current; the history part must be the plane's paint at camera 2's
/// pixel centres. Bound: bilinear interpolation of the perspective-warped linear paint and
/// the jitter's second-order shift move a value by well under 0.01 (a sixth of one pixel's
/// gradient; measured 0.002); reading the history unreprojected is off by more than 0.1.
#[test]
fn moving_camera_reprojects_the_previous_frame() {
    check_reprojection(camera);
}

/// The same through an orthographic camera (issue 17; `scene::Camera::proj`), 3 m high,
/// looking along camera 1's axis from both positions (turning towards the target would keep
/// the target at the centre, and the image nearly unchanged): the move shifts the view by
/// about 0.38 m (≈ 4 pixels at 32 / 3 pixels per meter), and the warp is affine, so bilinear
/// interpolation of the linear paint is exact up to the jitter's shift.
#[test]
fn moving_orthographic_camera_reprojects_the_previous_frame() {
    check_reprojection(|eye| {
        let axis = Vec3::new(0.2, 0.1, 0.0) - Vec3::new(0.0, 0.0, 6.0);
        voxgi::scene::Camera {
            position: eye,
            forward: axis.normalize(),
            up: Vec3::Y,
            fov_y_deg: 50.0,
            near: 0.1,
            far: 100.0,
            shift_x_tan: 0.0,
            projection: voxgi::scene::Projection::Orthographic,
            ortho_height_m: 3.0,
        }
        .view_proj(W as f32 / H as f32)
    });
}

fn check_reprojection(camera: impl Fn(Vec3) -> Mat4) {
    let ctx = common::context();
    let sampler = ctx
        .create_sampler(vk::Filter::NEAREST, false)
        .expect("sampler");
    let settings = TaaSettings {
        history_weight: 0.99,
        frames: 1,
    };
    let taa = TaaPass::new(&ctx, settings, (W, H), sampler.raw).expect("pass");
    let vp1 = camera(Vec3::new(0.0, 0.0, 6.0));
    let vp2 = camera(Vec3::new(0.35, 0.15, 5.8));
    let n = (W * H) as usize;
    let rgba = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
    let history: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            rgba(paint(
                plane_hit(vp1, pixel_ndc(i as u32 % W, i as u32 / W)).0,
            ))
        })
        .collect();
    let primaries = [
        [20.0, 0.0, 0.0],
        [0.0, 20.0, 0.0],
        [0.0, 0.0, 20.0],
        [0.0; 3],
    ];
    let current: Vec<[f32; 4]> = (0..n)
        .map(|i| rgba(primaries[(i % 2) + 2 * ((i / W as usize) % 2)]))
        .collect();

    // Frame 1: no history, the output (and the stored history) is the current image.
    taa.begin_frame(vp1);
    let out1 = run_taa(&ctx, &taa, &history, &vec![0.5; n]);
    assert!(out1 == history, "the first frame passes through");
    for _ in 0..120 {
        taa.begin_frame(vp1);
    }
    // Frame 2: the jittered camera 2 rendered the depth.
    let vp2_jittered = voxgi::post::taa::jittered(vp2, taa.begin_frame(vp2));
    let depth: Vec<f32> = (0..n)
        .map(|i| plane_hit(vp2_jittered, pixel_ndc(i as u32 % W, i as u32 / W)).1)
        .collect();
    let out2 = run_taa(&ctx, &taa, &current, &depth);
    common::assert_no_validation_messages(&ctx);

    let w_cur = 0.01f32;
    let (mut worst, mut worst_unprojected) = (0.0f32, 0.0f32);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            // Skip the border ring: its history may lie outside camera 1's image.
            let want_hist = paint(plane_hit(vp2, pixel_ndc(x, y)).0);
            let (hx, hy) = plane_hit_px(vp1, vp2, x, y);
            if hx < 1.0 || hy < 1.0 || hx > W as f32 - 1.0 || hy > H as f32 - 1.0 {
                continue;
            }
            for c in 0..3 {
                let want = (1.0 - w_cur) * want_hist[c] + w_cur * current[i][c];
                worst = worst.max((out2[i][c] - want).abs());
                let unprojected = (1.0 - w_cur) * history[i][c] + w_cur * current[i][c];
                worst_unprojected = worst_unprojected.max((unprojected - want).abs());
            }
        }
    }
    println!("worst error {worst:.4}; without reprojection it would be {worst_unprojected:.4}");
    assert!(worst < 0.01, "reprojected history off by {worst}");
    assert!(worst_unprojected > 0.1, "the camera moved far enough");
}

/// Camera 1's pixel position of the plane point under camera 2's pixel (x, y).
fn plane_hit_px(vp1: Mat4, vp2: Mat4, x: u32, y: u32) -> (f32, f32) {
    let p = plane_hit(vp2, pixel_ndc(x, y)).0;
    let ndc = vp1.project_point3(p);
    (
        (ndc.x * 0.5 + 0.5) * W as f32,
        (ndc.y * 0.5 + 0.5) * H as f32,
    )
}

/// Runs `taa` (and its history copy) once over `current` and `depth`; returns the resolved
/// radiance.
fn run_taa(
    ctx: &voxgi::vk::Context,
    taa: &TaaPass,
    current: &[[f32; 4]],
    depth: &[f32],
) -> Vec<[f32; 4]> {
    let cur = ctx
        .upload_image(
            &ImageDesc::new_2d("current", vk::Format::R32G32B32A32_SFLOAT, W, H),
            &[bytemuck::cast_slice(current).to_vec()],
        )
        .expect("upload");
    let dep = ctx
        .upload_image(
            &ImageDesc::new_2d("depth", vk::Format::R32_SFLOAT, W, H),
            &[bytemuck::cast_slice(depth).to_vec()],
        )
        .expect("upload");
    let readback = readback_buffer(ctx, "taa out", u64::from(W * H * 16)).expect("buffer");
    let mut g = RenderGraph::new();
    let c = g.import_image(&cur, Access::Sampled(Shader::Compute));
    let d = g.import_image(&dep, Access::Sampled(Shader::Compute));
    let out = taa.declare(&mut g, c, d);
    let buf = g.import_buffer(&readback, Access::HostRead);
    add_readback(&mut g, "readback_taa", out, buf);
    let exec = voxgi::graph::GraphExecutor::new(ctx, g, voxgi::vk::MAX_FRAMES_IN_FLIGHT)
        .expect("compiles");
    run_frames(ctx, &exec, 1, 0, |_| {}).expect("runs");
    let px = bytemuck::cast_slice::<u8, [f32; 4]>(readback.mapped().expect("mapped")).to_vec();
    px
}
