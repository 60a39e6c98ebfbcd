//! `morphkit transfer`.

/// Arguments of `morphkit transfer`.
#[derive(clap::Args, Debug)]
pub struct TransferArgs {}

/// Runs `morphkit transfer`.
pub fn run(_args: &TransferArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit transfer' is not available in this build yet")
}
