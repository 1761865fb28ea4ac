//! `t2e-league render`: play one episode and write it as an animated GIF.

use anyhow::{anyhow, Result};
use std::path::PathBuf;
use t2e_core::env::{CaptureRule, EnvConfig, Side, TrapEnv};
use t2e_core::render::episode::{render_episode, RenderOptions};
use t2e_learners::controllers::ControllerSpec;

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Map set to play on: small, medium, large (Gibson classes), gibson,
    /// shipped, a folder, FOLDER:CLASS, or a single .png file. The seed
    /// picks the map, as in `eval`.
    #[arg(long, default_value = "shipped", value_name = "SPEC")]
    pub maps: String,
    /// Captor controller: heuristic (expert captors), greedy (ASZ-greedy),
    /// greedy:K (ASZ-greedy on K-cell squares, K from 1 to 8; K here is not
    /// --k), random, still, ckpt:PATH (a trained policy, its most likely
    /// action) or sample:PATH (the same policy, sampling its actions).
    #[arg(long, default_value = "heuristic")]
    pub captors: ControllerSpec,
    /// Target controller: heuristic (rule-based target), greedy or greedy:K
    /// (ASZ-greedy's mirror: the move that leaves the target the largest
    /// ASZ; K as for --captors), lookahead:H or lookahead:H:CAPTORS (each
    /// move played H steps ahead against a model of the captors, the expert
    /// ones unless CAPTORS names another team; the best future kept),
    /// robust:H:M1+M2+... (the same against every team M1, M2, ...; the
    /// rule-based move unless some team catches it and another move is
    /// free under all), random, still, ckpt:PATH (a trained policy, its most likely action)
    /// or sample:PATH (the same policy, sampling its actions).
    #[arg(long, default_value = "heuristic")]
    pub target: ControllerSpec,
    /// Number of captors K.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=t2e_core::env::MAX_CAPTORS as i64))]
    pub k: u32,
    /// Target speed over captor speed (captors move at 1.0 m/s; 1.0, 1.2, 1.4 in the paper).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub speed_ratio: f64,
    /// Steps before the episode ends uncaptured (500 in evaluation).
    #[arg(long, default_value_t = 500)]
    pub episode_length: u32,
    /// Episode seed: picks the map and the start positions (same seed, same episode).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Capture rule: fast (12 probes, the paper's tables) or strict (|ASZ| threshold).
    #[arg(long, value_enum, default_value = "fast")]
    pub capture_rule: CaptureRule,
    /// Output GIF file (parent folders are created).
    #[arg(long, default_value = "episode.gif", value_name = "FILE.gif")]
    pub out: PathBuf,
    /// Pixels per 0.05 m cell.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub scale: u32,
    /// Draw every n-th step (the first and last states are always drawn).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
    /// Delay between frames in milliseconds (100 with --every 1 is real time).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(10..=10000))]
    pub delay_ms: u32,
    /// Do not shade the ASZ (target-first cells) and the captors' regions.
    #[arg(long)]
    pub no_asz: bool,
    /// Draw the whole grid instead of cropping to the map's free area.
    #[arg(long)]
    pub no_crop: bool,
}

pub fn run(args: RenderArgs) -> Result<()> {
    let ext = args.out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("gif") {
        return Err(anyhow!(
            "--out {}: render writes an animated GIF, so the file must end in .gif",
            args.out.display()
        ));
    }
    if !(args.speed_ratio.is_finite() && args.speed_ratio > 0.0 && args.speed_ratio <= 10.0) {
        return Err(anyhow!(
            "--speed-ratio {}: must be a number in (0, 10]",
            args.speed_ratio
        ));
    }
    // All maps of the set, in catalogue order, so the seed picks the same map as in `eval`.
    let maps = t2e_core::map::catalog::load_prepared(&args.maps)?;
    let cfg = EnvConfig {
        num_captors: args.k as usize,
        captor_speed: 1.0,
        target_speed: args.speed_ratio,
        episode_length: args.episode_length,
        capture_rule: args.capture_rule,
        observations: false,
        ..EnvConfig::default()
    };
    args.captors
        .check(Side::Captors, &cfg)
        .map_err(|e| anyhow!("--captors: {e}"))?;
    args.target
        .check(Side::Target, &cfg)
        .map_err(|e| anyhow!("--target: {e}"))?;
    let mut captors = args
        .captors
        .build(Side::Captors)
        .map_err(|e| anyhow!("--captors: {e}"))?;
    let mut target = args
        .target
        .build(Side::Target)
        .map_err(|e| anyhow!("--target: {e}"))?;
    let mut env = TrapEnv::new(cfg, maps).map_err(|e| anyhow!("environment settings: {e}"))?;
    let opts = RenderOptions {
        scale: args.scale,
        every: args.every,
        frame_delay_ms: args.delay_ms,
        crop: !args.no_crop,
        show_asz: !args.no_asz,
    };
    let s = render_episode(
        &mut env,
        captors.as_mut(),
        target.as_mut(),
        args.seed,
        &opts,
        &args.out,
    )?;
    println!(
        "map {}, seed {}: {} after {} steps (final |ASZ| {:.2} m^2) -> {} ({} frames, {:.1} MB)",
        s.map,
        s.seed,
        if s.captured {
            "captured"
        } else {
            "not captured"
        },
        s.steps,
        s.final_asz_m2,
        args.out.display(),
        s.frames,
        s.bytes as f64 / 1e6
    );
    Ok(())
}
