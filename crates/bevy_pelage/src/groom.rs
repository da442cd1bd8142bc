//! Groom files as Bevy assets: [`GroomLoader`] reads `.hair` (Cem Yuksel), `.tfx`
//! (AMD TressFX) and, with this crate's `usd` feature (on by default), USD
//! `BasisCurves` (`.usda`, `.usdc`, `.usd`, `.usdz`) into a [`GroomAsset`] through
//! pelage's own readers ([`pelage::scene::Groom::read`]); a [`Groom`] component puts
//! one on a furred entity.

use bevy::asset::io::Reader;
use bevy::asset::{Asset, AssetLoader, Handle, LoadContext};
use bevy::ecs::component::Component;
use bevy::reflect::TypePath;
use pelage::scene::{DynamicsParams, GuideParams};

/// A groom file's strands (pelage's [`pelage::scene::Groom`]), as read, in the space
/// of the mesh it is put on.
#[derive(Asset, TypePath, Clone, Debug)]
pub struct GroomAsset {
    /// The strands, widths and colours of the file.
    pub groom: pelage::scene::Groom,
}

/// Why a groom file did not load: Bevy reports it as the asset's load error
/// (`AssetServer::load_state` is `LoadState::Failed` with it, and Bevy logs it).
#[derive(Debug, thiserror::Error)]
pub enum GroomLoadError {
    /// The bytes could not be read.
    #[error("reading the groom file: {0}")]
    Io(#[from] std::io::Error),
    /// pelage refused the file: its format, a truncated or inconsistent file, a NaN
    /// point, a bad colour (the error names the file's attribute).
    #[error(transparent)]
    Groom(#[from] pelage::scene::GroomError),
}

/// The [`AssetLoader`] of [`GroomAsset`]s (registered by
/// [`PelagePlugin`](crate::PelagePlugin)).
#[derive(Default, TypePath)]
pub struct GroomLoader;

/// The file extensions [`GroomLoader`] takes.
#[cfg(feature = "usd")]
const EXTENSIONS: &[&str] = &["hair", "tfx", "usda", "usdc", "usd", "usdz"];
/// The file extensions [`GroomLoader`] takes.
#[cfg(not(feature = "usd"))]
const EXTENSIONS: &[&str] = &["hair", "tfx"];

impl AssetLoader for GroomLoader {
    type Asset = GroomAsset;
    type Settings = ();
    type Error = GroomLoadError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<GroomAsset, GroomLoadError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        let groom = pelage::scene::Groom::read(bytes, load_context.path().path())?;
        Ok(GroomAsset { groom })
    }

    fn extensions(&self) -> &[&str] {
        EXTENSIONS
    }
}

/// A groom on the entity's [`Mesh3d`](bevy::mesh::Mesh3d) in place of the fur that
/// [`Fur`](crate::Fur) grows: its strands (resampled to `segments` segments, in the
/// mesh's own space) bent by [`Fur::hair`](crate::Fur::hair)'s wind, or simulated, or
/// taken as guides for render strands rooted on the mesh. Without a `Mesh3d` the groom
/// is drawn alone (in the entity's space, in the wind; pelage refuses guides and
/// dynamics there: they need the mesh). The entity's [`Fur`](crate::Fur) still
/// gives the strands' width, colour, opacity, the wind and the shading (what a scene
/// file's `[hair.growth]` gives a `[groom]`).
///
/// The entity's fur is built once the asset has loaded; a file that does not load is
/// logged once (Bevy logs the loader's error too) and the entity gets no fur.
#[derive(Component, Clone, Debug)]
pub struct Groom {
    /// The groom file, as `asset_server.load("long_hair.hair")` hands it.
    pub asset: Handle<GroomAsset>,
    /// Segments per strand, 1..=`MAX_SEGMENTS` (a scene file's `[groom] segments`).
    pub segments: u32,
    /// Take the groom's strands as guides and interpolate render strands rooted on the
    /// mesh from them (a scene file's `[groom] guides`); `None` draws its own strands.
    pub guides: Option<GuideParams>,
    /// Simulate the strands (a scene file's `[dynamics]`); `None` bends them by the wind.
    pub dynamics: Option<DynamicsParams>,
}

impl Groom {
    /// `asset`'s own strands in 16 segments each (pelage's default), in the wind.
    pub fn new(asset: Handle<GroomAsset>) -> Self {
        Self {
            asset,
            segments: 16,
            guides: None,
            dynamics: None,
        }
    }
}
