//! `stance solve PROBLEM.json`: read a problem file (format in `docs/problem-format.md`),
//! solve it, print one JSON object with `joints`, `posture` and `report`.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use stance_document::Problem;

#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// The problem file (JSON).
    pub problem: PathBuf,
    /// Pretty-print the output.
    #[arg(long)]
    pub pretty: bool,
}

pub fn run(args: SolveArgs) -> Result<()> {
    let problem = load_problem(&args.problem)?;
    let (posture, report) = problem.solve()?;
    let out = problem.solution_json(&posture, &report);
    let text = if args.pretty {
        serde_json::to_string_pretty(&out)?
    } else {
        serde_json::to_string(&out)?
    };
    println!("{text}");
    Ok(())
}

pub fn load_problem(path: &std::path::Path) -> Result<Problem> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse_problem(&text).with_context(|| format!("invalid problem file {}", path.display()))
}

/// Parses a problem file; errors name the offending field (`tasks[2].target`).
pub fn parse_problem(text: &str) -> Result<Problem> {
    Problem::from_json(text).map_err(|e| anyhow!("{e}"))
}
