//! What a GPU device binds, as the structure's buffers must respect it: one
//! place for the rule that `dirt-gpu` allocates by and the cost model
//! (`dirt_cpu::cost::auto_within`) chooses by.

/// The arrays of a structure that a GPU splits across bindings: every buffer
/// that grows with the scene or with the structure's setting. Each is split
/// into chunks of a power of two elements, one binding each (`ids.wgsl`,
/// `tris.wgsl`, `hiz.wgsl`, `offsets.wgsl`), so that one binding's size does
/// not bound a scene; the device's bindings and memory do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SplitArray {
    /// The list ids, one u32 each.
    Ids,
    /// The triangles, nine f32 each (`dirt_math::Triangle`).
    Tris,
    /// The Hi-Z pyramid, depth bounds included: two u32 per cell.
    Hiz,
    /// The list offsets (and, while filling, the cursors): one u32 each.
    Offsets,
}

impl SplitArray {
    /// Every split array, in the order [`BindingLimits::for_device`] hands
    /// out spare bindings after the ids.
    pub const ALL: [SplitArray; 4] = [
        SplitArray::Ids,
        SplitArray::Offsets,
        SplitArray::Hiz,
        SplitArray::Tris,
    ];

    /// Bytes of one element.
    pub const fn elem_bytes(self) -> u64 {
        match self {
            SplitArray::Ids | SplitArray::Offsets => 4,
            SplitArray::Tris => 36,
            SplitArray::Hiz => 8,
        }
    }

    /// The array in words, for messages (`the list ids need … bytes`).
    pub const fn what(self) -> &'static str {
        match self {
            SplitArray::Ids => "the list ids",
            SplitArray::Tris => "the triangles",
            SplitArray::Hiz => "the Hi-Z pyramid",
            SplitArray::Offsets => "the list offsets",
        }
    }

    /// What one element is called, plural, for messages.
    const fn elements(self) -> &'static str {
        match self {
            SplitArray::Ids => "list ids",
            SplitArray::Tris => "triangles",
            SplitArray::Hiz => "Hi-Z cells",
            SplitArray::Offsets => "list offsets",
        }
    }
}

/// A device's binding limits as they bound a structure's size: how large one
/// binding is, and how many bindings each [`SplitArray`] is split across.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BindingLimits {
    /// Bytes one storage binding holds: the device's
    /// `max_storage_buffer_binding_size`, at most its `max_buffer_size`.
    pub max_binding: u64,
    /// Bindings the list ids are split across (at least 1).
    pub id_bindings: u32,
    /// Bindings the triangles are split across (at least 1).
    pub tri_bindings: u32,
    /// Bindings the Hi-Z pyramid is split across (at least 1).
    pub hiz_bindings: u32,
    /// Bindings the list offsets are split across (at least 1).
    pub offset_bindings: u32,
}

/// Base-2 logarithm of the largest power of two of `elem_bytes` elements one
/// binding of `max_binding` bytes holds, at most 2^30 (so that shifts and
/// masks stay within a u32).
fn shift_for(max_binding: u64, elem_bytes: u64) -> u32 {
    let n = (max_binding / elem_bytes).max(1);
    (63 - n.leading_zeros()).min(30)
}

impl BindingLimits {
    /// Storage buffers the trace binds besides the split arrays: rays, hits,
    /// statistics and the continuation pool.
    pub const FIXED_STORAGE_BUFFERS: u32 = 4;

    /// The most bindings one array is split across (eight: with 128 MiB
    /// each, 1 GiB); `dirt_shaders::MAX_CHUNKS` is the same number.
    pub const MAX_BINDINGS: u32 = 8;

    /// Storage buffers per shader stage a device needs: the fixed ones and
    /// one binding per split array (WebGPU's default limit, 8).
    pub const MIN_STORAGE_BUFFERS: u32 = Self::FIXED_STORAGE_BUFFERS + 4;

    /// Storage buffers per stage beyond which more bindings give nothing.
    pub const MAX_STORAGE_BUFFERS: u32 = Self::FIXED_STORAGE_BUFFERS + 4 * Self::MAX_BINDINGS;

    /// The limits of a device whose bindings hold `max_binding` bytes and
    /// which allows `storage_buffers` per shader stage (at least
    /// [`BindingLimits::MIN_STORAGE_BUFFERS`]): each array gets one binding,
    /// and the bindings beyond go to the list ids first (they grow fastest,
    /// with scene and depth complexity), then one at a time to the offsets,
    /// the Hi-Z pyramid and the triangles, up to
    /// [`BindingLimits::MAX_BINDINGS`] each.
    pub fn for_device(max_binding: u64, storage_buffers: u32) -> BindingLimits {
        let mut spare = storage_buffers.saturating_sub(Self::MIN_STORAGE_BUFFERS);
        let mut n = [1u32; 4];
        let ids = spare.min(Self::MAX_BINDINGS - 1);
        n[0] += ids;
        spare -= ids;
        'deal: while spare > 0 {
            let mut dealt = false;
            for c in &mut n[1..] {
                if spare == 0 {
                    break 'deal;
                }
                if *c < Self::MAX_BINDINGS {
                    *c += 1;
                    spare -= 1;
                    dealt = true;
                }
            }
            if !dealt {
                break;
            }
        }
        BindingLimits {
            max_binding,
            id_bindings: n[0],
            offset_bindings: n[1],
            hiz_bindings: n[2],
            tri_bindings: n[3],
        }
    }

    /// Bindings `array` is split across (at least 1).
    pub fn bindings(&self, array: SplitArray) -> u32 {
        match array {
            SplitArray::Ids => self.id_bindings,
            SplitArray::Tris => self.tri_bindings,
            SplitArray::Hiz => self.hiz_bindings,
            SplitArray::Offsets => self.offset_bindings,
        }
        .max(1)
    }

    /// Base-2 logarithm of `array`'s elements per chunk (per binding).
    pub fn shift(&self, array: SplitArray) -> u32 {
        shift_for(self.max_binding, array.elem_bytes())
    }

    /// Elements of `array` its bindings can hold, at most `u32::MAX` (ids,
    /// offsets and cells are u32 indices).
    pub fn capacity(&self, array: SplitArray) -> u64 {
        ((self.bindings(array) as u64) << self.shift(array)).min(u32::MAX as u64)
    }

    /// Whether a structure of these element counts fits: `(array, count)`
    /// pairs; an array not named is not checked.
    pub fn fits(&self, counts: impl IntoIterator<Item = (SplitArray, u64)>) -> bool {
        counts.into_iter().all(|(a, n)| n <= self.capacity(a))
    }
}

/// What the limits allow, in words, for messages: `bindings of at most B
/// bytes (max_storage_buffer_binding_size): I list ids in J bindings, …`.
impl std::fmt::Display for BindingLimits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "bindings of at most {} bytes (max_storage_buffer_binding_size)",
            self.max_binding
        )?;
        for (k, a) in SplitArray::ALL.into_iter().enumerate() {
            let sep = if k == 0 { ": " } else { ", " };
            write!(
                f,
                "{sep}{} {} in {} bindings",
                self.capacity(a),
                a.elements(),
                self.bindings(a)
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(max_binding: u64, id_bindings: u32) -> BindingLimits {
        BindingLimits {
            max_binding,
            id_bindings,
            tri_bindings: 2,
            hiz_bindings: 3,
            offset_bindings: 1,
        }
    }

    #[test]
    fn chunks_are_the_largest_power_of_two_a_binding_holds() {
        use SplitArray::*;
        assert_eq!(l(128 << 20, 1).shift(Ids), 25);
        assert_eq!(l((128 << 20) - 4, 1).shift(Ids), 24);
        assert_eq!(l(1000, 3).shift(Ids), 7);
        assert_eq!(l(1000, 3).capacity(Ids), 384);
        assert_eq!(l(0, 1).shift(Ids), 0);
        assert_eq!(l(u64::MAX, 8).shift(Ids), 30);
        assert_eq!(l(u64::MAX, 8).capacity(Ids), u32::MAX as u64);
        // 1000 bytes hold 27 triangles: chunks of 16, two bindings.
        assert_eq!(l(1000, 3).shift(Tris), 4);
        assert_eq!(l(1000, 3).capacity(Tris), 32);
        // 125 cells: chunks of 64, three bindings; offsets in one.
        assert_eq!(l(1000, 3).capacity(Hiz), 192);
        assert_eq!(l(1000, 3).capacity(Offsets), 128);
        assert!(l(1000, 3).fits([(Ids, 384), (Tris, 32), (Hiz, 192), (Offsets, 128)]));
        assert!(!l(1000, 3).fits([(Hiz, 193)]));
        assert!(!l(1000, 3).fits([(Offsets, 129)]));
        assert!(!l(1000, 3).fits([(Tris, 33)]));
        assert!(!l(1000, 3).fits([(Ids, 385)]));
    }

    #[test]
    fn spare_bindings_go_to_the_ids_first_then_in_turn() {
        let n = |s| {
            let b = BindingLimits::for_device(1 << 20, s);
            [
                b.id_bindings,
                b.offset_bindings,
                b.hiz_bindings,
                b.tri_bindings,
            ]
        };
        // WebGPU's default: one each.
        assert_eq!(n(8), [1, 1, 1, 1]);
        assert_eq!(n(0), [1, 1, 1, 1]);
        assert_eq!(n(10), [3, 1, 1, 1]);
        assert_eq!(n(15), [8, 1, 1, 1]);
        assert_eq!(n(17), [8, 2, 2, 1]);
        // Lavapipe's 32.
        assert_eq!(n(32), [8, 7, 7, 6]);
        assert_eq!(n(BindingLimits::MAX_STORAGE_BUFFERS), [8; 4]);
        assert_eq!(n(1000), [8; 4]);
        let text = BindingLimits::for_device(1000, 8).to_string();
        assert!(
            text.contains("1000 bytes") && text.contains("64 Hi-Z cells in 1 bindings"),
            "{text}"
        );
    }
}
