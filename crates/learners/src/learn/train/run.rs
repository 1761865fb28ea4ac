//! A training run from its first iteration to its last: `t2e-league train`
//! is this type's command line. It owns what a run folder holds beside the
//! checkpoints (`config.toml`, `metrics.csv`, `teacher.csv`, `curves.png`,
//! the periodic evaluations), starts or resumes the `Trainer`, and runs the loop:
//! iterate, append the metrics, checkpoint every `checkpoint_every`
//! iterations (and whenever a periodic evaluation is due), redraw the
//! curves, hand checkpoints to the periodic evaluation.
//!
//! On resume, metrics (and teacher) rows past the last checkpoint are dropped: they
//! describe iterations the resumed run plays again, and a kill -9 between
//! a row and its checkpoint would otherwise leave them twice.

use super::csv_rows::{append_row, keep_rows, read_csv};
use super::metrics::{Metrics, TeacherRow};
use super::periodic_eval::PeriodicEval;
use super::trainer::Trainer;
use crate::error::{LearnError, Result};
use crate::learn::map_sampling::MapSampling;
use crate::learn::run_config::TrainConfig;
use crate::nn::run_dir::{RunDir, RunDirError};
use crate::plots::line::{self, line_plot, Series};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use t2e_core::env::Side;
use t2e_core::map::PreparedMap;

/// How a run's loop ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
    /// `total_env_steps` reached.
    Done,
    /// The stop flag was raised (Ctrl-C).
    Stopped,
    /// This invocation's wall-clock budget (`--for`) ran out.
    OutOfTime,
}

impl Ended {
    pub fn label(self) -> &'static str {
        match self {
            Ended::Done => "done",
            Ended::Stopped => "stopped",
            Ended::OutOfTime => "out of time (--for)",
        }
    }
}

/// What the loop tells its caller after each iteration.
pub struct Iteration<'a> {
    pub metrics: &'a Metrics,
    /// The last few iterations' metrics (at most 5), newest last.
    pub recent: &'a [Metrics],
    /// Whether this iteration wrote a checkpoint on the run's schedule.
    pub checkpointed: bool,
}

/// The end of a run's loop: why, and the checkpoints it wrote last.
pub struct Finished {
    pub ended: Ended,
    pub checkpoints: Vec<PathBuf>,
    pub recent: Vec<Metrics>,
}

/// One training run in its folder.
pub struct TrainingRun {
    pub trainer: Trainer,
    cfg: TrainConfig,
    dir: RunDir,
    periodic: Option<PeriodicEval>,
    recent: Vec<Metrics>,
}

impl TrainingRun {
    /// A new run in `dir` (refused if `dir` already holds one): writes its
    /// `config.toml` whole, then builds the trainer.
    pub fn start(cfg: TrainConfig, maps: Arc<Vec<Arc<PreparedMap>>>, dir: &Path) -> Result<Self> {
        let dir = RunDir::new(dir);
        if dir.has_state() {
            return Err(RunDirError::HoldsARun(dir.root().to_path_buf()).into());
        }
        std::fs::create_dir_all(dir.root())
            .map_err(|e| LearnError::io(format!("cannot create {}", dir.root().display()), e))?;
        // Written whole and renamed: a run killed here leaves no half config
        // for --resume to read.
        let config = dir.config_path();
        let text = toml::to_string_pretty(&cfg).map_err(|cause| LearnError::Toml {
            context: format!("cannot write {}", config.display()),
            cause,
        })?;
        t2e_core::fs::write_file_atomically(&config, text.as_bytes())?;
        let _ = std::fs::remove_file(dir.metrics_path());
        let _ = std::fs::remove_file(dir.teacher_path());
        let trainer = Trainer::new(cfg.clone(), maps)?;
        Ok(TrainingRun::around(trainer, cfg, dir))
    }

    /// The run in `dir`, from the checkpoints its `state.json` names.
    pub fn resume(cfg: TrainConfig, maps: Arc<Vec<Arc<PreparedMap>>>, dir: &Path) -> Result<Self> {
        let dir = RunDir::new(dir);
        let trainer = Trainer::resume(cfg.clone(), maps, dir.root())?;
        let iteration = trainer.iteration;
        keep_rows(&dir.metrics_path(), |m: &Metrics| m.iteration <= iteration)?;
        for path in [dir.teacher_path(), dir.dagger_path()] {
            keep_rows(&path, |t: &TeacherRow| t.iteration <= iteration)?;
        }
        Ok(TrainingRun::around(trainer, cfg, dir))
    }

    fn around(trainer: Trainer, cfg: TrainConfig, dir: RunDir) -> TrainingRun {
        TrainingRun {
            trainer,
            cfg,
            dir,
            periodic: None,
            recent: Vec::new(),
        }
    }

    /// Who learns, on which maps, in how many worlds, on which device:
    /// the line a run's log starts with.
    pub fn describe(&self) -> String {
        let cfg = &self.cfg;
        let learners: Vec<String> = self
            .trainer
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
            MapSampling::Uniform => "",
            MapSampling::ClassBalanced => {
                " drawn class-balanced (a training option: each size class a third of the episodes)"
            }
        };
        format!(
            "training {} on maps {:?}{sampling}{extra}, {} worlds, device {:?}",
            learners.join(" + "),
            cfg.maps,
            cfg.num_envs,
            self.trainer.device
        )
    }

    pub fn dir(&self) -> &RunDir {
        &self.dir
    }

    /// Evaluates checkpoints as the run goes (`train --eval-every`).
    pub fn with_periodic_eval(mut self, periodic: PeriodicEval) -> Self {
        self.periodic = Some(periodic);
        self
    }

    /// Iterates until `total_env_steps`, `stop`, or `run_for` of this
    /// call's wall-clock, then checkpoints, redraws the curves and waits
    /// for the periodic evaluations still running.
    pub fn run(
        &mut self,
        stop: &AtomicBool,
        run_for: Option<Duration>,
        mut on_iteration: impl FnMut(&Iteration),
    ) -> Result<Finished> {
        let started = Instant::now();
        let mut ended = Ended::Done;
        while self.trainer.env_steps < self.cfg.total_env_steps {
            if stop.load(Ordering::SeqCst) {
                ended = Ended::Stopped;
                break;
            }
            if run_for.is_some_and(|d| started.elapsed() >= d) {
                ended = Ended::OutOfTime;
                break;
            }
            let m = self.trainer.iterate()?;
            append_row(&self.dir.metrics_path(), &m)?;
            if let Some(row) = TeacherRow::of(&m) {
                append_row(&self.dir.teacher_path(), &row)?;
            }
            if let Some(row) = TeacherRow::of_fitted(&m) {
                append_row(&self.dir.dagger_path(), &row)?;
            }
            self.recent.push(m.clone());
            if self.recent.len() > 5 {
                self.recent.remove(0);
            }
            let scheduled = self
                .trainer
                .iteration
                .is_multiple_of(self.cfg.checkpoint_every);
            let eval_due = self.periodic.as_ref().is_some_and(|p| p.is_due());
            if scheduled || eval_due {
                let written = self.trainer.save(self.dir.root())?;
                write_curves(&self.dir)?;
                if eval_due {
                    self.launch_eval(written);
                }
            }
            if let Some(p) = self.periodic.as_mut() {
                p.collect(false)?;
            }
            on_iteration(&Iteration {
                metrics: &m,
                recent: &self.recent,
                checkpointed: scheduled,
            });
        }
        if ended == Ended::Done && stop.load(Ordering::SeqCst) {
            ended = Ended::Stopped;
        }
        let written = self.trainer.save(self.dir.root())?;
        write_curves(&self.dir)?;
        if self.periodic.is_some() {
            // The last checkpoint too, then every evaluation still running.
            self.launch_eval(written.clone());
            tracing::info!("waiting for the periodic evaluations to finish");
            if let Some(p) = self.periodic.as_mut() {
                p.collect(true)?;
            }
        }
        Ok(Finished {
            ended,
            checkpoints: written,
            recent: self.recent.clone(),
        })
    }

    /// An evaluation that cannot start (a full disk, no processes left) is
    /// worth a warning, not the training run it watches.
    fn launch_eval(&mut self, written: Vec<PathBuf>) {
        let Some(p) = self.periodic.as_mut() else {
            return;
        };
        let sides: Vec<(Side, PathBuf)> = self
            .trainer
            .learner_sides()
            .into_iter()
            .map(|(s, _)| s)
            .zip(written)
            .collect();
        let env_steps = self.trainer.env_steps;
        if let Err(e) = p.launch(&sides, env_steps, self.trainer.wall_s) {
            tracing::warn!("periodic evaluation at {env_steps} env steps not started: {e:#}");
        }
    }
}

/// Averages over the last few iterations, for a progress line.
pub fn status_line(recent: &[Metrics]) -> String {
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

/// The rows of a run's `metrics.csv` (none before its first iteration).
pub fn read_metrics(dir: &RunDir) -> Result<Vec<Metrics>> {
    read_csv(&dir.metrics_path())
}

/// Capture rate and returns against environment steps, each point the
/// average over the episodes that ended in the last 20 iterations.
pub fn write_curves(dir: &RunDir) -> Result<()> {
    let rows = read_metrics(dir)?;
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
            line::palette(0),
        )],
        "training episodes ending in capture",
        "env steps (M)",
        "%",
        800,
        360,
    );
    let returns = line_plot(
        &[
            Series::new("captor", smooth(&|m| m.captor_return), line::palette(1)),
            Series::new("target", smooth(&|m| m.target_return), line::palette(2)),
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
    line::save_png(&img, dir.curves_path())
}
