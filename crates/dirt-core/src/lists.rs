//! What a build produces that both backends share the shape of.

use std::time::Duration;

/// The per-bucket primitive lists of `fill_primitives`, stored contiguously:
/// list `k` is `ids[offsets[k]..offsets[k + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct IdLists {
    pub offsets: Vec<u32>,
    pub ids: Vec<u32>,
}

impl IdLists {
    /// The ids of list `k`.
    #[inline]
    pub fn list(&self, k: usize) -> &[u32] {
        let (a, b) = (self.offsets[k] as usize, self.offsets[k + 1] as usize);
        &self.ids[a..b]
    }
}

/// Wall time of each build stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildTimings {
    pub fill_depth: Duration,
    pub mip_depth: Duration,
    pub fill_primitives: Duration,
}

impl BuildTimings {
    pub fn total(&self) -> Duration {
        self.fill_depth + self.mip_depth + self.fill_primitives
    }

    /// The stages by name, in build order.
    pub fn stages(&self) -> Vec<(&'static str, Duration)> {
        vec![
            ("fill_depth", self.fill_depth),
            ("mip_depth", self.mip_depth),
            ("fill_primitives", self.fill_primitives),
        ]
    }
}
