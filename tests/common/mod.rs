//! Shared fixture of the Vulkan integration tests: a context with the validation layer and
//! synchronization validation on; `finish` asserts that no message was reported.
#![allow(dead_code)]

use voxgi::vk::{Context, ContextDesc};

/// A validating context on the default device (lavapipe on CI). Without a Vulkan device the
/// test fails with the install hint: these tests never pass silently.
pub fn context() -> Context {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("voxgi-xdg");
        let _ = std::fs::create_dir_all(&dir);
        std::env::set_var("XDG_RUNTIME_DIR", dir);
    }
    let _ = env_logger::builder().is_test(true).try_init();
    match Context::new(&ContextDesc { validation: true, ..Default::default() }) {
        Ok(ctx) => ctx,
        Err(e) => panic!(
            "no Vulkan device with validation layers: {e}\n\
             Install them with tools/setup (Debian/Ubuntu: mesa-vulkan-drivers vulkan-validationlayers libvulkan1)"
        ),
    }
}

/// Fails the test if the validation layers reported anything, listing the messages.
pub fn assert_no_validation_messages(ctx: &Context) {
    let n = ctx.validation.total();
    if n > 0 {
        let msgs = ctx.validation.messages().join("\n---\n");
        panic!("{n} validation message(s):\n{msgs}");
    }
}

/// Runs `frames` frames of `renderer`'s graph (writing its frame constants per slot, as the
/// viewer does) and returns the linear radiance of the last one.
pub fn run_frames(
    ctx: &Context,
    renderer: &mut voxgi::render::Renderer,
    frames: usize,
) -> voxgi::eval::HdrImage {
    use voxgi::graph::GraphExecutor;
    use voxgi::vk::{FrameLoop, MAX_FRAMES_IN_FLIGHT};
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT).expect("graph");
    let mut frame_loop = FrameLoop::new(ctx, MAX_FRAMES_IN_FLIGHT, 64).expect("frame loop");
    for _ in 0..frames {
        let slot = frame_loop.current_slot();
        let (_, cmd, ts, _) = frame_loop.begin(ctx).expect("begin frame");
        renderer.write_frame(slot);
        exec.record(&cmd, slot, ts);
        frame_loop.submit(ctx, &[], &[]).expect("submit");
    }
    frame_loop.finish(ctx).expect("finish");
    frame_loop.destroy(ctx);
    exec.destroy(ctx);
    renderer.hdr_image()
}
