//! dirt-shaders: the WGSL of dirt, one file per stage named after it
//! (`fill_depth`, `mip_depth`, `fill_primitives`, `trace`), and shared modules
//! that mirror `dirt-math` function by function, with their naga validation.
//!
//! # Layout
//!
//! Every WGSL file lives in `shaders/wgsl/<name>.wgsl` and is embedded in the
//! crate at compile time (`build.rs` writes a table of `include_str!`s), so the
//! crate ships its WGSL; [`files`] lists them. A file with at least one
//! `@compute`, `@vertex` or `@fragment` entry point is a *stage* file
//! ([`entries`]); the others are shared *modules*.
//!
//! # Composition
//!
//! A line whose trimmed text is `#import <name>` is replaced by the
//! (recursively composed) text of `shaders/wgsl/<name>.wgsl`. Each module is
//! included at most once per composed shader (a later `#import` of it is
//! dropped), and import cycles are an error. [`compose`] returns the text
//! together with, for every output line, the module and line it came from, so
//! errors point at the original files. The directive is purely textual: it is
//! also honoured inside a `/* */` comment.
//!
//! # Validation
//!
//! [`validate`] / [`validate_source`] parse a composed shader with naga's WGSL
//! front end and validate it with [`ValidationFlags::all`] and
//! [`CAPABILITIES`]; every error message reads `module.wgsl:line:col: message`.
//! [`validate_all`] does this for every stage file (and for every module that
//! parses on its own); `cargo xtask validate-shaders` and this crate's tests
//! run it.

mod chunked;
mod compose;
mod layout;
mod validate;

pub use chunked::{
    CHUNKED_MODULES, Chunks, HIZ_BINDING, ID_BINDING, MAX_CHUNKS, OFFSET_BINDING, SCAN_BINDING,
    TRI_BINDING, chunked_module, compose_chunked,
};
pub use compose::{Composed, ShaderError, compose, compose_with};
pub use layout::{StructLayout, struct_layout};
pub use validate::{validate, validate_all, validate_source, validate_source_with_info};

use naga::valid::{Capabilities, ValidationFlags};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/wgsl_files.rs"));
}

/// The stages of the pipeline, in build-then-trace order. `dirt_cpu::<stage>`,
/// `shaders/wgsl/<stage>.wgsl` and `dirt_gpu::<stage>` carry these names.
pub const STAGES: [&str; 4] = ["fill_depth", "mip_depth", "fill_primitives", "trace"];

/// The stages that turn an application's input into what the build reads, for
/// builds recorded on the GPU: `gather` (its meshes into triangles) and
/// `views` (the view set from the triangles' bounds). Both backends share
/// their CPU reference, `dirt_core::<stage>`; `shaders/wgsl/<stage>.wgsl` and
/// `dirt_gpu::<stage>` carry the same names.
pub const PREPARE_STAGES: [&str; 2] = ["gather", "views"];

/// The stages of the GPU renderer (`dirt_render::gpu`), named after the CPU
/// renderer's modules `dirt_render::<stage>`: `camera` (primary rays),
/// `direct_visibility` (the rasterised candidates confirmed around the
/// primary trace), `fetch`, `shade` (its steps one entry point each), `shift`,
/// `accum`, and `output` (the image drawn on a window's or canvas's texture,
/// tone-mapped from the sums). The trace between them is [`STAGES`]' `trace`.
pub const RENDER_STAGES: [&str; 7] = [
    "camera",
    "direct_visibility",
    "fetch",
    "shade",
    "shift",
    "accum",
    "output",
];

/// The naga capabilities the shaders are validated against.
///
/// Empty: the WebGPU baseline, so the same WGSL runs in a browser. Widen only
/// with a reason written here (e.g. a stage that needs 64-bit atomics, which
/// lavapipe has but WebGPU does not), and request the matching wgpu feature
/// on the device.
pub const CAPABILITIES: Capabilities = Capabilities::empty();

/// Every WGSL file of the crate, `(module name, source)`, sorted by name. The
/// module name is the file stem: `shaders/wgsl/encode.wgsl` is `"encode"`.
pub fn files() -> &'static [(&'static str, &'static str)] {
    embedded::FILES
}

/// The embedded source of `shaders/wgsl/<name>.wgsl`, uncomposed.
pub fn source(name: &str) -> Option<&'static str> {
    files().iter().find(|(n, _)| *n == name).map(|&(_, s)| s)
}

/// The files that declare at least one `@compute`, `@vertex` or `@fragment`
/// entry point (found textually, outside comments), sorted by name: the
/// shaders [`validate_all`] validates.
pub fn entries() -> Vec<&'static str> {
    files()
        .iter()
        .filter(|(_, src)| has_entry_point(src))
        .map(|&(name, _)| name)
        .collect()
}

/// Whether `src` has an `@compute`, `@vertex` or `@fragment` attribute outside
/// comments.
fn has_entry_point(src: &str) -> bool {
    let code = strip_comments(src);
    let mut rest = code.as_str();
    while let Some(at) = rest.find('@') {
        rest = &rest[at + 1..];
        let attr = rest.trim_start();
        let end = attr
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(attr.len());
        if matches!(&attr[..end], "compute" | "vertex" | "fragment") {
            return true;
        }
    }
    false
}

/// `src` with `//` line comments and (nested) `/* */` block comments replaced
/// by spaces.
fn strip_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let mut chars = src.chars().peekable();
    let mut depth = 0usize;
    let mut line_comment = false;
    while let Some(c) = chars.next() {
        if line_comment {
            if c == '\n' {
                line_comment = false;
                out.push('\n');
            }
            continue;
        }
        match (c, chars.peek()) {
            ('/', Some('*')) => {
                chars.next();
                depth += 1;
            }
            ('*', Some('/')) if depth > 0 => {
                chars.next();
                depth -= 1;
            }
            ('/', Some('/')) if depth == 0 => line_comment = true,
            _ if depth > 0 => {}
            _ => out.push(c),
        }
        if depth > 0 || line_comment {
            out.push(' ');
        }
    }
    out
}

/// The validation flags used everywhere: all of them.
fn validation_flags() -> ValidationFlags {
    ValidationFlags::all()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn entry_points_are_found_outside_comments_only() {
        assert!(has_entry_point("@compute @workgroup_size(1) fn main() {}"));
        assert!(has_entry_point(
            "@ vertex\nfn vs() -> @builtin(position) vec4f { }"
        ));
        assert!(has_entry_point("@fragment fn fs() {}"));
        assert!(!has_entry_point("// @compute\nfn f() {}"));
        assert!(!has_entry_point(
            "/* @compute /* nested */ @vertex */ fn f() {}"
        ));
        assert!(!has_entry_point("@computed fn f() {}"));
        assert!(!has_entry_point("fn f() {}"));
    }

    #[test]
    fn files_are_embedded_and_sorted() {
        let names: Vec<_> = files().iter().map(|(n, _)| *n).collect();
        assert!(names.contains(&"encode"));
        assert!(names.contains(&"selftest_encode"));
        assert!(names.windows(2).all(|w| w[0] < w[1]));
        assert!(source("encode").unwrap().contains("fn f32_to_ordered"));
        assert_eq!(source("no_such_module"), None);
    }

    /// The composed `trace` (every module it imports) writes `||` and `&&`
    /// only where the right side must not run: the budget's `step()` and
    /// `work()`. Elsewhere the eager `|` and `&`: each short-circuit operator
    /// is a branch, and SwiftShader took ~400 s to compile the trace with them
    /// (docs/ARCHITECTURE.md, "WGSL every compiler takes").
    #[test]
    fn trace_short_circuits_only_the_budget() {
        let composed = compose("trace").unwrap();
        let code = strip_comments(&composed.text);
        let offending: Vec<String> = code
            .lines()
            .enumerate()
            .filter(|(_, l)| l.contains("||") || l.contains("&&"))
            .filter(|(_, l)| !l.contains("step(") && !l.contains("work("))
            .map(|(i, l)| {
                let (module, line) = composed.locate(i as u32 + 1);
                format!("{module}.wgsl:{line}: {}", l.trim())
            })
            .collect();
        assert!(
            offending.is_empty(),
            "short-circuit operators: {offending:#?}"
        );
        // The check sees the operators it is about.
        let budget = code.lines().filter(|l| l.contains("&& step(")).count();
        assert!(budget >= 4, "the walk's loops: {budget}");
    }

    #[test]
    fn selftest_is_an_entry_and_encode_is_a_module() {
        let e = entries();
        assert!(e.contains(&"selftest_encode"));
        assert!(!e.contains(&"encode"));
    }
}
