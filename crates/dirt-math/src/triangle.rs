//! The watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013).
//!
//! Written under the bit-exact rules of the design brief §3 so that WGSL can
//! mirror it operation for operation: only `+ - *`, comparisons and three
//! correctly rounded divisions (the per-ray shear constants and `t`, `u`, `v`);
//! no fused multiply-add, every product and sum bracketed as it is written.
//!
//! Rays through a shared edge or vertex hit at least one of the triangles that
//! share it: an edge function that is exactly zero counts as inside, so no ray
//! leaks between neighbours. Ties between triangles are broken by [`Hit::closer_than`].

use crate::num::fmax;
use crate::types::{Hit, Ray, Triangle};

/// Per-ray constants of the test: the axis permutation and the shear.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayShear {
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
}

impl RayShear {
    pub fn new(ray: &Ray) -> Self {
        let [dx, dy, dz] = ray.dir;
        // Components by axis through a select, not by indexing a copy of
        // `dir`: the copy went through the stack, and reading it back as
        // wider words than it was written stalled each ray's set-up.
        let d = |k: usize| match k {
            0 => dx,
            1 => dy,
            _ => dz,
        };
        let ax = dx.abs();
        let ay = dy.abs();
        let az = dz.abs();
        // Largest component; ties resolved towards x, then y (fixed, so WGSL can follow).
        let kz = if ax >= ay && ax >= az {
            0
        } else if ay >= az {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swap when the major component is negative.
        if d(kz) < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            kx,
            ky,
            kz,
            sx: d(kx) / d(kz),
            sy: d(ky) / d(kz),
            sz: 1.0 / d(kz),
        }
    }
}

/// Veltkamp split: `a = hi + lo` exactly, each half with at most 12 significant bits.
#[inline]
pub fn split(a: f32) -> (f32, f32) {
    let c = 4097.0 * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

/// Dekker's product: `a·b = p + e` exactly (barring overflow and underflow),
/// with `+ - *` only, so a GPU without fused multiply-add computes the same bits.
#[inline]
pub fn two_product(a: f32, b: f32) -> (f32, f32) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// `a·b − c·d` with an error of a few ulps of the result (not of the products).
#[inline]
pub fn diff_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let (p, pe) = two_product(a, b);
    let (q, qe) = two_product(c, d);
    (p - q) + (pe - qe)
}

/// An edge function `a·b − c·d`. The plain difference is kept when it has lost
/// fewer than 5 bits to cancellation; otherwise it is recomputed exactly
/// enough. The choice depends only on `|a·b|`, `|c·d|` and `|a·b − c·d|`, so the
/// two triangles sharing an edge (which see it with the products swapped) make
/// the same choice and get exactly opposite values: no leak between them.
#[inline]
pub fn edge_function(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = a * b;
    let q = c * d;
    let e = p - q;
    if e.abs() >= (p.abs() + q.abs()) * (1.0 / 32.0) {
        e
    } else {
        diff_of_products(a, b, c, d)
    }
}

/// Intersects `ray` with `tri`. Returns `(t, u, v)` with `t` in `[tmin, tmax]`,
/// `u` the weight of vertex 1 and `v` of vertex 2, or `None`.
///
/// Degenerate triangles (zero area, see [`is_degenerate`], or zero sheared area)
/// are never hit. Back faces are hit.
/// A reported hit point `origin + t·dir` lies within `2^-15 · max|vertex − origin|`
/// of the triangle point its barycentrics name: candidates that fail this (rays in
/// the plane of a triangle, where even accurate edge functions cannot place the
/// point) are misses. The traversal's dilation is larger than this bound, which is
/// what lets DIRT find every hit this test reports.
#[inline]
pub fn intersect(ray: &Ray, sh: &RayShear, tri: &Triangle) -> Option<(f32, f32, f32)> {
    intersect_below(ray, sh, tri, f32::INFINITY)
}

/// [`intersect`], with candidates beyond `cap` left out early (see [`finish`]).
#[inline]
pub fn intersect_below(
    ray: &Ray,
    sh: &RayShear,
    tri: &Triangle,
    cap: f32,
) -> Option<(f32, f32, f32)> {
    let o = ray.origin;
    let (kx, ky, kz) = (sh.kx, sh.ky, sh.kz);
    // Vertices relative to the origin.
    let a = [tri.v[0][0] - o[0], tri.v[0][1] - o[1], tri.v[0][2] - o[2]];
    let b = [tri.v[1][0] - o[0], tri.v[1][1] - o[1], tri.v[1][2] - o[2]];
    let c = [tri.v[2][0] - o[0], tri.v[2][1] - o[1], tri.v[2][2] - o[2]];
    // Shear so the ray runs along +z.
    let ax = a[kx] - sh.sx * a[kz];
    let ay = a[ky] - sh.sy * a[kz];
    let bx = b[kx] - sh.sx * b[kz];
    let by = b[ky] - sh.sy * b[kz];
    let cx = c[kx] - sh.sx * c[kz];
    let cy = c[ky] - sh.sy * c[kz];
    // Scaled barycentrics (edge functions), sign-accurate.
    let e0 = edge_function(cx, by, cy, bx);
    let e1 = edge_function(ax, cy, ay, cx);
    let e2 = edge_function(bx, ay, by, ax);
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    finish(ray, sh, tri, [a, b, c], [e0, e1, e2], cap)
}

/// The rest of [`intersect`] for a candidate whose edge functions `e` (of the
/// vertices `abc` relative to the origin, before the shear) passed the sign
/// test: the determinant, `t`, the barycentrics and the point check. Apart
/// so that a lane-wise front (several triangles at once) can end in the same
/// operations, and so the same bits.
///
/// A candidate whose `t` exceeds `cap` is `None` before the barycentrics and
/// the point check: a caller that keeps the closest hit passes its best `t`
/// (a `t` above it could not be kept, and one equal to it still is, so the
/// closest hit does not change). [`intersect`] passes infinity.
#[inline]
pub fn finish(
    ray: &Ray,
    sh: &RayShear,
    tri: &Triangle,
    [a, b, c]: [[f32; 3]; 3],
    [e0, e1, e2]: [f32; 3],
    cap: f32,
) -> Option<(f32, f32, f32)> {
    let kz = sh.kz;
    let det = e0 + e1 + e2;
    if det == 0.0 || det.is_nan() {
        return None;
    }
    let az = sh.sz * a[kz];
    let bz = sh.sz * b[kz];
    let cz = sh.sz * c[kz];
    let tt = e0 * az + e1 * bz + e2 * cz;
    let t = tt / det;
    if !(t >= ray.tmin && t <= ray.tmax && t <= cap) {
        return None;
    }
    let u = e1 / det;
    let v = e2 / det;
    // The point the barycentrics name, relative to the origin, against t·dir.
    let d = ray.dir;
    let mut err: f32 = 0.0;
    let mut size: f32 = 0.0;
    for k in 0..3 {
        let y = a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]);
        err = fmax(err, (t * d[k] - y).abs());
        size = fmax(fmax(fmax(size, a[k].abs()), b[k].abs()), c[k].abs());
    }
    if !(err <= size * (1.0 / 32768.0)) {
        return None;
    }
    // Checked last, so it costs nothing on the many candidates that miss.
    if is_degenerate(tri) {
        return None;
    }
    Some((t, u, v))
}

/// True when the triangle has zero area: the cross product of its edge vectors
/// `v1 − v0` and `v2 − v0` (as `f32`) is exactly zero, which covers repeated
/// vertices and collinear ones. [`intersect`] never hits such a triangle: its
/// sheared edge functions carry rounding, so without this a ray through one of
/// its vertices could see a tiny non-zero area and report a hit.
#[inline]
pub fn is_degenerate(tri: &Triangle) -> bool {
    let [a, b, c] = tri.v;
    let e = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let f = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let nx = edge_function(e[1], f[2], e[2], f[1]);
    let ny = edge_function(e[2], f[0], e[0], f[2]);
    let nz = edge_function(e[0], f[1], e[1], f[0]);
    nx == 0.0 && ny == 0.0 && nz == 0.0
}

/// Tests `tri` (id `prim`) and keeps it in `best` if it is closer under the
/// deterministic order of §2 (smaller `t`, then smaller id).
#[inline]
pub fn intersect_closest(ray: &Ray, sh: &RayShear, tri: &Triangle, prim: u32, best: &mut Hit) {
    // A hit beyond the best one could not be kept: its barycentrics are not needed.
    keep_closest(intersect_below(ray, sh, tri, best.t), prim, best);
}

/// Keeps the hit `(t, u, v)` of triangle `prim`, if any, in `best` when it is
/// closer: the second half of [`intersect_closest`], for tests made otherwise.
#[inline]
pub fn keep_closest(hit: Option<(f32, f32, f32)>, prim: u32, best: &mut Hit) {
    if let Some((t, u, v)) = hit {
        let cand = Hit { prim, t, u, v };
        if cand.closer_than(best) {
            *best = cand;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use proptest::prelude::*;

    fn ray(o: Vec3, d: Vec3) -> Ray {
        Ray::new(o, d, 0.0, f32::INFINITY)
    }

    #[test]
    fn hits_centre_and_reports_barycentrics() {
        let tri = Triangle::new(
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        );
        let r = ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z);
        let (t, u, v) = intersect(&r, &RayShear::new(&r), &tri).expect("hit");
        assert_eq!(t, 1.0);
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.25).abs() < 1e-6);
        let back = ray(Vec3::new(0.25, 0.25, 2.0), -Vec3::Z);
        assert_eq!(
            intersect(&back, &RayShear::new(&back), &tri).map(|h| h.0),
            Some(1.0)
        );
        let miss = ray(Vec3::new(0.75, 0.75, 0.0), Vec3::Z);
        assert!(intersect(&miss, &RayShear::new(&miss), &tri).is_none());
    }

    #[test]
    fn respects_the_parameter_range() {
        let tri = Triangle::new(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        );
        let mut r = ray(Vec3::ZERO, Vec3::Z);
        r.tmax = 1.5;
        assert!(intersect(&r, &RayShear::new(&r), &tri).is_none());
        r.tmax = 2.0;
        assert!(intersect(&r, &RayShear::new(&r), &tri).is_some());
        r.tmin = 2.5;
        r.tmax = 5.0;
        assert!(intersect(&r, &RayShear::new(&r), &tri).is_none());
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let p = Vec3::new(0.0, 0.0, 1.0);
        let tris = [
            Triangle::new(p, p, p),
            Triangle::new(p, p + Vec3::X, p + 2.0 * Vec3::X),
            Triangle::new(p, p + Vec3::X, p),
        ];
        for tri in &tris {
            for d in [Vec3::Z, Vec3::new(0.3, 0.1, 1.0), Vec3::X] {
                let r = ray(Vec3::new(0.5, 0.0, 0.0), d);
                assert!(
                    intersect(&r, &RayShear::new(&r), tri).is_none(),
                    "{tri:?} {d}"
                );
            }
        }
    }

    /// Regression: a ray aimed exactly at a vertex of a triangle whose three
    /// vertices lie on one line saw a non-zero sheared area from rounding and
    /// hit it at `u = v = 0`.
    #[test]
    fn collinear_triangle_is_not_hit_through_its_vertex() {
        let tri = Triangle {
            v: [
                [-0.04892361, 0.5, 0.25],
                [0.4510764, 0.5, 0.25],
                [0.20107639, 0.5, 0.25],
            ],
        };
        assert!(is_degenerate(&tri));
        let r = Ray {
            origin: [-1.6860116, -0.17935133, -1.2122355],
            tmin: 0.0,
            dir: [1.637088, 0.67935133, 1.4622355],
            tmax: f32::INFINITY,
        };
        assert_eq!(intersect(&r, &RayShear::new(&r), &tri), None);
        // A real triangle of the same size is hit there.
        let mut ok = tri;
        ok.v[2][1] = 0.75;
        assert!(!is_degenerate(&ok));
        assert!(intersect(&r, &RayShear::new(&r), &ok).is_some());
    }

    #[test]
    fn tie_break_prefers_smaller_id() {
        let tri = Triangle::new(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        );
        let r = ray(Vec3::ZERO, Vec3::Z);
        let sh = RayShear::new(&r);
        let mut best = Hit::MISS;
        intersect_closest(&r, &sh, &tri, 7, &mut best);
        intersect_closest(&r, &sh, &tri, 3, &mut best);
        intersect_closest(&r, &sh, &tri, 5, &mut best);
        assert_eq!(best.prim, 3);
    }

    /// Regression: a ray lying in the plane of a nearly edge-on triangle of
    /// 2CylinderEngine.glb. Plain edge functions cancel to zero and claimed a hit
    /// 25 units away from the triangle; brute force then disagreed with DIRT.
    #[test]
    fn ray_in_the_plane_of_a_triangle_is_not_hit_far_away() {
        let tri = Triangle {
            v: [
                [-317.66214, 11.350983, -95.10492],
                [-318.4213, 10.132622, -94.42256],
                [-317.99915, 9.068169, -93.32027],
            ],
        };
        let r = Ray::new(
            Vec3::new(-312.48438, -11.57077, -73.19285),
            Vec3::new(-0.44610596, 0.109119415, -0.3008423),
            0.0,
            f32::INFINITY,
        );
        assert_eq!(intersect(&r, &RayShear::new(&r), &tri), None);
    }

    proptest! {
        #[test]
        fn two_product_is_exact(a in -1e6f32..1e6, b in -1e6f32..1e6) {
            let (p, e) = two_product(a, b);
            prop_assert_eq!(p as f64 + e as f64, a as f64 * b as f64);
        }

        #[test]
        fn diff_of_products_is_accurate(a in -1e3f32..1e3, b in -1e3f32..1e3, c in -1e3f32..1e3, k in -4i32..4) {
            // c·d close to a·b: the cancelling case plain arithmetic gets wrong.
            let d = ((a as f64 * b as f64) / c as f64 * (1.0 + k as f64 * 1e-7)) as f32;
            prop_assume!(c.abs() > 1e-3 && d.is_finite());
            let exact = a as f64 * b as f64 - c as f64 * d as f64;
            let got = diff_of_products(a, b, c, d) as f64;
            let bound = 4.0 * f32::EPSILON as f64 * exact.abs() + 1e-12 * (a as f64 * b as f64).abs();
            prop_assert!((got - exact).abs() <= bound, "{} vs {}", got, exact);
        }

        // Reported hits lie on the triangle: the point at t is within the stated
        // bound of the point the barycentrics name, computed in f64.
        #[test]
        fn hit_points_lie_on_the_triangle(q in proptest::array::uniform9(-10.0f32..10.0), o in proptest::array::uniform3(-20.0f32..20.0), f in proptest::array::uniform2(0.0f32..1.0)) {
            let tri = Triangle { v: [[q[0], q[1], q[2]], [q[3], q[4], q[5]], [q[6], q[7], q[8]]] };
            let (u, v) = if f[0] + f[1] > 1.0 { (1.0 - f[0], 1.0 - f[1]) } else { (f[0], f[1]) };
            let p = tri.vertex(0) + (tri.vertex(1) - tri.vertex(0)) * u + (tri.vertex(2) - tri.vertex(0)) * v;
            let org = Vec3::from_array(o);
            let r = ray(org, p - org);
            prop_assume!(r.dir().length() > 1e-3);
            if let Some((t, hu, hv)) = intersect(&r, &RayShear::new(&r), &tri) {
                let at = |k: usize| org[k] as f64 + t as f64 * r.dir[k] as f64;
                let on = |k: usize| tri.v[0][k] as f64 + hu as f64 * (tri.v[1][k] as f64 - tri.v[0][k] as f64) + hv as f64 * (tri.v[2][k] as f64 - tri.v[0][k] as f64);
                let size = (0..3).map(|k| (0..3).map(|i| (tri.v[i][k] - o[k]).abs()).fold(0.0f32, f32::max)).fold(0.0f32, f32::max) as f64;
                for k in 0..3 {
                    prop_assert!((at(k) - on(k)).abs() <= size / 16384.0, "axis {}: {} vs {}", k, at(k), on(k));
                }
            }
        }

        // A ray through a random point of the shared edge of two triangles, or
        // through the shared vertex of a fan, hits at least one of them.
        #[test]
        fn shared_edges_never_leak(
            ox in -10.0f32..10.0, oy in -10.0f32..10.0, oz in -10.0f32..10.0,
            q in proptest::array::uniform12(-5.0f32..5.0), f in 0.01f32..0.99,
        ) {
            let a = Vec3::new(q[0], q[1], q[2]);
            let b = Vec3::new(q[3], q[4], q[5]);
            let c = Vec3::new(q[6], q[7], q[8]);
            let d = Vec3::new(q[9], q[10], q[11]);
            let t1 = Triangle::new(a, b, c);
            let t2 = Triangle::new(b, a, d);
            let target = a + (b - a) * f;
            let o = Vec3::new(ox, oy, oz);
            let dir = target - o;
            prop_assume!(dir.length() > 1e-3);
            // Only meaningful when c and d lie on opposite sides of the plane through o, a, b.
            let n = (a - o).cross(b - o);
            prop_assume!(n.dot(c - o) * n.dot(d - o) < 0.0);
            let r = ray(o, dir);
            let sh = RayShear::new(&r);
            let h1 = intersect(&r, &sh, &t1);
            let h2 = intersect(&r, &sh, &t2);
            // Degenerate (edge-on) projections are the one exception: nothing to hit.
            let area1 = (b - a).cross(c - a).length();
            let area2 = (a - b).cross(d - b).length();
            prop_assume!(area1 > 1e-3 && area2 > 1e-3);
            prop_assert!(h1.is_some() || h2.is_some(), "leak through shared edge");
        }
    }
}
