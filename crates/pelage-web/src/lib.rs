//! pelage in a web page: the creature of [`pelage::scene::Scene::default`] in wind, drawn on
//! WebGPU into a canvas (`web/index.html`), with controls for the wind, the strand count
//! and the transparency method, and the GPU time per pass where the browser offers
//! timestamp queries; or any `.hair` or `.tfx` groom the user drops on the page, picks
//! or names in the URL (`?groom=URL`), drawn alone ([`groom_scene`]) with its strand
//! count, so a groom can be viewed and timed in a browser.
//!
//! Built for `wasm32-unknown-unknown` this crate exports `Demo` to JavaScript
//! (through wasm-bindgen). On every target it exports the scene the page draws
//! ([`scene`]), so the native reference frame of the browser test
//! (`examples/browser_compare.rs`, run by `.ci/browser-test`) is the same scene by
//! construction.
//!
//! Everything runs under WebGPU's default limits and without optional features beyond
//! `timestamp-query`: the transparency methods that need more (the k-buffer and random
//! subsets declare 64-bit atomics) refuse with pelage's typed
//! [`ShadeError::Unsupported`](pelage::shade::ShadeError::Unsupported), and the page
//! offers only those [`pelage::shade::supported_methods`] names.

use std::path::Path;

use pelage::scene::Scene;
use pelage::scene::{Groom, GroomError, Mesh, Named, Resampled, Transparency};

#[cfg(target_arch = "wasm32")]
mod web;
#[cfg(target_arch = "wasm32")]
pub use web::Demo;

/// The transparency methods by [`Transparency::name`], in the order the page lists them:
/// the table every surface reads ([`pelage::scene::Named::NAMES`]).
pub fn methods() -> impl Iterator<Item = &'static str> {
    Transparency::NAMES.iter().map(|m| m.name)
}

/// The most strands the page asks for (its slider's end).
pub const MAX_STRANDS: u32 = 200_000;

/// The largest wind factor the page offers (times the default wind's forces).
pub const MAX_WIND: f32 = 4.0;

/// The longest side of a dropped groom's bounding box once placed, scene units: the
/// default camera frames the creature, about this size, at the origin.
pub const GROOM_FIT: f32 = 1.6;

/// Segments per strand a dropped groom is resampled to (as a scene file's `[groom]`
/// default).
pub const GROOM_SEGMENTS: u32 = 16;

/// The strand width of a dropped groom whose file gives none, scene units (the long
/// hair scene's, `scenes/long_hair.toml`, for a groom fitted to about the same size).
pub const GROOM_WIDTH: f32 = 0.003;

/// What the page's controls set.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Strands grown on the creature ([`pelage::scene::HairParams`]' `roots.count`).
    pub strands: u32,
    /// The wind's forces (strength and turbulence) relative to the default scene's.
    pub wind: f32,
    /// The transparency method, by [`Transparency::name`].
    pub method: String,
}

impl Default for Settings {
    /// The default scene's strands, wind and transparency method (the strand
    /// rasterizer, which needs no optional feature).
    fn default() -> Self {
        Self {
            strands: Scene::default().hair.roots.count,
            wind: 1.0,
            method: Scene::default().shade.transparency.name().into(),
        }
    }
}

/// Why the demo cannot draw.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// A transparency method name pelage does not know.
    #[error("unknown transparency method '{0}'; the known ones: {list}", list = Transparency::name_list())]
    UnknownMethod(String),
    /// A control's value outside what the page offers.
    #[error("{what} = {value} is out of range: {range}")]
    OutOfRange {
        /// The control.
        what: &'static str,
        /// The value asked for.
        value: f64,
        /// The accepted range.
        range: String,
    },
    /// The groom file could not be read, placed or resampled.
    #[error("{name}: {source}")]
    Groom {
        /// The file's name, as the page was given it.
        name: String,
        /// Why.
        source: GroomError,
    },
    /// pelage refused or failed (a method this adapter cannot run among them:
    /// [`pelage::shade::ShadeError::Unsupported`]).
    #[error(transparent)]
    Pelage(#[from] pelage::Error),
    /// The browser's WebGPU refused (no adapter, the canvas, a lost device) or raised
    /// an error.
    #[error("{0}")]
    Web(String),
}

/// The transparency method `name` ([`Transparency::name`]) with the defaults the
/// command line uses.
pub fn transparency(name: &str) -> Result<Transparency, DemoError> {
    Transparency::by_name(name).ok_or_else(|| DemoError::UnknownMethod(name.into()))
}

/// The scene the page draws: [`Scene::default`] (the creature, its fur, one light,
/// voxel shadows, the default camera) with `settings`' strand count, wind and method.
pub fn scene(settings: &Settings) -> Result<Scene, DemoError> {
    if !(1..=MAX_STRANDS).contains(&settings.strands) {
        return Err(DemoError::OutOfRange {
            what: "strands",
            value: f64::from(settings.strands),
            range: format!("1 to {MAX_STRANDS}"),
        });
    }
    if !(0.0..=MAX_WIND).contains(&settings.wind) {
        return Err(DemoError::OutOfRange {
            what: "wind",
            value: f64::from(settings.wind),
            range: format!("0 to {MAX_WIND}"),
        });
    }
    let mut scene = Scene::default();
    scene.hair.roots.count = settings.strands;
    scene.hair.wind.strength *= settings.wind;
    scene.hair.wind.turbulence *= settings.wind;
    scene.shade.transparency = transparency(&settings.method)?;
    Ok(scene)
}

/// A groom file's bytes (`.hair`, `.tfx`, or USD `BasisCurves` in `.usda`, `.usdc`,
/// `.usd` or `.usdz`, told by `name`'s extension: `Groom::read`) placed for the page:
/// centred on the origin, its longest side [`GROOM_FIT`], resampled to
/// [`GROOM_SEGMENTS`] segments per strand.
pub fn read_groom(bytes: Vec<u8>, name: &str) -> Result<Resampled, DemoError> {
    Groom::read(bytes, Path::new(name))
        .and_then(|g| g.normalized(GROOM_FIT))
        .and_then(|g| g.resample(GROOM_SEGMENTS))
        .map_err(|source| DemoError::Groom {
            name: name.into(),
            source,
        })
}

/// The scene the page draws for a groom ([`read_groom`]): the groom alone (no mesh),
/// [`GROOM_WIDTH`] wide where the file gives no widths, with `settings`' wind and method
/// and otherwise [`scene`]'s defaults. The strand count is the file's: `settings.strands`
/// is refused unless it is the groom's (the page shows the count and disables its
/// slider while a groom is shown).
pub fn groom_scene(groom: &Resampled, settings: &Settings) -> Result<Scene, DemoError> {
    let strands = groom.strands;
    let mut scene = crate::scene(&Settings {
        strands: strands.clamp(1, MAX_STRANDS),
        ..settings.clone()
    })?;
    if settings.strands != strands {
        return Err(DemoError::OutOfRange {
            what: "strands",
            value: f64::from(settings.strands),
            range: format!("the groom's own count, {strands}"),
        });
    }
    scene.mesh = Mesh::default();
    scene.groom = Some(groom.clone());
    scene.hair.growth.width = GROOM_WIDTH;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_name_round_trips() {
        for name in methods() {
            assert_eq!(transparency(name).unwrap().name(), name);
        }
        let e = transparency("fancy").unwrap_err().to_string();
        assert!(e.contains("unknown transparency method 'fancy'"), "{e}");
    }

    #[test]
    fn the_default_settings_draw_the_default_scene_with_the_strand_rasterizer() {
        let s = scene(&Settings::default()).unwrap();
        let expected = Scene::default();
        assert_eq!(expected.shade.transparency, Transparency::strand_raster());
        assert_eq!(s.hair, expected.hair);
        assert_eq!(s.shade, expected.shade);
        assert_eq!(s.camera, expected.camera);
    }

    /// The page's groom: the file's strands, placed and resampled, drawn alone; a
    /// strand count other than the file's and a broken file (`.hair` or USD) are errors
    /// naming what was wrong.
    #[test]
    fn a_groom_file_is_drawn_alone_with_its_own_strand_count() {
        let groom = read_placed("long_hair.hair");
        assert!(groom.strands > 1000, "{} strands", groom.strands);
        let settings = Settings {
            strands: groom.strands,
            ..Settings::default()
        };
        let s = groom_scene(&groom, &settings).unwrap();
        assert_eq!(s.groom.as_ref(), Some(&groom));
        assert_eq!(s.mesh.triangle_count(), 0);
        let other = Settings {
            strands: groom.strands + 1,
            ..settings
        };
        let e = groom_scene(&groom, &other).unwrap_err().to_string();
        assert!(e.contains("the groom's own count"), "{e}");
        let e = read_groom(
            b"#usda 1.0\ndef BasisCurves \"C\" {".to_vec(),
            "broken.usda",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("broken.usda"), "{e}");
        let e = read_groom(b"HAIR".to_vec(), "broken.hair")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("broken.hair: "), "{e}");
    }

    /// A USD groom (the repository's `scenes/usd_groom.usda`: 500 cubic B-splines under
    /// an Xform) reads in the page's build as `pelage render` reads it: same strands,
    /// placed and resampled like any groom.
    #[test]
    fn a_usd_groom_reads_in_the_pages_build() {
        assert_eq!(read_placed("usd_groom.usda").strands, 500);
    }

    /// `scenes/NAME` read as the page reads a groom, checked to be resampled to
    /// [`GROOM_SEGMENTS`] and scaled to [`GROOM_FIT`].
    fn read_placed(name: &str) -> Resampled {
        let path = format!("{}/../../scenes/{name}", env!("CARGO_MANIFEST_DIR"));
        let groom = read_groom(std::fs::read(path).unwrap(), name).unwrap();
        assert_eq!(groom.segments, GROOM_SEGMENTS);
        let (lo, hi) = groom.bounds();
        let side = (hi - lo).max_element();
        assert!(
            (side - GROOM_FIT).abs() < 0.05 * GROOM_FIT,
            "{name}: longest side {side}"
        );
        groom
    }

    #[test]
    fn controls_out_of_range_are_refused() {
        let strands = Settings {
            strands: 0,
            ..Settings::default()
        };
        assert!(matches!(
            scene(&strands),
            Err(DemoError::OutOfRange {
                what: "strands",
                ..
            })
        ));
        let wind = Settings {
            wind: f32::NAN,
            ..Settings::default()
        };
        assert!(matches!(
            scene(&wind),
            Err(DemoError::OutOfRange { what: "wind", .. })
        ));
    }
}
