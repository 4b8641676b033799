//! The renderer end to end on small images: DIRT renders equal the reference
//! renders bit for bit, direct visibility equals traced primary rays, a white
//! furnace converges to its analytic radiance, materials, textures and lights
//! are used, and bad input is refused.

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::{DirtCpu, brute_force::Brute};
use dirt_math::{Ray, Triangle, Vec3};
use dirt_render::direct_visibility::{self, rasterize};
use dirt_render::metrics::{mean, rmse};
use dirt_render::reference::Reference;
use dirt_render::{Camera, Image, Mode, RenderError, Renderer, Settings};
use dirt_scene::{Light, LightKind, Material, Scene, Texture};

fn settings(w: u32, h: u32, spp: u32, bounces: u32, mode: Mode) -> Settings {
    Settings {
        width: w,
        height: h,
        spp,
        bounces,
        mode,
        seed: 7,
        ..Settings::default()
    }
}

fn render_with(scene: &Scene, s: Settings, tracer: &mut dyn Tracer) -> dirt_render::Rendered {
    let camera = Camera::for_scene(scene, s.width as f32 / s.height as f32).expect("camera");
    let r = Renderer::new(scene, camera, s).expect("renderer");
    r.render(tracer, &mut |_| {}).expect("render")
}

fn render_cpu(scene: &Scene, s: Settings) -> dirt_render::Rendered {
    let mut t = DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::Linear)
        .expect("dirt build");
    render_with(scene, s, &mut t)
}

/// A deterministic soup of random triangles with a few materials and an emitter.
fn soup(n: usize, seed: u64) -> Scene {
    let mut x = seed;
    let mut rnd = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut triangles = Vec::new();
    let mut tri_material = Vec::new();
    for i in 0..n {
        let c = Vec3::new(rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0);
        let mut v = [Vec3::ZERO; 3];
        for p in &mut v {
            *p = c + Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.6;
        }
        triangles.push(Triangle::new(v[0], v[1], v[2]));
        tri_material.push((i % 4) as u32);
    }
    Scene {
        triangles,
        tri_material,
        materials: vec![
            Material::default(),
            Material::diffuse("red", [0.8, 0.1, 0.1]),
            Material {
                metallic: 1.0,
                roughness: 0.3,
                ..Material::diffuse("gold", [0.9, 0.7, 0.3])
            },
            Material {
                emissive: [4.0, 4.0, 4.0],
                ..Material::default()
            },
        ],
        name: "soup".into(),
        ..Scene::default()
    }
}

#[test]
fn dirt_equals_reference_and_brute_pixel_for_pixel() {
    let scenes = [
        dirt_scene::open("cornell").expect("cornell"),
        dirt_scene::open("spheres").expect("spheres"),
        soup(300, 5),
    ];
    for scene in &scenes {
        for mode in [Mode::Pt, Mode::Ao, Mode::Direct] {
            let s = settings(20, 16, 2, 3, mode);
            let dirt = render_cpu(scene, s);
            let mut hiz = DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
                .expect("dirt build");
            let dirt_hiz = render_with(scene, s, &mut hiz);
            let reference = render_with(scene, s, &mut Reference::new(&scene.triangles));
            let brute = render_with(scene, s, &mut Brute::new(&scene.triangles));
            assert!(
                mean(&dirt.image) > 0.0,
                "{} {mode:?}: black image",
                scene.name
            );
            assert_eq!(
                dirt.image.bits(),
                reference.image.bits(),
                "{} {mode:?}: dirt != reference",
                scene.name
            );
            assert_eq!(
                dirt.image.bits(),
                dirt_hiz.image.bits(),
                "{} {mode:?}: hiz",
                scene.name
            );
            assert_eq!(
                dirt.image.bits(),
                brute.image.bits(),
                "{} {mode:?}: brute",
                scene.name
            );
            assert_eq!(dirt.rays, reference.rays);
        }
    }
}

#[test]
fn direct_visibility_equals_traced_primary_rays() {
    for scene in [
        dirt_scene::open("cornell").expect("cornell"),
        dirt_scene::open("spheres").expect("spheres"),
        soup(500, 9),
    ] {
        let camera = Camera::for_scene(&scene, 4.0 / 3.0).expect("camera");
        let (w, h) = (48, 36);
        let renderer = Renderer::new(&scene, camera, settings(w, h, 1, 1, Mode::Pt)).expect("r");
        let raster = rasterize(&scene.triangles, &camera, w, h);
        assert!(
            raster
                .prim
                .iter()
                .filter(|&&p| p != dirt_math::INVALID_ID)
                .count()
                > (w * h / 10) as usize,
            "{}: the rasteriser proposes too little",
            scene.name
        );
        let mut brute = Brute::new(&scene.triangles);
        for sample in 0..3 {
            let rays = renderer.primary_rays(sample);
            let pixels: Vec<usize> = (0..rays.len()).collect();
            let (hits, stats) = direct_visibility::primary_hits(
                &mut brute,
                &scene.triangles,
                &raster,
                &rays,
                &pixels,
            )
            .expect("primary hits");
            let truth = dirt_cpu::brute_force::trace(&scene.triangles, &rays);
            for (i, (a, b)) in hits.iter().zip(&truth).enumerate() {
                assert_eq!(a.bits(), b.bits(), "{}: pixel {i}", scene.name);
            }
            assert!(stats.confirmed > 0, "{}: nothing confirmed", scene.name);
        }
    }
}

/// A closed cube, every face emitting `le` towards the inside and reflecting
/// with Lambertian albedo `albedo`, seen from inside.
fn furnace(albedo: f32, le: f32) -> Scene {
    let c = Vec3::ZERO;
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let quads = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for q in quads {
        for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            let (a, b, cc) = (corners[tri[0]], corners[tri[1]], corners[tri[2]]);
            // Front faces (counter-clockwise) towards the inside.
            let n = (b - a).cross(cc - a);
            triangles.push(if n.dot(c - a) > 0.0 {
                Triangle::new(a, b, cc)
            } else {
                Triangle::new(a, cc, b)
            });
        }
    }
    let n = triangles.len();
    let mut cam = dirt_scene::Camera::look_at(
        "inside",
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(1.0, 0.4, -0.5),
        Vec3::Y,
        1.2,
    );
    cam.aspect = Some(1.0);
    Scene {
        triangles,
        tri_material: vec![1; n],
        materials: vec![
            Material::default(),
            Material {
                emissive: [le; 3],
                ..Material::diffuse("furnace", [albedo; 3])
            },
        ],
        cameras: vec![cam],
        name: "furnace".into(),
        ..Scene::default()
    }
}

/// With uniform emission `Le` and albedo `a` everywhere, a path of `K`
/// scattering events sees `L = Le · (1 + a + … + a^K)` exactly in
/// expectation (Russian roulette does not bias it). Tolerance: 1 % on the
/// image mean with roulette off, 3 % with it on (noise only).
#[test]
fn white_furnace_converges_to_the_analytic_radiance() {
    for (albedo, k, roulette, tol) in [
        (1.0f32, 3u32, None, 0.01),
        (0.5, 4, None, 0.01),
        (0.8, 6, Some(2), 0.03),
    ] {
        let scene = furnace(albedo, 1.0);
        let expected: f64 = (0..=k).map(|j| f64::from(albedo).powi(j as i32)).sum();
        let s = Settings {
            russian_roulette: roulette,
            ..settings(16, 16, 32, k, Mode::Pt)
        };
        let r = render_with(&scene, s, &mut Reference::new(&scene.triangles));
        let m = mean(&r.image);
        assert!(
            (m - expected).abs() <= tol * expected,
            "albedo {albedo}, K = {k}: mean {m}, expected {expected}"
        );
    }
}

fn box_textured() -> Option<Scene> {
    let path = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
    if !std::path::Path::new(path).exists() {
        eprintln!("*** SKIPPING: {path} is not installed (assimp-testmodels) ***");
        return None;
    }
    Some(dirt_scene::open(path).expect("BoxTextured"))
}

#[test]
fn base_colour_textures_are_used() {
    check_textures_are_used(&mut |sc, s| render_cpu(sc, s).image);
}

/// Renders `BoxTextured` with `render` as it is and with its texture made
/// plain red and plain white: pixels that see the box lose green and blue
/// under red, and the texture changes the image. Returns the scene, the
/// settings and the original image for further checks; `None` without the
/// asset.
fn check_textures_are_used(
    render: &mut dyn FnMut(&Scene, Settings) -> Image,
) -> Option<(Scene, Settings, Image)> {
    let scene = box_textured()?;
    let tex = scene
        .materials
        .iter()
        .find_map(|m| m.base_color_texture)
        .expect("a textured material") as usize;
    let s = settings(32, 32, 2, 1, Mode::Direct);
    let mut with = |rgba: [u8; 4]| {
        let mut sc = scene.clone();
        let t = &sc.textures[tex];
        sc.textures[tex] = Texture {
            width: t.width,
            height: t.height,
            rgba8: rgba.repeat((t.width * t.height) as usize),
        };
        render(&sc, s)
    };
    let red = with([255, 0, 0, 255]);
    let white = with([255, 255, 255, 255]);
    let original = render(&scene, s);
    // Pixels that see the box: green and blue vanish under a red texture
    // (pixels partly covering the white sky keep some).
    let mut box_pixels = 0;
    for (r, w) in red.pixels.iter().zip(&white.pixels) {
        assert!(r[1] <= w[1] && r[2] <= w[2], "{r:?} {w:?}");
        if r[1] < 0.05 * w[1] && r[2] < 0.05 * w[2] {
            box_pixels += 1;
        }
    }
    assert!(box_pixels > 100, "only {box_pixels} pixels see the box");
    assert!(rmse(&original, &white).expect("size") > 0.01);
    assert!(rmse(&original, &red).expect("size") > 0.01);
    Some((scene, s, original))
}

#[test]
fn material_factors_are_used() {
    let Some(mut scene) = box_textured() else {
        return;
    };
    let s = settings(24, 24, 2, 1, Mode::Direct);
    let before = render_cpu(&scene, s).image;
    for m in &mut scene.materials {
        m.base_color = [1.0, 0.0, 0.0, 1.0];
    }
    let after = render_cpu(&scene, s).image;
    let green_before: f32 = before.pixels.iter().map(|p| p[1]).sum();
    let green_after: f32 = after.pixels.iter().map(|p| p[1]).sum();
    let red_after: f32 = after.pixels.iter().map(|p| p[0]).sum();
    // The background (white sky) keeps its green; the box loses all of it.
    assert!(
        green_after < green_before * 0.9,
        "{green_after} vs {green_before}"
    );
    assert!(red_after > green_after);
}

#[test]
fn emitters_and_punctual_lights_light_the_scene() {
    let s = settings(16, 16, 2, 2, Mode::Pt);
    let (cornell, dark) = cornell_and_dark();
    let lit = mean(&render_cpu(&cornell, s).image);
    // A closed room without lights is black (the sky cannot get in).
    assert_eq!(mean(&render_cpu(&dark, s).image), 0.0);
    assert!(lit > 0.01);
    let means: Vec<f64> = LIGHT_KINDS
        .iter()
        .map(|&kind| mean(&render_cpu(&with_light(&dark, kind), s).image))
        .collect();
    check_light_means(&means);
}

/// `cornell`, and `cornell` with its emitters turned off.
fn cornell_and_dark() -> (Scene, Scene) {
    let cornell = dirt_scene::open("cornell").expect("cornell");
    let mut dark = cornell.clone();
    for m in &mut dark.materials {
        m.emissive = [0.0; 3];
    }
    (cornell, dark)
}

/// A point, a spot and a directional light.
const LIGHT_KINDS: [LightKind; 3] = [
    LightKind::Point,
    LightKind::Spot {
        inner_cone: 0.2,
        outer_cone: 0.4,
    },
    LightKind::Directional,
];

/// `scene` with one light of `kind` under the ceiling of `cornell`, pointing down.
fn with_light(scene: &Scene, kind: LightKind) -> Scene {
    let mut sc = scene.clone();
    sc.lights.push(Light {
        name: String::new(),
        kind,
        position: Vec3::new(0.0, 1.8, 0.5),
        direction: Vec3::NEG_Y,
        color: [1.0, 1.0, 1.0],
        intensity: 3.0,
        range: None,
    });
    sc
}

/// The mean radiance of the dark room lit by each of [`LIGHT_KINDS`]: the
/// point and the spot light it, the spot less; a directional light outside
/// a closed room is shadowed everywhere.
fn check_light_means(means: &[f64]) {
    assert!(means[0] > 0.001 && means[1] > 0.001, "{means:?}");
    assert!(
        means[1] < means[0],
        "a spot lights less than a point: {means:?}"
    );
    assert_eq!(means[2], 0.0, "{means:?}");
}

#[test]
fn more_samples_reduce_the_error() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let reference = render_with(
        &scene,
        Settings {
            seed: 1000,
            ..settings(12, 12, 256, 3, Mode::Pt)
        },
        &mut Reference::new(&scene.triangles),
    )
    .image;
    let err = |spp| {
        let img = render_cpu(&scene, settings(12, 12, spp, 3, Mode::Pt)).image;
        rmse(&img, &reference).expect("size")
    };
    let (e1, e16) = (err(1), err(16));
    assert!(e16 < e1 * 0.6, "rmse 1 spp {e1}, 16 spp {e16}");
}

#[test]
fn bad_input_is_an_error() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let camera = Camera::for_scene(&scene, 4.0 / 3.0).expect("camera");
    let bad = [
        settings(0, 10, 1, 1, Mode::Pt),
        settings(10, 0, 1, 1, Mode::Pt),
        settings(10, 10, 0, 1, Mode::Pt),
        settings(10, 10, 1, 100_000, Mode::Pt),
        Settings {
            ao_radius: Some(-1.0),
            ..settings(10, 10, 1, 1, Mode::Ao)
        },
    ];
    for s in bad {
        assert!(Renderer::new(&scene, camera, s).is_err(), "{s:?}");
    }
    let empty = Scene::default();
    assert!(matches!(
        Renderer::new(&empty, camera, Settings::default()),
        Err(RenderError::EmptyScene)
    ));
    assert!(Camera::framing(&empty, 1.0).is_err());
    let mut broken = scene.clone();
    broken.tri_material[0] = 1000;
    assert!(matches!(
        Renderer::new(&broken, camera, Settings::default()),
        Err(RenderError::BadScene(_))
    ));
}

#[test]
fn png_and_exr_are_written_and_exr_is_linear() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let img = render_cpu(&scene, settings(8, 6, 1, 1, Mode::Pt)).image;
    let dir = std::env::temp_dir().join(format!("dirt-render-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let png = dir.join("a.png");
    let exr = dir.join("a.exr");
    img.write_png(&png, 0.0).expect("png");
    img.write_exr(&exr).expect("exr");
    let back = dirt_render::Image::read_exr(&exr).expect("read exr");
    assert_eq!(back.bits(), img.bits());
    let decoded = image::open(&png).expect("decode png").to_rgb8();
    assert_eq!((decoded.width(), decoded.height()), (8, 6));
    assert!(img.write_png(&dir.join("missing-dir/x.png"), 0.0).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rays_are_valid_and_shadow_rays_respect_tmax() {
    // An occluder beyond a segment's end does not block it.
    let tri = Triangle::new(
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
    );
    let r = Ray::new(Vec3::ZERO, Vec3::Z, 0.0, 1.0);
    let mut b = Brute::new(&[tri]);
    assert!(!b.trace(&[r]).expect("trace")[0].is_hit());
}

/// A progressive viewer adds one sample pass at a time: passes `0..n` added
/// in order and scaled by `1 / n` are the `n`-spp render, bit for bit, and
/// count the same rays.
#[test]
fn sample_passes_add_up_to_the_render() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    for mode in [Mode::Pt, Mode::Ao] {
        let s = settings(24, 16, 3, 3, mode);
        let camera = Camera::for_scene(&scene, 1.5).expect("camera");
        let r = Renderer::new(&scene, camera, s).expect("renderer");
        let mut t = DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
            .expect("dirt build");
        let whole = r.render(&mut t, &mut |_| {}).expect("render");
        let mut sum = vec![Vec3::ZERO; 24 * 16];
        let mut rays = 0;
        for sample in 0..s.spp {
            let pass = r.render_sample(&mut t, sample).expect("pass");
            rays += pass.rays;
            for (acc, v) in sum.iter_mut().zip(&pass.radiance) {
                *acc += *v;
            }
        }
        let inv = 1.0 / s.spp as f32;
        let mean: Vec<[f32; 3]> = sum.iter().map(|v| (*v * inv).to_array()).collect();
        assert_eq!(mean, whole.image.pixels, "{mode:?}");
        assert_eq!(rays, whole.rays, "{mode:?}");
    }
}

/// A tracer whose hits come one poll late, as a browser GPU's read-back does.
struct Late(DirtCpu);

impl dirt_render::AsyncTrace for Late {
    fn name(&self) -> String {
        "late".into()
    }
    async fn trace_rays(&mut self, rays: &[Ray]) -> Result<Vec<dirt_math::Hit>, RenderError> {
        YieldOnce(false).await;
        Ok(self.0.trace(rays)?)
    }
}

/// Pending once (waking its task), then ready.
struct YieldOnce(bool);

impl std::future::Future for YieldOnce {
    type Output = ();
    fn poll(
        mut self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<()> {
        if self.0 {
            return std::task::Poll::Ready(());
        }
        self.0 = true;
        cx.waker().wake_by_ref();
        std::task::Poll::Pending
    }
}

/// A sample through a tracer whose hits arrive later (awaited) is the
/// blocking sample, bit for bit.
#[test]
fn an_awaited_sample_is_the_blocking_sample() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    for mode in [Mode::Pt, Mode::Ao] {
        let s = settings(24, 16, 2, 3, mode);
        let camera = Camera::for_scene(&scene, 1.5).expect("camera");
        let r = Renderer::new(&scene, camera, s).expect("renderer");
        let mut t = DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
            .expect("dirt build");
        let blocking = r.render_sample(&mut t, 1).expect("pass");
        let mut late = Late(t);
        let awaited =
            pollster::block_on(r.render_sample_async(&mut late, 1)).expect("awaited pass");
        assert_eq!(awaited.radiance, blocking.radiance, "{mode:?}");
        assert_eq!(awaited.rays, blocking.rays, "{mode:?}");
    }
}

// ---- The deferred path tracer on the GPU (`dirt_render::gpu`) ----

mod on_gpu {
    use super::*;
    use dirt_gpu::{DirtGpu, Gpu, GpuAds};
    use dirt_render::gpu::{GpuRenderer, TraceKind, TraceRecord, Transfers};
    use dirt_render::trace::Recording;

    pub(super) fn render(
        gpu: &Gpu,
        scene: &Scene,
        s: Settings,
        inspect: Option<&mut dyn FnMut(TraceRecord)>,
    ) -> (dirt_render::Rendered, Transfers) {
        let camera = Camera::for_scene(scene, s.width as f32 / s.height as f32).expect("camera");
        let r = Renderer::new(scene, camera, s).expect("renderer");
        let tracer = DirtGpu::built(gpu, &scene.triangles, &AdsParams::default(), Traversal::HiZ)
            .expect("dirt-gpu build");
        let mut g = GpuRenderer::new(gpu, &r).expect("GPU renderer");
        let out = g
            .render_inspected(
                tracer.ads().expect("built"),
                Traversal::HiZ,
                &mut |_| {},
                inspect,
            )
            .expect("GPU render");
        (out, g.transfers())
    }

    fn lit_cornell() -> Scene {
        let mut sc = dirt_scene::open("cornell").expect("cornell");
        sc.lights.push(Light {
            name: "spot".into(),
            kind: LightKind::Spot {
                inner_cone: 0.3,
                outer_cone: 0.6,
            },
            position: Vec3::new(0.0, 1.5, 0.5),
            direction: Vec3::NEG_Y,
            color: [1.0, 0.8, 0.6],
            intensity: 2.0,
            range: Some(5.0),
        });
        sc
    }

    /// Every trace the GPU renderer records — primary, shadow and scatter
    /// rays, every bounce — returns the CPU structure's hits for the same
    /// rays, bit for bit; the primary rays are the CPU renderer's to rounding
    /// (the same random numbers: a jitter off by one number would move a ray
    /// by up to a pixel). The primary trace ran limited by the confirmed
    /// rasterised candidates (`direct_visibility`), and its rays are handed
    /// back at full length.
    #[test]
    fn every_gpu_render_trace_equals_the_cpu_trace() {
        let Some(gpu) = dirt_gpu::testing::exact_gpu("every_gpu_render_trace_equals_the_cpu_trace")
        else {
            return;
        };
        let scene = lit_cornell();
        let s = settings(24, 16, 2, 3, Mode::Pt);
        let mut cpu = DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
            .expect("dirt build");
        let camera = Camera::for_scene(&scene, 1.5).expect("camera");
        let reference = Renderer::new(&scene, camera, s).expect("renderer");
        let mut records = Vec::new();
        let mut keep = |r: TraceRecord| records.push(r);
        let (out, _) = render(gpu, &scene, s, Some(&mut keep));
        let primaries = u64::from(s.width * s.height * s.spp);
        let v = out.visibility;
        assert_eq!(v.confirmed + v.fallback, primaries, "{v:?}");
        // The CPU renderer confirms as many, to the rays' rounding.
        let cpu_v = reference
            .render(&mut cpu, &mut |_| {})
            .expect("cpu render")
            .visibility;
        assert!(
            v.confirmed > primaries / 2 && v.confirmed.abs_diff(cpu_v.confirmed) <= primaries / 100,
            "GPU {v:?}, CPU {cpu_v:?}"
        );
        let (mut shadow, mut scatter, mut hit) = (0usize, 0usize, 0usize);
        for r in &records {
            let hits = cpu.trace(&r.rays).expect("cpu trace");
            for (k, (g, c)) in r.hits.iter().zip(&hits).enumerate() {
                assert_eq!(
                    g.bits(),
                    c.bits(),
                    "sample {} {:?} ray {k} {:?}",
                    r.sample,
                    r.kind,
                    r.rays[k]
                );
            }
            let valid = r.rays.iter().filter(|x| x.validate().is_ok()).count();
            hit += r.hits.iter().filter(|h| h.is_hit()).count();
            match r.kind {
                TraceKind::Primary => {
                    let cpu_rays = reference.primary_rays(r.sample);
                    for (g, c) in r.rays.iter().zip(&cpu_rays) {
                        assert_eq!(g.origin, c.origin);
                        assert_eq!(g.tmax, f32::INFINITY, "a primary ray kept its limit");
                        let d = (g.dir() - c.dir()).abs().max_element();
                        assert!(d <= 1e-6, "primary ray {g:?} vs the CPU's {c:?}");
                    }
                }
                TraceKind::Shadow { .. } => shadow += valid,
                TraceKind::Scatter { .. } => scatter += valid,
                TraceKind::Occlusion => panic!("an occlusion trace in a path-traced render"),
            }
        }
        // 2 samples × (1 primary + 3 bounces × (shadow + scatter)).
        assert_eq!(records.len(), 14);
        assert!(
            shadow > 100 && scatter > 100 && hit > 1000,
            "{shadow} {scatter} {hit}"
        );
    }
    /// The GPU renderer's image of a scene with an area light, a spot and
    /// glossy and textured materials agrees with the CPU renderer's at equal
    /// samples far more closely than two CPU renders with different seeds
    /// (which differ by the noise alone); one read-back per image.
    #[test]
    fn gpu_images_agree_with_the_cpu_renderer() {
        let Some(gpu) = dirt_gpu::testing::any_gpu("gpu_images_agree_with_the_cpu_renderer") else {
            return;
        };
        let mut scene = lit_cornell();
        // A glossy metal and a mirror among the Lambertian walls.
        for (k, m) in scene.materials.iter_mut().enumerate() {
            if k % 3 == 1 && !m.is_emissive() {
                m.metallic = 1.0;
                m.roughness = if k % 2 == 0 { 0.0 } else { 0.4 };
            }
        }
        let s = settings(32, 24, 8, 3, Mode::Pt);
        let (g, transfers) = render(gpu, &scene, s, None);
        let c = render_cpu(&scene, s).image;
        let other_seed = render_cpu(&scene, Settings { seed: 8, ..s }).image;
        let e = rmse(&g.image, &c).expect("size");
        let noise = rmse(&other_seed, &c).expect("size");
        eprintln!("GPU vs CPU RMSE {e:.5}; CPU seed 7 vs 8 {noise:.5}; {transfers:?}");
        assert!(e < 0.1 * noise, "GPU vs CPU {e}, seed noise {noise}");
        assert!(mean(&g.image) > 0.01);
        assert_eq!(transfers.read_backs, 1);
        assert_eq!(transfers.submissions, s.spp + 2);
        assert_eq!(transfers.bytes_written, 8 * u64::from(s.spp));
        assert!(
            g.rays >= u64::from(s.width * s.height * s.spp),
            "{}",
            g.rays
        );
    }

    /// The white furnace of the CPU test, rendered on the GPU, within the same tolerance.
    #[test]
    fn gpu_white_furnace_converges_to_the_analytic_radiance() {
        let Some(gpu) =
            dirt_gpu::testing::any_gpu("gpu_white_furnace_converges_to_the_analytic_radiance")
        else {
            return;
        };
        for (albedo, k, roulette, tol) in [(1.0f32, 3u32, None, 0.01), (0.8, 6, Some(2), 0.03)] {
            let scene = furnace(albedo, 1.0);
            let expected: f64 = (0..=k).map(|j| f64::from(albedo).powi(j as i32)).sum();
            let s = Settings {
                russian_roulette: roulette,
                ..settings(16, 16, 32, k, Mode::Pt)
            };
            let m = mean(&render(gpu, &scene, s, None).0.image);
            assert!(
                (m - expected).abs() <= tol * expected,
                "albedo {albedo}, K = {k}: mean {m}, expected {expected}"
            );
        }
    }

    /// Textures, punctual lights and emitters change the GPU image as they
    /// change the CPU's: a red texture removes green and blue, a room without
    /// emitters is black, a point light lights it more than a spot, a
    /// directional light outside it lights nothing.
    #[test]
    fn gpu_renders_use_textures_and_lights() {
        let Some(gpu) = dirt_gpu::testing::any_gpu("gpu_renders_use_textures_and_lights") else {
            return;
        };
        let s = settings(16, 16, 2, 2, Mode::Pt);
        let (cornell, dark) = cornell_and_dark();
        assert!(mean(&render(gpu, &cornell, s, None).0.image) > 0.01);
        assert_eq!(mean(&render(gpu, &dark, s, None).0.image), 0.0);
        let means: Vec<f64> = LIGHT_KINDS
            .iter()
            .map(|&kind| mean(&render(gpu, &with_light(&dark, kind), s, None).0.image))
            .collect();
        check_light_means(&means);

        let Some((boxed, s, original)) =
            check_textures_are_used(&mut |sc, s| render(gpu, sc, s, None).0.image)
        else {
            return;
        };
        // The textured GPU image is the CPU's to rounding.
        let cpu = render_cpu(&boxed, s).image;
        assert!(rmse(&original, &cpu).expect("size") < 1e-3);
    }

    /// Ambient occlusion on the GPU: every trace returns the CPU structure's
    /// hits for the same rays, bit for bit; the occlusion rays are the CPU
    /// renderer's (the same random numbers) to the rounding of the GPU's
    /// `sqrt`, `sin` and `cos`; the image is the CPU renderer's but for the
    /// few pixels whose ray that rounding moved across an edge; one read-back.
    #[test]
    fn gpu_ambient_occlusion_equals_the_cpu_renderers() {
        let Some(gpu) =
            dirt_gpu::testing::exact_gpu("gpu_ambient_occlusion_equals_the_cpu_renderers")
        else {
            return;
        };
        let scene = dirt_scene::open("cornell").expect("cornell");
        let s = settings(24, 16, 4, 1, Mode::Ao);
        let mut records = Vec::new();
        let mut keep = |r: TraceRecord| records.push(r);
        let (g, _) = render(gpu, &scene, s, Some(&mut keep));
        let camera = Camera::for_scene(&scene, 1.5).expect("camera");
        let reference = Renderer::new(&scene, camera, s).expect("renderer");
        let mut cpu = Recording::new(
            DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ)
                .expect("dirt build"),
        );
        let c = reference.render(&mut cpu, &mut |_| {}).expect("cpu render");
        // Per sample: the primary trace, then the occlusion trace.
        assert_eq!(records.len(), 2 * s.spp as usize);
        assert_eq!(cpu.calls.len(), 2 * s.spp as usize);
        let mut occlusion_rays = 0;
        for (r, (cpu_rays, _)) in records.iter().zip(&cpu.calls) {
            let hits = cpu.inner.trace(&r.rays).expect("cpu trace");
            for (k, (a, b)) in r.hits.iter().zip(&hits).enumerate() {
                assert_eq!(a.bits(), b.bits(), "{:?} ray {k} {:?}", r.kind, r.rays[k]);
            }
            if r.kind != TraceKind::Occlusion {
                continue;
            }
            // The GPU's rays sit in their pixels' slots, the CPU's are packed
            // in pixel order: the same rays, in the same order, to rounding.
            let sent: Vec<&Ray> = r.rays.iter().filter(|x| x.validate().is_ok()).collect();
            assert_eq!(sent.len(), cpu_rays.len(), "sample {}", r.sample);
            for (a, b) in sent.iter().zip(cpu_rays) {
                let d = (a.origin() - b.origin()).abs().max_element()
                    + (a.dir() - b.dir()).abs().max_element()
                    + (a.tmax - b.tmax).abs();
                assert!(d <= 1e-5, "occlusion ray {a:?} vs the CPU's {b:?}");
            }
            occlusion_rays += sent.len();
        }
        assert!(
            occlusion_rays > 24 * 16 * 2,
            "only {occlusion_rays} occlusion rays"
        );
        assert_eq!(g.rays, c.rays, "rays traced");
        let differ = g
            .image
            .pixels
            .iter()
            .zip(&c.image.pixels)
            .filter(|(a, b)| a != b)
            .count();
        eprintln!(
            "AO: {occlusion_rays} occlusion rays; {differ} of {} pixels differ from the CPU renderer's",
            g.image.pixels.len()
        );
        assert!(
            differ * 50 <= g.image.pixels.len(),
            "{differ} of {} pixels differ",
            g.image.pixels.len()
        );
        let m = mean(&g.image);
        assert!(
            m > 0.05 && m < 0.95,
            "mean {m}: neither all lit nor all occluded"
        );
        // Without inspection: one read-back for the image.
        let (_, transfers) = render(gpu, &scene, s, None);
        assert_eq!(transfers.read_backs, 1);
    }

    /// The progressive form, as a window presents it: samples added one by
    /// one sum to the whole render's image bit for bit; a new camera
    /// (`set_camera`: parameters and candidates rewritten, nothing made
    /// again) gives what a renderer made for that camera gives, bit for bit;
    /// the counters come back in one read-back.
    #[test]
    fn gpu_samples_added_one_by_one_equal_the_whole_render() {
        let Some(gpu) =
            dirt_gpu::testing::any_gpu("gpu_samples_added_one_by_one_equal_the_whole_render")
        else {
            return;
        };
        let scene = lit_cornell();
        let s = settings(20, 16, 3, 2, Mode::Pt);
        let ads = GpuAds::build(gpu, &scene.triangles, &AdsParams::default()).expect("gpu build");
        let camera = Camera::for_scene(&scene, 1.25).expect("camera");
        let mut moved = camera;
        moved.eye += moved.right * 0.3;
        let whole = |c: Camera| {
            let r = Renderer::new(&scene, c, s).expect("renderer");
            GpuRenderer::new(gpu, &r)
                .expect("GPU renderer")
                .render(&ads, Traversal::HiZ, &mut |_| {})
                .expect("GPU render")
        };
        let (first, second) = (whole(camera), whole(moved));
        assert_ne!(
            first.image.bits(),
            second.image.bits(),
            "the camera did not move"
        );
        let r = Renderer::new(&scene, camera, s).expect("renderer");
        let mut g = GpuRenderer::new(gpu, &r).expect("GPU renderer");
        let n = u64::from(s.width * s.height);
        for (c, want) in [(camera, &first), (moved, &second)] {
            g.set_camera(&Renderer::new(&scene, c, s).expect("renderer"))
                .expect("set camera");
            for k in 0..s.spp {
                g.add_sample(&ads, Traversal::HiZ, k).expect("sample");
            }
            let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(
                &dirt_gpu::read_back(gpu, g.sums(), 0, n * 16).expect("sums"),
            );
            let inv = 1.0 / s.spp as f32;
            let got: Vec<u32> = sums
                .iter()
                .flat_map(|v| [v[0] * inv, v[1] * inv, v[2] * inv])
                .map(f32::to_bits)
                .collect();
            assert_eq!(got, want.image.bits(), "the sums of the samples");
            // The browser's form: the mean and the counters in one read-back, awaited.
            let (mean, _) = pollster::block_on(g.mean_async(s.spp)).expect("mean");
            assert_eq!(mean.bits(), want.image.bits(), "the mean read back");
            let c = g.counters().expect("counters");
            // The page's form when its canvas presents the sums: the counters alone, awaited.
            assert_eq!(pollster::block_on(g.counters_async()).expect("counters"), c);
            assert_eq!(c.rays_total(), want.rays);
            // The candidates are the new camera's: as many confirmed.
            assert_eq!(c.confirmed_total(), want.visibility.confirmed);
        }
        let other = settings(8, 8, 1, 1, Mode::Pt);
        let e = g
            .set_camera(&Renderer::new(&scene, camera, other).expect("renderer"))
            .expect_err("another size");
        assert!(matches!(e, RenderError::Unsupported(_)), "{e}");
    }

    /// `target`'s bytes (`w` x `h` RGBA8), read back through a buffer.
    fn texture_bytes(gpu: &Gpu, target: &dirt_gpu::wgpu::Texture) -> Vec<u8> {
        use dirt_gpu::wgpu;
        let (w, h) = (target.width(), target.height());
        let row = (4 * w).div_ceil(256) * 256;
        let buf = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: u64::from(row * h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_texture_to_buffer(
            target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            target.size(),
        );
        gpu.queue.submit([enc.finish()]);
        let padded = dirt_gpu::read_back(gpu, &buf, 0, buf.size()).expect("texture read back");
        padded
            .chunks_exact(row as usize)
            .flat_map(|r| r[..4 * w as usize].to_vec())
            .collect()
    }

    /// How many bytes of `got` differ from `want`, and the largest difference.
    fn byte_diff(got: &[u8], want: &[u8]) -> (usize, u8) {
        assert_eq!(got.len(), want.len());
        let d = got.iter().zip(want).map(|(a, b)| a.abs_diff(*b));
        (d.clone().filter(|&x| x > 0).count(), d.max().unwrap_or(0))
    }

    #[test]
    fn the_output_pass_draws_the_pngs_bytes() {
        use dirt_gpu::wgpu;
        use dirt_render::gpu::output::Output;
        let Some(gpu) = dirt_gpu::testing::any_gpu("the_output_pass_draws_the_pngs_bytes") else {
            return;
        };
        let scene = lit_cornell();
        let s = settings(20, 16, 3, 2, Mode::Pt);
        let ads = GpuAds::build(gpu, &scene.triangles, &AdsParams::default()).expect("gpu build");
        let camera = Camera::for_scene(&scene, 1.25).expect("camera");
        let r = Renderer::new(&scene, camera, s).expect("renderer");
        let mut g = GpuRenderer::new(gpu, &r).expect("GPU renderer");
        for k in 0..s.spp {
            g.add_sample(&ads, Traversal::HiZ, k).expect("sample");
        }
        let (mean, _) = pollster::block_on(g.mean_async(s.spp)).expect("mean");
        let exposure = 0.5;
        let png = mean.to_rgba8(exposure);
        let distinct: std::collections::HashSet<_> = png.chunks_exact(4).collect();
        assert!(distinct.len() > 20, "a blank image tests nothing");
        // A plain target, an sRGB one (the pass decodes, the target encodes
        // again), and one twice the size (each pixel drawn as 2x2 texels).
        for (format, scale) in [
            (wgpu::TextureFormat::Rgba8Unorm, 1),
            (wgpu::TextureFormat::Rgba8UnormSrgb, 1),
            (wgpu::TextureFormat::Bgra8Unorm, 2),
        ] {
            let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("output target"),
                size: wgpu::Extent3d {
                    width: s.width * scale,
                    height: s.height * scale,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = target.create_view(&Default::default());
            let mut out = Output::new(&gpu.device, &gpu.queue, format).expect("output pass");
            let drawn = |out: &mut Output, sums: bool| {
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                if sums {
                    out.encode_sums(
                        &mut enc,
                        &view,
                        g.sums(),
                        s.width,
                        s.height,
                        s.spp,
                        exposure,
                    )
                } else {
                    out.encode_bytes(&mut enc, &view, &png, s.width, s.height)
                }
                .expect("encode");
                gpu.queue.submit([enc.finish()]);
                let mut bytes = texture_bytes(gpu, &target);
                if format == wgpu::TextureFormat::Bgra8Unorm {
                    bytes.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
                }
                // Every `scale`-th texel of every `scale`-th row: the image's pixels.
                let w = (s.width * scale) as usize;
                let picked: Vec<u8> = (0..s.height as usize)
                    .flat_map(|y| (0..s.width as usize).map(move |x| (y, x)))
                    .flat_map(|(y, x)| {
                        let i = 4 * (y * scale as usize * w + x * scale as usize);
                        bytes[i..i + 4].to_vec()
                    })
                    .collect();
                (bytes, picked)
            };
            // The uploaded bytes come out as they went in.
            let (_, copied) = drawn(&mut out, false);
            let (n, max) = byte_diff(&copied, &png);
            assert!(max <= 1, "{format:?}: uploaded bytes moved by {max}");
            if !format.is_srgb() {
                assert_eq!(n, 0, "{format:?}: uploaded bytes changed");
            }
            // The sums tone-mapped on the GPU: the PNG's bytes, to a step of
            // rounding (the GPU's `pow` and division are not the CPU's bits).
            let (all, toned) = drawn(&mut out, true);
            let (n, max) = byte_diff(&toned, &png);
            assert!(max <= 1, "{format:?}: tone-mapped bytes off by up to {max}");
            assert!(
                n * 50 <= png.len(),
                "{format:?}: {n} of {} bytes off by one",
                png.len()
            );
            if scale == 2 {
                let w = (s.width * 2) as usize;
                for y in 0..(s.height * 2) as usize {
                    for x in 0..w {
                        let (i, j) = (4 * (y * w + x), 4 * ((y & !1) * w + (x & !1)));
                        assert_eq!(all[i..i + 4], all[j..j + 4], "texel ({x}, {y})");
                    }
                }
            }
        }
        // Wrong sizes are errors, not a panic or a draw out of bounds.
        let mut out = Output::new(&gpu.device, &gpu.queue, wgpu::TextureFormat::Rgba8Unorm)
            .expect("output pass");
        let target = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: 4,
                height: 4,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = target.create_view(&Default::default());
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        assert!(
            out.encode_sums(&mut enc, &view, g.sums(), 64, 64, 1, 0.0)
                .is_err()
        );
        assert!(out.encode_bytes(&mut enc, &view, &png, 21, 16).is_err());
    }

    /// An animation's next pose on the same renderer (`set_scene`: the
    /// triangle and light tables, the parameters and candidates rewritten)
    /// renders what a renderer made for that pose renders, bit for bit; a
    /// pose with another triangle count is refused.
    #[test]
    fn gpu_renderer_follows_a_new_pose_as_a_new_renderer_would() {
        let Some(gpu) =
            dirt_gpu::testing::any_gpu("gpu_renderer_follows_a_new_pose_as_a_new_renderer_would")
        else {
            return;
        };
        let scene = lit_cornell();
        // Every triangle (the light among them) moved and the room squashed.
        let mut posed = scene.clone();
        for t in &mut posed.triangles {
            for v in &mut t.v {
                v[0] = v[0] * 0.8 + 0.05;
                v[1] += 0.1;
            }
        }
        let s = settings(20, 16, 2, 2, Mode::Pt);
        let camera = Camera::for_scene(&scene, 1.25).expect("camera");
        let render = |g: &mut GpuRenderer, sc: &Scene| {
            let ads = GpuAds::build(gpu, &sc.triangles, &AdsParams::default()).expect("build");
            g.render(&ads, Traversal::HiZ, &mut |_| {})
                .expect("GPU render")
        };
        let fresh = {
            let r = Renderer::new(&posed, camera, s).expect("renderer");
            render(
                &mut GpuRenderer::new(gpu, &r).expect("GPU renderer"),
                &posed,
            )
        };
        let r = Renderer::new(&scene, camera, s).expect("renderer");
        let mut g = GpuRenderer::new(gpu, &r).expect("GPU renderer");
        let before = render(&mut g, &scene);
        assert_ne!(
            before.image.bits(),
            fresh.image.bits(),
            "the pose changed nothing"
        );
        g.set_scene(&Renderer::new(&posed, camera, s).expect("renderer"))
            .expect("set scene");
        let after = render(&mut g, &posed);
        assert_eq!(after.image.bits(), fresh.image.bits());
        assert_eq!(after.rays, fresh.rays);
        assert_eq!(after.visibility.confirmed, fresh.visibility.confirmed);
        let mut fewer = posed.clone();
        fewer.triangles.pop();
        fewer.tri_material.pop();
        if let Some(n) = fewer.tri_normals.as_mut() {
            n.pop();
        }
        if let Some(u) = fewer.tri_uvs.as_mut() {
            u.pop();
        }
        let e = g
            .set_scene(&Renderer::new(&fewer, camera, s).expect("renderer"))
            .expect_err("another triangle count");
        assert!(matches!(e, RenderError::Unsupported(_)), "{e}");
    }

    /// An image with more pixels than one dispatch of the trace takes is
    /// refused with the sizes, not rendered in part.
    #[test]
    fn gpu_renderer_refuses_an_image_larger_than_a_trace() {
        let Some(gpu) =
            dirt_gpu::testing::any_gpu("gpu_renderer_refuses_an_image_larger_than_a_trace")
        else {
            return;
        };
        let scene = dirt_scene::open("cornell").expect("cornell");
        let side = (f64::from(dirt_gpu::TraceResources::max_rays(gpu)).sqrt() as u32) + 1;
        let s = settings(side, side, 1, 1, Mode::Pt);
        let r = Renderer::new(&scene, Camera::for_scene(&scene, 1.0).expect("camera"), s)
            .expect("renderer");
        let e = GpuRenderer::new(gpu, &r).expect_err("too large an image");
        assert!(
            matches!(e, RenderError::Gpu(dirt_gpu::GpuError::TooLarge { .. })),
            "{e}"
        );
    }
}
