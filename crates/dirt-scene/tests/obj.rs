#![allow(clippy::unwrap_used)]
//! OBJ loading on hand-written files.

mod common;

use common::{load_no_panic, write};
use dirt_scene::SceneError;

const OBJ: &str = "mtllib box.mtl
o first
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl glow
f 1/1/1 2/2/1 3/3/1 4/4/1
o second
v 0 0 5
v 1 0 5
v 0 1 5
f 5 6 7
l 5 6
usemtl red
f 5 7 6
";

const MTL: &str = "newmtl red
Kd 0.9 0.1 0.1
newmtl glow
Kd 0.5 0.5 0.5
Ke 2 3 4
";

#[test]
fn order_materials_and_attributes() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "box.mtl", MTL);
    let s = load_no_panic(&write(dir.path(), "box.obj", OBJ)).unwrap();
    let tris: Vec<[[f32; 3]; 3]> = s.triangles.iter().map(|t| t.v).collect();
    assert_eq!(
        tris,
        vec![
            // quad 1 2 3 4 fan-triangulated: (1 2 3), (1 3 4)
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]],
            [[0.0, 0.0, 5.0], [0.0, 1.0, 5.0], [1.0, 0.0, 5.0]],
        ]
    );
    // Materials in .mtl order at k + 1: red = 1, glow = 2.
    assert_eq!(s.materials.len(), 3);
    assert_eq!(s.materials[1].name, "red");
    assert_eq!(s.materials[1].base_color, [0.9, 0.1, 0.1, 1.0]);
    assert_eq!(s.materials[2].emissive, [2.0, 3.0, 4.0]);
    assert_eq!(s.tri_material, vec![2, 2, 2, 1]);
    // UVs flipped to the glTF convention; missing ones are zero.
    let uvs = s.tri_uvs.as_ref().unwrap();
    assert_eq!(uvs[0], [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]);
    assert_eq!(uvs[2], [[0.0; 2]; 3]);
    let ns = s.tri_normals.as_ref().unwrap();
    assert_eq!(ns[0], [[0.0, 0.0, 1.0]; 3]);
    assert_eq!(
        ns[3],
        [[0.0, 0.0, -1.0]; 3],
        "face normal where the OBJ has none"
    );
}

#[test]
fn missing_mtl_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let s = load_no_panic(&write(dir.path(), "box.obj", OBJ)).unwrap();
    assert_eq!(s.len(), 4);
    assert_eq!(s.materials.len(), 1);
    assert!(s.tri_material.iter().all(|&m| m == 0));
    assert!(
        s.warnings.iter().any(|w| w.contains(".mtl")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn broken_obj_files() {
    let dir = tempfile::tempdir().unwrap();
    let r = load_no_panic(&write(dir.path(), "oor.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n"));
    assert!(
        matches!(
            r,
            Err(SceneError::Obj { .. } | SceneError::IndexOutOfRange { .. })
        ),
        "{r:?}"
    );
    let r = load_no_panic(&write(
        dir.path(),
        "inf.obj",
        "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
    ));
    assert!(
        matches!(
            r,
            Err(SceneError::NonFinite { vertex: 1, .. } | SceneError::Obj { .. })
        ),
        "{r:?}"
    );
    let r = load_no_panic(&write(dir.path(), "zero.obj", "v 0 0 0\nf 0 0 0\n"));
    assert!(r.is_err(), "{r:?}");
    let r = dirt_scene::load(&dir.path().join("absent.obj"));
    assert!(matches!(r, Err(SceneError::NotFound { .. })), "{r:?}");
    let s = load_no_panic(&write(dir.path(), "empty.obj", "")).unwrap();
    assert!(s.is_empty());
}
