//! Helpers shared by the integration tests.
#![allow(clippy::unwrap_used)]
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Where Debian's `assimp-testmodels` package installs its models. CI
/// installs the package; without it the tests that need it fail (loudly)
/// rather than pass vacuously.
pub fn assimp_models() -> PathBuf {
    let dir = PathBuf::from("/usr/share/assimp/models");
    assert!(
        dir.join("glTF2").is_dir(),
        "{} is missing: install the Debian/Ubuntu package `assimp-testmodels` \
         (apt-get install assimp-testmodels); these tests need its malformed models",
        dir.display()
    );
    dir
}

/// Standard base64 with padding (for `data:` URIs).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A `data:` URI holding `bytes`.
pub fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64(bytes))
}

pub fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

/// Little-endian f32s.
pub fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Loads `path`, asserting that the loader neither panics nor reports an
/// internal (caught panic) error.
pub fn load_no_panic(path: &Path) -> Result<dirt_scene::Scene, dirt_scene::SceneError> {
    let r = std::panic::catch_unwind(|| dirt_scene::load(path));
    let r = match r {
        Ok(r) => r,
        Err(_) => panic!("loading {} panicked", path.display()),
    };
    if let Err(e @ dirt_scene::SceneError::Internal { .. }) = &r {
        panic!("loading {} hit a caught panic: {e}", path.display());
    }
    if let Ok(s) = &r {
        s.validate()
            .unwrap_or_else(|e| panic!("{}: invariant broken: {e}", path.display()));
    }
    animate_no_panic(path);
    r
}

/// Loads `path` with its animations and poses it at a few times, asserting
/// that nothing panics and that every pose keeps the scene's invariants.
pub fn animate_no_panic(path: &Path) {
    let r = std::panic::catch_unwind(|| {
        let mut s = dirt_scene::load_animated(path)?;
        for t in [0.0, 0.3, 1.0, 1e9, -1.0] {
            s.pose(t)?;
            s.scene
                .validate()
                .unwrap_or_else(|e| panic!("{}: pose at {t}: {e}", path.display()));
        }
        Ok::<_, dirt_scene::SceneError>(())
    });
    match r {
        Ok(Err(e @ dirt_scene::SceneError::Internal { .. })) => {
            panic!("animating {} hit a caught panic: {e}", path.display())
        }
        Ok(_) => {}
        Err(_) => panic!("animating {} panicked", path.display()),
    }
}

/// Packs JSON and a BIN chunk into a GLB container.
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(b);
    out
}
