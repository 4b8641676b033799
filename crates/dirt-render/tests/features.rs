//! A render runs only what its scene and mode need, and leaving the rest out
//! changes no pixel.

use dirt_core::{AdsParams, Traversal};
use dirt_cpu::DirtCpu;
use dirt_render::fetch::Fetcher;
use dirt_render::{Camera, Mode, Renderer, Settings, features};
use dirt_scene::Scene;

fn small(mode: Mode) -> Settings {
    Settings {
        width: 24,
        height: 18,
        spp: 2,
        bounces: 3,
        mode,
        seed: 3,
        ..Settings::default()
    }
}

fn used(scene: &Scene, s: &Settings, name: &str) -> bool {
    features(scene, s)
        .iter()
        .find(|f| f.name == name)
        .unwrap_or_else(|| panic!("feature {name}"))
        .used
}

fn box_textured() -> Option<Scene> {
    let path = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
    if !std::path::Path::new(path).exists() {
        eprintln!("skipped: {path} is missing (Debian package assimp-testmodels)");
        return None;
    }
    Some(dirt_scene::open(path).expect("BoxTextured"))
}

#[test]
fn ambient_occlusion_fetches_geometry_only_and_the_image_is_the_same() {
    let scene = dirt_scene::open("cornell").expect("cornell");
    let s = small(Mode::Ao);
    let camera = Camera::for_scene(&scene, 24.0 / 18.0).expect("camera");
    let lean = Renderer::new(&scene, camera, s).expect("renderer");
    assert!(lean.fetcher.geometry_only);
    assert_eq!(lean.fetcher.decoded_textures(), 0);
    let mut full = Renderer::new(&scene, camera, s).expect("renderer");
    full.fetcher = Fetcher::new(&scene);
    let mut t =
        DirtCpu::built(&scene.triangles, &AdsParams::default(), Traversal::HiZ).expect("build");
    let a = lean.render(&mut t, &mut |_| {}).expect("render");
    let b = full.render(&mut t, &mut |_| {}).expect("render");
    let bits = |i: &dirt_render::Image| {
        i.pixels
            .iter()
            .flat_map(|p| p.map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a.image), bits(&b.image));
    assert!(!used(&scene, &s, "material fetch"));
    assert!(!used(&scene, &s, "shadow rays (next-event estimation)"));
}

#[test]
fn features_follow_the_scene() {
    let cornell = dirt_scene::open("cornell").expect("cornell");
    let pt = small(Mode::Pt);
    assert!(used(&cornell, &pt, "area-light sampling"));
    assert!(!used(&cornell, &pt, "punctual lights"));
    assert!(!used(&cornell, &pt, "base-colour textures"));
    assert!(used(&cornell, &pt, "shadow rays (next-event estimation)"));
    // Without emitters or lights there is nothing to sample.
    let mut dark = cornell.clone();
    for m in &mut dark.materials {
        m.emissive = [0.0; 3];
    }
    assert!(!used(&dark, &pt, "area-light sampling"));
    assert!(!used(&dark, &pt, "shadow rays (next-event estimation)"));
    let direct = small(Mode::Direct);
    assert!(!used(&cornell, &direct, "Russian roulette"));
}

#[test]
fn only_textures_that_used_materials_refer_to_are_decoded() {
    let Some(scene) = box_textured() else {
        return;
    };
    assert_eq!(Fetcher::new(&scene).decoded_textures(), 1);
    assert!(used(&scene, &small(Mode::Pt), "base-colour textures"));
    // Every triangle on the default material: the texture is not needed.
    let mut plain = scene.clone();
    plain.tri_material.iter_mut().for_each(|m| *m = 0);
    assert_eq!(Fetcher::new(&plain).decoded_textures(), 0);
    assert!(!used(&plain, &small(Mode::Pt), "base-colour textures"));
    assert!(!plain.textures.is_empty());
}
