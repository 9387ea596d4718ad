//! `compile`: a readable sequence of named steps, in plain Rust and testable without a GPU.
//!
//! 1. validate declarations;
//! 2. cull passes that feed no output;
//! 3. derive usage flags;
//! 4. compute transient lifetimes;
//! 5. place transients, aliasing those whose lifetimes do not overlap: the smallest of a
//!    packed, a buddy-allocated and an unaliased plan (see `placement`);
//! 6. plan barriers per (mip, layer) and merge them into ranges.

use super::access::{write_bits, Access, AccessInfo, Subresource};
use super::{GraphError, Origin, PassDecl, RenderGraph, ResourceDecl, ResourceId, ResourceKind};
use ash::vk;
use std::collections::{BTreeMap, HashMap};

mod placement;
pub use placement::PlacementStrategy;

/// Memory needs of one transient, as the device reports them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryRequirements {
    pub size_bytes: u64,
    pub alignment: u64,
    /// Transients with equal keys share arenas (one memory type each).
    pub memory_type: u32,
}

/// Supplies memory requirements for transient resources (the GPU, or an estimate in tests).
pub trait MemoryOracle {
    fn requirements(&self, resource: ResourceId, decl: &ResourceDeclView) -> MemoryRequirements;
}

/// What an oracle may look at.
pub struct ResourceDeclView<'a> {
    pub name: &'a str,
    pub image: Option<&'a crate::vk::ImageDesc>,
    pub buffer_size_bytes: u64,
    pub buffer_usage: vk::BufferUsageFlags,
}

/// A transient's place in an arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placement {
    pub arena: usize,
    pub offset: u64,
    pub size_bytes: u64,
}

/// One block of device memory that transients are placed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Arena {
    pub memory_type: u32,
    /// Buffers and (optimal-tiling) images never share an arena: placed at exact offsets,
    /// a buffer and an image alive together could meet inside one
    /// `bufferImageGranularity` page, which Vulkan counts as aliasing.
    pub holds_buffers: bool,
    /// High-water mark of the placements: the bytes to allocate.
    pub size_bytes: u64,
}

/// Transient memory with and without aliasing, and where the difference to the ideal goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryStats {
    /// Bytes the arenas take: the chosen plan, never more than `unaliased_bytes`.
    pub peak_aliased_bytes: u64,
    /// Bytes every transient takes back to back, each at its own aligned offset.
    pub unaliased_bytes: u64,
    /// The most bytes the transients alive at one pass ask for (summed over arenas):
    /// no placement can take less.
    pub live_peak_bytes: u64,
    /// Bytes the chosen plan reserves beyond what the transients ask for (buddy blocks
    /// rounded up to powers of two; 0 for the packed and unaliased plans).
    pub rounding_bytes: u64,
    /// The plan the arenas use.
    pub strategy: PlacementStrategy,
    /// What the packed and buddy plans would need; `None` where they cannot place the frame.
    pub packed_bytes: Option<u64>,
    pub buddy_bytes: Option<u64>,
    pub transient_count: usize,
}

impl MemoryStats {
    /// Bytes above the live peak: lost to rounding, alignment padding and fragmentation.
    pub fn waste_bytes(&self) -> u64 {
        self.peak_aliased_bytes.saturating_sub(self.live_peak_bytes)
    }

    /// One line for dumps and profiles: aliased, unaliased, wasted, and the plan's reason.
    pub fn summary(&self) -> String {
        let candidate = |name: &str, bytes: Option<u64>| match bytes {
            Some(b) => format!("{name} {b}"),
            None => format!("{name} impossible"),
        };
        format!(
            "{} bytes aliased, {} bytes without aliasing, {} bytes lost to rounding, {} bytes \
             above the live peak of {} ({} plan; candidates: {}, {}, unaliased {})",
            self.peak_aliased_bytes,
            self.unaliased_bytes,
            self.rounding_bytes,
            self.waste_bytes(),
            self.live_peak_bytes,
            self.strategy,
            candidate("packed", self.packed_bytes),
            candidate("buddy", self.buddy_bytes),
            self.unaliased_bytes,
        )
    }
}

/// One synchronization2 barrier (image or buffer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Barrier {
    pub resource: ResourceId,
    /// Mips/layers for images; whole buffer for buffers.
    pub sub: Subresource,
    pub src_stages: vk::PipelineStageFlags2,
    pub src_access: vk::AccessFlags2,
    pub dst_stages: vk::PipelineStageFlags2,
    pub dst_access: vk::AccessFlags2,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

/// The result of `compile`: everything the executor needs, and the dump shows.
#[derive(Clone, Debug)]
pub struct CompiledGraph {
    /// Indices into the declared passes, in execution order.
    pub order: Vec<usize>,
    /// Declared passes that were culled.
    pub culled: Vec<usize>,
    /// Barriers before each pass in `order`.
    pub pass_barriers: Vec<Vec<Barrier>>,
    /// Barriers after the last pass (imported resources back to their state).
    pub final_barriers: Vec<Barrier>,
    /// First and last position in `order` of each resource used by a live pass.
    pub lifetimes: Vec<Option<(usize, usize)>>,
    pub placements: Vec<Option<Placement>>,
    pub arenas: Vec<Arena>,
    pub memory: MemoryStats,
    /// Usage flags derived for each image (index = resource).
    pub image_usage: Vec<vk::ImageUsageFlags>,
    pub buffer_usage: Vec<vk::BufferUsageFlags>,
    /// Names of resources and passes, for dumps and errors.
    pub resource_names: Vec<String>,
    pub pass_names: Vec<String>,
}

/// The combined access of one pass per (resource, mip, layer).
type PassCells = BTreeMap<(ResourceId, u32, u32), (AccessInfo, Access)>;

impl RenderGraph {
    /// Compiles the declared frame (see the module doc for the steps).
    pub fn compile(&self, oracle: &dyn MemoryOracle) -> Result<CompiledGraph, GraphError> {
        self.validate()?;
        super::bind::check(self)?;
        let (order, culled) = self.cull()?;
        let (image_usage, buffer_usage) = self.usage_flags(&order);
        let lifetimes = self.lifetimes(&order);
        let (placements, arenas, memory) =
            self.place(&lifetimes, oracle, &image_usage, &buffer_usage)?;
        let (pass_barriers, final_barriers) = self.plan_barriers(&order, &lifetimes, &placements);
        Ok(CompiledGraph {
            order,
            culled,
            pass_barriers,
            final_barriers,
            lifetimes,
            placements,
            arenas,
            memory,
            image_usage,
            buffer_usage,
            resource_names: self.resources.iter().map(|r| r.name.clone()).collect(),
            pass_names: self.passes.iter().map(|p| p.name.clone()).collect(),
        })
    }

    fn validate(&self) -> Result<(), GraphError> {
        let mut names = std::collections::HashSet::new();
        let mut written: Vec<bool> = self
            .resources
            .iter()
            .map(|r| matches!(r.origin, Origin::Imported { .. }))
            .collect();
        for pass in &self.passes {
            if !names.insert(pass.name.as_str()) {
                return Err(GraphError::DuplicatePassName(pass.name.clone()));
            }
            for &(id, access, sel, declared_read) in &pass.accesses {
                let r = self.resource(id);
                let info = access.info();
                let (kind, ok) = if r.is_image() {
                    ("image", access.valid_for_image())
                } else {
                    ("buffer", access.valid_for_buffer())
                };
                if !ok {
                    return Err(GraphError::AccessKindMismatch {
                        pass: pass.name.clone(),
                        resource: r.name.clone(),
                        access,
                        kind,
                    });
                }
                if declared_read && info.writes {
                    return Err(GraphError::ReadDeclaredAsWrite {
                        pass: pass.name.clone(),
                        resource: r.name.clone(),
                        access,
                    });
                }
                let (mips, layers) = r.mips_layers();
                let s = sel.resolve(mips, layers);
                if s.mip_count == 0
                    || s.layer_count == 0
                    || s.base_mip + s.mip_count > mips
                    || s.base_layer + s.layer_count > layers
                {
                    return Err(GraphError::SubresourceOutOfRange {
                        pass: pass.name.clone(),
                        resource: r.name.clone(),
                        mips: (s.base_mip, s.mip_count),
                        layers: (s.base_layer, s.layer_count),
                        mip_levels: mips,
                        layer_count: layers,
                    });
                }
                if info.reads && !written[id.0 as usize] {
                    return Err(GraphError::ReadBeforeWrite {
                        pass: pass.name.clone(),
                        resource: r.name.clone(),
                    });
                }
            }
            self.pass_cells(pass)?;
            for &(id, access, _, _) in &pass.accesses {
                if access.info().writes {
                    written[id.0 as usize] = true;
                }
            }
        }
        Ok(())
    }

    pub(crate) fn resource(&self, id: ResourceId) -> &ResourceDecl {
        &self.resources[id.0 as usize]
    }

    /// The combined access of a pass per (resource, mip, layer).
    fn pass_cells(&self, pass: &PassDecl) -> Result<PassCells, GraphError> {
        let mut cells: BTreeMap<(ResourceId, u32, u32), (AccessInfo, Access)> = BTreeMap::new();
        for &(id, access, sel, _) in &pass.accesses {
            let r = self.resource(id);
            let (mips, layers) = r.mips_layers();
            let s = sel.resolve(mips, layers);
            let info = access.info();
            for m in s.base_mip..s.base_mip + s.mip_count {
                for l in s.base_layer..s.base_layer + s.layer_count {
                    match cells.get_mut(&(id, m, l)) {
                        None => {
                            cells.insert((id, m, l), (info, access));
                        }
                        Some((prev, prev_access)) => {
                            if r.is_image() && prev.layout != info.layout {
                                return Err(GraphError::ConflictingLayouts {
                                    pass: pass.name.clone(),
                                    resource: r.name.clone(),
                                    a: *prev_access,
                                    b: access,
                                });
                            }
                            prev.stages |= info.stages;
                            prev.access |= info.access;
                            prev.reads |= info.reads;
                            prev.writes |= info.writes;
                        }
                    }
                }
            }
        }
        Ok(cells)
    }

    /// Walks passes from last to first; a pass lives if it writes something needed.
    /// Outputs: imported resources (persistent, seen by the next frame or the host) but for
    /// the graph's cached images, and resources marked with `mark_output`.
    fn cull(&self) -> Result<(Vec<usize>, Vec<usize>), GraphError> {
        let mut needed: Vec<bool> = self
            .resources
            .iter()
            // A cached image is the graph's own: kept only for the passes that read it.
            .map(|r| {
                r.output || (matches!(r.origin, Origin::Imported { .. }) && r.caches.is_empty())
            })
            .collect();
        if !needed.iter().any(|&n| n) {
            return Err(GraphError::NoOutput);
        }
        let mut live = vec![false; self.passes.len()];
        // A history is written for the next frame, after the passes that read it in this one:
        // once a live pass reads it, walk again so that its writers (and their inputs) live.
        loop {
            for (i, pass) in self.passes.iter().enumerate().rev() {
                let feeds_output = pass
                    .accesses
                    .iter()
                    .any(|&(id, a, _, _)| a.info().writes && needed[id.0 as usize]);
                if feeds_output {
                    live[i] = true;
                    for &(id, a, _, _) in &pass.accesses {
                        if a.info().reads {
                            needed[id.0 as usize] = true;
                        }
                    }
                }
            }
            let revived = self.passes.iter().enumerate().any(|(i, pass)| {
                !live[i]
                    && pass.accesses.iter().any(|&(id, a, _, _)| {
                        let r = id.0 as usize;
                        a.info().writes && needed[r] && self.resources[r].history
                    })
            });
            if !revived {
                break;
            }
        }
        let order = (0..self.passes.len()).filter(|&i| live[i]).collect();
        let culled = (0..self.passes.len()).filter(|&i| !live[i]).collect();
        Ok((order, culled))
    }

    fn usage_flags(
        &self,
        order: &[usize],
    ) -> (Vec<vk::ImageUsageFlags>, Vec<vk::BufferUsageFlags>) {
        let mut img: Vec<vk::ImageUsageFlags> = self
            .resources
            .iter()
            .map(|r| match &r.kind {
                ResourceKind::Image(d) => d.usage,
                _ => vk::ImageUsageFlags::empty(),
            })
            .collect();
        let mut buf: Vec<vk::BufferUsageFlags> = self
            .resources
            .iter()
            .map(|r| match &r.kind {
                ResourceKind::Buffer { usage, .. } => *usage,
                _ => vk::BufferUsageFlags::empty(),
            })
            .collect();
        for &p in order {
            for &(id, a, _, _) in &self.passes[p].accesses {
                img[id.0 as usize] |= a.image_usage();
                buf[id.0 as usize] |= a.buffer_usage();
            }
        }
        (img, buf)
    }

    fn lifetimes(&self, order: &[usize]) -> Vec<Option<(usize, usize)>> {
        let mut life: Vec<Option<(usize, usize)>> = vec![None; self.resources.len()];
        for (pos, &p) in order.iter().enumerate() {
            for &(id, _, _, _) in &self.passes[p].accesses {
                let l = &mut life[id.0 as usize];
                *l = Some(match *l {
                    None => (pos, pos),
                    Some((a, _)) => (a, pos),
                });
            }
        }
        for (i, r) in self.resources.iter().enumerate() {
            if r.output && r.is_transient() {
                if let Some((a, _)) = life[i] {
                    life[i] = Some((a, order.len().saturating_sub(1)));
                }
            }
        }
        life
    }

    /// Memory requirements of every transient a live pass uses, with its derived usage.
    fn requirements(
        &self,
        lifetimes: &[Option<(usize, usize)>],
        oracle: &dyn MemoryOracle,
        image_usage: &[vk::ImageUsageFlags],
        buffer_usage: &[vk::BufferUsageFlags],
    ) -> Vec<Option<MemoryRequirements>> {
        let mut reqs: Vec<Option<MemoryRequirements>> = vec![None; self.resources.len()];
        for (i, r) in self.resources.iter().enumerate() {
            if !r.is_transient() || lifetimes[i].is_none() {
                continue;
            }
            let mut desc = match &r.kind {
                ResourceKind::Image(d) => Some(d.clone()),
                _ => None,
            };
            if let Some(d) = desc.as_mut() {
                d.usage |= image_usage[i];
            }
            let size = match &r.kind {
                ResourceKind::Buffer { size_bytes, .. } => *size_bytes,
                _ => 0,
            };
            let view = ResourceDeclView {
                name: &r.name,
                image: desc.as_ref(),
                buffer_size_bytes: size,
                buffer_usage: buffer_usage[i],
            };
            reqs[i] = Some(oracle.requirements(ResourceId(i as u32), &view));
        }
        reqs
    }

    /// Places transients in one arena per memory type, aliasing those whose lifetimes do not
    /// overlap. Of the candidate plans in `placement` (packed, buddy, unaliased) the one with
    /// the fewest bytes is kept; since not aliasing is a candidate, aliasing never costs
    /// memory, whatever the sizes and alignments.
    #[allow(clippy::type_complexity)]
    fn place(
        &self,
        lifetimes: &[Option<(usize, usize)>],
        oracle: &dyn MemoryOracle,
        image_usage: &[vk::ImageUsageFlags],
        buffer_usage: &[vk::BufferUsageFlags],
    ) -> Result<(Vec<Option<Placement>>, Vec<Arena>, MemoryStats), GraphError> {
        let reqs = self.requirements(lifetimes, oracle, image_usage, buffer_usage);
        // One arena per memory type and resource kind (see `Arena::holds_buffers`), in key
        // order for determinism; members in declaration order (the unaliased plan's order).
        let key = |i: usize, r: &MemoryRequirements| (r.memory_type, !self.resources[i].is_image());
        let mut keys: Vec<(u32, bool)> = reqs
            .iter()
            .enumerate()
            .filter_map(|(i, r)| Some(key(i, r.as_ref()?)))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        let members: Vec<Vec<(usize, MemoryRequirements, (usize, usize))>> = keys
            .iter()
            .map(|&k| {
                reqs.iter()
                    .zip(lifetimes)
                    .enumerate()
                    .filter_map(|(i, (r, life))| match (r, life) {
                        (Some(r), Some(life)) if key(i, r) == k => Some((i, *r, *life)),
                        _ => None,
                    })
                    .collect()
            })
            .collect();
        let items: Vec<Vec<placement::Item>> = members
            .iter()
            .map(|m| {
                m.iter()
                    .map(|&(_, r, (first, last))| placement::Item {
                        size_bytes: r.size_bytes,
                        alignment: r.alignment,
                        first,
                        last,
                    })
                    .collect()
            })
            .collect();
        let Some(choice) = placement::choose(&items) else {
            let resource = members
                .iter()
                .flatten()
                .next()
                .map_or_else(String::new, |&(i, _, _)| self.resources[i].name.clone());
            return Err(GraphError::Placement {
                resource,
                reason: "the transients need more than 2^64 bytes even without aliasing; \
                         check the sizes the memory oracle reports"
                    .into(),
            });
        };

        let total = |s: PlacementStrategy| {
            choice
                .totals
                .iter()
                .find(|(t, _)| *t == s)
                .and_then(|&(_, bytes)| bytes)
        };
        let mut stats = MemoryStats {
            strategy: choice.strategy,
            packed_bytes: total(PlacementStrategy::Packed),
            buddy_bytes: total(PlacementStrategy::Buddy),
            unaliased_bytes: total(PlacementStrategy::Unaliased).unwrap_or(u64::MAX),
            ..MemoryStats::default()
        };
        let mut placements = vec![None; self.resources.len()];
        let mut arenas = Vec::with_capacity(keys.len());
        for (arena, ((&(ty, holds_buffers), m), plan)) in
            keys.iter().zip(&members).zip(&choice.plans).enumerate()
        {
            for (&(i, r, _), slot) in m.iter().zip(&plan.slots) {
                stats.rounding_bytes += slot.reserved_bytes - r.size_bytes;
                stats.transient_count += 1;
                placements[i] = Some(Placement {
                    arena,
                    offset: slot.offset,
                    size_bytes: slot.reserved_bytes,
                });
            }
            stats.peak_aliased_bytes += plan.size_bytes;
            stats.live_peak_bytes += placement::live_peak_bytes(&items[arena]);
            arenas.push(Arena {
                memory_type: ty,
                holds_buffers,
                size_bytes: plan.size_bytes,
            });
        }
        Ok((placements, arenas, stats))
    }

    /// Derives every barrier from the declared accesses (see `CellState`).
    fn plan_barriers(
        &self,
        order: &[usize],
        lifetimes: &[Option<(usize, usize)>],
        placements: &[Option<Placement>],
    ) -> (Vec<Vec<Barrier>>, Vec<Barrier>) {
        let mut states: HashMap<(ResourceId, u32, u32), CellState> = HashMap::new();
        let initial = |this: &Self, id: ResourceId| -> CellState {
            let r = this.resource(id);
            match r.origin {
                Origin::Imported { state, .. } => {
                    let mut cell = CellState::imported(state.info(), r.is_image());
                    // A freshly acquired swapchain image may be in any layout (UNDEFINED after
                    // creation): discard it, see `Access::Present`.
                    cell.pristine = state == Access::Present;
                    cell
                }
                Origin::Transient => {
                    let (stages, access) =
                        this.alias_predecessors(id, order, lifetimes, placements);
                    CellState::transient(stages, access)
                }
            }
        };

        let mut pass_barriers = Vec::with_capacity(order.len());
        for &p in order {
            let mut raw = Vec::new();
            let cells = self.pass_cells(&self.passes[p]).unwrap_or_default();
            for (&(id, m, l), &(info, _)) in &cells {
                let is_image = self.resource(id).is_image();
                let state = states
                    .entry((id, m, l))
                    .or_insert_with(|| initial(self, id));
                if let Some(b) = state.apply(&info, is_image) {
                    raw.push(((id, m, l), b));
                }
            }
            pass_barriers.push(merge(raw, self));
        }

        // Imported resources return to their import state so every frame starts alike.
        let mut raw = Vec::new();
        let mut keys: Vec<_> = states.keys().copied().collect();
        keys.sort();
        for key in keys {
            let r = self.resource(key.0);
            if let Origin::Imported { state, .. } = r.origin {
                let info = state.info();
                if let Some(cell) = states.get_mut(&key) {
                    if let Some(b) = cell.apply_final(&info, r.is_image()) {
                        raw.push((key, b));
                    }
                }
            }
        }
        (pass_barriers, merge(raw, self))
    }

    /// What a transient's first access must wait for: the last accesses of the transients it
    /// aliases that end earlier in the frame; if it is the first occupant of its memory, the
    /// final accesses of every occupant (the same memory's use in the previous frame).
    fn alias_predecessors(
        &self,
        id: ResourceId,
        order: &[usize],
        lifetimes: &[Option<(usize, usize)>],
        placements: &[Option<Placement>],
    ) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        let Some(me) = placements[id.0 as usize] else {
            return (vk::PipelineStageFlags2::empty(), vk::AccessFlags2::empty());
        };
        let Some((my_start, _)) = lifetimes[id.0 as usize] else {
            return (vk::PipelineStageFlags2::empty(), vk::AccessFlags2::empty());
        };
        let overlapping: Vec<usize> = (0..self.resources.len())
            .filter(|&j| {
                placements[j].is_some_and(|o| {
                    o.arena == me.arena
                        && o.offset < me.offset + me.size_bytes
                        && me.offset < o.offset + o.size_bytes
                })
            })
            .collect();
        let earlier: Vec<usize> = overlapping
            .iter()
            .copied()
            .filter(|&j| lifetimes[j].is_some_and(|(_, end)| end < my_start))
            .collect();
        let sources = if earlier.is_empty() {
            overlapping
        } else {
            earlier
        };
        let mut stages = vk::PipelineStageFlags2::empty();
        let mut access = vk::AccessFlags2::empty();
        for j in sources {
            if let Some((_, end)) = lifetimes[j] {
                for &(rid, a, _, _) in &self.passes[order[end]].accesses {
                    if rid.0 as usize == j {
                        let info = a.info();
                        stages |= info.stages;
                        access |= info.access & write_bits();
                    }
                }
            }
        }
        (stages, access)
    }
}

/// Synchronization state of one (resource, mip, layer).
#[derive(Clone, Debug)]
struct CellState {
    layout: vk::ImageLayout,
    /// Stages and access of the last write (a layout transition counts as a write).
    write_stages: vk::PipelineStageFlags2,
    write_access: vk::AccessFlags2,
    /// Stages that read since the last write (a write must wait for them: WAR).
    read_stages: vk::PipelineStageFlags2,
    /// (stages, access) pairs the last write has been made visible to.
    visible: Vec<(vk::PipelineStageFlags2, vk::AccessFlags2)>,
    /// First access of a transient: its contents are undefined.
    pristine: bool,
}

impl CellState {
    fn imported(state: AccessInfo, is_image: bool) -> Self {
        // The previous frame ended with a barrier to `state`, so its writes are visible to
        // exactly that (stages, access) and later users chain on those stages.
        Self {
            layout: if is_image {
                state.layout
            } else {
                vk::ImageLayout::UNDEFINED
            },
            write_stages: state.stages,
            write_access: vk::AccessFlags2::NONE,
            read_stages: vk::PipelineStageFlags2::empty(),
            visible: vec![(state.stages, state.access)],
            pristine: false,
        }
    }

    fn transient(prev_stages: vk::PipelineStageFlags2, prev_access: vk::AccessFlags2) -> Self {
        Self {
            layout: vk::ImageLayout::UNDEFINED,
            write_stages: prev_stages,
            write_access: prev_access,
            read_stages: vk::PipelineStageFlags2::empty(),
            visible: vec![],
            pristine: true,
        }
    }

    fn covered(&self, info: &AccessInfo) -> bool {
        self.visible
            .iter()
            .any(|&(s, a)| s.contains(info.stages) && a.contains(info.access))
    }

    /// Updates the state for `info`; returns the barrier it needs, if any.
    fn apply(&mut self, info: &AccessInfo, is_image: bool) -> Option<PlainBarrier> {
        let layout = if is_image {
            info.layout
        } else {
            vk::ImageLayout::UNDEFINED
        };
        let transition = is_image && (self.layout != layout || self.pristine);
        let barrier = if info.writes || transition {
            let src_stages = self.write_stages | self.read_stages;
            let needed = transition || !src_stages.is_empty();
            let b = PlainBarrier {
                src_stages,
                src_access: self.write_access,
                dst_stages: info.stages,
                dst_access: info.access,
                old_layout: if self.pristine {
                    vk::ImageLayout::UNDEFINED
                } else {
                    self.layout
                },
                new_layout: layout,
            };
            if info.writes {
                self.write_stages = info.stages;
                self.write_access = info.access & write_bits();
                self.read_stages = if info.reads {
                    info.stages
                } else {
                    vk::PipelineStageFlags2::empty()
                };
                self.visible.clear();
            } else {
                // A layout transition is a write that completes before `info.stages`.
                self.write_stages = info.stages;
                self.write_access = vk::AccessFlags2::NONE;
                self.read_stages = info.stages;
                self.visible = vec![(info.stages, info.access)];
            }
            needed.then_some(b)
        } else if self.write_stages.is_empty() || self.covered(info) {
            self.read_stages |= info.stages;
            None
        } else {
            let b = PlainBarrier {
                src_stages: self.write_stages,
                src_access: self.write_access,
                dst_stages: info.stages,
                dst_access: info.access,
                old_layout: self.layout,
                new_layout: layout,
            };
            self.read_stages |= info.stages;
            self.visible.push((info.stages, info.access));
            Some(b)
        };
        self.layout = layout;
        self.pristine = false;
        barrier
    }

    /// The end-of-frame barrier back to an imported resource's state.
    fn apply_final(&mut self, info: &AccessInfo, is_image: bool) -> Option<PlainBarrier> {
        let layout = if is_image {
            info.layout
        } else {
            vk::ImageLayout::UNDEFINED
        };
        if self.layout == layout && self.covered(info) {
            return None;
        }
        // Always a full memory dependency: the next frame assumes availability.
        let b = PlainBarrier {
            src_stages: self.write_stages | self.read_stages,
            src_access: self.write_access,
            dst_stages: info.stages,
            dst_access: info.access,
            old_layout: self.layout,
            new_layout: layout,
        };
        self.layout = layout;
        Some(b)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct PlainBarrier {
    src_stages: vk::PipelineStageFlags2,
    src_access: vk::AccessFlags2,
    dst_stages: vk::PipelineStageFlags2,
    dst_access: vk::AccessFlags2,
    old_layout: vk::ImageLayout,
    new_layout: vk::ImageLayout,
}

/// A barrier and the layers, per mip, it applies to.
type BarrierGroup = (PlainBarrier, BTreeMap<u32, Vec<u32>>);

/// Merges per-cell barriers into ranges: runs of layers per mip, then runs of mips with the
/// same layer run and parameters.
fn merge(raw: Vec<((ResourceId, u32, u32), PlainBarrier)>, graph: &RenderGraph) -> Vec<Barrier> {
    // (resource, barrier) -> mip -> sorted layers
    let mut groups: BTreeMap<(ResourceId, u64), BarrierGroup> = BTreeMap::new();
    let mut keys: HashMap<PlainBarrier, u64> = HashMap::new();
    for ((id, m, l), b) in raw {
        let n = keys.len() as u64;
        let k = *keys.entry(b).or_insert(n);
        groups
            .entry((id, k))
            .or_insert_with(|| (b, BTreeMap::new()))
            .1
            .entry(m)
            .or_default()
            .push(l);
    }
    let mut out = Vec::new();
    for ((id, _), (b, mips)) in groups {
        let is_image = graph.resource(id).is_image();
        // (mip, base_layer, count)
        let mut runs: Vec<(u32, u32, u32)> = Vec::new();
        for (m, mut layers) in mips {
            layers.sort_unstable();
            let mut start = layers[0];
            let mut prev = layers[0];
            for &l in &layers[1..] {
                if l != prev + 1 {
                    runs.push((m, start, prev - start + 1));
                    start = l;
                }
                prev = l;
            }
            runs.push((m, start, prev - start + 1));
        }
        let mut merged: Vec<Subresource> = Vec::new();
        for (m, base, count) in runs {
            if let Some(last) = merged.last_mut() {
                if last.base_layer == base
                    && last.layer_count == count
                    && last.base_mip + last.mip_count == m
                {
                    last.mip_count += 1;
                    continue;
                }
            }
            merged.push(Subresource {
                base_mip: m,
                mip_count: 1,
                base_layer: base,
                layer_count: count,
            });
        }
        for sub in merged {
            out.push(Barrier {
                resource: id,
                sub,
                src_stages: b.src_stages,
                src_access: b.src_access,
                dst_stages: b.dst_stages,
                dst_access: b.dst_access,
                old_layout: if is_image {
                    b.old_layout
                } else {
                    vk::ImageLayout::UNDEFINED
                },
                new_layout: if is_image {
                    b.new_layout
                } else {
                    vk::ImageLayout::UNDEFINED
                },
            });
        }
    }
    out
}

/// An estimate for tests and dumps: bytes from the format's texel size, 256-byte alignment.
pub struct EstimateOracle;

impl MemoryOracle for EstimateOracle {
    fn requirements(&self, _id: ResourceId, r: &ResourceDeclView) -> MemoryRequirements {
        let size = match r.image {
            Some(d) => {
                let texel = texel_bytes(d.format);
                let mut total = 0u64;
                for m in 0..d.mip_levels {
                    let w = u64::from((d.width >> m).max(1));
                    let h = u64::from((d.height >> m).max(1));
                    let z = u64::from((d.depth >> m).max(1));
                    total += w * h * z * texel;
                }
                total * u64::from(d.layers)
            }
            None => r.buffer_size_bytes,
        };
        MemoryRequirements {
            size_bytes: size.max(1),
            alignment: 256,
            memory_type: 0,
        }
    }
}

/// Bytes per texel of the formats voxgi uses (4 for anything unknown).
pub fn texel_bytes(format: vk::Format) -> u64 {
    match format {
        vk::Format::R8_UNORM | vk::Format::R8_UINT => 1,
        vk::Format::R16_SFLOAT | vk::Format::D16_UNORM => 2,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT | vk::Format::R32G32_UINT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        _ => 4,
    }
}

/// Bytes of every texel of `desc`, all mips and layers, tightly packed.
pub fn texel_bytes_of(desc: &crate::vk::ImageDesc) -> u64 {
    let texel = texel_bytes(desc.format);
    (0..desc.mip_levels)
        .map(|m| {
            let side = |v: u32| u64::from((v >> m).max(1));
            side(desc.width) * side(desc.height) * side(desc.depth)
        })
        .sum::<u64>()
        * texel
        * u64::from(desc.layers)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{ImageHandle, Shader, SubresourceSel};
    use crate::vk::ImageDesc;

    fn img(name: &str, w: u32) -> ImageDesc {
        ImageDesc::new_2d(name, vk::Format::R32G32B32A32_SFLOAT, w, w)
    }

    fn compile(g: &RenderGraph) -> CompiledGraph {
        g.compile(&EstimateOracle).expect("graph compiles")
    }

    #[test]
    fn present_import_discards_at_start_and_returns_to_present() {
        let mut g = RenderGraph::new();
        let src = g.create_image(img("src", 16));
        let desc = ImageDesc::new_2d("swapchain", vk::Format::B8G8R8A8_UNORM, 16, 16);
        let sc = g.import_image_desc(desc, Access::Present);
        g.add_pass("fill")
            .write(src, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("blit")
            .read(src, Access::TransferRead)
            .write(sc, Access::TransferWrite)
            .record(|_| {});
        g.add_pass("overlay")
            .write(sc, Access::ColorAttachmentReadWrite)
            .record(|_| {});
        let c = compile(&g);
        let first: Vec<_> = c.pass_barriers[1]
            .iter()
            .filter(|b| b.resource == sc.0)
            .collect();
        assert_eq!(first.len(), 1);
        // Whatever layout presentation left, the frame discards it ...
        assert_eq!(first[0].old_layout, vk::ImageLayout::UNDEFINED);
        assert_eq!(first[0].new_layout, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        // ... after the acquire semaphore's wait (a non-empty source scope chains with it).
        assert!(first[0]
            .src_stages
            .contains(vk::PipelineStageFlags2::ALL_COMMANDS));
        // The overlay keeps the blitted contents.
        let mid: Vec<_> = c.pass_barriers[2]
            .iter()
            .filter(|b| b.resource == sc.0)
            .collect();
        assert_eq!(mid[0].old_layout, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        let last: Vec<_> = c
            .final_barriers
            .iter()
            .filter(|b| b.resource == sc.0)
            .collect();
        assert_eq!(last.len(), 1);
        assert_eq!(
            last[0].old_layout,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
        );
        assert_eq!(last[0].new_layout, vk::ImageLayout::PRESENT_SRC_KHR);
        assert_eq!(last[0].src_access, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
    }

    #[test]
    fn write_then_read_makes_one_barrier_with_layout_transition() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        let out = g.import_buffer_desc("out", 4096, Access::HostRead);
        g.add_pass("fill")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("copy")
            .read(a, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        assert_eq!(c.order, vec![0, 1]);
        // fill: UNDEFINED -> GENERAL for a.
        let b0: Vec<_> = c.pass_barriers[0]
            .iter()
            .filter(|b| b.resource == a.0)
            .collect();
        assert_eq!(b0.len(), 1);
        assert_eq!(b0[0].old_layout, vk::ImageLayout::UNDEFINED);
        assert_eq!(b0[0].new_layout, vk::ImageLayout::GENERAL);
        // copy: compute write -> transfer read, GENERAL -> TRANSFER_SRC.
        let b1: Vec<_> = c.pass_barriers[1]
            .iter()
            .filter(|b| b.resource == a.0)
            .collect();
        assert_eq!(b1.len(), 1);
        assert_eq!(b1[0].src_stages, vk::PipelineStageFlags2::COMPUTE_SHADER);
        assert_eq!(b1[0].src_access, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        assert_eq!(
            b1[0].dst_stages,
            vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT
        );
        assert_eq!(b1[0].dst_access, vk::AccessFlags2::TRANSFER_READ);
        assert_eq!(b1[0].old_layout, vk::ImageLayout::GENERAL);
        assert_eq!(b1[0].new_layout, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        // The read-back buffer returns to HostRead at the end of the frame.
        assert!(c.final_barriers.iter().any(|b| b.resource == out.0
            && b.src_access == vk::AccessFlags2::TRANSFER_WRITE
            && b.dst_stages == vk::PipelineStageFlags2::HOST));
    }

    #[test]
    fn read_after_read_makes_no_barrier() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        let b = g.create_image(img("b", 16));
        let c_img = g.create_image(img("c", 16));
        let out = g.import_buffer_desc("out", 1 << 20, Access::HostRead);
        g.add_pass("fill")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("r1")
            .read(a, Access::Sampled(Shader::Compute))
            .write(b, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("r2")
            .read(a, Access::Sampled(Shader::Compute))
            .read(b, Access::Sampled(Shader::Compute))
            .write(c_img, Access::TransferWrite)
            .record(|_| {});
        g.add_pass("copy")
            .read(c_img, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        assert!(
            c.pass_barriers[1].iter().any(|x| x.resource == a.0),
            "write->read barrier"
        );
        assert!(
            !c.pass_barriers[2].iter().any(|x| x.resource == a.0),
            "read->read needs none"
        );
    }

    #[test]
    fn culled_pass_is_never_ordered() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        let unused = g.create_image(img("unused", 16));
        let out = g.import_buffer_desc("out", 1 << 20, Access::HostRead);
        g.add_pass("fill")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("dead")
            .write(unused, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("copy")
            .read(a, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        assert_eq!(c.order, vec![0, 2]);
        assert_eq!(c.culled, vec![1]);
        assert!(
            c.placements[unused.0 .0 as usize].is_none(),
            "culled transients take no memory"
        );
    }

    #[test]
    fn aliasing_lowers_peak_bytes() {
        // a: [0,1], b: [1,2], c: [2,3] -> a and c can share memory.
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 64));
        let b = g.create_image(img("b", 64));
        let c_img = g.create_image(img("c", 64));
        let out = g.import_buffer_desc("out", 1 << 20, Access::HostRead);
        g.add_pass("p0")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("p1")
            .read(a, Access::Sampled(Shader::Fragment))
            .write(b, Access::ColorAttachment)
            .record(|_| {});
        g.add_pass("p2")
            .read(b, Access::Sampled(Shader::Compute))
            .write(c_img, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("p3")
            .read(c_img, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        let size = 64 * 64 * 16;
        assert_eq!(c.memory.unaliased_bytes, 3 * size);
        assert_eq!(c.memory.peak_aliased_bytes, 2 * size);
        let pa = c.placements[a.0 .0 as usize].expect("a placed");
        let pc = c.placements[c_img.0 .0 as usize].expect("c placed");
        assert_eq!(
            (pa.arena, pa.offset),
            (pc.arena, pc.offset),
            "a and c alias"
        );
        // c's first use waits for a's last use (the fragment shader read) before reusing memory.
        let first_c = c.pass_barriers[2]
            .iter()
            .find(|x| x.resource == c_img.0)
            .expect("c barrier");
        assert!(first_c
            .src_stages
            .contains(vk::PipelineStageFlags2::FRAGMENT_SHADER));
        assert_eq!(first_c.old_layout, vk::ImageLayout::UNDEFINED);
    }

    #[test]
    fn overlapping_lifetimes_never_share_memory() {
        let mut g = RenderGraph::new();
        let ids: Vec<_> = (0..6)
            .map(|i| g.create_image(img(&format!("t{i}"), 32 << (i % 3))))
            .collect();
        let out = g.import_buffer_desc("out", 1 << 20, Access::HostRead);
        for (i, &id) in ids.iter().enumerate() {
            let mut p = g
                .add_pass(&format!("w{i}"))
                .write(id, Access::StorageWrite(Shader::Compute));
            if i > 0 {
                p = p.read(ids[i - 1], Access::Sampled(Shader::Compute));
            }
            p.record(|_| {});
        }
        g.add_pass("copy")
            .read(ids[5], Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        for i in 0..ids.len() {
            for j in i + 1..ids.len() {
                let (li, lj) = (
                    c.lifetimes[ids[i].0 .0 as usize].unwrap(),
                    c.lifetimes[ids[j].0 .0 as usize].unwrap(),
                );
                let (pi, pj) = (
                    c.placements[ids[i].0 .0 as usize].unwrap(),
                    c.placements[ids[j].0 .0 as usize].unwrap(),
                );
                let time_overlap = li.0 <= lj.1 && lj.0 <= li.1;
                let mem_overlap =
                    pi.offset < pj.offset + pj.size_bytes && pj.offset < pi.offset + pi.size_bytes;
                assert!(
                    !(time_overlap && mem_overlap),
                    "t{i} and t{j} overlap in time and memory"
                );
            }
        }
        assert!(c.memory.peak_aliased_bytes < c.memory.unaliased_bytes);
    }

    #[test]
    fn read_of_never_written_resource_is_an_error() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("phantom", 16));
        let out = g.import_buffer_desc("out", 4096, Access::HostRead);
        g.add_pass("copy")
            .read(a, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let e = g.compile(&EstimateOracle).unwrap_err();
        assert_eq!(
            e,
            GraphError::ReadBeforeWrite {
                pass: "copy".into(),
                resource: "phantom".into()
            }
        );
        assert!(e.to_string().contains("phantom") && e.to_string().contains("copy"));
    }

    #[test]
    fn declaration_errors_are_reported() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        g.add_pass("p")
            .read(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        assert!(matches!(
            g.compile(&EstimateOracle),
            Err(GraphError::ReadDeclaredAsWrite { .. })
        ));

        let mut g = RenderGraph::new();
        let b = g.create_buffer("b", 64);
        g.add_pass("p")
            .write(b, Access::ColorAttachment)
            .record(|_| {});
        assert!(matches!(
            g.compile(&EstimateOracle),
            Err(GraphError::AccessKindMismatch { .. })
        ));

        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        g.add_pass("p")
            .write_sub(
                a,
                Access::StorageWrite(Shader::Compute),
                Subresource::mip(3),
            )
            .record(|_| {});
        assert!(matches!(
            g.compile(&EstimateOracle),
            Err(GraphError::SubresourceOutOfRange { .. })
        ));

        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        g.add_pass("p")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("p")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        assert!(matches!(
            g.compile(&EstimateOracle),
            Err(GraphError::DuplicatePassName(_))
        ));

        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        g.add_pass("p")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        assert_eq!(
            g.compile(&EstimateOracle).unwrap_err(),
            GraphError::NoOutput
        );

        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        g.add_pass("w")
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("p")
            .read(a, Access::Sampled(Shader::Compute))
            .write(a, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.mark_output(a);
        assert!(matches!(
            g.compile(&EstimateOracle),
            Err(GraphError::ConflictingLayouts { .. })
        ));
    }

    #[test]
    fn mip_chain_barriers_are_per_level() {
        // The OR-mipmap pattern: level l-1 sampled, level l written, for each level.
        let mut g = RenderGraph::new();
        let desc = ImageDesc::new_2d("bits", vk::Format::R32G32B32A32_UINT, 16, 16)
            .with_mips(5)
            .with_layers(2);
        let bits = g.import_image_desc(desc, Access::Sampled(Shader::Compute));
        g.add_pass("voxelize")
            .write_sub(
                bits,
                Access::StorageWrite(Shader::Fragment),
                Subresource::mip(0),
            )
            .record(|_| {});
        for l in 1..5 {
            g.add_pass(&format!("mip{l}"))
                .read_sub(
                    bits,
                    Access::Sampled(Shader::Compute),
                    Subresource::mip(l - 1),
                )
                .write_sub(
                    bits,
                    Access::StorageWrite(Shader::Compute),
                    Subresource::mip(l),
                )
                .record(|_| {});
        }
        let c = compile(&g);
        assert_eq!(c.order.len(), 5);
        for (pos, barriers) in c.pass_barriers.iter().enumerate().skip(1) {
            let read = barriers
                .iter()
                .find(|b| b.sub.base_mip == pos as u32 - 1)
                .expect("read barrier");
            assert_eq!(read.old_layout, vk::ImageLayout::GENERAL);
            assert_eq!(read.new_layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
            assert_eq!(
                (
                    read.sub.mip_count,
                    read.sub.base_layer,
                    read.sub.layer_count
                ),
                (1, 0, 2),
                "merged layers"
            );
            let write = barriers
                .iter()
                .find(|b| b.sub.base_mip == pos as u32)
                .expect("write barrier");
            assert_eq!(write.new_layout, vk::ImageLayout::GENERAL);
        }
        // At the end, only the last level still needs to go back to SHADER_READ_ONLY.
        assert_eq!(c.final_barriers.len(), 1);
        assert_eq!(c.final_barriers[0].sub.base_mip, 4);
    }

    #[test]
    fn usage_flags_are_derived_from_accesses() {
        let mut g = RenderGraph::new();
        let a = g.create_image(img("a", 16));
        let out = g.import_buffer_desc("out", 1 << 20, Access::HostRead);
        g.add_pass("draw")
            .write(a, Access::ColorAttachment)
            .record(|_| {});
        g.add_pass("copy")
            .read(a, Access::TransferRead)
            .write(out, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        assert_eq!(
            c.image_usage[a.0 .0 as usize],
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC
        );
        let _ = SubresourceSel::whole();
    }

    #[test]
    fn direct_light_frame_aliases_below_unaliased() {
        // The default Cornell direct-light frame at 512x512 with one 1024x1024 shadow layer,
        // sizes from EstimateOracle (texel bytes, 256-byte alignment; lavapipe reports the
        // same for these images). MiB: shadow 4 (passes 0..=2), albedo 2, normal 2, depth 1
        // (1..=2), radiance 4 (2..=4), ldr 1 (3..=5).
        let mut g = RenderGraph::new();
        let hdr = vk::Format::R16G16B16A16_SFLOAT;
        let shadow = g.create_image(
            ImageDesc::new_2d("shadow maps", vk::Format::D32_SFLOAT, 1024, 1024).with_layers(1),
        );
        let albedo = g.create_image(ImageDesc::new_2d("gbuffer albedo", hdr, 512, 512));
        let normal = g.create_image(ImageDesc::new_2d("gbuffer normal", hdr, 512, 512));
        let depth = g.create_image(ImageDesc::new_2d(
            "gbuffer depth",
            vk::Format::D32_SFLOAT,
            512,
            512,
        ));
        let radiance = g.create_image(ImageDesc::new_2d(
            "radiance",
            vk::Format::R32G32B32A32_SFLOAT,
            512,
            512,
        ));
        let ldr = g.create_image(ImageDesc::new_2d(
            "ldr",
            vk::Format::R8G8B8A8_UNORM,
            512,
            512,
        ));
        let hdr_buf = g.import_buffer_desc("readback hdr", 512 * 512 * 16, Access::HostRead);
        let ldr_buf = g.import_buffer_desc("readback ldr", 512 * 512 * 4, Access::HostRead);
        g.add_pass("shadow_depth")
            .write(shadow, Access::DepthAttachment)
            .record(|_| {});
        g.add_pass("gbuffer")
            .write(albedo, Access::ColorAttachment)
            .write(normal, Access::ColorAttachment)
            .write(depth, Access::DepthAttachment)
            .record(|_| {});
        g.add_pass("deferred_direct")
            .read(shadow, Access::Sampled(Shader::Compute))
            .read(albedo, Access::Sampled(Shader::Compute))
            .read(normal, Access::Sampled(Shader::Compute))
            .read(depth, Access::Sampled(Shader::Compute))
            .write(radiance, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("tonemap")
            .read(radiance, Access::Sampled(Shader::Compute))
            .write(ldr, Access::StorageWrite(Shader::Compute))
            .record(|_| {});
        g.add_pass("readback_hdr")
            .read(radiance, Access::TransferRead)
            .write(hdr_buf, Access::TransferWrite)
            .record(|_| {});
        g.add_pass("readback_ldr")
            .read(ldr, Access::TransferRead)
            .write(ldr_buf, Access::TransferWrite)
            .record(|_| {});
        let c = compile(&g);
        let mib = 1u64 << 20;
        let m = c.memory;
        // Back to back: 4 + 2 + 2 + 1 + 4 + 1 MiB (all multiples of 256 bytes, no padding).
        assert_eq!(m.unaliased_bytes, 14 * mib);
        // At deferred_direct everything but ldr is alive: 4 + 2 + 2 + 1 + 4 = 13 MiB.
        assert_eq!(m.live_peak_bytes, 13 * mib);
        // The buddy plan (the placement before the packed plan existed) puts the shadow map
        // at [0, 4), albedo and normal at [4, 8), then splits [8, 16) for the depth at
        // [8, 9), so the 4 MiB radiance goes to [12, 16): 16 MiB, more than no aliasing.
        assert_eq!(m.buddy_bytes, Some(16 * mib));
        // Packing reaches the live peak: shadow [0, 4), radiance [4, 8), albedo [8, 10),
        // normal [10, 12), depth [12, 13), and ldr (alive with radiance only) at 0.
        assert_eq!(m.strategy, PlacementStrategy::Packed);
        assert_eq!(m.peak_aliased_bytes, 13 * mib);
        assert!(m.peak_aliased_bytes <= m.unaliased_bytes, "{}", m.summary());
        assert_eq!((m.rounding_bytes, m.waste_bytes()), (0, 0));
        let offset = |h: ImageHandle| c.placements[h.0 .0 as usize].map(|p| p.offset);
        assert_eq!(
            offset(ldr),
            offset(shadow),
            "ldr reuses the shadow map's memory"
        );
        let text = c.dump_text(&g);
        assert!(
            text.contains(&format!(
                "{} bytes aliased, {} bytes without aliasing, 0 bytes lost to rounding",
                13 * mib,
                14 * mib
            )),
            "{text}"
        );
    }

    /// Memory requirements from a table keyed by resource index.
    struct TableOracle(HashMap<u32, MemoryRequirements>);

    impl MemoryOracle for TableOracle {
        fn requirements(&self, id: ResourceId, _: &ResourceDeclView) -> MemoryRequirements {
            self.0.get(&id.0).copied().unwrap_or(MemoryRequirements {
                size_bytes: 1,
                alignment: 1,
                memory_type: 0,
            })
        }
    }

    const RANDOM_PASSES: usize = 8;

    #[derive(Clone, Debug)]
    struct RandomTransient {
        req: MemoryRequirements,
        image: bool,
        first: usize,
        len: usize,
    }

    fn random_transient() -> impl proptest::strategy::Strategy<Value = RandomTransient> {
        use proptest::prelude::*;
        let size = prop_oneof![1u64..=4096, 1u64..=1 << 24];
        let life = (0..RANDOM_PASSES, 0..RANDOM_PASSES);
        (size, 0u32..=16, 0u32..3, any::<bool>(), life).prop_map(
            |(size_bytes, align_log2, memory_type, image, (first, len))| RandomTransient {
                req: MemoryRequirements {
                    size_bytes,
                    alignment: 1 << align_log2,
                    memory_type,
                },
                image,
                first,
                len,
            },
        )
    }

    /// A graph whose passes all write one imported buffer (so none is culled and pass `k` is
    /// at position `k`); transient `i` (a storage image or buffer, its size from the oracle)
    /// is written at its first pass and read at its last. Returns the graph, each
    /// transient's resource index and its expected lifetime.
    fn random_graph(ts: &[RandomTransient]) -> (RenderGraph, Vec<usize>, Vec<(usize, usize)>) {
        let mut g = RenderGraph::new();
        let out = g.import_buffer_desc("out", 4, Access::HostRead);
        let handles: Vec<ResourceId> = ts
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let name = format!("t{i}");
                if t.image {
                    g.create_image(img(&name, 4)).into()
                } else {
                    g.create_buffer(&name, 4).into()
                }
            })
            .collect();
        let lives: Vec<(usize, usize)> = ts
            .iter()
            .map(|t| (t.first, (t.first + t.len).min(RANDOM_PASSES - 1)))
            .collect();
        for pos in 0..RANDOM_PASSES {
            let mut p = g
                .add_pass(&format!("p{pos}"))
                .write(out, Access::StorageWrite(Shader::Compute));
            for (&h, &(first, last)) in handles.iter().zip(&lives) {
                if first == pos {
                    p = p.write(h, Access::StorageWrite(Shader::Compute));
                } else if last == pos {
                    p = p.read(h, Access::StorageRead(Shader::Compute));
                }
            }
            p.record(|_| {});
        }
        let ids = handles.iter().map(|h| h.0 as usize).collect();
        (g, ids, lives)
    }

    proptest::proptest! {
        #[test]
        fn random_placements_never_collide_and_never_cost_memory(
            ts in proptest::collection::vec(random_transient(), 1..24),
        ) {
            use proptest::prelude::*;
            let (g, ids, lives) = random_graph(&ts);
            let oracle = TableOracle(
                ids.iter().zip(&ts).map(|(&i, t)| (i as u32, t.req)).collect(),
            );
            let c = g
                .compile(&oracle)
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert_eq!(c.order.len(), RANDOM_PASSES);
            let mut placed = Vec::new();
            for ((&id, t), &life) in ids.iter().zip(&ts).zip(&lives) {
                prop_assert_eq!(c.lifetimes[id], Some(life));
                let p = c.placements[id].ok_or_else(|| TestCaseError::fail("not placed"))?;
                let arena = c.arenas[p.arena];
                prop_assert_eq!(arena.memory_type, t.req.memory_type);
                prop_assert_eq!(arena.holds_buffers, !t.image, "buffers and images share an arena");
                prop_assert_eq!(p.offset % t.req.alignment, 0, "misaligned");
                prop_assert!(p.size_bytes >= t.req.size_bytes);
                prop_assert!(p.offset + p.size_bytes <= arena.size_bytes);
                placed.push((p, life));
            }
            for (a, &(pa, la)) in placed.iter().enumerate() {
                for &(pb, lb) in &placed[a + 1..] {
                    let in_time = la.0 <= lb.1 && lb.0 <= la.1;
                    let in_memory = pa.arena == pb.arena
                        && pa.offset < pb.offset + pb.size_bytes
                        && pb.offset < pa.offset + pa.size_bytes;
                    prop_assert!(!(in_time && in_memory), "{:?} and {:?} collide", pa, pb);
                }
            }

            // Independent bounds, per arena (memory type and kind). Back to back, each offset
            // is padded by less than its alignment, so sum(size) <= unaliased <=
            // sum(size + align - 1). No placement takes less than the bytes alive at one pass
            // (the live peak).
            let mut keys: Vec<(u32, bool)> = ts.iter().map(|t| (t.req.memory_type, t.image)).collect();
            keys.sort_unstable();
            keys.dedup();
            prop_assert_eq!(c.arenas.len(), keys.len());
            let (mut sizes, mut padded, mut live_peak) = (0u64, 0u64, 0u64);
            for &key in &keys {
                let of_type = || {
                    ts.iter()
                        .zip(&lives)
                        .filter(move |(t, _)| (t.req.memory_type, t.image) == key)
                };
                sizes += of_type().map(|(t, _)| t.req.size_bytes).sum::<u64>();
                padded += of_type()
                    .map(|(t, _)| t.req.size_bytes + t.req.alignment - 1)
                    .sum::<u64>();
                live_peak += (0..RANDOM_PASSES)
                    .map(|pos| {
                        of_type()
                            .filter(|(_, l)| l.0 <= pos && pos <= l.1)
                            .map(|(t, _)| t.req.size_bytes)
                            .sum::<u64>()
                    })
                    .max()
                    .unwrap_or(0);
            }
            let m = c.memory;
            prop_assert_eq!(m.transient_count, ts.len());
            prop_assert!(sizes <= m.unaliased_bytes && m.unaliased_bytes <= padded);
            prop_assert_eq!(m.live_peak_bytes, live_peak);
            prop_assert!(m.live_peak_bytes <= m.peak_aliased_bytes);
            prop_assert!(
                m.peak_aliased_bytes <= m.unaliased_bytes,
                "aliasing costs memory: {}",
                m.summary()
            );
            prop_assert_eq!(
                m.peak_aliased_bytes,
                c.arenas.iter().map(|a| a.size_bytes).sum::<u64>()
            );
            let candidates = [m.packed_bytes, m.buddy_bytes, Some(m.unaliased_bytes)];
            prop_assert_eq!(Some(m.peak_aliased_bytes), candidates.iter().flatten().min().copied());
            let reserved: u64 = placed.iter().map(|(p, _)| p.size_bytes).sum();
            prop_assert_eq!(m.rounding_bytes, reserved - ts.iter().map(|t| t.req.size_bytes).sum::<u64>());
            if m.strategy != PlacementStrategy::Buddy {
                prop_assert_eq!(m.rounding_bytes, 0);
            }
        }
    }
}
