//! One groom type for every hair source: strands of any length from a Cem
//! Yuksel `.hair` file ([`HairFile`]), an AMD TressFX `.tfx` file
//! ([`TfxFile`]), a USD file's `BasisCurves` (feature `usd`, `usd_file`) or
//! plain point lists, with optional per-point widths and per-strand colours.
//!
//! A [`Groom`] stores its points flat, strand after strand, root first, with
//! an offsets array (`strand_count + 1` entries, strand `i` is
//! `points[offsets[i]..offsets[i + 1]]`): the layout of the variable-length
//! strand buffers in `DESIGN.md`. [`Groom::resample`] turns it into a fixed
//! number of segments per strand, evenly spaced by arc length, for renderers
//! that draw the same number of segments for every strand.
//!
//! Invariants (checked by every constructor): at least one strand, at least
//! one point per strand, at most `u32::MAX` points, every point finite,
//! every width finite, non-negative and at most [`MAX_EXTENT`](crate::MAX_EXTENT)
//! (errors name the file's attribute: a `.hair` or `.tfx` file's `thickness`).
//!
//! **Colours.** A groom carries at most one colour per strand (linear RGB), which
//! becomes the strand's colour in pelage-strands in place of `growth.color` (the
//! scene's `growth.color_jitter` still varies its brightness). Files with per-point
//! colours give each strand its **root** point's colour: a `.hair` file's colour array
//! (not its header's default colour, as its default thickness is not used either),
//! a `.tfx` file's `vertex_color` (RGB; alpha is not read), a USD file's
//! `primvars:displayColor` (see `usd_file`). Every colour of the file is checked
//! (finite, not negative), not only the roots'.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::hair_file::{HairFile, HairFileError};
use crate::params::MAX_SEGMENTS;
use crate::tfx_file::{TfxFile, TfxFileError};

/// File extensions [`Groom::load`] understands (lower case, without the dot); with the
/// `usd` feature also `usd_file::USD_EXTENSIONS`.
pub const SUPPORTED_EXTENSIONS: [&str; 2] = ["hair", "tfx"];

/// Hair strands from any source, with optional per-point widths.
#[derive(Clone, Debug, PartialEq)]
pub struct Groom {
    /// Every point, strand after strand, root first.
    points: Vec<Vec3>,
    /// `strand_count + 1` entries: strand `i` is `points[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<u32>,
    /// One width per point, if the source had widths.
    widths: Option<Vec<f32>>,
    /// One colour per strand (linear RGB), if the source had colours.
    colors: Option<Vec<Vec3>>,
}

/// A groom resampled to the same number of segments per strand (see
/// [`Groom::resample`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Resampled {
    /// `strands × (segments + 1)` points, strand after strand, root first.
    pub points: Vec<Vec3>,
    /// One width per point (interpolated like the points), if the groom has widths.
    pub widths: Option<Vec<f32>>,
    /// Segments per strand.
    pub segments: u32,
    /// Strands kept (every strand that is not degenerate).
    pub strands: u32,
    /// Degenerate strands skipped: a single point, or all points equal.
    pub skipped: u32,
    /// Index in the groom of every kept strand, in order.
    pub source_strands: Vec<u32>,
    /// One colour per kept strand (linear RGB), if the groom has colours.
    pub colors: Option<Vec<Vec3>>,
}

impl Resampled {
    /// Component-wise minimum and maximum of all points (the origin for no points).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let first = self.points.first().copied().unwrap_or(Vec3::ZERO);
        self.points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }
}

/// Why a groom could not be built, loaded, resampled or transformed.
#[derive(Debug, thiserror::Error)]
pub enum GroomError {
    /// The `.hair` file could not be read.
    #[error(transparent)]
    Hair(#[from] HairFileError),
    /// The `.tfx` file could not be read.
    #[error(transparent)]
    Tfx(#[from] TfxFileError),
    /// The USD file could not be read (feature `usd`; boxed: it names the file, prim
    /// and attribute).
    #[cfg(feature = "usd")]
    #[error(transparent)]
    Usd(Box<crate::usd_file::UsdFileError>),
    /// [`Groom::load`] does not know the file's extension.
    #[error(
        "cannot tell the hair format of {}: {}; the supported extensions are .hair (Cem Yuksel), .tfx (AMD TressFX 4){}",
        path.display(),
        match extension { Some(e) => format!("the extension .{e} is not supported"), None => "it has no extension".to_owned() },
        if cfg!(feature = "usd") { " and .usda, .usdc, .usd, .usdz (USD BasisCurves)" } else { "; USD files need pelage-scene's feature usd" }
    )]
    UnknownExtension {
        /// The file.
        path: PathBuf,
        /// Its extension, if it has one.
        extension: Option<String>,
    },
    /// [`Groom::read`] was handed more bytes than a groom file may have.
    #[error(
        "{} has {bytes} bytes, more than the {max} a groom file may have",
        path.display()
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        bytes: u64,
        /// [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES).
        max: u64,
    },
    /// There are no strands.
    #[error("the groom has no strands; there is no hair to draw")]
    NoStrands,
    /// The per-strand colours are not one per strand.
    #[error("the groom has {len} colours for {strands} strands; give one colour per strand")]
    BadColors {
        /// The number of colours.
        len: usize,
        /// The number of strands.
        strands: usize,
    },
    /// A strand's colour is NaN, infinite or negative.
    #[error(
        "the colour of strand {strand} is {value}; every component must be finite and not negative"
    )]
    BadColor {
        /// Strand index.
        strand: usize,
        /// The value found.
        value: Vec3,
    },
    /// A strand has no points.
    #[error("strand {strand} has no points; every strand needs at least one")]
    EmptyStrand {
        /// Strand index.
        strand: usize,
    },
    /// A point is NaN or infinite.
    #[error(
        "point {point} of strand {strand} is not finite ({value}); every coordinate must be a finite number"
    )]
    NonFinitePoint {
        /// Strand index.
        strand: usize,
        /// Point index within the strand.
        point: usize,
        /// The value found.
        value: Vec3,
    },
    /// A width is negative, NaN, infinite or larger than [`MAX_EXTENT`](crate::MAX_EXTENT).
    #[error(
        "the {attribute} of point {point} of strand {strand} is {value}; it must be finite and in 0..={max:e}",
        max = crate::MAX_EXTENT
    )]
    BadWidth {
        /// Where the width came from: `"thickness"` (a `.hair` or `.tfx` file's
        /// thickness array), `"width"`, `"width after groom.fit and groom.scale"`.
        attribute: &'static str,
        /// Strand index.
        strand: usize,
        /// Point index within the strand.
        point: usize,
        /// The value found.
        value: f32,
    },
    /// A colour of a file's per-point colour array is NaN, infinite or negative.
    #[error(
        "the {attribute} of point {point} (strand {strand}) is {value}; every component must be finite and not negative"
    )]
    BadPointColor {
        /// The array: `"colour array"` (`.hair`), `"vertex_color"` (`.tfx`).
        attribute: &'static str,
        /// Point index in the file (counting every strand's points).
        point: usize,
        /// The strand it belongs to.
        strand: usize,
        /// The value found.
        value: Vec3,
    },
    /// A [`HairFile`]'s arrays do not agree (its public fields were edited).
    #[error(
        "the .hair data is inconsistent: {array} has {len} entries but the segment counts need {expected}"
    )]
    InconsistentHair {
        /// The array whose length is wrong.
        array: &'static str,
        /// Its length.
        len: usize,
        /// The length the segment counts need.
        expected: u64,
    },
    /// More points than 32-bit offsets can address.
    #[error(
        "the groom has {count} points, more than the {max} that 32-bit strand offsets can address; split it"
    )]
    TooManyPoints {
        /// The point count.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// The segment count asked of [`Groom::resample`] is out of range.
    #[error("cannot resample to {segments} segments per strand; choose 1 to {max}")]
    BadSegments {
        /// The count asked for.
        segments: u32,
        /// The limit ([`MAX_SEGMENTS`]).
        max: u32,
    },
    /// Every strand is degenerate, so resampling leaves nothing.
    #[error(
        "all {strands} strands are degenerate (a single point, or all points equal); there is nothing to resample"
    )]
    AllDegenerate {
        /// Number of strands.
        strands: usize,
    },
    /// A scale, size or translation is not usable.
    #[error("{what} is {value}; it must be a finite number{}", if *.positive { " greater than 0" } else { "" })]
    BadTransform {
        /// Which argument.
        what: &'static str,
        /// Its value (the first bad component of a vector).
        value: f32,
        /// Whether it must be positive.
        positive: bool,
    },
}

#[cfg(feature = "usd")]
impl From<crate::usd_file::UsdFileError> for GroomError {
    fn from(e: crate::usd_file::UsdFileError) -> Self {
        GroomError::Usd(Box::new(e))
    }
}

impl Groom {
    /// A groom from strands given as point lists (root first), without widths.
    ///
    /// Errors: no strands, a strand without points, a NaN or infinite
    /// point, more than `u32::MAX` points.
    pub fn from_strands(strands: &[Vec<Vec3>]) -> Result<Groom, GroomError> {
        let mut offsets = Vec::with_capacity(strands.len() + 1);
        offsets.push(0u32);
        let mut total: u64 = 0;
        for strand in strands {
            total += strand.len() as u64;
            offsets.push(u32::try_from(total).map_err(|_| too_many(total))?);
        }
        let points = strands.iter().flatten().copied().collect();
        Groom::from_parts(points, offsets, None, None, "width")
    }

    /// A groom from a `.hair` file: its strands as they are, its per-point
    /// thickness as widths when the file has a thickness array (`has_thickness`),
    /// and each strand's root colour as the strand's colour when it has a colour
    /// array (`has_colors`); a file without one gets no widths or colours (its
    /// default thickness and colour are not used).
    ///
    /// Errors: no strands, a strand without points (segment count 0 is a
    /// single point, which is allowed), arrays whose lengths disagree with
    /// the segment counts, a NaN or infinite point, a negative, non-finite or
    /// too large thickness, a negative or non-finite colour (any point's).
    pub fn from_hair(hair: &HairFile) -> Result<Groom, GroomError> {
        let expected: u64 = hair.segments.iter().map(|&s| u64::from(s) + 1).sum();
        if expected != hair.points.len() as u64 {
            return Err(GroomError::InconsistentHair {
                array: "points",
                len: hair.points.len(),
                expected,
            });
        }
        if hair.has_thickness && hair.thickness.len() != hair.points.len() {
            return Err(GroomError::InconsistentHair {
                array: "thickness",
                len: hair.thickness.len(),
                expected,
            });
        }
        let mut offsets = Vec::with_capacity(hair.segments.len() + 1);
        offsets.push(0u32);
        let mut total: u64 = 0;
        for &s in &hair.segments {
            total += u64::from(s) + 1;
            offsets.push(u32::try_from(total).map_err(|_| too_many(total))?);
        }
        let widths = hair.has_thickness.then(|| hair.thickness.clone());
        let colors = if hair.has_colors {
            if hair.colors.len() != hair.points.len() {
                return Err(GroomError::InconsistentHair {
                    array: "colors",
                    len: hair.colors.len(),
                    expected,
                });
            }
            check_point_colors("colour array", hair.colors.iter().copied(), &offsets)?;
            Some(root_colors(&offsets, |point| {
                hair.colors.get(point).copied()
            }))
        } else {
            None
        };
        Groom::from_parts(hair.points.clone(), offsets, widths, colors, "thickness")
    }

    /// A groom from a `.tfx` file: its strands' `xyz` (the inverse mass `w`
    /// is dropped), its per-strand thickness, if any, as the width of
    /// every point of the strand, and the RGB of each strand's root
    /// `vertex_color`, if any, as the strand's colour (alpha is not read).
    ///
    /// Errors: what [`TfxFile::check`] reports, a negative or too large thickness, a
    /// negative or non-finite colour, more than `u32::MAX` points.
    pub fn from_tfx(tfx: &TfxFile) -> Result<Groom, GroomError> {
        tfx.check()?;
        let vps = tfx.vertices_per_strand as usize;
        let count = tfx.positions.len() as u64;
        u32::try_from(count).map_err(|_| too_many(count))?;
        let offsets = (0..=tfx.strand_count())
            .map(|s| u32::try_from(s * vps).map_err(|_| too_many(count)))
            .collect::<Result<Vec<u32>, _>>()?;
        let points = tfx.positions.iter().map(|p| p.truncate()).collect();
        let widths = tfx.thickness.as_ref().map(|t| {
            t.iter()
                .flat_map(|&w| std::iter::repeat_n(w, vps))
                .collect()
        });
        let colors = match &tfx.vertex_color {
            Some(c) => {
                check_point_colors("vertex_color", c.iter().map(|c| c.truncate()), &offsets)?;
                Some(root_colors(&offsets, |point| {
                    c.get(point).map(|c| c.truncate())
                }))
            }
            None => None,
        };
        Groom::from_parts(points, offsets, widths, colors, "thickness")
    }

    /// A groom from its parts as the USD reader gathers them (one colour per strand).
    #[cfg(feature = "usd")]
    pub(crate) fn from_usd_parts(
        points: Vec<Vec3>,
        offsets: Vec<u32>,
        widths: Option<Vec<f32>>,
        colors: Option<Vec<Vec3>>,
    ) -> Result<Groom, GroomError> {
        Groom::from_parts(points, offsets, widths, colors, "width")
    }

    /// This groom with one colour per strand (linear RGB), or none.
    ///
    /// Errors: a colour count other than the strand count
    /// ([`GroomError::BadColors`]), a NaN, infinite or negative colour.
    pub fn with_colors(mut self, colors: Option<Vec<Vec3>>) -> Result<Groom, GroomError> {
        self.colors = colors;
        self.check_colors()?;
        Ok(self)
    }

    /// Loads a `.hair`, `.tfx` or (feature `usd`) `.usda`, `.usdc`, `.usd` or `.usdz`
    /// file, chosen by the extension (in any letter case).
    ///
    /// Errors: an unknown or missing extension
    /// ([`GroomError::UnknownExtension`], naming the supported ones), and
    /// whatever reading the file or [`Groom::from_hair`] /
    /// [`Groom::from_tfx`] / `usd_file::load` report.
    pub fn load(path: impl AsRef<Path>) -> Result<Groom, GroomError> {
        let path = path.as_ref();
        let extension = path
            .extension()
            .map(OsStr::to_string_lossy)
            .map(|e| e.to_ascii_lowercase());
        match extension.as_deref() {
            Some("hair") => Groom::from_hair(&HairFile::read_path(path)?),
            Some("tfx") => Groom::from_tfx(&TfxFile::load(path)?),
            #[cfg(feature = "usd")]
            Some("usda" | "usdc" | "usd" | "usdz") => crate::usd_file::load(path),
            _ => Err(GroomError::UnknownExtension {
                path: path.to_path_buf(),
                extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
            }),
        }
    }

    /// Parses a groom file held in memory (an engine's asset loader's bytes), its format
    /// chosen by `path`'s extension as [`Groom::load`] chooses it: `.hair`
    /// ([`HairFile::read`]), `.tfx` ([`TfxFile::read`]) or, with the feature `usd`,
    /// `.usda`, `.usdc`, `.usd`, `.usdz` (`usd_file::read`). `path` only names the file.
    ///
    /// Errors: an unknown or missing extension ([`GroomError::UnknownExtension`]), more
    /// than [`MAX_GROOM_FILE_BYTES`](crate::MAX_GROOM_FILE_BYTES)
    /// ([`GroomError::TooLarge`]), and whatever parsing the bytes reports.
    pub fn read(bytes: Vec<u8>, path: &Path) -> Result<Groom, GroomError> {
        let len = bytes.len() as u64;
        if len > crate::MAX_GROOM_FILE_BYTES {
            return Err(GroomError::TooLarge {
                path: path.to_path_buf(),
                bytes: len,
                max: crate::MAX_GROOM_FILE_BYTES,
            });
        }
        let extension = path
            .extension()
            .map(OsStr::to_string_lossy)
            .map(|e| e.to_ascii_lowercase());
        match extension.as_deref() {
            Some("hair") => Groom::from_hair(&HairFile::read(&bytes)?),
            Some("tfx") => Groom::from_tfx(&TfxFile::read(&bytes)?),
            #[cfg(feature = "usd")]
            Some("usda" | "usdc" | "usd" | "usdz") => crate::usd_file::read(bytes, path),
            _ => Err(GroomError::UnknownExtension {
                path: path.to_path_buf(),
                extension: path.extension().map(|e| e.to_string_lossy().into_owned()),
            }),
        }
    }

    /// Checks the invariants and builds the groom.
    fn from_parts(
        points: Vec<Vec3>,
        offsets: Vec<u32>,
        widths: Option<Vec<f32>>,
        colors: Option<Vec<Vec3>>,
        width_attribute: &'static str,
    ) -> Result<Groom, GroomError> {
        if offsets.len() < 2 {
            return Err(GroomError::NoStrands);
        }
        let count = points.len() as u64;
        u32::try_from(count).map_err(|_| too_many(count))?;
        let groom = Groom {
            points,
            offsets,
            widths,
            colors,
        };
        groom.check_colors()?;
        for (strand, range) in groom.ranges().enumerate() {
            if range.is_empty() {
                return Err(GroomError::EmptyStrand { strand });
            }
            let points = groom.points.get(range.clone()).unwrap_or(&[]);
            if let Some((point, &value)) = points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
                return Err(GroomError::NonFinitePoint {
                    strand,
                    point,
                    value,
                });
            }
            if let Some(widths) = &groom.widths {
                let widths = widths.get(range).unwrap_or(&[]);
                if let Some((point, &value)) = widths
                    .iter()
                    .enumerate()
                    .find(|(_, w)| !(w.is_finite() && (0.0..=crate::MAX_EXTENT).contains(*w)))
                {
                    return Err(GroomError::BadWidth {
                        attribute: width_attribute,
                        strand,
                        point,
                        value,
                    });
                }
            }
        }
        Ok(groom)
    }

    /// Refuses colours that are not one finite colour per strand.
    fn check_colors(&self) -> Result<(), GroomError> {
        let Some(colors) = &self.colors else {
            return Ok(());
        };
        if colors.len() != self.strand_count() {
            return Err(GroomError::BadColors {
                len: colors.len(),
                strands: self.strand_count(),
            });
        }
        if let Some((strand, &value)) = colors
            .iter()
            .enumerate()
            .find(|(_, c)| !(c.is_finite() && c.min_element() >= 0.0))
        {
            return Err(GroomError::BadColor { strand, value });
        }
        Ok(())
    }

    /// Point index range of every strand.
    fn ranges(&self) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        self.offsets
            .windows(2)
            .map(|w| w[0] as usize..w[1] as usize)
    }

    /// Number of strands (at least 1).
    pub fn strand_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of points over all strands.
    pub fn point_count(&self) -> usize {
        self.points.len()
    }

    /// Every point, strand after strand, root first.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// `strand_count + 1` offsets into [`Groom::points`]: strand `i` is
    /// `points[offsets[i]..offsets[i + 1]]`.
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// One width per point, if the source had widths.
    pub fn widths(&self) -> Option<&[f32]> {
        self.widths.as_deref()
    }

    /// One colour per strand (linear RGB), if the source had colours (a USD file's
    /// `primvars:displayColor`).
    pub fn colors(&self) -> Option<&[Vec3]> {
        self.colors.as_deref()
    }

    /// The points of strand `index`, root first (`None` past the last strand).
    pub fn strand(&self, index: usize) -> Option<&[Vec3]> {
        let start = *self.offsets.get(index)? as usize;
        let end = *self.offsets.get(index + 1)? as usize;
        self.points.get(start..end)
    }

    /// The points of every strand, root first.
    pub fn strands(&self) -> impl Iterator<Item = &[Vec3]> + '_ {
        self.ranges().map(|r| self.points.get(r).unwrap_or(&[]))
    }

    /// Component-wise minimum and maximum of all points.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let first = self.points.first().copied().unwrap_or(Vec3::ZERO);
        self.points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// Resamples every strand to `segments` segments (`segments + 1` points)
    /// spaced evenly by arc length along the strand's polyline (linear
    /// interpolation between its points, in `f64`). The root and tip are
    /// kept exactly; widths are interpolated the same way. Degenerate
    /// strands (a single point, or all points equal) are skipped and
    /// counted in [`Resampled::skipped`].
    ///
    /// Errors: `segments` outside `1..=MAX_SEGMENTS`, every strand
    /// degenerate, more than `u32::MAX` output points.
    pub fn resample(&self, segments: u32) -> Result<Resampled, GroomError> {
        if segments == 0 || segments > MAX_SEGMENTS {
            return Err(GroomError::BadSegments {
                segments,
                max: MAX_SEGMENTS,
            });
        }
        let per_strand = segments as usize + 1;
        let mut cumulative = Vec::new();
        let mut lengths = Vec::with_capacity(self.strand_count());
        for strand in self.strands() {
            arc_lengths(strand, &mut cumulative);
            lengths.push(cumulative.last().copied().unwrap_or(0.0));
        }
        let kept = lengths.iter().filter(|&&l| l > 0.0).count();
        if kept == 0 {
            return Err(GroomError::AllDegenerate {
                strands: self.strand_count(),
            });
        }
        let out_count = (kept as u64) * per_strand as u64;
        u32::try_from(out_count).map_err(|_| too_many(out_count))?;
        let mut points = Vec::with_capacity(kept * per_strand);
        let mut widths = self
            .widths
            .as_ref()
            .map(|_| Vec::with_capacity(kept * per_strand));
        let mut source_strands = Vec::with_capacity(kept);
        for (index, (range, &length)) in self.ranges().zip(&lengths).enumerate() {
            if length <= 0.0 {
                continue;
            }
            let strand = self.points.get(range.clone()).unwrap_or(&[]);
            let strand_widths = self.widths.as_ref().and_then(|w| w.get(range));
            arc_lengths(strand, &mut cumulative);
            resample_strand(
                strand,
                strand_widths,
                &cumulative,
                segments,
                &mut points,
                widths.as_mut(),
            );
            source_strands.push(index as u32);
        }
        let colors = self.colors.as_ref().map(|c| {
            source_strands
                .iter()
                .map(|&s| c.get(s as usize).copied().unwrap_or(Vec3::ONE))
                .collect()
        });
        Ok(Resampled {
            points,
            widths,
            segments,
            strands: kept as u32,
            skipped: (self.strand_count() - kept) as u32,
            source_strands,
            colors,
        })
    }

    /// The groom scaled by `scale` about the origin, then moved by
    /// `translation` (`p * scale + translation`, computed in `f64`); widths
    /// are scaled too.
    ///
    /// Errors: a scale that is not finite and positive, a translation that
    /// is not finite, a result that overflows `f32`.
    pub fn transformed(&self, scale: f32, translation: Vec3) -> Result<Groom, GroomError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(GroomError::BadTransform {
                what: "the scale",
                value: scale,
                positive: true,
            });
        }
        if let Some(&value) = translation.to_array().iter().find(|v| !v.is_finite()) {
            return Err(GroomError::BadTransform {
                what: "a translation component",
                value,
                positive: false,
            });
        }
        let s = f64::from(scale);
        let t = translation.as_dvec3();
        let points = self
            .points
            .iter()
            .map(|p| (p.as_dvec3() * s + t).as_vec3())
            .collect();
        let widths = self
            .widths
            .as_ref()
            .map(|w| w.iter().map(|&w| (f64::from(w) * s) as f32).collect());
        Groom::from_parts(
            points,
            self.offsets.clone(),
            widths,
            self.colors.clone(),
            "width after groom.fit and groom.scale",
        )
    }

    /// The groom centred on the origin (the centre of its bounding box goes
    /// to 0) and scaled so that the largest side of its bounding box is
    /// `target_size`; `.hair` and `.tfx` files come in arbitrary units. A
    /// groom whose bounding box is a single point is only centred.
    ///
    /// Errors: a `target_size` that is not finite and positive.
    pub fn normalized(&self, target_size: f32) -> Result<Groom, GroomError> {
        if !(target_size.is_finite() && target_size > 0.0) {
            return Err(GroomError::BadTransform {
                what: "the target size",
                value: target_size,
                positive: true,
            });
        }
        let (lo, hi) = self.bounds();
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let centre = (lo + hi) * 0.5;
        let extent = (hi - lo).max_element();
        let scale = if extent > 0.0 {
            f64::from(target_size) / extent
        } else {
            1.0
        };
        let points = self
            .points
            .iter()
            .map(|p| ((p.as_dvec3() - centre) * scale).as_vec3())
            .collect();
        let widths = self
            .widths
            .as_ref()
            .map(|w| w.iter().map(|&w| (f64::from(w) * scale) as f32).collect());
        Groom::from_parts(
            points,
            self.offsets.clone(),
            widths,
            self.colors.clone(),
            "width after groom.fit and groom.scale",
        )
    }
}

/// A groom file as a scene describes it: which file, how it is placed, and how many
/// segments each strand is resampled to (the `[groom]` table of a scene file).
///
/// The file's points are first centred and scaled so that the longest side of their
/// bounding box is `fit` (when given; `.hair` and `.tfx` files come in any units), then
/// scaled by `scale` and moved by `translation`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroomSource {
    /// The `.hair` or `.tfx` file; relative to the scene file's folder in a scene file.
    pub path: PathBuf,
    /// Segments per strand after resampling by arc length (1 to [`MAX_SEGMENTS`]; the
    /// default 16). Every strand gets the same count.
    #[serde(default = "GroomSource::default_segments")]
    pub segments: u32,
    /// Centre the groom on the origin and scale it so that the longest side of its
    /// bounding box is this many scene units (> 0); leave out to keep the file's units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<f32>,
    /// Scale applied after `fit` (> 0; the default 1).
    #[serde(default = "GroomSource::default_scale")]
    pub scale: f32,
    /// Translation applied last, scene units (the default none).
    #[serde(default)]
    pub translation: Vec3,
    /// Take the file's strands as guides and interpolate this many render strands
    /// rooted on the mesh from them (`guides = { strands = 20000, clump = 0.3 }`; see
    /// [`GuideParams`](crate::GuideParams)); left out, the file's strands are drawn.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guides: Option<crate::GuideParams>,
}

impl GroomSource {
    fn default_segments() -> u32 {
        16
    }

    fn default_scale() -> f32 {
        1.0
    }

    /// The file at `path` with every other setting at its default.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            segments: Self::default_segments(),
            fit: None,
            scale: Self::default_scale(),
            translation: Vec3::ZERO,
            guides: None,
        }
    }

    /// Checks the settings (not the file); the error names the first bad one.
    pub fn validate(&self) -> Result<(), crate::ParamError> {
        if self.segments == 0 || self.segments > MAX_SEGMENTS {
            return Err(crate::ParamError::new(
                "groom.segments",
                self.segments,
                &format!("must be in 1..={MAX_SEGMENTS}"),
            ));
        }
        if let Some(fit) = self.fit {
            crate::params::positive("groom.fit", fit)?;
        }
        crate::params::positive("groom.scale", self.scale)?;
        for (axis, v) in ["x", "y", "z"].iter().zip(self.translation.to_array()) {
            crate::params::finite(&format!("groom.translation.{axis}"), v)?;
        }
        if let Some(guides) = &self.guides {
            guides.validate()?;
        }
        Ok(())
    }

    /// Reads the file, places it and resamples it to `segments` segments per strand.
    ///
    /// Errors: what [`Groom::load`], [`Groom::normalized`], [`Groom::transformed`] and
    /// [`Groom::resample`] report (a missing or broken file names its path).
    pub fn load(&self) -> Result<Resampled, GroomError> {
        let mut groom = Groom::load(&self.path)?;
        if let Some(fit) = self.fit {
            groom = groom.normalized(fit)?;
        }
        if self.scale != 1.0 || self.translation != Vec3::ZERO {
            groom = groom.transformed(self.scale, self.translation)?;
        }
        groom.resample(self.segments)
    }
}

/// Refuses a NaN, infinite or negative colour of a file's per-point colour array
/// (`colors`, one per point of the strands `offsets` delimit).
fn check_point_colors(
    attribute: &'static str,
    colors: impl Iterator<Item = Vec3>,
    offsets: &[u32],
) -> Result<(), GroomError> {
    for (point, value) in colors.enumerate() {
        if !(value.is_finite() && value.min_element() >= 0.0) {
            // The strand whose range holds the point: the last offset at or before it.
            let strand = offsets
                .partition_point(|&o| o as usize <= point)
                .saturating_sub(1);
            return Err(GroomError::BadPointColor {
                attribute,
                point,
                strand,
                value,
            });
        }
    }
    Ok(())
}

/// The root point's colour of every strand `offsets` delimit (white where `color` has
/// none, which the callers' length checks rule out).
fn root_colors(offsets: &[u32], color: impl Fn(usize) -> Option<Vec3>) -> Vec<Vec3> {
    offsets
        .windows(2)
        .map(|w| color(w[0] as usize).unwrap_or(Vec3::ONE))
        .collect()
}

pub(crate) fn too_many(count: u64) -> GroomError {
    GroomError::TooManyPoints {
        count,
        max: u64::from(u32::MAX),
    }
}

/// Fills `out` with the cumulative arc length at every point of `strand`
/// (`out[0] = 0`), in `f64` so that finite `f32` points never overflow.
fn arc_lengths(strand: &[Vec3], out: &mut Vec<f64>) {
    out.clear();
    let mut total = 0.0;
    let mut previous: Option<DVec3> = None;
    for p in strand {
        let p = p.as_dvec3();
        if let Some(q) = previous {
            total += p.distance(q);
        }
        out.push(total);
        previous = Some(p);
    }
}

/// Appends `segments + 1` points (and widths) spaced evenly by arc length
/// along `strand`, whose cumulative lengths are `cumulative` (same length,
/// last entry > 0).
fn resample_strand(
    strand: &[Vec3],
    strand_widths: Option<&[f32]>,
    cumulative: &[f64],
    segments: u32,
    points: &mut Vec<Vec3>,
    mut widths: Option<&mut Vec<f32>>,
) {
    let (Some(&first), Some(&last)) = (strand.first(), strand.last()) else {
        return;
    };
    let total = cumulative.last().copied().unwrap_or(0.0);
    let width_at = |i: usize| strand_widths.and_then(|w| w.get(i)).copied().unwrap_or(0.0);
    let mut j = 0usize; // current segment: strand[j] .. strand[j + 1]
    let last_segment = strand.len().saturating_sub(2);
    for k in 0..=segments {
        let (p, w) = if k == 0 {
            (first, width_at(0))
        } else if k == segments {
            (last, width_at(strand.len() - 1))
        } else {
            let s = total * f64::from(k) / f64::from(segments);
            while j < last_segment && cumulative.get(j + 1).is_some_and(|&c| c < s) {
                j += 1;
            }
            let c0 = cumulative.get(j).copied().unwrap_or(0.0);
            let c1 = cumulative.get(j + 1).copied().unwrap_or(c0);
            let t = if c1 > c0 {
                ((s - c0) / (c1 - c0)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let a = strand.get(j).copied().unwrap_or(first).as_dvec3();
            let b = strand.get(j + 1).copied().unwrap_or(last).as_dvec3();
            let wa = f64::from(width_at(j));
            let wb = f64::from(width_at(j + 1));
            ((a + (b - a) * t).as_vec3(), (wa + (wb - wa) * t) as f32)
        };
        points.push(p);
        if let Some(widths) = widths.as_deref_mut() {
            widths.push(w);
        }
    }
}
