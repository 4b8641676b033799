//! The plain `trace` stage (`trace::trace_ray_plain`, the loops `trace.wgsl`
//! mirrors) and the fast path behind `dirt_cpu::trace`, side by side in one
//! process on the same rays, interleaved, one thread: CPU nanoseconds per ray
//! (from `/proc/self/task/*/schedstat`, so a busy machine inflates them far
//! less than wall time) and the ratio. Checks that both give the same hits and
//! statistics.
//!
//! ```text
//! cargo bench -p dirt-cpu --bench trace_side_by_side -- SCENE RAYS.npy [REPS [hiz|linear [fast]]]
//! ```
//! `SCENE`: a built-in scene or a glTF/OBJ path; `RAYS.npy` as written by `dirt rays`;
//! `fast` times only the fast path (for a profiler).

use dirt_core::{AdsParams, RayStats, Traversal};
use dirt_cpu::trace::trace_ray_plain;
use dirt_cpu::{Ads, trace_with_stats};
use dirt_math::{Hit, Ray, Triangle};
use std::time::Instant;

/// CPU time of every thread of this process so far, in nanoseconds.
fn cpu_ns() -> u64 {
    let mut sum = 0;
    if let Ok(tasks) = std::fs::read_dir("/proc/self/task") {
        for t in tasks.flatten() {
            if let Ok(s) = std::fs::read_to_string(t.path().join("schedstat")) {
                sum += s
                    .split_whitespace()
                    .next()
                    .and_then(|v| v.parse::<u64>().ok())
                    .unwrap_or(0);
            }
        }
    }
    sum
}

/// A float32 `(N, 8)` C-order .npy as rays.
fn read_rays(path: &str) -> Vec<Ray> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {path}: {e}"));
    assert!(bytes.starts_with(b"\x93NUMPY"), "{path}: not a .npy file");
    let (len, start) = if bytes[6] == 1 {
        (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10)
    } else {
        (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        )
    };
    let header = String::from_utf8_lossy(&bytes[start..start + len]);
    assert!(
        header.contains("<f4") && header.contains("False") && header.contains(", 8"),
        "{path}: expected little-endian float32 of shape (N, 8), C order: {header}"
    );
    bytes[start + len..]
        .chunks_exact(32)
        .map(|row| {
            let f = |k: usize| {
                f32::from_le_bytes([row[4 * k], row[4 * k + 1], row[4 * k + 2], row[4 * k + 3]])
            };
            Ray {
                origin: [f(0), f(1), f(2)],
                tmin: f(3),
                dir: [f(4), f(5), f(6)],
                tmax: f(7),
            }
        })
        .collect()
}

fn plain(ads: &Ads, tris: &[Triangle], rays: &[Ray], t: Traversal) -> (Vec<Hit>, Vec<RayStats>) {
    rays.iter()
        .map(|r| {
            let mut s = RayStats::default();
            (trace_ray_plain(ads, tris, r, t, &mut s), s)
        })
        .unzip()
}

fn main() {
    // `cargo bench` passes `--bench`; keep only our positional arguments.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let scene = args.first().map_or("cornell", String::as_str);
    let Some(rays_path) = args.get(1) else {
        eprintln!("usage: trace_side_by_side SCENE RAYS.npy [REPS]");
        return;
    };
    let reps: usize = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(3);
    let traversals: &[Traversal] = match args.get(3).map(String::as_str) {
        Some("hiz") => &[Traversal::HiZ],
        Some("linear") => &[Traversal::Linear],
        _ => &[Traversal::HiZ, Traversal::Linear],
    };
    let only_fast = args.get(4).is_some_and(|a| a == "fast");
    let scene = dirt_scene::open(scene).unwrap_or_else(|e| panic!("cannot open {scene}: {e}"));
    let tris = &scene.triangles;
    let rays = read_rays(rays_path);
    let params = AdsParams::default();
    let ads = Ads::build(tris, &params).expect("valid parameters");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    println!(
        "{} ({} triangles), {} rays from {rays_path}, default parameters, one thread, best of {reps}",
        scene.name,
        tris.len(),
        rays.len()
    );
    for &t in traversals {
        let (want, want_stats) = plain(&ads, tris, &rays, t);
        let (hits, stats) = pool.install(|| trace_with_stats(&ads, tris, &rays, t));
        let same = want.iter().zip(&hits).all(|(a, b)| a.bits() == b.bits()) && want_stats == stats;
        assert!(same, "{t:?}: the fast path differs from the plain stage");
        let n = rays.len() as f64;
        let mut best = [(f64::INFINITY, f64::INFINITY); 3];
        for _ in 0..reps {
            let runs: [&dyn Fn(); 3] = [
                &|| {
                    std::hint::black_box(plain(&ads, tris, &rays, t));
                },
                &|| {
                    std::hint::black_box(pool.install(|| dirt_cpu::trace(&ads, tris, &rays, t)));
                },
                &|| {
                    std::hint::black_box(pool.install(|| trace_with_stats(&ads, tris, &rays, t)));
                },
            ];
            for (k, run) in runs.iter().enumerate().skip(usize::from(only_fast)) {
                let (c0, w0) = (cpu_ns(), Instant::now());
                run();
                let (c, w) = (cpu_ns() - c0, w0.elapsed().as_nanos());
                best[k].0 = best[k].0.min(c as f64 / n);
                best[k].1 = best[k].1.min(w as f64 / n);
            }
        }
        let s = |f: fn(&RayStats) -> u32| stats.iter().map(|s| f(s) as f64).sum::<f64>() / n;
        println!(
            "{t:?}: {:.2} views, {:.2} tiles, {:.2} buckets, {:.2} tests per ray",
            s(|s| s.views),
            s(|s| s.tiles),
            s(|s| s.buckets),
            s(|s| s.tests)
        );
        for (k, name) in ["plain", "fast", "fast+stats"].iter().enumerate() {
            println!(
                "  {name:<11} {:8.0} ns CPU/ray  {:6.3} Mrays/s CPU  {:8.0} ns wall/ray  x{:.2} (CPU, vs plain)",
                best[k].0,
                1e3 / best[k].0,
                best[k].1,
                best[0].0 / best[k].0
            );
        }
    }
}
