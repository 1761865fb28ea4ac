//! The `t2e-league` command line: one module per subcommand.
use clap::{Parser, Subcommand};

pub mod bench;
pub mod eval;
pub mod maps;
pub mod render;

#[derive(Parser, Debug)]
#[command(
    name = "t2e-league",
    version,
    about = "Multi-robot target trapping (T2E): environment, heuristics, evaluation and league training"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// List, show and generate maps.
    Maps(maps::MapsArgs),
    /// Evaluate captors against a target with the paper's protocol (spec §8).
    Eval(eval::EvalArgs),
    /// Render one episode to an animated GIF.
    Render(render::RenderArgs),
    /// Measure environment, ASZ and observation speed and print a table.
    Bench(bench::BenchArgs),
}

pub fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    match cli.command {
        Command::Maps(a) => maps::run(a),
        Command::Eval(a) => eval::run(a),
        Command::Render(a) => render::run(a),
        Command::Bench(a) => bench::run(a),
    }
}
