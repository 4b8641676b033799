//! Exactness on the built-in scenes and on a real asset no one here wrote
//! (`2CylinderEngine.glb` from Debian's assimp-testmodels, installed by `.ci/run`).

use dirt_tests::{adversarial_rays, assert_exact_over_matrix};
use std::path::Path;

pub const ENGINE: &str =
    "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";

#[test]
fn builtin_scenes_are_exact() {
    for name in dirt_scene::BUILTIN_NAMES {
        let scene = dirt_scene::builtin(name).expect("built-in exists");
        let rays = adversarial_rays(&scene.triangles, 40, 11);
        assert_exact_over_matrix(name, &scene.triangles, &rays, 64);
    }
}

#[test]
fn two_cylinder_engine_is_exact() {
    assert!(
        Path::new(ENGINE).exists(),
        "{ENGINE} is missing: install Debian's assimp-testmodels (.ci/run does)"
    );
    let scene = dirt_scene::load(Path::new(ENGINE)).expect("the engine loads");
    assert!(scene.len() > 10_000, "{} triangles", scene.len());
    let rays = adversarial_rays(&scene.triangles, 25, 5);
    assert_exact_over_matrix("2CylinderEngine", &scene.triangles, &rays, 64);
}
