//! SPIR-V reflection: the descriptor bindings, the push-constant block, the specialization
//! constants and the layouts of the structs in buffer blocks a shader declares.
//!
//! The shader is the one statement of a pipeline's interface. Pipeline layouts are built from
//! what this module reads out of the SPIR-V, and the render graph checks each pass's declared
//! bindings against it (`graph::bind`), so a binding is never typed in twice. Rust structs
//! that mirror push blocks ([`push_constants!`](crate::push_constants)) or buffer structs
//! ([`gpu_struct!`](crate::gpu_struct)) are checked against the reflected layouts by name,
//! offset and size; specialization constants ([`spec_constants!`](crate::spec_constants)) by
//! name and type. Pure logic: it reads the words `build.rs` embedded and needs no device.
//!
//! Only what voxgi's shaders use is understood: descriptor set 0, combined image samplers,
//! storage images, storage and uniform buffers (arrays of them count as one binding with a
//! count), and one push-constant block per stage. Anything else is an error naming the shader,
//! not a silent gap.

#![forbid(unsafe_code)]

use std::collections::{BTreeMap, HashMap};

/// The kind of descriptor a binding takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    /// `sampler2D` and friends: an image view with a sampler.
    CombinedImageSampler,
    /// `image2D` and friends.
    StorageImage,
    /// `buffer` blocks (std430).
    StorageBuffer,
    /// `uniform` blocks (std140).
    UniformBuffer,
}

impl BindingKind {
    pub fn glsl_name(self) -> &'static str {
        match self {
            BindingKind::CombinedImageSampler => "combined image sampler",
            BindingKind::StorageImage => "storage image",
            BindingKind::StorageBuffer => "storage buffer",
            BindingKind::UniformBuffer => "uniform buffer",
        }
    }
}

/// Shader stages, as a small bit set (the Vulkan flags live in the `vk` layer's callers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Stages(pub u8);

impl Stages {
    pub const VERTEX: Stages = Stages(1);
    pub const GEOMETRY: Stages = Stages(2);
    pub const FRAGMENT: Stages = Stages(4);
    pub const COMPUTE: Stages = Stages(8);

    pub fn union(self, other: Stages) -> Stages {
        Stages(self.0 | other.0)
    }
    pub fn contains(self, other: Stages) -> bool {
        self.0 & other.0 == other.0
    }
    /// The stage of a shader file by its extension (`.vert`, `.geom`, `.frag`, `.comp`).
    pub fn of_file(file_name: &str) -> Option<Stages> {
        match file_name.rsplit('.').next()? {
            "vert" => Some(Stages::VERTEX),
            "geom" => Some(Stages::GEOMETRY),
            "frag" => Some(Stages::FRAGMENT),
            "comp" => Some(Stages::COMPUTE),
            _ => None,
        }
    }
    /// Stage names joined by `+`, for messages.
    pub fn names(self) -> String {
        let all = [
            (Stages::VERTEX, "vertex"),
            (Stages::GEOMETRY, "geometry"),
            (Stages::FRAGMENT, "fragment"),
            (Stages::COMPUTE, "compute"),
        ];
        let v: Vec<&str> = all
            .iter()
            .filter(|(s, _)| self.contains(*s))
            .map(|(_, n)| *n)
            .collect();
        v.join("+")
    }
}

/// One descriptor binding of set 0.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReflectedBinding {
    pub binding: u32,
    pub kind: BindingKind,
    /// The GLSL variable (or block instance/type) name, for messages.
    pub name: String,
    /// Array length (1 for a single descriptor).
    pub count: u32,
    /// Declared `readonly` (images) or every member `readonly` (buffers).
    pub read_only: bool,
    /// Declared `writeonly`.
    pub write_only: bool,
    /// Stages that declare it.
    pub stages: Stages,
}

/// One member of the push-constant block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PushMember {
    pub name: String,
    pub offset: u32,
    pub size_bytes: u32,
}

/// The push-constant block.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct PushBlock {
    pub members: Vec<PushMember>,
    /// End of the last member (what a pipeline layout's range must cover).
    pub size_bytes: u32,
}

/// One member of a struct in a buffer block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StructMember {
    pub name: String,
    pub offset: u32,
    /// Bytes it spans: arrays stride × length, runtime arrays 0, matrices their columns'
    /// stride × count.
    pub size_bytes: u32,
}

/// The explicit layout (offsets and strides as std430 or std140 gave them) of a struct that a
/// storage or uniform buffer block holds, or of the block itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StructLayout {
    /// The GLSL type name (the block's type name for a block).
    pub name: String,
    pub members: Vec<StructMember>,
    /// End of the last member.
    pub size_bytes: u32,
    /// The array stride where the shader declares an array of it: the size a mirroring Rust
    /// struct must have exactly.
    pub array_stride: Option<u32>,
}

/// What one shader, or the stages of one pipeline together, declares.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct ShaderInterface {
    /// The shader files, joined by `+` for a pipeline of several stages.
    pub name: String,
    pub bindings: BTreeMap<u32, ReflectedBinding>,
    pub push: Option<PushBlock>,
    /// The structs of its storage and uniform buffer blocks (nested ones too) and the blocks
    /// themselves, by GLSL type name.
    pub structs: BTreeMap<String, StructLayout>,
    /// Its specialization constants by GLSL name: those the compiled SPIR-V still declares
    /// (the optimizer drops a constant no code reads).
    pub spec: BTreeMap<String, SpecConstant>,
}

/// The scalar type of a specialization constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SpecType {
    Bool,
    Uint,
    Int,
    Float,
}

impl SpecType {
    pub fn glsl_name(self) -> &'static str {
        match self {
            SpecType::Bool => "bool",
            SpecType::Uint => "uint",
            SpecType::Int => "int",
            SpecType::Float => "float",
        }
    }
}

/// One specialization constant (`layout(constant_id = N) const T NAME`). The workgroup size
/// set by `layout(local_size_x_id = N) in;` has no GLSL name and is called `local_size_x`
/// (`_y`, `_z`) after its layout qualifier.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SpecConstant {
    pub name: String,
    pub id: u32,
    pub ty: SpecType,
}

/// A value for a specialization constant, typed so that a `bool` cannot be given to a `uint`.
/// Make lists of them with [`spec_constants!`](crate::spec_constants).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpecValue {
    Bool(bool),
    Uint(u32),
    Int(i32),
    Float(f32),
}

impl SpecValue {
    pub fn ty(self) -> SpecType {
        match self {
            SpecValue::Bool(_) => SpecType::Bool,
            SpecValue::Uint(_) => SpecType::Uint,
            SpecValue::Int(_) => SpecType::Int,
            SpecValue::Float(_) => SpecType::Float,
        }
    }

    /// The 32 bits Vulkan reads: a `VkBool32` (0 or 1) for a bool, the value's bits otherwise.
    pub fn bits(self) -> u32 {
        match self {
            SpecValue::Bool(b) => u32::from(b),
            SpecValue::Uint(v) => v,
            SpecValue::Int(v) => v as u32,
            SpecValue::Float(v) => v.to_bits(),
        }
    }
}

impl From<bool> for SpecValue {
    fn from(v: bool) -> Self {
        SpecValue::Bool(v)
    }
}
impl From<u32> for SpecValue {
    fn from(v: u32) -> Self {
        SpecValue::Uint(v)
    }
}
impl From<i32> for SpecValue {
    fn from(v: i32) -> Self {
        SpecValue::Int(v)
    }
}
impl From<f32> for SpecValue {
    fn from(v: f32) -> Self {
        SpecValue::Float(v)
    }
}

/// A named specialization constant value, as [`spec_constants!`](crate::spec_constants) lists
/// them.
pub type SpecEntry = (&'static str, SpecValue);

/// The specialization constants of a pipeline by their GLSL names, checked against the SPIR-V
/// when the pipeline is created: `spec_constants![HAS_PHONG = phong, K = MAX_LAYERS]` is an
/// array of [`SpecEntry`]. The value's Rust type picks the GLSL type it must match (`bool`,
/// `u32` for `uint`, `i32` for `int`, `f32` for `float`).
#[macro_export]
macro_rules! spec_constants {
    ($($name:ident = $value:expr),* $(,)?) => {
        [$((stringify!($name), $crate::vk::reflect::SpecValue::from($value))),*]
    };
}

/// Why a shader's interface could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ReflectError {
    #[error("shader `{0}`: not SPIR-V (bad magic number or truncated)")]
    NotSpirv(String),
    #[error("shader `{shader}`: `{name}` is in descriptor set {set}; voxgi pipelines have one push-descriptor set: use set = 0")]
    OtherSet {
        shader: String,
        name: String,
        set: u32,
    },
    #[error("shader `{shader}`: `{name}` at binding {binding} is a {what}, which voxgi does not bind: use a combined image sampler, storage image, storage buffer or uniform buffer")]
    Unsupported {
        shader: String,
        name: String,
        binding: u32,
        what: &'static str,
    },
    #[error("pipeline `{pipeline}`: binding {binding} is a {a} in one stage and a {b} in another: declare it the same way in every stage")]
    StageConflict {
        pipeline: String,
        binding: u32,
        a: &'static str,
        b: &'static str,
    },
    #[error("pipeline `{pipeline}`: its stages lay out struct `{name}` differently: declare it the same way in every stage")]
    StructConflict { pipeline: String, name: String },
    #[error("pipeline `{pipeline}`: its stages declare specialization constant `{name}` differently ({a} vs {b}): give it the same constant_id and type in every stage")]
    SpecConflict {
        pipeline: String,
        name: String,
        a: String,
        b: String,
    },
    #[error("shader `{shader}`: specialization constant id {id} has no name: declare it as `layout(constant_id = {id}) const T NAME`")]
    UnnamedSpec { shader: String, id: u32 },
    #[error("pipeline `{pipeline}`: the push-constant blocks of its stages disagree on member `{member}` ({a} vs {b}): declare the same block in every stage")]
    PushConflict {
        pipeline: String,
        member: String,
        a: String,
        b: String,
    },
}

// SPIR-V opcodes, decorations and storage classes used here (SPIR-V 1.6 specification, §3).
const OP_NAME: u16 = 5;
const OP_MEMBER_NAME: u16 = 6;
const OP_TYPE_BOOL: u16 = 20;
const OP_TYPE_INT: u16 = 21;
const OP_TYPE_FLOAT: u16 = 22;
const OP_TYPE_VECTOR: u16 = 23;
const OP_TYPE_MATRIX: u16 = 24;
const OP_TYPE_IMAGE: u16 = 25;
const OP_TYPE_SAMPLER: u16 = 26;
const OP_TYPE_SAMPLED_IMAGE: u16 = 27;
const OP_TYPE_ARRAY: u16 = 28;
const OP_TYPE_RUNTIME_ARRAY: u16 = 29;
const OP_TYPE_STRUCT: u16 = 30;
const OP_TYPE_POINTER: u16 = 32;
const OP_CONSTANT: u16 = 43;
const OP_SPEC_CONSTANT_TRUE: u16 = 48;
const OP_SPEC_CONSTANT_FALSE: u16 = 49;
const OP_SPEC_CONSTANT: u16 = 50;
const OP_VARIABLE: u16 = 59;
const OP_DECORATE: u16 = 71;
const OP_EXECUTION_MODE_ID: u16 = 331;
const OP_MEMBER_DECORATE: u16 = 72;

const DEC_SPEC_ID: u32 = 1;
const DEC_BLOCK: u32 = 2;
const DEC_BUFFER_BLOCK: u32 = 3;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_MATRIX_STRIDE: u32 = 7;
const DEC_NON_WRITABLE: u32 = 24;
const DEC_NON_READABLE: u32 = 25;
const DEC_BINDING: u32 = 33;
const DEC_DESCRIPTOR_SET: u32 = 34;
const DEC_OFFSET: u32 = 35;
const EXECUTION_MODE_LOCAL_SIZE_ID: u32 = 38;

const SC_UNIFORM_CONSTANT: u32 = 0;
const SC_UNIFORM: u32 = 2;
const SC_PUSH_CONSTANT: u32 = 9;
const SC_STORAGE_BUFFER: u32 = 12;

#[derive(Clone, Debug)]
enum Type {
    Scalar {
        bytes: u32,
    },
    Vector {
        component: u32,
        count: u32,
    },
    Matrix {
        column: u32,
        count: u32,
    },
    /// `sampled`: 1 sampled, 2 storage (OpTypeImage's "Sampled" operand).
    Image {
        sampled: u32,
    },
    Sampler,
    SampledImage,
    Array {
        element: u32,
        length_id: u32,
    },
    RuntimeArray {
        element: u32,
    },
    Struct {
        members: Vec<u32>,
    },
    Pointer {
        pointee: u32,
    },
}

#[derive(Default)]
struct Module {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    decorations: HashMap<u32, Vec<(u32, u32)>>,
    member_decorations: HashMap<(u32, u32), Vec<(u32, u32)>>,
    types: HashMap<u32, Type>,
    constants: HashMap<u32, u32>,
    /// (id, pointer type, storage class)
    variables: Vec<(u32, u32, u32)>,
    /// The scalar type of each scalar type id (bool, int, float), for specialization constants.
    scalar_types: HashMap<u32, SpecType>,
    /// (result id, type id) of each scalar specialization constant, in module order.
    spec_constants: Vec<(u32, u32)>,
    /// The x, y and z operands of `OpExecutionModeId … LocalSizeId` (`local_size_x_id`).
    local_size_ids: Vec<u32>,
}

impl Module {
    fn parse(shader: &str, words: &[u32]) -> Result<Module, ReflectError> {
        if words.len() < 5 || words[0] != 0x0723_0203 {
            return Err(ReflectError::NotSpirv(shader.into()));
        }
        let mut m = Module::default();
        let mut i = 5;
        while i < words.len() {
            let count = (words[i] >> 16) as usize;
            let opcode = (words[i] & 0xffff) as u16;
            if count == 0 || i + count > words.len() {
                return Err(ReflectError::NotSpirv(shader.into()));
            }
            let ops = &words[i + 1..i + count];
            let at = |k: usize| ops.get(k).copied().unwrap_or(0);
            match opcode {
                OP_NAME => {
                    m.names.insert(at(0), string(&ops[1.min(ops.len())..]));
                }
                OP_MEMBER_NAME => {
                    m.member_names
                        .insert((at(0), at(1)), string(&ops[2.min(ops.len())..]));
                }
                OP_DECORATE => m.decorations.entry(at(0)).or_default().push((at(1), at(2))),
                OP_MEMBER_DECORATE => m
                    .member_decorations
                    .entry((at(0), at(1)))
                    .or_default()
                    .push((at(2), at(3))),
                OP_TYPE_INT | OP_TYPE_FLOAT => {
                    m.types.insert(at(0), Type::Scalar { bytes: at(1) / 8 });
                    let ty = match (opcode, at(2)) {
                        (OP_TYPE_FLOAT, _) => SpecType::Float,
                        (_, 0) => SpecType::Uint,
                        _ => SpecType::Int,
                    };
                    m.scalar_types.insert(at(0), ty);
                }
                OP_TYPE_BOOL => {
                    m.scalar_types.insert(at(0), SpecType::Bool);
                }
                OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE | OP_SPEC_CONSTANT => {
                    m.spec_constants.push((at(1), at(0)));
                }
                OP_EXECUTION_MODE_ID if at(1) == EXECUTION_MODE_LOCAL_SIZE_ID => {
                    m.local_size_ids = ops.get(2..).unwrap_or(&[]).to_vec();
                }
                OP_TYPE_VECTOR => {
                    m.types.insert(
                        at(0),
                        Type::Vector {
                            component: at(1),
                            count: at(2),
                        },
                    );
                }
                OP_TYPE_MATRIX => {
                    m.types.insert(
                        at(0),
                        Type::Matrix {
                            column: at(1),
                            count: at(2),
                        },
                    );
                }
                OP_TYPE_IMAGE => {
                    m.types.insert(at(0), Type::Image { sampled: at(6) });
                }
                OP_TYPE_SAMPLER => {
                    m.types.insert(at(0), Type::Sampler);
                }
                OP_TYPE_SAMPLED_IMAGE => {
                    m.types.insert(at(0), Type::SampledImage);
                }
                OP_TYPE_ARRAY => {
                    m.types.insert(
                        at(0),
                        Type::Array {
                            element: at(1),
                            length_id: at(2),
                        },
                    );
                }
                OP_TYPE_RUNTIME_ARRAY => {
                    m.types.insert(at(0), Type::RuntimeArray { element: at(1) });
                }
                OP_TYPE_STRUCT => {
                    m.types.insert(
                        at(0),
                        Type::Struct {
                            members: ops.get(1..).unwrap_or(&[]).to_vec(),
                        },
                    );
                }
                OP_TYPE_POINTER => {
                    m.types.insert(at(0), Type::Pointer { pointee: at(2) });
                }
                // 32-bit constants only: array lengths.
                OP_CONSTANT => {
                    m.constants.insert(at(1), at(2));
                }
                OP_VARIABLE => m.variables.push((at(1), at(0), at(2))),
                _ => {}
            }
            i += count;
        }
        Ok(m)
    }

    fn decoration(&self, id: u32, dec: u32) -> Option<u32> {
        self.decorations
            .get(&id)?
            .iter()
            .find(|(d, _)| *d == dec)
            .map(|(_, v)| *v)
    }

    fn member_decoration(&self, ty: u32, member: u32, dec: u32) -> Option<u32> {
        self.member_decorations
            .get(&(ty, member))?
            .iter()
            .find(|(d, _)| *d == dec)
            .map(|(_, v)| *v)
    }

    /// Size in bytes of a type laid out with its explicit strides and offsets.
    fn size_of(&self, ty: u32) -> u32 {
        match self.types.get(&ty) {
            Some(Type::Scalar { bytes }) => *bytes,
            Some(Type::Vector { component, count }) => self.size_of(*component) * count,
            Some(Type::Matrix { column, count }) => self.size_of(*column) * count,
            Some(Type::Array { element, length_id }) => {
                let stride = self
                    .decoration(ty, DEC_ARRAY_STRIDE)
                    .unwrap_or_else(|| self.size_of(*element));
                stride * self.constants.get(length_id).copied().unwrap_or(1)
            }
            Some(Type::Struct { members }) => (0..members.len() as u32)
                .map(|k| self.member_end(ty, k))
                .max()
                .unwrap_or(0),
            _ => 0,
        }
    }

    /// Offset + size of struct member `k` (a matrix member's size uses its MatrixStride).
    fn member_end(&self, ty: u32, k: u32) -> u32 {
        let Some(Type::Struct { members }) = self.types.get(&ty) else {
            return 0;
        };
        let member = members.get(k as usize).copied().unwrap_or(0);
        let offset = self.member_decoration(ty, k, DEC_OFFSET).unwrap_or(0);
        let size = match (
            self.types.get(&member),
            self.member_decoration(ty, k, DEC_MATRIX_STRIDE),
        ) {
            (Some(Type::Matrix { count, .. }), Some(stride)) => count * stride,
            _ => self.size_of(member),
        };
        offset + size
    }

    fn name_of(&self, id: u32) -> String {
        self.names.get(&id).cloned().unwrap_or_default()
    }

    /// The struct under `ty` after unwrapping arrays, with the stride of the outermost array
    /// (`None` when `ty` is no array).
    fn struct_under(&self, mut ty: u32) -> Option<(u32, Option<u32>)> {
        let mut stride = None;
        loop {
            match self.types.get(&ty)? {
                Type::Array { element, .. } | Type::RuntimeArray { element } => {
                    stride = stride.or(self.decoration(ty, DEC_ARRAY_STRIDE));
                    ty = *element;
                }
                Type::Struct { .. } => return Some((ty, stride)),
                _ => return None,
            }
        }
    }

    /// Adds the layout of struct `ty` and of the structs its members hold to `out`.
    fn collect_structs(
        &self,
        ty: u32,
        array_stride: Option<u32>,
        out: &mut BTreeMap<String, StructLayout>,
    ) {
        let Some(Type::Struct { members }) = self.types.get(&ty) else {
            return;
        };
        let layout = StructLayout {
            name: self.name_of(ty),
            members: (0..members.len() as u32)
                .map(|k| {
                    let offset = self.member_decoration(ty, k, DEC_OFFSET).unwrap_or(0);
                    StructMember {
                        name: self.member_names.get(&(ty, k)).cloned().unwrap_or_default(),
                        offset,
                        size_bytes: self.member_end(ty, k) - offset,
                    }
                })
                .collect(),
            size_bytes: self.size_of(ty),
            array_stride,
        };
        for &member in members {
            if let Some((inner, stride)) = self.struct_under(member) {
                self.collect_structs(inner, stride, out);
            }
        }
        out.entry(layout.name.clone()).or_insert(layout);
    }
}

impl Module {
    /// The specialization constants by name. glslang may emit one `constant_id` twice (the
    /// workgroup size's constant appears once in the execution mode and once in
    /// `gl_WorkGroupSize`), so the
    /// constants are grouped by id; a group takes the name one of its members has, else, for a
    /// component of the workgroup size, `local_size_x`, `_y` or `_z`.
    fn spec(&self, shader: &str) -> Result<BTreeMap<String, SpecConstant>, ReflectError> {
        let mut by_id: BTreeMap<u32, (String, SpecType)> = BTreeMap::new();
        for &(id, ty) in &self.spec_constants {
            let Some(spec_id) = self.decoration(id, DEC_SPEC_ID) else {
                continue;
            };
            let Some(&ty) = self.scalar_types.get(&ty) else {
                continue;
            };
            let entry = by_id.entry(spec_id).or_insert((String::new(), ty));
            if entry.0.is_empty() {
                entry.0 = self.name_of(id);
            }
            if entry.0.is_empty() {
                entry.0 = self.workgroup_component(id).unwrap_or_default();
            }
        }
        let mut out = BTreeMap::new();
        for (id, (name, ty)) in by_id {
            if name.is_empty() {
                return Err(ReflectError::UnnamedSpec {
                    shader: shader.into(),
                    id,
                });
            }
            out.insert(name.clone(), SpecConstant { name, id, ty });
        }
        Ok(out)
    }

    /// `local_size_x` (`_y`, `_z`) when constant `id` is that component of the workgroup size
    /// (the operands of the LocalSizeId execution mode).
    fn workgroup_component(&self, id: u32) -> Option<String> {
        let k = self.local_size_ids.iter().position(|&x| x == id)?;
        ["local_size_x", "local_size_y", "local_size_z"]
            .get(k)
            .map(|n| (*n).to_string())
    }
}

/// Decodes a nul-terminated SPIR-V literal string.
fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Reads the set-0 bindings and the push-constant block of one shader stage.
pub fn reflect(shader: &str, words: &[u32]) -> Result<ShaderInterface, ReflectError> {
    let m = Module::parse(shader, words)?;
    let stage = Stages::of_file(shader).unwrap_or_default();
    let mut out = ShaderInterface {
        name: shader.into(),
        spec: m.spec(shader)?,
        ..Default::default()
    };
    for &(var, pointer, class) in &m.variables {
        let Some(Type::Pointer { pointee }) = m.types.get(&pointer) else {
            continue;
        };
        if class == SC_PUSH_CONSTANT {
            let Some(Type::Struct { members }) = m.types.get(pointee) else {
                continue;
            };
            let members: Vec<PushMember> = (0..members.len() as u32)
                .map(|k| {
                    let offset = m.member_decoration(*pointee, k, DEC_OFFSET).unwrap_or(0);
                    PushMember {
                        name: m
                            .member_names
                            .get(&(*pointee, k))
                            .cloned()
                            .unwrap_or_default(),
                        offset,
                        size_bytes: m.member_end(*pointee, k) - offset,
                    }
                })
                .collect();
            out.push = Some(PushBlock {
                size_bytes: m.size_of(*pointee),
                members,
            });
            continue;
        }
        if ![SC_UNIFORM_CONSTANT, SC_UNIFORM, SC_STORAGE_BUFFER].contains(&class) {
            continue;
        }
        let Some(binding) = m.decoration(var, DEC_BINDING) else {
            continue;
        };
        // The variable's name; blocks declared without an instance name are named by type.
        let mut name = m.name_of(var);
        if name.is_empty() {
            name = m.name_of(*pointee);
        }
        let set = m.decoration(var, DEC_DESCRIPTOR_SET).unwrap_or(0);
        if set != 0 {
            return Err(ReflectError::OtherSet {
                shader: shader.into(),
                name,
                set,
            });
        }
        // Arrays of descriptors: unwrap to the element, counting.
        let mut ty = *pointee;
        let mut count = 1;
        loop {
            match m.types.get(&ty) {
                Some(Type::Array { element, length_id }) => {
                    count *= m.constants.get(length_id).copied().unwrap_or(1);
                    ty = *element;
                }
                Some(Type::RuntimeArray { element }) if class == SC_UNIFORM_CONSTANT => {
                    ty = *element;
                }
                _ => break,
            }
        }
        let unsupported = |what| ReflectError::Unsupported {
            shader: shader.into(),
            name: name.clone(),
            binding,
            what,
        };
        let has = |dec| m.decoration(var, dec).is_some();
        let (kind, read_only, write_only) = match (class, m.types.get(&ty)) {
            (SC_UNIFORM_CONSTANT, Some(Type::SampledImage)) => {
                (BindingKind::CombinedImageSampler, true, false)
            }
            (SC_UNIFORM_CONSTANT, Some(Type::Image { sampled: 2 })) => (
                BindingKind::StorageImage,
                has(DEC_NON_WRITABLE),
                has(DEC_NON_READABLE),
            ),
            (SC_UNIFORM_CONSTANT, Some(Type::Image { .. })) => {
                return Err(unsupported("separate sampled image"))
            }
            (SC_UNIFORM_CONSTANT, Some(Type::Sampler)) => {
                return Err(unsupported("separate sampler"))
            }
            (SC_UNIFORM | SC_STORAGE_BUFFER, Some(Type::Struct { members })) => {
                m.collect_structs(ty, None, &mut out.structs);
                let storage =
                    class == SC_STORAGE_BUFFER || m.decoration(ty, DEC_BUFFER_BLOCK).is_some();
                if !storage && m.decoration(ty, DEC_BLOCK).is_none() {
                    return Err(unsupported("uniform without a block"));
                }
                let all = |dec| {
                    has(dec)
                        || (0..members.len() as u32)
                            .all(|k| m.member_decoration(ty, k, dec).is_some())
                };
                if storage {
                    (
                        BindingKind::StorageBuffer,
                        all(DEC_NON_WRITABLE),
                        all(DEC_NON_READABLE),
                    )
                } else {
                    (BindingKind::UniformBuffer, true, false)
                }
            }
            _ => return Err(unsupported("resource of an unknown type")),
        };
        out.bindings.insert(
            binding,
            ReflectedBinding {
                binding,
                kind,
                name,
                count,
                read_only,
                write_only,
                stages: stage,
            },
        );
    }
    Ok(out)
}

/// The interface of a pipeline made of several stages: the union of their bindings (each
/// binding of one kind in every stage that declares it) and their push-constant blocks.
pub fn merge(stages: &[ShaderInterface]) -> Result<ShaderInterface, ReflectError> {
    let name = stages
        .iter()
        .map(|s| s.name.as_str())
        .collect::<Vec<_>>()
        .join("+");
    let mut out = ShaderInterface {
        name: name.clone(),
        ..Default::default()
    };
    for s in stages {
        for (b, r) in &s.bindings {
            match out.bindings.get_mut(b) {
                Some(existing) if existing.kind != r.kind => {
                    return Err(ReflectError::StageConflict {
                        pipeline: name,
                        binding: *b,
                        a: existing.kind.glsl_name(),
                        b: r.kind.glsl_name(),
                    })
                }
                Some(existing) => {
                    existing.stages = existing.stages.union(r.stages);
                    existing.read_only &= r.read_only;
                    existing.write_only &= r.write_only;
                    existing.count = existing.count.max(r.count);
                }
                None => {
                    out.bindings.insert(*b, r.clone());
                }
            }
        }
        for (struct_name, layout) in &s.structs {
            match out.structs.get_mut(struct_name) {
                Some(x) if x.members != layout.members => {
                    return Err(ReflectError::StructConflict {
                        pipeline: name,
                        name: struct_name.clone(),
                    })
                }
                Some(x) => x.array_stride = x.array_stride.or(layout.array_stride),
                None => {
                    out.structs.insert(struct_name.clone(), layout.clone());
                }
            }
        }
        for (spec_name, c) in &s.spec {
            let clash = out
                .spec
                .values()
                .find(|x| (x.name == c.name || x.id == c.id) && *x != c);
            if let Some(x) = clash {
                let show = |c: &SpecConstant| {
                    format!("`{}` {} at constant_id {}", c.name, c.ty.glsl_name(), c.id)
                };
                return Err(ReflectError::SpecConflict {
                    pipeline: name,
                    name: spec_name.clone(),
                    a: show(x),
                    b: show(c),
                });
            }
            out.spec.insert(spec_name.clone(), c.clone());
        }
        if let Some(p) = &s.push {
            let merged = out.push.get_or_insert_with(Default::default);
            for member in &p.members {
                match merged.members.iter().find(|x| x.offset == member.offset) {
                    Some(x) if x.name != member.name || x.size_bytes != member.size_bytes => {
                        return Err(ReflectError::PushConflict {
                            pipeline: name,
                            member: member.name.clone(),
                            a: format!("`{}` at {} ({} bytes)", x.name, x.offset, x.size_bytes),
                            b: format!(
                                "`{}` at {} ({} bytes)",
                                member.name, member.offset, member.size_bytes
                            ),
                        })
                    }
                    Some(_) => {}
                    None => merged.members.push(member.clone()),
                }
            }
            merged.members.sort_by_key(|x| x.offset);
            merged.size_bytes = merged.size_bytes.max(p.size_bytes);
        }
    }
    Ok(out)
}

/// A Rust struct pushed as push constants: its named fields, checked against the shader's
/// block by [`check_push`]. Implement it with [`push_constants!`](crate::push_constants).
pub trait PushConstants: bytemuck::Pod {
    /// (field name, byte offset, size in bytes), in declaration order.
    fn fields() -> Vec<(&'static str, u32, u32)>;
}

/// A Rust struct that mirrors a struct of the shaders' storage or uniform buffers: its named
/// fields, checked against the reflected layout by [`check_struct`]. Implement it with
/// [`gpu_struct!`](crate::gpu_struct).
pub trait GpuStruct: bytemuck::Pod {
    /// (field name, byte offset, size in bytes), in declaration order.
    fn fields() -> Vec<(&'static str, u32, u32)>;
}

/// The (name, offset, size) list of a `#[repr(C)]` struct's fields, for [`push_constants!`]
/// and [`gpu_struct!`](crate::gpu_struct).
#[doc(hidden)]
#[macro_export]
macro_rules! struct_fields {
    ($ty:ty { $($field:ident),* $(,)? }) => {{
        fn size_of_field<T, F>(_: impl Fn(&T) -> &F) -> u32 {
            std::mem::size_of::<F>() as u32
        }
        vec![$((
            stringify!($field),
            std::mem::offset_of!($ty, $field) as u32,
            size_of_field(|s: &$ty| &s.$field),
        )),*]
    }};
}

/// Implements [`PushConstants`] for a `#[repr(C)]` struct from the list of its fields. Fields
/// whose names start with `_` are padding and need no shader member.
#[macro_export]
macro_rules! push_constants {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        impl $crate::vk::reflect::PushConstants for $ty {
            fn fields() -> Vec<(&'static str, u32, u32)> {
                $crate::struct_fields!($ty { $($field),* })
            }
        }
    };
}

/// Implements [`GpuStruct`] for a `#[repr(C)]` struct from the list of its fields. Fields
/// whose names start with `_` are padding and need no shader member.
#[macro_export]
macro_rules! gpu_struct {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        impl $crate::vk::reflect::GpuStruct for $ty {
            fn fields() -> Vec<(&'static str, u32, u32)> {
                $crate::struct_fields!($ty { $($field),* })
            }
        }
    };
}

/// Compares the shader's `members` (name, offset, size) with the Rust `fields`: every member
/// needs a field of the same name, offset and size, every field not starting with `_` a
/// member. `what` names the shader side in messages.
fn check_fields(
    members: &[(&str, u32, u32)],
    what: &str,
    rust_name: &str,
    fields: &[(&'static str, u32, u32)],
    problems: &mut Vec<String>,
) {
    for &(name, m_offset, m_size) in members {
        match fields.iter().find(|f| f.0 == name) {
            None => problems.push(format!(
                "shader member `{name}` (offset {m_offset}) has no field in `{rust_name}`"
            )),
            Some(&(_, offset, size)) if offset != m_offset || size != m_size => {
                problems.push(format!(
                    "`{name}` is at offset {offset} ({size} bytes) in `{rust_name}` but at {m_offset} ({m_size} bytes) in the shader"
                ))
            }
            Some(_) => {}
        }
    }
    for &(name, offset, _) in fields {
        if !name.starts_with('_') && !members.iter().any(|m| m.0 == name) {
            problems.push(format!(
                "field `{name}` (offset {offset}) of `{rust_name}` is not in the shader's {what}"
            ));
        }
    }
}

fn problems_to_result(problems: Vec<String>) -> Result<(), String> {
    if problems.is_empty() {
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// Checks that the Rust push-constant struct `rust` (its fields, see [`PushConstants`]) has the
/// shader's block layout: every shader member has a Rust field of the same name, offset and
/// size, every Rust field not starting with `_` is a shader member, and the struct is at least
/// as large as the block. Returns what differs, for an error naming the pipeline.
pub fn check_push(
    block: Option<&PushBlock>,
    rust_name: &str,
    fields: &[(&'static str, u32, u32)],
    rust_size: u32,
) -> Result<(), String> {
    let empty = PushBlock::default();
    let block = block.unwrap_or(&empty);
    let members: Vec<(&str, u32, u32)> = block
        .members
        .iter()
        .map(|m| (m.name.as_str(), m.offset, m.size_bytes))
        .collect();
    let mut problems = Vec::new();
    check_fields(
        &members,
        "push-constant block",
        rust_name,
        fields,
        &mut problems,
    );
    if rust_size < block.size_bytes {
        problems.push(format!(
            "`{rust_name}` has {rust_size} bytes, the shader's block {}",
            block.size_bytes
        ));
    }
    problems_to_result(problems)
}

/// Checks that the Rust struct `rust_name` (its fields, see [`GpuStruct`], and its size) has
/// the layout of the shader's buffer struct `layout` (see [`ShaderInterface::structs`]):
/// members as in [`check_push`], and the size equal to the shader's array stride where it
/// declares arrays of the struct, else at least the end of its last member.
pub fn check_struct(
    layout: &StructLayout,
    rust_name: &str,
    fields: &[(&'static str, u32, u32)],
    rust_size: u32,
) -> Result<(), String> {
    let members: Vec<(&str, u32, u32)> = layout
        .members
        .iter()
        .map(|m| (m.name.as_str(), m.offset, m.size_bytes))
        .collect();
    let mut problems = Vec::new();
    let what = format!("struct `{}`", layout.name);
    check_fields(&members, &what, rust_name, fields, &mut problems);
    match layout.array_stride {
        Some(stride) if stride != rust_size => problems.push(format!(
            "`{rust_name}` has {rust_size} bytes, the shader's array stride of `{}` is {stride}",
            layout.name
        )),
        None if rust_size < layout.size_bytes => problems.push(format!(
            "`{rust_name}` has {rust_size} bytes, the shader's `{}` {}",
            layout.name, layout.size_bytes
        )),
        _ => {}
    }
    problems_to_result(problems)
}

/// Checks the named values `given` against the shader's specialization constants `declared`
/// and returns (constant id, 32-bit value) for each: every given name must be declared, with
/// the value's type, and every declared constant given, so that a constant the shader starts
/// reading cannot keep its GLSL default unnoticed. Returns what differs, for an error naming
/// the pipeline.
pub fn check_spec(
    declared: &BTreeMap<String, SpecConstant>,
    given: &[SpecEntry],
) -> Result<Vec<(u32, u32)>, String> {
    let mut problems = Vec::new();
    let mut out = Vec::with_capacity(given.len());
    for (k, &(name, value)) in given.iter().enumerate() {
        match declared.get(name) {
            None => problems.push(format!(
                "`{name}` is not a specialization constant of the shader (it declares {})",
                list(declared.keys())
            )),
            Some(c) if c.ty != value.ty() => problems.push(format!(
                "`{name}` is a {} in the shader but given a {} ({value:?})",
                c.ty.glsl_name(),
                value.ty().glsl_name()
            )),
            Some(_) if given[..k].iter().any(|g| g.0 == name) => {
                problems.push(format!("`{name}` is given twice"))
            }
            Some(c) => out.push((c.id, value.bits())),
        }
    }
    for c in declared.values() {
        if !given.iter().any(|g| g.0 == c.name) {
            problems.push(format!(
                "the shader's `{}` ({} at constant_id {}) is not given a value",
                c.name,
                c.ty.glsl_name(),
                c.id
            ));
        }
    }
    problems_to_result(problems).map(|()| out)
}

/// `none` or the names in backticks, for messages.
fn list<'a>(names: impl Iterator<Item = &'a String>) -> String {
    let v: Vec<String> = names.map(|n| format!("`{n}`")).collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(file: &str) -> Vec<u32> {
        let bytes = crate::vk::shaders::get(file).expect("embedded shader");
        bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    /// `tonemap.comp` declares `sampler2D hdr` at 0, `writeonly image2D` at 1, the exposure
    /// buffer at 2 and a block of five 32-bit members: the layout std430 gives them is 0, 4,
    /// 8, 12, 16 (20 bytes).
    #[test]
    fn tonemap_interface() {
        let i = reflect("tonemap.comp", &words("tonemap.comp")).unwrap();
        assert_eq!(i.bindings.len(), 3);
        assert_eq!(i.bindings[&0].kind, BindingKind::CombinedImageSampler);
        assert_eq!(i.bindings[&1].kind, BindingKind::StorageImage);
        assert_eq!(i.bindings[&1].stages, Stages::COMPUTE);
        assert_eq!(i.bindings[&2].kind, BindingKind::StorageBuffer);
        let push = i.push.unwrap();
        let names: Vec<(&str, u32)> = push
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.offset))
            .collect();
        assert_eq!(
            names,
            [
                ("exposure", 0),
                ("op", 4),
                ("white", 8),
                ("drago_bias", 12),
                ("dither", 16)
            ]
        );
        assert_eq!(push.size_bytes, 20);
    }

    /// `gbuffer.vert`'s block is `mat4 model; uint material; mat3x4 motion;`: 64 + 4 bytes,
    /// then three vec4 columns aligned to 16 (at 80, 48 bytes): 128.
    #[test]
    fn matrix_member_size_uses_its_stride() {
        let i = reflect("gbuffer.vert", &words("gbuffer.vert")).unwrap();
        let push = i.push.unwrap();
        assert_eq!(push.members[0].size_bytes, 64);
        assert_eq!(
            (push.members[2].offset, push.members[2].size_bytes),
            (80, 48)
        );
        assert_eq!(push.size_bytes, 128);
        assert_eq!(i.bindings[&0].kind, BindingKind::StorageBuffer);
    }

    fn members(layout: &StructLayout) -> Vec<(&str, u32, u32)> {
        layout
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.offset, m.size_bytes))
            .collect()
    }

    /// `gi_filter.comp` reads `buffer FrameBuf { GpuFrame frame; }` (`frame.glsl`). std430
    /// (GLSL 4.50 §7.6.2.2) aligns vec4, mat4 and structs of them to 16 bytes and gives an
    /// array of structs the struct's size as stride: GpuLight is five vec4 (80 bytes),
    /// GpuShadowView a mat4 and two vec4 (96); GpuFrame two mat4 (0, 64), three vec4 (128,
    /// 144, 160), 64 lights at 176 (5120 bytes), 64 shadow views at 5296 (6144 bytes), a mat4
    /// at 11440 and vec4s at 11504, 11520, 11536 and 11552.
    #[test]
    fn buffer_structs_have_their_std430_layout() {
        let i = reflect("gi_filter.comp", &words("gi_filter.comp")).unwrap();
        let frame = &i.structs["GpuFrame"];
        assert_eq!(
            members(frame),
            [
                ("view_proj", 0, 64),
                ("inv_view_proj", 64, 64),
                ("camera_position", 128, 16),
                ("counts", 144, 16),
                ("shadow", 160, 16),
                ("lights", 176, 5120),
                ("shadow_views", 5296, 6144),
                ("prev_view_proj", 11440, 64),
                ("jitter_ndc", 11504, 16),
                ("camera_forward", 11520, 16),
                ("environment", 11536, 16),
                ("radiance_scale", 11552, 16),
            ]
        );
        assert_eq!((frame.size_bytes, frame.array_stride), (11568, None));
        let light = &i.structs["GpuLight"];
        assert_eq!(light.array_stride, Some(80));
        assert_eq!(
            light.members[4],
            StructMember {
                name: "info".into(),
                offset: 64,
                size_bytes: 16
            }
        );
        assert_eq!(i.structs["GpuShadowView"].array_stride, Some(96));
        assert_eq!(members(&i.structs["GpuShadowView"])[2], ("axis", 80, 16));
        // The block itself, by its type name: one member, the struct.
        assert_eq!(members(&i.structs["FrameBuf"]), [("frame", 0, 11568)]);
        // A runtime array of structs: `Ray { vec4 origin_tmax; vec4 dir; }`, stride 32.
        let rays = reflect("voxel_rays.comp", &words("voxel_rays.comp")).unwrap();
        let ray = &rays.structs["Ray"];
        assert_eq!(members(ray), [("origin_tmax", 0, 16), ("dir", 16, 16)]);
        assert_eq!(ray.array_stride, Some(32));
    }

    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Ray {
        origin_tmax: [f32; 4],
        dir: [f32; 4],
    }
    crate::gpu_struct!(Ray { origin_tmax, dir });

    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct PaddedRay {
        origin_tmax: [f32; 4],
        dir: [f32; 4],
        _pad: [f32; 4],
    }
    crate::gpu_struct!(PaddedRay {
        origin_tmax,
        dir,
        _pad
    });

    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Renamed {
        origin: [f32; 4],
        dir: [f32; 4],
    }
    crate::gpu_struct!(Renamed { origin, dir });

    #[test]
    fn buffer_structs_are_checked_by_name_offset_and_stride() {
        let i = reflect("voxel_rays.comp", &words("voxel_rays.comp")).unwrap();
        let ray = &i.structs["Ray"];
        assert_eq!(check_struct(ray, "Ray", &Ray::fields(), 32), Ok(()));
        let err = check_struct(ray, "PaddedRay", &PaddedRay::fields(), 48).unwrap_err();
        assert!(err.contains("array stride of `Ray` is 32"), "{err}");
        let err = check_struct(ray, "Renamed", &Renamed::fields(), 32).unwrap_err();
        assert!(
            err.contains("`origin_tmax` (offset 0) has no field in `Renamed`")
                && err.contains(
                    "field `origin` (offset 0) of `Renamed` is not in the shader's struct `Ray`"
                ),
            "{err}"
        );
    }

    #[test]
    fn every_embedded_shader_reflects() {
        for (name, _) in crate::vk::shaders::ALL {
            reflect(name, &words(name)).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn stages_merge_and_conflicts_are_errors() {
        let a = reflect("shadow_depth.vert", &words("shadow_depth.vert")).unwrap();
        let b = reflect("shadow_depth.geom", &words("shadow_depth.geom")).unwrap();
        let m = merge(&[a, b.clone()]).unwrap();
        assert_eq!(m.name, "shadow_depth.vert+shadow_depth.geom");
        assert!(!b.bindings.is_empty());
        let mut c = b.clone();
        if let Some(first) = c.bindings.values_mut().next() {
            first.kind = BindingKind::UniformBuffer;
        }
        c.name = "x.frag".into();
        assert!(matches!(
            merge(&[b, c]),
            Err(ReflectError::StageConflict { .. })
        ));
    }

    #[test]
    fn garbage_is_not_spirv() {
        assert_eq!(
            reflect("x.comp", &[1, 2, 3]),
            Err(ReflectError::NotSpirv("x.comp".into()))
        );
        // A header followed by an instruction claiming more words than there are.
        assert!(reflect("x.comp", &[0x0723_0203, 0, 0, 10, 0, 0x00ff_0005]).is_err());
    }

    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Tonemap {
        exposure: f32,
        op: u32,
        white: f32,
        drago_bias: f32,
        dither: u32,
    }
    crate::push_constants!(Tonemap {
        exposure,
        op,
        white,
        drago_bias,
        dither
    });

    #[repr(C)]
    #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
    struct Swapped {
        op: u32,
        exposure: f32,
        white: f32,
        drago_bias: f32,
        dither: u32,
    }
    crate::push_constants!(Swapped {
        op,
        exposure,
        white,
        drago_bias,
        dither
    });

    #[test]
    fn push_structs_are_checked_by_name_and_offset() {
        let i = reflect("tonemap.comp", &words("tonemap.comp")).unwrap();
        assert_eq!(
            check_push(i.push.as_ref(), "Tonemap", &Tonemap::fields(), 20),
            Ok(())
        );
        let err = check_push(i.push.as_ref(), "Swapped", &Swapped::fields(), 20).unwrap_err();
        assert!(err.contains("`exposure` is at offset 4"), "{err}");
        let err = check_push(i.push.as_ref(), "Tonemap", &Tonemap::fields()[..3], 12).unwrap_err();
        assert!(
            err.contains("`drago_bias` (offset 12) has no field"),
            "{err}"
        );
    }

    fn spec_of(file: &str) -> BTreeMap<String, SpecConstant> {
        reflect(file, &words(file)).unwrap().spec
    }

    /// `gi_vpl_gather.comp` (through `gi_vpl_gather_body.glsl`) declares `bool HAS_PHONG` at
    /// constant_id 0, `bool HAS_GGX` at 1 and `float MIN_ROUGHNESS` at 2;
    /// `voxelize_triangles.comp` sets its workgroup width with `local_size_x_id = 0`, a
    /// constant without a GLSL name, which glslang emits twice (in the LocalSizeId execution
    /// mode and in `gl_WorkGroupSize`).
    #[test]
    fn spec_constants_are_reflected_by_name_id_and_type() {
        let spec = spec_of("gi_vpl_gather.comp");
        let got: Vec<(&str, u32, SpecType)> = spec
            .values()
            .map(|c| (c.name.as_str(), c.id, c.ty))
            .collect();
        assert_eq!(
            got,
            [
                ("HAS_GGX", 1, SpecType::Bool),
                ("HAS_PHONG", 0, SpecType::Bool),
                ("MIN_ROUGHNESS", 2, SpecType::Float),
            ]
        );
        let size = spec_of("voxelize_triangles.comp");
        assert_eq!(size.len(), 1);
        assert_eq!(
            size["local_size_x"],
            SpecConstant {
                name: "local_size_x".into(),
                id: 0,
                ty: SpecType::Uint
            }
        );
        assert!(spec_of("tonemap.comp").is_empty());
    }

    #[test]
    fn spec_values_are_checked_by_name_and_type() {
        let spec = spec_of("gi_vpl_gather.comp");
        let ok = check_spec(
            &spec,
            &crate::spec_constants![HAS_PHONG = true, HAS_GGX = false, MIN_ROUGHNESS = 0.5f32],
        );
        assert_eq!(ok, Ok(vec![(0, 1), (1, 0), (2, 0.5f32.to_bits())]));
        // A misspelt name is unknown, and the constant it meant is left without a value.
        let err = check_spec(
            &spec,
            &crate::spec_constants![HAS_PONG = true, HAS_GGX = false, MIN_ROUGHNESS = 0.5f32],
        )
        .unwrap_err();
        assert!(
            err.contains("`HAS_PONG` is not a specialization constant of the shader")
                && err.contains("`HAS_PHONG` (bool at constant_id 0) is not given a value"),
            "{err}"
        );
        // A bool given as a number, and a float given as its bits.
        let err = check_spec(
            &spec,
            &crate::spec_constants![
                HAS_PHONG = 1u32,
                HAS_GGX = false,
                MIN_ROUGHNESS = 0.5f32.to_bits()
            ],
        )
        .unwrap_err();
        assert!(
            err.contains("`HAS_PHONG` is a bool in the shader but given a uint")
                && err.contains("`MIN_ROUGHNESS` is a float in the shader but given a uint"),
            "{err}"
        );
        let err = check_spec(
            &spec,
            &crate::spec_constants![
                HAS_PHONG = true,
                HAS_PHONG = true,
                HAS_GGX = false,
                MIN_ROUGHNESS = 0.0f32
            ],
        )
        .unwrap_err();
        assert!(err.contains("`HAS_PHONG` is given twice"), "{err}");
    }

    /// Vulkan applies one specialization to every stage by constant_id, so the stages of a
    /// pipeline must agree on each constant's id and type: `light_map.geom` declares
    /// `AREA_LIGHT_MAPS` at 2, `light_map.frag` `HAS_DISSOLVE`, `HAS_GGX`, `HAS_MAPS` and
    /// `HAS_ALPHA_MAP` at 0, 1, 3 and 4.
    #[test]
    fn stages_merge_their_spec_constants_and_conflicts_are_errors() {
        let geom = reflect("light_map.geom", &words("light_map.geom")).unwrap();
        let frag = reflect("light_map.frag", &words("light_map.frag")).unwrap();
        let m = merge(&[geom.clone(), frag.clone()]).unwrap();
        let ids: Vec<(&str, u32)> = m.spec.values().map(|c| (c.name.as_str(), c.id)).collect();
        assert_eq!(
            ids,
            [
                ("AREA_LIGHT_MAPS", 2),
                ("HAS_ALPHA_MAP", 4),
                ("HAS_DISSOLVE", 0),
                ("HAS_GGX", 1),
                ("HAS_MAPS", 3)
            ]
        );
        let mut moved = geom;
        if let Some(c) = moved.spec.get_mut("AREA_LIGHT_MAPS") {
            c.id = 1;
        }
        assert!(matches!(
            merge(&[moved, frag]),
            Err(ReflectError::SpecConflict { .. })
        ));
    }
}
