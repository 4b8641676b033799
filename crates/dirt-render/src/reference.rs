//! The reference tracer: an obvhs BVH2 (PLOC build) proposes candidates, and
//! `dirt_math`'s watertight test with [`Hit::closer_than`] picks the closest,
//! so its hits are brute force's bit for bit.
//!
//! obvhs's own traversal prunes with `t < tmax` in its own float arithmetic,
//! which could drop a node holding a hit at exactly the best `t` with a
//! smaller id, or a hit whose rounded `t` lies a little outside a tight box.
//! So the walk here is ours and conservative: boxes are dilated by far more
//! than the test's error bound, and a node is pruned only when its entry
//! distance is strictly beyond the best `t` (or its exit before `tmin`).

use dirt_math::triangle::{RayShear, intersect_closest};
use dirt_math::{Hit, Ray, Triangle};
use glam_obvhs::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb as ObvhsAabb;
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;

/// A node of the walk: box, and either children (`count == 0`) or a range
/// of `prims`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: [f32; 3],
    max: [f32; 3],
    count: u32,
    first: u32,
}

/// The obvhs BVH over a scene's triangles.
pub struct Reference {
    tris: Vec<Triangle>,
    nodes: Vec<Node>,
    prims: Vec<u32>,
    /// Largest absolute vertex coordinate: the scale of the dilation.
    scale: f32,
}

impl std::fmt::Debug for Reference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reference")
            .field("triangles", &self.tris.len())
            .field("nodes", &self.nodes.len())
            .finish()
    }
}

impl Reference {
    /// Builds the BVH (obvhs `build_bvh2`, medium quality).
    pub fn new(tris: &[Triangle]) -> Self {
        let scale = tris
            .iter()
            .flat_map(|t| t.v.iter().flatten())
            .fold(0.0f32, |m, c| m.max(c.abs()));
        if tris.is_empty() {
            return Self {
                tris: Vec::new(),
                nodes: Vec::new(),
                prims: Vec::new(),
                scale,
            };
        }
        let boxes: Vec<ObvhsAabb> = tris
            .iter()
            .map(|t| {
                let a = Vec3A::from_array(t.v[0]);
                let b = Vec3A::from_array(t.v[1]);
                let c = Vec3A::from_array(t.v[2]);
                ObvhsAabb::new(a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let mut build_time = std::time::Duration::ZERO;
        let bvh: Bvh2 = obvhs::bvh2::builder::build_bvh2(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut build_time,
        );
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| Node {
                min: n.aabb.min.to_array(),
                max: n.aabb.max.to_array(),
                count: n.prim_count,
                first: n.first_index,
            })
            .collect();
        Self {
            tris: tris.to_vec(),
            nodes,
            prims: bvh.primitive_indices.clone(),
            scale,
        }
    }

    /// Closest hits of `rays` into `hits` (in parallel, one per ray). Rays
    /// that fail [`Ray::validate`] miss, as in brute force.
    pub fn trace_to(&self, rays: &[Ray], hits: &mut [Hit]) {
        rays.par_iter()
            .zip(hits.par_iter_mut())
            .for_each(|(r, h)| *h = self.trace_ray(r));
    }

    /// Bytes of the walk's nodes and primitive indices.
    pub fn memory_bytes(&self) -> u64 {
        (std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.prims.as_slice())) as u64
    }

    /// The closest hit of one ray.
    pub fn trace_ray(&self, ray: &Ray) -> Hit {
        let mut best = Hit::MISS;
        if self.nodes.is_empty() || ray.validate().is_err() {
            return best;
        }
        let sh = RayShear::new(ray);
        let o = ray.origin;
        let d = ray.dir;
        // Far above the triangle test's bound on the hit point's error
        // (2^-15 of the vertex distance) and the rounding of the slab test.
        let omax = o[0].abs().max(o[1].abs()).max(o[2].abs());
        let delta = (omax + self.scale) * (1.0 / 1024.0) + f32::MIN_POSITIVE;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = self.nodes[i as usize];
            let Some(entry) = self.enter(&node, o, d, delta, ray.tmin, ray.tmax) else {
                continue;
            };
            // Strict: a node entered at exactly the best t may still hold a
            // hit at that t with a smaller id.
            if entry > best.t {
                continue;
            }
            if node.count > 0 {
                for k in node.first..node.first + node.count {
                    let prim = self.prims[k as usize];
                    intersect_closest(ray, &sh, &self.tris[prim as usize], prim, &mut best);
                }
            } else {
                let (a, b) = (node.first, node.first + 1);
                let ea = self.enter(&self.nodes[a as usize], o, d, delta, ray.tmin, ray.tmax);
                let eb = self.enter(&self.nodes[b as usize], o, d, delta, ray.tmin, ray.tmax);
                // Push the farther child first so the nearer is walked first.
                match (ea, eb) {
                    (Some(x), Some(y)) if x <= y => {
                        stack.push(b);
                        stack.push(a);
                    }
                    (Some(_), Some(_)) => {
                        stack.push(a);
                        stack.push(b);
                    }
                    (Some(_), None) => stack.push(a),
                    (None, Some(_)) => stack.push(b),
                    (None, None) => {}
                }
            }
        }
        best
    }

    /// The parameter at which the ray enters the node's box dilated by
    /// `delta`, or `None` when it misses the box within `[tmin, tmax]`.
    fn enter(
        &self,
        n: &Node,
        o: [f32; 3],
        d: [f32; 3],
        delta: f32,
        tmin: f32,
        tmax: f32,
    ) -> Option<f32> {
        let mut lo = f32::NEG_INFINITY;
        let mut hi = f32::INFINITY;
        for k in 0..3 {
            let bmin = n.min[k] - delta;
            let bmax = n.max[k] + delta;
            if d[k] == 0.0 {
                if o[k] < bmin || o[k] > bmax {
                    return None;
                }
                continue;
            }
            let t0 = (bmin - o[k]) / d[k];
            let t1 = (bmax - o[k]) / d[k];
            lo = lo.max(t0.min(t1));
            hi = hi.min(t0.max(t1));
        }
        if lo > hi || hi < tmin || lo > tmax {
            return None;
        }
        Some(lo.max(tmin))
    }
}
