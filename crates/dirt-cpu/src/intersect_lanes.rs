//! [`intersect_closest`] for [`LANES`] triangles at once: the part of the
//! watertight test that decides most misses — vertices relative to the
//! origin, the shear, the three edge functions and their sign test — as
//! lanes the compiler puts side by side in vector registers. A lane whose
//! edge function cancels too much takes [`edge_function`]'s accurate path on
//! its own; a lane that passes the sign test ends in the scalar
//! [`finish`]. Every value a lane computes is the scalar test's, from the
//! same operands in the same order (`+ − ×`, correctly rounded `/`,
//! comparisons; no fused multiply-add), so each lane's result is
//! [`intersect`]'s, bit for bit. The lanes also compute [`finish`]'s `t` and
//! test its range, the best hit so far as the cap, so only candidates that
//! could be kept reach the scalar rest, nearest first: the first of them that
//! is a hit ends the group (a farther one could not be kept).
//!
//! The closest hit does not depend on the order the candidates are tested
//! in: [`intersect`] does not read the best hit, and [`Hit::closer_than`] is
//! a total order on hits (`t`, then id). So testing a list in groups of
//! lanes, then keeping the closest, gives the scalar loop's hit.
//! The tests below check both on random triangles and rays.
//!
//! [`intersect`]: dirt_math::triangle::intersect
//! [`intersect_closest`]: dirt_math::triangle::intersect_closest

use dirt_math::triangle::{RayShear, diff_of_products, finish, keep_closest};
use dirt_math::{Hit, Ray, Triangle};
use std::array::from_fn;

/// Triangles tested together: four `f32` lanes fill the x86-64 baseline's
/// vector registers (SSE2), and NEON's.
pub(crate) const LANES: usize = 4;

type L = [f32; LANES];

/// [`edge_function`](dirt_math::triangle::edge_function) of four lanes: the
/// plain difference where it lost fewer than 5 bits, else the accurate one.
#[inline(always)]
fn edge_lanes(a: L, b: L, c: L, d: L) -> L {
    let p: L = from_fn(|k| a[k] * b[k]);
    let q: L = from_fn(|k| c[k] * d[k]);
    let e: L = from_fn(|k| p[k] - q[k]);
    let plain: [bool; LANES] = from_fn(|k| e[k].abs() >= (p[k].abs() + q[k].abs()) * (1.0 / 32.0));
    if plain.iter().all(|&x| x) {
        return e;
    }
    from_fn(|k| {
        if plain[k] {
            e[k]
        } else {
            diff_of_products(a[k], b[k], c[k], d[k])
        }
    })
}

/// Tests the triangles `ids` (indices into `tris`) and keeps the closest hit
/// in `best`, as [`intersect_closest`](dirt_math::triangle::intersect_closest)
/// on each in turn would.
#[inline]
pub(crate) fn intersect_closest_lanes(
    ray: &Ray,
    sh: &RayShear,
    tris: &[Triangle],
    ids: [u32; LANES],
    best: &mut Hit,
) {
    let o = ray.origin;
    let tri: [&Triangle; LANES] = from_fn(|k| &tris[ids[k] as usize]);
    let (kx, ky, kz) = (sh.kx, sh.ky, sh.kz);
    // Vertex `n`'s component `axis` relative to the origin, as lanes: only
    // the ray's three axes in its order, loaded where they lie, so no lane
    // array is indexed by the ray's axes.
    let rel = |n: usize, axis: usize| -> L { from_fn(|k| tri[k].v[n][axis] - o[axis]) };
    let vertex = |n: usize| -> [L; 3] { [rel(n, kx), rel(n, ky), rel(n, kz)] };
    let (a, b, c) = (vertex(0), vertex(1), vertex(2));
    let (sx, sy) = (sh.sx, sh.sy);
    let shear = |p: &[L; 3]| -> (L, L) {
        (
            from_fn(|k| p[0][k] - sx * p[2][k]),
            from_fn(|k| p[1][k] - sy * p[2][k]),
        )
    };
    let ((ax, ay), (bx, by), (cx, cy)) = (shear(&a), shear(&b), shear(&c));
    let e0 = edge_lanes(cx, by, cy, bx);
    let e1 = edge_lanes(ax, cy, ay, cx);
    let e2 = edge_lanes(bx, ay, by, ax);
    // The scalar test's rejection, eagerly: some edge function negative and some positive.
    let pass: [bool; LANES] = from_fn(|k| {
        let neg = (e0[k] < 0.0) | (e1[k] < 0.0) | (e2[k] < 0.0);
        let pos = (e0[k] > 0.0) | (e1[k] > 0.0) | (e2[k] > 0.0);
        !(neg & pos)
    });
    if !pass.iter().any(|&x| x) {
        return;
    }
    // finish's determinant and `t`, as lanes, and its range test with the
    // best hit so far as the cap: a lane that fails here would fail there
    // (the cap only falls as lanes are kept), so only the rest go on.
    let det: L = from_fn(|k| e0[k] + e1[k] + e2[k]);
    let sz = sh.sz;
    let tt: L =
        from_fn(|k| e0[k] * (sz * a[2][k]) + e1[k] * (sz * b[2][k]) + e2[k] * (sz * c[2][k]));
    let t: L = from_fn(|k| tt[k] / det[k]);
    let cap = best.t;
    let pass: [bool; LANES] = from_fn(|k| {
        pass[k] & (det[k] != 0.0) & (t[k] >= ray.tmin) & (t[k] <= ray.tmax) & (t[k] <= cap)
    });
    if !pass.iter().any(|&x| x) {
        return;
    }
    // Nearest first, in the order `Hit::closer_than` keeps hits (`t`, then
    // id): the `t` finish computes is the lane's, so once a lane is a hit
    // (kept or not), no lane after it could be kept, and the rest are not
    // finished. Stacked triangles pass several lanes of a group.
    let mut left = pass;
    while let Some(k) = nearest(&left, &t, &ids) {
        left[k] = false;
        // The vertices relative to the origin in world axes, as finish
        // takes them: the same subtractions, so the same bits.
        let v = &tri[k].v;
        let abc: [[f32; 3]; 3] = from_fn(|n| from_fn(|axis| v[n][axis] - o[axis]));
        let hit = finish(ray, sh, tri[k], abc, [e0[k], e1[k], e2[k]], best.t);
        if hit.is_some() {
            keep_closest(hit, ids[k], best);
            return;
        }
    }
}

/// The lane of `left` whose `(t, id)` comes first in `Hit::closer_than`'s order.
#[inline(always)]
fn nearest(left: &[bool; LANES], t: &L, ids: &[u32; LANES]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for k in 0..LANES {
        if left[k] && best.is_none_or(|b| t[k] < t[b] || (t[k] == t[b] && ids[k] < ids[b])) {
            best = Some(k);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_math::Vec3;
    use dirt_math::triangle::{intersect, intersect_closest};
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f32> {
        prop_oneof![
            4 => -2.0f32..2.0,
            1 => Just(0.0f32),
            1 => Just(-0.0f32),
            1 => Just(1.0f32),
            1 => -1e-20f32..1e-20,
            1 => -3e7f32..3e7,
        ]
    }

    fn v3() -> impl Strategy<Value = Vec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Triangles that share vertices and edges with one another (fans over a
    /// few points), so rays through edges and vertices are common; some
    /// degenerate, some needles.
    fn triangles() -> impl Strategy<Value = Vec<Triangle>> {
        (
            prop::collection::vec(v3(), 3..7),
            prop::collection::vec((0usize..7, 0usize..7, 0usize..7), 1..13),
        )
            .prop_map(|(points, idx)| {
                idx.iter()
                    .map(|&(a, b, c)| {
                        let p = |i: usize| points[i % points.len()];
                        Triangle::new(p(a), p(b), p(c))
                    })
                    .collect()
            })
    }

    /// The scalar loop: each id in turn, every candidate tested in full
    /// (no cap), so the cap the lanes use is checked too.
    fn scalar(ray: &Ray, tris: &[Triangle], ids: &[u32]) -> Hit {
        let sh = RayShear::new(ray);
        let mut best = Hit::MISS;
        for &id in ids {
            keep_closest(intersect(ray, &sh, &tris[id as usize]), id, &mut best);
        }
        best
    }

    /// Groups of LANES, then the rest one by one: the trace's loop.
    fn lanes(ray: &Ray, tris: &[Triangle], ids: &[u32]) -> Hit {
        let sh = RayShear::new(ray);
        let mut best = Hit::MISS;
        let mut groups = ids.chunks_exact(LANES);
        for g in groups.by_ref() {
            intersect_closest_lanes(ray, &sh, tris, from_fn(|k| g[k]), &mut best);
        }
        for &id in groups.remainder() {
            intersect_closest(ray, &sh, &tris[id as usize], id, &mut best);
        }
        best
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(3000))]

        /// Every lane is the scalar test: the same hit, to the bit, for rays
        /// aimed at vertices, edge points and interiors, and from anywhere.
        #[test]
        fn lanes_hit_what_the_scalar_loop_hits(
            tris in triangles(),
            o in v3(),
            aim in (0usize..12, 0.0f32..1.0, 0.0f32..1.0),
            free in v3(),
            aimed in any::<bool>(),
            tmin in prop_oneof![Just(0.0f32), 0.0f32..1.0],
            tmax in prop_oneof![Just(f32::INFINITY), 0.5f32..4.0],
        ) {
            let (n, s, r) = aim;
            let t = &tris[n % tris.len()];
            let v = |k: usize| Vec3::from(t.v[k]);
            // A vertex, an edge point or an interior point of one triangle.
            let target = match n % 3 {
                0 => v(n % 3),
                1 => v(0) + (v(1) - v(0)) * s,
                _ => v(0) + (v(1) - v(0)) * s + (v(2) - v(0)) * (r * (1.0 - s)),
            };
            let d = if aimed { target - o } else { free };
            let ray = Ray::new(o, d, tmin, tmax);
            prop_assume!(ray.validate().is_ok());
            // Every triangle, some twice, in list order and reversed.
            let mut ids: Vec<u32> = (0..tris.len() as u32).collect();
            ids.extend((0..tris.len() as u32).step_by(3));
            let want = scalar(&ray, &tris, &ids);
            prop_assert_eq!(lanes(&ray, &tris, &ids).bits(), want.bits());
            ids.reverse();
            prop_assert_eq!(lanes(&ray, &tris, &ids).bits(), want.bits());
        }
    }

    /// Triangles whose sheared edge functions cancel (vertices far from the
    /// origin, the ray through a shared edge): lanes mix the plain and the
    /// accurate path, and the shared edge still leaks nothing.
    #[test]
    fn lanes_take_the_accurate_path_where_it_cancels() {
        let far = 1.0e6f32;
        let a = Vec3::new(far, far, 10.0);
        let b = Vec3::new(far + 1.0, far + 0.5, 10.0);
        let c = Vec3::new(far + 0.25, far + 1.0, 10.0);
        let d = Vec3::new(far - 0.75, far + 0.75, 10.0);
        let tris = vec![
            Triangle::new(a, b, c),
            Triangle::new(a, c, d),
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y),
            Triangle::new(a, a, b),
        ];
        let (mut hits, mut accurate) = (0, 0);
        for k in 0..=64 {
            let on_edge = a + (c - a) * (k as f32 / 64.0);
            let o = Vec3::new(far * 0.5, far * 0.5 - 3.0, -5.0);
            let ray = Ray::new(o, on_edge - o, 0.0, f32::INFINITY);
            let ids = [0, 1, 2, 3];
            let want = scalar(&ray, &tris, &ids);
            assert_eq!(lanes(&ray, &tris, &ids).bits(), want.bits(), "ray {k}");
            hits += usize::from(want.is_hit());
            // Whether the shared edge's function of triangle 0 cancels past the plain path.
            let sh = RayShear::new(&ray);
            let sheared = |p: Vec3| {
                let p = (p - o).to_array();
                (p[sh.kx] - sh.sx * p[sh.kz], p[sh.ky] - sh.sy * p[sh.kz])
            };
            let ((ax, ay), (cx, cy)) = (sheared(a), sheared(c));
            let (p, q) = (ax * cy, ay * cx);
            accurate += usize::from((p - q).abs() < (p.abs() + q.abs()) * (1.0 / 32.0));
        }
        // Rays through the shared edge find one of its triangles, and some of
        // them needed the accurate edge function.
        assert!(hits >= 60, "{hits} of 65 rays hit");
        assert!(accurate > 0, "no ray took the accurate path");
    }
}
