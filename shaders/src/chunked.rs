//! Arrays split across bindings: the list ids (`ids`) and the triangles
//! (`tris`, and `tris_out` for `gather`, which writes them). A device that
//! allows more storage buffers per stage than dirt's minimum gets each split
//! across several bindings of `2^shift` elements (entry `at` is element
//! `at & mask` of chunk `at >> shift`), so that one binding's size does not
//! bound a scene. `wgsl/<module>.wgsl` is each module for one chunk (what
//! every stage composes by default); [`chunked_module`] writes it for any
//! number (`chunked_module(m, 1)` is the file itself, tested), and
//! [`compose_chunked`] composes a stage with the modules of a device's counts.

use crate::{Composed, ShaderError, compose_with, source};
use std::fmt::Write as _;

/// The most chunks a module declares (eight bindings: with 128 MiB each, 1 GiB).
pub const MAX_CHUNKS: u32 = 8;

/// The binding of the ids' chunk 0; chunk `c` is at `ID_BINDING + c`.
pub const ID_BINDING: u32 = 16;

/// The binding of the triangles' chunk 0; chunk `c` is at `TRI_BINDING + c`.
pub const TRI_BINDING: u32 = 24;

/// How many chunks each split array has on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chunks {
    pub ids: u32,
    pub tris: u32,
}

impl Chunks {
    /// One chunk each: the modules as the files hold them.
    pub const ONE: Chunks = Chunks { ids: 1, tris: 1 };
}

/// The split modules, by name.
pub const CHUNKED_MODULES: [&str; 3] = ["ids", "tris", "tris_out"];

/// `switch sel { … }` over `chunks` chunks, each arm `body(c)`. With
/// `last_default` the last chunk is the default arm (loads, whose index the
/// caller keeps in range); else every chunk has its case and the default does
/// nothing (stores past the end write nothing).
fn switch(sel: &str, chunks: u32, last_default: bool, body: &dyn Fn(u32) -> String) -> String {
    let mut out = format!("    switch {sel} {{\n");
    for c in 0..chunks {
        let label = if last_default && c + 1 == chunks {
            "default".to_owned()
        } else {
            format!("case {c}u")
        };
        let _ = write!(out, "        {label}: {{\n{}        }}\n", body(c));
    }
    if !last_default {
        out.push_str("        default: {}\n");
    }
    out.push_str("    }\n");
    out
}

/// `module` (one of [`CHUNKED_MODULES`]) for `chunks` chunks (1..=[`MAX_CHUNKS`]):
/// the file's leading comment, one binding per chunk, and its functions
/// choosing the chunk with a `switch`. `None` for another name.
pub fn chunked_module(module: &str, chunks: u32) -> Option<String> {
    if !CHUNKED_MODULES.contains(&module) {
        return None;
    }
    let chunks = chunks.clamp(1, MAX_CHUNKS);
    let file = source(module)?;
    let mut out: String = file
        .lines()
        .take_while(|l| l.starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect();
    let (binding, decl) = match module {
        "ids" => (ID_BINDING, "read_write> ids{c}: array<u32>"),
        "tris" => (TRI_BINDING, "read> tris{c}: array<f32>"),
        _ => (TRI_BINDING, "read_write> tris{c}: array<f32>"),
    };
    for c in 0..chunks {
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var<storage, {};",
            binding + c,
            decl.replace("{c}", &c.to_string())
        );
    }
    match module {
        "ids" => {
            out.push_str(
                "\n// Entry `at`; the caller keeps `at` below the ids' capacity.\n\
                 fn id_load(at: u32, shift: u32) -> u32 {\n    \
                 let i = at & ((1u << shift) - 1u);\n    \
                 var id = 0u;\n",
            );
            out += &switch("at >> shift", chunks, true, &|c| {
                format!("            id = ids{c}[i];\n")
            });
            out.push_str(
                "    return id;\n}\n\n\
                 // Writes entry `at`; past the end of the chunks nothing is written.\n\
                 fn id_store(at: u32, shift: u32, id: u32) {\n    \
                 let i = at & ((1u << shift) - 1u);\n",
            );
            out += &switch("at >> shift", chunks, false, &|c| {
                format!(
                    "            if i < arrayLength(&ids{c}) {{\n                ids{c}[i] = id;\n            }}\n"
                )
            });
            out.push_str("}\n");
        }
        "tris" => {
            out.push_str(
                "\n// Vertex `k` of triangle `prim`; the caller keeps `prim` below the count.\n\
                 fn tri_load(prim: u32, k: u32, shift: u32) -> vec3<f32> {\n    \
                 let b = (prim & ((1u << shift) - 1u)) * 9u + k * 3u;\n    \
                 var p = vec3<f32>(0.0);\n",
            );
            out += &switch("prim >> shift", chunks, true, &|c| {
                format!(
                    "            p = vec3<f32>(tris{c}[b], tris{c}[b + 1u], tris{c}[b + 2u]);\n"
                )
            });
            out.push_str("    return p;\n}\n");
        }
        _ => {
            out.push_str(
                "\n// Writes vertex `k` of triangle `prim`; past the end of the chunks nothing is written.\n\
                 fn tri_store(prim: u32, k: u32, shift: u32, p: vec3<f32>) {\n    \
                 let b = (prim & ((1u << shift) - 1u)) * 9u + k * 3u;\n",
            );
            out += &switch("prim >> shift", chunks, false, &|c| {
                format!(
                    "            if b + 2u < arrayLength(&tris{c}) {{\n                tris{c}[b] = p.x;\n                tris{c}[b + 1u] = p.y;\n                tris{c}[b + 2u] = p.z;\n            }}\n"
                )
            });
            out.push_str("}\n");
        }
    }
    Some(out)
}

/// [`crate::compose`] with the split modules of `chunks`.
pub fn compose_chunked(entry: &str, chunks: Chunks) -> Result<Composed, ShaderError> {
    let ids = chunked_module("ids", chunks.ids).unwrap_or_default();
    let tris = chunked_module("tris", chunks.tris).unwrap_or_default();
    let tris_out = chunked_module("tris_out", chunks.tris).unwrap_or_default();
    compose_with(entry, &|name| match name {
        "ids" => Some(ids.as_str()),
        "tris" => Some(tris.as_str()),
        "tris_out" => Some(tris_out.as_str()),
        _ => source(name),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_one_chunk_modules_are_the_files() {
        for m in CHUNKED_MODULES {
            assert_eq!(
                chunked_module(m, 1).as_deref(),
                Some(source(m).expect("the file")),
                "{m}"
            );
        }
        assert_eq!(chunked_module("encode", 1), None);
    }

    #[test]
    fn every_chunk_count_validates_in_the_stages_that_use_it() {
        for n in 1..=MAX_CHUNKS {
            for m in CHUNKED_MODULES {
                let text = chunked_module(m, n).expect("a module");
                assert_eq!(text.matches("@binding(").count(), n as usize, "{m}");
            }
            for (stage, chunks) in [
                (
                    "trace",
                    Chunks {
                        ids: n,
                        tris: 9 - n,
                    },
                ),
                ("fill_primitives", Chunks { ids: n, tris: n }),
                ("fill_depth", Chunks { ids: 1, tris: n }),
                ("views", Chunks { ids: 1, tris: n }),
                ("gather", Chunks { ids: 1, tris: n }),
            ] {
                let c = compose_chunked(stage, chunks).expect("composes");
                crate::validate_source(&c)
                    .unwrap_or_else(|e| panic!("{stage} with {chunks:?}: {e:?}"));
            }
        }
    }
}
