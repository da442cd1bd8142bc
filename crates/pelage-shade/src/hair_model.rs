//! The hair shading model on the GPU: [`HairModel`] puts the chosen model's parameters
//! (and Marschner's lookup tables when asked) behind the contract `shade/hair_model.wgsl`.

use pelage_gpu::{BoundResource, Gpu, ShaderBinding, UniformBuffer};
use pelage_scene::{MultipleScattering, ShadingModel};

use crate::models::{
    ChiangTables, KajiyaKayUniforms, MarschnerLut, MarschnerUniforms, SadeghiUniforms,
};
use crate::volume::VolumeField;

/// Resolution of Marschner's lookup tables when [`ShadingModel::Marschner`] has `lut`
/// set: 128 texels per axis, where `tests/models.rs` measures the tables within 0.43% of
/// the analytic model at the 99th percentile (circular fibre; 1.2% for an elliptical one).
pub const LUT_RESOLUTION: u32 = 128;

/// The contract every hair pass imports (`hair_radiance`).
pub const CONTRACT: &str = "shade/hair_model.wgsl";

/// The shading model of stage 3: a uniform with its parameters, Marschner's tables when
/// it is evaluated through them, and the [`ShaderBinding`] that redirects
/// the contract `shade/hair_model.wgsl` to the model's WGSL with its resources at `@group(2)`.
#[derive(Debug)]
pub struct HairModel {
    binding: ShaderBinding,
    lut: Option<MarschnerLut>,
    chiang: Option<ChiangTables>,
    volume: Option<VolumeField>,
    bytes: u64,
    /// The model and parameters in use (see [`HairModel::update`]).
    params: ShadingModel,
}

impl HairModel {
    /// Uploads `model`'s parameters; for Marschner through tables and for Chiang, builds
    /// the tables (one compute submission, waited for, here and never in the frame).
    pub fn new(gpu: &Gpu, model: &ShadingModel) -> crate::Result<Self> {
        model.validate()?;
        let mut chiang = None;
        let mut volume = None;
        let (module, resources, lut) = match model {
            ShadingModel::KajiyaKay(p) => {
                let u = UniformBuffer::new(
                    gpu,
                    "pelage kajiya-kay",
                    &KajiyaKayUniforms::from_params(p),
                )?;
                (
                    CONTRACT,
                    vec![BoundResource::Uniform(u.buffer.clone())],
                    None,
                )
            }
            ShadingModel::Marschner { params, lut: false } => {
                let u = UniformBuffer::new(
                    gpu,
                    "pelage marschner",
                    &MarschnerUniforms::from_params(params),
                )?;
                (
                    "shade/models/marschner_model.wgsl",
                    vec![BoundResource::Uniform(u.buffer.clone())],
                    None,
                )
            }
            ShadingModel::Marschner { params, lut: true } => {
                let lut = MarschnerLut::new(gpu, params, LUT_RESOLUTION)?;
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                lut.encode(&mut encoder);
                gpu.submit_and_wait([encoder.finish()])?;
                // marschner_lut_lookup.wgsl (0..=3) and marschner_lut_model.wgsl (4).
                let resources = vec![
                    BoundResource::Storage(lut.m_buffer().clone()),
                    BoundResource::Storage(lut.n0_buffer().clone()),
                    BoundResource::Storage(lut.n1_buffer().clone()),
                    BoundResource::Uniform(lut.info_buffer().clone()),
                    BoundResource::Uniform(lut.model_buffer().clone()),
                ];
                (
                    "shade/models/marschner_lut_model.wgsl",
                    resources,
                    Some(lut),
                )
            }
            ShadingModel::Sadeghi(p) => {
                let u =
                    UniformBuffer::new(gpu, "pelage sadeghi", &SadeghiUniforms::from_params(p))?;
                (
                    "shade/models/sadeghi_model.wgsl",
                    vec![BoundResource::Uniform(u.buffer.clone())],
                    None,
                )
            }
            ShadingModel::Chiang(p) => {
                let tables = ChiangTables::new(gpu, p)?;
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                tables.encode(&mut encoder);
                gpu.submit_and_wait([encoder.finish()])?;
                // chiang.wgsl: the model uniform, then the two tables; with a method
                // that reads the grid, its uniform and fluence
                // (chiang_volume_common_model.wgsl).
                let mut resources = vec![
                    BoundResource::Uniform(tables.model_buffer().clone()),
                    BoundResource::Storage(tables.n_buffer().clone()),
                    BoundResource::Storage(tables.dual_buffer().clone()),
                ];
                if p.multiple_scattering.uses_grid() {
                    let field = VolumeField::new(gpu, p)?;
                    resources.push(BoundResource::Uniform(field.uniform_buffer().clone()));
                    resources.push(BoundResource::Storage(field.fluence_buffer().clone()));
                    volume = Some(field);
                }
                chiang = Some(tables);
                (model_module(model), resources, None)
            }
        };
        let bytes = resources
            .iter()
            .map(|r| r.buffer().map_or(0, wgpu::Buffer::size))
            .sum();
        // The grid's fluence is the one frame resource a model reads (the tables are
        // written once at build).
        let reads = match volume {
            Some(_) => vec![crate::VOLUME_FLUENCE.to_string()],
            None => Vec::new(),
        };
        Ok(Self {
            binding: ShaderBinding {
                contract: CONTRACT,
                module,
                sources: &crate::SHADERS,
                group: 2,
                resources,
                reads,
            },
            lut,
            chiang,
            volume,
            bytes,
            params: model.clone(),
        })
    }

    /// Errors with [`ShadeError::NeedsRebuild`](crate::ShadeError::NeedsRebuild) when
    /// [`HairModel::update`] cannot take `model` in place: another kind of model (other
    /// WGSL, other resources), or a Marschner fibre from tables turning from circular to
    /// elliptical or back (another table layout). Bad values are a parameter error.
    pub fn check_update(&self, model: &ShadingModel) -> crate::Result<()> {
        model.validate()?;
        if model_module(model) != self.binding.module {
            return Err(crate::ShadeError::NeedsRebuild(format!(
                "shade.model ({} to {}: another shader)",
                self.params.name(),
                model.name()
            )));
        }
        if let (Some(field), ShadingModel::Chiang(p)) = (&self.volume, model) {
            let held = field.uniforms();
            if p.volume_grid != held.resolution {
                return Err(crate::ShadeError::NeedsRebuild(format!(
                    "shading.chiang.volume_grid ({} to {}: the grid's buffers)",
                    held.resolution, p.volume_grid
                )));
            }
            if p.volume_iterations != held.iterations {
                return Err(crate::ShadeError::NeedsRebuild(format!(
                    "shading.chiang.volume_iterations ({} to {}: the grid's passes)",
                    held.iterations, p.volume_iterations
                )));
            }
        }
        if let (Some(lut), ShadingModel::Marschner { params, .. }) = (&self.lut, model) {
            if MarschnerLut::slices_for(params, lut.resolution()) != lut.slices() {
                return Err(crate::ShadeError::NeedsRebuild(
                    "shading.marschner.eccentricity (a fibre turning from circular to elliptical \
                     or back changes the lookup tables' layout)"
                        .into(),
                ));
            }
        }
        Ok(())
    }

    /// Takes new parameters of the same kind of model in place (see
    /// [`HairModel::check_update`] for what is refused): rewrites the model's uniform and,
    /// when what they tabulate changed, fills Marschner's or Chiang's tables again (one
    /// compute submission, waited for). The result is what [`HairModel::new`] builds
    /// for `model`.
    pub fn update(&mut self, gpu: &Gpu, model: &ShadingModel) -> crate::Result<()> {
        self.check_update(model)?;
        if *model == self.params {
            return Ok(());
        }
        let first = || match self
            .binding
            .resources
            .first()
            .and_then(BoundResource::buffer)
        {
            Some(buffer) => Ok(buffer.clone()),
            None => Err(pelage_gpu::GpuError::Validation(
                "the shading model has no uniform buffer at binding 0".into(),
            )),
        };
        let queue = &gpu.queue;
        let mut tables = None;
        match model {
            ShadingModel::KajiyaKay(p) => pelage_gpu::write_storage(
                queue,
                "pelage kajiya-kay",
                &first()?,
                &KajiyaKayUniforms::from_params(p),
            )?,
            ShadingModel::Marschner { params, lut: false } => pelage_gpu::write_storage(
                queue,
                "pelage marschner",
                &first()?,
                &MarschnerUniforms::from_params(params),
            )?,
            ShadingModel::Marschner { params, lut: true } => {
                if let Some(lut) = &self.lut {
                    // The tables tabulate the parameters: fill them again.
                    lut.update(queue, params)?;
                    let mut encoder = gpu.device.create_command_encoder(&Default::default());
                    lut.encode(&mut encoder);
                    tables = Some(encoder);
                }
            }
            ShadingModel::Sadeghi(p) => pelage_gpu::write_storage(
                queue,
                "pelage sadeghi",
                &first()?,
                &SadeghiUniforms::from_params(p),
            )?,
            ShadingModel::Chiang(p) => {
                if let Some(chiang) = &mut self.chiang {
                    if chiang.update(queue, p)? {
                        let mut encoder = gpu.device.create_command_encoder(&Default::default());
                        chiang.encode(&mut encoder);
                        tables = Some(encoder);
                    }
                }
            }
        }
        if let Some(encoder) = tables {
            gpu.submit_and_wait([encoder.finish()])?;
        }
        self.params = model.clone();
        Ok(())
    }

    /// The model and parameters in use.
    pub fn params(&self) -> &ShadingModel {
        &self.params
    }

    /// Chiang's tables and uniform, when the model is Chiang's.
    pub fn chiang(&self) -> Option<&ChiangTables> {
        self.chiang.as_ref()
    }

    /// The volume method's grid field (uniform and fluence), when Chiang's model uses it.
    pub fn volume(&self) -> Option<&VolumeField> {
        self.volume.as_ref()
    }

    /// The redirect of the contract `shade/hair_model.wgsl` and the resources of `@group(2)`.
    pub fn binding(&self) -> &ShaderBinding {
        &self.binding
    }

    /// Marschner's tables, when the model reads them.
    pub fn lut(&self) -> Option<&MarschnerLut> {
        self.lut.as_ref()
    }

    /// Bytes of GPU memory: the parameters, and the tables if any.
    pub fn memory_bytes(&self) -> u64 {
        self.bytes
    }

    /// Redirects for a hair pass: the model's, unless it is the contract's default.
    pub(crate) fn redirect(&self) -> Option<pelage_gpu::Redirect> {
        (self.binding.module != CONTRACT).then(|| self.binding.redirect())
    }
}

/// The WGSL file that implements [`CONTRACT`] for `model` (what [`HairModel::new`] binds).
fn model_module(model: &ShadingModel) -> &'static str {
    match model {
        ShadingModel::KajiyaKay(_) => CONTRACT,
        ShadingModel::Marschner { lut: false, .. } => "shade/models/marschner_model.wgsl",
        ShadingModel::Marschner { lut: true, .. } => "shade/models/marschner_lut_model.wgsl",
        ShadingModel::Sadeghi(_) => "shade/models/sadeghi_model.wgsl",
        ShadingModel::Chiang(p) if p.multiple_scattering == MultipleScattering::Volume => {
            "shade/models/chiang_volume_model.wgsl"
        }
        ShadingModel::Chiang(p) if p.multiple_scattering == MultipleScattering::DualVolume => {
            "shade/models/chiang_dual_volume_model.wgsl"
        }
        ShadingModel::Chiang(p) if p.multiple_scattering == MultipleScattering::Dual => {
            "shade/models/chiang_dual_model.wgsl"
        }
        ShadingModel::Chiang(_) => "shade/models/chiang_model.wgsl",
    }
}
