//! `morphkit convert`.

/// Arguments of `morphkit convert`.
#[derive(clap::Args, Debug)]
pub struct ConvertArgs {}

/// Runs `morphkit convert`.
pub fn run(_args: &ConvertArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit convert' is not available in this build yet")
}
