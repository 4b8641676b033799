//! The page's logic natively: its passes are `dirt render`'s samples, and the
//! browser's measurement ([`dirt_web::check`]) finds nothing differing on the
//! CI device (lavapipe, the exact path) and finds a difference planted in a
//! structure.

#![cfg(not(target_arch = "wasm32"))]

use dirt_core::{AdsParams, Traversal};
use dirt_gpu::testing::{current_test_name, exact_gpu};
use dirt_render::{Camera, Renderer, Settings};
use dirt_web::{Backend, Page, check, compare, probe_rays};

/// `n` steps of the page on the CPU are the `n`-spp render of its camera, byte for byte.
#[test]
fn the_pages_passes_are_the_render() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let (w, h) = (24, 18);
    let backend = Backend::cpu(AdsParams::default(), Traversal::HiZ);
    let mut page = pollster::block_on(Page::new(scene.clone(), w, h, backend)).expect("page");
    page.orbit.drag_orbit(30.0, -10.0);
    page.restart();
    for _ in 0..3 {
        pollster::block_on(page.step()).expect("step");
    }
    assert_eq!(page.samples(), 3);
    let settings = Settings {
        width: w,
        height: h,
        spp: 3,
        ..Settings::default()
    };
    let camera =
        Camera::look_at(page.orbit.eye, page.orbit.target, page.orbit.fov).expect("camera");
    let r = Renderer::new(&scene, camera, settings).expect("renderer");
    let mut t = dirt_cpu::DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
        .expect("build");
    let whole = r.render(&mut t, &mut |_| {}).expect("render");
    let want: Vec<u8> = whole
        .image
        .to_srgb8(0.0)
        .chunks_exact(3)
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect();
    assert_eq!(page.rgba(), Some(want));
    assert!(
        page.camera_args().starts_with("--eye="),
        "{}",
        page.camera_args()
    );
    // A bad size is an error, not a panic.
    let backend = Backend::cpu(AdsParams::default(), Traversal::HiZ);
    assert!(pollster::block_on(Page::new(scene, 0, 10, backend)).is_err());
}

/// On lavapipe the frame build, its structure and its hits equal the CPU's
/// bit for bit; the measurement the browser runs is the same code.
#[test]
fn the_check_finds_nothing_on_the_exact_path() {
    let Some(g) = exact_gpu(&current_test_name()) else {
        return;
    };
    let scene = dirt_scene::open("cornell").expect("cornell");
    let rays = probe_rays(&scene.triangles, 800, 5);
    for params in dirt_web::check_params() {
        for traversal in [Traversal::Linear, Traversal::HiZ] {
            let c = pollster::block_on(check(g, &scene.triangles, &rays, &params, traversal))
                .expect("check");
            assert!(c.structure.is_empty(), "{}", c.summary());
            assert!(c.structure.hiz_total > 0 && c.structure.lists_total > 0);
            assert!(c.gpu_cpu.is_empty(), "{}", c.summary());
            assert!(c.gpu_truth.is_empty(), "{}", c.summary());
            assert!(c.cpu_truth.is_empty(), "{}", c.summary());
            assert!(c.summary().contains("0/800 rays differ"), "{}", c.summary());
        }
    }
}

/// The comparison sees one changed Hi-Z cell, one changed list and one changed hit.
#[test]
fn the_comparison_counts_what_differs() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let params = AdsParams {
        resolution: 16,
        buckets: 2,
        ..AdsParams::default()
    };
    let cpu = dirt_cpu::Ads::build(&scene.triangles, &params).expect("build");
    // The CPU's own structure laid out as a frame structure: nothing differs.
    let views = compare::frame_views(&cpu);
    let n_views = cpu.views.views.len();
    let per_view = |level: &Vec<[u32; 2]>| level.len() / cpu.views.slots().max(1);
    let mut hiz: Vec<Vec<[u32; 2]>> = cpu
        .hiz
        .iter()
        .map(|level| {
            let per = per_view(level);
            let mut out = Vec::new();
            for v in &cpu.views.views {
                if v.slot == dirt_math::view::NO_SLOT {
                    out.extend(std::iter::repeat_n(
                        [
                            dirt_math::encode::ORDERED_POS_INF,
                            dirt_math::encode::ORDERED_NEG_INF,
                        ],
                        per,
                    ));
                } else {
                    let s = v.slot as usize;
                    out.extend_from_slice(&level[s * per..(s + 1) * per]);
                }
            }
            out
        })
        .collect();
    let per_list = (params.tiles() as usize).pow(2) * params.buckets as usize;
    let mut offsets = vec![0u32];
    let mut ids = Vec::new();
    for v in &cpu.views.views {
        for k in 0..per_list {
            if v.slot != dirt_math::view::NO_SLOT {
                let at = v.slot as usize * per_list + k;
                let (a, b) = (
                    cpu.lists.offsets[at] as usize,
                    cpu.lists.offsets[at + 1] as usize,
                );
                ids.extend_from_slice(&cpu.lists.ids[a..b]);
            }
            offsets.push(ids.len() as u32);
        }
    }
    let mut lists = dirt_core::IdLists { offsets, ids };
    assert!(compare::structure(&views, &hiz, &lists, &cpu).is_empty());
    assert_eq!(n_views, 6);
    // Plant one difference in each.
    hiz[0][0][0] ^= 1;
    let first_full = (0..lists.offsets.len() - 1)
        .find(|&k| lists.offsets[k + 1] > lists.offsets[k])
        .expect("a list with ids");
    let at = lists.offsets[first_full] as usize;
    lists.ids[at] = lists.ids[at].wrapping_add(1_000_000);
    let d = compare::structure(&views, &hiz, &lists, &cpu);
    assert_eq!((d.views, d.hiz_cells, d.lists), (0, 1, 1), "{d:?}");
    let rays = probe_rays(&scene.triangles, 50, 2);
    let truth = dirt_cpu::brute_force::trace(&scene.triangles, &rays);
    let mut other = truth.clone();
    let i = other.iter().position(|h| h.is_hit()).expect("a hit");
    other[i].t = f32::from_bits(other[i].t.to_bits() + 2);
    let d = compare::hits(&other, &truth, None);
    assert_eq!((d.differ, d.prim, d.t, d.t_ulps), (1, 0, 1, 2), "{d:?}");
}

/// The page on the GPU (lavapipe: the frame build and the trace awaited)
/// shows the same bytes as on the CPU.
#[test]
fn the_page_on_the_gpu_shows_the_cpus_image() {
    let Some(g) = exact_gpu(&current_test_name()) else {
        return;
    };
    let scene = dirt_scene::open("cornell").expect("cornell");
    let params = AdsParams::default();
    let mut on_gpu = pollster::block_on(Page::new(
        scene.clone(),
        20,
        15,
        Backend::gpu(g, params, Traversal::HiZ),
    ))
    .expect("gpu page");
    let mut on_cpu = pollster::block_on(Page::new(
        scene,
        20,
        15,
        Backend::cpu(params, Traversal::HiZ),
    ))
    .expect("cpu page");
    for _ in 0..2 {
        pollster::block_on(on_gpu.step()).expect("gpu step");
        pollster::block_on(on_cpu.step()).expect("cpu step");
    }
    assert!(matches!(on_gpu.backend(), Backend::Gpu(_)));
    // No canvas presents it here: the mean is read back each step.
    assert!(!on_gpu.presents());
    assert!(on_gpu.rgba().is_some());
    assert_eq!(on_gpu.rgba(), on_cpu.rgba());
    assert!(on_gpu.rays_per_second() > 0.0);
}
