use dirt_core::Tracer;
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = dirt_scene::open(&a[1]).expect("scene");
    let n: usize = a[2].parse().unwrap();
    let reps: usize = a[3].parse().unwrap();
    let tris = &scene.triangles;
    let rays =
        dirt_eval::rays::generate(tris, None, dirt_eval::rays::RayKind::Mixed, n, 1).unwrap();
    let mut t = dirt_cpu::DirtCpu::auto(None, n as u64);
    t.build(tris).unwrap();
    eprintln!("{}", t.name());
    let mut hits = vec![dirt_core::Hit::MISS; n];
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t0 = Instant::now();
        t.trace_into(&rays, &mut hits, None).unwrap();
        best = best.min(t0.elapsed().as_secs_f64() * 1e3);
    }
    println!(
        "{n} rays best {best:.2} ms, {:.2} Mrays/s",
        n as f64 / best / 1e3
    );
}
