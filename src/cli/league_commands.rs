//! The league's subcommands: `run` (the manager), `status`, `export`, and
//! the hidden `league-learner` the manager spawns.

use super::flag_error::as_flag;
use super::progress::Bars;
use anyhow::{bail, Context, Result};
use league::error::LeagueError;
use league::rules::players::Role;
use league::rules::supervision::Outcome;
use league::run::folder::layout::LeagueDir;
use league::run::processes::child::{self, ChildCommand};
use league::run::processes::worker::WorkerOptions;
use league::run::processes::{manager, spawn};
use league::run::view::{Quiet, View};
use league::run::{seat::learner, status};
use league::store::StoreUrl;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use t2e_core::env::Side;

#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// League config (TOML; see configs/league-*.toml). Needed to start a
    /// league; to resume one, --dir alone is enough.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// League folder (default: runs/league/NAME, NAME from the config); give
    /// it alone to resume that league. With --store: the folder of the local
    /// workers' logs.
    #[arg(long, value_name = "DIR")]
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
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = workers_in_range)]
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
    /// Seats to run at once on this host, 1 to 256.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = seats_in_range)]
    pub seats: usize,
    /// The name its leases and heartbeats record (default: the hostname).
    #[arg(long)]
    pub host: Option<String>,
    /// Stop after this long: seats checkpoint and go back to the store.
    #[arg(long = "for", value_name = "DURATION", allow_hyphen_values = true)]
    pub run_for: Option<String>,
    /// How long a seat stays this worker's without a renewal; after that,
    /// another worker may take it (renewed every third of it).
    #[arg(
        long,
        value_name = "DURATION",
        default_value = "60s",
        allow_hyphen_values = true
    )]
    pub lease: String,
}

/// Where an existing league is, for the commands that read one (`status`,
/// `export`, `exploit`). `run` and `worker` declare their own: `run`'s
/// --dir names a league to create and `worker`'s flags are required.
#[derive(clap::Args, Debug)]
pub struct LeagueLocation {
    /// League folder (default: the only league folder under runs/league/).
    #[arg(long, value_name = "DIR")]
    pub dir: Option<PathBuf>,
    /// The league's store when it is not league.db in the league folder (as
    /// `run --store`).
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// The pool folder every host shares (with --store, as `run --pool`):
    /// where the players' files are, and where `exploit` writes its best
    /// response; `status` reads its report from the store alone.
    #[arg(long, value_name = "DIR")]
    pub pool: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub struct StatusArgs {
    #[command(flatten)]
    pub league: LeagueLocation,
    /// Print JSON instead of tables (fields: docs/reference/status-json.md).
    #[arg(long)]
    pub json: bool,
    /// Redraw every DURATION (e.g. 5s, 1m; a bare number is seconds; at
    /// least 0.5s) until Ctrl-C.
    #[arg(long, value_name = "DURATION", allow_hyphen_values = true)]
    pub watch: Option<String>,
    /// Also draw ratings over time and the payoff matrix as a heat map (PNG).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

/// A side, as the command line names it.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum SideArg {
    Captors,
    Target,
}

impl From<SideArg> for t2e_core::env::Side {
    fn from(s: SideArg) -> Self {
        match s {
            SideArg::Captors => t2e_core::env::Side::Captors,
            SideArg::Target => t2e_core::env::Side::Target,
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Player name (as `status` lists it) or id.
    #[arg(required_unless_present = "best", conflicts_with = "best")]
    pub player: Option<String>,
    /// Export the main learner's snapshot of this side (captors or target)
    /// that did best on the validation panel (`[evaluator] validation_*`),
    /// among those whose validation games are all played.
    #[arg(long, value_name = "SIDE")]
    pub best: Option<SideArg>,
    #[command(flatten)]
    pub league: LeagueLocation,
    /// Folder to create: weights, sidecar, league config, rating history, SHA256SUMS.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct ExploitArgs {
    /// The frozen player: a name or id as `status` lists it, or a checkpoint
    /// folder of this league (a snapshot or an `export`).
    pub player: String,
    #[command(flatten)]
    pub league: LeagueLocation,
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
    /// Evaluation episodes per map set: 500, as `eval --episodes` (the
    /// paper's protocol). The league results in docs/ give --episodes 100,
    /// to fit two CPU cores.
    #[arg(long, default_value_t = 500)]
    pub episodes: usize,
    /// Steps before an evaluation episode counts as escaped (the paper tests on 500).
    #[arg(long, default_value_t = 500)]
    pub episode_length: u32,
    /// v_e / v_p (default: the league's first curriculum stage).
    #[arg(long)]
    pub speed_ratio: Option<f64>,
    /// A target best response's `heuristic_prior`: 10 leans on the
    /// rule-based target's action, 0 starts from nothing (default: the
    /// league's target learner's). Give the same value to compare two
    /// leagues' captors: a prior-free best response can stay weaker than the
    /// rule-based target.
    #[arg(long)]
    pub heuristic_prior: Option<f64>,
    /// Threads for libtorch and rayon alike.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Hide the progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// A league seat's process (`league-learner`, `league-evaluator`), spawned
/// by `run` or a worker: its arguments are read by the league's own typed
/// command (`league::run::processes::child::ChildCommand`), the one that wrote them.
#[derive(clap::Args, Debug)]
pub struct SeatArgs {
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
    pub args: Vec<std::ffi::OsString>,
}

impl SeatArgs {
    fn read(&self, subcommand: &str) -> Result<(Role, LeagueDir)> {
        match ChildCommand::parse_seat(subcommand, &self.args)? {
            ChildCommand::Seat { role, dir } => Ok((role, spawn::dir_from_env(&dir)?)),
            other => bail!("{subcommand}: not a seat ({other:?})"),
        }
    }
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
        .map(|t| t2e_core::util::parse_duration("--for", t))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let dir = match (&args.dir, &args.config) {
        (Some(d), _) => d.clone(),
        (None, Some(c)) => {
            let cfg = league::rules::config::LeagueConfig::load(c)?;
            let name = t2e_core::util::safe_component(&cfg.name, 100);
            PathBuf::from(LEAGUES).join(name)
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
        return Ok(manager::run(
            &LeagueDir::new(dir),
            args.config.as_deref(),
            run_for,
            &STOP,
            &Bars::default(),
        )?);
    };
    let url = StoreUrl::parse(store).map_err(anyhow::Error::msg)?;
    let Some(pool) = &args.pool else {
        bail!("--store {url}: give --pool DIR too, the folder every host shares");
    };
    refuse_file_as_pool(pool)?;
    let league = LeagueDir::with_store(pool, url);
    let seats = {
        let cfg = match &args.config {
            Some(c) => league::rules::config::LeagueConfig::load(c)?,
            None => league.config()?,
        };
        2 + [Side::Captors, Side::Target]
            .into_iter()
            .filter(|s| cfg.exploiters.enabled(*s))
            .count()
            + usize::from(cfg.evaluator.enabled)
    };
    match args.workers {
        Some(n) if n > MAX_LOCAL_WORKERS => bail!(
            "--workers {n}: at most {MAX_LOCAL_WORKERS} on one host (this league has {seats} seats; a local worker runs one)"
        ),
        Some(n) if n > seats => tracing::warn!(
            "--workers {n} for {seats} seats: {} stand by, each a process of its own (about 190 MB), to take a seat whose worker dies",
            n - seats
        ),
        Some(n) if n > 0 && n < seats => tracing::warn!(
            "--workers {n} of {seats} seats: the other {} run only when workers on other hosts take them; until then the main learners wait for each other (pace_env_steps)",
            seats - n
        ),
        _ => {}
    }
    let launch = manager::Launch::Workers {
        local: args.workers.unwrap_or(seats),
        logs: dir.join("logs"),
    };
    Ok(manager::run_with(
        &league,
        args.config.as_deref(),
        run_for,
        &STOP,
        &launch,
        &Bars::default(),
    )?)
}

/// Where status, export and exploit look for a league without --dir.
pub const LEAGUES: &str = "runs/league";

/// Whether `dir` holds a league: its store, config or identity.
fn holds_league(dir: &Path) -> bool {
    ["league.db", "config.toml", "league.json"]
        .iter()
        .any(|f| dir.join(f).is_file())
}

/// The league folder of status, export and exploit: `--dir` when given,
/// else the one league folder under runs/league/ (said on stderr). None or
/// several is an error that lists what is there.
pub fn find_league_dir(dir: Option<&Path>) -> Result<PathBuf> {
    if let Some(d) = dir {
        return Ok(d.to_path_buf());
    }
    let base = Path::new(LEAGUES);
    let Ok(entries) = std::fs::read_dir(base) else {
        bail!(
            "no --dir given, and there is no {LEAGUES}/ folder here: give --dir DIR, the league folder `run` made \
             (`run --config C` makes {LEAGUES}/NAME, NAME from the config)"
        );
    };
    let (mut leagues, mut others) = (Vec::new(), Vec::new());
    for e in entries.flatten() {
        let path = e.path();
        if !path.is_dir() {
            continue;
        }
        if holds_league(&path) {
            leagues.push(path);
        } else {
            others.push(path);
        }
    }
    leagues.sort();
    others.sort();
    let list = |paths: &[PathBuf]| {
        paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    match leagues.len() {
        1 => {
            let d = leagues.remove(0);
            tracing::info!(
                "league folder: {} (the only one under {LEAGUES}/; --dir picks another)",
                d.display()
            );
            Ok(d)
        }
        0 if others.is_empty() => bail!(
            "no --dir given, and {LEAGUES}/ holds no league folder: give --dir DIR, the league folder `run` made"
        ),
        0 => bail!(
            "no --dir given, and no folder under {LEAGUES}/ holds a league (league.db, config.toml or league.json); \
             found only: {}. Give --dir DIR, the league folder `run` made",
            list(&others)
        ),
        n => bail!(
            "no --dir given, and {LEAGUES}/ holds {n} league folders: {}. Give --dir with the one you mean",
            list(&leagues)
        ),
    }
}

/// The league of status, export and exploit: with --store, the store and
/// the shared pool (--pool, required when `pool_needed`); without, the
/// league folder (`find_league_dir`) and league.db in it.
fn locate_league(at: &LeagueLocation, pool_needed: &str) -> Result<LeagueDir> {
    let (dir, store, pool) = (at.dir.as_deref(), at.store.as_deref(), at.pool.as_deref());
    let Some(store) = store else {
        if pool.is_some() {
            bail!("--pool goes with --store URL (a league whose store is not league.db in its folder)");
        }
        return Ok(LeagueDir::new(find_league_dir(dir)?));
    };
    let url = StoreUrl::parse(store).map_err(anyhow::Error::msg)?;
    if dir.is_some() {
        bail!("--dir with --store: give the shared pool folder as --pool DIR (as `run`, `export` and `worker` take it)");
    }
    match pool {
        Some(p) => Ok(LeagueDir::with_store(p, url)),
        None if pool_needed.is_empty() => {
            // No pool: the report comes from the store alone; it names the
            // store where it would name the folder.
            let root = PathBuf::from(url.to_string());
            Ok(LeagueDir::with_store(root, url))
        }
        None => bail!("--store: give --pool DIR too, the folder every host shares ({pool_needed})"),
    }
}

/// `--seats`: a whole number of seats a host can run.
/// The most local workers `run --workers` starts (as a worker's `--seats`).
const MAX_LOCAL_WORKERS: usize = 256;

/// `--workers`: a whole number of local workers, 0 or more.
fn workers_in_range(text: &str) -> Result<usize, String> {
    match text.parse::<i64>() {
        Ok(n) if n >= 0 => Ok(n as usize),
        Ok(n) => Err(format!(
            "--workers {n}: the local workers to start, 0 (every seat on other hosts) or more"
        )),
        Err(_) => Err(format!("--workers {text}: not a whole number of workers")),
    }
}

fn seats_in_range(text: &str) -> Result<usize, String> {
    match text.parse::<i64>() {
        Ok(n) if (1..=256).contains(&n) => Ok(n as usize),
        Ok(n) => Err(format!("--seats {n}: a worker runs 1 to 256 seats at once")),
        Err(_) => Err(format!(
            "--seats {text}: not a whole number of seats (1 to 256)"
        )),
    }
}

/// A pool that is a file (a mistyped path) would fail later with the
/// file system's words; say what it is instead.
fn refuse_file_as_pool(pool: &Path) -> Result<()> {
    if pool.exists() && !pool.is_dir() {
        bail!(
            "--pool {}: a file, not a folder; the pool is the folder every host shares (the league's snapshots and logs)",
            pool.display()
        );
    }
    Ok(())
}

pub fn worker(args: WorkerArgs) -> Result<()> {
    refuse_file_as_pool(&args.pool)?;
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
        host: args.host.clone().unwrap_or_else(league::store::host_name),
        run_for: args
            .run_for
            .as_deref()
            .map(|t| t2e_core::util::parse_duration("--for", t))
            .transpose()
            .map_err(anyhow::Error::msg)?,
        lease: t2e_core::util::parse_duration("--lease", &args.lease)
            .map_err(anyhow::Error::msg)?,
        logs: args.dir.join("logs"),
    };
    opts.validate().map_err(as_flag)?;
    if args.dir.is_file() {
        bail!(
            "--dir {}: a file, not a folder; the worker writes its logs under DIR/logs",
            args.dir.display()
        );
    }
    if !args.pool.is_dir() {
        bail!(
            "--pool {}: not a folder; give the league's pool folder, the one every host shares",
            args.pool.display()
        );
    }
    // Children read the host name from the environment (heartbeats).
    std::env::set_var("T2E_HOST", &opts.host);
    on_ctrl_c()?;
    Ok(league::run::processes::worker::run_worker(
        &LeagueDir::with_store(&args.pool, url),
        &opts,
        &STOP,
    )?)
}

pub fn status(args: StatusArgs) -> Result<()> {
    let watch = args
        .watch
        .as_deref()
        .map(|t| t2e_core::util::parse_duration("--watch", t))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    if let Some(w) = watch {
        if w.as_secs_f64() < 0.5 {
            bail!(
                "--watch {}: must be at least 0.5s",
                args.watch.as_deref().unwrap_or("")
            );
        }
    }
    let dir = locate_league(&args.league, "")?;
    if watch.is_some() {
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
            if watch.is_some() {
                print!("\x1b[2J\x1b[H");
            }
            print!("{}", crate::cli::status_text::render(&r));
        }
        let Some(w) = watch else { break };
        let until = std::time::Instant::now() + w;
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
    let dir = locate_league(&args.league, "it holds the players' files")?;
    let player = match (args.player, args.best) {
        (Some(p), _) => p,
        (None, Some(side)) => {
            let chosen = status::best_validated(&dir, side.into())?;
            println!(
                "{}: the best worst case of the validation panel ({}): {:.1}% won against {}, its worst team; {:.1}% on average, {:.0} steps a game, over {} episodes",
                chosen.player.name,
                chosen.opponents,
                100.0 * chosen.worst_win_rate,
                chosen.worst_opponent,
                100.0 * chosen.win_rate,
                chosen.mean_steps,
                chosen.episodes
            );
            chosen.player.name
        }
        (None, None) => unreachable!("clap requires PLAYER or --best"),
    };
    status::export(&dir, &player, &args.out)?;
    println!("exported {player} -> {}", args.out.display());
    Ok(())
}

pub fn exploit(args: ExploitArgs) -> Result<()> {
    use league::run::exploit::best_response::{self, Budget, ExploitOptions, ExploitOutcome};
    let dir = locate_league(
        &args.league,
        "it holds the player's files, and the best response goes there",
    )?;
    let opts = ExploitOptions {
        budget: Budget::parse(&args.budget).map_err(anyhow::Error::msg)?,
        seed: args.seed,
        maps: args.maps.clone(),
        episodes: args.episodes,
        episode_length: args.episode_length,
        speed_ratio: args.speed_ratio,
        heuristic_prior: args.heuristic_prior,
        threads: args.threads,
        progress: !args.quiet,
    };
    opts.validate().map_err(as_flag)?;
    ctrlc::set_handler(|| {
        if best_response::EVALUATING.load(Ordering::SeqCst) {
            tracing::info!("stopped during the evaluation, nothing recorded; the same command evaluates the trained best response again");
            // _exit, not exit: the evaluation's threads are still running,
            // and libtorch's static destructors under them abort the process.
            // SAFETY: ends the process; nothing is left to flush or save.
            unsafe { libc::_exit(130) }
        }
        STOP.store(true, Ordering::SeqCst)
    })
    .context("cannot install the Ctrl-C handler")?;
    let view: Box<dyn View> = if args.quiet {
        Box::new(Quiet)
    } else {
        Box::new(Bars::default())
    };
    match best_response::run(&dir, &args.player, &opts, &STOP, view.as_ref())? {
        ExploitOutcome::Recorded {
            rows,
            player,
            fresh,
        } => {
            if !fresh {
                println!("already recorded in the store (the same player, weights, learner, budget, seed and evaluation):");
            }
            print!("{}", render_exploit(&rows, &player));
            Ok(())
        }
        ExploitOutcome::Stopped { env_steps, folder } => {
            tracing::info!(
                "stopped at {env_steps} env steps, nothing recorded; the same command resumes it from {}",
                folder.display()
            );
            std::process::exit(130)
        }
    }
}

pub fn evaluator(args: SeatArgs) -> Result<()> {
    let (_, dir) = args.read(child::EVALUATOR)?;
    let lock_path = dir.root.join("learners").join("evaluator.lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = spawn::try_lock(&lock_path)? else {
        bail!(
            "{}: another evaluator is running this league",
            lock_path.display()
        );
    };
    on_ctrl_c()?;
    exit_with(league::run::evaluation::evaluator::run_evaluator(
        &dir, &STOP,
    ))
}

/// A league process's exit code (`league::rules::supervision`): the manager reads
/// the outcome from it.
fn exit_with(result: Result<Outcome, LeagueError>) -> Result<()> {
    use league::rules::supervision::{EXIT_CANNOT_START, EXIT_STOPPED};
    match result {
        Ok(Outcome::Done) => Ok(()),
        Ok(Outcome::Stopped) => std::process::exit(EXIT_STOPPED),
        Err(e) if e.is_cannot_start() => {
            tracing::error!("{}", e.chain());
            std::process::exit(EXIT_CANNOT_START)
        }
        Err(e) => Err(e.into()),
    }
}

pub fn learner(args: SeatArgs) -> Result<()> {
    let (role, dir) = args.read(child::LEARNER)?;
    let Role::Learner(seat) = role else {
        bail!("{}: not a learner's seat", child::LEARNER);
    };
    let lock_path = dir.seat_dir(seat).with_extension("lock");
    std::fs::create_dir_all(lock_path.parent().unwrap())?;
    let Some(_lock) = spawn::try_lock(&lock_path)? else {
        bail!(
            "{}: another {} is running this league",
            lock_path.display(),
            seat.name()
        );
    };
    on_ctrl_c()?;
    exit_with(learner::run_learner(&dir, seat, &STOP))
}

/// The rows as a table: map set, episodes, the best response's win rate
/// with its 95% Wilson interval.
fn render_exploit(rows: &[league::store::ExploitRecord], player: &str) -> String {
    use t2e_learners::eval::wilson_interval;
    let mut s = String::new();
    if let Some(r) = rows.first() {
        s.push_str(&format!(
            "best response ({}, budget {}: {} env steps, {:.1} min of training, seed {}) against {player}, {}:1 at 1.0:{}:\n",
            r.best_response,
            r.budget,
            r.env_steps,
            r.train_ms as f64 / 60_000.0,
            r.seed,
            r.num_captors,
            t2e_learners::eval::ratio_label(r.speed_ratio),
        ));
    }
    s.push_str("| maps | episodes | best response wins % | 95% interval |\n|---|---|---|---|\n");
    for r in rows {
        let (lo, hi) = wilson_interval(r.wins as usize, r.episodes as usize);
        s.push_str(&format!(
            "| {} | {} | {:.1} | [{:.1}, {:.1}] |\n",
            r.maps,
            r.episodes,
            100.0 * r.wins as f64 / r.episodes as f64,
            100.0 * lo,
            100.0 * hi
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;
    use std::ffi::OsString;

    fn parse(child: &ChildCommand) -> Command {
        let mut argv: Vec<OsString> = vec!["t2e-league".into()];
        argv.extend(child.args());
        Cli::try_parse_from(argv).unwrap().command
    }

    /// What the league's parents spawn is what the binary reads: every
    /// seat comes back as the same typed command, and a local worker with
    /// its pool, log folder and seat count.
    #[test]
    fn the_cli_reads_every_child_process_the_league_spawns() {
        use league::rules::players::Seat;
        let dir = PathBuf::from("/tmp/a league");
        for role in [
            Role::Evaluator,
            Role::Learner(Seat::main(Side::Captors)),
            Role::Learner(Seat::exploiter(Side::Target)),
        ] {
            let child = ChildCommand::Seat {
                role,
                dir: dir.clone(),
            };
            let (args, subcommand) = match parse(&child) {
                Command::LeagueLearner(a) => (a, child::LEARNER),
                Command::LeagueEvaluator(a) => (a, child::EVALUATOR),
                other => panic!("{child:?} parsed as {other:?}"),
            };
            assert_eq!(subcommand, child.subcommand());
            assert_eq!(
                ChildCommand::parse_seat(subcommand, &args.args).unwrap(),
                child
            );
        }
        let worker = ChildCommand::Worker {
            pool: dir.clone(),
            logs: PathBuf::from("/tmp/logs"),
            seats: 1,
        };
        match parse(&worker) {
            Command::Worker(w) => {
                assert_eq!(w.pool, dir);
                assert_eq!(w.dir, PathBuf::from("/tmp/logs"));
                assert_eq!(w.seats, 1);
            }
            other => panic!("the worker parsed as {other:?}"),
        }
    }
}
