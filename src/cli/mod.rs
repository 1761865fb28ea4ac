//! The `t2e-league` command line: one module per subcommand.
use clap::{Parser, Subcommand};

pub mod bench;
mod bench_before;
mod bench_greedy;
mod bench_opponents;
mod bench_store;
pub mod docs;
pub mod eval;
mod flag_error;
pub mod league_commands;
pub mod logging;
pub mod maps;
mod progress;
pub mod render;
pub mod status_text;
pub mod table;
pub mod threads;
pub mod train;
pub mod tune_target;

#[derive(Parser, Debug)]
#[command(
    name = "t2e-league",
    version,
    about = "Multi-robot target trapping (T2E): environment, heuristics, evaluation and league training"
)]
pub struct Cli {
    /// How log lines are written to stderr: `text` (messages as they read)
    /// or `json` (one object a line: timestamp, level, target, message, for
    /// a cluster's log collector). A league's processes inherit it. Levels
    /// follow `RUST_LOG` (default `info`).
    #[arg(long, global = true, value_enum, env = logging::ENV, default_value_t = logging::LogFormat::Text)]
    pub log_format: logging::LogFormat,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// List, show and generate maps.
    Maps(maps::MapsArgs),
    /// Evaluate captors against a target with the paper's protocol: success
    /// rate, steps, path length and SoA over fixed episode seeds.
    Eval(eval::EvalArgs),
    /// Render one episode to an animated GIF.
    Render(render::RenderArgs),
    /// Train captors, the target or both with MAPPO, IPPO, MADDPG or MAAC from a config.
    Train(train::TrainArgs),
    /// Measure speed and print a table: the environment, ASZ and
    /// observations (default), training iterations (--train CONFIG), a
    /// league learner's opponent inference (--opponents) or the league
    /// store's writes (--store URL).
    Bench(bench::BenchArgs),
    /// The paper's Tables II and III (Markdown, LaTeX) from eval folders,
    /// with the paper's numbers beside ours.
    Table(table::TableArgs),
    /// Search the rule-based target's family (five constants) by CMA-ES for
    /// the target a training panel of captor teams catches least.
    TuneTarget(tune_target::TuneTargetArgs),
    /// Run a league (or resume the one in --dir): captor and target learners
    /// against pools of each other's snapshots.
    Run(league_commands::RunArgs),
    /// A league's players, ratings, payoff matrix, curriculum and learners.
    Status(league_commands::StatusArgs),
    /// Write one league player as a self-contained checkpoint folder.
    Export(league_commands::ExportArgs),
    /// Train a fresh best response against one frozen league player for a
    /// fixed budget; its win rate (95% interval) goes to the store and `status`.
    Exploit(league_commands::ExploitArgs),
    /// Write the manifest (SHA256SUMS) that a checkpoint folder written
    /// before 0.2.0 lacks, after checking its files against meta.json: it
    /// vouches for meta.json as it is now, so seal only folders you trust.
    Seal(SealArgs),
    /// Run a league's seats on this host, taken from its store (a league
    /// started with `run --store URL --pool DIR`).
    Worker(league_commands::WorkerArgs),
    /// One learner of a league (spawned by `run`).
    #[command(hide = true)]
    LeagueLearner(league_commands::SeatArgs),
    /// A league's evaluator (spawned by `run`).
    #[command(hide = true)]
    LeagueEvaluator(league_commands::SeatArgs),
    /// Write docs/reference/cli.md and the man pages from these definitions.
    #[command(hide = true)]
    GenerateDocs(docs::GenerateDocsArgs),
}

/// Keeps freed memory in the heap instead of returning it to the OS: PPO
/// updates allocate and free the same tens-of-megabyte tensors many times
/// per iteration, and glibc's default of mapping and unmapping each one cost
/// a third of the update time in page faults.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}

pub fn main() -> anyhow::Result<()> {
    keep_freed_memory();
    let cli = Cli::parse();
    logging::init(cli.log_format);
    match cli.command {
        Command::Maps(a) => maps::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Seal(a) => seal(a),
        Command::Render(a) => render::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Table(a) => table::run(a),
        Command::Train(a) => train::run(a),
        Command::TuneTarget(a) => tune_target::run(a),
        Command::Run(a) => league_commands::run(a),
        Command::Status(a) => league_commands::status(a),
        Command::Export(a) => league_commands::export(a),
        Command::Exploit(a) => league_commands::exploit(a),
        Command::Worker(a) => league_commands::worker(a),
        Command::LeagueLearner(a) => league_commands::learner(a),
        Command::LeagueEvaluator(a) => league_commands::evaluator(a),
        Command::GenerateDocs(a) => docs::run::<Cli>(a),
    }
}

#[derive(clap::Args, Debug)]
pub struct SealArgs {
    /// Checkpoint folders (each holding meta.json).
    #[arg(required = true)]
    pub folders: Vec<std::path::PathBuf>,
}

fn seal(args: SealArgs) -> anyhow::Result<()> {
    for folder in &args.folders {
        t2e_learners::nn::checkpoint::seal(folder)?;
        println!("{}: sealed (SHA256SUMS written)", folder.display());
    }
    Ok(())
}
