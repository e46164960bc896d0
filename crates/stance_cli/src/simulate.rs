//! `stance simulate` (not built yet).

#[derive(clap::Args, Debug)]
pub struct SimulateArgs {}

pub fn run(_args: SimulateArgs) -> anyhow::Result<()> {
    anyhow::bail!("`stance simulate` is not available in this build yet")
}
