//! Just enough SPIR-V reflection to check a host struct against the block a shader
//! declares: the byte offset of every member (std140 / push-constant `Offset`
//! decorations, as the GLSL compiler laid them out) and each member's size. Tests compare
//! these with the Rust mirrors (`offset_of!`), so a field added, reordered or resized on
//! one side only fails a test instead of shading with the wrong values.

use std::collections::HashMap;

use anyhow::{bail, ensure, Context as _, Result};

/// One member of a block: its name, byte offset and byte size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    pub size: u32,
}

const OP_NAME: u16 = 5;
const OP_MEMBER_NAME: u16 = 6;
const OP_TYPE_INT: u16 = 21;
const OP_TYPE_FLOAT: u16 = 22;
const OP_TYPE_VECTOR: u16 = 23;
const OP_TYPE_MATRIX: u16 = 24;
const OP_TYPE_ARRAY: u16 = 28;
const OP_TYPE_STRUCT: u16 = 30;
const OP_CONSTANT: u16 = 43;
const OP_DECORATE: u16 = 71;
const OP_MEMBER_DECORATE: u16 = 72;
const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_MATRIX_STRIDE: u32 = 7;
const DECORATION_OFFSET: u32 = 35;

enum Type {
    Scalar(u32),
    Vector { component: u32, count: u32 },
    Matrix { count: u32 },
    Array { length: u32 },
    Struct(Vec<u32>),
}

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// The members of the block type named `block` (its GLSL block name, e.g. `SweepParams`
/// or `Push`) in a SPIR-V module, in declaration order.
pub fn block_members(spirv: &[u8], block: &str) -> Result<Vec<Member>> {
    ensure!(
        spirv.len() % 4 == 0 && spirv.len() >= 20,
        "not a SPIR-V module"
    );
    let words: Vec<u32> = spirv
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    ensure!(words[0] == 0x0723_0203, "not a SPIR-V module (magic)");
    let mut names: HashMap<u32, String> = HashMap::new();
    let mut member_names: HashMap<(u32, u32), String> = HashMap::new();
    let mut offsets: HashMap<(u32, u32), u32> = HashMap::new();
    let mut matrix_strides: HashMap<(u32, u32), u32> = HashMap::new();
    let mut array_strides: HashMap<u32, u32> = HashMap::new();
    let mut constants: HashMap<u32, u32> = HashMap::new();
    let mut types: HashMap<u32, Type> = HashMap::new();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        let op = (words[i] & 0xffff) as u16;
        ensure!(
            count > 0 && i + count <= words.len(),
            "truncated SPIR-V at word {i}"
        );
        let w = &words[i + 1..i + count];
        match op {
            OP_NAME if !w.is_empty() => {
                names.insert(w[0], string(&w[1..]));
            }
            OP_MEMBER_NAME if w.len() >= 2 => {
                member_names.insert((w[0], w[1]), string(&w[2..]));
            }
            OP_MEMBER_DECORATE if w.len() >= 4 && w[2] == DECORATION_OFFSET => {
                offsets.insert((w[0], w[1]), w[3]);
            }
            OP_MEMBER_DECORATE if w.len() >= 4 && w[2] == DECORATION_MATRIX_STRIDE => {
                matrix_strides.insert((w[0], w[1]), w[3]);
            }
            OP_DECORATE if w.len() >= 3 && w[1] == DECORATION_ARRAY_STRIDE => {
                array_strides.insert(w[0], w[2]);
            }
            OP_CONSTANT if w.len() >= 3 => {
                constants.insert(w[1], w[2]);
            }
            OP_TYPE_INT | OP_TYPE_FLOAT if w.len() >= 2 => {
                types.insert(w[0], Type::Scalar(w[1] / 8));
            }
            OP_TYPE_VECTOR if w.len() >= 3 => {
                types.insert(
                    w[0],
                    Type::Vector {
                        component: w[1],
                        count: w[2],
                    },
                );
            }
            OP_TYPE_MATRIX if w.len() >= 3 => {
                types.insert(w[0], Type::Matrix { count: w[2] });
            }
            OP_TYPE_ARRAY if w.len() >= 3 => {
                // An array sized by a specialization constant (a shared-memory tile) has
                // no length until the pipeline is made; it is left out, so a block that
                // used one would fail below as a member of unknown type.
                if let Some(&length) = constants.get(&w[2]) {
                    types.insert(w[0], Type::Array { length });
                }
            }
            OP_TYPE_STRUCT if !w.is_empty() => {
                types.insert(w[0], Type::Struct(w[1..].to_vec()));
            }
            _ => {}
        }
        i += count;
    }
    let id = names
        .iter()
        .filter(|(id, name)| {
            name.as_str() == block && matches!(types.get(id), Some(Type::Struct(_)))
        })
        .map(|(id, _)| *id)
        .next()
        .with_context(|| format!("no block named '{block}' in the module"))?;
    let Some(Type::Struct(member_types)) = types.get(&id) else {
        bail!("'{block}' is not a struct");
    };
    // Size of a type as laid out in the block (a matrix by its stride, an array by its).
    let size_of = |ty: u32, matrix_stride: Option<u32>| -> Result<u32> {
        fn scalar_or_vector(types: &HashMap<u32, Type>, ty: u32) -> Option<u32> {
            match types.get(&ty)? {
                Type::Scalar(bytes) => Some(*bytes),
                Type::Vector { component, count } => {
                    Some(scalar_or_vector(types, *component)? * count)
                }
                _ => None,
            }
        }
        match types.get(&ty) {
            Some(Type::Scalar(_)) | Some(Type::Vector { .. }) => {
                scalar_or_vector(&types, ty).context("bad vector type")
            }
            Some(Type::Matrix { count, .. }) => {
                Ok(count * matrix_stride.context("a matrix member without a MatrixStride")?)
            }
            Some(Type::Array { length, .. }) => Ok(length
                * array_strides
                    .get(&ty)
                    .context("an array without an ArrayStride")?),
            Some(Type::Struct(_)) => bail!("nested structs are not supported"),
            None => bail!("unknown type id {ty}"),
        }
    };
    member_types
        .iter()
        .enumerate()
        .map(|(m, &ty)| {
            let key = (id, m as u32);
            Ok(Member {
                name: member_names
                    .get(&key)
                    .cloned()
                    .with_context(|| format!("member {m} of '{block}' has no name"))?,
                offset: *offsets
                    .get(&key)
                    .with_context(|| format!("member {m} of '{block}' has no offset"))?,
                size: size_of(ty, matrix_strides.get(&key).copied())?,
            })
        })
        .collect()
}

/// Check a host struct against the block `block` of `spirv`: every shader member must be a
/// host field of the same name at the same offset with the same size; with
/// `exact_size` (uniform buffers) the host struct is exactly as long as the block (its
/// last member's end rounded up to 16 bytes, std140), otherwise (push constants) at
/// least as long. `host` lists (field name, offset, size); see [`host_layout`].
pub fn check_block(
    spirv: &[u8],
    block: &str,
    host: &[(&str, usize, usize)],
    host_size: usize,
    exact_size: bool,
) -> Result<()> {
    let members = block_members(spirv, block)?;
    let mut problems = Vec::new();
    for m in &members {
        match host.iter().find(|(name, _, _)| *name == m.name) {
            None => problems.push(format!("shader member '{}' has no host field", m.name)),
            Some((_, offset, size)) => {
                if *offset as u32 != m.offset || *size as u32 != m.size {
                    problems.push(format!(
                        "'{}': shader offset {} size {}, host offset {offset} size {size}",
                        m.name, m.offset, m.size
                    ));
                }
            }
        }
    }
    for (name, _, _) in host {
        if !name.starts_with("pad") && !members.iter().any(|m| m.name == *name) {
            problems.push(format!("host field '{name}' is not in the shader's block"));
        }
    }
    let end = members.iter().map(|m| m.offset + m.size).max().unwrap_or(0) as usize;
    let block_size = if exact_size {
        end.div_ceil(16) * 16
    } else {
        end
    };
    if (exact_size && host_size != block_size) || host_size < block_size {
        problems.push(format!(
            "host struct is {host_size} bytes, the shader's block {block_size}"
        ));
    }
    ensure!(
        problems.is_empty(),
        "block '{block}': {}",
        problems.join("; ")
    );
    Ok(())
}

/// `(name, offset, size)` of the listed fields of a `#[repr(C)]` struct, for
/// [`check_block`]: `host_layout!(SweepParams { view_to_tex, camera })`.
#[macro_export]
macro_rules! host_layout {
    ($ty:ty { $($field:ident),* $(,)? }) => {{
        fn size_of_field<T, F>(_: impl Fn(&T) -> &F) -> usize {
            std::mem::size_of::<F>()
        }
        vec![$((
            stringify!($field),
            std::mem::offset_of!($ty, $field),
            size_of_field(|s: &$ty| &s.$field),
        )),*]
    }};
}

/// Asserts, in a test, that the listed fields of the `#[repr(C)]` struct `Ty` match the
/// block `block` of `spirv` ([`check_block`] with `exact_size`), panicking with the
/// differences: `assert_host_block!(SPV, "Push", Push { dims, scale }, exact_size = false)`.
#[macro_export]
macro_rules! assert_host_block {
    ($spirv:expr, $block:expr, $ty:ty { $($field:ident),* $(,)? }, exact_size = $exact:expr) => {
        $crate::vk::spirv::check_block(
            $spirv,
            $block,
            &$crate::host_layout!($ty { $($field),* }),
            std::mem::size_of::<$ty>(),
            $exact,
        )
        .unwrap()
    };
}
