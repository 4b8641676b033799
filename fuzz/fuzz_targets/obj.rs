//! OBJ bytes into `dirt_scene::load`: an error is fine, a panic is not.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = dirt_scene::load(&common::file_with("f.obj", data)) {
        assert!(scene.validate().is_ok(), "{:?}", scene.validate());
    }
});
