//! Texture maps over a mesh's UVs ([`Mesh::uvs`](crate::Mesh::uvs)): PNG images that
//! the root sampler reads at each root (regions, density, length, colour; see
//! [`RootTextures`](crate::RootTextures)).
//!
//! The roots are placed on the CPU, so a map is only ever sampled on the CPU: no GPU
//! texture is made. `(u, v) = (0, 0)` is the image's bottom-left corner and `(1, 1)` its
//! top-right (OBJ's convention; the image's first row is its top); coordinates outside
//! [0, 1] clamp to the edge. [`MapImage::nearest`] reads the texel that holds `(u, v)`
//! (for region indices, which must not be blended), [`MapImage::bilinear`] blends the
//! four texels around it, texel centres at `((x + ½) / width, 1 − (y + ½) / height)`.

#[cfg(feature = "maps")]
use std::path::Path;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// The most bytes a texture map file may have: 64 MiB.
pub const MAX_MAP_FILE_BYTES: u64 = 64 << 20;

/// The widest and tallest texture map accepted, texels.
pub const MAX_MAP_SIZE: u32 = 8192;

/// Why a texture map could not be read.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// The file could not be read (or is larger than [`MAX_MAP_FILE_BYTES`]).
    #[error("could not read texture map {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is not an image `image` can decode (pelage reads PNG), or it is larger
    /// than [`MAX_MAP_SIZE`] on a side.
    #[error(
        "could not decode texture map {}: {message} (a PNG of at most {MAX_MAP_SIZE} x {MAX_MAP_SIZE} texels is expected)",
        path.display()
    )]
    Decode {
        /// The file.
        path: PathBuf,
        /// The decoder's report.
        message: String,
    },
}

/// The texels of a [`MapImage`], at the file's precision.
#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// 8 bits per channel (and files of 1, 2 or 4, expanded).
    Eight(Vec<[u8; 4]>),
    /// 16 bits per channel.
    Sixteen(Vec<[u16; 4]>),
}

/// An RGBA image held for sampling at the file's bit depth: row 0 at the top.
///
/// Every PNG bit depth and colour type is read: grey of 1, 2, 4, 8 or 16 bits, grey with
/// alpha, RGB and RGBA of 8 or 16 bits, and palette images of 1 to 8 bits (each texel
/// the colour of its palette entry). A texel has two readings:
///
/// - its **native** integer values ([`MapImage::texel`], [`MapImage::nearest`],
///   [`MapImage::region`]): 0 to `2^bits - 1` for grey of `bits` bits, 0 to 255 for 8-bit
///   and palette images, 0 to 65535 for 16-bit ones. Region maps read these: a 16-bit
///   map's region 1 is the value 1, a 1-bit map's regions are 0 and 1.
/// - its **unit** values in [0, 1] ([`MapImage::unit`]): the native value over its
///   largest, so that black is 0 and white is 1 at every bit depth (an 8-bit 255, a
///   16-bit 65535 and a 1-bit 1 are all 1). Density, length and colour maps read these.
#[derive(Clone, Debug, PartialEq)]
pub struct MapImage {
    width: u32,
    height: u32,
    texels: Texels,
    /// Bits per channel of the native values: 1, 2, 4, 8 or 16.
    bits: u8,
}

impl MapImage {
    /// An 8-bit image of `width` x `height` texels (row 0 at the top). `None` when a
    /// side is 0 or above [`MAX_MAP_SIZE`], or `texels` does not hold `width * height`
    /// texels.
    pub fn new(width: u32, height: u32, texels: Vec<[u8; 4]>) -> Option<Self> {
        Self::checked(width, texels.len(), height).then_some(Self {
            width,
            height,
            texels: Texels::Eight(texels),
            bits: 8,
        })
    }

    /// A 16-bit image, as [`MapImage::new`].
    pub fn new16(width: u32, height: u32, texels: Vec<[u16; 4]>) -> Option<Self> {
        Self::checked(width, texels.len(), height).then_some(Self {
            width,
            height,
            texels: Texels::Sixteen(texels),
            bits: 16,
        })
    }

    fn checked(width: u32, len: usize, height: u32) -> bool {
        (1..=MAX_MAP_SIZE).contains(&width)
            && (1..=MAX_MAP_SIZE).contains(&height)
            && len == width as usize * height as usize
    }

    /// Decodes a PNG file's bytes (any bit depth and colour type), at most
    /// [`MAX_MAP_SIZE`] texels on a side. `path` only names the file in errors.
    /// (Feature `maps`.)
    #[cfg(feature = "maps")]
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Self, MapError> {
        let decode_error = |message: String| MapError::Decode {
            path: path.to_path_buf(),
            message,
        };
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| decode_error(e.to_string()))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_MAP_SIZE);
        limits.max_image_height = Some(MAX_MAP_SIZE);
        reader.limits(limits);
        let decoded = reader.decode().map_err(|e| decode_error(e.to_string()))?;
        let (width, height) = (decoded.width(), decoded.height());
        let wide = matches!(
            decoded,
            image::DynamicImage::ImageLuma16(_)
                | image::DynamicImage::ImageLumaA16(_)
                | image::DynamicImage::ImageRgb16(_)
                | image::DynamicImage::ImageRgba16(_)
        );
        let image = if wide {
            let texels = decoded.into_rgba16().pixels().map(|p| p.0).collect();
            Self::new16(width, height, texels)
        } else {
            let texels = decoded.into_rgba8().pixels().map(|p| p.0).collect();
            // The decoder expands grey of 1, 2 or 4 bits to 8 (times 255, 85 or 17):
            // keep the file's depth so native values are the file's.
            let bits = match png_header(bytes) {
                Some((depth @ (1 | 2 | 4), GREY)) => depth,
                _ => 8,
            };
            Self::new(width, height, texels).map(|m| Self { bits, ..m })
        };
        image.ok_or_else(|| decode_error(format!("{width} x {height} texels")))
    }

    /// Reads and decodes the file at `path` (at most [`MAX_MAP_FILE_BYTES`]).
    /// (Feature `maps`.)
    #[cfg(feature = "maps")]
    pub fn load(path: &Path) -> Result<Self, MapError> {
        let bytes = crate::limits::read_capped(path, MAX_MAP_FILE_BYTES, "texture maps").map_err(
            |source| MapError::Io {
                path: path.to_path_buf(),
                source,
            },
        )?;
        Self::decode(&bytes, path)
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bits per channel of the native values: 1, 2, 4 (grey files of that depth), 8
    /// (8-bit and palette files) or 16.
    pub fn bits(&self) -> u8 {
        self.bits
    }

    /// The largest native value, `2^bits - 1`: what reads as 1.
    pub fn max_value(&self) -> u16 {
        ((1u32 << self.bits) - 1) as u16
    }

    /// Number of texels.
    fn len(&self) -> usize {
        match &self.texels {
            Texels::Eight(t) => t.len(),
            Texels::Sixteen(t) => t.len(),
        }
    }

    /// The native values of texel number `i` (row 0 first), or zeros past the end.
    fn native(&self, i: usize) -> [u16; 4] {
        match &self.texels {
            Texels::Eight(t) => {
                // 1-, 2- and 4-bit grey was expanded by 255 / max.
                let div = 255 / self.max_value().max(1);
                t.get(i)
                    .map_or([0; 4], |t| t.map(|c| u16::from(c) / div.max(1)))
            }
            Texels::Sixteen(t) => t.get(i).copied().unwrap_or_default(),
        }
    }

    /// The red channel's native value of every texel, row 0 (the top) first: a region
    /// map's regions.
    pub fn reds(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.len()).map(|i| u32::from(self.native(i)[0]))
    }

    /// Native values of texel `(x, y)`, both clamped into the image.
    pub fn texel(&self, x: i64, y: i64) -> [u16; 4] {
        let x = x.clamp(0, i64::from(self.width) - 1) as usize;
        let y = y.clamp(0, i64::from(self.height) - 1) as usize;
        self.native(y * self.width as usize + x)
    }

    /// Unit values (native over [`MapImage::max_value`], in [0, 1]) of texel `(x, y)`,
    /// both clamped into the image.
    pub fn unit(&self, x: i64, y: i64) -> [f32; 4] {
        let max = f32::from(self.max_value());
        self.texel(x, y).map(|c| f32::from(c) / max)
    }

    /// `uv` in texel units, the image's top-left corner at (0, 0) (non-finite reads as 0).
    fn texel_space(&self, uv: Vec2) -> Vec2 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        Vec2::new(uv.x * self.width as f32, (1.0 - uv.y) * self.height as f32)
    }

    /// Native values of the texel holding `uv` (nearest lookup, clamped to the edge).
    pub fn nearest(&self, uv: Vec2) -> [u16; 4] {
        let t = self.texel_space(uv).floor();
        self.texel(t.x as i64, t.y as i64)
    }

    /// The region at `uv`: the red channel's native value of the texel holding it.
    pub fn region(&self, uv: Vec2) -> u32 {
        u32::from(self.nearest(uv)[0])
    }

    /// The bilinear blend at `uv` of the four texels around it, each read through
    /// `decode` from its unit values (the red channel for a scalar map, sRGB to linear
    /// for colour).
    pub fn bilinear(&self, uv: Vec2, decode: impl Fn([f32; 4]) -> Vec3) -> Vec3 {
        let t = self.texel_space(uv) - Vec2::splat(0.5);
        let base = t.floor();
        let f = t - base;
        let (x, y) = (base.x as i64, base.y as i64);
        let row = |y: i64| decode(self.unit(x, y)).lerp(decode(self.unit(x + 1, y)), f.x);
        row(y).lerp(row(y + 1), f.y)
    }

    /// The red channel's unit value at `uv`, blended bilinearly (a scalar map's value,
    /// in [0, 1]).
    pub fn scalar(&self, uv: Vec2) -> f32 {
        self.bilinear(uv, |t| Vec3::splat(t[0])).x
    }

    /// The linear RGB colour at `uv`: each texel's sRGB colour made linear, then blended
    /// bilinearly.
    pub fn color(&self, uv: Vec2) -> Vec3 {
        self.bilinear(uv, |t| {
            Vec3::new(
                srgb_unit_to_linear(t[0]),
                srgb_unit_to_linear(t[1]),
                srgb_unit_to_linear(t[2]),
            )
        })
    }
}

/// PNG colour type 0: grey.
#[cfg(feature = "maps")]
const GREY: u8 = 0;

/// The bit depth and colour type of a PNG's header (`IHDR`, which must come first), or
/// `None` for bytes that do not start as a PNG.
#[cfg(feature = "maps")]
fn png_header(bytes: &[u8]) -> Option<(u8, u8)> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    let header = bytes.get(..26)?;
    (header.starts_with(SIGNATURE) && &header[12..16] == b"IHDR").then(|| (header[24], header[25]))
}

/// The sRGB transfer function inverted: an 8-bit sRGB channel as linear [0, 1].
pub fn srgb_to_linear(c: u8) -> f32 {
    srgb_unit_to_linear(f32::from(c) / 255.0)
}

/// The sRGB transfer function inverted: an sRGB value in [0, 1] as linear [0, 1].
pub fn srgb_unit_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A texture map named by its path in a scene file (written as a plain string), and
/// the image once [`TextureMap::load`] has read it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "PathBuf", into = "PathBuf")]
pub struct TextureMap {
    /// The PNG file (a scene file's relative path is made relative to its folder).
    pub path: PathBuf,
    /// The decoded image; `None` until loaded (root sampling refuses an unloaded map).
    pub image: Option<Arc<MapImage>>,
}

impl From<PathBuf> for TextureMap {
    fn from(path: PathBuf) -> Self {
        Self { path, image: None }
    }
}

impl From<TextureMap> for PathBuf {
    fn from(map: TextureMap) -> Self {
        map.path
    }
}

impl TextureMap {
    /// A map already in memory; `path` only names it in messages.
    pub fn from_image(path: impl Into<PathBuf>, image: MapImage) -> Self {
        Self {
            path: path.into(),
            image: Some(Arc::new(image)),
        }
    }

    /// Reads the image at [`TextureMap::path`] (again, if it was loaded). (Feature
    /// `maps`.)
    #[cfg(feature = "maps")]
    pub fn load(&mut self) -> Result<(), MapError> {
        self.image = Some(Arc::new(MapImage::load(&self.path)?));
        Ok(())
    }

    /// The image, or an error naming the key `name` when it was never loaded.
    pub fn loaded(&self, name: &str) -> Result<&MapImage, crate::ParamError> {
        self.image.as_deref().ok_or_else(|| {
            crate::ParamError::new(
                name,
                &self.path,
                "the texture map was not loaded (SceneFile::load loads it; otherwise call TextureMap::load)",
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient() -> MapImage {
        // 2 x 2: top row red 0 and 255, bottom row 100 and 200.
        MapImage::new(
            2,
            2,
            vec![
                [0, 0, 0, 255],
                [255, 0, 0, 255],
                [100, 0, 0, 255],
                [200, 0, 0, 255],
            ],
        )
        .unwrap()
    }

    #[test]
    fn nearest_reads_the_texel_holding_uv_with_v_up() {
        let m = gradient();
        assert_eq!(m.nearest(Vec2::new(0.25, 0.75))[0], 0);
        assert_eq!(m.nearest(Vec2::new(0.75, 0.75))[0], 255);
        assert_eq!(m.nearest(Vec2::new(0.25, 0.25))[0], 100);
        assert_eq!(m.nearest(Vec2::new(0.75, 0.25))[0], 200);
        // Clamped outside [0, 1], and at exactly 1.
        assert_eq!(m.nearest(Vec2::new(1.0, 0.0))[0], 200);
        assert_eq!(m.nearest(Vec2::new(-3.0, 7.0))[0], 0);
        assert_eq!(m.nearest(Vec2::NAN)[0], 100);
    }

    #[test]
    fn bilinear_is_exact_at_texel_centres_and_blends_between() {
        let m = gradient();
        assert_eq!(m.scalar(Vec2::new(0.25, 0.75)), 0.0);
        assert_eq!(m.scalar(Vec2::new(0.75, 0.25)), 200.0 / 255.0);
        let centre = m.scalar(Vec2::splat(0.5));
        assert!((centre - (0.0 + 255.0 + 100.0 + 200.0) / 4.0 / 255.0).abs() < 1e-6);
        // Halfway along the top row.
        let top = m.scalar(Vec2::new(0.5, 0.75));
        assert!((top - 0.5).abs() < 1e-6, "{top}");
    }

    #[test]
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        assert!((srgb_to_linear(188) - 0.5029).abs() < 1e-3);
    }

    #[test]
    #[cfg(feature = "maps")]
    fn bad_files_are_errors_naming_the_file() {
        let e = MapImage::decode(b"not a png", Path::new("x.png")).unwrap_err();
        assert!(e.to_string().contains("x.png"), "{e}");
        let e = MapImage::load(Path::new("/no/such/map.png")).unwrap_err();
        assert!(matches!(e, MapError::Io { .. }), "{e}");
        assert!(MapImage::new(0, 1, vec![]).is_none());
        assert!(MapImage::new(2, 2, vec![[0; 4]; 3]).is_none());
        assert!(
            MapImage::new(MAX_MAP_SIZE + 1, 1, vec![[0; 4]; MAX_MAP_SIZE as usize + 1]).is_none()
        );
    }

    #[test]
    #[cfg(feature = "maps")]
    fn an_oversized_png_is_refused() {
        let mut bytes = Vec::new();
        image::RgbaImage::new(MAX_MAP_SIZE + 1, 1)
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .unwrap();
        let e = MapImage::decode(&bytes, Path::new("big.png")).unwrap_err();
        assert!(matches!(e, MapError::Decode { .. }), "{e}");
    }
}
