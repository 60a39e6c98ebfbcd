//! `morphkit bench`.

/// Arguments of `morphkit bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {}

/// Runs `morphkit bench`.
pub fn run(_args: &BenchArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit bench' is not available in this build yet")
}
