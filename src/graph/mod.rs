//! The render graph: declare passes and resources, compile, execute.
//!
//! A frame is a list of passes. Each pass declares every resource it touches and how
//! ([`Access`]), then hands over one closure that records its commands. [`RenderGraph::compile`]
//! is plain Rust (no GPU): it validates the declarations, culls passes that feed no output,
//! computes transient lifetimes, places transients in buddy-allocated arenas (aliasing those
//! whose lifetimes do not overlap) and derives every barrier and layout transition. The
//! [`GraphExecutor`] creates the transients on the GPU and records the frame, wrapping each
//! pass in a debug label and a timestamp pair. No pass records a barrier.
//!
//! ```no_run
//! # use voxgi::graph::*;
//! # use voxgi::vk::{vk, ImageDesc};
//! let mut g = RenderGraph::new();
//! let img = g.create_image(ImageDesc::new_2d("gradient", vk::Format::R8G8B8A8_UNORM, 64, 64));
//! let out = g.import_buffer_desc("readback", 64 * 64 * 4, Access::HostRead);
//! g.add_pass("demo_gradient")
//!     .write(img, Access::StorageWrite(Shader::Compute))
//!     .record(move |_ctx| { /* bind, dispatch */ });
//! g.add_pass("readback")
//!     .read(img, Access::TransferRead)
//!     .write(out, Access::TransferWrite)
//!     .record(move |_ctx| { /* copy */ });
//! ```
//! Imported resources are persistent: each frame starts and ends with them in the state they
//! were imported with, so one compiled graph serves every frame.

mod access;
mod bind;
pub mod buddy;
mod cache;
mod compile;
mod dump;
mod execute;
mod oneshot;

pub use access::{Access, AccessInfo, Shader, Subresource, SubresourceSel};
pub use bind::Load;
pub use cache::{Cache, KeyHasher};
pub use compile::{
    texel_bytes, texel_bytes_of, Arena, Barrier, CompiledGraph, EstimateOracle, MemoryOracle,
    MemoryRequirements, MemoryStats, Placement, ResourceDeclView,
};
pub use execute::{
    cached_image_sizes, transient_arenas, GpuBuffer, GpuImage, GraphExecutor, PassContext,
};
pub use oneshot::{add_readback, readback_buffer, run_frames, run_once, OneShotError};

use crate::vk::{vk, Bindable, Buffer, Image, ImageDesc, ShaderInterface};

/// Errors of graph declaration and compilation. Each names the pass and resource.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum GraphError {
    #[error("pass `{pass}` reads `{resource}`, but no earlier pass writes it and it is not imported: add the pass that produces it before `{pass}`, or import it")]
    ReadBeforeWrite { pass: String, resource: String },
    #[error("pass `{pass}` declares {access:?} on `{resource}`, which is not valid for a {kind}")]
    AccessKindMismatch {
        pass: String,
        resource: String,
        access: Access,
        kind: &'static str,
    },
    #[error(
        "pass `{pass}` declares `{resource}` with `.read()` but {access:?} writes: use `.write()`"
    )]
    ReadDeclaredAsWrite {
        pass: String,
        resource: String,
        access: Access,
    },
    #[error("pass `{pass}` accesses mips {mips:?} / layers {layers:?} of `{resource}`, which has {mip_levels} mips and {layer_count} layers")]
    SubresourceOutOfRange {
        pass: String,
        resource: String,
        mips: (u32, u32),
        layers: (u32, u32),
        mip_levels: u32,
        layer_count: u32,
    },
    #[error("pass `{pass}` uses the same subresource of `{resource}` in two layouts ({a:?} and {b:?}); split the pass or use distinct mips/layers")]
    ConflictingLayouts {
        pass: String,
        resource: String,
        a: Access,
        b: Access,
    },
    #[error("two passes are named `{0}`: pass names must be unique (they key the timings)")]
    DuplicatePassName(String),
    #[error("the graph has no output: import a resource or mark one with `mark_output`, otherwise every pass is culled")]
    NoOutput,
    #[error(transparent)]
    Binding(Box<BindingError>),
    #[error("transient `{resource}` cannot be placed: {reason}")]
    Placement { resource: String, reason: String },
    #[error("GPU error while building the graph: {0}")]
    Gpu(String),
}

/// A pass's declared bindings or attachments disagree with its pipeline's shaders or each
/// other (boxed into [`GraphError::Binding`]: the messages carry several names).
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum BindingError {
    #[error("pass `{pass}` binds nothing at binding {binding}, where `{shader}` declares `{name}` ({kind}): bind a resource there with `.bind*()` (`.bind_one_of()` if the record closure picks one per dispatch or draw)")]
    UnboundBinding {
        pass: String,
        shader: String,
        binding: u32,
        name: String,
        kind: &'static str,
    },
    #[error("pass `{pass}` binds `{resource}` at binding {binding}, which `{shader}` does not declare: fix the binding number or remove the binding")]
    UnknownBinding {
        pass: String,
        shader: String,
        binding: u32,
        resource: String,
    },
    #[error("pass `{pass}` binds `{resource}` at binding {binding} as a {declared}, but `{shader}` declares `{name}` there as a {expected}")]
    BindingKindMismatch {
        pass: String,
        shader: String,
        binding: u32,
        resource: String,
        name: String,
        declared: &'static str,
        expected: &'static str,
    },
    #[error("pass `{pass}` declares `{resource}` at binding {binding} for the {declared} stage, but `{shader}` uses `{name}` in the {used} stage: declare the access for every stage that uses it, or the barrier will not cover them")]
    BindingStageMismatch {
        pass: String,
        shader: String,
        binding: u32,
        resource: String,
        name: String,
        declared: String,
        used: String,
    },
    #[error("pass `{pass}` declares a read of `{resource}` at binding {binding}, but `{shader}` does not declare `{name}` readonly, so it may write: add `readonly` in the shader, or declare a write")]
    ReadOfWritableBinding {
        pass: String,
        shader: String,
        binding: u32,
        resource: String,
        name: String,
    },
    #[error("pass `{pass}` declares a write of `{resource}` at binding {binding}, but `{shader}` declares `{name}` readonly: declare a read")]
    WriteOfReadonlyBinding {
        pass: String,
        shader: String,
        binding: u32,
        resource: String,
        name: String,
    },
    #[error("pass `{pass}` declares binding {binding} as one of no resources: list at least one in `.bind_one_of()`, or do not declare the pass")]
    EmptyChoice { pass: String, binding: u32 },
    #[error("pass `{pass}` binds binding {binding} twice")]
    DuplicateBinding { pass: String, binding: u32 },
    #[error("pass `{pass}` declares bindings but no pipeline: call `.pipeline(&p)` so its bindings can be checked against the shader")]
    BindingsWithoutPipeline { pass: String },
    #[error("pass `{pass}` declares attachments of different sizes (`{a}` and `{b}`): render to attachments of one size")]
    AttachmentSizeMismatch { pass: String, a: String, b: String },
}

/// A resource in the graph; typed handles wrap it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ResourceId(pub u32);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageHandle(pub ResourceId);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferHandle(pub ResourceId);

impl From<ImageHandle> for ResourceId {
    fn from(h: ImageHandle) -> Self {
        h.0
    }
}
impl From<BufferHandle> for ResourceId {
    fn from(h: BufferHandle) -> Self {
        h.0
    }
}

/// GPU handles of an imported image (copied; the owner keeps the `Image`).
#[derive(Clone, Debug)]
pub(crate) struct ImportedImage {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub mip_views: Vec<vk::ImageView>,
    pub layer_views: Vec<vk::ImageView>,
}

#[derive(Clone, Debug)]
pub(crate) enum ResourceKind {
    Image(ImageDesc),
    Buffer {
        size_bytes: u64,
        usage: vk::BufferUsageFlags,
    },
}

#[derive(Clone, Debug)]
pub(crate) enum Origin {
    Transient,
    /// Persistent; valid in `state` at the start and the end of every frame.
    Imported {
        state: Access,
        image: Option<ImportedImage>,
        buffer: Option<vk::Buffer>,
    },
}

#[derive(Clone, Debug)]
pub(crate) struct ResourceDecl {
    pub name: String,
    pub kind: ResourceKind,
    pub origin: Origin,
    pub output: bool,
    /// For a buffer holding one window per frame slot: (stride, size) in bytes. A pass that
    /// binds it sees the window of the slot it records.
    pub slot_window: Option<(u64, u64)>,
    /// A view of one layer of another image ([`RenderGraph::layer`]): (image, layer). It owns
    /// no memory; every access declared on it is an access of that layer of the image.
    pub layer_of: Option<(ResourceId, u32)>,
    /// A persistent image the executor owns and keeps while these validities hold
    /// ([`RenderGraph::create_cached_image`]; empty: not cached).
    pub caches: Vec<std::sync::Arc<Cache>>,
    /// A cached image that is a history ([`RenderGraph::create_history_image`]): a frame
    /// writes it for the next one, so its writers live while a live pass reads it, even
    /// earlier in the frame.
    pub history: bool,
}

impl ResourceDecl {
    pub(crate) fn mips_layers(&self) -> (u32, u32) {
        match &self.kind {
            ResourceKind::Image(d) => (d.mip_levels, d.layers),
            ResourceKind::Buffer { .. } => (1, 1),
        }
    }
    pub(crate) fn is_image(&self) -> bool {
        matches!(self.kind, ResourceKind::Image(_))
    }
    pub(crate) fn is_transient(&self) -> bool {
        matches!(self.origin, Origin::Transient)
    }
}

/// The closure a pass records with.
pub type RecordFn = Box<dyn Fn(&PassContext) + 'static>;

/// Per frame slot, whether the passes that declare it (`.when()`) record: a chain that has
/// nothing new to do in a frame (voxelization while nothing moved) is skipped there, and its
/// outputs keep what an earlier frame wrote (an imported image keeps its contents across
/// layout changes). The executor still emits the passes' barriers and timestamps, so the
/// compiled frame stays one frame for every slot; the host opens or closes the slot before
/// recording it.
#[derive(Debug)]
pub struct SlotCondition {
    open: [std::sync::atomic::AtomicBool; crate::vk::MAX_FRAMES_IN_FLIGHT],
}

impl Default for SlotCondition {
    fn default() -> Self {
        Self {
            open: std::array::from_fn(|_| std::sync::atomic::AtomicBool::new(true)),
        }
    }
}

impl SlotCondition {
    pub fn set(&self, slot: usize, open: bool) {
        if let Some(g) = self.open.get(slot) {
            g.store(open, std::sync::atomic::Ordering::Release);
        }
    }

    pub fn is_open(&self, slot: usize) -> bool {
        self.open
            .get(slot)
            .is_none_or(|g| g.load(std::sync::atomic::Ordering::Acquire))
    }
}

pub(crate) struct PassDecl {
    pub name: String,
    /// (resource, access, selection, declared with `.read()`)
    pub accesses: Vec<(ResourceId, Access, SubresourceSel, bool)>,
    pub record: Option<RecordFn>,
    /// The shaders of the pipeline the pass binds, when it declares its bindings.
    pub interface: Option<&'static ShaderInterface>,
    pub bindings: Vec<bind::BindingDecl>,
    /// Color attachments in location order, then at most one depth attachment.
    pub attachments: Vec<bind::AttachmentDecl>,
    /// Multiview: the views one draw renders, one bit per attachment layer (0: one view).
    pub view_mask: u32,
    /// Records only in the slots this leaves open (`None`: always).
    pub condition: Option<std::sync::Arc<SlotCondition>>,
    /// The cache whose images the pass produces ([`PassBuilder::cached`]; its condition is
    /// `condition`).
    pub cache: Option<std::sync::Arc<Cache>>,
}

/// The declared frame.
#[derive(Default)]
pub struct RenderGraph {
    pub(crate) resources: Vec<ResourceDecl>,
    pub(crate) passes: Vec<PassDecl>,
    /// Appended to the name of every pass added ([`RenderGraph::set_pass_suffix`]).
    pass_suffix: String,
}

impl RenderGraph {
    pub fn new() -> Self {
        Self::default()
    }

    fn push(&mut self, name: &str, kind: ResourceKind, origin: Origin) -> ResourceId {
        self.resources.push(ResourceDecl {
            name: name.to_owned(),
            kind,
            origin,
            output: false,
            slot_window: None,
            layer_of: None,
            caches: Vec::new(),
            history: false,
        });
        ResourceId(self.resources.len() as u32 - 1)
    }

    /// Layer `layer` of the array image `image` as an image of its own (one layer, viewed as
    /// 2D): passes declare and bind it like any image, and the graph turns each access into
    /// an access of that layer of `image`, so barriers, lifetimes and culling follow the
    /// layer. A stereo frame renders both eyes into two-layer images in one multiview pass,
    /// then runs each eye's screen-space passes on its layer.
    ///
    /// # Panics
    /// If `image` is not an image of this graph with more than `layer` layers (a programming
    /// error: handles and layer counts come from code).
    pub fn layer(&mut self, image: ImageHandle, layer: u32) -> ImageHandle {
        let parent = &mut self.resources[image.0 .0 as usize];
        let ResourceKind::Image(desc) = &mut parent.kind else {
            panic!("layer of `{}`, which is not an image", parent.name);
        };
        assert!(
            layer < desc.layers && desc.depth == 1,
            "layer {layer} of `{}`, which has {} layer(s)",
            parent.name,
            desc.layers
        );
        desc.layer_views = true;
        let mut view = desc.clone();
        view.name = format!("{}[{layer}]", desc.name);
        view.layers = 1;
        view.array = false;
        view.layer_views = false;
        let origin = Origin::Transient;
        let id = self.push(&view.name.clone(), ResourceKind::Image(view), origin);
        self.resources[id.0 as usize].layer_of = Some((image.0, layer));
        ImageHandle(id)
    }

    /// A transient image; its usage flags are derived from the declared accesses.
    pub fn create_image(&mut self, desc: ImageDesc) -> ImageHandle {
        let name = desc.name.clone();
        ImageHandle(self.push(&name, ResourceKind::Image(desc), Origin::Transient))
    }

    /// A transient buffer; its usage flags are derived from the declared accesses.
    pub fn create_buffer(&mut self, name: &str, size_bytes: u64) -> BufferHandle {
        BufferHandle(self.push(
            name,
            ResourceKind::Buffer {
                size_bytes,
                usage: vk::BufferUsageFlags::empty(),
            },
            Origin::Transient,
        ))
    }

    /// Imports a persistent image that is in `state` before and after each frame.
    pub fn import_image(&mut self, image: &Image, state: Access) -> ImageHandle {
        let imported = ImportedImage {
            raw: image.raw,
            view: image.view,
            mip_views: image.mip_views.clone(),
            layer_views: image.layer_views.clone(),
        };
        ImageHandle(self.push(
            &image.desc.name,
            ResourceKind::Image(image.desc.clone()),
            Origin::Imported {
                state,
                image: Some(imported),
                buffer: None,
            },
        ))
    }

    /// Imports a persistent buffer that is in `state` before and after each frame.
    pub fn import_buffer(&mut self, buffer: &Buffer, state: Access) -> BufferHandle {
        BufferHandle(self.push(
            &buffer.desc.name,
            ResourceKind::Buffer {
                size_bytes: buffer.desc.size_bytes,
                usage: buffer.desc.usage,
            },
            Origin::Imported {
                state,
                image: None,
                buffer: Some(buffer.raw),
            },
        ))
    }

    /// Imports a persistent buffer that holds one `size_bytes` window per frame slot,
    /// `stride_bytes` apart (per-frame constants the host writes while other slots are in
    /// flight). A pass binding it sees its slot's window.
    pub fn import_buffer_per_slot(
        &mut self,
        buffer: &Buffer,
        stride_bytes: u64,
        size_bytes: u64,
        state: Access,
    ) -> BufferHandle {
        let h = self.import_buffer(buffer, state);
        self.resources[h.0 .0 as usize].slot_window = Some((stride_bytes, size_bytes));
        h
    }

    /// A persistent image that the graph's executor creates and owns (one for every frame
    /// slot, never aliased), in `state` before and after each frame like an imported one,
    /// whose contents stay valid while `caches` hold: the passes that write it declare
    /// [`PassBuilder::cached`] with one of them (one cache for the whole image, or one per
    /// part, such as a layer a pass of its own writes; see `graph/cache.rs`).
    pub fn create_cached_image(
        &mut self,
        desc: ImageDesc,
        state: Access,
        caches: &[std::sync::Arc<Cache>],
    ) -> ImageHandle {
        let h = self.import_image_desc(desc, state);
        self.resources[h.0 .0 as usize].caches = caches.to_vec();
        h
    }

    /// A history: a persistent image the executor owns, like a cached one, that a frame's
    /// passes read (what the previous frame left) and then write (for the next frame).
    /// `validity` says whether it holds a previous frame: the executor invalidates it when it
    /// creates the image (a new graph, a resize), the owner when the history no longer
    /// applies (the lights changed), and the owner's [`Cache::validate`] with a fixed key
    /// before each frame tells the first frame after either (see `gi/gi_temporal.rs`). The
    /// passes that write it live while a live pass reads it.
    pub fn create_history_image(
        &mut self,
        desc: ImageDesc,
        state: Access,
        validity: &std::sync::Arc<Cache>,
    ) -> ImageHandle {
        let h = self.create_cached_image(desc, state, std::slice::from_ref(validity));
        self.resources[h.0 .0 as usize].history = true;
        h
    }

    /// Imports an image by description only (no GPU handle): for compiling without a GPU.
    pub fn import_image_desc(&mut self, desc: ImageDesc, state: Access) -> ImageHandle {
        let name = desc.name.clone();
        ImageHandle(self.push(
            &name,
            ResourceKind::Image(desc),
            Origin::Imported {
                state,
                image: None,
                buffer: None,
            },
        ))
    }

    /// Imports a buffer by description only (no GPU handle): for compiling without a GPU.
    pub fn import_buffer_desc(
        &mut self,
        name: &str,
        size_bytes: u64,
        state: Access,
    ) -> BufferHandle {
        BufferHandle(self.push(
            name,
            ResourceKind::Buffer {
                size_bytes,
                usage: vk::BufferUsageFlags::empty(),
            },
            Origin::Imported {
                state,
                image: None,
                buffer: None,
            },
        ))
    }

    /// Keeps the passes that produce `resource` even if nothing reads it in this graph.
    pub fn mark_output(&mut self, resource: impl Into<ResourceId>) {
        let id = resource.into();
        if let Some(r) = self.resources.get_mut(id.0 as usize) {
            r.output = true;
        }
    }

    /// Appends `suffix` to the names of the passes added from now on: a second copy of a
    /// chain of passes in the same frame (a one-frame stereo frame's right eye, `[R]`) keeps
    /// pass names unique and recognizable in timings.
    pub fn set_pass_suffix(&mut self, suffix: &str) {
        self.pass_suffix = suffix.to_owned();
    }

    pub fn add_pass(&mut self, name: &str) -> PassBuilder<'_> {
        self.passes.push(PassDecl {
            name: format!("{name}{}", self.pass_suffix),
            accesses: Vec::new(),
            record: None,
            interface: None,
            bindings: Vec::new(),
            attachments: Vec::new(),
            condition: None,
            cache: None,
            view_mask: 0,
        });
        let index = self.passes.len() - 1;
        PassBuilder { graph: self, index }
    }

    pub fn pass_names(&self) -> impl Iterator<Item = &str> {
        self.passes.iter().map(|p| p.name.as_str())
    }

    pub fn resource_name(&self, id: impl Into<ResourceId>) -> &str {
        self.resources
            .get(id.into().0 as usize)
            .map(|r| r.name.as_str())
            .unwrap_or("?")
    }
}

/// Declares one pass's accesses, then its recording closure.
pub struct PassBuilder<'g> {
    graph: &'g mut RenderGraph,
    index: usize,
}

impl PassBuilder<'_> {
    fn add(self, id: ResourceId, access: Access, sel: SubresourceSel, declared_read: bool) -> Self {
        // An access of a layer view is an access of that layer of its image.
        let (id, sel) = match self.graph.resources[id.0 as usize].layer_of {
            Some((image, layer)) => (image, sel.layers(layer, 1)),
            None => (id, sel),
        };
        self.graph.passes[self.index]
            .accesses
            .push((id, access, sel, declared_read));
        self
    }
    /// Declares a read of the whole resource.
    pub fn read(self, r: impl Into<ResourceId>, access: Access) -> Self {
        self.add(r.into(), access, SubresourceSel::whole(), true)
    }
    /// Declares a write (or read-write) of the whole resource.
    pub fn write(self, r: impl Into<ResourceId>, access: Access) -> Self {
        self.add(r.into(), access, SubresourceSel::whole(), false)
    }
    /// Declares a read of some mips/layers of an image.
    pub fn read_sub(self, r: ImageHandle, access: Access, sel: SubresourceSel) -> Self {
        self.add(r.into(), access, sel, true)
    }
    /// Declares a write of some mips/layers of an image.
    pub fn write_sub(self, r: ImageHandle, access: Access, sel: SubresourceSel) -> Self {
        self.add(r.into(), access, sel, false)
    }
    /// The pipeline whose set-0 bindings this pass fills: the compile step checks every
    /// binding the pass declares against what its shaders declare, and [`PassContext::bind`]
    /// pushes them.
    pub fn pipeline(self, pipeline: &impl Bindable) -> Self {
        self.graph.passes[self.index].interface = Some(pipeline.interface());
        self
    }
    fn add_binding(mut self, decl: bind::BindingDecl, sel: SubresourceSel) -> Self {
        let read = !decl.access.info().writes;
        let access = decl.access;
        let resources = decl.resources().to_vec();
        self.graph.passes[self.index].bindings.push(decl);
        for r in resources {
            self = self.add(r, access, sel, read);
        }
        self
    }
    /// Declares `resource` with `access` at `binding` of the pass's pipeline: a storage image
    /// or buffer (`Storage*`), or a uniform buffer (`Uniform`). Read or write follows the access.
    pub fn bind(self, binding: u32, resource: impl Into<ResourceId>, access: Access) -> Self {
        self.add_binding(
            bind::BindingDecl::new(binding, resource.into(), access),
            SubresourceSel::whole(),
        )
    }
    /// Declares a sampled read of `image` through `sampler` at `binding`, by `shader`.
    pub fn bind_sampled(
        self,
        binding: u32,
        image: ImageHandle,
        sampler: vk::Sampler,
        shader: Shader,
    ) -> Self {
        let mut decl = bind::BindingDecl::new(binding, image.into(), Access::Sampled(shader));
        decl.sampler = Some(sampler);
        self.add_binding(decl, SubresourceSel::whole())
    }
    /// Declares mip `level` of `image` (its one-level view) with `access` at `binding`: a
    /// storage image (`Storage*`), or, with `sampler`, a sampled one (`Sampled`).
    pub fn bind_mip(
        self,
        binding: u32,
        image: ImageHandle,
        level: u32,
        access: Access,
        sampler: Option<vk::Sampler>,
    ) -> Self {
        let mut decl = bind::BindingDecl::new(binding, image.into(), access);
        decl.sampler = sampler;
        decl.mip = Some(level);
        self.add_binding(decl, Subresource::mip(level))
    }
    /// Declares `binding` as filled by one of `resources` at a time, all with `access`: the
    /// record closure picks one per dispatch or draw with [`PassContext::bind_with`] or
    /// [`PassContext::push_with`] (point lists in chunks, triangle sets, per-material
    /// textures). Every one is checked against the shader and gets its barrier; a buffer
    /// imported per slot is bound as its slot's window, like with `.bind()`.
    pub fn bind_one_of<R: Into<ResourceId>>(
        self,
        binding: u32,
        resources: impl IntoIterator<Item = R>,
        access: Access,
    ) -> Self {
        let mut list: Vec<ResourceId> = Vec::new();
        for r in resources.into_iter().map(Into::into) {
            if !list.contains(&r) {
                list.push(r);
            }
        }
        self.add_binding(
            bind::BindingDecl::one_of(binding, list, access),
            SubresourceSel::whole(),
        )
    }
    /// [`Self::bind_one_of`] for images sampled through `sampler` by `shader`.
    pub fn bind_one_of_sampled(
        self,
        binding: u32,
        images: impl IntoIterator<Item = ImageHandle>,
        sampler: vk::Sampler,
        shader: Shader,
    ) -> Self {
        let mut list: Vec<ResourceId> = Vec::new();
        for r in images.into_iter().map(ResourceId::from) {
            if !list.contains(&r) {
                list.push(r);
            }
        }
        let mut decl = bind::BindingDecl::one_of(binding, list, Access::Sampled(shader));
        decl.sampler = Some(sampler);
        self.add_binding(decl, SubresourceSel::whole())
    }
    /// Declares a color attachment (the next location), loaded as `load` says.
    pub fn color(self, image: ImageHandle, load: Load) -> Self {
        let access = match load {
            Load::Keep => Access::ColorAttachmentReadWrite,
            _ => Access::ColorAttachment,
        };
        self.graph.passes[self.index]
            .attachments
            .push(bind::AttachmentDecl {
                image,
                load,
                depth: false,
                read_only: false,
            });
        self.add(image.into(), access, SubresourceSel::whole(), false)
    }
    /// Declares the depth attachment (tested and written), loaded as `load` says.
    pub fn depth(self, image: ImageHandle, load: Load) -> Self {
        self.graph.passes[self.index]
            .attachments
            .push(bind::AttachmentDecl {
                image,
                load,
                depth: true,
                read_only: false,
            });
        self.add(
            image.into(),
            Access::DepthAttachment,
            SubresourceSel::whole(),
            false,
        )
    }
    /// Declares the depth attachment tested against but not written (its contents kept):
    /// surfaces drawn over a finished depth buffer, such as transparent layers.
    pub fn depth_read(self, image: ImageHandle) -> Self {
        self.graph.passes[self.index]
            .attachments
            .push(bind::AttachmentDecl {
                image,
                load: Load::Keep,
                depth: true,
                read_only: true,
            });
        self.add(
            image.into(),
            Access::DepthRead,
            SubresourceSel::whole(),
            false,
        )
    }
    /// Renders with multiview: one draw renders view i into layer i of every attachment, for
    /// each bit i of `mask` (`gl_ViewIndex`); the pipeline must have the same mask
    /// (`GraphicsPipelineDesc::view_mask`).
    pub fn view_mask(self, mask: u32) -> Self {
        self.graph.passes[self.index].view_mask = mask;
        self
    }
    /// Records the pass only in the frame slots `condition` leaves open (`None`: always).
    pub fn when(self, condition: Option<std::sync::Arc<SlotCondition>>) -> Self {
        self.graph.passes[self.index].condition = condition;
        self
    }
    /// Records the pass only in the frame slots where `cache` is invalid: it produces the
    /// cache's images ([`RenderGraph::create_cached_image`]), and the host validates the
    /// cache with the frame's key before recording ([`Cache::validate`]). `None`: always.
    pub fn cached(self, cache: Option<&std::sync::Arc<Cache>>) -> Self {
        self.graph.passes[self.index].cache = cache.cloned();
        self.when(cache.map(|c| c.condition()))
    }
    /// Hands over the recording closure; ends the declaration.
    pub fn record(self, f: impl Fn(&PassContext) + 'static) {
        self.graph.passes[self.index].record = Some(Box::new(f));
    }
}
