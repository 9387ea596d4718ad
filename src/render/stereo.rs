//! Stereo rendering: both eyes of a [`StereoRig`] with parallel axes and off-axis frusta
//! ([`Camera::eye`]), packed by the `stereo_pack` pass. Three paths give the same images:
//!
//! - **One frame** ([`StereoPath::OneFrame`], [`StereoPath::default`]): one
//!   [`Renderer`] built with [`Renderer::new_stereo`] renders both eyes in one frame graph.
//!   World-space passes run once (shadow maps, voxelization, attribute volumes, reflective
//!   light maps, the VPLs and their bounces, the radiance volume); the G-buffer draws both
//!   eyes into two-layer images (one pass per eye); every screen-space pass (direct light, the
//!   GI gathers, filter, SAO, composite, TAA, exposure, bloom, tone mapping, FXAA) runs once
//!   per eye on its layer ([`crate::graph::RenderGraph::layer`]), the right eye's named with
//!   [`RIGHT_EYE_SUFFIX`]. Per eye as well: the frame constants, TAA's history and jitter,
//!   the exposure state, the path tracer's history.
//! - **Multiview** ([`StereoPath::Multiview`]): the same frame with both eyes' G-buffer in one
//!   Vulkan multiview pass (`gbuffer_multiview`: view i into layer i). The command line's
//!   default where the device has the feature ([`default_path`]); on lavapipe before Mesa
//!   23.0.4 its draws carry a flushing instance ([`MultiviewDefect`]).
//! - **Two passes** ([`StereoPath::TwoPass`]): one [`Renderer`] renders the whole frame graph
//!   once per eye (`prepare` with each eye's camera), sharing only what [`Renderer::new`]
//!   builds once (scene upload, static voxelization, atlases). The fallback where one frame
//!   cannot run ([`multiview_blocker`]), and what `--stereo-path two-pass` asks for.
//!
//! [`Camera::eye`]: crate::scene::Camera::eye

use super::multiview::{MultiviewDefect, RIGHT_EYE_SUFFIX};
use super::run::{render_frames, RenderOutput};
use super::{FrameImages, RenderError, RenderSettings, Renderer};
use crate::graph::{run_once, Access, OneShotError, RenderGraph, Shader};
use crate::post::{StereoMode, StereoPackPass};
use crate::scene::{Eye, Scene, StereoRig};
use crate::vk::{vk, Buffer, Context, ImageDesc, PassTiming};

/// How a stereo pair is rendered (`--stereo-path`; without it the command line takes
/// [`default_path`], and so does the viewer).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum StereoPath {
    /// Both eyes in one frame, world-space work once, the G-buffer drawn once per eye into
    /// its layer. Runs on every device.
    #[default]
    OneFrame,
    /// Both eyes in one frame, world-space work once, the G-buffer of both eyes in one
    /// Vulkan multiview pass.
    Multiview,
    /// The whole frame once per eye.
    TwoPass,
}

impl StereoPath {
    pub fn name(self) -> &'static str {
        match self {
            StereoPath::OneFrame => "one-frame",
            StereoPath::Multiview => "multiview",
            StereoPath::TwoPass => "two-pass",
        }
    }
}

/// Why a one-frame stereo renderer (`path` [`StereoPath::OneFrame`] or
/// [`StereoPath::Multiview`]) cannot render `scene` with `settings` on this device (`None`:
/// it can). Each of these keeps state or views that belong to one camera.
pub fn multiview_blocker(
    ctx: &Context,
    path: StereoPath,
    scene: &Scene,
    settings: &RenderSettings,
) -> Option<String> {
    let device = path != StereoPath::Multiview || ctx.info.multiview;
    multiview_blocker_for(device, scene, settings)
}

fn multiview_blocker_for(
    device_multiview: bool,
    scene: &Scene,
    settings: &RenderSettings,
) -> Option<String> {
    let directional = scene.lights.iter().any(crate::scene::Light::is_directional);
    let oit = settings.transparency == crate::scene::Transparency::Oit && scene.has_transparency();
    if !device_multiview {
        Some("the device lacks the Vulkan 1.1 feature `multiview`".into())
    } else if settings.debug.is_some() {
        Some("--debug views render one view".into())
    } else if let Some(why) = settings.gi.method.spec().multiview_blocker {
        Some(why.into())
    } else if oit {
        Some("the transparency lists (--transparency oit) are drawn for one view".into())
    } else if directional && settings.shadow.cascades >= 2 {
        Some("the cascaded shadow maps (--shadow-cascades) are fitted to one camera".into())
    } else {
        None
    }
}

/// The stereo path `voxgi render --stereo` and `voxgi profile --stereo` take without
/// `--stereo-path`, and why: multiview where the device has the feature (with the workaround
/// of a [`MultiviewDefect`] where the driver has one), else one-frame.
pub fn default_path(info: &crate::vk::DeviceInfo) -> (StereoPath, String) {
    if !info.multiview {
        return (
            StereoPath::OneFrame,
            "default: the device lacks the Vulkan feature multiview".into(),
        );
    }
    match MultiviewDefect::of(info.driver_id, &info.driver_info) {
        None => (
            StereoPath::Multiview,
            "default: the device has multiview".into(),
        ),
        Some(d) => (
            StereoPath::Multiview,
            format!("default: the device has multiview; {}", d.describe()),
        ),
    }
}

/// The right eye of a one-frame stereo renderer: its frame constants, post passes (TAA
/// history and jitter, exposure state) and read-back buffers.
pub(super) struct OnePass {
    pub rig: StereoRig,
    /// The right eye's frame constants, un-jittered (`Renderer::frame_data` is the left's).
    pub frame_right: super::GpuFrame,
    pub post_right: crate::post::PostPasses,
    /// The right eye's un-jittered view-projection of the last frame written (the motion
    /// vectors' previous camera; scenes with moving objects under TAA).
    pub prev_view_proj_right: Option<glam::Mat4>,
    /// Read-back of the right eye's radiance and tone-mapped image.
    pub readback_right: [Buffer; 2],
}

impl OnePass {
    pub fn new(
        ctx: &Context,
        rig: StereoRig,
        settings: &RenderSettings,
        sampler: vk::Sampler,
        moving: bool,
    ) -> Result<Self, RenderError> {
        let size = (settings.width, settings.height);
        let [hdr, ldr] = super::readback_descs(size);
        Ok(Self {
            rig,
            frame_right: bytemuck::Zeroable::zeroed(),
            post_right: crate::post::PostPasses::new(ctx, &settings.post, size, sampler, moving)?,
            prev_view_proj_right: None,
            readback_right: [ctx.create_buffer(&hdr)?, ctx.create_buffer(&ldr)?],
        })
    }

    /// The right eye's frame constants for the next frame, with its TAA jitter and, with
    /// `motion`, its previous camera.
    pub fn jittered_right_frame(&mut self, motion: bool) -> super::GpuFrame {
        let view_proj = glam::Mat4::from_cols_array(&self.frame_right.view_proj);
        let mut frame = super::jittered(self.frame_right, &mut self.post_right);
        if motion {
            let prev = self.prev_view_proj_right.unwrap_or(view_proj);
            frame.prev_view_proj = prev.to_cols_array();
            self.prev_view_proj_right = Some(view_proj);
        }
        frame
    }
}

impl Renderer {
    /// A one-frame stereo renderer's new eye separation or convergence, taken by the next
    /// [`Renderer::prepare`] (nothing for a mono renderer).
    pub fn set_stereo_rig(&mut self, rig: StereoRig) {
        if let Some(st) = &mut self.stereo {
            st.rig = rig;
        }
    }

    /// The radiance and tone-mapped pixels of eye `eye` (0 left, 1 right) of the last
    /// completed frame of a one-frame stereo renderer; a mono renderer's image for eye 0.
    pub fn eye_images(&self, eye: u32) -> (crate::eval::HdrImage, Vec<u8>) {
        match (eye, &self.stereo) {
            (1, Some(st)) => {
                let [hdr, ldr] = &st.readback_right;
                let (w, h) = (self.settings.width, self.settings.height);
                (super::hdr_from(hdr, (w, h)), super::ldr_from(ldr, (w, h)))
            }
            _ => (self.hdr_image(), self.ldr_pixels()),
        }
    }
}

/// The renderers of a stereo pair drawn in one frame graph (the viewer's frame, `voxgi profile
/// --stereo`): one renderer of both eyes ([`Renderer::new_stereo`], one-frame or multiview), or
/// on the two-pass path one mono renderer per eye, both declared into the same graph (the
/// right eye's passes with [`RIGHT_EYE_SUFFIX`]). Like [`render_stereo`], a one-frame path
/// that cannot run ([`multiview_blocker`]) falls back to two passes and keeps the reason.
pub struct StereoRenderers {
    /// The renderer of both eyes, or on the two-pass path the left eye's.
    pub primary: Renderer,
    /// The right eye's renderer on the two-pass path.
    pub right: Option<Renderer>,
    pub rig: StereoRig,
    /// The path that runs.
    pub path: StereoPath,
    /// Why the path asked for could not run (`None`: it runs).
    pub fallback: Option<String>,
}

impl StereoRenderers {
    /// Renderers of `scene`'s stereo pair (`scene.camera` is the centre between the eyes),
    /// each eye `settings.width` × `settings.height`, on `path` or on two passes where it
    /// cannot run.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
        rig: StereoRig,
        path: StereoPath,
    ) -> Result<Self, RenderError> {
        super::check_projection(&scene.camera, settings, true)?;
        let fallback = match path {
            StereoPath::TwoPass => None,
            p => multiview_blocker(ctx, p, scene, settings),
        };
        let path = if fallback.is_some() {
            StereoPath::TwoPass
        } else {
            path
        };
        let (primary, right) = match path {
            StereoPath::TwoPass => {
                let left = eye_scene(scene, rig, Eye::Left);
                let right = eye_scene(scene, rig, Eye::Right);
                (
                    Renderer::new(ctx, &left, settings.clone())?,
                    Some(Renderer::new(ctx, &right, settings.clone())?),
                )
            }
            p => {
                let multiview = p == StereoPath::Multiview;
                let r = Renderer::new_stereo(ctx, scene, settings.clone(), rig, multiview)?;
                (r, None)
            }
        };
        Ok(Self {
            primary,
            right,
            rig,
            path,
            fallback,
        })
    }

    /// Prepares the next frame of `scene` (its camera is the centre between the eyes).
    pub fn prepare(&mut self, scene: &Scene) -> Result<(), RenderError> {
        prepare_pair(&mut self.primary, self.right.as_mut(), self.rig, scene)
    }

    /// Writes frame slot `slot`'s constants of every renderer ([`Renderer::write_frame`]).
    pub fn write_frame(&mut self, slot: usize) {
        self.primary.write_frame(slot);
        if let Some(right) = &mut self.right {
            right.write_frame(slot);
        }
    }

    /// Declares both eyes' frames into `g`: (left, right).
    pub fn declare_eyes(&self, g: &mut RenderGraph) -> [FrameImages; 2] {
        declare_pair(&self.primary, self.right.as_ref(), g)
    }
}

/// Prepares the next frame of a stereo pair of `scene` (its camera is the centre between the
/// eyes): a one-frame `primary` takes the centre camera, a two-pass pair (`right` given) each
/// eye's camera of `rig`.
pub fn prepare_pair(
    primary: &mut Renderer,
    right: Option<&mut Renderer>,
    rig: StereoRig,
    scene: &Scene,
) -> Result<(), RenderError> {
    match right {
        Some(right) => {
            primary.prepare(&eye_scene(scene, rig, Eye::Left))?;
            right.prepare(&eye_scene(scene, rig, Eye::Right))
        }
        None => {
            primary.set_stereo_rig(rig);
            primary.prepare(scene)
        }
    }
}

/// Declares the eyes of a stereo pair into `g`: both from a one-frame renderer, or (`right`
/// given, the two-pass path) the left eye from `primary` and the right eye from `right`, its
/// passes named with [`RIGHT_EYE_SUFFIX`].
pub fn declare_pair(
    primary: &Renderer,
    right: Option<&Renderer>,
    g: &mut RenderGraph,
) -> [FrameImages; 2] {
    match right {
        Some(right) => {
            let left = primary.declare(g);
            g.set_pass_suffix(RIGHT_EYE_SUFFIX);
            let right = right.declare(g);
            g.set_pass_suffix("");
            [left, right]
        }
        None => {
            let eyes = primary.declare_eyes(g);
            // A one-frame renderer declares both eyes; a mono one (never built as a pair's
            // primary without `right`) would show its one eye twice.
            [eyes[0], *eyes.last().unwrap_or(&eyes[0])]
        }
    }
}

/// The convergence distance `voxgi render --stereo` and the viewer take without
/// `--convergence`: the depth of the centre of the scene's bounding box at `time_s` along the
/// view direction, or 2 m when that centre is not in front of the camera.
pub fn default_convergence_m(scene: &Scene, time_s: f32) -> f32 {
    let b = scene.aabb_at(time_s);
    let along = ((b.min + b.max) * 0.5 - scene.camera.position).dot(scene.camera.forward);
    if along > 0.0 {
        along
    } else {
        2.0
    }
}

/// A stereo frame's settings: the packing and the eyes' parallax.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoSettings {
    pub mode: StereoMode,
    pub rig: StereoRig,
    /// The path asked for; one pass falls back to two where it cannot run.
    pub path: StereoPath,
}

/// The result of [`render_stereo`].
pub struct StereoOutput {
    /// Each eye's frame, as [`super::render_image`] returns it. On a one-frame path the
    /// frame's timings (both eyes, every pass) are the left eye's; the right's are empty.
    pub left: RenderOutput,
    pub right: RenderOutput,
    /// The packed image, sRGB RGBA8, of `packed_size`.
    pub packed: Vec<u8>,
    pub packed_size: (u32, u32),
    /// GPU time of the packing (`stereo_pack` and its read-back).
    pub pack_timings: Vec<PassTiming>,
    /// The path that ran.
    pub path: StereoPath,
    /// Why one pass was asked for and two ran (`None`: the path asked for ran).
    pub fallback: Option<String>,
}

/// The scene as seen by one eye of `rig`.
pub fn eye_scene(scene: &Scene, rig: StereoRig, eye: Eye) -> Scene {
    let mut s = scene.clone();
    s.camera = scene.camera.eye(rig, eye);
    s
}

/// Renders both eyes of `scene` (each `settings.width` × `settings.height`) on
/// `stereo.path`, or on two passes where one cannot run ([`multiview_blocker`]), and packs
/// the pair with `stereo.mode`.
pub fn render_stereo(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    stereo: StereoSettings,
) -> Result<StereoOutput, RenderError> {
    check_packed_width(stereo.mode, settings.width)?;
    super::check_projection(&scene.camera, settings, true)?;
    let fallback = match stereo.path {
        StereoPath::TwoPass => None,
        path => multiview_blocker(ctx, path, scene, settings),
    };
    let path = match fallback {
        Some(_) => StereoPath::TwoPass,
        None => stereo.path,
    };
    let (left, right) = match path {
        StereoPath::OneFrame | StereoPath::Multiview => {
            let (rig, multiview) = (stereo.rig, path == StereoPath::Multiview);
            let mut renderer = Renderer::new_stereo(ctx, scene, settings.clone(), rig, multiview)?;
            let left = render_frames(ctx, &mut renderer)?;
            let (hdr, ldr) = renderer.eye_images(1);
            let right = RenderOutput {
                hdr,
                ldr,
                timings: Vec::new(),
                ..left.clone_facts()
            };
            (left, right)
        }
        StereoPath::TwoPass => {
            let left_scene = eye_scene(scene, stereo.rig, Eye::Left);
            let right_scene = eye_scene(scene, stereo.rig, Eye::Right);
            let mut renderer = Renderer::new(ctx, &left_scene, settings.clone())?;
            let left = render_frames(ctx, &mut renderer)?;
            // A new camera resets accumulated indirect light (`Renderer::prepare`).
            renderer.prepare(&right_scene)?;
            let right = render_frames(ctx, &mut renderer)?;
            (left, right)
        }
    };
    // The eyes' renderer is gone before the packing pass allocates.
    let eye_size = (settings.width, settings.height);
    let (packed, pack_timings) = pack(ctx, (&left.ldr, &right.ldr), stereo.mode, eye_size)?;
    Ok(StereoOutput {
        left,
        right,
        packed,
        packed_size: stereo.mode.packed_size(eye_size),
        pack_timings,
        path,
        fallback,
    })
}

/// What [`profile_stereo`] measured: the stereo frame (both eyes and their packing) and, in
/// the same run, the mono frame of the same settings (the centre camera).
pub struct StereoProfile {
    pub stereo: super::ProfileRun,
    pub mono: super::ProfileRun,
    /// The path that ran, and why it is not the one asked for.
    pub path: StereoPath,
    pub fallback: Option<String>,
}

/// Frames of each graph per round of [`profile_stereo`].
pub const PROFILE_ROUND_FRAMES: usize = 5;

/// Per-pass GPU timing over many frames of `scene`'s stereo pair (for `voxgi profile
/// --stereo`): the frame graph of [`StereoRenderers`] (one-frame, multiview, or two-pass as
/// two renderers in one graph) with the packing and its read-back, and the mono frame of the
/// same settings. After `warmup` frames of each, the two graphs take turns in rounds of a few
/// frames until each has `frames`, so both see the same load of a shared machine.
pub fn profile_stereo(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    stereo: StereoSettings,
    frames: usize,
    warmup: usize,
) -> Result<StereoProfile, RenderError> {
    check_packed_width(stereo.mode, settings.width)?;
    let mut pair = StereoRenderers::new(ctx, scene, settings, stereo.rig, stereo.path)?;
    pair.prepare(scene)?;
    let mut mono = Renderer::new(ctx, scene, settings.clone())?;
    let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
    let pack = StereoPackPass::new(ctx, sampler.raw)?;
    let eye = (settings.width, settings.height);
    let (pw, ph) = stereo.mode.packed_size(eye);
    let readback = crate::graph::readback_buffer(ctx, "stereo read-back", u64::from(pw * ph * 4))?;
    let mut g = RenderGraph::new();
    let [left, right] = pair.declare_eyes(&mut g);
    let packed = pack.declare(&mut g, (left.ldr, right.ldr), stereo.mode, eye);
    let buf = g.import_buffer(&readback, Access::HostRead);
    crate::graph::add_readback(&mut g, "readback_stereo", packed, buf);
    let in_flight = crate::vk::MAX_FRAMES_IN_FLIGHT;
    let exec_stereo = crate::graph::GraphExecutor::new(ctx, g, in_flight)?;
    let exec_mono = crate::graph::GraphExecutor::new(ctx, mono.graph(), in_flight)?;
    use crate::graph::run_frames as run;
    run(ctx, &exec_stereo, warmup, warmup, |slot| {
        pair.write_frame(slot)
    })?;
    run(ctx, &exec_mono, warmup, warmup, |slot| {
        mono.write_frame(slot)
    })?;
    let (mut stereo_frames, mut mono_frames) = (Vec::new(), Vec::new());
    while stereo_frames.len() < frames || mono_frames.len() < frames {
        let n = PROFILE_ROUND_FRAMES
            .min(frames - stereo_frames.len().min(frames))
            .max(1);
        stereo_frames.extend(run(ctx, &exec_stereo, n, 0, |slot| pair.write_frame(slot))?);
        let n = PROFILE_ROUND_FRAMES
            .min(frames - mono_frames.len().min(frames))
            .max(1);
        mono_frames.extend(run(ctx, &exec_mono, n, 0, |slot| mono.write_frame(slot))?);
    }
    stereo_frames.truncate(frames);
    mono_frames.truncate(frames);
    let mut stereo_run = super::run::profile_run(&exec_stereo, &pair.primary, stereo_frames);
    if let Some(right) = &pair.right {
        stereo_run.setup.extend(right.setup_timings());
    }
    Ok(StereoProfile {
        stereo: stereo_run,
        mono: super::run::profile_run(&exec_mono, &mono, mono_frames),
        path: pair.path,
        fallback: pair.fallback,
    })
}

/// Refuses a packed image wider than the renderer's widest image ([`crate::limits::WIDTH`]):
/// side-by-side-full doubles `--width`.
fn check_packed_width(mode: StereoMode, width: u32) -> Result<(), crate::limits::LimitError> {
    let (packed_w, _) = mode.packed_size((width, 1));
    let max = crate::limits::WIDTH.max;
    if packed_w > max {
        return Err(crate::limits::LimitError {
            name: "--width".into(),
            value: width.to_string(),
            expected: format!(
                "at most {} with --stereo side-by-side-full, whose image is twice as wide (at most {max})",
                max / 2
            ),
        });
    }
    Ok(())
}

/// Packs two sRGB RGBA8 eye images of `eye_size` with `mode` on the GPU (`stereo_pack`);
/// returns the packed pixels and the passes' timings.
pub fn pack(
    ctx: &Context,
    (left, right): (&[u8], &[u8]),
    mode: StereoMode,
    eye_size: (u32, u32),
) -> Result<(Vec<u8>, Vec<PassTiming>), RenderError> {
    let (w, h) = eye_size;
    let eye_desc = |name: &str| ImageDesc::new_2d(name, vk::Format::R8G8B8A8_UNORM, w, h);
    let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
    let pass = StereoPackPass::new(ctx, sampler.raw)?;
    let (pw, ph) = mode.packed_size(eye_size);
    let left = ctx.upload_image(&eye_desc("left eye"), &[left.to_vec()])?;
    let right = ctx.upload_image(&eye_desc("right eye"), &[right.to_vec()])?;
    let readback = crate::graph::readback_buffer(ctx, "stereo read-back", u64::from(pw * ph * 4))?;
    let mut g = RenderGraph::new();
    let l = g.import_image(&left, Access::Sampled(Shader::Compute));
    let r = g.import_image(&right, Access::Sampled(Shader::Compute));
    let packed = pass.declare(&mut g, (l, r), mode, eye_size);
    let buf = g.import_buffer(&readback, Access::HostRead);
    crate::graph::add_readback(&mut g, "readback_stereo", packed, buf);
    let timings = run_once(ctx, g).map_err(|e| match e {
        OneShotError::Graph(e) => RenderError::Graph(e),
        OneShotError::Vk(e) => RenderError::Vk(e),
    })?;
    let pixels = readback
        .mapped()
        .map(|m| m[..(pw * ph * 4) as usize].to_vec())
        .unwrap_or_default();
    Ok((pixels, timings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Scene {
        crate::scene::builtin("cornell").expect("built-in scene")
    }

    /// Each configuration that keeps one camera's state falls back, with its reason naming
    /// the flag; the plain frame does not.
    #[test]
    fn multiview_blockers_name_their_reason() {
        let scene = cornell();
        let s = RenderSettings::default();
        assert_eq!(multiview_blocker_for(true, &scene, &s), None);
        let no_device = multiview_blocker_for(false, &scene, &s).unwrap_or_default();
        assert!(no_device.contains("multiview"), "{no_device}");
        let mut ssgi = s.clone();
        ssgi.gi.method = crate::gi::GiMethod::Ssgi;
        let why = multiview_blocker_for(true, &scene, &ssgi).unwrap_or_default();
        assert!(why.contains("--gi ssgi"), "{why}");
        let mut debug = s.clone();
        debug.debug = Some(Default::default());
        let why = multiview_blocker_for(true, &scene, &debug).unwrap_or_default();
        assert!(why.contains("--debug"), "{why}");
        for gi in [
            crate::gi::GiMethod::None,
            crate::gi::GiMethod::Hemisphere,
            crate::gi::GiMethod::Vpl,
            crate::gi::GiMethod::Pathtrace,
        ] {
            let mut m = s.clone();
            m.gi.method = gi;
            m.post.taa = Some(Default::default());
            assert_eq!(multiview_blocker_for(true, &scene, &m), None, "{gi:?}");
        }
    }
}
