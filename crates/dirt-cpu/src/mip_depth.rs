//! Stage `mip_depth`: the Hi-Z pyramid. Level `l + 1` holds, per 2×2 block of
//! level `l`, the min of the mins and the max of the maxes (blocks cut at the
//! grid's edge). Level 0 is the output of `fill_depth`.
//!
//! Layout of each level: one block per view with content, in slot order
//! ([`dirt_math::View::slot`]), then row-major cells, `[enc(zmin), enc(zmax)]`.

use dirt_math::ViewSet;
use dirt_math::dda::{hiz_levels, hiz_width};
use dirt_math::encode::{ORDERED_NEG_INF, ORDERED_POS_INF};

/// All levels, level 0 first (a copy of `depth`).
pub fn mip_depth(views: &ViewSet, depth: &[[u32; 2]]) -> Vec<Vec<[u32; 2]>> {
    mip_depth_over(views, depth.to_vec())
}

/// [`mip_depth`] taking the depth bounds as level 0 instead of copying them.
pub fn mip_depth_over(views: &ViewSet, depth: Vec<[u32; 2]>) -> Vec<Vec<[u32; 2]>> {
    let tiles = views.views.first().map_or(1, |v| v.tiles);
    let n_views = views.slots();
    let levels = hiz_levels(tiles);
    let mut out = vec![depth];
    for l in 1..levels {
        let src_w = hiz_width(tiles, l - 1) as usize;
        let w = hiz_width(tiles, l) as usize;
        let src = &out[(l - 1) as usize];
        let mut dst = vec![[ORDERED_POS_INF, ORDERED_NEG_INF]; n_views * w * w];
        for view in 0..n_views {
            for j in 0..w {
                for i in 0..w {
                    let mut e = [ORDERED_POS_INF, ORDERED_NEG_INF];
                    for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (si, sj) = (2 * i + di, 2 * j + dj);
                        if si < src_w && sj < src_w {
                            let s = src[view * src_w * src_w + sj * src_w + si];
                            e[0] = e[0].min(s[0]);
                            e[1] = e[1].max(s[1]);
                        }
                    }
                    dst[view * w * w + j * w + i] = e;
                }
            }
        }
        out.push(dst);
    }
    out
}
