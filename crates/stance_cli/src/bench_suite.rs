//! `stance bench --suite DIR [--peer FILE.jsonl] [--no-restarts]`: every problem file of a
//! folder and its sub-folders, one family per folder (as `stance families` writes them),
//! solved from its start posture with the file's settings. Per family: cases met at every
//! level, median and 90th-percentile iterations, median time per solve and per iteration;
//! with a peer's results on the same files (`stance-textbook`, `bench/placo/compare.py`), its
//! counts beside them, how many of the peer's met cases Stance meets too, and the ratios of
//! the medians (iterations and times over the cases both meet).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde::Deserialize;
use serde_json::json;
use stance_ik::Solver;

use crate::bench::median;

/// One problem's result (Stance's or a peer's line).
#[derive(Debug, Clone, Deserialize)]
struct Row {
    family: Option<String>,
    problem: String,
    met_every_level: bool,
    iterations: usize,
    us_per_solve: f64,
    /// How the solve ended (Stance's rows; `bench/placo/compare.py` reads it).
    #[serde(default)]
    status: Option<serde_json::Value>,
    /// Every level's residual (Stance's rows).
    #[serde(default)]
    residuals: Vec<f64>,
}

fn problem_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list the folder", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            problem_files(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "json") {
            out.push(path);
        }
    }
    Ok(())
}

fn name_of(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Solves `path` (timed over at least 5 runs and about 20 ms).
fn solve_row(path: &Path, no_restarts: bool) -> Result<Row> {
    let problem = crate::solve::load_problem(path)?;
    let mut settings = problem.settings;
    if no_restarts {
        settings.restarts = false;
    }
    let mut solver: Solver = problem.solver(settings)?;
    let (start, _) = problem.start_posture();
    let budget = Duration::from_millis(20);
    let mut times = Vec::new();
    let mut last = None;
    let started = Instant::now();
    while times.len() < 5 || (started.elapsed() < budget && times.len() < 200) {
        let mut posture = start.clone();
        let t = Instant::now();
        let report = solver.solve(&problem.skeleton, &problem.tasks, &mut posture)?;
        times.push(t.elapsed().as_secs_f64() * 1e6);
        last = Some(report);
    }
    let report = last.context("no solve")?;
    Ok(Row {
        family: path.parent().map(name_of),
        problem: name_of(path),
        met_every_level: report.levels.iter().all(|l| l.met || l.posture_only),
        iterations: report.iterations,
        us_per_solve: median(times),
        status: Some(serde_json::to_value(report.status)?),
        residuals: report.levels.iter().map(|l| l.residual_after).collect(),
    })
}

fn percentile(mut v: Vec<usize>, p: f64) -> Option<usize> {
    v.sort_unstable();
    let last = v.len().checked_sub(1)?;
    Some(v[((p * v.len() as f64) as usize).min(last)])
}

fn median_usize(v: &[usize]) -> f64 {
    median(v.iter().map(|&x| x as f64).collect())
}

fn read_peer(path: &Path) -> Result<HashMap<(String, String), Row>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the peer's results", path.display()))?;
    let mut out = HashMap::new();
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let row: Row = serde_json::from_str(line)
            .with_context(|| format!("{}: line {}", path.display(), i + 1))?;
        out.insert(
            (row.family.clone().unwrap_or_default(), row.problem.clone()),
            row,
        );
    }
    Ok(out)
}

pub fn run(dir: &Path, peer: Option<&Path>, no_restarts: bool, json_out: bool) -> Result<()> {
    let mut files = Vec::new();
    problem_files(dir, &mut files)?;
    if files.is_empty() {
        bail!(
            "{}: no problem file (*.json) in the folder or its sub-folders",
            dir.display()
        );
    }
    let peer = peer.map(read_peer).transpose()?;
    let mut families: BTreeMap<String, Vec<Row>> = BTreeMap::new();
    for path in &files {
        let row = solve_row(path, no_restarts)?;
        families
            .entry(row.family.clone().unwrap_or_default())
            .or_default()
            .push(row);
    }
    if !json_out {
        println!(
            "{:<9} {:>5} {:>9} {:>6} {:>6} {:>10} {:>9}{}",
            "family",
            "cases",
            "met",
            "it med",
            "it p90",
            "us/solve",
            "us/iter",
            if peer.is_some() {
                "  | peer met  both  it med (both)  per solve x (both)"
            } else {
                ""
            }
        );
    }
    let mut summaries = Vec::new();
    for (family, rows) in &families {
        let met = rows.iter().filter(|r| r.met_every_level).count();
        let iterations: Vec<usize> = rows.iter().map(|r| r.iterations).collect();
        let per_solve = median(rows.iter().map(|r| r.us_per_solve).collect());
        let per_iteration = median(
            rows.iter()
                .map(|r| r.us_per_solve / r.iterations.max(1) as f64)
                .collect(),
        );
        let mut summary = json!({
            "family": family,
            "cases": rows.len(),
            "met_every_level": met,
            "median_iterations": median_usize(&iterations),
            "p90_iterations": percentile(iterations, 0.9),
            "median_us_per_solve": per_solve,
            "median_us_per_iteration": per_iteration,
        });
        let mut peer_text = String::new();
        if let Some(peer) = &peer {
            let pairs: Vec<(&Row, &Row)> = rows
                .iter()
                .filter_map(|r| {
                    peer.get(&(family.clone(), r.problem.clone()))
                        .map(|p| (r, p))
                })
                .collect();
            let peer_met = pairs.iter().filter(|(_, p)| p.met_every_level).count();
            let both: Vec<&(&Row, &Row)> = pairs
                .iter()
                .filter(|(r, p)| r.met_every_level && p.met_every_level)
                .collect();
            let ours_it = median_usize(&both.iter().map(|(r, _)| r.iterations).collect::<Vec<_>>());
            let peer_it = median_usize(&both.iter().map(|(_, p)| p.iterations).collect::<Vec<_>>());
            let ours_us = median(both.iter().map(|(r, _)| r.us_per_solve).collect());
            let peer_us = median(both.iter().map(|(_, p)| p.us_per_solve).collect());
            summary["peer"] = json!({
                "cases": pairs.len(),
                "met_every_level": peer_met,
                "stance_meets_where_peer_meets": both.len(),
                "median_iterations_both": {"stance": ours_it, "peer": peer_it},
                "median_us_per_solve_both": {"stance": ours_us, "peer": peer_us},
                "per_solve_ratio": peer_us / ours_us,
            });
            peer_text = format!(
                "  | {:>3}/{:<4} {:>3}/{:<3} {:>5.1} vs {:<5.1} {:>8.1}x",
                peer_met,
                pairs.len(),
                both.len(),
                peer_met,
                ours_it,
                peer_it,
                peer_us / ours_us
            );
        }
        if !json_out {
            println!(
                "{:<9} {:>5} {:>4}/{:<4} {:>6.1} {:>6} {:>10.1} {:>9.2}{peer_text}",
                family,
                rows.len(),
                met,
                rows.len(),
                median_usize(&rows.iter().map(|r| r.iterations).collect::<Vec<_>>()),
                summary["p90_iterations"],
                per_solve,
                per_iteration,
            );
        }
        summaries.push(summary);
    }
    if json_out {
        let results: Vec<serde_json::Value> = families
            .values()
            .flatten()
            .map(|r| {
                json!({
                    "family": r.family,
                    "problem": r.problem,
                    "met_every_level": r.met_every_level,
                    "iterations": r.iterations,
                    "us_per_solve": r.us_per_solve,
                    "status": r.status,
                    "residuals": r.residuals,
                })
            })
            .collect();
        println!(
            "{}",
            json!({"restarts": !no_restarts, "families": summaries, "results": results})
        );
    }
    Ok(())
}
