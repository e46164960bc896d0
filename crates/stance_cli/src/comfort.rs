//! `stance comfort FILE [--json]`: the comfort of a posture (docs/comfort.md): RULA with its
//! parts, the joint loads against gravity as shares of strength, the effort. FILE is a problem
//! file (its skeleton, `posture` and `comfort` settings) or a document (its posture on the
//! default H-Anim body at `--loa`).

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use serde_json::Value;
use stance_document::comfort::report_json;
use stance_document::{Document, Problem};
use stance_hanim::comfort::{ComfortReport, ComfortSettings, comfort_report};
use stance_hanim::strength::{aligned_axes, built_axes};
use stance_hanim::{LevelOfArticulation, SkeletonOptions, default_skeleton, readable_name};

#[derive(clap::Args, Debug)]
pub struct ComfortArgs {
    /// A problem file or a document (JSON).
    pub file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Level of articulation of the default body a document is measured on (1-4).
    #[arg(long, default_value_t = 2)]
    pub loa: u8,
}

pub fn run(args: ComfortArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.file)
        .with_context(|| format!("cannot read {}", args.file.display()))?;
    let root: Value = serde_json::from_str(&text)
        .with_context(|| format!("{} is not JSON", args.file.display()))?;
    let report = if root.get("skeleton").is_some() {
        let problem = Problem::from_json(&text)
            .map_err(|e| anyhow!("invalid problem file {}: {e}", args.file.display()))?;
        comfort_report(
            &problem.skeleton,
            &aligned_axes(&problem.skeleton),
            &problem.start,
            &problem.comfort,
        )
    } else {
        let document = Document::from_json(&text)
            .map_err(|e| anyhow!("invalid document {}: {e}", args.file.display()))?;
        let loa = LevelOfArticulation::from_number(args.loa)
            .ok_or_else(|| anyhow!("--loa {}: expected 1, 2, 3 or 4", args.loa))?;
        let body = default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })?;
        let posture = document
            .to_posture(&body.skeleton)
            .map_err(|e| anyhow!("{}: {e}", args.file.display()))?;
        comfort_report(
            &body.skeleton,
            &built_axes(&body),
            &posture,
            &ComfortSettings::default(),
        )
    };
    if args.json {
        println!("{}", report_json(&report));
    } else {
        print_text(&report);
    }
    Ok(())
}

fn print_text(report: &ComfortReport) {
    match &report.rula {
        Some(r) => {
            println!("RULA {} (action level {})", r.score, r.action_level);
            for (side, parts) in [("left", &r.left), ("right", &r.right)] {
                println!(
                    "  {side}: upper arm {}, lower arm {}, wrist {}, twist {}; score A {}, C {}",
                    parts.upper_arm,
                    parts.lower_arm,
                    parts.wrist,
                    parts.wrist_twist,
                    parts.posture_a,
                    parts.score_c
                );
            }
            println!(
                "  neck {}, trunk {}, legs {}; score B {}, D {}",
                r.body.neck, r.body.trunk, r.body.legs, r.body.posture_b, r.body.score_d
            );
        }
        None => println!("RULA: this body lacks a joint RULA measures"),
    }
    println!("highest joint loads:");
    for load in report.highest(5) {
        let share = load.share.map_or_else(
            || "strength unknown".to_owned(),
            |s| format!("{:.0} % of strength", 100.0 * s),
        );
        println!(
            "  {}: {:.1} N m, {share}{}",
            readable_name(&load.joint),
            load.torque_nm,
            if load.flagged { " (above 15 %)" } else { "" }
        );
    }
    println!(
        "effort {:.4} (sum of squared shares), joint ranges {:.4}",
        report.terms.effort, report.terms.range
    );
}
