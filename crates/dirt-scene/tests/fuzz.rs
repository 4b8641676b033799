#![allow(clippy::unwrap_used)]
//! Random and mutated bytes never make the loaders panic.

mod common;

use common::{assimp_models, data_uri, f32_bytes, glb, load_no_panic, write};
use proptest::prelude::*;

/// A small document using most features; `with_image` adds an image whose
/// bytes are not a PNG (so that document fails at decoding).
fn seed_gltf(with_image: bool) -> String {
    let doc = valid_gltf();
    if with_image {
        return doc;
    }
    doc.replace(
        r#""pbrMetallicRoughness":{"baseColorTexture":{"index":0}}"#,
        r#""doubleSided":true"#,
    )
    .replace(
        r#""textures":[{"source":0}],"images":[{"bufferView":0,"mimeType":"image/png"}],"#,
        "",
    )
}

fn valid_gltf() -> String {
    let mut buf = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    buf.extend([0u8, 1, 2, 0]); // indices at 36
    buf.extend(f32_bytes(&[5.0, 6.0, 7.0])); // sparse value at 40
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"extensionsUsed":["KHR_lights_punctual"],
"nodes":[{{"mesh":0,"children":[1],"camera":0}},{{"mesh":1,"rotation":[0,0,0,1],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":1,"znear":0.1}}}}],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"spot","spot":{{}}}}]}}}},
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":0,"TEXCOORD_0":3}},"indices":1,"mode":4,"material":0}}]}},
{{"primitives":[{{"attributes":{{"POSITION":2}},"indices":1,"mode":5}},{{"attributes":{{"POSITION":2}},"mode":6}}]}}],
"materials":[{{"emissiveFactor":[1,1,1],"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{{"bufferView":0,"mimeType":"image/png"}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5121,"count":3,"type":"SCALAR"}},
{{"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[5,6,7],
 "sparse":{{"count":1,"indices":{{"bufferView":1,"byteOffset":2,"componentType":5121}},"values":{{"bufferView":2}}}}}},
{{"bufferView":0,"componentType":5121,"normalized":true,"count":3,"type":"VEC2"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":3}},{{"buffer":0,"byteOffset":40,"byteLength":12}}],
"buffers":[{{"uri":"{}","byteLength":52}}]}}"#,
        data_uri(&buf)
    )
}

/// `seed_gltf(false)` as GLB, its buffer moved into the BIN chunk.
fn seed_glb() -> Vec<u8> {
    let json = seed_gltf(false);
    let uri_start = json.find("\"uri\"").unwrap();
    let uri_end = uri_start + json[uri_start..].find("\",").unwrap() + 2;
    let json = format!("{}{}", &json[..uri_start], &json[uri_end..]);
    let mut bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([0u8, 1, 2, 0]);
    bin.extend(f32_bytes(&[5.0, 6.0, 7.0]));
    glb(&json, &bin)
}

const VALID_OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -1 -2 -3\n";

/// Applies `(position, kind, byte)` edits: kind 0 replaces, 1 inserts, 2
/// deletes the byte at `position % len`.
fn mutate(base: &[u8], edits: &[(usize, u8, u8)]) -> Vec<u8> {
    let mut b = base.to_vec();
    for &(pos, kind, byte) in edits {
        if b.is_empty() {
            break;
        }
        let i = pos % b.len();
        match kind % 3 {
            0 => b[i] = byte,
            1 => b.insert(i, byte),
            _ => {
                b.remove(i);
            }
        }
    }
    b
}

/// Bytes likely to matter in JSON / OBJ numbers and structure.
fn interesting_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        any::<u8>(),
        prop::sample::select(b"0123456789-.e,:[]{}\"/ \nfv%".to_vec())
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes(bytes in prop::collection::vec(any::<u8>(), 0..512), ext in prop::sample::select(vec!["gltf", "glb", "obj"])) {
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), &format!("f.{ext}"), &bytes));
    }

    #[test]
    fn random_glb_body(bytes in prop::collection::vec(any::<u8>(), 0..256), version in 0u32..4) {
        let mut b = b"glTF".to_vec();
        b.extend(version.to_le_bytes());
        b.extend(((bytes.len() + 12) as u32).to_le_bytes());
        b.extend(bytes);
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), "f.glb", &b));
    }

    #[test]
    fn mutated_gltf(edits in prop::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..6), image in any::<bool>()) {
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), "f.gltf", mutate(seed_gltf(image).as_bytes(), &edits)));
    }

    #[test]
    fn mutated_glb(edits in prop::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..6)) {
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), "f.glb", mutate(&seed_glb(), &edits)));
    }

    #[test]
    fn mutated_skin(edits in prop::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..6)) {
        let seed = std::fs::read(assimp_models().join("glTF2/simple_skin/simple_skin.gltf")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), "f.gltf", mutate(&seed, &edits)));
    }

    #[test]
    fn mutated_obj(edits in prop::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..6)) {
        let dir = tempfile::tempdir().unwrap();
        let _ = load_no_panic(&write(dir.path(), "f.obj", mutate(VALID_OBJ.as_bytes(), &edits)));
    }
}

#[test]
fn the_fuzz_seeds_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    let r = load_no_panic(&write(dir.path(), "f.gltf", seed_gltf(true)));
    // The image in buffer view 0 is not a PNG: the seed is valid up to that.
    assert!(
        matches!(r, Err(dirt_scene::SceneError::Gltf { .. })),
        "{r:?}"
    );
    let s = load_no_panic(&write(dir.path(), "g.gltf", seed_gltf(false))).unwrap();
    assert_eq!(s.len(), 1 + 1 + 1);
    assert_eq!(s.triangles[1].v[2], [5.0, 6.0, 7.0]);
    assert_eq!((s.cameras.len(), s.lights.len()), (1, 1));
    let g = load_no_panic(&write(dir.path(), "g.glb", seed_glb())).unwrap();
    assert_eq!(g.triangles, s.triangles);
    let s = load_no_panic(&write(dir.path(), "f.obj", VALID_OBJ)).unwrap();
    assert_eq!(s.len(), 3);
}
