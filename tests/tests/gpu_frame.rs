//! Builds recorded into an application's frame (`GpuAds::frame`,
//! `encode_build`): from its own vertex and index buffers, with the views
//! computed on the GPU, build and trace recorded into one encoder and
//! submitted once. On lavapipe they equal the CPU's build over the same mesh
//! (`dirt_core::gather`), bit for bit: views, Hi-Z levels, lists (as sets),
//! hits and statistics. dirt itself submits and waits for nothing.

use dirt_core::gather::{self, IndexFormat, MeshLayout};
use dirt_core::{AdsParams, Traversal, ViewsKind};
use dirt_cpu::{Ads, trace_with_stats};
use dirt_gpu::testing::{current_test_name, exact_gpu};
use dirt_gpu::trace::STRUCTURE_FULL;
use dirt_gpu::{Gpu, GpuAds, GpuMesh, TraceResources};
use dirt_math::view::Axis;
use dirt_math::{Hit, Ray, RayStats, Triangle, Vec3};
use dirt_tests::{adversarial_rays, random_scene, read_buffer};
use proptest::prelude::*;
use wgpu::util::DeviceExt;

/// A mesh as an application holds it: interleaved vertices (a 3-float normal,
/// then the position, then 2 floats of texture coordinates: 32 bytes) and
/// indices, with every vertex shared by the triangles that use it.
struct AppMesh {
    vertices: Vec<u8>,
    indices: Vec<u8>,
    layout: MeshLayout,
}

fn app_mesh(tris: &[Triangle], format: IndexFormat, transform: Option<[[f32; 4]; 3]>) -> AppMesh {
    let mut vertices = Vec::new();
    let mut index: Vec<u32> = Vec::new();
    let mut seen: Vec<[u32; 3]> = Vec::new();
    for t in tris {
        for k in 0..3 {
            let p = t.vertex(k);
            let key = p.to_array().map(f32::to_bits);
            let i = match seen.iter().position(|s| *s == key) {
                Some(i) => i,
                None => {
                    seen.push(key);
                    for w in [0.0, 0.0, 1.0, p.x, p.y, p.z, 0.5, 0.5] {
                        vertices.extend_from_slice(&f32::to_le_bytes(w));
                    }
                    seen.len() - 1
                }
            };
            index.push(i as u32);
        }
    }
    let mut indices: Vec<u8> = match format {
        IndexFormat::U16 => index
            .iter()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect(),
        IndexFormat::U32 => index.iter().flat_map(|i| i.to_le_bytes()).collect(),
    };
    // Storage bindings are whole words; wgpu buffers are too.
    indices.resize(indices.len().div_ceil(4) * 4, 0);
    let mut layout = MeshLayout::indexed(32, 12, format, tris.len() as u32);
    layout.transform = transform;
    AppMesh {
        vertices,
        indices,
        layout,
    }
}

fn storage(g: &Gpu, bytes: &[u8], extra: wgpu::BufferUsages) -> wgpu::Buffer {
    let mut b = bytes.to_vec();
    b.resize(b.len().max(16), 0);
    g.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &b,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | extra,
        })
}

/// The tests of this file share one device and count what dirt submits on
/// it: they run one at a time.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

struct Frame {
    hits: Vec<Hit>,
    stats: Vec<RayStats>,
}

/// One frame as an application records it: build and trace into one encoder,
/// one submission (its own), then its own read-back of hits and statistics.
fn record_frame(
    g: &Gpu,
    ads: &mut GpuAds,
    res: &mut TraceResources,
    meshes: &[(&wgpu::Buffer, &wgpu::Buffer, MeshLayout)],
    rays: &[Ray],
    trav: Traversal,
) -> Frame {
    let n = rays.len() as u64;
    let ray_buf = storage(g, bytemuck::cast_slice(rays), wgpu::BufferUsages::empty());
    let hit_buf = storage(
        g,
        &vec![0u8; (n * 16) as usize],
        wgpu::BufferUsages::empty(),
    );
    let stat_buf = storage(
        g,
        &vec![0u8; (n * 16) as usize],
        wgpu::BufferUsages::empty(),
    );
    let gpu_meshes: Vec<GpuMesh<'_>> = meshes
        .iter()
        .map(|(v, i, layout)| GpuMesh {
            vertices: v,
            indices: Some(i),
            layout: *layout,
        })
        .collect();
    let before = g.host_syncs();
    let mut enc = g.device.create_command_encoder(&Default::default());
    ads.encode_build(g, &mut enc, &gpu_meshes)
        .expect("encode_build");
    res.encode_trace(
        g,
        &mut enc,
        ads,
        &ray_buf,
        &hit_buf,
        Some(&stat_buf),
        n as u32,
        trav,
    )
    .expect("encode_trace");
    assert_eq!(
        g.host_syncs(),
        before,
        "recording a frame must neither submit nor wait"
    );
    g.queue.submit([enc.finish()]);
    // Rays still unfinished after the recorded rounds: the application records more.
    loop {
        let pool = res.pool().expect("a trace was recorded");
        let head: dirt_gpu::PoolHeader =
            bytemuck::pod_read_unaligned(&read_buffer(&g.device, &g.queue, pool)[..16]);
        if head.count_in == 0 {
            break;
        }
        let mut enc = g.device.create_command_encoder(&Default::default());
        res.encode_continue(g, &mut enc).expect("encode_continue");
        g.queue.submit([enc.finish()]);
    }
    let hits = bytemuck::pod_collect_to_vec::<u8, Hit>(&read_buffer(&g.device, &g.queue, &hit_buf));
    let stats =
        bytemuck::pod_collect_to_vec::<u8, RayStats>(&read_buffer(&g.device, &g.queue, &stat_buf));
    assert_eq!(
        g.host_syncs(),
        before,
        "a frame's only submission is the application's"
    );
    Frame {
        hits: hits[..rays.len()].to_vec(),
        stats: stats[..rays.len()].to_vec(),
    }
}

/// Structure of a frame structure against the CPU's over the same
/// triangles: the comparison the web page runs in a browser
/// (`dirt_web::compare::structure`), which must find nothing here.
fn compare_structure(g: &Gpu, ads: &GpuAds, cpu: &Ads) -> Result<(), TestCaseError> {
    let views = ads.read_views(g).expect("read views");
    let hiz = ads.read_hiz(g).expect("read hi-z");
    let lists = ads.read_lists(g).expect("read lists");
    let d = dirt_web::compare::structure(&views, &hiz, &lists, cpu);
    prop_assert!(d.is_empty(), "{:?}", d);
    prop_assert!(d.hiz_total > 0 && d.lists_total > 0);
    Ok(())
}

fn check_frame(
    tris: &[Triangle],
    transform: Option<[[f32; 4]; 3]>,
    format: IndexFormat,
    params: &AdsParams,
    seed: u64,
    budget: u32,
) -> Result<(), TestCaseError> {
    let Some(g) = exact_gpu(&current_test_name()) else {
        return Ok(());
    };
    let _serial = serial();
    let mesh = app_mesh(tris, format, transform);
    let cpu_tris =
        gather::gather(&mesh.vertices, Some(&mesh.indices), &mesh.layout).expect("gather");
    let cpu = Ads::build(&cpu_tris, params).expect("cpu build");
    let v = storage(g, &mesh.vertices, wgpu::BufferUsages::VERTEX);
    let i = storage(g, &mesh.indices, wgpu::BufferUsages::INDEX);
    // Room enough: this test is about the structure, not the ids' growth.
    let mut ads = GpuAds::frame(g, params, cpu.lists.ids.len() as u64 + 1).expect("frame");
    let mut res = TraceResources::new(g);
    // The default budget, or one that stops rays mid-walk, many times.
    res.budget = budget;
    let rays = adversarial_rays(&cpu_tris, 6, seed);
    for trav in [Traversal::Linear, Traversal::HiZ] {
        let f = record_frame(g, &mut ads, &mut res, &[(&v, &i, mesh.layout)], &rays, trav);
        let (ch, cs) = trace_with_stats(&cpu, &cpu_tris, &rays, trav);
        for r in 0..rays.len() {
            prop_assert_eq!(
                f.hits[r].bits(),
                ch[r].bits(),
                "{:?} ray {}: gpu {:?} cpu {:?}",
                trav,
                r,
                f.hits[r],
                ch[r]
            );
            prop_assert_eq!(f.stats[r], cs[r], "{:?} ray {} statistics", trav, r);
        }
    }
    compare_structure(g, &ads, &cpu)
}

fn params_strategy() -> impl Strategy<Value = AdsParams> {
    (
        prop::sample::select(ViewsKind::ALL.to_vec()),
        prop::sample::select(vec![8u32, 16, 32]),
        prop::sample::select(vec![1u32, 2, 8]),
        prop::option::of((-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0)),
        prop::option::of(prop::sample::select(Axis::ALL.to_vec())),
    )
        .prop_map(|(views, res, buckets, center, axis)| AdsParams {
            views,
            resolution: res,
            buckets,
            tile: 1,
            // One orthographic view takes no centre (the split's is its cut).
            center: center
                .map(|(x, y, z)| Vec3::new(x, y, z))
                .filter(|_| views != ViewsKind::Ortho),
            axis: axis.filter(|_| views.is_ortho()),
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn frame_builds_equal_the_cpu_bit_for_bit(
        seed in any::<u64>(),
        n in 1usize..60,
        scale in prop::sample::select(vec![1.0f32, 1e-3, 300.0]),
        params in params_strategy(),
        u16_indices in prop::bool::ANY,
        transformed in prop::bool::ANY,
        budget in prop::sample::select(vec![dirt_gpu::trace::WORK_BUDGET, 40]),
    ) {
        let tris = random_scene(seed, n, scale);
        let transform = transformed.then_some([
            [0.8, -0.6, 0.0, 0.25],
            [0.6, 0.8, 0.0, -1.5],
            [0.0, 0.0, 1.5, 0.125],
        ]);
        let format = if u16_indices { IndexFormat::U16 } else { IndexFormat::U32 };
        check_frame(&tris, transform, format, &params, seed, budget)?;
    }
}

#[test]
fn builtin_scenes_built_in_a_frame_equal_the_cpu() {
    for name in ["cornell", "layers"] {
        let scene = dirt_scene::builtin(name).expect("built-in");
        for views in ViewsKind::ALL {
            let params = AdsParams {
                views,
                resolution: 32,
                buckets: 4,
                tile: 1,
                center: None,
                axis: None,
            };
            check_frame(&scene.triangles, None, IndexFormat::U32, &params, 3, 100)
                .expect("gpu == cpu");
        }
    }
}

/// Lists that outgrow the ids: that frame's rays all say STRUCTURE_FULL (no
/// wrong hit, nothing dropped silently), the feedback counts the overflow once
/// the submission completes, and the next build grows the ids and is exact.
#[test]
fn a_frame_whose_lists_overflow_says_so_and_the_next_fits() {
    let Some(g) = exact_gpu("a_frame_whose_lists_overflow_says_so_and_the_next_fits") else {
        return;
    };
    let _serial = serial();
    let tris = dirt_scene::builtin("cornell").expect("built-in").triangles;
    let params = AdsParams {
        resolution: 32,
        buckets: 4,
        ..AdsParams::default()
    };
    let mesh = app_mesh(&tris, IndexFormat::U32, None);
    let v = storage(g, &mesh.vertices, wgpu::BufferUsages::empty());
    let i = storage(g, &mesh.indices, wgpu::BufferUsages::empty());
    let cpu = Ads::build(&tris, &params).expect("cpu build");
    let needed = cpu.lists.ids.len() as u64;
    let mut ads = GpuAds::frame(g, &params, 16).expect("frame");
    let mut res = TraceResources::new(g);
    let rays = adversarial_rays(&tris, 30, 5);
    let meshes = [(&v, &i, mesh.layout)];
    let first = record_frame(g, &mut ads, &mut res, &meshes, &rays, Traversal::HiZ);
    assert!(
        first.hits.iter().all(|h| h.prim == STRUCTURE_FULL),
        "an overflowed structure is never traced"
    );
    assert!(first.stats.iter().all(|s| *s == RayStats::default()));
    let fb = ads.feedback().expect("a frame structure has feedback");
    assert_eq!(
        (fb.recorded, fb.completed, fb.overflows, fb.grown),
        (1, 1, 1, 0),
        "{fb:?}"
    );
    assert_eq!(fb.entries_needed, needed);
    assert!(fb.capacity < needed);

    let second = record_frame(g, &mut ads, &mut res, &meshes, &rays, Traversal::HiZ);
    let (ch, _) = trace_with_stats(&cpu, &tris, &rays, Traversal::HiZ);
    for (r, (a, b)) in second.hits.iter().zip(&ch).enumerate() {
        assert_eq!(a.bits(), b.bits(), "ray {r}");
    }
    let fb = ads.feedback().expect("feedback");
    assert_eq!(
        (fb.recorded, fb.completed, fb.overflows, fb.grown),
        (2, 2, 1, 1),
        "{fb:?}"
    );
    assert!(
        fb.capacity >= needed + needed / 4,
        "grown with headroom: {fb:?}"
    );
}

/// A deforming mesh, frame after frame, in two meshes (one transformed), as an
/// application updates its vertex buffer: every frame equals the CPU's build
/// over that frame's triangles, and the triangle count may change.
#[test]
fn a_deforming_mesh_is_exact_every_frame() {
    let Some(g) = exact_gpu("a_deforming_mesh_is_exact_every_frame") else {
        return;
    };
    let _serial = serial();
    let base = dirt_tests::uv_sphere(Vec3::ZERO, 1.0, 8, 12);
    let floor = dirt_tests::grid(3, 4.0, -1.5);
    let lift: [[f32; 4]; 3] = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, -1.0, 0.0],
        [0.0, 1.0, 0.0, 0.5],
    ];
    let params = AdsParams {
        resolution: 32,
        buckets: 4,
        ..AdsParams::default()
    };
    let mut ads = GpuAds::frame(g, &params, 1 << 18).expect("frame");
    let mut res = TraceResources::new(g);
    let floor_mesh = app_mesh(&floor, IndexFormat::U16, Some(lift));
    let fv = storage(g, &floor_mesh.vertices, wgpu::BufferUsages::empty());
    let fi = storage(g, &floor_mesh.indices, wgpu::BufferUsages::empty());
    let sphere0 = app_mesh(&base, IndexFormat::U32, None);
    let sv = storage(g, &sphere0.vertices, wgpu::BufferUsages::COPY_DST);
    let si = storage(g, &sphere0.indices, wgpu::BufferUsages::empty());
    for frame in 0..4u32 {
        // The sphere squashes and swells; the same indices, new positions.
        let s = 1.0 + 0.3 * frame as f32;
        let moved: Vec<Triangle> = base
            .iter()
            .map(|t| {
                let f = |p: Vec3| Vec3::new(p.x * s, p.y / s, p.z + 0.1 * frame as f32);
                Triangle::new(f(t.vertex(0)), f(t.vertex(1)), f(t.vertex(2)))
            })
            .collect();
        let m = app_mesh(&moved, IndexFormat::U32, None);
        g.queue.write_buffer(&sv, 0, &m.vertices);
        let with_floor = frame % 2 == 1;
        let mut meshes = vec![(&sv, &si, m.layout)];
        if with_floor {
            meshes.push((&fv, &fi, floor_mesh.layout));
        }
        let mut cpu_tris =
            gather::gather(&m.vertices, Some(&m.indices), &m.layout).expect("gather");
        if with_floor {
            cpu_tris.extend(
                gather::gather(
                    &floor_mesh.vertices,
                    Some(&floor_mesh.indices),
                    &floor_mesh.layout,
                )
                .expect("gather"),
            );
        }
        let cpu = Ads::build(&cpu_tris, &params).expect("cpu build");
        let rays = adversarial_rays(&cpu_tris, 20, frame as u64);
        let f = record_frame(g, &mut ads, &mut res, &meshes, &rays, Traversal::Linear);
        let (ch, cs) = trace_with_stats(&cpu, &cpu_tris, &rays, Traversal::Linear);
        for r in 0..rays.len() {
            assert_eq!(f.hits[r].bits(), ch[r].bits(), "frame {frame} ray {r}");
            assert_eq!(f.stats[r], cs[r], "frame {frame} ray {r} statistics");
        }
        compare_structure(g, &ads, &cpu).expect("structure");
    }
    assert_eq!(ads.feedback().expect("feedback").overflows, 0);
}

/// A non-finite vertex (or an index past the vertices, which reads as NaN):
/// the build has no views, every ray misses, and the feedback names the triangle.
#[test]
fn a_non_finite_triangle_is_named_and_nothing_is_hit() {
    let Some(g) = exact_gpu("a_non_finite_triangle_is_named_and_nothing_is_hit") else {
        return;
    };
    let _serial = serial();
    let mut tris = dirt_tests::grid(2, 2.0, 0.0);
    let params = AdsParams {
        resolution: 16,
        ..AdsParams::default()
    };
    let rays = [Ray::new(
        Vec3::new(0.1, 0.2, 3.0),
        -Vec3::Z,
        0.0,
        f32::INFINITY,
    )];
    let mut ads = GpuAds::frame(g, &params, 1 << 12).expect("frame");
    let mut res = TraceResources::new(g);
    let ok = app_mesh(&tris, IndexFormat::U32, None);
    let (v, i) = (
        storage(g, &ok.vertices, wgpu::BufferUsages::empty()),
        storage(g, &ok.indices, wgpu::BufferUsages::empty()),
    );
    let f = record_frame(
        g,
        &mut ads,
        &mut res,
        &[(&v, &i, ok.layout)],
        &rays,
        Traversal::HiZ,
    );
    assert!(f.hits[0].is_hit(), "the finite grid is hit");
    assert_eq!(ads.feedback().expect("feedback").non_finite, None);

    tris[5] = Triangle::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y);
    let bad = app_mesh(&tris, IndexFormat::U32, None);
    let (v, i) = (
        storage(g, &bad.vertices, wgpu::BufferUsages::empty()),
        storage(g, &bad.indices, wgpu::BufferUsages::empty()),
    );
    let f = record_frame(
        g,
        &mut ads,
        &mut res,
        &[(&v, &i, bad.layout)],
        &rays,
        Traversal::HiZ,
    );
    assert!(!f.hits[0].is_hit());
    assert_eq!(ads.feedback().expect("feedback").non_finite, Some(5));
    let cpu_err = Ads::build(&tris, &params)
        .expect_err("an error")
        .to_string();
    assert!(cpu_err.contains("triangle 5"), "{cpu_err}");

    // An index past the end of the vertex buffer: the same, never a read out of bounds.
    let mut idx: Vec<u8> = ok.indices.clone();
    idx[3 * 4 * 2..3 * 4 * 2 + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
    let (v, i) = (
        storage(g, &ok.vertices, wgpu::BufferUsages::empty()),
        storage(g, &idx, wgpu::BufferUsages::empty()),
    );
    let f = record_frame(
        g,
        &mut ads,
        &mut res,
        &[(&v, &i, ok.layout)],
        &rays,
        Traversal::HiZ,
    );
    assert!(!f.hits[0].is_hit());
    assert_eq!(ads.feedback().expect("feedback").non_finite, Some(2));
}

/// The caller's mistakes are errors before anything is recorded.
#[test]
fn wrong_meshes_and_structures_are_errors() {
    let Some(g) = dirt_gpu::testing::any_gpu("wrong_meshes_and_structures_are_errors") else {
        return;
    };
    let _serial = serial();
    let tris = dirt_tests::grid(1, 1.0, 0.0);
    let params = AdsParams {
        resolution: 8,
        ..AdsParams::default()
    };
    let m = app_mesh(&tris, IndexFormat::U32, None);
    let v = storage(g, &m.vertices, wgpu::BufferUsages::empty());
    let i = storage(g, &m.indices, wgpu::BufferUsages::empty());
    let vertex_only = g
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &m.vertices,
            usage: wgpu::BufferUsages::VERTEX,
        });
    let mut ads = GpuAds::frame(g, &params, 1024).expect("frame");
    let mut enc = g.device.create_command_encoder(&Default::default());
    let mesh = |vertices, indices, layout| GpuMesh {
        vertices,
        indices,
        layout,
    };
    let no_storage = ads.encode_build(g, &mut enc, &[mesh(&vertex_only, Some(&i), m.layout)]);
    assert!(
        no_storage
            .expect_err("an error")
            .to_string()
            .contains("STORAGE")
    );
    let few = MeshLayout {
        triangles: 1000,
        ..m.layout
    };
    let short = ads.encode_build(g, &mut enc, &[mesh(&v, Some(&i), few)]);
    assert!(
        short
            .expect_err("an error")
            .to_string()
            .contains("index buffer holds")
    );
    let no_indices = ads.encode_build(g, &mut enc, &[mesh(&v, None, m.layout)]);
    assert!(no_indices.is_err());
    let odd = MeshLayout {
        vertex_stride: 30,
        ..m.layout
    };
    assert!(
        ads.encode_build(g, &mut enc, &[mesh(&v, Some(&i), odd)])
            .is_err()
    );
    let mut host = GpuAds::build(g, &tris, &params).expect("host build");
    let e = host.encode_build(g, &mut enc, &[mesh(&v, Some(&i), m.layout)]);
    assert!(
        e.expect_err("an error")
            .to_string()
            .contains("GpuAds::frame")
    );
    assert_eq!(
        ads.feedback().expect("feedback").recorded,
        0,
        "nothing was recorded"
    );
    // More ids than the id bindings hold: refused by name before any allocation.
    let e = GpuAds::frame(g, &params, u64::MAX / 8).expect_err("too large");
    assert!(
        matches!(e, dirt_gpu::GpuError::SplitTooLarge { what: "the list ids", bindings, .. } if bindings == g.id_bindings()),
        "{e}"
    );
}

/// A device destroyed in the middle of a frame: dirt's calls return errors
/// that say the device is lost, nothing panics, and a new `Gpu` traces again.
#[test]
fn a_destroyed_device_is_an_error_and_a_new_gpu_works() {
    let required = std::env::var("DIRT_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let g = match Gpu::new() {
        Ok(g) => g,
        Err(e) if !required => {
            eprintln!("SKIP a_destroyed_device_is_an_error_and_a_new_gpu_works: {e}");
            return;
        }
        Err(e) => panic!("{e}"),
    };
    let tris = dirt_tests::grid(2, 2.0, 0.0);
    let params = AdsParams {
        resolution: 16,
        ..AdsParams::default()
    };
    let rays = [Ray::new(
        Vec3::new(0.1, 0.2, 3.0),
        -Vec3::Z,
        0.0,
        f32::INFINITY,
    )];
    let m = app_mesh(&tris, IndexFormat::U32, None);
    let v = storage(&g, &m.vertices, wgpu::BufferUsages::empty());
    let i = storage(&g, &m.indices, wgpu::BufferUsages::empty());
    let mut ads = GpuAds::frame(&g, &params, 1 << 12).expect("frame");
    let mut enc = g.device.create_command_encoder(&Default::default());
    let mesh = GpuMesh {
        vertices: &v,
        indices: Some(&i),
        layout: m.layout,
    };
    ads.encode_build(&g, &mut enc, &[mesh])
        .expect("recorded before the loss");
    g.device.destroy();
    let mut res = TraceResources::new(&g);
    let e = res
        .trace_host(&g, &ads, &rays, Traversal::HiZ, false)
        .expect_err("no trace on a destroyed device");
    assert!(matches!(e, dirt_gpu::GpuError::DeviceLost { .. }), "{e:?}");
    let e = GpuAds::build(&g, &tris, &params).expect_err("no build on a destroyed device");
    assert!(matches!(e, dirt_gpu::GpuError::DeviceLost { .. }), "{e:?}");
    drop((ads, res, enc));

    let fresh = Gpu::new().expect("a new Gpu after the loss");
    let ads = GpuAds::build(&fresh, &tris, &params).expect("build");
    let (hits, _) = dirt_gpu::trace::trace(&fresh, &ads, &rays, Traversal::HiZ).expect("trace");
    assert!(hits[0].is_hit());
}

/// `DirtGpu` with `frame_builds`: the host-slice wrapper of a frame build
/// (one submission, built again when the lists outgrew the ids) traces the
/// same bits as the host build; non-finite input is the CPU's error.
#[test]
fn the_tracer_builds_in_a_frame_with_the_same_hits() {
    use dirt_core::Tracer;
    let Some(g) = exact_gpu("the_tracer_builds_in_a_frame_with_the_same_hits") else {
        return;
    };
    let _serial = serial();
    let tris = dirt_scene::builtin("layers").expect("built-in").triangles;
    let params = AdsParams {
        resolution: 32,
        buckets: 4,
        ..AdsParams::default()
    };
    let rays = adversarial_rays(&tris, 40, 8);
    let mut host = dirt_gpu::DirtGpu::new(g, params, Traversal::HiZ);
    host.build(&tris).expect("host build");
    let mut frame = dirt_gpu::DirtGpu::new(g, params, Traversal::HiZ);
    frame.frame_builds = true;
    frame.entries_hint = 16;
    let before = g.host_syncs();
    let report = frame.build(&tris).expect("frame build");
    let syncs = g.host_syncs();
    assert_eq!(
        (
            syncs.submissions - before.submissions,
            syncs.waits - before.waits
        ),
        (4, 2),
        "the first build overflowed the hinted ids and ran once more (each build: its submission and one read-back of its list total)"
    );
    assert_eq!(report.stages.len(), 1);
    let fb = frame
        .ads()
        .and_then(|a| a.feedback())
        .expect("a frame structure");
    assert_eq!((fb.overflows, fb.grown), (1, 1), "{fb:?}");
    let mut hs = vec![Hit::MISS; rays.len()];
    let mut ss = vec![RayStats::default(); rays.len()];
    host.trace_into(&rays, &mut hs, Some(&mut ss))
        .expect("trace");
    let mut hf = vec![Hit::MISS; rays.len()];
    let mut sf = vec![RayStats::default(); rays.len()];
    frame
        .trace_into(&rays, &mut hf, Some(&mut sf))
        .expect("trace");
    for r in 0..rays.len() {
        assert_eq!(hf[r].bits(), hs[r].bits(), "ray {r}");
        assert_eq!(sf[r], ss[r], "ray {r} statistics");
    }
    let mut bad = tris.clone();
    bad[7] = Triangle::new(Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::X, Vec3::Y);
    let e = frame.build(&bad).expect_err("non-finite");
    assert!(
        matches!(e, dirt_core::CoreError::NonFiniteTriangle { index: 7 }),
        "{e}"
    );
}
