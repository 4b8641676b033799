//! The Hi-Z of a view's depth layer ([`ScreenSpaceParams::hiz`]): a min/max
//! depth pyramid over the per-pixel depth bounds, and the hierarchical march
//! over it, whose hits are those of the linear march bit for bit.
//!
//! **Pyramid.** Level 0 is the per-pixel bounds themselves and is not stored
//! again: `[z_f, z_f]` of the nearest fragment ([`Layers::Nearest`], `[inf,
//! -inf]` for an empty pixel) or the A-buffer's `[zmin, zmax]`
//! ([`Layers::All`]). Level `l + 1` holds, per 2×2 block of level `l`, the min
//! of the mins and the max of the maxes (blocks cut at the grid's edge), as
//! DIRT's own pyramid (`mip_depth`), with its shapes ([`hiz_levels`],
//! [`hiz_width`]; pixels are DIRT tiles with `tiles = resolution`).
//!
//! **March.** Depth first from the top cell. A cell is skipped when the ray
//! misses its frustum ([`HiZCell::clip`]) or when the ray's depth span over
//! it, widened by the ray's `eps`, cannot overlap `[min, max + thickness]` of
//! the cell: a pixel's fragment at `z_f` is hit only when the span over the
//! pixel (inside the span over the cell) overlaps `[z_f, z_f + thickness]`,
//! and `min <= z_f <= max`. At level 0 the pixel is treated exactly as the
//! linear march treats it: the same membership in the walk ([`walk_tiles`]:
//! the band range, the band's minor range, a non-empty span), the same span
//! (the same half-spaces clipped in the same order), the same test and hit
//! construction (`ScreenSpace::first_in_pixel`, `hit`).
//!
//! **Order guarantee.** The linear march returns the first pixel *in walk
//! order* whose test passes. The walk order is lexicographic: bands of the
//! major axis in the ray's direction, then pixels of the minor axis in the
//! ray's direction inside a band. So each pixel has a key, (position of its
//! band, position in the band), and the linear march's answer is the pixel of
//! smallest key that passes. The hierarchical march keeps the smallest-key
//! hit found so far and skips every cell whose smallest key (that of its
//! corner first in walk order) is not smaller: a hit is replaced only by a
//! hit of smaller key, and a cell is skipped by key only when none of its
//! pixels could replace it. Every other skip is conservative (no pixel in the
//! skipped cell can pass the level-0 test). Hence when the march ends, every
//! pixel of smaller key than the hit kept has been checked or proven not to
//! pass: the kept hit is the linear march's. Children are visited in walk
//! order ([`child_order`]'s corners, reordered band-major: the entered
//! corner, its neighbour in the same band, then the next band's two), so the
//! first hit found is usually the answer and the rest is skipped by key.
//!
//! The walk's other stop rule, the band entered after the bound (the best
//! hit of an earlier view), is applied afterwards: when the bound is finite,
//! the bands up to the hit's are clipped in walk order and the hit is dropped
//! if the walk would have stopped before reaching it, as the linear march
//! would (it finds nothing before that band, since no pixel of smaller key
//! passes). A bounded march (`max_steps > 0`) runs the linear march.

#[cfg(doc)]
use super::{Layers, ScreenSpaceParams};
use super::{ScreenSpace, ViewStore};
use dirt_core::{Hit, Ray};
use dirt_math::clip::Interval;
#[cfg(doc)]
use dirt_math::dda::walk_tiles;
use dirt_math::dda::{
    HiZCell, WalkPlan, child_order, clip_to_slab, hiz_levels, hiz_width, index_range,
    projected_direction, tile_xy,
};
use dirt_math::{View, ViewRay};

/// One stored level (`>= 1`) of the pyramid: `w`² cells, row-major, `[min, max]`.
#[derive(Debug, Default)]
pub(super) struct Level {
    pub(super) w: u32,
    pub(super) cells: Vec<[f32; 2]>,
}

/// Levels `1..hiz_levels(tiles)` over the per-pixel bounds `level0(pixel)`
/// (`tiles`² pixels, row-major).
pub(super) fn pyramid(tiles: u32, level0: impl Fn(usize) -> [f32; 2]) -> Vec<Level> {
    let levels = hiz_levels(tiles);
    let mut out: Vec<Level> = Vec::with_capacity(levels as usize - 1);
    for l in 1..levels {
        let src_w = hiz_width(tiles, l - 1) as usize;
        let w = hiz_width(tiles, l);
        let wu = w as usize;
        let src = |k: usize| match out.last() {
            None => level0(k),
            Some(prev) => prev.cells[k],
        };
        let mut cells = vec![[f32::INFINITY, f32::NEG_INFINITY]; wu * wu];
        for j in 0..wu {
            for i in 0..wu {
                let mut e = [f32::INFINITY, f32::NEG_INFINITY];
                for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (si, sj) = (2 * i + di, 2 * j + dj);
                    if si < src_w && sj < src_w {
                        let s = src(sj * src_w + si);
                        e[0] = e[0].min(s[0]);
                        e[1] = e[1].max(s[1]);
                    }
                }
                cells[j * wu + i] = e;
            }
        }
        out.push(Level { w, cells });
    }
    out
}

/// The walk's order of one ray in one view: which axis the bands cut, and
/// the directions.
#[derive(Clone, Copy)]
struct Order {
    major: usize,
    forward: bool,
    minor_forward: bool,
    tiles: u32,
}

impl Order {
    /// `(major, minor)` index ranges of the block `[i0, i1) × [j0, j1)`.
    #[inline]
    fn axes(&self, i0: u32, i1: u32, j0: u32, j1: u32) -> (u32, u32, u32, u32) {
        if self.major == 0 {
            (i0, i1, j0, j1)
        } else {
            (j0, j1, i0, i1)
        }
    }

    /// Walk key of the block's pixel first in walk order: (position of its
    /// band, position inside the band). Keys order pixels as the walk does.
    #[inline]
    fn first_key(&self, i0: u32, i1: u32, j0: u32, j1: u32) -> u64 {
        let (k0, k1, m0, m1) = self.axes(i0, i1, j0, j1);
        let a = if self.forward { k0 } else { self.tiles - k1 };
        let b = if self.minor_forward {
            m0
        } else {
            self.tiles - m1
        };
        (u64::from(a) << 32) | u64::from(b)
    }
}

/// A band's interval and its minor index range.
type Band = (Interval, u32, u32);

/// The ray's band over major slab `k` (the walk's clipping), and its minor
/// index range; `None` when the walk visits no pixel of that band.
#[inline]
fn band(v: &View, vr: &ViewRay, iv: Interval, major: usize, delta: f32, k: u32) -> Option<Band> {
    let band = clip_to_slab(v, vr, iv, major, k);
    if band.is_empty() {
        return None;
    }
    let minor = 1 - major;
    let p = tile_xy(v, vr, band.t0);
    let q = tile_xy(v, vr, band.t1);
    let (m0, m1) = index_range(p[minor], q[minor], delta, v.tiles)?;
    Some((band, m0, m1))
}

/// Most cells waiting: one path down the pyramid with at most three siblings
/// per level (13 levels at [`super::MAX_RESOLUTION`]).
const STACK: usize = 64;
const _: () = assert!(3 * 13 < STACK && hiz_levels_max() <= 13);

const fn hiz_levels_max() -> u32 {
    let mut n = 1;
    let mut w = super::MAX_RESOLUTION;
    while w > 1 {
        w = w.div_ceil(2);
        n += 1;
    }
    n
}

impl ScreenSpace {
    /// [`ScreenSpace::march`] through the Hi-Z pyramid: the same result, bit
    /// for bit (module docs).
    pub(super) fn march_hiz(
        &self,
        s: &ViewStore,
        v: &View,
        vr: &ViewRay,
        iv: Interval,
        ray: &Ray,
        bound: f32,
    ) -> Option<Hit> {
        // The walk's plan: `walk_tiles`' own.
        let plan = WalkPlan::of(v, vr, iv)?;
        let tiles = v.tiles;
        let (major, minor, delta) = (plan.major, plan.minor(), plan.delta);
        let (k0, k1) = (plan.k0, plan.k1);
        let order = Order {
            major,
            forward: plan.forward,
            minor_forward: plan.minor_forward,
            tiles,
        };
        // The children in walk order: `child_order` gives the entered corner,
        // its neighbour across the major boundary, the one across the minor
        // boundary, the far corner; the walk finishes the entered corner's
        // band first, so the second and third swap.
        let (dx, dy) = projected_direction(v, vr, &iv);
        let co = child_order(dx, dy);
        let children = [co[0], co[2], co[1], co[3]];
        let ascending = vr.d[2] >= 0.0;
        let th = self.thickness;

        let levels = s.hiz.len() as u32 + 1;
        let mut stack = [HiZCell {
            level: 0,
            i: 0,
            j: 0,
        }; STACK];
        stack[0] = HiZCell {
            level: levels - 1,
            i: 0,
            j: 0,
        };
        let mut len = 1;
        let mut best: Option<(u64, u32, Hit)> = None;
        // The last band clipped (pixels of one band are often visited in a row).
        let mut last_band: Option<(u32, Option<Band>)> = None;
        while len > 0 {
            len -= 1;
            let cell = stack[len];
            let i0 = cell.i << cell.level;
            let j0 = cell.j << cell.level;
            let i1 = ((cell.i + 1) << cell.level).min(tiles);
            let j1 = ((cell.j + 1) << cell.level).min(tiles);
            // Not before the hit kept in walk order: skip.
            if let Some((key, _, _)) = best
                && order.first_key(i0, i1, j0, j1) >= key
            {
                continue;
            }
            // Outside the walk's bands: skip.
            let (ck0, ck1, _, _) = order.axes(i0, i1, j0, j1);
            if ck1 <= k0 || ck0 > k1 {
                continue;
            }
            if cell.level == 0 {
                // Exactly the linear march's pixel.
                let (k, m) = if major == 0 {
                    (cell.i, cell.j)
                } else {
                    (cell.j, cell.i)
                };
                let bk = match last_band {
                    Some((lk, bk)) if lk == k => bk,
                    _ => {
                        let bk = band(v, vr, iv, major, delta, k);
                        last_band = Some((k, bk));
                        bk
                    }
                };
                let Some((band_iv, m0, m1)) = bk else {
                    continue;
                };
                if m < m0 || m > m1 {
                    continue;
                }
                let span = clip_to_slab(v, vr, band_iv, minor, m);
                if span.is_empty() {
                    continue;
                }
                let pixel = (cell.j * tiles + cell.i) as usize;
                let za = vr.o[2] + span.t0 * vr.d[2];
                let zb = vr.o[2] + span.t1 * vr.d[2];
                let (lo, hi) = (za.min(zb), za.max(zb));
                if let Some(f) = self.first_in_pixel(s, pixel, lo, hi, ascending) {
                    let key = order.first_key(cell.i, cell.i + 1, cell.j, cell.j + 1);
                    best = Some((key, k, self.hit(f, vr, span, ray, lo, hi)));
                }
                continue;
            }
            let civ = cell.clip(v, vr, iv);
            if civ.is_empty() {
                continue;
            }
            let level = &s.hiz[cell.level as usize - 1];
            let [zmin, zmax] = level.cells[(cell.j * level.w + cell.i) as usize];
            let za = vr.o[2] + civ.t0 * vr.d[2];
            let zb = vr.o[2] + civ.t1 * vr.d[2];
            // Widened by eps: only skips are decided here, never hits.
            let (lo, hi) = (za.min(zb) - vr.eps, za.max(zb) + vr.eps);
            if !(hi >= zmin && lo <= zmax + th) {
                continue;
            }
            let cw = if cell.level == 1 {
                tiles
            } else {
                s.hiz[cell.level as usize - 2].w
            };
            for &(di, dj) in children.iter().rev() {
                let (i, j) = (2 * cell.i + di, 2 * cell.j + dj);
                if i < cw && j < cw {
                    stack[len] = HiZCell {
                        level: cell.level - 1,
                        i,
                        j,
                    };
                    len += 1;
                }
            }
        }
        let (_, k_hit, hit) = best?;
        // The walk's bound rule: it ends at the first band entered after
        // `bound`. Nothing before the hit's pixel passes, so the linear march
        // finds nothing if that band comes before it (or is its own).
        if bound < f32::INFINITY {
            for n in 0..=(k1 - k0) {
                let k = plan.band(n);
                let band = clip_to_slab(v, vr, iv, major, k);
                if !band.is_empty() && band.t0 > bound {
                    return None;
                }
                if k == k_hit {
                    break;
                }
            }
        }
        Some(hit)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Layers, ScreenSpace, ScreenSpaceParams};
    use dirt_core::Tracer;
    use dirt_math::dda::{hiz_levels, hiz_width};
    use dirt_math::{INVALID_ID, Triangle, Vec3};

    fn random_tris(n: usize, mut seed: u64) -> Vec<Triangle> {
        let mut f = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32) / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(f(), f(), f());
                let mut p = || c + 0.2 * Vec3::new(f(), f(), f());
                Triangle::new(p(), p(), p())
            })
            .collect()
    }

    /// Every level bounds its children, and the top cell bounds every
    /// pixel's fragments (exactly: its min and max are the extreme depths),
    /// for the single layer and for the A-buffer, at resolutions that are
    /// and are not powers of two.
    #[test]
    fn the_top_level_bounds_every_pixel() {
        let tris = random_tris(200, 3);
        for res in [1, 2, 7, 64, 100] {
            for p in [
                ScreenSpaceParams::single_layer(Vec3::new(0.1, 0.3, -2.5), res, 0.01),
                ScreenSpaceParams {
                    hiz: true,
                    ..ScreenSpaceParams::mmrt(res, 4, 0.01)
                },
            ] {
                let mut s = ScreenSpace::new(p).expect("params");
                s.build(&tris).expect("build");
                assert!(s.views() > 0);
                for st in &s.stores {
                    let levels = hiz_levels(res);
                    assert_eq!(st.hiz.len() as u32, levels - 1);
                    let level0: Vec<[f32; 2]> = match p.layers {
                        Layers::Nearest => st
                            .frags
                            .iter()
                            .map(|f| {
                                if f.prim == INVALID_ID {
                                    [f32::INFINITY, f32::NEG_INFINITY]
                                } else {
                                    [f.z, f.z]
                                }
                            })
                            .collect(),
                        Layers::All => st.bounds.clone(),
                    };
                    let (lo, hi) = level0
                        .iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), c| {
                            (a.min(c[0]), b.max(c[1]))
                        });
                    if let Layers::All = p.layers {
                        // The bounds hold every fragment.
                        for f in &st.frags {
                            assert!(lo <= f.z && f.z <= hi);
                        }
                    }
                    let Some(top) = st.hiz.last() else {
                        assert_eq!(res, 1);
                        continue;
                    };
                    assert_eq!(top.w, 1);
                    // (Low resolutions may catch no pixel centre.)
                    assert!(res < 64 || hi > lo, "r{res}: an empty view");
                    assert_eq!(top.cells[0], [lo, hi], "r{res} {}", p.label());
                    for z in &level0 {
                        assert!(top.cells[0][0] <= z[0] && z[1] <= top.cells[0][1]);
                    }
                    // Each cell bounds its children (cut at the edge).
                    for l in 1..levels as usize {
                        let lv = &st.hiz[l - 1];
                        let w = hiz_width(res, l as u32) as usize;
                        let cw = hiz_width(res, l as u32 - 1) as usize;
                        assert_eq!(lv.w as usize, w);
                        for j in 0..cw {
                            for i in 0..cw {
                                let c = if l == 1 {
                                    level0[j * cw + i]
                                } else {
                                    st.hiz[l - 2].cells[j * cw + i]
                                };
                                let e = lv.cells[(j / 2) * w + i / 2];
                                assert!(e[0] <= c[0] && c[1] <= e[1]);
                            }
                        }
                    }
                }
            }
        }
    }
}
