//! What a GPU device binds, as the structure's buffers must respect it: one
//! place for the rule that `dirt-gpu` allocates by and the cost model
//! (`dirt_cpu::cost::auto_within`) chooses by.

/// A device's binding limits as they bound a structure's size.
///
/// The triangles, the Hi-Z pyramid and the list offsets are each one
/// binding; the list ids, the one buffer that grows with depth complexity,
/// are split across [`BindingLimits::id_bindings`] bindings of
/// `2^`[`BindingLimits::id_shift`] ids each (`ids.wgsl`), so a structure's
/// lists may hold several bindings' worth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BindingLimits {
    /// Bytes one storage binding holds: the device's
    /// `max_storage_buffer_binding_size`, at most its `max_buffer_size`.
    pub max_binding: u64,
    /// Bindings the list ids are split across (at least 1).
    pub id_bindings: u32,
}

impl BindingLimits {
    /// Base-2 logarithm of the ids per chunk: the largest power of two of
    /// 4-byte words that one binding holds, at most 2^30 (so that shifts and
    /// masks stay within a u32).
    pub fn id_shift(&self) -> u32 {
        let words = (self.max_binding / 4).max(1);
        (63 - words.leading_zeros()).min(30)
    }

    /// List ids the chunks can hold, at most `u32::MAX` (offsets are u32).
    pub fn id_capacity(&self) -> u64 {
        ((self.id_bindings.max(1) as u64) << self.id_shift()).min(u32::MAX as u64)
    }

    /// Whether a structure of these sizes fits: `largest_other` bytes in the
    /// largest of triangles, Hi-Z pyramid and offsets, `ids` list entries.
    pub fn fits(&self, largest_other: u64, ids: u64) -> bool {
        largest_other <= self.max_binding && ids <= self.id_capacity()
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
        };
        assert_eq!(l(128 << 20, 1).id_shift(), 25);
        assert_eq!(l((128 << 20) - 4, 1).id_shift(), 24);
        assert_eq!(l(1000, 3).id_shift(), 7);
        assert_eq!(l(1000, 3).id_capacity(), 384);
        assert_eq!(l(0, 1).id_shift(), 0);
        assert_eq!(l(u64::MAX, 8).id_shift(), 30);
        assert_eq!(l(u64::MAX, 8).id_capacity(), u32::MAX as u64);
        assert!(l(1000, 3).fits(1000, 384));
        assert!(!l(1000, 3).fits(1001, 1));
        assert!(!l(1000, 3).fits(4, 385));
    }
}
