//! Single shared functions, GPU (WGSL) against CPU (dirt-math), bit for bit.

use dirt_gpu::testing::exact_gpu;
use dirt_math::triangle::{RayShear, intersect};
use dirt_math::{Ray, Triangle, Vec3};
use dirt_tests::{Rng, adversarial_rays};

#[test]
fn div_cr_equals_cpu_division() {
    let Some(g) = exact_gpu("div_cr_equals_cpu_division") else {
        return;
    };
    let mut rng = Rng(3);
    let n = 1u32 << 20;
    let mut input = Vec::with_capacity(2 * n as usize);
    for _ in 0..n {
        input.push(rng.u32() ^ (rng.u32() << 1));
        input.push(rng.u32() ^ (rng.u32() << 1));
    }
    let out = dirt_gpu::selftest::run(g, "divide", &input, n, n as usize).expect("run");
    let mut bad = 0;
    for i in 0..n as usize {
        let q = f32::from_bits(input[2 * i]) / f32::from_bits(input[2 * i + 1]);
        let gq = f32::from_bits(out[i]);
        if !(q.is_nan() && gq.is_nan()) && q.to_bits() != out[i] {
            bad += 1;
        }
    }
    assert_eq!(bad, 0, "{bad} of {n} divisions differ");
}

#[test]
fn triangle_test_equals_cpu() {
    let Some(g) = exact_gpu("triangle_test_equals_cpu") else {
        return;
    };
    let mut rng = Rng(4);
    let mut tris = Vec::new();
    for _ in 0..64 {
        let c = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        tris.push(Triangle::new(
            c + rng.dir() * 0.3,
            c + rng.dir() * 0.3,
            c + rng.dir() * 0.3,
        ));
    }
    let rays = adversarial_rays(&tris, 400, 5);
    let mut input = Vec::new();
    let mut cases = Vec::new();
    let truth = dirt_cpu::brute_force::trace(&tris, &rays);
    for (k, r) in rays.iter().enumerate() {
        let winner = if truth[k].is_hit() {
            truth[k].prim as usize
        } else {
            k % tris.len()
        };
        for t in [&tris[winner], &tris[(k * 7 + 3) % tris.len()]] {
            input.extend_from_slice(bytemuck::cast_slice::<Ray, u32>(std::slice::from_ref(r)));
            input.extend_from_slice(bytemuck::cast_slice::<Triangle, u32>(std::slice::from_ref(
                t,
            )));
            cases.push((*r, *t));
        }
    }
    let n = cases.len();
    let out = dirt_gpu::selftest::run(g, "intersect_one", &input, n as u32, 4 * n).expect("run");
    let mut bad = Vec::new();
    for (i, (r, t)) in cases.iter().enumerate() {
        let cpu = intersect(r, &RayShear::new(r), t);
        let cw = match cpu {
            Some((t, u, v)) => [1, t.to_bits(), u.to_bits(), v.to_bits()],
            None => [0, 0, 0, 0],
        };
        let gw = [
            out[4 * i],
            if out[4 * i] == 1 { out[4 * i + 1] } else { 0 },
            if out[4 * i] == 1 { out[4 * i + 2] } else { 0 },
            if out[4 * i] == 1 { out[4 * i + 3] } else { 0 },
        ];
        if cw != gw {
            bad.push(format!("{r:?} {t:?}: cpu {cpu:?} gpu {gw:?}"));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {n} differ; first: {}",
        bad.len(),
        bad[0]
    );
    assert!(
        hits_seen(&out, n) > n / 10,
        "too few hits to prove anything"
    );
}

fn hits_seen(out: &[u32], n: usize) -> usize {
    (0..n).filter(|&i| out[4 * i] == 1).count()
}

#[test]
fn view_clip_and_walk_setup_equal_cpu() {
    use dirt_math::clip::clip_ray_to_view;
    use dirt_math::dda::{dilation, tile_xy};
    let Some(g) = exact_gpu("view_clip_and_walk_setup_equal_cpu") else {
        return;
    };
    let mut bad = Vec::new();
    for (si, name) in ["cornell", "foliage"].iter().enumerate() {
        let scene = dirt_scene::builtin(name).expect("built-in");
        let rays = adversarial_rays(&scene.triangles, 60, 17 + si as u64);
        for params in [
            dirt_core::AdsParams {
                resolution: 64,
                tile: 2,
                ..Default::default()
            },
            dirt_core::AdsParams {
                views: dirt_core::ViewsKind::Single,
                resolution: 32,
                ..Default::default()
            },
            dirt_core::AdsParams {
                views: dirt_core::ViewsKind::OrthoSplit,
                resolution: 32,
                ..Default::default()
            },
        ] {
            let vs = dirt_core::views_for(&scene.triangles, &params).expect("views");
            let mut input = Vec::new();
            let mut cases = Vec::new();
            for (k, v) in vs.views.iter().enumerate() {
                let vg = dirt_math::ViewGpu::new(v, vs.adjacency.get(k).copied().unwrap_or([0; 4]));
                for r in &rays {
                    input.extend_from_slice(bytemuck::cast_slice::<dirt_math::ViewGpu, u32>(
                        std::slice::from_ref(&vg),
                    ));
                    input.extend_from_slice(bytemuck::cast_slice::<Ray, u32>(
                        std::slice::from_ref(r),
                    ));
                    cases.push((*v, *r));
                }
            }
            let n = cases.len();
            let out =
                dirt_gpu::selftest::run(g, "view_walk_one", &input, n as u32, 8 * n).expect("run");
            for (i, (v, r)) in cases.iter().enumerate() {
                let vr = v.ray(r);
                let (iv, exit) = clip_ray_to_view(v, &vr, r.tmin, r.tmax);
                let mut want = [
                    iv.t0.to_bits(),
                    iv.t1.to_bits(),
                    exit.map_or(u32::MAX, |e| e as u32),
                    0,
                    0,
                    0,
                    0,
                    0,
                ];
                if !iv.is_empty() {
                    let a = tile_xy(v, &vr, iv.t0);
                    let b = tile_xy(v, &vr, iv.t1);
                    want[3..].copy_from_slice(&[
                        dilation(v, &vr, &iv).to_bits(),
                        a[0].to_bits(),
                        a[1].to_bits(),
                        b[0].to_bits(),
                        b[1].to_bits(),
                    ]);
                }
                if out[8 * i..8 * i + 8] != want {
                    bad.push(format!(
                        "{name} {r:?}: gpu {:?} cpu {want:?}",
                        &out[8 * i..8 * i + 8]
                    ));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{} differ; first: {}", bad.len(), bad[0]);
}
