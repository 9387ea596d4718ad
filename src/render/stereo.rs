//! Stereo rendering, two-pass: one [`Renderer`] renders the frame once per eye, each eye
//! through the whole frame graph with its own off-axis camera ([`Camera::eye`]), and the
//! `stereo_pack` pass packs the two tone-mapped images.
//!
//! What the eyes share: everything [`Renderer::new`] builds once — the scene on the GPU, the
//! static voxelization and the texture atlases. Every per-frame pass runs again for the second
//! eye. Of the GI methods, the world-space parts are view-independent and could be shared by a
//! one-pass (multiview) renderer: the radiance volume of `--gi radiance-volume`, the shadow and
//! reflective light maps, and the VPLs of `--gi vpl` (generated from the light maps); the
//! screen-space gathers (hemisphere rays, path tracing, VPL gathering, the filter) are per eye.
//! Vulkan multiview (both eyes in one pass over a two-layer image) is the follow-up.
//!
//! [`Camera::eye`]: crate::scene::Camera::eye

use super::run::render_frames;
use super::{RenderError, RenderOutput, RenderSettings, Renderer};
use crate::graph::{run_once, Access, OneShotError, RenderGraph, Shader};
use crate::post::{StereoMode, StereoPackPass};
use crate::scene::{Eye, Scene, StereoRig};
use crate::vk::{vk, Context, ImageDesc, PassTiming};

/// A stereo frame's settings: the packing and the eyes' parallax.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoSettings {
    pub mode: StereoMode,
    pub rig: StereoRig,
}

/// The result of [`render_stereo`].
pub struct StereoOutput {
    /// Each eye's frame, as [`super::render_image`] returns it.
    pub left: RenderOutput,
    pub right: RenderOutput,
    /// The packed image, sRGB RGBA8, of `packed_size`.
    pub packed: Vec<u8>,
    pub packed_size: (u32, u32),
    /// GPU time of the packing (`stereo_pack` and its read-back).
    pub pack_timings: Vec<PassTiming>,
}

/// The scene as seen by one eye of `rig`.
pub fn eye_scene(scene: &Scene, rig: StereoRig, eye: Eye) -> Scene {
    let mut s = scene.clone();
    s.camera = scene.camera.eye(rig, eye);
    s
}

/// Renders `scene` once per eye (each eye `settings.width` × `settings.height`) and packs the
/// pair with `stereo.mode`.
pub fn render_stereo(
    ctx: &Context,
    scene: &Scene,
    settings: &RenderSettings,
    stereo: StereoSettings,
) -> Result<StereoOutput, RenderError> {
    check_packed_width(stereo.mode, settings.width)?;
    let left_scene = eye_scene(scene, stereo.rig, Eye::Left);
    let right_scene = eye_scene(scene, stereo.rig, Eye::Right);
    let mut renderer = Renderer::new(ctx, &left_scene, settings.clone())?;
    let left = render_frames(ctx, &mut renderer)?;
    // A new camera resets accumulated indirect light (`Renderer::prepare`).
    renderer.prepare(&right_scene)?;
    let right = render_frames(ctx, &mut renderer)?;
    // The eyes' renderer goes before the packing pass allocates.
    drop(renderer);
    let eye_size = (settings.width, settings.height);
    let (packed, pack_timings) = pack(ctx, (&left.ldr, &right.ldr), stereo.mode, eye_size)?;
    Ok(StereoOutput {
        left,
        right,
        packed,
        packed_size: stereo.mode.packed_size(eye_size),
        pack_timings,
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
