//! A pass's bindings and attachments, declared once with their access.
//!
//! `.bind(binding, resource, access)` is the only statement of a descriptor: the graph derives
//! the barrier from the access, [`PassContext::bind`](super::PassContext::bind) writes the
//! descriptor from it, and [`check`] (run by `compile`) holds it against the bindings the
//! pipeline's shaders declare (reflected SPIR-V), so a wrong number, kind, stage or a read of
//! a binding the shader may write is an error naming the pass, the binding and the shader —
//! before any GPU work. Attachments likewise: `.color(image, Load::Clear(..))` states the load
//! op once and `PassContext::begin_rendering` begins with it.

use super::{Access, BindingError, GraphError, ImageHandle, RenderGraph, ResourceId, Shader};
use crate::vk::reflect::{BindingKind, ShaderInterface, Stages};
use crate::vk::vk;

/// How an attachment starts its pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Load {
    /// Cleared to this color (color attachments).
    Clear([f32; 4]),
    /// Cleared to this depth (depth attachments).
    ClearDepth(f32),
    /// Keeps its contents (drawing over what an earlier pass wrote).
    Keep,
}

/// What fills a declared binding.
#[derive(Clone, Debug)]
pub(crate) enum BindingSource {
    /// One resource, for the whole pass.
    Fixed(ResourceId),
    /// One of these resources, chosen per dispatch or draw by the record closure
    /// ([`PassContext::bind_with`](super::PassContext::bind_with)): chunked point lists,
    /// per-material textures.
    OneOf(Vec<ResourceId>),
}

/// One declared descriptor binding.
#[derive(Clone, Debug)]
pub(crate) struct BindingDecl {
    pub binding: u32,
    pub source: BindingSource,
    pub access: Access,
    pub sampler: Option<vk::Sampler>,
    /// An image binding of one mip level's view (`None`: the whole image).
    pub mip: Option<u32>,
}

impl BindingDecl {
    pub fn new(binding: u32, resource: ResourceId, access: Access) -> Self {
        Self {
            binding,
            source: BindingSource::Fixed(resource),
            access,
            sampler: None,
            mip: None,
        }
    }
    pub fn one_of(binding: u32, resources: Vec<ResourceId>, access: Access) -> Self {
        Self {
            binding,
            source: BindingSource::OneOf(resources),
            access,
            sampler: None,
            mip: None,
        }
    }
    /// The resources that may fill the binding.
    pub fn resources(&self) -> &[ResourceId] {
        match &self.source {
            BindingSource::Fixed(r) => std::slice::from_ref(r),
            BindingSource::OneOf(rs) => rs,
        }
    }
}

/// One declared attachment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AttachmentDecl {
    pub image: ImageHandle,
    pub load: Load,
    pub depth: bool,
    /// A depth attachment tested but not written (`PassBuilder::depth_read`).
    pub read_only: bool,
}

/// The descriptor kind an access of a resource takes (`None`: not a descriptor access).
fn kind_of(access: Access, is_image: bool) -> Option<BindingKind> {
    match (access, is_image) {
        (Access::Sampled(_), true) => Some(BindingKind::CombinedImageSampler),
        (Access::StorageRead(_) | Access::StorageWrite(_) | Access::StorageReadWrite(_), true) => {
            Some(BindingKind::StorageImage)
        }
        (Access::StorageRead(_) | Access::StorageWrite(_) | Access::StorageReadWrite(_), false) => {
            Some(BindingKind::StorageBuffer)
        }
        (Access::Uniform(_), false) => Some(BindingKind::UniformBuffer),
        _ => None,
    }
}

fn stages_of(shader: Shader) -> Stages {
    match shader {
        Shader::Vertex => Stages::VERTEX,
        Shader::Geometry => Stages::GEOMETRY,
        Shader::Fragment => Stages::FRAGMENT,
        Shader::Graphics => Stages::VERTEX
            .union(Stages::GEOMETRY)
            .union(Stages::FRAGMENT),
        Shader::Compute => Stages::COMPUTE,
    }
}

fn shader_of(access: Access) -> Option<Shader> {
    match access {
        Access::Sampled(s)
        | Access::StorageRead(s)
        | Access::StorageWrite(s)
        | Access::StorageReadWrite(s)
        | Access::Uniform(s) => Some(s),
        _ => None,
    }
}

fn describe(kind: Option<BindingKind>, access: Access) -> &'static str {
    match kind {
        Some(k) => k.glsl_name(),
        None => match access {
            Access::Sampled(_) => "sampled buffer",
            Access::Uniform(_) => "uniform image",
            _ => "non-descriptor access",
        },
    }
}

fn binding_error(e: BindingError) -> GraphError {
    GraphError::Binding(Box::new(e))
}

/// Holds one resource that may fill binding `b` of `pass` against the reflected binding.
fn check_binding(
    graph: &RenderGraph,
    pass: &str,
    interface: &ShaderInterface,
    b: &BindingDecl,
    resource: ResourceId,
) -> Result<(), GraphError> {
    let pass_name = || pass.to_owned();
    let shader = || interface.name.clone();
    let decl = &graph.resources[resource.0 as usize];
    let resource_name = || decl.name.clone();
    let Some(reflected) = interface.bindings.get(&b.binding) else {
        return Err(binding_error(BindingError::UnknownBinding {
            pass: pass_name(),
            shader: shader(),
            binding: b.binding,
            resource: resource_name(),
        }));
    };
    let kind = kind_of(b.access, decl.is_image());
    if kind != Some(reflected.kind) {
        return Err(binding_error(BindingError::BindingKindMismatch {
            pass: pass_name(),
            shader: shader(),
            binding: b.binding,
            resource: resource_name(),
            name: reflected.name.clone(),
            declared: describe(kind, b.access),
            expected: reflected.kind.glsl_name(),
        }));
    }
    let declared = shader_of(b.access).map_or(Stages::default(), stages_of);
    if !declared.contains(reflected.stages) {
        return Err(binding_error(BindingError::BindingStageMismatch {
            pass: pass_name(),
            shader: shader(),
            binding: b.binding,
            resource: resource_name(),
            name: reflected.name.clone(),
            declared: declared.names(),
            used: reflected.stages.names(),
        }));
    }
    let info = b.access.info();
    let storage = matches!(
        reflected.kind,
        BindingKind::StorageImage | BindingKind::StorageBuffer
    );
    if storage && !info.writes && !reflected.read_only {
        return Err(binding_error(BindingError::ReadOfWritableBinding {
            pass: pass_name(),
            shader: shader(),
            binding: b.binding,
            resource: resource_name(),
            name: reflected.name.clone(),
        }));
    }
    if info.writes && reflected.read_only {
        return Err(binding_error(BindingError::WriteOfReadonlyBinding {
            pass: pass_name(),
            shader: shader(),
            binding: b.binding,
            resource: resource_name(),
            name: reflected.name.clone(),
        }));
    }
    Ok(())
}

/// Checks every pass's declared bindings against its pipeline's reflected interface.
pub(crate) fn check(graph: &RenderGraph) -> Result<(), GraphError> {
    for pass in &graph.passes {
        let pass_name = || pass.name.clone();
        let Some(interface) = pass.interface else {
            if !pass.bindings.is_empty() {
                return Err(binding_error(BindingError::BindingsWithoutPipeline {
                    pass: pass_name(),
                }));
            }
            continue;
        };
        let shader = || interface.name.clone();
        for (i, b) in pass.bindings.iter().enumerate() {
            if pass.bindings[..i].iter().any(|o| o.binding == b.binding) {
                return Err(binding_error(BindingError::DuplicateBinding {
                    pass: pass_name(),
                    binding: b.binding,
                }));
            }
        }
        for b in &pass.bindings {
            if b.resources().is_empty() {
                return Err(binding_error(BindingError::EmptyChoice {
                    pass: pass_name(),
                    binding: b.binding,
                }));
            }
            for &resource in b.resources() {
                check_binding(graph, &pass.name, interface, b, resource)?;
            }
        }
        for (binding, reflected) in &interface.bindings {
            if !pass.bindings.iter().any(|b| b.binding == *binding) {
                return Err(binding_error(BindingError::UnboundBinding {
                    pass: pass_name(),
                    shader: shader(),
                    binding: *binding,
                    name: reflected.name.clone(),
                    kind: reflected.kind.glsl_name(),
                }));
            }
        }
        let sizes: Vec<(String, (u32, u32))> = pass
            .attachments
            .iter()
            .filter_map(|a| match &graph.resources[a.image.0 .0 as usize].kind {
                super::ResourceKind::Image(d) => Some((d.name.clone(), (d.width, d.height))),
                super::ResourceKind::Buffer { .. } => None,
            })
            .collect();
        if let Some(((a, _), (b, _))) = sizes
            .first()
            .and_then(|f| sizes.iter().find(|o| o.1 != f.1).map(|o| (f, o)))
        {
            return Err(binding_error(BindingError::AttachmentSizeMismatch {
                pass: pass_name(),
                a: a.clone(),
                b: b.clone(),
            }));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Access, RenderGraph, Shader};
    use crate::vk::reflect::{ReflectedBinding, ShaderInterface};
    use crate::vk::ImageDesc;

    /// An interface like `tonemap.comp`'s: a sampler at 0, a writeonly storage image at 1.
    fn tonemap_like() -> &'static ShaderInterface {
        let mut i = ShaderInterface {
            name: "t.comp".into(),
            ..Default::default()
        };
        for (binding, kind, read_only, write_only) in [
            (0, BindingKind::CombinedImageSampler, true, false),
            (1, BindingKind::StorageImage, false, true),
            (2, BindingKind::StorageBuffer, true, false),
        ] {
            i.bindings.insert(
                binding,
                ReflectedBinding {
                    binding,
                    kind,
                    name: format!("b{binding}"),
                    count: 1,
                    read_only,
                    write_only,
                    stages: Stages::COMPUTE,
                },
            );
        }
        Box::leak(Box::new(i))
    }

    struct Fake(&'static ShaderInterface);
    impl crate::vk::Bindable for Fake {
        fn bind_info(&self) -> (vk::PipelineBindPoint, vk::Pipeline, vk::PipelineLayout) {
            (
                vk::PipelineBindPoint::COMPUTE,
                vk::Pipeline::null(),
                vk::PipelineLayout::null(),
            )
        }
        fn interface(&self) -> &'static ShaderInterface {
            self.0
        }
    }

    /// Declares the pass with `edit` applied to the correct declaration's list.
    fn graph_with(
        edit: impl FnOnce(
            crate::graph::PassBuilder<'_>,
            crate::graph::ImageHandle,
            crate::graph::ImageHandle,
            crate::graph::BufferHandle,
        ) -> crate::graph::PassBuilder<'_>,
    ) -> Result<(), GraphError> {
        let mut g = RenderGraph::new();
        let src = g.import_image_desc(
            ImageDesc::new_2d("src", vk::Format::R8G8B8A8_UNORM, 4, 4),
            Access::Sampled(Shader::Compute),
        );
        let dst = g.import_image_desc(
            ImageDesc::new_2d("dst", vk::Format::R8G8B8A8_UNORM, 4, 4),
            Access::StorageWrite(Shader::Compute),
        );
        let buf = g.import_buffer_desc("buf", 64, Access::StorageRead(Shader::Compute));
        let pipe = Fake(tonemap_like());
        let p = g.add_pass("t").pipeline(&pipe);
        edit(p, src, dst, buf).record(|_| {});
        check(&g)
    }

    #[test]
    fn a_correct_declaration_passes() {
        let sampler = vk::Sampler::null();
        graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, sampler, Shader::Compute)
                .bind(1, dst, Access::StorageWrite(Shader::Compute))
                .bind(2, buf, Access::StorageRead(Shader::Compute))
        })
        .unwrap();
    }

    #[test]
    fn every_disagreement_with_the_shader_is_an_error() {
        let s = vk::Sampler::null();
        let c = Shader::Compute;
        let missing = graph_with(|p, src, dst, _| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
        });
        assert!(matches!(
            missing,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::UnboundBinding { binding: 2, .. })
        ));
        let unknown = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind(2, buf, Access::StorageRead(c))
                .bind(7, buf, Access::StorageRead(c))
        });
        assert!(matches!(
            unknown,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::UnknownBinding { binding: 7, .. })
        ));
        let kind = graph_with(|p, src, dst, buf| {
            p.bind(0, src, Access::StorageRead(c))
                .bind(1, dst, Access::StorageWrite(c))
                .bind(2, buf, Access::StorageRead(c))
        });
        assert!(matches!(
            kind,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::BindingKindMismatch { binding: 0, .. })
        ));
        let stage = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, Shader::Fragment)
                .bind(1, dst, Access::StorageWrite(c))
                .bind(2, buf, Access::StorageRead(c))
        });
        assert!(matches!(
            stage,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::BindingStageMismatch { binding: 0, .. })
        ));
        let write_of_readonly = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind(2, buf, Access::StorageReadWrite(c))
        });
        assert!(matches!(
            write_of_readonly,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::WriteOfReadonlyBinding { binding: 2, .. })
        ));
        let read_of_writable = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageRead(c))
                .bind(2, buf, Access::StorageRead(c))
        });
        assert!(matches!(
            read_of_writable,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::ReadOfWritableBinding { binding: 1, .. })
        ));
        let twice = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind(2, buf, Access::StorageRead(c))
                .bind(2, buf, Access::StorageRead(c))
        });
        assert!(matches!(
            twice,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::DuplicateBinding { binding: 2, .. })
        ));
    }

    #[test]
    fn every_choice_of_a_one_of_binding_is_checked() {
        let (s, c) = (vk::Sampler::null(), Shader::Compute);
        let image_among_buffers = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind_one_of(2, [buf.0, src.0], Access::StorageRead(c))
        });
        assert!(matches!(
            image_among_buffers,
            Err(GraphError::Binding(b)) if matches!(
                &*b,
                BindingError::BindingKindMismatch { binding: 2, resource, .. } if resource == "src"
            )
        ));
        let write_of_readonly = graph_with(|p, src, dst, buf| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind_one_of(2, [buf], Access::StorageReadWrite(c))
        });
        assert!(matches!(
            write_of_readonly,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::WriteOfReadonlyBinding { binding: 2, .. })
        ));
        let empty = graph_with(|p, src, dst, _| {
            p.bind_sampled(0, src, s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind_one_of(
                    2,
                    Vec::<crate::graph::BufferHandle>::new(),
                    Access::StorageRead(c),
                )
        });
        assert!(matches!(
            empty,
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::EmptyChoice { binding: 2, .. })
        ));
        let sampled = graph_with(|p, src, dst, buf| {
            p.bind_one_of_sampled(0, [src, src], s, c)
                .bind(1, dst, Access::StorageWrite(c))
                .bind_one_of(2, [buf], Access::StorageRead(c))
        });
        sampled.unwrap();
    }

    /// A one-of binding declares an access of each of its resources (once), so each gets the
    /// barrier after the pass that wrote it, as a `.bind()` of it would.
    #[test]
    fn each_choice_gets_its_barrier() {
        let c = Shader::Compute;
        let mut g = RenderGraph::new();
        let src = g.import_image_desc(
            ImageDesc::new_2d("src", vk::Format::R8G8B8A8_UNORM, 4, 4),
            Access::Sampled(c),
        );
        let dst = g.import_image_desc(
            ImageDesc::new_2d("dst", vk::Format::R8G8B8A8_UNORM, 4, 4),
            Access::StorageWrite(c),
        );
        let (a, b) = (
            g.create_buffer("chunk a", 64),
            g.create_buffer("chunk b", 64),
        );
        g.add_pass("fill")
            .write(a, Access::TransferWrite)
            .write(b, Access::TransferWrite)
            .record(|_| {});
        let pipe = Fake(tonemap_like());
        g.add_pass("t")
            .pipeline(&pipe)
            .bind_sampled(0, src, vk::Sampler::null(), c)
            .bind(1, dst, Access::StorageWrite(c))
            .bind_one_of(2, [a, b, a], Access::StorageRead(c))
            .record(|_| {});
        let t = &g.passes[1];
        assert_eq!(t.bindings[2].resources(), &[a.0, b.0], "choices are a set");
        assert_eq!(t.accesses.iter().filter(|x| x.0 == a.0).count(), 1);
        let compiled = g.compile(&crate::graph::EstimateOracle).unwrap();
        let pos = compiled
            .order
            .iter()
            .position(|&p| compiled.pass_names[p] == "t")
            .unwrap();
        for chunk in [a, b] {
            let barrier = compiled.pass_barriers[pos]
                .iter()
                .find(|x| x.resource == chunk.0)
                .expect("a barrier before the read");
            assert_eq!(barrier.src_access, vk::AccessFlags2::TRANSFER_WRITE);
            assert_eq!(barrier.dst_access, vk::AccessFlags2::SHADER_STORAGE_READ);
        }
    }

    #[test]
    fn bindings_need_a_pipeline() {
        let mut g = RenderGraph::new();
        let buf = g.import_buffer_desc("buf", 64, Access::StorageRead(Shader::Compute));
        g.add_pass("p")
            .bind(0, buf, Access::StorageRead(Shader::Compute))
            .record(|_| {});
        assert!(matches!(
            check(&g),
            Err(GraphError::Binding(b)) if matches!(*b, BindingError::BindingsWithoutPipeline { .. })
        ));
    }
}
