//! `t2e-league table`: the paper's Tables II and III (Markdown, LaTeX), or
//! with `--cross` its Table V (Markdown), from the summaries of `eval`
//! output folders.

use anyhow::{bail, Context, Result};
use std::path::PathBuf;
use t2e_core::fs::write_file_atomically;
use t2e_learners::eval::{cross_table, paper_table, Summary};

#[derive(clap::Args, Debug)]
pub struct TableArgs {
    /// `eval --out` folders, their setting folders (one setting each), or
    /// the summary.json files of either.
    #[arg(required = true)]
    pub evals: Vec<PathBuf>,
    /// Also write the Markdown here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also write the LaTeX tables here.
    #[arg(long)]
    pub latex: Option<PathBuf>,
    /// Lay out the paper's Table V instead: each captors against each
    /// target evaluated (the rule-based one, learned ones), per class and
    /// pooled over the classes, with the paper's co-evolution cells beside.
    #[arg(long)]
    pub cross: bool,
}

/// Every summary of the given folders, in order, each with the file it was
/// read from.
pub fn read_summaries(paths: &[PathBuf]) -> Result<Vec<paper_table::Sourced>> {
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
        // An eval --out folder's list, or one setting folder's summary.
        let summaries: Vec<Summary> = match serde_json::from_str::<Vec<Summary>>(&text) {
            Ok(list) => list,
            Err(list_err) => match serde_json::from_str::<Summary>(&text) {
                Ok(one) => vec![one],
                Err(_) => {
                    return Err(anyhow::Error::new(list_err))
                        .with_context(|| format!("{}: not an eval summary", file.display()))
                }
            },
        };
        if summaries.is_empty() {
            bail!("{}: holds no summary (an empty list)", file.display());
        }
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
        all.extend(
            summaries
                .into_iter()
                .map(|s| (file.display().to_string(), s)),
        );
    }
    Ok(all)
}

pub fn run(args: TableArgs) -> Result<()> {
    // An output that is one of the inputs (or the other output) would be
    // overwritten by the table: refuse before reading anything.
    let same = |a: &std::path::Path, b: &std::path::Path| match (a.canonicalize(), b.canonicalize())
    {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    };
    let outputs: Vec<(&str, &PathBuf)> = [("--out", &args.out), ("--latex", &args.latex)]
        .into_iter()
        .filter_map(|(o, p)| p.as_ref().map(|p| (o, p)))
        .collect();
    for (option, out) in &outputs {
        for input in &args.evals {
            let file = if input.is_dir() {
                input.join("summary.json")
            } else {
                input.clone()
            };
            if same(out, &file) || same(out, input) {
                bail!(
                    "{option} {}: is the input {}; the table would overwrite it",
                    out.display(),
                    file.display()
                );
            }
        }
    }
    if let [(_, a), (_, b)] = outputs[..] {
        if same(a, b) {
            bail!(
                "--out and --latex are both {}: one would overwrite the other",
                a.display()
            );
        }
    }
    if args.cross && args.latex.is_some() {
        bail!("--latex with --cross: Table V is written as Markdown only (--out)");
    }
    let summaries = read_summaries(&args.evals)?;
    if args.cross {
        let md = cross_table::markdown(&summaries).map_err(anyhow::Error::msg)?;
        if let Some(p) = &args.out {
            write_file_atomically(p, md.as_bytes())
                .with_context(|| format!("cannot write {}", p.display()))?;
        }
        print!("{md}");
        return Ok(());
    }
    if summaries.iter().all(|(_, s)| {
        s.target != "heuristic" || !["small", "medium", "large"].contains(&s.maps.as_str())
    }) {
        bail!(
            "none of the {} summaries belongs in the paper's tables: they need the rule-based target (--target heuristic) on the Gibson classes (--maps small,medium,large); for captors against learned targets (the paper's Table V) add --cross",
            summaries.len()
        );
    }
    let md = paper_table::markdown(&summaries).map_err(anyhow::Error::msg)?;
    let tex = paper_table::latex(&summaries).map_err(anyhow::Error::msg)?;
    // Written whole and renamed into place: a killed run leaves the old
    // table or the new one, never half of one.
    if let Some(p) = &args.out {
        write_file_atomically(p, md.as_bytes())
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    if let Some(p) = &args.latex {
        write_file_atomically(p, tex.as_bytes())
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    print!("{md}");
    Ok(())
}
