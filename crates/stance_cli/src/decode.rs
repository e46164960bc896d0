//! `stance decode` (not built yet).

#[derive(clap::Args, Debug)]
pub struct DecodeArgs {}

pub fn run(_args: DecodeArgs) -> anyhow::Result<()> {
    anyhow::bail!("`stance decode` is not available in this build yet")
}
