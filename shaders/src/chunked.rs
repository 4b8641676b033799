//! Arrays split across bindings: the list ids (`ids`), the triangles
//! (`tris`; `tris_out` for `gather`, which writes them), the Hi-Z pyramid
//! (`hiz`; `hiz_out` for `mip_depth`, `hiz_atomic` for `fill_depth`) and the
//! list offsets (`offsets`; `lists` for the atomic counters and cursors of
//! `fill_primitives`, `scan_data` for its prefix sum). A device that allows
//! more storage buffers per stage than dirt's minimum gets each split across
//! several bindings of `2^shift` elements (element `at` is element
//! `at & mask` of chunk `at >> shift`), so that one binding's size does not
//! bound a scene. `wgsl/<module>.wgsl` is each module for one chunk (what
//! every stage composes by default); [`chunked_module`] writes it for any
//! number (`chunked_module(m, 1)` is the file itself, tested), and
//! [`compose_chunked`] composes a stage with the modules of a structure's counts.

use crate::{Composed, ShaderError, compose_with, source};
use std::fmt::Write as _;

/// The most chunks a module declares (eight bindings: with 128 MiB each, 1 GiB).
pub const MAX_CHUNKS: u32 = 8;

/// The binding of the ids' chunk 0; chunk `c` is at `ID_BINDING + c`.
pub const ID_BINDING: u32 = 16;

/// The binding of the triangles' chunk 0; chunk `c` is at `TRI_BINDING + c`.
pub const TRI_BINDING: u32 = 24;

/// The binding of the Hi-Z pyramid's chunk 0; chunk `c` is at `HIZ_BINDING + c`.
pub const HIZ_BINDING: u32 = 32;

/// The binding of the list offsets' (or counters', or cursors') chunk 0.
pub const OFFSET_BINDING: u32 = 40;

/// The binding of the prefix sum's data chunk 0 (the offsets, or one level's sums in chunk 0).
pub const SCAN_BINDING: u32 = 48;

/// How many chunks each split array has in a pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Chunks {
    pub ids: u32,
    pub tris: u32,
    pub hiz: u32,
    pub offsets: u32,
}

impl Chunks {
    /// One chunk each: the modules as the files hold them.
    pub const ONE: Chunks = Chunks {
        ids: 1,
        tris: 1,
        hiz: 1,
        offsets: 1,
    };
}

/// The split modules, by name.
pub const CHUNKED_MODULES: [&str; 9] = [
    "ids",
    "tris",
    "tris_out",
    "hiz",
    "hiz_out",
    "hiz_atomic",
    "offsets",
    "lists",
    "scan_data",
];

/// One function of a split module: `head` (its comment and signature), the
/// local index line `index` (`{idx}`: element `arg` within its chunk, `{pidx}`
/// the same in parentheses), `pre`, then a `switch` on `arg >> shift` whose arm
/// for chunk `c` is `arm` with `{v}` the chunk's variable, then `tail`. With
/// `last_default` the last chunk is the default arm (accesses whose index the
/// caller keeps in range); else every chunk has its case and the default does
/// nothing (stores past the end write nothing). With one chunk there is no
/// switch and no mask: the index is `arg` itself (below `2^shift`, or past the
/// chunk's end where a guarded store writes nothing), so a scene that fits one
/// binding runs what it would without chunks.
struct Func {
    head: &'static str,
    arg: &'static str,
    index: &'static str,
    pre: &'static str,
    last_default: bool,
    arm: &'static str,
    tail: &'static str,
}

/// A split module: its chunks' variable (`{var}{c}`), first binding, access
/// and element type, and functions.
struct Spec {
    var: &'static str,
    binding: u32,
    access: &'static str,
    elem: &'static str,
    funcs: &'static [Func],
}

const HIZ_CELL: Func = Func {
    head: "\n// Cell `cell`: (enc(zmin), enc(zmax)); the caller keeps `cell` below the cells.\n\
           fn hiz_cell(cell: u32, shift: u32) -> vec2<u32> {\n",
    arg: "cell",
    index: "    let i = 2u * {pidx};\n",
    pre: "    var z = vec2<u32>(0u);\n",
    last_default: true,
    arm: "            z = vec2<u32>({v}[i], {v}[i + 1u]);\n",
    tail: "    return z;\n}\n",
};

fn spec(module: &str) -> Option<Spec> {
    Some(match module {
        "ids" => Spec {
            var: "ids",
            binding: ID_BINDING,
            access: "read_write",
            elem: "u32",
            funcs: &[
                Func {
                    head: "\n// Entry `at`; the caller keeps `at` below the ids' capacity.\n\
                           fn id_load(at: u32, shift: u32) -> u32 {\n",
                    arg: "at",
                    index: "    let i = {idx};\n",
                    pre: "    var id = 0u;\n",
                    last_default: true,
                    arm: "            id = {v}[i];\n",
                    tail: "    return id;\n}\n",
                },
                Func {
                    head: "\n// Writes entry `at`; past the end of the chunks nothing is written.\n\
                           fn id_store(at: u32, shift: u32, id: u32) {\n",
                    arg: "at",
                    index: "    let i = {idx};\n",
                    pre: "",
                    last_default: false,
                    arm: "            if i < arrayLength(&{v}) {\n                {v}[i] = id;\n            }\n",
                    tail: "}\n",
                },
            ],
        },
        "tris" => Spec {
            var: "tris",
            binding: TRI_BINDING,
            access: "read",
            elem: "f32",
            funcs: &[Func {
                head: "\n// Vertex `k` of triangle `prim`; the caller keeps `prim` below the count.\n\
                       fn tri_load(prim: u32, k: u32, shift: u32) -> vec3<f32> {\n",
                arg: "prim",
                index: "    let b = {pidx} * 9u + k * 3u;\n",
                pre: "    var p = vec3<f32>(0.0);\n",
                last_default: true,
                arm: "            p = vec3<f32>({v}[b], {v}[b + 1u], {v}[b + 2u]);\n",
                tail: "    return p;\n}\n",
            }],
        },
        "tris_out" => Spec {
            var: "tris",
            binding: TRI_BINDING,
            access: "read_write",
            elem: "f32",
            funcs: &[Func {
                head: "\n// Writes vertex `k` of triangle `prim`; past the end of the chunks nothing is written.\n\
                       fn tri_store(prim: u32, k: u32, shift: u32, p: vec3<f32>) {\n",
                arg: "prim",
                index: "    let b = {pidx} * 9u + k * 3u;\n",
                pre: "",
                last_default: false,
                arm: "            if b + 2u < arrayLength(&{v}) {\n                {v}[b] = p.x;\n                {v}[b + 1u] = p.y;\n                {v}[b + 2u] = p.z;\n            }\n",
                tail: "}\n",
            }],
        },
        "hiz" => Spec {
            var: "hiz",
            binding: HIZ_BINDING,
            access: "read",
            elem: "u32",
            funcs: &[HIZ_CELL],
        },
        "hiz_out" => Spec {
            var: "hiz",
            binding: HIZ_BINDING,
            access: "read_write",
            elem: "u32",
            funcs: &[
                HIZ_CELL,
                Func {
                    head: "\n// Writes cell `cell`; the caller keeps `cell` below the cells.\n\
                           fn hiz_store(cell: u32, shift: u32, z: vec2<u32>) {\n",
                    arg: "cell",
                    index: "    let i = 2u * {pidx};\n",
                    pre: "",
                    last_default: true,
                    arm: "            {v}[i] = z.x;\n            {v}[i + 1u] = z.y;\n",
                    tail: "}\n",
                },
            ],
        },
        "hiz_atomic" => Spec {
            var: "hiz",
            binding: HIZ_BINDING,
            access: "read_write",
            elem: "atomic<u32>",
            funcs: &[
                Func {
                    head: "\n// Widens cell `cell` to hold [lo, hi] (encoded: atomic min and max); the\n\
                           // caller keeps `cell` below the cells.\n\
                           fn hiz_widen(cell: u32, shift: u32, lo: u32, hi: u32) {\n",
                    arg: "cell",
                    index: "    let i = 2u * {pidx};\n",
                    pre: "",
                    last_default: true,
                    arm: "            atomicMin(&{v}[i], lo);\n            atomicMax(&{v}[i + 1u], hi);\n",
                    tail: "}\n",
                },
                Func {
                    head: "\n// Sets cell `cell`; past the end of the chunks nothing is written.\n\
                           fn hiz_set(cell: u32, shift: u32, z: vec2<u32>) {\n",
                    arg: "cell",
                    index: "    let i = 2u * {pidx};\n",
                    pre: "",
                    last_default: false,
                    arm: "            if i + 1u < arrayLength(&{v}) {\n                atomicStore(&{v}[i], z.x);\n                atomicStore(&{v}[i + 1u], z.y);\n            }\n",
                    tail: "}\n",
                },
            ],
        },
        "offsets" => Spec {
            var: "offsets",
            binding: OFFSET_BINDING,
            access: "read",
            elem: "u32",
            funcs: &[Func {
                head: "\n// Offset `at`; the caller keeps `at` below the offsets' count.\n\
                       fn offset_load(at: u32, shift: u32) -> u32 {\n",
                arg: "at",
                index: "    let i = {idx};\n",
                pre: "    var o = 0u;\n",
                last_default: true,
                arm: "            o = {v}[i];\n",
                tail: "    return o;\n}\n",
            }],
        },
        "lists" => Spec {
            var: "lists",
            binding: OFFSET_BINDING,
            access: "read_write",
            elem: "atomic<u32>",
            funcs: &[Func {
                head: "\n// Adds one to counter `at` and returns what it held; the caller keeps `at`\n\
                       // below the counters' count.\n\
                       fn list_add(at: u32, shift: u32) -> u32 {\n",
                arg: "at",
                index: "    let i = {idx};\n",
                pre: "    var old = 0u;\n",
                last_default: true,
                arm: "            old = atomicAdd(&{v}[i], 1u);\n",
                tail: "    return old;\n}\n",
            }],
        },
        "scan_data" => Spec {
            var: "scan_data",
            binding: SCAN_BINDING,
            access: "read_write",
            elem: "u32",
            funcs: &[
                Func {
                    head: "\n// Element `at`; the caller keeps `at` below the count.\n\
                           fn scan_load(at: u32, shift: u32) -> u32 {\n",
                    arg: "at",
                    index: "    let i = {idx};\n",
                    pre: "    var x = 0u;\n",
                    last_default: true,
                    arm: "            x = {v}[i];\n",
                    tail: "    return x;\n}\n",
                },
                Func {
                    head: "\n// Writes element `at`; the caller keeps `at` below the count.\n\
                           fn scan_store(at: u32, shift: u32, x: u32) {\n",
                    arg: "at",
                    index: "    let i = {idx};\n",
                    pre: "",
                    last_default: true,
                    arm: "            {v}[i] = x;\n",
                    tail: "}\n",
                },
            ],
        },
        _ => return None,
    })
}

/// `f` over `chunks` chunks of `var`: its head, index, `pre`, the chunk
/// `switch` (or, for one chunk, the one arm) and tail.
fn function(f: &Func, var: &str, chunks: u32) -> String {
    let (idx, pidx) = if chunks == 1 {
        (f.arg.to_owned(), f.arg.to_owned())
    } else {
        let m = format!("{} & ((1u << shift) - 1u)", f.arg);
        (m.clone(), format!("({m})"))
    };
    let mut out = format!(
        "{}{}{}",
        f.head,
        f.index.replace("{idx}", &idx).replace("{pidx}", &pidx),
        f.pre
    );
    if chunks == 1 {
        for line in f.arm.replace("{v}", &format!("{var}0")).lines() {
            let _ = writeln!(out, "{}", line.strip_prefix("        ").unwrap_or(line));
        }
        out.push_str(f.tail);
        return out;
    }
    let _ = writeln!(out, "    switch {} >> shift {{", f.arg);
    for c in 0..chunks {
        let label = if f.last_default && c + 1 == chunks {
            "default".to_owned()
        } else {
            format!("case {c}u")
        };
        let arm = f.arm.replace("{v}", &format!("{var}{c}"));
        let _ = write!(out, "        {label}: {{\n{arm}        }}\n");
    }
    if !f.last_default {
        out.push_str("        default: {}\n");
    }
    out.push_str("    }\n");
    out.push_str(f.tail);
    out
}

/// `module` (one of [`CHUNKED_MODULES`]) for `chunks` chunks (1..=[`MAX_CHUNKS`]):
/// the file's leading comment, one binding per chunk, and its functions
/// choosing the chunk with a `switch`. `None` for another name.
pub fn chunked_module(module: &str, chunks: u32) -> Option<String> {
    let spec = spec(module)?;
    let chunks = chunks.clamp(1, MAX_CHUNKS);
    let file = source(module)?;
    let mut out: String = file
        .lines()
        .take_while(|l| l.starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect();
    for c in 0..chunks {
        let _ = writeln!(
            out,
            "@group(0) @binding({}) var<storage, {}> {}{c}: array<{}>;",
            spec.binding + c,
            spec.access,
            spec.var,
            spec.elem
        );
    }
    for f in spec.funcs {
        out += &function(f, spec.var, chunks);
    }
    Some(out)
}

/// The chunk count of `module` in `chunks`.
fn count_of(module: &str, chunks: Chunks) -> u32 {
    match module {
        "ids" => chunks.ids,
        "tris" | "tris_out" => chunks.tris,
        "hiz" | "hiz_out" | "hiz_atomic" => chunks.hiz,
        _ => chunks.offsets,
    }
}

/// [`crate::compose`] with the split modules of `chunks`.
pub fn compose_chunked(entry: &str, chunks: Chunks) -> Result<Composed, ShaderError> {
    let modules: Vec<(&str, String)> = CHUNKED_MODULES
        .iter()
        .map(|m| {
            (
                *m,
                chunked_module(m, count_of(m, chunks)).unwrap_or_default(),
            )
        })
        .collect();
    compose_with(entry, &|name| {
        modules
            .iter()
            .find(|(m, _)| *m == name)
            .map(|(_, text)| text.as_str())
            .or_else(|| source(name))
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
            let c = |ids, tris, hiz, offsets| Chunks {
                ids,
                tris,
                hiz,
                offsets,
            };
            for (stage, chunks) in [
                ("trace", c(n, 9 - n, n, 9 - n)),
                ("fill_primitives", c(n, n, 9 - n, n)),
                ("fill_depth", c(1, n, n, 1)),
                ("mip_depth", c(1, 1, n, 1)),
                ("views", c(1, n, 1, 1)),
                ("gather", c(1, n, 1, 1)),
            ] {
                let c = compose_chunked(stage, chunks).expect("composes");
                crate::validate_source(&c)
                    .unwrap_or_else(|e| panic!("{stage} with {chunks:?}: {e:?}"));
            }
        }
    }
}
