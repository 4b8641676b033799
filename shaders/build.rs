//! Embeds every `wgsl/*.wgsl` file of this crate: writes `$OUT_DIR/wgsl_files.rs`,
//! a table of `(module name, include_str!(absolute path))` sorted by name.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::{env, fs};

fn main() {
    let manifest_dir =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let wgsl_dir = manifest_dir.join("wgsl");
    // A directory's mtime changes when a file is added, removed or renamed in it.
    println!("cargo:rerun-if-changed={}", wgsl_dir.display());

    let mut files: Vec<(String, PathBuf)> = Vec::new();
    if wgsl_dir.is_dir() {
        for entry in fs::read_dir(&wgsl_dir).expect("read shaders/wgsl") {
            let path = entry.expect("read shaders/wgsl entry").path();
            if !path.is_file() || path.extension().and_then(|e| e.to_str()) != Some("wgsl") {
                continue;
            }
            let name = module_name(&path);
            println!("cargo:rerun-if-changed={}", path.display());
            files.push((name, path));
        }
    }
    files.sort();

    let mut out = String::from(
        "/// Every `wgsl/*.wgsl` file of the crate: (module name, source), sorted by name.\n\
         pub static FILES: &[(&str, &str)] = &[\n",
    );
    for (name, path) in &files {
        let path = path.to_str().expect("shaders/wgsl path is UTF-8");
        writeln!(out, "    ({name:?}, include_str!({path:?})),").expect("write to String");
    }
    out.push_str("];\n");

    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out_dir.join("wgsl_files.rs"), out).expect("write wgsl_files.rs");
}

/// The file stem, which `#import` uses; it must be a plain identifier so
/// `#import <name>` lines stay unambiguous.
fn module_name(path: &Path) -> String {
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("shaders/wgsl file name is UTF-8");
    assert!(
        !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'),
        "shaders/wgsl/{name}.wgsl: module names must be [A-Za-z0-9_]+",
    );
    name.to_owned()
}
