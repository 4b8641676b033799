//! naga parsing and validation, with errors mapped back to the original files.

use naga::Span;
use naga::valid::{ModuleInfo, ValidationError, Validator};

use crate::{CAPABILITIES, Composed, compose, entries, files, validation_flags};

/// Composes, parses and validates the embedded shader `entry`.
///
/// Every error reads `module.wgsl:line:col: message` (composition errors:
/// `module.wgsl:line: message`).
pub fn validate(entry: &str) -> Result<naga::Module, Vec<String>> {
    let composed = compose(entry).map_err(|e| vec![e.to_string()])?;
    validate_source(&composed)
}

/// Parses `c.text` with naga's WGSL front end and validates it with
/// [`naga::valid::ValidationFlags::all`] and [`CAPABILITIES`].
///
/// Every error reads `module.wgsl:line:col: message`, the position mapped
/// back through [`Composed::origin`], followed by naga's labels and notes on
/// the same line. An error naga gives no position for reads
/// `entry.wgsl: message`.
pub fn validate_source(c: &Composed) -> Result<naga::Module, Vec<String>> {
    validate_source_with_info(c).map(|(module, _)| module)
}

/// [`validate_source`], also returning naga's [`ModuleInfo`] (which naga's
/// back ends, e.g. SPIR-V out, need).
pub fn validate_source_with_info(c: &Composed) -> Result<(naga::Module, ModuleInfo), Vec<String>> {
    let module = naga::front::wgsl::parse_str(&c.text).map_err(|e| {
        let labels: Vec<(Span, &str)> = e.labels().collect();
        let notes: Vec<&str> = e.notes().collect();
        vec![format_error(c, e.message(), &labels, &notes)]
    })?;
    let info = Validator::new(validation_flags(), CAPABILITIES)
        .validate(&module)
        .map_err(|e| {
            // naga's message, then its chain of causes.
            let mut message = e.as_inner().to_string();
            let mut cause = std::error::Error::source(e.as_inner());
            while let Some(c) = cause {
                message.push_str(": ");
                message.push_str(&c.to_string());
                cause = c.source();
            }
            let mut labels: Vec<(Span, &str)> = e.spans().map(|(s, d)| (*s, d.as_str())).collect();
            if labels.is_empty() {
                labels.extend(fallback_span(c, &module, e.as_inner()).map(|s| (s, "")));
            }
            vec![format_error(c, &message, &labels, &[])]
        })?;
    Ok((module, info))
}

/// Validates every stage file ([`entries`]), and every other module that
/// parses on its own (a module may use names only its importers define; those
/// are checked through the stages that import them). Collects all errors,
/// each once, in file order.
pub fn validate_all() -> Result<(), Vec<String>> {
    let stages = entries();
    let mut errors: Vec<String> = Vec::new();
    let mut push = |new: Vec<String>| {
        for e in new {
            if !errors.contains(&e) {
                errors.push(e);
            }
        }
    };
    for &(name, _) in files() {
        if stages.contains(&name) {
            if let Err(e) = validate(name) {
                push(e);
            }
            continue;
        }
        match compose(name) {
            Err(e) => push(vec![e.to_string()]),
            Ok(c) => {
                if naga::front::wgsl::parse_str(&c.text).is_ok()
                    && let Err(e) = validate_source(&c)
                {
                    push(e);
                }
            }
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors)
    }
}

/// `module.wgsl:line:col: message (label); other.wgsl:l:c: label; note: …`,
/// on one line. The first label is the primary position.
fn format_error(c: &Composed, message: &str, labels: &[(Span, &str)], notes: &[&str]) -> String {
    let mut located = labels
        .iter()
        .filter_map(|&(span, label)| Some((position(c, span)?, label)));
    let mut out = match located.next() {
        Some((pos, label)) => {
            let mut s = format!("{pos}: {message}");
            if !label.is_empty() && label != message {
                s.push_str(&format!(" ({label})"));
            }
            s
        }
        None => format!("{}.wgsl: {message}", c.entry),
    };
    for (pos, label) in located {
        out.push_str(&format!("; {pos}: {label}"));
    }
    for note in notes {
        out.push_str(&format!("; note: {note}"));
    }
    // One error, one line.
    out.replace(['\n', '\r'], " ")
}

/// Where naga attaches no span to a validation error, the span of the item
/// it names: the declaration naga recorded for a type, constant, override,
/// global or function, or the `fn <name>` of an entry point.
fn fallback_span(c: &Composed, module: &naga::Module, e: &ValidationError) -> Option<Span> {
    let span = match *e {
        ValidationError::Type { handle, .. } => module.types.get_span(handle),
        ValidationError::Constant { handle, .. } => module.constants.get_span(handle),
        ValidationError::Override { handle, .. } => module.overrides.get_span(handle),
        ValidationError::GlobalVariable { handle, .. } => module.global_variables.get_span(handle),
        ValidationError::Function { handle, .. } => module.functions.get_span(handle),
        ValidationError::ConstExpression { handle, .. }
        | ValidationError::ArraySizeError { handle } => module.global_expressions.get_span(handle),
        ValidationError::EntryPoint { ref name, .. } => find_fn(&c.text, name)?,
        _ => return None,
    };
    span.is_defined().then_some(span)
}

/// The span of the name in the first `fn <name>` of `text` (a textual search).
fn find_fn(text: &str, name: &str) -> Option<Span> {
    if name.is_empty() {
        return None;
    }
    let is_ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut from = 0;
    while let Some(found) = text[from..].find(name) {
        let start = from + found;
        let end = start + name.len();
        from = end;
        let head = &text[..start];
        let before = head.trim_end();
        if before.len() < head.len()
            && before
                .strip_suffix("fn")
                .is_some_and(|b| !b.ends_with(is_ident))
            && !text[end..].starts_with(is_ident)
        {
            return Some(Span::from(start..end));
        }
    }
    None
}

/// `module.wgsl:line:col` of the start of `span` in the composed text.
fn position(c: &Composed, span: Span) -> Option<String> {
    let start = span.to_range()?.start;
    if start > c.text.len() || !c.text.is_char_boundary(start) {
        return None;
    }
    let loc = span.location(&c.text);
    let (module, line) = c.locate(loc.line_number);
    Some(format!("{module}.wgsl:{line}:{}", loc.line_position))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::compose_with;
    use std::collections::HashMap;

    fn composed(files: &[(&str, &str)], entry: &str) -> Composed {
        let map: HashMap<&str, &str> = files.iter().copied().collect();
        compose_with(entry, &|n| map.get(n).copied()).unwrap()
    }

    const GOOD_STAGE: &str = "\
#import helpers

@group(0) @binding(0) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    out[id.x] = twice(id.x);
}
";

    #[test]
    fn the_real_tree_validates() {
        if let Err(errors) = validate_all() {
            panic!("shader validation failed:\n{}", errors.join("\n"));
        }
    }

    #[test]
    fn a_good_composed_shader_validates() {
        let c = composed(
            &[
                ("stage", GOOD_STAGE),
                (
                    "helpers",
                    "fn twice(x: u32) -> u32 {\n    return x * 2u;\n}\n",
                ),
            ],
            "stage",
        );
        let module = validate_source(&c).unwrap();
        assert_eq!(module.entry_points.len(), 1);
        assert_eq!(module.entry_points[0].name, "main");
    }

    /// The test that proves validation catches a broken shader: a type error in
    /// an imported module is reported at that module's own line and column.
    #[test]
    fn a_type_error_in_an_imported_module_names_that_module_and_line() {
        let helpers = "\
// helpers: line 1
// line 2

fn twice(x: u32) -> u32 {
    let y: u32 = 1.5;
    return x * y;
}
";
        let c = composed(&[("stage", GOOD_STAGE), ("helpers", helpers)], "stage");
        let errors = validate_source(&c).unwrap_err();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(errors[0].starts_with("helpers.wgsl:5:"), "{errors:?}");
        assert!(errors[0].contains("u32"), "{errors:?}");
    }

    #[test]
    fn a_syntax_error_in_the_stage_after_an_import_names_the_stage_line() {
        let stage = "#import helpers\n\nfn main() {\n    let a = 1u\n}\n";
        let c = composed(
            &[
                ("stage", stage),
                ("helpers", "fn h() {}\nfn h2() {}\nfn h3() {}\n"),
            ],
            "stage",
        );
        let errors = validate_source(&c).unwrap_err();
        // naga points at the token after the missing `;`, on line 5.
        assert!(errors[0].starts_with("stage.wgsl:5:1: "), "{errors:?}");
        assert!(errors[0].contains("expected"), "{errors:?}");
    }

    /// An error only the validator (not the front end) finds, and that naga
    /// gives no span for, is placed at the entry point's name.
    #[test]
    fn a_validation_error_names_the_module_and_line() {
        let helpers = "\
// helpers

fn helper() {}

@compute @workgroup_size(1)
fn   bad_entry(@builtin(position) p: vec4<f32>) {}
";
        let c = composed(
            &[
                ("stage", "// stage\n#import helpers\n"),
                ("helpers", helpers),
            ],
            "stage",
        );
        let errors = validate_source(&c).unwrap_err();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(errors[0].starts_with("helpers.wgsl:6:6: "), "{errors:?}");
        assert!(errors[0].contains("bad_entry"), "{errors:?}");
        assert!(
            errors[0].contains("not available at this stage"),
            "{errors:?}"
        );
    }

    /// A capability outside the WebGPU baseline is refused.
    #[test]
    fn f64_needs_a_capability() {
        let c = composed(
            &[("s", "// s\nfn f() {\n    var x: f64 = 1.0lf;\n}\n")],
            "s",
        );
        let errors = validate_source(&c).unwrap_err();
        assert!(errors[0].contains("FLOAT64"), "{errors:?}");
        assert!(errors[0].starts_with("s.wgsl:"), "{errors:?}");
    }

    #[test]
    fn find_fn_finds_whole_names_after_fn_only() {
        let text = "fn main2() {}\nlet main = 1;\nfnmain\nfn  main() {}";
        let span = find_fn(text, "main").unwrap().to_range().unwrap();
        assert_eq!(&text[span.clone()], "main");
        assert_eq!(span.start, text.rfind("main").unwrap());
        assert_eq!(find_fn(text, "nope"), None);
        assert_eq!(find_fn(text, ""), None);
    }

    #[test]
    fn a_composition_error_is_reported_by_validate() {
        let errors = validate("no_such_shader").unwrap_err();
        assert_eq!(errors.len(), 1);
        assert!(errors[0].contains("no_such_shader"));
    }

    #[test]
    fn the_selftest_kernel_has_its_entry_point() {
        let module = validate("selftest_encode").unwrap();
        let ep = &module.entry_points[0];
        assert_eq!(ep.name, "main");
        assert_eq!(ep.stage, naga::ShaderStage::Compute);
        assert_eq!(ep.workgroup_size, [64, 1, 1]);
    }

    #[test]
    fn the_encode_module_validates_on_its_own() {
        let module = validate("encode").unwrap();
        let names: Vec<_> = module
            .functions
            .iter()
            .filter_map(|(_, f)| f.name.as_deref())
            .collect();
        assert_eq!(names, ["f32_to_ordered", "ordered_to_f32"]);
    }
}
