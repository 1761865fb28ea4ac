//! `t2e-league table`: the paper's Tables II and III (Markdown, LaTeX) from
//! the summaries of `eval` output folders.

use crate::eval::{paper_table, Summary};
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct TableArgs {
    /// `eval --out` folders (or their summary.json files).
    #[arg(required = true)]
    pub evals: Vec<PathBuf>,
    /// Also write the Markdown here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the LaTeX tables here.
    #[arg(long)]
    pub latex: Option<PathBuf>,
}

/// Every summary of the given folders, in order.
pub fn read_summaries(paths: &[PathBuf]) -> Result<Vec<Summary>> {
    let mut all = Vec::new();
    for p in paths {
        let file = if p.is_dir() {
            p.join("summary.json")
        } else {
            p.clone()
        };
        if !file.is_file() {
            bail!(
                "{}: not found (give an eval --out folder or its summary.json)",
                file.display()
            );
        }
        let text = std::fs::read_to_string(&file)
            .with_context(|| format!("{}: cannot read", file.display()))?;
        let summaries: Vec<Summary> = serde_json::from_str(&text)
            .with_context(|| format!("{}: not an eval summary", file.display()))?;
        for s in &summaries {
            if !(s.sr.is_finite() && (0.0..=100.0).contains(&s.sr) && s.episodes > 0) {
                bail!(
                    "{}: a summary with SR {} over {} episodes: not a result",
                    file.display(),
                    s.sr,
                    s.episodes
                );
            }
        }
        all.extend(summaries);
    }
    Ok(all)
}

pub fn run(args: TableArgs) -> Result<()> {
    let summaries = read_summaries(&args.evals)?;
    let md = paper_table::markdown(&summaries);
    print!("{md}");
    if let Some(p) = &args.out {
        std::fs::write(p, &md).with_context(|| format!("cannot write {}", p.display()))?;
    }
    if let Some(p) = &args.latex {
        std::fs::write(p, paper_table::latex(&summaries))
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    Ok(())
}
