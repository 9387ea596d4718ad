//! Indirect light on the voxel ray test (thesis ch. 6). `hemisphere`: one bounce by
//! hemisphere sampling with radiance from reflective light maps, filtered by the
//! geometry-aware filter and added to the direct light.

pub mod vpl;

use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::scene::Scene;
use crate::vk::{vk, Buffer, ComputePipeline, Context, Image, ImageDesc, VkError};
use crate::voxel::attributes::TriangleAttributeVolumes;
use crate::voxel::ray_mask::RayMaskLut;
use crate::voxel::VoxelGrid;
use bytemuck::{Pod, Zeroable};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// A GI method of the speed/accuracy ladder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum GiMethod {
    /// No indirect light.
    #[default]
    None,
    /// One bounce: N rays per pixel, radiance at hits from reflective light maps (§6.2).
    Hemisphere,
    /// B bounces with albedo and normal from voxel volumes and direct light at every hit from
    /// the shadow maps, accumulated over frames (§6.3).
    Pathtrace,
    /// Virtual point lights from the reflective light maps, B bounces, interleaved sampling
    /// with voxel visibility and the geometry-aware filter (Ch. 7).
    Vpl,
}

/// Parameters of the indirect-light passes (all exposed on the command line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GiSettings {
    pub method: GiMethod,
    /// Rays per pixel.
    pub rays: u32,
    /// Ray length in meters; `None`: the scene's diagonal (unbounded in practice).
    pub radius_m: Option<f32>,
    /// Self-intersection offset along the normal, in voxel diagonals (thesis §4.4, k₁).
    pub normal_offset_voxels: f32,
    /// Self-intersection offset along the ray, k₂ · h / (d·n) in voxel diagonals h, clamped
    /// to `ray_offset_max_voxels` (thesis §4.4).
    pub ray_offset_voxels: f32,
    pub ray_offset_max_voxels: f32,
    /// Light-map hit tolerance, in voxel diagonals (plus the map texel's footprint).
    pub hit_tolerance_voxels: f32,
    pub start_level: u32,
    pub max_iterations: u32,
    /// Reflective light-map resolution per view (the thesis used 256²).
    pub light_map_resolution: u32,
    /// Geometry-aware filter radius in pixels (0: off) and number of h+v passes.
    pub filter_radius: u32,
    pub filter_passes: u32,
    /// Seed of the per-pixel rotation (vary per frame to accumulate).
    pub seed: u32,
    /// Path-tracer bounces: a fixed count, or unbounded by Russian roulette.
    pub bounces: Bounces,
    /// Frames a headless render accumulates (path tracer; the viewer accumulates while still).
    pub accumulate_frames: u32,
    /// Where the hemisphere method reads the radiance at ray hits.
    pub radiance_source: RadianceSource,
    /// The VPL method's parameters.
    pub vpl: vpl::VplSettings,
}

/// How long the path tracer's paths are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bounces {
    /// Exactly this many bounces (1..=[`Bounces::MAX`]): biased low by the light of the
    /// bounces left out.
    Fixed(u32),
    /// [`Bounces::ROULETTE_AFTER`] bounces, then Russian roulette: unbiased but for the
    /// safety cap of [`Bounces::MAX`] bounces (see `glsl/gi_pathtrace.comp` for its bound).
    Unbounded,
}

impl Bounces {
    /// The most bounces a path takes: the largest fixed count and the safety cap of the
    /// unbounded setting (`MAX_PATH_BOUNCES` in `glsl/gi_pathtrace.comp`).
    pub const MAX: u32 = 64;
    /// Bounces an unbounded path always takes before Russian roulette may end it
    /// (`ROULETTE_AFTER` in `glsl/gi_pathtrace.comp`).
    pub const ROULETTE_AFTER: u32 = 3;
    /// The spelling of [`Bounces::Unbounded`] on the command line and in scene files.
    pub const UNBOUNDED_NAME: &'static str = "unbounded";

    /// The push-constant value (`gi.params2.y`): the count, or 0 for unbounded.
    pub fn push_value(self) -> f32 {
        match self {
            Bounces::Fixed(n) => n.clamp(1, Self::MAX) as f32,
            Bounces::Unbounded => 0.0,
        }
    }

    /// What a flag or scene value must be, for error messages.
    pub fn expected() -> String {
        format!(
            "an integer in [1, {}] or \"{}\" (Russian roulette)",
            Self::MAX,
            Self::UNBOUNDED_NAME
        )
    }

    /// A fixed count checked against [1, MAX].
    pub fn fixed(n: i64) -> Option<Bounces> {
        (1..=i64::from(Self::MAX))
            .contains(&n)
            .then_some(Bounces::Fixed(n as u32))
    }
}

impl std::fmt::Display for Bounces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Bounces::Fixed(n) => write!(f, "{n}"),
            Bounces::Unbounded => f.write_str(Self::UNBOUNDED_NAME),
        }
    }
}

/// Parses `--gi-bounces`: a count or `unbounded` (clap names the flag in its error).
impl std::str::FromStr for Bounces {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == Self::UNBOUNDED_NAME {
            return Ok(Bounces::Unbounded);
        }
        s.parse::<i64>()
            .ok()
            .and_then(Bounces::fixed)
            .ok_or_else(|| format!("expected {}", Bounces::expected()))
    }
}

/// Where hemisphere sampling reads the radiance leaving a hit surface (thesis §6.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum RadianceSource {
    /// Reflective light maps rendered per shadow view (radiance, position, normal).
    #[default]
    Maps,
    /// A direct-radiance voxel volume congruent with the bits (diffuse senders).
    Volume,
}

impl Default for GiSettings {
    fn default() -> Self {
        Self {
            method: GiMethod::None,
            rays: 16,
            radius_m: None,
            normal_offset_voxels: 1.0,
            ray_offset_voxels: 0.0,
            ray_offset_max_voxels: 4.0,
            hit_tolerance_voxels: 1.5,
            start_level: 1,
            max_iterations: 1024,
            light_map_resolution: 256,
            filter_radius: 4,
            filter_passes: 2,
            seed: 0,
            bounces: Bounces::Fixed(2),
            accumulate_frames: 1,
            radiance_source: RadianceSource::Maps,
            vpl: vpl::VplSettings::default(),
        }
    }
}

/// Push constants of the GI passes (`glsl/include/gi_common.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuGiPush {
    pub world_to_voxel: [f32; 16],
    pub dims: [i32; 4],
    pub params: [f32; 4],
    pub iparams: [u32; 4],
    pub params2: [f32; 4],
}

crate::push_constants!(GpuGiPush {
    world_to_voxel,
    dims,
    params,
    iparams,
    params2
});

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuFilterPush {
    direction: [i32; 2],
    radius: i32,
    plane_tolerance: f32,
}

crate::push_constants!(GpuFilterPush {
    direction,
    radius,
    plane_tolerance
});

/// The G-buffer and light inputs of the GI passes.
#[derive(Clone, Copy, Debug)]
pub struct GiInputs {
    pub frame: BufferHandle,
    pub albedo: ImageHandle,
    pub normal: ImageHandle,
    pub depth: ImageHandle,
    pub direct: ImageHandle,
    pub voxels: ImageHandle,
    pub rlm_radiance: ImageHandle,
    pub rlm_position: ImageHandle,
    pub rlm_normal: ImageHandle,
    pub shadow_map: ImageHandle,
    /// The G-buffer's specular image, present when the scene has Phong materials.
    pub specular: Option<ImageHandle>,
    /// The scene's materials (`GpuMaterial`), for glossy senders in the light maps.
    pub materials: BufferHandle,
    pub width: u32,
    pub height: u32,
}

/// What the GI passes are built for.
#[derive(Clone, Copy)]
pub struct GiTarget<'a> {
    pub scene: &'a Scene,
    pub time_s: f32,
    /// The voxel grid the frame voxelizes.
    pub grid: &'a VoxelGrid,
    /// Of the shadow maps, whose views the light maps share.
    pub shadow_resolution: u32,
    /// Frame width and height.
    pub size: (u32, u32),
    /// The scene has Phong materials (the G-buffer has a specular image).
    pub has_phong: bool,
    /// The atlas voxelizer writes the attribute volumes of the objects it voxelizes
    /// ([`crate::voxel::gpu::VoxelFrame::enable_attribute_volumes`]); the triangle
    /// attribute pass covers only the others.
    pub atlas_attributes: bool,
}

/// Pipelines and constant data of the GI passes.
pub struct GiPasses {
    pub settings: GiSettings,
    pathtracer: Option<PathTracer>,
    vpl: Option<vpl::VplPasses>,
    /// Frames accumulated since the last reset (path tracer).
    frames: Arc<AtomicU32>,
    hemisphere: ComputePipeline,
    filter: ComputePipeline,
    composite: ComputePipeline,
    lut: Buffer,
    sampler: vk::Sampler,
    push: GpuGiPush,
}

impl GiPasses {
    /// Creates the pipelines (and, for the path tracer, its volumes and history) for `target`.
    pub fn new(
        ctx: &Context,
        settings: GiSettings,
        target: &GiTarget<'_>,
    ) -> Result<Self, VkError> {
        let GiTarget {
            scene,
            time_s,
            grid,
            shadow_resolution,
            has_phong,
            ..
        } = *target;
        let scene_diagonal_m = scene.aabb_at(time_s).extent().length();
        let hemisphere = ctx.compute_pipeline(
            "gi_hemisphere.comp",
            crate::vk::PushLayout::of::<GpuGiPush>(),
            &[(0, u32::from(has_phong))],
        )?;
        let filter = ctx.compute_pipeline(
            "gi_filter.comp",
            crate::vk::PushLayout::of::<GpuFilterPush>(),
            &[],
        )?;
        let composite =
            ctx.compute_pipeline("gi_composite.comp", None, &[(0, u32::from(has_phong))])?;
        let lut = ctx.upload_buffer(
            "ray mask lut",
            &RayMaskLut::new().to_gpu_bytes(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let sampler = ctx.create_sampler(vk::Filter::NEAREST, false)?;
        let ext = grid.extent_voxels();
        let levels = crate::voxel::bits::mip_count(grid.res_x(), grid.res_y());
        let push = GpuGiPush {
            world_to_voxel: grid.world_to_voxel_matrix().to_cols_array(),
            dims: [ext.x as i32, ext.y as i32, ext.z as i32, levels as i32 - 1],
            params: [
                settings.radius_m.unwrap_or(scene_diagonal_m),
                settings.normal_offset_voxels,
                settings.hit_tolerance_voxels,
                grid.voxel_diagonal_m(),
            ],
            iparams: [
                settings.rays,
                settings.start_level,
                settings.max_iterations,
                settings.seed,
            ],
            params2: [
                shadow_resolution as f32 / settings.light_map_resolution.max(1) as f32,
                settings.bounces.push_value(),
                settings.ray_offset_voxels,
                settings.ray_offset_max_voxels,
            ],
        };
        let pathtracer =
            if settings.method != GiMethod::Vpl && Self::needs_attribute_volumes(&settings) {
                Some(PathTracer::new(
                    ctx,
                    target,
                    settings.method == GiMethod::Pathtrace,
                )?)
            } else {
                None
            };
        let vpl = (settings.method == GiMethod::Vpl)
            .then(|| vpl::VplPasses::new(ctx, &settings, target))
            .transpose()?;
        Ok(Self {
            settings,
            pathtracer,
            vpl,
            frames: Arc::new(AtomicU32::new(0)),
            hemisphere,
            filter,
            composite,
            lut,
            sampler,
            push,
        })
    }

    /// Prepares frame slot `slot` for scene time `t_s` (after the slot's fence): rewrites the
    /// attribute volumes and restarts accumulation when moving objects moved.
    pub fn update_dynamic(&mut self, t_s: f32, slot: usize) {
        let moved = self
            .pathtracer
            .as_mut()
            .is_some_and(|pt| pt.update(t_s, slot));
        let vpl_moved = self.vpl.as_mut().is_some_and(|v| v.update(t_s, slot));
        if moved || vpl_moved {
            self.reset();
        }
    }

    /// Counts a new frame (call before recording it): the path tracer accumulates into it.
    pub fn advance(&self) {
        self.frames.fetch_add(1, Ordering::SeqCst);
    }

    /// Restarts accumulation (camera, lights or scene changed).
    pub fn reset(&self) {
        self.frames.store(0, Ordering::SeqCst);
    }

    /// Frames accumulated so far.
    pub fn accumulated_frames(&self) -> u32 {
        self.frames.load(Ordering::SeqCst)
    }

    /// Whether the chosen method reads the albedo and normal volumes.
    pub fn needs_attribute_volumes(settings: &GiSettings) -> bool {
        settings.method == GiMethod::Pathtrace
            || (settings.method == GiMethod::Vpl && settings.vpl.bounces > 1)
            || (settings.method == GiMethod::Hemisphere
                && settings.radiance_source == RadianceSource::Volume)
    }

    /// Declares the indirect-light, filter and composite passes; returns the total radiance.
    /// `voxels` declares the atlas part of the attribute volumes when it has one
    /// ([`GiTarget::atlas_attributes`]).
    pub fn add_passes(
        &self,
        g: &mut RenderGraph,
        inp: &GiInputs,
        voxels: Option<&crate::voxel::gpu::VoxelFrame>,
    ) -> ImageHandle {
        let lut = g.import_buffer(&self.lut, Access::StorageRead(Shader::Compute));
        let attributes = |g: &mut RenderGraph, a, n| {
            if let Some(v) = voxels {
                v.add_attribute_passes(g, a, n);
            }
        };
        let mut vpls = None;
        let irradiance = match (&self.pathtracer, &self.vpl) {
            (_, Some(v)) => {
                let (irradiance, buffer) = v.add_passes(g, inp, (lut, self.sampler), attributes);
                vpls = Some((v, buffer));
                irradiance
            }
            (Some(pt), None) => pt.add_passes(
                g,
                inp,
                lut,
                (self.push, self.sampler),
                self.frames.clone(),
                attributes,
            ),
            (None, None) => self.add_hemisphere(g, inp, lut),
        };
        let total = self.add_filter_and_composite(g, inp, irradiance);
        if let Some((v, buffer)) = vpls {
            v.add_points(g, inp, buffer, total, self.sampler);
        }
        total
    }

    fn add_hemisphere(
        &self,
        g: &mut RenderGraph,
        inp: &GiInputs,
        lut: BufferHandle,
    ) -> ImageHandle {
        let (w, h) = (inp.width, inp.height);
        let sampler = self.sampler;
        let irradiance = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let pipe = self.hemisphere;
        let push = self.push;
        let i = *inp;
        add_ray_pass(
            g,
            "gi_hemisphere",
            pipe,
            &i,
            lut,
            sampler,
            &[(5, i.rlm_radiance), (6, i.rlm_position), (7, i.rlm_normal)],
            (irradiance, Access::StorageWrite(Shader::Compute)),
            Some(i.materials),
            move || push,
        );
        irradiance
    }

    fn add_filter_and_composite(
        &self,
        g: &mut RenderGraph,
        inp: &GiInputs,
        irradiance: ImageHandle,
    ) -> ImageHandle {
        let (w, h) = (inp.width, inp.height);
        let groups = (w.div_ceil(8), h.div_ceil(8));
        let sampler = self.sampler;
        let i = *inp;

        // Geometry-aware filter, horizontal then vertical, `filter_passes` times.
        let mut current = irradiance;
        let passes = if self.settings.filter_radius == 0 {
            0
        } else {
            self.settings.filter_passes
        };
        for p in 0..passes {
            for (axis, dir) in [("h", [1, 0]), ("v", [0, 1])] {
                let out = g.create_image(ImageDesc::new_2d(
                    &format!("filtered irradiance {p}{axis}"),
                    vk::Format::R32G32B32A32_SFLOAT,
                    w,
                    h,
                ));
                let pipe = self.filter;
                let src = current;
                let fp = GpuFilterPush {
                    direction: dir,
                    radius: self.settings.filter_radius as i32,
                    plane_tolerance: 0.02,
                };
                let c = Shader::Compute;
                g.add_pass(&format!("gi_filter[{p}{axis}]"))
                    .pipeline(&pipe)
                    .bind(0, i.frame, Access::StorageRead(c))
                    .bind_sampled(1, i.normal, sampler, c)
                    .bind_sampled(2, i.depth, sampler, c)
                    .bind_sampled(3, src, sampler, c)
                    .bind(4, out, Access::StorageWrite(c))
                    .record(move |ctx| {
                        ctx.bind(&pipe);
                        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&fp));
                        ctx.cmd.dispatch(groups.0, groups.1, 1);
                    });
                current = out;
            }
        }

        let total = g.create_image(ImageDesc::new_2d(
            "radiance (direct + indirect)",
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
        ));
        let pipe = self.composite;
        let indirect = current;
        let c = Shader::Compute;
        // Without Phong materials the shader never reads its specular binding; albedo fills it.
        let specular = i.specular.unwrap_or(i.albedo);
        g.add_pass("gi_composite")
            .pipeline(&pipe)
            .bind_sampled(0, i.direct, sampler, c)
            .bind_sampled(1, i.albedo, sampler, c)
            .bind_sampled(2, indirect, sampler, c)
            .bind(3, total, Access::StorageWrite(c))
            .bind_sampled(4, specular, sampler, c)
            .record(move |ctx| {
                ctx.bind(&pipe);
                ctx.cmd.dispatch(groups.0, groups.1, 1);
            });
        total
    }

    pub fn destroy(self, ctx: &Context) {
        if let Some(pt) = self.pathtracer {
            pt.destroy(ctx);
        }
        if let Some(v) = self.vpl {
            v.destroy(ctx);
        }
        ctx.destroy_compute_pipeline(self.hemisphere);
        ctx.destroy_compute_pipeline(self.filter);
        ctx.destroy_compute_pipeline(self.composite);
        ctx.destroy_buffer(self.lut);
        ctx.destroy_sampler(self.sampler);
    }
}

/// Persistent resources of the volume-based methods: the albedo and normal volumes, plus the
/// path tracer's pipeline and history, or the direct-radiance volume and its hemisphere
/// pipeline.
struct PathTracer {
    pathtrace: Option<ComputePipeline>,
    radiance: Option<RadianceVolume>,
    /// Writes the attributes of the objects the atlas voxelizer does not handle (all of them
    /// without it); `None` when there are none.
    volumes: TriangleAttributeVolumes,
    history: Image,
}

/// The direct-radiance volume (rgba32f, congruent with the bits) and its passes. f32 because
/// f16 cannot hold radiance from lights of 1e-6 to 1e6 W/sr (tests/extremes.rs): 16 bytes per
/// voxel, 33.5 MB at 128³.
struct RadianceVolume {
    volume_pipeline: ComputePipeline,
    hemisphere_pipeline: ComputePipeline,
    image: Image,
}

impl PathTracer {
    fn new(ctx: &Context, target: &GiTarget<'_>, path_trace: bool) -> Result<Self, VkError> {
        let GiTarget {
            scene,
            time_s,
            grid,
            size: (w, h),
            has_phong,
            atlas_attributes,
            ..
        } = *target;
        let pathtrace = path_trace
            .then(|| {
                ctx.compute_pipeline(
                    "gi_pathtrace.comp",
                    crate::vk::PushLayout::of::<GpuGiPush>(),
                    &[(0, u32::from(has_phong))],
                )
            })
            .transpose()?;
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST;
        let resting = Access::Sampled(Shader::Compute).info().layout;
        let zero = vk::ClearColorValue { float32: [0.0; 4] };
        // Objects the atlas voxelizer handles get their attributes from its points.
        let volumes = TriangleAttributeVolumes::new(ctx, scene, time_s, grid, atlas_attributes)?;
        // The history exists for the path tracer only; the radiance volume for the hemisphere
        // method reading it (1x1 placeholder history otherwise, never bound).
        let (hw, hh) = if path_trace { (w, h) } else { (1, 1) };
        let history = ctx.create_image(
            &ImageDesc::new_2d(
                "path tracer history",
                vk::Format::R32G32B32A32_SFLOAT,
                hw,
                hh,
            )
            .with_usage(usage),
        )?;
        ctx.clear_new_image(&history, zero, resting)?;
        let radiance = if path_trace {
            None
        } else {
            Some(RadianceVolume::new(ctx, grid, has_phong)?)
        };
        Ok(Self {
            pathtrace,
            radiance,
            volumes,
            history,
        })
    }

    /// For scenes with moving objects: writes frame slot `slot`'s triangles at `t_s` when they
    /// changed, so that frame rewrites the volumes. Returns whether they changed.
    fn update(&mut self, t_s: f32, slot: usize) -> bool {
        self.volumes.update(t_s, slot)
    }

    fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        lut: BufferHandle,
        (push, sampler): (GpuGiPush, vk::Sampler),
        frames: Arc<AtomicU32>,
        atlas_attributes: impl FnOnce(&mut RenderGraph, ImageHandle, ImageHandle),
    ) -> ImageHandle {
        let read = Access::Sampled(Shader::Compute);
        // The first frame writes the volumes; later frames keep them until something moves.
        let (albedo, normal) = self.volumes.add_passes(g, atlas_attributes);
        let Some(pipe) = self.pathtrace else {
            return match &self.radiance {
                Some(rv) => rv.add_passes(g, i, lut, (albedo, normal), (push, sampler), frames),
                // Unreachable by construction (one of the two exists); no indirect light.
                None => albedo,
            };
        };
        let history = g.import_image(&self.history, read);
        let i = *i;
        add_ray_pass(
            g,
            "gi_pathtrace",
            pipe,
            &i,
            lut,
            sampler,
            &[(5, albedo), (6, normal), (7, i.shadow_map)],
            (history, Access::StorageReadWrite(Shader::Compute)),
            None,
            move || {
                let mut p = push;
                // Frames accumulated before this one (`advance` ran before recording).
                p.iparams[3] = frames.load(Ordering::SeqCst).saturating_sub(1);
                p
            },
        );
        history
    }

    fn destroy(self, ctx: &Context) {
        if let Some(p) = self.pathtrace {
            ctx.destroy_compute_pipeline(p);
        }
        if let Some(rv) = self.radiance {
            ctx.destroy_compute_pipeline(rv.volume_pipeline);
            ctx.destroy_compute_pipeline(rv.hemisphere_pipeline);
            ctx.destroy_image(rv.image);
        }
        self.volumes.destroy(ctx);
        ctx.destroy_image(self.history);
    }
}

impl RadianceVolume {
    fn new(ctx: &Context, grid: &VoxelGrid, has_phong: bool) -> Result<Self, VkError> {
        let volume_pipeline = ctx.compute_pipeline(
            "gi_radiance_volume.comp",
            crate::vk::PushLayout::of::<GpuGiPush>(),
            &[],
        )?;
        let hemisphere_pipeline = ctx.compute_pipeline(
            "gi_hemisphere_volume.comp",
            crate::vk::PushLayout::of::<GpuGiPush>(),
            &[(0, u32::from(has_phong))],
        )?;
        let ext = grid.extent_voxels();
        let usage = vk::ImageUsageFlags::STORAGE
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_DST;
        let image = ctx.create_image(
            &ImageDesc::new_2d(
                "direct radiance volume",
                vk::Format::R32G32B32A32_SFLOAT,
                ext.x,
                ext.y,
            )
            .with_depth(ext.z)
            .with_usage(usage),
        )?;
        ctx.clear_new_image(
            &image,
            vk::ClearColorValue { float32: [0.0; 4] },
            Access::Sampled(Shader::Compute).info().layout,
        )?;
        Ok(Self {
            volume_pipeline,
            hemisphere_pipeline,
            image,
        })
    }

    fn add_passes(
        &self,
        g: &mut RenderGraph,
        i: &GiInputs,
        lut: BufferHandle,
        (albedo, normal): (ImageHandle, ImageHandle),
        (push, sampler): (GpuGiPush, vk::Sampler),
        frames: Arc<AtomicU32>,
    ) -> ImageHandle {
        let read = Access::Sampled(Shader::Compute);
        let i = *i;
        let volume = g.import_image(&self.image, read);
        let pipe = self.volume_pipeline;
        let dims = push.dims;
        let c = Shader::Compute;
        g.add_pass("gi_radiance_volume")
            .pipeline(&pipe)
            .bind(0, i.frame, Access::StorageRead(c))
            .bind_sampled(1, i.voxels, sampler, c)
            .bind_sampled(2, albedo, sampler, c)
            .bind_sampled(3, normal, sampler, c)
            .bind_sampled(4, i.shadow_map, sampler, c)
            .bind(5, volume, Access::StorageWrite(c))
            .record(move |ctx| {
                // The direct radiance changes only with the lights, the shadow maps and the
                // scene, and each of those restarts the frame count (`GiPasses::reset`): the
                // first frame after a restart computes the volume, later ones keep it (it
                // cost 675 ms per frame at 128³ on lavapipe).
                if frames.load(Ordering::SeqCst) > 1 {
                    return;
                }
                ctx.bind(&pipe);
                ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                ctx.cmd.dispatch(
                    (dims[0] as u32).div_ceil(4),
                    (dims[1] as u32).div_ceil(4),
                    (dims[2] as u32).div_ceil(4),
                );
            });
        let irradiance = g.create_image(ImageDesc::new_2d(
            "indirect irradiance",
            vk::Format::R32G32B32A32_SFLOAT,
            i.width,
            i.height,
        ));
        let pipe = self.hemisphere_pipeline;
        add_ray_pass(
            g,
            "gi_hemisphere_volume",
            pipe,
            &i,
            lut,
            sampler,
            &[(5, volume), (6, normal)],
            (irradiance, Access::StorageWrite(Shader::Compute)),
            None,
            move || push,
        );
        irradiance
    }
}

/// Declares one of the GI ray passes (`gi_hemisphere`, `gi_hemisphere_volume`,
/// `gi_pathtrace`): they share the frame, G-buffer, voxel and ray-mask inputs (bindings 0-4) and
/// the specular and albedo images (9, 10); `own` are the pass's further sampled images by
/// binding, `out` its output image at binding 8, `materials` an optional buffer at binding 11,
/// and `push` its push constants at record time.
#[allow(clippy::too_many_arguments)]
fn add_ray_pass(
    g: &mut RenderGraph,
    name: &str,
    pipe: ComputePipeline,
    i: &GiInputs,
    lut: BufferHandle,
    sampler: vk::Sampler,
    own: &[(u32, ImageHandle)],
    (out, out_access): (ImageHandle, Access),
    materials: Option<BufferHandle>,
    push: impl Fn() -> GpuGiPush + 'static,
) {
    let c = Shader::Compute;
    let groups = (i.width.div_ceil(8), i.height.div_ceil(8));
    // Without Phong materials the shaders never read their specular binding; albedo fills it.
    let specular = i.specular.unwrap_or(i.albedo);
    let mut pass = g
        .add_pass(name)
        .pipeline(&pipe)
        .bind(0, i.frame, Access::StorageRead(c))
        .bind_sampled(1, i.normal, sampler, c)
        .bind_sampled(2, i.depth, sampler, c)
        .bind_sampled(3, i.voxels, sampler, c)
        .bind(4, lut, Access::StorageRead(c))
        .bind(8, out, out_access)
        .bind_sampled(9, specular, sampler, c)
        .bind_sampled(10, i.albedo, sampler, c);
    for &(b, h) in own {
        pass = pass.bind_sampled(b, h, sampler, c);
    }
    if let Some(m) = materials {
        pass = pass.bind(11, m, Access::StorageRead(c));
    }
    pass.record(move |ctx| {
        ctx.bind(&pipe);
        ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push()));
        ctx.cmd.dispatch(groups.0, groups.1, 1);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_constants_fit_and_match_glsl() {
        assert_eq!(
            std::mem::size_of::<GpuGiPush>(),
            128,
            "the Vulkan minimum push-constant size"
        );
        assert_eq!(std::mem::offset_of!(GpuGiPush, dims), 64);
        assert_eq!(std::mem::offset_of!(GpuGiPush, params2), 112);
        assert_eq!(std::mem::size_of::<GpuFilterPush>(), 16);
    }

    #[test]
    fn bounces_parse_print_and_encode() {
        use std::str::FromStr;
        for n in [1, 2, 3, 8, Bounces::MAX] {
            let b = Bounces::from_str(&n.to_string());
            assert_eq!(b, Ok(Bounces::Fixed(n)));
            // Fixed counts reach the shader as before the unbounded setting existed.
            assert_eq!(Bounces::Fixed(n).push_value(), n as f32);
        }
        assert_eq!(Bounces::from_str("unbounded"), Ok(Bounces::Unbounded));
        assert_eq!(Bounces::Unbounded.push_value(), 0.0);
        for b in [Bounces::Fixed(5), Bounces::Unbounded] {
            assert_eq!(Bounces::from_str(&b.to_string()), Ok(b), "round trip");
        }
        for bad in ["0", "65", "-1", "inf", "Unbounded", "", "2.5"] {
            let e = Bounces::from_str(bad).expect_err(bad);
            assert!(
                e.contains("[1, 64]") && e.contains("\"unbounded\""),
                "{bad}: {e}"
            );
        }
    }
}
