//! The voxel grid a renderer keeps frame to frame ([`VoxelFrame`]): the triangle voxelizer's
//! passes (`super::gpu`), the atlas voxelizer's (`super::gpu_atlas`) and, for the GI methods
//! that read them, the atlas's attribute volumes (`super::gpu_atlas_volumes`), assembled.

use super::coverage::scene_coverage;
use super::gpu::{
    add_store_and_mip_passes, add_store_and_mip_passes_gated, add_voxelize_passes,
    add_voxelize_passes_gated, check_finite, column_bytes, scene_triangles, voxelize_static_timed,
    ColumnBase, DynamicTriangles, GpuTriangle, GpuVoxelError, GpuVoxelGrid, SlotGate,
    TriangleBuffer, TriangleSource, VoxelPipelines, VoxelSettings, Voxelizer,
};
use super::gpu_atlas_volumes::AtlasVolumes;
use crate::graph::{run_once, ImageHandle, RenderGraph};
use crate::scene::Scene;
use crate::vk::{Buffer, Context, PassTiming, MAX_FRAMES_IN_FLIGHT};
use std::sync::Arc;

/// The voxel grid of a scene with the resources of its per-frame passes.
///
/// - Static objects are voxelized once (unless `revoxelize_static`).
/// - Without dynamic objects the whole grid, hierarchy included, is built once in
///   [`VoxelFrame::new`] and the frame declares no voxel passes at all.
/// - Dynamic (moving or animated) objects: [`VoxelFrame::update`] writes their world-space
///   triangles at the frame's time into the slot's region of a host-visible buffer, and the
///   frame's voxel passes record only when those triangles differ from the ones last
///   voxelized (a [`SlotGate`]): nothing is re-voxelized while nothing moves.
pub struct VoxelFrame {
    pub voxels: GpuVoxelGrid,
    pipelines: VoxelPipelines,
    static_tris: TriangleBuffer,
    static_columns: Option<Buffer>,
    dynamic: Option<DynamicVoxels>,
    revoxelize_static: bool,
    /// Atlas voxelizer state (with [`Voxelizer::Atlas`]): its atlases live in `atlas_cache`,
    /// in memory for the renderer's lifetime, so a static mesh is packed once per run.
    atlas: Option<super::gpu_atlas::AtlasScene>,
    /// The atlas's albedo and normal volumes' passes ([`Self::enable_attribute_volumes`]).
    atlas_volumes: Option<AtlasVolumes>,
    atlas_cache: super::atlas::AtlasCache,
    /// The dynamic atlas objects' model matrices and sequence frames in the grid (as
    /// `DynamicVoxels::voxelized`).
    atlas_pose: Option<super::gpu_atlas::AtlasPose>,
    /// Open in the frame slots that re-voxelize (present when anything is dynamic).
    gate: Option<Arc<SlotGate>>,
    /// GPU times of the one-time passes run before the first frame (atlas building, the
    /// static voxelization), in order.
    setup: Vec<PassTiming>,
    /// The last [`VoxelFrame::update`] moved an atlas object (its attribute volumes change).
    atlas_moved: bool,
}

/// The moving part of a [`VoxelFrame`].
struct DynamicVoxels {
    /// The scene's dynamic objects with the scene's meshes (textures dropped).
    scene: Scene,
    /// Per object of `scene`, its index in the whole scene.
    indices: Vec<usize>,
    triangles: DynamicTriangles,
    /// The triangles in the grid (or about to be, once the last open slot's frame runs).
    voxelized: Option<Vec<GpuTriangle>>,
}

/// Triangles of `scene`'s dynamic objects at `t_s`, validated like the CPU reference.
fn dynamic_triangles(scene: &Scene, t_s: f32) -> Result<Vec<GpuTriangle>, GpuVoxelError> {
    let tris = scene_triangles(scene, t_s, true);
    check_finite(&tris)?;
    let coverage = scene_coverage(scene, t_s, true);
    Ok(tris
        .iter()
        .zip(coverage)
        .map(|(&t, c)| GpuTriangle::covered(t, c))
        .collect())
}

/// The most triangles the dynamic objects of `scene` have at any time (OBJ sequences change
/// meshes).
fn dynamic_capacity(scene: &Scene) -> u32 {
    let tri_count = |m: usize| scene.meshes.get(m).map_or(0, |m| m.indices.len() / 3);
    scene
        .objects
        .iter()
        .filter(|o| o.dynamic || o.is_animated())
        .map(|o| match &o.animation {
            Some(crate::scene::Animation::ObjSequence { meshes, .. }) => meshes
                .iter()
                .copied()
                .chain([o.mesh])
                .map(tri_count)
                .max()
                .unwrap_or(0),
            _ => tri_count(o.mesh),
        })
        .sum::<usize>()
        .min(u32::MAX as usize) as u32
}

impl VoxelFrame {
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        settings: &VoxelSettings,
    ) -> Result<Self, GpuVoxelError> {
        let grid = settings.grid_for(scene, t_s)?;
        let pipelines = VoxelPipelines::new(ctx)?;
        let voxels = GpuVoxelGrid::new(ctx, &grid)?;
        let atlas_mode = settings.voxelizer == Voxelizer::Atlas;
        let (tris, coverage) = if atlas_mode {
            (Vec::new(), Vec::new())
        } else {
            (
                scene_triangles(scene, t_s, false),
                scene_coverage(scene, t_s, false),
            )
        };
        let static_tris =
            TriangleBuffer::upload_covered(ctx, "static triangles", &tris, &coverage)?;
        let mut frame = Self {
            voxels,
            pipelines,
            static_tris,
            static_columns: None,
            dynamic: None,
            revoxelize_static: settings.revoxelize_static,
            atlas: None,
            atlas_volumes: None,
            atlas_cache: Default::default(),
            atlas_pose: None,
            gate: None,
            setup: Vec::new(),
            atlas_moved: false,
        };
        frame.init(ctx, scene, t_s, atlas_mode)?;
        Ok(frame)
    }

    fn init(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        t_s: f32,
        atlas_mode: bool,
    ) -> Result<(), GpuVoxelError> {
        let grid = self.voxels.grid;
        if atlas_mode {
            let a =
                super::gpu_atlas::AtlasScene::new(ctx, scene, t_s, &grid, &mut self.atlas_cache);
            let a = a?;
            self.setup.extend(a.setup_timings().cloned());
            self.atlas = Some(a);
        }
        let tri_dynamic = |o: &crate::scene::Object| {
            (o.dynamic || o.is_animated())
                && !(atlas_mode && super::gpu_atlas::uses_atlas(scene, o))
        };
        if scene.objects.iter().any(tri_dynamic) {
            let mut dyn_scene = scene.clone();
            let indices = (0..scene.objects.len())
                .filter(|&i| tri_dynamic(&scene.objects[i]))
                .collect();
            dyn_scene.objects.retain(tri_dynamic);
            dyn_scene.textures.clear();
            let tris = dynamic_triangles(&dyn_scene, t_s)?;
            let mut triangles = DynamicTriangles::new(
                ctx,
                "dynamic triangles",
                &grid,
                dynamic_capacity(&dyn_scene).max(tris.len() as u32),
            )?;
            for slot in 0..MAX_FRAMES_IN_FLIGHT {
                triangles.write(slot, &tris);
            }
            self.dynamic = Some(DynamicVoxels {
                scene: dyn_scene,
                indices,
                triangles,
                voxelized: None,
            });
        }
        let atlas_static = self.atlas.as_ref().is_some_and(|a| a.has_static());
        if self.has_frame_passes() {
            self.gate = Some(Arc::new(SlotGate::default()));
        }
        if !self.revoxelize_static && (self.static_tris.count > 0 || atlas_static) {
            if self.has_frame_passes() {
                let (columns, timings) = match &self.atlas {
                    Some(a) => super::gpu_atlas::voxelize_static_atlas(
                        ctx,
                        a,
                        &self.pipelines,
                        &grid,
                        &self.static_tris,
                    )?,
                    None => voxelize_static_timed(ctx, &self.pipelines, &grid, &self.static_tris)?,
                };
                self.static_columns = Some(columns);
                self.setup.extend(timings);
            } else {
                // Nothing ever moves: build the grid and its hierarchy now, once.
                let mut g = RenderGraph::new();
                let image = self.voxels.import(&mut g);
                let columns = g.create_buffer("voxel column buffer", column_bytes(&grid));
                add_voxelize_passes(
                    &mut g,
                    &self.pipelines,
                    &grid,
                    columns,
                    ColumnBase::Clear,
                    &[&self.static_tris],
                );
                if let Some(a) = &self.atlas {
                    a.add_pass(&mut g, &grid, columns, true, false, None);
                }
                add_store_and_mip_passes(&mut g, &self.pipelines, &self.voxels, columns, image);
                self.setup.extend(run_once(ctx, g)?);
            }
        }
        Ok(())
    }

    /// GPU times of the one-time passes that ran before the first frame, in order.
    pub fn setup_timings(&self) -> &[PassTiming] {
        &self.setup
    }

    /// How many atlases the atlas voxelizer packed (0 without it): one per distinct mesh and
    /// scale, one per OBJ sequence.
    pub fn atlases_packed(&self) -> u32 {
        self.atlas_cache.packed
    }

    /// How many atlas point lists were built (one per atlas and sequence frame).
    pub fn atlas_point_lists(&self) -> usize {
        self.atlas.as_ref().map_or(0, |a| a.point_lists())
    }

    /// Whether the frame declares voxel passes (dynamic objects, or `revoxelize_static`).
    pub fn has_frame_passes(&self) -> bool {
        self.dynamic.is_some()
            || self.revoxelize_static
            || self.atlas.as_ref().is_some_and(|a| a.has_dynamic())
    }

    /// Takes the dynamic objects' transforms from `scene` (the scene this frame was made for,
    /// its objects in the same order): an object the viewer's editor moves is re-voxelized
    /// where it now is by the next [`Self::update`]. Animated objects follow their keyframes.
    pub fn follow_objects(&mut self, scene: &Scene) {
        if let Some(d) = &mut self.dynamic {
            for (o, &i) in d.scene.objects.iter_mut().zip(&d.indices) {
                if let Some(src) = scene.objects.get(i) {
                    o.transform = src.transform;
                }
            }
        }
        if let Some(a) = &mut self.atlas {
            a.follow_objects(scene);
        }
    }

    /// Prepares frame slot `slot` for scene time `t_s` (call after the slot's fence): writes
    /// the dynamic triangles when they changed since they were last voxelized. Returns
    /// whether this frame re-voxelizes.
    pub fn update(&mut self, t_s: f32, slot: usize) -> Result<bool, GpuVoxelError> {
        if let Some(v) = self.atlas_volumes.as_mut() {
            v.prepare(slot);
        }
        let tris = match &self.dynamic {
            Some(d) => Some(dynamic_triangles(&d.scene, t_s)?),
            None => None,
        };
        let pose = self.atlas.as_ref().map(|a| a.pose_at(t_s));
        let tris_changed = match (&self.dynamic, &tris) {
            (Some(d), Some(t)) => d.voxelized.as_ref() != Some(t),
            _ => false,
        };
        let models_changed = match &pose {
            Some(p) if !p.models.is_empty() => self.atlas_pose.as_ref() != Some(p),
            _ => false,
        };
        let run = self.revoxelize_static || tris_changed || models_changed;
        self.atlas_moved = models_changed;
        if run {
            if let (Some(d), Some(tris)) = (&mut self.dynamic, tris) {
                d.triangles.write(slot, &tris);
                d.voxelized = Some(tris);
            }
            if let (Some(a), Some(pose)) = (&self.atlas, pose) {
                a.write_pose(slot, &pose);
                self.atlas_pose = Some(pose);
            }
        }
        if let Some(g) = &self.gate {
            g.set(slot, run);
        }
        Ok(run)
    }

    /// Creates the albedo and normal volumes' atlas passes (Thiedemann 2010, §4.3.2) when the atlas
    /// voxelizer is active, for a GI method that reads them, with the value volumes `values`
    /// (emission, material and their maps); static objects are splatted now, once. Returns
    /// whether the atlas writes the volumes (then [`Self::add_attribute_passes`] declares the
    /// per-frame part). Objects that keep the triangle voxelizer (OBJ sequences whose frames
    /// differ in topology) are left to the caller's triangle attributes. The first call
    /// decides: later calls keep the passes it made (the GI method's, before a debug view's).
    pub fn enable_attribute_volumes(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        values: super::attributes::ValueVolumes,
    ) -> Result<bool, GpuVoxelError> {
        let grid = self.voxels.grid;
        let statics_once = !self.revoxelize_static;
        let Some(atlas) = &mut self.atlas else {
            return Ok(false);
        };
        if self.atlas_volumes.is_none() && atlas.point_count() > 0 {
            let v = AtlasVolumes::new(ctx, atlas, scene, &grid, statics_once, values)?;
            self.atlas_volumes = Some(v);
        }
        Ok(self.atlas_volumes.is_some())
    }

    /// Whether the atlas writes the attribute volumes ([`Self::enable_attribute_volumes`]).
    pub fn has_attribute_volumes(&self) -> bool {
        self.atlas.is_some() && self.atlas_volumes.is_some()
    }

    /// Whether the last [`Self::update`] moved an object whose attributes the atlas writes
    /// (accumulated GI restarts then).
    pub fn attributes_moved(&self) -> bool {
        self.atlas_moved && self.has_attribute_volumes()
    }

    /// Declares `voxelize_atlas_volumes` and the atlas resolves writing the imported attribute
    /// volumes `v` (see [`super::gpu_atlas_volumes`]); nothing without
    /// [`Self::enable_attribute_volumes`]. Record in the same frames as [`Self::add_passes`].
    pub fn add_attribute_passes(
        &self,
        g: &mut RenderGraph,
        v: &super::attributes::AttributeHandles,
    ) {
        let Some(atlas) = &self.atlas else {
            return;
        };
        let Some(volumes) = &self.atlas_volumes else {
            return;
        };
        volumes.add_passes(
            g,
            (atlas, &self.voxels.grid),
            v,
            self.revoxelize_static,
            self.gate.clone(),
        );
    }

    /// Declares the frame's voxel passes (none when [`Self::has_frame_passes`] is false);
    /// returns the column image (resting state [`super::gpu::VOXEL_IMAGE_STATE`]).
    pub fn add_passes(&self, g: &mut RenderGraph) -> ImageHandle {
        let image = self.voxels.import(g);
        if !self.has_frame_passes() {
            return image;
        }
        let grid = &self.voxels.grid;
        let columns = g.create_buffer("voxel column buffer", column_bytes(grid));
        let base = match &self.static_columns {
            Some(b) => ColumnBase::Copy(b),
            None => ColumnBase::Clear,
        };
        let mut sources = Vec::new();
        if self.static_columns.is_none() {
            sources.push(TriangleSource::Fixed(&self.static_tris));
        }
        if let Some(d) = &self.dynamic {
            sources.push(TriangleSource::PerSlot(&d.triangles));
        }
        let gate = self.gate.clone();
        add_voxelize_passes_gated(
            g,
            &self.pipelines,
            grid,
            columns,
            base,
            &sources,
            gate.clone(),
        );
        if let Some(a) = &self.atlas {
            let statics = self.static_columns.is_none();
            a.add_pass(g, grid, columns, statics, true, gate.clone());
        }
        add_store_and_mip_passes_gated(g, &self.pipelines, &self.voxels, columns, image, gate);
        image
    }
}
