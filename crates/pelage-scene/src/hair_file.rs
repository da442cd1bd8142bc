//! Cem Yuksel's `.hair` format: read and write.
//!
//! Layout (little-endian): a 128-byte header
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `char[4]` | signature `"HAIR"` |
//! | 4 | `u32` | hair (strand) count |
//! | 8 | `u32` | point count |
//! | 12 | `u32` | arrays present: 1 segments, 2 points, 4 thickness, 8 transparency, 16 colours |
//! | 16 | `u32` | default segment count |
//! | 20 | `f32` | default thickness |
//! | 24 | `f32` | default transparency |
//! | 28 | `f32[3]` | default colour |
//! | 40 | `char[88]` | free-form information |
//!
//! followed directly, without padding, by the arrays that are present in this
//! order: segments (`u16` per strand), points (`f32 × 3` per point), thickness
//! (`f32` per point), transparency (`f32` per point), colours (`f32 × 3` per
//! point). Strand `i` has `segments[i] + 1` points, root first. Unknown bits
//! of the array field are ignored; bytes after the arrays are ignored.
//!
//! Reading never trusts the header: all sizes are computed with checked
//! 64-bit arithmetic and compared with the file length before anything is
//! allocated, and every read is a bounds-checked little-endian decode (no
//! pointer casts, so unaligned input is fine).

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::Vec3;

/// Size of the fixed header in bytes.
pub const HEADER_SIZE: usize = 128;
/// Size of the `info` field of the header in bytes.
pub const INFO_SIZE: usize = 88;
/// The four signature bytes every `.hair` file starts with.
pub const SIGNATURE: [u8; 4] = *b"HAIR";

/// Array bit: a per-strand segment count array is present.
pub const ARRAY_SEGMENTS: u32 = 1;
/// Array bit: the point array is present (mandatory for pelage).
pub const ARRAY_POINTS: u32 = 2;
/// Array bit: a per-point thickness array is present.
pub const ARRAY_THICKNESS: u32 = 4;
/// Array bit: a per-point transparency array is present.
pub const ARRAY_TRANSPARENCY: u32 = 8;
/// Array bit: a per-point colour array is present.
pub const ARRAY_COLORS: u32 = 16;

/// The contents of a `.hair` file, with every per-point array expanded.
///
/// `has_*` and `default_*` keep what the file said, so that writing what was
/// read gives back the same bytes (for files whose `info` is UTF-8 padded
/// with NULs and whose array field has no unknown bits).
#[derive(Clone, Debug, PartialEq)]
pub struct HairFile {
    /// Segment count of every strand (expanded from the default when the
    /// file has no segments array). A strand has `segments + 1` points.
    pub segments: Vec<u16>,
    /// All strand points, strand after strand, root first.
    pub points: Vec<Vec3>,
    /// Thickness per point (filled from `default_thickness` when absent).
    pub thickness: Vec<f32>,
    /// Transparency per point (filled from `default_transparency` when absent).
    pub transparency: Vec<f32>,
    /// Colour per point (filled from `default_color` when absent).
    pub colors: Vec<Vec3>,
    /// The header's information text: up to 88 bytes, cut at the first NUL,
    /// decoded as lossy UTF-8.
    pub info: String,
    /// Whether the file has (or will be written with) a segments array.
    pub has_segments: bool,
    /// Whether the file has (or will be written with) a thickness array.
    pub has_thickness: bool,
    /// Whether the file has (or will be written with) a transparency array.
    pub has_transparency: bool,
    /// Whether the file has (or will be written with) a colour array.
    pub has_colors: bool,
    /// Segment count of every strand when there is no segments array.
    pub default_segments: u32,
    /// Thickness of every point when there is no thickness array.
    pub default_thickness: f32,
    /// Transparency of every point when there is no transparency array.
    pub default_transparency: f32,
    /// Colour of every point when there is no colour array.
    pub default_color: Vec3,
}

/// What is wrong with a `.hair` file or with a [`HairFile`] about to be written.
#[derive(Debug, thiserror::Error)]
pub enum HairFileError {
    /// The data is shorter than the 128-byte header.
    #[error(
        ".hair data is {got} bytes, shorter than the {needed}-byte header; the file is truncated or not a .hair file"
    )]
    Truncated {
        /// Bytes needed.
        needed: u64,
        /// Bytes available.
        got: u64,
    },
    /// The first four bytes are not `"HAIR"`.
    #[error(
        "not a .hair file: the signature is {found:02x?} ({}), expected \"HAIR\"",
        String::from_utf8_lossy(found)
    )]
    BadSignature {
        /// The four bytes found.
        found: [u8; 4],
    },
    /// The header's counts need more bytes than the file has.
    #[error(
        "the header (hair_count {hair_count}, point_count {point_count}, arrays {arrays:#x}) needs {needed} bytes but the file has {got}; the file is truncated or its header is corrupt"
    )]
    ArraysExceedFile {
        /// Strand count from the header.
        hair_count: u32,
        /// Point count from the header.
        point_count: u32,
        /// Array bit field from the header.
        arrays: u32,
        /// Bytes needed for header and arrays (`u64::MAX` if that overflows).
        needed: u64,
        /// Bytes in the file.
        got: u64,
    },
    /// The points do not add up: `Σ (segments + 1) != point_count`.
    #[error(
        "{hair_count} strands with their segment counts need {expected_points} points (segments + 1 per strand{}), but point_count is {point_count}",
        if *.from_default { ", all from the default segment count" } else { "" }
    )]
    SegmentPointMismatch {
        /// Number of strands.
        hair_count: u64,
        /// Number of points present.
        point_count: u64,
        /// Number of points the segment counts need.
        expected_points: u64,
        /// Whether the segment counts came from the default (no segments array).
        from_default: bool,
    },
    /// The default segment count does not fit the per-strand `u16` segments.
    #[error(
        "the default segment count {default_segments} is larger than 65535, the most a strand can have; the file is corrupt"
    )]
    DefaultSegmentsTooLarge {
        /// The default segment count from the header.
        default_segments: u32,
    },
    /// The file has no point array.
    #[error(
        "the .hair file has no point array (arrays field {arrays:#x} lacks bit 2); pelage needs strand points"
    )]
    MissingPoints {
        /// Array bit field from the header.
        arrays: u32,
    },
    /// A point is NaN or infinite.
    #[error("point {index} is not finite ({value}); every coordinate must be a finite number")]
    NonFinitePoint {
        /// Point index.
        index: usize,
        /// The value found.
        value: Vec3,
    },
    /// A per-point or per-strand array has the wrong length.
    #[error("{array} has {len} entries but must have {expected} (one per {per})")]
    LengthMismatch {
        /// Name of the array.
        array: &'static str,
        /// Its length.
        len: usize,
        /// The length it must have.
        expected: usize,
        /// `"point"` or `"strand"`.
        per: &'static str,
    },
    /// An array is marked absent but its values differ from the default,
    /// so writing would lose them.
    #[error(
        "{array}[{index}] differs from the default, but {flag} is false, so it would not be written; set {flag} = true or reset the value"
    )]
    NotDefault {
        /// Name of the array.
        array: &'static str,
        /// First index that differs.
        index: usize,
        /// The flag to set.
        flag: &'static str,
    },
    /// `info` does not fit in the header or contains a NUL byte.
    #[error(
        "info is {len} bytes{}; it must be at most 88 bytes of text without NUL bytes",
        if *.has_nul { " and contains a NUL byte" } else { "" }
    )]
    BadInfo {
        /// Length of `info` in bytes.
        len: usize,
        /// Whether `info` contains a NUL byte.
        has_nul: bool,
    },
    /// More strands or points than the format's `u32` counts can hold.
    #[error("{what} count {count} exceeds the format's limit of {max}")]
    TooMany {
        /// `"strand"` or `"point"`.
        what: &'static str,
        /// The count.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// A strand given to [`HairFile::from_strands`] has too few or too many points.
    #[error(
        "strand {strand} has {points} points; a strand needs between 2 and 65536 points (1 to 65535 segments)"
    )]
    BadStrandLength {
        /// Strand index.
        strand: usize,
        /// Its point count.
        points: usize,
    },
    /// Reading or writing a file failed.
    #[error("could not {action} {}: {source}", path.display())]
    Io {
        /// What was being done (`"read"`, `"write"`, ...).
        action: &'static str,
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

/// A bounds-checked little-endian reader over a byte slice.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], HairFileError> {
        let got = self.bytes.len() as u64;
        let end = self.pos.checked_add(n).ok_or(HairFileError::Truncated {
            needed: u64::MAX,
            got,
        })?;
        let slice = self
            .bytes
            .get(self.pos..end)
            .ok_or(HairFileError::Truncated {
                needed: end as u64,
                got,
            })?;
        self.pos = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], HairFileError> {
        Ok(fixed(self.take(N)?))
    }

    fn u32(&mut self) -> Result<u32, HairFileError> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    fn f32(&mut self) -> Result<f32, HairFileError> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    fn vec3(&mut self) -> Result<Vec3, HairFileError> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }

    /// `count` little-endian f32 values.
    fn f32s(&mut self, count: usize) -> Result<Vec<f32>, HairFileError> {
        let bytes = self.take(count.checked_mul(4).ok_or(HairFileError::Truncated {
            needed: u64::MAX,
            got: self.bytes.len() as u64,
        })?)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(fixed(c)))
            .collect())
    }

    /// `count` little-endian Vec3 values.
    fn vec3s(&mut self, count: usize) -> Result<Vec<Vec3>, HairFileError> {
        let bytes = self.take(count.checked_mul(12).ok_or(HairFileError::Truncated {
            needed: u64::MAX,
            got: self.bytes.len() as u64,
        })?)?;
        Ok(bytes
            .chunks_exact(12)
            .map(|c| {
                let mut xyz = c.chunks_exact(4).map(|f| f32::from_le_bytes(fixed(f)));
                let mut next = || xyz.next().unwrap_or(0.0);
                Vec3::new(next(), next(), next())
            })
            .collect())
    }
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

/// Bytes the arrays named in `arrays` need, header included; `None` on overflow.
fn file_size(hair_count: u32, point_count: u32, arrays: u32) -> Option<u64> {
    let hairs = u64::from(hair_count);
    let points = u64::from(point_count);
    let mut size = HEADER_SIZE as u64;
    let mut add = |bit: u32, bytes: Option<u64>| -> Option<()> {
        if arrays & bit != 0 {
            size = size.checked_add(bytes?)?;
        }
        Some(())
    };
    add(ARRAY_SEGMENTS, hairs.checked_mul(2))?;
    add(ARRAY_POINTS, points.checked_mul(12))?;
    add(ARRAY_THICKNESS, points.checked_mul(4))?;
    add(ARRAY_TRANSPARENCY, points.checked_mul(4))?;
    add(ARRAY_COLORS, points.checked_mul(12))?;
    Some(size)
}

/// Converts a count known to fit the (already size-checked) file into `usize`.
fn to_usize(value: u32, file_len: u64) -> Result<usize, HairFileError> {
    usize::try_from(value).map_err(|_| HairFileError::Truncated {
        needed: u64::from(value),
        got: file_len,
    })
}

impl HairFile {
    /// Parses a `.hair` file held in memory. Works on any alignment.
    ///
    /// Errors: shorter than the header ([`HairFileError::Truncated`]), wrong
    /// signature, arrays that need more bytes than there are (checked before
    /// anything is allocated), no point array, segment counts that do not
    /// add up to the point count, a NaN or infinite point. Unknown array bits
    /// and trailing bytes are ignored.
    pub fn read(bytes: &[u8]) -> Result<HairFile, HairFileError> {
        let file_len = bytes.len() as u64;
        if bytes.len() < HEADER_SIZE {
            return Err(HairFileError::Truncated {
                needed: HEADER_SIZE as u64,
                got: file_len,
            });
        }
        let mut r = Reader { bytes, pos: 0 };
        let signature: [u8; 4] = r.array()?;
        if signature != SIGNATURE {
            return Err(HairFileError::BadSignature { found: signature });
        }
        let hair_count = r.u32()?;
        let point_count = r.u32()?;
        let arrays = r.u32()?;
        let default_segments = r.u32()?;
        let default_thickness = r.f32()?;
        let default_transparency = r.f32()?;
        let default_color = r.vec3()?;
        let info_bytes: [u8; INFO_SIZE] = r.array()?;

        if arrays & ARRAY_POINTS == 0 {
            return Err(HairFileError::MissingPoints { arrays });
        }
        let needed = file_size(hair_count, point_count, arrays);
        if needed.is_none_or(|n| n > file_len) {
            return Err(HairFileError::ArraysExceedFile {
                hair_count,
                point_count,
                arrays,
                needed: needed.unwrap_or(u64::MAX),
                got: file_len,
            });
        }
        let has_segments = arrays & ARRAY_SEGMENTS != 0;
        let has_thickness = arrays & ARRAY_THICKNESS != 0;
        let has_transparency = arrays & ARRAY_TRANSPARENCY != 0;
        let has_colors = arrays & ARRAY_COLORS != 0;

        // Segment counts, checked against the point count before any
        // allocation that the file size does not bound.
        let hairs = to_usize(hair_count, file_len)?;
        let points = to_usize(point_count, file_len)?;
        let segments: Vec<u16> = if has_segments {
            let raw = r.take(hairs.saturating_mul(2))?;
            let segments: Vec<u16> = raw
                .chunks_exact(2)
                .map(|c| u16::from_le_bytes(fixed(c)))
                .collect();
            let expected_points: u64 = segments.iter().map(|&s| u64::from(s) + 1).sum();
            if expected_points != u64::from(point_count) {
                return Err(HairFileError::SegmentPointMismatch {
                    hair_count: u64::from(hair_count),
                    point_count: u64::from(point_count),
                    expected_points,
                    from_default: false,
                });
            }
            segments
        } else {
            let expected_points =
                u64::from(hair_count).saturating_mul(u64::from(default_segments) + 1);
            if expected_points != u64::from(point_count) {
                return Err(HairFileError::SegmentPointMismatch {
                    hair_count: u64::from(hair_count),
                    point_count: u64::from(point_count),
                    expected_points,
                    from_default: true,
                });
            }
            if hair_count == 0 {
                Vec::new()
            } else {
                let default = u16::try_from(default_segments)
                    .map_err(|_| HairFileError::DefaultSegmentsTooLarge { default_segments })?;
                // hair_count <= point_count here, and the points fit in the file.
                vec![default; hairs]
            }
        };

        let point_values = r.vec3s(points)?;
        if let Some((index, &value)) = point_values
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(HairFileError::NonFinitePoint { index, value });
        }
        let thickness = if has_thickness {
            r.f32s(points)?
        } else {
            vec![default_thickness; points]
        };
        let transparency = if has_transparency {
            r.f32s(points)?
        } else {
            vec![default_transparency; points]
        };
        let colors = if has_colors {
            r.vec3s(points)?
        } else {
            vec![default_color; points]
        };

        let info_len = info_bytes.iter().position(|&b| b == 0).unwrap_or(INFO_SIZE);
        let info = String::from_utf8_lossy(info_bytes.get(..info_len).unwrap_or(&[])).into_owned();

        Ok(HairFile {
            segments,
            points: point_values,
            thickness,
            transparency,
            colors,
            info,
            has_segments,
            has_thickness,
            has_transparency,
            has_colors,
            default_segments,
            default_thickness,
            default_transparency,
            default_color,
        })
    }

    /// Reads and parses the `.hair` file at `path` (see [`HairFile::read`]).
    ///
    /// Reads the header first and then only the bytes it declares, at most
    /// [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES): a path to a stream such
    /// as `/dev/zero` stops at its signature after 128 bytes.
    pub fn read_path(path: &Path) -> Result<HairFile, HairFileError> {
        use std::io::Read;
        let io = |source| HairFileError::Io {
            action: "read",
            path: path.to_path_buf(),
            source,
        };
        let mut file = crate::limits::open_regular(path).map_err(io)?;
        let file_len = file.metadata().map(|m| m.len()).map_err(io)?;
        let mut bytes = Vec::with_capacity(HEADER_SIZE);
        (&mut file)
            .take(HEADER_SIZE as u64)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() == HEADER_SIZE && bytes[..4] == SIGNATURE {
            let word = |at: usize| u32::from_le_bytes(fixed(&bytes[at..at + 4]));
            let (hair_count, point_count, arrays) = (word(4), word(8), word(12));
            let needed = file_size(hair_count, point_count, arrays);
            // A header that claims more than the file holds is named by its counts and
            // the file's real size, whether or not the claim passes the size cap.
            if needed.is_none_or(|n| n > file_len) && arrays & ARRAY_POINTS != 0 {
                return Err(HairFileError::ArraysExceedFile {
                    hair_count,
                    point_count,
                    arrays,
                    needed: needed.unwrap_or(u64::MAX),
                    got: file_len,
                });
            }
            if let Some(size) = needed {
                let limit = crate::MAX_GROOM_FILE_BYTES;
                if size > limit {
                    return Err(io(crate::limits::too_large(limit, "groom files")));
                }
                (&mut file)
                    .take(size - HEADER_SIZE as u64)
                    .read_to_end(&mut bytes)
                    .map_err(io)?;
            }
        }
        // A bad signature, a short file or counts that overflow are `read`'s to name.
        HairFile::read(&bytes)
    }

    /// Builds a file from strands (each a list of points, root first), with
    /// a segments array and the format's usual defaults for the rest
    /// (thickness 1, transparency 0, colour white; no per-point arrays).
    ///
    /// Errors: a strand with fewer than 2 or more than 65536 points, a NaN
    /// or infinite point, more than `u32::MAX` strands or points.
    pub fn from_strands(strands: &[Vec<Vec3>]) -> Result<HairFile, HairFileError> {
        let max = u64::from(u32::MAX);
        if strands.len() as u64 > max {
            return Err(HairFileError::TooMany {
                what: "strand",
                count: strands.len() as u64,
                max,
            });
        }
        let mut segments = Vec::with_capacity(strands.len());
        let mut total: u64 = 0;
        for (strand, points) in strands.iter().enumerate() {
            let segment_count = points
                .len()
                .checked_sub(1)
                .filter(|&s| s >= 1)
                .and_then(|s| u16::try_from(s).ok())
                .ok_or(HairFileError::BadStrandLength {
                    strand,
                    points: points.len(),
                })?;
            segments.push(segment_count);
            total = total.saturating_add(points.len() as u64);
        }
        if total > max {
            return Err(HairFileError::TooMany {
                what: "point",
                count: total,
                max,
            });
        }
        let points: Vec<Vec3> = strands.iter().flatten().copied().collect();
        if let Some((index, &value)) = points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(HairFileError::NonFinitePoint { index, value });
        }
        let n = points.len();
        Ok(HairFile {
            segments,
            points,
            thickness: vec![1.0; n],
            transparency: vec![0.0; n],
            colors: vec![Vec3::ONE; n],
            info: String::new(),
            has_segments: true,
            has_thickness: false,
            has_transparency: false,
            has_colors: false,
            default_segments: 0,
            default_thickness: 1.0,
            default_transparency: 0.0,
            default_color: Vec3::ONE,
        })
    }

    /// Point index range of every strand, in order (`segments[i] + 1`
    /// points each): what an offsets buffer is built from. Stops early,
    /// without panicking, at the first strand that would run past the end
    /// of `points` (only possible if the struct was edited inconsistently;
    /// [`HairFile::check`] reports that).
    pub fn strand_ranges(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        let point_count = self.points.len();
        self.segments.iter().scan(0usize, move |start, &s| {
            let end = start.checked_add(usize::from(s) + 1)?;
            if end > point_count {
                return None;
            }
            let range = *start..end;
            *start = end;
            Some(range)
        })
    }

    /// The points of every strand, root first (see [`HairFile::strand_ranges`]).
    pub fn strands(&self) -> impl Iterator<Item = &[Vec3]> + '_ {
        self.strand_ranges()
            .filter_map(move |range| self.points.get(range))
    }

    /// Checks that the struct can be written as it is and read back equal:
    /// counts fit in `u32`, segment counts add up to the point count,
    /// per-point arrays have one entry per point, values of arrays marked
    /// absent equal their default, segment counts equal the default when
    /// there is no segments array, points are finite, and `info` fits.
    pub fn check(&self) -> Result<(), HairFileError> {
        let max = u64::from(u32::MAX);
        for (what, count) in [
            ("strand", self.segments.len()),
            ("point", self.points.len()),
        ] {
            if count as u64 > max {
                return Err(HairFileError::TooMany {
                    what,
                    count: count as u64,
                    max,
                });
            }
        }
        let n = self.points.len();
        for (array, len) in [
            ("thickness", self.thickness.len()),
            ("transparency", self.transparency.len()),
            ("colors", self.colors.len()),
        ] {
            if len != n {
                return Err(HairFileError::LengthMismatch {
                    array,
                    len,
                    expected: n,
                    per: "point",
                });
            }
        }
        let expected_points: u64 = self.segments.iter().map(|&s| u64::from(s) + 1).sum();
        if expected_points != n as u64 {
            return Err(HairFileError::SegmentPointMismatch {
                hair_count: self.segments.len() as u64,
                point_count: n as u64,
                expected_points,
                from_default: false,
            });
        }
        if !self.has_segments {
            if let Some(index) = self
                .segments
                .iter()
                .position(|&s| u32::from(s) != self.default_segments)
            {
                return Err(HairFileError::NotDefault {
                    array: "segments",
                    index,
                    flag: "has_segments",
                });
            }
        }
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits();
        let same3 = |a: Vec3, b: Vec3| same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z);
        let not_default = [
            (
                !self.has_thickness,
                "thickness",
                "has_thickness",
                self.thickness
                    .iter()
                    .position(|&v| !same(v, self.default_thickness)),
            ),
            (
                !self.has_transparency,
                "transparency",
                "has_transparency",
                self.transparency
                    .iter()
                    .position(|&v| !same(v, self.default_transparency)),
            ),
            (
                !self.has_colors,
                "colors",
                "has_colors",
                self.colors
                    .iter()
                    .position(|&v| !same3(v, self.default_color)),
            ),
        ];
        for (absent, array, flag, first_different) in not_default {
            if let (true, Some(index)) = (absent, first_different) {
                return Err(HairFileError::NotDefault { array, index, flag });
            }
        }
        if let Some((index, &value)) = self.points.iter().enumerate().find(|(_, p)| !p.is_finite())
        {
            return Err(HairFileError::NonFinitePoint { index, value });
        }
        let info = self.info.as_bytes();
        let has_nul = info.contains(&0);
        if info.len() > INFO_SIZE || has_nul {
            return Err(HairFileError::BadInfo {
                len: info.len(),
                has_nul,
            });
        }
        Ok(())
    }

    /// Encodes the file (after [`HairFile::check`]). Arrays are written for
    /// the `has_*` flags that are set, plus the point array.
    pub fn write(&self) -> Result<Vec<u8>, HairFileError> {
        self.check()?;
        let too_many = |what, count: usize| HairFileError::TooMany {
            what,
            count: count as u64,
            max: u64::from(u32::MAX),
        };
        let hair_count = u32::try_from(self.segments.len())
            .map_err(|_| too_many("strand", self.segments.len()))?;
        let point_count =
            u32::try_from(self.points.len()).map_err(|_| too_many("point", self.points.len()))?;
        let mut arrays = ARRAY_POINTS;
        for (present, bit) in [
            (self.has_segments, ARRAY_SEGMENTS),
            (self.has_thickness, ARRAY_THICKNESS),
            (self.has_transparency, ARRAY_TRANSPARENCY),
            (self.has_colors, ARRAY_COLORS),
        ] {
            if present {
                arrays |= bit;
            }
        }
        let size = file_size(hair_count, point_count, arrays)
            .and_then(|s| usize::try_from(s).ok())
            .ok_or_else(|| too_many("point", self.points.len()))?;

        let mut out = Vec::with_capacity(size);
        out.extend_from_slice(&SIGNATURE);
        for v in [hair_count, point_count, arrays, self.default_segments] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let c = self.default_color;
        for v in [
            self.default_thickness,
            self.default_transparency,
            c.x,
            c.y,
            c.z,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let mut info = [0u8; INFO_SIZE];
        let text = self.info.as_bytes();
        if let Some(dst) = info.get_mut(..text.len()) {
            dst.copy_from_slice(text);
        }
        out.extend_from_slice(&info);

        let put_f32s = |out: &mut Vec<u8>, values: &[f32]| {
            for v in values {
                out.extend_from_slice(&v.to_le_bytes());
            }
        };
        let put_vec3s = |out: &mut Vec<u8>, values: &[Vec3]| {
            for v in values {
                for x in [v.x, v.y, v.z] {
                    out.extend_from_slice(&x.to_le_bytes());
                }
            }
        };
        if self.has_segments {
            for s in &self.segments {
                out.extend_from_slice(&s.to_le_bytes());
            }
        }
        put_vec3s(&mut out, &self.points);
        if self.has_thickness {
            put_f32s(&mut out, &self.thickness);
        }
        if self.has_transparency {
            put_f32s(&mut out, &self.transparency);
        }
        if self.has_colors {
            put_vec3s(&mut out, &self.colors);
        }
        Ok(out)
    }
}
