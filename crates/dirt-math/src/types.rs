//! `#[repr(C)]` Pod types shared with WGSL. Each is declared here once.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Primitive id of a miss.
pub const INVALID_ID: u32 = u32::MAX;

/// A ray segment `origin + t * dir` for `t` in `[tmin, tmax]`.
///
/// repr(C), Pod, 32 bytes; matches WGSL `struct Ray { origin: vec3<f32>, tmin: f32, dir: vec3<f32>, tmax: f32 }`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Ray {
    pub origin: [f32; 3],
    pub tmin: f32,
    pub dir: [f32; 3],
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Self {
            origin: origin.to_array(),
            tmin,
            dir: dir.to_array(),
            tmax,
        }
    }
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(self.origin)
    }
    pub fn dir(&self) -> Vec3 {
        Vec3::from_array(self.dir)
    }
    /// Point at parameter `t`, written out (no fused multiply-add).
    pub fn at(&self, t: f32) -> Vec3 {
        Vec3::new(
            self.origin[0] + t * self.dir[0],
            self.origin[1] + t * self.dir[1],
            self.origin[2] + t * self.dir[2],
        )
    }
    /// Why this ray cannot be traced, if it cannot: non-finite values, a zero
    /// direction, or an empty or negative parameter range. Every tracer
    /// (`dirt_cpu::trace`, brute force, `dirt_gpu::trace`) returns a miss for
    /// such a ray; the command line refuses the file, naming the row.
    pub fn validate(&self) -> Result<(), RayProblem> {
        if !self.origin.iter().all(|c| c.is_finite()) {
            return Err(RayProblem::NonFiniteOrigin);
        }
        if !self.dir.iter().all(|c| c.is_finite()) {
            return Err(RayProblem::NonFiniteDirection);
        }
        if self.dir == [0.0; 3] {
            return Err(RayProblem::ZeroDirection);
        }
        if self.tmin.is_nan() || self.tmax.is_nan() {
            return Err(RayProblem::NanRange);
        }
        if !(self.tmin >= 0.0) || self.tmin.is_infinite() {
            return Err(RayProblem::BadTmin);
        }
        if self.tmax < self.tmin {
            return Err(RayProblem::EmptyRange);
        }
        Ok(())
    }
}

/// What is wrong with a ray (see [`Ray::validate`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RayProblem {
    #[error("origin is not finite")]
    NonFiniteOrigin,
    #[error("direction is not finite")]
    NonFiniteDirection,
    #[error("direction is zero")]
    ZeroDirection,
    #[error("tmin or tmax is NaN")]
    NanRange,
    #[error("tmin must be finite and >= 0")]
    BadTmin,
    #[error("tmax < tmin")]
    EmptyRange,
}

/// The closest hit of a ray: primitive id, ray parameter and barycentrics
/// (`u` weights vertex 1, `v` weights vertex 2). `prim == INVALID_ID` is a miss.
///
/// repr(C), Pod, 16 bytes; matches WGSL `struct Hit { prim: u32, t: f32, u: f32, v: f32 }`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Hit {
    pub prim: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl Hit {
    pub const MISS: Hit = Hit {
        prim: INVALID_ID,
        t: f32::INFINITY,
        u: 0.0,
        v: 0.0,
    };

    pub fn is_hit(&self) -> bool {
        self.prim != INVALID_ID
    }

    /// The deterministic order of §2: smaller `t` first, then smaller primitive id.
    /// Keeping the minimum under this order makes the result independent of the
    /// order in which candidates are tested.
    pub fn closer_than(&self, other: &Hit) -> bool {
        self.t < other.t || (self.t == other.t && self.prim < other.prim)
    }

    /// Bitwise equality (`t`, `u`, `v` compared as bits).
    pub fn bits(&self) -> [u32; 4] {
        [
            self.prim,
            self.t.to_bits(),
            self.u.to_bits(),
            self.v.to_bits(),
        ]
    }
}

impl Default for Hit {
    fn default() -> Self {
        Self::MISS
    }
}

/// A world-space triangle in the flattened scene order.
///
/// repr(C), Pod, 36 bytes; stored in WGSL as 9 consecutive `f32` of an `array<f32>`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Triangle {
    pub v: [[f32; 3]; 3],
}

impl Triangle {
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        Self {
            v: [a.to_array(), b.to_array(), c.to_array()],
        }
    }
    pub fn vertex(&self, i: usize) -> Vec3 {
        Vec3::from_array(self.v[i])
    }
    pub fn is_finite(&self) -> bool {
        self.v.iter().flatten().all(|c| c.is_finite())
    }
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    /// Grows the box to hold `p`. Of two equal zeros the minimum is `-0.0` and
    /// the maximum `+0.0` (the order of [`crate::encode`]), so the bounds, and
    /// every view fitted to them, are the same on the GPU, which reduces them
    /// with atomic min/max of that encoding. NaN coordinates are ignored.
    pub fn grow(&mut self, p: Vec3) {
        self.take_in(p, p);
    }

    /// The smallest box holding both (of equal zeros as in [`Aabb::grow`]):
    /// in that order the union is associative and commutative, so bounds
    /// merged from parts in any grouping equal those grown point by point.
    pub fn union(&self, other: &Aabb) -> Aabb {
        let mut b = *self;
        b.take_in(other.min, other.max);
        b
    }

    /// `min` lowered to `lo`, `max` raised to `hi`, component-wise.
    fn take_in(&mut self, lo: Vec3, hi: Vec3) {
        let lower = |a: f32, b: f32| b < a || (b == a && b.is_sign_negative());
        let pick_min = |a: f32, b: f32| if lower(a, b) { b } else { a };
        let pick_max = |a: f32, b: f32| {
            if b > a || (b == a && a.is_sign_negative()) {
                b
            } else {
                a
            }
        };
        self.min = Vec3::new(
            pick_min(self.min.x, lo.x),
            pick_min(self.min.y, lo.y),
            pick_min(self.min.z, lo.z),
        );
        self.max = Vec3::new(
            pick_max(self.max.x, hi.x),
            pick_max(self.max.y, hi.y),
            pick_max(self.max.z, hi.z),
        );
    }
    /// The bounds of the triangles' vertices, bit for bit those grown vertex
    /// by vertex ([`Aabb::grow`]). Written as running minima and maxima over
    /// the coordinates taken twelve at a time (four vertices, three vector
    /// registers an extreme), folded per axis before anything borrows them:
    /// nine a triangle, or borrowed by the closures below, they stayed a
    /// scalar loop through memory (the deforming grid's 32,768 triangles:
    /// 175-209 -> 30 µs on one thread). A comparison with NaN is false, so
    /// NaN is ignored as `grow` ignores it; the extremes of a set do not
    /// depend on the order they are taken in; and the sign of a zero bound,
    /// which the comparisons leave to that order, is set afterwards as
    /// `grow` orders zeros.
    pub fn of_triangles(tris: &[Triangle]) -> Aabb {
        const W: usize = 12;
        let flat: &[f32] = bytemuck::cast_slice(tris);
        let mut lo = [f32::INFINITY; W];
        let mut hi = [f32::NEG_INFINITY; W];
        let mut chunks = flat.chunks_exact(W);
        for c in &mut chunks {
            for k in 0..W {
                lo[k] = if c[k] < lo[k] { c[k] } else { lo[k] };
                hi[k] = if c[k] > hi[k] { c[k] } else { hi[k] };
            }
        }
        // Lane `k` holds coordinates of axis `k % 3` (W is a multiple of 3).
        for (k, &x) in chunks.remainder().iter().enumerate() {
            lo[k] = if x < lo[k] { x } else { lo[k] };
            hi[k] = if x > hi[k] { x } else { hi[k] };
        }
        // Folded into plain values before any closure borrows them: borrowed,
        // the running extremes were kept in memory through the loop.
        let (mut mins, mut maxs) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for k in 0..W {
            mins[k % 3] = mins[k % 3].min(lo[k]);
            maxs[k % 3] = maxs[k % 3].max(hi[k]);
        }
        let axis = |a: usize| {
            let (min, max) = (mins[a], maxs[a]);
            // Of equal zeros the minimum is -0.0 and the maximum +0.0 where
            // the vertices hold one (rare: only a bound at exactly zero looks).
            let any = |bits: u32| {
                tris.iter()
                    .any(|t| t.v.iter().any(|p| p[a].to_bits() == bits))
            };
            let min = if min == 0.0 {
                if any((-0.0f32).to_bits()) { -0.0 } else { 0.0 }
            } else {
                min
            };
            let max = if max == 0.0 {
                if any(0.0f32.to_bits()) { 0.0 } else { -0.0 }
            } else {
                max
            };
            (min, max)
        };
        let (x, y, z) = (axis(0), axis(1), axis(2));
        Aabb {
            min: Vec3::new(x.0, y.0, z.0),
            max: Vec3::new(x.1, y.1, z.1),
        }
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
}

/// One view as the GPU passes read it (see [`crate::View`]), with the cube's
/// adjacency (`adjacency[edge]` = the face across that edge; unused for a single view).
///
/// repr(C), Pod, 112 bytes; matches WGSL `struct View` in `shaders/wgsl/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ViewGpu {
    pub apex: [f32; 3],
    pub tan: f32,
    pub right: [f32; 3],
    pub near: f32,
    pub up: [f32; 3],
    pub far: f32,
    pub forward: [f32; 3],
    pub eps: f32,
    pub tiles: u32,
    pub step: f32,
    pub scale: f32,
    /// [`crate::View::slot`]: the view's block in the per-tile buffers, or
    /// [`crate::view::NO_SLOT`] for a view without content.
    pub slot: u32,
    pub adjacency: [u32; 4],
    /// [`crate::View::ortho`] as 0 or 1.
    pub ortho: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl ViewGpu {
    pub fn new(v: &crate::View, adjacency: [u32; 4]) -> Self {
        Self {
            apex: v.apex.to_array(),
            tan: v.tan,
            right: v.right.to_array(),
            near: v.near,
            up: v.up.to_array(),
            far: v.far,
            forward: v.forward.to_array(),
            eps: v.eps,
            tiles: v.tiles,
            step: v.step,
            scale: v.scale,
            slot: v.slot,
            adjacency,
            ortho: v.ortho as u32,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }
}

/// Per-ray traversal statistics, as both backends count them.
///
/// repr(C), Pod, 16 bytes; matches WGSL `struct RayStats`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RayStats {
    /// Views whose part of the ray was walked.
    pub views: u32,
    /// Tiles entered.
    pub tiles: u32,
    /// Bucket lists scanned.
    pub buckets: u32,
    /// Ray/triangle tests.
    pub tests: u32,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f32> {
        prop_oneof![Just(0.0f32), Just(-0.0f32), -3.0f32..3.0]
    }

    fn wild() -> impl Strategy<Value = f32> {
        prop_oneof![
            Just(0.0f32),
            Just(-0.0f32),
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            -3.0f32..3.0
        ]
    }

    proptest! {
        // The side-by-side bounds of triangles equal those grown vertex by
        // vertex, to the bit: signed zeros, NaN and infinities included.
        #[test]
        fn bounds_of_triangles_equal_grown_bounds(
            tris in prop::collection::vec(prop::array::uniform9(wild()), 0..30),
        ) {
            let tris: Vec<Triangle> = tris
                .into_iter()
                .map(|c| Triangle { v: [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]] })
                .collect();
            let mut grown = Aabb::EMPTY;
            for t in &tris {
                for i in 0..3 {
                    grown.grow(t.vertex(i));
                }
            }
            let bits = |b: Aabb| (b.min.to_array().map(f32::to_bits), b.max.to_array().map(f32::to_bits));
            prop_assert_eq!(bits(Aabb::of_triangles(&tris)), bits(grown));
        }

        // Bounds merged from parts, in any split and order, equal the bounds
        // grown point by point, to the bit (signed zeros included).
        #[test]
        fn union_of_parts_equals_grown_bounds(
            pts in prop::collection::vec((coord(), coord(), coord()), 0..40),
            cut in 0usize..41,
        ) {
            let pts: Vec<Vec3> = pts.into_iter().map(|(x, y, z)| Vec3::new(x, y, z)).collect();
            let cut = cut.min(pts.len());
            let grow = |ps: &[Vec3]| {
                let mut b = Aabb::EMPTY;
                for &p in ps {
                    b.grow(p);
                }
                b
            };
            let bits = |b: Aabb| (b.min.to_array().map(f32::to_bits), b.max.to_array().map(f32::to_bits));
            let whole = bits(grow(&pts));
            let (a, b) = (grow(&pts[..cut]), grow(&pts[cut..]));
            prop_assert_eq!(bits(a.union(&b)), whole);
            prop_assert_eq!(bits(b.union(&a)), whole);
            prop_assert_eq!(bits(Aabb::EMPTY.union(&a).union(&b)), whole);
        }
    }
}
