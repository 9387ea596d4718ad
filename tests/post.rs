//! Post-processing on known images fed through the graph: auto exposure converges to key / L
//! on a uniform scene, bloom conserves the total radiance and spreads a point, FXAA leaves
//! flat regions unchanged and smooths a hard diagonal edge, dither keeps the mean of a gradient
//! without bands. Validation on.

mod common;

use voxgi::graph::{
    add_readback, readback_buffer, run_frames, Access, GraphExecutor, ImageHandle, RenderGraph,
    Shader,
};
use voxgi::post::TonemapPass;
use voxgi::post::{AutoExposure, BloomPass, ExposurePass, FxaaPass, ToneMap, ToneOperator};
use voxgi::vk::{vk, Context, ImageDesc, MAX_FRAMES_IN_FLIGHT};

/// Uploads `px` (`w`×`h`, RGBA32F) as a sampled image.
fn upload_hdr(ctx: &Context, px: &[[f32; 4]], (w, h): (u32, u32)) -> voxgi::vk::Image {
    let desc = ImageDesc::new_2d("input", vk::Format::R32G32B32A32_SFLOAT, w, h);
    ctx.upload_image(&desc, &[bytemuck::cast_slice(px).to_vec()])
        .expect("upload")
}

/// Builds a graph with `declare` (given the imported input), reads back the image it returns
/// (`texel_bytes` per texel), runs it `frames` times and returns the bytes.
fn run_graph(
    ctx: &Context,
    input: &voxgi::vk::Image,
    frames: usize,
    texel_bytes: u64,
    declare: impl FnOnce(&mut RenderGraph, ImageHandle) -> ImageHandle,
) -> Vec<u8> {
    let (w, h) = (input.desc.width, input.desc.height);
    let readback = readback_buffer(ctx, "out", u64::from(w * h) * texel_bytes).expect("buffer");
    let mut g = RenderGraph::new();
    let i = g.import_image(input, Access::Sampled(Shader::Compute));
    let out = declare(&mut g, i);
    let buf = g.import_buffer(&readback, Access::HostRead);
    add_readback(&mut g, "readback_out", out, buf);
    let exec = GraphExecutor::new(ctx, g, MAX_FRAMES_IN_FLIGHT).expect("compiles");
    run_frames(ctx, &exec, frames, 0, |_| {}).expect("runs");
    let bytes = readback.mapped().expect("mapped").to_vec();
    bytes
}

fn nearest(ctx: &Context) -> voxgi::vk::Sampler {
    ctx.create_sampler(vk::Filter::NEAREST, false)
        .expect("sampler")
}

/// Tone-maps `px` linearly (exposure 1 unless `auto`) and returns the RGBA8 pixels.
fn tone_map(
    ctx: &Context,
    px: &[[f32; 4]],
    size: (u32, u32),
    tm: ToneMap,
    auto: Option<&ExposurePass>,
    frames: usize,
) -> Vec<u8> {
    let sampler = nearest(ctx);
    let pass = TonemapPass::new(ctx, sampler.raw).expect("pipeline");
    let input = upload_hdr(ctx, px, size);
    run_graph(ctx, &input, frames, 4, |g, i| {
        let exposure = auto.map(|e| e.declare(g, i));
        pass.declare(g, i, exposure, tm, size)
    })
}

fn srgb_encode(v: f64) -> f64 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(e: f64) -> f64 {
    if e <= 0.04045 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

const LINEAR: ToneMap = ToneMap {
    operator: ToneOperator::Linear,
    exposure: 1.0,
    white: 1.0,
    drago_bias: 0.85,
    dither: false,
};

/// A uniform frame of luminance L has the log-average L + δ (δ = 1e-4, Reinhard et al. 2002
/// Eq. 1), so auto exposure sets key / (L + δ) in its first frame and keeps it; after the
/// scene switches to luminance L₂ it adapts in log space, ln e_k = ln t₂ + (1 − a)^k (ln t₁ −
/// ln t₂) after k frames. The exposure is then read through the tone-mapping pass: linear
/// tone mapping of the uniform frame gives the key itself, sRGB-encoded, within 1 LSB.
/// Bounds: f32 log/exp and the reduction's sums over 3072 equal terms err by ~1e-6
/// relative; 1e-4 leaves room, a wrong key, mean or adaptation step is off by percents.
#[test]
fn auto_exposure_converges_to_key_over_luminance() {
    let ctx = common::context();
    let size = (64, 48);
    let n = (size.0 * size.1) as usize;
    let settings = AutoExposure {
        key: 0.18,
        adaptation: 0.2,
    };
    let sampler = nearest(&ctx);
    let pass = ExposurePass::new(&ctx, settings, sampler.raw).expect("pass");
    // Rec. 709 luminance of (0.5, 0.25, 1.0) times s.
    let lum = |s: f64| s * (0.2126 * 0.5 + 0.7152 * 0.25 + 0.0722);
    let frame = |s: f32| vec![[0.5 * s, 0.25 * s, s, 1.0]; n];
    let exposure_after = |s: f32, frames: usize| {
        let input = upload_hdr(&ctx, &frame(s), size);
        let readback = readback_buffer(&ctx, "exposure", 8).expect("buffer");
        let mut g = RenderGraph::new();
        let i = g.import_image(&input, Access::Sampled(Shader::Compute));
        let e = pass.declare(&mut g, i);
        let buf = g.import_buffer(&readback, Access::HostRead);
        g.add_pass("readback_exposure")
            .read(e, Access::TransferRead)
            .write(buf, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd
                    .copy_buffer(ctx.buffer(e).raw, ctx.buffer(buf).raw, 8)
            });
        let exec = GraphExecutor::new(&ctx, g, MAX_FRAMES_IN_FLIGHT).expect("compiles");
        run_frames(&ctx, &exec, frames, 0, |_| {}).expect("runs");
        let v: [f32; 2] = bytemuck::cast_slice(readback.mapped().expect("mapped"))[..2]
            .try_into()
            .expect("two floats");
        f64::from(v[0])
    };
    let delta = 1e-4;
    let t1 = 0.18 / (lum(2.0) + delta);
    let e1 = exposure_after(2.0, 3);
    assert!(
        (e1 / t1 - 1.0).abs() < 1e-4,
        "exposure {e1}, key / L̄ = {t1}"
    );
    let t2 = 0.18 / (lum(16.0) + delta);
    let k = 5;
    let want = (t2.ln() + 0.8f64.powi(k) * (t1.ln() - t2.ln())).exp();
    let e2 = exposure_after(16.0, k as usize);
    assert!(
        (e2 / want - 1.0).abs() < 1e-4,
        "exposure {e2}, closed form {want}"
    );
    // Converged, linear tone mapping shows the key: every channel scaled by key / L.
    let converged = exposure_after(16.0, 60);
    assert!((converged / t2 - 1.0).abs() < 1e-4, "{converged} vs {t2}");
    let ldr = tone_map(&ctx, &frame(16.0), size, LINEAR, Some(&pass), 1);
    let scale = t2 * 16.0;
    for (ch, c) in [0.5, 0.25, 1.0].into_iter().enumerate() {
        let want = srgb_encode((c * scale).min(1.0)) * 255.0;
        assert!(
            (f64::from(ldr[ch]) - want).abs() <= 1.0,
            "channel {ch}: {} vs {want:.2}",
            ldr[ch]
        );
    }
    common::assert_no_validation_messages(&ctx);
}

/// A ramp spanning one 8-bit step, 64 columns × 64 rows, tone-mapped linearly: column x has
/// the encoded value (100 + x/64)/255 exactly (the radiance is its sRGB decoding). Without
/// dither every row is the same two levels (a band edge mid-ramp), column means off by up to
/// 0.5 LSB. With triangular dither of ±1 LSB the quantized value's mean is the value itself
/// and its error variance 1/6 + 1/12 = 1/4 LSB² (Lipshitz et al. 1992): a column mean of 64
/// pixels errs by σ = 1/16 LSB, so every column must be within 0.25 LSB (4σ) and the whole
/// image's mean within 0.04 LSB (5σ of 1/128).
#[test]
fn dither_keeps_the_mean_and_removes_banding() {
    let ctx = common::context();
    let (w, h) = (64u32, 64u32);
    let target = |x: u32| 100.0 + f64::from(x) / f64::from(w);
    let px: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let v = srgb_decode(target(i % w) / 255.0) as f32;
            [v, v, v, 1.0]
        })
        .collect();
    let column_means = |ldr: &[u8]| -> Vec<f64> {
        (0..w)
            .map(|x| {
                (0..h)
                    .map(|y| f64::from(ldr[((y * w + x) * 4) as usize]))
                    .sum::<f64>()
                    / f64::from(h)
            })
            .collect()
    };
    let plain = column_means(&tone_map(&ctx, &px, (w, h), LINEAR, None, 1));
    let dithered = column_means(&tone_map(
        &ctx,
        &px,
        (w, h),
        ToneMap {
            dither: true,
            ..LINEAR
        },
        None,
        1,
    ));
    common::assert_no_validation_messages(&ctx);
    let worst = |m: &[f64]| {
        (0..w)
            .map(|x| (m[x as usize] - target(x)).abs())
            .fold(0.0, f64::max)
    };
    let levels: std::collections::BTreeSet<u64> =
        plain.iter().map(|m| (m * 1000.0) as u64).collect();
    assert!(
        levels.len() <= 2,
        "undithered, the ramp is two bands: {levels:?}"
    );
    assert!(
        worst(&plain) > 0.4,
        "undithered columns are off by up to half a step"
    );
    assert!(
        worst(&dithered) < 0.25,
        "dithered column off by {}",
        worst(&dithered)
    );
    let mean = dithered.iter().sum::<f64>() / f64::from(w);
    let want = (0..w).map(target).sum::<f64>() / f64::from(w);
    assert!((mean - want).abs() < 0.04, "mean {mean} vs {want}");
}

/// Bloom moves light, never makes or loses it: the sum of the output's radiance equals the
/// input's (each box mean and bilinear ×2 upsampling conserves radiance × area exactly; f32
/// sums over 4096 pixels leave ~1e-6 relative, bound 1e-4). A single bright pixel spreads:
/// the centre keeps (1 − s) of its value plus its share of the blur, and pixels 8 px away
/// (inside the widest 64-px level) receive light.
#[test]
fn bloom_conserves_energy_and_spreads_a_point() {
    let ctx = common::context();
    let size = (64u32, 64u32);
    let n = (size.0 * size.1) as usize;
    let sampler = nearest(&ctx);
    let strength = 0.3;
    let pass = BloomPass::new(&ctx, strength, sampler.raw).expect("pass");
    let bloom = |px: &[[f32; 4]]| -> Vec<[f32; 4]> {
        let input = upload_hdr(&ctx, px, size);
        let out = run_graph(&ctx, &input, 1, 16, |g, i| pass.declare(g, i, size));
        bytemuck::cast_slice(&out).to_vec()
    };
    let total = |px: &[[f32; 4]]| {
        px.iter().fold([0.0f64; 3], |s, p| {
            [
                s[0] + f64::from(p[0]),
                s[1] + f64::from(p[1]),
                s[2] + f64::from(p[2]),
            ]
        })
    };
    // A textured frame: a hash pattern with a few bright spots.
    let textured: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let v = ((i * 2654435761) % 1000) as f32 / 1000.0;
            let spot = if i % 611 == 0 { 50.0 } else { 0.0 };
            [v + spot, 0.5 * v, 1.0 - v, 1.0]
        })
        .collect();
    let out = bloom(&textured);
    let (a, b) = (total(&textured), total(&out));
    for c in 0..3 {
        assert!(
            (b[c] / a[c] - 1.0).abs() < 1e-4,
            "channel {c}: {} → {}",
            a[c],
            b[c]
        );
    }
    let mut point = vec![[0.0f32, 0.0, 0.0, 1.0]; n];
    let centre = (32 * size.0 + 32) as usize;
    point[centre] = [100.0, 100.0, 100.0, 1.0];
    let out = bloom(&point);
    assert!(
        (total(&out)[0] / 100.0 - 1.0).abs() < 1e-4,
        "the point's energy stays"
    );
    let c = out[centre][0];
    assert!(
        c > (1.0 - strength) * 100.0 && c < 100.0,
        "the centre keeps most: {c}"
    );
    for off in [8usize, 8 * size.0 as usize] {
        assert!(out[centre + off][0] > 0.0, "light reaches 8 px away");
    }
    common::assert_no_validation_messages(&ctx);
}

/// FXAA on a 64×64 RGBA8 image, black above and white below a hard edge along the line
/// y = 0.4 x + 20 (a staircase of 2.5 px steps). The flat halves, i.e. every pixel more than
/// 2.5 px from the line (FXAA's early exit sees no contrast in its 4-neighbourhood there), are
/// bit-identical. Near the line the error against each pixel's exact coverage of the white
/// half-plane (in encoded values: FXAA blends what it reads) must at least halve — the
/// staircase's pixels are all or nothing, FXAA 3.11's edge search sets each pixel's blend from
/// its position along the step (measured 12.7 → 3.9 of 255).
#[test]
fn fxaa_keeps_flat_regions_and_smooths_a_diagonal_edge() {
    let ctx = common::context();
    let (w, h) = (64u32, 64u32);
    let line = |x: f64| 0.4 * x + 20.0;
    // Coverage of the region y > line(x) within pixel (x, y), by 64×64 sub-samples (exact to
    // 1/64 for a line).
    let coverage = |x: u32, y: u32| {
        let mut k = 0;
        for sy in 0..64 {
            for sx in 0..64 {
                let (fx, fy) = (
                    f64::from(x) + (f64::from(sx) + 0.5) / 64.0,
                    f64::from(y) + (f64::from(sy) + 0.5) / 64.0,
                );
                k += u32::from(fy > line(fx));
            }
        }
        f64::from(k) / 4096.0
    };
    let input: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            let v = if f64::from(y) + 0.5 > line(f64::from(x) + 0.5) {
                255
            } else {
                0
            };
            [v, v, v, 255]
        })
        .collect();
    let desc = ImageDesc::new_2d("ldr", vk::Format::R8G8B8A8_UNORM, w, h);
    let image = ctx
        .upload_image(&desc, std::slice::from_ref(&input))
        .expect("upload");
    let pass = FxaaPass::new(&ctx).expect("pass");
    let out = run_graph(&ctx, &image, 1, 4, |g, i| pass.declare(g, i, (w, h)));
    common::assert_no_validation_messages(&ctx);
    let (mut err_in, mut err_out, mut edge_pixels) = (0.0, 0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = ((y * w + x) * 4) as usize;
            let d = (f64::from(y) + 0.5 - line(f64::from(x) + 0.5)).abs();
            if d > 2.5 {
                assert_eq!(
                    out[i..i + 4],
                    input[i..i + 4],
                    "flat pixel ({x}, {y}) changed"
                );
                continue;
            }
            if x == 0 || x == w - 1 {
                continue;
            }
            let want = coverage(x, y) * 255.0;
            err_in += (f64::from(input[i]) - want).abs();
            err_out += (f64::from(out[i]) - want).abs();
            edge_pixels += 1;
        }
    }
    let (err_in, err_out) = (err_in / edge_pixels as f64, err_out / edge_pixels as f64);
    println!("edge error against coverage: input {err_in:.2}, FXAA {err_out:.2} (8-bit units)");
    assert!(
        err_out < 0.8 * err_in,
        "FXAA error {err_out:.2} vs staircase {err_in:.2}"
    );
}
