use dirt_core::{AdsParams, ViewsKind};
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let wave;
    let scene_tris = if a[1] == "wave" {
        wave = dirt_eval::dynamic::wave_grid(128, 0.3);
        &wave
    } else {
        wave = dirt_scene::open(&a[1]).expect("scene").triangles;
        &wave
    };
    let r: u32 = a[2].parse().unwrap();
    let n: usize = a[3].parse().unwrap();
    let views = if a.get(4).map(|s| s.as_str()) == Some("cube") {
        ViewsKind::Cube
    } else {
        ViewsKind::Single
    };
    let p = AdsParams {
        views,
        resolution: r,
        buckets: 8,
        tile: 1,
        center: None,
    };
    let tris = scene_tris;
    let mut best = f64::INFINITY;
    for _ in 0..n {
        let t0 = Instant::now();
        let ads = dirt_cpu::Ads::build(tris, &p).unwrap();
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        best = best.min(ms);
        std::hint::black_box(&ads);
        if n < 4 {
            println!("{}", ads.stats());
        }
    }
    println!("{} tris, best build {best:.2} ms", tris.len());
}
