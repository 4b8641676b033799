//! `.npy` bytes into the rays reader of `dirt trace`: an error is fine, a
//! panic is not, and every ray it accepts is valid.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.npy");
    if let Ok(rays) = dirt_cli::npy::read_rays_from(data, path) {
        assert!(rays.iter().all(|r| r.validate().is_ok()));
    }
});
