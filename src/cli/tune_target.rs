//! `t2e-league tune-target`: CMA-ES over the rule-based target's family
//! (`eval::tune`), its flags, progress bar, files and last table.

use super::progress::style;
use anyhow::{bail, Context, Result};
use indicatif::ProgressBar;
use std::io::Write as _;
use std::path::PathBuf;
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::eval::tune::{tune, Candidate, TuneOutcome, TuneSettings};
use t2e_learners::plots::line::{self, line_plot, Series};

#[derive(clap::Args, Debug)]
pub struct TuneTargetArgs {
    /// The training panel: captor teams, comma-separated, whose worst
    /// capture rate the search minimises (keep the test teams out of it).
    #[arg(long, value_delimiter = ',', required = true)]
    pub panel: Vec<String>,
    /// Maps the panel plays (held-out protocol: generated maps, never the
    /// Gibson test maps).
    #[arg(long, default_value = "generated:20")]
    pub maps: String,
    /// Number of captors.
    #[arg(long, default_value_t = 3)]
    pub k: usize,
    /// v_e / v_p.
    #[arg(long, default_value_t = 1.2)]
    pub speed_ratio: f64,
    /// Episodes per team per candidate, on the same starts for every candidate.
    #[arg(long, default_value_t = 50)]
    pub episodes: usize,
    /// Steps before an episode counts as escaped.
    #[arg(long, default_value_t = 500)]
    pub episode_length: u32,
    /// Generations of CMA-ES.
    #[arg(long, default_value_t = 12)]
    pub generations: usize,
    /// Candidates per generation.
    #[arg(long, default_value_t = 8)]
    pub population: usize,
    /// CMA-ES's initial step size (the search space's origin is the rule).
    #[arg(long, default_value_t = 0.5)]
    pub sigma: f64,
    /// Seeds the panel's starts and CMA-ES's samples.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Threads for the episodes (rayon).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Folder to write: candidates.csv (one row per candidate, as played),
    /// tune.json (the outcome) and tune.png (the worst capture rate per
    /// candidate and the best so far).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: TuneTargetArgs) -> Result<()> {
    if args.threads == 0 || args.threads > 256 {
        bail!("--threads {}: must be in 1..=256", args.threads);
    }
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build_global();
    let panel = args
        .panel
        .iter()
        .map(|p| {
            p.parse::<ControllerSpec>()
                .with_context(|| format!("--panel {p}"))
        })
        .collect::<Result<Vec<_>>>()?;
    let maps = t2e_core::map::catalog::load_prepared(&args.maps)
        .with_context(|| format!("--maps {}", args.maps))?;
    t2e_core::protocol::Protocol::HeldOut
        .check_training_maps(&args.maps, &maps)
        .map_err(|e| anyhow::anyhow!("--maps {}: {e}", args.maps))?;
    let settings = TuneSettings {
        panel,
        num_captors: args.k,
        speed_ratio: args.speed_ratio,
        episodes: args.episodes,
        episode_length: args.episode_length,
        eval_seed: args.seed,
        search_seed: args.seed,
        generations: args.generations,
        population: args.population,
        sigma: args.sigma,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv_path = args.out.join("candidates.csv");
    // Appended and flushed per candidate: a killed search keeps what it
    // played, and a second search never truncates it.
    let mut csv = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&csv_path)
        .with_context(|| {
            format!(
                "cannot create {} (a search already there is kept: pick another --out)",
                csv_path.display()
            )
        })?;
    writeln!(csv, "generation,target,worst,{}", args.panel.join(","))?;
    let total = 1 + args.generations * args.population;
    let bar = ProgressBar::new(total as u64);
    bar.set_style(style(
        "[{elapsed_precise}] [{bar:25}] {pos}/{len} candidates {msg}",
    ));
    let mut best = f64::INFINITY;
    let outcome = tune(&settings, &maps, |c: &Candidate| {
        let cells: Vec<String> = c.capture.iter().map(|x| format!("{x:.1}")).collect();
        let _ = writeln!(
            csv,
            "{},\"{}\",{:.1},{}",
            c.generation,
            c.target,
            c.worst,
            cells.join(",")
        );
        let _ = csv.flush();
        best = best.min(c.worst);
        bar.set_message(format!("worst capture: best so far {best:.1}%"));
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    let json = serde_json::to_string_pretty(&outcome)?;
    t2e_core::fs::write_file_atomically(&args.out.join("tune.json"), json.as_bytes())?;
    plot_outcome(&args, &outcome)?;
    print_outcome(&args, &outcome);
    Ok(())
}

/// tune.png: each candidate's worst capture rate, the best so far and the
/// rule's; apart from `run` because it is drawn once, from the outcome.
fn plot_outcome(args: &TuneTargetArgs, outcome: &TuneOutcome) -> Result<()> {
    let worst: Vec<(f64, f64)> = outcome
        .candidates
        .iter()
        .enumerate()
        .map(|(i, c)| ((i + 1) as f64, c.worst))
        .collect();
    let mut so_far = f64::INFINITY;
    let best_so_far: Vec<(f64, f64)> = worst
        .iter()
        .map(|&(i, w)| {
            so_far = so_far.min(w);
            (i, so_far)
        })
        .collect();
    let rule: Vec<(f64, f64)> = vec![
        (1.0, outcome.rule.worst),
        (worst.len() as f64, outcome.rule.worst),
    ];
    let img = line_plot(
        &[
            Series::new("candidate", worst, line::palette(0)),
            Series::new("best so far", best_so_far, line::palette(1)),
            Series::new("rule-based target", rule, line::palette(2)),
        ],
        "worst capture rate over the panel (%)",
        "candidate",
        "%",
        800,
        400,
    );
    line::save_png(&img, args.out.join("tune.png"))?;
    Ok(())
}

/// The last table: the rule's and the best target's capture rates per team;
/// apart from `run` because it is printed once, from the outcome.
fn print_outcome(args: &TuneTargetArgs, outcome: &TuneOutcome) {
    println!("| target | worst | {} |", args.panel.join(" | "));
    println!("|---|---|{}", "---|".repeat(args.panel.len()));
    let best_label = if outcome.best.target == outcome.rule.target {
        "best found: the rule itself"
    } else {
        "best found"
    };
    for (label, c) in [("rule-based", &outcome.rule), (best_label, &outcome.best)] {
        let cells: Vec<String> = c.capture.iter().map(|x| format!("{x:.1}")).collect();
        println!(
            "| {label} `{}` | {:.1} | {} |",
            c.target,
            c.worst,
            cells.join(" | ")
        );
    }
    println!(
        "\n{} candidates, {} episodes each per team; files in {}",
        outcome.candidates.len(),
        args.episodes,
        args.out.display()
    );
}
