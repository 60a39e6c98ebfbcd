//! `morphkit info`.

/// Arguments of `morphkit info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {}

/// Runs `morphkit info`.
pub fn run(_args: &InfoArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit info' is not available in this build yet")
}
