//! [`Blocks`]: a sequence the build grows without reallocating, for what one
//! pass keeps for the next (`fill_depth`'s fragments, the count pass's list
//! indices). A `Vec` grown by doubling can hold twice its length, and copies
//! itself at each growth while both copies are alive; with several pieces in
//! flight that slack decided the build's peak memory. Here each new block
//! holds as many items as the blocks before it (so few blocks), at least
//! [`MIN`] and at most [`MAX`]: the slack stays below one block and under the
//! items already kept, and nothing is copied.

/// Items in the first block.
const MIN: usize = 256;

/// Most items in one block.
const MAX: usize = 1 << 14;

#[derive(Debug)]
pub(crate) struct Blocks<T> {
    blocks: Vec<Vec<T>>,
    len: usize,
}

impl<T: Copy> Blocks<T> {
    pub(crate) fn new() -> Self {
        Blocks {
            blocks: Vec::new(),
            len: 0,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    pub(crate) fn push(&mut self, x: T) {
        match self.blocks.last_mut() {
            Some(b) if b.len() < b.capacity() => b.push(x),
            _ => {
                let mut b = Vec::with_capacity(self.len.clamp(MIN, MAX));
                b.push(x);
                self.blocks.push(b);
            }
        }
        self.len += 1;
    }

    /// Frees the last block's unused room (the pass is done with this sequence).
    pub(crate) fn trim(&mut self) {
        if let Some(b) = self.blocks.last_mut() {
            b.shrink_to_fit();
        }
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = T> + '_ {
        self.blocks.iter().flatten().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_keep_every_item_in_order_with_bounded_room() {
        for n in [0usize, 1, MIN - 1, MIN, MIN + 1, 3 * MAX + 17] {
            let mut b = Blocks::new();
            for k in 0..n {
                b.push(k as u32);
            }
            assert_eq!(b.len(), n);
            assert!(b.iter().eq(0..n as u32), "{n} items");
            let room: usize = b.blocks.iter().map(|v| v.capacity() - v.len()).sum();
            assert!(room < MAX && room <= n.max(MIN), "{n} items: {room} unused");
            b.trim();
            let room: usize = b.blocks.iter().map(|v| v.capacity() - v.len()).sum();
            assert_eq!(room, 0, "{n} items: trimmed");
        }
    }
}
