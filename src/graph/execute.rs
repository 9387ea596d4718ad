//! Executes a compiled graph: creates the transients of each frame slot in their arenas and
//! records the frame, wrapping every pass in a debug label and a timestamp pair and
//! inserting the barriers the compile step derived.

use super::bind::BindingSource;
use super::compile::{CompiledGraph, MemoryOracle, MemoryRequirements, ResourceDeclView};
use super::{
    Access, BufferHandle, GraphError, ImageHandle, Load, Origin, RenderGraph, ResourceId,
    ResourceKind,
};
use crate::vk::{
    vk, Arena, Attachment, Bindable, Buffer, BufferDesc, Cmd, Context, Descriptor, Image,
    ImageDesc, MemoryLocation, TimestampRecorder,
};

/// GPU handles of an image as a pass sees it.
#[derive(Clone, Debug)]
pub struct GpuImage {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    /// One view per mip level when the image has several.
    pub mip_views: Vec<vk::ImageView>,
    /// One 2D view per layer when the graph takes layers of it ([`RenderGraph::layer`]).
    pub layer_views: Vec<vk::ImageView>,
    pub desc: ImageDesc,
}

impl GpuImage {
    pub fn extent_2d(&self) -> vk::Extent2D {
        vk::Extent2D {
            width: self.desc.width,
            height: self.desc.height,
        }
    }
    /// The view of one mip level (the full view when there is only one level).
    pub fn mip_view(&self, level: u32) -> vk::ImageView {
        self.mip_views
            .get(level as usize)
            .copied()
            .unwrap_or(self.view)
    }
}

/// GPU handle of a buffer as a pass sees it.
#[derive(Clone, Copy, Debug)]
pub struct GpuBuffer {
    pub raw: vk::Buffer,
    /// The window the pass sees: the whole buffer (offset 0), or its slot's window of a buffer
    /// imported per slot.
    pub offset: u64,
    pub size_bytes: u64,
}

#[derive(Clone, Debug)]
enum GpuResource {
    Image(GpuImage),
    Buffer(GpuBuffer),
}

/// What a pass's recording closure receives.
pub struct PassContext<'a> {
    pub cmd: &'a Cmd<'a>,
    /// Frame slot being recorded (0..frames in flight), for per-slot data such as uniforms.
    pub slot: usize,
    resources: &'a [Option<GpuResource>],
    decls: &'a [super::ResourceDecl],
    pass: &'a super::PassDecl,
}

impl PassContext<'_> {
    /// Panics unless this pass declared `id`: a resource used without a declaration has no
    /// barrier, so the use would race. Handles are created by the graph and passes are
    /// declared in code, so this is a programming error, caught by the first frame any test
    /// records.
    fn declared(&self, id: ResourceId) {
        // A layer view's accesses were declared on its image.
        let id = self
            .decls
            .get(id.0 as usize)
            .and_then(|d| d.layer_of)
            .map_or(id, |(image, _)| image);
        if !self.pass.accesses.iter().any(|a| a.0 == id) {
            panic!(
                "pass `{}` uses `{}`, which it did not declare: add a `.read()`, `.write()` or `.bind()` for it",
                self.pass.name,
                self.decls.get(id.0 as usize).map_or("?", |r| r.name.as_str())
            );
        }
    }

    /// The image behind a handle this pass declared.
    ///
    /// # Panics
    /// If the pass did not declare it (see `declared`), or the handle is of another graph.
    pub fn image(&self, h: ImageHandle) -> &GpuImage {
        self.declared(h.0);
        match self.resources.get(h.0 .0 as usize) {
            Some(Some(GpuResource::Image(i))) => i,
            _ => panic!("image handle {:?} does not belong to this graph", h.0),
        }
    }

    /// The buffer behind a handle this pass declared (see `image` for the panics). A buffer
    /// imported per slot is seen as the window of the slot being recorded.
    pub fn buffer(&self, h: BufferHandle) -> GpuBuffer {
        self.declared(h.0);
        match self.resources.get(h.0 .0 as usize) {
            Some(Some(GpuResource::Buffer(b))) => {
                let mut b = *b;
                if let window @ Some(_) = self.decls[h.0 .0 as usize].slot_window {
                    (b.offset, b.size_bytes) = bound_range(window, self.slot);
                }
                b
            }
            _ => panic!("buffer handle {:?} does not belong to this graph", h.0),
        }
    }

    /// The descriptor of `id` at the declared binding `b`.
    fn descriptor(&self, b: &super::bind::BindingDecl, id: ResourceId) -> Option<Descriptor> {
        Some(match self.resources.get(id.0 as usize) {
            Some(Some(GpuResource::Image(img))) => {
                let view = b.mip.map_or(img.view, |level| img.mip_view(level));
                match b.sampler {
                    Some(sampler) => Descriptor::SampledImage {
                        binding: b.binding,
                        view,
                        sampler,
                    },
                    None => Descriptor::StorageImage {
                        binding: b.binding,
                        view,
                    },
                }
            }
            Some(Some(GpuResource::Buffer(_))) => {
                let buf = self.buffer(BufferHandle(id));
                let (offset, range) = bound_range(self.decls[id.0 as usize].slot_window, self.slot);
                match b.access {
                    Access::Uniform(_) => Descriptor::UniformBuffer {
                        binding: b.binding,
                        buffer: buf.raw,
                        offset,
                        range,
                    },
                    _ => Descriptor::StorageBuffer {
                        binding: b.binding,
                        buffer: buf.raw,
                        offset,
                        range,
                    },
                }
            }
            _ => return None,
        })
    }

    /// The descriptors of the bindings this pass declared with one resource, in binding order.
    pub fn descriptors(&self) -> Vec<Descriptor> {
        let mut out: Vec<Descriptor> = self
            .pass
            .bindings
            .iter()
            .filter_map(|b| match b.source {
                BindingSource::Fixed(id) => self.descriptor(b, id),
                BindingSource::OneOf(_) => None,
            })
            .collect();
        out.sort_by_key(|d| d.binding());
        out
    }

    /// The descriptors of `choices`: for each, a binding declared with `.bind_one_of()` and
    /// the one of its resources to bind.
    ///
    /// # Panics
    /// If a binding was not declared with `.bind_one_of()`, or the resource is not one of its
    /// declared resources (it would have no barrier and was not checked against the shader).
    fn chosen(&self, choices: &[(u32, ResourceId)]) -> Vec<Descriptor> {
        choices
            .iter()
            .filter_map(|&(binding, id)| {
                let decl = self.pass.bindings.iter().find(|b| b.binding == binding);
                let allowed = decl.filter(|b| {
                    matches!(&b.source, BindingSource::OneOf(rs) if rs.contains(&id))
                });
                let Some(b) = allowed else {
                    panic!(
                        "pass `{}` binds `{}` at binding {binding}, which it did not declare there: list it in `.bind_one_of({binding}, ..)`",
                        self.pass.name,
                        self.decls.get(id.0 as usize).map_or("?", |r| r.name.as_str())
                    );
                };
                self.descriptor(b, id)
            })
            .collect()
    }

    /// Panics unless `pipeline` is the one the pass declared with `.pipeline()` (its bindings
    /// were checked against that one's shaders).
    fn check_pipeline(&self, pipeline: &impl Bindable) {
        let declared = self.pass.interface.map(|i| i as *const _);
        if declared != Some(pipeline.interface() as *const _) {
            panic!(
                "pass `{}` binds a pipeline of `{}` but declared {}: declare it with `.pipeline()`",
                self.pass.name,
                pipeline.interface().name,
                self.pass
                    .interface
                    .map_or("none".to_owned(), |i| format!("`{}`", i.name))
            );
        }
    }

    /// Binds `pipeline` and pushes the descriptors this pass declared for it.
    ///
    /// # Panics
    /// If `pipeline` is not the one the pass declared with `.pipeline()`.
    pub fn bind(&self, pipeline: &impl Bindable) {
        self.check_pipeline(pipeline);
        self.cmd.bind(pipeline, &self.descriptors());
    }

    /// [`Self::bind`], with the `.bind_one_of()` bindings filled by `choices`:
    /// `(binding, resource)` pairs, each resource one of those declared at that binding.
    ///
    /// # Panics
    /// As [`Self::bind`]; also if a choice was not declared (see `chosen`).
    pub fn bind_with<R: Into<ResourceId> + Copy>(
        &self,
        pipeline: &impl Bindable,
        choices: &[(u32, R)],
    ) {
        self.check_pipeline(pipeline);
        let mut descriptors = self.descriptors();
        descriptors.extend(self.chosen(&Self::ids(choices)));
        descriptors.sort_by_key(|d| d.binding());
        self.cmd.bind(pipeline, &descriptors);
    }

    /// Pushes only `choices` (see [`Self::bind_with`]) to the bound `pipeline`: switching
    /// one-of bindings between draws without rebinding the rest.
    pub fn push_with<R: Into<ResourceId> + Copy>(
        &self,
        pipeline: &impl Bindable,
        choices: &[(u32, R)],
    ) {
        self.check_pipeline(pipeline);
        self.cmd
            .push_descriptors(pipeline, &self.chosen(&Self::ids(choices)));
    }

    fn ids<R: Into<ResourceId> + Copy>(choices: &[(u32, R)]) -> Vec<(u32, ResourceId)> {
        choices.iter().map(|&(b, r)| (b, r.into())).collect()
    }

    /// Begins dynamic rendering into the attachments this pass declared, with their load ops,
    /// over their extent and all their layers.
    pub fn begin_rendering(&self) {
        let mut colors = Vec::new();
        let mut depth = None;
        let mut extent = vk::Extent2D::default();
        let mut layers = 1;
        for a in &self.pass.attachments {
            let img = self.image(a.image);
            extent = img.extent_2d();
            // With multiview Vulkan ignores the layer count (each view draws into its layer);
            // lavapipe clears only `layerCount` layers at the load op, so it stays the
            // attachments' layer count.
            layers = img.desc.layers.max(1);
            let clear = match a.load {
                Load::Clear(c) => Some(vk::ClearValue {
                    color: vk::ClearColorValue { float32: c },
                }),
                Load::ClearDepth(d) => Some(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: d,
                        stencil: 0,
                    },
                }),
                Load::Keep => None,
            };
            let att = Attachment {
                view: img.view,
                clear,
                read_only: a.read_only,
            };
            if a.depth {
                depth = Some(att);
            } else {
                colors.push(att);
            }
        }
        self.cmd
            .begin_rendering_layers(extent, (layers, self.pass.view_mask), &colors, depth);
    }

    /// Binds a declared buffer as vertex buffer 0.
    pub fn bind_vertex_buffer(&self, h: BufferHandle) {
        self.cmd.bind_vertex_buffer(self.buffer(h).raw);
    }

    /// Binds a declared buffer as the index buffer (u32 indices).
    pub fn bind_index_buffer(&self, h: BufferHandle) {
        self.cmd.bind_index_buffer(self.buffer(h).raw);
    }
}

/// The `(offset, range)` of a buffer that a pass recording frame slot `slot` binds: its
/// slot's window of a buffer imported per slot (`slot_window`: stride and size), the whole
/// buffer otherwise.
pub(crate) fn bound_range(slot_window: Option<(u64, u64)>, slot: usize) -> (u64, u64) {
    match slot_window {
        Some((stride, size)) => (slot as u64 * stride, size),
        None => (0, vk::WHOLE_SIZE),
    }
}

/// The transients of one frame slot. Fields drop in declaration order: the images and
/// buffers placed in the arenas are released before the arenas.
struct Slot {
    images: Vec<Image>,
    buffers: Vec<Buffer>,
    resources: Vec<Option<GpuResource>>,
    arenas: Vec<Arena>,
}

/// A compiled graph with its GPU resources, recorded once per frame. Dropping it releases
/// the transients once the frames that used them completed.
pub struct GraphExecutor {
    graph: RenderGraph,
    compiled: CompiledGraph,
    slots: Vec<Slot>,
    /// The cached images ([`RenderGraph::create_cached_image`]) by resource index, shared by
    /// every slot. After `slots`: the slots only copy their handles.
    cached: Vec<(usize, Image)>,
}

/// Memory requirements from the device, without creating anything.
struct DeviceOracle<'a> {
    ctx: &'a Context,
    error: std::cell::RefCell<Option<String>>,
    /// Never report less than the texels (buffers: the bytes) asked for: a driver may wrap
    /// the size of an image beyond what it can create at 32 bits; memory checks use this.
    at_least_texels: bool,
}

impl MemoryOracle for DeviceOracle<'_> {
    fn requirements(&self, _id: ResourceId, r: &ResourceDeclView) -> MemoryRequirements {
        let mut req = match r.image {
            Some(desc) => self.ctx.image_requirements(desc),
            None => self
                .ctx
                .buffer_requirements(r.buffer_size_bytes, r.buffer_usage),
        };
        if self.at_least_texels {
            let floor = match r.image {
                Some(desc) => super::texel_bytes_of(desc),
                None => r.buffer_size_bytes,
            };
            req.size = req.size.max(floor);
        }
        let memory_type = self
            .ctx
            .device_local_type(req.memory_type_bits)
            .unwrap_or_else(|| {
                *self.error.borrow_mut() =
                    Some(format!("no memory type fits transient `{}`", r.name));
                0
            });
        MemoryRequirements {
            size_bytes: req.size,
            alignment: req.alignment,
            memory_type,
        }
    }
}

/// Compiles `graph` against the device without creating anything: the arenas its transients
/// would take in each frame slot (what [`GraphExecutor::new`] allocates per slot).
pub fn transient_arenas(
    ctx: &Context,
    graph: &RenderGraph,
) -> Result<Vec<super::compile::Arena>, GraphError> {
    let oracle = DeviceOracle {
        ctx,
        error: Default::default(),
        at_least_texels: true,
    };
    let compiled = graph.compile(&oracle)?;
    if let Some(e) = oracle.error.borrow_mut().take() {
        return Err(GraphError::Gpu(e));
    }
    Ok(compiled.arenas)
}

/// The cached images ([`RenderGraph::create_cached_image`]) that [`GraphExecutor::new`]
/// would create for `graph` (once, not per slot): their names and device sizes in bytes, for
/// checking memory before anything is allocated.
pub fn cached_image_sizes(
    ctx: &Context,
    graph: &RenderGraph,
) -> Result<Vec<(String, u64)>, GraphError> {
    let compiled = graph.compile(&super::compile::EstimateOracle)?;
    let mut used = vec![false; graph.resources.len()];
    for &p in &compiled.order {
        for &(id, ..) in &graph.passes[p].accesses {
            used[id.0 as usize] = true;
        }
    }
    Ok(graph
        .resources
        .iter()
        .enumerate()
        .filter(|&(i, r)| !r.caches.is_empty() && used[i])
        .filter_map(|(i, r)| match &r.kind {
            ResourceKind::Image(desc) => {
                let mut d = desc.clone();
                d.usage |= compiled.image_usage[i];
                let bytes = ctx
                    .image_requirements(&d)
                    .size
                    .max(super::texel_bytes_of(&d));
                Some((r.name.clone(), bytes))
            }
            ResourceKind::Buffer { .. } => None,
        })
        .collect())
}

impl GraphExecutor {
    /// Compiles `graph` against the device and creates its transients for `frames_in_flight`
    /// slots (each slot has its own arenas, so frames in flight never share transients).
    pub fn new(
        ctx: &Context,
        graph: RenderGraph,
        frames_in_flight: usize,
    ) -> Result<Self, GraphError> {
        let oracle = DeviceOracle {
            ctx,
            error: Default::default(),
            at_least_texels: false,
        };
        let compiled = graph.compile(&oracle)?;
        if let Some(e) = oracle.error.borrow_mut().take() {
            return Err(GraphError::Gpu(e));
        }
        let mut exec = Self {
            graph,
            compiled,
            slots: Vec::new(),
            cached: Vec::new(),
        };
        exec.cached = exec
            .create_cached(ctx)
            .map_err(|e| GraphError::Gpu(e.to_string()))?;
        for s in 0..frames_in_flight.max(1) {
            let slot = exec
                .create_slot(ctx, s)
                .map_err(|e| GraphError::Gpu(e.to_string()))?;
            exec.slots.push(slot);
        }
        Ok(exec)
    }

    /// Creates the cached images that a live pass uses, in their resting layout, and
    /// invalidates their caches: new images hold nothing yet.
    fn create_cached(&self, ctx: &Context) -> Result<Vec<(usize, Image)>, crate::vk::VkError> {
        let mut used = vec![false; self.graph.resources.len()];
        for &p in &self.compiled.order {
            for &(id, ..) in &self.graph.passes[p].accesses {
                used[id.0 as usize] = true;
            }
        }
        let mut images = Vec::new();
        for (i, r) in self.graph.resources.iter().enumerate() {
            let (ResourceKind::Image(desc), Origin::Imported { state, .. }) = (&r.kind, &r.origin)
            else {
                continue;
            };
            if r.caches.is_empty() {
                continue;
            }
            for cache in &r.caches {
                cache.invalidate();
            }
            if !used[i] {
                continue;
            }
            let mut d = desc.clone();
            d.usage |= self.compiled.image_usage[i];
            images.push((i, ctx.create_image_in_layout(&d, state.info().layout)?));
        }
        Ok(images)
    }

    fn create_slot(&self, ctx: &Context, index: usize) -> Result<Slot, crate::vk::VkError> {
        let mut slot = Slot {
            arenas: Vec::new(),
            images: Vec::new(),
            buffers: Vec::new(),
            resources: vec![None; self.graph.resources.len()],
        };
        for (i, a) in self.compiled.arenas.iter().enumerate() {
            slot.arenas.push(ctx.allocate_arena(
                a.memory_type,
                a.size_bytes,
                &format!("graph arena {i} (slot {index})"),
            )?);
        }
        for (i, r) in self.graph.resources.iter().enumerate() {
            let gpu = match (&r.origin, &r.kind) {
                (
                    Origin::Imported {
                        image: Some(img), ..
                    },
                    ResourceKind::Image(desc),
                ) => Some(GpuResource::Image(GpuImage {
                    raw: img.raw,
                    view: img.view,
                    mip_views: img.mip_views.clone(),
                    layer_views: img.layer_views.clone(),
                    desc: desc.clone(),
                })),
                (
                    Origin::Imported {
                        buffer: Some(b), ..
                    },
                    ResourceKind::Buffer { size_bytes, .. },
                ) => Some(GpuResource::Buffer(GpuBuffer {
                    raw: *b,
                    offset: 0,
                    size_bytes: *size_bytes,
                })),
                (Origin::Transient, kind) => {
                    let Some(place) = self.compiled.placements[i] else {
                        continue;
                    };
                    let memory = &slot.arenas[place.arena];
                    let created = match kind {
                        ResourceKind::Image(desc) => {
                            let mut d = desc.clone();
                            d.usage |= self.compiled.image_usage[i];
                            ctx.create_image_in(&d, memory, place.offset).map(|img| {
                                let g = GpuImage {
                                    raw: img.raw,
                                    view: img.view,
                                    mip_views: img.mip_views.clone(),
                                    layer_views: img.layer_views.clone(),
                                    desc: d,
                                };
                                slot.images.push(img);
                                GpuResource::Image(g)
                            })
                        }
                        ResourceKind::Buffer { size_bytes, .. } => {
                            let desc = BufferDesc {
                                name: r.name.clone(),
                                size_bytes: *size_bytes,
                                usage: self.compiled.buffer_usage[i],
                                location: MemoryLocation::GpuOnly,
                            };
                            ctx.create_buffer_in(&desc, memory, place.offset).map(|b| {
                                let g = GpuBuffer {
                                    raw: b.raw,
                                    offset: 0,
                                    size_bytes: *size_bytes,
                                };
                                slot.buffers.push(b);
                                GpuResource::Buffer(g)
                            })
                        }
                    };
                    Some(created?)
                }
                // Cached: the executor's image, the same in every slot.
                (Origin::Imported { .. }, ResourceKind::Image(desc)) if !r.caches.is_empty() => {
                    self.cached
                        .iter()
                        .find(|(index, _)| *index == i)
                        .map(|(_, img)| {
                            GpuResource::Image(GpuImage {
                                raw: img.raw,
                                view: img.view,
                                mip_views: img.mip_views.clone(),
                                layer_views: img.layer_views.clone(),
                                desc: desc.clone(),
                            })
                        })
                }
                // Imported by description only: compile-only graphs cannot execute.
                _ => None,
            };
            slot.resources[i] = gpu;
        }
        // Layer views: their image's view of that layer (images come before their views).
        for (i, r) in self.graph.resources.iter().enumerate() {
            let (Some((image, layer)), ResourceKind::Image(desc)) = (r.layer_of, &r.kind) else {
                continue;
            };
            slot.resources[i] = match &slot.resources[image.0 as usize] {
                Some(GpuResource::Image(img)) => img.layer_views.get(layer as usize).map(|&view| {
                    GpuResource::Image(GpuImage {
                        raw: img.raw,
                        view,
                        mip_views: Vec::new(),
                        layer_views: Vec::new(),
                        desc: desc.clone(),
                    })
                }),
                _ => None,
            };
        }
        Ok(slot)
    }

    /// Points an imported image at another image of the same format and size, for every frame
    /// slot: the swapchain image acquired this frame. Barriers stay as compiled (they depend on
    /// the declared accesses only).
    pub fn rebind_image(&mut self, handle: ImageHandle, image: &Image) -> Result<(), GraphError> {
        let index = handle.0 .0 as usize;
        let Some(r) = self.graph.resources.get_mut(index) else {
            return Err(GraphError::Gpu(format!(
                "rebind: image handle {:?} is not in this graph",
                handle.0
            )));
        };
        let fits = match &r.kind {
            ResourceKind::Image(d) => {
                d.format == image.desc.format
                    && (d.width, d.height, d.depth, d.layers, d.mip_levels)
                        == (
                            image.desc.width,
                            image.desc.height,
                            image.desc.depth,
                            image.desc.layers,
                            image.desc.mip_levels,
                        )
            }
            ResourceKind::Buffer { .. } => false,
        };
        let Origin::Imported {
            image: Some(imported),
            ..
        } = &mut r.origin
        else {
            return Err(GraphError::Gpu(format!(
                "rebind: `{}` is not an imported image",
                r.name
            )));
        };
        if !fits {
            return Err(GraphError::Gpu(format!(
                "rebind: `{}` cannot take `{}`, whose format or size differs: build a new graph",
                r.name, image.desc.name
            )));
        }
        imported.raw = image.raw;
        imported.view = image.view;
        imported.mip_views = image.mip_views.clone();
        imported.layer_views = image.layer_views.clone();
        for slot in &mut self.slots {
            if let Some(GpuResource::Image(g)) = &mut slot.resources[index] {
                g.raw = image.raw;
                g.view = image.view;
                g.mip_views = image.mip_views.clone();
            }
        }
        Ok(())
    }

    pub fn compiled(&self) -> &CompiledGraph {
        &self.compiled
    }

    pub fn graph(&self) -> &RenderGraph {
        &self.graph
    }

    /// Records the frame into `cmd` using the transients of `slot`.
    pub fn record(&self, cmd: &Cmd, slot: usize, timestamps: &mut TimestampRecorder) {
        let Some(s) = self.slots.get(slot % self.slots.len().max(1)) else {
            return;
        };
        for (pos, &p) in self.compiled.order.iter().enumerate() {
            let pass = &self.graph.passes[p];
            cmd.begin_label(&pass.name, label_color(p));
            let ts = timestamps.begin(cmd, &pass.name);
            self.emit(cmd, s, &self.compiled.pass_barriers[pos]);
            let runs = pass.condition.as_ref().is_none_or(|c| c.is_open(slot));
            if let Some(f) = pass.record.as_ref().filter(|_| runs) {
                f(&PassContext {
                    cmd,
                    slot,
                    resources: &s.resources,
                    decls: &self.graph.resources,
                    pass,
                });
            }
            timestamps.end(cmd, ts);
            cmd.end_label();
        }
        self.emit(cmd, s, &self.compiled.final_barriers);
    }

    fn emit(&self, cmd: &Cmd, slot: &Slot, barriers: &[super::Barrier]) {
        let mut images = Vec::new();
        let mut buffers = Vec::new();
        for b in barriers {
            match &slot.resources[b.resource.0 as usize] {
                Some(GpuResource::Image(img)) => images.push(
                    vk::ImageMemoryBarrier2::default()
                        .src_stage_mask(b.src_stages)
                        .src_access_mask(b.src_access)
                        .dst_stage_mask(b.dst_stages)
                        .dst_access_mask(b.dst_access)
                        .old_layout(b.old_layout)
                        .new_layout(b.new_layout)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .image(img.raw)
                        .subresource_range(vk::ImageSubresourceRange {
                            aspect_mask: img.desc.aspect(),
                            base_mip_level: b.sub.base_mip,
                            level_count: b.sub.mip_count,
                            base_array_layer: b.sub.base_layer,
                            layer_count: b.sub.layer_count,
                        }),
                ),
                Some(GpuResource::Buffer(buf)) => buffers.push(
                    vk::BufferMemoryBarrier2::default()
                        .src_stage_mask(b.src_stages)
                        .src_access_mask(b.src_access)
                        .dst_stage_mask(b.dst_stages)
                        .dst_access_mask(b.dst_access)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .buffer(buf.raw)
                        .offset(0)
                        .size(vk::WHOLE_SIZE),
                ),
                None => {}
            }
        }
        cmd.barriers(&images, &buffers);
    }
}

/// A stable per-pass color for debug labels (RenderDoc groups).
fn label_color(index: usize) -> [f32; 4] {
    let h = (index as f32 * 0.618_034).fract();
    [
        0.5 + 0.5 * (std::f32::consts::TAU * h).cos(),
        0.5 + 0.5 * (std::f32::consts::TAU * (h + 0.33)).cos(),
        0.5 + 0.5 * (std::f32::consts::TAU * (h + 0.67)).cos(),
        1.0,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each frame slot binds its own window of a buffer imported per slot (the voxelizer's
    /// per-slot triangles: slot s at s·stride), any other buffer whole.
    #[test]
    fn per_slot_buffers_bind_their_slot_window() {
        let mut g = RenderGraph::new();
        let read = Access::StorageRead(crate::graph::Shader::Compute);
        let whole = g.import_buffer_desc("whole", 1024, read);
        let per_slot = g.import_buffer_desc("per slot", 1024, read);
        g.resources[per_slot.0 .0 as usize].slot_window = Some((512, 480));
        let window =
            |h: BufferHandle, slot| bound_range(g.resources[h.0 .0 as usize].slot_window, slot);
        assert_eq!(window(per_slot, 0), (0, 480));
        assert_eq!(window(per_slot, 1), (512, 480));
        assert_eq!(window(whole, 1), (0, vk::WHOLE_SIZE));
    }
}
