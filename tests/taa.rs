//! Temporal anti-aliasing (`--taa`, `glsl/taa.comp`): a static view converges towards the
//! supersampled image, and the reprojected history of a moving camera shows the previous
//! frame's world-anchored content at the new pixels. Validation on, across frames.

mod common;

use glam::camera::rh::{proj::directx, view::look_at_mat4};
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
    let mut proj = directx::perspective(50f32.to_radians(), W as f32 / H as f32, 0.1, 100.0);
    proj.y_axis.y = -proj.y_axis.y;
    proj * look_at_mat4(eye, Vec3::new(0.2, 0.1, 0.0), Vec3::Y)
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
        ..Default::default()
    };
    let taa = TaaPass::new(&ctx, settings, (W, H), (W, H), sampler.raw, false).expect("pass");
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
    let out = taa.declare(&mut g, c, d, None);
    let buf = g.import_buffer(&readback, Access::HostRead);
    add_readback(&mut g, "readback_taa", out, buf);
    let exec = voxgi::graph::GraphExecutor::new(ctx, g, voxgi::vk::MAX_FRAMES_IN_FLIGHT)
        .expect("compiles");
    run_frames(ctx, &exec, 1, 0, |_| {}).expect("runs");
    let px = bytemuck::cast_slice::<u8, [f32; 4]>(readback.mapped().expect("mapped")).to_vec();
    px
}

/// The reprojection where its bilinear fetch must be exact: the plane z = 0 seen head-on from
/// 6 m, the camera stepped sideways by exactly one pixel's footprint there
/// (6 · 2 tan 25° / H), so the reprojected position of every pixel (its jitter taken out and
/// put back) is the centre of a texel of the previous frame one column over: the bilinear
/// weights are 1 and 0, and the history part of the blend is that texel's value. Bound: f32
/// rounding only. The reprojection multiplies by previous VP × inverse(current VP), both in
/// world space: inverting a view-projection with near 0.1 m for a point 6 m away loses about
/// (6/0.1)² · 2⁻²⁴ ≈ 2e-4 of an NDC unit, i.e. 2e-4 · W/2 ≈ 5e-3 px at most, which moves the
/// value by 5e-3 of one pixel's difference of the paint (0.5 per meter × 0.175 m per pixel =
/// 0.087): 4.4e-4; the YCoCg round trip adds a few ulps of 3. Bound 5e-4 (measured 8e-6).
/// Unreprojected, the history is a whole pixel's difference off (0.087).
#[test]
fn a_camera_step_of_one_texel_reprojects_the_history_exactly() {
    let ctx = common::context();
    let sampler = ctx
        .create_sampler(vk::Filter::NEAREST, false)
        .expect("sampler");
    let settings = TaaSettings {
        history_weight: 0.99,
        frames: 1,
        ..Default::default()
    };
    let taa = TaaPass::new(&ctx, settings, (W, H), (W, H), sampler.raw, false).expect("pass");
    let head_on = |x: f32| {
        let mut proj = directx::perspective(50f32.to_radians(), W as f32 / H as f32, 0.1, 100.0);
        proj.y_axis.y = -proj.y_axis.y;
        proj * look_at_mat4(Vec3::new(x, 0.0, 6.0), Vec3::new(x, 0.0, 0.0), Vec3::Y)
    };
    let step = 6.0 * 2.0 * 25f32.to_radians().tan() / H as f32;
    let (vp1, vp2) = (head_on(0.0), head_on(step));
    let n = (W * H) as usize;
    let rgba = |c: [f32; 3]| [c[0], c[1], c[2], 1.0];
    let pixel = |i: usize| (i as u32 % W, i as u32 / W);
    let history: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let (x, y) = pixel(i);
            rgba(paint(plane_hit(vp1, pixel_ndc(x, y)).0))
        })
        .collect();
    // Saturated primaries: every 3×3 box holds the history, which clipping then keeps.
    let primaries = [
        [20.0, 0.0, 0.0],
        [0.0, 20.0, 0.0],
        [0.0, 0.0, 20.0],
        [0.0; 3],
    ];
    let current: Vec<[f32; 4]> = (0..n)
        .map(|i| rgba(primaries[(i % 2) + 2 * ((i / W as usize) % 2)]))
        .collect();
    taa.begin_frame(vp1);
    run_taa(&ctx, &taa, &history, &vec![0.5; n]);
    for _ in 0..120 {
        taa.begin_frame(vp1);
    }
    let vp2_jittered = voxgi::post::taa::jittered(vp2, taa.begin_frame(vp2));
    let depth: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y) = pixel(i);
            plane_hit(vp2_jittered, pixel_ndc(x, y)).1
        })
        .collect();
    let out = run_taa(&ctx, &taa, &current, &depth);
    common::assert_no_validation_messages(&ctx);
    let w_cur = 0.01f32;
    let (mut worst, mut worst_unprojected, mut compared) = (0.0f32, 0.0f32, 0);
    for y in 0..H {
        for x in 0..W {
            // Camera 1's pixel under camera 2's pixel (x, y): a pixel centre one column over.
            let (hx, hy) = plane_hit_px(vp1, vp2, x, y);
            let (qx, qy) = ((hx - 0.5).round(), (hy - 0.5).round());
            assert!(
                (hx - 0.5 - qx).abs() < 1e-3 && (hy - 0.5 - qy).abs() < 1e-3,
                "({x}, {y}) came from ({hx}, {hy}), not a pixel centre"
            );
            assert_eq!((qy as u32, (qx - x as f32).abs()), (y, 1.0));
            if qx < 0.0 || qx >= W as f32 {
                continue;
            }
            compared += 1;
            let (i, j) = ((y * W + x) as usize, (qy as u32 * W + qx as u32) as usize);
            for c in 0..3 {
                let want = (1.0 - w_cur) * history[j][c] + w_cur * current[i][c];
                worst = worst.max((out[i][c] - want).abs());
                let unprojected = (1.0 - w_cur) * history[i][c] + w_cur * current[i][c];
                worst_unprojected = worst_unprojected.max((out[i][c] - unprojected).abs());
            }
        }
    }
    println!(
        "one-texel step: {compared} pixels, worst {worst:e}; unreprojected {worst_unprojected:e}"
    );
    assert_eq!(compared, ((W - 1) * H) as usize);
    assert!(worst < 1e-5, "reprojected history off by {worst}");
    assert!(
        worst_unprojected > 0.03,
        "the step moves the image: {worst_unprojected}"
    );
}

/// Mean |a − b| over the pixels where `mask` holds, all channels.
fn masked_error(a: &[[f32; 3]], b: &[[f32; 3]], mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((p, q), &m) in a.iter().zip(b).zip(mask) {
        if m {
            for c in 0..3 {
                sum += f64::from((p[c] - q[c]).abs());
            }
            n += 3;
        }
    }
    sum / n.max(1) as f64
}

/// `cornell_mover.toml` lit by a point light at the camera instead of its spot light: every
/// visible point is lit, so the moving cube casts no visible shadow (its shadow lies exactly
/// behind it as seen from the camera) and everything that changes on the screen is the cube.
fn mover_lit_from_the_camera() -> voxgi::scene::Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenes/cornell_mover.toml"
    );
    let text = std::fs::read_to_string(path).expect("scene file");
    let start = text.find("[[lights]]").expect("a light");
    let end = text[start..].find("[[objects]]").expect("objects") + start;
    let light = "[[lights]]\nkind = \"point\"\nposition = [0.278, 0.273, -0.800]\n\
                 intensity_w_sr = [5.0, 5.0, 5.0]\n\n";
    let text = format!("{}{light}{}", &text[..start], &text[end..]);
    voxgi::scene::Scene::from_toml_str(
        &text,
        std::path::Path::new(path),
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")),
    )
    .expect("parses")
}

/// The pixels of a `size`² image whose centre's camera ray meets the cube `model` (the
/// built-in unit cube, edges 1 m, centred at its origin): a slab test in the cube's frame.
fn cube_coverage(scene: &voxgi::scene::Scene, model: Mat4, size: u32) -> Vec<bool> {
    let inv = model.inverse();
    (0..size * size)
        .map(|i| {
            let (near, far) = scene
                .camera
                .pixel_ray_points(i % size, i / size, size, size);
            let o = inv.transform_point3(near);
            let d = inv.transform_vector3(far - near);
            let (mut t0, mut t1) = (0.0f32, 1.0f32);
            for a in 0..3 {
                let (lo, hi) = ((-0.5 - o[a]) / d[a], (0.5 - o[a]) / d[a]);
                t0 = t0.max(lo.min(hi));
                t1 = t1.min(lo.max(hi));
            }
            t0 <= t1
        })
        .collect()
}

/// The pixels within `r` pixels (Chebyshev) of a set pixel of `mask` (a `size`² image).
fn dilate(mask: &[bool], size: u32, r: i32) -> Vec<bool> {
    let s = size as i32;
    (0..s * s)
        .map(|i| {
            let (x, y) = (i % s, i / s);
            (-r..=r).any(|dy| {
                (-r..=r).any(|dx| {
                    let (qx, qy) = (x + dx, y + dy);
                    (0..s).contains(&qx) && (0..s).contains(&qy) && mask[(qy * s + qx) as usize]
                })
            })
        })
        .collect()
}

/// Motion vectors for moving objects: the cube of [`mover_lit_from_the_camera`] moves
/// (0.25 m/s) and turns while the camera stays; TAA runs 24 frames 0.035 s of scene time
/// apart (about a pixel of motion per frame at 64²), with motion vectors and, for
/// comparison, reprojecting with the camera only (as before motion vectors).
///
/// (a) No ghost where the cube was: at every pixel the cube covered in the last 8 frames and
/// now lies at least 2 px from (the centre-sampled coverage of the current cube: a jittered
/// sample moves a silhouette by at most half a pixel, and the 3×3 neighbourhood adds one),
/// every sample of the pixel's 3×3 neighbourhood in the last frame is background, so TAA
/// clips the history (the cube's colour) into their YCoCg box before blending: the output
/// lies in the box (a convex mix of a point in it and its centre sample). In RGB a point of
/// that box differs from the box's samples by at most the sum of the three YCoCg ranges, each
/// at most the RGB range of the samples (|Y|, |Co|, |Cg| weights sum to 1), i.e. 3× the
/// range, and the samples lie within 2 px of the pixel: the bound is 3× the range of the
/// fresh (un-jittered) render's 5×5 block around the pixel, plus 2e-3 for the jitter's
/// sub-pixel shading changes. A ghost of the cube (0.2 darker than the wall) breaks it.
///
/// (b) The cube itself is reprojected from where it was: its pixels' error against the fresh
/// render is below that of the camera-only reprojection (whose history there is the wall,
/// clipped towards the cube's neighbourhood); measured 0.052 against 0.067 (mean |ΔL|), bound
/// 0.9×.
#[test]
fn moving_objects_leave_no_ghost() {
    use voxgi::render::render_animation;
    const SIZE: u32 = 64;
    let scene = mover_lit_from_the_camera();
    let mover = scene
        .objects
        .iter()
        .find(|o| o.name == "mover")
        .expect("the mover");
    let times: Vec<f32> = (0..24).map(|k| 0.1 + 0.035 * k as f32).collect();
    let t_end = *times.last().expect("times");
    let ctx = common::context();
    let settings = |taa: Option<TaaSettings>, time_s: f32| RenderSettings {
        width: SIZE,
        height: SIZE,
        time_s,
        post: PostSettings {
            taa,
            ..Default::default()
        },
        ..Default::default()
    };
    let taa = |motion_vectors: bool| TaaSettings {
        motion_vectors,
        ..Default::default()
    };
    let fresh = render_image(&ctx, &scene, &settings(None, t_end))
        .expect("renders")
        .hdr;
    let with =
        render_animation(&ctx, &scene, &settings(Some(taa(true)), 0.0), &times).expect("renders");
    let without =
        render_animation(&ctx, &scene, &settings(Some(taa(false)), 0.0), &times).expect("renders");
    common::assert_no_validation_messages(&ctx);
    let last = times.len() - 1;
    let (with, without) = (&with[last].data, &without[last].data);
    let cover: Vec<Vec<bool>> = times
        .iter()
        .map(|&t| cube_coverage(&scene, mover.transform_at(t), SIZE))
        .collect();
    let n = (SIZE * SIZE) as usize;
    let near_now = dilate(&cover[last], SIZE, 2);
    let left: Vec<usize> = (0..n)
        .filter(|&i| !near_now[i] && cover[last - 8..last].iter().any(|c| c[i]))
        .collect();
    let s = SIZE as i32;
    let (mut worst_excess, mut worst_ghost) = (f32::MIN, 0.0f32);
    for &i in &left {
        let (x, y) = (i as i32 % s, i as i32 / s);
        for (c, (&got, &want)) in with[i].iter().zip(&fresh.data[i]).enumerate() {
            let (mut lo, mut hi) = (f32::MAX, f32::MIN);
            for q in 0..25 {
                let (qx, qy) = (x + q % 5 - 2, y + q / 5 - 2);
                if (0..s).contains(&qx) && (0..s).contains(&qy) {
                    let v = fresh.data[(qy * s + qx) as usize][c];
                    (lo, hi) = (lo.min(v), hi.max(v));
                }
            }
            let ghost = (got - want).abs();
            worst_ghost = worst_ghost.max(ghost);
            worst_excess = worst_excess.max(ghost - (3.0 * (hi - lo) + 2e-3));
        }
    }
    let now = &cover[last];
    let e_with = masked_error(with, &fresh.data, now);
    let e_without = masked_error(without, &fresh.data, now);
    println!(
        "where the cube was ({} px): worst |TAA − fresh| {worst_ghost:.4}, worst excess over \
         the bound {worst_excess:.4}; on the cube ({} px): mean error with motion vectors \
         {e_with:.4}, camera only {e_without:.4}",
        left.len(),
        now.iter().filter(|&&m| m).count()
    );
    assert!(
        left.len() >= 40,
        "the cube moved off {} px only",
        left.len()
    );
    assert!(
        worst_excess <= 0.0,
        "a ghost {worst_excess} above the bound"
    );
    assert!(e_with < 0.9 * e_without, "{e_with} vs {e_without}");
}

/// Motion vectors exist only where a scene has moving objects: with the mover under TAA the
/// frame's transients grow by exactly the motion image (R16G16 float, 4 bytes per pixel)
/// when they are asked for; in a scene without moving objects the setting changes nothing,
/// neither the transients nor a bit of the TAA image (the G-buffer and TAA compile without
/// the motion code, as before motion vectors existed).
#[test]
fn only_moving_scenes_have_motion_vectors() {
    const SIZE: u32 = 32;
    let ctx = common::context();
    let render = |scene: &voxgi::scene::Scene, motion_vectors: bool| {
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            post: PostSettings {
                taa: Some(TaaSettings {
                    motion_vectors,
                    frames: 4,
                    ..Default::default()
                }),
                ..Default::default()
            },
            ..Default::default()
        };
        render_image(&ctx, scene, &settings).expect("renders")
    };
    let mover = mover_lit_from_the_camera();
    let (on, off) = (render(&mover, true), render(&mover, false));
    assert_eq!(
        on.transient_bytes.1 - off.transient_bytes.1,
        u64::from(SIZE * SIZE * 4),
        "unaliased transient bytes"
    );
    let still = load_scene_arg(Some("cornell")).expect("scene");
    let (on, off) = (render(&still, true), render(&still, false));
    common::assert_no_validation_messages(&ctx);
    assert_eq!(on.hdr.data, off.hdr.data);
    assert_eq!(on.transient_bytes, off.transient_bytes);
}

/// Six bars, 5 cm wide and 40 cm tall, 5 cm apart, alternately emissive (2 W/(m² sr)) and
/// black, before a black wall; no lights. All move 0.6 m along +x in 1 s (keyframes), so
/// the group is a striped ("textured") moving object: every 3×3 neighbourhood on it holds
/// both colours, and TAA's clip box keeps whatever history it is given there.
fn striped_mover() -> voxgi::scene::Scene {
    let mut text = String::from(
        "[camera]\nposition = [0.0, 0.0, -1.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 50.0\n\
         [[objects]]\nbuiltin = \"quad\"\ntranslate = [0.0, 0.0, 0.3]\n\
         rotate_deg = [-90.0, 0.0, 0.0]\nscale = [3.0, 1.0, 3.0]\nmaterial = { albedo = 0.0 }\n",
    );
    for k in 0..6 {
        let x = -0.55 + 0.1 * k as f32;
        let emission = if k % 2 == 0 { 2.0 } else { 0.0 };
        text += &format!(
            "[[objects]]\nbuiltin = \"cube\"\nscale = [0.05, 0.4, 0.05]\n\
             material = {{ albedo = 0.0, emission_w_sr_m2 = {emission:.1} }}\n\
             [objects.animation]\nloop = false\n\
             [[objects.animation.keyframes]]\ntime_s = 0.0\ntranslate = [{x}, 0.0, 0.0]\n\
             [[objects.animation.keyframes]]\ntime_s = 1.0\ntranslate = [{}, 0.0, 0.0]\n",
            x + 0.6
        );
    }
    voxgi::scene::Scene::from_toml_str(
        &text,
        std::path::Path::new("<striped mover>"),
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")),
    )
    .expect("parses")
}

/// Motion vectors on a striped moving object ([`striped_mover`], 24 TAA frames 0.035 s
/// apart: about 1.4 px per frame at 64²): over the pixels the bars cover at the last frame,
/// the TAA image with motion vectors stays much closer to a fresh render than the one
/// reprojected with the camera only, whose history there is the stripes a frame or more ago
/// (the stripes' period is 7 px, so the clip box, spanning both colours, keeps it), and as
/// close as a still frame's TAA image (whose difference from the fresh render is its
/// anti-aliasing). Measured 0.032 with, 0.222 without, 0.031 still (mean |ΔL| over 530 px);
/// bounds: below half the camera-only error and 1.25× the still frame's.
#[test]
fn striped_moving_objects_keep_their_stripes() {
    use voxgi::render::render_animation;
    const SIZE: u32 = 64;
    let scene = striped_mover();
    let times: Vec<f32> = (0..24).map(|k| 0.1 + 0.035 * k as f32).collect();
    let t_end = *times.last().expect("times");
    let ctx = common::context();
    let settings = |taa: Option<TaaSettings>, time_s: f32| RenderSettings {
        width: SIZE,
        height: SIZE,
        time_s,
        post: PostSettings {
            taa,
            ..Default::default()
        },
        ..Default::default()
    };
    let taa = |motion_vectors: bool| TaaSettings {
        motion_vectors,
        ..Default::default()
    };
    let fresh = render_image(&ctx, &scene, &settings(None, t_end))
        .expect("renders")
        .hdr;
    let still = render_image(&ctx, &scene, &settings(Some(taa(true)), t_end))
        .expect("renders")
        .hdr;
    let with =
        render_animation(&ctx, &scene, &settings(Some(taa(true)), 0.0), &times).expect("renders");
    let without =
        render_animation(&ctx, &scene, &settings(Some(taa(false)), 0.0), &times).expect("renders");
    common::assert_no_validation_messages(&ctx);
    let last = times.len() - 1;
    let bars: Vec<Vec<bool>> = scene.objects[1..]
        .iter()
        .map(|o| cube_coverage(&scene, o.transform_at(t_end), SIZE))
        .collect();
    let covered: Vec<bool> = (0..(SIZE * SIZE) as usize)
        .map(|i| bars.iter().any(|m| m[i]))
        .collect();
    let e_with = masked_error(&with[last].data, &fresh.data, &covered);
    let e_without = masked_error(&without[last].data, &fresh.data, &covered);
    let e_still = masked_error(&still.data, &fresh.data, &covered);
    println!(
        "striped mover ({} px): mean |TAA − fresh| with motion vectors {e_with:.4}, camera only \
         {e_without:.4}, a still frame's TAA {e_still:.4}",
        covered.iter().filter(|&&m| m).count()
    );
    assert!(e_with < 0.5 * e_without, "{e_with} vs {e_without}");
    assert!(
        e_with < 1.25 * e_still,
        "{e_with} vs a still frame's {e_still}"
    );
}
