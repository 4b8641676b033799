//! Struct layouts as naga computes them, to compare with `#[repr(C)]` Rust types.

use naga::TypeInner;
use naga::proc::Layouter;

/// The memory layout of a WGSL struct as naga sees it (WGSL's default layout
/// rules, i.e. storage-buffer layout).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StructLayout {
    /// The struct's size in bytes (its span, tail padding included).
    pub size: u32,
    /// `(name, offset, size)` of each member in declaration order; `size` is
    /// the member type's size per naga's layouter (for a runtime-sized array,
    /// the size of one element's stride).
    pub members: Vec<(String, u32, u32)>,
}

/// The layout of the struct named `name` in `module`, or `None` if there is no
/// such struct (or naga cannot lay the module's types out).
pub fn struct_layout(module: &naga::Module, name: &str) -> Option<StructLayout> {
    let (_, ty) = module.types.iter().find(|(_, ty)| {
        ty.name.as_deref() == Some(name) && matches!(ty.inner, TypeInner::Struct { .. })
    })?;
    let TypeInner::Struct { ref members, span } = ty.inner else {
        return None;
    };
    let mut layouter = Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    Some(StructLayout {
        size: span,
        members: members
            .iter()
            .map(|m| {
                (
                    m.name.clone().unwrap_or_default(),
                    m.offset,
                    layouter[m.ty].size,
                )
            })
            .collect(),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn layout_of_an_in_memory_struct() {
        let module = naga::front::wgsl::parse_str(
            "struct Node {
                a: f32,
                b: vec3<f32>,
                c: u32,
                d: vec2<u32>,
                e: array<f32, 3>,
            }
            struct Tail { n: u32, items: array<vec4<f32>> }
            struct Other { x: u32 }",
        )
        .unwrap();
        let layout = struct_layout(&module, "Node").unwrap();
        assert_eq!(
            layout,
            StructLayout {
                size: 64,
                members: vec![
                    ("a".into(), 0, 4),
                    ("b".into(), 16, 12),
                    ("c".into(), 28, 4),
                    ("d".into(), 32, 8),
                    ("e".into(), 40, 12),
                ],
            }
        );
        let tail = struct_layout(&module, "Tail").unwrap();
        assert_eq!(tail.members[1].0, "items");
        assert_eq!(tail.members[1].1, 16);
        assert_eq!(tail.members[1].2, 16); // one element's stride
        assert_eq!(tail.size, 32);
        assert_eq!(struct_layout(&module, "Missing"), None);
        assert_eq!(struct_layout(&module, "f32"), None);
    }
}
