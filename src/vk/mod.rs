//! Thin layer over `ash`. The only module that calls Vulkan directly; every `unsafe` block
//! states the invariant it relies on in a `// SAFETY:` line.

mod cmd;
mod context;
mod frame;
mod pipeline;
pub mod reflect;
mod release;
mod resources;
mod swapchain;

pub use ash::vk;
pub use cmd::{Attachment, Cmd};
pub use context::{
    describe_devices, Context, ContextDesc, DeviceInfo, TeardownReport, ValidationLog,
};
pub use frame::{
    FrameLoop, FrameSlot, InFlight, PassTiming, TimestampRecorder, MAX_FRAMES_IN_FLIGHT,
};
pub use pipeline::{
    check_push_against, check_spec_against, check_struct_against, descriptor_type, interface_of,
    Bindable, ComputePipeline, Descriptor, GraphicsPipeline, GraphicsPipelineDesc, Pipeline,
    PipelineHandle, PushLayout, Sampler, ShaderModule,
};
pub use reflect::{BindingKind, GpuStruct, PushConstants, ShaderInterface, SpecEntry, SpecValue};
pub use release::ReleaseQueue;
pub use resources::{Arena, Buffer, BufferDesc, Image, ImageDesc, MemoryLocation};
pub use swapchain::{surface_extensions, Acquired, Presented, Swapchain};

/// Errors of the Vulkan layer. Each message says what happened and what to do.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan loader ({0}). Install it: `sudo apt-get install libvulkan1 mesa-vulkan-drivers` (or run tools/setup)")]
    NoLoader(String),
    #[error("the validation layer VK_LAYER_KHRONOS_validation is not installed. Install it: `sudo apt-get install vulkan-validationlayers` (or run tools/setup), or run without --validate")]
    MissingValidationLayer,
    #[error("the Vulkan instance lacks the extension {0}. Update the Vulkan loader and drivers (tools/setup installs them)")]
    MissingInstanceExtension(String),
    #[error("no usable Vulkan device. Devices seen:\n{report}Install a Vulkan 1.3 driver (on a machine without a GPU: `sudo apt-get install mesa-vulkan-drivers` for lavapipe)")]
    NoDevice { report: String },
    #[error("no usable Vulkan device matches `{wanted}` (from --device or VOXGI_DEVICE). Devices seen:\n{report}Pass an index or part of a usable device's name")]
    DeviceNotFound { wanted: String, report: String },
    #[error("Vulkan call failed while trying to {what}: {result}")]
    Call {
        what: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation failed: {0}. Lower the resolution or the voxel grid size")]
    Allocation(String),
    #[error("shader `{0}` is not embedded in this build (is glsl/{0} missing?)")]
    MissingShader(String),
    #[error("invalid SPIR-V for shader `{name}`: {reason}")]
    InvalidSpirv { name: String, reason: String },
    #[error("{0}")]
    ShaderInterface(String),
    #[error("{0}")]
    Invalid(String),
}

impl VkError {
    /// Adapter for `map_err`: names the operation that failed.
    pub fn vk(what: &'static str) -> impl Fn(vk::Result) -> VkError {
        move |result| VkError::Call { what, result }
    }
}

/// SPIR-V of every `glsl/*` shader, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

    /// SPIR-V bytes of `glsl/<file_name>`, e.g. `demo_gradient.comp`.
    pub fn get(file_name: &str) -> Option<&'static [u8]> {
        ALL.iter().find(|(n, _)| *n == file_name).map(|(_, b)| *b)
    }
}
