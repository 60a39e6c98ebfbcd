//! `morphkit demo`.

/// Arguments of `morphkit demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {}

/// Runs `morphkit demo`.
pub fn run(_args: &DemoArgs) -> anyhow::Result<()> {
    anyhow::bail!("'morphkit demo' is not available in this build yet")
}
