//! Writes each input to a file, since the loaders read paths (relative
//! buffer and material references resolve against the file's folder).

use std::path::PathBuf;

/// A file named `name` in a folder of this process, holding `data`.
pub fn file_with(name: &str, data: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dirt-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("fuzz scratch folder");
    let path = dir.join(name);
    std::fs::write(&path, data).expect("write fuzz input");
    path
}
