//! Indirect light on the voxel ray test (Thiedemann 2010 ch. 6): the assembly of the GI passes.
//! Each method is one file in `method/`, its [`MethodSpec`], which says what the method needs
//! and builds its passes; the registry there lists the methods once. Each pass (or pass
//! family) lives in the file named after its shader: `gi_hemisphere`
//! (one bounce, radiance from reflective light maps), `gi_radiance_volume` (one bounce,
//! radiance from a direct-radiance volume), `gi_pathtrace` (B bounces, accumulated), then
//! `gi_filter` (geometry-aware filter), `sao` (ambient obscurance, optional) and
//! `gi_composite` (direct + indirect); `gi_common`
//! holds what the ray passes share (push constants, common bindings). The settings are plain
//! data in [`crate::scene`] (re-exported here).

pub mod emitters;
pub mod gi_common;
mod gi_composite;
mod gi_filter;
mod gi_hemisphere;
mod gi_pathtrace;
mod gi_radiance_volume;
mod gi_svgf;
mod gi_temporal;
mod gi_vpl_emit;
mod method;
mod sao;
pub mod ssgi;
pub mod ssgi_brdf_lut;
pub mod ssgi_reflect;
pub mod vpl;

pub use crate::scene::{
    Bounces, GiFilterKind, GiSettings, RadianceSource, SaoSettings, SsgiMips, SsgiResolution,
    SsgiSettings, SsrRays,
};
pub use gi_common::GpuGiPush;
pub use gi_temporal::TemporalView;
pub use method::{EmitterReach, GiMethod, LayerIndirect, MethodSpec, Refusal};
pub use sao::GpuSaoPush;

use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{vk, Buffer, Context, ImageDesc, VkError};
use crate::voxel::attributes::{TriangleAttributeVolumes, ValueVolumes};
use crate::voxel::ray_mask::RayMaskLut;
use crate::voxel::VoxelGrid;
use gi_common::GiShared;
use gi_composite::GiComposite;
use gi_filter::GiFilter;
use gi_svgf::GiSvgf;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

/// The G-buffer and light inputs of the GI passes.
#[derive(Clone, Copy, Debug)]
pub struct GiInputs {
    pub frame: BufferHandle,
    pub albedo: ImageHandle,
    pub normal: ImageHandle,
    pub depth: ImageHandle,
    pub direct: ImageHandle,
    /// The voxel grid and the reflective light maps. Screen-space GI has neither and never
    /// reads them: the renderer fills them with the depth and direct images, as the passes
    /// fill a shader's unread bindings ([`GiMethod::needs_voxels`]).
    pub voxels: ImageHandle,
    pub rlm_radiance: ImageHandle,
    pub rlm_position: ImageHandle,
    pub rlm_normal: ImageHandle,
    pub shadow_map: ImageHandle,
    /// The G-buffer's motion vectors, in scenes with moving objects.
    pub motion: Option<ImageHandle>,
    /// The G-buffer's specular image, present when the scene has Phong materials.
    pub specular: Option<ImageHandle>,
    /// The scene's materials (`GpuMaterial`), for glossy senders in the light maps.
    pub materials: BufferHandle,
    /// Their GGX parameters (`GpuMaterialPbr`), for GGX senders in the light maps.
    pub materials_pbr: BufferHandle,
    /// The environment map, in scenes lit by one (binding 15 of the ray passes), and the
    /// bilinear, repeating sampler it is read with.
    pub environment_map: Option<ImageHandle>,
    /// The map's importance-sampling tables (binding 16 of the path tracer), with it.
    pub environment_cdf: Option<BufferHandle>,
    pub environment_sampler: vk::Sampler,
    pub width: u32,
    pub height: u32,
}

/// What the GI passes are built for.
#[derive(Clone, Copy)]
pub struct GiTarget<'a> {
    pub scene: &'a Scene,
    /// Views rendered per frame: 1, or 2 for a one-frame stereo frame (per-eye histories).
    pub eyes: u32,
    pub time_s: f32,
    /// The voxel grid the frame voxelizes.
    pub grid: &'a VoxelGrid,
    /// Of the shadow maps, whose views the light maps share.
    pub shadow_resolution: u32,
    /// Frame width and height.
    pub size: (u32, u32),
    /// The scene has Phong materials (the G-buffer has a specular image).
    pub has_phong: bool,
    /// The G-buffer has motion vectors (scenes with moving objects).
    pub motion: bool,
    /// Temporal accumulation ([`GiPasses::temporal_on`]): the ray passes advance their
    /// sample pattern every frame.
    pub temporal: bool,
    /// The atlas voxelizer writes the attribute volumes of the objects it voxelizes
    /// ([`crate::voxel::frame::VoxelFrame::enable_attribute_volumes`]); the triangle
    /// attribute pass covers only the others.
    pub atlas_attributes: bool,
    /// `shadow.cache`: view-independent volumes (the direct-radiance volume) are kept while
    /// the lights and the objects stay; off, they are computed every frame.
    pub cache: bool,
}

/// One GI method's indirect-light passes: what a method module implements.
trait GiMethodPasses {
    /// The validity of the method's cached view-independent volumes (with `shadow.cache`):
    /// [`GiPasses`] validates it before each frame with a key that every change of the lights
    /// or the objects advances, and the method's passes that write them declare it
    /// (`.cached`). `None`: the method keeps no such volume.
    fn world_cache(&self) -> Option<&Arc<crate::graph::Cache>> {
        None
    }

    /// Declares the method's view-independent passes (the VPLs, the radiance volume), once
    /// per frame, before [`GiMethodPasses::add_passes`]: a one-frame stereo frame shares their
    /// results between the eyes ([`GiShared::world`]). Screen-space methods have none.
    fn add_world_passes(
        &self,
        _g: &mut RenderGraph,
        _inp: &GiInputs,
        _shared: &GiShared,
    ) -> MethodWorld {
        MethodWorld::default()
    }
    /// Declares the method's passes of one eye (`shared.eye`); returns the image the filter and the composite read
    /// (irradiance at Lambert pixels, indirect radiance at Phong and GGX pixels), and what the method
    /// draws over the composite, if anything.
    fn add_passes(&self, g: &mut RenderGraph, inp: &GiInputs, shared: &GiShared) -> GiOutput;
    /// The scene's lights or emitters may have changed (`Renderer::prepare`): a method that
    /// keeps a table built from them on the CPU rebuilds it.
    fn update_scene(&mut self, _scene: &crate::scene::Scene, _t_s: f32) {}
    /// Writes frame slot `slot`'s copy of such a table (after the slot's fence).
    fn write_slot(&mut self, _slot: usize) {}
    /// The parameters of the rays transparent layers trace, when they are the method's own
    /// rather than the ray passes' [`GpuGiPush`] (the VPL gather's).
    fn layer_params(&self) -> Option<LayerParams> {
        None
    }
}

/// The parameters of transparent layers' indirect light, as `oit_gather`'s parameter buffer
/// holds them ([`GiPasses::transparent_indirect`]).
#[derive(Clone, Copy, Debug)]
pub enum LayerParams {
    /// The ray passes' push constants (the path tracer's and the hemisphere method's rays).
    Rays(GpuGiPush),
    /// The VPL gather's push constants.
    Vpls(vpl::GpuVplGatherPush),
}

impl LayerParams {
    /// The buffer's contents.
    pub fn bytes(&self) -> &[u8] {
        match self {
            LayerParams::Rays(p) => bytemuck::bytes_of(p),
            LayerParams::Vpls(p) => bytemuck::bytes_of(p),
        }
    }
}

/// What a method's view-independent passes produced in a frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct MethodWorld {
    /// An image (the radiance volume).
    pub image: Option<ImageHandle>,
    /// A buffer (the VPLs).
    pub buffer: Option<BufferHandle>,
}

/// The frame's view-independent GI resources, declared by the first eye's
/// [`GiPasses::add_eye_passes`] and reused by the second.
#[derive(Clone, Copy, Debug)]
pub struct GiWorld {
    lut: BufferHandle,
    attributes: Option<crate::voxel::attributes::AttributeHandles>,
    method: MethodWorld,
}

impl GiWorld {
    /// What a pass outside the method that traces its rays reads: `oit_gather`
    /// ([`GiPasses::transparent_indirect`]).
    pub fn ray_inputs(&self) -> LayerRayInputs {
        LayerRayInputs {
            lut: self.lut,
            attributes: self.attributes,
            radiance_volume: self.method.image,
            vpls: self.method.buffer,
        }
    }
}

/// The frame's resources the method's rays read at their hits, for `oit_gather`.
#[derive(Clone, Copy, Debug)]
pub struct LayerRayInputs {
    /// The ray-mask table.
    pub lut: BufferHandle,
    /// The attribute volumes, when the method reads them.
    pub attributes: Option<crate::voxel::attributes::AttributeHandles>,
    /// The direct-radiance volume (`--gi-radiance volume`).
    pub radiance_volume: Option<ImageHandle>,
    /// The frame's VPLs (`--gi vpl`).
    pub vpls: Option<BufferHandle>,
}

/// What a GI method's passes produce.
struct GiOutput {
    /// The unfiltered indirect light.
    indirect: ImageHandle,
    /// Declares a debug view drawn into the lit image (direct + filtered indirect) after the
    /// composite, e.g. the VPLs as dots.
    overlay: Option<Overlay>,
}

type Overlay = Box<dyn FnOnce(&mut RenderGraph, ImageHandle)>;

impl From<ImageHandle> for GiOutput {
    fn from(indirect: ImageHandle) -> Self {
        Self {
            indirect,
            overlay: None,
        }
    }
}

/// Pipelines and constant data of the GI passes.
pub struct GiPasses {
    pub settings: GiSettings,
    /// The chosen method's passes.
    method: Box<dyn GiMethodPasses>,
    /// The albedo and normal volumes, for the methods that read them.
    attributes: Option<TriangleAttributeVolumes>,
    filter: Filter,
    /// Temporal accumulation between the method and the filter (`gi.temporal`, for the
    /// methods whose spec has `temporal`).
    temporal: Option<gi_temporal::GiTemporal>,
    /// Frames recorded since the passes were made: the sample pattern's index under
    /// `gi.temporal`.
    sample_index: Arc<AtomicU32>,
    /// Ambient obscurance multiplied into the indirect light, when on.
    sao: Option<sao::Sao>,
    composite: GiComposite,
    accumulation: Accumulation,
    /// Advanced by every change of the lights or the objects: the key of the method's cached
    /// view-independent volumes ([`GiMethodPasses::world_cache`]).
    world_generation: AtomicU64,
    lut: Buffer,
    sampler: crate::vk::Sampler,
    push: GpuGiPush,
}

impl GiPasses {
    /// The frame-sized images [`GiPasses::new`] creates for `settings` at `size` (the
    /// method's history; with SSR on a `glossy` scene, the reflection history too), for the
    /// renderer's memory check before anything is allocated.
    pub fn frame_image_descs(
        settings: &GiSettings,
        size: (u32, u32),
        glossy: bool,
    ) -> Vec<ImageDesc> {
        // Per stereo eye: see `GiTarget::eyes` (the renderer repeats this list per eye).
        let mut images = (settings.method.spec().history)(settings, size, glossy);
        if Self::temporal_on(settings) {
            images.extend(gi_temporal::GiTemporal::history_descs(size));
        }
        images
    }

    /// Whether `settings` accumulate the indirect light over frames with reprojection.
    pub fn temporal_on(settings: &GiSettings) -> bool {
        settings.temporal && settings.method.spec().temporal
    }

    /// Creates the pipelines (and the method's volumes and history) for `target`.
    pub fn new(
        ctx: &Context,
        settings: GiSettings,
        target: &GiTarget<'_>,
    ) -> Result<Self, VkError> {
        let method = (settings.method.spec().build)(ctx, &settings, target)?;
        // Objects the atlas voxelizer handles get their attributes from its points.
        let attributes = Self::needs_attribute_volumes(&settings, target.scene)
            .then(|| {
                let t = target;
                TriangleAttributeVolumes::new(
                    ctx,
                    t.scene,
                    t.time_s,
                    t.grid,
                    t.atlas_attributes,
                    Self::value_volumes(&settings, t.scene),
                )
            })
            .transpose()?;
        Ok(Self {
            settings,
            method,
            attributes,
            filter: Filter::new(
                ctx,
                settings.filter,
                target.has_phong || target.scene.has_ggx(),
                Self::temporal_on(&settings),
            )?,
            temporal: Self::temporal_on(&settings)
                .then(|| {
                    gi_temporal::GiTemporal::new(
                        ctx,
                        target.motion,
                        target.eyes,
                        settings.temporal_frames,
                    )
                })
                .transpose()?,
            sample_index: Arc::default(),
            sao: settings
                .sao
                .map(|s| {
                    let fov = target.scene.camera.fov_y_deg;
                    sao::Sao::new(ctx, GpuSaoPush::new(&s, fov, target.size, settings.seed))
                })
                .transpose()?,
            composite: GiComposite::new(
                ctx,
                target.has_phong,
                (settings.sao.is_some(), settings.sao.is_some_and(|s| s.view)),
                target.scene.has_ggx(),
            )?,
            accumulation: Accumulation::default(),
            world_generation: AtomicU64::new(0),
            lut: ctx.upload_buffer(
                "ray mask lut",
                &RayMaskLut::new().to_gpu_bytes(),
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?,
            sampler: ctx.create_sampler(vk::Filter::NEAREST, false)?,
            push: GpuGiPush::new(&settings, target),
        })
    }

    /// Prepares frame slot `slot` for scene time `t_s` (after the slot's fence): rewrites the
    /// attribute volumes and restarts accumulation when moving objects moved (shortens the
    /// history under temporal accumulation).
    pub fn update_dynamic(&mut self, t_s: f32, slot: usize) {
        self.method.write_slot(slot);
        if self
            .attributes
            .as_mut()
            .is_some_and(|a| a.update(t_s, slot))
        {
            self.objects_moved();
        }
    }

    /// Takes the dynamic objects' transforms from `scene` for the attribute volumes (see
    /// `TriangleAttributeVolumes::follow_objects`).
    pub fn follow_objects(&mut self, scene: &crate::scene::Scene) {
        if let Some(a) = &mut self.attributes {
            a.follow_objects(scene);
        }
    }

    /// Follows the scene's lights and emitters at `t_s` (`Renderer::prepare`; see
    /// [`GiMethodPasses::update_scene`]).
    pub fn update_scene(&mut self, scene: &crate::scene::Scene, t_s: f32) {
        self.method.update_scene(scene, t_s);
    }

    /// Counts a new frame, to be recorded in frame slot `slot` (call before recording it):
    /// the path tracer accumulates into it, and the passes that run once per restart run in
    /// it only if it is the first.
    pub fn advance(&self, slot: usize) {
        self.accumulation.advance();
        if let Some(c) = self.method.world_cache() {
            c.validate(slot, self.world_generation.load(Ordering::SeqCst));
        }
        self.sample_index.fetch_add(1, Ordering::SeqCst);
        if let Some(t) = &self.temporal {
            t.advance(slot);
        }
    }

    /// The lights changed (moved, edited, switched; the environment, pre-exposure or shadow
    /// parameters): the view-independent volumes are computed again and accumulation
    /// restarts.
    pub fn lights_changed(&self) {
        self.world_generation.fetch_add(1, Ordering::SeqCst);
        self.reset();
    }

    /// Restarts accumulation (lights or scene changed; without temporal accumulation, the
    /// camera too). The view-independent volumes stay: they do not depend on the camera.
    pub fn reset(&self) {
        self.accumulation.reset();
        if let Some(t) = &self.temporal {
            t.reset();
        }
    }

    /// Whether the indirect light is accumulated with reprojection: a camera move keeps it
    /// ([`Self::set_views`]), only a change of lights or scene calls for [`Self::reset`].
    pub fn reprojects(&self) -> bool {
        self.temporal.is_some()
    }

    /// The cameras (one per eye) of the next frame to be recorded, for the reprojection.
    pub fn set_views(&self, views: &[TemporalView]) {
        if let Some(t) = &self.temporal {
            t.set_views(views);
        }
    }

    /// Objects moved since the last frame: under temporal accumulation the next frame keeps
    /// a short history instead of starting over.
    pub fn objects_moved(&self) {
        self.world_generation.fetch_add(1, Ordering::SeqCst);
        match &self.temporal {
            Some(t) => t.objects_moved(),
            None => self.reset(),
        }
    }

    /// The validity of the method's cached view-independent volume (the direct-radiance
    /// volume with `shadow.cache`), if it keeps one.
    pub fn world_cache(&self) -> Option<&Arc<crate::graph::Cache>> {
        self.method.world_cache()
    }

    /// Frames accumulated so far.
    pub fn accumulated_frames(&self) -> u32 {
        self.accumulation.frames.load(Ordering::SeqCst)
    }

    /// The emission and material volumes the chosen method reads with the albedo and normal
    /// volumes, and the PBR maps they sample (the material volume where the method's hits
    /// sample the lobes, [`MethodSpec::material_volume`]).
    pub fn value_volumes(settings: &GiSettings, scene: &Scene) -> ValueVolumes {
        let lobes = (settings.method.spec().material_volume)(settings);
        ValueVolumes::new(scene, lobes, settings.voxel_map_texels)
    }

    /// The ray parameters (rays, bounces, offsets, the grid; the VPL gather's for VPLs)
    /// transparent layers trace their indirect light with, and which rays, when the method
    /// gives them any ([`MethodSpec::transparent_indirect`]) and the attribute volumes those
    /// rays read exist ([`LayerIndirect::reads_attribute_volumes`]).
    pub fn transparent_indirect(&self, scene: &Scene) -> Option<(LayerParams, LayerIndirect)> {
        let kind = (self.settings.method.spec().transparent_indirect)(&self.settings)?;
        let params = self
            .method
            .layer_params()
            .unwrap_or(LayerParams::Rays(self.push));
        (!kind.reads_attribute_volumes(scene) || self.attributes.is_some())
            .then_some((params, kind))
    }

    /// Whether the chosen method reads the albedo and normal volumes (and with them, in
    /// scenes with emitters, the emission volume).
    pub fn needs_attribute_volumes(settings: &GiSettings, scene: &Scene) -> bool {
        (settings.method.spec().attribute_volumes)(settings, scene)
    }

    /// Declares the indirect-light, filter and composite passes; returns the total radiance.
    /// `voxels` declares the atlas part of the attribute volumes when it has one
    /// ([`GiTarget::atlas_attributes`]).
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        inp: &GiInputs,
        voxels: Option<&crate::voxel::frame::VoxelFrame>,
    ) -> ImageHandle {
        self.add_eye_passes(g, inp, voxels, 0, &mut None)
    }

    /// [`GiPasses::add_passes`] for eye `eye` of a one-frame stereo frame: the first call
    /// declares the view-independent passes (attribute volumes, the method's world passes)
    /// and leaves their handles in `world`; a later call with the same `world` reuses them
    /// and declares only the eye's screen-space passes.
    pub fn add_eye_passes(
        &self,
        g: &mut RenderGraph,
        inp: &GiInputs,
        voxels: Option<&crate::voxel::frame::VoxelFrame>,
        eye: u32,
        world: &mut Option<GiWorld>,
    ) -> ImageHandle {
        let mut shared = GiShared {
            lut: BufferHandle(crate::graph::ResourceId(0)),
            sampler: self.sampler.raw,
            push: self.push,
            frames: self.accumulation.frames.clone(),
            sample_index: self.temporal.is_some().then(|| self.sample_index.clone()),
            attributes: None,
            eye,
            world: MethodWorld::default(),
        };
        let w = match *world {
            Some(w) => w,
            None => {
                shared.lut = g.import_buffer(&self.lut, Access::StorageRead(Shader::Compute));
                // The first frame writes the volumes; later frames keep them until something
                // moves.
                shared.attributes = self.attributes.as_ref().map(|a| {
                    a.add_passes(g, |g: &mut RenderGraph, volumes| {
                        if let Some(v) = voxels {
                            v.add_attribute_passes(g, volumes);
                        }
                    })
                });
                let w = GiWorld {
                    lut: shared.lut,
                    attributes: shared.attributes,
                    method: self.method.add_world_passes(g, inp, &shared),
                };
                *world = Some(w);
                w
            }
        };
        shared.lut = w.lut;
        shared.attributes = w.attributes;
        shared.world = w.method;
        let GiOutput { indirect, overlay } = self.method.add_passes(g, inp, &shared);
        let (indirect, moments) = match &self.temporal {
            Some(t) => {
                let (accumulated, moments) = t.add_passes(g, inp, self.sampler.raw, indirect, eye);
                (accumulated, Some(moments))
            }
            None => (indirect, None),
        };
        let s = &self.settings;
        let tile = (s.method.spec().filter_tile)(s);
        let filtered = match &self.filter {
            Filter::Geometric(f) => f.add_passes(
                g,
                inp,
                self.sampler.raw,
                (s.filter_radius, s.filter_passes, tile),
                indirect,
                moments,
            ),
            Filter::Svgf(f) => f.add_passes(
                g,
                inp,
                self.sampler.raw,
                (s.filter_radius > 0, s.filter_passes, tile),
                indirect,
                moments,
            ),
        };
        let ao = self
            .sao
            .as_ref()
            .map(|s| s.add_passes(g, inp, self.sampler.raw));
        let total = self
            .composite
            .add_pass(g, inp, self.sampler.raw, filtered, ao);
        if let Some(overlay) = overlay {
            overlay(g, total);
        }
        total
    }
}

/// The spatial filter of the indirect light (`gi.filter`).
enum Filter {
    Geometric(GiFilter),
    Svgf(GiSvgf),
}

impl Filter {
    fn new(
        ctx: &Context,
        kind: GiFilterKind,
        glossy: bool,
        temporal: bool,
    ) -> Result<Self, VkError> {
        Ok(match kind {
            GiFilterKind::Geometric => Self::Geometric(GiFilter::new(ctx, glossy, temporal)?),
            GiFilterKind::Svgf => Self::Svgf(GiSvgf::new(ctx, glossy, temporal)?),
        })
    }
}

/// Frames accumulated since the last restart.
#[derive(Default)]
struct Accumulation {
    /// Counting the frame being recorded.
    frames: Arc<AtomicU32>,
}

impl Accumulation {
    fn advance(&self) {
        self.frames.fetch_add(1, Ordering::SeqCst);
    }

    /// The next frame recorded, in any slot, is a first frame.
    fn reset(&self) {
        self.frames.store(0, Ordering::SeqCst);
    }
}
