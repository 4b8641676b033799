#![allow(clippy::unwrap_used)]
//! glTF loading: the flattened order, transforms, materials, cameras and
//! lights on hand-written files, and the error for each kind of breakage.

mod common;

use std::path::{Path, PathBuf};

use common::{data_uri, f32_bytes, glb, load_no_panic, write};
use dirt_scene::{CameraKind, LightKind, Scene, SceneError, Vec3};

const P: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 2.0, 0.0],
];
const S: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The buffer of the order test (144 bytes) and its JSON without the
/// buffer's `uri`, which `@BUFFER@` stands for.
fn order_doc() -> (Vec<u8>, String) {
    let mut buf = f32_bytes(&P.concat()); // view 0: positions, 0..60
    buf.extend(f32_bytes(&[[S, S, 0.0]; 5].concat())); // view 1: normals, 60..120
    buf.extend([0u8, 1, 2, 3, 4, 0, 0, 0]); // view 2: strip u8, 120..125
    buf.extend([4u8, 0, 1, 2]); // view 3: fan u8, 128..132
    buf.extend([0u8, 0, 3, 0, 4, 0, 0, 0]); // view 4: triangles u16, 132..138
    buf.extend([0u8, 1, 0, 0]); // view 5: lines u8, 140..142
    assert_eq!(buf.len(), 144);
    let json = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission"],
  "scene": 1,
  "scenes": [{"nodes": [3]}, {"nodes": [0, 3]}],
  "nodes": [
    {"name": "root", "translation": [10, 0, 0], "children": [1, 2], "camera": 0},
    {"name": "scaled", "scale": [2, 2, 2], "mesh": 0},
    {"translation": [0, 5, 0], "scale": [1, 4, 1], "mesh": 1, "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"mesh": 1, "children": [4]},
    {"rotation": [0, 0.70710677, 0, 0.70710677], "camera": 1}
  ],
  "cameras": [
    {"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}},
    {"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.01, "zfar": 50}}
  ],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "spot", "color": [1, 0.5, 0.25], "intensity": 5, "range": 20, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}
  ]}},
  "materials": [
    {"name": "m0", "emissiveFactor": [1, 0.5, 0.25], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}},
    {"name": "m1", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.3, 1], "metallicFactor": 0.5, "roughnessFactor": 0.25},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.75}}}
  ],
  "meshes": [
    {"primitives": [
      {"attributes": {"POSITION": 0}, "indices": 2, "mode": 5, "material": 1},
      {"attributes": {"POSITION": 0}, "indices": 5, "mode": 1},
      {"attributes": {"POSITION": 0}, "indices": 3, "mode": 6}
    ]},
    {"name": "two", "primitives": [
      {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 4, "material": 0},
      {"attributes": {"POSITION": 0}}
    ]}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [0, 0, 0], "max": [1, 2, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5121, "count": 5, "type": "SCALAR"},
    {"bufferView": 3, "componentType": 5121, "count": 4, "type": "SCALAR"},
    {"bufferView": 4, "componentType": 5123, "count": 3, "type": "SCALAR"},
    {"bufferView": 5, "componentType": 5121, "count": 2, "type": "SCALAR"}
  ],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 60},
    {"buffer": 0, "byteOffset": 60, "byteLength": 60},
    {"buffer": 0, "byteOffset": 120, "byteLength": 5},
    {"buffer": 0, "byteOffset": 128, "byteLength": 4},
    {"buffer": 0, "byteOffset": 132, "byteLength": 6},
    {"buffer": 0, "byteOffset": 140, "byteLength": 2}
  ],
  "buffers": [{@BUFFER@"byteLength": 144}]
}"#;
    (buf, json.to_string())
}

fn v(p: [f32; 3], scale: [f32; 3], offset: [f32; 3]) -> [f32; 3] {
    [
        p[0] * scale[0] + offset[0],
        p[1] * scale[1] + offset[1],
        p[2] * scale[2] + offset[2],
    ]
}

fn check_order_scene(s: &Scene) {
    let n1 = |i: usize| v(P[i], [2.0; 3], [10.0, 0.0, 0.0]); // node 1: T(10,0,0) * S(2)
    let n2 = |i: usize| v(P[i], [1.0, 4.0, 1.0], [10.0, 5.0, 0.0]); // node 2: T(10,0,0) * T(0,5,0) * S(1,4,1)
    let n3 = |i: usize| P[i]; // node 3: identity
    let expected: Vec<[[f32; 3]; 3]> = vec![
        // node 1, mesh 0, primitive 0: strip 0 1 2 3 4 with alternating winding
        [n1(0), n1(1), n1(2)],
        [n1(1), n1(3), n1(2)],
        [n1(2), n1(3), n1(4)],
        // primitive 1 (lines) skipped; primitive 2: fan 4 0 1 2
        [n1(0), n1(1), n1(4)],
        [n1(1), n1(2), n1(4)],
        // node 2, mesh 1: u16 triangles 0 3 4, then non-indexed (5 vertices: one triangle)
        [n2(0), n2(3), n2(4)],
        [n2(0), n2(1), n2(2)],
        // node 3 (second root), mesh 1 again
        [n3(0), n3(3), n3(4)],
        [n3(0), n3(1), n3(2)],
    ];
    let got: Vec<[[f32; 3]; 3]> = s.triangles.iter().map(|t| t.v).collect();
    assert_eq!(got, expected);
    assert_eq!(s.tri_material, vec![2, 2, 2, 0, 0, 1, 0, 1, 0]);

    // Materials: default at 0, glTF material k at k + 1.
    assert_eq!(s.materials.len(), 3);
    assert_eq!(s.materials[0], dirt_scene::Material::default());
    assert_eq!(s.materials[1].name, "m0");
    assert_eq!(s.materials[1].emissive, [4.0, 2.0, 1.0]);
    assert_eq!(s.materials[2].name, "m1");
    assert_eq!(s.materials[2].base_color, [0.1, 0.2, 0.3, 1.0]);
    assert_eq!(
        (s.materials[2].metallic, s.materials[2].roughness),
        (0.5, 0.25)
    );
    assert_eq!(s.materials[2].transmission, 0.75);

    // Normals: inverse-transpose of S(1,4,1) for node 2, identity for node 3,
    // face normals where the primitive has none.
    let ns = s.tri_normals.as_ref().unwrap();
    let want = Vec3::new(1.0, 0.25, 0.0).normalize();
    for n in ns[5] {
        assert!((Vec3::from_array(n) - want).length() < 1e-6, "{n:?}");
    }
    for n in ns[7] {
        assert!(
            (Vec3::from_array(n) - Vec3::new(S, S, 0.0)).length() < 1e-6,
            "{n:?}"
        );
    }
    assert_eq!(ns[0], [[0.0, 0.0, 1.0]; 3]);
    assert_eq!(
        ns[1],
        [[0.0, 0.0, 1.0]; 3],
        "odd strip triangles keep the strip's facing"
    );
    assert!(s.tri_uvs.is_none());

    // Cameras in traversal order: node 0 then node 4.
    assert_eq!(s.cameras.len(), 2);
    let c = &s.cameras[0];
    assert_eq!(c.position, Vec3::new(10.0, 0.0, 0.0));
    assert_eq!((c.forward, c.up), (Vec3::NEG_Z, Vec3::Y));
    assert_eq!(
        (c.yfov_radians, c.aspect, c.znear, c.zfar),
        (0.8, Some(1.5), 0.1, Some(100.0))
    );
    assert_eq!(c.kind, CameraKind::Perspective);
    let c = &s.cameras[1];
    assert!(c.position.length() < 1e-6);
    assert!((c.forward - Vec3::NEG_X).length() < 1e-6, "{}", c.forward);
    assert!((c.up - Vec3::Y).length() < 1e-6);
    assert_eq!(
        c.kind,
        CameraKind::Orthographic {
            xmag: 2.0,
            ymag: 1.0
        }
    );

    // The spot light on node 2.
    assert_eq!(s.lights.len(), 1);
    let l = &s.lights[0];
    assert_eq!(
        l.kind,
        LightKind::Spot {
            inner_cone: 0.1,
            outer_cone: 0.5
        }
    );
    assert_eq!(l.position, Vec3::new(10.0, 5.0, 0.0));
    assert!((l.direction - Vec3::NEG_Z).length() < 1e-6);
    assert_eq!(
        (l.color, l.intensity, l.range),
        ([1.0, 0.5, 0.25], 5.0, Some(20.0))
    );

    assert!(
        s.warnings.iter().any(|w| w.contains("Lines")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("not a multiple of 3")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn flattened_order_gltf_with_data_uri() {
    let dir = tempfile::tempdir().unwrap();
    let (buf, json) = order_doc();
    let json = json.replace("@BUFFER@", &format!("\"uri\": \"{}\", ", data_uri(&buf)));
    let path = write(dir.path(), "order.gltf", json);
    let s = load_no_panic(&path).unwrap();
    assert_eq!(s.name, "order");
    check_order_scene(&s);
}

#[test]
fn flattened_order_gltf_with_external_bin_and_escaped_uri() {
    let dir = tempfile::tempdir().unwrap();
    let (buf, json) = order_doc();
    write(dir.path(), "my data.bin", &buf);
    let json = json.replace("@BUFFER@", "\"uri\": \"my%20data.bin\", ");
    let path = write(dir.path(), "order.gltf", json);
    check_order_scene(&load_no_panic(&path).unwrap());
}

#[test]
fn flattened_order_glb() {
    let dir = tempfile::tempdir().unwrap();
    let (buf, json) = order_doc();
    let path = write(
        dir.path(),
        "order.glb",
        glb(&json.replace("@BUFFER@", ""), &buf),
    );
    check_order_scene(&load_no_panic(&path).unwrap());
}

/// The same documents from bytes in memory, as a web page hands a dropped
/// file: a GLB and a `.gltf` with data URIs load as from disk; an external
/// URI, which bytes cannot reach, is a named error; garbage is an error.
#[test]
fn scenes_from_bytes_in_memory() {
    let (buf, json) = order_doc();
    let from_glb =
        dirt_scene::load_gltf_bytes("order.glb", glb(&json.replace("@BUFFER@", ""), &buf))
            .expect("a GLB from bytes");
    assert_eq!(from_glb.name, "order");
    check_order_scene(&from_glb);
    let with_uri = json.replace("@BUFFER@", &format!("\"uri\": \"{}\", ", data_uri(&buf)));
    let from_json = dirt_scene::load_gltf_bytes("order.gltf", with_uri.clone().into_bytes())
        .expect("a .gltf with data URIs from bytes");
    check_order_scene(&from_json);
    // The same scene as from a file, triangle for triangle.
    let dir = tempfile::tempdir().unwrap();
    let from_file = load_no_panic(&write(dir.path(), "order.gltf", &with_uri)).unwrap();
    assert_eq!(from_json.triangles, from_file.triangles);
    let animated =
        dirt_scene::load_animated_bytes("order.gltf", with_uri.into_bytes()).expect("animated");
    assert!(!animated.is_animated());
    assert_eq!(animated.scene.triangles, from_file.triangles);

    let external = json.replace("@BUFFER@", "\"uri\": \"order.bin\", ");
    match dirt_scene::load_gltf_bytes("order.gltf", external.into_bytes()) {
        Err(SceneError::BadResource {
            path,
            what,
            problem,
        }) => {
            assert_eq!(path, PathBuf::from("order.gltf"));
            assert!(what.contains("buffer 0"), "{what}");
            assert!(problem.contains("from bytes"), "{problem}");
        }
        other => panic!("expected BadResource, got {:?}", other.map(|s| s.name)),
    }
    for garbage in [
        &b""[..],
        b"glTF\x02\x00\x00\x00",
        b"{ not json",
        &[0xff; 64],
    ] {
        assert!(dirt_scene::load_gltf_bytes("x.glb", garbage.to_vec()).is_err());
    }
}

// ---------------------------------------------------------------------------
// Small one-primitive documents for the error cases.

/// A document with one node, one mesh, one primitive. `buf` becomes buffer
/// 0 (data URI) with a single view 0 over all of it; `accessors` and
/// `primitive` are JSON.
fn one_prim(buf: &[u8], accessors: &str, primitive: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"name": "M", "primitives": [{primitive}]}}],
  "accessors": {accessors},
  "bufferViews": [{{"buffer": 0, "byteLength": {len}}}],
  "buffers": [{{"uri": "{uri}", "byteLength": {len}}}]}}"#,
        len = buf.len(),
        uri = data_uri(buf)
    )
}

fn load_str(name: &str, json: &str) -> (tempfile::TempDir, PathBuf, Result<Scene, SceneError>) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), name, json);
    let r = load_no_panic(&path);
    (dir, path, r)
}

const POS3: &str = r#"{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}"#;

fn tri_buf(extra: &[u8]) -> Vec<u8> {
    let mut b = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    b.extend(extra);
    b
}

#[test]
fn index_out_of_range_names_mesh_primitive_and_index() {
    let buf = tri_buf(&[0, 1, 7, 0]);
    let acc = format!(
        r#"[{POS3}, {{"bufferView": 0, "byteOffset": 36, "componentType": 5121, "count": 3, "type": "SCALAR"}}]"#
    );
    let (_d, _p, r) = load_str(
        "oor.gltf",
        &one_prim(
            &buf,
            &acc,
            r#"{"attributes": {"POSITION": 0}, "indices": 1}"#,
        ),
    );
    match r {
        Err(
            e @ SceneError::IndexOutOfRange {
                index: 7,
                position: 2,
                vertex_count: 3,
                ..
            },
        ) => {
            let msg = e.to_string();
            assert!(
                msg.contains("mesh 0 'M' primitive 0") && msg.contains("index 7"),
                "{msg}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn non_finite_positions_are_rejected() {
    let buf = f32_bytes(&[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let (_d, _p, r) = load_str(
        "nan.gltf",
        &one_prim(
            &buf,
            &format!("[{POS3}]"),
            r#"{"attributes": {"POSITION": 0}}"#,
        ),
    );
    assert!(
        matches!(r, Err(SceneError::NonFinite { vertex: 1, .. })),
        "{r:?}"
    );

    // Finite in the file, infinite after the node transform.
    let buf = tri_buf(&[]);
    let json = one_prim(&buf, &format!("[{POS3}]"), r#"{"attributes": {"POSITION": 0}}"#)
        .replace(r#""nodes": [{"mesh": 0}]"#, r#""nodes": [{"mesh": 0, "scale": [3e38, 3e38, 3e38], "children": [1]}, {"mesh": 0, "scale": [10, 10, 10]}]"#);
    let (_d, _p, r) = load_str("overflow.gltf", &json);
    assert!(
        matches!(
            r,
            Err(SceneError::NonFiniteTransform { .. } | SceneError::NonFinite { .. })
        ),
        "{r:?}"
    );
}

#[test]
fn wrong_accessor_types_and_counts_are_rejected() {
    let buf = tri_buf(&f32_bytes(&[0.0, 1.0, 2.0]));
    // Float indices.
    let acc = format!(
        r#"[{POS3}, {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "SCALAR"}}]"#
    );
    let (_d, _p, r) = load_str(
        "fidx.gltf",
        &one_prim(
            &buf,
            &acc,
            r#"{"attributes": {"POSITION": 0}, "indices": 1}"#,
        ),
    );
    assert!(
        matches!(&r, Err(SceneError::Accessor { attribute, .. }) if attribute == "indices"),
        "{r:?}"
    );

    // VEC2 positions.
    let acc = r#"[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"}]"#;
    let (_d, _p, r) = load_str(
        "vec2.gltf",
        &one_prim(&buf, acc, r#"{"attributes": {"POSITION": 0}}"#),
    );
    assert!(
        matches!(&r, Err(SceneError::Accessor { attribute, .. }) if attribute == "POSITION"),
        "{r:?}"
    );

    // NORMAL with fewer elements than POSITION.
    let acc = format!(
        r#"[{POS3}, {{"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"}}]"#
    );
    let (_d, _p, r) = load_str(
        "ncount.gltf",
        &one_prim(
            &buf,
            &acc,
            r#"{"attributes": {"POSITION": 0, "NORMAL": 1}}"#,
        ),
    );
    assert!(
        matches!(&r, Err(SceneError::Accessor { attribute, .. }) if attribute == "NORMAL"),
        "{r:?}"
    );

    // An accessor reading past the end of its view.
    let acc = r#"[{"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}]"#;
    let (_d, _p, r) = load_str(
        "past.gltf",
        &one_prim(&buf, acc, r#"{"attributes": {"POSITION": 0}}"#),
    );
    assert!(
        matches!(&r, Err(SceneError::Accessor { problem, .. }) if problem.contains("need")),
        "{r:?}"
    );

    // A stride smaller than the element.
    let json = one_prim(
        &buf,
        &format!("[{POS3}]"),
        r#"{"attributes": {"POSITION": 0}}"#,
    )
    .replace(
        r#""bufferViews": [{"buffer": 0,"#,
        r#""bufferViews": [{"buffer": 0, "byteStride": 4,"#,
    );
    let (_d, _p, r) = load_str("stride.gltf", &json);
    assert!(
        matches!(&r, Err(SceneError::Accessor { problem, .. }) if problem.contains("stride")),
        "{r:?}"
    );
}

#[test]
fn broken_buffers_and_views_are_rejected_by_name() {
    let buf = tri_buf(&[]);
    let good = one_prim(
        &buf,
        &format!("[{POS3}]"),
        r#"{"attributes": {"POSITION": 0}}"#,
    );

    // A view past the end of the buffer.
    let json = good.replace(
        r#""bufferViews": [{"buffer": 0, "byteLength": 36}]"#,
        r#""bufferViews": [{"buffer": 0, "byteOffset": 8, "byteLength": 36}]"#,
    );
    let (_d, _p, r) = load_str("view.gltf", &json);
    assert!(
        matches!(&r, Err(SceneError::BadResource { what, .. }) if what == "buffer view 0"),
        "{r:?}"
    );

    // A missing external buffer.
    let uri = data_uri(&buf);
    let (_d, p, r) = load_str("missing.gltf", &good.replace(&uri, "nothere.bin"));
    match r {
        Err(SceneError::MissingResource { resolved, .. }) => {
            assert_eq!(resolved, p.parent().unwrap().join("nothere.bin"))
        }
        other => panic!("{other:?}"),
    }

    // A URI that percent-decodes to invalid UTF-8 (the gltf crate would panic).
    let (_d, _p, r) = load_str("utf8.gltf", &good.replace(&uri, "%FF%FE.bin"));
    assert!(matches!(r, Err(SceneError::BadResource { .. })), "{r:?}");

    // An unsupported URI scheme.
    let (_d, _p, r) = load_str(
        "http.gltf",
        &good.replace(&uri, "http://example.invalid/a.bin"),
    );
    assert!(matches!(r, Err(SceneError::BadResource { .. })), "{r:?}");

    // A buffer shorter than its byteLength.
    let (_d, _p, r) = load_str("short.gltf", &good.replace(&uri, &data_uri(&buf[..20])));
    assert!(matches!(r, Err(SceneError::Gltf { .. })), "{r:?}");
}

#[test]
fn node_graphs() {
    let buf = tri_buf(&[]);
    let good = one_prim(
        &buf,
        &format!("[{POS3}]"),
        r#"{"attributes": {"POSITION": 0}}"#,
    );

    // A node that is its own child.
    let json = good.replace(
        r#""nodes": [{"mesh": 0}]"#,
        r#""nodes": [{"mesh": 0, "children": [0]}]"#,
    );
    let (_d, _p, r) = load_str("self.gltf", &json);
    assert!(
        matches!(r, Err(SceneError::RecursiveNodes { node: 0, .. })),
        "{r:?}"
    );

    // A longer cycle below the root.
    let json = good.replace(
        r#""nodes": [{"mesh": 0}]"#,
        r#""nodes": [{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [1]}]"#,
    );
    let (_d, _p, r) = load_str("cycle.gltf", &json);
    assert!(
        matches!(r, Err(SceneError::RecursiveNodes { node: 1, .. })),
        "{r:?}"
    );

    // A node shared by two parents is instanced twice (not a cycle).
    let json = good.replace(
        r#""scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}]"#,
        r#""scenes": [{"nodes": [1, 2]}],
  "nodes": [{"mesh": 0}, {"children": [0], "translation": [5, 0, 0]}, {"children": [0]}]"#,
    );
    let (_d, _p, r) = load_str("dag.gltf", &json);
    let s = r.unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!(s.triangles[0].v[0], [5.0, 0.0, 0.0]);
    assert_eq!(s.triangles[1].v[0], [0.0, 0.0, 0.0]);

    // Deep hierarchies do not overflow the stack.
    let depth = 100_000;
    let nodes: Vec<String> = (0..depth)
        .map(|i| {
            if i + 1 < depth {
                format!(r#"{{"children": [{}]}}"#, i + 1)
            } else {
                r#"{"mesh": 0}"#.to_string()
            }
        })
        .collect();
    let json = good.replace(
        r#""nodes": [{"mesh": 0}]"#,
        &format!(r#""nodes": [{}]"#, nodes.join(",")),
    );
    let (_d, _p, r) = load_str("deep.gltf", &json);
    assert_eq!(r.unwrap().len(), 1);

    // No scenes: all root nodes in index order.
    let json = good.replace(r#""scene": 0, "scenes": [{"nodes": [0]}],"#, "").replace(
        r#""nodes": [{"mesh": 0}]"#,
        r#""nodes": [{"children": [2], "translation": [1, 0, 0]}, {"mesh": 0, "translation": [2, 0, 0]}, {"mesh": 0}]"#,
    );
    let (_d, _p, r) = load_str("noscene.gltf", &json);
    let s = r.unwrap();
    let xs: Vec<f32> = s.triangles.iter().map(|t| t.v[0][0]).collect();
    assert_eq!(xs, vec![1.0, 2.0]);
}

#[test]
fn sparse_and_quantized_accessors() {
    // Base positions from the view, vertex 2 replaced through a sparse block;
    // TEXCOORD_0 as normalised u8.
    let mut buf = tri_buf(&[]);
    buf.extend([2u8, 0, 0, 0]); // sparse index (u8) at 36
    buf.extend(f32_bytes(&[5.0, 6.0, 7.0])); // sparse value at 40
    buf.extend([0u8, 255, 255, 0, 51, 102, 0, 0]); // uv u8 normalised at 52
    let acc = r#"[
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [5,6,7],
       "sparse": {"count": 1, "indices": {"bufferView": 0, "byteOffset": 36, "componentType": 5121},
                  "values": {"bufferView": 0, "byteOffset": 40}}},
      {"bufferView": 0, "byteOffset": 52, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"}
    ]"#;
    let (_d, _p, r) = load_str(
        "sparse.gltf",
        &one_prim(
            &buf,
            acc,
            r#"{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}"#,
        ),
    );
    let s = r.unwrap();
    assert_eq!(
        s.triangles[0].v,
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [5.0, 6.0, 7.0]]
    );
    assert_eq!(s.tri_uvs.unwrap()[0], [[0.0, 1.0], [1.0, 0.0], [0.2, 0.4]]);
    assert!(s.tri_normals.is_none());
}

#[test]
fn file_level_errors() {
    let dir = tempfile::tempdir().unwrap();
    let r = dirt_scene::load(&dir.path().join("a.fbx"));
    assert!(
        matches!(&r, Err(e @ SceneError::UnsupportedExtension { extension, .. }) if extension == "fbx" && e.to_string().contains("\"fbx\"")),
        "{r:?}"
    );
    let r = dirt_scene::load(&dir.path().join("noext"));
    assert!(
        matches!(r, Err(SceneError::UnsupportedExtension { .. })),
        "{r:?}"
    );
    let r = dirt_scene::load(&dir.path().join("absent.glb"));
    assert!(
        matches!(&r, Err(e @ SceneError::NotFound { .. }) if e.to_string().contains("absent.glb")),
        "{r:?}"
    );
    let r = dirt_scene::load(Path::new("/"));
    assert!(
        matches!(r, Err(SceneError::UnsupportedExtension { .. })),
        "{r:?}"
    );
    let p = write(
        dir.path(),
        "v1.gltf",
        r#"{"asset": {"version": "1.0"}, "meshes": {}}"#,
    );
    assert!(matches!(
        load_no_panic(&p),
        Err(SceneError::UnsupportedGltfVersion { .. })
    ));
    let p = write(dir.path(), "junk.GLTF", "not json");
    assert!(matches!(load_no_panic(&p), Err(SceneError::Gltf { .. })));
    let p = write(dir.path(), "empty.gltf", r#"{"asset": {"version": "2.0"}}"#);
    let s = load_no_panic(&p).unwrap();
    assert!(s.is_empty() && s.materials.len() == 1);
}
