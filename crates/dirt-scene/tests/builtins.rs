#![allow(clippy::unwrap_used)]
//! The built-in procedural scenes.

use dirt_scene::{
    BUILTIN_NAMES, DEFAULT_SCENE, Mat4, SceneError, Vec3, builtin, builtin_scaled, open,
};

const COUNTS: &[(&str, usize)] = &[
    ("cornell", 998),
    ("layers", 512),
    ("foliage", 4096),
    ("spheres", 33794),
];

#[test]
fn every_builtin_loads_with_the_documented_count() {
    assert_eq!(BUILTIN_NAMES.len(), COUNTS.len());
    for &(name, count) in COUNTS {
        assert!(BUILTIN_NAMES.contains(&name));
        let s = builtin(name).unwrap();
        assert_eq!(s.name, name);
        assert_eq!(s.len(), count, "{name}");
        assert!(s.len() < 100_000);
        s.validate().unwrap();
        assert!(s.triangles.iter().all(|t| t.is_finite()), "{name}");
        assert!(
            s.tri_material
                .iter()
                .all(|&m| (m as usize) < s.materials.len()),
            "{name}"
        );
        assert_eq!(s.materials[0], dirt_scene::Material::default());
        assert_eq!(s.cameras.len(), 1, "{name}");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        if let Some(ns) = &s.tri_normals {
            for n in ns.iter().flatten() {
                let l = Vec3::from_array(*n).length();
                assert!((l - 1.0).abs() < 1e-4, "{name}: normal length {l}");
            }
        }
        // No degenerate triangles in the built-ins.
        for (i, t) in s.triangles.iter().enumerate() {
            let a = (t.vertex(1) - t.vertex(0))
                .cross(t.vertex(2) - t.vertex(0))
                .length();
            assert!(a > 0.0, "{name}: triangle {i} is degenerate");
        }
        // The camera sees the scene: it looks towards the bounds' centre.
        let c = &s.cameras[0];
        let b = s.bounds();
        assert!(c.forward.dot(b.center() - c.position) > 0.0, "{name}");
        assert!((c.forward.length() - 1.0).abs() < 1e-5 && c.forward.dot(c.up).abs() < 1e-5);
    }
}

#[test]
fn builtins_are_deterministic() {
    for name in BUILTIN_NAMES {
        assert_eq!(builtin(name), builtin(name), "{name}");
    }
}

#[test]
fn open_resolves_names_and_rejects_unknown_ones() {
    assert_eq!(open(DEFAULT_SCENE).unwrap(), builtin("cornell").unwrap());
    assert_eq!(open("layers").unwrap().len(), 512);
    match open("cornel") {
        Err(e @ SceneError::UnknownBuiltin { .. }) => {
            let msg = e.to_string();
            for name in BUILTIN_NAMES {
                assert!(msg.contains(name), "{msg}");
            }
        }
        other => panic!("{other:?}"),
    }
    assert!(builtin("nope").is_none());
    assert!(matches!(
        open("no/such/file.gltf"),
        Err(SceneError::NotFound { .. })
    ));
}

#[test]
fn cornell_is_closed_with_camera_inside_and_a_ceiling_light() {
    let s = builtin("cornell").unwrap();
    let b = s.bounds();
    assert_eq!(b.min, Vec3::new(-1.0, 0.0, -1.0));
    assert_eq!(b.max, Vec3::new(1.0, 2.0, 2.0));
    let cam = &s.cameras[0];
    assert!(cam.position.cmpgt(b.min).all() && cam.position.cmplt(b.max).all());
    // Facing the back wall (z = -1).
    assert!((cam.forward - Vec3::NEG_Z).length() < 1e-6);

    // Six walls of two triangles: every ray from inside hits one. Check by
    // casting rays from the camera in many directions against the 12 wall
    // triangles (Möller-Trumbore).
    let walls = &s.triangles[..12];
    let hit = |o: Vec3, d: Vec3| {
        walls.iter().any(|t| {
            let (v0, v1, v2) = (t.vertex(0), t.vertex(1), t.vertex(2));
            let (e1, e2) = (v1 - v0, v2 - v0);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                return false;
            }
            let s = o - v0;
            let u = s.dot(p) / det;
            let q = s.cross(e1);
            let v = d.dot(q) / det;
            let tt = e2.dot(q) / det;
            (-1e-6..=1.0 + 1e-6).contains(&u) && v >= -1e-6 && u + v <= 1.0 + 1e-6 && tt > 0.0
        })
    };
    for i in 0..200 {
        let a = i as f32 * 2.399_963; // golden angle
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / 200.0;
        let r = (1.0 - z * z).sqrt();
        let d = Vec3::new(r * a.cos(), r * a.sin(), z);
        assert!(hit(cam.position, d), "ray {d} escapes the room");
    }

    // Red left wall, green right wall, an emissive quad near the ceiling.
    let red = &s.materials[s.tri_material[6] as usize];
    let green = &s.materials[s.tri_material[8] as usize];
    assert!(red.base_color[0] > 0.5 && red.base_color[1] < 0.1);
    assert!(green.base_color[1] > 0.3 && green.base_color[0] < 0.2);
    let light_tris: Vec<usize> = (0..s.len())
        .filter(|&i| s.material_of(i).unwrap().is_emissive())
        .collect();
    assert_eq!(light_tris, vec![12, 13]);
    for &i in &light_tris {
        assert!(s.triangles[i].v.iter().all(|v| v[1] > 1.9 && v[1] < 2.0));
    }
}

#[test]
fn layers_stack_many_quads_under_the_centre() {
    let s = builtin("layers").unwrap();
    let zs: Vec<f32> = s.triangles.iter().map(|t| t.v[0][2]).collect();
    let mut distinct = zs.clone();
    distinct.dedup();
    assert_eq!(distinct.len(), 256);
    // Every layer covers the z axis.
    for t in &s.triangles {
        assert!(t.v.iter().all(|v| v[2] == t.v[0][2]));
    }
    assert!(
        distinct.windows(2).all(|w| w[1] < w[0]),
        "nearest layer first"
    );
}

#[test]
fn foliage_is_thin_and_long() {
    let s = builtin("foliage").unwrap();
    for t in &s.triangles {
        let (a, b, c) = (t.vertex(0), t.vertex(1), t.vertex(2));
        let len = ((a + b) * 0.5 - c).length();
        let width = (a - b).length();
        assert!(len > 5.0 * width, "{len} {width}");
    }
    let b = s.bounds();
    assert!(b.min.cmpge(Vec3::splat(-1.3)).all() && b.max.cmple(Vec3::splat(1.3)).all());
}

#[test]
fn spheres_sit_on_the_ground() {
    let s = builtin("spheres").unwrap();
    assert_eq!(s.materials.len(), 1 + 1 + 64);
    let b = s.bounds();
    assert!((b.min.y - 0.0).abs() < 1e-6 && (b.max.y - 0.8).abs() < 1e-5);
    assert!(s.tri_normals.is_some());
}

#[test]
fn scaled_and_transformed_variants() {
    for name in BUILTIN_NAMES {
        let base = builtin(name).unwrap();
        let b0 = base.bounds();
        for (scale, offset) in [
            (1e-4, Vec3::ZERO),
            (1e4, Vec3::ZERO),
            (1.0, Vec3::new(1e5, -2e5, 3e5)),
        ] {
            let s = builtin_scaled(name, scale, offset).unwrap();
            s.validate().unwrap();
            assert_eq!(s.len(), base.len());
            assert_eq!(s.tri_material, base.tri_material);
            let b = s.bounds();
            let tol = 1e-5 * (scale * b0.extent().max_element() + offset.abs().max_element());
            assert!(
                (b.min - (b0.min * scale + offset)).abs().max_element() <= tol,
                "{name} {scale} {offset}"
            );
            assert!(
                (b.max - (b0.max * scale + offset)).abs().max_element() <= tol,
                "{name} {scale} {offset}"
            );
            let c = &s.cameras[0];
            assert!((c.position - (base.cameras[0].position * scale + offset)).length() <= tol);
            assert!((c.forward - base.cameras[0].forward).length() < 1e-5);
        }
    }
    assert!(builtin_scaled("nope", 1.0, Vec3::ZERO).is_none());

    // A mirror keeps normals unit length and pointing the mirrored way.
    let s = builtin("spheres").unwrap();
    let m = s.transformed(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
    let (n0, n1) = (
        s.tri_normals.as_ref().unwrap(),
        m.tri_normals.as_ref().unwrap(),
    );
    for (a, b) in n0.iter().zip(n1).take(2000) {
        for (a, b) in a.iter().zip(b) {
            let d = Vec3::new(-a[0], a[1], a[2]) - Vec3::from_array(*b);
            assert!(d.length() < 1e-6, "{a:?} {b:?}");
        }
    }
}
