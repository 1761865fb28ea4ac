//! `t2e-league train`: one training run from a TOML config (see configs/).

use super::periodic_eval::{EvalPlan, PeriodicEval};
use crate::learn::train::{Metrics, TrainConfig, Trainer};
use crate::render::plot::{self, line_plot, Series};
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

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
    pub device: Option<crate::learn::config::DeviceChoice>,
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
            .map(|t| crate::util::parse_duration(option, t))
            .transpose()
            .map_err(anyhow::Error::msg)
    };
    if args.threads > 256 {
        bail!("--threads {}: at most 256", args.threads);
    }
    let (threads, why) = crate::util::thread_count(args.threads);
    // Before anything uses the global pool, so the environments get it too.
    // An error means this process already started the pool (a library
    // caller running a second command): that pool stays.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global();
    tch::set_num_threads(threads as i32);
    let run_for = duration("--for", &args.run_for)?;
    let eval_every = duration("--eval-every", &args.eval_every)?;
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
    if cfg.protocol == crate::protocol::Protocol::HeldOut {
        refuse_test_maps(&cfg.maps)?;
    }
    let run_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(&cfg.name));
    if !args.resume && crate::learn::persist::RunDir::new(&run_dir).has_state() {
        bail!(
            "{} already holds a run: add --resume to continue it, or pick another --out or name",
            run_dir.display()
        );
    }
    std::fs::create_dir_all(&run_dir)
        .with_context(|| format!("cannot create {}", run_dir.display()))?;
    let eval_plan = match eval_every {
        Some(every) => {
            let plan = EvalPlan {
                every,
                maps: args.eval_maps.clone(),
                episodes: args.eval_episodes,
                episode_length: args.eval_episode_length,
                seed: 0,
                num_captors: cfg.env.num_captors,
                speed_ratio: cfg.env.speed_ratio(),
            };
            crate::eval::EvalSetting {
                num_captors: plan.num_captors,
                speed_ratio: plan.speed_ratio,
                episodes: plan.episodes,
                episode_length: plan.episode_length,
                ..Default::default()
            }
            .validate()
            .map_err(|e| anyhow::anyhow!("--eval-episodes / --eval-episode-length: {e}"))?;
            for m in &plan.maps {
                crate::map::catalog::load_prepared(m)
                    .with_context(|| format!("--eval-maps {m}"))?;
            }
            Some(plan)
        }
        None => None,
    };
    let maps = crate::map::catalog::load_prepared(&cfg.maps)
        .with_context(|| format!("maps = \"{}\"", cfg.maps))?;
    let mut trainer = if args.resume {
        let t = Trainer::resume(cfg.clone(), maps, &run_dir)?;
        keep_metrics_up_to(&run_dir.join("metrics.csv"), t.iteration)?;
        tracing::info!(
            "resuming {} at iteration {}, {} env steps",
            run_dir.display(),
            t.iteration,
            t.env_steps
        );
        t
    } else {
        // Written whole and renamed: a run killed here leaves no half config
        // for --resume to read.
        crate::fs::write_file_atomically(
            &run_dir.join("config.toml"),
            toml::to_string_pretty(&cfg)?.as_bytes(),
        )?;
        let _ = std::fs::remove_file(run_dir.join("metrics.csv"));
        Trainer::new(cfg.clone(), maps)?
    };
    if let Some(d) = run_for {
        trainer.set_clock_budget(d.as_secs_f64());
    }
    ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            tracing::info!("\nsecond Ctrl-C: quitting without a final checkpoint");
            std::process::exit(130);
        }
        tracing::info!("\nCtrl-C: finishing this iteration and writing a checkpoint (Ctrl-C again to quit now)");
    })
    .context("cannot install the Ctrl-C handler")?;

    let learners: Vec<String> = trainer
        .learner_sides()
        .iter()
        .map(|(s, a)| format!("{} {}", s.name(), a.name()))
        .collect();
    let extra = if cfg.extra_maps.is_off() {
        String::new()
    } else {
        format!(
            " + extra maps {:?} for {:.0}% of the episodes (a training option: not the protocol's maps alone)",
            cfg.extra_maps.maps,
            100.0 * cfg.extra_maps.share
        )
    };
    let sampling = match cfg.map_sampling {
        crate::learn::map_sampling::MapSampling::Uniform => "",
        crate::learn::map_sampling::MapSampling::ClassBalanced => {
            " drawn class-balanced (a training option: each size class a third of the episodes)"
        }
    };
    tracing::info!(
        "training {} on maps {:?}{sampling}{extra}, {} worlds, device {:?}, {threads} threads ({why}), run folder {}",
        learners.join(" + "),
        cfg.maps,
        cfg.num_envs,
        trainer.device,
        run_dir.display()
    );
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(cfg.total_env_steps);
        b.set_style(
            ProgressStyle::with_template(
                "[{elapsed_precise}] [{bar:25}] {human_pos}/{human_len} steps {msg}",
            )
            .unwrap()
            .progress_chars("=> "),
        );
        b.set_position(trainer.env_steps);
        b
    };
    let metrics_path = run_dir.join("metrics.csv");
    let mut recent: Vec<Metrics> = Vec::new();
    let mut periodic = eval_plan.map(|p| PeriodicEval::new(p, &run_dir));
    let started = std::time::Instant::now();
    let mut out_of_time = false;
    while trainer.env_steps < cfg.total_env_steps && !STOP.load(Ordering::SeqCst) {
        if run_for.is_some_and(|d| started.elapsed() >= d) {
            out_of_time = true;
            break;
        }
        let m = trainer.iterate()?;
        append_metrics(&metrics_path, &m)?;
        bar.set_position(m.env_steps);
        recent.push(m);
        if recent.len() > 5 {
            recent.remove(0);
        }
        bar.set_message(status_line(&recent));
        let eval_due = periodic.as_ref().is_some_and(|p| p.is_due());
        if trainer.iteration % cfg.checkpoint_every == 0 || eval_due {
            let written = trainer.save(&run_dir)?;
            write_curves(&run_dir)?;
            if args.quiet && trainer.iteration % cfg.checkpoint_every == 0 {
                tracing::info!("iteration {}: {}", trainer.iteration, status_line(&recent));
            }
            if let (true, Some(p)) = (eval_due, periodic.as_mut()) {
                let sides: Vec<_> = trainer
                    .learner_sides()
                    .into_iter()
                    .map(|(s, _)| s)
                    .zip(written)
                    .collect();
                launch_or_warn(p, &sides, trainer.env_steps, trainer.wall_s);
            }
        }
        if let Some(p) = periodic.as_mut() {
            p.collect(false)?;
        }
    }
    let written = trainer.save(&run_dir)?;
    write_curves(&run_dir)?;
    bar.finish_and_clear();
    if let Some(p) = periodic.as_mut() {
        // The last checkpoint too, then every evaluation still running.
        let sides: Vec<_> = trainer
            .learner_sides()
            .into_iter()
            .map(|(s, _)| s)
            .zip(written.iter().cloned())
            .collect();
        launch_or_warn(p, &sides, trainer.env_steps, trainer.wall_s);
        tracing::info!("waiting for the periodic evaluations to finish");
        p.collect(true)?;
    }
    let why = if STOP.load(Ordering::SeqCst) {
        "stopped"
    } else if out_of_time {
        "out of time (--for)"
    } else {
        "done"
    };
    println!(
        "{why} after {} iterations, {} env steps, {:.1} min of training: {}",
        trainer.iteration,
        trainer.env_steps,
        trainer.wall_s / 60.0,
        status_line(&recent)
    );
    for w in written {
        println!("checkpoint {}", w.display());
    }
    println!("curves {}", run_dir.join("curves.png").display());
    Ok(())
}

/// An evaluation that cannot start (a full disk, no processes left) is
/// worth a warning, not the training run it watches.
fn launch_or_warn(
    p: &mut PeriodicEval,
    sides: &[(crate::env::Side, PathBuf)],
    env_steps: u64,
    wall_s: f64,
) {
    if let Err(e) = p.launch(sides, env_steps, wall_s) {
        tracing::warn!("periodic evaluation at {env_steps} env steps not started: {e:#}");
    }
}

/// Under the held-out protocol the Gibson maps are the test set: never
/// train on them (by name here; `Trainer` checks every map's content).
fn refuse_test_maps(spec: &str) -> Result<()> {
    let head = spec.split(':').next().unwrap_or("");
    let named_test = ["small", "medium", "large", "gibson"].contains(&head);
    let gibson = crate::map::catalog::gibson_dir().and_then(|d| d.canonicalize().ok());
    let is_gibson_dir = Path::new(head)
        .canonicalize()
        .ok()
        .is_some_and(|p| gibson.as_ref().is_some_and(|g| p.starts_with(g)));
    if named_test || is_gibson_dir {
        bail!("maps = \"{spec}\": the Gibson maps are the test set of protocol = \"held-out\"; train on generated maps (generated:N, shipped or a folder of your own), or set protocol = \"paper\" to train on them as the paper did");
    }
    Ok(())
}

/// Averages over the last few iterations, for the progress bar.
fn status_line(recent: &[Metrics]) -> String {
    if recent.is_empty() {
        return "no new iterations".into();
    }
    let mean = |f: &dyn Fn(&Metrics) -> f64| {
        let v: Vec<f64> = recent.iter().map(f).filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    // No episode finished yet: say so instead of printing NaN.
    let shown = |x: f64, digits: usize| {
        if x.is_finite() {
            format!("{x:.digits$}")
        } else {
            "-".into()
        }
    };
    format!(
        "| {} steps/s | capture {}% | ep len {} | return captor {} target {}",
        shown(mean(&|m| m.steps_per_s), 0),
        shown(100.0 * mean(&|m| m.capture_rate), 1),
        shown(mean(&|m| m.episode_len), 0),
        shown(mean(&|m| m.captor_return), 1),
        shown(mean(&|m| m.target_return), 1),
    )
}

fn append_metrics(path: &Path, m: &Metrics) -> Result<()> {
    let fresh = !path.exists();
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    let mut w = csv::WriterBuilder::new()
        .has_headers(fresh)
        .from_writer(file);
    w.serialize(m)?;
    w.flush()?;
    Ok(())
}

pub fn read_metrics(path: &Path) -> Result<Vec<Metrics>> {
    super::csv_rows::read_csv(path)
}

/// After a kill, rows past the last checkpoint describe iterations the
/// resumed run repeats: drop them.
fn keep_metrics_up_to(path: &Path, iteration: u64) -> Result<()> {
    let rows: Vec<Metrics> = read_metrics(path)?
        .into_iter()
        .filter(|m| m.iteration <= iteration)
        .collect();
    let _ = std::fs::remove_file(path);
    for m in &rows {
        append_metrics(path, m)?;
    }
    Ok(())
}

/// Capture rate and returns against environment steps, each point the
/// average over the episodes that ended in the last 20 iterations.
pub fn write_curves(run_dir: &Path) -> Result<()> {
    let rows = read_metrics(&run_dir.join("metrics.csv"))?;
    if rows.is_empty() {
        return Ok(());
    }
    let smooth = |f: &dyn Fn(&Metrics) -> f64| -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for i in 0..rows.len() {
            let (mut sum, mut n) = (0.0, 0usize);
            for m in &rows[i.saturating_sub(19)..=i] {
                if m.episodes > 0 && f(m).is_finite() {
                    sum += f(m) * m.episodes as f64;
                    n += m.episodes;
                }
            }
            if n > 0 {
                out.push((rows[i].env_steps as f64 / 1e6, sum / n as f64));
            }
        }
        out
    };
    let capture = line_plot(
        &[Series::new(
            "capture rate",
            smooth(&|m| 100.0 * m.capture_rate),
            plot::palette(0),
        )],
        "training episodes ending in capture",
        "env steps (M)",
        "%",
        800,
        360,
    );
    let returns = line_plot(
        &[
            Series::new("captor", smooth(&|m| m.captor_return), plot::palette(1)),
            Series::new("target", smooth(&|m| m.target_return), plot::palette(2)),
        ],
        "mean episode return per robot",
        "env steps (M)",
        "return",
        800,
        360,
    );
    let mut img = image::RgbImage::new(800, 720);
    image::imageops::replace(&mut img, &capture, 0, 0);
    image::imageops::replace(&mut img, &returns, 0, 360);
    plot::save_png(&img, run_dir.join("curves.png"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_test_maps_are_refused_for_training() {
        for spec in ["small", "medium:x", "gibson", "large"] {
            let err = refuse_test_maps(spec).unwrap_err().to_string();
            assert!(err.contains("test set"), "{spec}: {err}");
        }
        assert!(refuse_test_maps("generated:20").is_ok());
        assert!(refuse_test_maps("shipped").is_ok());
        if let Some(g) = crate::map::catalog::gibson_dir() {
            assert!(refuse_test_maps(&g.display().to_string()).is_err());
        }
    }

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
                crate::league::config::LeagueConfig::load(&p).unwrap();
                continue;
            }
            if p.extension().and_then(|x| x.to_str()) == Some("toml") {
                let cfg = TrainConfig::load(&p).unwrap();
                if cfg.protocol == crate::protocol::Protocol::HeldOut {
                    refuse_test_maps(&cfg.maps).unwrap();
                }
                n += 1;
            }
        }
        assert!(n >= 8, "{n} configs");
    }
}
