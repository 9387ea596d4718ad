//! How a pass uses a resource, and the pipeline stages, access masks, image layouts and usage
//! flags that follow from it. Barriers are derived from these alone.

use ash::vk;

/// Shader stages a descriptor access happens in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Shader {
    Vertex,
    Geometry,
    Fragment,
    /// Vertex, geometry and fragment stages.
    Graphics,
    Compute,
}

impl Shader {
    fn stages(self) -> vk::PipelineStageFlags2 {
        use vk::PipelineStageFlags2 as S;
        match self {
            Shader::Vertex => S::VERTEX_SHADER,
            Shader::Geometry => S::GEOMETRY_SHADER,
            Shader::Fragment => S::FRAGMENT_SHADER,
            Shader::Graphics => S::VERTEX_SHADER | S::GEOMETRY_SHADER | S::FRAGMENT_SHADER,
            Shader::Compute => S::COMPUTE_SHADER,
        }
    }
}

/// One declared use of a resource by a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Sampled image / combined image sampler.
    Sampled(Shader),
    /// Storage image or storage buffer, read only.
    StorageRead(Shader),
    /// Storage image or storage buffer, written (contents before the pass are not read).
    StorageWrite(Shader),
    /// Storage image or storage buffer, read and written (atomics, read-modify-write).
    StorageReadWrite(Shader),
    /// Uniform buffer.
    Uniform(Shader),
    ColorAttachment,
    /// Color attachment with blending or a logic op (reads the old contents).
    ColorAttachmentReadWrite,
    /// Depth test and write.
    DepthAttachment,
    /// Depth test without write.
    DepthRead,
    TransferRead,
    TransferWrite,
    VertexBuffer,
    IndexBuffer,
    IndirectBuffer,
    /// The host reads the resource after the frame (read-back buffers).
    HostRead,
    /// The image is presented after the frame. As an import state it also means the frame
    /// starts from an acquired image whose contents are discarded (its first access must
    /// overwrite it), so no frame depends on the layout the presentation engine left.
    Present,
}

/// Synchronization facts of an [`Access`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccessInfo {
    pub stages: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    /// Layout an image must be in; `UNDEFINED` for buffers-only accesses.
    pub layout: vk::ImageLayout,
    pub reads: bool,
    pub writes: bool,
}

/// Every access bit that denotes a write.
pub(crate) fn write_bits() -> vk::AccessFlags2 {
    use vk::AccessFlags2 as A;
    A::SHADER_STORAGE_WRITE
        | A::SHADER_WRITE
        | A::COLOR_ATTACHMENT_WRITE
        | A::DEPTH_STENCIL_ATTACHMENT_WRITE
        | A::TRANSFER_WRITE
        | A::HOST_WRITE
        | A::MEMORY_WRITE
}

impl Access {
    pub fn info(self) -> AccessInfo {
        use vk::AccessFlags2 as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags2 as S;
        let (stages, access, layout, reads, writes) = match self {
            Access::Sampled(s) => (
                s.stages(),
                A::SHADER_SAMPLED_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                true,
                false,
            ),
            Access::StorageRead(s) => (s.stages(), A::SHADER_STORAGE_READ, L::GENERAL, true, false),
            Access::StorageWrite(s) => {
                (s.stages(), A::SHADER_STORAGE_WRITE, L::GENERAL, false, true)
            }
            Access::StorageReadWrite(s) => (
                s.stages(),
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
                L::GENERAL,
                true,
                true,
            ),
            Access::Uniform(s) => (s.stages(), A::UNIFORM_READ, L::UNDEFINED, true, false),
            Access::ColorAttachment => (
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE,
                L::COLOR_ATTACHMENT_OPTIMAL,
                false,
                true,
            ),
            Access::ColorAttachmentReadWrite => (
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
                L::COLOR_ATTACHMENT_OPTIMAL,
                true,
                true,
            ),
            // The depth test reads only values written in the same pass (after the clear), so
            // for culling and read-before-write checks this is a write.
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_ATTACHMENT_OPTIMAL,
                false,
                true,
            ),
            Access::DepthRead => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ,
                L::DEPTH_READ_ONLY_OPTIMAL,
                true,
                false,
            ),
            // Copies, blits and clears are distinct sync2 stages; a transfer access may be any.
            Access::TransferRead => (
                S::COPY | S::BLIT,
                A::TRANSFER_READ,
                L::TRANSFER_SRC_OPTIMAL,
                true,
                false,
            ),
            Access::TransferWrite => (
                S::COPY | S::BLIT | S::CLEAR,
                A::TRANSFER_WRITE,
                L::TRANSFER_DST_OPTIMAL,
                false,
                true,
            ),
            Access::VertexBuffer => (
                S::VERTEX_ATTRIBUTE_INPUT,
                A::VERTEX_ATTRIBUTE_READ,
                L::UNDEFINED,
                true,
                false,
            ),
            Access::IndexBuffer => (S::INDEX_INPUT, A::INDEX_READ, L::UNDEFINED, true, false),
            Access::IndirectBuffer => (
                S::DRAW_INDIRECT,
                A::INDIRECT_COMMAND_READ,
                L::UNDEFINED,
                true,
                false,
            ),
            Access::HostRead => (S::HOST, A::HOST_READ, L::GENERAL, true, false),
            // ALL_COMMANDS, not NONE: a frame's first barrier on a swapchain image must chain
            // with the acquire semaphore's wait, which only a non-empty source scope does.
            Access::Present => (S::ALL_COMMANDS, A::NONE, L::PRESENT_SRC_KHR, true, false),
        };
        AccessInfo {
            stages,
            access,
            layout,
            reads,
            writes,
        }
    }

    /// Whether this access is meaningful for images.
    pub fn valid_for_image(self) -> bool {
        !matches!(
            self,
            Access::Uniform(_)
                | Access::VertexBuffer
                | Access::IndexBuffer
                | Access::IndirectBuffer
        )
    }

    /// Whether this access is meaningful for buffers.
    pub fn valid_for_buffer(self) -> bool {
        !matches!(
            self,
            Access::Sampled(_)
                | Access::ColorAttachment
                | Access::ColorAttachmentReadWrite
                | Access::DepthAttachment
                | Access::DepthRead
                | Access::Present
        )
    }

    /// Image usage flags this access requires; the graph ORs them into each image's desc.
    pub fn image_usage(self) -> vk::ImageUsageFlags {
        use vk::ImageUsageFlags as U;
        match self {
            Access::Sampled(_) => U::SAMPLED,
            Access::StorageRead(_) | Access::StorageWrite(_) | Access::StorageReadWrite(_) => {
                U::STORAGE
            }
            Access::ColorAttachment | Access::ColorAttachmentReadWrite => U::COLOR_ATTACHMENT,
            Access::DepthAttachment | Access::DepthRead => U::DEPTH_STENCIL_ATTACHMENT,
            Access::TransferRead => U::TRANSFER_SRC,
            Access::TransferWrite => U::TRANSFER_DST,
            _ => U::empty(),
        }
    }

    /// Buffer usage flags this access requires.
    pub fn buffer_usage(self) -> vk::BufferUsageFlags {
        use vk::BufferUsageFlags as U;
        match self {
            Access::StorageRead(_) | Access::StorageWrite(_) | Access::StorageReadWrite(_) => {
                U::STORAGE_BUFFER
            }
            Access::Uniform(_) => U::UNIFORM_BUFFER,
            Access::TransferRead => U::TRANSFER_SRC,
            Access::TransferWrite => U::TRANSFER_DST,
            Access::VertexBuffer => U::VERTEX_BUFFER,
            Access::IndexBuffer => U::INDEX_BUFFER,
            Access::IndirectBuffer => U::INDIRECT_BUFFER,
            _ => U::empty(),
        }
    }
}

/// Mip levels and array layers of an image an access touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Subresource {
    pub base_mip: u32,
    pub mip_count: u32,
    pub base_layer: u32,
    pub layer_count: u32,
}

impl Subresource {
    /// A single mip level, all layers (`layers` of the image).
    pub fn mip(level: u32) -> SubresourceSel {
        SubresourceSel {
            mips: Some((level, 1)),
            layers: None,
        }
    }
    /// A range of mip levels, all layers.
    pub fn mips(base: u32, count: u32) -> SubresourceSel {
        SubresourceSel {
            mips: Some((base, count)),
            layers: None,
        }
    }
}

/// A partial selection, completed against the image's mip and layer counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SubresourceSel {
    pub mips: Option<(u32, u32)>,
    pub layers: Option<(u32, u32)>,
}

impl SubresourceSel {
    pub fn whole() -> Self {
        Self::default()
    }
    pub fn layers(mut self, base: u32, count: u32) -> Self {
        self.layers = Some((base, count));
        self
    }
    pub(crate) fn resolve(self, mip_levels: u32, layers: u32) -> Subresource {
        let (base_mip, mip_count) = self.mips.unwrap_or((0, mip_levels));
        let (base_layer, layer_count) = self.layers.unwrap_or((0, layers));
        Subresource {
            base_mip,
            mip_count,
            base_layer,
            layer_count,
        }
    }
}
