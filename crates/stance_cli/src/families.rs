//! `stance families`: writes the generated problem families (`stance_hanim::families`) as
//! problem files, one folder per family (`DIR/NAME/NAME-0000.json`), for `stance bench
//! --suite` and for peers run on the same files.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use stance_document::problem_json;
use stance_hanim::families::{Family, families};

#[derive(clap::Args, Debug)]
pub struct FamiliesArgs {
    /// The folder to write into (created; a family's folder is replaced).
    #[arg(long, required_unless_present = "list")]
    pub out: Option<PathBuf>,
    /// Problems per family.
    #[arg(long, default_value_t = 40)]
    pub cases: usize,
    /// Seed (the same files for the same seed, in every version).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only these families (default: every one; `--list` names them).
    #[arg(long)]
    pub family: Vec<String>,
    /// List the families and whether the solver was tuned on them, and write nothing.
    #[arg(long)]
    pub list: bool,
}

pub fn run(args: FamiliesArgs) -> Result<()> {
    let all = families();
    if args.list {
        for f in &all {
            let tuned = if f.tuned { "tuned" } else { "held out" };
            println!("{:<8} {:<9} {}", f.name, tuned, f.description);
        }
        return Ok(());
    }
    let chosen: Vec<&Family> = if args.family.is_empty() {
        all.iter().collect()
    } else {
        args.family
            .iter()
            .map(|name| {
                all.iter().find(|f| f.name == name).with_context(|| {
                    let names: Vec<&str> = all.iter().map(|f| f.name).collect();
                    format!("no family `{name}` (there are {})", names.join(", "))
                })
            })
            .collect::<Result<_>>()?
    };
    let Some(out) = &args.out else {
        bail!("--out is needed");
    };
    if args.cases == 0 {
        bail!("--cases must be at least 1");
    }
    for family in chosen {
        let dir = out.join(family.name);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .with_context(|| format!("{}: cannot replace the folder", dir.display()))?;
        }
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        let skeleton = family.body.skeleton()?;
        for index in 0..args.cases {
            let problem = family.problem(&skeleton, args.seed, index)?;
            let json = problem_json(&skeleton, &problem.tasks, &problem.start)?;
            let path = dir.join(format!("{}.json", problem.name));
            std::fs::write(&path, serde_json::to_string(&json)?)
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        println!(
            "{}: {} problems ({}) in {}",
            family.name,
            args.cases,
            if family.tuned { "tuned" } else { "held out" },
            dir.display()
        );
    }
    Ok(())
}
