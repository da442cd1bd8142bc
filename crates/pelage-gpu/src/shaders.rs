//! The shader library: every `.wgsl` file under the workspace's `wgsl/` folder,
//! embedded at build time, composed through `#import` lines and validated with naga.
//!
//! ```text
//! #import shared/math.wgsl      // paths are relative to wgsl/
//! ```
//! An import line is replaced by the imported file (recursively), wrapped in
//! `// --- begin <name>` / `// --- end <name>` markers. Each file is included
//! at most once per composed shader: the first import wins, later ones become
//! comments. Import cycles and unknown files are errors naming the importing
//! file and line.

use std::collections::HashSet;

use crate::context::Gpu;
use crate::error::Result;

include!(concat!(env!("OUT_DIR"), "/wgsl_sources.rs"));

/// What went wrong finding, composing, parsing or validating a shader.
#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    /// No embedded file has this name.
    #[error(
        "unknown shader `{name}`; the library holds: [{}]. Names are paths relative to wgsl/; \
         files added there are embedded at the next build",
        ShaderLibrary::names().collect::<Vec<_>>().join(", ")
    )]
    Unknown {
        /// The name asked for.
        name: String,
    },
    /// An `#import` line is malformed or names a file that does not exist.
    #[error("{file}:{line}: cannot import `{target}`: {reason}")]
    Import {
        /// The file holding the import line.
        file: String,
        /// 1-based line number of the import.
        line: usize,
        /// What the line tried to import.
        target: String,
        /// Why it failed and what to do.
        reason: String,
    },
    /// Files import each other in a loop.
    #[error("import cycle: {}; remove one of these imports", .chain.join(" -> "))]
    Cycle {
        /// The files in the loop, starting and ending with the same one.
        chain: Vec<String>,
    },
    /// naga could not parse the composed shader.
    #[error("shader `{name}` does not parse:\n{message}")]
    Parse {
        /// The shader composed.
        name: String,
        /// naga's report, with the originating file and line.
        message: String,
    },
    /// naga parsed the composed shader but it is not valid.
    #[error("shader `{name}` fails validation:\n{message}")]
    Validate {
        /// The shader composed.
        name: String,
        /// naga's report, with the originating file and line.
        message: String,
    },
}

/// Access to the embedded shaders (see the module docs for `#import`).
pub struct ShaderLibrary;

impl ShaderLibrary {
    /// Names of every embedded shader (paths relative to `wgsl/`), sorted.
    pub fn names() -> impl Iterator<Item = &'static str> {
        SOURCES.iter().map(|(name, _)| *name)
    }

    /// The raw text of one file, imports unresolved.
    pub fn source(name: &str) -> Result<&'static str, ShaderError> {
        lookup(name).ok_or_else(|| ShaderError::Unknown { name: name.into() })
    }

    /// The file with its `#import` lines resolved recursively.
    pub fn compose(name: &str) -> Result<String, ShaderError> {
        Ok(compose_with(name, &lookup)?.text)
    }

    /// Compose, then parse and validate with naga (all validation checks, all
    /// capabilities). Errors carry naga's report and the file and line the
    /// problem came from.
    pub fn validate(name: &str) -> Result<naga::Module, ShaderError> {
        validate_composed(name, &compose_with(name, &lookup)?)
    }

    /// Compose, validate with naga, and create a [`wgpu::ShaderModule`] inside
    /// an error scope (so the device's own checks are caught too).
    pub fn module(gpu: &Gpu, name: &str) -> Result<wgpu::ShaderModule> {
        Self::module_redirected(gpu, name, &[])
    }

    /// [`ShaderLibrary::compose`] with some imports redirected: for each
    /// `(from, to)`, `#import from` includes the file `to` instead. This is how a
    /// pass picks an implementation of a contract (say, which shadow method
    /// `shadow/none.wgsl` stands for) without knowing the method.
    pub fn compose_redirected(
        name: &str,
        redirects: &[(&str, &str)],
    ) -> Result<String, ShaderError> {
        Ok(compose_with(name, &redirected(redirects))?.text)
    }

    /// [`ShaderLibrary::validate`] with redirected imports.
    pub fn validate_redirected(
        name: &str,
        redirects: &[(&str, &str)],
    ) -> Result<naga::Module, ShaderError> {
        validate_composed(name, &compose_with(name, &redirected(redirects))?)
    }

    /// [`ShaderLibrary::module`] with redirected imports.
    pub fn module_redirected(
        gpu: &Gpu,
        name: &str,
        redirects: &[(&str, &str)],
    ) -> Result<wgpu::ShaderModule> {
        let composed = compose_with(name, &redirected(redirects))?;
        validate_composed(name, &composed)?;
        gpu.scoped(|device| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(composed.text.into()),
            })
        })
    }
}

/// A lookup that reads `to` wherever `from` is asked for.
fn redirected<'r>(
    redirects: &'r [(&'r str, &'r str)],
) -> impl Fn(&str) -> Option<&'static str> + 'r {
    move |name| {
        let target = redirects
            .iter()
            .find(|(from, _)| *from == name)
            .map_or(name, |(_, to)| *to);
        lookup(target)
    }
}

/// Find an embedded file by name.
fn lookup(name: &str) -> Option<&'static str> {
    SOURCES
        .binary_search_by(|(n, _)| (*n).cmp(name))
        .ok()
        .and_then(|i| SOURCES.get(i))
        .map(|(_, source)| *source)
}

/// A composed shader and, for each of its lines, the file and 1-based line it came from.
#[derive(Debug, Default)]
struct Composed {
    text: String,
    origin: Vec<(String, usize)>,
}

impl Composed {
    fn push(&mut self, line: &str, file: &str, number: usize) {
        self.text.push_str(line);
        self.text.push('\n');
        self.origin.push((file.to_string(), number));
    }

    /// For each labelled span naga reported, which file and line it came from:
    /// naga's report numbers the lines of the composed text.
    fn origins<'s>(&self, spans: impl Iterator<Item = (naga::Span, &'s str)>) -> String {
        let mut notes = String::new();
        for (span, label) in spans {
            let Some(start) = span.to_range().map(|r| r.start) else {
                continue;
            };
            let Some(prefix) = self.text.get(..start) else {
                continue;
            };
            let line = prefix.matches('\n').count() + 1;
            if let Some((file, number)) = self.origin.get(line - 1) {
                notes.push_str(&format!("\ncomposed line {line} is {file}:{number}"));
                if !label.is_empty() {
                    notes.push_str(&format!(" ({label})"));
                }
            }
        }
        notes
    }
}

/// Compose `root`, finding files with `lookup`.
fn compose_with<'a>(
    root: &str,
    lookup: &dyn Fn(&str) -> Option<&'a str>,
) -> Result<Composed, ShaderError> {
    let source = lookup(root).ok_or_else(|| ShaderError::Unknown { name: root.into() })?;
    let mut out = Composed::default();
    let mut stack = Vec::new();
    let mut done = HashSet::new();
    include(root, source, lookup, &mut stack, &mut done, &mut out)?;
    Ok(out)
}

/// Append `name` to `out`, resolving its imports depth first. `stack` holds
/// the files being included (for cycle detection), `done` those finished.
fn include<'a>(
    name: &str,
    source: &str,
    lookup: &dyn Fn(&str) -> Option<&'a str>,
    stack: &mut Vec<String>,
    done: &mut HashSet<String>,
    out: &mut Composed,
) -> Result<(), ShaderError> {
    stack.push(name.to_string());
    for (index, line) in source.lines().enumerate() {
        let number = index + 1;
        let import_error = |target: &str, reason: &str| ShaderError::Import {
            file: name.to_string(),
            line: number,
            target: target.to_string(),
            reason: reason.to_string(),
        };
        let target = match parse_import(line) {
            None => {
                out.push(line, name, number);
                continue;
            }
            Some(Err((target, reason))) => return Err(import_error(target, reason)),
            Some(Ok(target)) => target,
        };
        if stack.iter().any(|s| s == target) {
            let mut chain = stack.clone();
            chain.push(target.to_string());
            return Err(ShaderError::Cycle { chain });
        }
        if done.contains(target) {
            out.push(
                &format!("// #import {target} (already included)"),
                name,
                number,
            );
            continue;
        }
        let Some(imported) = lookup(target) else {
            return Err(import_error(
                target,
                "no such file under wgsl/ (paths are relative to wgsl/, e.g. shared/math.wgsl)",
            ));
        };
        out.push(&format!("// --- begin {target}"), name, number);
        include(target, imported, lookup, stack, done, out)?;
        out.push(&format!("// --- end {target}"), name, number);
    }
    stack.pop();
    done.insert(name.to_string());
    Ok(())
}

/// `None` for an ordinary line; for an `#import` line the target, or the text
/// found and why it is not a valid import.
fn parse_import(line: &str) -> Option<Result<&str, (&str, &'static str)>> {
    let rest = line.trim_start().strip_prefix("#import")?;
    // A trailing `// comment` is allowed.
    let rest = rest.split_once("//").map_or(rest, |(before, _)| before);
    if !rest.is_empty() && !rest.starts_with(char::is_whitespace) {
        return Some(Err((line.trim(), "write `#import path/to/file.wgsl`")));
    }
    let target = rest.trim();
    let target = target
        .strip_prefix('"')
        .and_then(|t| t.strip_suffix('"'))
        .unwrap_or(target);
    Some(if target.is_empty() {
        Err((
            target,
            "the path is missing; write `#import path/to/file.wgsl`",
        ))
    } else if target.contains(char::is_whitespace) {
        Err((target, "only a `// comment` may follow the path"))
    } else if !target.ends_with(".wgsl") {
        Err((target, "imports name a .wgsl file relative to wgsl/"))
    } else {
        Ok(target)
    })
}

/// Parse and validate a composed shader with naga.
fn validate_composed(name: &str, composed: &Composed) -> Result<naga::Module, ShaderError> {
    let text = &composed.text;
    let module = naga::front::wgsl::parse_str(text).map_err(|e| ShaderError::Parse {
        name: name.into(),
        message: e.emit_to_string_with_path(text, name) + &composed.origins(e.labels()),
    })?;
    let mut validator = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    validator
        .validate(&module)
        .map_err(|e| ShaderError::Validate {
            name: name.into(),
            message: e.emit_to_string_with_path(text, name)
                + &composed.origins(e.spans().map(|(span, label)| (*span, label.as_str()))),
        })?;
    Ok(module)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Compose `root` from an in-memory set of files.
    fn compose(files: &[(&'static str, &'static str)], root: &str) -> Result<String, ShaderError> {
        let find = |name: &str| files.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
        compose_with(root, &find).map(|c| c.text)
    }

    #[test]
    fn import_is_inlined_with_markers() {
        let files = [
            ("a.wgsl", "#import lib/b.wgsl // helpers\nfn a() {}"),
            ("lib/b.wgsl", "fn b() {}"),
        ];
        let text = compose(&files, "a.wgsl").unwrap();
        assert_eq!(
            text,
            "// --- begin lib/b.wgsl\nfn b() {}\n// --- end lib/b.wgsl\nfn a() {}\n"
        );
    }

    #[test]
    fn nested_import_comes_first() {
        let files = [
            ("a.wgsl", "#import b.wgsl\nfn a() {}"),
            ("b.wgsl", "  #import c.wgsl\nfn b() {}"),
            ("c.wgsl", "fn c() {}"),
        ];
        let text = compose(&files, "a.wgsl").unwrap();
        let (c, b, a) = (
            text.find("fn c()").unwrap(),
            text.find("fn b()").unwrap(),
            text.find("fn a()").unwrap(),
        );
        assert!(c < b && b < a, "{text}");
    }

    #[test]
    fn duplicate_import_included_once() {
        let files = [
            (
                "a.wgsl",
                "#import b.wgsl\n#import c.wgsl\n#import \"c.wgsl\"\nfn a() {}",
            ),
            ("b.wgsl", "#import c.wgsl\nfn b() {}"),
            ("c.wgsl", "fn c() {}"),
        ];
        let text = compose(&files, "a.wgsl").unwrap();
        assert_eq!(text.matches("fn c()").count(), 1, "{text}");
        assert!(text.contains("already included"));
    }

    #[test]
    fn cycle_is_an_error() {
        let files = [("a.wgsl", "#import b.wgsl"), ("b.wgsl", "#import a.wgsl")];
        match compose(&files, "a.wgsl") {
            Err(ShaderError::Cycle { chain }) => assert_eq!(chain, ["a.wgsl", "b.wgsl", "a.wgsl"]),
            other => panic!("expected a cycle, got {other:?}"),
        }
    }

    #[test]
    fn missing_file_names_importer_and_line() {
        let files = [("a.wgsl", "fn a() {}\n#import nope.wgsl")];
        let err = compose(&files, "a.wgsl").unwrap_err();
        assert!(
            matches!(&err, ShaderError::Import { file, line: 2, target, .. }
                if file == "a.wgsl" && target == "nope.wgsl"),
            "{err:?}"
        );
        assert!(
            err.to_string()
                .starts_with("a.wgsl:2: cannot import `nope.wgsl`")
        );
    }

    #[test]
    fn malformed_imports_are_errors() {
        for line in [
            "#import",
            "#import a.wgsl extra",
            "#import a.txt",
            "#importa.wgsl",
        ] {
            let files = [("x.wgsl", line), ("a.wgsl", "")];
            let files: Vec<_> = files.to_vec();
            let err = compose(&files, "x.wgsl").unwrap_err();
            assert!(
                matches!(err, ShaderError::Import { line: 1, .. }),
                "{line}: {err:?}"
            );
        }
    }

    #[test]
    fn unknown_root() {
        assert!(matches!(
            compose(&[], "none.wgsl"),
            Err(ShaderError::Unknown { .. })
        ));
    }

    #[test]
    fn bad_shader_reports_naga_message_and_origin() {
        let files = [
            (
                "main.wgsl",
                "#import lib.wgsl\nfn f() -> f32 { return helper(); }",
            ),
            (
                "lib.wgsl",
                "fn helper() -> f32 {\n    return vec2<f32>(1.0);\n}",
            ),
        ];
        let find = |name: &str| files.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
        let composed = compose_with("main.wgsl", &find).unwrap();
        let err = validate_composed("main.wgsl", &composed).unwrap_err();
        let ShaderError::Validate { message, .. } = &err else {
            panic!("expected a validation error, got {err:?}");
        };
        // naga's own report, pointing into the composed text, and where that came from.
        assert!(message.contains("main.wgsl:"), "{message}");
        assert!(message.contains("lib.wgsl:2"), "{message}");
    }

    #[test]
    fn good_shader_validates() {
        let files = [("ok.wgsl", "fn f(x: f32) -> f32 { return x * 2.0; }")];
        let find = |name: &str| files.iter().find(|(n, _)| *n == name).map(|(_, s)| *s);
        let composed = compose_with("ok.wgsl", &find).unwrap();
        validate_composed("ok.wgsl", &composed).unwrap();
    }

    #[test]
    fn sources_are_sorted_for_lookup() {
        assert!(SOURCES.windows(2).all(|w| w[0].0 < w[1].0));
    }
}
