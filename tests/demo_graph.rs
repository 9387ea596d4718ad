//! The demo graph on a real device: pixel values, culling, aliasing, timings, and zero
//! validation (including synchronization validation) messages.

mod common;

use voxgi::demo::{expected_pixel, Demo};
use voxgi::vk::{FrameLoop, MAX_FRAMES_IN_FLIGHT};

#[test]
fn demo_frame_reads_back_the_expected_pixels_without_validation_messages() {
    let ctx = common::context();
    let (w, h) = (67, 45); // not multiples of the 8x8 workgroup: edges must be handled
    let demo = Demo::new(&ctx, w, h).expect("demo pipelines");
    let exec = demo
        .executor(&ctx, MAX_FRAMES_IN_FLIGHT)
        .expect("demo graph compiles");
    let c = exec.compiled();
    let live: Vec<&str> = c.order.iter().map(|&p| c.pass_names[p].as_str()).collect();
    assert_eq!(
        live,
        ["demo_gradient", "demo_blit", "demo_pack", "demo_readback"]
    );
    assert_eq!(
        c.culled
            .iter()
            .map(|&p| c.pass_names[p].as_str())
            .collect::<Vec<_>>(),
        ["demo_unused"]
    );
    assert!(
        c.memory.peak_aliased_bytes < c.memory.unaliased_bytes,
        "pattern and packed images alias"
    );

    let mut frames = FrameLoop::new(&ctx, MAX_FRAMES_IN_FLIGHT, 8).expect("frame loop");
    let mut timings = Vec::new();
    for _ in 0..5 {
        let (slot, cmd, ts, done) = frames.begin(&ctx).expect("begin frame");
        exec.record(&cmd, slot, ts);
        if !done.is_empty() {
            timings.push(done);
        }
        frames.submit(&ctx, &[], &[]).expect("submit");
    }
    timings.extend(frames.finish(&ctx).expect("finish"));

    let pixels = demo.pixels();
    assert_eq!(pixels.len(), (w * h * 4) as usize);
    let mut worst = 0i32;
    for y in 0..h {
        for x in 0..w {
            let i = ((y * w + x) * 4) as usize;
            let want = expected_pixel(x, y, w, h);
            for ch in 0..4 {
                worst = worst.max((i32::from(pixels[i + ch]) - i32::from(want[ch])).abs());
            }
        }
    }
    // Float -> UNORM8 conversion may round either way at exact half steps.
    assert!(
        worst <= 1,
        "pixels differ from the pattern by up to {worst}"
    );

    // Every frame reported a timestamp pair per live pass, in order, with sane values.
    assert_eq!(timings.len(), 5);
    for frame in &timings {
        let names: Vec<&str> = frame.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, live);
        assert!(frame
            .iter()
            .all(|t| t.gpu_ms.is_finite() && t.gpu_ms >= 0.0 && t.gpu_ms < 10_000.0));
    }

    common::assert_no_validation_messages(&ctx);
}

#[test]
fn device_override_that_matches_nothing_is_a_clear_error() {
    let desc = voxgi::vk::ContextDesc {
        device: Some("no-such-gpu-xyz".into()),
        ..Default::default()
    };
    let err = voxgi::vk::Context::new(&desc)
        .err()
        .expect("no device matches");
    let text = err.to_string();
    assert!(
        text.contains("no-such-gpu-xyz") && text.contains("Devices seen"),
        "{text}"
    );
}

#[test]
fn a_reader_that_closes_stdout_early_ends_the_command_quietly() {
    // `voxgi graph --demo | head -0`: stdout is closed before the dump is written. The
    // command ends quietly and still releases everything (no leak, no teardown message).
    for args in [
        &["--validate", "graph", "--demo"][..],
        &["--validate", "graph", "--width", "32", "--height", "32"][..],
    ] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("run the voxgi binary");
        drop(child.stdout.take());
        let out = child.wait_with_output().expect("wait for voxgi");
        let stderr = String::from_utf8_lossy(&out.stderr).to_lowercase();
        assert!(
            out.status.success()
                && !stderr.contains("panicked")
                && !stderr.contains("error")
                && !stderr.contains("leak"),
            "{args:?}: status {}, stderr:\n{stderr}",
            out.status
        );
    }
}
