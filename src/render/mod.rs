//! The frame of voxgi: shadow maps → G-buffer → deferred direct light → (indirect light) →
//! tone mapping, with read-back of the linear HDR radiance and the tone-mapped image.
//!
//! Each pass lives in the file named after its shader (`shadow_depth.rs` for
//! `glsl/shadow_depth.*`, …) with its pipeline, push constants and declaration; [`Renderer`]
//! owns them and the scene on the GPU ([`SceneGpu`]) and assembles the frame in
//! [`Renderer::declare`]. [`render_image`] and [`profile_scene`] run frames headless.

mod create;
mod declare;
mod deferred_direct;
mod direct_emitters;
mod frame;
mod gbuffer;
mod gbuffer_view;
pub mod gpu;
mod light_map;
pub mod memory;
mod multiview;
mod oit;
mod oit_clear;
mod oit_gather;
mod oit_resolve;
mod preflight;
mod run;
mod scene_gpu;
mod settings_check;
mod shadow_depth;
pub mod shadow_texels;
mod stereo;
mod textures;

pub use create::needs_voxels;
pub use gbuffer::Gbuffer;
pub use light_map::LightMaps;
pub use multiview::{MesaVersion, MultiviewDefect, RIGHT_EYE_SUFFIX};
pub use oit::{OitStats, DEFAULT_NODES_PER_PIXEL as OIT_DEFAULT_NODES_PER_PIXEL};
pub use oit_resolve::MAX_LAYERS as OIT_MAX_LAYERS;
pub use preflight::{check_lights, check_projection, check_setting_combination};
pub use run::{
    frames_to_image, profile_camera_path, profile_scene, profile_steps, render_animation,
    render_flight, render_image, render_sequence, Flight, ProfileRun, RenderOutput, SequenceOutput,
};
pub use scene_gpu::{Draw, DrawLists, SceneGpu, SceneInputs};
pub use settings_check::{check_device_limits, check_render_settings};
pub use stereo::{
    declare_pair as declare_stereo_pair, default_convergence_m,
    default_path as default_stereo_path, eye_scene, multiview_blocker, pack as stereo_pack,
    prepare_pair as prepare_stereo_pair, profile_stereo, render_stereo, StereoOutput, StereoPath,
    StereoProfile, StereoRenderers, StereoSettings, PROFILE_ROUND_FRAMES,
};

use crate::eval::HdrImage;
use crate::graph::{Access, GraphError, ImageHandle, RenderGraph};
use crate::light::{area::frame_lights, shadow_views, PointShadow, ShadowSettings};
use crate::post::{ToneMap, TonemapPass};
use crate::scene::{Light, Scene};
use crate::vk::{vk, Buffer, Context, ImageDesc, PassTiming, Sampler, VkError};
use bytemuck::Zeroable;
use deferred_direct::DeferredDirectPass;
use gbuffer::{GbufferFeatures, GbufferPass};
use glam::Vec3;
use gpu::*;
use light_map::LightMapPass;
use shadow_depth::ShadowDepthPass;

use frame::jittered;
use preflight::{
    check_frame_memory, check_voxel_memory, frame_subject, readback_descs, FRAME_FLAGS,
};

const GBUFFER_COLOR: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
const HDR: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Errors of building or running a frame.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error("the scene has {0} lights (each area light counts its samples); voxgi renders at most {MAX_LIGHTS}: remove some or lower --area-samples / the lights' `samples`")]
    TooManyLights(usize),
    #[error("the scene's lights need {0} shadow-map views; at most {MAX_SHADOW_VIEWS} fit (a point light takes 6, or 2 with paraboloid shadows, an area light 1 per sample, a directional light 1 plus its cascades): remove some point lights, use --point-shadows paraboloid, lower --area-samples / the lights' `samples` or --shadow-cascades")]
    TooManyShadowViews(usize),
    /// A settings value out of its range ([`crate::limits`]), named by its flag.
    #[error(transparent)]
    Settings(#[from] crate::limits::LimitError),
    #[error("the scene has no geometry to render: add an object")]
    EmptyScene,
    #[error("SAO (--sao, or `sao = true` in the scene's [gi] table) darkens only indirect light, and --gi none has none: choose a --gi method (hemisphere, pathtrace, vpl, ssgi) or leave out --sao (--sao off turns the scene's off)")]
    SaoWithoutGi,
    #[error(transparent)]
    Voxel(#[from] crate::voxel::gpu::GpuVoxelError),
    /// A frame size or voxel grid that does not fit the device, found before allocating.
    #[error(transparent)]
    OutOfDeviceMemory(memory::MemoryError),
    /// A one-frame stereo renderer was asked for where it cannot run (the reason).
    #[error("one-frame stereo cannot render this: {0}; use --stereo-path two-pass")]
    MultiviewUnavailable(String),
    /// An orthographic camera (`--projection orthographic`, the scene's `[camera]
    /// projection`, the viewer's toggle) with a feature built for a pinhole camera.
    #[error("{what} cannot render with an orthographic camera: {why}. Use --projection perspective (or `projection = \"perspective\"` in the scene's [camera] table), or {instead}")]
    Orthographic {
        what: &'static str,
        why: &'static str,
        instead: &'static str,
    },
}

/// What a frame renders.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Scene time (animation), seconds.
    pub time_s: f32,
    pub shadow: ShadowSettings,
    pub tonemap: ToneMap,
    /// Voxelize the scene with these settings, even if nothing needs voxels. `None`: voxelize
    /// only what needs voxels (a GI method, the emitters' or the environment's direct light,
    /// a voxel debug view), with the scene's `[voxel]` settings ([`Scene::voxel_settings`]).
    pub voxels: Option<crate::voxel::gpu::VoxelSettings>,
    /// Indirect light (method `None`: direct light only).
    pub gi: crate::gi::GiSettings,
    /// Show a voxel debug view instead of the lit image (voxelizes with the scene's
    /// `[voxel]` settings when `voxels` is `None`).
    pub debug: Option<crate::voxel::debug_view::DebugSettings>,
    /// Post-processing around tone mapping (TAA, …); off by default.
    pub post: crate::post::PostSettings,
    /// How the camera view draws surfaces with d < 1 (only in scenes that have them).
    pub transparency: crate::scene::Transparency,
    /// Capacity of the transparency node buffer, in nodes per pixel on average
    /// ([`crate::limits::OIT_NODES_PER_PIXEL`]).
    pub oit_nodes_per_pixel: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            time_s: 0.0,
            shadow: ShadowSettings::default(),
            tonemap: ToneMap::default(),
            voxels: None,
            gi: crate::gi::GiSettings::default(),
            debug: None,
            post: Default::default(),
            transparency: Default::default(),
            oit_nodes_per_pixel: oit::DEFAULT_NODES_PER_PIXEL,
        }
    }
}

/// The images a declared frame produces.
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    /// Linear radiance, RGBA32F.
    pub radiance: ImageHandle,
    /// Tone-mapped, sRGB-encoded values in RGBA8 UNORM.
    pub ldr: ImageHandle,
}

/// A scene on the GPU with the passes of its frame.
pub struct Renderer {
    pub settings: RenderSettings,
    scene: SceneGpu,
    readback_hdr: Buffer,
    readback_ldr: Buffer,
    /// Nearest-neighbour sampler of the G-buffer, shadow maps and radiance. Held to keep it
    /// alive: the passes were given its raw handle.
    #[allow(dead_code)]
    sampler: Sampler,
    shadow_depth: ShadowDepthPass,
    gbuffer: GbufferPass,
    deferred: DeferredDirectPass,
    /// The emitters' and the environment's direct light, where no GI method brings it.
    direct_emitters: Option<direct_emitters::DirectEmittersPass>,
    tonemap: TonemapPass,
    post: crate::post::PostPasses,
    has_phong: bool,
    /// The lights' own shadow views (the light maps have one layer each).
    shadow_view_count: u32,
    /// Shadow-array layers kept for the directional lights' cascades, after the lights' own
    /// views: the cascade count × the directional lights (a frame may use fewer).
    cascade_view_capacity: u32,
    frame_data: GpuFrame,
    /// The scene's pre-exposure of half-float radiance, fixed when the renderer is made (the
    /// voxelizers scale their emission with the same one).
    pre_exposure: crate::scene::PreExposure,
    /// The un-jittered view-projection of the last frame written (motion vectors only).
    prev_view_proj: Option<glam::Mat4>,
    voxels: Option<crate::voxel::frame::VoxelFrame>,
    /// Indirect-light passes and the light-map pass (for the voxel methods), when a GI method
    /// is on.
    gi: Option<(crate::gi::GiPasses, Option<LightMapPass>)>,
    voxel_debug: Option<crate::voxel::debug_view::VoxelDebugPass>,
    atlas_view: Option<crate::voxel::atlas_view::AtlasViewPass>,
    gbuffer_view: Option<gbuffer_view::GbufferViewPass>,
    /// The transparency lists, in scenes with d < 1 materials and `--transparency oit`.
    oit: Option<oit::OitPasses>,
    shadow_texels: Option<shadow_texels::ShadowTexelsPass>,
    /// What `--shadow-resolution auto` picked, when it was asked for.
    auto_shadow: Option<shadow_texels::AutoShadowResolution>,
    /// One-pass stereo: both eyes in one frame (`render/stereo.rs`); `frame_data`,
    /// `readback_*` and `post` are then the left eye's.
    stereo: Option<stereo::OnePass>,
    /// Per object, whether it was dynamic (or animated) when the renderer was made: only
    /// those move in the voxels.
    moving: Vec<bool>,
}

impl Renderer {
    /// What `--shadow-resolution auto` picked for this renderer (`None`: a fixed resolution).
    pub fn auto_shadow_resolution(&self) -> Option<shadow_texels::AutoShadowResolution> {
        self.auto_shadow
    }

    /// Whether moving object `object` (changing its transform in the scene given to
    /// [`Self::prepare`]) is drawn and voxelized where it goes: it was dynamic when the
    /// renderer was made, or nothing of the renderer depends on where static objects are
    /// (no voxels). Otherwise the object must be marked dynamic and a new renderer made (the
    /// static grid holds it where it was).
    pub fn can_move(&self, object: usize) -> bool {
        self.voxels.is_none() || self.moving.get(object).copied().unwrap_or(false)
    }

    /// Frames the indirect light has accumulated since the last reset (`None`: GI off).
    /// The caches of the light-space passes, by name (`shadow map V` per layer, `light
    /// maps`, `direct radiance volume`): how often each rendered and was reused (empty while
    /// `shadow.cache` is off).
    pub fn cache_counts(&self) -> Vec<(String, (u64, u64))> {
        let layers = self.shadow_view_count + self.cascade_view_capacity;
        let light_map = self.gi.as_ref().and_then(|(_, lm)| lm.as_ref());
        let light_map = light_map.and_then(|lm| lm.cache());
        let volume = self.gi.as_ref().and_then(|(gi, _)| gi.world_cache());
        self.shadow_depth
            .caches(layers)
            .iter()
            .chain(light_map)
            .chain(volume)
            .map(|c| (c.name().to_owned(), c.counts()))
            .collect()
    }

    /// The size of the frame's tone-mapped image: the frame's, or TAA upsampling's
    /// (`PostSettings::upsample_to`; the viewer's dynamic resolution) where larger.
    pub fn output_size(&self) -> (u32, u32) {
        self.post
            .upsampled()
            .unwrap_or((self.settings.width, self.settings.height))
    }

    pub fn gi_accumulated_frames(&self) -> Option<u32> {
        self.gi.as_ref().map(|(gi, _)| gi.accumulated_frames())
    }

    /// Number of culled camera draws and total draws (for statistics and tests).
    pub fn camera_draws(&self) -> (usize, usize) {
        let visible = self.scene.draws.read().map(|d| d.camera.len()).unwrap_or(0);
        (visible, self.scene.all_draws.len())
    }

    /// The transparency lists' counters of the last completed frame (`None`: no lists).
    pub fn oit_stats(&self) -> Option<OitStats> {
        self.oit.as_ref().map(oit::OitPasses::stats)
    }

    pub fn shadow_view_count(&self) -> u32 {
        self.shadow_view_count
    }

    pub fn has_phong(&self) -> bool {
        self.has_phong
    }

    /// Linear radiance of the last completed frame.
    pub fn hdr_image(&self) -> HdrImage {
        hdr_from(
            &self.readback_hdr,
            (self.settings.width, self.settings.height),
        )
    }

    /// Tone-mapped sRGB RGBA8 pixels of the last completed frame.
    pub fn ldr_pixels(&self) -> Vec<u8> {
        ldr_from(
            &self.readback_ldr,
            (self.settings.width, self.settings.height),
        )
    }

    /// GPU times of the one-time passes the renderer submitted outside its frame graph
    /// (atlas building, static voxelization), in order.
    pub fn setup_timings(&self) -> Vec<PassTiming> {
        self.voxels
            .as_ref()
            .map(|v| v.setup_timings().to_vec())
            .unwrap_or_default()
    }

    /// What the debug view shows and measured in `value` (its value image), for the CLI.
    pub fn debug_description(&self, value: &HdrImage) -> Option<String> {
        if let Some(pass) = &self.gbuffer_view {
            return Some(pass.describe(value));
        }
        if self.shadow_texels.is_some() {
            return Some(shadow_texels::describe(value));
        }
        match (&self.atlas_view, &self.settings.debug) {
            (Some(pass), _) => Some(pass.describe(value)),
            (None, Some(d)) => Some(crate::voxel::debug_view::describe(d, value)),
            _ => None,
        }
    }
}

/// The linear radiance in a read-back buffer of a `w`×`h` frame (black if unmapped).
fn hdr_from(buffer: &Buffer, (w, h): (u32, u32)) -> HdrImage {
    let data: Vec<[f32; 3]> = buffer
        .mapped()
        .map(|m| {
            bytemuck::cast_slice::<u8, [f32; 4]>(&m[..(w * h * 16) as usize])
                .iter()
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        })
        .unwrap_or_else(|| vec![[0.0; 3]; (w * h) as usize]);
    HdrImage {
        width: w,
        height: h,
        data,
    }
}

/// The tone-mapped sRGB RGBA8 pixels in a read-back buffer of a `w`×`h` frame.
fn ldr_from(buffer: &Buffer, (w, h): (u32, u32)) -> Vec<u8> {
    let n = (w * h * 4) as usize;
    buffer.mapped().map(|m| m[..n].to_vec()).unwrap_or_default()
}
