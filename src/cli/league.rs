//! The league's subcommands: `run` (the manager), `status`, `export`, and
//! the hidden `league-learner` the manager spawns.

use crate::env::Side;
use crate::league::dir::LeagueDir;
use crate::league::store::StoreUrl;
use crate::league::supervision::{CannotStart, Outcome};
use crate::league::worker::WorkerOptions;
use crate::league::{learner, manager, process, status};
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
    /// The league's store, shared by workers on many hosts:
    /// postgres://USER[:PASSWORD]@HOST:PORT/DB (the password may come from
    /// PGPASSWORD instead), or a SQLite file. With it, --pool is the shared
    /// folder of snapshots and checkpoints, --dir holds the local workers'
    /// logs, and the seats run on workers. Default: league.db in --dir.
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// The pool folder every host shares (with --store).
    #[arg(long, value_name = "DIR")]
    pub pool: Option<PathBuf>,
    /// Workers this manager starts on its own host (with --store; default:
    /// one per seat; 0 leaves every seat to workers on other hosts).
    #[arg(long, value_name = "N")]
    pub workers: Option<usize>,
}

#[derive(clap::Args, Debug)]
pub struct WorkerArgs {
    /// The league's store (as `run --store`); default: $T2E_STORE.
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// The pool folder every host shares (as `run --pool`).
    #[arg(long, value_name = "DIR")]
    pub pool: PathBuf,
    /// A local folder for this worker's logs.
    #[arg(long, value_name = "DIR")]
    pub dir: PathBuf,
    /// Seats to run at once on this host.
    #[arg(long, default_value_t = 1)]
    pub seats: usize,
    /// The name its leases and heartbeats record (default: the hostname).
    #[arg(long)]
    pub host: Option<String>,
    /// Stop after this long: seats checkpoint and go back to the store.
    #[arg(long = "for", value_name = "DURATION", allow_hyphen_values = true)]
    pub run_for: Option<String>,
    /// How long a seat stays this worker's without a renewal; after that,
    /// another worker may take it (renewed every third of it).
    #[arg(long, value_name = "DURATION", default_value = "60s")]
    pub lease: String,
}

#[derive(clap::Args, Debug)]
pub struct StatusArgs {
    /// League directory (with --store: the pool folder, optional).
    #[arg(long, default_value = "runs/league/default")]
    pub dir: PathBuf,
    /// The league's store when it is not league.db in --dir (as `run --store`).
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
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
    /// The league's store when it is not league.db in --dir (as `run --store`).
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// The pool folder (with --store): where the player's files are.
    #[arg(long, value_name = "DIR")]
    pub pool: Option<PathBuf>,
    /// Folder to create: weights, sidecar, league config, rating history, SHA256SUMS.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct ExploitArgs {
    /// The frozen player: a name or id as `status` lists it, or a checkpoint
    /// folder of this league (a snapshot or an `export`).
    pub player: String,
    /// League directory (with --store: the pool folder).
    #[arg(long, default_value = "runs/league/default")]
    pub dir: PathBuf,
    /// The league's store when it is not league.db in --dir (as `run --store`).
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// How long the best response trains: env steps (200000) or training
    /// wall-clock (90s, 10m, 2h).
    #[arg(long, allow_hyphen_values = true)]
    pub budget: String,
    /// Seeds the best response's weights, its training episodes and the
    /// evaluation's starts.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Evaluation map sets, comma-separated (as `eval --maps`); one row each.
    #[arg(long, default_value = "small,medium,large", value_delimiter = ',')]
    pub maps: Vec<String>,
    /// Evaluation episodes per map set.
    #[arg(long, default_value_t = 200)]
    pub episodes: usize,
    /// Steps before an evaluation episode counts as escaped (the paper tests on 500).
    #[arg(long, default_value_t = 500)]
    pub episode_length: u32,
    /// v_e / v_p (default: the league's first curriculum stage).
    #[arg(long)]
    pub speed_ratio: Option<f64>,
    /// Threads for libtorch and rayon alike.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Hide the progress bars.
    #[arg(long)]
    pub quiet: bool,
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
    let Some(store) = &args.store else {
        if args.pool.is_some() || args.workers.is_some() {
            bail!("--pool and --workers go with --store URL (a league whose seats run on workers)");
        }
        return manager::run(&LeagueDir::new(dir), args.config.as_deref(), run_for, &STOP);
    };
    let url = StoreUrl::parse(store).map_err(anyhow::Error::msg)?;
    let Some(pool) = &args.pool else {
        bail!("--store {url}: give --pool DIR too, the folder every host shares");
    };
    let league = LeagueDir::with_store(pool, url);
    let seats = {
        let cfg = match &args.config {
            Some(c) => crate::league::config::LeagueConfig::load(c)?,
            None => league.config()?,
        };
        2 + [Side::Captors, Side::Target]
            .into_iter()
            .filter(|s| cfg.exploiters.enabled(*s))
            .count()
            + usize::from(cfg.evaluator.enabled)
    };
    let launch = manager::Launch::Workers {
        local: args.workers.unwrap_or(seats),
        logs: dir.join("logs"),
    };
    manager::run_with(&league, args.config.as_deref(), run_for, &STOP, &launch)
}

/// The league directory of `--dir` and `--store`: league.db in it by default.
fn league_dir(dir: &std::path::Path, store: Option<&str>) -> Result<LeagueDir> {
    Ok(match store {
        None => LeagueDir::new(dir),
        Some(s) => LeagueDir::with_store(dir, StoreUrl::parse(s).map_err(anyhow::Error::msg)?),
    })
}

pub fn worker(args: WorkerArgs) -> Result<()> {
    let store = match args
        .store
        .clone()
        .or_else(|| std::env::var("T2E_STORE").ok())
    {
        Some(s) => s,
        None => bail!("--store: give the league's store URL (or set T2E_STORE)"),
    };
    let url = StoreUrl::parse(&store).map_err(anyhow::Error::msg)?;
    let opts = WorkerOptions {
        seats: args.seats,
        host: args
            .host
            .clone()
            .unwrap_or_else(crate::league::store::host_name),
        run_for: args
            .run_for
            .as_deref()
            .map(|t| crate::util::parse_duration("--for", t))
            .transpose()
            .map_err(anyhow::Error::msg)?,
        lease: crate::util::parse_duration("--lease", &args.lease).map_err(anyhow::Error::msg)?,
        logs: args.dir.join("logs"),
    };
    opts.check()?;
    if !args.pool.is_dir() {
        bail!(
            "--pool {}: not a folder; give the league's pool folder, the one every host shares",
            args.pool.display()
        );
    }
    // Children read the host name from the environment (heartbeats).
    std::env::set_var("T2E_HOST", &opts.host);
    on_ctrl_c()?;
    crate::league::worker::run_worker(&LeagueDir::with_store(&args.pool, url), &opts, &STOP)
}

pub fn status(args: StatusArgs) -> Result<()> {
    let dir = league_dir(&args.dir, args.store.as_deref())?;
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
    let dir = match (&args.store, &args.pool) {
        (Some(_), None) => {
            bail!("--store: give --pool DIR too, the folder that holds the players' files")
        }
        (Some(s), Some(pool)) => league_dir(pool, Some(s))?,
        (None, Some(_)) => bail!("--pool goes with --store URL"),
        (None, None) => LeagueDir::new(&args.dir),
    };
    status::export(&dir, &args.player, &args.out)?;
    println!("exported {} -> {}", args.player, args.out.display());
    Ok(())
}

pub fn exploit(args: ExploitArgs) -> Result<()> {
    use crate::league::exploit::{self, Budget, ExploitOptions, ExploitOutcome};
    let dir = league_dir(&args.dir, args.store.as_deref())?;
    let opts = ExploitOptions {
        budget: Budget::parse(&args.budget).map_err(anyhow::Error::msg)?,
        seed: args.seed,
        maps: args.maps.clone(),
        episodes: args.episodes,
        episode_length: args.episode_length,
        speed_ratio: args.speed_ratio,
        threads: args.threads,
        progress: !args.quiet,
    };
    on_ctrl_c()?;
    match exploit::run(&dir, &args.player, &opts, &STOP)? {
        ExploitOutcome::Recorded {
            rows,
            player,
            fresh,
        } => {
            if !fresh {
                println!("already recorded in the store (the same player, weights, learner, budget, seed and evaluation):");
            }
            print!("{}", exploit::render(&rows, &player));
            Ok(())
        }
        ExploitOutcome::Stopped { env_steps, folder } => {
            eprintln!(
                "stopped at {env_steps} env steps, nothing recorded; the same command resumes it from {}",
                folder.display()
            );
            std::process::exit(130)
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct EvaluatorArgs {
    #[arg(long)]
    pub dir: PathBuf,
}

pub fn evaluator(args: EvaluatorArgs) -> Result<()> {
    let dir = process::dir_from_env(&args.dir)?;
    let lock_path = dir.root.join("learners").join("evaluator.lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = process::try_lock(&lock_path)? else {
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
fn exit_with(result: Result<Outcome>) -> Result<()> {
    use crate::league::supervision::{EXIT_CANNOT_START, EXIT_STOPPED};
    match result {
        Ok(Outcome::Done) => Ok(()),
        Ok(Outcome::Stopped) => std::process::exit(EXIT_STOPPED),
        Err(e) if e.downcast_ref::<CannotStart>().is_some() => {
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
    let dir = process::dir_from_env(&args.dir)?;
    let seat = crate::league::players::Seat {
        side,
        exploiter: args.exploiter,
    };
    let lock_path = dir.seat_dir(seat).with_extension("lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = process::try_lock(&lock_path)? else {
        bail!(
            "{}: another {} is running this league",
            lock_path.display(),
            seat.name()
        );
    };
    on_ctrl_c()?;
    exit_with(learner::run_learner(&dir, seat, &STOP))
}
