//! Order-independent transparency with per-pixel linked lists (Yang et al. 2010; Dachsbacher
//! 2014, part 3): surfaces with MTL d < 1 leave the G-buffer; after the opaque frame is lit,
//! `oit_clear` empties the lists, `oit_gather` appends every shaded transparent fragment in
//! front of the opaque depth, `oit_resolve` sorts each pixel's K nearest layers and blends them
//! back to front, and `oit_stats` copies the counters for the host ([`OitStats`]). Only scenes
//! with such a material and `--transparency oit` have these passes or their memory.

use super::oit_clear::OitClearPass;
pub use super::oit_gather::{LayerVariant, OitVoxelInputs};
use super::oit_gather::{OitGatherPass, OitIndirect, OitLists};
use super::oit_resolve::{OitResolvePass, MAX_LAYERS};
use super::scene_gpu::SceneInputs;
use crate::gi::LayerParams;
use crate::graph::{Access, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Buffer, Context, ImageDesc, VkError};

/// Node-buffer capacity per pixel when no flag says otherwise: a pixel covered by one or two
/// transparent layers, on average over the frame, fits several times over.
pub const DEFAULT_NODES_PER_PIXEL: u32 = 4;
/// Bytes of a node: half-float rgb and alpha, depth, next index (`oit_gather.frag`).
pub const NODE_BYTES: u64 = 16;

/// What the lists of the last completed frame held, read back from the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OitStats {
    /// Transparent fragments in front of the opaque depth (stored or not).
    pub fragments: u32,
    /// Nodes the buffer holds (width × height × nodes per pixel).
    pub capacity: u32,
    /// Pixels with more than [`MAX_LAYERS`] stored layers: their farthest layers were dropped.
    pub pixels_over_max_layers: u32,
    /// Layers dropped in those pixels.
    pub layers_over_max_layers: u32,
}

impl OitStats {
    /// Fragments lost because the node buffer was full.
    pub fn fragments_dropped(&self) -> u32 {
        self.fragments.saturating_sub(self.capacity)
    }

    /// A warning when anything was dropped, naming the way out; `None` when every layer was
    /// blended.
    pub fn overflow_warning(&self) -> Option<String> {
        let mut parts = Vec::new();
        if self.fragments_dropped() > 0 {
            parts.push(format!(
                "{} of {} transparent fragments did not fit the node buffer ({} nodes; raise --oit-nodes-per-pixel)",
                self.fragments_dropped(),
                self.fragments,
                self.capacity
            ));
        }
        if self.pixels_over_max_layers > 0 {
            parts.push(format!(
                "{} pixels had more than {MAX_LAYERS} transparent layers; their {} farthest layers were left out",
                self.pixels_over_max_layers, self.layers_over_max_layers
            ));
        }
        (!parts.is_empty()).then(|| parts.join("; "))
    }
}

/// The transparency passes and the host-visible copy of their counters.
pub struct OitPasses {
    clear: OitClearPass,
    gather: OitGatherPass,
    resolve: OitResolvePass,
    stats: Buffer,
    nodes_per_pixel: u32,
    shadow_sampler: vk::Sampler,
    /// The GI method's ray (or VPL gather) parameters for the fragments' indirect light
    /// ([`crate::gi::GiPasses::transparent_indirect`]), when it gives them any.
    gi_params: Option<Buffer>,
}

impl OitPasses {
    /// `materials`: (Phong, GGX, albedo textures, alpha maps) in the scene; `sampler`: the renderer's
    /// nearest-neighbour sampler (shadow maps, radiance); `indirect`: the GI method's ray
    /// parameters and the variant tracing its rays, when the fragments get indirect light.
    pub fn new(
        ctx: &Context,
        materials: (bool, bool, bool, bool),
        nodes_per_pixel: u32,
        sampler: vk::Sampler,
        indirect: Option<(LayerParams, LayerVariant)>,
    ) -> Result<Self, VkError> {
        // Written once: the renderer is made anew when the GI settings change.
        let gi_params = indirect
            .map(|(params, _)| {
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
                ctx.upload_buffer("oit gi params", params.bytes(), usage)
            })
            .transpose()?;
        Ok(Self {
            clear: OitClearPass::new(ctx)?,
            gather: OitGatherPass::new(ctx, materials, indirect.map(|(_, variant)| variant))?,
            resolve: OitResolvePass::new(ctx, sampler)?,
            stats: crate::graph::readback_buffer(ctx, "oit stats", 16)?,
            nodes_per_pixel,
            shadow_sampler: sampler,
            gi_params,
        })
    }

    /// Nodes the buffer of a `w` × `h` frame holds.
    pub fn capacity(&self, (w, h): (u32, u32)) -> u32 {
        let nodes = u64::from(w) * u64::from(h) * u64::from(self.nodes_per_pixel);
        nodes.min(u64::from(u32::MAX - 1)) as u32
    }

    /// Declares the four passes; returns `opaque` with the transparent layers blended over it.
    /// `voxels`: what the GI passes declared for the fragments' indirect light (`None`: direct
    /// light only).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        (depth, shadow_maps): (ImageHandle, ImageHandle),
        opaque: ImageHandle,
        size: (u32, u32),
        voxels: Option<OitVoxelInputs>,
    ) -> ImageHandle {
        let capacity = self.capacity(size);
        let lists = OitLists {
            heads: g.create_image(ImageDesc::new_2d(
                "oit heads",
                vk::Format::R32_UINT,
                size.0,
                size.1,
            )),
            nodes: g.create_buffer("oit nodes", u64::from(capacity) * NODE_BYTES),
            counters: g.create_buffer("oit counters", 16),
        };
        self.clear
            .declare(g, lists.heads, lists.counters, capacity, size);
        let indirect = match (&self.gi_params, voxels) {
            (Some(params), Some(inputs)) => Some(OitIndirect {
                params: g.import_buffer(params, Access::StorageRead(Shader::Fragment)),
                inputs,
            }),
            _ => None,
        };
        self.gather.declare(
            g,
            scene,
            lists,
            (depth, shadow_maps),
            self.shadow_sampler,
            indirect,
        );
        let out = self.resolve.declare(
            g,
            (lists.heads, lists.nodes, lists.counters),
            scene.frame,
            opaque,
            size,
        );
        let stats = g.import_buffer(&self.stats, Access::HostRead);
        let counters = lists.counters;
        g.add_pass("oit_stats")
            .read(counters, Access::TransferRead)
            .write(stats, Access::TransferWrite)
            .record(move |ctx| {
                ctx.cmd
                    .copy_buffer(ctx.buffer(counters).raw, ctx.buffer(stats).raw, 16);
            });
        out
    }

    /// The counters of the last completed frame.
    pub fn stats(&self) -> OitStats {
        let words: [u32; 4] = self
            .stats
            .mapped()
            .map(|m| bytemuck::pod_read_unaligned(&m[..16]))
            .unwrap_or_default();
        OitStats {
            fragments: words[0],
            capacity: words[1],
            pixels_over_max_layers: words[2],
            layers_over_max_layers: words[3],
        }
    }
}
