//! `t2e-league bench`: speed of the environment, the ASZ and observations,
//! printed as a table beside the reference implementation's figures.

use super::bench_before::BEFORE_DATE;
use anyhow::{Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;
use std::time::{Duration, Instant};
use t2e_core::asz::{AszFields, FastMarching};
use t2e_core::env::{Action, Controller, EnvConfig, Side, TrapEnv, VecEnv, PATCH_LEN};
use t2e_core::heuristics::{target_action, Heuristic};
use t2e_core::map::{self, PreparedMap};
use t2e_learners::controllers::ControllerSpec;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Maps for the environment rows (default: the Gibson set, else the shipped maps).
    #[arg(long)]
    pub maps: Option<String>,
    /// Seconds to spend on each row.
    #[arg(long, default_value_t = 2.0)]
    pub seconds: f64,
    /// Worlds in the batched rows.
    #[arg(long, default_value_t = 64)]
    pub envs: usize,
    /// Instead of the environment table, time whole training iterations
    /// (rollout + update) of this training config, any learner, and print
    /// where the time goes and the network FLOP/s against the cores' peak.
    /// Repeat it to compare configs side by side in one run.
    #[arg(long, alias = "ppo")]
    pub train: Vec<std::path::PathBuf>,
    /// Iterations to time, after warming up (one iteration; an off-policy
    /// learner's until its replay holds `learning_starts` and it updates).
    #[arg(long, default_value_t = 5)]
    pub iterations: usize,
    /// Device for --train: auto, cpu or cuda.
    #[arg(long)]
    pub device: Option<t2e_learners::learn::run_config::DeviceChoice>,
    /// Instead of the environment table, time a league learner's opponent
    /// inference (one pass per opponent, and stacked) against its own, per
    /// robot row, over --envs worlds.
    #[arg(long)]
    pub opponents: bool,
    /// Instead of the environment table, time the league store's writes
    /// (matches with their rating updates) with --writers concurrent
    /// writers: a postgres:// URL, or `sqlite` for a fresh SQLite file.
    #[arg(long, value_name = "URL")]
    pub store: Option<String>,
    /// Threads for libtorch and rayon, at most 256. Default (0):
    /// OMP_NUM_THREADS if set, else the cores the load average leaves free.
    /// The table says which count it used.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub threads: usize,
    /// A captor team (a controller spec such as `ckpt:PATH`, three captors)
    /// to time as a planner's model: adds the lookahead and robust
    /// lookahead targets' rows against it, its futures batched and played
    /// one game at a time.
    #[arg(long, value_name = "TEAM")]
    pub planner_model: Option<String>,
    /// Concurrent writers for --store, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,4,8")]
    pub writers: Vec<usize>,
}

/// One config's whole iterations, timed.
struct TrainTiming {
    label: String,
    learners: String,
    device: tch::Device,
    worlds_steps: String,
    steps_per_s: f64,
    secs_per_iteration: f64,
    shares: [f64; 3],
    /// Network FLOPs per iteration (rollout passes + update passes).
    flops_per_iteration: f64,
}

/// Times whole training iterations of training configs, any learner, in
/// turn in this one process, so the rows compare on the same machine state.
fn train_table(args: &BenchArgs, paths: &[std::path::PathBuf]) -> Result<()> {
    let peak = matmul_peak_flops();
    let mut rows = Vec::new();
    for path in paths {
        rows.push(time_training(args, path)?);
    }
    println!(
        "| config | learners | device | threads | worlds x steps | env steps/s | x first row | s per iteration | env | inference | update | GFLOP/s | % of peak |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let first = rows[0].steps_per_s;
    for r in &rows {
        let gflops = r.flops_per_iteration / r.secs_per_iteration / 1e9;
        println!(
            "| {} | {} | {:?} | {} | {} | {:.0} | {:.2} | {:.3} | {:.0}% | {:.0}% | {:.0}% | {:.2} | {:.1}% |",
            r.label,
            r.learners,
            r.device,
            rayon::current_num_threads(),
            r.worlds_steps,
            r.steps_per_s,
            r.steps_per_s / first,
            r.secs_per_iteration,
            100.0 * r.shares[0],
            100.0 * r.shares[1],
            100.0 * r.shares[2],
            gflops,
            100.0 * gflops * 1e9 / peak,
        );
    }
    println!(
        "\npeak: {:.1} GFLOP/s, measured here as a 1024 x 1024 f32 matmul on {} torch threads; network FLOPs per iteration counted from the layer shapes (NetConfig::forward_flops; a backward pass as two forwards)",
        peak / 1e9,
        tch::get_num_threads()
    );
    Ok(())
}

/// f32 FLOP/s of a large matmul: what the cores can give dense network work.
fn matmul_peak_flops() -> f64 {
    let a = tch::Tensor::randn([1024, 1024], (tch::Kind::Float, tch::Device::Cpu));
    let b = tch::Tensor::randn([1024, 1024], (tch::Kind::Float, tch::Device::Cpu));
    let _ = a.matmul(&b);
    let start = Instant::now();
    let mut n = 0;
    while start.elapsed().as_secs_f64() < 1.0 {
        let _ = a.matmul(&b);
        n += 1;
    }
    2.0 * 1024f64.powi(3) * n as f64 / start.elapsed().as_secs_f64()
}

fn time_training(args: &BenchArgs, path: &std::path::Path) -> Result<TrainTiming> {
    let mut cfg = t2e_learners::learn::train::TrainConfig::load(path)?;
    if let Some(d) = &args.device {
        cfg.device = *d;
    }
    let maps = map::catalog::load_prepared(&cfg.maps)?;
    let mut trainer = t2e_learners::learn::train::Trainer::new(cfg.clone(), maps)?;
    for _ in 0..1000 {
        let m = trainer.iterate()?;
        if m.captor_value_loss.is_some() || m.target_value_loss.is_some() {
            break;
        }
    }
    let (mut secs, mut env, mut inf, mut upd, mut steps) = (0.0, 0.0, 0.0, 0.0, 0u64);
    for _ in 0..args.iterations.max(1) {
        let m = trainer.iterate()?;
        secs += m.time_env + m.time_inference + m.time_update;
        env += m.time_env;
        inf += m.time_inference;
        upd += m.time_update;
        steps += (cfg.num_envs * cfg.rollout_steps) as u64;
    }
    let learners: Vec<String> = trainer
        .learner_sides()
        .iter()
        .map(|(s, a)| format!("{} {}", s.name(), a.name()))
        .collect();
    Ok(TrainTiming {
        label: path.display().to_string(),
        learners: learners.join(" + "),
        device: trainer.device,
        worlds_steps: format!("{} x {}", cfg.num_envs, cfg.rollout_steps),
        steps_per_s: steps as f64 / secs,
        secs_per_iteration: secs / args.iterations.max(1) as f64,
        shares: [env / secs, inf / secs, upd / secs],
        flops_per_iteration: trainer.network_flops_per_iteration(),
    })
}

struct Row {
    what: String,
    per_op: Duration,
    unit: &'static str,
    reference: Option<f64>,
    /// Microseconds per op measured before the environment's speed work
    /// (`BEFORE_DATE`), where that row was measured the same way.
    before_us: Option<f64>,
}

/// Repeats `op` (which reports how many units it did) for about `secs` seconds.
fn measure(secs: f64, mut op: impl FnMut() -> u64) -> Duration {
    for _ in 0..3 {
        op();
    }
    let start = Instant::now();
    let mut units = 0u64;
    while start.elapsed().as_secs_f64() < secs {
        units += op();
    }
    start.elapsed() / units.max(1) as u32
}

/// Steps one world for `n` steps with the given action source, building
/// observations of every robot when `obs`; resets on episode end.
fn single_core_steps(
    env: &mut TrapEnv,
    rng: &mut ChaCha8Rng,
    both_heuristic: bool,
    obs: bool,
    n: u64,
    vec: &mut [f32],
    patch: &mut [u8],
) -> u64 {
    let k = env.num_captors();
    let mut acts = vec![Action::Stop; k + 1];
    let mut rewards = vec![0f32; k + 1];
    for _ in 0..n {
        if both_heuristic {
            Heuristic.act(env, Side::Captors, &mut acts[..k]);
        } else {
            for a in &mut acts[..k] {
                *a = Action::from_index(rng.gen_range(0..Action::COUNT));
            }
        }
        acts[k] = target_action(env);
        env.step_state(&acts, &mut rewards);
        if env.is_done() {
            env.reset_state(rng.gen()).expect("placement");
        }
        if obs {
            let vl = env.cfg.vector_len();
            for i in 0..=k {
                env.write_observation(
                    i,
                    &mut vec[i * vl..(i + 1) * vl],
                    &mut patch[i * PATCH_LEN..(i + 1) * PATCH_LEN],
                );
            }
        }
    }
    n
}

pub fn run(args: BenchArgs) -> Result<()> {
    if !(args.seconds.is_finite() && args.seconds >= 0.05 && args.seconds <= 3600.0) {
        anyhow::bail!(
            "--seconds {}: must be a time in [0.05, 3600] seconds per row",
            args.seconds
        );
    }
    if args.envs == 0 || args.envs > 4096 {
        anyhow::bail!("--envs {}: must be in 1..=4096", args.envs);
    }
    if args.iterations == 0 {
        anyhow::bail!("--iterations 0: needs at least one timed iteration");
    }
    let (threads, why) = super::threads::size_pools(args.threads)?;
    tracing::info!("bench: {threads} threads ({why})");
    if let Some(load) = t2e_core::util::load_average() {
        // Timings on a shared machine measure the other processes too.
        if load >= 0.5 {
            tracing::warn!(
                "the machine is busy (load {load:.1} on {} cores): these timings will read low; compare ratios measured side by side",
                t2e_core::util::cores()
            );
        }
    }
    if !args.train.is_empty() {
        return train_table(&args, &args.train);
    }
    if let Some(url) = &args.store {
        let url = if url == "sqlite" {
            "sqlite:league.db"
        } else {
            url.as_str()
        };
        return super::bench_store::run(url, &args.writers, args.seconds);
    }
    if args.opponents {
        return super::bench_opponents::run(args.seconds, args.envs);
    }
    let gibson = map::catalog::gibson_dir().is_some();
    let env_spec = args.maps.clone().unwrap_or_else(|| {
        if gibson {
            "gibson".into()
        } else {
            "shipped".into()
        }
    });
    let maps = map::catalog::load_prepared(&env_spec)?;
    let secs = args.seconds;
    let cfg = EnvConfig {
        num_captors: 3,
        ..EnvConfig::default()
    };
    // Checked before the tables, so a wrong path fails at once.
    let planner_model = match &args.planner_model {
        Some(spec) => {
            let spec: ControllerSpec = spec
                .parse()
                .with_context(|| format!("--planner-model {spec}"))?;
            spec.check(Side::Captors, &cfg)
                .with_context(|| format!("--planner-model {spec}"))?;
            Some(spec)
        }
        None => None,
    };
    let on_gibson = env_spec == "gibson";
    let mut rows = single_core_rows(&cfg, &maps, secs, on_gibson)?;
    rows.extend(batched_rows(&cfg, &maps, secs, args.envs, on_gibson)?);
    rows.extend(asz_rows(&cfg, secs)?);
    print_rows(&rows, &env_spec, secs);
    // The ASZ-greedy captor does 4 ASZ per captor per step.
    super::bench_greedy::run(&cfg, &maps, &env_spec, secs, planner_model.as_ref())
}

/// The environment's step on one core, with and without observations.
fn single_core_rows(
    cfg: &EnvConfig,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    secs: f64,
    on_gibson: bool,
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    let one_pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    for (what, both, obs, reference, before_us) in [
        (
            "env step, 3v1, observations, rule-based target, random captors, 1 core",
            false,
            true,
            Some(275.0),
            11.44,
        ),
        (
            "env step, 3v1, no observations, both sides heuristic, 1 core",
            true,
            false,
            Some(160.0),
            11.84,
        ),
    ] {
        let mut env = TrapEnv::new(cfg.clone(), maps.clone()).map_err(anyhow::Error::msg)?;
        env.reset_state(1)?;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut vec = vec![0f32; 4 * cfg.vector_len()];
        let mut patch = vec![0u8; 4 * PATCH_LEN];
        let per = one_pool.install(|| {
            measure(secs, || {
                single_core_steps(&mut env, &mut rng, both, obs, 1000, &mut vec, &mut patch)
            })
        });
        rows.push(Row {
            what: what.into(),
            per_op: per,
            unit: "steps/s",
            reference,
            before_us: on_gibson.then_some(before_us),
        });
    }

    Ok(rows)
}

/// The vector env on every thread, one observation build, and the
/// held-out check of the generated training maps.
fn batched_rows(
    cfg: &EnvConfig,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    secs: f64,
    envs: usize,
    on_gibson: bool,
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    let threads = rayon::current_num_threads();
    let mut venv = VecEnv::new(cfg.clone(), maps.clone(), envs, 3).map_err(anyhow::Error::msg)?;
    venv.script(Side::Target, || Box::new(Heuristic));
    venv.reset()?;
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut acts = vec![Action::Stop; envs * 4];
    let per = measure(secs, || {
        for a in acts.iter_mut() {
            *a = Action::from_index(rng.gen_range(0..Action::COUNT));
        }
        venv.step(&acts).expect("placement");
        envs as u64
    });
    rows.push(Row {
        what: format!("vector env, {} worlds, 3v1, observations, rule-based target, random captors, {threads} cores", envs),
        per_op: per,
        unit: "steps/s",
        reference: Some(275.0 * threads as f64),
        // 65.7 k world-steps/s on one thread with 64 worlds.
        before_us: (on_gibson && threads == 1 && envs == 64).then_some(1e6 / 65.7e3),
    });

    // One observation build (vector + 48x48 patch) of one robot.
    let mut env = TrapEnv::new(cfg.clone(), maps.clone()).map_err(anyhow::Error::msg)?;
    env.reset_state(5)?;
    let mut vec = vec![0f32; cfg.vector_len()];
    let mut patch = vec![0u8; PATCH_LEN];
    let per = measure(secs, || {
        for i in 0..4 {
            env.write_observation(i, &mut vec, &mut patch);
        }
        4
    });
    rows.push(Row {
        what: "one observation build (vector + 48x48 patch)".into(),
        per_op: per,
        unit: "obs/s",
        reference: None,
        before_us: on_gibson.then_some(1.90),
    });

    // The held-out protocol's check of a league's 60 generated training maps
    // against the test maps, which every held-out run pays at its start
    // (0.17 s on one thread, 2026-11-28).
    let generated = map::catalog::load_prepared("generated:20")?;
    let per = measure(secs, || {
        t2e_core::protocol::Protocol::HeldOut
            .check_training_maps("generated:20", &generated)
            .expect("generated maps pass the held-out check");
        1
    });
    rows.push(Row {
        what: format!(
            "held-out check of {} generated training maps",
            generated.len()
        ),
        per_op: per,
        unit: "checks/s",
        reference: None,
        before_us: None,
    });

    Ok(rows)
}

/// ASZ on the smallest, a medium and the largest Gibson map, over random
/// placements (none without the Gibson maps).
fn asz_rows(cfg: &EnvConfig, secs: f64) -> Result<Vec<Row>> {
    let Some(dir) = map::catalog::gibson_dir() else {
        return Ok(Vec::new());
    };
    let mut rows = Vec::new();
    for (name, reference_ms, before_us) in [
        ("Kettle_floor_trav_0_v3", Some(14.0), 202.0),
        ("Ladue_floor_trav_0_v3", None, 587.0),
        ("Graceville_floor_trav_0_v3", Some(23.0), 1185.0),
    ] {
        let m = Arc::new(PreparedMap::new(map::load_png(
            &dir.join(format!("{name}.png")),
        )?));
        rows.extend(asz_rows_on(cfg, &m, name, secs, reference_ms, before_us)?);
    }
    Ok(rows)
}

/// One map's ASZ rows: the labelled march, the per-robot fields, the
/// planner's case (one captor moved), and a full arrival-time march.
fn asz_rows_on(
    cfg: &EnvConfig,
    m: &Arc<PreparedMap>,
    name: &str,
    secs: f64,
    reference_ms: Option<f64>,
    before_us: f64,
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    let free = m.grid.free_cells();
    let mut env =
        TrapEnv::new(cfg.clone(), Arc::new(vec![m.clone()])).map_err(anyhow::Error::msg)?;
    let starts: Vec<_> = (0..64)
        .map(|s| {
            env.reset_state(s).expect("placement");
            env.asz_sources()
        })
        .collect();
    let mut fm = FastMarching::new();
    let mut i = 0;
    let per = measure(secs, || {
        let (c, t) = &starts[i % starts.len()];
        i += 1;
        std::hint::black_box(fm.asz_cells(&**m, *t, c));
        1
    });
    rows.push(Row {
        what: format!("ASZ (3 captors, random starts) on {name}, {free} free cells"),
        per_op: per,
        unit: "ASZ/s",
        reference: reference_ms.map(|ms: f64| 1000.0 / ms),
        before_us: Some(before_us),
    });
    let mut fields = AszFields::new();
    let per = measure(secs, || {
        let (c, t) = &starts[i % starts.len()];
        i += 1;
        std::hint::black_box(fields.asz_cells(&**m, *t, c));
        1
    });
    rows.push(Row {
        what: format!(
            "ASZ by per-robot fields (3 captors, random starts, no field kept) on {name}"
        ),
        per_op: per,
        unit: "ASZ/s",
        reference: reference_ms.map(|ms: f64| 1000.0 / ms),
        before_us: None,
    });
    rows.push(moved_captor_row(
        m,
        name,
        &starts,
        &mut fields,
        secs,
        reference_ms,
    ));
    let per = measure(secs, || {
        let (c, t) = &starts[i % starts.len()];
        i += 1;
        let mut sources = c.clone();
        sources.push(*t);
        fm.march(&**m, &sources, None);
        1
    });
    rows.push(Row {
        what: format!("full arrival-time march (4 fronts, every cell) on {name}"),
        per_op: per,
        unit: "marches/s",
        reference: None,
        before_us: None,
    });
    Ok(rows)
}

/// The planner's case: the other robots' fields kept, one captor moved.
/// The fields keep the counts of the last moves of one state, so the
/// captor visits more cells around its own in turn than they keep, and its
/// field is marched every time.
fn moved_captor_row(
    m: &Arc<PreparedMap>,
    name: &str,
    starts: &[(Vec<t2e_core::asz::Source>, t2e_core::asz::Source)],
    fields: &mut AszFields,
    secs: f64,
    reference_ms: Option<f64>,
) -> Row {
    let mut i = 0;
    let (c, t) = &starts[0];
    fields.asz_cells(&**m, *t, c);
    let moves: Vec<[f64; 2]> = (-6..=6i32)
        .flat_map(|dr| (-6..=6i32).map(move |dc| (dr, dc)))
        .filter(|&step| step != (0, 0))
        .map(|(dr, dc)| {
            [
                c[0].pos[0] + map::CELL_SIZE * dc as f64,
                c[0].pos[1] + map::CELL_SIZE * dr as f64,
            ]
        })
        .filter(|&p| {
            let (r, col) = m.grid.cell_of(p);
            m.grid.is_free(r, col)
        })
        .collect();
    let per = measure(secs, || {
        i += 1;
        let moved = moves[i % moves.len()];
        std::hint::black_box(fields.with_moved_captor(&**m, *t, c, 0, moved));
        1
    });
    Row {
        what: format!(
            "ASZ by per-robot fields, one captor moved, the others' fields kept, on {name}"
        ),
        per_op: per,
        unit: "ASZ/s",
        reference: reference_ms.map(|ms: f64| 1000.0 / ms),
        before_us: None,
    }
}

fn print_rows(rows: &[Row], env_spec: &str, secs: f64) {
    let threads = rayon::current_num_threads();
    println!(
        "maps for env rows: {env_spec}; {:.1} s per row; {threads} rayon threads\n",
        secs
    );
    println!(
        "| what | time per op | rate | {BEFORE_DATE} | x {BEFORE_DATE} | reference (Python, same machine) | speed-up |"
    );
    println!("|---|---|---|---|---|---|---|");
    for r in rows {
        let per_us = r.per_op.as_secs_f64() * 1e6;
        let rate = 1.0 / r.per_op.as_secs_f64();
        let (reference, ratio) = match r.reference {
            Some(x) => (format!("{x:.0} {}", r.unit), format!("{:.0}x", rate / x)),
            None => ("-".into(), "-".into()),
        };
        let (before, speedup) = match r.before_us {
            Some(b) => (format!("{b:.2} us"), format!("{:.2}x", b / per_us)),
            None => ("-".into(), "-".into()),
        };
        println!(
            "| {} | {per_us:.2} us | {rate:.0} {} | {before} | {speedup} | {reference} | {ratio} |",
            r.what, r.unit,
        );
    }
    println!(
        "\n{BEFORE_DATE}: the same row measured with `bench --threads 1` on the Gibson maps before the environment's speed work; compare ratios measured side by side on a quiet machine"
    );
}
