//! What a command can fail with, and the exit code each failure gets.

use crate::output::OutputError;
use pelage::gpu::GpuError;
use pelage::scene::SceneFileError;

/// A failed command.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The scene file is missing, malformed or out of range (the message names the
    /// path, or the key and its line).
    #[error(transparent)]
    SceneFile(#[from] SceneFileError),
    /// The options do not fit together.
    #[error("{0}")]
    Usage(String),
    /// Building or rendering the scene failed.
    #[error(transparent)]
    Render(#[from] pelage::Error),
    /// Writing an output file failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A progress bar could not be drawn.
    #[error("progress bar: {0}")]
    Progress(#[from] indicatif::style::TemplateError),
    /// A lab or the benchmark failed.
    #[error("{0}")]
    Lab(Box<dyn std::error::Error>),
}

impl CliError {
    /// 2 for input the user can fix (a scene file, options, out-of-range parameters, a
    /// `WGPU_BACKEND` naming no backend, a method this adapter cannot run: the message
    /// names those that can),
    /// 1 for everything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::SceneFile(_)
            | CliError::Usage(_)
            | CliError::Render(
                pelage::Error::Param(_)
                | pelage::Error::Contract(pelage::contract::ContractError::Param(_))
                | pelage::Error::Strands(pelage::strands::StrandsError::Param(_))
                | pelage::Error::Shadow(pelage::shadow::ShadowError::Param(_))
                | pelage::Error::Shade(
                    pelage::shade::ShadeError::Param(_) | pelage::shade::ShadeError::Unsupported(_),
                )
                | pelage::Error::Gpu(GpuError::BadBackend { .. }),
            ) => 2,
            _ => 1,
        }
    }
}

impl From<GpuError> for CliError {
    fn from(e: GpuError) -> Self {
        CliError::Render(e.into())
    }
}
