//! `voxgi generate`: procedural scenes written as files (OBJ, MTL, PNG textures, scene TOML).

use super::{outln, CliError};
use std::io::Write;
use std::path::PathBuf;

/// The scenes `voxgi generate` can write.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GeneratedScene {
    /// A courtyard with two floors of arcades, banners and a roof opening, about 300 000
    /// triangles (Sponza scale; `voxgi::scene::atrium`).
    Atrium,
}

/// Arguments of `voxgi generate`.
#[derive(clap::Args, Clone)]
pub struct GenerateArgs {
    /// Which scene.
    pub scene: GeneratedScene,
    /// Output directory (created); `assets/scenes/atrium.toml` loads
    /// `assets/generated/atrium/`, where `tools/atrium` writes.
    #[arg(long, default_value = "assets/generated/atrium")]
    pub out: PathBuf,
}

/// Writes the scene's files and reports what it wrote.
pub fn generate(args: &GenerateArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match args.scene {
        GeneratedScene::Atrium => {
            let triangles = crate::scene::atrium::write(&args.out)?;
            outln!(
                out,
                "wrote {} ({} triangles): {}",
                args.out.display(),
                triangles,
                crate::scene::atrium::FILES.join(", ")
            );
        }
    }
    Ok(())
}
