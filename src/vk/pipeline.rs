//! Shader modules, compute and graphics pipelines with one push-descriptor set whose layout
//! is reflected from the shaders, samplers.

use super::reflect::{self, BindingKind, PushConstants, ShaderInterface, SpecEntry};
use super::release::{Garbage, ReleaseQueue};
use super::{shaders, Context, VkError};
use ash::vk;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A descriptor pushed at bind time, addressed by its binding in set 0.
#[derive(Clone, Copy, Debug)]
pub enum Descriptor {
    SampledImage {
        binding: u32,
        view: vk::ImageView,
        sampler: vk::Sampler,
    },
    StorageImage {
        binding: u32,
        view: vk::ImageView,
    },
    StorageBuffer {
        binding: u32,
        buffer: vk::Buffer,
        offset: u64,
        range: u64,
    },
    UniformBuffer {
        binding: u32,
        buffer: vk::Buffer,
        offset: u64,
        range: u64,
    },
}

impl Descriptor {
    pub fn binding(&self) -> u32 {
        match *self {
            Descriptor::SampledImage { binding, .. }
            | Descriptor::StorageImage { binding, .. }
            | Descriptor::StorageBuffer { binding, .. }
            | Descriptor::UniformBuffer { binding, .. } => binding,
        }
    }
    pub fn descriptor_type(&self) -> vk::DescriptorType {
        match self {
            Descriptor::SampledImage { .. } => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Descriptor::StorageImage { .. } => vk::DescriptorType::STORAGE_IMAGE,
            Descriptor::StorageBuffer { .. } => vk::DescriptorType::STORAGE_BUFFER,
            Descriptor::UniformBuffer { .. } => vk::DescriptorType::UNIFORM_BUFFER,
        }
    }
    /// A whole-buffer storage descriptor.
    pub fn storage_buffer(binding: u32, buffer: vk::Buffer) -> Self {
        Descriptor::StorageBuffer {
            binding,
            buffer,
            offset: 0,
            range: vk::WHOLE_SIZE,
        }
    }
}

/// Anything `Cmd::bind` accepts.
pub trait Bindable {
    fn bind_info(&self) -> (vk::PipelineBindPoint, vk::Pipeline, vk::PipelineLayout);
    /// The bindings and push constants its shaders declare.
    fn interface(&self) -> &'static ShaderInterface;
    /// Bytes of its push-constant range (0: none).
    fn push_bytes(&self) -> u32 {
        push_bytes(self.interface())
    }
}

/// A Rust push-constant struct's layout, checked against the shader's block when a pipeline
/// is created.
#[derive(Clone, Debug)]
pub struct PushLayout {
    pub type_name: &'static str,
    pub fields: Vec<(&'static str, u32, u32)>,
    pub size_bytes: u32,
}

impl PushLayout {
    pub fn of<T: PushConstants>() -> Option<PushLayout> {
        Some(PushLayout {
            type_name: std::any::type_name::<T>()
                .rsplit("::")
                .next()
                .unwrap_or("push constants"),
            fields: T::fields(),
            size_bytes: std::mem::size_of::<T>() as u32,
        })
    }
}

fn check_push_layout(
    interface: &ShaderInterface,
    push: Option<&PushLayout>,
) -> Result<(), VkError> {
    let (name, fields, size) = match push {
        Some(p) => (p.type_name, p.fields.as_slice(), p.size_bytes),
        None => ("no push constants", &[][..], 0),
    };
    reflect::check_push(interface.push.as_ref(), name, fields, size).map_err(|problems| {
        VkError::ShaderInterface(format!(
            "pipeline `{}`: push constants do not match the shader: {problems}",
            interface.name
        ))
    })
}

/// The (constant id, value) pairs of the named specialization constants `spec`, checked
/// against those the pipeline's shaders declare (see [`reflect::check_spec`]).
fn check_spec_values(
    interface: &ShaderInterface,
    spec: &[SpecEntry],
) -> Result<Vec<(u32, u32)>, VkError> {
    reflect::check_spec(&interface.spec, spec).map_err(|problems| {
        // A pass is named after its shaders' file stem (`gbuffer.vert+gbuffer.frag`: `gbuffer`).
        let pass = interface
            .name
            .split(['.', '+'])
            .next()
            .unwrap_or(&interface.name);
        VkError::ShaderInterface(format!(
            "pass `{pass}` (shader `{}`): specialization constants do not match the shader: {problems}",
            interface.name
        ))
    })
}

/// Checks the named specialization constants `spec` against those the embedded shaders
/// `files` declare, without a device (what creating their pipeline checks): for tier-1 tests.
pub fn check_spec_against(files: &[&str], spec: &[SpecEntry]) -> Result<(), VkError> {
    check_spec_values(interface_of(files)?, spec).map(|_| ())
}

/// Checks the Rust push struct `push` against the block the embedded shaders `files` declare,
/// without a device (what creating their pipeline checks): for tier-1 tests.
pub fn check_push_against(files: &[&str], push: Option<PushLayout>) -> Result<(), VkError> {
    check_push_layout(interface_of(files)?, push.as_ref())
}

/// Checks the Rust struct `T` against the struct `glsl_struct` of the buffer blocks the
/// embedded shaders `files` declare (name, offset and size of every member, and its array
/// stride): for tests of the `Gpu*` buffer structs, without a device.
pub fn check_struct_against<T: reflect::GpuStruct>(
    files: &[&str],
    glsl_struct: &str,
) -> Result<(), VkError> {
    let interface = interface_of(files)?;
    let rust_name = std::any::type_name::<T>()
        .rsplit("::")
        .next()
        .unwrap_or("struct");
    let layout = interface.structs.get(glsl_struct).ok_or_else(|| {
        VkError::ShaderInterface(format!(
            "`{}` declares no buffer struct `{glsl_struct}` (declared: {:?})",
            interface.name,
            interface.structs.keys().collect::<Vec<_>>()
        ))
    })?;
    reflect::check_struct(
        layout,
        rust_name,
        &T::fields(),
        std::mem::size_of::<T>() as u32,
    )
    .map_err(|problems| {
        VkError::ShaderInterface(format!(
            "`{}`: `{rust_name}` does not match the shader's `{glsl_struct}`: {problems}",
            interface.name
        ))
    })
}

/// The push-constant range of an interface: its block's size, rounded to the 4 bytes Vulkan
/// ranges are counted in.
fn push_bytes(interface: &ShaderInterface) -> u32 {
    interface
        .push
        .as_ref()
        .map_or(0, |p| p.size_bytes.next_multiple_of(4))
}

pub fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::CombinedImageSampler => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
    }
}

/// The interface of the pipeline made of the embedded shaders `files`, reflected once per
/// combination and kept for the program's life: the set of shaders is fixed at build time,
/// so the leak is bounded by it.
pub fn interface_of(files: &[&str]) -> Result<&'static ShaderInterface, VkError> {
    static CACHE: OnceLock<Mutex<HashMap<String, &'static ShaderInterface>>> = OnceLock::new();
    let key = files.join("+");
    let cache = CACHE.get_or_init(Default::default);
    if let Some(i) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(i);
    }
    let mut stages = Vec::with_capacity(files.len());
    for f in files {
        let bytes = shaders::get(f).ok_or_else(|| VkError::MissingShader((*f).into()))?;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| {
            VkError::InvalidSpirv {
                name: (*f).into(),
                reason: e.to_string(),
            }
        })?;
        stages.push(
            reflect::reflect(f, &words).map_err(|e| VkError::ShaderInterface(e.to_string()))?,
        );
    }
    let merged = reflect::merge(&stages).map_err(|e| VkError::ShaderInterface(e.to_string()))?;
    let interned: &'static ShaderInterface = Box::leak(Box::new(merged));
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key, interned);
    Ok(interned)
}

/// A shader module; destroyed on drop (pipelines do not need it after creation).
pub struct ShaderModule {
    pub raw: vk::ShaderModule,
    pub name: String,
    release: Arc<ReleaseQueue>,
}

impl Drop for ShaderModule {
    fn drop(&mut self) {
        self.release.release(vec![Garbage::ShaderModule(self.raw)]);
    }
}

impl Context {
    /// A shader module of the embedded SPIR-V `glsl/<file_name>`.
    pub fn shader_module(&self, file_name: &str) -> Result<ShaderModule, VkError> {
        let bytes =
            shaders::get(file_name).ok_or_else(|| VkError::MissingShader(file_name.into()))?;
        let words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).map_err(|e| {
            VkError::InvalidSpirv {
                name: file_name.into(),
                reason: e.to_string(),
            }
        })?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: words is valid SPIR-V produced by shaderc at build time.
        let raw = unsafe { self.device.create_shader_module(&info, None) }
            .map_err(VkError::vk("create a shader module"))?;
        self.set_name(raw, file_name);
        Ok(ShaderModule {
            raw,
            name: file_name.into(),
            release: Arc::clone(&self.release),
        })
    }

    /// A pipeline owner with the push-descriptor set layout and pipeline layout of a
    /// reflected interface (every binding the shaders declare, and a push-constant range
    /// covering their block) and no pipeline yet: what fails later is released with it.
    fn pipeline_with_layout(
        &self,
        bind_point: vk::PipelineBindPoint,
        interface: &'static ShaderInterface,
    ) -> Result<Pipeline, VkError> {
        let mut owner = Pipeline {
            handle: PipelineHandle {
                bind_point,
                raw: vk::Pipeline::null(),
                layout: vk::PipelineLayout::null(),
                set_layout: vk::DescriptorSetLayout::null(),
                interface,
            },
            release: Arc::clone(&self.release),
        };
        let b: Vec<vk::DescriptorSetLayoutBinding> = interface
            .bindings
            .values()
            .map(|r| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(r.binding)
                    .descriptor_type(descriptor_type(r.kind))
                    .descriptor_count(r.count)
                    .stage_flags(vk::ShaderStageFlags::ALL)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&b);
        // SAFETY: valid device and create info.
        let set_layout = unsafe { self.device.create_descriptor_set_layout(&info, None) }
            .map_err(VkError::vk("create a descriptor set layout"))?;
        owner.handle.set_layout = set_layout;
        let push_constant_bytes = push_bytes(interface);
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::ALL,
            offset: 0,
            size: push_constant_bytes,
        }];
        let set_layouts = [set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_constant_bytes > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid device; set_layout is live.
        owner.handle.layout = unsafe { self.device.create_pipeline_layout(&layout_info, None) }
            .map_err(VkError::vk("create a pipeline layout"))?;
        Ok(owner)
    }

    /// A compute pipeline of `glsl/<file_name>`. Its set-0 bindings and push-constant range
    /// come from the shader itself (reflected SPIR-V); `push` is the Rust struct pushed to it,
    /// whose fields must match the shader's block by name, offset and size. `spec` names a value
    /// for each specialization constant the shader declares ([`spec_constants!`]).
    ///
    /// [`spec_constants!`]: crate::spec_constants
    pub fn compute_pipeline(
        &self,
        file_name: &str,
        push: Option<PushLayout>,
        spec: &[SpecEntry],
    ) -> Result<ComputePipeline, VkError> {
        let interface = interface_of(&[file_name])?;
        check_push_layout(interface, push.as_ref())?;
        let spec = check_spec_values(interface, spec)?;
        let module = self.shader_module(file_name)?;
        let mut owner = self.pipeline_with_layout(vk::PipelineBindPoint::COMPUTE, interface)?;
        let layout = owner.layout;
        let (entries, data) = spec_data(&spec);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(&data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout)];
        // SAFETY: module and layout are live; info points to live locals.
        let result = unsafe {
            self.device
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        };
        drop(module);
        owner.handle.raw = result.map_err(|(_, e)| VkError::Call {
            what: "create a compute pipeline",
            result: e,
        })?[0];
        self.set_name(owner.raw, file_name);
        Ok(owner)
    }

    pub fn graphics_pipeline(
        &self,
        desc: &GraphicsPipelineDesc,
    ) -> Result<GraphicsPipeline, VkError> {
        self.graphics_pipeline_blend(desc, Blend::None)
    }

    /// A graphics pipeline whose color attachments blend premultiplied-alpha "over" the
    /// existing contents (overlays such as the viewer's UI).
    pub fn graphics_pipeline_premultiplied(
        &self,
        desc: &GraphicsPipelineDesc,
    ) -> Result<GraphicsPipeline, VkError> {
        self.graphics_pipeline_blend(desc, Blend::Premultiplied)
    }

    /// A graphics pipeline whose color attachments add the fragment to the existing contents
    /// (`ONE, ONE`): sums, such as the per-voxel attribute sums of layered voxelization.
    pub fn graphics_pipeline_additive(
        &self,
        desc: &GraphicsPipelineDesc,
    ) -> Result<GraphicsPipeline, VkError> {
        self.graphics_pipeline_blend(desc, Blend::Additive)
    }

    fn graphics_pipeline_blend(
        &self,
        desc: &GraphicsPipelineDesc,
        blend: Blend,
    ) -> Result<GraphicsPipeline, VkError> {
        let mut files = vec![desc.vertex.as_str()];
        files.extend(desc.geometry.as_deref());
        files.push(desc.fragment.as_str());
        let interface = interface_of(&files)?;
        check_push_layout(interface, desc.push.as_ref())?;
        let spec = check_spec_values(interface, &desc.spec)?;
        let mut modules = vec![
            (
                vk::ShaderStageFlags::VERTEX,
                self.shader_module(&desc.vertex)?,
            ),
            (
                vk::ShaderStageFlags::FRAGMENT,
                self.shader_module(&desc.fragment)?,
            ),
        ];
        if let Some(g) = &desc.geometry {
            modules.push((vk::ShaderStageFlags::GEOMETRY, self.shader_module(g)?));
        }
        let mut owner = self.pipeline_with_layout(vk::PipelineBindPoint::GRAPHICS, interface)?;
        let layout = owner.layout;
        let (entries, data) = spec_data(&spec);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(&data);
        let stages: Vec<vk::PipelineShaderStageCreateInfo> = modules
            .iter()
            .map(|(stage, m)| {
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(*stage)
                    .module(m.raw)
                    .name(c"main")
                    .specialization_info(&spec_info)
            })
            .collect();
        let (vertex_bindings, attributes) = vertex_descriptions(desc);
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vertex_bindings)
            .vertex_attribute_descriptions(&attributes);
        let input_assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .depth_bias_enable(desc.depth_bias)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_format.is_some() && desc.depth_test)
            .depth_write_enable(desc.depth_format.is_some() && desc.depth_write)
            .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
        let blend_attachments: Vec<vk::PipelineColorBlendAttachmentState> = desc
            .color_formats
            .iter()
            .map(|_| blend.attachment_state())
            .collect();
        let mut blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        if let Some(op) = desc.logic_op {
            blend = blend.logic_op_enable(true).logic_op(op);
        }
        let mut dynamic_states = vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        if desc.depth_bias {
            dynamic_states.push(vk::DynamicState::DEPTH_BIAS);
        }
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED))
            .view_mask(desc.view_mask);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering)];
        // SAFETY: modules and layout are live; info points to live locals.
        let result = unsafe {
            self.device
                .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
        };
        drop(modules);
        owner.handle.raw = result.map_err(|(_, e)| VkError::Call {
            what: "create a graphics pipeline",
            result: e,
        })?[0];
        self.set_name(owner.raw, &desc.fragment);
        Ok(owner)
    }

    /// A sampler with the given filter and clamp-to-edge addressing.
    pub fn create_sampler(&self, filter: vk::Filter, anisotropy: bool) -> Result<Sampler, VkError> {
        self.create_sampler_with(filter, anisotropy, vk::SamplerAddressMode::CLAMP_TO_EDGE)
    }

    /// A sampler with the given filter and addressing: `REPEAT` for material textures, whose
    /// OBJ texture coordinates tile past [0, 1] (as in Mitsuba's `bitmap`, whose default
    /// `wrap_mode` is `repeat`).
    pub fn create_sampler_with(
        &self,
        filter: vk::Filter,
        anisotropy: bool,
        address: vk::SamplerAddressMode,
    ) -> Result<Sampler, VkError> {
        let mipmap_mode = if filter == vk::Filter::LINEAR {
            vk::SamplerMipmapMode::LINEAR
        } else {
            vk::SamplerMipmapMode::NEAREST
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(mipmap_mode)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(address)
            .anisotropy_enable(anisotropy)
            .max_anisotropy(if anisotropy {
                self.info.max_sampler_anisotropy.min(16.0)
            } else {
                1.0
            })
            .max_lod(vk::LOD_CLAMP_NONE);
        // SAFETY: valid device and create info.
        let raw = unsafe { self.device.create_sampler(&info, None) }
            .map_err(VkError::vk("create a sampler"))?;
        Ok(Sampler {
            raw,
            release: Arc::clone(&self.release),
        })
    }
}

/// A sampler; destroyed on drop once the GPU is done with it. Descriptors take `raw`.
pub struct Sampler {
    pub raw: vk::Sampler,
    release: Arc<ReleaseQueue>,
}

impl Drop for Sampler {
    fn drop(&mut self) {
        self.release.release(vec![Garbage::Sampler(self.raw)]);
    }
}

/// How a graphics pipeline's color attachments combine with their contents.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Blend {
    None,
    Premultiplied,
    Additive,
}

impl Blend {
    /// The blend state of each color attachment.
    fn attachment_state(self) -> vk::PipelineColorBlendAttachmentState {
        let b = vk::PipelineColorBlendAttachmentState::default()
            .color_write_mask(vk::ColorComponentFlags::RGBA);
        match self {
            Blend::Premultiplied => b
                .blend_enable(true)
                .src_color_blend_factor(vk::BlendFactor::ONE)
                .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                .color_blend_op(vk::BlendOp::ADD)
                .src_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_DST_ALPHA)
                .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                .alpha_blend_op(vk::BlendOp::ADD),
            Blend::Additive => b
                .blend_enable(true)
                .src_color_blend_factor(vk::BlendFactor::ONE)
                .dst_color_blend_factor(vk::BlendFactor::ONE)
                .color_blend_op(vk::BlendOp::ADD)
                .src_alpha_blend_factor(vk::BlendFactor::ONE)
                .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                .alpha_blend_op(vk::BlendOp::ADD),
            Blend::None => b,
        }
    }
}

/// The vertex buffer binding (one interleaved buffer at binding 0, none for a stride of 0)
/// and the attributes, at locations in the order `desc` lists them.
fn vertex_descriptions(
    desc: &GraphicsPipelineDesc,
) -> (
    Vec<vk::VertexInputBindingDescription>,
    Vec<vk::VertexInputAttributeDescription>,
) {
    let bindings = if desc.vertex_stride > 0 {
        vec![vk::VertexInputBindingDescription {
            binding: 0,
            stride: desc.vertex_stride,
            input_rate: vk::VertexInputRate::VERTEX,
        }]
    } else {
        vec![]
    };
    let attributes = desc
        .vertex_attributes
        .iter()
        .enumerate()
        .map(
            |(i, &(format, offset))| vk::VertexInputAttributeDescription {
                location: i as u32,
                binding: 0,
                format,
                offset,
            },
        )
        .collect();
    (bindings, attributes)
}

/// Map entries and data of 32-bit specialization constants.
fn spec_data(spec: &[(u32, u32)]) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let entries = spec
        .iter()
        .enumerate()
        .map(|(i, &(id, _))| vk::SpecializationMapEntry {
            constant_id: id,
            offset: 4 * i as u32,
            size: 4,
        })
        .collect();
    let data = spec.iter().flat_map(|&(_, v)| v.to_ne_bytes()).collect();
    (entries, data)
}

/// The handles of a pipeline, copied into the closures that record it (`*pipeline`). Valid
/// while the [`Pipeline`] they come from lives.
#[derive(Clone, Copy, Debug)]
pub struct PipelineHandle {
    pub bind_point: vk::PipelineBindPoint,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    /// What the shaders declare (interned for the program's life, so handles stay `Copy`).
    pub interface: &'static ShaderInterface,
}

impl Bindable for PipelineHandle {
    fn bind_info(&self) -> (vk::PipelineBindPoint, vk::Pipeline, vk::PipelineLayout) {
        (self.bind_point, self.raw, self.layout)
    }
    fn interface(&self) -> &'static ShaderInterface {
        self.interface
    }
}

/// A compute or graphics pipeline with its layouts: owns them and releases them on drop.
/// Dereferences to its copyable [`PipelineHandle`].
pub struct Pipeline {
    handle: PipelineHandle,
    release: Arc<ReleaseQueue>,
}

/// A pipeline made by [`Context::compute_pipeline`].
pub type ComputePipeline = Pipeline;
/// A pipeline made by [`Context::graphics_pipeline`] and its blending variants.
pub type GraphicsPipeline = Pipeline;

impl std::ops::Deref for Pipeline {
    type Target = PipelineHandle;
    fn deref(&self) -> &PipelineHandle {
        &self.handle
    }
}

impl Bindable for Pipeline {
    fn bind_info(&self) -> (vk::PipelineBindPoint, vk::Pipeline, vk::PipelineLayout) {
        self.handle.bind_info()
    }
    fn interface(&self) -> &'static ShaderInterface {
        self.handle.interface
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        let h = &self.handle;
        self.release.release(vec![
            Garbage::Pipeline(h.raw),
            Garbage::PipelineLayout(h.layout),
            Garbage::DescriptorSetLayout(h.set_layout),
        ]);
    }
}

/// Plain creation data of a graphics pipeline (dynamic rendering).
#[derive(Clone, Debug)]
pub struct GraphicsPipelineDesc {
    pub vertex: String,
    pub geometry: Option<String>,
    pub fragment: String,
    /// The Rust struct pushed as push constants (`None`: the shaders declare none). Bindings
    /// and the push range come from the shaders.
    pub push: Option<PushLayout>,
    /// Stride of vertex binding 0; 0 means no vertex buffer (e.g. a full-screen triangle).
    pub vertex_stride: u32,
    /// (format, offset) per location.
    pub vertex_attributes: Vec<(vk::Format, u32)>,
    pub topology: vk::PrimitiveTopology,
    pub cull_mode: vk::CullModeFlags,
    pub color_formats: Vec<vk::Format>,
    pub depth_format: Option<vk::Format>,
    pub depth_test: bool,
    pub depth_write: bool,
    pub depth_bias: bool,
    /// Logic op on every color attachment (e.g. OR for binary voxel columns).
    pub logic_op: Option<vk::LogicOp>,
    /// Specialization constants by GLSL name ([`spec_constants!`](crate::spec_constants)),
    /// applied to every stage; together the stages must declare exactly these.
    pub spec: Vec<SpecEntry>,
    /// Multiview (`VkPipelineRenderingCreateInfo::viewMask`): the views the pipeline renders
    /// in one draw, one bit per attachment layer; 0 for an ordinary single-view pipeline. The
    /// pass that binds it begins rendering with the same mask.
    pub view_mask: u32,
}

impl GraphicsPipelineDesc {
    /// A full-screen pass: no vertex input, triangle list, no culling, one color target.
    pub fn fullscreen(vertex: &str, fragment: &str, color: vk::Format) -> Self {
        Self {
            vertex: vertex.into(),
            geometry: None,
            fragment: fragment.into(),
            push: None,
            vertex_stride: 0,
            vertex_attributes: vec![],
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull_mode: vk::CullModeFlags::NONE,
            color_formats: vec![color],
            depth_format: None,
            depth_test: false,
            depth_write: false,
            depth_bias: false,
            logic_op: None,
            view_mask: 0,
            spec: vec![],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::reflect::SpecValue;

    /// What creating the light-map pipeline checks, without a device: its three stages
    /// together declare five constants, and a wrong type or a missing one is an error naming
    /// the pass, the shaders and the constant.
    #[test]
    fn spec_constants_are_checked_at_pipeline_creation() {
        let files = ["light_map.vert", "light_map.geom", "light_map.frag"];
        let good = crate::spec_constants![
            HAS_DISSOLVE = false,
            HAS_GGX = true,
            AREA_LIGHT_MAPS = true,
            HAS_MAPS = false,
            HAS_ALPHA_MAP = false,
        ];
        assert!(check_spec_against(&files, &good).is_ok());
        let mut wrong = good;
        wrong[2] = ("AREA_LIGHT_MAPS", SpecValue::Uint(1));
        let err = check_spec_against(&files, &wrong).unwrap_err().to_string();
        assert!(
            err.contains(
                "pass `light_map` (shader `light_map.vert+light_map.geom+light_map.frag`)"
            ) && err.contains("`AREA_LIGHT_MAPS` is a bool in the shader but given a uint"),
            "{err}"
        );
        let err = check_spec_against(&files, &good[..3])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("`HAS_MAPS` (bool at constant_id 3) is not given a value"),
            "{err}"
        );
    }
}
