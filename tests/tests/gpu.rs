//! GPU == CPU, bit for bit, on lavapipe: depth bounds, Hi-Z levels, id lists
//! (as sets per list), hits and per-ray statistics, on random scenes and rays.

use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, trace_with_stats};
use dirt_gpu::testing::{any_gpu, current_test_name, exact_gpu};
use dirt_gpu::{GpuAds, TraceResources};
use dirt_math::view::Axis;
use dirt_math::{Ray, Triangle, Vec3};
use dirt_tests::{adversarial_rays, random_scene};
use proptest::prelude::*;

/// Every list as a sorted set.
fn sorted_lists(l: &dirt_core::IdLists) -> Vec<Vec<u32>> {
    l.offsets
        .windows(2)
        .map(|w| {
            let mut v = l.ids[w[0] as usize..w[1] as usize].to_vec();
            v.sort_unstable();
            v
        })
        .collect()
}

fn compare(
    tris: &[Triangle],
    rays: &[Ray],
    params: &AdsParams,
    budget: u32,
) -> Result<(), TestCaseError> {
    let Some(g) = exact_gpu(&current_test_name()) else {
        return Ok(());
    };
    let cpu = Ads::build(tris, params).expect("cpu build");
    let ads = GpuAds::build(g, tris, params).expect("gpu build");
    let hiz = ads.read_hiz(g).expect("read hi-z");
    prop_assert_eq!(hiz.len(), cpu.hiz.len());
    for (l, (a, b)) in hiz.iter().zip(&cpu.hiz).enumerate() {
        let bad = a.iter().zip(b).position(|(x, y)| x != y);
        prop_assert!(
            bad.is_none(),
            "Hi-Z level {} differs at cell {:?}: gpu {:?} cpu {:?}",
            l,
            bad,
            bad.map(|i| a[i]),
            bad.map(|i| b[i])
        );
    }
    let lists = ads.read_lists(g).expect("read lists");
    prop_assert_eq!(&lists.offsets, &cpu.lists.offsets, "list offsets differ");
    prop_assert!(
        sorted_lists(&lists) == sorted_lists(&cpu.lists),
        "list contents differ"
    );
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let (ch, cs) = trace_with_stats(&cpu, tris, rays, trav);
        // The default budget, and small ones that stop most rays mid-walk
        // (in every loop) and continue them over many dispatches.
        for budget in [dirt_gpu::trace::WORK_BUDGET, budget] {
            let mut res = TraceResources::new(g);
            res.budget = budget;
            res.rounds = 16;
            let traced = res
                .trace_host(g, &ads, rays, trav, true)
                .expect("gpu trace");
            let (gh, gs) = (traced.hits, traced.stats);
            for i in 0..rays.len() {
                prop_assert_eq!(
                    gh[i].bits(),
                    ch[i].bits(),
                    "{:?} budget {} ray {} {:?}: gpu {:?} cpu {:?}",
                    trav,
                    budget,
                    i,
                    rays[i],
                    gh[i],
                    ch[i]
                );
                prop_assert_eq!(
                    gs[i],
                    cs[i],
                    "{:?} budget {} ray {} statistics",
                    trav,
                    budget,
                    i
                );
            }
        }
    }
    Ok(())
}

fn params_strategy() -> impl Strategy<Value = AdsParams> {
    (
        prop::sample::select(ViewsKind::ALL.to_vec()),
        prop::sample::select(vec![8u32, 16, 24, 32]),
        prop::sample::select(vec![1u32, 2, 8, 32]),
        prop::sample::select(vec![1u32, 2, 4]),
        prop::option::of(prop::sample::select(Axis::ALL.to_vec())),
    )
        .prop_map(|(views, res, buckets, tile, axis)| AdsParams {
            views,
            resolution: res,
            buckets,
            tile: if res % tile == 0 { tile } else { 1 },
            center: None,
            axis: axis.filter(|_| views.is_ortho()),
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]
    #[test]
    fn gpu_equals_cpu_bit_for_bit(seed in any::<u64>(), n in 1usize..80, scale in prop::sample::select(vec![1.0f32, 1e-3, 300.0]), params in params_strategy(), budget in prop::sample::select(vec![30u32, 60, 120])) {
        let tris = random_scene(seed, n, scale);
        let rays = adversarial_rays(&tris, 6, seed ^ 0x5eed);
        compare(&tris, &rays, &params, budget)?;
    }
}

#[test]
fn builtin_scenes_gpu_equals_cpu() {
    for name in ["cornell", "layers"] {
        let scene = dirt_scene::builtin(name).expect("built-in");
        let rays = adversarial_rays(&scene.triangles, 40, 9);
        for views in ViewsKind::ALL {
            let params = AdsParams {
                views,
                resolution: 64,
                buckets: 8,
                tile: 2,
                center: None,
                axis: None,
            };
            compare(&scene.triangles, &rays, &params, 100).expect("gpu == cpu");
        }
    }
}

#[test]
fn empty_scene_builds_and_misses() {
    let Some(g) = any_gpu("empty_scene_builds_and_misses") else {
        return;
    };
    let ads = GpuAds::build(g, &[], &AdsParams::default()).expect("empty scene builds");
    let rays = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)];
    let (h, _) = dirt_gpu::trace::trace(g, &ads, &rays, Traversal::Linear).expect("trace");
    assert!(!h[0].is_hit());
}

/// A ray whose walk needs more loop iterations than the GPU's budget per
/// dispatch (here: a 2400-triangle list in every tile it crosses) is
/// continued on the GPU over several dispatches, with the same hit and
/// statistics as the CPU's one walk; nothing is silently wrong.
#[test]
fn rays_over_the_gpu_work_budget_are_continued_exactly() {
    let Some(g) = exact_gpu("rays_over_the_gpu_work_budget_are_continued_exactly") else {
        return;
    };
    let mut tris = Vec::new();
    for k in 0..1200 {
        tris.extend(dirt_tests::grid(1, 2.0, k as f32 * 1e-3));
    }
    // Between two layers, parallel to them: crosses many tiles, tests every list.
    let rays = [
        Ray::new(
            Vec3::new(-3.0, 0.1, 0.60051),
            Vec3::new(1.0, 0.01, 0.0),
            0.0,
            f32::INFINITY,
        ),
        Ray::new(Vec3::new(0.1, 0.2, 5.0), -Vec3::Z, 0.0, f32::INFINITY),
    ];
    let params = AdsParams {
        views: ViewsKind::Cube,
        resolution: 16,
        buckets: 1,
        tile: 1,
        center: None,
        axis: None,
    };
    let cpu = Ads::build(&tris, &params).expect("cpu build");
    let ads = GpuAds::build(g, &tris, &params).expect("gpu build");
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let traced = dirt_gpu::trace::trace_report(g, &ads, &rays, trav).expect("trace");
        let (ch, cs) = trace_with_stats(&cpu, &tris, &rays, trav);
        assert!(
            cs[0].tests > dirt_gpu::trace::WORK_BUDGET,
            "the test ray should exceed the budget (tests {})",
            cs[0].tests
        );
        assert!(
            traced.rounds >= 1,
            "{trav:?}: the ray over the budget must take a continuation round"
        );
        for i in 0..rays.len() {
            assert_eq!(traced.hits[i].bits(), ch[i].bits(), "{trav:?} ray {i}");
            assert_eq!(traced.stats[i], cs[i], "{trav:?} ray {i}");
        }
    }
    let (ch, _) = trace_with_stats(&cpu, &tris, &rays, Traversal::Linear);
    assert_eq!(
        ch[1].bits(),
        dirt_cpu::brute_force::trace(&tris, &rays[1..])[0].bits()
    );
}

/// A structure larger than every binding of the device together is refused
/// before any work, by name, with the sizes in the message: never truncated.
#[test]
fn oversized_structure_is_a_clear_error() {
    let Some(g) = any_gpu("oversized_structure_is_a_clear_error") else {
        return;
    };
    let tris = random_scene(1, 10, 1.0);
    let params = AdsParams {
        views: ViewsKind::Cube,
        resolution: 2048,
        buckets: 64,
        tile: 1,
        center: None,
        axis: None,
    };
    // 6·2048²·64 + 1 offsets: 6 GiB, beyond any device's offset bindings.
    let e = GpuAds::build(g, &tris, &params).expect_err("refused");
    let msg = e.to_string();
    match e {
        dirt_gpu::GpuError::SplitTooLarge {
            what,
            bytes,
            bindings,
            per_binding,
        } => {
            assert_eq!(what, "the list offsets");
            assert_eq!(bytes, (6 * 2048 * 2048 * 64 + 1) * 4);
            assert_eq!(bindings, g.bindings(dirt_core::SplitArray::Offsets));
            assert!(bytes > bindings as u64 * per_binding, "{msg}");
            assert!(
                msg.contains("max_storage_buffers_per_shader_stage"),
                "{msg}"
            );
        }
        other => panic!("expected SplitTooLarge, got {other:?}"),
    }
}

/// As a wgpu application would: its own device and queue, its own ray and hit
/// buffers, its own encoder. `encode_trace` only records: until the
/// application submits, the hit buffer keeps what it held; after, it holds
/// the CPU's hits bit for bit.
#[test]
fn an_applications_device_and_buffers_trace_when_it_submits() {
    use dirt_gpu::wgpu;
    use wgpu::util::DeviceExt;
    // Only for the skip rule and the adapter's facts; the device is the test's own.
    if exact_gpu("an_applications_device_and_buffers_trace_when_it_submits").is_none() {
        return;
    }
    let (device, queue) =
        pollster::block_on(dirt_gpu::Gpu::open_device()).expect("the application's device");
    let gpu = dirt_gpu::Gpu::from_device(&device, &queue, &dirt_gpu::GpuOptions::default())
        .expect("dirt on the application's device");
    assert!(gpu.exact, "{}", gpu.exactness);
    let scene = dirt_scene::builtin("cornell").expect("built-in");
    let tris = &scene.triangles;
    let rays = adversarial_rays(tris, 10, 3);
    let params = AdsParams {
        resolution: 32,
        ..AdsParams::default()
    };
    let ads = GpuAds::build(&gpu, tris, &params).expect("gpu build");
    let ray_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("app rays"),
        contents: bytemuck::cast_slice(&rays),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let sentinel = vec![0xabu8; rays.len() * 16];
    let hit_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("app hits"),
        contents: &sentinel,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let read = |buf: &wgpu::Buffer| dirt_tests::read_buffer(&device, &queue, buf);
    let mut res = TraceResources::new(&gpu);
    let mut enc = device.create_command_encoder(&Default::default());
    res.encode_trace(
        &gpu,
        &mut enc,
        &ads,
        &ray_buf,
        &hit_buf,
        None,
        rays.len() as u32,
        Traversal::HiZ,
    )
    .expect("encode");
    assert_eq!(read(&hit_buf), sentinel, "encode_trace must not submit");
    queue.submit([enc.finish()]);
    let got: Vec<dirt_math::Hit> = bytemuck::pod_collect_to_vec(&read(&hit_buf));
    let cpu = Ads::build(tris, &params).expect("cpu build");
    let (want, _) = trace_with_stats(&cpu, tris, &rays, Traversal::HiZ);
    assert_eq!(res.read_header(&gpu).expect("header").count_in, 0);
    for i in 0..rays.len() {
        assert_eq!(got[i].bits(), want[i].bits(), "ray {i}");
    }
}

/// A trace whose ray count is on the GPU (`encode_trace_counted`): the rays
/// below the count are traced, as the CPU traces them, bit for bit, through
/// continuation rounds too; the hits past the count keep what they held; a
/// count past the buffer is clamped to it, and zero traces nothing.
#[test]
fn a_counted_trace_traces_the_rays_below_the_gpus_count() {
    use dirt_gpu::wgpu;
    use wgpu::util::DeviceExt;
    let Some(g) = exact_gpu("a_counted_trace_traces_the_rays_below_the_gpus_count") else {
        return;
    };
    let scene = dirt_scene::builtin("cornell").expect("built-in");
    let tris = &scene.triangles;
    let rays = adversarial_rays(tris, 12, 7);
    let n = rays.len() as u32;
    let params = AdsParams {
        resolution: 32,
        ..AdsParams::default()
    };
    let ads = GpuAds::build(g, tris, &params).expect("gpu build");
    let cpu = Ads::build(tris, &params).expect("cpu build");
    let (want, _) = trace_with_stats(&cpu, tris, &rays, Traversal::HiZ);
    let ray_buf = g
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("rays"),
            contents: bytemuck::cast_slice(&rays),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let sentinel = vec![0xabu8; rays.len() * 16];
    let hit_buf = g
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hits"),
            contents: &sentinel,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        });
    // The count sits at byte 8, as a field of an application's own state would.
    let counter = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("counter"),
        size: 16,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let read = |buf: &wgpu::Buffer| dirt_tests::read_buffer(&g.device, &g.queue, buf);
    let mut res = TraceResources::new(g);
    // A small budget: some rays finish in the continuation rounds.
    res.budget = 40;
    let mut rounds = 0;
    for count in [n / 3, 0, n, n + 100, u32::MAX] {
        g.queue.write_buffer(&hit_buf, 0, &sentinel);
        g.queue
            .write_buffer(&counter, 0, bytemuck::cast_slice(&[9u32, 9, count, 9]));
        let mut enc = g.device.create_command_encoder(&Default::default());
        res.encode_trace_counted(
            g,
            &mut enc,
            &ads,
            &ray_buf,
            &hit_buf,
            None,
            n,
            (&counter, 8),
            Traversal::HiZ,
        )
        .expect("encode");
        g.queue.submit([enc.finish()]);
        loop {
            let head = res.read_header(g).expect("header");
            if head.count_in == 0 {
                rounds += head.rounds;
                break;
            }
            let mut enc = g.device.create_command_encoder(&Default::default());
            res.encode_continue(g, &mut enc).expect("continue");
            g.queue.submit([enc.finish()]);
        }
        let got: Vec<dirt_math::Hit> = bytemuck::pod_collect_to_vec(&read(&hit_buf));
        let traced = count.min(n) as usize;
        for i in 0..traced {
            assert_eq!(got[i].bits(), want[i].bits(), "count {count}: ray {i}");
        }
        let bytes: &[u8] = bytemuck::cast_slice(&got);
        let written =
            (traced..rays.len()).find(|&i| bytes[i * 16..][..16] != sentinel[i * 16..][..16]);
        assert_eq!(
            written, None,
            "count {count}: a hit past the count was written"
        );
    }
    assert!(rounds > 0, "the budget made no continuation round");
    // The counter is checked as the other buffers are.
    let storage_only = g.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    for (buf, at) in [(&storage_only, 0), (&counter, 6), (&counter, 16)] {
        let mut enc = g.device.create_command_encoder(&Default::default());
        match res.encode_trace_counted(
            g,
            &mut enc,
            &ads,
            &ray_buf,
            &hit_buf,
            None,
            n,
            (buf, at),
            Traversal::HiZ,
        ) {
            Err(dirt_gpu::GpuError::Buffer { what, .. }) => assert_eq!(what, "the ray counter"),
            other => panic!("counter at {at}: expected a buffer error, got {other:?}"),
        }
    }
}

/// Buffers handed in by the caller are checked before anything is recorded:
/// too small, or without `STORAGE`, is an error that names the buffer.
#[test]
fn callers_buffers_of_the_wrong_size_or_usage_are_errors() {
    use dirt_gpu::wgpu;
    let Some(g) = any_gpu("callers_buffers_of_the_wrong_size_or_usage_are_errors") else {
        return;
    };
    let tris = random_scene(5, 10, 1.0);
    let ads = GpuAds::build(g, &tris, &AdsParams::default()).expect("gpu build");
    let buf = |size, usage| {
        g.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage,
            mapped_at_creation: false,
        })
    };
    let storage = wgpu::BufferUsages::STORAGE;
    let rays_ok = buf(32 * 10, storage);
    let hits_ok = buf(16 * 10, storage);
    let cases = [
        (
            "the ray buffer",
            buf(32 * 9, storage),
            buf(16 * 10, storage),
        ),
        (
            "the hit buffer",
            buf(32 * 10, storage),
            buf(16 * 9, storage),
        ),
        (
            "the hit buffer",
            buf(32 * 10, storage),
            buf(16 * 10, wgpu::BufferUsages::COPY_SRC),
        ),
    ];
    let mut res = TraceResources::new(g);
    for (what, rays, hits) in &cases {
        let mut enc = g.device.create_command_encoder(&Default::default());
        match res.encode_trace(g, &mut enc, &ads, rays, hits, None, 10, Traversal::Linear) {
            Err(dirt_gpu::GpuError::Buffer { what: w, problem }) => {
                assert_eq!(w, *what, "{problem}");
            }
            other => panic!("{what}: expected a buffer error, got {other:?}"),
        }
    }
    let mut enc = g.device.create_command_encoder(&Default::default());
    let small_stats = buf(16, storage);
    assert!(matches!(
        res.encode_trace(
            g,
            &mut enc,
            &ads,
            &rays_ok,
            &hits_ok,
            Some(&small_stats),
            10,
            Traversal::Linear
        ),
        Err(dirt_gpu::GpuError::Buffer { .. })
    ));
    res.budget = 0;
    assert!(
        res.encode_trace(
            g,
            &mut enc,
            &ads,
            &rays_ok,
            &hits_ok,
            None,
            10,
            Traversal::Linear
        )
        .is_err(),
        "a zero budget could never finish a ray"
    );
}
