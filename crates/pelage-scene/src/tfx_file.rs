//! AMD TressFX's binary `.tfx` format (TressFX 4): read and write.
//!
//! The layout is AMD's `TressFXTFXFileHeader` from `src/TressFX/TressFXFileFormat.h`
//! in GPUOpen-Effects/TressFX (little-endian, 160 bytes):
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `f32` | `version` (the TressFX 4 exporters write 4.0) |
//! | 4 | `u32` | `numHairStrands` |
//! | 8 | `u32` | `numVerticesPerStrand`, the same for every strand |
//! | 12 | `u32` | `offsetVertexPosition`: `float4[numHairStrands × numVerticesPerStrand]` |
//! | 16 | `u32` | `offsetStrandUV`: `float2[numHairStrands]`, 0 if absent |
//! | 20 | `u32` | `offsetVertexUV`: `float2[numHairStrands × numVerticesPerStrand]`, 0 if absent |
//! | 24 | `u32` | `offsetStrandThickness`: `float[numHairStrands]`, 0 if absent |
//! | 28 | `u32` | `offsetVertexColor`: `float4[numHairStrands × numVerticesPerStrand]`, 0 if absent |
//! | 32 | `u32[32]` | `reserved` |
//!
//! The offsets are byte offsets from the start of the file (the header's
//! comment says they are 8-byte aligned; this reader does not require it).
//! Positions are stored strand after strand, root first. Their `w` is the
//! vertex's inverse mass for TressFX's simulation: AMD's Maya exporter
//! (`tool/Maya/TressFX_Exporter.py`, `SaveTFXBinaryFile`) writes `w = 0`
//! (immovable) for the first two vertices of every strand, and for the last
//! one with "both ends immovable", and `w = 1` for the rest. AMD's loader
//! (`src/TressFX/TressFXAsset.cpp`, `TressFXAsset::LoadHairData`) refuses
//! files whose version is below its major version 4, reads the positions
//! from `offsetVertexPosition` and the strand UVs from `offsetStrandUV`.
//! (The header comment gives the position array as `FLOAT4[numHairStrands]`;
//! the loader and the exporters use one `float4` per vertex, as here.)
//!
//! Reading never trusts the header: every array's end is computed with
//! checked 64-bit arithmetic and compared with the file length before
//! anything is allocated, and every read is a bounds-checked little-endian
//! decode (no pointer casts, so unaligned input is fine). Bytes not covered
//! by an array are ignored.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

/// Size of the fixed header in bytes.
pub const HEADER_SIZE: usize = 160;
/// Number of `u32` words in the header's `reserved` field.
pub const RESERVED_WORDS: usize = 32;
/// Lowest version read: TressFX 4. AMD's own loader refuses older files, and
/// TressFX 3 files have a different header.
pub const MIN_VERSION: f32 = 4.0;
/// The version [`TfxFile::from_strands`] writes (what AMD's exporters write).
pub const VERSION: f32 = 4.0;
/// Most vertices per strand accepted. TressFX itself simulates 4 to 64
/// (powers of two); other exporters write other counts, so this limit only
/// refuses counts no hair asset has (the same as the most points a `.hair`
/// strand can have).
pub const MAX_VERTICES_PER_STRAND: u32 = 65536;

/// The contents of a `.tfx` file.
///
/// Strand `i` is `positions[i * vertices_per_strand .. (i + 1) * vertices_per_strand]`,
/// root first. Writing what was read gives back the same bytes when the file
/// was laid out the way [`TfxFile::write`] lays it out (arrays in header
/// order right after the header, each starting on an 8-byte boundary).
#[derive(Clone, Debug, PartialEq)]
pub struct TfxFile {
    /// The header's version number (at least [`MIN_VERSION`]).
    pub version: f32,
    /// Vertices of every strand (2 to [`MAX_VERTICES_PER_STRAND`]).
    pub vertices_per_strand: u32,
    /// Every vertex, strand after strand, root first: `xyz` the position,
    /// `w` the inverse mass (0 = immovable in TressFX's simulation).
    pub positions: Vec<Vec4>,
    /// One texture coordinate per strand (`offsetStrandUV`), if present.
    pub strand_uv: Option<Vec<Vec2>>,
    /// One texture coordinate per vertex (`offsetVertexUV`), if present.
    pub vertex_uv: Option<Vec<Vec2>>,
    /// One thickness per strand (`offsetStrandThickness`), if present.
    pub thickness: Option<Vec<f32>>,
    /// One RGBA colour per vertex (`offsetVertexColor`), if present.
    pub vertex_color: Option<Vec<Vec4>>,
    /// The header's reserved words, kept so that a read file is written back
    /// unchanged.
    pub reserved: [u32; RESERVED_WORDS],
}

/// What is wrong with a `.tfx` file or with a [`TfxFile`] about to be written.
#[derive(Debug, thiserror::Error)]
pub enum TfxFileError {
    /// The data ends before the 160-byte header does.
    #[error(
        ".tfx data is truncated at byte {got} while reading {what}, which needs {needed} bytes; the file is cut short or not a TressFX .tfx file"
    )]
    Truncated {
        /// What was being read.
        what: &'static str,
        /// Bytes needed.
        needed: u64,
        /// Bytes available.
        got: u64,
    },
    /// The version is not a TressFX 4 version.
    #[error(
        "the .tfx version is {version}, but pelage reads TressFX 4 files (version {MIN_VERSION} or later); older TressFX 3 files have a different header: re-export the hair with a TressFX 4 exporter"
    )]
    UnsupportedVersion {
        /// The version found.
        version: f32,
    },
    /// The header says there are no strands.
    #[error(
        "the .tfx header says the file has 0 hair strands; there is no hair to load (or the header is corrupt)"
    )]
    NoStrands,
    /// Fewer than two vertices per strand: no strand has a segment.
    #[error(
        "the .tfx header says {count} vertices per strand; a strand needs at least 2 (TressFX writes 4 to 64)"
    )]
    TooFewVerticesPerStrand {
        /// The count found.
        count: u32,
    },
    /// Implausibly many vertices per strand.
    #[error(
        "the .tfx header says {count} vertices per strand, more than the {max} pelage accepts (TressFX writes 4 to 64); the header is corrupt"
    )]
    TooManyVerticesPerStrand {
        /// The count found.
        count: u32,
        /// The limit.
        max: u32,
    },
    /// The mandatory position array, or an optional array whose offset is
    /// not 0, starts inside the header.
    #[error(
        "the {array} offset is {offset}, inside the {HEADER_SIZE}-byte header{}; arrays start at byte {HEADER_SIZE} or later",
        if *.mandatory { " (the position array is mandatory)" } else { " (0 would mean: absent)" }
    )]
    OffsetInHeader {
        /// Name of the array.
        array: &'static str,
        /// The offset found.
        offset: u32,
        /// Whether the array must be present.
        mandatory: bool,
    },
    /// An array's offset lies past the end of the file.
    #[error(
        "the {array} offset {offset} is beyond the end of the {got}-byte file; the file is truncated or its header is corrupt"
    )]
    OffsetBeyondEnd {
        /// Name of the array.
        array: &'static str,
        /// The offset found.
        offset: u32,
        /// Bytes in the file.
        got: u64,
    },
    /// An array runs past the end of the file (or its size overflows).
    #[error(
        "the header's counts ({strands} strands × {vertices_per_strand} vertices per strand) need {count} {array} entries of {entry_size} bytes from offset {offset}, ending at byte {}, but the file has {got} bytes; the file is truncated or its header is corrupt",
        end_text(*.end)
    )]
    ArrayExceedsFile {
        /// Name of the array.
        array: &'static str,
        /// Strand count from the header.
        strands: u32,
        /// Vertices per strand from the header.
        vertices_per_strand: u32,
        /// Entries the array needs.
        count: u64,
        /// Bytes per entry.
        entry_size: u64,
        /// Where the array starts.
        offset: u32,
        /// Where it would end (`None` if that overflows 64 bits).
        end: Option<u64>,
        /// Bytes in the file.
        got: u64,
    },
    /// A position (or its `w`) is NaN or infinite.
    #[error(
        "vertex {vertex} of strand {strand} is not finite ({value}); every position coordinate and w must be a finite number"
    )]
    NonFinitePosition {
        /// Strand index.
        strand: usize,
        /// Vertex index within the strand.
        vertex: usize,
        /// The value found.
        value: Vec4,
    },
    /// A strand thickness is NaN or infinite.
    #[error("the thickness of strand {strand} is not finite ({value}); it must be a finite number")]
    NonFiniteThickness {
        /// Strand index.
        strand: usize,
        /// The value found.
        value: f32,
    },
    /// The position count is not a whole number of strands (or is zero).
    #[error(
        "there are {positions} positions, which is not a positive multiple of vertices_per_strand ({vertices_per_strand}); every strand must have the same number of vertices"
    )]
    PositionCount {
        /// Length of `positions`.
        positions: usize,
        /// `vertices_per_strand`.
        vertices_per_strand: u32,
    },
    /// An optional array has the wrong length.
    #[error("{array} has {len} entries but must have {expected} (one per {per})")]
    LengthMismatch {
        /// Name of the array.
        array: &'static str,
        /// Its length.
        len: usize,
        /// The length it must have.
        expected: usize,
        /// `"strand"` or `"vertex"`.
        per: &'static str,
    },
    /// Strands given to [`TfxFile::from_strands`] differ in length.
    #[error(
        "strand {strand} has {len} points but strand 0 has {expected}; a .tfx file needs the same number of vertices in every strand (resample the strands first)"
    )]
    UnequalStrands {
        /// Strand index.
        strand: usize,
        /// Its point count.
        len: usize,
        /// Point count of strand 0.
        expected: usize,
    },
    /// The data does not fit the format's 32-bit counts and offsets.
    #[error(
        "{what} is {count}, more than the format's 32-bit fields can hold ({max}); split the hair into several files"
    )]
    TooLarge {
        /// What overflowed (`"the strand count"`, `"an array offset"`).
        what: &'static str,
        /// The value.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// Reading a file failed.
    #[error("could not {action} {}: {source}", path.display())]
    Io {
        /// What was being done (`"read"`).
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// Formats an array end for [`TfxFileError::ArrayExceedsFile`].
fn end_text(end: Option<u64>) -> String {
    end.map_or_else(|| "more than 2^64".to_owned(), |e| e.to_string())
}

/// The first `N` bytes of `bytes` as an array (zero-padded if shorter; the
/// callers pass `chunks_exact(N)` chunks, so that never happens).
fn fixed<const N: usize>(bytes: &[u8]) -> [u8; N] {
    let mut out = [0u8; N];
    for (dst, src) in out.iter_mut().zip(bytes) {
        *dst = *src;
    }
    out
}

/// Little-endian `f32`s of a byte slice whose length is a multiple of 4.
fn f32s(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes.chunks_exact(4).map(|c| f32::from_le_bytes(fixed(c)))
}

/// Header word `index` (0-based, 4 bytes each); 0 if out of range, which the
/// caller rules out by checking the length first.
fn word(bytes: &[u8], index: usize) -> [u8; 4] {
    bytes.get(index * 4..index * 4 + 4).map_or([0; 4], fixed)
}

/// The header fields, as read.
struct Header {
    version: f32,
    strands: u32,
    vertices_per_strand: u32,
    offsets: [u32; 5],
    reserved: [u32; RESERVED_WORDS],
}

/// The arrays in header order: name, whether mandatory, entries per strand
/// (`false`) or per vertex (`true`), bytes per entry.
const ARRAYS: [(&str, bool, bool, u64); 5] = [
    ("vertex position", true, true, 16),
    ("strand UV", false, false, 8),
    ("vertex UV", false, true, 8),
    ("strand thickness", false, false, 4),
    ("vertex colour", false, true, 16),
];

impl TfxFile {
    /// Parses a `.tfx` file held in memory. Works on any alignment.
    ///
    /// Errors: shorter than the header ([`TfxFileError::Truncated`]), a
    /// version below 4 or not finite, zero strands, fewer than 2 or more than
    /// [`MAX_VERTICES_PER_STRAND`] vertices per strand, an array offset
    /// inside the header or past the end of the file, an array that runs
    /// past the end (all checked before anything is allocated), a NaN or
    /// infinite position or thickness.
    pub fn read(bytes: &[u8]) -> Result<TfxFile, TfxFileError> {
        let got = bytes.len() as u64;
        if bytes.len() < HEADER_SIZE {
            return Err(TfxFileError::Truncated {
                what: "the header",
                needed: HEADER_SIZE as u64,
                got,
            });
        }
        let u32_at = |i| u32::from_le_bytes(word(bytes, i));
        let mut reserved = [0u32; RESERVED_WORDS];
        for (k, r) in reserved.iter_mut().enumerate() {
            *r = u32_at(8 + k);
        }
        let header = Header {
            version: f32::from_le_bytes(word(bytes, 0)),
            strands: u32_at(1),
            vertices_per_strand: u32_at(2),
            offsets: [u32_at(3), u32_at(4), u32_at(5), u32_at(6), u32_at(7)],
            reserved,
        };
        check_counts(header.version, header.strands, header.vertices_per_strand)?;

        // Every array's extent against the file, before any allocation.
        let mut slices: [Option<&[u8]>; 5] = [None; 5];
        for (slot, (&offset, &(array, mandatory, per_vertex, entry_size))) in
            slices.iter_mut().zip(header.offsets.iter().zip(&ARRAYS))
        {
            if offset == 0 && !mandatory {
                continue;
            }
            if (offset as usize) < HEADER_SIZE {
                return Err(TfxFileError::OffsetInHeader {
                    array,
                    offset,
                    mandatory,
                });
            }
            if u64::from(offset) > got {
                return Err(TfxFileError::OffsetBeyondEnd { array, offset, got });
            }
            let strands = u64::from(header.strands);
            let count = if per_vertex {
                strands.checked_mul(u64::from(header.vertices_per_strand))
            } else {
                Some(strands)
            };
            let end = count
                .and_then(|c| c.checked_mul(entry_size))
                .and_then(|size| size.checked_add(u64::from(offset)));
            let exceeds = || TfxFileError::ArrayExceedsFile {
                array,
                strands: header.strands,
                vertices_per_strand: header.vertices_per_strand,
                count: count.unwrap_or(u64::MAX),
                entry_size,
                offset,
                end,
                got,
            };
            let slice = end
                .filter(|&e| e <= got)
                .and_then(|e| usize::try_from(e).ok())
                .and_then(|e| bytes.get(offset as usize..e))
                .ok_or_else(exceeds)?;
            *slot = Some(slice);
        }
        let [positions, strand_uv, vertex_uv, thickness, vertex_color] = slices;

        let vec4s = |b: &[u8]| -> Vec<Vec4> {
            b.chunks_exact(16)
                .map(|c| {
                    let mut v = f32s(c);
                    let mut next = || v.next().unwrap_or(0.0);
                    Vec4::new(next(), next(), next(), next())
                })
                .collect()
        };
        let vec2s = |b: &[u8]| -> Vec<Vec2> {
            b.chunks_exact(8)
                .map(|c| {
                    let mut v = f32s(c);
                    let mut next = || v.next().unwrap_or(0.0);
                    Vec2::new(next(), next())
                })
                .collect()
        };
        let file = TfxFile {
            version: header.version,
            vertices_per_strand: header.vertices_per_strand,
            positions: positions.map(vec4s).unwrap_or_default(),
            strand_uv: strand_uv.map(vec2s),
            vertex_uv: vertex_uv.map(vec2s),
            thickness: thickness.map(|b| f32s(b).collect()),
            vertex_color: vertex_color.map(vec4s),
            reserved: header.reserved,
        };
        file.check_values()?;
        Ok(file)
    }

    /// Reads and parses the `.tfx` file at `path` (see [`TfxFile::read`]); at
    /// most [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES) are read.
    pub fn load(path: impl AsRef<Path>) -> Result<TfxFile, TfxFileError> {
        let path = path.as_ref();
        let bytes = crate::limits::read_capped(path, crate::MAX_GROOM_FILE_BYTES, "groom files")
            .map_err(|source| TfxFileError::Io {
                action: "read",
                path: path.to_path_buf(),
                source,
            })?;
        TfxFile::read(&bytes)
    }

    /// Builds a file from strands that all have the same number of points
    /// (root first), version [`VERSION`], no optional arrays. `w` follows
    /// AMD's exporter: 0 (immovable) for the first two vertices of every
    /// strand, 1 for the others.
    ///
    /// Errors: no strands, strands of different lengths, fewer than 2 or
    /// more than [`MAX_VERTICES_PER_STRAND`] points, a NaN or infinite
    /// point, more than `u32::MAX` strands.
    pub fn from_strands(strands: &[Vec<Vec3>]) -> Result<TfxFile, TfxFileError> {
        let first = strands.first().ok_or(TfxFileError::NoStrands)?;
        let len = first.len();
        if let Some((strand, s)) = strands.iter().enumerate().find(|(_, s)| s.len() != len) {
            return Err(TfxFileError::UnequalStrands {
                strand,
                len: s.len(),
                expected: len,
            });
        }
        let vertices_per_strand = u32::try_from(len).unwrap_or(u32::MAX);
        let file = TfxFile {
            version: VERSION,
            vertices_per_strand,
            positions: strands
                .iter()
                .flat_map(|s| {
                    s.iter()
                        .enumerate()
                        .map(|(k, p)| p.extend(if k < 2 { 0.0 } else { 1.0 }))
                })
                .collect(),
            strand_uv: None,
            vertex_uv: None,
            thickness: None,
            vertex_color: None,
            reserved: [0; RESERVED_WORDS],
        };
        file.check()?;
        Ok(file)
    }

    /// Number of strands (`positions.len() / vertices_per_strand`, 0 if
    /// `vertices_per_strand` is 0).
    pub fn strand_count(&self) -> usize {
        self.positions
            .len()
            .checked_div(self.vertices_per_strand as usize)
            .unwrap_or(0)
    }

    /// The vertices of every strand, root first (a trailing partial strand,
    /// only possible in an inconsistent struct, is left out).
    pub fn strands(&self) -> impl Iterator<Item = &[Vec4]> + '_ {
        self.positions
            .chunks_exact((self.vertices_per_strand as usize).max(1))
    }

    /// Checks that the struct can be written as it is and read back equal:
    /// a version [`TfxFile::read`] accepts, 2 to [`MAX_VERTICES_PER_STRAND`]
    /// vertices per strand, a positive whole number of strands (at most
    /// `u32::MAX`), optional arrays of the right length, finite positions
    /// and thicknesses.
    pub fn check(&self) -> Result<(), TfxFileError> {
        let vps = self.vertices_per_strand;
        check_counts(self.version, 1, vps)?;
        let strands = self.strand_count();
        if strands == 0 || !self.positions.len().is_multiple_of(vps as usize) {
            return Err(TfxFileError::PositionCount {
                positions: self.positions.len(),
                vertices_per_strand: vps,
            });
        }
        if u32::try_from(strands).is_err() {
            return Err(TfxFileError::TooLarge {
                what: "the strand count",
                count: strands as u64,
                max: u64::from(u32::MAX),
            });
        }
        let vertices = self.positions.len();
        let lengths = [
            (
                "strand_uv",
                self.strand_uv.as_ref().map(Vec::len),
                strands,
                "strand",
            ),
            (
                "vertex_uv",
                self.vertex_uv.as_ref().map(Vec::len),
                vertices,
                "vertex",
            ),
            (
                "thickness",
                self.thickness.as_ref().map(Vec::len),
                strands,
                "strand",
            ),
            (
                "vertex_color",
                self.vertex_color.as_ref().map(Vec::len),
                vertices,
                "vertex",
            ),
        ];
        for (array, len, expected, per) in lengths {
            if let Some(len) = len.filter(|&l| l != expected) {
                return Err(TfxFileError::LengthMismatch {
                    array,
                    len,
                    expected,
                    per,
                });
            }
        }
        self.check_values()
    }

    /// Finite positions and thicknesses.
    fn check_values(&self) -> Result<(), TfxFileError> {
        let vps = (self.vertices_per_strand as usize).max(1);
        if let Some((i, &value)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(TfxFileError::NonFinitePosition {
                strand: i / vps,
                vertex: i % vps,
                value,
            });
        }
        if let Some((strand, &value)) = self
            .thickness
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, t)| !t.is_finite())
        {
            return Err(TfxFileError::NonFiniteThickness { strand, value });
        }
        Ok(())
    }

    /// Encodes the file (after [`TfxFile::check`]): the header, then the
    /// arrays that are present in header order, each starting on an 8-byte
    /// boundary (the strand thickness array is padded with zero bytes).
    ///
    /// Errors: what [`TfxFile::check`] reports, and an array that would
    /// start beyond the 32-bit offsets' reach (about 4 GiB).
    pub fn write(&self) -> Result<Vec<u8>, TfxFileError> {
        self.check()?;
        let strands = self.strand_count();
        let vec4 = |v: &Vec4| v.to_array();
        let vec2 = |v: &Vec2| v.to_array();
        let arrays: [Option<Vec<f32>>; 5] = [
            Some(self.positions.iter().flat_map(vec4).collect()),
            self.strand_uv
                .as_ref()
                .map(|a| a.iter().flat_map(vec2).collect()),
            self.vertex_uv
                .as_ref()
                .map(|a| a.iter().flat_map(vec2).collect()),
            self.thickness.clone(),
            self.vertex_color
                .as_ref()
                .map(|a| a.iter().flat_map(vec4).collect()),
        ];
        let mut offsets = [0u32; 5];
        let mut end = HEADER_SIZE as u64;
        for (offset, array) in offsets.iter_mut().zip(&arrays) {
            if let Some(values) = array {
                *offset = u32::try_from(end).map_err(|_| TfxFileError::TooLarge {
                    what: "an array offset",
                    count: end,
                    max: u64::from(u32::MAX),
                })?;
                end += (values.len() as u64 * 4).next_multiple_of(8);
            }
        }

        let mut out = Vec::with_capacity(usize::try_from(end).unwrap_or(0));
        out.extend_from_slice(&self.version.to_le_bytes());
        let counts = [strands as u32, self.vertices_per_strand];
        for v in counts.iter().chain(&offsets).chain(&self.reserved) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for values in arrays.iter().flatten() {
            for v in values {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.resize(out.len().next_multiple_of(8), 0);
        }
        Ok(out)
    }
}

/// The header checks shared by reading and writing.
fn check_counts(version: f32, strands: u32, vertices_per_strand: u32) -> Result<(), TfxFileError> {
    if !(version.is_finite() && version >= MIN_VERSION) {
        return Err(TfxFileError::UnsupportedVersion { version });
    }
    if strands == 0 {
        return Err(TfxFileError::NoStrands);
    }
    if vertices_per_strand < 2 {
        return Err(TfxFileError::TooFewVerticesPerStrand {
            count: vertices_per_strand,
        });
    }
    if vertices_per_strand > MAX_VERTICES_PER_STRAND {
        return Err(TfxFileError::TooManyVerticesPerStrand {
            count: vertices_per_strand,
            max: MAX_VERTICES_PER_STRAND,
        });
    }
    Ok(())
}
