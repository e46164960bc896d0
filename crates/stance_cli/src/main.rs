//! `stance`: the command-line face of the Stance core.

use clap::{Parser, Subcommand};

mod avatar;
mod bench;
mod bench_collision;
mod bench_comfort;
mod bench_suite;
mod comfort;
mod decode;
mod families;
mod lift;
mod link;
mod render;
mod retarget;
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
    /// Measure the comfort of a posture (RULA, joint loads, effort) of a problem file or a
    /// document.
    Comfort(comfort::ComfortArgs),
    /// Benchmark the solver scenarios (or one problem file).
    Bench(bench::BenchArgs),
    /// Write the generated problem families as problem files (for `bench --suite`).
    Families(families::FamiliesArgs),
    /// Decode a recorded sensor byte stream into JSON lines.
    Decode(decode::DecodeArgs),
    /// Write a simulated sensor byte stream.
    SimulateSensors(simulate::SimulateArgs),
    /// Print a JSON summary of an avatar file (joints, H-Anim mapping with match method and
    /// confidence, meshes, extensions).
    Inspect(avatar::InspectArgs),
    /// Pose an avatar with a posture file and write it as GLB.
    ExportPosed(avatar::ExportPosedArgs),
    /// Write the generated default avatar (H-Anim LOA2, skinned) as GLB.
    MakeAvatar(avatar::MakeAvatarArgs),
    /// Encode a document into a posture link, or decode a link into a document.
    Link(link::LinkArgs),
    /// Render a document's posture or a scene (on the default body or an avatar) as a PNG image.
    Render(render::RenderArgs),
    /// Lift a posture from OpenPose keypoints (JSON) into a document.
    Lift(lift::LiftArgs),
    /// Retargets clips (BVH, glTF animations) onto an avatar, holding foot contacts.
    Retarget(retarget::RetargetArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Solve(args) => solve::run(args),
        Command::Comfort(args) => comfort::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Families(args) => families::run(args),
        Command::Decode(args) => decode::run(args),
        Command::SimulateSensors(args) => simulate::run(args),
        Command::Inspect(args) => avatar::inspect(args),
        Command::ExportPosed(args) => avatar::export_posed(args),
        Command::MakeAvatar(args) => avatar::make_avatar(args),
        Command::Link(args) => link::run(args),
        Command::Retarget(args) => retarget::run(args),
        Command::Render(args) => render::run(args),
        Command::Lift(args) => lift::run(args),
    }
}
