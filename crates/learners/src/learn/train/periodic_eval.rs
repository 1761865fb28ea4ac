//! `train --eval-every`: the curve researchers read, SR with its interval
//! against wall-clock time and env steps. Every period the trainer hands
//! its newest checkpoint (an immutable folder) to a child `t2e-league eval`
//! at the lowest CPU priority with one thread, so evaluation takes only the
//! cycles training leaves idle and never changes what training does. Rows
//! land in `eval.csv` and `eval.png` of the run folder as children finish.

use crate::error::{LearnError, Result, ResultExt};
use crate::eval::Summary;
use crate::nn::run_dir::RunDir;
use crate::plots::line::{self, line_plot, Series};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// One row of `eval.csv`: one checkpoint on one map set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalRow {
    pub env_steps: u64,
    /// Training wall-clock of the run when the checkpoint was written (s).
    pub wall_s: f64,
    /// `captors` or `target`: the side evaluated against the rule-based other.
    pub side: String,
    pub maps: String,
    pub episodes: usize,
    pub episode_length: u32,
    pub sr: f64,
    pub sr_low: f64,
    pub sr_high: f64,
    pub time: f64,
    /// A target's departure rate (%): its decisions that differ from the
    /// rule-based target's (empty for captors, and in older files).
    #[serde(default)]
    pub departure: Option<f64>,
}

/// What to evaluate and how often.
#[derive(Clone, Debug)]
pub struct EvalPlan {
    pub every: Duration,
    pub maps: Vec<String>,
    pub episodes: usize,
    pub episode_length: u32,
    pub seed: u64,
    pub num_captors: usize,
    pub speed_ratio: f64,
}

impl EvalPlan {
    /// Checks the plan before training starts, so a typo in an evaluation
    /// flag fails now and not at the first period: its settings, and that
    /// every map set loads. Errors name the flag.
    pub fn validate(&self) -> Result<()> {
        crate::eval::EvalSetting {
            num_captors: self.num_captors,
            speed_ratio: self.speed_ratio,
            episodes: self.episodes,
            episode_length: self.episode_length,
            ..Default::default()
        }
        .validate()
        .context("--eval-episodes / --eval-episode-length")?;
        for m in &self.maps {
            t2e_core::map::catalog::load_prepared(m).with_context(|| format!("--eval-maps {m}"))?;
        }
        Ok(())
    }
}

struct Running {
    child: Child,
    side: String,
    env_steps: u64,
    wall_s: f64,
    out: PathBuf,
}

pub struct PeriodicEval {
    plan: EvalPlan,
    dir: RunDir,
    next_due: Instant,
    running: Vec<Running>,
    /// Env steps of the last checkpoint handed out: the run's final
    /// checkpoint may be the one just evaluated.
    last_launched: Option<u64>,
}

impl PeriodicEval {
    pub fn new(plan: EvalPlan, dir: &RunDir) -> PeriodicEval {
        PeriodicEval {
            next_due: Instant::now() + plan.every,
            plan,
            dir: dir.clone(),
            running: Vec::new(),
            last_launched: None,
        }
    }

    pub fn is_due(&self) -> bool {
        Instant::now() >= self.next_due
    }

    /// Starts evaluating the checkpoint folders `checkpoints` ((side, dir),
    /// as `Trainer::save` wrote them) at `env_steps` and `wall_s`.
    pub fn launch(
        &mut self,
        checkpoints: &[(t2e_core::env::Side, PathBuf)],
        env_steps: u64,
        wall_s: f64,
    ) -> Result<()> {
        self.next_due = Instant::now() + self.plan.every;
        if self.last_launched == Some(env_steps) {
            return Ok(());
        }
        self.last_launched = Some(env_steps);
        for (side, dir) in checkpoints {
            let out = self.dir.eval_dir(*side, env_steps);
            std::fs::create_dir_all(&out)
                .map_err(|e| LearnError::io(format!("cannot create {}", out.display()), e))?;
            let ckpt = format!("ckpt:{}", dir.display());
            let (captors, target) = match side {
                t2e_core::env::Side::Captors => (ckpt.as_str(), "heuristic"),
                t2e_core::env::Side::Target => ("heuristic", ckpt.as_str()),
            };
            let log_path = out.join("eval.log");
            let cannot_write =
                |e| LearnError::io(format!("cannot write {}", log_path.display()), e);
            let cannot_start = |cause| LearnError::Process {
                what: "cannot start the periodic evaluation".into(),
                cause,
            };
            let log = std::fs::File::create(&log_path).map_err(cannot_write)?;
            let mut cmd = t2e_core::util::own_command().map_err(cannot_start)?;
            cmd.args(["eval", "--captors", captors, "--target", target])
                .args(["--k", &self.plan.num_captors.to_string()])
                .args(["--speed-ratio", &self.plan.speed_ratio.to_string()])
                .args(["--maps", &self.plan.maps.join(",")])
                .args(["--episodes", &self.plan.episodes.to_string()])
                .args(["--episode-length", &self.plan.episode_length.to_string()])
                .args(["--seed", &self.plan.seed.to_string()])
                .args(["--soa-every", "0", "--quiet", "--out"])
                .arg(&out)
                .env("RAYON_NUM_THREADS", "1")
                .env("OMP_NUM_THREADS", "1")
                .stdin(Stdio::null())
                .stdout(log.try_clone().map_err(cannot_write)?)
                .stderr(log);
            lowest_priority(&mut cmd);
            let child = cmd.spawn().map_err(cannot_start)?;
            self.running.push(Running {
                child,
                side: side.name().to_string(),
                env_steps,
                wall_s,
                out,
            });
        }
        Ok(())
    }

    /// Collects finished evaluations into `eval.csv` / `eval.png`; with
    /// `wait`, first waits for every running one (the run's end).
    pub fn collect(&mut self, wait: bool) -> Result<()> {
        let mut new_rows = Vec::new();
        let mut still = Vec::new();
        for mut r in self.running.drain(..) {
            let status = if wait {
                r.child.wait().map(Some)
            } else {
                r.child.try_wait()
            }
            .map_err(|cause| LearnError::Process {
                what: format!(
                    "cannot wait for the periodic evaluation at {} env steps",
                    r.env_steps
                ),
                cause,
            })?;
            match status {
                None => still.push(r),
                Some(s) if s.success() => {
                    new_rows.extend(rows_of(&r)?);
                }
                Some(s) => tracing::warn!(
                    "periodic evaluation at {} env steps failed ({s}); see {}",
                    r.env_steps,
                    r.out.join("eval.log").display()
                ),
            }
        }
        self.running = still;
        if !new_rows.is_empty() {
            let path = self.dir.eval_csv_path();
            let mut rows = read_rows(&path)?;
            rows.extend(new_rows);
            rows.sort_by(|a, b| {
                (a.env_steps, &a.side, &a.maps).cmp(&(b.env_steps, &b.side, &b.maps))
            });
            write_rows(&path, &rows)?;
            plot_rows(&self.dir.eval_png_path(), &rows)?;
            if rows.iter().any(|r| r.departure.is_some()) {
                plot_departure(&self.dir.departure_png_path(), &rows)?;
            }
        }
        Ok(())
    }
}

/// nice 19: the child runs on cycles nothing else wants.
fn lowest_priority(cmd: &mut Command) {
    use std::os::unix::process::CommandExt;
    // SAFETY: setpriority is async-signal-safe and touches only this process.
    unsafe {
        cmd.pre_exec(|| {
            libc::setpriority(libc::PRIO_PROCESS, 0, 19);
            Ok(())
        });
    }
}

fn rows_of(r: &Running) -> Result<Vec<EvalRow>> {
    let path = r.out.join("summary.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| LearnError::io(format!("cannot read {}", path.display()), e))?;
    let summaries: Vec<Summary> =
        serde_json::from_str(&text).map_err(|cause| LearnError::Json {
            context: format!("{}: malformed", path.display()),
            cause,
        })?;
    Ok(summaries
        .into_iter()
        .map(|s| EvalRow {
            env_steps: r.env_steps,
            wall_s: r.wall_s,
            side: r.side.clone(),
            maps: s.maps,
            episodes: s.episodes,
            episode_length: s.episode_length,
            sr: s.sr,
            sr_low: s.sr_low,
            sr_high: s.sr_high,
            time: s.time,
            departure: s.target_departure,
        })
        .collect())
}

pub fn read_rows(path: &Path) -> Result<Vec<EvalRow>> {
    super::csv_rows::read_csv(path)
}

fn write_rows(path: &Path, rows: &[EvalRow]) -> Result<()> {
    let context = || format!("cannot write {}", path.display());
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|cause| LearnError::Csv {
            context: context(),
            cause,
        })?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| LearnError::io(context(), e.into_error()))?;
    Ok(t2e_core::fs::write_file_atomically(path, &bytes)?)
}

/// SR per map set against wall-clock minutes (top) and env steps (bottom),
/// each point with its 95% interval drawn as a lighter band of two lines.
pub fn plot_rows(path: &Path, rows: &[EvalRow]) -> Result<()> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.side.clone(), r.maps.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let series = |x: &dyn Fn(&EvalRow) -> f64| -> Vec<Series> {
        let mut out = Vec::new();
        for (i, (side, maps)) in keys.iter().enumerate() {
            let pick: Vec<&EvalRow> = rows
                .iter()
                .filter(|r| &r.side == side && &r.maps == maps)
                .collect();
            let label = if keys.iter().all(|(s, _)| s == side) {
                maps.clone()
            } else {
                format!("{side} {maps}")
            };
            let color = line::palette(i);
            let light = color.map(|c| ((c as u16 + 2 * 255) / 3) as u8);
            out.push(Series::new(
                format!("{label} (light: 95% CI)"),
                pick.iter().map(|r| (x(r), r.sr)).collect(),
                color,
            ));
            out.push(Series::new(
                "",
                pick.iter().map(|r| (x(r), r.sr_low)).collect(),
                light,
            ));
            out.push(Series::new(
                "",
                pick.iter().map(|r| (x(r), r.sr_high)).collect(),
                light,
            ));
        }
        out
    };
    let by_time = line_plot(
        &series(&|r| r.wall_s / 60.0),
        "SR against the rule-based opponent (episodes of the eval length)",
        "training wall-clock (min)",
        "SR %",
        800,
        360,
    );
    let by_steps = line_plot(
        &series(&|r| r.env_steps as f64 / 1e6),
        "SR against env steps",
        "env steps (M)",
        "SR %",
        800,
        360,
    );
    let mut img = image::RgbImage::new(800, 720);
    image::imageops::replace(&mut img, &by_time, 0, 0);
    image::imageops::replace(&mut img, &by_steps, 0, 360);
    line::save_png(&img, path)
}

/// A learned target's departure rate (% of its decisions that are not the
/// rule-based target's) per map set against env steps: how far training
/// has taken it from a copy.
pub fn plot_departure(path: &Path, rows: &[EvalRow]) -> Result<()> {
    let mut maps: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.departure.is_some()) {
        if !maps.contains(&r.maps.as_str()) {
            maps.push(&r.maps);
        }
    }
    let series: Vec<Series> = maps
        .iter()
        .enumerate()
        .map(|(i, m)| {
            Series::new(
                m.to_string(),
                rows.iter()
                    .filter(|r| r.maps == *m)
                    .filter_map(|r| r.departure.map(|d| (r.env_steps as f64 / 1e6, d)))
                    .collect(),
                line::palette(i),
            )
        })
        .collect();
    let img = line_plot(
        &series,
        "target decisions that differ from the rule-based target's",
        "env steps (M)",
        "departure %",
        800,
        360,
    );
    line::save_png(&img, path)
}
