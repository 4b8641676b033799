//! The README's "Using the crates" example, run as written: the code between
//! the markers below must stand in README.md line for line.

use std::error::Error;

fn cpu_example() -> Result<(), Box<dyn Error>> {
    // README BEGIN
    use dirt_core::{Tracer, Traversal};
    use dirt_cpu::{DirtCpu, brute_force::Brute};
    use dirt_math::{Ray, Vec3};

    let scene = dirt_scene::open("cornell")?; // built-in name or glTF/OBJ path
    let rays = vec![Ray::new(
        Vec3::new(0.0, 1.0, 1.9),
        Vec3::new(0.0, 0.0, -1.0),
        0.0,
        f32::INFINITY,
    )];

    // The cost model chooses the parameters for frames of 100 000 rays at the first
    // build (DirtCpu::new(AdsParams { .. }, traversal) fixes them instead).
    let mut dirt = DirtCpu::auto(Traversal::HiZ, 100_000);
    dirt.build(&scene.triangles)?; // rebuild every frame for a moving scene
    let hits = dirt.trace(&rays)?;
    let truth = Brute::new(&scene.triangles).trace(&rays)?;
    assert_eq!(hits[0].bits(), truth[0].bits()); // Hit { prim, t, u, v }; hit.is_hit()
    // README END
    assert!(
        hits[0].is_hit(),
        "the example's ray hits the floor of cornell"
    );
    Ok(())
}

#[test]
fn the_readme_example_runs() {
    cpu_example().expect("README example");
}

/// The text without any whitespace, so rustfmt's layout here and the README's
/// compare equal.
fn squeeze(s: &str) -> String {
    s.split_whitespace().collect()
}

#[test]
fn the_readme_shows_this_example() {
    let me = include_str!("readme.rs");
    let start = me.find("// README BEGIN").expect("begin marker") + "// README BEGIN".len();
    let end = me.find("    // README END").expect("end marker");
    let example = squeeze(&me[start..end]);
    assert!(
        squeeze(include_str!("../../README.md")).contains(&example),
        "README.md's `Using the crates` example differs from tests/tests/readme.rs"
    );
}
