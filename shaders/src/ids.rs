//! The list ids' module for any number of chunks. `wgsl/ids.wgsl` is the
//! one-chunk module (what every stage composes by default); a device that
//! binds more storage buffers per stage gets [`ids_module`] of more chunks,
//! composed in its place by [`compose_with_ids`].

use crate::{Composed, ShaderError, compose_with, source};
use std::fmt::Write as _;

/// The binding of chunk 0; chunk `c` is at `ID_BINDING + c`.
pub const ID_BINDING: u32 = 16;

/// The most chunks a module declares (eight bindings: with 128 MiB each,
/// 1 GiB of ids).
pub const MAX_ID_CHUNKS: u32 = 8;

/// `wgsl/ids.wgsl` for `chunks` chunks (1..=[`MAX_ID_CHUNKS`]): the same
/// comment, one binding per chunk, and `id_load` / `id_store` choosing the
/// chunk with a `switch`. `ids_module(1)` is the file itself (tested).
pub fn ids_module(chunks: u32) -> String {
    let chunks = chunks.clamp(1, MAX_ID_CHUNKS);
    let file = source("ids").unwrap_or_default();
    let mut out: String = file
        .lines()
        .take_while(|l| l.starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect();
    for c in 0..chunks {
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var<storage, read_write> ids{c}: array<u32>;",
            ID_BINDING + c
        );
    }
    out.push_str(
        "\n// Entry `at`; the caller keeps `at` below the ids' capacity.\n\
         fn id_load(at: u32, shift: u32) -> u32 {\n    \
         let i = at & ((1u << shift) - 1u);\n    \
         var id = 0u;\n    \
         switch at >> shift {\n",
    );
    for c in 0..chunks {
        let label = if c + 1 == chunks {
            "default".to_owned()
        } else {
            format!("case {c}u")
        };
        let _ = write!(
            out,
            "        {label}: {{\n            id = ids{c}[i];\n        }}\n"
        );
    }
    out.push_str(
        "    }\n    return id;\n}\n\n\
         // Writes entry `at`; past the end of the chunks nothing is written.\n\
         fn id_store(at: u32, shift: u32, id: u32) {\n    \
         let i = at & ((1u << shift) - 1u);\n    \
         switch at >> shift {\n",
    );
    for c in 0..chunks {
        let _ = write!(
            out,
            "        case {c}u: {{\n            if i < arrayLength(&ids{c}) {{\n                ids{c}[i] = id;\n            }}\n        }}\n"
        );
    }
    out.push_str("        default: {}\n    }\n}\n");
    out
}

/// [`crate::compose`] with the ids' module of `chunks` chunks.
pub fn compose_with_ids(entry: &str, chunks: u32) -> Result<Composed, ShaderError> {
    let ids = ids_module(chunks);
    compose_with(entry, &|name| {
        if name == "ids" {
            Some(ids.as_str())
        } else {
            source(name)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_one_chunk_module_is_the_file() {
        assert_eq!(ids_module(1), source("ids").expect("ids.wgsl"));
    }

    #[test]
    fn every_chunk_count_validates_in_the_stages_that_use_it() {
        for chunks in 1..=MAX_ID_CHUNKS {
            let module = ids_module(chunks);
            assert_eq!(
                module.matches("var<storage, read_write> ids").count(),
                chunks as usize
            );
            for stage in ["trace", "fill_primitives"] {
                let c = compose_with_ids(stage, chunks).expect("composes");
                crate::validate_source(&c)
                    .unwrap_or_else(|e| panic!("{stage} with {chunks} chunks: {e:?}"));
            }
        }
    }
}
