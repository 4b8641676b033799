//! Measures every candidate the cost model chooses among
//! (`dirt_cpu::cost::candidates_all`) on one scene: the eval's rays (its five
//! ray types, 5 000 each, the eval's seed) traced through `DirtCpu` with each
//! traversal, and the build, each the best of two runs; next to them the
//! model's prediction and which candidate the one-off choice
//! (`dirt_cpu::cost::auto`, the eval headline's setting) picks. The rows go
//! fastest trace first. Run in release, with the threads the eval uses:
//!
//! ```text
//! RAYON_NUM_THREADS=2 cargo run --release -p dirt-eval --example sweep -- cornell [ROWS]
//! ```
//!
//! This is where the first guesses of `cost::auto` (the orthographic sets
//! first, at the resolutions of `cost::Extents`) were read from.

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::Ads;
use dirt_cpu::cost::{CostModel, Counts};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell", String::as_str);
    let rows_shown: usize = match args.get(2) {
        Some(n) => n.parse()?,
        None => 20,
    };
    let scene = dirt_scene::open(name)?;
    let tris = scene.triangles.clone();
    let reference = Ads::build(&tris, &AdsParams::default())?;
    let rays = dirt_eval::rays::table1(&scene, 5000, 1, |r| {
        dirt_cpu::trace(&reference, &tris, r, Traversal::Linear)
    })?;
    let all: Vec<_> = rays.iter().flat_map(|(_, r)| r.iter().copied()).collect();
    // The headline's sample, so that the choice marked is the headline's.
    let sample = dirt_cpu::cost::stride_sample(&all, dirt_eval::harness::CHOICE_SAMPLE);
    let model = CostModel::CALIBRATED;
    let candidates = dirt_cpu::cost::candidates_all(&AdsParams::default(), &tris);
    let chosen = dirt_cpu::cost::auto(
        &tris,
        &sample,
        all.len() as u64,
        Traversal::HiZ,
        &model,
        &candidates,
    )?
    .best
    .params;
    // (ns a ray at the faster traversal, linear, hiz, build ms, model ns, model ms, label, chosen)
    let mut rows = Vec::new();
    for p in &candidates {
        let ads = Ads::build(&tris, p)?;
        let counts = Counts::measure(&ads, &tris, &sample, Traversal::HiZ);
        let mut trace_s = [f64::MAX; 2];
        for (k, t) in Traversal::ALL.into_iter().enumerate() {
            let mut tracer = dirt_cpu::DirtCpu::new(*p, t);
            tracer.build(&tris)?;
            for _ in 0..2 {
                let start = Instant::now();
                for (_, r) in &rays {
                    std::hint::black_box(tracer.trace(r)?);
                }
                trace_s[k] = trace_s[k].min(start.elapsed().as_secs_f64());
            }
        }
        let mut build_s = f64::MAX;
        for _ in 0..2 {
            let start = Instant::now();
            std::hint::black_box(Ads::build(&tris, p)?);
            build_s = build_s.min(start.elapsed().as_secs_f64());
        }
        let per_ray = |s: f64| s * 1e9 / all.len() as f64;
        let label = format!(
            "{:?} r{} B{}{}",
            p.views,
            p.resolution,
            p.buckets,
            p.center.map_or(String::new(), |c| format!(" at {c}"))
        );
        rows.push((
            per_ray(trace_s[0].min(trace_s[1])),
            per_ray(trace_s[0]),
            per_ray(trace_s[1]),
            build_s * 1e3,
            model.ray_ns(&counts),
            model.build_ms(&counts),
            label,
            *p == chosen,
        ));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("rank  ns/ray (linear / hiz)  build ms | model ns, ms | candidate");
    for (i, r) in rows.iter().enumerate() {
        if i < rows_shown || r.7 {
            println!(
                "{i:4} {:7.0} ({:.0} / {:.0}) {:8.2} | {:6.0} {:7.2} | {}{}",
                r.0,
                r.1,
                r.2,
                r.3,
                r.4,
                r.5,
                r.6,
                if r.7 { "  <= cost::auto" } else { "" }
            );
        }
    }
    Ok(())
}
