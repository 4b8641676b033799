//! The architecture invariants of docs/ARCHITECTURE.md, checked on the
//! sources: which crate may depend on which, where the GPU crate still uses
//! the CPU crate, and one error enum per library crate.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lives in the workspace")
        .to_path_buf()
}

fn crate_dir(name: &str) -> PathBuf {
    match name {
        "dirt-shaders" => root().join("shaders"),
        _ => root().join("crates").join(name),
    }
}

/// Names under `[dependencies]` of a crate's Cargo.toml (not dev- or build-).
fn dependencies(name: &str) -> BTreeSet<String> {
    let text = fs::read_to_string(crate_dir(name).join("Cargo.toml")).expect("Cargo.toml");
    let mut deps = BTreeSet::new();
    let mut inside = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            inside = line == "[dependencies]";
            continue;
        }
        if inside && let Some((key, _)) = line.split_once('=') {
            let key = key.trim().trim_end_matches(".workspace").to_string();
            if !key.is_empty() && !key.starts_with('#') {
                deps.insert(key);
            }
        }
    }
    deps
}

fn dirt_deps(name: &str) -> BTreeSet<String> {
    dependencies(name)
        .into_iter()
        .filter(|d| d.starts_with("dirt-"))
        .collect()
}

fn set(items: &[&str]) -> BTreeSet<String> {
    items.iter().map(|s| s.to_string()).collect()
}

/// Every `.rs` file under a crate's `src/`.
fn sources(name: &str) -> Vec<(PathBuf, String)> {
    fn walk(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
        for entry in fs::read_dir(dir).expect("src dir").flatten() {
            let p = entry.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                let text = fs::read_to_string(&p).expect("source");
                out.push((p, text));
            }
        }
    }
    let mut out = Vec::new();
    walk(&crate_dir(name).join("src"), &mut out);
    out
}

const GPU_CRATES: [&str; 2] = ["wgpu", "naga"];

#[test]
fn the_layers_only_depend_downwards() {
    // Each crate's allowed dirt dependencies: the stack from the bottom up.
    let allowed: &[(&str, &[&str])] = &[
        ("dirt-math", &[]),
        ("dirt-core", &["dirt-math"]),
        ("dirt-scene", &["dirt-math"]),
        ("dirt-cpu", &["dirt-math", "dirt-core"]),
        ("dirt-shaders", &[]),
        ("dirt-gpu", &["dirt-math", "dirt-core", "dirt-shaders"]),
        (
            "dirt-render",
            &[
                "dirt-math",
                "dirt-core",
                "dirt-scene",
                "dirt-cpu",
                "dirt-gpu",
            ],
        ),
        (
            "dirt-view",
            &[
                "dirt-math",
                "dirt-core",
                "dirt-scene",
                "dirt-cpu",
                "dirt-gpu",
                "dirt-render",
            ],
        ),
        (
            "dirt-web",
            &[
                "dirt-math",
                "dirt-core",
                "dirt-scene",
                "dirt-cpu",
                "dirt-gpu",
                "dirt-render",
            ],
        ),
    ];
    for (name, ok) in allowed {
        let extra: Vec<String> = dirt_deps(name).difference(&set(ok)).cloned().collect();
        assert!(
            extra.is_empty(),
            "{name} depends on {extra:?}, above it in the stack"
        );
    }
}

#[test]
fn math_core_cpu_and_scene_know_no_gpu() {
    for name in ["dirt-math", "dirt-core", "dirt-cpu", "dirt-scene"] {
        let deps = dependencies(name);
        for g in GPU_CRATES {
            assert!(!deps.contains(g), "{name} depends on {g}");
        }
    }
}

/// dirt-gpu takes its types from dirt-core and keeps no CPU in the loop: it
/// does not depend on dirt-cpu, and no code of it names it (comments may, to
/// say which CPU stage a pass mirrors).
#[test]
fn the_gpu_crate_needs_no_cpu_crate() {
    assert!(!dirt_deps("dirt-gpu").contains("dirt-cpu"));
    for (path, text) in sources("dirt-gpu") {
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            let code = code.split('`').step_by(2).collect::<String>();
            assert!(
                !code.contains("dirt_cpu::"),
                "{}:{}: dirt-gpu uses dirt-cpu: {}",
                path.display(),
                n + 1,
                line.trim()
            );
        }
    }
}

/// The window is the viewer's alone: no other crate pulls in winit.
#[test]
fn only_the_viewer_knows_winit() {
    for name in [
        "dirt-math",
        "dirt-core",
        "dirt-scene",
        "dirt-cpu",
        "dirt-gpu",
        "dirt-shaders",
        "dirt-render",
        "dirt-eval",
        "dirt-web",
        "dirt-cli",
    ] {
        assert!(
            !dependencies(name).contains("winit"),
            "{name} depends on winit"
        );
    }
    assert!(dependencies("dirt-view").contains("winit"));
}

#[test]
fn each_library_crate_has_one_error_enum() {
    for name in [
        "dirt-math",
        "dirt-core",
        "dirt-scene",
        "dirt-cpu",
        "dirt-gpu",
        "dirt-shaders",
        "dirt-render",
        "dirt-eval",
        "dirt-view",
        "dirt-web",
        "dirt-cli",
    ] {
        let derives: usize = sources(name)
            .iter()
            .map(|(_, text)| text.matches("thiserror::Error)]").count())
            .sum();
        assert_eq!(
            derives, 1,
            "{name} has {derives} thiserror error enums; one per library crate"
        );
    }
}

/// `create_buffer_init` panics on a lost device; the library crates make
/// their buffers with `dirt_gpu::buffer_init` (the queue writes them), so a
/// lost device is an error (ARCHITECTURE, "Faults are errors").
#[test]
fn no_library_crate_creates_a_buffer_that_panics_on_a_lost_device() {
    for name in [
        "dirt-gpu",
        "dirt-render",
        "dirt-eval",
        "dirt-view",
        "dirt-web",
        "dirt-cli",
    ] {
        for (path, text) in sources(name) {
            let calls = text
                .lines()
                .map(|line| line.split("//").next().unwrap_or(""))
                .filter(|code| code.contains("create_buffer_init"))
                .count();
            assert_eq!(calls, 0, "{} calls create_buffer_init", path.display());
        }
    }
}
