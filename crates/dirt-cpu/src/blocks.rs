//! [`Blocks`]: a sequence the build grows without reallocating, for what one
//! pass keeps for the next (`fill_depth`'s fragments, the count pass's list
//! indices). A `Vec` grown by doubling can hold twice its length, and copies
//! itself at each growth while both copies are alive; with several pieces in
//! flight that slack decided the build's peak memory. Here each new block
//! holds as many items as the blocks before it (so few blocks), at least
//! [`MIN`] and at most [`MAX`]: the slack stays below one block and under the
//! items already kept, and nothing is copied. [`Groups`] adds how many items
//! each triangle has: what a pass keeps for one piece of triangles;
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

    /// Inlined where it is called (once a fragment or list node); a new
    /// block, once in hundreds of items or more, is made out of line. The
    /// item is written in one place whichever way: where the new block was
    /// handed the item, the item went through the stack on every push, and
    /// a fragment's three words, written there one by one and read back as
    /// wider words, stalled each push (a sixth of the coverage's time).
    #[inline]
    pub(crate) fn push(&mut self, x: T) {
        if self.blocks.last().is_none_or(|b| b.len() >= b.capacity()) {
            self.new_block();
        }
        if let Some(b) = self.blocks.last_mut() {
            b.push(x);
        }
        self.len += 1;
    }

    #[cold]
    #[inline(never)]
    fn new_block(&mut self) {
        self.blocks
            .push(Vec::with_capacity(self.len.clamp(MIN, MAX)));
    }

    /// Frees the last block's unused room (the pass is done with this sequence).
    pub(crate) fn trim(&mut self) {
        if let Some(b) = self.blocks.last_mut() {
            b.shrink_to_fit();
        }
    }

    #[cfg(test)]
    pub(crate) fn iter(&self) -> impl Iterator<Item = T> + '_ {
        self.blocks.iter().flatten().copied()
    }
}

/// [`Blocks`] in consecutive groups (one per triangle of a piece).
///
/// A group's size takes one byte where it is below [`WIDE`] (a triangle's
/// fragments or lists, nearly always), else [`WIDE`] and its size in
/// `wide`: four bytes a triangle were as much as the items themselves on a
/// deforming grid (about two a triangle) and took the build's peak past its
/// bound (`peak_memory.rs`).
#[derive(Debug)]
pub(crate) struct Groups<T> {
    /// Each closed group's size, or [`WIDE`].
    sizes: Vec<u8>,
    /// The sizes of the groups of [`WIDE`] items or more, in order; below
    /// `u32::MAX` items in all (the build's budgets keep them there).
    wide: Vec<u32>,
    /// Items in the closed groups (where the open group starts).
    closed: usize,
    items: Blocks<T>,
}

/// The size byte of a group of this many items or more.
const WIDE: u8 = u8::MAX;

impl<T: Copy> Groups<T> {
    pub(crate) fn new() -> Self {
        Groups {
            sizes: Vec::new(),
            wide: Vec::new(),
            closed: 0,
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
        let n = self.items.len() - self.closed;
        match u8::try_from(n) {
            Ok(b) if b < WIDE => self.sizes.push(b),
            _ => {
                self.sizes.push(WIDE);
                self.wide.push(n.min(u32::MAX as usize) as u32);
            }
        }
        self.closed = self.items.len();
    }

    /// Frees the unused room (the pass is done with these groups).
    pub(crate) fn trim(&mut self) {
        self.items.trim();
        self.sizes.shrink_to_fit();
        self.wide.shrink_to_fit();
    }

    /// Every item, in order, without its group.
    pub(crate) fn items(&self) -> impl Iterator<Item = &T> {
        self.items.blocks.iter().flatten()
    }

    /// Calls `item(state, group, x)` for every item of every closed group, in
    /// order, and `end(state, group)` after each group's items (empty groups
    /// included); `state` is what both may change. A walk over the blocks'
    /// slices: the items are visited in a plain loop the compiler sees
    /// through, not through an iterator per group.
    pub(crate) fn for_each_group<S>(
        &self,
        state: &mut S,
        mut item: impl FnMut(&mut S, usize, T),
        mut end: impl FnMut(&mut S, usize),
    ) {
        let mut wide = self.wide.iter();
        let mut blocks = self.items.blocks.iter();
        let mut rest: &[T] = &[];
        for (g, &size) in self.sizes.iter().enumerate() {
            let mut n = if size == WIDE {
                wide.next().map_or(0, |&n| n as usize)
            } else {
                usize::from(size)
            };
            // The group's items, from this block and the next ones.
            while n > 0 {
                if rest.is_empty() {
                    match blocks.next() {
                        Some(b) => rest = b.as_slice(),
                        None => break,
                    }
                }
                let (head, tail) = rest.split_at(n.min(rest.len()));
                for &x in head {
                    item(state, g, x);
                }
                n -= head.len();
                rest = tail;
            }
            end(state, g);
        }
    }
}

/// How many items the pieces of a pass may keep together. A piece is kept
/// whole or not at all: one that does not fit what was left is dropped (the
/// next pass finds its items again).
#[derive(Debug)]
pub(crate) struct Budget {
    max: AtomicUsize,
    used: AtomicUsize,
}

impl Budget {
    pub(crate) fn new(max: usize) -> Self {
        Budget {
            max: AtomicUsize::new(max),
            used: AtomicUsize::new(0),
        }
    }

    /// What is left of the budget now.
    pub(crate) fn room(&self) -> usize {
        self.max
            .load(Ordering::Relaxed)
            .saturating_sub(self.used.load(Ordering::Relaxed))
    }

    /// Raises the budget by `n` items (for what the pass has shown the
    /// structure will hold), to at most `ceiling`.
    pub(crate) fn raise(&self, n: usize, ceiling: usize) {
        let _ = self
            .max
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |m| {
                Some(m.saturating_add(n).min(ceiling))
            });
    }

    /// Charges a piece's `groups` to the budget: kept (trimmed) when `wanted`
    /// and they fit in what was left, else dropped.
    pub(crate) fn settle<T: Copy>(&self, groups: Groups<T>, wanted: bool) -> Option<Groups<T>> {
        if wanted {
            self.keep(groups).ok()
        } else {
            self.charge(groups.len());
            None
        }
    }

    /// [`Budget::settle`] of wanted groups, giving them back when they do
    /// not fit (for the caller's last use before they are dropped).
    pub(crate) fn keep<T: Copy>(&self, mut groups: Groups<T>) -> Result<Groups<T>, Groups<T>> {
        if self.charge(groups.len()) {
            groups.trim();
            Ok(groups)
        } else {
            Err(groups)
        }
    }

    /// Charges `n` items; whether they fit in what was left.
    fn charge(&self, n: usize) -> bool {
        let before = self.used.fetch_add(n, Ordering::Relaxed);
        before.saturating_add(n) <= self.max.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Groups of `sizes` items (counting up from 0) walked back.
    fn walk(sizes: &[usize]) -> Vec<Vec<u32>> {
        let mut g = Groups::new();
        let mut x = 0u32;
        for &n in sizes {
            for _ in 0..n {
                g.push(x);
                x += 1;
            }
            g.close();
        }
        assert_eq!(g.len(), x as usize);
        let mut walked = (Vec::<Vec<u32>>::new(), Vec::<u32>::new());
        g.for_each_group(
            &mut walked,
            |(got, open), k, x| {
                assert_eq!(k, got.len(), "an item of group {k} given after its end");
                open.push(x);
            },
            |(got, open), k| {
                assert_eq!(k, got.len(), "groups ended in order");
                got.push(std::mem::take(open));
            },
        );
        let (got, open) = walked;
        assert!(open.is_empty());
        got
    }

    #[test]
    fn groups_give_back_each_groups_items() {
        // Empty groups first, in the middle and last; groups across the
        // first blocks' ends (MIN, then 2·MIN items) and one larger than a block.
        // Sizes on both sides of the one-byte ones (WIDE).
        let w = usize::from(WIDE);
        let cases: [&[usize]; 5] = [
            &[2, 0, 1, 3],
            &[0, 0, 5, 0],
            &[MIN - 1, 2, 0, MIN, 7, 0, 0],
            &[3, MAX + 100, 0, 2 * MAX, 1, 0],
            &[w - 1, w, w + 1, 1, w, 0, 3 * w],
        ];
        for sizes in cases {
            let got = walk(sizes);
            let mut x = 0u32;
            let want: Vec<Vec<u32>> = sizes
                .iter()
                .map(|&n| {
                    let v: Vec<u32> = (x..x + n as u32).collect();
                    x += n as u32;
                    v
                })
                .collect();
            assert_eq!(got, want, "groups of {sizes:?}");
        }
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

    #[test]
    fn a_raised_budget_stops_at_its_ceiling() {
        let b = Budget::new(10);
        b.raise(5, 100);
        assert_eq!(b.room(), 15);
        b.raise(1000, 100);
        assert_eq!(b.room(), 100);
        // A ceiling of 0 (nothing may be kept) keeps the budget at 0.
        let none = Budget::new(0);
        none.raise(1000, 0);
        assert_eq!(none.room(), 0);
    }
}
