//! The league's subcommands: `run` (the manager), `status`, `export`, and
//! the hidden `league-learner` the manager spawns.

use crate::env::Side;
use crate::league::dir::LeagueDir;
use crate::league::{learner, manager, status};
use anyhow::{bail, Context, Result};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// League config (TOML; see configs/league-*.toml). Needed to start a
    /// league; a directory that holds one resumes it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// League directory (default: runs/league/NAME, NAME from the config).
    #[arg(long)]
    pub dir: Option<PathBuf>,
    /// Stop after this long (e.g. 90s, 10m, 2h): every learner finishes its
    /// iteration and checkpoints. Without it, the league runs to its budget.
    #[arg(long = "for", value_name = "DURATION", allow_hyphen_values = true)]
    pub run_for: Option<String>,
}

#[derive(clap::Args, Debug)]
pub struct StatusArgs {
    /// League directory.
    #[arg(long, default_value = "runs/league/default")]
    pub dir: PathBuf,
    /// Print the documented JSON shape (see src/league/status.rs) instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Redraw every this many seconds until Ctrl-C.
    #[arg(long, value_name = "SECONDS")]
    pub watch: Option<f64>,
    /// Also draw ratings over time and the payoff matrix as a heat map (PNG).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Player name (as `status` lists it) or id.
    pub player: String,
    /// League directory.
    #[arg(long, default_value = "runs/league/default")]
    pub dir: PathBuf,
    /// Folder to create: weights, sidecar, league config, rating history, SHA256SUMS.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct LearnerArgs {
    #[arg(long)]
    pub dir: PathBuf,
    /// captors or target.
    #[arg(long)]
    pub side: String,
    /// Run the side's main exploiter instead of its main learner.
    #[arg(long)]
    pub exploiter: bool,
}

static STOP: AtomicBool = AtomicBool::new(false);

fn on_ctrl_c() -> Result<()> {
    ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst))
        .context("cannot install the Ctrl-C handler")
}

pub fn run(args: RunArgs) -> Result<()> {
    let run_for = args
        .run_for
        .as_deref()
        .map(|t| crate::util::parse_duration("--for", t))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let dir = match (&args.dir, &args.config) {
        (Some(d), _) => d.clone(),
        (None, Some(c)) => {
            let cfg = crate::league::config::LeagueConfig::load(c)?;
            let name = crate::util::safe_component(&cfg.name, 100);
            PathBuf::from("runs/league").join(name)
        }
        (None, None) => bail!(
            "give --config configs/league-*.toml to start a league, or --dir DIR to resume one"
        ),
    };
    on_ctrl_c()?;
    manager::run(&LeagueDir::new(dir), args.config.as_deref(), run_for, &STOP)
}

pub fn status(args: StatusArgs) -> Result<()> {
    let dir = LeagueDir::new(&args.dir);
    if let Some(w) = args.watch {
        if !(w.is_finite() && w >= 0.5) {
            bail!("--watch {w}: must be at least 0.5 seconds");
        }
        on_ctrl_c()?;
    }
    loop {
        let r = status::report(&dir)?;
        if let Some(p) = &args.plot {
            status::plot(&dir, &r, p)?;
        }
        if args.json {
            println!("{}", serde_json::to_string_pretty(&r)?);
        } else {
            if args.watch.is_some() {
                print!("\x1b[2J\x1b[H");
            }
            print!("{}", status::render(&r));
        }
        let Some(w) = args.watch else { break };
        let until = std::time::Instant::now() + std::time::Duration::from_secs_f64(w);
        while std::time::Instant::now() < until {
            if STOP.load(Ordering::SeqCst) {
                return Ok(());
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }
    Ok(())
}

pub fn export(args: ExportArgs) -> Result<()> {
    status::export(&LeagueDir::new(&args.dir), &args.player, &args.out)?;
    println!("exported {} -> {}", args.player, args.out.display());
    Ok(())
}

#[derive(clap::Args, Debug)]
pub struct EvaluatorArgs {
    #[arg(long)]
    pub dir: PathBuf,
}

pub fn evaluator(args: EvaluatorArgs) -> Result<()> {
    let dir = LeagueDir::new(&args.dir);
    let lock_path = dir.root.join("learners").join("evaluator.lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = manager::try_lock(&lock_path)? else {
        bail!(
            "{}: another evaluator is running this league",
            lock_path.display()
        );
    };
    on_ctrl_c()?;
    exit_with(crate::league::evaluator::run_evaluator(&dir, &STOP))
}

/// A league process's exit code (`league::supervision`): the manager reads
/// the outcome from it.
fn exit_with(result: Result<learner::Outcome>) -> Result<()> {
    use crate::league::supervision::{EXIT_CANNOT_START, EXIT_STOPPED};
    match result {
        Ok(learner::Outcome::Done) => Ok(()),
        Ok(learner::Outcome::Stopped) => std::process::exit(EXIT_STOPPED),
        Err(e) if e.downcast_ref::<learner::CannotStart>().is_some() => {
            eprintln!("error: {e:#}");
            std::process::exit(EXIT_CANNOT_START)
        }
        Err(e) => Err(e),
    }
}

pub fn learner(args: LearnerArgs) -> Result<()> {
    let side = match args.side.as_str() {
        "captors" => Side::Captors,
        "target" => Side::Target,
        other => bail!("--side {other}: expected captors or target"),
    };
    let dir = LeagueDir::new(&args.dir);
    let seat = learner::Seat {
        side,
        exploiter: args.exploiter,
    };
    let lock_path = dir.seat_dir(seat).with_extension("lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = manager::try_lock(&lock_path)? else {
        bail!(
            "{}: another {} is running this league",
            lock_path.display(),
            seat.name()
        );
    };
    on_ctrl_c()?;
    exit_with(learner::run_learner(&dir, seat, &STOP))
}
