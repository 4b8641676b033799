#![allow(clippy::unwrap_used)]
//! The models of Debian's `assimp-testmodels` package, malformed ones
//! included: each loads or gives a `SceneError`, never a panic.
//! These tests fail (with instructions) when the package is not installed.

mod common;

use std::path::{Path, PathBuf};

use common::{assimp_models, load_no_panic};
use dirt_scene::SceneError;

fn gltf2(rel: &str) -> PathBuf {
    let p = assimp_models().join("glTF2").join(rel);
    assert!(
        p.exists(),
        "{} is missing from assimp-testmodels",
        p.display()
    );
    p
}

fn all_models(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            all_models(&p, out);
        } else if let Some(ext) = p.extension()
            && ["gltf", "glb", "obj"].contains(&ext.to_string_lossy().to_ascii_lowercase().as_str())
        {
            out.push(p);
        }
    }
}

#[test]
fn every_gltf_and_obj_model_loads_or_errors_without_panicking() {
    let mut files = Vec::new();
    all_models(&assimp_models(), &mut files);
    files.sort();
    assert!(files.len() > 50, "only {} models found", files.len());
    let (mut ok, mut err) = (0, 0);
    for f in &files {
        match load_no_panic(f) {
            Ok(_) => ok += 1,
            Err(e) => {
                assert!(
                    e.to_string().contains(&*f.to_string_lossy()),
                    "error does not name the file: {e}"
                );
                err += 1;
            }
        }
    }
    assert!(ok > 30 && err > 10, "ok {ok}, err {err}");
}

#[test]
fn malformed_gltf2_models_give_specific_errors() {
    type Expect = fn(&SceneError) -> bool;
    let cases: &[(&str, Expect)] = &[
        ("BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", |e| {
            matches!(e, SceneError::NonFinite { .. })
        }),
        ("IndexOutOfRange/IndexOutOfRange.gltf", |e| {
            matches!(e, SceneError::IndexOutOfRange { .. })
        }),
        ("IndexOutOfRange/AllIndicesOutOfRange.gltf", |e| {
            matches!(e, SceneError::IndexOutOfRange { .. })
        }),
        ("MissingBin/BoxTextured.gltf", |e| {
            matches!(e, SceneError::MissingResource { .. })
        }),
        ("RecursiveNodes/RecursiveNodes.gltf", |e| {
            matches!(e, SceneError::RecursiveNodes { .. })
        }),
        ("IncorrectVertexArrays/Cube.gltf", |e| {
            matches!(
                e,
                SceneError::BadResource { .. } | SceneError::Accessor { .. }
            )
        }),
        ("SchemaFailures/sceneWrongType.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("wrongTypes/badArray.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("wrongTypes/badNumber.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("wrongTypes/badObject.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("wrongTypes/badString.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("wrongTypes/badUint.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
        }),
        ("draco/2CylinderEngine.gltf", |e| {
            matches!(e, SceneError::Gltf { .. })
                && e.to_string().contains("KHR_draco_mesh_compression")
        }),
    ];
    for (rel, is_expected) in cases {
        match load_no_panic(&gltf2(rel)) {
            Err(e) => assert!(is_expected(&e), "{rel}: unexpected error {e:?}"),
            Ok(s) => panic!("{rel}: loaded {} triangles, expected an error", s.len()),
        }
    }
    let e = load_no_panic(&gltf2("MissingBin/BoxTextured.gltf"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("BoxTextured0.bin"), "{e}");
}

#[test]
fn odd_but_loadable_gltf2_models() {
    // Texture coordinates in odd places (assimp issue 3269).
    let s = load_no_panic(&gltf2("issue_3269/texcoord_crash.gltf")).unwrap();
    assert!(!s.is_empty() && s.tri_uvs.is_some());
    // Unknown extension objects are ignored.
    assert_eq!(
        load_no_panic(&gltf2("wrongTypes/badExtension.gltf"))
            .unwrap()
            .len(),
        12
    );
    // Zero normals are replaced by face normals, with a warning.
    let s = load_no_panic(&gltf2("BoxBadNormals-glTF-Binary/BoxBadNormals.glb")).unwrap();
    assert!(
        s.tri_normals
            .unwrap()
            .iter()
            .flatten()
            .all(|n| (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0).abs() < 1e-4)
    );
    assert!(!s.warnings.is_empty());
    // A default scene index that names no scene.
    let s = load_no_panic(&gltf2("TestNoRootNode/NoScene.gltf")).unwrap();
    assert!(s.is_empty() && !s.warnings.is_empty());
    // Points and lines are skipped with a warning, triangle modes load.
    for i in 0..16 {
        let s = load_no_panic(&gltf2(&format!(
            "glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_{i:02}.gltf"
        )))
        .unwrap();
        if s.is_empty() {
            assert!(
                s.warnings.iter().any(|w| w.contains("skipped")),
                "{i}: {:?}",
                s.warnings
            );
        } else {
            assert_eq!(s.len(), 2, "{i}");
        }
    }
    // Cameras.
    let s = load_no_panic(&gltf2("cameras/Cameras.gltf")).unwrap();
    assert_eq!(s.cameras.len(), 2);
    assert!(
        s.cameras
            .iter()
            .all(|c| c.position.is_finite() && (c.forward.length() - 1.0).abs() < 1e-5)
    );
}

#[test]
fn two_cylinder_engine() {
    let s = load_no_panic(&gltf2("2CylinderEngine-glTF-Binary/2CylinderEngine.glb")).unwrap();
    assert!(!s.is_empty());
    assert!(s.materials.len() > 1);
    assert!(s.tri_material.iter().any(|&m| m != 0));
    assert!(s.tri_normals.is_some());
    assert!(!s.bounds().is_empty());
}

#[test]
fn box_textured_variants() {
    for rel in [
        "BoxTextured-glTF/BoxTextured.gltf",
        "BoxTextured-glTF-Binary/BoxTextured.glb",
        "BoxTextured-glTF-Embedded/BoxTextured.gltf",
    ] {
        let s = load_no_panic(&gltf2(rel)).unwrap();
        assert_eq!(s.len(), 12, "{rel}");
        assert_eq!(s.textures.len(), 1, "{rel}");
        let t = &s.textures[0];
        assert!(t.width > 0 && t.height > 0);
        assert_eq!(t.rgba8.len(), (t.width * t.height * 4) as usize);
        // Not a blank image.
        assert!(t.rgba8.chunks(4).any(|p| p[..3] != t.rgba8[..3]), "{rel}");
        let textured = s
            .materials
            .iter()
            .position(|m| m.base_color_texture == Some(0))
            .unwrap();
        assert!(
            s.tri_material.iter().all(|&m| m as usize == textured),
            "{rel}"
        );
        let uvs = s.tri_uvs.as_ref().unwrap();
        assert!(
            uvs.iter().flatten().any(|uv| uv[0] != 0.0 || uv[1] != 0.0),
            "{rel}"
        );
        assert!(uvs.iter().flatten().flatten().all(|c| c.is_finite()));
    }
}

#[test]
fn glb_version_1_is_refused_by_name() {
    let p = assimp_models().join("glTF/BoxTextured-glTF-Binary/BoxTextured.glb");
    assert!(matches!(
        load_no_panic(&p),
        Err(SceneError::UnsupportedGltfVersion { .. })
    ));
}

#[test]
fn obj_models() {
    let dir = assimp_models().join("OBJ");
    let s = load_no_panic(&dir.join("spider.obj")).unwrap();
    assert_eq!(s.len(), 1368);
    assert!(s.materials.len() > 1 && s.tri_normals.is_some() && s.tri_uvs.is_some());
    let s = load_no_panic(&dir.join("box.obj")).unwrap();
    assert_eq!(s.len(), 12);
    let e = load_no_panic(&assimp_models().join("invalid/malformed.obj")).unwrap_err();
    assert!(matches!(e, SceneError::Obj { .. }), "{e:?}");
}

#[test]
fn obj_that_is_not_utf8_text_says_so() {
    let e = load_no_panic(&assimp_models().join("OBJ/box_UTF16BE.obj")).unwrap_err();
    assert!(
        matches!(e, SceneError::ObjNotText { utf16: true, .. }) && e.to_string().contains("UTF-16"),
        "{e}"
    );
    let e = load_no_panic(&assimp_models().join("OBJ/regr01.obj")).unwrap_err();
    assert!(matches!(e, SceneError::ObjNotText { .. }), "{e}");
}
