//! `morphkit blend`.

/// Arguments of `morphkit blend`.
#[derive(clap::Args, Debug)]
pub struct BlendArgs {}

/// Runs `morphkit blend`.
pub fn run(_args: &BlendArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit blend' is not available in this build yet")
}
