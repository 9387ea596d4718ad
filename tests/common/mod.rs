//! Shared fixture of the Vulkan integration tests: a context with the validation layer and
//! synchronization validation on. Dropping it destroys the device and instance and fails the
//! test on any validation message of its whole life, teardown included (objects never
//! destroyed), and on GPU memory never freed.
#![allow(dead_code)]

use voxgi::vk::{Context, ContextDesc, TeardownReport};

/// The world points where the camera ray through the center of pixel (x, y) of a square
/// `size`² image meets the near and far planes (`Camera::pixel_ray_points`).
pub fn pixel_ray_points(
    scene: &voxgi::scene::Scene,
    x: u32,
    y: u32,
    size: u32,
) -> (glam::Vec3, glam::Vec3) {
    scene.camera.pixel_ray_points(x, y, size, size)
}

/// A validating [`Context`] that checks its own teardown: when it is dropped (at the end of the
/// test, after everything created from it), it destroys the device and instance and panics if
/// the validation layers reported anything at any time or GPU memory was never freed. A
/// check before teardown would miss the layers' reports of objects never destroyed.
pub struct TestContext(Option<Context>);

impl TestContext {
    /// Destroys the context and returns what it left behind instead of asserting on it: for
    /// the tests that check that misuse is reported.
    pub fn finish(mut self) -> TeardownReport {
        self.0
            .take()
            .expect("context alive until finished")
            .finish()
    }
}

impl std::ops::Deref for TestContext {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.0.as_ref().expect("context alive until finished")
    }
}

impl Drop for TestContext {
    fn drop(&mut self) {
        let Some(ctx) = self.0.take() else { return };
        let report = ctx.finish();
        // A test already failing keeps its own message (a second panic would abort).
        if !report.is_clean() && !std::thread::panicking() {
            panic!(
                "{} validation message(s) and {} leaked allocation(s) over the context's life \
                 (teardown included):\n{report}",
                report.validation_messages.len(),
                report.leaked_allocations.len()
            );
        }
    }
}

/// Gives the process an `XDG_RUNTIME_DIR` where it has none (a bare CI container), so that
/// the loader and winit do not warn about it on stderr, which the tests read.
fn ensure_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("voxgi-xdg");
        let _ = std::fs::create_dir_all(&dir);
        std::env::set_var("XDG_RUNTIME_DIR", dir);
    }
}

/// A fresh folder `voxgi-NAME-PID` in the system's temp dir (emptied if it exists).
pub fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("voxgi-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("creates the temp dir");
    dir
}

/// Runs the built `voxgi` binary with `args` and waits for it.
pub fn voxgi(args: &[&str]) -> std::process::Output {
    voxgi_with(args, |_| {})
}

/// [`voxgi`], with `setup` adjusting the command first (its working directory, its
/// environment).
pub fn voxgi_with(
    args: &[&str],
    setup: impl FnOnce(&mut std::process::Command),
) -> std::process::Output {
    ensure_runtime_dir();
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"));
    cmd.args(args);
    setup(&mut cmd);
    cmd.output().expect("the voxgi binary runs")
}

/// A small buffer the transfer queue fills and the host reads, for the negative controls.
pub fn transfer_buffer(ctx: &Context, name: &str) -> voxgi::vk::Buffer {
    use voxgi::vk::{vk, BufferDesc, MemoryLocation};
    ctx.create_buffer(&BufferDesc {
        name: name.into(),
        size_bytes: 256,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        location: MemoryLocation::GpuToCpu,
    })
    .expect("buffer")
}

/// Runs a graph whose one pass fills `target` twice, a deliberate misuse for the negative
/// controls: the graph places barriers only between passes, so nothing orders the second
/// write after the first (synchronization validation's WRITE_AFTER_WRITE hazard).
pub fn run_write_after_write(ctx: &Context, target: &voxgi::vk::Buffer) {
    use voxgi::graph::{run_once, Access, RenderGraph};
    let mut g = RenderGraph::new();
    let out = g.import_buffer(target, Access::HostRead);
    g.add_pass("hazard")
        .write(out, Access::TransferWrite)
        .record(move |p| {
            let raw = p.buffer(out).raw;
            p.cmd.fill_buffer(raw, 1);
            p.cmd.fill_buffer(raw, 2);
        });
    run_once(ctx, g).expect("the graph runs");
}

/// A validating context on the default device (lavapipe on CI), checked at teardown (see
/// [`TestContext`]). Without a Vulkan device the test fails with the install hint: these
/// tests never pass silently.
pub fn context() -> TestContext {
    TestContext(Some(raw_context()))
}

/// A validating context that does not check itself at teardown; call [`Context::finish`].
pub fn raw_context() -> Context {
    ensure_runtime_dir();
    let _ = env_logger::builder().is_test(true).try_init();
    match Context::new(&ContextDesc { validation: true, ..Default::default() }) {
        Ok(ctx) => ctx,
        Err(e) => panic!(
            "no Vulkan device with validation layers: {e}\n\
             Install them with tools/setup (Debian/Ubuntu: mesa-vulkan-drivers vulkan-validationlayers libvulkan1)"
        ),
    }
}

/// Fails the test if the validation layers reported anything so far, listing the messages.
/// (Teardown is checked when the [`TestContext`] drops.)
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
    use voxgi::vk::MAX_FRAMES_IN_FLIGHT;
    let exec = GraphExecutor::new(ctx, renderer.graph(), MAX_FRAMES_IN_FLIGHT).expect("graph");
    voxgi::graph::run_frames(ctx, &exec, frames, 0, |slot| renderer.write_frame(slot))
        .expect("frames run");
    renderer.hdr_image()
}

/// Host-visible copies of every mip level of a GPU voxel column image, for comparing it with
/// the CPU hierarchy.
pub struct VoxelReadback {
    buffers: Vec<voxgi::vk::Buffer>,
    /// Image size of each level (power-of-two padded, see `voxel::gpu`).
    sizes: Vec<(u32, u32)>,
    layers: u32,
}

impl VoxelReadback {
    pub fn new(ctx: &Context, grid: &voxgi::voxel::VoxelGrid, levels: u32) -> Self {
        let (w, h) = voxgi::voxel::gpu::image_extent(grid);
        let layers = grid.layers();
        let sizes: Vec<(u32, u32)> = (0..levels)
            .map(|l| ((w >> l).max(1), (h >> l).max(1)))
            .collect();
        let buffers = sizes
            .iter()
            .enumerate()
            .map(|(l, &(lw, lh))| {
                voxgi::graph::readback_buffer(
                    ctx,
                    &format!("voxel readback {l}"),
                    u64::from(lw * lh * layers) * 16,
                )
                .expect("readback buffer")
            })
            .collect();
        Self {
            buffers,
            sizes,
            layers,
        }
    }

    /// Declares the pass that copies every level of `image` into the buffers.
    pub fn add_pass(&self, g: &mut voxgi::graph::RenderGraph, image: voxgi::graph::ImageHandle) {
        use voxgi::graph::Access;
        let outs: Vec<_> = self
            .buffers
            .iter()
            .map(|b| g.import_buffer(b, Access::HostRead))
            .collect();
        let mut pass = g
            .add_pass("voxel_readback")
            .read(image, Access::TransferRead);
        for &o in &outs {
            pass = pass.write(o, Access::TransferWrite);
        }
        let (sizes, layers) = (self.sizes.clone(), self.layers);
        pass.record(move |ctx| {
            for (l, (&o, &(lw, lh))) in outs.iter().zip(&sizes).enumerate() {
                let extent = voxgi::vk::vk::Extent3D {
                    width: lw,
                    height: lh,
                    depth: 1,
                };
                ctx.cmd.copy_image_to_buffer(
                    ctx.image(image).raw,
                    extent,
                    l as u32,
                    layers,
                    ctx.buffer(o).raw,
                );
            }
        });
    }

    /// Every level read back (after the frame completed), cropped to the CPU hierarchy's
    /// sizes for `grid`. Panics if the padding holds any bit.
    pub fn levels(&self, grid: &voxgi::voxel::VoxelGrid) -> Vec<voxgi::voxel::BitGrid> {
        use voxgi::voxel::bits::mip_extent;
        use voxgi::voxel::BitGrid;
        let layers = self.layers;
        let mut out = Vec::new();
        for (l, (b, &(lw, lh))) in self.buffers.iter().zip(&self.sizes).enumerate() {
            let bytes = &b.mapped().expect("host-visible")[..(lw * lh * layers * 16) as usize];
            let full = BitGrid::from_gpu_bytes(lw, lh, layers, bytes).expect("read-back size");
            let (cw, ch) = (
                mip_extent(grid.res_x(), l as u32),
                mip_extent(grid.res_y(), l as u32),
            );
            let mut crop = BitGrid::new(cw, ch, layers);
            for layer in 0..layers {
                for y in 0..lh {
                    for x in 0..lw {
                        let c = full.column(x, y, layer);
                        if x < cw && y < ch {
                            *crop.column_mut(x, y, layer) = c;
                        } else {
                            assert_eq!(c, [0; 4], "padding texel ({x},{y}) of level {l} is set");
                        }
                    }
                }
            }
            out.push(crop);
        }
        out
    }
}

/// The shipped animated test scene: Cornell walls and a keyframed cube that moves, turns and
/// partly leaves the box (`assets/scenes/cornell_mover.toml`).
pub fn animated_scene() -> voxgi::scene::Scene {
    voxgi::scene::Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/scenes/cornell_mover.toml"
    ))
    .expect("animated test scene loads")
}

/// Renders `scene` at `size`² with default settings but `gi`, on a fresh validating context,
/// failing the test on any validation message.
pub fn render_with_gi(
    scene: &voxgi::scene::Scene,
    size: u32,
    gi: voxgi::gi::GiSettings,
) -> voxgi::render::RenderOutput {
    let ctx = context();
    let settings = voxgi::render::RenderSettings {
        width: size,
        height: size,
        gi,
        ..Default::default()
    };
    let out = voxgi::render::render_image(&ctx, scene, &settings).expect("renders");
    assert_no_validation_messages(&ctx);
    out
}
