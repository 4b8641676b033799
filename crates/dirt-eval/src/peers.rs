//! Peers measured in the same run on the same triangles and rays: `obvhs`
//! (a compressed wide BVH, CWBVH), with the `embree` feature Embree 3, and
//! the compact uniform grid of seed 002 (`dirt_cpu::grid`, an exact baseline
//! that shares DIRT's triangle test, so its hits are held to every bit).
//! Each is a [`Tracer`], measured by [`crate::measure`] like DIRT.
//!
//! **Adding a tracer to the evaluation**: implement [`Tracer`] for it and add
//! its one line to [`available`]. The harness then builds and traces it on
//! every scene and ray type, and on every frame of the dynamic scene, beside
//! DIRT and against brute force.
//!
//! Each peer uses its own triangle test, as it would in an application. Their
//! hits are reported as [`Hit`]s with the primitive id in the scene's order
//! and `t`; `u` and `v` are left 0, since the error is counted on `prim`
//! and `t` (see [`crate::Match::PEER`]).
//!
//! Threads: the obvhs build is single-threaded (the crate's `parallel`
//! feature is off); traces of both peers run over rayon's pool, as DIRT's do.

use std::time::Duration;

use dirt_core::{
    BuildReport, CoreError, Hit, Ray, RayStats, TraceReport, Tracer, Triangle, trace_each,
};

/// A peer of the evaluation: its name and how to make it.
#[derive(Clone, Copy, Debug)]
pub struct Peer {
    /// The name of its rows (`backend`).
    pub name: &'static str,
    /// A tracer, not yet built, given the harness's thread count. An error
    /// (a library that cannot start) is noted and the peer skipped.
    pub make: fn(threads: usize) -> Result<Box<dyn Tracer>, CoreError>,
    /// Whether it uses DIRT's triangle test: its hits are then compared bit
    /// for bit ([`crate::Match::Bits`]), else within [`crate::Match::PEER`].
    pub exact: bool,
}

impl Peer {
    /// How its hits are compared with brute force's.
    pub fn how(&self) -> crate::Match {
        if self.exact {
            crate::Match::Bits
        } else {
            crate::Match::PEER
        }
    }
}

/// The grid's name in the rows: its density is the paper's.
pub const GRID: &str = "grid ρ4";

/// The name of the grid's rows at `density` cells per triangle ([`GRID`] at the default).
pub fn grid_name(density: f32) -> String {
    format!("grid ρ{density}")
}

/// The peers this build has, one line each (Embree only with the `embree` feature).
pub fn available() -> Vec<Peer> {
    vec![
        Peer {
            name: "obvhs",
            make: |_| Ok(Box::new(Obvhs::default())),
            exact: false,
        },
        #[cfg(feature = "embree")]
        Peer {
            name: "embree",
            make: |threads| Ok(Box::new(embree::Embree::new(threads)?)),
            exact: false,
        },
        Peer {
            name: GRID,
            make: |_| {
                Ok(Box::new(dirt_cpu::grid::Grid::new(
                    dirt_cpu::grid::DEFAULT_DENSITY,
                )?))
            },
            exact: true,
        },
    ]
}

/// Whether a peer's error says its library could not do the work (the
/// harness notes it and skips the peer) rather than that the input was bad.
pub fn unavailable(e: &CoreError) -> bool {
    matches!(e, CoreError::Backend { .. })
}

/// The structure of a peer's last build; tracing before any build is an error.
fn built<'a, T>(structure: &'a Option<T>, tracer: &str) -> Result<&'a T, CoreError> {
    structure.as_ref().ok_or_else(|| CoreError::NotBuilt {
        tracer: tracer.to_string(),
    })
}

/// obvhs's CWBVH with its own triangles.
#[derive(Default)]
pub struct Obvhs {
    bvh: Option<obvhs::cwbvh::CwBvh>,
    tris: Vec<obvhs::triangle::Triangle>,
}

impl std::fmt::Debug for Obvhs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Obvhs")
            .field("nodes", &self.bvh.as_ref().map(|b| b.nodes.len()))
            .finish()
    }
}

impl Obvhs {
    fn trace_ray(bvh: &obvhs::cwbvh::CwBvh, tris: &[obvhs::triangle::Triangle], r: &Ray) -> Hit {
        if r.validate().is_err() || tris.is_empty() {
            return Hit::MISS;
        }
        let o = bytemuck::cast([r.origin[0], r.origin[1], r.origin[2], 0.0f32]);
        let d = bytemuck::cast([r.dir[0], r.dir[1], r.dir[2], 0.0f32]);
        let ray = obvhs::ray::Ray::new(o, d, r.tmin, r.tmax);
        let mut hit = obvhs::ray::RayHit::none();
        // obvhs ids are BVH-order indices: map through `primitive_indices`.
        let found = bvh.ray_traverse(ray, &mut hit, |ray, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(ray)
        });
        if found {
            Hit {
                prim: bvh.primitive_indices[hit.primitive_id as usize],
                t: hit.t,
                u: 0.0,
                v: 0.0,
            }
        } else {
            Hit::MISS
        }
    }
}

impl Tracer for Obvhs {
    fn name(&self) -> String {
        "obvhs".to_string()
    }

    /// A CWBVH with obvhs's `fast_build` preset (the preset meant for
    /// structures rebuilt every frame).
    fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
        self.tris = tris
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
            &self.tris,
            obvhs::BvhBuildParams::fast_build(),
            &mut Duration::default(),
        );
        let memory = (bvh.nodes.len() * std::mem::size_of::<obvhs::cwbvh::node::CwBvhNode>()
            + bvh.primitive_indices.len() * 4) as u64;
        self.bvh = Some(bvh);
        Ok(BuildReport {
            stages: Vec::new(),
            memory: Some(memory),
        })
    }

    fn trace_into(
        &mut self,
        rays: &[Ray],
        hits: &mut [Hit],
        stats: Option<&mut [RayStats]>,
    ) -> Result<TraceReport, CoreError> {
        let bvh = built(&self.bvh, "obvhs")?;
        let tris = &self.tris;
        trace_each(rays, hits, stats.as_deref(), |r| {
            Obvhs::trace_ray(bvh, tris, r)
        })
    }
}

#[cfg(feature = "embree")]
pub mod embree {
    //! Embree 3 through the `embree3` crate: one triangle geometry, single-ray
    //! `intersect` calls from rayon's pool (the crate's 16-wide packets need a
    //! 64-byte aligned mask; single rays avoid that).

    use super::*;
    use dirt_core::check_lengths;
    use embree3::{BufferUsage, Config, Device, Format, GeometryKind, IntersectContext, RayHit};
    use rayon::prelude::*;

    /// An Embree device and the scene of its last build.
    pub struct Embree {
        device: Device,
        scene: Option<embree3::Scene<'static>>,
    }

    impl std::fmt::Debug for Embree {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("Embree")
        }
    }

    /// What Embree refused, with its error code.
    fn err(what: &str, e: impl std::fmt::Debug) -> CoreError {
        CoreError::backend("embree", crate::EvalError::Peer(format!("{what}: {e:?}")))
    }

    impl Embree {
        /// A device building on `threads` threads; call [`Tracer::build`] before tracing.
        pub fn new(threads: usize) -> Result<Embree, CoreError> {
            let device = Device::with_config(Config {
                threads: threads as u32,
                ..Config::default()
            })
            .map_err(|e| err("cannot create a device", e))?;
            Ok(Embree {
                device,
                scene: None,
            })
        }
    }

    impl Tracer for Embree {
        fn name(&self) -> String {
            "embree".to_string()
        }

        /// One triangle geometry over `tris`, committed with the default build quality.
        fn build(&mut self, tris: &[Triangle]) -> Result<BuildReport, CoreError> {
            self.scene = None;
            let mut scene = self
                .device
                .create_scene()
                .map_err(|e| err("cannot create a scene", e))?;
            let n = tris.len();
            let mut geom = self
                .device
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
            self.scene = Some(scene);
            Ok(BuildReport::default())
        }

        fn trace_into(
            &mut self,
            rays: &[Ray],
            hits: &mut [Hit],
            stats: Option<&mut [RayStats]>,
        ) -> Result<TraceReport, CoreError> {
            check_lengths(rays, hits, stats.as_deref())?;
            let scene = built(&self.scene, "embree")?;
            rays.par_iter().zip(hits.par_iter_mut()).for_each_init(
                IntersectContext::incoherent,
                |ctx, (r, h)| {
                    *h = if r.validate().is_err() {
                        Hit::MISS
                    } else {
                        let mut rh = RayHit::from_ray(embree3::Ray::segment(
                            r.origin, r.dir, r.tmin, r.tmax,
                        ));
                        scene.intersect(ctx, &mut rh);
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
                    };
                },
            );
            Ok(TraceReport::default())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dirt_math::Vec3;

    #[test]
    fn peers_are_tracers_with_the_scene_order_of_primitives() {
        let tris: Vec<Triangle> = (0..8)
            .map(|k| {
                let z = 8.0 - k as f32;
                Triangle::new(
                    Vec3::new(-1.0, -1.0, z),
                    Vec3::new(1.0, -1.0, z),
                    Vec3::new(0.0, 1.0, z),
                )
            })
            .collect();
        let rays = [
            Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 0.0, f32::INFINITY),
            Ray::new(Vec3::new(5.0, 0.0, -1.0), Vec3::Z, 0.0, f32::INFINITY),
        ];
        let truth = dirt_cpu::brute_force::trace(&tris, &rays);
        for peer in available() {
            let mut t = (peer.make)(1).expect("peer starts");
            assert_eq!(t.name(), peer.name);
            assert!(matches!(t.trace(&rays), Err(CoreError::NotBuilt { .. })));
            t.build(&tris).expect("peer builds");
            let hits = t.trace(&rays).expect("peer traces");
            assert_eq!(
                crate::compare(&hits, &truth, peer.how()).differ,
                0,
                "{}: {hits:?}",
                peer.name
            );
            assert_eq!(hits[0].prim, 7);
        }
    }
}
