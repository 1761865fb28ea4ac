//! `t2e-league train`: one training run from a TOML config (see configs/),
//! a `TrainingRun` with its flags, its progress bar and its last words.

use super::progress::style;
use super::threads::size_pools;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use t2e_core::map::PreparedMap;
use t2e_learners::learn::train::periodic_eval::{EvalPlan, PeriodicEval};
use t2e_learners::learn::train::run::{status_line, TrainingRun};
use t2e_learners::learn::train::TrainConfig;

#[derive(Args, Debug)]
pub struct TrainArgs {
    /// Training config (TOML; see configs/). With --resume, defaults to the
    /// run folder's own config.toml.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Run folder (default: runs/NAME, NAME from the config).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Continue the run in the run folder from its last checkpoint.
    #[arg(long)]
    pub resume: bool,
    /// Override total_env_steps (e.g. to extend a finished run with --resume).
    #[arg(long)]
    pub total_env_steps: Option<u64>,
    /// Override the device: auto, cpu or cuda.
    #[arg(long)]
    pub device: Option<t2e_learners::learn::run_config::DeviceChoice>,
    /// Threads for libtorch and the environments' rayon pool, at most 256.
    /// Default (0): OMP_NUM_THREADS if set, else the cores the load average
    /// leaves free, so a run beside another busy process does not fight it
    /// for every core.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub threads: usize,
    /// Hide the progress bar (logs one line per checkpoint instead).
    #[arg(long)]
    pub quiet: bool,
    /// Stop after this much training wall-clock in this invocation (90s,
    /// 10m, 2h), with a final checkpoint, even before total_env_steps.
    #[arg(long = "for", value_name = "DURATION", allow_hyphen_values = true)]
    pub run_for: Option<String>,
    /// Every DURATION, evaluate the newest checkpoint of each learning side
    /// against the rule-based opponent in a child process at the lowest CPU
    /// priority (one thread); SR against wall-clock and env steps goes to
    /// eval.csv and eval.png in the run folder.
    #[arg(long, value_name = "DURATION", allow_hyphen_values = true)]
    pub eval_every: Option<String>,
    /// Map sets of the periodic evaluation (as `eval --maps`).
    #[arg(long, default_value = "small,medium,large", value_delimiter = ',')]
    pub eval_maps: Vec<String>,
    /// Episodes per map set of each periodic evaluation: 100, fewer than
    /// `eval --episodes` (500), to keep the check cheap beside training.
    #[arg(long, default_value_t = 100)]
    pub eval_episodes: usize,
    /// Episode length of the periodic evaluation (the paper tests on 500).
    #[arg(long, default_value_t = 500)]
    pub eval_episode_length: u32,
}

/// Set by Ctrl-C: the loop saves a checkpoint and stops after the current iteration.
static STOP: AtomicBool = AtomicBool::new(false);

pub fn run(args: TrainArgs) -> Result<()> {
    let duration = |option: &str, text: &Option<String>| {
        text.as_deref()
            .map(|t| t2e_core::util::parse_duration(option, t))
            .transpose()
            .map_err(anyhow::Error::msg)
    };
    // Before anything uses the global pool, so the environments get it too.
    let (threads, why) = size_pools(args.threads)?;
    let run_for = duration("--for", &args.run_for)?;
    let eval_every = duration("--eval-every", &args.eval_every)?;
    let cfg = train_config(&args)?;
    let run_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(&cfg.name));
    let eval_plan = eval_every
        .map(|every| -> Result<EvalPlan> {
            let plan = EvalPlan {
                every,
                maps: args.eval_maps.clone(),
                episodes: args.eval_episodes,
                episode_length: args.eval_episode_length,
                seed: 0,
                num_captors: cfg.env.num_captors,
                speed_ratio: cfg.env.speed_ratio(),
            };
            plan.validate()?;
            Ok(plan)
        })
        .transpose()?;
    let maps = t2e_core::map::catalog::load_prepared(&cfg.maps)
        .with_context(|| format!("maps = \"{}\"", cfg.maps))?;
    let mut run = open_run(&args, &cfg, maps, &run_dir)?;
    if let Some(plan) = eval_plan {
        let periodic = PeriodicEval::new(plan, run.dir());
        run = run.with_periodic_eval(periodic);
    }
    if let Some(d) = run_for {
        run.trainer.set_clock_budget(d.as_secs_f64());
    }
    install_ctrl_c()?;
    tracing::info!(
        "{}, {threads} threads ({why}), run folder {}",
        run.describe(),
        run_dir.display()
    );
    let bar = progress_bar(args.quiet, cfg.total_env_steps, run.trainer.env_steps);
    let finished = run.run(&STOP, run_for, |it| {
        bar.set_position(it.metrics.env_steps);
        bar.set_message(status_line(it.recent));
        if args.quiet && it.checkpointed {
            tracing::info!(
                "iteration {}: {}",
                it.metrics.iteration,
                status_line(it.recent)
            );
        }
    })?;
    bar.finish_and_clear();
    println!(
        "{} after {} iterations, {} env steps, {:.1} min of training: {}",
        finished.ended.label(),
        run.trainer.iteration,
        run.trainer.env_steps,
        run.trainer.wall_s / 60.0,
        status_line(&finished.recent)
    );
    for w in finished.checkpoints {
        println!("checkpoint {}", w.display());
    }
    println!("curves {}", run.dir().curves_path().display());
    Ok(())
}

/// The run's config: `--config`, or a resumed run's stored one, with the
/// flags that override it.
fn train_config(args: &TrainArgs) -> Result<TrainConfig> {
    let mut cfg = match (&args.config, &args.out, args.resume) {
        (Some(p), _, _) => TrainConfig::load(p)?,
        (None, Some(out), true) => TrainConfig::load_stored(&out.join("config.toml"))?,
        _ => bail!("--config is required (or --resume --out RUN_FOLDER to reuse a run's config)"),
    };
    if let Some(s) = args.total_env_steps {
        cfg.total_env_steps = s;
    }
    if let Some(d) = &args.device {
        cfg.device = *d;
    }
    cfg.protocol.refuse_test_map_names(&cfg.maps)?;
    Ok(cfg)
}

/// A fresh run in `run_dir`, or the one there resumed (logging where it
/// picks up).
fn open_run(
    args: &TrainArgs,
    cfg: &TrainConfig,
    maps: Arc<Vec<Arc<PreparedMap>>>,
    run_dir: &Path,
) -> Result<TrainingRun> {
    if !args.resume {
        return Ok(TrainingRun::start(cfg.clone(), maps, run_dir)?);
    }
    let run = TrainingRun::resume(cfg.clone(), maps, run_dir)?;
    tracing::info!(
        "resuming {} at iteration {}, {} env steps",
        run_dir.display(),
        run.trainer.iteration,
        run.trainer.env_steps
    );
    Ok(run)
}

/// Ctrl-C once stops after the iteration with a checkpoint, twice quits now.
fn install_ctrl_c() -> Result<()> {
    ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            tracing::info!("\nsecond Ctrl-C: quitting without a final checkpoint");
            std::process::exit(130);
        }
        tracing::info!("\nCtrl-C: finishing this iteration and writing a checkpoint (Ctrl-C again to quit now)");
    })
    .context("cannot install the Ctrl-C handler")
}

/// The steps bar (hidden with `--quiet`), at `at` steps for a resumed run.
fn progress_bar(quiet: bool, total: u64, at: u64) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total);
    bar.set_style(style(
        "[{elapsed_precise}] [{bar:25}] {human_pos}/{human_len} steps {msg}",
    ));
    bar.set_position(at);
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_config_typo_names_the_file_and_the_field() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("typo.toml");
        std::fs::write(
            &path,
            "name = \"x\"\nprotocol = \"held-out\"\n[captors.ppo]\nentropy_coeff = 0.02\n",
        )
        .unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(
            err.contains("typo.toml") && err.contains("entropy_coeff"),
            "{err}"
        );
        std::fs::write(&path, "protocol = \"held-out\"\n[env]\nnum_captors = 0\n").unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(
            err.contains("typo.toml") && err.contains("env.num_captors"),
            "{err}"
        );
        std::fs::write(
            &path,
            "protocol = \"held-out\"\n[target]\nplay = \"mapo\"\n",
        )
        .unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(err.contains("target.play") && err.contains("mapo"), "{err}");
        std::fs::write(&path, "[target]\nplay = \"mappo\"\n").unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(
            err.contains("typo.toml") && err.contains("protocol: missing"),
            "{err}"
        );
        std::fs::write(&path, "protocol = \"paper\"\n[target]\nplay = \"mapo\"\n").unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(err.contains("target.play") && err.contains("mapo"), "{err}");
    }

    #[test]
    fn every_shipped_config_is_valid() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let league = p
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("league-"));
            if league {
                league::rules::config::LeagueConfig::load(&p).unwrap();
                continue;
            }
            if p.extension().and_then(|x| x.to_str()) == Some("toml") {
                let cfg = TrainConfig::load(&p).unwrap();
                cfg.protocol.refuse_test_map_names(&cfg.maps).unwrap();
                n += 1;
            }
        }
        assert!(n >= 8, "{n} configs");
    }
}
