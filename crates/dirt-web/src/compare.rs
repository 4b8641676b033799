//! A frame structure built on a GPU, and its hits, against the CPU
//! reference over the same triangles and rays: what differs, counted, with
//! the first difference in words. On lavapipe (NoContraction SPIR-V) nothing
//! may differ; in a browser (Tint compiling the WGSL for the page's device)
//! this is the measurement of how far the portable path holds.

use dirt_core::IdLists;
use dirt_cpu::Ads;
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF};
use dirt_math::view::NO_SLOT;
use dirt_math::{Hit, RayStats, ViewGpu};

/// Elements of a frame structure that differ from the CPU's.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StructureDiff {
    /// Views whose bytes differ (of six).
    pub views: usize,
    /// Hi-Z cells (all levels, all views) that differ.
    pub hiz_cells: usize,
    /// Hi-Z cells compared.
    pub hiz_total: usize,
    /// Lists (per view, tile and bucket) whose sorted ids differ.
    pub lists: usize,
    /// Lists compared.
    pub lists_total: usize,
    /// The first difference, in words.
    pub first: Option<String>,
}

impl StructureDiff {
    /// Nothing differs.
    pub fn is_empty(&self) -> bool {
        self.views == 0 && self.hiz_cells == 0 && self.lists == 0
    }

    fn note(&mut self, what: impl FnOnce() -> String) {
        if self.first.is_none() {
            self.first = Some(what());
        }
    }
}

/// The CPU's views as a frame structure holds them: every view in its own
/// block (slot `k`), views without content keeping [`NO_SLOT`].
pub fn frame_views(cpu: &Ads) -> Vec<ViewGpu> {
    let mut out = vec![ViewGpu::default(); 6];
    for (k, v) in cpu.views.views.iter().enumerate() {
        let mut v = *v;
        if v.slot != NO_SLOT {
            v.slot = k as u32;
        }
        out[k] = ViewGpu::new(&v, cpu.views.adjacency.get(k).copied().unwrap_or([0; 4]));
    }
    out
}

/// A frame structure's views, Hi-Z and lists (as read back) against `cpu`.
/// The frame structure's block `v` is the CPU's block `slot(v)`; blocks of
/// views without content must stay empty. Ids are compared as sorted sets
/// per list (the GPU's order inside a list is its atomics').
pub fn structure(
    views: &[ViewGpu],
    hiz: &[Vec<[u32; 2]>],
    lists: &IdLists,
    cpu: &Ads,
) -> StructureDiff {
    let mut d = StructureDiff::default();
    let want = frame_views(cpu);
    for (k, w) in want.iter().enumerate().take(cpu.views.views.len()) {
        let got = views.get(k).copied().unwrap_or_default();
        if bytemuck::bytes_of(&got) != bytemuck::bytes_of(w) {
            d.views += 1;
            d.note(|| format!("view {k}: gpu {got:?}, cpu {w:?}"));
        }
    }
    let n_views = cpu.views.views.len();
    if hiz.len() != cpu.hiz.len() {
        d.note(|| format!("{} Hi-Z levels, cpu {}", hiz.len(), cpu.hiz.len()));
    }
    for (l, (gl, cl)) in hiz.iter().zip(&cpu.hiz).enumerate() {
        let per = gl.len() / n_views.max(1);
        for (v, view) in cpu.views.views.iter().enumerate() {
            let got = &gl[v * per..(v + 1) * per];
            d.hiz_total += per;
            for (c, cell) in got.iter().enumerate() {
                let want = if view.slot == NO_SLOT {
                    [ORDERED_POS_INF, ORDERED_NEG_INF]
                } else {
                    let at = view.slot as usize * per + c;
                    cl.get(at).copied().unwrap_or([0, 0])
                };
                if *cell != want {
                    d.hiz_cells += 1;
                    d.note(|| {
                        format!("Hi-Z level {l} view {v} cell {c}: gpu {cell:?}, cpu {want:?}")
                    });
                }
            }
        }
    }
    let per = (cpu.params.tiles() as usize).pow(2) * cpu.params.buckets as usize;
    let sorted = |l: &IdLists, k: usize| -> Vec<u32> {
        let (Some(&a), Some(&b)) = (l.offsets.get(k), l.offsets.get(k + 1)) else {
            return Vec::new();
        };
        let mut v = l.ids.get(a as usize..b as usize).unwrap_or(&[]).to_vec();
        v.sort_unstable();
        v
    };
    for (v, view) in cpu.views.views.iter().enumerate() {
        for k in 0..per {
            let got = sorted(lists, v * per + k);
            let want = if view.slot == NO_SLOT {
                Vec::new()
            } else {
                sorted(&cpu.lists, view.slot as usize * per + k)
            };
            d.lists_total += 1;
            if got != want {
                d.lists += 1;
                d.note(|| format!("view {v} list {k}: gpu {got:?}, cpu {want:?}"));
            }
        }
    }
    d
}

/// Rays whose hits (or statistics) differ between two tracers, by field.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HitDiff {
    pub rays: usize,
    /// Rays whose hit differs in any bit.
    pub differ: usize,
    /// ... in the primitive (or hit against miss).
    pub prim: usize,
    /// ... in the bits of `t` (same primitive).
    pub t: usize,
    /// ... in the bits of `u` or `v` (same primitive).
    pub uv: usize,
    /// The largest difference of `t` in units in the last place (same primitive).
    pub t_ulps: u32,
    /// Rays whose statistics differ (when both were given).
    pub stats: usize,
    /// The first differing ray, in words.
    pub first: Option<String>,
}

impl HitDiff {
    /// Nothing differs.
    pub fn is_empty(&self) -> bool {
        self.differ == 0 && self.stats == 0
    }
}

/// `a` against `b`, ray by ray (bits, not values); statistics when both are given.
pub fn hits(a: &[Hit], b: &[Hit], stats: Option<(&[RayStats], &[RayStats])>) -> HitDiff {
    let mut d = HitDiff {
        rays: a.len().max(b.len()),
        ..HitDiff::default()
    };
    if a.len() != b.len() {
        d.differ = d.rays;
        d.first = Some(format!("{} hits against {}", a.len(), b.len()));
    }
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        if x.bits() == y.bits() {
            continue;
        }
        d.differ += 1;
        if x.prim != y.prim {
            d.prim += 1;
        } else {
            if x.t.to_bits() != y.t.to_bits() {
                d.t += 1;
                d.t_ulps = d.t_ulps.max(x.t.to_bits().abs_diff(y.t.to_bits()));
            }
            if x.u.to_bits() != y.u.to_bits() || x.v.to_bits() != y.v.to_bits() {
                d.uv += 1;
            }
        }
        if d.first.is_none() {
            d.first = Some(format!("ray {i}: {x:?} against {y:?}"));
        }
    }
    if let Some((sa, sb)) = stats {
        d.stats = sa.iter().zip(sb).filter(|(x, y)| x != y).count() + sa.len().abs_diff(sb.len());
    }
    d
}
