//! `oit_gather`: draws the surfaces with MTL d < 1 over the finished opaque depth (tested, not
//! written), shades each fragment with the deferred pass's direct light and its emission, and
//! appends it to its pixel's linked list (`glsl/gbuffer.vert`, `glsl/oit_gather.frag`). Under a
//! GI method that gives transparent layers indirect light, the fragments also trace its rays:
//! the path tracer's voxel paths (`glsl/oit_gather_indirect.frag`), the hemisphere method's
//! one bounce (`glsl/oit_gather_hemisphere{,_emission,_volume}.frag`) or the VPL method's
//! gather over every interleaved set (`glsl/oit_gather_vpl.frag`).

use super::gbuffer::GpuGbufferPush;
use super::light_map::LightMaps;
use super::scene_gpu::{vertex_attributes, SceneInputs};
use super::DEPTH;
use crate::gi::LayerIndirect;
use crate::graph::{Access, BufferHandle, ImageHandle, RenderGraph, Shader};
use crate::vk::{vk, Context, GraphicsPipeline, GraphicsPipelineDesc, VkError};
use crate::voxel::attributes::AttributeHandles;

/// The linked lists of a frame: head pointers (r32ui), nodes and counters.
#[derive(Clone, Copy, Debug)]
pub struct OitLists {
    pub heads: ImageHandle,
    pub nodes: BufferHandle,
    pub counters: BufferHandle,
}

/// What the fragments' rays read, declared by the GI passes of the frame: the voxel
/// hierarchy, the ray-mask table, and what each kind of ray reads at its hits.
#[derive(Clone, Copy, Debug)]
pub struct OitVoxelInputs {
    pub voxels: ImageHandle,
    pub lut: BufferHandle,
    /// The attribute volumes, when the method reads them.
    pub attributes: Option<AttributeHandles>,
    /// The reflective light maps, when the frame renders them.
    pub light_maps: Option<LightMaps>,
    /// The direct-radiance volume (`--gi-radiance volume`).
    pub radiance_volume: Option<ImageHandle>,
    /// The frame's VPLs (`--gi vpl`).
    pub vpls: Option<BufferHandle>,
}

/// The fragments' indirect-light inputs: the GI method's ray parameters (a `GpuGiPush`, or
/// the VPL gather's `GpuVplGatherPush`, in a buffer) and what its rays read.
#[derive(Clone, Copy, Debug)]
pub struct OitIndirect {
    pub params: BufferHandle,
    pub inputs: OitVoxelInputs,
}

/// Which indirect-light variant the pass makes: the rays it traces and what of the scene they
/// read.
#[derive(Clone, Copy, Debug)]
pub struct LayerVariant {
    pub kind: LayerIndirect,
    /// The scene has emitters, which the variants read from the emission volume.
    pub emission: bool,
    /// The scene's environment (`Environment::shader_kind`), which the path tracer's and the
    /// hemisphere method's rays read where they leave the voxel grid.
    pub environment: u32,
}

/// The indirect-light variant of the pass: its pipeline and what it was made for.
struct IndirectVariant {
    pipeline: GraphicsPipeline,
    variant: LayerVariant,
}

pub struct OitGatherPass {
    pipeline: GraphicsPipeline,
    /// The variant that adds the GI method's indirect light, made when the method gives
    /// transparent layers any; a frame without its inputs draws with `pipeline`.
    indirect: Option<IndirectVariant>,
}

impl OitGatherPass {
    /// `phong`, `ggx`, `textures`, `alpha_maps`: what the scene's materials have (the shader
    /// compiles in only those). `indirect`: make this indirect-light variant.
    pub fn new(
        ctx: &Context,
        materials: (bool, bool, bool, bool),
        indirect: Option<LayerVariant>,
    ) -> Result<Self, VkError> {
        Ok(Self {
            pipeline: Self::pipeline(ctx, materials, None)?,
            indirect: indirect
                .map(|variant| {
                    Ok::<_, VkError>(IndirectVariant {
                        pipeline: Self::pipeline(ctx, materials, Some(variant))?,
                        variant,
                    })
                })
                .transpose()?,
        })
    }

    /// The fragment shader of the plain pass or of an indirect variant.
    fn fragment_shader(indirect: Option<LayerVariant>) -> &'static str {
        match indirect.map(|v| (v.kind, v.emission)) {
            None => "oit_gather.frag",
            Some((LayerIndirect::Paths, _)) => "oit_gather_indirect.frag",
            Some((LayerIndirect::LightMaps, false)) => "oit_gather_hemisphere.frag",
            Some((LayerIndirect::LightMaps, true)) => "oit_gather_hemisphere_emission.frag",
            Some((LayerIndirect::RadianceVolume, _)) => "oit_gather_hemisphere_volume.frag",
            Some((LayerIndirect::Vpls, _)) => "oit_gather_vpl.frag",
        }
    }

    fn pipeline(
        ctx: &Context,
        (phong, ggx, textures, alpha_maps): (bool, bool, bool, bool),
        indirect: Option<LayerVariant>,
    ) -> Result<GraphicsPipeline, VkError> {
        let mut spec = crate::spec_constants![
            HAS_PHONG = phong,
            HAS_GGX = ggx,
            HAS_TEXTURES = textures,
            HAS_ALPHA_MAP = alpha_maps,
        ]
        .to_vec();
        // The light maps' variants read emission by variant, not by a constant; the VPLs
        // carry the emitters' light themselves (`gi_vpl_emit`) and bring no environment.
        if let Some(v) = indirect {
            if matches!(v.kind, LayerIndirect::Paths | LayerIndirect::RadianceVolume) {
                spec.extend(crate::spec_constants![HAS_EMISSION = v.emission]);
            }
            if v.kind != LayerIndirect::Vpls {
                spec.extend(crate::spec_constants![ENVIRONMENT = v.environment]);
            }
        }
        ctx.graphics_pipeline(&GraphicsPipelineDesc {
            // The G-buffer's vertex stage: the same positions, so the depth test against the
            // opaque depth compares equal transforms.
            vertex: "gbuffer.vert".into(),
            geometry: None,
            fragment: Self::fragment_shader(indirect).into(),
            push: crate::vk::PushLayout::of::<GpuGbufferPush>(),
            vertex_stride: std::mem::size_of::<super::gpu::GpuVertex>() as u32,
            vertex_attributes: vertex_attributes(),
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![],
            depth_format: Some(DEPTH),
            depth_test: true,
            depth_write: false,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec,
        })
    }

    /// Declares the pass appending the transparent draws' fragments to `lists` (cleared by
    /// `oit_clear`), tested against the opaque `depth`; with `indirect`, the fragments add the
    /// GI method's indirect light (when this pass made that variant and the frame has what
    /// its rays read).
    pub fn declare(
        &self,
        g: &mut RenderGraph,
        scene: &SceneInputs,
        lists: OitLists,
        (depth, shadow_maps): (ImageHandle, ImageHandle),
        sampler: vk::Sampler,
        indirect: Option<OitIndirect>,
    ) {
        // The indirect variant, its inputs and the images its hits read, when this pass made
        // it and the frame has all of them.
        let traced = indirect.and_then(|i| {
            let v = self.indirect.as_ref()?;
            Some((*v.pipeline, i, Self::hit_inputs(v, &i.inputs)?))
        });
        let pipe = traced.as_ref().map_or(*self.pipeline, |&(p, _, _)| p);
        let (vertices, indices) = (scene.vertices, scene.indices);
        let draws = scene.draws.clone();
        let textures = scene.textures.clone();
        let placeholder = scene.placeholder();
        let f = Shader::Fragment;
        let mut pass = g
            .add_pass("oit_gather")
            .pipeline(&pipe)
            .bind(0, scene.frame, Access::StorageRead(Shader::Graphics))
            .bind(1, scene.materials, Access::StorageRead(f))
            .bind_one_of_sampled(2, textures.clone(), scene.texture_sampler, f)
            .bind(3, scene.materials_pbr, Access::StorageRead(f))
            .bind_sampled(4, shadow_maps, sampler, f)
            .bind(5, lists.heads, Access::StorageReadWrite(f))
            .bind(6, lists.nodes, Access::StorageWrite(f))
            .bind(7, lists.counters, Access::StorageReadWrite(f))
            .read(vertices, Access::VertexBuffer)
            .read(indices, Access::IndexBuffer)
            .depth_read(depth);
        if let Some((_, i, hits)) = traced {
            pass = pass
                .bind(8, i.params, Access::StorageRead(f))
                .bind_sampled(9, i.inputs.voxels, sampler, f)
                .bind(10, i.inputs.lut, Access::StorageRead(f));
            match hits {
                LayerHits::Images(images) => {
                    for (binding, image) in (11..).zip(images) {
                        pass = pass.bind_sampled(binding, image, sampler, f);
                    }
                    // The environment map, where rays leaving the grid read one (the
                    // placeholder texture fills the binding otherwise, never read).
                    let map = scene.environment_map.unwrap_or(placeholder);
                    pass = pass.bind_sampled(16, map, scene.environment_sampler, f);
                }
                LayerHits::Vpls(vpls) => pass = pass.bind(11, vpls, Access::StorageRead(f)),
            }
        }
        pass.record(move |ctx| {
            ctx.begin_rendering();
            let texture = |t: Option<usize>| {
                t.and_then(|i| textures.get(i).copied())
                    .unwrap_or(placeholder)
            };
            ctx.bind_with(&pipe, &[(2, placeholder)]);
            ctx.bind_vertex_buffer(vertices);
            ctx.bind_index_buffer(indices);
            if let Ok(lists) = draws.read() {
                let mut bound = None;
                for d in &lists.transparent {
                    if d.texture != bound {
                        ctx.push_with(&pipe, &[(2, texture(d.texture))]);
                        bound = d.texture;
                    }
                    let push = GpuGbufferPush::of(d);
                    ctx.cmd.push_constants(&pipe, bytemuck::bytes_of(&push));
                    ctx.cmd
                        .draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                }
            }
            ctx.cmd.end_rendering();
        });
    }
}

/// What an indirect variant reads besides the voxels, bound from 11 on.
enum LayerHits {
    /// The images its rays sample at their hits.
    Images(Vec<ImageHandle>),
    /// The VPL buffer (binding 11).
    Vpls(BufferHandle),
}

impl OitGatherPass {
    /// What variant `v` reads at its rays' hits, or `None` where the frame lacks it (the pass
    /// then draws without indirect light).
    fn hit_inputs(v: &IndirectVariant, i: &OitVoxelInputs) -> Option<LayerHits> {
        let images = match v.variant.kind {
            LayerIndirect::Vpls => return Some(LayerHits::Vpls(i.vpls?)),
            LayerIndirect::Paths => {
                let a = i.attributes?;
                // Without emitters the shader never reads its emission binding; albedo fills it.
                vec![a.albedo, a.normal, a.emission.unwrap_or(a.albedo)]
            }
            LayerIndirect::LightMaps => {
                let m = i.light_maps?;
                let mut images = vec![m.radiance, m.position, m.normal];
                if v.variant.emission {
                    let a = i.attributes?;
                    images.extend([a.emission.unwrap_or(a.albedo), a.normal]);
                }
                images
            }
            LayerIndirect::RadianceVolume => {
                let a = i.attributes?;
                // Without Phong or GGX materials the shader never reads the material volume,
                // nor without emitters the emission volume; albedo fills them.
                let (material, emission) = (a.material, a.emission);
                vec![
                    i.radiance_volume?,
                    a.normal,
                    material.unwrap_or(a.albedo),
                    a.albedo,
                    emission.unwrap_or(a.albedo),
                ]
            }
        };
        Some(LayerHits::Images(images))
    }
}

#[cfg(test)]
mod tests {
    /// The indirect variants' parameter buffer holds what the ray passes get as push
    /// constants: each shader's `GpuGiPush` has the Rust struct's names, offsets and sizes.
    #[test]
    fn gi_params_buffer_matches_the_ray_passes_push_constants() {
        for file in [
            "oit_gather_indirect.frag",
            "oit_gather_hemisphere.frag",
            "oit_gather_hemisphere_emission.frag",
            "oit_gather_hemisphere_volume.frag",
        ] {
            crate::vk::check_struct_against::<crate::gi::GpuGiPush>(&[file], "GpuGiPush")
                .unwrap_or_else(|e| panic!("{file}: {e}"));
        }
        // The VPL variant's buffer holds the VPL gather's push constants.
        crate::vk::check_struct_against::<crate::gi::vpl::GpuVplGatherPush>(
            &["oit_gather_vpl.frag"],
            "GpuVplGatherPush",
        )
        .unwrap_or_else(|e| panic!("oit_gather_vpl.frag: {e}"));
    }
}
