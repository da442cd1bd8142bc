//! The path tracer (`pelage_reference::path_tracer`) on the strands a [`Renderer`] grew,
//! and the image measures `pelage trace`, `pelage compare` and the scattering lab share.
//!
//! [`TracedScene::from_renderer`] reads the renderer's last frame back from the GPU: the
//! strand vertices (its full-detail layout), each strand's root width and colour, and the
//! mesh as the frame posed it. The hair is Chiang fibres: the scene's own parameters for
//! the Chiang model (a σ_a per strand from its colour when the absorption is
//! colour-driven), Chiang's defaults with each strand's colour for any other model. The
//! mesh is a Lambertian of albedo `π · shade.mesh_color`, at most 1 per channel
//! (`pelage_scene::mesh_albedo`: the renderer's mesh shading and its volume grid, see the
//! path tracer's module docs).

use glam::{DVec3, Vec3, Vec4};
use image::RgbaImage;
use pelage::gpu::{Gpu, GpuError, read_buffer};
use pelage::scene::{Absorption, ChiangParams, ShadingModel};
use pelage::{Renderer, scene::Scene};
use pelage_reference::chiang::ChiangFibre;
use pelage_reference::flip::{FlipMap, LinearImage};
use pelage_reference::oit::linear_to_srgb8;
use pelage_reference::path_tracer::{HairScene, PathTraceError, PathTracer};
use pelage_reference::transmittance::{Segment, segments_from_strands};

/// What reading a renderer's frame back for the path tracer can fail with.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// Building or rendering the scene failed.
    #[error(transparent)]
    Render(#[from] pelage::Error),
    /// Reading a buffer back failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The path tracer refused the scene or the settings.
    #[error(transparent)]
    PathTrace(#[from] PathTraceError),
    /// The renderer's frame is not one the path tracer can take (the message says why).
    #[error("{0}")]
    Frame(String),
}

/// Chiang's fibre with `params`' roughness, tilt and index, and absorption `sigma_a`.
pub fn chiang_fibre(params: &ChiangParams, sigma_a: Vec3) -> ChiangFibre {
    ChiangFibre {
        sigma_a: sigma_a.as_dvec3(),
        beta_m: f64::from(params.beta_m),
        beta_n: f64::from(params.beta_n),
        alpha: f64::from(params.alpha_deg).to_radians(),
        eta: f64::from(params.eta),
    }
}

/// A renderer's frame as the path tracer's scene: the owned data a [`HairScene`] borrows.
#[derive(Clone, Debug)]
pub struct TracedScene {
    /// Strand segments (the real cylinders, tapered as the renderer's ribbons).
    pub segments: Vec<Segment>,
    /// Strands read back.
    pub strands: usize,
    /// The strand vertices as stage 1 left them (`strands × (segments + 1)`, w the strand
    /// parameter): what the volume grid's CPU mirror splats.
    pub vertices: Vec<Vec4>,
    /// Segments per strand.
    pub segments_per_strand: u32,
    /// Root width of each strand.
    pub widths: Vec<f32>,
    /// Colour of each strand.
    pub colors: Vec<Vec3>,
    /// Tip width as a fraction of the root width.
    pub tip_width: f32,
    /// The fibre (its σ_a is the hair colour's when absorption is per strand).
    pub fibre: ChiangFibre,
    /// σ_a per strand, for colour-driven absorption.
    pub strand_sigma_a: Option<Vec<DVec3>>,
    /// Mesh positions as the frame posed them.
    pub mesh_positions: Vec<Vec3>,
    /// Mesh normals as the frame posed them (one per position).
    pub mesh_normals: Vec<Vec3>,
    /// Mesh triangles.
    pub mesh_triangles: Vec<[u32; 3]>,
    /// The mesh's albedo, `pelage_scene::mesh_albedo` of `shade.mesh_color` (`π ·
    /// mesh_color`, at most 1 per channel, as the volume grid takes it).
    pub mesh_albedo: DVec3,
    /// Set when `shade.mesh_color` is above `1/π` in a channel: the albedo is capped at 1.
    pub mesh_note: Option<String>,
    /// The scene's lights.
    pub lights: Vec<pelage::scene::Light>,
    /// Set when the hair's model is not Chiang's: what the path tracer traces instead.
    pub model_note: Option<String>,
}

impl TracedScene {
    /// Reads back the frame `renderer` last rendered of `scene` (waits for the GPU). The
    /// frame must be at full detail (level of detail off): the roots' widths are read
    /// from the CPU copy, which a level of detail would have widened.
    pub fn from_renderer(
        scene: &Scene,
        renderer: &Renderer,
        gpu: &Gpu,
    ) -> Result<Self, TraceError> {
        let strands = renderer.frame().strands();
        let buffers = strands.buffers();
        let frame = strands
            .frame()
            .ok_or_else(|| TraceError::Frame("the renderer has not grown a frame yet".into()))?;
        let roots = strands.roots();
        let layout = frame.layout;
        if layout.strands as usize != roots.len() || layout.segments != buffers.segments {
            return Err(TraceError::Frame(format!(
                "the frame holds {} strands of {} segments, not all {} of {} (a level of \
                 detail): the path tracer needs the hair at full detail",
                layout.strands,
                layout.segments,
                roots.len(),
                buffers.segments
            )));
        }
        let bytes = read_buffer(gpu, &buffers.vertices)?;
        let floats: &[f32] = bytemuck::try_cast_slice(&bytes)
            .map_err(|e| TraceError::Frame(format!("strand vertices: {e}")))?;
        let count = usize::try_from(layout.vertices()).unwrap_or(usize::MAX);
        let vertices: Vec<Vec4> = floats
            .chunks_exact(4)
            .take(count)
            .map(Vec4::from_slice)
            .collect();
        if vertices.len() != count {
            return Err(TraceError::Frame(format!(
                "the strand buffer holds {} vertices, the frame {count}",
                vertices.len()
            )));
        }
        let per = (layout.segments + 1) as usize;
        let widths: Vec<f32> = roots.iter().map(|r| r.width).collect();
        let growth = &strands.params().growth;
        let segments = segments_from_strands(&vertices, per, &widths, growth.tip_width, 1.0);
        let colors: Vec<Vec3> = roots.iter().map(|r| r.color).collect();
        let (params, model_note) = match &scene.shade.model {
            ShadingModel::Chiang(p) => (p.clone(), None),
            other => (
                ChiangParams::default(),
                Some(format!(
                    "the hair's model is {}: the path tracer traces Chiang fibres (pbrt's \
                     defaults) of each strand's colour instead",
                    other.name()
                )),
            ),
        };
        let (fibre, strand_sigma_a) = match params.absorption() {
            Absorption::Fixed(sigma) => (chiang_fibre(&params, sigma), None),
            Absorption::FromColor => (
                chiang_fibre(&params, params.sigma_a_for(growth.color)),
                Some(
                    colors
                        .iter()
                        .map(|c| params.sigma_a_for(*c).as_dvec3())
                        .collect(),
                ),
            ),
        };
        let mesh = renderer.frame().mesh_buffers();
        let read_vec3 = |buffer: &wgpu::Buffer, what: &str| -> Result<Vec<Vec3>, TraceError> {
            let bytes = read_buffer(gpu, buffer)?;
            let floats: &[f32] = bytemuck::try_cast_slice(&bytes)
                .map_err(|e| TraceError::Frame(format!("mesh {what}: {e}")))?;
            Ok(floats
                .chunks_exact(3)
                .take(mesh.vertex_count as usize)
                .map(Vec3::from_slice)
                .collect())
        };
        let mesh_positions = read_vec3(&mesh.positions, "positions")?;
        let mesh_normals = read_vec3(&mesh.normals, "normals")?;
        let indices = read_buffer(gpu, &mesh.indices)?;
        let indices: &[u32] = bytemuck::try_cast_slice(&indices)
            .map_err(|e| TraceError::Frame(format!("mesh indices: {e}")))?;
        let mesh_triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .take(mesh.triangle_count as usize)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        Ok(Self {
            segments,
            strands: roots.len(),
            vertices,
            segments_per_strand: layout.segments,
            widths,
            colors,
            tip_width: growth.tip_width,
            fibre,
            strand_sigma_a,
            mesh_positions,
            mesh_normals,
            mesh_triangles,
            mesh_albedo: scene.shade.mesh_albedo().as_dvec3(),
            mesh_note: (scene.shade.mesh_color.max_element() > std::f32::consts::FRAC_1_PI).then(
                || {
                    format!(
                        "shade.mesh_color = {} is above 1/π = 0.318 in a channel: the body's \
                         albedo π·mesh_color is capped at 1 there (the volume grid does the \
                         same), {}",
                        scene.shade.mesh_color,
                        scene.shade.mesh_albedo()
                    )
                },
            ),
            lights: scene.lights.clone(),
            model_note,
        })
    }

    /// The path tracer of this scene (checks it and builds its BVHs).
    pub fn tracer(&self) -> Result<PathTracer, PathTraceError> {
        PathTracer::new(&HairScene {
            segments: &self.segments,
            fibre: self.fibre,
            strand_sigma_a: self.strand_sigma_a.as_deref(),
            mesh_positions: &self.mesh_positions,
            mesh_triangles: &self.mesh_triangles,
            mesh_albedo: self.mesh_albedo,
            lights: &self.lights,
        })
    }
}

/// Whether a mask value marks a hair pixel (at least half its samples hit hair first).
pub fn is_hair(mask: f32) -> bool {
    mask >= 0.5
}

/// Mean of `map` over the pixels where `mask` is hair (NaN when there are none).
pub fn masked_mean(map: &FlipMap, mask: &[f32]) -> f64 {
    let (sum, n) = map
        .values
        .iter()
        .zip(mask)
        .filter(|(_, m)| is_hair(**m))
        .fold((0.0f64, 0usize), |(s, n), (v, _)| {
            (s + f64::from(*v), n + 1)
        });
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// Rec. 709 luminance of a linear RGB pixel.
pub fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Mean linear luminance of `image` over the mask's hair pixels (NaN when there are none).
pub fn hair_luminance(image: &LinearImage, mask: &[f32]) -> f64 {
    let (sum, n) = image
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, m)| is_hair(**m))
        .fold((0.0f64, 0usize), |(s, n), (p, _)| {
            (s + luminance(*p), n + 1)
        });
    if n == 0 { f64::NAN } else { sum / n as f64 }
}

/// Mean linear colour of `image` over the mask's hair pixels (NaN when there are none).
pub fn hair_color(image: &LinearImage, mask: &[f32]) -> DVec3 {
    let (sum, n) = image
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, m)| is_hair(**m))
        .fold((DVec3::ZERO, 0usize), |(s, n), (p, _)| {
            (s + Vec3::from_array(*p).as_dvec3(), n + 1)
        });
    if n == 0 { DVec3::NAN } else { sum / n as f64 }
}

/// A FLIP map as a heat image (black, red, yellow, white at 1).
pub fn heat(map: &FlipMap) -> Result<RgbaImage, TraceError> {
    let mut out = RgbaImage::new(map.width, map.height);
    if out.pixels().len() != map.values.len() {
        return Err(TraceError::Frame(format!(
            "a FLIP map of {}x{} holds {} values",
            map.width,
            map.height,
            map.values.len()
        )));
    }
    for (px, v) in out.pixels_mut().zip(&map.values) {
        let v = v.clamp(0.0, 1.0);
        let r = (3.0 * v).min(1.0);
        let g = (3.0 * v - 1.0).clamp(0.0, 1.0);
        let b = (3.0 * v - 2.0).clamp(0.0, 1.0);
        *px = image::Rgba([
            linear_to_srgb8(r),
            linear_to_srgb8(g),
            linear_to_srgb8(b),
            255,
        ]);
    }
    Ok(out)
}
