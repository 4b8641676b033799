//! Rebuild the structure only when what it depends on changed.
//!
//! The structure depends on the triangles and the build parameters, and on
//! nothing else (not on the camera or the rays). A [`BuildCache`] keeps the
//! last structure with a key of those two and rebuilds only when the key
//! changes. The geometry part of the key is either a caller's generation
//! counter ([`Geometry::Generation`], free) or a hash of the triangles' bytes
//! ([`Geometry::Hash`], one pass over them). Both backends use it: the value
//! is any structure (`Ads`, or `dirt_gpu::GpuAds`).

use dirt_core::AdsParams;
use dirt_math::Triangle;
use std::hash::{Hash, Hasher};

/// How a [`BuildCache`] tells that geometry changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Geometry {
    /// The caller's counter: it changes whenever any vertex changed.
    Generation(u64),
    /// Hash the triangles' bytes (costs one pass; needs no bookkeeping).
    Hash,
}

/// Key of a built structure.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    geometry: GeometryKey,
    params: AdsParams,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum GeometryKey {
    Generation(u64),
    /// Hash and triangle count (the count guards the hash a little more).
    Hash(u64, usize),
}

/// Hash of the triangles' bytes (positive zero and negative zero differ,
/// as they can change a hit's bits).
pub fn geometry_hash(tris: &[Triangle]) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    // Triangle is Pod: its bytes are its value.
    let bytes: &[u8] = bytemuck::cast_slice(tris);
    bytes.hash(&mut h);
    h.finish()
}

/// What [`BuildCache::get`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reuse {
    /// Built now (first use, or geometry or parameters changed).
    Built,
    /// The structure of a previous call was still valid.
    Reused,
}

/// The last structure built, kept until geometry or parameters change.
#[derive(Debug)]
pub struct BuildCache<T> {
    entry: Option<(Key, T)>,
    /// Builds so far.
    pub builds: u64,
    /// Calls answered without building.
    pub reuses: u64,
}

impl<T> Default for BuildCache<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> BuildCache<T> {
    pub fn new() -> Self {
        Self {
            entry: None,
            builds: 0,
            reuses: 0,
        }
    }

    /// The structure for `tris` and `params`: the cached one when geometry
    /// and parameters are unchanged, else the result of `build` (kept).
    pub fn get<E>(
        &mut self,
        tris: &[Triangle],
        geometry: Geometry,
        params: &AdsParams,
        build: impl FnOnce() -> Result<T, E>,
    ) -> Result<(&T, Reuse), E> {
        let key = Key {
            geometry: match geometry {
                Geometry::Generation(g) => GeometryKey::Generation(g),
                Geometry::Hash => GeometryKey::Hash(geometry_hash(tris), tris.len()),
            },
            params: *params,
        };
        let (entry, reuse) = match self.entry.take() {
            Some((k, v)) if k == key => {
                self.reuses += 1;
                ((k, v), Reuse::Reused)
            }
            // A failed build leaves the cache empty (taken above).
            _ => {
                let v = build()?;
                self.builds += 1;
                ((key, v), Reuse::Built)
            }
        };
        let (_, v) = self.entry.insert(entry);
        Ok((v, reuse))
    }

    /// Drops the cached structure (the next `get` builds).
    pub fn clear(&mut self) {
        self.entry = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ads;
    use dirt_math::Vec3;

    fn tri(z: f32) -> Triangle {
        Triangle::new(Vec3::new(0.0, 0.0, z), Vec3::X, Vec3::Y)
    }

    #[test]
    fn rebuilds_only_when_geometry_or_params_change() {
        let mut cache = BuildCache::new();
        let p = AdsParams {
            resolution: 16,
            ..AdsParams::default()
        };
        let mut tris = vec![tri(0.5), tri(-0.5)];
        let build = |t: &[Triangle], p: &AdsParams| Ads::build(t, p);
        let (_, r) = cache
            .get(&tris, Geometry::Hash, &p, || build(&tris, &p))
            .expect("build");
        assert_eq!(r, Reuse::Built);
        // Same geometry, same parameters (a camera-only change): reused.
        let (_, r) = cache
            .get(&tris, Geometry::Hash, &p, || build(&tris, &p))
            .expect("build");
        assert_eq!(r, Reuse::Reused);
        // One coordinate moved: rebuilt, and the new structure sees the new triangle.
        tris[1].v[2][0] = 0.25;
        let (ads, r) = cache
            .get(&tris, Geometry::Hash, &p, || build(&tris, &p))
            .expect("build");
        assert_eq!(r, Reuse::Built);
        assert_eq!(ads.triangles, 2);
        // A parameter changed: rebuilt.
        let q = AdsParams { buckets: 2, ..p };
        let (ads, r) = cache
            .get(&tris, Geometry::Hash, &q, || build(&tris, &q))
            .expect("build");
        assert_eq!((r, ads.params.buckets), (Reuse::Built, 2));
        // Generation counters: equal generation reuses, a new one rebuilds.
        let (_, r) = cache
            .get(&tris, Geometry::Generation(7), &q, || build(&tris, &q))
            .expect("build");
        assert_eq!(r, Reuse::Built);
        let (_, r) = cache
            .get(&tris, Geometry::Generation(7), &q, || build(&tris, &q))
            .expect("build");
        assert_eq!(r, Reuse::Reused);
        assert_eq!((cache.builds, cache.reuses), (4, 2));
    }

    #[test]
    fn a_failed_build_is_not_cached() {
        let mut cache: BuildCache<Ads> = BuildCache::new();
        let tris = vec![tri(0.0)];
        let bad = AdsParams {
            resolution: 0,
            ..AdsParams::default()
        };
        assert!(
            cache
                .get(&tris, Geometry::Hash, &bad, || Ads::build(&tris, &bad))
                .is_err()
        );
        let good = AdsParams::default();
        let (_, r) = cache
            .get(&tris, Geometry::Hash, &good, || Ads::build(&tris, &good))
            .expect("build");
        assert_eq!(r, Reuse::Built);
    }

    #[test]
    fn negative_zero_is_a_change() {
        let a = [tri(0.0)];
        let b = [tri(-0.0)];
        assert_ne!(geometry_hash(&a), geometry_hash(&b));
    }
}
