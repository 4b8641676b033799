//! glTF and GLB bytes into `dirt_scene::load`: an error is fine, a panic is
//! not (libFuzzer's panic hook aborts before the loader's own `catch_unwind`).
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The loader takes either container under either extension; name it as a user would.
    let name = if data.starts_with(b"glTF") {
        "f.glb"
    } else {
        "f.gltf"
    };
    if let Ok(scene) = dirt_scene::load(&common::file_with(name, data)) {
        assert!(scene.validate().is_ok(), "{:?}", scene.validate());
    }
});
