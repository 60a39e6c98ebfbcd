//! `morphkit correspond`.

/// Arguments of `morphkit correspond`.
#[derive(clap::Args, Debug)]
pub struct CorrespondArgs {}

/// Runs `morphkit correspond`.
pub fn run(_args: &CorrespondArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit correspond' is not available in this build yet")
}
