//! The desktop viewer, `voxgi view`: a winit window, the renderer's frame presented through
//! the render graph, and an egui side panel drawn by the graph pass `egui`.
//!
//! Why not egui-ash's runner: its painter is private to its own event loop, records its own
//! render pass and texture uploads with hand-written barriers and layout changes the graph
//! cannot see (they would contradict the graph's barriers: validation errors), needs a second
//! gpu-allocator, and indexes its buffers by swapchain image rather than frame in flight. So
//! the viewer drives winit itself, takes input through egui-winit, and draws egui's meshes in
//! one ~100-line graph pass; every barrier of the frame, swapchain transitions included, is
//! derived by the graph.
//!
//! Frame: renderer passes → `present` (blit of the tone-mapped image into the acquired
//! swapchain image, converting RGBA to the swapchain's BGRA; optional screenshot copy) →
//! `egui`. The swapchain image is imported with [`Access::Present`] and rebound every frame.

mod camera;
mod dynres;
mod edit;
mod edit_ui;
mod frame_graph;
mod open;
mod overlay;
mod panel;
mod pick;
mod stereo;

pub use camera::{FlyCamera, MoveKeys};
pub use dynres::viewer_gi;
pub use open::{OpenControls, OpenError, SceneOpener};
pub use panel::{Controls, TimingStats};
pub use stereo::StereoControls;

use crate::gi::{GiMethod, GiSettings};
use crate::graph::{Access, GraphError, GraphExecutor, ImageHandle, RenderGraph};
use crate::render::{FrameImages, RenderError, RenderSettings, Renderer};
use crate::scene::{scaled, Camera, Light, Projection, Scene};
use crate::vk::{
    surface_extensions, vk, Acquired, Buffer, BufferDesc, Context, ContextDesc, FrameLoop,
    MemoryLocation, Presented, Swapchain, VkError, MAX_FRAMES_IN_FLIGHT,
};
use overlay::Overlay;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Seconds between the camera keyframes recorded in the viewer (printed on exit, saved as
/// `[camera_path]`; edit `time_s` to retime the flight).
pub const RECORDED_KEY_SPACING_S: f32 = 2.0;

/// Errors of the viewer. Each says what to do.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error("cannot open a window: {0}. Without a display, run under `xvfb-run -a`")]
    Window(String),
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error("cannot write the screenshot {path}: {reason}")]
    Screenshot { path: PathBuf, reason: String },
    #[error("the scripted run presented {done} of {wanted} frames in {seconds} s (is the window minimized or hidden?)")]
    Stalled {
        done: u64,
        wanted: u64,
        seconds: u64,
    },
    #[error("the scripted run asked to {what} the window, which did not happen within {seconds} s: minimizing needs a window manager (under Xvfb start one, e.g. `openbox`; tools/setup installs it)")]
    Minimize { what: &'static str, seconds: u64 },
}

/// How to run the viewer.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    pub validation: bool,
    pub device: Option<String>,
    /// Initial inner size of the window, pixels.
    pub width: u32,
    pub height: u32,
    /// Initial tone mapping and shadows (the size comes from the window).
    pub settings: RenderSettings,
    /// Scripted run: exit after this many presented frames.
    pub frames: Option<u64>,
    /// Scripted run: resize the window to (width, height) halfway through; the run ends only
    /// once the swapchain has that size. (The scene renders right of the panel, so
    /// screenshots are narrower than the window.)
    pub resize_to: Option<(u32, u32)>,
    /// Scripted run: minimize (iconify) the window once this many frames were presented, and
    /// restore it after `restore_after` redraws were skipped while minimized; the run ends
    /// only after the restore. Needs a window manager (X11: one that honours
    /// `WM_CHANGE_STATE` and sets `_NET_WM_STATE_HIDDEN`, such as openbox).
    pub minimize_at: Option<u64>,
    pub restore_after: u64,
    /// Screenshot path (PNG). A scripted run writes one of its last frame; otherwise F12 and
    /// the panel button write here (default `voxgi-shot-N.png`).
    pub screenshot: Option<PathBuf>,
    /// The sweep (its folder, as `voxgi sweep --out` wrote it) and the scene's name in it,
    /// for the panel's "best within budget" ([`crate::tune::tune_from_dir`]).
    pub sweep_dir: PathBuf,
    pub scene_name: String,
    /// The panel's initial time budget, ms.
    pub budget_ms: f32,
    /// Dynamic resolution: the frame budget the internal scale holds (`post.frame_budget_ms`).
    pub dynres: crate::scene::DynamicResolution,
    /// Start in stereo (`--stereo`): packing, parallax and path. `None`: mono, the panel's
    /// parallax starting at [`StereoControls::off`].
    pub stereo: Option<StereoControls>,
    /// `--stereo-path`; `None`: the device's default ([`crate::render::default_stereo_path`]),
    /// which replaces the path in `stereo` (or the panel's) once the device is known.
    pub stereo_path: Option<crate::render::StereoPath>,
    /// Where "Save scene" (Ctrl+S) writes; `None`: the scene's own file.
    pub save_to: Option<PathBuf>,
    /// The built-in scene shown (its TOML text is what a save edits), `None` for a file.
    pub builtin: Option<String>,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            validation: false,
            device: None,
            width: 1280,
            height: 720,
            settings: RenderSettings::default(),
            frames: None,
            resize_to: None,
            minimize_at: None,
            restore_after: 10,
            screenshot: None,
            sweep_dir: PathBuf::from("sweep"),
            scene_name: "cornell".into(),
            budget_ms: 100.0,
            dynres: Default::default(),
            stereo: None,
            stereo_path: None,
            save_to: None,
            builtin: None,
        }
    }
}

/// What a run did.
#[derive(Debug, Default)]
pub struct ViewerReport {
    pub frames: u64,
    pub screenshots: Vec<PathBuf>,
    /// Redraws skipped because the window was minimized (or zero-sized).
    pub skipped_minimized: u64,
    /// Validation messages (errors and warnings, teardown included) and GPU memory never
    /// freed; anything in it is a bug.
    pub teardown: crate::vk::TeardownReport,
    /// Where the fly camera was when the viewer closed.
    pub camera: Option<Camera>,
    /// Cameras recorded with the panel's "Add camera keyframe", in order.
    pub camera_keys: Vec<Camera>,
    /// Scene files written by "Save scene" (Ctrl+S).
    pub saved: Vec<PathBuf>,
    /// The floating origin of the scene shown at exit (`Scene::origin_m`): `camera` and
    /// `camera_keys` are local to it.
    pub origin_m: glam::DVec3,
}

/// Scripted runs give up after this long.
const SCRIPT_TIMEOUT: Duration = Duration::from_secs(120);
/// How long a scripted minimize or restore may take to reach the window.
const MINIMIZE_TIMEOUT: Duration = Duration::from_secs(10);
/// While minimized nothing throttles the loop (no presentation): poll at about 60 Hz.
const MINIMIZED_POLL: Duration = Duration::from_millis(16);
/// Enough timestamp pairs for any frame graph (a stereo frame's included: the screen-space
/// passes twice).
const MAX_PASSES: u32 = 128;

/// Opens the window and runs until it is closed (or the scripted frames are done). `opener`
/// opens the scenes dropped on the window or named in the panel while it runs.
pub fn run(
    scene: Scene,
    opts: &ViewerOptions,
    opener: &SceneOpener,
) -> Result<ViewerReport, AppError> {
    let event_loop = EventLoop::new().map_err(|e| AppError::Window(e.to_string()))?;
    let mut app = App {
        opts,
        opener,
        scene: Some(scene),
        open: None,
        outcome: Ok(()),
    };
    let loop_result = event_loop.run_app(&mut app);
    // The viewer (its GPU objects, swapchain and surface) goes before the context and window.
    let closed = app.open.take().map(|o| {
        let report = o.viewer.close(&o.ctx);
        (report, o.ctx, o.window)
    });
    app.outcome?;
    loop_result.map_err(|e| AppError::Window(e.to_string()))?;
    let Some((report, ctx, _window)) = closed else {
        return Err(AppError::Window(
            "the event loop ended before the window opened".into(),
        ));
    };
    Ok(ViewerReport {
        teardown: ctx.finish(),
        ..report
    })
}

/// The viewer with what it draws with; fields drop in order (viewer, context, window).
struct Open {
    viewer: Viewer,
    ctx: Context,
    window: Window,
}

/// winit's application: opens the window, context and viewer when the event loop starts
/// (winit 0.30 creates windows from a running loop) and hands the viewer its events.
struct App<'a> {
    opts: &'a ViewerOptions,
    opener: &'a SceneOpener<'a>,
    /// The scene until the viewer takes it.
    scene: Option<Scene>,
    open: Option<Open>,
    /// The first error, which ended the loop.
    outcome: Result<(), AppError>,
}

impl App<'_> {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<(), AppError> {
        // A second `resumed` (platforms that suspend) finds the viewer open.
        let Some(scene) = self.scene.take() else {
            return Ok(());
        };
        let attributes = Window::default_attributes()
            .with_title("voxgi")
            .with_inner_size(PhysicalSize::new(
                self.opts.width.max(1),
                self.opts.height.max(1),
            ));
        let window = event_loop
            .create_window(attributes)
            .map_err(|e| AppError::Window(e.to_string()))?;
        let ctx = Context::new(&ContextDesc {
            validation: self.opts.validation,
            device: self.opts.device.clone(),
            instance_extensions: surface_extensions(display_handle(event_loop)?)?,
            swapchain: true,
        })?;
        let viewer = Viewer::new(&ctx, &window, scene, self.opts)?;
        self.open = Some(Open {
            viewer,
            ctx,
            window,
        });
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: AppError) {
        self.outcome = Err(e);
        event_loop.exit();
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.open(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(o) = self.open.as_mut() else {
            return;
        };
        let r = o
            .viewer
            .handle(&o.ctx, &o.window, event, event_loop, self.opener);
        if let Err(e) = r {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(o) = self.open.as_ref().filter(|o| !o.viewer.window_gone) {
            o.window.request_redraw();
        }
    }
}

/// The window system's display connection, for the surface.
fn display_handle(
    source: &impl HasDisplayHandle,
) -> Result<raw_window_handle::RawDisplayHandle, AppError> {
    Ok(source
        .display_handle()
        .map_err(|e| AppError::Window(e.to_string()))?
        .as_raw())
}

/// The compiled frame for one swapchain size and set of graph-shaping settings.
struct FrameGraph {
    exec: GraphExecutor,
    present: ImageHandle,
    /// Tone-mapped pixels (the scene, without the panel) of a frame, when `shot_wanted` was
    /// set while recording it.
    shot: Buffer,
    shot_wanted: Rc<Cell<bool>>,
    extent: vk::Extent2D,
    /// The settings this graph bakes in (size, shadow resolution, tone map).
    settings: RenderSettings,
    /// The stereo packing it presents (`None`: mono).
    stereo_mode: Option<crate::post::StereoMode>,
    /// Size of the presented (and screenshot) image: the packing's in stereo.
    shot_size: (u32, u32),
    /// The scene's area of the window the image is upscaled to (mono; `None` in stereo).
    display: Option<(u32, u32)>,
}

struct Viewer {
    opts: ViewerOptions,
    scene: Scene,
    base_lights: Vec<Light>,
    light_names: Vec<String>,
    object_names: Vec<String>,
    lens: Camera,
    fly: FlyCamera,
    keys: MoveKeys,
    looking: bool,
    cursor: Option<(f64, f64)>,
    renderer: Option<Renderer>,
    /// Stereo on: the right eye's renderer (two-pass), the packing, the path that runs
    /// (`app/stereo.rs`); `renderer` then renders both eyes, or the left one.
    stereo: Option<stereo::ViewerStereo>,
    swapchain: Option<Swapchain>,
    swapchain_dirty: bool,
    overlay: Option<Overlay>,
    frame_loop: Option<FrameLoop>,
    graph: Option<FrameGraph>,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    controls: Controls,
    stats: TimingStats,
    /// The frame-time graph's frames (kept across graph rebuilds: a GI switch shows as the
    /// old passes leaving and the new ones arriving).
    history: frame_graph::FrameHistory,
    last_frame: Instant,
    frame_ms: f32,
    /// The last frame's wall time (`frame_ms` is its moving average).
    frame_dt_ms: f32,
    started: Instant,
    report: ViewerReport,
    status: String,
    resize_requested: bool,
    minimize_script: MinimizeScript,
    /// The window was minimized (or zero-sized) at the last redraw.
    minimized: bool,
    /// The window's inner size as winit last reported it (`Resized`). Kept here rather than
    /// asked of the window each frame: winit's X11 backend panics on asking a window that
    /// another client destroyed, before the viewer sees `Destroyed`.
    window_px: PhysicalSize<u32>,
    /// The window was larger than the device draws at the last redraw (see
    /// [`max_window_px`]): nothing is drawn until it is smaller.
    oversized: bool,
    /// The window was destroyed under the viewer (not closed): the viewer exits without
    /// touching it again.
    window_gone: bool,
    /// The window's size whose frame did not fit the device's memory
    /// ([`Self::check_window_memory`]): nothing is drawn until the size changes.
    refused_px: Option<PhysicalSize<u32>>,
    /// Width of the side panel in pixels: the scene renders to the right of it.
    panel_px: u32,
    /// Where the panel's GPU-time table was drawn last frame (logged by scripted runs).
    panel_layout: panel::PanelLayout,
    /// The scene editor (`edit.rs`) and the GPU pass that answers its clicks.
    editor: edit::Editor,
    pick: Option<pick::PickPass>,
    /// The scene's part of the window in the last frame: left, top, width, height (pixels).
    view_rect: [f32; 4],
    /// A Ctrl key is held (Ctrl+S saves instead of moving back).
    ctrl: bool,
    /// What of the scene the current renderer was made for (lights, moving objects, bounds).
    scene_shape: Option<edit::SceneShape>,
    /// The lights before a change that needs a new renderer, until it is made.
    light_backup: Option<edit::LightBackup>,
    /// Where the selected object's position x field was drawn (window pixels; logged when it
    /// moves, for scripted tests).
    position_field: Option<[f32; 2]>,
    /// The panel's scroll state last logged (window px: offset, largest offset, contents'
    /// and view's heights, the screenshot button's centre), for scripted tests.
    panel_scroll: Option<[f32; 6]>,
    /// The panel's named controls last logged and their centres (window px), likewise.
    panel_spots: std::collections::HashMap<String, [f32; 2]>,
    /// Frames recorded with the current renderer (in a still view, the frames TAA has
    /// blended); scripted runs log it for their last frame.
    renderer_frames: u64,
    /// Per frame slot, when its pick was recorded and the frame count then (for the log).
    pick_started: [Option<(Instant, u64)>; MAX_FRAMES_IN_FLIGHT],
    /// Dynamic resolution: the internal scale of the scene's area (`dynres.rs`).
    dynres: dynres::ScaleController,
    /// The scene's area of the window (mono; `None` in stereo, which is not scaled): the
    /// internal image is upscaled to it.
    display: Option<(u32, u32)>,
    /// The camera of the last frame, and whether this frame's is the same (dynamic
    /// resolution refines a still view).
    last_camera: Option<Camera>,
    still: bool,
    /// Per frame slot, the scale (eighths) of the frame it recorded, for dynamic resolution's
    /// measurement of it; `None` for a renderer's first frame (one-time work) or in stereo.
    recorded_steps: [Option<u32>; MAX_FRAMES_IN_FLIGHT],
    /// The panel's GI settings the renderer was last given (applied once no slider is
    /// dragged); dynamic resolution renders them with the scale's ray count.
    gi_base: GiSettings,
}

/// The view the editor's handles are drawn for.
struct ViewGeomArgs {
    geom: edit::ViewGeom,
    time_s: f32,
}

/// Where a scripted minimize (`ViewerOptions::minimize_at`) stands.
#[derive(Clone, Copy, Debug, PartialEq)]
enum MinimizeScript {
    /// Not yet (or not scripted).
    Pending,
    /// Minimize requested at this time; waiting for the window manager.
    Requested(Instant),
    /// The viewer saw the window minimized.
    Minimized,
    /// Restore requested at this time; waiting for the window manager.
    Restoring(Instant),
    Done,
}

/// The status line's prefix for a refused projection switch.
const PROJECTION_STATUS: &str = "projection not switched";

/// The largest window the viewer draws into: its swapchain images are 2D images of the
/// window's size, and the panel's pass sets a viewport of that size.
fn max_window_px(info: &crate::vk::DeviceInfo) -> [u32; 2] {
    let [vw, vh] = info.max_viewport_dimensions;
    [
        info.max_image_dimension_2d.min(vw),
        info.max_image_dimension_2d.min(vh),
    ]
}

/// Graph-shaping settings differ (per-frame values such as PCF radius do not count; the
/// cascade count sets the shadow maps' layers).
fn needs_new_graph(a: &RenderSettings, b: &RenderSettings) -> bool {
    (a.width, a.height, a.shadow.resolution) != (b.width, b.height, b.shadow.resolution)
        || a.shadow.cascades != b.shadow.cascades
        || a.tonemap != b.tonemap
}

/// Settings the renderer bakes into its resources differ: the GI passes are made for one method
/// and set of parameters, and the path tracer's and TAA's histories (and the post passes) for
/// one size; the light-space passes are made cached (`shadow.cache`) or not, and the sampled
/// direct light with its sample count (`shadow.direct_samples`). A new renderer then.
fn needs_new_renderer(a: &RenderSettings, b: &RenderSettings) -> bool {
    let sized = a.gi.method != GiMethod::None
        || a.debug.is_some()
        || a.post != crate::post::PostSettings::default();
    a.gi != b.gi
        || a.shadow.cache != b.shadow.cache
        || a.shadow.direct_samples != b.shadow.direct_samples
        || a.debug != b.debug
        || a.post != b.post
        || (sized && (a.width, a.height) != (b.width, b.height))
}

/// The debug view the panel asks for, keeping `current`'s other debug parameters (level,
/// steps scale).
fn debug_settings(
    c: &Controls,
    current: Option<crate::voxel::debug_view::DebugSettings>,
) -> Option<crate::voxel::debug_view::DebugSettings> {
    c.debug.map(|view| crate::voxel::debug_view::DebugSettings {
        view,
        object: c.atlas_object,
        ..current.unwrap_or_default()
    })
}

/// The pixel of a `frame`-sized image under pixel `p` of the `display`-sized area it is
/// scaled to (the same pixel when the sizes agree).
fn internal_pixel((x, y): (u32, u32), display: (u32, u32), frame: (u32, u32)) -> (u32, u32) {
    let map = |v: u32, d: u32, f: u32| {
        ((u64::from(v) * u64::from(f) / u64::from(d.max(1))) as u32).min(f.saturating_sub(1))
    };
    (map(x, display.0, frame.0), map(y, display.1, frame.1))
}

/// One line about the indirect light, for the log.
fn describe_gi(gi: &GiSettings) -> String {
    let method = describe_gi_method(gi);
    match gi.sao {
        Some(s) => format!("{method}, SAO r {} m", s.radius_m),
        None => method,
    }
}

/// The post chain and tone mapping for the log: the stages on, then operator and exposure.
fn describe_post(post: &crate::post::PostSettings, tone: &crate::post::ToneMap) -> String {
    let mut parts = Vec::new();
    if let Some(t) = post.taa {
        parts.push(format!("taa α {}", t.history_weight));
    }
    if let Some((w, h)) = post.upsample_to {
        parts.push(format!("TAA upsampling to {w}x{h}"));
    }
    if let Some(a) = post.auto_exposure {
        parts.push(format!("auto exposure key {}", a.key));
    }
    if let Some(b) = post.bloom {
        parts.push(format!("bloom {b}"));
    }
    if post.fxaa {
        parts.push("fxaa".into());
    }
    if tone.dither {
        parts.push("dither".into());
    }
    parts.push(format!("tonemap {:?} × {}", tone.operator, tone.exposure));
    parts.join(", ")
}

fn describe_gi_method(gi: &GiSettings) -> String {
    (gi.method.spec().describe)(gi)
}

impl Viewer {
    fn new(
        ctx: &Context,
        window: &Window,
        scene: Scene,
        opts: &ViewerOptions,
    ) -> Result<Self, AppError> {
        let size = window.inner_size();
        let extent = vk::Extent2D {
            width: size.width,
            height: size.height,
        };
        let swapchain = Swapchain::new(
            ctx,
            display_handle(window)?,
            window
                .window_handle()
                .map_err(|e| AppError::Window(e.to_string()))?
                .as_raw(),
            extent,
            MAX_FRAMES_IN_FLIGHT,
        )?;
        let mut viewer = Self::with_swapchain(window, scene, opts, Some(swapchain));
        viewer.resolve_stereo_path(ctx);
        viewer.init_gpu(ctx)?;
        Ok(viewer)
    }

    /// The stereo path of `--stereo-path`, else the device's default.
    fn resolve_stereo_path(&mut self, ctx: &Context) {
        self.controls.stereo.path = match self.opts.stereo_path {
            Some(path) => path,
            None => {
                let (path, why) = crate::render::default_stereo_path(&ctx.info);
                log::info!("stereo path {} ({why})", path.name());
                path
            }
        };
    }

    /// The viewer of `scene` before any GPU object (but the swapchain, if given) is made.
    fn with_swapchain(
        window: &Window,
        scene: Scene,
        opts: &ViewerOptions,
        swapchain: Option<Swapchain>,
    ) -> Self {
        let egui_ctx = egui::Context::default();
        // The dark theme whatever the system's (egui 0.29+ follows the system by default).
        egui_ctx.set_theme(egui::Theme::Dark);
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(8192),
        );
        let fly = FlyCamera::from_camera(&scene.camera, scene.aabb_at(0.0).extent().length());
        let light_names = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| edit::light_name(i, l))
            .collect();
        let editor = edit::Editor::new(&scene, &fly, opts.builtin.clone(), opts.save_to.clone());
        let controls = Controls {
            tonemap: opts.settings.tonemap,
            post: opts.settings.post,
            shadow: opts.settings.shadow,
            gi: opts.settings.gi,
            light_scale: vec![1.0; scene.lights.len()],
            speed_m_s: fly.speed_m_s,
            time_s: opts.settings.time_s,
            animate: false,
            debug: opts.settings.debug.map(|d| d.view),
            atlas_object: opts.settings.debug.map_or(0, |d| d.object),
            screenshot: false,
            add_keyframe: false,
            budget_ms: opts.budget_ms,
            tune: false,
            dynres: opts.dynres,
            stereo: opts
                .stereo
                .unwrap_or_else(|| StereoControls::off(&scene, opts.settings.time_s)),
            projection: scene.camera.projection,
            ortho_height_m: scene.camera.ortho_height_m,
            open: open::OpenControls::showing(match (&scene.source, &opts.builtin) {
                (Some(file), _) => file.display().to_string(),
                (None, Some(name)) => name.clone(),
                (None, None) => opts.scene_name.clone(),
            }),
        };
        Self {
            opts: opts.clone(),
            base_lights: scene.lights.clone(),
            light_names,
            object_names: scene.objects.iter().map(|o| o.name.clone()).collect(),
            lens: scene.camera,
            fly,
            scene,
            keys: MoveKeys::default(),
            looking: false,
            cursor: None,
            renderer: None,
            stereo: None,
            swapchain,
            swapchain_dirty: false,
            overlay: None,
            frame_loop: None,
            graph: None,
            egui_ctx,
            egui_state,
            controls,
            stats: TimingStats::new(120),
            history: frame_graph::FrameHistory::new(frame_graph::HISTORY_FRAMES),
            last_frame: Instant::now(),
            frame_ms: 0.0,
            frame_dt_ms: 0.0,
            started: Instant::now(),
            report: ViewerReport::default(),
            status: String::new(),
            resize_requested: false,
            minimize_script: if opts.minimize_at.is_some() {
                MinimizeScript::Pending
            } else {
                MinimizeScript::Done
            },
            minimized: false,
            window_px: window.inner_size(),
            oversized: false,
            window_gone: false,
            refused_px: None,
            panel_px: 0,
            panel_layout: panel::PanelLayout::default(),
            editor,
            pick: None,
            view_rect: [0.0, 0.0, 1.0, 1.0],
            ctrl: false,
            scene_shape: None,
            light_backup: None,
            position_field: None,
            panel_scroll: None,
            panel_spots: Default::default(),
            renderer_frames: 0,
            pick_started: [None; MAX_FRAMES_IN_FLIGHT],
            dynres: dynres::ScaleController::new(opts.dynres),
            display: None,
            last_camera: None,
            still: false,
            recorded_steps: [None; MAX_FRAMES_IN_FLIGHT],
            gi_base: opts.settings.gi,
        }
    }

    /// The GPU objects that outlive scenes: the panel's, the pick pass and the frame loop.
    /// The renderer is made before the first frame, once the panel's width is known
    /// ([`Self::update_renderer`]).
    fn init_gpu(&mut self, ctx: &Context) -> Result<(), AppError> {
        let Some(format) = self.swapchain.as_ref().map(|s| s.format) else {
            return Ok(());
        };
        self.overlay = Some(Overlay::new(ctx, format)?);
        self.pick = Some(pick::PickPass::new(ctx)?);
        self.frame_loop = Some(FrameLoop::new(ctx, MAX_FRAMES_IN_FLIGHT, MAX_PASSES)?);
        Ok(())
    }

    fn handle(
        &mut self,
        ctx: &Context,
        window: &Window,
        event: WindowEvent,
        elwt: &ActiveEventLoop,
        opener: &SceneOpener,
    ) -> Result<(), AppError> {
        match event {
            WindowEvent::Destroyed => {
                // Another client destroyed the window (a close asks first: CloseRequested).
                // A frame may have found its surface lost first, and said so.
                if !self.window_gone {
                    log::warn!("the window was destroyed: exiting");
                }
                self.window_gone = true;
                elwt.exit();
            }
            _ if self.window_gone => {}
            event => {
                let consumed = self.egui_state.on_window_event(window, &event).consumed;
                match event {
                    WindowEvent::CloseRequested => elwt.exit(),
                    WindowEvent::Resized(size) => {
                        self.window_px = size;
                        self.swapchain_dirty = true;
                    }
                    // Opened at the next redraw, as the panel's "Open" is.
                    WindowEvent::DroppedFile(path) => {
                        log::info!("dropped on the window: {}", path.display());
                        self.controls.open.path = path.to_string_lossy().into_owned();
                        self.controls.open.requested = true;
                    }
                    WindowEvent::RedrawRequested => {
                        let script_done = self.redraw(ctx, window, opener)?;
                        if script_done {
                            elwt.exit();
                        }
                    }
                    WindowEvent::KeyboardInput {
                        event:
                            KeyEvent {
                                physical_key: PhysicalKey::Code(code),
                                state,
                                repeat,
                                ..
                            },
                        ..
                    } => {
                        // Releases always count, so no key sticks when egui takes focus.
                        let down = state == ElementState::Pressed;
                        if !down || !consumed {
                            self.key(code, down, repeat, elwt);
                        }
                    }
                    WindowEvent::MouseInput {
                        state,
                        button: MouseButton::Right,
                        ..
                    } => self.looking = state == ElementState::Pressed && !consumed,
                    // The editor: a click selects, a press on a handle drags it.
                    WindowEvent::MouseInput {
                        state,
                        button: MouseButton::Left,
                        ..
                    } => match state {
                        ElementState::Pressed if !consumed => self.edit_press(),
                        ElementState::Released => self.edit_release(),
                        _ => {}
                    },
                    WindowEvent::ModifiersChanged(m) => self.ctrl = m.state().control_key(),
                    WindowEvent::CursorMoved { position, .. } => {
                        if let (true, Some((x, y))) = (self.looking, self.cursor) {
                            self.fly
                                .look((position.x - x) as f32, (position.y - y) as f32);
                        }
                        self.cursor = Some((position.x, position.y));
                        self.edit_drag();
                    }
                    WindowEvent::MouseWheel { delta, .. } if !consumed => {
                        let notches = match delta {
                            MouseScrollDelta::LineDelta(_, y) => y,
                            MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                        };
                        self.fly.scroll_speed(notches);
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// Movement keys follow the key's state; actions (screenshot, next GI method, exit) fire
    /// once per press, not again on the system's key repeat (a press held past the repeat
    /// delay, or delivered late on a busy machine, would otherwise step two GI methods).
    fn key(&mut self, code: KeyCode, down: bool, repeat: bool, elwt: &ActiveEventLoop) {
        let press = down && !repeat;
        // Ctrl+S saves the scene; S without Ctrl moves back.
        if code == KeyCode::KeyS && self.ctrl && press {
            self.save_scene();
            return;
        }
        let edit = match code {
            KeyCode::Digit1 => Some(edit::EditAction::Handle(edit::HandleMode::Move)),
            KeyCode::Digit2 => Some(edit::EditAction::Handle(edit::HandleMode::Rotate)),
            KeyCode::Digit3 => Some(edit::EditAction::Handle(edit::HandleMode::Scale)),
            KeyCode::Insert => Some(edit::EditAction::AddLight(self.editor.new_light_kind)),
            KeyCode::Delete => match self.editor.selection {
                Some(edit::Selection::Light(i)) => Some(edit::EditAction::RemoveLight(i)),
                _ => None,
            },
            _ => None,
        };
        if let Some(a) = edit.filter(|_| press) {
            self.apply_edit(a);
            return;
        }
        let k = &mut self.keys;
        match code {
            KeyCode::KeyW => k.forward = down,
            KeyCode::KeyS => k.back = down && !self.ctrl,
            KeyCode::KeyA => k.left = down,
            KeyCode::KeyD => k.right = down,
            KeyCode::KeyE => k.up = down,
            KeyCode::KeyQ => k.down = down,
            KeyCode::ShiftLeft | KeyCode::ShiftRight => k.fast = down,
            KeyCode::F12 if press => self.controls.screenshot = true,
            KeyCode::KeyG if press => {
                self.controls.gi.method = self.controls.gi.method.next();
                // Presses between two frames take effect together, in the next frame: the
                // log says each was seen (scripted tests count them).
                log::info!("key G: indirect light {}", self.controls.gi.method.name());
            }
            KeyCode::KeyO if press => {
                self.controls.projection = match self.controls.projection {
                    Projection::Perspective => Projection::Orthographic,
                    Projection::Orthographic => Projection::Perspective,
                }
            }
            KeyCode::Escape if press => elwt.exit(),
            _ => {}
        }
    }

    /// Renders and presents one frame. Returns `true` when a scripted run is done.
    fn redraw(
        &mut self,
        ctx: &Context,
        window: &Window,
        opener: &SceneOpener,
    ) -> Result<bool, AppError> {
        self.advance(window)?;
        let Some(extent) = self.presentable_extent(ctx, window)? else {
            return Ok(false);
        };
        // A scene dropped on the window or asked for in the panel (last frame): this frame
        // shows it, or the current scene and why it was not opened.
        if std::mem::take(&mut self.controls.open.requested) {
            let arg = self.controls.open.path.trim().to_owned();
            self.open_scene(ctx, window, extent, opener, &arg)?;
        }
        // The scripted run's last frame is the one it screenshots.
        let last_scripted = self.opts.frames.is_some_and(|n| {
            self.report.frames + 1 >= n
                && self.minimize_script == MinimizeScript::Done
                && self
                    .opts
                    .resize_to
                    .is_none_or(|(w, h)| (extent.width, extent.height) == (w, h))
        });
        let (prims, ppp) = self.run_ui(ctx, window, extent)?;
        if last_scripted {
            // For the window tests: they check the table's geometry at the window's size.
            log::info!("panel timing table: {}", self.panel_layout.to_json());
        }
        if !self.apply_controls(ctx, extent)? {
            return Ok(false);
        }
        self.draw_and_present(ctx, extent, (&prims, ppp), last_scripted)
    }

    /// Advances the clock, the scripted run's steps and the camera, and applies the panel's
    /// one-shot buttons (keyframe, tune).
    fn advance(&mut self, window: &Window) -> Result<(), AppError> {
        let now = Instant::now();
        let dt_s = (now - self.last_frame).as_secs_f32();
        self.last_frame = now;
        if self.controls.animate {
            // Bounded so a stalled frame does not jump the animation.
            self.controls.time_s += dt_s.min(0.1);
        }
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * dt_s * 1000.0;
        self.frame_dt_ms = dt_s * 1000.0;
        if let Some(wanted) = self.opts.frames {
            if self.started.elapsed() > SCRIPT_TIMEOUT {
                return Err(AppError::Stalled {
                    done: self.report.frames,
                    wanted,
                    seconds: SCRIPT_TIMEOUT.as_secs(),
                });
            }
            if let (Some((w, h)), false) = (self.opts.resize_to, self.resize_requested) {
                if self.report.frames >= wanted / 2 {
                    let _ = window.request_inner_size(PhysicalSize::new(w, h));
                    self.resize_requested = true;
                }
            }
            self.step_minimize_script(window)?;
        }

        self.fly.advance(self.keys, dt_s);
        self.scene.camera = self.fly.apply(&self.lens);
        // Still: the same camera as the last frame and no running scene time.
        self.still = self.last_camera == Some(self.scene.camera) && !self.controls.animate;
        self.last_camera = Some(self.scene.camera);
        if std::mem::take(&mut self.controls.add_keyframe) {
            self.report.camera_keys.push(self.scene.camera);
        }
        if std::mem::take(&mut self.controls.tune) {
            self.apply_best_within_budget();
        }
        Ok(())
    }

    /// The swapchain's extent, recreated for the window's size when needed; `None` while
    /// there is nothing to present (minimized, zero-sized, no swapchain).
    fn presentable_extent(
        &mut self,
        ctx: &Context,
        window: &Window,
    ) -> Result<Option<vk::Extent2D>, AppError> {
        // Minimized (or zero-sized): nothing to present until the window is back. On X11 an
        // iconified window keeps its size (and the surface its extent), so ask the window
        // manager's state too.
        let size = self.window_px;
        if size.width == 0 || size.height == 0 || window.is_minimized() == Some(true) {
            if !self.minimized {
                self.minimized = true;
                if let Some(s) = &self.swapchain {
                    let px = vk::Extent2D {
                        width: size.width,
                        height: size.height,
                    };
                    let e = s.surface_extent(ctx, px)?;
                    log::info!(
                        "minimized: window {}x{}, surface extent {}x{}; skipping frames",
                        size.width,
                        size.height,
                        e.width,
                        e.height
                    );
                }
            }
            self.report.skipped_minimized += 1;
            std::thread::sleep(MINIMIZED_POLL);
            return Ok(None);
        }
        if self.minimized {
            // Back from minimized: the surface may have changed meanwhile.
            log::info!("restored: recreating the swapchain");
            self.minimized = false;
            self.swapchain_dirty = true;
        }
        // A window larger than the device's largest image or viewport cannot have a
        // swapchain of its size (the X11 surface admits no other), so nothing is drawn until
        // it is smaller; the scene, edits and settings stay as they are.
        let [max_w, max_h] = max_window_px(&ctx.info);
        if size.width > max_w || size.height > max_h {
            if !self.oversized {
                self.oversized = true;
                self.status = format!(
                    "the window is {}x{} px, larger than this device draws ({max_w}x{max_h} px \
                     at most): nothing is drawn until it is that small",
                    size.width, size.height
                );
                log::warn!("{}", self.status);
            }
            std::thread::sleep(MINIMIZED_POLL);
            return Ok(None);
        }
        if self.oversized {
            self.oversized = false;
            self.status.clear();
            log::info!(
                "the window is {}x{} px again: drawing",
                size.width,
                size.height
            );
            self.swapchain_dirty = true;
        }
        let window_px = vk::Extent2D {
            width: size.width,
            height: size.height,
        };
        // Within the device's limits but too big for its memory: refused before the
        // swapchain or anything else of that size is made, and checked once per size.
        if self.refused_px == Some(size) {
            std::thread::sleep(MINIMIZED_POLL);
            return Ok(None);
        }
        let resizing = self
            .swapchain
            .as_ref()
            .is_some_and(|s| s.extent != window_px);
        if resizing || self.refused_px.is_some() {
            if let Err(e) = self.check_window_memory(ctx, size) {
                self.refused_px = Some(size);
                self.status = format!(
                    "the window is {}x{} px, more than this device's memory holds: {e}; \
                     nothing is drawn until it is smaller",
                    size.width, size.height
                );
                log::warn!("{}", self.status);
                std::thread::sleep(MINIMIZED_POLL);
                return Ok(None);
            }
            if self.refused_px.take().is_some() {
                self.status.clear();
                log::info!(
                    "the window is {}x{} px again: drawing",
                    size.width,
                    size.height
                );
            }
        }
        let Some(swapchain) = self.swapchain.as_mut() else {
            return Ok(None);
        };
        if self.swapchain_dirty || swapchain.extent != window_px {
            swapchain.recreate(ctx, window_px)?;
            self.swapchain_dirty = false;
        }
        let extent = swapchain.extent;
        Ok((extent.width > 0 && extent.height > 0).then_some(extent))
    }

    /// Refuses a window `size` whose frame cannot fit the device's memory, before anything
    /// of that size is made: the swapchain's images, the screenshot buffer and the renderer's
    /// frame at the size the scene would render (`Renderer::check_frame_size`, which names
    /// the allocation). In stereo and under TAA upsampling the count is the mono frame's, an
    /// estimate.
    fn check_window_memory(
        &mut self,
        ctx: &Context,
        size: PhysicalSize<u32>,
    ) -> Result<(), RenderError> {
        use crate::render::memory::MemoryNeed;
        let Some(renderer) = self.renderer.as_mut() else {
            return Ok(());
        };
        let panel_px = if size.width > self.panel_px + 64 {
            self.panel_px
        } else {
            0
        };
        let area = (size.width - panel_px, size.height);
        let frame = match self.controls.stereo.mode {
            None => self.dynres.internal_size(area),
            mode => stereo::eye_size(mode, area),
        };
        let images = self
            .swapchain
            .as_ref()
            .map_or(0, |s| s.images.len())
            .max(MAX_FRAMES_IN_FLIGHT + 1);
        let px = |(w, h): (u32, u32)| u64::from(w) * u64::from(h);
        let mut extra: Vec<MemoryNeed> = (0..images)
            .map(|i| MemoryNeed {
                name: format!("swapchain image {i}"),
                bytes: px((size.width, size.height)) * 4,
                is_buffer: false,
            })
            .collect();
        extra.push(MemoryNeed {
            name: "screenshot".into(),
            bytes: px(frame) * 4,
            is_buffer: true,
        });
        match renderer.check_frame_size(ctx, &self.scene, frame, &extra) {
            // The advice is the window's, not the command line's size flags.
            Err(RenderError::OutOfDeviceMemory(mut m)) => {
                m.flags = "the window's size";
                Err(RenderError::OutOfDeviceMemory(m))
            }
            // Only memory refuses a size here; anything else the frame at that size meets
            // is met (and reported) where it is made.
            Err(e) => {
                log::debug!("the window's frame memory was not counted: {e}");
                Ok(())
            }
            Ok(()) => Ok(()),
        }
    }

    /// Applies the panel to the scene and the renderer's settings: a new renderer or graph
    /// where a setting needs one, then the frame's constants. `false` when there is no
    /// renderer to draw with.
    fn apply_controls(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<bool, AppError> {
        let Some(settings) = self.update_renderer(ctx, extent)? else {
            return Ok(false);
        };
        let Some(renderer) = self.renderer.as_mut() else {
            return Ok(false);
        };
        renderer.settings = settings.clone();
        match &mut self.stereo {
            Some(st) => st.prepare(renderer, &self.scene, &settings, &self.controls.stereo)?,
            None => renderer.prepare(&self.scene)?,
        }
        let stereo_mode = self.stereo.as_ref().and(self.controls.stereo.mode);
        if self.graph.as_ref().is_none_or(|g| {
            g.extent != extent
                || needs_new_graph(&g.settings, &settings)
                || g.stereo_mode != stereo_mode
                || g.display != self.display
        }) {
            self.rebuild(ctx)?;
        }
        Ok(true)
    }

    /// The frame's settings from the panel for a swapchain of `extent`, and the renderer for
    /// them: a new one where a setting needs one, and the first one (made here, once the
    /// panel's width is known, so that it has the scene's size from the start). `None` when
    /// there is no renderer to draw with.
    fn update_renderer(
        &mut self,
        ctx: &Context,
        extent: vk::Extent2D,
    ) -> Result<Option<RenderSettings>, AppError> {
        for (i, base) in self.base_lights.iter().enumerate() {
            let s = self.controls.light_scale.get(i).copied().unwrap_or(1.0);
            self.scene.lights[i] = scaled(base, s);
        }
        let first = self.renderer.is_none();
        let current = match self.renderer.as_ref() {
            Some(r) => r.settings.clone(),
            None => self.opts.settings.clone(),
        };
        // The scene fills the window right of the panel (all of it when the window is narrow).
        let panel_px = if extent.width > self.panel_px + 64 {
            self.panel_px
        } else {
            0
        };
        let mut settings = current.clone();
        settings.time_s = self.controls.time_s;
        // Stereo: each eye's size whose packing fills the area (`app/stereo.rs`).
        let area = (extent.width - panel_px, extent.height);
        (settings.width, settings.height) = stereo::eye_size(self.controls.stereo.mode, area);
        // Mono: the internal size of dynamic resolution, upscaled to the area when presented.
        // (A stereo packing is not scaled.)
        if let Some(change) = self.dynres.set(self.controls.dynres) {
            self.log_scale(change, area);
        }
        if first && self.controls.stereo.mode.is_none() && self.dynres.steps() != dynres::STEPS {
            self.log_scale(dynres::Change::Start, area);
        }
        self.display = self.controls.stereo.mode.is_none().then_some(area);
        if self.display.is_some() {
            (settings.width, settings.height) = self.dynres.internal_size(area);
        }
        settings.tonemap = self.controls.tonemap;
        settings.shadow = self.controls.shadow;
        // Each GI edit costs a new renderer: apply them once no slider is being dragged.
        if !self.egui_ctx.input(|i| i.pointer.any_down()) {
            self.gi_base = self.controls.gi;
            settings.post = self.controls.post;
            settings.debug = debug_settings(&self.controls, settings.debug);
        }
        // The scale's ray count and TAA upsampling into the area (mono only): both change
        // only together with the scale's size, whose new renderer carries them.
        (settings.gi, settings.post.upsample_to) = match self.display {
            Some(area) => (
                self.dynres.gi(self.gi_base),
                self.dynres
                    .upsample_to((settings.width, settings.height), area),
            ),
            None => (self.gi_base, None),
        };
        self.apply_projection(&settings);
        let stereo_changed = match (&self.stereo, self.controls.stereo.mode) {
            (Some(st), _) => st.outdated(&self.controls.stereo),
            (None, mode) => mode.is_some(),
        };
        let editing = self.editor.dragging() || self.egui_ctx.input(|i| i.pointer.any_down());
        if first {
            log::info!("indirect light: {}", describe_gi(&settings.gi));
            log::info!(
                "post-processing: {}",
                describe_post(&settings.post, &settings.tonemap)
            );
        }
        if first
            || needs_new_renderer(&current, &settings)
            || stereo_changed
            || self.scene_needs_new_renderer(editing)
        {
            let lights_before = self.scene_shape.clone();
            match self.replace_renderer(ctx, &mut settings, area) {
                Err(e) if self.light_backup.is_some() => {
                    self.restore_lights();
                    self.editor.status = format!("the lights were not changed: {e}");
                    log::warn!("{}", self.editor.status);
                }
                r => r?,
            }
            if self.scene_shape != lights_before {
                self.light_change_done();
            }
        }
        Ok(self.renderer.is_some().then_some(settings))
    }

    /// Records the frame (with the panel's `ui` primitives and pixels per point), submits and
    /// presents it, answers a pick that landed and saves a screenshot when one is due.
    fn draw_and_present(
        &mut self,
        ctx: &Context,
        extent: vk::Extent2D,
        (prims, ppp): (&[egui::ClippedPrimitive], f32),
        last_scripted: bool,
    ) -> Result<bool, AppError> {
        let (Some(frame_loop), Some(graph), Some(renderer), Some(overlay), Some(swapchain)) = (
            self.frame_loop.as_mut(),
            self.graph.as_mut(),
            self.renderer.as_mut(),
            self.overlay.as_mut(),
            self.swapchain.as_ref(),
        ) else {
            return Ok(false);
        };
        let slot = frame_loop.current_slot();
        let (_, cmd, timestamps, finished) = frame_loop.begin(ctx)?;
        self.history.push(&finished);
        // The pick this slot recorded two frames ago has landed (the fence was waited).
        let picked = self.pick.as_mut().and_then(|p| p.collect(slot)).map(|p| {
            let gpu_ms: f64 = finished
                .iter()
                .filter(|t| t.name.starts_with("pick"))
                .map(|t| t.gpu_ms)
                .sum();
            let started = self.pick_started.get_mut(slot).and_then(Option::take);
            (p, gpu_ms, started)
        });
        // The finished frame's GPU time (its passes' timestamps): what dynamic resolution holds.
        // It is measured at the scale that frame was recorded at (a renderer's first frame not).
        let gpu_ms = (!finished.is_empty()).then(|| finished.iter().map(|t| t.gpu_ms).sum());
        let measured_steps = self.recorded_steps.get_mut(slot).and_then(Option::take);
        let recording_steps = self.dynres.steps();
        let change = self.dynres.observe(gpu_ms.zip(measured_steps), self.still);
        self.stats.push(finished);
        let (index, ready) = match swapchain.acquire(slot)? {
            Acquired::Image { index, ready } => (index, ready),
            Acquired::OutOfDate => {
                // Keep the frame loop in step with an empty submission; resize next frame.
                frame_loop.submit(ctx, &[], &[])?;
                self.swapchain_dirty = true;
                return Ok(false);
            }
            Acquired::SurfaceLost => {
                // The window was destroyed mid-frame; `Destroyed` has not arrived yet. Keep
                // the frame loop in step (its teardown waits for the frames in flight) and
                // exit as `Destroyed` does.
                frame_loop.submit(ctx, &[], &[])?;
                log::warn!("the window was destroyed: exiting");
                self.window_gone = true;
                return Ok(true);
            }
        };
        // A click waiting for the GPU is answered by this frame (recorded below).
        let frame_size = (renderer.settings.width, renderer.settings.height);
        // A stereo packing shows two eyes: clicks pick nothing there. The click is in the
        // window's pixels of the scene: the internal image's pixel under it.
        let display = graph.display.unwrap_or(frame_size);
        let pick_request = self
            .editor
            .take_pick_request()
            .filter(|_| self.stereo.is_none())
            .map(|p| internal_pixel(p, display, frame_size));
        if let Some(p) = self.pick.as_mut() {
            p.arm(slot, pick_request, frame_size);
        }
        if let Some(s) = self.pick_started.get_mut(slot) {
            *s = pick_request.map(|_| (Instant::now(), self.report.frames));
        }
        graph
            .exec
            .rebind_image(graph.present, &swapchain.images[index as usize])?;
        renderer.write_frame(slot);
        if let Some(st) = &mut self.stereo {
            st.write_frame(slot);
        }
        overlay.write_frame(slot, prims, ppp, extent);
        let shot = self.controls.screenshot || last_scripted;
        graph.shot_wanted.set(shot);
        if let Some(s) = self.recorded_steps.get_mut(slot) {
            *s = (self.renderer_frames > 0 && self.display.is_some()).then_some(recording_steps);
        }
        graph.exec.record(&cmd, slot, timestamps);
        frame_loop.submit(
            ctx,
            &[(ready, vk::PipelineStageFlags2::ALL_COMMANDS)],
            &[swapchain.render_semaphore(index)],
        )?;
        match swapchain.present(ctx, index)? {
            Presented::Done => {}
            Presented::Recreate => self.swapchain_dirty = true,
            // As at acquisition: the window was destroyed and `Destroyed` has not arrived.
            Presented::SurfaceLost => {
                log::warn!("the window was destroyed: exiting");
                self.window_gone = true;
            }
        }
        if let Some((p, gpu_ms, started)) = picked {
            if let Some((t, frame)) = started {
                log::info!(
                    "edit: pick at {:?} answered {} ms and {} frames after it was recorded (GPU: pick + pick_readback {gpu_ms:.3} ms)",
                    p.pixel,
                    t.elapsed().as_millis(),
                    self.report.frames - frame
                );
            }
            self.edit_picked(p);
        }
        self.report.frames += 1;
        self.renderer_frames += 1;
        if let (Some(change), Some(area)) = (change, self.display) {
            self.log_scale(change, area);
        }
        // For scripted tests (`RUST_LOG=voxgi::app=debug`): they wait for frames and for the
        // camera to get somewhere, not for a fixed time. Local coordinates (without
        // `Scene::origin_m`).
        // Then what dynamic resolution saw: the size rendered, the GPU time of the frame
        // that finished (two frames back) and this frame's wall time.
        log::debug!(
            "frame {} presented at {}x{} ({} of its renderer); camera at {:?} looking {:?}; \
             renders {}x{}, GPU {} ms, wall {:.1} ms",
            self.report.frames,
            extent.width,
            extent.height,
            self.renderer_frames,
            self.scene.camera.position.to_array(),
            self.scene.camera.forward.to_array(),
            frame_size.0,
            frame_size.1,
            gpu_ms.map_or_else(|| "-".to_owned(), |t: f64| format!("{t:.1}")),
            self.frame_dt_ms
        );
        if last_scripted {
            log::info!(
                "scripted run: the last frame is frame {} of its renderer",
                self.renderer_frames
            );
        }
        if shot {
            self.controls.screenshot = false;
            self.save_screenshot(ctx)?;
        }
        Ok(last_scripted)
    }

    /// Advances a scripted minimize: request it, wait until the window is minimized, skip
    /// `restore_after` redraws, request the restore, wait until the window is back.
    fn step_minimize_script(&mut self, window: &Window) -> Result<(), AppError> {
        let timed_out = |since: Instant, what| {
            if since.elapsed() > MINIMIZE_TIMEOUT {
                Err(AppError::Minimize {
                    what,
                    seconds: MINIMIZE_TIMEOUT.as_secs(),
                })
            } else {
                Ok(())
            }
        };
        match self.minimize_script {
            MinimizeScript::Pending => {
                if self
                    .opts
                    .minimize_at
                    .is_some_and(|n| self.report.frames >= n)
                {
                    window.set_minimized(true);
                    self.minimize_script = MinimizeScript::Requested(Instant::now());
                }
            }
            MinimizeScript::Requested(since) => {
                if self.minimized {
                    self.minimize_script = MinimizeScript::Minimized;
                } else {
                    timed_out(since, "minimize")?;
                }
            }
            MinimizeScript::Minimized => {
                if self.report.skipped_minimized >= self.opts.restore_after.max(1) {
                    window.set_minimized(false);
                    self.minimize_script = MinimizeScript::Restoring(Instant::now());
                }
            }
            MinimizeScript::Restoring(since) => {
                if !self.minimized {
                    self.minimize_script = MinimizeScript::Done;
                } else {
                    timed_out(since, "restore")?;
                }
            }
            MinimizeScript::Done => {}
        }
        Ok(())
    }

    /// Runs the panel; returns egui's triangles and pixels per point.
    fn run_ui(
        &mut self,
        ctx: &Context,
        window: &Window,
        extent: vk::Extent2D,
    ) -> Result<(Vec<egui::ClippedPrimitive>, f32), AppError> {
        self.controls.speed_m_s = self.fly.speed_m_s;
        let raw = self.egui_state.take_egui_input(window);
        let egui_ctx = self.egui_ctx.clone();
        let stereo_status = self.stereo.as_ref().map(stereo::ViewerStereo::describe);
        let info = panel::PanelInfo {
            device: &ctx.info.name,
            extent_px: (extent.width, extent.height),
            frame_ms: self.frame_ms,
            light_names: &self.light_names,
            object_names: &self.object_names,
            status: &self.status,
            gi_frames: self
                .renderer
                .as_ref()
                .and_then(Renderer::gi_accumulated_frames),
            stereo: stereo_status.as_deref(),
            history: &self.history,
            internal: self
                .renderer
                .as_ref()
                .map_or((0, 0), |r| (r.settings.width, r.settings.height)),
            scale_steps: self.display.map_or(dynres::STEPS, |_| self.dynres.steps()),
            gi: self.renderer.as_ref().map(|r| r.settings.gi),
        };
        let (controls, stats) = (&mut self.controls, &self.stats);
        let mut layout = panel::PanelLayout::default();
        let edit_view = edit_ui::EditView {
            editor: &self.editor,
            scene: &self.scene,
            light_names: &self.light_names,
        };
        let view = ViewGeomArgs {
            geom: edit::ViewGeom {
                camera: self.scene.camera,
                rect_px: self.view_rect,
            },
            time_s: controls.time_s,
        };
        let mut edits = edit_ui::PanelOut {
            actions: Vec::new(),
            position_field: None,
        };
        let mut out = egui_ctx.run_ui(raw, |root| {
            let mut edit_ui = |ui: &mut egui::Ui| edits = edit_ui::panel(ui, &edit_view);
            layout = panel::draw(root, controls, stats, &info, &mut edit_ui);
            let c = root.ctx();
            edit_ui::paint(
                c,
                edit_view.editor,
                edit_view.scene,
                &view.geom,
                view.time_s,
                c.pixels_per_point(),
            );
        });
        for a in edits.actions {
            self.apply_edit(a);
        }
        let field = edits.position_field.map(|r| {
            let c = r.center() * out.pixels_per_point;
            [c.x.round(), c.y.round()]
        });
        if field != self.position_field {
            if let Some([x, y]) = field {
                log::info!("edit: position field x at [{x}, {y}] (window px)");
            }
            self.position_field = field;
        }
        // Rounded down: the scene starts under the panel's edge rather than leaving a gap.
        self.panel_px = (layout.panel.width() * out.pixels_per_point)
            .max(0.0)
            .floor() as u32;
        self.log_panel_scroll(&layout.scroll, out.pixels_per_point);
        self.log_panel_spots(&layout.spots, out.pixels_per_point);
        self.panel_layout = layout;
        self.fly.speed_m_s = self.controls.speed_m_s;
        self.egui_state
            .handle_platform_output(window, out.platform_output);
        if let Some(overlay) = self.overlay.as_mut() {
            if overlay.update_textures(ctx, &mut out.textures_delta)? {
                // The atlas image changed: the graph imports the old one. (Dropped graphs are
                // released once the frames in flight that use them completed.)
                self.graph = None;
            }
        }
        // Applied or not wanted (no overlay): egui asserts that a dropped delta is empty.
        out.textures_delta.clear();
        let ppp = out.pixels_per_point;
        Ok((egui_ctx.tessellate(out.shapes, ppp), ppp))
    }

    /// Logs where the panel's scroll area stands and where its last control is when either
    /// changed (window px): the window tests scroll with the wheel and aim their clicks.
    fn log_panel_scroll(&mut self, s: &panel::ScrollLayout, ppp: f32) {
        let button = s.screenshot_button.center();
        let now = [
            s.offset,
            s.max_offset(),
            s.content_height,
            s.view.height(),
            button.x,
            button.y,
        ]
        .map(|v| (v * ppp).round());
        if self.panel_scroll != Some(now) && now.iter().all(|v| v.is_finite()) {
            let [offset, max, content, view, x, y] = now;
            log::info!(
                "panel: scrolled {offset} of {max} px (contents {content} px in a {view} px view); screenshot button at [{x}, {y}] (window px)"
            );
            self.panel_scroll = Some(now);
        }
    }

    /// Logs where each of the panel's named controls is when it appeared or moved (window
    /// px): the window tests aim their clicks with it.
    fn log_panel_spots(&mut self, spots: &[panel::Spot], ppp: f32) {
        self.panel_spots
            .retain(|name, _| spots.iter().any(|(n, _)| n == name));
        for (name, rect) in spots {
            let c = rect.center() * ppp;
            let at = [c.x.round(), c.y.round()];
            if at.iter().all(|v| v.is_finite()) && self.panel_spots.get(name) != Some(&at) {
                log::info!("panel: `{name}` at [{}, {}] (window px)", at[0], at[1]);
                self.panel_spots.insert(name.clone(), at);
            }
        }
    }

    /// Replaces the renderer by one made for `settings` and the panel's stereo controls (and
    /// drops the graph, which imports the old one's resources). When that fails for new GI
    /// or stereo settings, the old renderer stays, those settings revert (each eye's size
    /// fitted to `area` again) and the panel says why.
    fn replace_renderer(
        &mut self,
        ctx: &Context,
        settings: &mut RenderSettings,
        area: (u32, u32),
    ) -> Result<(), AppError> {
        ctx.wait_idle()?;
        self.graph = None;
        let started = Instant::now();
        match self.new_renderer(ctx, settings) {
            Ok((r, st)) => {
                self.renderer = Some(r);
                self.renderer_frames = 0;
                self.stereo = st;
                self.scene_shape = Some(edit::SceneShape::of(&self.scene));
                log::info!(
                    "new renderer {}x{}, indirect light: {}; post-processing: {} (made in {} ms)",
                    settings.width,
                    settings.height,
                    describe_gi(&settings.gi),
                    describe_post(&settings.post, &settings.tonemap),
                    started.elapsed().as_millis()
                );
                Ok(())
            }
            Err(e) => {
                // The old renderer stays; the GI settings and the stereo controls it was made
                // for come back.
                let old_gi = self.renderer.as_ref().map(|r| r.settings.gi);
                let old_stereo = self.stereo.as_ref().map(|st| st.built_for);
                let old_mode = old_stereo.and_then(|c| c.mode);
                let old_path = old_stereo.map(|c| c.path);
                let gi_changed = old_gi.is_some_and(|old| old != settings.gi);
                let stereo_changed = old_mode != self.controls.stereo.mode
                    || old_path.is_some_and(|p| p != self.controls.stereo.path);
                let Some(old_gi) = old_gi.filter(|_| gi_changed || stereo_changed) else {
                    return Err(e.into());
                };
                settings.gi = old_gi;
                self.controls.gi = old_gi;
                self.controls.stereo.mode = old_mode;
                if let Some(p) = old_path {
                    self.controls.stereo.path = p;
                }
                (settings.width, settings.height) = stereo::eye_size(old_mode, area);
                self.status = format!("settings not applied: {e}");
                log::warn!("{}", self.status);
                Ok(())
            }
        }
    }

    /// A renderer for `settings` and the panel's stereo controls: mono, or both eyes (with
    /// the stereo state; the status line says which path runs and why it fell back).
    fn new_renderer(
        &mut self,
        ctx: &Context,
        settings: &RenderSettings,
    ) -> Result<(Renderer, Option<stereo::ViewerStereo>), RenderError> {
        let c = self.controls.stereo;
        if c.mode.is_none() {
            if self.status.starts_with("stereo: ") {
                self.status.clear();
            }
            return Ok((Renderer::new(ctx, &self.scene, settings.clone())?, None));
        }
        let (r, st) = stereo::ViewerStereo::build(ctx, &self.scene, settings, c)?;
        self.status = st.describe();
        log::info!("{}", self.status);
        Ok((r, Some(st)))
    }

    /// The panel's projection and orthographic height, onto the camera, unless the frame (its
    /// GI method) cannot render them: then the panel switches back and the status says why.
    fn apply_projection(&mut self, settings: &RenderSettings) {
        let c = &self.controls;
        if (c.projection, c.ortho_height_m) == (self.lens.projection, self.lens.ortho_height_m) {
            return;
        }
        let lens = Camera {
            projection: c.projection,
            ortho_height_m: c.ortho_height_m,
            ..self.lens
        };
        match crate::render::check_projection(&lens, settings, c.stereo.mode.is_some()) {
            Ok(()) => {
                self.lens = lens;
                self.scene.camera = self.fly.apply(&self.lens);
                log::info!("projection: {}", lens.projection.name());
                if self.status.starts_with(PROJECTION_STATUS) {
                    self.status.clear();
                }
            }
            Err(e) => {
                self.controls.projection = self.lens.projection;
                self.controls.ortho_height_m = self.lens.ortho_height_m;
                self.status = format!("{PROJECTION_STATUS}: {e}");
                log::warn!("{}", self.status);
            }
        }
    }

    /// The panel's "best within budget": the most accurate configuration of this scene in
    /// the sweep that fits the budget (`voxgi tune`'s choice) becomes the GI settings, which
    /// makes a new renderer; the status line says what was chosen, or why nothing was.
    fn apply_best_within_budget(&mut self) {
        let budget = f64::from(self.controls.budget_ms);
        let dir = &self.opts.sweep_dir;
        match crate::tune::tune_from_dir(dir, &self.opts.scene_name, budget) {
            Ok((row, _, layer)) => {
                self.controls.gi = crate::scene::schema::apply(self.controls.gi, &[&layer]);
                self.status = format!(
                    "best within {budget} ms: {} ({:.1} ms to the image, relMSE {:.4}, on {})",
                    row.config, row.image_ms, row.rel_mse, row.device
                );
                log::info!("{}", self.status);
            }
            Err(e) => {
                self.status = format!("best within {budget} ms: {e}");
                log::warn!("{}", self.status);
            }
        }
    }

    /// Builds the frame graph for the current swapchain and renderer settings.
    fn rebuild(&mut self, ctx: &Context) -> Result<(), AppError> {
        ctx.wait_idle()?;
        self.graph = None;
        self.stats.clear();
        let (Some(renderer), Some(overlay), Some(swapchain)) = (
            self.renderer.as_ref(),
            self.overlay.as_ref(),
            self.swapchain.as_ref(),
        ) else {
            return Ok(());
        };
        if !overlay.ready() {
            return Ok(());
        }
        let extent = swapchain.extent;
        let mut g = RenderGraph::new();
        // The presented image: the tone-mapped frame, or in stereo both eyes' packing.
        let stereo_mode = self.stereo.as_ref().and(self.controls.stereo.mode);
        // Picks in flight belong to the old graph; a stereo packing has no pick pass.
        if let Some(p) = self.pick.as_mut() {
            p.forget();
        }
        let (ldr, (w, h)) = match (&self.stereo, stereo_mode) {
            (Some(st), Some(mode)) => st.declare(renderer, &mut g, mode),
            _ => {
                let (FrameImages { ldr, .. }, scene_inputs) = renderer.declare_with_scene(&mut g);
                if let Some(p) = self.pick.as_ref() {
                    p.declare(&mut g, &scene_inputs);
                }
                // TAA upsampling resolves into the scene's area: larger than the frame.
                (ldr, renderer.output_size())
            }
        };
        // The scene's place in the window: right-aligned, left of it is the panel. (Only a
        // side-by-side packing of 1-pixel eyes is wider than the window: squeezed into it.)
        // Under dynamic resolution the internal image is upscaled to the scene's area.
        let display = self.display.filter(|_| stereo_mode.is_none());
        let (dst_w, dst_h) = display.unwrap_or((w, h));
        let (dst_w, dst_h) = (dst_w.min(extent.width), dst_h.min(extent.height));
        // Bilinear where the sizes differ; the same size copies pixels as they are.
        let filter = if (dst_w, dst_h) == (w, h) {
            vk::Filter::NEAREST
        } else {
            vk::Filter::LINEAR
        };
        let scene_rect = vk::Rect2D {
            offset: vk::Offset2D {
                x: (extent.width - dst_w) as i32,
                y: 0,
            },
            extent: vk::Extent2D {
                width: dst_w,
                height: dst_h,
            },
        };
        let shot = ctx.create_buffer(&BufferDesc {
            name: "screenshot".into(),
            size_bytes: u64::from(w) * u64::from(h) * 4,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            location: MemoryLocation::GpuToCpu,
        })?;
        let present = g.import_image(&swapchain.images[0], Access::Present);
        let shot_handle = g.import_buffer(&shot, Access::HostRead);
        let shot_wanted = Rc::new(Cell::new(false));
        let wanted = shot_wanted.clone();
        g.add_pass("present")
            .read(ldr, Access::TransferRead)
            .write(present, Access::TransferWrite)
            .write(shot_handle, Access::TransferWrite)
            .record(move |c| {
                let (src, dst) = (c.image(ldr), c.image(present));
                c.cmd
                    .blit_image(src.raw, src.extent_2d(), dst.raw, scene_rect, filter);
                if wanted.get() {
                    let e = src.extent_2d();
                    c.cmd.copy_image_to_buffer(
                        src.raw,
                        vk::Extent3D {
                            width: e.width,
                            height: e.height,
                            depth: 1,
                        },
                        0,
                        1,
                        c.buffer(shot_handle).raw,
                    );
                }
            });
        overlay.declare(&mut g, present);
        let exec = GraphExecutor::new(ctx, g, MAX_FRAMES_IN_FLIGHT)?;
        self.view_rect = [scene_rect.offset.x as f32, 0.0, dst_w as f32, dst_h as f32];
        log::info!(
            "edit: scene viewport at [{}, 0] size [{dst_w}, {dst_h}] px",
            scene_rect.offset.x
        );
        let frame = (renderer.settings.width, renderer.settings.height);
        log::info!(
            "frame graph: {}, presents {w}x{h}{}",
            stereo_mode.map_or_else(|| "mono".to_owned(), crate::post::StereoMode::name),
            if (dst_w, dst_h) != (w, h) {
                format!(" upscaled to {dst_w}x{dst_h}")
            } else if stereo_mode.is_none() && frame != (w, h) {
                format!(" TAA-upsampled from {}x{}", frame.0, frame.1)
            } else {
                String::new()
            }
        );
        self.graph = Some(FrameGraph {
            exec,
            present,
            shot,
            shot_wanted,
            extent,
            settings: renderer.settings.clone(),
            stereo_mode,
            shot_size: (w, h),
            display: self.display,
        });
        Ok(())
    }

    /// Logs a change of the internal scale (and why) for the `area` it scales.
    fn log_scale(&self, change: dynres::Change, area: (u32, u32)) {
        let steps = self.dynres.steps();
        let (w, h) = self.dynres.internal_size(area);
        let why = match change {
            dynres::Change::Down { gpu_ms } => format!(
                "{gpu_ms:.1} ms over the {} ms budget",
                self.controls.dynres.frame_budget_ms
            ),
            dynres::Change::Up { gpu_ms } => format!(
                "{gpu_ms:.1} ms well within the {} ms budget",
                self.controls.dynres.frame_budget_ms
            ),
            dynres::Change::Refine => "the camera stands still: refining".into(),
            dynres::Change::Moving => "the camera moves".into(),
            dynres::Change::Settings => "new settings".into(),
            dynres::Change::Start => "starting at the smallest scale".into(),
        };
        log::info!(
            "dynamic resolution: {w}x{h} of {}x{} (scale {steps}/{}): {why}",
            area.0,
            area.1,
            dynres::STEPS
        );
    }

    fn save_screenshot(&mut self, ctx: &Context) -> Result<(), AppError> {
        ctx.wait_idle()?;
        let Some(g) = &self.graph else { return Ok(()) };
        let path = match &self.opts.screenshot {
            Some(p) => p.clone(),
            None => PathBuf::from(format!(
                "voxgi-shot-{}.png",
                self.report.screenshots.len() + 1
            )),
        };
        let (w, h) = g.shot_size;
        let n = (w * h * 4) as usize;
        let pixels = g.shot.mapped().map(|m| m[..n].to_vec()).unwrap_or_default();
        image::save_buffer(&path, &pixels, w, h, image::ColorType::Rgba8).map_err(|e| {
            AppError::Screenshot {
                path: path.clone(),
                reason: e.to_string(),
            }
        })?;
        self.status = format!("wrote {}", path.display());
        log::info!("{}", self.status);
        // In a still view, the frames TAA has blended into this image.
        log::info!("screenshot: frame {} of its renderer", self.renderer_frames);
        self.report.screenshots.push(path);
        Ok(())
    }

    /// Waits for the frames in flight and returns the report. Dropping the viewer then
    /// releases its GPU objects; the swapchain's drop waits for the device and destroys the
    /// swapchain and then the surface (the window outlives the viewer).
    fn close(mut self, ctx: &Context) -> ViewerReport {
        if let Some(fl) = self.frame_loop.as_mut() {
            // What a close mid-frame waits for (the window tests check it was a frame still
            // running, not one that had completed unseen).
            match fl.in_flight(ctx) {
                Ok(n) => log::info!(
                    "closing: waiting for {} frames in flight ({} still running)",
                    n.submitted,
                    n.running
                ),
                Err(e) => log::warn!("closing: the frames in flight are unknown: {e}"),
            }
            let _ = fl.finish(ctx);
        }
        self.report.camera = Some(self.fly.apply(&self.lens));
        self.report.origin_m = self.scene.origin_m;
        std::mem::take(&mut self.report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_panels_atlas_object_reaches_the_renderer_settings() {
        use crate::voxel::debug_view::{DebugSettings, DebugView};
        let current = RenderSettings {
            debug: Some(DebugSettings {
                view: DebugView::Level,
                level: 3,
                ..Default::default()
            }),
            ..Default::default()
        };
        let mut c = Controls {
            tonemap: current.tonemap,
            post: current.post,
            shadow: current.shadow,
            gi: current.gi,
            light_scale: Vec::new(),
            speed_m_s: 1.0,
            time_s: 0.0,
            animate: false,
            debug: Some(DebugView::Atlas),
            atlas_object: 2,
            screenshot: false,
            add_keyframe: false,
            budget_ms: 100.0,
            tune: false,
            dynres: Default::default(),
            stereo: StereoControls::off(&crate::scene::builtin("cornell").expect("cornell"), 0.0),
            projection: crate::scene::Projection::Perspective,
            ortho_height_m: 1.0,
            open: Default::default(),
        };
        let d = debug_settings(&c, current.debug).expect("a debug view");
        assert_eq!((d.view, d.object, d.level), (DebugView::Atlas, 2, 3));
        let picked = RenderSettings {
            debug: Some(d),
            ..current.clone()
        };
        c.atlas_object = 1;
        let other = RenderSettings {
            debug: debug_settings(&c, picked.debug),
            ..current.clone()
        };
        assert!(
            needs_new_renderer(&picked, &other),
            "another object needs a new renderer"
        );
        c.debug = None;
        assert_eq!(debug_settings(&c, picked.debug), None);
    }

    #[test]
    fn light_scale_scales_the_radiometric_quantity() {
        let p = Light::Point {
            position: Vec3::ZERO,
            intensity_w_sr: Vec3::splat(2.0),
        };
        assert_eq!(
            scaled(&p, 0.5),
            Light::Point {
                position: Vec3::ZERO,
                intensity_w_sr: Vec3::ONE
            }
        );
        let d = Light::Directional {
            direction: Vec3::NEG_Y,
            irradiance_w_m2: Vec3::ONE,
        };
        assert!(
            matches!(scaled(&d, 3.0), Light::Directional { irradiance_w_m2, .. } if irradiance_w_m2 == Vec3::splat(3.0))
        );
    }

    #[test]
    fn clicks_map_to_the_internal_image_under_them() {
        // The same size: the same pixel.
        assert_eq!(internal_pixel((37, 11), (100, 50), (100, 50)), (37, 11));
        // A quarter per axis: pixel x of the area lies in internal pixel ⌊x · 25/100⌋.
        assert_eq!(internal_pixel((0, 0), (100, 50), (25, 12)), (0, 0));
        assert_eq!(internal_pixel((3, 4), (100, 50), (25, 12)), (0, 0));
        assert_eq!(internal_pixel((4, 5), (100, 50), (25, 12)), (1, 1));
        assert_eq!(internal_pixel((99, 49), (100, 50), (25, 12)), (24, 11));
        // Never outside the image, whatever the click.
        assert_eq!(internal_pixel((500, 500), (100, 50), (25, 12)), (24, 11));
    }

    #[test]
    fn only_graph_shaping_settings_rebuild() {
        let a = RenderSettings::default();
        let mut b = a.clone();
        b.shadow.pcf_radius += 1;
        b.shadow.bias_texels *= 2.0;
        assert!(!needs_new_graph(&a, &b));
        b.shadow.cascade_lambda = 0.9;
        assert!(!needs_new_graph(&a, &b));
        let mut cascades = a.clone();
        cascades.shadow.cascades = 2;
        assert!(needs_new_graph(&a, &cascades));
        b.tonemap.exposure *= 2.0;
        assert!(needs_new_graph(&a, &b));
        let mut c = a.clone();
        c.width += 1;
        assert!(needs_new_graph(&a, &c));
    }

    #[test]
    fn gi_changes_need_a_new_renderer() {
        let a = RenderSettings::default();
        let mut b = a.clone();
        // Without GI a size change only rebuilds the graph.
        b.width += 1;
        b.tonemap.exposure *= 2.0;
        assert!(!needs_new_renderer(&a, &b));
        for change in [
            |g: &mut GiSettings| g.method = GiMethod::Pathtrace,
            |g: &mut GiSettings| g.rays += 1,
            |g: &mut GiSettings| g.bounces = crate::gi::Bounces::Unbounded,
            |g: &mut GiSettings| g.radius_m = Some(1.0),
            |g: &mut GiSettings| g.filter_radius += 1,
            |g: &mut GiSettings| g.filter_passes += 1,
            |g: &mut GiSettings| g.normal_offset_voxels += 0.5,
        ] {
            let mut c = a.clone();
            change(&mut c.gi);
            assert!(needs_new_renderer(&a, &c), "{:?}", c.gi);
        }
        // With GI on, the path tracer's history has the frame's size.
        let mut on = a.clone();
        on.gi.method = GiMethod::Hemisphere;
        let mut resized = on.clone();
        resized.height += 1;
        assert!(needs_new_renderer(&on, &resized));
        assert!(!needs_new_renderer(&on, &on.clone()));
    }
}
