//! `stance`: the command-line face of the Stance core.

use clap::{Parser, Subcommand};

mod bench;
mod decode;
mod simulate;
mod solve;

#[derive(Parser, Debug)]
#[command(
    name = "stance",
    version,
    about = "Stance posture editor core, headless"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Solve an IK problem file and print the solved posture as JSON.
    Solve(solve::SolveArgs),
    /// Benchmark the solver scenarios (or one problem file).
    Bench(bench::BenchArgs),
    /// Decode a recorded sensor byte stream into JSON lines.
    Decode(decode::DecodeArgs),
    /// Write a simulated sensor byte stream.
    SimulateSensors(simulate::SimulateArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Solve(args) => solve::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Decode(args) => decode::run(args),
        Command::SimulateSensors(args) => simulate::run(args),
    }
}
