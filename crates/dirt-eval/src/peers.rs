//! Peers measured in the same run on the same triangles and rays: `obvhs`
//! (a compressed wide BVH, CWBVH) and, with the `embree` feature, Embree 3.
//!
//! Each peer uses its own triangle test, as it would in an application. Their
//! hits are reported as [`Hit`]s with the primitive id in the scene's order
//! and `t`; `u` and `v` are left 0, since the error is counted on `prim`
//! and `t` (see [`crate::compare`]).
//!
//! Threads: the obvhs build is single-threaded (the crate's `parallel`
//! feature is off); traces of both peers run over rayon's pool, as DIRT's do.

use std::time::{Duration, Instant};

use dirt_math::{Hit, Ray, Triangle};
use rayon::prelude::*;

use crate::EvalError;

/// A built peer structure.
pub trait Peer: Sync {
    /// Trace `rays`, closest hits in the scene's primitive order.
    fn trace(&self, rays: &[Ray]) -> Vec<Hit>;
    /// Bytes of the structure, where the peer says.
    fn memory(&self) -> Option<u64>;
}

/// Which peer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeerKind {
    Obvhs,
    Embree,
}

impl PeerKind {
    pub fn name(self) -> &'static str {
        match self {
            PeerKind::Obvhs => "obvhs",
            PeerKind::Embree => "embree",
        }
    }

    /// The peers this build has (Embree only with the `embree` feature).
    pub fn available() -> Vec<PeerKind> {
        let mut v = vec![PeerKind::Obvhs];
        if cfg!(feature = "embree") {
            v.push(PeerKind::Embree);
        }
        v
    }

    /// Builds the peer's structure over `tris`; returns it and the build's wall time.
    pub fn build(
        self,
        tris: &[Triangle],
        threads: usize,
    ) -> Result<(Box<dyn Peer>, Duration), EvalError> {
        match self {
            PeerKind::Obvhs => {
                let start = Instant::now();
                let p = Obvhs::build(tris);
                Ok((Box::new(p), start.elapsed()))
            }
            PeerKind::Embree => embree_build(tris, threads),
        }
    }
}

/// obvhs's CWBVH with its own triangles.
pub struct Obvhs {
    bvh: obvhs::cwbvh::CwBvh,
    tris: Vec<obvhs::triangle::Triangle>,
}

impl std::fmt::Debug for Obvhs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Obvhs")
            .field("nodes", &self.bvh.nodes.len())
            .finish()
    }
}

impl Obvhs {
    /// Builds a CWBVH with obvhs's `fast_build` preset (the preset meant for
    /// structures rebuilt every frame).
    pub fn build(tris: &[Triangle]) -> Obvhs {
        let tris: Vec<obvhs::triangle::Triangle> = tris
            .iter()
            .map(|t| {
                let v = |i: usize| {
                    let p = t.vertex(i);
                    bytemuck::cast([p.x, p.y, p.z, 0.0f32])
                };
                obvhs::triangle::Triangle {
                    v0: v(0),
                    v1: v(1),
                    v2: v(2),
                }
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        Obvhs { bvh, tris }
    }

    fn trace_ray(&self, r: &Ray) -> Hit {
        if r.validate().is_err() || self.tris.is_empty() {
            return Hit::MISS;
        }
        let o = bytemuck::cast([r.origin[0], r.origin[1], r.origin[2], 0.0f32]);
        let d = bytemuck::cast([r.dir[0], r.dir[1], r.dir[2], 0.0f32]);
        let ray = obvhs::ray::Ray::new(o, d, r.tmin, r.tmax);
        let mut hit = obvhs::ray::RayHit::none();
        // obvhs ids are BVH-order indices: map through `primitive_indices`.
        let found = self.bvh.ray_traverse(ray, &mut hit, |ray, id| {
            self.tris[self.bvh.primitive_indices[id] as usize].intersect(ray)
        });
        if found {
            Hit {
                prim: self.bvh.primitive_indices[hit.primitive_id as usize],
                t: hit.t,
                u: 0.0,
                v: 0.0,
            }
        } else {
            Hit::MISS
        }
    }
}

impl Peer for Obvhs {
    fn trace(&self, rays: &[Ray]) -> Vec<Hit> {
        rays.par_iter().map(|r| self.trace_ray(r)).collect()
    }

    fn memory(&self) -> Option<u64> {
        Some(
            (self.bvh.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
                + self.bvh.primitive_indices.len() * 4) as u64,
        )
    }
}

#[cfg(not(feature = "embree"))]
fn embree_build(_: &[Triangle], _: usize) -> Result<(Box<dyn Peer>, Duration), EvalError> {
    Err(EvalError::PeerUnavailable(
        "embree: this build has no Embree (build with `--features embree`, needs libembree-dev)"
            .into(),
    ))
}

#[cfg(feature = "embree")]
fn embree_build(tris: &[Triangle], threads: usize) -> Result<(Box<dyn Peer>, Duration), EvalError> {
    let e = embree::Embree::device(threads)?;
    let start = Instant::now();
    let scene = embree::Embree::build(e, tris)?;
    Ok((Box::new(scene), start.elapsed()))
}

#[cfg(feature = "embree")]
pub mod embree {
    //! Embree 3 through the `embree3` crate: one triangle geometry, single-ray
    //! `intersect` calls from rayon's pool (the crate's 16-wide packets need a
    //! 64-byte aligned mask; single rays avoid that).

    use super::*;
    use embree3::{BufferUsage, Config, Device, Format, GeometryKind, IntersectContext, RayHit};

    /// A committed Embree scene.
    pub struct Embree {
        scene: embree3::Scene<'static>,
    }

    impl std::fmt::Debug for Embree {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("Embree")
        }
    }

    fn err(what: &str, e: impl std::fmt::Debug) -> EvalError {
        EvalError::PeerUnavailable(format!("embree: {what}: {e:?}"))
    }

    impl Embree {
        /// A device building on `threads` threads.
        pub fn device(threads: usize) -> Result<Device, EvalError> {
            Device::with_config(Config {
                threads: threads as u32,
                ..Config::default()
            })
            .map_err(|e| err("cannot create a device", e))
        }

        /// Builds a scene over `tris` on `device`.
        pub fn build(device: Device, tris: &[Triangle]) -> Result<Embree, EvalError> {
            let mut scene = device
                .create_scene()
                .map_err(|e| err("cannot create a scene", e))?;
            let n = tris.len();
            let mut geom = device
                .create_geometry(GeometryKind::TRIANGLE)
                .map_err(|e| err("cannot create a geometry", e))?;
            {
                let mut verts = geom
                    .set_new_buffer::<[f32; 3]>(BufferUsage::VERTEX, 0, Format::FLOAT3, 12, 3 * n)
                    .map_err(|e| err("vertex buffer", e))?;
                for (i, t) in tris.iter().enumerate() {
                    for k in 0..3 {
                        verts[3 * i + k] = t.vertex(k).to_array();
                    }
                }
            }
            {
                let mut idx = geom
                    .set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, n)
                    .map_err(|e| err("index buffer", e))?;
                for (i, slot) in idx.iter_mut().enumerate() {
                    let b = 3 * i as u32;
                    *slot = [b, b + 1, b + 2];
                }
            }
            let geom = geom.commit();
            scene.attach_geometry(&geom);
            scene.commit();
            Ok(Embree { scene })
        }
    }

    impl Peer for Embree {
        fn trace(&self, rays: &[Ray]) -> Vec<Hit> {
            rays.par_iter()
                .map_init(IntersectContext::incoherent, |ctx, r| {
                    if r.validate().is_err() {
                        return Hit::MISS;
                    }
                    let mut rh =
                        RayHit::from_ray(embree3::Ray::segment(r.origin, r.dir, r.tmin, r.tmax));
                    self.scene.intersect(ctx, &mut rh);
                    if rh.hit.is_valid() {
                        Hit {
                            prim: rh.hit.primID,
                            t: rh.ray.tfar,
                            u: 0.0,
                            v: 0.0,
                        }
                    } else {
                        Hit::MISS
                    }
                })
                .collect()
        }

        fn memory(&self) -> Option<u64> {
            None
        }
    }
}
