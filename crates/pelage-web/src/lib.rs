//! pelage in a web page: the creature of [`pelage::Scene::default`] in wind, drawn on
//! WebGPU into a canvas (`web/index.html`), with controls for the wind, the strand count
//! and the transparency method, and the GPU time per pass where the browser offers
//! timestamp queries.
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

use pelage::Scene;
use pelage::scene::{Named, Transparency};

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
