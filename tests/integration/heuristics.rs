//! The rule-based robots of spec §7 and the controller catalogue.

use t2e_core::asz::Source;
use t2e_core::env::physics::{self, Robot};
use t2e_core::env::*;
use t2e_core::heuristics::*;
use t2e_core::map::Grid;
use t2e_learners::controllers::ControllerSpec;

use crate::common;
use common::{robot, room};

/// K captors and a target in `g`, episodes of 500 steps.
fn env_in(k: usize, g: Grid, robots: Vec<Robot>) -> TrapEnv {
    let cfg = EnvConfig {
        num_captors: k,
        episode_length: 500,
        ..EnvConfig::default()
    };
    common::env_with(cfg, common::maps(g), robots)
}

#[test]
fn forces_become_actions_along_the_larger_axis() {
    // Heading +x: forward is +x, right is -y.
    assert_eq!(force_to_action(0.0, [1.0, 0.2]), Action::Forward);
    assert_eq!(force_to_action(0.0, [-1.0, 0.2]), Action::Backward);
    assert_eq!(force_to_action(0.0, [0.1, -1.0]), Action::TurnRight);
    assert_eq!(force_to_action(0.0, [0.1, 1.0]), Action::TurnLeft);
    // Heading +y: forward is +y, right is +x.
    assert_eq!(
        force_to_action(std::f64::consts::FRAC_PI_2, [1.0, 0.0]),
        Action::TurnRight
    );
}

#[test]
fn target_flees_and_captor_chases() {
    // Big room, captor east of the target, both facing east (+x).
    let g = room(60, 260, 60, 260);
    let env = env_in(
        1,
        g.clone(),
        vec![robot(1.0, 0.0, 0.0), robot(0.0, 0.0, 0.0)],
    );
    assert_eq!(
        target_action(&env),
        Action::Backward,
        "away from the captor is -x, behind it"
    );
    assert_eq!(
        expert_captor_action(&env, 0),
        Action::Backward,
        "the target is behind the captor"
    );
    // Facing west, both go forward.
    let env = env_in(
        1,
        g.clone(),
        vec![
            robot(1.0, 0.0, std::f64::consts::PI),
            robot(0.0, 0.0, std::f64::consts::PI),
        ],
    );
    assert_eq!(target_action(&env), Action::Forward);
    assert_eq!(expert_captor_action(&env, 0), Action::Forward);
    // A wall 0.3 m ahead outweighs a far captor behind: the target turns or backs off.
    let g = room(60, 260, 60, 166); // east wall at x = 0.3
    let env = env_in(1, g, vec![robot(-4.0, 0.0, 0.0), robot(0.0, 0.0, 0.0)]);
    assert_ne!(
        target_action(&env),
        Action::Forward,
        "does not drive into the wall"
    );
}

/// In the open, three expert captors closing in from three sides ring a
/// still target. (Their wall term, 0.6 sum D / d_m, balances the pull towards
/// the target about a metre from walls and corridor mouths, so a target
/// resting by a wall is safe from them: one reason their SR stays near 70%.)
#[test]
fn expert_captors_ring_a_still_target_in_the_open() {
    let g = room(60, 260, 60, 260);
    let robots: Vec<Robot> = (0..3)
        .map(|i| {
            let a = i as f64 * 2.0 * std::f64::consts::PI / 3.0 + 0.3;
            robot(
                2.0 * a.cos(),
                2.0 * a.sin(),
                (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU),
            )
        })
        .chain([robot(0.0, 0.0, 0.0)])
        .collect();
    let mut env = env_in(3, g, robots);
    let mut acts = [Action::Stop; 4];
    let mut h = Heuristic;
    while !env.is_done() {
        h.act(&env, Side::Captors, &mut acts[..3]);
        env.step(&acts);
    }
    assert!(env.captured, "not captured after {} steps", env.steps);
    assert!(env.steps < 100, "took {} steps", env.steps);
}

/// Robot `i` after one step of `a`, the others still.
fn moved_alone(env: &TrapEnv, i: usize, a: Action) -> Robot {
    let mut alone = [env.robots[i]];
    physics::step(
        env.map(),
        &mut alone,
        &[env.spec(i)],
        &[a],
        env.cfg.drive_force,
        &mut [0.0],
    );
    alone[0]
}

#[test]
fn greedy_captor_picks_the_action_that_shrinks_the_asz_most() {
    let g = room(60, 260, 60, 260);
    let robots = vec![
        robot(-1.0, 0.0, 0.3),
        robot(1.0, 1.5, 2.0),
        robot(1.0, -1.5, 4.0),
        robot(0.0, 0.0, 0.0),
    ];
    let env = env_in(3, g, robots);
    let mut greedy = AszGreedy::default();
    let (captors, target) = env.asz_sources();
    for i in 0..3 {
        let chosen = greedy.captor_action(&env, i);
        let asz_after = |a: Action| {
            let alone = [moved_alone(&env, i, a)];
            let mut c = captors.clone();
            c[i] = Source {
                pos: alone[0].pos,
                speed: 1.0,
            };
            t2e_core::asz::AszFields::new().asz_cells(&**env.map(), target, &c)
        };
        let sizes: Vec<usize> = [
            Action::Forward,
            Action::Backward,
            Action::TurnRight,
            Action::TurnLeft,
        ]
        .iter()
        .map(|&a| asz_after(a))
        .collect();
        let best = *sizes.iter().min().unwrap();
        assert!(
            sizes.iter().any(|&s| s != best),
            "the actions must differ here: {sizes:?}"
        );
        assert_eq!(
            asz_after(chosen),
            best,
            "captor {i} chose {chosen:?} among {sizes:?}"
        );
    }
}

#[test]
fn greedy_target_picks_the_action_that_keeps_the_largest_asz() {
    // Captors on the target's left, open room on its right, the target
    // facing away from them: forward and backward leave it different ASZs.
    let g = room(60, 260, 60, 260);
    let robots = vec![
        robot(-1.5, 0.5, 0.0),
        robot(-1.5, -0.5, 0.0),
        robot(-2.0, 0.0, 0.0),
        robot(0.0, 0.0, 0.0),
    ];
    let env = env_in(3, g, robots);
    let t = env.target_index();
    let (captors, target) = env.asz_sources();
    let actions = [
        Action::Forward,
        Action::Backward,
        Action::TurnRight,
        Action::TurnLeft,
    ];
    let sizes: Vec<usize> = actions
        .iter()
        .map(|&a| {
            let moved = Source {
                pos: moved_alone(&env, t, a).pos,
                speed: target.speed,
            };
            t2e_core::asz::AszFields::new().asz_cells(&**env.map(), moved, &captors)
        })
        .collect();
    let best = *sizes.iter().max().unwrap();
    assert!(
        sizes.iter().any(|&s| s != best),
        "the actions must differ here: {sizes:?}"
    );
    let chosen = AszGreedy::default().target_action(&env);
    let i = actions.iter().position(|&a| a == chosen).unwrap();
    assert_eq!(sizes[i], best, "chose {chosen:?} among {sizes:?}");
    // On coarse cells it still moves away from the captors.
    let mut out = [Action::Stop];
    AszGreedy::new(2).act(&env, Side::Target, &mut out);
    assert_ne!(out[0], Action::Stop);
}

#[test]
fn controllers_are_named_and_checked_per_side() {
    for name in ["heuristic", "greedy", "greedy:2", "random", "still"] {
        let spec: ControllerSpec = name.parse().unwrap();
        assert_eq!(spec.to_string(), name);
        assert!(spec.build(Side::Captors).is_ok());
    }
    // The ASZ-greedy rule plays either side (the target keeps its largest ASZ).
    assert!(ControllerSpec::Greedy { coarsening: 2 }
        .build(Side::Target)
        .is_ok());
    for bad in ["greedy:0", "greedy:9", "greedy:x", "greedy:"] {
        assert!(
            bad.parse::<ControllerSpec>()
                .unwrap_err()
                .to_string()
                .contains("coarsening"),
            "{bad}"
        );
    }
    assert!("greedy:1".parse::<ControllerSpec>().unwrap().to_string() == "greedy");
    assert!("magic"
        .parse::<ControllerSpec>()
        .unwrap_err()
        .to_string()
        .contains("unknown controller"));
    for empty in ["ckpt:", "sample:"] {
        assert!(
            empty
                .parse::<ControllerSpec>()
                .unwrap_err()
                .to_string()
                .contains("needs a path"),
            "{empty}"
        );
    }
    // A checkpoint greedily and the same checkpoint sampled are two controllers.
    let greedy: ControllerSpec = "ckpt:runs/x".parse().unwrap();
    let sampled: ControllerSpec = "sample:runs/x".parse().unwrap();
    assert_ne!(greedy, sampled);
    assert_eq!(
        (greedy.to_string(), sampled.to_string()),
        ("ckpt:runs/x".into(), "sample:runs/x".into())
    );
    let missing = sampled.build(Side::Captors).err().unwrap().to_string();
    assert!(missing.contains("runs/x"), "{missing}");
}

#[test]
fn random_controller_replays_with_the_seed() {
    let g = room(60, 260, 60, 260);
    let env = env_in(
        3,
        g,
        vec![
            robot(-1.0, 0.0, 0.0),
            robot(1.0, 1.0, 0.0),
            robot(1.0, -1.0, 0.0),
            robot(3.0, 3.0, 0.0),
        ],
    );
    let draw = |seed| {
        let mut r = RandomActions::new();
        r.reset(&env, seed);
        let mut out = vec![Action::Stop; 30];
        for chunk in out.chunks_mut(3) {
            r.act(&env, Side::Captors, chunk);
        }
        out
    };
    assert_eq!(draw(5), draw(5));
    assert_ne!(draw(5), draw(6));
    let all = draw(5);
    assert!(
        Action::ALL.iter().all(|a| all.contains(a)),
        "all five actions occur in 30 draws"
    );
}

#[test]
fn randomised_experts_draw_their_constants_per_episode_and_replay_with_the_seed() {
    let g = room(60, 260, 60, 260);
    let env = env_in(
        3,
        g,
        vec![
            robot(-1.0, 0.0, 0.0),
            robot(1.0, 1.0, 0.0),
            robot(1.0, -1.0, 0.0),
            robot(3.0, 3.0, 0.7),
        ],
    );
    let params = |team: u64, episode: u64| {
        let mut e = RandomisedExpert::new(team);
        e.reset(&env, episode);
        e.params()
    };
    assert_eq!(params(1, 5), params(1, 5), "same team, same episode");
    assert_ne!(params(1, 5), params(1, 6), "a new episode draws anew");
    assert_ne!(params(1, 5), params(2, 5), "teams differ");
    for episode in 0..200 {
        let p = params(3, episode);
        assert!((0.3..1.2).contains(&p.wall_weight), "{p:?}");
        assert!((0.5..20.0).contains(&p.separation), "{p:?}");
        assert!((0.0..1.0).contains(&p.lead_m), "{p:?}");
        assert!((0.0..0.1).contains(&p.noise), "{p:?}");
    }
    // The spec's constants are the expert, decision for decision.
    for i in 0..3 {
        assert_eq!(
            expert_captor_action_with(&env, i, &ExpertParams::SPEC),
            expert_captor_action(&env, i)
        );
    }
    // A lead far enough ahead turns the chase: aiming 1 m ahead of a target
    // heading 0.7 rad changes at least one captor's action here, or the
    // constants would not make another team.
    let lead = ExpertParams {
        lead_m: 1.0,
        separation: 20.0,
        ..ExpertParams::SPEC
    };
    assert!(
        (0..3).any(|i| expert_captor_action_with(&env, i, &lead) != expert_captor_action(&env, i)),
        "the constants change what the experts do"
    );
    // Named and refused as a target.
    let spec: ControllerSpec = "expert:7".parse().unwrap();
    assert_eq!(spec.to_string(), "expert:7");
    assert!(spec.build(Side::Captors).is_ok());
    let err = spec.build(Side::Target).err().unwrap().to_string();
    assert!(err.contains("captor team"), "{err}");
    assert!("expert:x"
        .parse::<ControllerSpec>()
        .unwrap_err()
        .to_string()
        .contains("expert:SEED"));
}

/// The ASZ-greedy rule as the spec states it, every robot's field marched
/// afresh for each move, written apart from `AszGreedy`: whatever field the
/// planner keeps, it
/// must pick the same action on every state. Also says whether the sizes
/// decided (not the geodesic fallback).
fn greedy_by_definition(
    env: &TrapEnv,
    i: usize,
    fm: &mut t2e_core::asz::FastMarching,
) -> (Action, bool) {
    let actions = [
        Action::Forward,
        Action::Backward,
        Action::TurnRight,
        Action::TurnLeft,
    ];
    let (mut captors, target) = env.asz_sources();
    let sizes: Vec<usize> = actions
        .iter()
        .map(|&a| {
            captors[i] = Source {
                pos: moved_alone(env, i, a).pos,
                speed: env.spec(i).max_speed,
            };
            t2e_core::asz::AszFields::new().asz_cells(&**env.map(), target, &captors)
        })
        .collect();
    if sizes.iter().any(|&s| s != sizes[0]) {
        let best = (0..4).min_by_key(|&a| sizes[a]).unwrap();
        return (actions[best], true);
    }
    let map = env.map();
    fm.distance_field(&**map, target.pos);
    let geodesic = |a: Action| {
        let (r, c) = map.grid.cell_of(moved_alone(env, i, a).pos);
        if map.grid.is_free(r, c) {
            fm.time(map.padded_index(r, c))
        } else {
            f32::INFINITY
        }
    };
    let best = (0..4)
        .min_by(|&a, &b| geodesic(actions[a]).total_cmp(&geodesic(actions[b])))
        .unwrap();
    (actions[best], false)
}

/// Three captors and a target on the 26 Gibson maps, episodes of 500 steps.
fn gibson_3v1() -> TrapEnv {
    let maps = t2e_core::map::catalog::load_prepared("gibson").unwrap();
    let cfg = EnvConfig {
        num_captors: 3,
        episode_length: 500,
        ..EnvConfig::default()
    };
    TrapEnv::new(cfg, maps).unwrap()
}

#[test]
fn greedy_captors_pick_the_definitions_action_on_real_states() {
    let mut env = gibson_3v1();
    let mut greedy = AszGreedy::default();
    let mut fm = t2e_core::asz::FastMarching::new();
    let mut rewards = vec![0f32; 4];
    let (mut decisions, mut by_size) = (0, 0);
    for seed in 0..26u64 {
        env.reset_state(seed).unwrap();
        // States along an episode of the rule-based robots, where captors
        // close in and the moves' regions differ.
        for step in 0..(40 + 9 * seed) {
            let mut acts = [Action::Stop; 4];
            Heuristic.act(&env, Side::Captors, &mut acts[..3]);
            Heuristic.act(&env, Side::Target, &mut acts[3..]);
            env.step_state(&acts, &mut rewards);
            if env.is_done() {
                break;
            }
            if step % 20 != 19 {
                continue;
            }
            for i in 0..3 {
                let (expected, sized) = greedy_by_definition(&env, i, &mut fm);
                assert_eq!(
                    greedy.captor_action(&env, i),
                    expected,
                    "seed {seed}, step {step}, captor {i}"
                );
                decisions += 1;
                by_size += usize::from(sized);
            }
        }
    }
    // Most decisions must be decided by the sizes, not the fallback.
    assert!(
        decisions >= 100 && by_size * 2 > decisions,
        "{decisions} decisions, {by_size} by size"
    );
}

#[test]
fn lookahead_targets_are_named_and_play_the_target_only() {
    for (name, horizon, model) in [
        ("lookahead:10", 10, ControllerSpec::Heuristic),
        (
            "lookahead:3:greedy:2",
            3,
            ControllerSpec::Greedy { coarsening: 2 },
        ),
        (
            "lookahead:1:expert:7",
            1,
            ControllerSpec::RandomisedExpert { seed: 7 },
        ),
    ] {
        let spec: ControllerSpec = name.parse().unwrap();
        assert_eq!(
            spec,
            ControllerSpec::Lookahead {
                horizon,
                captors: Box::new(model)
            }
        );
        assert_eq!(spec.to_string(), name);
        assert!(spec.build(Side::Target).is_ok());
        let refused = spec.build(Side::Captors).err().unwrap().to_string();
        assert!(refused.contains("target only"), "{refused}");
    }
    for bad in [
        "lookahead:",
        "lookahead:0",
        "lookahead:101",
        "lookahead:x",
        "lookahead:5:lookahead:5",
    ] {
        let why = bad.parse::<ControllerSpec>().unwrap_err().to_string();
        assert!(why.contains("horizon"), "{bad}: {why}");
    }
    // The model must be a captor team that parses.
    let why = "lookahead:5:magic"
        .parse::<ControllerSpec>()
        .unwrap_err()
        .to_string();
    assert!(why.contains("unknown controller 'magic'"), "{why}");
}

/// Where `first`, then the rule-based target, leads in `horizon` steps
/// against the expert captors, written apart from `Lookahead`: caught (and
/// when), or |ASZ| on 0.2 m cells at the end.
fn future_by_definition(env: &TrapEnv, first: Action, horizon: usize) -> (bool, usize) {
    future_against(env, first, horizon, &mut Heuristic)
}

#[test]
fn the_lookahead_target_plays_the_best_simulated_future() {
    let mut env = gibson_3v1();
    let horizon = 6;
    let mut lookahead = Lookahead::new(horizon, Box::new(Heuristic));
    let mut rewards = vec![0f32; 4];
    let (mut decisions, mut departures, mut escapes) = (0, 0, 0);
    for seed in 0..12u64 {
        env.reset_state(seed).unwrap();
        for step in 0..120 {
            let mut acts = [Action::Stop; 4];
            Heuristic.act(&env, Side::Captors, &mut acts[..3]);
            let chosen = lookahead.target_action(&env);
            if step % 10 == 9 {
                let rule = target_action(&env);
                let futures: Vec<(bool, usize)> = Action::ALL
                    .iter()
                    .map(|&a| future_by_definition(&env, a, horizon))
                    .collect();
                let best = *futures.iter().max().unwrap();
                let of = |a: Action| futures[Action::ALL.iter().position(|&b| b == a).unwrap()];
                assert_eq!(of(chosen), best, "seed {seed}, step {step}: {futures:?}");
                // Equal futures keep the rule-based action.
                if of(rule) == best {
                    assert_eq!(chosen, rule, "seed {seed}, step {step}");
                }
                decisions += 1;
                departures += usize::from(chosen != rule);
                escapes += usize::from(!of(rule).0 && best.0);
            }
            acts[3] = chosen;
            env.step_state(&acts, &mut rewards);
            if env.is_done() {
                break;
            }
        }
    }
    assert!(
        decisions >= 60 && departures > 0,
        "{decisions} decisions, {departures} departures, {escapes} escapes"
    );
}

#[test]
fn a_copied_world_plays_on_as_the_original() {
    let maps = t2e_core::map::catalog::load_prepared("shipped").unwrap();
    let cfg = EnvConfig {
        num_captors: 3,
        ..EnvConfig::default()
    };
    let mut env = TrapEnv::new(cfg.clone(), maps.clone()).unwrap();
    env.reset_state(4).unwrap();
    let mut rewards = vec![0f32; 4];
    let mut step_both = |env: &mut TrapEnv| {
        let mut acts = [Action::Stop; 4];
        Heuristic.act(env, Side::Captors, &mut acts[..3]);
        Heuristic.act(env, Side::Target, &mut acts[3..]);
        env.step_state(&acts, &mut rewards);
        rewards.clone()
    };
    for _ in 0..30 {
        step_both(&mut env);
    }
    let mut copy = env.clone();
    // clone_from into a world of another episode overwrites all of it.
    let mut other = TrapEnv::new(cfg, maps).unwrap();
    other.reset_state(9).unwrap();
    other.clone_from(&env);
    for _ in 0..200 {
        let want = step_both(&mut env);
        assert_eq!(step_both(&mut copy), want);
        assert_eq!(step_both(&mut other), want);
        assert_eq!(copy.robots, env.robots);
        assert_eq!(other.robots, env.robots);
        assert_eq!((copy.steps, copy.captured), (env.steps, env.captured));
        assert_eq!(copy.path_len, env.path_len);
        if env.is_done() {
            break;
        }
    }
}

/// Where `first`, then the rule-based target, leads in `horizon` steps
/// against `team`, written apart from the planners: caught (and when), or
/// |ASZ| on 0.2 m cells at the end.
fn future_against(
    env: &TrapEnv,
    first: Action,
    horizon: usize,
    team: &mut dyn Controller,
) -> (bool, usize) {
    let mut sim = env.clone();
    let k = sim.num_captors();
    let mut rewards = vec![0f32; k + 1];
    for step in 0..horizon {
        if sim.is_done() {
            break;
        }
        let mut acts = vec![Action::Stop; k + 1];
        team.act(&sim, Side::Captors, &mut acts[..k]);
        acts[k] = if step == 0 {
            first
        } else {
            target_action(&sim)
        };
        sim.step_state(&acts, &mut rewards);
        if sim.captured {
            return (false, step);
        }
    }
    let lattice = t2e_core::asz::CoarseLattice::new(sim.map(), 4);
    let (captors, target) = sim.asz_sources();
    (
        true,
        t2e_core::asz::AszFields::new().asz_cells(&lattice, target, &captors),
    )
}

/// The robust target keeps the rule-based move unless some model catches
/// it, and then departs only to a move no model catches, the one with the
/// largest worst-case |ASZ|; each decision is checked against futures
/// simulated apart from it, against each model in turn.
#[test]
fn the_robust_target_departs_only_where_every_model_agrees() {
    let mut env = gibson_3v1();
    let horizon = 6;
    let spec: ControllerSpec = "robust:6:heuristic+greedy:4".parse().unwrap();
    assert_eq!(spec.to_string(), "robust:6:heuristic+greedy:4");
    let models =
        || -> Vec<Box<dyn Controller>> { vec![Box::new(Heuristic), Box::new(AszGreedy::new(4))] };
    let mut robust = RobustLookahead::new(horizon, models());
    let mut check_models = models();
    let mut rewards = vec![0f32; 4];
    let (mut checked, mut departures, mut rule_caught) = (0, 0, 0);
    for seed in 0..10u64 {
        env.reset_state(seed).unwrap();
        for step in 0..120 {
            let mut acts = [Action::Stop; 4];
            Heuristic.act(&env, Side::Captors, &mut acts[..3]);
            let chosen = robust.target_action(&env);
            let rule = target_action(&env);
            if chosen != rule || step % 15 == 14 {
                let worst = |a: Action, models: &mut Vec<Box<dyn Controller>>| -> Option<usize> {
                    let futures: Vec<(bool, usize)> = models
                        .iter_mut()
                        .map(|m| future_against(&env, a, horizon, m.as_mut()))
                        .collect();
                    futures
                        .iter()
                        .all(|f| f.0)
                        .then(|| futures.iter().map(|f| f.1).min().unwrap())
                };
                let rule_worst = worst(rule, &mut check_models);
                let others: Vec<(Action, Option<usize>)> = Action::ALL
                    .iter()
                    .filter(|&&a| a != rule)
                    .map(|&a| (a, worst(a, &mut check_models)))
                    .collect();
                let best_free = others
                    .iter()
                    .filter_map(|(a, w)| w.map(|w| (w, *a)))
                    .max_by_key(|(w, _)| *w);
                match (rule_worst, best_free) {
                    (Some(_), _) | (None, None) => {
                        assert_eq!(chosen, rule, "seed {seed}, step {step}")
                    }
                    (None, Some((w, _))) => {
                        let got = others
                            .iter()
                            .find(|(a, _)| *a == chosen)
                            .and_then(|(_, w)| *w);
                        assert_eq!(got, Some(w), "seed {seed}, step {step}: {others:?}");
                    }
                }
                checked += 1;
                departures += usize::from(chosen != rule);
                rule_caught += usize::from(rule_worst.is_none());
            }
            acts[3] = chosen;
            env.step_state(&acts, &mut rewards);
            if env.is_done() {
                break;
            }
        }
    }
    let (decisions, counted) = robust.departures();
    assert!(
        decisions >= 100 && counted as usize == departures,
        "{decisions} decisions, {counted} counted, {departures} seen"
    );
    assert!(
        checked >= 40 && departures > 0,
        "{checked} checked, {departures} departures, {rule_caught} rule moves caught"
    );
    for bad in [
        "robust:6",
        "robust:0:heuristic",
        "robust:6:lookahead:3",
        "robust:6:heuristic+robust:2:greedy",
    ] {
        let why = bad.parse::<ControllerSpec>().unwrap_err().to_string();
        assert!(why.contains("robust:H:MODELS"), "{bad}: {why}");
    }
    assert!(spec
        .build(Side::Captors)
        .err()
        .unwrap()
        .to_string()
        .contains("target only"));
    // A learned team is a model like any other (its memory kept: below).
    let learned: ControllerSpec = "robust:6:heuristic+ckpt:runs/x".parse().unwrap();
    assert!(learned.is_checkpoint());
}

/// A planner's learned model stands for a team that played the real game:
/// after every decision it holds the GRU state of a twin of that team that
/// stepped through the real states only, however many futures the planner
/// simulated from it. Were the futures' steps kept, the model's memory
/// would be that of a team that lived through them.
#[test]
fn a_planners_learned_model_remembers_the_real_game_not_its_futures() {
    let seed = 7;
    let (model, mut env) = stored_team_and_world(seed);
    let mut lookahead = Lookahead::new(4, model.build(Side::Captors).unwrap());
    let mut robust = RobustLookahead::new(
        4,
        vec![Box::new(Heuristic), model.build(Side::Captors).unwrap()],
    );
    // The twin plays the real captors.
    let mut twin = model.build(Side::Captors).unwrap();
    lookahead.reset(&env, seed);
    robust.reset(&env, seed);
    twin.reset(&env, seed);
    assert_eq!(twin.memory(), Some(Vec::new()), "a fresh episode's memory");
    let (mut actions, mut rewards) = (vec![Action::Stop; 3], vec![0f32; 3]);
    let mut steps = 0;
    while steps < 12 && !env.is_done() {
        // Both planners decide in the same state; the lookahead's move is played.
        actions[2] = lookahead.target_action(&env);
        robust.target_action(&env);
        twin.act(&env, Side::Captors, &mut actions[..2]);
        let real = twin.memory().unwrap();
        assert_eq!(real.len(), 2 * 8, "two robots, hidden 8");
        assert_eq!(
            lookahead.model().memory().as_ref(),
            Some(&real),
            "step {steps}"
        );
        assert_eq!(
            robust.models()[1].memory().as_ref(),
            Some(&real),
            "step {steps}"
        );
        env.step_state(&actions, &mut rewards);
        steps += 1;
    }
    assert!(steps >= 2, "the episode ended at step {steps}");
    assert!(twin.memory().unwrap().iter().any(|&h| h != 0.0));
}

#[test]
fn the_tuned_targets_rule_is_the_rule_based_target_and_each_constant_changes_decisions() {
    let mut env = gibson_3v1();
    let spec: ControllerSpec = "tuned:0,0.6,1,0,0".parse().unwrap();
    assert_eq!(spec, ControllerSpec::Tuned(TargetParams::RULE));
    assert_eq!(spec.to_string(), "tuned:0,0.6,1,0,0");
    let varied = [
        TargetParams {
            falloff: 3.0,
            ..TargetParams::RULE
        },
        TargetParams {
            wall_weight: 2.0,
            ..TargetParams::RULE
        },
        TargetParams {
            wall_range: 0.1,
            ..TargetParams::RULE
        },
        TargetParams {
            lead_s: 1.5,
            ..TargetParams::RULE
        },
        TargetParams {
            open_pull: 1.0,
            ..TargetParams::RULE
        },
    ];
    let mut differ = [0usize; 5];
    let mut rewards = vec![0f32; 4];
    let mut states = 0;
    for seed in 0..8u64 {
        env.reset_state(seed).unwrap();
        for _ in 0..100 {
            if env.is_done() {
                break;
            }
            let rule = target_action(&env);
            assert_eq!(
                tuned_target_action(&env, &TargetParams::RULE),
                rule,
                "seed {seed}"
            );
            for (n, p) in differ.iter_mut().zip(&varied) {
                *n += usize::from(tuned_target_action(&env, p) != rule);
            }
            states += 1;
            let mut acts = [Action::Stop; 4];
            Heuristic.act(&env, Side::Captors, &mut acts[..3]);
            acts[3] = rule;
            env.step_state(&acts, &mut rewards);
        }
    }
    assert!(states > 300, "{states} states");
    for (n, p) in differ.iter().zip(&varied) {
        assert!(*n > 0, "{p:?} decided as the rule in all {states} states");
    }
    for bad in [
        "tuned:0,0.6,1,0",
        "tuned:0,0.6,1,0,x",
        "tuned:-1,0.6,1,0,0",
        "tuned:0,0.6,0,0,0",
    ] {
        assert!(bad.parse::<ControllerSpec>().is_err(), "{bad}");
    }
    assert!(spec.build(Side::Captors).is_err());
}

/// The stored two-captor MAPPO team (hidden 8) and a Gibson world for it.
fn stored_team_and_world(seed: u64) -> (ControllerSpec, TrapEnv) {
    let ckpt = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/stored/export-captors");
    let model: ControllerSpec = format!("ckpt:{}", ckpt.display()).parse().unwrap();
    let maps = t2e_core::map::catalog::load_prepared("gibson").unwrap();
    let cfg = EnvConfig {
        num_captors: 2,
        episode_length: 500,
        ..EnvConfig::default()
    };
    let mut env = TrapEnv::new(cfg, maps).unwrap();
    env.reset_state(seed).unwrap();
    (model, env)
}

#[test]
fn a_learned_team_plays_many_games_in_one_batch_as_it_plays_each_alone() {
    tch::set_num_threads(1);
    let (model, env) = stored_team_and_world(3);
    let mut batched = model.build(Side::Captors).unwrap();
    let mut alone = model.build(Side::Captors).unwrap();
    batched.reset(&env, 3);
    alone.reset(&env, 3);
    // Five games that part at their first step, as a planner's futures do;
    // each side keeps its own memories of them.
    let mut games: Vec<TrapEnv> = (0..5).map(|_| env.clone()).collect();
    let mut memories = vec![Vec::new(); 5];
    let mut alone_memories = vec![Vec::new(); 5];
    let mut rewards = vec![0f32; 3];
    let mut steps = 0;
    while steps < 30 && !games.iter().any(|g| g.is_done()) {
        let mut out = vec![Action::Stop; 5 * 2];
        {
            let views: Vec<&TrapEnv> = games.iter().collect();
            batched.act_batch(&views, Side::Captors, &mut memories, &mut out);
        }
        for (g, game) in games.iter_mut().enumerate() {
            alone.set_memory(&alone_memories[g]);
            let mut one = [Action::Stop; 2];
            alone.act(game, Side::Captors, &mut one);
            alone_memories[g] = alone.memory().unwrap();
            assert_eq!(&out[2 * g..2 * g + 2], &one, "game {g}, step {steps}");
            assert_eq!(alone_memories[g].len(), 2 * 8, "game {g}, step {steps}");
            assert_eq!(memories[g].len(), 2 * 8, "game {g}, step {steps}");
            for (a, b) in alone_memories[g].iter().zip(&memories[g]) {
                assert!((a - b).abs() < 1e-5, "game {g}, step {steps}: {a} vs {b}");
            }
            let target = if steps == 0 {
                Action::ALL[g]
            } else {
                target_action(game)
            };
            game.step_state(&[one[0], one[1], target], &mut rewards);
        }
        steps += 1;
    }
    assert!(steps >= 10, "the games ended at step {steps}");
    let parted = games
        .iter()
        .filter(|g| g.robots[2].pos != games[0].robots[2].pos)
        .count();
    assert!(parted >= 2, "the games never parted");
    assert!(
        memories.iter().any(|m| m != &memories[0]),
        "the games' memories never parted"
    );
}

#[test]
fn planners_decide_alike_with_a_learned_model_batched_or_played_one_by_one() {
    // Its many small forwards slow down many times over when libtorch's
    // threads share the cores with the other tests.
    tch::set_num_threads(1);
    let (model, _) = stored_team_and_world(0);
    let team = || model.build(Side::Captors).unwrap();
    let one_by_one = || -> Box<dyn Controller> { Box::new(OneGameAtATime(team())) };
    let mut lookahead = Lookahead::new(10, team());
    let mut lookahead_one = Lookahead::new(10, one_by_one());
    let mut robust = RobustLookahead::new(10, vec![team(), Box::new(Heuristic)]);
    let mut robust_one = RobustLookahead::new(10, vec![one_by_one(), Box::new(Heuristic)]);
    // Plays each future alone, the way the planners' futures are defined.
    let mut reference = team();
    // Each game starts in a corner of a 10 m room with the two captors
    // close, so that the rule's move is sometimes caught and the robust
    // target's alternatives are simulated too, the learned model first;
    // the expert captors play.
    let room_cfg = EnvConfig {
        num_captors: 2,
        episode_length: 500,
        ..EnvConfig::default()
    };
    let corners = [
        (-3.5, -3.5, 1.0),
        (3.5, -3.5, -1.0),
        (-3.5, 3.5, -1.0),
        (3.5, 3.5, 1.0),
    ];
    let (mut actions, mut rewards) = (vec![Action::Stop; 3], vec![0f32; 3]);
    let (mut steps, mut lookahead_departures) = (0, 0);
    for (game, &(x, y, s)) in corners.iter().cycle().take(8).enumerate() {
        let gap = if game < 4 { 1.0 } else { 1.5 };
        let towards = |v: f64| if v < 0.0 { v + gap } else { v - gap };
        let robots = vec![
            robot(towards(x), y, 0.0),
            robot(x, towards(y), s),
            robot(x, y, 0.5),
        ];
        let mut env = common::env_with(
            room_cfg.clone(),
            common::maps(room(60, 260, 60, 260)),
            robots,
        );
        let seed = game as u64;
        for planner in [
            &mut lookahead as &mut dyn Controller,
            &mut lookahead_one,
            &mut robust,
            &mut robust_one,
        ] {
            planner.reset(&env, seed);
        }
        for step in 0..40 {
            if env.is_done() {
                break;
            }
            let rule = target_action(&env);
            let mut moves = vec![rule];
            moves.extend(Action::ALL.into_iter().filter(|&a| a != rule));
            // Each move's future played alone, from the model's memory.
            let mut alone = |memory: &[f32], first: Action| {
                reference.set_memory(memory);
                future_against(&env, first, 10, reference.as_mut())
            };
            let memory = lookahead.model().memory().unwrap();
            let mut best: Option<((bool, usize), Action)> = None;
            for &first in &moves {
                let future = alone(&memory, first);
                if best.is_none_or(|(b, _)| future > b) {
                    best = Some((future, first));
                }
            }
            let planned = lookahead.target_action(&env);
            assert_eq!(planned, best.unwrap().1, "game {game}, step {step}");
            assert_eq!(
                planned,
                lookahead_one.target_action(&env),
                "game {game}, step {step}"
            );
            lookahead_departures += usize::from(planned != rule);
            let memory = robust.models()[0].memory().unwrap();
            let mut worst = |first: Action| {
                let learned = alone(&memory, first);
                let expert = future_against(&env, first, 10, &mut Heuristic);
                (learned.0 && expert.0).then(|| learned.1.min(expert.1))
            };
            let expected = match worst(rule) {
                Some(_) => rule,
                None => moves[1..]
                    .iter()
                    .filter_map(|&a| worst(a).map(|w| (w, a)))
                    .fold(None, |b: Option<(usize, Action)>, (w, a)| {
                        if b.is_none_or(|(bw, _)| w > bw) {
                            Some((w, a))
                        } else {
                            b
                        }
                    })
                    .map_or(rule, |(_, a)| a),
            };
            let robust_move = robust.target_action(&env);
            assert_eq!(robust_move, expected, "game {game}, step {step}");
            assert_eq!(
                robust_move,
                robust_one.target_action(&env),
                "game {game}, step {step}"
            );
            Heuristic.act(&env, Side::Captors, &mut actions[..2]);
            actions[2] = robust_move;
            env.step_state(&actions, &mut rewards);
            steps += 1;
        }
    }
    assert_eq!(robust.departures(), robust_one.departures());
    assert_eq!(robust.contested(), robust_one.contested());
    assert!(
        robust.contested() >= 1 && robust.departures().1 >= 1,
        "the robust target simulated its alternatives in {} of {steps} decisions and departed in {}",
        robust.contested(),
        robust.departures().1
    );
    assert!(
        lookahead_departures > 0,
        "the lookahead never departed in {steps} steps"
    );
}
