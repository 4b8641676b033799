//! [`Blocks`]: a sequence the build grows without reallocating, for what one
//! pass keeps for the next (`fill_depth`'s fragments, the count pass's list
//! indices). A `Vec` grown by doubling can hold twice its length, and copies
//! itself at each growth while both copies are alive; with several pieces in
//! flight that slack decided the build's peak memory. Here each new block
//! holds as many items as the blocks before it (so few blocks), at least
//! [`MIN`] and at most [`MAX`]: the slack stays below one block and under the
//! items already kept, and nothing is copied. [`Groups`] adds where each
//! triangle's items end: what a pass keeps for one piece of triangles;
//! [`Budget`] bounds what all pieces keep together.

use std::sync::atomic::{AtomicUsize, Ordering};

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

/// [`Blocks`] in consecutive groups (one per triangle of a piece).
#[derive(Debug)]
pub(crate) struct Groups<T> {
    /// Where each group's items end; below `u32::MAX` items in all (the
    /// build's budgets keep them there).
    ends: Vec<u32>,
    items: Blocks<T>,
}

impl<T: Copy> Groups<T> {
    pub(crate) fn new() -> Self {
        Groups {
            ends: Vec::new(),
            items: Blocks::new(),
        }
    }

    /// Items in all groups.
    pub(crate) fn len(&self) -> usize {
        self.items.len()
    }

    /// An item of the open group.
    pub(crate) fn push(&mut self, x: T) {
        self.items.push(x);
    }

    /// Ends the open group (its items are those pushed since the last close).
    pub(crate) fn close(&mut self) {
        self.ends
            .push(self.items.len().min(u32::MAX as usize) as u32);
    }

    /// Frees the unused room (the pass is done with these groups).
    pub(crate) fn trim(&mut self) {
        self.items.trim();
        self.ends.shrink_to_fit();
    }

    /// Calls `f(group, items)` for every closed group, in order.
    pub(crate) fn for_each_group(&self, mut f: impl FnMut(usize, &mut dyn Iterator<Item = T>)) {
        let (mut all, mut start) = (self.items.iter(), 0);
        for (g, &end) in self.ends.iter().enumerate() {
            f(g, &mut all.by_ref().take(end as usize - start));
            start = end as usize;
        }
    }
}

/// How many items the pieces of a pass may keep together. A piece is kept
/// whole or not at all: one that does not fit what was left is dropped (the
/// next pass finds its items again).
#[derive(Debug)]
pub(crate) struct Budget {
    max: usize,
    used: AtomicUsize,
}

impl Budget {
    pub(crate) fn new(max: usize) -> Self {
        Budget {
            max,
            used: AtomicUsize::new(0),
        }
    }

    /// What is left of the budget now.
    pub(crate) fn room(&self) -> usize {
        self.max.saturating_sub(self.used.load(Ordering::Relaxed))
    }

    /// Charges a piece's `groups` to the budget: kept (trimmed) when `wanted`
    /// and they fit in what was left, else dropped.
    pub(crate) fn settle<T: Copy>(&self, mut groups: Groups<T>, wanted: bool) -> Option<Groups<T>> {
        let n = groups.len();
        let before = self.used.fetch_add(n, Ordering::Relaxed);
        (wanted && before.saturating_add(n) <= self.max).then(|| {
            groups.trim();
            groups
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_give_back_each_groups_items() {
        let mut g = Groups::new();
        let want: Vec<Vec<u32>> = vec![vec![1, 2], vec![], vec![3], vec![4, 5, 6]];
        for items in &want {
            for &x in items {
                g.push(x);
            }
            g.close();
        }
        let mut got: Vec<Vec<u32>> = Vec::new();
        g.for_each_group(|k, items| {
            assert_eq!(k, got.len());
            got.push(items.collect());
        });
        assert_eq!(got, want);
        assert_eq!(g.len(), 6);
    }

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
