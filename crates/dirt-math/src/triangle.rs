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
        let d = ray.dir;
        let ax = d[0].abs();
        let ay = d[1].abs();
        let az = d[2].abs();
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
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        }
    }
}

/// Intersects `ray` with `tri`. Returns `(t, u, v)` with `t` in `[tmin, tmax]`,
/// `u` the weight of vertex 1 and `v` of vertex 2, or `None`.
/// Degenerate triangles (zero sheared area) are never hit. Back faces are hit.
#[inline]
pub fn intersect(ray: &Ray, sh: &RayShear, tri: &Triangle) -> Option<(f32, f32, f32)> {
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
    // Scaled barycentrics (edge functions).
    let e0 = cx * by - cy * bx;
    let e1 = ax * cy - ay * cx;
    let e2 = bx * ay - by * ax;
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 || det.is_nan() {
        return None;
    }
    let az = sh.sz * a[kz];
    let bz = sh.sz * b[kz];
    let cz = sh.sz * c[kz];
    let tt = e0 * az + e1 * bz + e2 * cz;
    let t = tt / det;
    if !(t >= ray.tmin && t <= ray.tmax) {
        return None;
    }
    Some((t, e1 / det, e2 / det))
}

/// Tests `tri` (id `prim`) and keeps it in `best` if it is closer under the
/// deterministic order of §2 (smaller `t`, then smaller id).
#[inline]
pub fn intersect_closest(ray: &Ray, sh: &RayShear, tri: &Triangle, prim: u32, best: &mut Hit) {
    if let Some((t, u, v)) = intersect(ray, sh, tri) {
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

    proptest! {
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
