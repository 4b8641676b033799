//! What a GPU device binds, as the structure's buffers must respect it: one
//! place for the rule that `dirt-gpu` allocates by and the cost model
//! (`dirt_cpu::cost::auto_within`) chooses by.

/// A device's binding limits as they bound a structure's size.
///
/// The Hi-Z pyramid and the list offsets are each one binding. The
/// triangles and the list ids, the buffers that grow with the scene and
/// with its depth complexity, are split across
/// [`BindingLimits::tri_bindings`] and [`BindingLimits::id_bindings`]
/// bindings of a power of two elements each (`tris.wgsl`, `ids.wgsl`), so
/// that they may hold several bindings' worth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BindingLimits {
    /// Bytes one storage binding holds: the device's
    /// `max_storage_buffer_binding_size`, at most its `max_buffer_size`.
    pub max_binding: u64,
    /// Bindings the list ids are split across (at least 1).
    pub id_bindings: u32,
    /// Bindings the triangles are split across (at least 1).
    pub tri_bindings: u32,
}

/// Base-2 logarithm of the largest power of two of `elem_bytes` elements one
/// binding of `max_binding` bytes holds, at most 2^30 (so that shifts and
/// masks stay within a u32).
fn shift_for(max_binding: u64, elem_bytes: u64) -> u32 {
    let n = (max_binding / elem_bytes).max(1);
    (63 - n.leading_zeros()).min(30)
}

impl BindingLimits {
    /// Bytes of one list id.
    pub const ID_BYTES: u64 = 4;
    /// Bytes of one triangle (`dirt_math::Triangle`).
    pub const TRI_BYTES: u64 = 36;

    /// Base-2 logarithm of the list ids per chunk.
    pub fn id_shift(&self) -> u32 {
        shift_for(self.max_binding, Self::ID_BYTES)
    }

    /// List ids the chunks can hold, at most `u32::MAX` (offsets are u32).
    pub fn id_capacity(&self) -> u64 {
        ((self.id_bindings.max(1) as u64) << self.id_shift()).min(u32::MAX as u64)
    }

    /// Base-2 logarithm of the triangles per chunk.
    pub fn tri_shift(&self) -> u32 {
        shift_for(self.max_binding, Self::TRI_BYTES)
    }

    /// Triangles the chunks can hold, at most `u32::MAX`.
    pub fn tri_capacity(&self) -> u64 {
        ((self.tri_bindings.max(1) as u64) << self.tri_shift()).min(u32::MAX as u64)
    }

    /// Whether a structure of these sizes fits: `largest_whole` bytes in the
    /// larger of Hi-Z pyramid and offsets, `tris` triangles, `ids` list entries.
    pub fn fits(&self, largest_whole: u64, tris: u64, ids: u64) -> bool {
        largest_whole <= self.max_binding
            && tris <= self.tri_capacity()
            && ids <= self.id_capacity()
    }
}

/// What the limits allow, in words, for messages: `one binding of B bytes
/// (max_storage_buffer_binding_size) for Hi-Z and offsets, T triangles in K
/// bindings, I list ids in J bindings`.
impl std::fmt::Display for BindingLimits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "one binding of {} bytes (max_storage_buffer_binding_size) for Hi-Z and offsets, {} triangles in {} bindings, {} list ids in {} bindings",
            self.max_binding,
            self.tri_capacity(),
            self.tri_bindings,
            self.id_capacity(),
            self.id_bindings
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_are_the_largest_power_of_two_a_binding_holds() {
        let l = |max_binding, id_bindings| BindingLimits {
            max_binding,
            id_bindings,
            tri_bindings: 2,
        };
        assert_eq!(l(128 << 20, 1).id_shift(), 25);
        assert_eq!(l((128 << 20) - 4, 1).id_shift(), 24);
        assert_eq!(l(1000, 3).id_shift(), 7);
        assert_eq!(l(1000, 3).id_capacity(), 384);
        assert_eq!(l(0, 1).id_shift(), 0);
        assert_eq!(l(u64::MAX, 8).id_shift(), 30);
        assert_eq!(l(u64::MAX, 8).id_capacity(), u32::MAX as u64);
        // 1000 bytes hold 27 triangles: chunks of 16, two bindings.
        assert_eq!(l(1000, 3).tri_shift(), 4);
        assert_eq!(l(1000, 3).tri_capacity(), 32);
        assert!(l(1000, 3).fits(1000, 32, 384));
        assert!(!l(1000, 3).fits(1001, 1, 1));
        assert!(!l(1000, 3).fits(4, 33, 1));
        assert!(!l(1000, 3).fits(4, 1, 385));
    }
}
