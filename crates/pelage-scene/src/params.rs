//! Parameters of stage 1 (roots, growth, wind), as plain serde data.
//!
//! Every struct has a `validate` method that answers bad values (NaN, Inf,
//! negative lengths, zero segments, ...) with a [`ParamError`] naming the
//! parameter, and a `Default` that renders the built-in scene.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// The most segments one strand may have (the `.hair` format's own limit is 65535;
/// generated fur never needs more than a few dozen).
pub const MAX_SEGMENTS: u32 = 256;

/// A parameter that is out of its valid range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("parameter `{name}` = {value}: {reason}")]
pub struct ParamError {
    /// Dotted path of the parameter, e.g. `growth.length`.
    pub name: String,
    /// The offending value, formatted.
    pub value: String,
    /// What the valid range is.
    pub reason: String,
}

impl ParamError {
    /// An error for parameter `name` holding `value`, with what its valid range is.
    pub fn new(name: &str, value: impl std::fmt::Debug, reason: &str) -> Self {
        Self {
            name: name.to_string(),
            value: format!("{value:?}"),
            reason: reason.to_string(),
        }
    }
}

pub(crate) fn finite(name: &str, v: f32) -> Result<(), ParamError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ParamError::new(name, v, "must be a finite number"))
    }
}

pub(crate) fn non_negative(name: &str, v: f32) -> Result<(), ParamError> {
    finite(name, v)?;
    if v < 0.0 {
        return Err(ParamError::new(name, v, "must be >= 0"));
    }
    Ok(())
}

/// Errors unless `v` is finite, > 0 and at most [`crate::MAX_EXTENT`] (a length or width
/// whose squares the shaders take).
pub(crate) fn extent(name: &str, v: f32) -> Result<(), ParamError> {
    positive(name, v)?;
    if v > crate::MAX_EXTENT {
        return Err(ParamError::new(
            name,
            v,
            &format!(
                "must be at most {:e} scene units: larger values overflow 32-bit floats where \
                 distances are squared",
                crate::MAX_EXTENT
            ),
        ));
    }
    Ok(())
}

pub(crate) fn positive(name: &str, v: f32) -> Result<(), ParamError> {
    finite(name, v)?;
    if v <= 0.0 {
        return Err(ParamError::new(name, v, "must be > 0"));
    }
    Ok(())
}

pub(crate) fn finite_vec(name: &str, v: Vec3) -> Result<(), ParamError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ParamError::new(name, v, "every component must be finite"))
    }
}

/// The largest value of a colour channel (hair, region, mesh, background) and of the
/// ambient term: the shaders multiply colours by lights of up to
/// [`MAX_RADIANCE`](crate::MAX_RADIANCE) and by the shading models' weights, and this
/// keeps every product finite in 32-bit floats.
pub const MAX_COLOR: f32 = 1.0e4;

/// Errors unless every channel of `v` is finite and in [0, [`MAX_COLOR`]].
pub(crate) fn color(name: &str, v: Vec3) -> Result<(), ParamError> {
    if !v.is_finite() || v.min_element() < 0.0 || v.max_element() > MAX_COLOR {
        return Err(ParamError::new(
            name,
            v,
            &format!("every channel must be finite and in [0, {MAX_COLOR:e}]"),
        ));
    }
    Ok(())
}

/// How the surface under a root is interpolated from the triangle's corners.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceInterpolation {
    /// Linear position, normalised linear normal (the mesh as drawn).
    Flat,
    /// PN triangles (Vlachos et al. 2001): cubic position, quadratic normal.
    #[default]
    PnTriangle,
}

/// Where strands grow: how many, and how they are spread over the mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RootParams {
    /// Number of strands. Strand `i` keeps its root when this changes.
    pub count: u32,
    /// Seed of every random choice (roots, jitter, phases).
    pub seed: u32,
    /// Optional per-vertex density weight (>= 0), one per mesh vertex; a triangle's
    /// share of the strands is its area times the mean weight of its corners.
    pub density: Option<Vec<f32>>,
    /// Optional per-vertex length scale (>= 0), interpolated at each root.
    pub length_scale: Option<Vec<f32>>,
    /// Optional per-vertex region index, one per mesh vertex: each root takes the
    /// region of its triangle's corner nearest to it (the largest barycentric). 0 is
    /// `[hair.growth]` itself, `k` its `k`-th `[[hair.growth.regions]]` entry.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<Vec<u32>>,
    /// Texture maps over the mesh's UVs, sampled at each root (`[hair.roots.textures]`).
    #[serde(skip_serializing_if = "RootTextures::is_empty")]
    pub textures: RootTextures,
}

/// The largest value of a per-vertex density or length map ([`RootParams::density`],
/// [`RootParams::length_scale`]): a length scale multiplies `growth.length`, which the
/// product must keep within [`crate::MAX_EXTENT`] (see
/// [`RootParams::validate_lengths`]).
pub const MAX_MAP_VALUE: f32 = 1.0e6;

/// Texture maps over the mesh's UVs (PNG; see [`crate::surface_map`]), each sampled at
/// every root. They combine with the per-vertex maps of [`RootParams`] by multiplying
/// (density, length); a region may come from one or the other, not both.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RootTextures {
    /// Region index per texel: the red channel's integer value at the file's bit depth
    /// (0..=255 for 8-bit and palette PNGs, 0..=65535 for 16-bit, 0..=1 for 1-bit grey;
    /// see [`MapImage`](crate::MapImage)), read at the texel holding the root (nearest:
    /// regions are not blended). 0 is `[hair.growth]`, `k` its
    /// `k`-th `[[hair.growth.regions]]`; a texel naming a region that does not exist
    /// is an error.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<crate::TextureMap>,
    /// Density weight: red over its largest value (255 for 8 bits, 65535 for 16: the
    /// same [0, 1] at every bit depth), bilinear. A triangle's share of the strands is its
    /// area times the mean of the map at four points (its centroid and the midpoints
    /// from the centroid to each corner), so features smaller than a triangle are
    /// averaged away.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub density: Option<crate::TextureMap>,
    /// Length scale: red over its largest value (bilinear) at the root, in [0, 1].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_scale: Option<crate::TextureMap>,
    /// Colour: the texel's sRGB colour made linear (bilinear), multiplying the strand's
    /// colour (its region's, or `growth.color`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub color: Option<crate::TextureMap>,
}

impl RootTextures {
    /// Whether no map is given.
    pub fn is_empty(&self) -> bool {
        self.maps().all(|(_, m)| m.is_none())
    }

    /// Every map with its key (`roots.textures.region`, ...).
    pub fn maps(&self) -> impl Iterator<Item = (&'static str, Option<&crate::TextureMap>)> {
        [
            ("roots.textures.region", self.region.as_ref()),
            ("roots.textures.density", self.density.as_ref()),
            ("roots.textures.length_scale", self.length_scale.as_ref()),
            ("roots.textures.color", self.color.as_ref()),
        ]
        .into_iter()
    }

    /// The same, to change (to load every map, say).
    pub fn maps_mut(&mut self) -> impl Iterator<Item = (&'static str, &mut crate::TextureMap)> {
        [
            ("roots.textures.region", self.region.as_mut()),
            ("roots.textures.density", self.density.as_mut()),
            ("roots.textures.length_scale", self.length_scale.as_mut()),
            ("roots.textures.color", self.color.as_mut()),
        ]
        .into_iter()
        .filter_map(|(name, m)| m.map(|m| (name, m)))
    }
}

impl Default for RootParams {
    fn default() -> Self {
        Self {
            count: 20_000,
            seed: 1,
            density: None,
            length_scale: None,
            region: None,
            textures: RootTextures::default(),
        }
    }
}

impl RootParams {
    /// Checks the parameters against a mesh with `vertex_count` vertices.
    pub fn validate(&self, vertex_count: usize) -> Result<(), ParamError> {
        if self.count == 0 {
            return Err(ParamError::new(
                "roots.count",
                self.count,
                "must be at least 1",
            ));
        }
        for (name, map) in [
            ("roots.density", &self.density),
            ("roots.length_scale", &self.length_scale),
        ] {
            if let Some(map) = map {
                if map.len() != vertex_count {
                    return Err(ParamError::new(
                        name,
                        format!("{} values", map.len()),
                        &format!("needs one value per mesh vertex ({vertex_count})"),
                    ));
                }
                if let Some((i, v)) = map
                    .iter()
                    .enumerate()
                    .find(|(_, v)| !v.is_finite() || **v < 0.0 || **v > MAX_MAP_VALUE)
                {
                    return Err(ParamError::new(
                        &format!("{name}[{i}]"),
                        v,
                        &format!("must be finite and in [0, {MAX_MAP_VALUE:e}]"),
                    ));
                }
            }
        }
        if let Some(map) = &self.density {
            if map.iter().all(|v| *v == 0.0) {
                return Err(ParamError::new(
                    "roots.density",
                    format!("{} values, all 0", map.len()),
                    "no triangle can carry strands when every density weight is 0: give \
                     some vertex a weight above 0",
                ));
            }
        }
        if let Some(map) = &self.region {
            if map.len() != vertex_count {
                return Err(ParamError::new(
                    "roots.region",
                    format!("{} values", map.len()),
                    &format!("needs one value per mesh vertex ({vertex_count})"),
                ));
            }
            if self.textures.region.is_some() {
                return Err(ParamError::new(
                    "roots.textures.region",
                    "given with roots.region",
                    "give the region map either per vertex or as a texture, not both",
                ));
            }
        }
        Ok(())
    }

    /// Checks the region maps against `region_count` regions (`[hair.growth]` and its
    /// `regions`) and, for a mesh, that every texture map is loaded and the mesh has
    /// UVs: what [`RootParams::validate`] cannot know.
    pub fn validate_maps(
        &self,
        region_count: usize,
        mesh: Option<&crate::Mesh>,
    ) -> Result<(), ParamError> {
        let reason = |value: usize| {
            ParamError::new(
                "roots.region",
                value,
                &format!(
                    "names a region that does not exist: there are {region_count} (0 = \
                     [hair.growth], k = its k-th [[hair.growth.regions]])"
                ),
            )
        };
        if let Some(map) = &self.region {
            if let Some((i, &v)) = map
                .iter()
                .enumerate()
                .find(|(_, v)| **v as usize >= region_count)
            {
                let mut e = reason(v as usize);
                e.name = format!("roots.region[{i}]");
                return Err(e);
            }
        }
        if let Some(map) = &self.textures.region {
            if let Some(image) = map.image.as_deref() {
                let width = image.width() as usize;
                if let Some((i, t)) = image
                    .reds()
                    .enumerate()
                    .find(|(_, t)| *t as usize >= region_count)
                {
                    let mut e = reason(t as usize);
                    e.name = "roots.textures.region".into();
                    e.value = format!(
                        "{} at texel ({}, {}) of {} ({}-bit)",
                        t,
                        i % width,
                        i / width,
                        map.path.display(),
                        image.bits()
                    );
                    return Err(e);
                }
            }
        }
        if let Some(map) = &self.textures.density {
            if let Some(image) = map.image.as_deref() {
                if image.reds().all(|v| v == 0) {
                    return Err(ParamError::new(
                        "roots.textures.density",
                        &map.path,
                        "every texel's red channel is 0, so no triangle can carry strands: \
                         a density map needs some texel above 0 where the mesh is",
                    ));
                }
            }
        }
        let Some(mesh) = mesh else {
            return Ok(());
        };
        for (name, map) in self.textures.maps() {
            let Some(map) = map else { continue };
            map.loaded(name)?;
            if !mesh.has_uvs() {
                return Err(ParamError::new(
                    name,
                    &map.path,
                    "the mesh has no texture coordinates (UVs) to read a texture map with: \
                     use a mesh with UVs (an OBJ with `vt`, the creature, a plane) or a \
                     per-vertex map",
                ));
            }
        }
        Ok(())
    }
}

impl RootParams {
    /// Checks what combines these maps with `growth`: the longest strand, the longest
    /// region's `length · (1 + length_jitter)` times the largest per-vertex length
    /// scale, must stay within [`crate::MAX_EXTENT`] (each factor may be in range while
    /// their product overflows); a region map must have regions to choose between and
    /// regions a region map choosing them. Errors name `roots.length_scale`,
    /// `roots.region` / `roots.textures.region` or `growth.regions`.
    pub fn validate_with(&self, growth: &GrowthParams) -> Result<(), ParamError> {
        self.validate_lengths(growth)?;
        self.validate_regions_used(growth)
    }

    /// The first half of [`RootParams::validate_with`]: the longest strand, the longest
    /// region's `length · (1 + length_jitter)` times the largest per-vertex length scale,
    /// within [`crate::MAX_EXTENT`]; the error names `roots.length_scale`.
    pub fn validate_lengths(&self, growth: &GrowthParams) -> Result<(), ParamError> {
        if let Some(map) = &self.length_scale {
            let scale = map.iter().copied().fold(0.0f32, f32::max);
            let longest = growth
                .resolved_regions()
                .iter()
                .map(|g| f64::from(g.length) * (1.0 + f64::from(g.length_jitter)))
                .fold(0.0f64, f64::max);
            let product = longest * f64::from(scale);
            if product > f64::from(crate::MAX_EXTENT) {
                return Err(ParamError::new(
                    "roots.length_scale",
                    format!(
                        "largest {scale} times a strand length of up to {longest} = {product:e}"
                    ),
                    &format!(
                        "the longest scaled strand must be at most {:e} scene units",
                        crate::MAX_EXTENT
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The second half of [`RootParams::validate_with`]: a region map needs regions, and
    /// regions a region map.
    pub fn validate_regions_used(&self, growth: &GrowthParams) -> Result<(), ParamError> {
        let map_key = if self.region.is_some() {
            Some("roots.region")
        } else if self.textures.region.is_some() {
            Some("roots.textures.region")
        } else {
            None
        };
        match (map_key, growth.regions.is_empty()) {
            (Some(key), true) => Err(ParamError::new(
                key,
                "a region map",
                "there are no [[hair.growth.regions]] for it to choose: every root would be \
                 in region 0 ([hair.growth]); add regions or leave the map out",
            )),
            (None, false) => Err(ParamError::new(
                "growth.regions",
                format!("{} regions", growth.regions.len()),
                "no region map says where they grow, so they would never be used: give \
                 [hair.roots.textures] region = \"map.png\" (or a per-vertex \
                 [hair.roots] region) or leave the regions out",
            )),
            _ => Ok(()),
        }
    }
}

/// The most waves (or turns of a curl) a strand may have, and the steepest slope of a
/// wave (amplitude x frequency): products of two keys that the growth shader takes sines
/// and arctangents of, which must stay finite.
pub const MAX_WAVES: f32 = 1.0e6;

/// The most regions a groom may have besides `[hair.growth]` (an 8-bit region map's
/// largest index).
pub const MAX_REGIONS: usize = 255;

/// A region of the fur: the keys of [`GrowthParams`] it grows with instead of the
/// base ones (any left out keep the base value). Only what each strand carries on its
/// own can differ by region: its shape (`hair_type`), length, jitters, width and colour.
/// `segments` stays one per groom (the vertex buffer and the level of detail are laid
/// out by it), and `force_weight`, `gravity`, `tip_width`, `opacity`, `color_jitter`
/// and `surface` are read once by the passes for every strand.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RegionParams {
    /// Straight, wavy or curly.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hair_type: Option<HairType>,
    /// Strand length, scene units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length: Option<f32>,
    /// Relative length jitter in [0, 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_jitter: Option<f32>,
    /// Largest tilt away from the normal, radians, in [0, π/2].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction_jitter: Option<f32>,
    /// Root width, scene units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<f32>,
    /// Base colour, linear RGB.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub color: Option<Vec3>,
}

/// The shape a strand is grown in, on top of gravity and wind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum HairType {
    /// Straight strands that bend only under the forces.
    #[default]
    Straight,
    /// A planar wave: the tangent swings by `atan(2π·amplitude·frequency·cos(2π·frequency·s))`
    /// around the growth direction, `s` being the arc length from the root.
    Wavy {
        /// Amplitude of the wave, in scene units.
        amplitude: f32,
        /// Waves per scene unit of strand length.
        frequency: f32,
    },
    /// A helix around the growth direction.
    Curly {
        /// Helix radius, in scene units.
        radius: f32,
        /// Rise per turn along the growth direction, in scene units.
        pitch: f32,
    },
}

/// How strands grow from their roots.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GrowthParams {
    /// Segments per strand (1..=`MAX_SEGMENTS`); a strand has `segments + 1` vertices.
    pub segments: u32,
    /// Strand length in scene units (before jitter and the length map).
    pub length: f32,
    /// Relative length jitter in [0, 1): each strand's length is scaled by `1 ± jitter`.
    pub length_jitter: f32,
    /// Largest tilt of a strand's root direction away from the surface normal, radians, in [0, π/2].
    pub direction_jitter: f32,
    /// Seed 001's force weight: each segment's direction becomes `normalize(d + force_weight·F)`,
    /// so more segments (and a larger weight) bend more. 0 = rigid.
    pub force_weight: f32,
    /// Gravity, in the same units as the wind force.
    pub gravity: Vec3,
    /// Straight, wavy or curly.
    pub hair_type: HairType,
    /// Strand width at the root, in scene units.
    pub width: f32,
    /// Width at the tip as a fraction of the root width, in [0, 1].
    pub tip_width: f32,
    /// Base colour, linear RGB in [0, 1].
    pub color: Vec3,
    /// Per-strand brightness jitter in [0, 1).
    pub color_jitter: f32,
    /// Opacity of one strand, in [0, 1]: the fraction of light one crossing absorbs
    /// (shadows and transparency use it).
    pub opacity: f32,
    /// How the root position and normal are interpolated.
    pub surface: SurfaceInterpolation,
    /// Regions 1, 2, ... of a region map ([`RootParams::region`] or
    /// [`RootTextures::region`]), each overriding some of the keys above; region 0 is
    /// these parameters themselves. At most [`MAX_REGIONS`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionParams>,
}

impl Default for GrowthParams {
    fn default() -> Self {
        Self {
            segments: 8,
            length: 0.13,
            length_jitter: 0.3,
            direction_jitter: 0.35,
            force_weight: 0.16,
            gravity: Vec3::new(0.0, -1.0, 0.0),
            hair_type: HairType::Straight,
            width: 0.004,
            tip_width: 0.2,
            color: Vec3::new(0.36, 0.2, 0.09),
            color_jitter: 0.25,
            opacity: 0.6,
            surface: SurfaceInterpolation::PnTriangle,
            regions: Vec::new(),
        }
    }
}

impl GrowthParams {
    /// The parameters of every region, region 0 (these, without `regions`) first, then
    /// each of `regions` over them.
    pub fn resolved_regions(&self) -> Vec<GrowthParams> {
        let base = GrowthParams {
            regions: Vec::new(),
            ..self.clone()
        };
        let mut out = Vec::with_capacity(self.regions.len() + 1);
        out.push(base.clone());
        for r in &self.regions {
            out.push(GrowthParams {
                hair_type: r.hair_type.unwrap_or(base.hair_type),
                length: r.length.unwrap_or(base.length),
                length_jitter: r.length_jitter.unwrap_or(base.length_jitter),
                direction_jitter: r.direction_jitter.unwrap_or(base.direction_jitter),
                width: r.width.unwrap_or(base.width),
                color: r.color.unwrap_or(base.color),
                ..base.clone()
            });
        }
        out
    }

    /// Checks every field and every region; the error names the first bad one (a
    /// region's as `growth.regions[i].length`, `i` counting from 0 in file order: region
    /// `i + 1` of the map).
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.regions.len() > MAX_REGIONS {
            return Err(ParamError::new(
                "growth.regions",
                format!("{} regions", self.regions.len()),
                &format!("at most {MAX_REGIONS} (an 8-bit region map's largest index)"),
            ));
        }
        for (i, region) in self.resolved_regions().iter().enumerate() {
            region.validate_fields().map_err(|mut e| {
                if i > 0 {
                    e.name = e
                        .name
                        .replacen("growth.", &format!("growth.regions[{}].", i - 1), 1);
                }
                e
            })?;
        }
        Ok(())
    }

    /// Checks every field but `regions`.
    fn validate_fields(&self) -> Result<(), ParamError> {
        if self.segments == 0 || self.segments > MAX_SEGMENTS {
            return Err(ParamError::new(
                "growth.segments",
                self.segments,
                &format!("must be in 1..={MAX_SEGMENTS}"),
            ));
        }
        extent("growth.length", self.length)?;
        non_negative("growth.length_jitter", self.length_jitter)?;
        if self.length_jitter >= 1.0 {
            return Err(ParamError::new(
                "growth.length_jitter",
                self.length_jitter,
                "must be < 1",
            ));
        }
        non_negative("growth.direction_jitter", self.direction_jitter)?;
        if self.direction_jitter > std::f32::consts::FRAC_PI_2 {
            return Err(ParamError::new(
                "growth.direction_jitter",
                self.direction_jitter,
                "must be at most π/2 radians",
            ));
        }
        non_negative("growth.force_weight", self.force_weight)?;
        finite_vec("growth.gravity", self.gravity)?;
        match self.hair_type {
            HairType::Straight => {}
            HairType::Wavy {
                amplitude,
                frequency,
            } => {
                non_negative("growth.hair_type.amplitude", amplitude)?;
                non_negative("growth.hair_type.frequency", frequency)?;
                // Combined in the shader: the slope 2π·amplitude·frequency and the phase
                // 2π·frequency·s along a strand of up to `length`.
                let (slope, waves) = (
                    f64::from(amplitude) * f64::from(frequency),
                    f64::from(frequency) * f64::from(self.length),
                );
                if slope > f64::from(MAX_WAVES) || waves > f64::from(MAX_WAVES) {
                    return Err(ParamError::new(
                        "growth.hair_type.frequency",
                        frequency,
                        &format!(
                            "amplitude x frequency ({slope:e}) and frequency x growth.length \
                             ({waves:e}) must each be at most {MAX_WAVES:e}"
                        ),
                    ));
                }
            }
            HairType::Curly { radius, pitch } => {
                non_negative("growth.hair_type.radius", radius)?;
                positive("growth.hair_type.pitch", pitch)?;
                for (name, v) in [
                    ("growth.hair_type.radius", radius),
                    ("growth.hair_type.pitch", pitch),
                ] {
                    if v > crate::MAX_EXTENT {
                        return Err(ParamError::new(
                            name,
                            v,
                            &format!("must be at most {:e} scene units", crate::MAX_EXTENT),
                        ));
                    }
                }
                // Turns along a strand: length / pitch.
                let turns = f64::from(self.length) / f64::from(pitch);
                if turns > f64::from(MAX_WAVES) {
                    return Err(ParamError::new(
                        "growth.hair_type.pitch",
                        pitch,
                        &format!(
                            "growth.length / pitch ({turns:e} turns) must be at most {MAX_WAVES:e}"
                        ),
                    ));
                }
            }
        }
        extent("growth.width", self.width)?;
        non_negative("growth.tip_width", self.tip_width)?;
        if self.tip_width > 1.0 {
            return Err(ParamError::new(
                "growth.tip_width",
                self.tip_width,
                "must be in [0, 1]",
            ));
        }
        color("growth.color", self.color)?;
        non_negative("growth.color_jitter", self.color_jitter)?;
        if self.color_jitter >= 1.0 {
            return Err(ParamError::new(
                "growth.color_jitter",
                self.color_jitter,
                "must be < 1",
            ));
        }
        non_negative("growth.opacity", self.opacity)?;
        if self.opacity > 1.0 {
            return Err(ParamError::new(
                "growth.opacity",
                self.opacity,
                "must be in [0, 1]",
            ));
        }
        Ok(())
    }
}

/// The wind: a force field evaluated for a time `t`, so any frame can be computed on its own.
///
/// `F(p, t) = direction·strength·gust(t + phase) + turbulence·noise(p·turbulence_scale − direction·t·turbulence_speed)`,
/// where `gust` is smooth value noise in time around 1 (`1 ± gust_strength`), `phase` is a per-strand
/// offset in `[0, phase_spread)` seconds and `noise` is a vector of coherent 3-D value noise in [-1, 1].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WindParams {
    /// Wind direction (normalised on use; zero means no directional wind).
    pub direction: Vec3,
    /// Mean force of the wind.
    pub strength: f32,
    /// Relative gust amplitude in [0, 1].
    pub gust_strength: f32,
    /// Gusts per second.
    pub gust_frequency: f32,
    /// Force amplitude of the turbulence.
    pub turbulence: f32,
    /// Spatial frequency of the turbulence, cells per scene unit.
    pub turbulence_scale: f32,
    /// Speed at which the turbulence is carried along the wind, scene units per second.
    pub turbulence_speed: f32,
    /// Spread of per-strand gust phases, seconds.
    pub phase_spread: f32,
}

/// The largest force magnitude accepted (anything larger bends every strand fully anyway).
pub const MAX_FORCE: f32 = 1.0e6;

impl Default for WindParams {
    fn default() -> Self {
        Self {
            direction: Vec3::new(1.0, 0.0, 0.3),
            strength: 0.9,
            gust_strength: 0.8,
            gust_frequency: 0.7,
            turbulence: 0.5,
            turbulence_scale: 3.0,
            turbulence_speed: 1.5,
            phase_spread: 0.6,
        }
    }
}

impl WindParams {
    /// No wind at all.
    pub fn calm() -> Self {
        Self {
            strength: 0.0,
            turbulence: 0.0,
            ..Self::default()
        }
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        finite_vec("wind.direction", self.direction)?;
        for (name, v) in [
            ("wind.strength", self.strength),
            ("wind.turbulence", self.turbulence),
        ] {
            non_negative(name, v)?;
            if v > MAX_FORCE {
                return Err(ParamError::new(
                    name,
                    v,
                    &format!("must be at most {MAX_FORCE}"),
                ));
            }
        }
        non_negative("wind.gust_strength", self.gust_strength)?;
        if self.gust_strength > 1.0 {
            return Err(ParamError::new(
                "wind.gust_strength",
                self.gust_strength,
                "must be in [0, 1]",
            ));
        }
        non_negative("wind.gust_frequency", self.gust_frequency)?;
        non_negative("wind.turbulence_scale", self.turbulence_scale)?;
        non_negative("wind.turbulence_speed", self.turbulence_speed)?;
        non_negative("wind.phase_spread", self.phase_spread)?;
        Ok(())
    }
}

/// Strand dynamics (`pelage_strands::SimulateStrands`): position-based dynamics of every
/// strand vertex, integrated by Verlet in fixed substeps, then projected root to tip onto
/// the global shape, local shape, collision and length constraints.
///
/// The stiffnesses are fractions of the way to the target taken per
/// [`STIFFNESS_INTERVAL`] (1/120 s, the default substep); a substep of `h` seconds takes
/// [`DynamicsParams::stiffness_per_substep`] of it, so the pull does not depend on how
/// many substeps a frame is cut into, on the frame rate or on `max_substep`. (TressFX
/// applies its stiffnesses once per substep, which makes hair stiffer as substeps get
/// shorter: at 50 fps a frame of three substeps pulled three times where 60 fps pulled
/// twice.)
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DynamicsParams {
    /// Gravity, scene units per second squared.
    pub gravity: Vec3,
    /// Acceleration per unit of the wind's force (`WindParams`; the wind's own field,
    /// turbulence and gusts included), scene units per second squared.
    pub wind_response: f32,
    /// Velocity damping rate, per second: velocities decay by `exp(-damping·h)` per
    /// substep of `h` seconds.
    pub damping: f32,
    /// Local shape stiffness in [0, 1]: how far each segment is turned back toward its
    /// rest direction in its parent segment's frame, per [`STIFFNESS_INTERVAL`].
    pub local_stiffness: f32,
    /// Global shape stiffness in [0, 1] at the root: how far each vertex is pulled
    /// toward its rest position carried by the root's frame, per [`STIFFNESS_INTERVAL`].
    pub global_stiffness: f32,
    /// Fraction of the strand, from the root, over which the global stiffness falls
    /// linearly to zero, in (0, 1].
    pub global_range: f32,
    /// Müller et al. 2012's velocity correction of follow-the-leader in [0, 1]: the
    /// fraction of the next vertex's length correction taken off a vertex's velocity.
    pub length_damping: f32,
    /// Friction of the colliders in [0, 1]: the fraction of the tangential velocity a
    /// vertex loses on contact.
    pub friction: f32,
    /// The longest substep, seconds, in (0, 0.05]: a frame of `dt` takes
    /// `ceil(dt / max_substep)` equal substeps, give or take [`SUBSTEP_SLACK`]. A
    /// simulation also refuses one shorter than [`DynamicsParams::min_substep`] for
    /// its scene's size and accelerations (2.2e-4 s for strands 1 unit from the origin
    /// under gravity 9.8), where 32-bit positions can no longer hold a substep's motion.
    pub max_substep: f32,
    /// The longest frame simulated, seconds, in (0, 1]: a longer frame (a hitch, a
    /// breakpoint) is simulated as this long.
    pub max_frame: f32,
    /// A root that moves farther than this in one frame, scene units (> 0), has been
    /// teleported: its strand is reset to rest at the new pose.
    pub teleport_distance: f32,
    /// Spheres and capsules the strands cannot enter, in the mesh's space (they move
    /// with a [`MeshMotion`]); at most [`MAX_COLLIDERS`].
    pub colliders: Vec<Collider>,
    /// Nodes along the longest axis of a signed distance field of the mesh itself
    /// (`pelage_strands::BodySdf`) that strands collide with besides the colliders: 0
    /// (the default) for none, else in
    /// [[`MIN_SDF_RESOLUTION`](crate::MIN_SDF_RESOLUTION),
    /// [`MAX_SDF_RESOLUTION`](crate::MAX_SDF_RESOLUTION)] and at most the device's
    /// `max_texture_dimension_3d`. Built once for a rigid or still mesh; for a skinned
    /// one, see `sdf_skinned`.
    pub sdf_resolution: u32,
    /// How a skinned mesh's field follows the skin ([`SkinnedSdf`]): `through_skin` (the
    /// default) or `rebuilt`. Fixed when the simulation is made.
    pub sdf_skinned: SkinnedSdf,
    /// How far beyond the body's field the collision step keeps a vertex, in the field's
    /// cells, in [0, [`MAX_SDF_STANDOFF`]] (on top of half the strand's width): the field
    /// is read by trilinear interpolation between nodes a cell apart, which says
    /// "farther" than the surface is where the surface bends within a cell (a faceted
    /// part's edges, the crease where parts meet, a rim thinner than a cell): near the
    /// built-in creature's surface by more than 0.04 cells at 128 (0.07 at 64) at one
    /// point in ten and by 0.23 (0.36) at one in a hundred; on a smooth sphere by at most
    /// 0.03 at one in a hundred (`cargo test -p pelage-strands --test sdf standoff --
    /// --nocapture`). The default, 0.25, is the best measured point on the creature's
    /// rig (vertices deeper than half a width after a frame, the field at 64 read
    /// through the skin: 1.35% at 0, 0.62% at 0.125, 0.17% at 0.25, 0.25% at 0.5); hair
    /// resting on the body rests that much farther from it. 0: the interpolated surface.
    pub sdf_standoff: f32,
}

/// The largest [`DynamicsParams::sdf_standoff`], in the field's cells.
pub const MAX_SDF_STANDOFF: f32 = 2.0;

/// How the distance field of a skinned body (`DynamicsParams::sdf_resolution` > 0 on a
/// mesh skinned by a `[skin]` rig or `Frame::with_skin`) follows the skin.
///
/// Measured on the creature's rig (`pelage bench`, `cargo test -p pelage-strands --test
/// sdf`; the dynamics page of the book): with the default standoff the two tie on the
/// vertices that end a frame deeper than half a strand width (through the skin 0.17% at
/// 64 and 0.04% at 128, rebuilt 0.12% and 0.03%: a strand or two rooted at a junction of
/// the creature's parts), and on lavapipe the rebuilt field costs 1.2x to 2.1x less in
/// all. Through the skin is the default because its field is the bind pose's whatever
/// the motion (a rebuilt field spans the box the caller says every pose stays in, its
/// cells coarser for a generous box, and a pose that leaves it loses its collisions),
/// and its per-frame pass is 0.07x the growth pass where the rebuild's is 0.9x to 3.5x
/// and grows with the nodes and the triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SkinnedSdf {
    /// Built once in the bind pose and read through the skin: each frame blends the
    /// joint matrices at a lattice over the field (`pelage_strands::SdfSkin`), and the
    /// collision step finds each vertex's bind-pose point through the blend's inverse.
    #[default]
    ThroughSkin,
    /// Rebuilt every frame from the skinned mesh, over the box of every pose.
    Rebuilt,
}

/// The time the shape stiffnesses of [`DynamicsParams`] are given for, seconds: 1/120 s,
/// the default substep.
pub const STIFFNESS_INTERVAL: f32 = 1.0 / 120.0;

/// How much longer than [`DynamicsParams::max_substep`] a substep may be, a fraction:
/// frame times are `f32` seconds, so a frame of 1/60 s measured as a difference of two
/// times is up to 0.4% longer or shorter at 600 s, and without slack about one frame in
/// five of 1/60 s took three substeps of 1/120 s instead of two. The slack covers
/// `f32` times up to 2 048 s (34 minutes); past that a time's rounding alone is over 1%
/// of a 1/60 s frame, and callers should restart their clock.
pub const SUBSTEP_SLACK: f32 = 0.01;

/// How many units in the last place of a 32-bit position the velocity change of one
/// substep must be at least (see [`DynamicsParams::min_substep`]): 4, so that rounding
/// takes at most an eighth of it.
pub const SUBSTEP_ULPS: f32 = 4.0;

/// The most colliders a simulation takes.
pub const MAX_COLLIDERS: usize = 16;

/// A body strands cannot enter: the points within `radius` of `center`, or of the
/// segment from `center` to `end` (a capsule) when `end` is given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Collider {
    /// The sphere's centre, or one end of the capsule's axis.
    pub center: Vec3,
    /// The radius (> 0).
    pub radius: f32,
    /// The other end of the capsule's axis (none: a sphere).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<Vec3>,
}

impl Collider {
    /// A sphere.
    pub fn sphere(center: Vec3, radius: f32) -> Self {
        Self {
            center,
            radius,
            end: None,
        }
    }

    /// A capsule from `a` to `b`.
    pub fn capsule(a: Vec3, b: Vec3, radius: f32) -> Self {
        Self {
            center: a,
            radius,
            end: Some(b),
        }
    }

    /// The ends of the axis (equal for a sphere).
    pub fn axis(&self) -> (Vec3, Vec3) {
        (self.center, self.end.unwrap_or(self.center))
    }

    /// How far `p` is inside the collider (negative outside).
    pub fn depth(&self, p: Vec3) -> f32 {
        let (a, b) = self.axis();
        let axis = b - a;
        let len2 = axis.length_squared();
        let s = if len2 > 0.0 {
            ((p - a).dot(axis) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.radius - p.distance(a + axis * s)
    }

    /// The collider moved by `f` (a rigid motion).
    pub fn moved(&self, f: impl Fn(Vec3) -> Vec3) -> Self {
        Self {
            center: f(self.center),
            radius: self.radius,
            end: self.end.map(f),
        }
    }

    /// Checks the collider; the error names it as `name`.
    pub fn validate(&self, name: &str) -> Result<(), ParamError> {
        let (a, b) = self.axis();
        if !(a.is_finite() && b.is_finite())
            || a.abs().max_element() > crate::MAX_EXTENT
            || b.abs().max_element() > crate::MAX_EXTENT
        {
            return Err(ParamError::new(
                name,
                self,
                &format!(
                    "its centre and end must be finite and at most {:e} in magnitude",
                    crate::MAX_EXTENT
                ),
            ));
        }
        extent(&format!("{name}.radius"), self.radius)
    }
}

/// A rigid motion of the mesh over time (and of the colliders with it): a turn about
/// the vertical axis through `pivot` and a nod about the horizontal x axis, each a
/// sine of its amplitude and frequency.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeshMotion {
    /// The point the mesh turns about.
    pub pivot: Vec3,
    /// Amplitude of the turn about the vertical axis, radians.
    pub turn: f32,
    /// Turns per second.
    pub turn_frequency: f32,
    /// Amplitude of the nod about the x axis, radians.
    pub nod: f32,
    /// Nods per second.
    pub nod_frequency: f32,
}

impl Default for MeshMotion {
    fn default() -> Self {
        Self {
            pivot: Vec3::ZERO,
            turn: 1.0,
            turn_frequency: 0.35,
            nod: 0.35,
            nod_frequency: 0.6,
        }
    }
}

impl MeshMotion {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        finite_vec("motion.pivot", self.pivot)?;
        for (name, v) in [
            ("motion.turn", self.turn),
            ("motion.turn_frequency", self.turn_frequency),
            ("motion.nod", self.nod),
            ("motion.nod_frequency", self.nod_frequency),
        ] {
            non_negative(name, v)?;
            if v > 1000.0 {
                return Err(ParamError::new(name, v, "must be in [0, 1000]"));
            }
        }
        Ok(())
    }

    /// The rotation at time `t` (seconds): the turn after the nod.
    pub fn rotation(&self, t: f32) -> glam::Quat {
        let tau = std::f32::consts::TAU;
        glam::Quat::from_rotation_y(self.turn * (tau * self.turn_frequency * t).sin())
            * glam::Quat::from_rotation_x(self.nod * (tau * self.nod_frequency * t).sin())
    }

    /// The motion at time `t` as a matrix (world from rest): the rotation about the
    /// pivot.
    pub fn matrix(&self, t: f32) -> glam::Mat4 {
        glam::Mat4::from_translation(self.pivot)
            * glam::Mat4::from_quat(self.rotation(t))
            * glam::Mat4::from_translation(-self.pivot)
    }

    /// Where the point `p` of the mesh at rest is at time `t`.
    pub fn point(&self, p: Vec3, t: f32) -> Vec3 {
        self.pivot + self.rotation(t) * (p - self.pivot)
    }

    /// `mesh` at time `t`: positions turned about the pivot, normals turned.
    pub fn apply(&self, mesh: &crate::Mesh, t: f32) -> crate::Mesh {
        let q = self.rotation(t);
        crate::Mesh {
            positions: mesh
                .positions
                .iter()
                .map(|&p| self.pivot + q * (p - self.pivot))
                .collect(),
            normals: mesh.normals.iter().map(|&n| q * n).collect(),
            indices: mesh.indices.clone(),
            uvs: mesh.uvs.clone(),
        }
    }

    /// A box holding `bounds` in every pose: the sphere around the pivot through the
    /// box's farthest corner.
    pub fn reach(&self, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
        let r = (lo - self.pivot)
            .abs()
            .max((hi - self.pivot).abs())
            .length();
        (self.pivot - Vec3::splat(r), self.pivot + Vec3::splat(r))
    }
}

impl Default for DynamicsParams {
    fn default() -> Self {
        Self {
            gravity: Vec3::new(0.0, -9.8, 0.0),
            wind_response: 4.0,
            damping: 2.0,
            local_stiffness: 0.3,
            global_stiffness: 0.2,
            global_range: 0.3,
            length_damping: 0.9,
            friction: 0.3,
            max_substep: 1.0 / 120.0,
            max_frame: 0.1,
            teleport_distance: 1.0,
            colliders: Vec::new(),
            sdf_resolution: 0,
            sdf_skinned: SkinnedSdf::ThroughSkin,
            sdf_standoff: 0.25,
        }
    }
}

/// The largest gravity or wind response accepted, scene units per second squared.
pub const MAX_ACCELERATION: f32 = 1.0e4;

impl DynamicsParams {
    /// Checks every field; the error names the first bad one (e.g. `dynamics.damping`).
    pub fn validate(&self) -> Result<(), ParamError> {
        finite_vec("dynamics.gravity", self.gravity)?;
        if self.gravity.length() > MAX_ACCELERATION {
            return Err(ParamError::new(
                "dynamics.gravity",
                self.gravity,
                &format!("must be at most {MAX_ACCELERATION} long"),
            ));
        }
        let bounded = |name: &str, v: f32, max: f32| {
            non_negative(name, v)?;
            if v > max {
                return Err(ParamError::new(name, v, &format!("must be in [0, {max}]")));
            }
            Ok(())
        };
        bounded(
            "dynamics.wind_response",
            self.wind_response,
            MAX_ACCELERATION,
        )?;
        bounded("dynamics.damping", self.damping, 1000.0)?;
        bounded("dynamics.local_stiffness", self.local_stiffness, 1.0)?;
        bounded("dynamics.global_stiffness", self.global_stiffness, 1.0)?;
        bounded("dynamics.length_damping", self.length_damping, 1.0)?;
        bounded("dynamics.friction", self.friction, 1.0)?;
        bounded("dynamics.sdf_standoff", self.sdf_standoff, MAX_SDF_STANDOFF)?;
        let in_range = |name: &str, v: f32, max: f32| {
            positive(name, v)?;
            if v > max {
                return Err(ParamError::new(name, v, &format!("must be in (0, {max}]")));
            }
            Ok(())
        };
        in_range("dynamics.global_range", self.global_range, 1.0)?;
        in_range("dynamics.max_substep", self.max_substep, 0.05)?;
        in_range("dynamics.max_frame", self.max_frame, 1.0)?;
        extent("dynamics.teleport_distance", self.teleport_distance)?;
        if self.colliders.len() > MAX_COLLIDERS {
            return Err(ParamError::new(
                "dynamics.colliders",
                self.colliders.len(),
                &format!("at most {MAX_COLLIDERS} colliders"),
            ));
        }
        for (i, c) in self.colliders.iter().enumerate() {
            c.validate(&format!("dynamics.colliders[{i}]"))?;
        }
        crate::check_sdf_resolution(self.sdf_resolution)
    }

    /// The steady acceleration the strands are under, scene units per second squared:
    /// gravity's length plus `wind_response` times the wind's mean force
    /// (`wind.strength`; gusts and turbulence come and go).
    pub fn steady_acceleration(&self, wind: &WindParams) -> f32 {
        self.gravity.length() + self.wind_response * wind.strength
    }

    /// The shortest `max_substep` that moves strands reaching `extent` scene units from
    /// the origin under [`DynamicsParams::steady_acceleration`] `a`:
    /// `sqrt(SUBSTEP_ULPS · extent · ε / a)`, `ε` being `f32::EPSILON`. Verlet
    /// integration keeps a vertex's velocity as the difference of two 32-bit positions,
    /// so a substep of `h` changes it by `a·h²`, which must be several units in the
    /// last place of the positions (`extent · ε`): below about half of one it rounds to
    /// nothing and the strands freeze in their rest pose (at `extent` 1 and gravity
    /// 9.8, any `h` under about 8e-5 s; the bound there is 2.2e-4 s). 0 when `a` is 0 (nothing pulls the strands).
    pub fn min_substep(&self, extent: f32, wind: &WindParams) -> f32 {
        let a = f64::from(self.steady_acceleration(wind));
        if !(a > 0.0 && extent.is_finite()) {
            return 0.0;
        }
        let ulp = f64::from(extent.abs()) * f64::from(f32::EPSILON);
        (f64::from(SUBSTEP_ULPS) * ulp / a).sqrt() as f32
    }

    /// Checks `max_substep` against [`DynamicsParams::min_substep`] for strands reaching
    /// `extent` scene units from the origin with `wind` (what [`DynamicsParams::validate`]
    /// cannot know); the error names `dynamics.max_substep` and its range there.
    pub fn validate_at_scale(&self, extent: f32, wind: &WindParams) -> Result<(), ParamError> {
        let min = self.min_substep(extent, wind);
        if self.max_substep < min {
            return Err(ParamError::new(
                "dynamics.max_substep",
                self.max_substep,
                &format!(
                    "must be in [{min:.3e}, 0.05] seconds for this scene: a shorter substep \
                     changes a strand's velocity by less than {SUBSTEP_ULPS} units in the last \
                     place of 32-bit positions {extent} units from the origin under an \
                     acceleration of {} (gravity and the mean wind), and the strands freeze",
                    self.steady_acceleration(wind)
                ),
            ));
        }
        Ok(())
    }

    /// The substeps a frame of `dt` seconds takes, and their length: `dt` clamped to
    /// [0, `max_frame`], cut into `ceil(dt / (max_substep · (1 + SUBSTEP_SLACK)))` equal
    /// substeps (none for 0): a substep is at most 1% longer than `max_substep`.
    pub fn substeps(&self, dt: f32) -> (u32, f32) {
        let dt = if dt.is_finite() {
            dt.clamp(0.0, self.max_frame)
        } else {
            0.0
        };
        let longest = self.max_substep * (1.0 + SUBSTEP_SLACK);
        let count = (dt / longest).ceil().max(0.0) as u32;
        if count == 0 {
            (0, 0.0)
        } else {
            (count, dt / count as f32)
        }
    }

    /// The fraction of the way to its target a substep of `h` seconds takes for a
    /// `stiffness` given per [`STIFFNESS_INTERVAL`]: `1 - (1 - stiffness)^(h / interval)`,
    /// so that the substeps covering one interval together leave `1 - stiffness` of the
    /// way, as one substep of the interval does. `stiffness` is clamped to [0, 1]; a
    /// substep of 0 s (or not finite) takes `stiffness` itself.
    pub fn stiffness_per_substep(stiffness: f32, h: f32) -> f32 {
        let s = if stiffness.is_finite() {
            stiffness.clamp(0.0, 1.0)
        } else {
            0.0
        };
        if !(h.is_finite() && h > 0.0) || s == 1.0 {
            return s;
        }
        let ratio = f64::from(h) / f64::from(STIFFNESS_INTERVAL);
        // 1 - (1 - s)^ratio, exact to f32 at ratio 1 (the default substep).
        (-(ratio * (-f64::from(s)).ln_1p()).exp_m1()) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stiffness_per_substep_composes_to_the_interval() {
        for s in [0.0f32, 0.05, 0.2, 0.3, 0.77, 0.999, 1.0] {
            // One substep of the interval takes the stiffness itself, exactly.
            assert_eq!(
                DynamicsParams::stiffness_per_substep(s, STIFFNESS_INTERVAL),
                s
            );
            assert_eq!(
                DynamicsParams::stiffness_per_substep(s, (1.0f32 / 60.0) / 2.0),
                s
            );
            // n substeps of interval / n leave what one substep of the interval leaves.
            for n in [2u32, 3, 4, 8, 40] {
                let h = STIFFNESS_INTERVAL / n as f32;
                let per = DynamicsParams::stiffness_per_substep(s, h);
                assert!((0.0..=s).contains(&per), "{s} {n}: {per}");
                let left = (1.0 - f64::from(per)).powi(n as i32);
                assert!(
                    (left - (1.0 - f64::from(s))).abs() < 1e-6,
                    "{s} in {n} substeps leaves {left}"
                );
            }
            // A longer substep pulls farther, never past the target.
            let long = DynamicsParams::stiffness_per_substep(s, 0.05);
            assert!((s..=1.0).contains(&long), "{s}: {long}");
        }
        assert_eq!(DynamicsParams::stiffness_per_substep(0.3, 0.0), 0.3);
        assert_eq!(DynamicsParams::stiffness_per_substep(f32::NAN, 0.01), 0.0);
        assert_eq!(DynamicsParams::stiffness_per_substep(0.3, f32::NAN), 0.3);
    }

    #[test]
    fn defaults_are_valid() {
        GrowthParams::default().validate().unwrap();
        WindParams::default().validate().unwrap();
        DynamicsParams::default().validate().unwrap();
        RootParams::default().validate(3).unwrap();
    }

    #[test]
    fn frames_are_cut_into_substeps_no_longer_than_the_cap() {
        let d = DynamicsParams::default();
        assert_eq!(d.substeps(0.0), (0, 0.0));
        assert_eq!(d.substeps(-1.0), (0, 0.0));
        assert_eq!(d.substeps(f32::NAN), (0, 0.0));
        let (n, h) = d.substeps(0.001);
        assert_eq!(n, 1);
        assert!((h - 0.001).abs() < 1e-9);
        // 100 ms at 1/120 s: 12 substeps; 5 s is clamped to max_frame.
        let (n, h) = d.substeps(0.1);
        assert_eq!(n, 12);
        assert!(h <= d.max_substep + 1e-9);
        assert_eq!(d.substeps(5.0), d.substeps(d.max_frame));
    }

    #[test]
    fn frames_of_a_steady_rate_take_the_same_substeps_for_ten_minutes() {
        let d = DynamicsParams::default();
        // Frame times as a caller computes them: f32 seconds from a frame counter.
        for (fps, want) in [(60.0, 2), (120.0, 1), (50.0, 3), (30.0, 4), (144.0, 1)] {
            let mut counts = std::collections::BTreeMap::new();
            for frame in 1..=(600.0 * fps) as u32 {
                let t = |f: u32| (f64::from(f) / fps) as f32;
                let (n, h) = d.substeps(t(frame) - t(frame - 1));
                assert!(h <= d.max_substep * (1.0 + SUBSTEP_SLACK), "{fps} fps: {h}");
                *counts.entry(n).or_insert(0u32) += 1;
            }
            assert_eq!(
                counts.keys().copied().collect::<Vec<_>>(),
                [want],
                "{fps} fps: {counts:?}"
            );
        }
    }

    #[test]
    fn bad_values_name_the_parameter() {
        let g = GrowthParams {
            length: f32::NAN,
            ..Default::default()
        };
        assert_eq!(g.validate().unwrap_err().name, "growth.length");
        let g = GrowthParams {
            segments: 0,
            ..Default::default()
        };
        assert_eq!(g.validate().unwrap_err().name, "growth.segments");
        let w = WindParams {
            strength: -1.0,
            ..Default::default()
        };
        assert_eq!(w.validate().unwrap_err().name, "wind.strength");
        let d = DynamicsParams {
            damping: f32::NAN,
            ..Default::default()
        };
        assert_eq!(d.validate().unwrap_err().name, "dynamics.damping");
        let d = DynamicsParams {
            max_substep: 0.0,
            ..Default::default()
        };
        assert_eq!(d.validate().unwrap_err().name, "dynamics.max_substep");
        let g = GrowthParams {
            opacity: 1.5,
            ..Default::default()
        };
        assert_eq!(g.validate().unwrap_err().name, "growth.opacity");
        let v = VoxelParams {
            fixed_point_bits: 30,
            ..Default::default()
        };
        assert_eq!(v.validate().unwrap_err().name, "shadow.fixed_point_bits");
        for bias in [-0.5, 8.5, 1e30, f32::NAN] {
            let v = VoxelParams {
                bias_voxels: bias,
                ..Default::default()
            };
            assert_eq!(
                v.validate().unwrap_err().name,
                "shadow.bias_voxels",
                "{bias}"
            );
        }
        let r = RootParams {
            density: Some(vec![1.0, -1.0, 1.0]),
            ..Default::default()
        };
        assert_eq!(r.validate(3).unwrap_err().name, "roots.density[1]");
    }
}

/// Everything stage 1 needs: where strands grow, how, and the wind.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HairParams {
    /// Root placement.
    pub roots: RootParams,
    /// Strand shape.
    pub growth: GrowthParams,
    /// Wind.
    pub wind: WindParams,
    /// Level of detail: how many strands and segments the hair's size on screen needs.
    pub lod: crate::LodParams,
}

impl HairParams {
    /// Validates every part against a mesh with `vertex_count` vertices.
    pub fn validate(&self, vertex_count: usize) -> Result<(), ParamError> {
        self.roots.validate(vertex_count)?;
        self.growth.validate()?;
        self.roots.validate_with(&self.growth)?;
        self.roots
            .validate_maps(self.growth.regions.len() + 1, None)?;
        self.wind.validate()?;
        self.lod.validate()
    }
}

/// The Lambertian albedo of a body of colour `mesh_color` (`shade.mesh_color`, its BRDF
/// `ρ/π`): `π · mesh_color`, at most 1 per channel (a brighter Lambertian would make light
/// at every bounce). One definition for every renderer that carries the body's bounce: the
/// volume grid and the path tracer.
pub fn mesh_albedo(mesh_color: Vec3) -> Vec3 {
    (mesh_color * std::f32::consts::PI).min(Vec3::ONE)
}

/// How stage 3 draws, shades and composites the hair.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ShadeParams {
    /// Clear colour, linear RGB.
    pub background: Vec3,
    /// Colour of the opaque mesh (the body), linear RGB: its Lambertian BRDF `ρ/π` (the
    /// raster shades it `mesh_color · (ambient + Σ E max(n·l, 0))`). The light the body
    /// bounces into the hair (the volume grid, the path tracer of `pelage trace` and the
    /// lab) uses the albedo [`ShadeParams::mesh_albedo`], `π · mesh_color` at most 1 per
    /// channel: above `1/π` a channel is as white as a Lambertian can be.
    pub mesh_color: Vec3,
    /// Ambient light, a fraction of the base colour.
    pub ambient: f32,
    /// The hair shading model (Kajiya-Kay, Marschner analytic or from lookup tables,
    /// Sadeghi, Chiang) and its parameters; Chiang with dual scattering by default (the
    /// scattering lab measures it closest to the path tracer).
    pub model: crate::ShadingModel,
    /// Darkening at the root in [0, 1], a stand-in for self-shadowing until a shadow method is on.
    pub root_occlusion: f32,
    /// Ribbons are at least this many pixels wide (>= 0).
    pub min_pixels: f32,
    /// Samples per pixel of the opaque method: 1 or 4. The transparency methods
    /// composite per pixel and always draw 1 sample: the ribbons' coverage alpha does
    /// their anti-aliasing (see [`ShadeParams::samples`]).
    pub sample_count: u32,
    /// How the hair's fragments are composited (opaque, an OIT method, or the strand
    /// rasterizer, the default: the bench and the OIT lab measure it the fastest and at
    /// least as accurate as any other).
    pub transparency: crate::Transparency,
}

impl Default for ShadeParams {
    fn default() -> Self {
        Self {
            background: Vec3::new(0.04, 0.045, 0.055),
            mesh_color: Vec3::new(0.25, 0.16, 0.11),
            ambient: 0.18,
            model: crate::ShadingModel::default(),
            root_occlusion: 0.65,
            min_pixels: 0.7,
            sample_count: 4,
            transparency: crate::Transparency::default(),
        }
    }
}

impl ShadeParams {
    /// The body's Lambertian albedo for the light it bounces into the hair:
    /// [`mesh_albedo`] of `mesh_color`.
    pub fn mesh_albedo(&self) -> Vec3 {
        mesh_albedo(self.mesh_color)
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        color("shade.background", self.background)?;
        color("shade.mesh_color", self.mesh_color)?;
        non_negative("shade.ambient", self.ambient)?;
        if self.ambient > MAX_COLOR {
            return Err(ParamError::new(
                "shade.ambient",
                self.ambient,
                &format!("must be in [0, {MAX_COLOR:e}]"),
            ));
        }
        self.model.validate()?;
        non_negative("shade.root_occlusion", self.root_occlusion)?;
        if self.root_occlusion > 1.0 {
            return Err(ParamError::new(
                "shade.root_occlusion",
                self.root_occlusion,
                "must be in [0, 1]",
            ));
        }
        non_negative("shade.min_pixels", self.min_pixels)?;
        if self.sample_count != 1 && self.sample_count != 4 {
            return Err(ParamError::new(
                "shade.sample_count",
                self.sample_count,
                "must be 1 or 4",
            ));
        }
        self.transparency.validate()
    }

    /// Samples per pixel the targets need: `sample_count` for the opaque method, 1 for
    /// the transparency methods.
    pub fn samples(&self) -> u32 {
        match self.transparency {
            crate::Transparency::Opaque => self.sample_count,
            _ => 1,
        }
    }
}

/// How density is deposited into the voxel grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Splat {
    /// Each sample adds to the voxel it falls in.
    Nearest,
    /// Each sample spreads over the 8 nearest voxel centres.
    #[default]
    Trilinear,
}

/// Voxel shadows (seed 001): density splatted into a light-space grid fitted to the
/// hair every frame, summed along the light; the mesh casts its own shadow through a
/// shadow map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VoxelParams {
    /// Voxels per axis (x and y across the light, z along it), each in 2..=512.
    /// Ignored when `voxel_size` is set.
    pub resolution: [u32; 3],
    /// Target voxel edge in scene units (> 0); when set, the resolution is derived from
    /// it and the box the hair can reach (the same on every axis, since the light may
    /// turn), clamped to 2..=512.
    pub voxel_size: Option<f32>,
    /// Nearest or trilinear splatting.
    pub splat: Splat,
    /// The lookup reads this many voxels toward the light, in
    /// 0..=[`VoxelParams::MAX_BIAS_VOXELS`], so a strand does not shadow itself (more
    /// would skip most of the hair in front: a few voxels of bias leave a groom nearly
    /// unshadowed). Measured (pelage-shadow's tests): 1.5 keeps an isolated strand at
    /// T >= 0.99 when it lies at 45 degrees or more to the light; 1.0 is about 10% more
    /// accurate on a dense groom but lets strands within 75 degrees of the light shadow
    /// themselves by 1 to 4%.
    pub bias_voxels: f32,
    /// Fixed-point precision of the density grid: 2^bits units per unit of optical
    /// depth, in 8..=28. A column saturates (never wraps) at an optical depth of
    /// 2^(32 - bits): 65 536 at the default 16, where transmittance is e^-65536.
    pub fixed_point_bits: u32,
    /// Side of the mesh shadow map in texels (0 = the mesh casts no shadow).
    pub mesh_map_size: u32,
    /// PCF radius of the mesh shadow map: 0 = one tap, 1 = 3x3, 2 = 5x5.
    pub mesh_pcf_radius: u32,
}

impl Default for VoxelParams {
    fn default() -> Self {
        Self {
            resolution: [128, 128, 128],
            voxel_size: None,
            splat: Splat::Trilinear,
            bias_voxels: 1.5,
            fixed_point_bits: 16,
            mesh_map_size: 1024,
            mesh_pcf_radius: 1,
        }
    }
}

impl VoxelParams {
    /// The largest `bias_voxels` accepted.
    pub const MAX_BIAS_VOXELS: f32 = 8.0;

    /// The grid resolution for hair that stays inside the world box `reach`: `resolution`,
    /// or the one `voxel_size` gives over the box's diagonal.
    pub fn resolution_for(&self, reach: (Vec3, Vec3)) -> [u32; 3] {
        match self.voxel_size {
            Some(size) if size > 0.0 => {
                let diagonal = (reach.1 - reach.0).length();
                let n = (diagonal / size).ceil();
                let n = if n.is_finite() {
                    n.clamp(2.0, 512.0) as u32
                } else {
                    512
                };
                [n; 3]
            }
            _ => self.resolution,
        }
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        if let Some(r) = self.resolution.iter().find(|r| !(2..=512).contains(*r)) {
            return Err(ParamError::new(
                "shadow.resolution",
                r,
                "each axis must be in 2..=512",
            ));
        }
        if let Some(size) = self.voxel_size {
            positive("shadow.voxel_size", size)?;
        }
        non_negative("shadow.bias_voxels", self.bias_voxels)?;
        if self.bias_voxels > Self::MAX_BIAS_VOXELS {
            return Err(ParamError::new(
                "shadow.bias_voxels",
                self.bias_voxels,
                &format!("must be in 0..={} voxels", Self::MAX_BIAS_VOXELS),
            ));
        }
        if !(8..=28).contains(&self.fixed_point_bits) {
            return Err(ParamError::new(
                "shadow.fixed_point_bits",
                self.fixed_point_bits,
                "must be in 8..=28",
            ));
        }
        if self.mesh_map_size > 8192 {
            return Err(ParamError::new(
                "shadow.mesh_map_size",
                self.mesh_map_size,
                "must be at most 8192",
            ));
        }
        if self.mesh_pcf_radius > 2 {
            return Err(ParamError::new(
                "shadow.mesh_pcf_radius",
                self.mesh_pcf_radius,
                "must be 0, 1 or 2",
            ));
        }
        Ok(())
    }
}

/// Texel format of the deep opacity layers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpacityFormat {
    /// 8-bit unorm: accumulated opacity clamps at 1 (the seeds' format, and its failure).
    Unorm8,
    /// 16-bit float.
    #[default]
    Float16,
    /// 32-bit float.
    Float32,
}

/// How the deep opacity layers are spaced behind the front-most hair.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum LayerSpacing {
    /// Every layer `depth` scene units deep (the last one runs to the back of the hair).
    Linear {
        /// Depth of one layer, scene units (> 0).
        depth: f32,
    },
    /// Layer ends at these increasing fractions of the hair's depth along the light
    /// (seed 003: 0.05, 0.15, then the rest); the last layer runs to the back.
    Fractions {
        /// Increasing fractions in (0, 1], one per layer but the last.
        ends: Vec<f32>,
    },
}

/// A hair depth map seen from the light, shared by the map methods.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MapParams {
    /// Side of the map in texels, 16..=8192.
    pub size: u32,
    /// PCF radius: 0 = one texel, 1 = 3x3, 2 = 5x5 (shadow map and ADSM).
    pub pcf_radius: u32,
    /// Side of the mesh shadow map (0 = the mesh casts no shadow).
    pub mesh_map_size: u32,
}

impl Default for MapParams {
    fn default() -> Self {
        Self {
            size: 1024,
            pcf_radius: 1,
            mesh_map_size: 1024,
        }
    }
}

impl MapParams {
    fn validate(&self, method: &str) -> Result<(), ParamError> {
        if !(16..=8192).contains(&self.size) {
            return Err(ParamError::new(
                &format!("shadow.{method}.size"),
                self.size,
                "must be in 16..=8192",
            ));
        }
        if self.pcf_radius > 2 {
            return Err(ParamError::new(
                &format!("shadow.{method}.pcf_radius"),
                self.pcf_radius,
                "must be 0, 1 or 2",
            ));
        }
        if self.mesh_map_size > 8192 {
            return Err(ParamError::new(
                &format!("shadow.{method}.mesh_map_size"),
                self.mesh_map_size,
                "must be at most 8192",
            ));
        }
        Ok(())
    }
}

/// Deep opacity maps (Yuksel and Keyser 2008): the front-most hair depth from the
/// light, then layers of accumulated opacity behind it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DeepOpacityParams {
    /// The maps' size and the mesh map.
    pub map: MapParams,
    /// Opacity layers, 2..=8 (seed 000 used 3).
    pub layers: u32,
    /// Where the layers end.
    pub spacing: LayerSpacing,
    /// Texel format of the layers.
    pub format: OpacityFormat,
}

impl Default for DeepOpacityParams {
    fn default() -> Self {
        Self {
            map: MapParams::default(),
            layers: 3,
            spacing: LayerSpacing::Fractions {
                ends: vec![0.05, 0.15],
            },
            format: OpacityFormat::Float16,
        }
    }
}

/// A hair shadow map with percentage-closer filtering: hair treated as opaque.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ShadowMapParams {
    /// The map's size, its PCF kernel and the mesh map.
    pub map: MapParams,
    /// Depth bias, scene units (>= 0): a point this close behind the front-most hair is lit.
    pub bias: f32,
}

impl Default for ShadowMapParams {
    fn default() -> Self {
        Self {
            map: MapParams::default(),
            bias: 0.01,
        }
    }
}

/// Approximated deep shadow maps (TressFX): the number of fibres in front of a point is
/// its depth behind the front-most hair divided by a fibre spacing, T = (1 - opacity)^n.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdsmParams {
    /// The map's size, its PCF kernel and the mesh map.
    pub map: MapParams,
    /// Mean distance between fibres along the light, scene units (> 0).
    pub fiber_spacing: f32,
}

impl Default for AdsmParams {
    fn default() -> Self {
        Self {
            map: MapParams::default(),
            fiber_spacing: 0.02,
        }
    }
}

/// Which shadow method stage 2 runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "method", deny_unknown_fields)]
pub enum ShadowParams {
    /// No shadows.
    None,
    /// Voxel density with a prefix sum along the light.
    Voxel(VoxelParams),
    /// Deep opacity maps (`deep_opacity`, or `dom` as the command line once said).
    #[serde(alias = "dom")]
    DeepOpacity(DeepOpacityParams),
    /// Hair shadow map with PCF (`shadow_map`, or `map`).
    #[serde(alias = "map")]
    ShadowMap(ShadowMapParams),
    /// Approximated deep shadow maps.
    Adsm(AdsmParams),
}

impl Default for ShadowParams {
    /// Voxel shadows at their defaults.
    fn default() -> Self {
        Self::Voxel(VoxelParams::default())
    }
}

/// A power of two at least `v`, within `[lo, hi]` (`hi` for anything not finite).
fn power_of_two_in(v: f32, lo: u32, hi: u32) -> u32 {
    if !v.is_finite() {
        return hi;
    }
    (v.ceil().max(1.0).min(hi as f32) as u32)
        .next_power_of_two()
        .clamp(lo, hi)
}

impl ShadowParams {
    /// This method sized down to hair whose bounding box spans `extent_pixels` on
    /// screen: shadow detail finer than the picture can show is not modelled, and the
    /// configured resolution stays the most that is used. The voxel grid gets one cell
    /// per 4 pixels of the hair's extent (a voxel shadow is a smooth, trilinearly read
    /// volume: its detail is the hair volume's, not a strand's), a power of two of at
    /// least 16 per axis; the hair maps one texel per pixel (at least 128), the mesh's
    /// shadow map two (at least 256). The light-space grid and maps are fitted to the
    /// hair every frame, so these counts span the hair in the light's view too. A voxel
    /// grid given by `voxel_size` is left alone.
    pub fn sized_for(&self, extent_pixels: f32) -> Self {
        let down = |configured: u32, wanted: f32, lo: u32| {
            power_of_two_in(wanted, lo, configured.max(lo)).min(configured)
        };
        let mut out = self.clone();
        match &mut out {
            Self::None => {}
            Self::Voxel(v) => {
                if v.voxel_size.is_none() {
                    v.resolution = v.resolution.map(|r| down(r, extent_pixels / 4.0, 16));
                }
                v.mesh_map_size = down(v.mesh_map_size, extent_pixels * 2.0, 256);
            }
            Self::DeepOpacity(DeepOpacityParams { map, .. })
            | Self::ShadowMap(ShadowMapParams { map, .. })
            | Self::Adsm(AdsmParams { map, .. }) => {
                map.size = down(map.size, extent_pixels, 128);
                map.mesh_map_size = down(map.mesh_map_size, extent_pixels * 2.0, 256);
            }
        }
        out
    }

    /// Checks the chosen method's parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Self::None => Ok(()),
            Self::Voxel(v) => v.validate(),
            Self::DeepOpacity(d) => {
                d.map.validate("deep_opacity")?;
                if !(2..=8).contains(&d.layers) {
                    return Err(ParamError::new(
                        "shadow.deep_opacity.layers",
                        d.layers,
                        "must be in 2..=8",
                    ));
                }
                match &d.spacing {
                    LayerSpacing::Linear { depth } => {
                        positive("shadow.deep_opacity.spacing.depth", *depth)
                    }
                    LayerSpacing::Fractions { ends } => {
                        if ends.len() + 1 != d.layers as usize {
                            return Err(ParamError::new(
                                "shadow.deep_opacity.spacing.ends",
                                ends,
                                &format!("needs layers - 1 = {} values", d.layers - 1),
                            ));
                        }
                        let increasing = ends.windows(2).all(|w| w[0] < w[1]);
                        if !increasing || ends.iter().any(|e| !(*e > 0.0 && *e <= 1.0)) {
                            return Err(ParamError::new(
                                "shadow.deep_opacity.spacing.ends",
                                ends,
                                "must increase strictly within (0, 1]",
                            ));
                        }
                        Ok(())
                    }
                }
            }
            Self::ShadowMap(m) => {
                m.map.validate("shadow_map")?;
                non_negative("shadow.shadow_map.bias", m.bias)
            }
            Self::Adsm(a) => {
                a.map.validate("adsm")?;
                positive("shadow.adsm.fiber_spacing", a.fiber_spacing)
            }
        }
    }
}
