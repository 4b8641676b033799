//! The `#import` preprocessor.

use std::collections::{BTreeSet, HashSet};
use std::sync::Mutex;

/// A composition error. Its message starts with the `module.wgsl:line` of the
/// offending `#import` where there is one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShaderError {
    /// The shader asked for does not exist.
    #[error("unknown shader `{name}` (no {name}.wgsl)")]
    UnknownShader {
        /// The name asked for.
        name: String,
    },
    /// An `#import` names a module that does not exist.
    #[error("{file}.wgsl:{line}: unknown module `{name}` in #import (no {name}.wgsl)")]
    UnknownImport {
        /// The module imported.
        name: String,
        /// The importing module.
        file: String,
        /// The 1-based line of the `#import` in `file`.
        line: u32,
    },
    /// An `#import` closes a cycle.
    #[error("{file}.wgsl:{line}: import cycle: {}", chain.join(" -> "))]
    ImportCycle {
        /// The import chain from the composed shader down to the module
        /// imported twice, e.g. `["stage", "a", "b", "a"]`.
        chain: Vec<String>,
        /// The module whose `#import` closes the cycle.
        file: String,
        /// The 1-based line of that `#import` in `file`.
        line: u32,
    },
    /// A line starting with `#import` that is not `#import <identifier>`.
    #[error("{file}.wgsl:{line}: malformed #import `{text}` (expected `#import <name>`)")]
    MalformedImport {
        /// The trimmed line.
        text: String,
        /// The module it is in.
        file: String,
        /// Its 1-based line.
        line: u32,
    },
}

/// A composed shader: the text naga sees, and where each of its lines came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Composed {
    /// The shader that was composed (the entry module's name).
    pub entry: &'static str,
    /// The composed WGSL; every line ends with `\n`.
    pub text: String,
    /// For each line of `text` (index 0 is line 1): the module it came from
    /// and its 1-based line there.
    pub origin: Vec<(&'static str, u32)>,
}

impl Composed {
    /// Maps a 1-based line of [`Composed::text`] to `(module, 1-based line)`.
    /// Lines past the end map to the last line (naga may point just past the
    /// end of the text); an empty shader maps everything to `(entry, 1)`.
    pub fn locate(&self, composed_line: u32) -> (&str, u32) {
        let index = (composed_line.max(1) as usize - 1).min(self.origin.len().saturating_sub(1));
        self.origin
            .get(index)
            .map_or((self.entry, 1), |&(module, line)| (module, line))
    }
}

/// Composes the embedded shader `entry` (a name from [`crate::files`]).
pub fn compose(entry: &str) -> Result<Composed, ShaderError> {
    compose_with(entry, &crate::source)
}

/// Composes `entry`, reading every module's source from `lookup` (name without
/// `.wgsl` → source), e.g. in-memory fixtures in tests.
///
/// Module names that are not embedded files are interned for the life of the
/// process (they end up in [`Composed::origin`] as `&'static str`).
pub fn compose_with<'s>(
    entry: &str,
    lookup: &dyn Fn(&str) -> Option<&'s str>,
) -> Result<Composed, ShaderError> {
    let source = lookup(entry).ok_or_else(|| ShaderError::UnknownShader {
        name: entry.to_owned(),
    })?;
    let entry = intern(entry);
    let mut composer = Composer {
        lookup,
        included: HashSet::from([entry]),
        stack: Vec::new(),
        out: Composed {
            entry,
            text: String::with_capacity(source.len()),
            origin: Vec::new(),
        },
    };
    composer.include(entry, source)?;
    Ok(composer.out)
}

struct Composer<'a, 's> {
    lookup: &'a dyn Fn(&str) -> Option<&'s str>,
    /// Modules already included or being included.
    included: HashSet<&'static str>,
    /// The chain of modules being included, outermost first.
    stack: Vec<&'static str>,
    out: Composed,
}

impl Composer<'_, '_> {
    fn include(&mut self, module: &'static str, source: &str) -> Result<(), ShaderError> {
        self.stack.push(module);
        for (index, text) in source.lines().enumerate() {
            let line = u32::try_from(index + 1).unwrap_or(u32::MAX);
            let Some(import) = parse_import(text) else {
                self.out.text.push_str(text);
                self.out.text.push('\n');
                self.out.origin.push((module, line));
                continue;
            };
            let name = import.map_err(|()| ShaderError::MalformedImport {
                text: text.trim().to_owned(),
                file: module.to_owned(),
                line,
            })?;
            if self.stack.contains(&name) {
                // The whole chain from the entry: it shows how the cycle was reached.
                let mut chain: Vec<String> = self.stack.iter().map(|m| (*m).to_owned()).collect();
                chain.push(name.to_owned());
                return Err(ShaderError::ImportCycle {
                    chain,
                    file: module.to_owned(),
                    line,
                });
            }
            if self.included.contains(name) {
                continue;
            }
            let source = (self.lookup)(name).ok_or_else(|| ShaderError::UnknownImport {
                name: name.to_owned(),
                file: module.to_owned(),
                line,
            })?;
            let name = intern(name);
            self.included.insert(name);
            self.include(name, source)?;
        }
        self.stack.pop();
        Ok(())
    }
}

/// `None` if `line` is not an import directive, `Some(Err(()))` if it starts
/// with `#import` but is not `#import <identifier>`.
fn parse_import(line: &str) -> Option<Result<&str, ()>> {
    let rest = line.trim().strip_prefix("#import")?;
    let name = rest.trim();
    let ok = rest.starts_with(char::is_whitespace)
        && !name.is_empty()
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    Some(if ok { Ok(name) } else { Err(()) })
}

/// A `'static` copy of a module name: the embedded file's own name when there
/// is one, otherwise a string leaked once per distinct name.
fn intern(name: &str) -> &'static str {
    if let Some(&(n, _)) = crate::files().iter().find(|(n, _)| *n == name) {
        return n;
    }
    static INTERNED: Mutex<BTreeSet<&'static str>> = Mutex::new(BTreeSet::new());
    let mut set = INTERNED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&n) = set.get(name) {
        return n;
    }
    let n: &'static str = Box::leak(name.to_owned().into_boxed_str());
    set.insert(n);
    n
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn fixtures<'a>(files: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<&'a str> + 'a {
        let map: HashMap<&str, &str> = files.iter().copied().collect();
        move |name| map.get(name).copied()
    }

    #[test]
    fn imports_are_inlined_in_order_once_each() {
        let files = [
            (
                "stage",
                "// stage\n#import b\n  #import a  \nfn main() {}\n#import b\n",
            ),
            ("a", "// a1\n#import c\n// a3\n"),
            ("b", "// b1\r\n#import c\r\n// b3\r\n"),
            ("c", "// c1\n// c2"),
        ];
        let c = compose_with("stage", &fixtures(&files)).unwrap();
        assert_eq!(
            c.text,
            "// stage\n// b1\n// c1\n// c2\n// b3\n// a1\n// a3\nfn main() {}\n"
        );
        assert_eq!(
            c.origin,
            vec![
                ("stage", 1),
                ("b", 1),
                ("c", 1),
                ("c", 2),
                ("b", 3),
                ("a", 1),
                ("a", 3),
                ("stage", 4),
            ]
        );
        assert_eq!(c.entry, "stage");
        assert_eq!(c.locate(1), ("stage", 1));
        assert_eq!(c.locate(4), ("c", 2));
        assert_eq!(c.locate(8), ("stage", 4));
        assert_eq!(c.locate(99), ("stage", 4));
        assert_eq!(c.locate(0), ("stage", 1));
    }

    #[test]
    fn a_module_importing_the_entry_is_a_cycle() {
        let files = [("s", "#import a\n"), ("a", "\n\n#import s\n")];
        let err = compose_with("s", &fixtures(&files)).unwrap_err();
        assert_eq!(
            err,
            ShaderError::ImportCycle {
                chain: vec!["s".into(), "a".into(), "s".into()],
                file: "a".into(),
                line: 3,
            }
        );
        assert_eq!(err.to_string(), "a.wgsl:3: import cycle: s -> a -> s");
    }

    #[test]
    fn an_indirect_cycle_is_reported_with_its_chain() {
        let files = [
            ("s", "#import x\n#import a\n"),
            ("x", "// x\n"),
            ("a", "#import b\n"),
            ("b", "// b\n#import x\n#import a\n"),
        ];
        let err = compose_with("s", &fixtures(&files)).unwrap_err();
        assert_eq!(err.to_string(), "b.wgsl:3: import cycle: s -> a -> b -> a");
    }

    #[test]
    fn a_self_import_is_a_cycle() {
        let files = [("s", "#import s\n")];
        let err = compose_with("s", &fixtures(&files)).unwrap_err();
        assert_eq!(err.to_string(), "s.wgsl:1: import cycle: s -> s");
    }

    #[test]
    fn an_unknown_import_names_the_importing_file_and_line() {
        let files = [("s", "#import a\n"), ("a", "// a\n\n   #import nope\n")];
        let err = compose_with("s", &fixtures(&files)).unwrap_err();
        assert_eq!(
            err,
            ShaderError::UnknownImport {
                name: "nope".into(),
                file: "a".into(),
                line: 3,
            }
        );
        assert!(
            err.to_string()
                .starts_with("a.wgsl:3: unknown module `nope`")
        );
    }

    #[test]
    fn an_unknown_entry_is_an_error() {
        let err = compose_with("nope", &fixtures(&[])).unwrap_err();
        assert_eq!(
            err,
            ShaderError::UnknownShader {
                name: "nope".into()
            }
        );
        assert!(compose("no_such_shader").is_err());
    }

    #[test]
    fn malformed_imports_are_errors() {
        for bad in [
            "#import",
            "#import a b",
            "#importa",
            "#import a;",
            "#import \"a\"",
        ] {
            let src = format!("// ok\n{bad}\n");
            let files = [("s", src.as_str()), ("a", "")];
            let err = compose_with("s", &fixtures(&files)).unwrap_err();
            assert!(
                matches!(err, ShaderError::MalformedImport { line: 2, .. }),
                "{bad}: {err}"
            );
        }
        // Commented out: not a directive.
        let files = [("s", "// #import nope\n")];
        assert_eq!(
            compose_with("s", &fixtures(&files)).unwrap().text,
            "// #import nope\n"
        );
    }

    #[test]
    fn embedded_shaders_compose() {
        let c = compose("selftest_encode").unwrap();
        assert!(c.text.contains("fn f32_to_ordered"));
        assert!(!c.text.contains("#import"));
        assert_eq!(c.origin.len(), c.text.lines().count());
        assert!(c.origin.iter().any(|&(m, _)| m == "encode"));
    }
}
