#![allow(clippy::unwrap_used)]
//! Paths that are not regular files: a scene or material library naming a
//! device or a FIFO gives an error or a warning; it never blocks and never
//! reads without end. Found while fuzzing the OBJ loader: `mtllib /dev/zero`
//! allocated until memory ran out, and an `.mtl` that is a FIFO blocked forever.
#![cfg(unix)]

mod common;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use common::write;
use dirt_scene::{Scene, SceneError};

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// Loads on another thread; a load that has not finished after a minute is a
/// hang (the loads here take milliseconds), reported instead of blocking the suite.
fn load_or_hang(path: PathBuf) -> Result<Scene, SceneError> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(dirt_scene::load(&path));
    });
    rx.recv_timeout(Duration::from_secs(60))
        .expect("loading did not finish: it blocks or reads without end")
}

fn mkfifo(p: &Path) {
    let ok = std::process::Command::new("mkfifo")
        .arg(p)
        .status()
        .unwrap()
        .success();
    assert!(ok, "mkfifo {}", p.display());
}

#[test]
fn obj_mtllib_naming_a_device_is_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "a.obj", format!("mtllib /dev/zero\n{TRIANGLE}"));
    let s = load_or_hang(obj).unwrap();
    assert_eq!(s.len(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("/dev/zero") && w.contains("not a regular file")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn obj_mtllib_naming_a_fifo_is_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    mkfifo(&dir.path().join("m.mtl"));
    let obj = write(dir.path(), "a.obj", format!("mtllib m.mtl\n{TRIANGLE}"));
    let s = load_or_hang(obj).unwrap();
    assert_eq!(s.len(), 1);
    assert!(
        s.warnings.iter().any(|w| w.contains("m.mtl")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn scene_path_that_is_a_device_or_fifo_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["z.obj", "z.gltf", "z.glb"] {
        let p = dir.path().join(name);
        std::os::unix::fs::symlink("/dev/zero", &p).unwrap();
        let e = load_or_hang(p).unwrap_err();
        assert!(
            matches!(e, SceneError::Io { .. }) && e.to_string().contains("not a regular file"),
            "{name}: {e}"
        );
    }
    for name in ["f.obj", "f.gltf"] {
        let p = dir.path().join(name);
        mkfifo(&p);
        let e = load_or_hang(p).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{name}: {e}");
    }
    // A directory named like a scene.
    let p = dir.path().join("d.obj");
    std::fs::create_dir(&p).unwrap();
    assert!(load_or_hang(p).is_err());
}

#[test]
fn gltf_buffer_naming_a_device_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let doc =
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"file:///dev/zero","byteLength":12}]}"#;
    let p = write(dir.path(), "a.gltf", doc);
    let e = load_or_hang(p).unwrap_err();
    assert!(matches!(e, SceneError::MissingResource { .. }), "{e}");
}
