//! Tone mapping (`glsl/tonemap.comp`): every operator against its closed form evaluated here,
//! on a known radiance image fed through the graph, within ±1 LSB of the 8-bit sRGB output.
//! Validation on.

mod common;

use voxgi::graph::{run_once, Access, RenderGraph, Shader};
use voxgi::post::{ToneMap, ToneOperator, TonemapPass};
use voxgi::vk::{vk, ImageDesc};

const W: u32 = 32;
const H: u32 = 4;

/// The input radiance: row 0 grey from 1e-4 to 40 W/(m²·sr) (log-spaced), rows 1–3 the same
/// scale times saturated colors, so luminance-based operators are tested off the grey axis.
fn radiance() -> Vec<[f32; 4]> {
    let tints = [
        [1.0, 1.0, 1.0],
        [1.0, 0.3, 0.05],
        [0.1, 0.8, 0.3],
        [0.2, 0.1, 1.5],
    ];
    let mut px = Vec::new();
    for tint in tints {
        for x in 0..W {
            let l = 1e-4f32 * (40.0f32 / 1e-4).powf(x as f32 / (W - 1) as f32);
            px.push([l * tint[0], l * tint[1], l * tint[2], 1.0]);
        }
    }
    px
}

fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The operators' closed forms, in f64: Reinhard-style logarithmic mapping with white w,
/// L_d = ln(1 + L)/ln(1 + w); Drago et al. 2003, Eq. 4 with L_d,max = 100 cd/m² (so its
/// factor L_d,max · 0.01 is 1), L_d = ln(L + 1) / (log10(w + 1) · ln(2 + 8 (L/w)^(ln b / ln 0.5)));
/// the luminance operators scale the color by L_d / L. Filmic: the ACES fit of Narkowicz
/// 2015, x(2.51x + 0.03)/(x(2.43x + 0.59) + 0.14) per channel. Then clamp to [0, 1].
fn tone_map(tm: &ToneMap, rgb: [f32; 3]) -> [f64; 3] {
    let c = rgb.map(|v| f64::from(v.max(0.0)) * f64::from(tm.exposure));
    let l = luminance(c);
    let w = f64::from(tm.white);
    let scale = |ld: f64| if l > 0.0 { ld / l } else { 0.0 };
    let out = match tm.operator {
        ToneOperator::Linear => c,
        ToneOperator::Logarithmic => {
            let s = scale((1.0 + l).ln() / (1.0 + w).ln());
            c.map(|v| v * s)
        }
        ToneOperator::Drago => {
            let b = f64::from(tm.drago_bias);
            let ld = (l + 1.0).ln()
                / ((w + 1.0).log10() * (2.0 + 8.0 * (l / w).powf(b.ln() / 0.5f64.ln())).ln());
            let s = scale(ld);
            c.map(|v| v * s)
        }
        ToneOperator::Filmic => c.map(|x| x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)),
    };
    out.map(|v| v.clamp(0.0, 1.0))
}

/// IEC 61966-2-1 sRGB encoding, as an 8-bit value (unrounded).
fn srgb_8bit(v: f64) -> f64 {
    let e = if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    e * 255.0
}

/// Runs the `tonemap` pass over [`radiance`] and returns the RGBA8 output.
fn run_tonemap(tm: ToneMap) -> Vec<u8> {
    let ctx = common::context();
    let bytes: Vec<u8> = bytemuck::cast_slice(&radiance()).to_vec();
    let desc = ImageDesc::new_2d("radiance", vk::Format::R32G32B32A32_SFLOAT, W, H);
    let input = ctx.upload_image(&desc, &[bytes]).expect("upload");
    let sampler = ctx
        .create_sampler(vk::Filter::NEAREST, false)
        .expect("sampler");
    let pass = TonemapPass::new(&ctx, sampler.raw).expect("pipeline");
    let readback = voxgi::graph::readback_buffer(&ctx, "ldr", u64::from(W * H * 4)).unwrap();
    let mut g = RenderGraph::new();
    let hdr = g.import_image(&input, Access::Sampled(Shader::Compute));
    let ldr = pass.declare(&mut g, hdr, None, tm, (W, H));
    let out = g.import_buffer(&readback, Access::HostRead);
    let extent = vk::Extent3D {
        width: W,
        height: H,
        depth: 1,
    };
    g.add_pass("readback_ldr")
        .read(ldr, Access::TransferRead)
        .write(out, Access::TransferWrite)
        .record(move |ctx| {
            let buffer = ctx.buffer(out).raw;
            ctx.cmd
                .copy_image_to_buffer(ctx.image(ldr).raw, extent, 0, 1, buffer)
        });
    run_once(&ctx, g).expect("runs");
    let pixels = readback.mapped().expect("host visible").to_vec();
    common::assert_no_validation_messages(&ctx);
    pixels
}

fn check(tm: ToneMap) {
    let gpu = run_tonemap(tm);
    let mut distinct = std::collections::BTreeSet::new();
    for (i, p) in radiance().iter().enumerate() {
        let want = tone_map(&tm, [p[0], p[1], p[2]]).map(srgb_8bit);
        for ch in 0..3 {
            let got = gpu[i * 4 + ch];
            distinct.insert(got);
            // ±1 LSB: the GPU's f32 pow/log and its float-to-UNORM rounding against the exact
            // value; anything wrong in a formula moves a mid-range value by more.
            assert!(
                (f64::from(got) - want[ch]).abs() <= 1.0,
                "{:?} pixel {i} channel {ch}: {got}, closed form {:.3} (radiance {p:?})",
                tm.operator,
                want[ch]
            );
        }
        assert_eq!(gpu[i * 4 + 3], 255, "alpha");
    }
    // The ramp spans the operator's range, not just black and white.
    assert!(
        distinct.len() > 40,
        "{:?}: {} distinct values",
        tm.operator,
        distinct.len()
    );
}

#[test]
fn every_tone_operator_matches_its_closed_form() {
    for operator in [
        ToneOperator::Linear,
        ToneOperator::Logarithmic,
        ToneOperator::Drago,
        ToneOperator::Filmic,
    ] {
        check(ToneMap {
            operator,
            exposure: 0.8,
            white: 4.0,
            drago_bias: 0.85,
            dither: false,
        });
    }
}

#[test]
fn drago_bias_and_white_change_the_curve_as_the_closed_form_says() {
    // The other end of Drago's bias range and another white point, so that a shader that
    // ignored either would fail one of the two tests.
    check(ToneMap {
        operator: ToneOperator::Drago,
        exposure: 1.5,
        white: 20.0,
        drago_bias: 0.5,
        dither: false,
    });
    check(ToneMap {
        operator: ToneOperator::Logarithmic,
        exposure: 1.5,
        white: 20.0,
        drago_bias: 0.5,
        dither: false,
    });
}
