//! The shader library: the `.wgsl` files each pelage crate embeds, composed through
//! `#import` lines and validated with naga.
//!
//! Every crate keeps its WGSL in a `wgsl/` folder beside its `Cargo.toml` and lists
//! the files with [`wgsl_sources!`](crate::wgsl_sources) into a `pub static SHADERS:`
//! [`ShaderSources`] (a listed file that does not exist fails the build). A shader's
//! name is its path relative to that folder, unique across crates:
//!
//! ```text
//! #import shared/math.wgsl      // pelage-gpu's wgsl/shared/math.wgsl
//! ```
//! An import line is replaced by the imported file (recursively), wrapped in
//! `// --- begin <name>` / `// --- end <name>` markers. Each file is included
//! at most once per composed shader: the first import wins, later ones become
//! comments. Import cycles and unknown files are errors naming the importing
//! file and line.
//!
//! A [`ShaderLibrary`] searches one crate's sources and those it `uses`
//! (transitively: pelage-shade's sources use pelage-gpu's). A [`Redirect`] carries
//! the sources of the file it redirects to, so a consumer composes a producer's
//! implementation of a contract (a [`ShaderBinding`](crate::ShaderBinding)) without
//! depending on the producer's crate.

use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};

use crate::context::Gpu;
use crate::error::Result;

/// The shaders of pelage-gpu: `shared/*.wgsl`, numeric helpers any pass includes
/// (constants and finite checks, hashing and noise, the bounds reduction). The
/// structs and functions the stages hand each other live in `pelage-contract`.
pub static SHADERS: ShaderSources = crate::wgsl_sources!(
    "shared/bounds.wgsl",
    "shared/math.wgsl",
    "shared/noise.wgsl",
);

/// A [`ShaderSources`] of the calling crate's WGSL files, embedded with `include_str!`.
///
/// ```text
/// pub static SHADERS: ShaderSources = pelage_gpu::wgsl_sources!(
///     uses [&pelage_gpu::SHADERS];      // sources its files import from (optional)
///     "strands/grow.wgsl",              // <crate>/wgsl/strands/grow.wgsl
///     "strands/lod.wgsl",
/// );
/// ```
/// Names are paths relative to the crate's `wgsl/` folder (or to the folder given as
/// `in "examples/wgsl";` before `uses`, relative to the crate's root). A name whose
/// file does not exist is a compile error; a file on disk left out of the list is
/// caught by a test calling [`ShaderSources::check_against_dir`].
#[macro_export]
macro_rules! wgsl_sources {
    (in $dir:literal; uses [$($uses:expr),* $(,)?]; $($name:literal),+ $(,)?) => {
        $crate::ShaderSources::new(
            ::core::env!("CARGO_PKG_NAME"),
            $dir,
            &[$((
                $name,
                ::core::include_str!(::core::concat!(
                    ::core::env!("CARGO_MANIFEST_DIR"), "/", $dir, "/", $name
                )),
            )),+],
            &[$($uses),*],
        )
    };
    (in $dir:literal; $($name:literal),+ $(,)?) => {
        $crate::wgsl_sources!(in $dir; uses []; $($name),+)
    };
    (uses [$($uses:expr),* $(,)?]; $($name:literal),+ $(,)?) => {
        $crate::wgsl_sources!(in "wgsl"; uses [$($uses),*]; $($name),+)
    };
    ($($name:literal),+ $(,)?) => {
        $crate::wgsl_sources!(in "wgsl"; uses []; $($name),+)
    };
}

/// The WGSL files one crate embeds (build it with [`wgsl_sources!`](crate::wgsl_sources)),
/// and the sources of the crates its files import from.
pub struct ShaderSources {
    crate_name: &'static str,
    dir: &'static str,
    files: &'static [(&'static str, &'static str)],
    uses: &'static [&'static ShaderSources],
}

impl ShaderSources {
    /// Sources of `crate_name`: `files` as (name, text), names relative to `dir`
    /// (relative to the crate's root), importing from `uses`. The macro
    /// [`wgsl_sources!`](crate::wgsl_sources) fills all four.
    pub const fn new(
        crate_name: &'static str,
        dir: &'static str,
        files: &'static [(&'static str, &'static str)],
        uses: &'static [&'static ShaderSources],
    ) -> Self {
        Self {
            crate_name,
            dir,
            files,
            uses,
        }
    }

    /// The crate the files belong to.
    pub const fn crate_name(&self) -> &'static str {
        self.crate_name
    }

    /// The folder the names are relative to, relative to the crate's root (`wgsl`).
    pub const fn dir(&self) -> &'static str {
        self.dir
    }

    /// Every file as (name, text), in the order listed.
    pub const fn files(&self) -> &'static [(&'static str, &'static str)] {
        self.files
    }

    /// The sources this crate's files import from.
    pub const fn uses(&self) -> &'static [&'static ShaderSources] {
        self.uses
    }

    /// The names of this crate's files (not those of [`ShaderSources::uses`]).
    pub fn names(&self) -> impl Iterator<Item = &'static str> + use<> {
        self.files.iter().map(|(name, _)| *name)
    }

    /// The text of one of this crate's files.
    pub fn get(&self, name: &str) -> Option<&'static str> {
        self.files
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, text)| *text)
    }

    /// A library searching these sources and, transitively, those they use.
    pub fn library(&'static self) -> ShaderLibrary {
        ShaderLibrary::new(self)
    }

    /// Checks these sources against the folder they were embedded from (pass
    /// `concat!(env!("CARGO_MANIFEST_DIR"), "/wgsl")`): every `.wgsl` file below `dir`
    /// is listed, every listed name is a file there and is listed once, and every
    /// file composes (with [`ShaderSources::library`]) and passes naga validation.
    /// Returns how many shaders were validated. Meant for each crate's tests.
    pub fn check_against_dir(
        &'static self,
        dir: impl AsRef<Path>,
    ) -> Result<usize, SourcesCheckError> {
        let dir = dir.as_ref();
        let mut on_disk = Vec::new();
        walk(dir, dir, &mut on_disk)?;
        on_disk.sort();
        let mut listed: Vec<&str> = self.names().collect();
        listed.sort_unstable();
        let mut duplicates: Vec<String> = listed
            .windows(2)
            .filter(|w| w[0] == w[1])
            .map(|w| w[0].to_string())
            .collect();
        duplicates.dedup();
        listed.dedup();
        let unlisted: Vec<String> = (on_disk.iter())
            .filter(|n| listed.binary_search(&n.as_str()).is_err())
            .cloned()
            .collect();
        let not_on_disk: Vec<String> = (listed.iter())
            .filter(|n| on_disk.binary_search_by(|d| d.as_str().cmp(n)).is_err())
            .map(|n| n.to_string())
            .collect();
        if !(unlisted.is_empty() && not_on_disk.is_empty() && duplicates.is_empty()) {
            return Err(SourcesCheckError::Mismatch {
                crate_name: self.crate_name.into(),
                dir: dir.to_path_buf(),
                unlisted,
                not_on_disk,
                duplicates,
            });
        }
        let library = self.library();
        let failures: Vec<ShaderError> = (self.names())
            .filter_map(|name| library.validate(name).err())
            .collect();
        if !failures.is_empty() {
            return Err(SourcesCheckError::Invalid {
                crate_name: self.crate_name.into(),
                total: listed.len(),
                failures,
            });
        }
        Ok(listed.len())
    }
}

impl fmt::Debug for ShaderSources {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ShaderSources")
            .field("crate_name", &self.crate_name)
            .field("dir", &self.dir)
            .field("names", &self.names().collect::<Vec<_>>())
            .field(
                "uses",
                &self.uses.iter().map(|u| u.crate_name).collect::<Vec<_>>(),
            )
            .finish()
    }
}

/// Names of every `.wgsl` file below `dir`, relative to `root`, '/'-separated.
fn walk(root: &Path, dir: &Path, names: &mut Vec<String>) -> Result<(), SourcesCheckError> {
    let io = |source| SourcesCheckError::Io {
        path: dir.to_path_buf(),
        source,
    };
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let path = entry.map_err(io)?.path();
        if path.is_dir() {
            walk(root, &path, names)?;
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let Ok(relative) = path.strip_prefix(root) else {
                continue;
            };
            let parts: Vec<_> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            names.push(parts.join("/"));
        }
    }
    Ok(())
}

/// What [`ShaderSources::check_against_dir`] found wrong.
#[derive(Debug, thiserror::Error)]
pub enum SourcesCheckError {
    /// The folder could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The list in `wgsl_sources!` and the files on disk differ.
    #[error(
        "{crate_name}: the shaders listed in its `wgsl_sources!` and the .wgsl files under {} \
         differ:{}{}{}",
        dir.display(),
        list("\n  on disk but not listed (add them to the list, or delete them)", unlisted),
        list("\n  listed but not on disk (is this the folder they were embedded from?)", not_on_disk),
        list("\n  listed more than once", duplicates)
    )]
    Mismatch {
        /// The crate checked.
        crate_name: String,
        /// The folder checked.
        dir: PathBuf,
        /// Files on disk the list leaves out.
        unlisted: Vec<String>,
        /// Listed names with no file on disk.
        not_on_disk: Vec<String>,
        /// Names listed more than once.
        duplicates: Vec<String>,
    },
    /// Some shaders do not compose or do not pass naga validation.
    #[error(
        "{crate_name}: {} of {total} shaders fail:\n\n{}",
        failures.len(),
        failures.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n\n")
    )]
    Invalid {
        /// The crate checked.
        crate_name: String,
        /// How many shaders it lists.
        total: usize,
        /// Every failure.
        failures: Vec<ShaderError>,
    },
}

/// `: [a, b]` after `what`, or nothing for an empty list.
fn list(what: &str, names: &[String]) -> String {
    if names.is_empty() {
        String::new()
    } else {
        format!("{what}: [{}]", names.join(", "))
    }
}

/// An import redirected: `#import from` includes the file `to` instead, found in
/// `sources` when given (the crate that implements the contract), else in the library.
#[derive(Clone, Copy, Debug)]
pub struct Redirect {
    /// The name imported (a contract, e.g. `shadow/none.wgsl`).
    pub from: &'static str,
    /// The file included in its place (e.g. `shadow/voxel_lookup.wgsl`).
    pub to: &'static str,
    /// The sources holding `to`, added to the library for this composition.
    pub sources: Option<&'static ShaderSources>,
}

impl Redirect {
    /// `from` read as `to`, a file the library already holds.
    pub const fn new(from: &'static str, to: &'static str) -> Self {
        Self {
            from,
            to,
            sources: None,
        }
    }

    /// `from` read as `to`, a file of `sources`.
    pub const fn to_sources(
        from: &'static str,
        to: &'static str,
        sources: &'static ShaderSources,
    ) -> Self {
        Self {
            from,
            to,
            sources: Some(sources),
        }
    }
}

impl From<(&'static str, &'static str)> for Redirect {
    fn from((from, to): (&'static str, &'static str)) -> Self {
        Self::new(from, to)
    }
}

/// What went wrong finding, composing, parsing or validating a shader.
#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    /// No file of the library has this name.
    #[error(
        "unknown shader `{name}`; searched the WGSL of {}, which holds: [{}]. Names are paths \
         relative to a crate's wgsl/ folder, embedded when the crate lists them in \
         `wgsl_sources!`; another crate's files come in through its `ShaderSources` \
         (a `ShaderBinding`'s redirect, or `ShaderLibrary::with`)",
        searched.join(", "),
        holds.join(", ")
    )]
    Unknown {
        /// The name asked for.
        name: String,
        /// The crates whose sources were searched.
        searched: Vec<String>,
        /// Every name they hold, sorted.
        holds: Vec<String>,
    },
    /// Two crates' sources hold a file of the same name.
    #[error(
        "shader `{name}` is in the WGSL of more than one crate ({}); names must be unique \
         across crates: rename one",
        crates.join(", ")
    )]
    Ambiguous {
        /// The name.
        name: String,
        /// The crates holding it.
        crates: Vec<String>,
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

/// The shaders of one or more crates, searched by name (see the module docs for
/// `#import`). Build it from the composing crate's sources:
/// `pelage_strands::SHADERS.library()`.
#[derive(Clone)]
pub struct ShaderLibrary {
    sources: Vec<&'static ShaderSources>,
}

impl fmt::Debug for ShaderLibrary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ShaderLibrary")
            .field("crates", &self.crate_names())
            .finish()
    }
}

impl ShaderLibrary {
    /// A library of `sources` and, transitively, the sources they use.
    pub fn new(sources: &'static ShaderSources) -> Self {
        Self {
            sources: Vec::new(),
        }
        .with(sources)
    }

    /// This library with `sources` (and those they use) added; sources already held
    /// are not added twice.
    pub fn with(mut self, sources: &'static ShaderSources) -> Self {
        self.add(sources);
        self
    }

    fn add(&mut self, sources: &'static ShaderSources) {
        if self.sources.iter().any(|s| std::ptr::eq(*s, sources)) {
            return;
        }
        self.sources.push(sources);
        for used in sources.uses {
            self.add(used);
        }
    }

    /// The sources searched, in search order.
    pub fn sources(&self) -> &[&'static ShaderSources] {
        &self.sources
    }

    /// The crates whose sources are searched, in search order.
    pub fn crate_names(&self) -> Vec<&'static str> {
        self.sources.iter().map(|s| s.crate_name).collect()
    }

    /// Names of every shader the library holds, sorted.
    pub fn names(&self) -> Vec<&'static str> {
        let mut names: Vec<_> = self.sources.iter().flat_map(|s| s.names()).collect();
        names.sort_unstable();
        names
    }

    /// The raw text of one file, imports unresolved.
    pub fn source(&self, name: &str) -> Result<&'static str, ShaderError> {
        self.find(name)?.ok_or_else(|| self.unknown(name))
    }

    /// The file with its `#import` lines resolved recursively.
    pub fn compose(&self, name: &str) -> Result<String, ShaderError> {
        self.compose_redirected(name, &[])
    }

    /// Compose, then parse and validate with naga (all validation checks, all
    /// capabilities). Errors carry naga's report and the file and line the
    /// problem came from.
    pub fn validate(&self, name: &str) -> Result<naga::Module, ShaderError> {
        self.validate_redirected(name, &[])
    }

    /// Compose, validate with naga, and create a [`wgpu::ShaderModule`] inside
    /// an error scope (so the device's own checks are caught too).
    pub fn module(&self, gpu: &Gpu, name: &str) -> Result<wgpu::ShaderModule> {
        self.module_redirected(gpu, name, &[])
    }

    /// [`ShaderLibrary::compose`] with some imports redirected: for each
    /// [`Redirect`], `#import from` includes the file `to` instead, searched in the
    /// redirect's sources too. This is how a pass picks an implementation of a
    /// contract (say, which shadow method `shadow/none.wgsl` stands for) without
    /// knowing the method.
    pub fn compose_redirected(
        &self,
        name: &str,
        redirects: &[Redirect],
    ) -> Result<String, ShaderError> {
        Ok(self.compose_with(name, redirects)?.text)
    }

    /// [`ShaderLibrary::validate`] with redirected imports.
    pub fn validate_redirected(
        &self,
        name: &str,
        redirects: &[Redirect],
    ) -> Result<naga::Module, ShaderError> {
        validate_composed(name, &self.compose_with(name, redirects)?)
    }

    /// [`ShaderLibrary::module`] with redirected imports.
    pub fn module_redirected(
        &self,
        gpu: &Gpu,
        name: &str,
        redirects: &[Redirect],
    ) -> Result<wgpu::ShaderModule> {
        let composed = self.compose_with(name, redirects)?;
        validate_composed(name, &composed)?;
        gpu.scoped(|device| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(composed.text.into()),
            })
        })
    }

    /// Compose `name` with `redirects`, their sources added.
    fn compose_with(&self, name: &str, redirects: &[Redirect]) -> Result<Composed, ShaderError> {
        let library = (redirects.iter())
            .filter_map(|r| r.sources)
            .fold(self.clone(), ShaderLibrary::with);
        compose_with(
            name,
            &Resolver {
                library: &library,
                redirects,
            },
        )
    }

    /// The file called `name`, or an error if more than one crate holds one.
    fn find(&self, name: &str) -> Result<Option<&'static str>, ShaderError> {
        let mut found: Option<(&ShaderSources, &'static str)> = None;
        for sources in &self.sources {
            let Some(text) = sources.get(name) else {
                continue;
            };
            if let Some((first, _)) = found {
                return Err(ShaderError::Ambiguous {
                    name: name.into(),
                    crates: vec![first.crate_name.into(), sources.crate_name.into()],
                });
            }
            found = Some((sources, text));
        }
        Ok(found.map(|(_, text)| text))
    }

    fn unknown(&self, name: &str) -> ShaderError {
        ShaderError::Unknown {
            name: name.into(),
            searched: self.crate_names().into_iter().map(String::from).collect(),
            holds: self.names().into_iter().map(String::from).collect(),
        }
    }
}

/// Finds the files of one composition: the library's, with imports redirected.
struct Resolver<'a> {
    library: &'a ShaderLibrary,
    redirects: &'a [Redirect],
}

impl Resolver<'_> {
    /// The file `name` stands for, and its text if there is one.
    fn find<'n>(&self, name: &'n str) -> Result<(&'n str, Option<&'static str>), ShaderError> {
        let target = (self.redirects.iter())
            .find(|r| r.from == name)
            .map_or(name, |r| r.to);
        Ok((target, self.library.find(target)?))
    }

    /// Why an import of `name` found nothing.
    fn missing(&self, name: &str, target: &str) -> String {
        let redirected = if name == target {
            String::new()
        } else {
            format!(" (`{name}` is redirected to `{target}`)")
        };
        format!(
            "no such file in the WGSL of {}{redirected}; names are paths relative to a crate's \
             wgsl/ folder, e.g. shared/math.wgsl",
            self.library.crate_names().join(", ")
        )
    }
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

/// Compose `root`, finding files with `files`.
fn compose_with(root: &str, files: &Resolver<'_>) -> Result<Composed, ShaderError> {
    let (target, source) = files.find(root)?;
    let source = source.ok_or_else(|| files.library.unknown(target))?;
    let mut out = Composed::default();
    let mut stack = Vec::new();
    let mut done = HashSet::new();
    include(target, source, files, &mut stack, &mut done, &mut out)?;
    Ok(out)
}

/// Append the file `name` to `out`, resolving its imports depth first. `stack`
/// holds the files being included (for cycle detection), `done` those finished;
/// both name files after redirection.
fn include(
    name: &str,
    source: &str,
    files: &Resolver<'_>,
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
        let import = match parse_import(line) {
            None => {
                out.push(line, name, number);
                continue;
            }
            Some(Err((target, reason))) => return Err(import_error(target, reason)),
            Some(Ok(import)) => import,
        };
        let (target, imported) = files.find(import)?;
        let shown = if target == import {
            target.to_string()
        } else {
            format!("{target} (as {import})")
        };
        if stack.iter().any(|s| s == target) {
            let mut chain = stack.clone();
            chain.push(target.to_string());
            return Err(ShaderError::Cycle { chain });
        }
        if done.contains(target) {
            out.push(
                &format!("// #import {shown} (already included)"),
                name,
                number,
            );
            continue;
        }
        let Some(imported) = imported else {
            return Err(import_error(import, &files.missing(import, target)));
        };
        out.push(&format!("// --- begin {shown}"), name, number);
        include(target, imported, files, stack, done, out)?;
        out.push(&format!("// --- end {shown}"), name, number);
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
        Err((
            target,
            "imports name a .wgsl file relative to a crate's wgsl/ folder",
        ))
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

    /// Sources of a made-up crate, leaked so they live as long as a crate's static.
    fn sources(
        crate_name: &'static str,
        files: &[(&'static str, &'static str)],
        uses: &[&'static ShaderSources],
    ) -> &'static ShaderSources {
        let files = Box::leak(files.to_vec().into_boxed_slice());
        let uses = Box::leak(uses.to_vec().into_boxed_slice());
        Box::leak(Box::new(ShaderSources::new(
            crate_name, "wgsl", files, uses,
        )))
    }

    /// Compose `root` from an in-memory set of files.
    fn compose(files: &[(&'static str, &'static str)], root: &str) -> Result<String, ShaderError> {
        sources("test", files, &[]).library().compose(root)
    }

    /// A scratch folder of `.wgsl` files (name, text), removed when dropped.
    struct Scratch(PathBuf);

    impl Scratch {
        fn new(tag: &str, files: &[(&str, &str)]) -> Self {
            let dir = std::env::temp_dir()
                .join(format!("pelage-gpu-shaders-{tag}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            for (name, text) in files {
                let path = dir.join(name);
                std::fs::create_dir_all(path.parent().unwrap()).unwrap();
                std::fs::write(path, text).unwrap();
            }
            Self(dir)
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
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
    fn unknown_root_lists_crates_and_names() {
        let base = sources("base-crate", &[("lib.wgsl", "")], &[]);
        let top = sources("top-crate", &[("top.wgsl", "")], &[base]);
        let err = top.library().compose("nope.wgsl").unwrap_err();
        let ShaderError::Unknown {
            name,
            searched,
            holds,
        } = &err
        else {
            panic!("expected an unknown shader, got {err:?}");
        };
        assert_eq!(name, "nope.wgsl");
        assert_eq!(searched, &["top-crate", "base-crate"]);
        assert_eq!(holds, &["lib.wgsl", "top.wgsl"]);
        let message = err.to_string();
        assert!(message.contains("top-crate, base-crate"), "{message}");
        assert!(message.contains("[lib.wgsl, top.wgsl]"), "{message}");
    }

    #[test]
    fn imports_reach_used_crates_transitively() {
        let base = sources("base", &[("base/a.wgsl", "fn a() {}")], &[]);
        let mid = sources(
            "mid",
            &[("mid/b.wgsl", "#import base/a.wgsl\nfn b() {}")],
            &[base],
        );
        let top = sources(
            "top",
            &[("top/c.wgsl", "#import mid/b.wgsl\nfn c() {}")],
            &[mid, base],
        );
        let library = top.library();
        assert_eq!(library.crate_names(), ["top", "mid", "base"]);
        let text = library.compose("top/c.wgsl").unwrap();
        assert!(
            text.find("fn a()").unwrap() < text.find("fn c()").unwrap(),
            "{text}"
        );
        // The producer's files are found only when a redirect brings its sources.
        assert!(matches!(
            base.library().compose("top/c.wgsl"),
            Err(ShaderError::Unknown { .. })
        ));
    }

    #[test]
    fn redirect_brings_the_producers_sources() {
        let base = sources(
            "base",
            &[("contract.wgsl", "fn f() -> f32 { return 1.0; }")],
            &[],
        );
        let producer = sources(
            "producer",
            &[
                (
                    "impl.wgsl",
                    "#import helper.wgsl\nfn f() -> f32 { return g(); }",
                ),
                ("helper.wgsl", "fn g() -> f32 { return 0.5; }"),
            ],
            &[base],
        );
        let consumer = sources(
            "consumer",
            &[(
                "pass.wgsl",
                "#import contract.wgsl\nfn main() -> f32 { return f(); }",
            )],
            &[base],
        );
        let library = consumer.library();
        let plain = library.compose("pass.wgsl").unwrap();
        assert!(plain.contains("return 1.0"), "{plain}");

        let redirect = Redirect::to_sources("contract.wgsl", "impl.wgsl", producer);
        let text = library
            .compose_redirected("pass.wgsl", &[redirect])
            .unwrap();
        assert!(
            text.contains("// --- begin impl.wgsl (as contract.wgsl)"),
            "{text}"
        );
        assert!(
            text.contains("return g()") && text.contains("return 0.5"),
            "{text}"
        );
        assert!(!text.contains("return 1.0"), "{text}");
        library
            .validate_redirected("pass.wgsl", &[redirect])
            .unwrap();

        // Without the producer's sources the redirect target is missing, and the
        // error says which crates were searched and what was redirected.
        let err = (library
            .compose_redirected("pass.wgsl", &[("contract.wgsl", "impl.wgsl").into()]))
        .unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(err, ShaderError::Import { line: 1, .. }),
            "{err:?}"
        );
        assert!(
            message.starts_with("pass.wgsl:1: cannot import `contract.wgsl`"),
            "{message}"
        );
        assert!(message.contains("consumer, base"), "{message}");
        assert!(message.contains("redirected to `impl.wgsl`"), "{message}");
    }

    #[test]
    fn a_name_in_two_crates_is_an_error() {
        let base = sources("base", &[("same.wgsl", "")], &[]);
        let top = sources(
            "top",
            &[("same.wgsl", ""), ("top.wgsl", "#import same.wgsl")],
            &[base],
        );
        for root in ["same.wgsl", "top.wgsl"] {
            match top.library().compose(root) {
                Err(ShaderError::Ambiguous { name, crates }) => {
                    assert_eq!(name, "same.wgsl");
                    assert_eq!(crates, ["top", "base"]);
                }
                other => panic!("{root}: expected an ambiguity, got {other:?}"),
            }
        }
    }

    #[test]
    fn library_holds_each_crate_once() {
        let base = sources("base", &[("a.wgsl", "")], &[]);
        let top = sources("top", &[("b.wgsl", "")], &[base]);
        let library = top.library().with(base).with(top);
        assert_eq!(library.crate_names(), ["top", "base"]);
        assert_eq!(library.names(), ["a.wgsl", "b.wgsl"]);
        assert_eq!(library.source("a.wgsl").unwrap(), "");
    }

    #[test]
    fn check_against_dir_passes_a_matching_folder() {
        let files = [
            ("x/a.wgsl", "fn a() {}"),
            ("b.wgsl", "#import x/a.wgsl\nfn b() { a(); }"),
        ];
        let dir = Scratch::new("ok", &files);
        let sources = sources("ok-crate", &files, &[]);
        assert_eq!(sources.check_against_dir(&dir.0).unwrap(), 2);
    }

    #[test]
    fn check_against_dir_finds_unlisted_missing_and_twice_listed_files() {
        let dir = Scratch::new(
            "mismatch",
            &[
                ("a.wgsl", ""),
                ("sub/forgotten.wgsl", ""),
                ("notes.txt", ""),
            ],
        );
        let sources = sources(
            "mismatch-crate",
            &[("a.wgsl", ""), ("a.wgsl", ""), ("gone.wgsl", "")],
            &[],
        );
        let err = sources.check_against_dir(&dir.0).unwrap_err();
        let SourcesCheckError::Mismatch {
            unlisted,
            not_on_disk,
            duplicates,
            ..
        } = &err
        else {
            panic!("expected a mismatch, got {err:?}");
        };
        assert_eq!(unlisted, &["sub/forgotten.wgsl"]);
        assert_eq!(not_on_disk, &["gone.wgsl"]);
        assert_eq!(duplicates, &["a.wgsl"]);
        let message = err.to_string();
        assert!(message.starts_with("mismatch-crate:"), "{message}");
        assert!(message.contains("sub/forgotten.wgsl"), "{message}");
    }

    #[test]
    fn check_against_dir_reports_every_invalid_shader() {
        let files = [
            ("good.wgsl", "fn f() {}"),
            ("bad.wgsl", "fn f() -> f32 { return vec2<f32>(1.0); }"),
            ("broken.wgsl", "#import nope.wgsl"),
        ];
        let dir = Scratch::new("invalid", &files);
        let sources = sources("invalid-crate", &files, &[]);
        match sources.check_against_dir(&dir.0) {
            Err(SourcesCheckError::Invalid {
                total, failures, ..
            }) => {
                assert_eq!(total, 3);
                assert_eq!(failures.len(), 2, "{failures:?}");
                assert!(matches!(failures[0], ShaderError::Validate { .. }));
                assert!(matches!(failures[1], ShaderError::Import { .. }));
            }
            other => panic!("expected invalid shaders, got {other:?}"),
        }
        assert!(matches!(
            sources.check_against_dir(dir.0.join("absent")),
            Err(SourcesCheckError::Io { .. })
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
        let err = sources("test", &files, &[])
            .library()
            .validate("main.wgsl")
            .unwrap_err();
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
        sources("test", &files, &[])
            .library()
            .validate("ok.wgsl")
            .unwrap();
    }
}
