//! The ASZ-greedy rows of `t2e-league bench`: one decision for 3 captors on
//! the spec's 0.05 m cells and on coarser ones (`greedy:K`), over states
//! taken from real episodes, and how often each coarsening picks the same
//! action as the spec's cells; then the lookahead target's decision.

use super::bench_before::BEFORE_DATE;
use anyhow::Result;
use std::sync::Arc;
use std::time::Instant;
use t2e_core::env::{Action, Controller, EnvConfig, OneGameAtATime, Side, TrapEnv};
use t2e_core::heuristics::{
    target_action, AszGreedy, Heuristic, Lookahead, RandomisedExpert, RobustLookahead,
};
use t2e_core::map::PreparedMap;
use t2e_learners::controllers::ControllerSpec;

/// Coarsenings timed, the spec's first.
const COARSENINGS: [usize; 4] = [1, 2, 3, 4];

/// States of episodes of the expert captors against the rule-based target:
/// every 20th step of the first 200, over 8 episodes.
fn episode_states(cfg: &EnvConfig, maps: &Arc<Vec<Arc<PreparedMap>>>) -> Result<Vec<TrapEnv>> {
    let mut states = Vec::new();
    let new_env = || TrapEnv::new(cfg.clone(), maps.clone()).map_err(anyhow::Error::msg);
    let k = cfg.num_captors;
    for seed in 0..8u64 {
        let mut env = new_env()?;
        env.reset_state(seed)?;
        let mut played: Vec<Vec<Action>> = Vec::new();
        for step in 0..200 {
            if step % 20 == 0 {
                // Replaying the episode's actions rebuilds the state: TrapEnv
                // holds buffers that are not worth a Clone.
                let mut copy = new_env()?;
                copy.reset_state(seed)?;
                let mut rewards = vec![0f32; k + 1];
                for acts in &played {
                    copy.step_state(acts, &mut rewards);
                }
                states.push(copy);
            }
            let mut acts = vec![Action::Stop; k + 1];
            Heuristic.act(&env, Side::Captors, &mut acts[..k]);
            Heuristic.act(&env, Side::Target, &mut acts[k..]);
            let mut rewards = vec![0f32; k + 1];
            env.step_state(&acts, &mut rewards);
            played.push(acts);
            if env.is_done() {
                break;
            }
        }
    }
    Ok(states)
}

pub fn run(
    cfg: &EnvConfig,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    env_spec: &str,
    secs: f64,
    planner_model: Option<&ControllerSpec>,
) -> Result<()> {
    let states = episode_states(cfg, maps)?;
    greedy_rows(&states, cfg.num_captors, env_spec, secs);
    target_rows(&states, secs);
    if let Some(model) = planner_model {
        model_rows(&states, secs, model)?;
    }
    Ok(())
}

/// The planners against a learned team (`--planner-model`): each target's
/// decision with the team's futures batched (one forward per simulated
/// step for all of them) and played one game at a time, on the same states.
fn model_rows(states: &[TrapEnv], secs: f64, model: &ControllerSpec) -> Result<()> {
    println!("\nAgainst `{model}` as a model:\n");
    println!("| target controller | futures | time per decision | decisions/s | moves other than the rule-based target's |");
    println!("|---|---|---|---|---|");
    for robust in [false, true] {
        for batched in [true, false] {
            let team = model.build(Side::Captors)?;
            let team: Box<dyn Controller> = if batched {
                team
            } else {
                Box::new(OneGameAtATime(team))
            };
            let mut target: Box<dyn Controller> = if robust {
                let mut models: Vec<Box<dyn Controller>> = vec![
                    Box::new(Heuristic),
                    Box::new(RandomisedExpert::new(1)),
                    Box::new(RandomisedExpert::new(2)),
                ];
                models.push(team);
                Box::new(RobustLookahead::new(10, models))
            } else {
                Box::new(Lookahead::new(10, team))
            };
            let name = if robust {
                "robust:10:heuristic+expert:1+expert:2+MODEL"
            } else {
                "lookahead:10:MODEL"
            };
            let mut out = [Action::Stop];
            let mut departures = 0;
            for env in states {
                target.reset(env, 0);
                target.act(env, Side::Target, &mut out);
                departures += usize::from(out[0] != target_action(env));
            }
            let start = Instant::now();
            let mut decisions = 0usize;
            while start.elapsed().as_secs_f64() < secs {
                let env = &states[decisions % states.len()];
                target.reset(env, 0);
                target.act(env, Side::Target, &mut out);
                decisions += 1;
            }
            let per = start.elapsed().as_secs_f64() / decisions as f64;
            println!(
                "| {name} | {} | {:.2} ms | {:.0} | {:.1}% ({departures} of {}) |",
                if batched {
                    "batched"
                } else {
                    "one game at a time"
                },
                per * 1e3,
                1.0 / per,
                100.0 * departures as f64 / states.len() as f64,
                states.len()
            );
        }
    }
    Ok(())
}

/// The captors' table: each coarsening's time and agreement with the spec's
/// cells; apart from `run` so each table is one function.
fn greedy_rows(states: &[TrapEnv], k: usize, env_spec: &str, secs: f64) {
    let decide = |greedy: &mut AszGreedy, env: &TrapEnv| {
        let mut acts = vec![Action::Stop; k];
        greedy.act(env, Side::Captors, &mut acts);
        acts
    };
    let mut spec_actions = Vec::new();
    println!(
        "\nASZ-greedy, one decision for {k} captors, over {} states of expert-captor episodes on {env_spec} (every 20th step of the first 200, 8 episodes), {secs:.1} s per row, 1 thread\n",
        states.len()
    );
    // The spec's cells' decision before the environment's speed work
    // (bench.rs's BEFORE_DATE), on the Gibson maps.
    let before_ms = (env_spec == "gibson").then_some(7.86);
    println!(
        "| controller | cell | time per decision | decisions/s | x greedy | {before} | x {before} | same action as greedy |",
        before = BEFORE_DATE
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut first_rate = None;
    for coarsening in COARSENINGS {
        let mut greedy = AszGreedy::new(coarsening);
        let actions: Vec<Vec<Action>> = states.iter().map(|env| decide(&mut greedy, env)).collect();
        if coarsening == 1 {
            spec_actions = actions.clone();
        }
        let same = actions
            .iter()
            .zip(&spec_actions)
            .flat_map(|(a, b)| a.iter().zip(b))
            .filter(|(a, b)| a == b)
            .count();
        let total = states.len() * k;
        let start = Instant::now();
        let mut decisions = 0usize;
        while start.elapsed().as_secs_f64() < secs {
            decide(&mut greedy, &states[decisions % states.len()]);
            decisions += 1;
        }
        let per = start.elapsed().as_secs_f64() / decisions as f64;
        let rate = 1.0 / per;
        let base = *first_rate.get_or_insert(rate);
        let (before, speedup) = match before_ms.filter(|_| coarsening == 1) {
            Some(b) => (format!("{b:.2} ms"), format!("{:.2}x", b / (per * 1e3))),
            None => ("-".into(), "-".into()),
        };
        println!(
            "| {} | {:.2} m | {:.2} ms | {:.0} | {:.1}x | {before} | {speedup} | {:.1}% ({same} of {total}) |",
            greedy.name(),
            0.05 * coarsening as f64,
            per * 1e3,
            rate,
            rate / base,
            100.0 * same as f64 / total as f64
        );
    }
}

/// The target's table: the lookahead and robust lookahead targets' time and
/// departures from the rule-based target; apart from `run` so each table is
/// one function.
fn target_rows(states: &[TrapEnv], secs: f64) {
    // The lookahead target's decision over the same states: five futures of
    // its horizon against the expert captors, each scored by a coarse ASZ.
    println!("\n| target controller | time per decision | decisions/s | moves other than the rule-based target's |");
    println!("|---|---|---|---|");
    for horizon in [5, 10, 20] {
        let mut lookahead = Lookahead::new(horizon, Box::new(Heuristic));
        let departures = states
            .iter()
            .filter(|env| lookahead.target_action(env) != target_action(env))
            .count();
        let start = Instant::now();
        let mut decisions = 0usize;
        while start.elapsed().as_secs_f64() < secs {
            lookahead.target_action(&states[decisions % states.len()]);
            decisions += 1;
        }
        let per = start.elapsed().as_secs_f64() / decisions as f64;
        println!(
            "| {} | {:.2} ms | {:.0} | {:.1}% ({departures} of {}) |",
            lookahead.name(),
            per * 1e3,
            1.0 / per,
            100.0 * departures as f64 / states.len() as f64,
            states.len()
        );
    }
    // The robust lookahead target against one, two and three models: its
    // cost grows with the models, and it departs far less often.
    for models in 1..=3u64 {
        let make = || -> Vec<Box<dyn Controller>> {
            (0..models)
                .map(|m| -> Box<dyn Controller> {
                    if m == 0 {
                        Box::new(Heuristic)
                    } else {
                        Box::new(RandomisedExpert::new(m))
                    }
                })
                .collect()
        };
        let mut robust = RobustLookahead::new(10, make());
        let departures = states
            .iter()
            .filter(|env| robust.target_action(env) != target_action(env))
            .count();
        let start = Instant::now();
        let mut decisions = 0usize;
        while start.elapsed().as_secs_f64() < secs {
            robust.target_action(&states[decisions % states.len()]);
            decisions += 1;
        }
        let per = start.elapsed().as_secs_f64() / decisions as f64;
        let names = ["heuristic", "expert:1", "expert:2"][..models as usize].join("+");
        println!(
            "| robust:10:{names} | {:.2} ms | {:.0} | {:.1}% ({departures} of {}) |",
            per * 1e3,
            1.0 / per,
            100.0 * departures as f64 / states.len() as f64,
            states.len()
        );
    }
}
