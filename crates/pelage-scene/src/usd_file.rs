//! USD grooms: every `UsdGeomBasisCurves` prim of a `.usda`, `.usdc`, `.usd` or `.usdz`
//! file read into one [`Groom`], and a groom written back as linear `BasisCurves`
//! (feature `usd`).
//!
//! The files are parsed by the pure-Rust [`openusd`] crate, which reads and writes all
//! three encodings (text, binary crate, zip package). pelage reads the file's **root
//! layer** only: composition arcs (sublayers, references, payloads, variants, inherits)
//! are not followed, and `over` and `class` prims are not drawn. openusd can compose a
//! stage, but only by opening files itself, which would bypass the size cap below; a
//! groom exported from a DCC is a flat layer.
//!
//! What is read, per `BasisCurves` prim (in path order, each prim's curves after the
//! last one's):
//!
//! - `type` (`linear`, or `cubic` with `basis` = `bezier`, `bspline` or `catmullRom`)
//!   and `wrap` (`nonperiodic`, `pinned`, `periodic`), with USD's fallbacks `cubic`,
//!   `bezier` and `nonperiodic` when unauthored. Cubic curves are evaluated to
//!   polylines of [`CUBIC_SAMPLES`] steps per segment; a periodic curve is closed (its
//!   polyline ends where it starts);
//! - `curveVertexCounts` and `points` (`point3f[]`, also `double3`/`half3` arrays);
//! - `widths` with `constant`, `uniform`, `vertex` (the fallback) or `varying`
//!   interpolation; vertex widths of a cubic curve follow its basis (clamped at 0:
//!   Catmull-Rom overshoots), varying ones are linear along each segment;
//! - `primvars:displayColor` with `constant` (the fallback), `uniform`, `vertex` or
//!   `varying` interpolation, kept as one colour per strand (the root's for vertex
//!   and varying colours);
//! - the world transform: the `xformOpOrder` of the prim and of every ancestor
//!   (`translate`, `scale`, `rotateX/Y/Z`, the six `rotateXYZ`-style orders, `orient`,
//!   `transform`, each optionally `!invert!`, and `!resetXformStack!`), applied to the
//!   points in `f64`; widths are scaled by the cube root of the transform's volume
//!   scale.
//!
//! An attribute's `default` value is read; an attribute with only time samples gives
//! its earliest sample. Not read: `normals`, `accelerations`/`velocities`, any other
//! primvar, the `hermite` and `power` bases, `faceVarying` interpolation, instancing.
//!
//! Reading is capped at [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES), checks
//! every count against the data before it allocates by it, and names the file, the
//! prim and the attribute of every problem ([`UsdFileError`]).
//!
//! **Bounds.** Before text is handed to openusd's parser (which recurses once per
//! nested prim, dictionary or array), it is lexed with openusd's own tokenizer, and
//! brackets nested deeper than [`MAX_USD_NESTING`] are refused
//! ([`UsdFileError::TooDeep`]): the parser's stack at that depth fits a 2 MiB thread
//! with room to spare. The same pass estimates what openusd will allocate for the
//! layer (every spec, its path and its values; [`USD_MEMORY_FACTOR`]) and refuses a
//! text whose estimate exceeds [`USD_MEMORY_FACTOR`] times its size plus
//! [`USD_MEMORY_ALLOWANCE`] ([`UsdFileError::TooManySpecs`]): a file of many tiny prims
//! costs openusd far more per byte than a groom's long arrays. Binary crate files are
//! read by openusd without recursion; their prims nested deeper than
//! [`MAX_USD_NESTING`] are refused when pelage walks them. A zip package's layer gets
//! the checks of its encoding; packages nest at most [`MAX_USDZ_NESTING`] deep.
//! Pelage's own walk is linear in the prims: every prim's world transform is computed
//! once, from its parent's.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};
use openusd::sdf::{self, AbstractData, ChildrenKey, FieldKey, SpecType, Value};

use crate::groom::Groom;

/// Polyline steps per segment of a cubic curve (`bezier`, `bspline`, `catmullRom`).
pub const CUBIC_SAMPLES: usize = 8;

/// File extensions the USD reader understands (lower case, without the dot).
pub const USD_EXTENSIONS: [&str; 4] = ["usda", "usdc", "usd", "usdz"];

/// The name of the prim [`encode`] writes the curves to.
pub const WRITTEN_PRIM: &str = "/Groom";

/// The deepest nesting of brackets (`{` prim bodies and dictionaries, `(` metadata and
/// tuples, `[` arrays) a USD text may have, and the deepest prim path pelage walks in
/// any USD file. openusd's text parser recurses once per level; at this depth it needs
/// well under 2 MiB of stack (tested on a 2 MiB thread in a debug build). Real
/// hierarchies are a few dozen levels deep.
pub const MAX_USD_NESTING: usize = 128;

/// The deepest nesting of `.usdz` packages inside `.usdz` packages pelage opens.
pub const MAX_USDZ_NESTING: usize = 4;

/// Reading a USD text of `B` bytes is refused when the estimate of what openusd
/// allocates for it exceeds `USD_MEMORY_FACTOR × B +` [`USD_MEMORY_ALLOWANCE`]; the
/// estimate is made from the tokens before parsing. With pelage's own copies, the
/// peak heap of reading a text file stays under `(USD_MEMORY_FACTOR + 16) × B +
/// USD_MEMORY_ALLOWANCE` (measured in `tests/usd_memory.rs`).
pub const USD_MEMORY_FACTOR: u64 = 16;

/// The constant part of the memory budget of a USD text (see [`USD_MEMORY_FACTOR`]).
pub const USD_MEMORY_ALLOWANCE: u64 = 64 << 20;

/// What is wrong with a USD groom file, or why one could not be written.
#[derive(Debug, thiserror::Error)]
pub enum UsdFileError {
    /// Reading or writing the file failed.
    #[error("could not {action} {}: {source}", path.display())]
    Io {
        /// What was being done (`"read"`, `"write"`).
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The bytes are none of the three USD encodings.
    #[error(
        "{} is not a USD file: it starts with {start:02x?}, neither \"#usda \" (text), \"PXR-USDC\" (binary) nor a zip package",
        file.display()
    )]
    UnknownFormat {
        /// The file.
        file: PathBuf,
        /// Its first bytes.
        start: Vec<u8>,
    },
    /// The file is empty or holds only blank space.
    #[error(
        "{} is empty{}: a USD file starts with \"#usda 1.0\" (text), \"PXR-USDC\" (binary) or is a zip package (.usdz)",
        file.display(),
        blank_words(*.bytes)
    )]
    Empty {
        /// The file.
        file: PathBuf,
        /// Its size.
        bytes: u64,
    },
    /// A USD text nests brackets deeper than [`MAX_USD_NESTING`].
    #[error(
        "{}: brackets nest {depth} deep at line {line} (prims inside prims, dictionaries or arrays); pelage reads USD nested at most {limit} deep",
        file.display()
    )]
    TooDeep {
        /// The file.
        file: PathBuf,
        /// The depth reached (the first past the limit).
        depth: usize,
        /// The line where it is reached (1 for the first).
        line: usize,
        /// [`MAX_USD_NESTING`].
        limit: usize,
    },
    /// A prim path is deeper than [`MAX_USD_NESTING`] (a binary file's hierarchy).
    #[error(
        "{}: prim {prim} is nested {depth} deep; pelage reads USD nested at most {limit} deep",
        file.display()
    )]
    TooDeepPrim {
        /// The file.
        file: PathBuf,
        /// The prim path (its first 200 bytes).
        prim: String,
        /// Its depth.
        depth: usize,
        /// [`MAX_USD_NESTING`].
        limit: usize,
    },
    /// Reading the text would take more memory than the budget for its size.
    #[error(
        "{}: {specs} statements in {bytes} bytes of USD text would need about {} MiB to read, more than {factor} times the file's size plus {} MiB; pelage reads grooms whose curves are long arrays in few prims, not files of very many small prims",
        file.display(),
        estimate >> 20,
        allowance >> 20
    )]
    TooManySpecs {
        /// The file.
        file: PathBuf,
        /// The statements (prims, attributes, metadata) counted.
        specs: u64,
        /// The file's size.
        bytes: u64,
        /// The estimated memory, bytes.
        estimate: u64,
        /// [`USD_MEMORY_FACTOR`].
        factor: u64,
        /// [`USD_MEMORY_ALLOWANCE`].
        allowance: u64,
    },
    /// A zip package is unreadable or holds no USD layer.
    #[error("{}: {problem}", file.display())]
    Package {
        /// The file.
        file: PathBuf,
        /// What is wrong, with the zip reader's reason.
        problem: String,
    },
    /// A width is larger than [`MAX_EXTENT`](crate::MAX_EXTENT) (after the prim's
    /// transform).
    #[error(
        "{}: {prim}.widths[{index}] gives a width of {value} after the prim's transform; widths must be at most {max:e}",
        file.display(),
        max = crate::MAX_EXTENT
    )]
    WidthTooLarge {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The entry of `widths` (the first of the curve's).
        index: usize,
        /// The width after the transform.
        value: f64,
    },
    /// openusd could not parse the file.
    #[error("cannot parse the {format} file {}: {message}", file.display())]
    Parse {
        /// The file.
        file: PathBuf,
        /// `"usda"`, `"usdc"` or `"usdz"`.
        format: &'static str,
        /// openusd's report.
        message: String,
    },
    /// The file has no `def BasisCurves` prim.
    #[error(
        "{} has no BasisCurves prim in its root layer; pelage reads hair from UsdGeomBasisCurves (references and payloads are not followed)",
        file.display()
    )]
    NoCurves {
        /// The file.
        file: PathBuf,
    },
    /// A required attribute is not authored.
    #[error("{}: prim {prim} has no {attribute}; a BasisCurves groom needs it", file.display())]
    Missing {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The attribute.
        attribute: String,
    },
    /// An attribute holds a value of another type.
    #[error("{}: {prim}.{attribute} holds a {found} value; expected {expected}", file.display())]
    WrongType {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The attribute.
        attribute: String,
        /// What it must hold.
        expected: &'static str,
        /// The kind of value it holds (openusd's name: `IntVec`, `Token`, ...).
        found: String,
    },
    /// A token attribute (`type`, `basis`, `wrap`, an `interpolation`) has a value
    /// pelage does not read.
    #[error("{}: {prim}.{attribute} is \"{value}\"; pelage reads {supported}", file.display())]
    Unsupported {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The attribute (or `attribute:interpolation`).
        attribute: String,
        /// The value found.
        value: String,
        /// The values pelage reads.
        supported: &'static str,
    },
    /// A curve has a vertex count its type, basis and wrap cannot draw.
    #[error(
        "{}: {prim}.curveVertexCounts[{curve}] is {count}; {rule}",
        file.display()
    )]
    BadVertexCount {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The curve index within the prim.
        curve: usize,
        /// Its vertex count.
        count: i64,
        /// What the basis needs.
        rule: String,
    },
    /// The vertex counts do not add up to the number of points.
    #[error(
        "{}: {prim}.curveVertexCounts add up to {sum} but {prim}.points has {points} entries; they must be equal",
        file.display()
    )]
    CountsMismatch {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The sum of the counts.
        sum: u64,
        /// The number of points.
        points: usize,
    },
    /// A per-curve or per-vertex attribute has the wrong number of entries.
    #[error(
        "{}: {prim}.{attribute} has {len} entries but {interpolation} interpolation needs {expected}; fix the array or its interpolation",
        file.display()
    )]
    LengthMismatch {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The attribute.
        attribute: String,
        /// Its length.
        len: usize,
        /// The length its interpolation needs.
        expected: u64,
        /// The interpolation.
        interpolation: &'static str,
    },
    /// A value is NaN, infinite, or (for a width) negative or larger than
    /// [`MAX_EXTENT`](crate::MAX_EXTENT).
    #[error(
        "{}: {prim}.{attribute}[{index}] is {value}; values must be finite{}",
        file.display(),
        if *.negative_allowed { "" } else { " and not negative" }
    )]
    BadValue {
        /// The file.
        file: PathBuf,
        /// The prim path.
        prim: String,
        /// The attribute.
        attribute: String,
        /// The entry.
        index: usize,
        /// The value, as text.
        value: String,
        /// Whether negative values are fine (points, colours).
        negative_allowed: bool,
    },
    /// An xform op is not one pelage applies, or its value is not usable.
    #[error("{}: the transform of {prim}: {op}: {problem}", file.display())]
    BadXform {
        /// The file.
        file: PathBuf,
        /// The prim the op belongs to (the curves' prim or an ancestor).
        prim: String,
        /// The op's name as `xformOpOrder` lists it.
        op: String,
        /// What is wrong.
        problem: String,
    },
    /// The groom cannot be written as USD (openusd refused the data or the path
    /// has no USD extension).
    #[error("cannot write {}: {message}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// Where an attribute lives, for errors.
struct Site<'a> {
    file: &'a Path,
    prim: &'a sdf::Path,
}

impl Site<'_> {
    fn prim(&self) -> String {
        self.prim.as_str().to_owned()
    }

    fn missing(&self, attribute: &str) -> UsdFileError {
        UsdFileError::Missing {
            file: self.file.to_path_buf(),
            prim: self.prim(),
            attribute: attribute.to_owned(),
        }
    }

    fn wrong_type(&self, attribute: &str, expected: &'static str, found: &Value) -> UsdFileError {
        UsdFileError::WrongType {
            file: self.file.to_path_buf(),
            prim: self.prim(),
            attribute: attribute.to_owned(),
            expected,
            found: value_kind(found),
        }
    }

    fn unsupported(&self, attribute: &str, value: &str, supported: &'static str) -> UsdFileError {
        UsdFileError::Unsupported {
            file: self.file.to_path_buf(),
            prim: self.prim(),
            attribute: attribute.to_owned(),
            value: value.to_owned(),
            supported,
        }
    }

    fn bad_value(
        &self,
        attribute: &str,
        index: usize,
        value: String,
        negative_allowed: bool,
    ) -> UsdFileError {
        UsdFileError::BadValue {
            file: self.file.to_path_buf(),
            prim: self.prim(),
            attribute: attribute.to_owned(),
            index,
            value,
            negative_allowed,
        }
    }

    fn length(
        &self,
        attribute: &str,
        len: usize,
        expected: u64,
        interpolation: Interpolation,
    ) -> UsdFileError {
        UsdFileError::LengthMismatch {
            file: self.file.to_path_buf(),
            prim: self.prim(),
            attribute: attribute.to_owned(),
            len,
            expected,
            interpolation: interpolation.name(),
        }
    }
}

/// The three encodings of a USD layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Text,
    Crate,
    Zip,
}

/// The encoding `bytes` start with (after blank space, for text); `None` for none.
fn encoding(bytes: &[u8]) -> Option<Encoding> {
    let text = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .and_then(|s| bytes.get(s..));
    if text.is_some_and(|t| t.starts_with(openusd::usda::MAGIC)) {
        Some(Encoding::Text)
    } else if bytes.starts_with(openusd::usdc::MAGIC) {
        Some(Encoding::Crate)
    } else if bytes.starts_with(b"PK\x03\x04") {
        Some(Encoding::Zip)
    } else {
        None
    }
}

/// " (0 bytes)" or " (its N bytes are blank space)", for [`UsdFileError::Empty`].
fn blank_words(bytes: u64) -> String {
    if bytes == 0 {
        " (0 bytes)".to_owned()
    } else {
        format!(" (its {bytes} bytes are blank space)")
    }
}

/// `error` and every error it stems from, joined by ": " (openusd's package errors say
/// "failed to access USDZ entry" and keep the reason in their source).
fn chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        let part = e.to_string();
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = e.source();
    }
    text
}

/// What [`scan_text`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct TextShape {
    /// The deepest bracket nesting.
    depth: usize,
    /// Statements counted (tokens outside arrays and tuples).
    statements: u64,
    /// What openusd is estimated to allocate, bytes.
    estimate: u64,
}

/// Bytes openusd allocates at most for one token of a statement (outside arrays and
/// tuples), besides its path: a spec or a field in a hash map, a name.
const STATEMENT_BYTES: u64 = 512;
/// Bytes openusd allocates at most for one token inside an array or a tuple other
/// than a number or punctuation, besides the token's text and prim path (a `String`,
/// a token, a path).
const VALUE_BYTES: u64 = 48;
/// Bytes openusd allocates at most for one number inside an array or a tuple (an
/// `f64` is 8; twice that for the vectors' growth).
const NUMBER_BYTES: u64 = 16;

/// Lexes `text` with openusd's tokenizer (so strings, comments and asset paths are
/// skipped exactly as the parser skips them) and measures its bracket nesting and an
/// estimate of what parsing it allocates; stops with [`UsdFileError::TooDeep`] at the
/// first bracket past [`MAX_USD_NESTING`]. A lexing error ends the scan: the parser
/// reports it, and never reads past it.
fn scan_text(text: &str, file: &Path) -> Result<TextShape, UsdFileError> {
    use logos::Logos;
    use openusd::usda::token::Token;
    let mut lexer = Token::lexer(text);
    // Per open bracket: its kind and the length of the prim path outside it.
    let mut stack: Vec<(char, u64)> = Vec::new();
    let mut path_len: u64 = 1;
    let mut last_name: u64 = 0;
    let mut shape = TextShape::default();
    while let Some(token) = lexer.next() {
        let Ok(token) = token else { break };
        let in_value = matches!(stack.last(), Some(('[' | '(', _)));
        let cost = if in_value {
            match token {
                // Separators and brackets of a value hold nothing of their own.
                Token::Punctuation(_) => 0,
                Token::Number(_) => NUMBER_BYTES,
                _ => VALUE_BYTES + lexer.span().len() as u64 + path_len,
            }
        } else {
            shape.statements += 1;
            STATEMENT_BYTES + path_len
        };
        shape.estimate = shape.estimate.saturating_add(cost);
        match token {
            Token::Punctuation(open @ ('{' | '(' | '[')) => {
                stack.push((open, path_len));
                if stack.len() > MAX_USD_NESTING {
                    let at = lexer.span().start;
                    let line = text
                        .get(..at)
                        .map_or(0, |t| t.bytes().filter(|&b| b == b'\n').count())
                        + 1;
                    return Err(UsdFileError::TooDeep {
                        file: file.to_path_buf(),
                        depth: stack.len(),
                        line,
                        limit: MAX_USD_NESTING,
                    });
                }
                shape.depth = shape.depth.max(stack.len());
                if open == '{' {
                    // A prim body (or a variant's, or a dictionary): the paths inside it
                    // are longer by the last name and a separator or `{set=sel}`.
                    path_len = path_len.saturating_add(last_name + 4);
                }
            }
            Token::Punctuation('}' | ')' | ']') => {
                if let Some((_, outer)) = stack.pop() {
                    path_len = outer;
                }
            }
            Token::String(name) => last_name = name.len() as u64,
            _ => {}
        }
    }
    Ok(shape)
}

/// The estimate, in bytes, of what openusd allocates to parse the USD text `text` (the
/// figure [`USD_MEMORY_FACTOR`] bounds): per token of a statement 512 bytes plus the
/// length of its prim path; inside an array or tuple, per number 16 bytes, per other
/// value 48 bytes plus its length and its prim path's, nothing for punctuation.
///
/// Errors: brackets nested deeper than [`MAX_USD_NESTING`] ([`UsdFileError::TooDeep`]).
pub fn text_memory_estimate(text: &str) -> Result<u64, UsdFileError> {
    Ok(scan_text(text, Path::new("<text>"))?.estimate)
}

/// Checks a USD text before parsing: its nesting ([`MAX_USD_NESTING`]) and the memory
/// parsing it is estimated to take ([`USD_MEMORY_FACTOR`]).
fn check_text(text: &str, file: &Path) -> Result<(), UsdFileError> {
    let shape = scan_text(text, file)?;
    let bytes = text.len() as u64;
    let budget = bytes
        .saturating_mul(USD_MEMORY_FACTOR)
        .saturating_add(USD_MEMORY_ALLOWANCE);
    if shape.estimate > budget {
        return Err(UsdFileError::TooManySpecs {
            file: file.to_path_buf(),
            specs: shape.statements,
            bytes,
            estimate: shape.estimate,
            factor: USD_MEMORY_FACTOR,
            allowance: USD_MEMORY_ALLOWANCE,
        });
    }
    Ok(())
}

/// The layer of a USD text (checked by [`check_text`] first).
fn open_text(bytes: &[u8], file: &Path) -> Result<Box<dyn AbstractData>, UsdFileError> {
    let parse = |message: String| UsdFileError::Parse {
        file: file.to_path_buf(),
        format: "usda",
        message,
    };
    let text = std::str::from_utf8(bytes)
        .map_err(|e| parse(format!("not UTF-8 text (at byte {})", e.valid_up_to())))?;
    check_text(text, file)?;
    let data = openusd::usda::parse(text).map_err(|e| parse(chain(&e)))?;
    Ok(Box::new(data))
}

/// The layer of a binary crate file.
fn open_crate(bytes: Vec<u8>, file: &Path) -> Result<Box<dyn AbstractData>, UsdFileError> {
    let data = openusd::usdc::CrateData::open(bytes, true).map_err(|e| UsdFileError::Parse {
        file: file.to_path_buf(),
        format: "usdc",
        message: chain(&e),
    })?;
    Ok(Box::new(data))
}

/// The root layer of a zip package: its first `.usda`, `.usdc` or `.usd` entry (or a
/// nested package's, at most [`MAX_USDZ_NESTING`] deep), read with the checks of its
/// encoding. `file` names the package in errors, `nesting` counts the packages around.
fn open_package(
    bytes: Vec<u8>,
    file: &Path,
    nesting: usize,
) -> Result<Box<dyn AbstractData>, UsdFileError> {
    let package = |problem: String| UsdFileError::Package {
        file: file.to_path_buf(),
        problem,
    };
    if nesting > MAX_USDZ_NESTING {
        return Err(package(format!(
            "packages nest more than {MAX_USDZ_NESTING} deep (a .usdz whose first layer is a .usdz ...)"
        )));
    }
    let mut archive = openusd::usdz::Archive::from_bytes(bytes)
        .map_err(|e| package(format!("not a readable zip package: {}", chain(&e))))?;
    let name = archive.first_layer_name().ok_or_else(|| {
        package(
            "the zip package holds no USD layer (no .usda, .usdc, .usd or .usdz entry); a .usdz's first entry must be one".to_owned(),
        )
    })?;
    let entry = archive
        .entry(&name)
        .map_err(|e| package(format!("cannot read its entry {name:?}: {}", chain(&e))))?
        .to_vec();
    drop(archive);
    let inner = PathBuf::from(format!("{}[{name}]", file.display()));
    match encoding(&entry) {
        Some(Encoding::Zip) => open_package(entry, &inner, nesting + 1),
        Some(Encoding::Crate) => open_crate(entry, &inner),
        Some(Encoding::Text) => open_text(&entry, &inner),
        None if entry.iter().all(u8::is_ascii_whitespace) => Err(UsdFileError::Empty {
            file: inner,
            bytes: entry.len() as u64,
        }),
        None => Err(UsdFileError::UnknownFormat {
            file: inner,
            start: entry.iter().take(8).copied().collect(),
        }),
    }
}

/// The root layer of a USD file, whatever its encoding.
fn open_layer(bytes: Vec<u8>, file: &Path) -> Result<Box<dyn AbstractData>, UsdFileError> {
    match encoding(&bytes) {
        Some(Encoding::Text) => open_text(&bytes, file),
        Some(Encoding::Crate) => open_crate(bytes, file),
        Some(Encoding::Zip) => open_package(bytes, file, 0),
        None if bytes.iter().all(u8::is_ascii_whitespace) => Err(UsdFileError::Empty {
            file: file.to_path_buf(),
            bytes: bytes.len() as u64,
        }),
        None => Err(UsdFileError::UnknownFormat {
            file: file.to_path_buf(),
            start: bytes.iter().take(8).copied().collect(),
        }),
    }
}

/// Reads every `BasisCurves` prim of the USD file held in `bytes` (text, binary or
/// zip package, told apart by content) into one groom; `file` names it in errors.
///
/// Errors: see [`UsdFileError`]; the groom's own checks (a NaN point, too many
/// points) come as [`GroomError`](crate::GroomError).
pub fn read(bytes: Vec<u8>, file: &Path) -> Result<Groom, crate::GroomError> {
    let layer = open_layer(bytes, file)?;
    read_layer(layer.as_ref(), file)
}

/// Bytes [`load`] reads before it checks that a file is USD at all.
const HEAD_BYTES: u64 = 256;

/// Reads the USD file at `path` (see [`read`]): at most
/// [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES), and only its first 256 bytes
/// when they are not USD. A path that is not a regular file (a FIFO, a device, a
/// socket) is refused before it is opened.
pub fn load(path: &Path) -> Result<Groom, crate::GroomError> {
    use std::io::Read;
    let io = |source| UsdFileError::Io {
        action: "read",
        path: path.to_path_buf(),
        source,
    };
    let limit = crate::MAX_GROOM_FILE_BYTES;
    let mut file = crate::limits::open_regular(path).map_err(io)?;
    let expected = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::with_capacity(expected.min(limit) as usize + 1);
    (&mut file)
        .take(HEAD_BYTES)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    let blank = bytes.iter().all(u8::is_ascii_whitespace);
    if encoding(&bytes).is_none() && !blank {
        return Err(UsdFileError::UnknownFormat {
            file: path.to_path_buf(),
            start: bytes.iter().take(8).copied().collect(),
        }
        .into());
    }
    (&mut file)
        .take(limit + 1 - bytes.len() as u64)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(io(crate::limits::too_large(limit, "groom files")).into());
    }
    read(bytes, path)
}

/// The strands of every curve prim, gathered.
#[derive(Default)]
struct Gathered {
    points: Vec<Vec3>,
    offsets: Vec<u32>,
    widths: Vec<f32>,
    any_widths: bool,
    colors: Vec<Vec3>,
    any_colors: bool,
}

fn read_layer(layer: &dyn AbstractData, file: &Path) -> Result<Groom, crate::GroomError> {
    let mut prims: Vec<sdf::Path> = Vec::new();
    for p in layer.spec_paths() {
        if !matches!(layer.spec_type(&p), Some(SpecType::Prim)) {
            continue;
        }
        let depth = p.prim_element_count();
        if depth > MAX_USD_NESTING {
            let text = p.as_str();
            let cut = (0..=200.min(text.len()))
                .rev()
                .find(|&i| text.is_char_boundary(i))
                .unwrap_or(0);
            return Err(UsdFileError::TooDeepPrim {
                file: file.to_path_buf(),
                prim: format!(
                    "{}{}",
                    text.get(..cut).unwrap_or(""),
                    if cut < text.len() { "..." } else { "" }
                ),
                depth,
                limit: MAX_USD_NESTING,
            }
            .into());
        }
        if !p.contains_prim_variant_selection()
            && is_def(layer, &p)
            && token_field(layer, &p, FieldKey::TypeName.as_str()).as_deref() == Some("BasisCurves")
        {
            prims.push(p);
        }
    }
    if prims.is_empty() {
        return Err(UsdFileError::NoCurves {
            file: file.to_path_buf(),
        }
        .into());
    }
    let mut out = Gathered {
        offsets: vec![0],
        ..Gathered::default()
    };
    let mut worlds = Worlds::default();
    for prim in &prims {
        let site = Site { file, prim };
        let world = worlds.of(layer, &site)?;
        read_prim(layer, &site, world, &mut out)?;
    }
    let widths = out.any_widths.then_some(out.widths);
    let colors = out.any_colors.then_some(out.colors);
    Groom::from_usd_parts(out.points, out.offsets, widths, colors)
}

fn is_def(layer: &dyn AbstractData, prim: &sdf::Path) -> bool {
    match layer.try_field(prim, FieldKey::Specifier.as_str()) {
        Ok(Some(v)) => matches!(v.as_ref(), Value::Specifier(sdf::Specifier::Def)),
        _ => false,
    }
}

/// A token-valued field of a spec (`typeName`, `interpolation`).
fn token_field(layer: &dyn AbstractData, path: &sdf::Path, field: &str) -> Option<String> {
    match layer.try_field(path, field).ok()??.as_ref() {
        Value::Token(t) => Some(t.as_str().to_owned()),
        Value::String(s) => Some(s.clone()),
        _ => None,
    }
}

/// The value of attribute `name` of `prim`: its default, else its earliest time
/// sample; `None` when neither is authored or the value is blocked.
fn attribute<'a>(
    layer: &'a dyn AbstractData,
    site: &Site<'_>,
    name: &str,
) -> Result<Option<Cow<'a, Value>>, UsdFileError> {
    let Ok(path) = site.prim.append_property(name) else {
        return Ok(None);
    };
    let field = |field: &str| {
        layer
            .try_field(&path, field)
            .map_err(|e| UsdFileError::Parse {
                file: site.file.to_path_buf(),
                format: "usd",
                message: format!("{}.{name}: {e}", site.prim.as_str()),
            })
    };
    let value = match field(FieldKey::Default.as_str())? {
        Some(v) => Some(v),
        None => match field(FieldKey::TimeSamples.as_str())? {
            Some(Cow::Owned(Value::TimeSamples(samples))) => {
                samples.into_iter().next().map(|(_, v)| Cow::Owned(v))
            }
            Some(Cow::Borrowed(Value::TimeSamples(samples))) => {
                samples.first().map(|(_, v)| Cow::Borrowed(v))
            }
            _ => None,
        },
    };
    Ok(value.filter(|v| !matches!(v.as_ref(), Value::ValueBlock | Value::None)))
}

/// A token attribute with a fallback.
fn token_attribute(
    layer: &dyn AbstractData,
    site: &Site<'_>,
    name: &str,
    fallback: &str,
) -> Result<String, UsdFileError> {
    match attribute(layer, site, name)? {
        None => Ok(fallback.to_owned()),
        Some(v) => match v.as_ref() {
            Value::Token(t) => Ok(t.as_str().to_owned()),
            Value::String(s) => Ok(s.clone()),
            other => Err(site.wrong_type(name, "a token", other)),
        },
    }
}

/// How a curve is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Basis {
    Linear,
    Bezier,
    Bspline,
    CatmullRom,
}

/// How a curve's ends are treated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wrap {
    Nonperiodic,
    Pinned,
    Periodic,
}

/// How a primvar's values map to the curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interpolation {
    Constant,
    Uniform,
    Vertex,
    Varying,
}

impl Interpolation {
    fn name(self) -> &'static str {
        match self {
            Interpolation::Constant => "constant",
            Interpolation::Uniform => "uniform",
            Interpolation::Vertex => "vertex",
            Interpolation::Varying => "varying",
        }
    }

    /// The attribute's authored interpolation, or `fallback`.
    fn of(
        layer: &dyn AbstractData,
        site: &Site<'_>,
        name: &str,
        fallback: Interpolation,
    ) -> Result<Interpolation, UsdFileError> {
        let Ok(path) = site.prim.append_property(name) else {
            return Ok(fallback);
        };
        match token_field(layer, &path, "interpolation").as_deref() {
            None => Ok(fallback),
            Some("constant") => Ok(Interpolation::Constant),
            Some("uniform") => Ok(Interpolation::Uniform),
            Some("vertex") => Ok(Interpolation::Vertex),
            Some("varying") => Ok(Interpolation::Varying),
            Some(other) => Err(site.unsupported(
                &format!("{name}:interpolation"),
                other,
                "constant, uniform, vertex and varying",
            )),
        }
    }
}

/// The segments of one curve: how many, and the number of varying values.
#[derive(Clone, Copy)]
struct Segments {
    count: usize,
    varying: u64,
}

impl Basis {
    /// The segments of a curve of `n` control points, or what the basis needs.
    fn segments(self, wrap: Wrap, n: i64) -> Result<Segments, String> {
        let periodic = wrap == Wrap::Periodic;
        let count = match self {
            Basis::Linear => {
                let min = if periodic { 3 } else { 2 };
                if n < min {
                    return Err(format!(
                        "a {} linear curve needs at least {min} vertices",
                        if periodic { "periodic" } else { "nonperiodic" }
                    ));
                }
                if periodic { n } else { n - 1 }
            }
            Basis::Bezier if periodic => {
                if n < 3 || n % 3 != 0 {
                    return Err("a periodic bezier curve needs a multiple of 3 vertices".into());
                }
                n / 3
            }
            Basis::Bezier => {
                if n < 4 || (n - 4) % 3 != 0 {
                    return Err("a bezier curve needs 4, 7, 10, ... (4 + 3k) vertices".into());
                }
                (n - 1) / 3
            }
            Basis::Bspline | Basis::CatmullRom => match wrap {
                Wrap::Periodic if n < 3 => {
                    return Err("a periodic cubic curve needs at least 3 vertices".into());
                }
                Wrap::Periodic => n,
                Wrap::Pinned if n < 2 => {
                    return Err("a pinned cubic curve needs at least 2 vertices".into());
                }
                Wrap::Pinned => n - 1,
                Wrap::Nonperiodic if n < 4 => {
                    return Err(
                        "a nonperiodic cubic curve needs at least 4 vertices (or wrap = \"pinned\")"
                            .into(),
                    );
                }
                Wrap::Nonperiodic => n - 3,
            },
        };
        let count = usize::try_from(count).map_err(|_| "too many segments".to_owned())?;
        Ok(Segments {
            count,
            varying: count as u64 + u64::from(!periodic),
        })
    }

    /// The control point indices of segment `j` of a curve of `n` control points (two
    /// for linear, four for cubic; `-1` and `n` are the phantom points of a pinned
    /// curve).
    fn span(self, wrap: Wrap, n: i64, j: i64) -> [i64; 4] {
        let n = n.max(1);
        match (self, wrap) {
            (Basis::Linear, _) => [j, (j + 1) % n, 0, 0],
            // A nonperiodic bezier's last index 3j + 3 is below n; a periodic one wraps.
            (Basis::Bezier, _) => [3 * j, 3 * j + 1, 3 * j + 2, (3 * j + 3) % n],
            (_, Wrap::Periodic) => [j, (j + 1) % n, (j + 2) % n, (j + 3) % n],
            (_, Wrap::Pinned) => [j - 1, j, j + 1, j + 2],
            (_, Wrap::Nonperiodic) => [j, j + 1, j + 2, j + 3],
        }
    }

    /// The weights of a cubic segment's four control points at `t` in [0, 1].
    fn weights(self, t: f64) -> [f64; 4] {
        let s = 1.0 - t;
        let (t2, t3) = (t * t, t * t * t);
        match self {
            Basis::Linear => [s, t, 0.0, 0.0],
            Basis::Bezier => [s * s * s, 3.0 * t * s * s, 3.0 * t2 * s, t3],
            Basis::Bspline => [
                s * s * s / 6.0,
                (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                t3 / 6.0,
            ],
            Basis::CatmullRom => [
                0.5 * (-t3 + 2.0 * t2 - t),
                0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                0.5 * (t3 - t2),
            ],
        }
    }
}

/// Something a curve's basis interpolates: positions and widths.
trait Blend: Copy + std::ops::Add<Output = Self> + std::ops::Mul<f64, Output = Self> {}
impl Blend for f64 {}
impl Blend for DVec3 {}

/// Control point `k` of a curve (`-1` and `len` are the phantom points of a pinned
/// curve: `2 P[0] - P[1]` and `2 P[n-1] - P[n-2]`); `None` past them.
fn control<T: Blend>(values: &[T], k: i64) -> Option<T> {
    let n = values.len() as i64;
    let at = |i: i64| usize::try_from(i).ok().and_then(|i| values.get(i)).copied();
    if k < 0 {
        Some(at(0)? * 2.0 + at(1)? * -1.0)
    } else if k >= n {
        Some(at(n - 1)? * 2.0 + at(n - 2)? * -1.0)
    } else {
        at(k)
    }
}

/// The sample points of one curve: `(segment, t)` for the root, then
/// [`CUBIC_SAMPLES`] (cubic) or 1 (linear) steps per segment.
fn samples(basis: Basis, segments: usize) -> impl Iterator<Item = (usize, f64)> {
    let steps = if basis == Basis::Linear {
        1
    } else {
        CUBIC_SAMPLES
    };
    std::iter::once((0, 0.0)).chain(
        (0..segments).flat_map(move |j| (1..=steps).map(move |k| (j, k as f64 / steps as f64))),
    )
}

/// A curve's value at `(segment, t)`; `zero` for a span past the curve's control
/// points (which [`Basis::segments`] never makes).
fn evaluate<T: Blend>(basis: Basis, values: &[T], span: [i64; 4], t: f64, zero: T) -> T {
    let taps = if basis == Basis::Linear { 2 } else { 4 };
    span.iter()
        .zip(basis.weights(t))
        .take(taps)
        .fold(zero, |sum, (&k, w)| {
            sum + control(values, k).unwrap_or(zero) * w
        })
}

/// Reads one prim's curves into `out`.
fn read_prim(
    layer: &dyn AbstractData,
    site: &Site<'_>,
    world: DMat4,
    out: &mut Gathered,
) -> Result<(), crate::GroomError> {
    let curve_type = token_attribute(layer, site, "type", "cubic")?;
    let basis = match curve_type.as_str() {
        "linear" => Basis::Linear,
        "cubic" => match token_attribute(layer, site, "basis", "bezier")?.as_str() {
            "bezier" => Basis::Bezier,
            "bspline" => Basis::Bspline,
            "catmullRom" => Basis::CatmullRom,
            other => {
                return Err(site
                    .unsupported("basis", other, "bezier, bspline and catmullRom")
                    .into());
            }
        },
        other => return Err(site.unsupported("type", other, "linear and cubic").into()),
    };
    let wrap = match token_attribute(layer, site, "wrap", "nonperiodic")?.as_str() {
        "nonperiodic" => Wrap::Nonperiodic,
        // Pinned only changes bspline and catmullRom curves.
        "pinned" if matches!(basis, Basis::Bspline | Basis::CatmullRom) => Wrap::Pinned,
        "pinned" => Wrap::Nonperiodic,
        "periodic" => Wrap::Periodic,
        other => {
            return Err(site
                .unsupported("wrap", other, "nonperiodic, pinned and periodic")
                .into());
        }
    };

    let counts = read_counts(layer, site)?;
    let points = read_points(layer, site, &world)?;
    let sum: u64 = counts.iter().map(|&c| c.max(0) as u64).sum();
    if sum != points.len() as u64 {
        return Err(UsdFileError::CountsMismatch {
            file: site.file.to_path_buf(),
            prim: site.prim(),
            sum,
            points: points.len(),
        }
        .into());
    }
    let mut layouts = Vec::with_capacity(counts.len());
    let steps = if basis == Basis::Linear {
        1
    } else {
        CUBIC_SAMPLES
    };
    let mut out_points = 0usize;
    for (curve, &count) in counts.iter().enumerate() {
        let segments =
            basis
                .segments(wrap, count)
                .map_err(|rule| UsdFileError::BadVertexCount {
                    file: site.file.to_path_buf(),
                    prim: site.prim(),
                    curve,
                    count,
                    rule,
                })?;
        out_points = out_points.saturating_add(segments.count.saturating_mul(steps) + 1);
        layouts.push(segments);
    }
    out.points.reserve(out_points);
    let varying_total: u64 = layouts.iter().map(|l| l.varying).sum();
    let width_scale = DMat3::from_mat4(world).determinant().abs().cbrt();
    let widths = read_per_curve(
        layer,
        site,
        "widths",
        Interpolation::Vertex,
        (counts.len() as u64, sum, varying_total),
        scalar_array,
    )?;
    if let Some((_, values)) = &widths {
        check_values(
            site,
            "widths",
            values,
            |w| w.is_finite() && *w >= 0.0,
            false,
        )?;
    }
    let colors = read_per_curve(
        layer,
        site,
        "primvars:displayColor",
        Interpolation::Constant,
        (counts.len() as u64, sum, varying_total),
        vec3_array,
    )?;
    if let Some((_, values)) = &colors {
        check_values(
            site,
            "primvars:displayColor",
            values,
            |c| c.is_finite() && c.min_element() >= 0.0,
            false,
        )?;
    }
    if widths.is_some() && !out.any_widths {
        // Curves of earlier prims without widths get 0: the renderer's default width.
        out.widths.resize(out.points.len(), 0.0);
        out.any_widths = true;
    }
    if out.any_widths {
        out.widths.reserve(out_points);
    }
    if colors.is_some() && !out.any_colors {
        out.colors
            .resize(out.offsets.len().saturating_sub(1), Vec3::ONE);
        out.any_colors = true;
    }

    let mut first_point = 0usize;
    let mut first_varying = 0usize;
    for (curve, (layout, &count)) in layouts.iter().zip(&counts).enumerate() {
        let n = count as usize;
        let control_points: Vec<DVec3> = points
            .get(first_point..first_point + n)
            .unwrap_or(&[])
            .iter()
            .map(|p| p.as_dvec3())
            .collect();
        let curve_widths: Option<Vec<f64>> = widths.as_ref().map(|(interp, w)| {
            let pick = |i: usize| f64::from(w.get(i).copied().unwrap_or(0.0));
            match interp {
                Interpolation::Constant => vec![pick(0); n],
                Interpolation::Uniform => vec![pick(curve); n],
                Interpolation::Vertex => (first_point..first_point + n).map(pick).collect(),
                Interpolation::Varying => (first_varying..first_varying + layout.varying as usize)
                    .map(pick)
                    .collect(),
            }
        });
        let varying_widths = widths
            .as_ref()
            .is_some_and(|(i, _)| *i == Interpolation::Varying);
        for (segment, t) in samples(basis, layout.count) {
            let span = basis.span(wrap, count, segment as i64);
            let p = evaluate(basis, &control_points, span, t, DVec3::ZERO);
            out.points.push(p.as_vec3());
            if let Some(w) = &curve_widths {
                let w = if varying_widths {
                    // Varying values sit at segment ends, the last one wrapping round
                    // on a periodic curve.
                    let count = w.len().max(1);
                    let a = w.get(segment % count).copied().unwrap_or(0.0);
                    let b = w.get((segment + 1) % count).copied().unwrap_or(a);
                    a + (b - a) * t
                } else {
                    evaluate(basis, w, span, t, 0.0)
                };
                let scaled = w.max(0.0) * width_scale;
                if scaled > f64::from(crate::MAX_EXTENT) {
                    return Err(UsdFileError::WidthTooLarge {
                        file: site.file.to_path_buf(),
                        prim: site.prim(),
                        index: first_point,
                        value: scaled,
                    }
                    .into());
                }
                out.widths.push(scaled as f32);
            } else if out.any_widths {
                out.widths.push(0.0);
            }
        }
        let total = out.points.len() as u64;
        out.offsets
            .push(u32::try_from(total).map_err(|_| crate::groom::too_many(total))?);
        if let Some((interp, c)) = &colors {
            let index = match interp {
                Interpolation::Constant => 0,
                Interpolation::Uniform => curve,
                Interpolation::Vertex => first_point,
                Interpolation::Varying => first_varying,
            };
            out.colors.push(c.get(index).copied().unwrap_or(Vec3::ONE));
        } else if out.any_colors {
            out.colors.push(Vec3::ONE);
        }
        first_point += n;
        first_varying += layout.varying as usize;
    }
    Ok(())
}

/// Checks every value of a primvar.
fn check_values<T: std::fmt::Debug>(
    site: &Site<'_>,
    attribute: &str,
    values: &[T],
    ok: impl Fn(&T) -> bool,
    negative_allowed: bool,
) -> Result<(), UsdFileError> {
    match values.iter().enumerate().find(|(_, v)| !ok(v)) {
        Some((index, v)) => {
            Err(site.bad_value(attribute, index, format!("{v:?}"), negative_allowed))
        }
        None => Ok(()),
    }
}

/// `curveVertexCounts`, as `i64` (negative counts are refused by the basis).
fn read_counts(layer: &dyn AbstractData, site: &Site<'_>) -> Result<Vec<i64>, UsdFileError> {
    const NAME: &str = "curveVertexCounts";
    let value = attribute(layer, site, NAME)?.ok_or_else(|| site.missing(NAME))?;
    let counts: Vec<i64> = match value.as_ref() {
        Value::IntVec(v) => v.iter().map(|&c| i64::from(c)).collect(),
        Value::UintVec(v) => v.iter().map(|&c| i64::from(c)).collect(),
        Value::Int64Vec(v) => v.clone(),
        other => return Err(site.wrong_type(NAME, "an int[] array", other)),
    };
    if counts.is_empty() {
        return Err(UsdFileError::BadVertexCount {
            file: site.file.to_path_buf(),
            prim: site.prim(),
            curve: 0,
            count: 0,
            rule: "the prim has no curves (curveVertexCounts is empty)".into(),
        });
    }
    Ok(counts)
}

/// `points`, transformed to world space; a NaN or infinite point is an error.
fn read_points(
    layer: &dyn AbstractData,
    site: &Site<'_>,
    world: &DMat4,
) -> Result<Vec<Vec3>, UsdFileError> {
    const NAME: &str = "points";
    let value = attribute(layer, site, NAME)?.ok_or_else(|| site.missing(NAME))?;
    let mut points = vec3_array(value.as_ref())
        .map_err(|found| site.wrong_type(NAME, "a point3f[] array", found))?;
    drop(value);
    check_values(site, NAME, &points, |p| p.is_finite(), true)?;
    if *world != DMat4::IDENTITY {
        for (index, p) in points.iter_mut().enumerate() {
            let q = world.transform_point3(p.as_dvec3()).as_vec3();
            if !q.is_finite() {
                return Err(site.bad_value(
                    "points (after the prim's transform)",
                    index,
                    format!("{q}"),
                    true,
                ));
            }
            *p = q;
        }
    }
    Ok(points)
}

/// An array of 3-vectors (`float3`, `double3`, `half3`), or the value back.
fn vec3_array(value: &Value) -> Result<Vec<Vec3>, &Value> {
    Ok(match value {
        Value::Vec3fVec(v) => v.iter().map(|p| Vec3::new(p.x, p.y, p.z)).collect(),
        Value::Vec3dVec(v) => v
            .iter()
            .map(|p| DVec3::new(p.x, p.y, p.z).as_vec3())
            .collect(),
        Value::Vec3hVec(v) => v
            .iter()
            .map(|p| Vec3::new(p.x.to_f32(), p.y.to_f32(), p.z.to_f32()))
            .collect(),
        Value::Vec3f(p) => vec![Vec3::new(p.x, p.y, p.z)],
        Value::Vec3d(p) => vec![DVec3::new(p.x, p.y, p.z).as_vec3()],
        other => return Err(other),
    })
}

/// An array of scalars (`float`, `double`, `half`), or the value back.
fn scalar_array(value: &Value) -> Result<Vec<f32>, &Value> {
    Ok(match value {
        Value::FloatVec(v) => v.clone(),
        Value::DoubleVec(v) => v.iter().map(|&w| w as f32).collect(),
        Value::HalfVec(v) => v.iter().map(|w| w.to_f32()).collect(),
        Value::Float(w) => vec![*w],
        Value::Double(w) => vec![*w as f32],
        other => return Err(other),
    })
}

/// A primvar with its interpolation, its length checked against `(curves, vertices,
/// varying)`; `None` when unauthored.
fn read_per_curve<T>(
    layer: &dyn AbstractData,
    site: &Site<'_>,
    name: &str,
    fallback: Interpolation,
    (curves, vertices, varying): (u64, u64, u64),
    convert: impl Fn(&Value) -> Result<Vec<T>, &Value>,
) -> Result<Option<(Interpolation, Vec<T>)>, UsdFileError> {
    let Some(value) = attribute(layer, site, name)? else {
        return Ok(None);
    };
    let values = convert(value.as_ref()).map_err(|found| {
        site.wrong_type(
            name,
            "an array of numbers (widths) or colours (displayColor)",
            found,
        )
    })?;
    let interpolation = Interpolation::of(layer, site, name, fallback)?;
    let expected = match interpolation {
        Interpolation::Constant => 1,
        Interpolation::Uniform => curves,
        Interpolation::Vertex => vertices,
        Interpolation::Varying => varying,
    };
    if values.len() as u64 != expected {
        return Err(site.length(name, values.len(), expected, interpolation));
    }
    Ok(Some((interpolation, values)))
}

/// The world transforms of the prims walked so far, each computed once from its
/// parent's: the walk costs one local transform per prim, however deep the prims
/// nest (it cost one per ancestor per curve prim, cubic in the depth of nested
/// curves).
#[derive(Default)]
struct Worlds {
    known: std::collections::HashMap<sdf::Path, DMat4>,
}

impl Worlds {
    /// The prim's world transform (column vectors): the product of the `xformOpOrder`
    /// ops of every ancestor and of the prim, outermost first.
    fn of(&mut self, layer: &dyn AbstractData, site: &Site<'_>) -> Result<DMat4, UsdFileError> {
        // The prim and its ancestors not yet known, innermost first.
        let mut missing = Vec::new();
        let mut world = DMat4::IDENTITY;
        let mut next = Some(site.prim.clone());
        while let Some(prim) = next {
            if prim.is_abs_root() || prim.as_str().is_empty() {
                break;
            }
            if let Some(known) = self.known.get(&prim) {
                world = *known;
                break;
            }
            next = prim.parent();
            missing.push(prim);
        }
        for prim in missing.into_iter().rev() {
            let (local, reset) = local_transform(
                layer,
                &Site {
                    file: site.file,
                    prim: &prim,
                },
            )?;
            world = if reset { local } else { world * local };
            self.known.insert(prim, world);
        }
        Ok(world)
    }
}

/// A prim's local transform and whether it resets the parent's.
fn local_transform(
    layer: &dyn AbstractData,
    site: &Site<'_>,
) -> Result<(DMat4, bool), UsdFileError> {
    #[cfg(test)]
    tests::LOCAL_TRANSFORMS.with(|n| n.set(n.get() + 1));
    let Some(order) = attribute(layer, site, "xformOpOrder")? else {
        return Ok((DMat4::IDENTITY, false));
    };
    let ops: Vec<String> = match order.as_ref() {
        Value::TokenVec(v) => v.iter().map(|t| t.as_str().to_owned()).collect(),
        Value::StringVec(v) => v.clone(),
        other => return Err(site.wrong_type("xformOpOrder", "a token[] array", other)),
    };
    let mut m = DMat4::IDENTITY;
    let mut reset = false;
    for op in &ops {
        if op == "!resetXformStack!" {
            m = DMat4::IDENTITY;
            reset = true;
            continue;
        }
        let bad = |problem: String| UsdFileError::BadXform {
            file: site.file.to_path_buf(),
            prim: site.prim(),
            op: op.clone(),
            problem,
        };
        let (invert, name) = match op.strip_prefix("!invert!") {
            Some(rest) => (true, rest),
            None => (false, op.as_str()),
        };
        let kind = name
            .strip_prefix("xformOp:")
            .map(|k| k.split(':').next().unwrap_or(k))
            .ok_or_else(|| bad("not an xformOp: name".into()))?;
        let value =
            attribute(layer, site, name)?.ok_or_else(|| bad("the op has no value".into()))?;
        let op_matrix = xform_op(kind, value.as_ref()).map_err(bad)?;
        let op_matrix = if invert {
            if op_matrix.determinant() == 0.0 {
                return Err(bad("cannot invert a singular transform".into()));
            }
            op_matrix.inverse()
        } else {
            op_matrix
        };
        if !op_matrix.is_finite() {
            return Err(bad("the transform is not finite".into()));
        }
        m *= op_matrix;
    }
    Ok((m, reset))
}

/// One xform op as a matrix (column vectors).
fn xform_op(kind: &str, value: &Value) -> Result<DMat4, String> {
    let vec3 = || -> Result<DVec3, String> {
        match value {
            Value::Vec3d(v) => Ok(DVec3::new(v.x, v.y, v.z)),
            Value::Vec3f(v) => Ok(DVec3::new(v.x.into(), v.y.into(), v.z.into())),
            Value::Vec3h(v) => Ok(DVec3::new(v.x.to_f64(), v.y.to_f64(), v.z.to_f64())),
            _ => Err(format!("expected a 3-vector, found {}", value_kind(value))),
        }
    };
    let scalar = || -> Result<f64, String> {
        match value {
            Value::Double(v) => Ok(*v),
            Value::Float(v) => Ok((*v).into()),
            Value::Half(v) => Ok(v.to_f64()),
            _ => Err(format!("expected a number, found {}", value_kind(value))),
        }
    };
    let axis = |c: char, degrees: f64| match c {
        'X' => DMat4::from_rotation_x(degrees.to_radians()),
        'Y' => DMat4::from_rotation_y(degrees.to_radians()),
        _ => DMat4::from_rotation_z(degrees.to_radians()),
    };
    Ok(match kind {
        "translate" => DMat4::from_translation(vec3()?),
        "scale" => DMat4::from_scale(vec3()?),
        "rotateX" => axis('X', scalar()?),
        "rotateY" => axis('Y', scalar()?),
        "rotateZ" => axis('Z', scalar()?),
        "rotateXYZ" | "rotateXZY" | "rotateYXZ" | "rotateYZX" | "rotateZXY" | "rotateZYX" => {
            let angles = vec3()?;
            let angle = |c: char| match c {
                'X' => angles.x,
                'Y' => angles.y,
                _ => angles.z,
            };
            // rotateABC turns about A first: R_C · R_B · R_A.
            kind.trim_start_matches("rotate")
                .chars()
                .fold(DMat4::IDENTITY, |m, c| axis(c, angle(c)) * m)
        }
        "orient" => {
            let q = match value {
                Value::Quatd(q) => DQuat::from_xyzw(q.x, q.y, q.z, q.w),
                Value::Quatf(q) => DQuat::from_xyzw(q.x.into(), q.y.into(), q.z.into(), q.w.into()),
                Value::Quath(q) => {
                    DQuat::from_xyzw(q.x.to_f64(), q.y.to_f64(), q.z.to_f64(), q.w.to_f64())
                }
                _ => {
                    return Err(format!(
                        "expected a quaternion, found {}",
                        value_kind(value)
                    ));
                }
            };
            if !(q.is_finite() && q.length() > 0.0) {
                return Err("the quaternion must be finite and not zero".into());
            }
            DMat4::from_quat(q.normalize())
        }
        "transform" => match value {
            // USD's row-major matrix for row vectors is glam's column-major one.
            Value::Matrix4d(m) => DMat4::from_cols_array(&m.0),
            _ => return Err(format!("expected a matrix4d, found {}", value_kind(value))),
        },
        other => {
            return Err(format!(
                "pelage applies translate, scale, rotateX/Y/Z, rotateXYZ (any order), orient and transform, not {other}"
            ));
        }
    })
}

/// The kind of a value (`IntVec`, `Token`, ...), never its contents (which may be an
/// array of millions).
fn value_kind(value: &Value) -> String {
    format!("{:?}", sdf::ValueKind::from(value))
}

/// USD text for `groom`: one `def BasisCurves "Groom"` prim, `type = "linear"`, its
/// `curveVertexCounts`, `points`, vertex-interpolated `widths` and uniform
/// `primvars:displayColor` when the groom has them.
pub fn to_usda(groom: &Groom) -> Result<String, UsdFileError> {
    let data = layer_of(groom)?;
    openusd::usda::TextWriter::write_to_string(&data).map_err(|e| UsdFileError::Write {
        path: PathBuf::from("<text>"),
        message: e.to_string(),
    })
}

/// The binary crate (`.usdc`) encoding of what [`to_usda`] writes.
pub fn to_usdc(groom: &Groom) -> Result<Vec<u8>, UsdFileError> {
    let data = layer_of(groom)?;
    let mut out = std::io::Cursor::new(Vec::new());
    openusd::usdc::CrateWriter::write(&data, &mut out).map_err(|e| UsdFileError::Write {
        path: PathBuf::from("<bytes>"),
        message: e.to_string(),
    })?;
    Ok(out.into_inner())
}

/// A USD zip package (`.usdz`) holding what [`to_usdc`] writes as `groom.usdc`.
pub fn to_usdz(groom: &Groom) -> Result<Vec<u8>, UsdFileError> {
    let error = |message: String| UsdFileError::Write {
        path: PathBuf::from("<bytes>"),
        message,
    };
    let layer = to_usdc(groom)?;
    let mut writer = openusd::usdz::ArchiveWriter::new(std::io::Cursor::new(Vec::new()));
    writer
        .add_layer("groom.usdc", &layer)
        .map_err(|e| error(e.to_string()))?;
    let out = writer.finish().map_err(|e| error(e.to_string()))?;
    Ok(out.into_inner())
}

/// `groom` encoded for a file at `path`: `.usda` (text), `.usdc`/`.usd` (binary crate)
/// or `.usdz` (package), chosen by the extension (another is an error naming the path).
/// The caller writes the bytes (the command line writes them atomically).
pub fn encode(groom: &Groom, path: &Path) -> Result<Vec<u8>, UsdFileError> {
    let write_error = |message: String| UsdFileError::Write {
        path: path.to_path_buf(),
        message,
    };
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let bytes = match extension.as_deref() {
        Some("usda") => to_usda(groom)
            .map_err(|e| write_error(e.to_string()))?
            .into_bytes(),
        Some("usdc" | "usd") => to_usdc(groom).map_err(|e| write_error(e.to_string()))?,
        Some("usdz") => to_usdz(groom).map_err(|e| write_error(e.to_string()))?,
        _ => {
            return Err(write_error(
                "pelage writes USD as .usda (text), .usdc / .usd (binary) or .usdz (package)"
                    .into(),
            ));
        }
    };
    Ok(bytes)
}

/// The layer [`to_usda`] and [`encode`] write.
fn layer_of(groom: &Groom) -> Result<sdf::Data, UsdFileError> {
    let path_error = |e: sdf::PathParseError| UsdFileError::Write {
        path: PathBuf::from(WRITTEN_PRIM),
        message: e.to_string(),
    };
    let prim = sdf::Path::new(WRITTEN_PRIM).map_err(path_error)?;
    let name = WRITTEN_PRIM.trim_start_matches('/');
    let mut data = sdf::Data::new();
    let root = data.create_spec(sdf::Path::abs_root(), SpecType::PseudoRoot);
    root.add(
        ChildrenKey::PrimChildren,
        Value::TokenVec(vec![name.into()]),
    );
    root.add(FieldKey::DefaultPrim, Value::Token(name.into()));
    root.add(
        FieldKey::Documentation,
        Value::String("A hair groom written by pelage".into()),
    );

    let counts: Vec<i32> = groom
        .offsets()
        .windows(2)
        .map(|w| i32::try_from(w[1] - w[0]).unwrap_or(i32::MAX))
        .collect();
    let gf3 = |v: &Vec3| openusd::gf::Vec3f {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    let mut attributes: Vec<(&str, &str, Value, Option<&str>, bool)> = vec![
        ("type", "token", Value::Token("linear".into()), None, true),
        (
            "wrap",
            "token",
            Value::Token("nonperiodic".into()),
            None,
            true,
        ),
        (
            "curveVertexCounts",
            "int[]",
            Value::IntVec(counts),
            None,
            false,
        ),
        (
            "points",
            "point3f[]",
            Value::Vec3fVec(groom.points().iter().map(gf3).collect()),
            None,
            false,
        ),
    ];
    if let Some(widths) = groom.widths() {
        attributes.push((
            "widths",
            "float[]",
            Value::FloatVec(widths.to_vec()),
            Some("vertex"),
            false,
        ));
    }
    if let Some(colors) = groom.colors() {
        attributes.push((
            "primvars:displayColor",
            "color3f[]",
            Value::Vec3fVec(colors.iter().map(gf3).collect()),
            Some("uniform"),
            false,
        ));
    }
    let spec = data.create_spec(prim.clone(), SpecType::Prim);
    spec.add(FieldKey::Specifier, Value::Specifier(sdf::Specifier::Def));
    spec.add(FieldKey::TypeName, Value::Token("BasisCurves".into()));
    spec.add(
        ChildrenKey::PropertyChildren,
        Value::TokenVec(attributes.iter().map(|a| a.0.into()).collect()),
    );
    for (attr, type_name, value, interpolation, uniform) in attributes {
        let path = prim.append_property(attr).map_err(path_error)?;
        let spec = data.create_spec(path, SpecType::Attribute);
        spec.add(FieldKey::TypeName, Value::Token(type_name.into()));
        if uniform {
            spec.add(
                FieldKey::Variability,
                Value::Variability(sdf::Variability::Uniform),
            );
        }
        if let Some(interpolation) = interpolation {
            spec.add("interpolation", Value::Token(interpolation.into()));
        }
        spec.add(FieldKey::Default, value);
    }
    Ok(data)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::cell::Cell;

    thread_local! {
        /// Local transforms computed on this thread ([`local_transform`] calls).
        pub(crate) static LOCAL_TRANSFORMS: Cell<usize> = const { Cell::new(0) };
    }

    /// `depth` nested `BasisCurves` prims, each with one linear curve and a translate.
    fn nested_curves(depth: usize) -> String {
        let mut text = String::from("#usda 1.0\n");
        for level in 0..depth {
            text.push_str(&format!(
                "def BasisCurves \"C{level}\" {{\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n point3f[] points = [(0, 0, 0), (0, 1, 0)]\n double3 xformOp:translate = (1, 0, 0)\n uniform token[] xformOpOrder = [\"xformOp:translate\"]\n"
            ));
        }
        text.push_str(&"}\n".repeat(depth));
        text
    }

    #[test]
    fn nested_curves_cost_one_transform_per_prim() {
        let depth = 100;
        let text = nested_curves(depth);
        LOCAL_TRANSFORMS.with(|n| n.set(0));
        let groom = read(text.into_bytes(), Path::new("nested.usda")).unwrap();
        assert_eq!(groom.strand_count(), depth);
        // Each prim's transform once (it was once per ancestor per curve prim:
        // depth (depth + 1) / 2 = 5 050 here).
        assert_eq!(LOCAL_TRANSFORMS.with(Cell::get), depth);
        // The deepest curve is moved by every ancestor's translate.
        let deepest = groom.strands().map(|s| s[0].x).fold(0.0f32, f32::max);
        assert_eq!(deepest, depth as f32);
    }

    #[test]
    fn the_scan_skips_brackets_in_strings_and_comments() {
        let text = "#usda 1.0\n# {{{{ [[[[\ndef \"A\" ( doc = \"((((\" ) {\n string s = '[[[['\n asset a = @{{{{@\n /* {{{{ */ }\n";
        let shape = scan_text(text, Path::new("a.usda")).unwrap();
        assert_eq!(shape.depth, 1);
    }
}
