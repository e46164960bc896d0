//! `stance solve` (not built yet).

#[derive(clap::Args, Debug)]
pub struct SolveArgs {}

pub fn run(_args: SolveArgs) -> anyhow::Result<()> {
    anyhow::bail!("`stance solve` is not available in this build yet")
}
