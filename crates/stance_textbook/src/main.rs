//! `stance-textbook DIR...`: solves every problem file (`*.json`, in DIR and its sub-folders)
//! with the plain textbook recursion and prints one JSON line per problem (`family`,
//! `problem`, `met_every_level`, `iterations`, `us_per_solve`, `residuals`): the peer file of
//! `stance bench --suite DIR --peer FILE`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use stance_textbook::{Problem, Settings};

fn files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "json") {
            out.push(path);
        }
    }
    Ok(())
}

fn main() -> Result<()> {
    let mut settings = Settings::default();
    let mut dirs: Vec<PathBuf> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        if arg == "--lambda" {
            settings.lambda = args
                .next()
                .and_then(|v| v.parse().ok())
                .context("--lambda needs a number")?;
        } else {
            dirs.push(PathBuf::from(arg));
        }
    }
    if dirs.is_empty() {
        bail!("usage: stance-textbook [--lambda L] DIR... (problem files; prints JSON lines)");
    }
    let mut paths = Vec::new();
    for dir in &dirs {
        files(dir, &mut paths)?;
    }
    for path in paths {
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let problem = Problem::from_json(&text).with_context(|| format!("{}", path.display()))?;
        // The median of a few timed solves (at least 3, about 20 ms in all).
        let mut times = Vec::new();
        let mut solution = None;
        let started = Instant::now();
        while times.len() < 3 || (started.elapsed().as_millis() < 20 && times.len() < 50) {
            let t = Instant::now();
            solution = Some(problem.solve(&settings));
            times.push(t.elapsed().as_secs_f64() * 1e6);
        }
        times.sort_by(f64::total_cmp);
        let Some(solution) = solution else { continue };
        let family = path
            .parent()
            .and_then(Path::file_name)
            .map(|n| n.to_string_lossy().into_owned());
        let line = serde_json::json!({
            "family": family,
            "problem": path.file_name().map(|n| n.to_string_lossy().into_owned()),
            "met_every_level": solution.met_every_level,
            "iterations": solution.iterations,
            "us_per_solve": times[times.len() / 2],
            "residuals": solution.residuals,
        });
        println!("{line}");
    }
    Ok(())
}
