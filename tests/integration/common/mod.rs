//! Builders shared by the integration tests: synthetic rooms, robots, worlds.
#![allow(dead_code)]

use std::sync::Arc;
use t2e_core::env::physics::Robot;
use t2e_core::env::{EnvConfig, TrapEnv};
use t2e_core::map::{Grid, PreparedMap};

/// Free rectangle rows r0..r1, cols c0..c1 of a 320-cell grid.
pub fn room(r0: usize, r1: usize, c0: usize, c1: usize) -> Grid {
    Grid::with_free_rects("room", 320, &[(r0..r1, c0..c1)])
}

/// One prepared map, as an environment takes it.
pub fn maps(g: Grid) -> Arc<Vec<Arc<PreparedMap>>> {
    Arc::new(vec![Arc::new(PreparedMap::new(g))])
}

/// A robot at rest at (x, y) with heading `theta`.
pub fn robot(x: f64, y: f64, theta: f64) -> Robot {
    Robot {
        pos: [x, y],
        vel: [0.0, 0.0],
        theta,
        collided: false,
    }
}

/// A world on `m` with robots placed by hand (captors first, target last).
pub fn env_with(cfg: EnvConfig, m: Arc<Vec<Arc<PreparedMap>>>, robots: Vec<Robot>) -> TrapEnv {
    let mut env = TrapEnv::new(cfg, m).unwrap();
    env.set_robots(0, robots);
    env
}

/// The children of process `parent` whose command line holds `needle`
/// (from /proc), with their pids.
pub fn children_of(parent: u32, needle: &str) -> Vec<i64> {
    let mut pids = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<i64>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(e.path().join("stat")) else {
            continue;
        };
        // Fields after the command name (which may hold spaces): state, ppid, ...
        let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
            continue;
        };
        let ppid: u32 = rest
            .split_whitespace()
            .nth(1)
            .and_then(|x| x.parse().ok())
            .unwrap_or(0);
        let cmd = std::fs::read(e.path().join("cmdline"))
            .map(|c| String::from_utf8_lossy(&c).replace('\0', " "))
            .unwrap_or_default();
        if ppid == parent && cmd.contains(needle) {
            pids.push(pid);
        }
    }
    pids
}

/// One MAPPO captor against a target that stands still, on maps the test
/// hands the trainer (`maps` is not read), budget unbounded: the base the
/// learning tests set their worlds, episode length and networks on.
pub fn one_captor_against_still(name: &str, seed: u64) -> t2e_learners::learn::train::TrainConfig {
    use t2e_learners::learn::train::{SideConfig, TrainConfig};
    TrainConfig {
        name: name.into(),
        seed,
        total_env_steps: u64::MAX,
        checkpoint_every: 1000,
        device: t2e_learners::learn::run_config::DeviceChoice::Cpu,
        protocol: t2e_core::protocol::Protocol::HeldOut,
        maps: "unused".into(),
        env: EnvConfig {
            num_captors: 1,
            ..EnvConfig::default()
        },
        captors: SideConfig {
            play: "mappo".parse().unwrap(),
            ..SideConfig::default()
        },
        target: SideConfig {
            play: "still".parse().unwrap(),
            ..SideConfig::default()
        },
        ..TrainConfig::default()
    }
}

/// A training config small enough to run an iteration in a test: MAPPO
/// captors (K = 2, tiny networks) against the rule-based target, 2 worlds x
/// 10 steps.
pub fn tiny_train_config(
    name: &str,
    protocol: t2e_core::protocol::Protocol,
    maps: &str,
) -> t2e_learners::learn::train::TrainConfig {
    use t2e_learners::learn::train::{SideConfig, TrainConfig};
    TrainConfig {
        name: name.into(),
        seed: 1,
        num_envs: 2,
        rollout_steps: 10,
        total_env_steps: 20,
        device: t2e_learners::learn::run_config::DeviceChoice::Cpu,
        protocol,
        maps: maps.into(),
        extra_maps: Default::default(),
        env: EnvConfig {
            num_captors: 2,
            episode_length: 20,
            ..EnvConfig::default()
        },
        captors: SideConfig {
            play: "mappo".parse().unwrap(),
            net: t2e_learners::nn::NetConfig {
                hidden: 8,
                conv_channels: [2, 2],
                patch_pool: 4,
                ..Default::default()
            },
            ..SideConfig::default()
        },
        target: SideConfig {
            play: "heuristic".parse().unwrap(),
            ..SideConfig::default()
        },
        ..TrainConfig::default()
    }
}
pub mod league;
pub mod postgres;

/// Waits for `child` (its stderr piped) at most `secs` seconds, killing it
/// and failing the test past that: a command that blocks (on a FIFO, say)
/// fails instead of hanging the suite.
pub fn output_within(
    mut child: std::process::Child,
    secs: u64,
    what: &str,
) -> std::process::Output {
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(secs) {
            let _ = child.kill();
            panic!("{what}: still running after {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}
