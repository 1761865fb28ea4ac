//! The environment against spec §2–§6: physics numbers, walls, contact,
//! capture, rewards, placement, observations, determinism and the vector env.

use std::sync::Arc;
use t2e_core::env::physics::{blocked_probes, target_is_trapped, Robot};
use t2e_core::env::potential::Potential;
use t2e_core::env::vec_env::episode_seed;
use t2e_core::env::*;
use t2e_core::heuristics::{Heuristic, RandomActions};
use t2e_core::map::PreparedMap;

use crate::common;
use common::{env_with, maps, robot, room};

/// A 10 m x 10 m room centred at the origin.
fn big_room() -> Arc<Vec<Arc<PreparedMap>>> {
    maps(room(60, 260, 60, 260))
}

fn cfg(k: usize) -> EnvConfig {
    EnvConfig {
        num_captors: k,
        ..EnvConfig::default()
    }
}

#[test]
fn drive_reaches_the_speed_limit_in_two_steps() {
    let mut env = env_with(
        cfg(1),
        big_room(),
        vec![robot(-3.0, 0.0, 0.0), robot(3.0, 0.0, 0.0)],
    );
    let s = env.step(&[Action::Forward, Action::Forward]);
    // Captor: F = 1 * 3^2 = 9, v = 0.9 after one step, moved 0.09 m.
    assert!((env.robots[0].vel[0] - 0.9).abs() < 1e-12);
    assert!((env.robots[0].pos[0] - (-3.0 + 0.09)).abs() < 1e-12);
    // Target: F = 16, v = 1.6 -> clamped to 1.0.
    assert!((env.robots[1].vel[0] - 1.0).abs() < 1e-12);
    env.step(&[Action::Forward, Action::Forward]);
    assert!(
        (env.robots[0].vel[0] - 1.0).abs() < 1e-12,
        "0.9 * 0.75 + 0.9 > 1 is clamped"
    );
    assert!(!s.info.collided[0] && !s.terminations[0] && !s.truncations[0]);

    // Single-factor drive: F = 3, v = 0.3.
    let single = EnvConfig {
        drive_force: DriveForce::Single,
        ..cfg(1)
    };
    let mut env = env_with(
        single,
        big_room(),
        vec![robot(-3.0, 0.0, 0.0), robot(3.0, 0.0, 0.0)],
    );
    env.step(&[Action::Forward, Action::Stop]);
    assert!((env.robots[0].vel[0] - 0.3).abs() < 1e-12);
}

#[test]
fn turning_rotates_by_thirty_degrees_and_drives_at_point_eight() {
    let mut env = env_with(
        cfg(1),
        big_room(),
        vec![robot(0.0, 0.0, 0.0), robot(3.0, 3.0, 0.0)],
    );
    env.step(&[Action::TurnLeft, Action::TurnRight]);
    let pi6 = std::f64::consts::PI / 6.0;
    assert!((env.robots[0].theta - pi6).abs() < 1e-12);
    assert!(
        (env.robots[1].theta - (2.0 * std::f64::consts::PI - pi6)).abs() < 1e-12,
        "kept in [0, 2pi)"
    );
    // 0.8 * 9 * 0.1 = 0.72 along the new heading.
    let v = env.robots[0].vel;
    assert!((v[0] - 0.72 * pi6.cos()).abs() < 1e-12 && (v[1] - 0.72 * pi6.sin()).abs() < 1e-12);
}

#[test]
fn walls_repel_and_block_and_cost_a_point() {
    // Room x in [-5, 5]: a captor heading for the east wall.
    let m = big_room();
    let mut env = env_with(
        cfg(1),
        m.clone(),
        vec![robot(4.5, 0.0, 0.0), robot(-3.0, 0.0, 0.0)],
    );
    let mut collided_steps = 0;
    for _ in 0..30 {
        let s = env.step(&[Action::Forward, Action::Stop]);
        assert!(
            !m[0].disc_touches_obstacle(env.robots[0].pos, 0.2),
            "never overlaps a wall"
        );
        assert!(env.robots[0].pos[0] <= 4.8 + 1e-9);
        collided_steps += s.info.collided[0] as usize;
    }
    // Drive and repulsion balance about 0.3 m from the wall; the robot hovers
    // there, flagged on most steps (as in the reference).
    assert!(
        collided_steps > 10,
        "pressing into the wall keeps the robot flagged"
    );
    // A one-cell pillar between two rays (at 15 degrees, 0.3 m away) does not
    // repel, but the disc reaches it: the robot stays, stops, and the step
    // costs exactly 1 + 0.4.
    let mut g = room(60, 260, 60, 260);
    g.set_free(160, 170, false);
    let pillar = g.cell_center(160, 170);
    let a = 15f64.to_radians();
    let mut r = robot(pillar[0] - 0.3 * a.cos(), pillar[1] - 0.3 * a.sin(), a);
    r.vel = [a.cos(), a.sin()];
    let start = r.pos;
    let mut env = env_with(cfg(1), maps(g), vec![r, robot(-3.0, 0.0, 0.0)]);
    let s = env.step(&[Action::Forward, Action::Stop]);
    assert_eq!(env.robots[0].pos, start);
    assert_eq!(env.robots[0].vel, [0.0, 0.0]);
    assert!(
        s.info.collided[0] && (s.rewards[0] + 1.4).abs() < 1e-6,
        "{:?}",
        s.rewards
    );
    // Repulsion: standing still 0.25 m from the wall (d_east = 0.25 < 0.3) pushes west.
    let mut env = env_with(
        cfg(1),
        m.clone(),
        vec![robot(4.75, 0.0, 0.0), robot(-3.0, 0.0, 0.0)],
    );
    let s = env.step(&[Action::Stop, Action::Stop]);
    assert!(s.info.collided[0] && env.robots[0].vel[0] < 0.0);
    // F = (1 - ln(0.25/0.3)) * 1 * 3 * 3 = 10.64, v = 1.064 -> clamped 1.0 westwards.
    assert!((env.robots[0].vel[0] + 1.0).abs() < 1e-9);
}

#[test]
fn overlapping_robots_are_pushed_apart() {
    let mut env = env_with(
        cfg(1),
        big_room(),
        vec![robot(0.0, 0.0, 0.0), robot(0.39, 0.0, 0.0)],
    );
    env.step(&[Action::Stop, Action::Stop]);
    assert!(env.robots[0].vel[0] < 0.0 && env.robots[1].vel[0] > 0.0);
    assert!(
        (env.robots[0].vel[0] + env.robots[1].vel[0]).abs() < 1e-9,
        "equal and opposite"
    );
    // Far apart: no force at all.
    let mut env = env_with(
        cfg(1),
        big_room(),
        vec![robot(0.0, 0.0, 0.0), robot(1.0, 0.0, 0.0)],
    );
    env.step(&[Action::Stop, Action::Stop]);
    assert_eq!(env.robots[0].vel, [0.0, 0.0]);
}

#[test]
fn fast_capture_needs_every_probe_blocked() {
    // Target in a 0.6 m wide dead end (x in [0, 0.6]) ending at y = 0;
    // probes on three sides hit walls, the open side needs a captor.
    let mut g = room(60, 160, 60, 260); // y in [0, 5], x in [-5, 5]
    for r in 160..200 {
        for c in 160..172 {
            g.set_free(r, c, true); // x in [0, 0.6], y in [-2, 0]
        }
    }
    let m = PreparedMap::new(g);
    let target = [0.3, -1.75];
    assert!(!target_is_trapped(&m, target, &[]));
    let plug = robot(0.3, -1.35, 0.0);
    assert!(target_is_trapped(&m, target, &[plug]));
    let loose = robot(0.3, -0.9, 0.0);
    assert!(!target_is_trapped(&m, target, &[loose]));
    // In the open, a captor 0.45 m away blocks the probes within +-78.8
    // degrees of it: two opposite captors leave gaps, three close the ring.
    let ring = |n: usize| -> Vec<Robot> {
        (0..n)
            .map(|i| {
                let a = i as f64 * 2.0 * std::f64::consts::PI / n as f64;
                robot(0.45 * a.cos(), 2.5 + 0.45 * a.sin(), 0.0)
            })
            .collect()
    };
    assert!(!target_is_trapped(&m, [0.0, 2.5], &ring(2)));
    assert!(target_is_trapped(&m, [0.0, 2.5], &ring(3)));
    // The trap potential counts them: a captor 0.45 m away blocks the
    // probes within 60.6 degrees of it (0, +-30, +-60), 5 of the 12.
    assert_eq!(blocked_probes(&m, [0.0, 2.5], &[]), 0);
    assert_eq!(blocked_probes(&m, [0.0, 2.5], &ring(1)), 5);
    assert_eq!(blocked_probes(&m, [0.0, 2.5], &ring(2)), 10);
    assert_eq!(blocked_probes(&m, [0.0, 2.5], &ring(3)), 12);
    let walls = blocked_probes(&m, target, &[]);
    assert!(0 < walls && walls < 12, "{walls}");
    assert_eq!(blocked_probes(&m, target, &[plug]), 12);
}

#[test]
fn the_vector_env_tracks_the_trap_potential_of_every_state() {
    // Expert captors against the rule-based target in a small room: the
    // potential of each world's state after every step (after any reset),
    // and of the state an episode ended in, 1 exactly at a capture.
    let m = maps(room(120, 200, 120, 200)); // 4 m x 4 m
    let short = EnvConfig {
        episode_length: 60,
        observations: false,
        ..cfg(3)
    };
    let mut venv = VecEnv::new(short, m, 6, 5).unwrap();
    venv.script(Side::Captors, || Box::new(Heuristic));
    venv.script(Side::Target, || Box::new(Heuristic));
    venv.track_potential(Potential::Trap);
    venv.reset().unwrap();
    let actions = vec![Action::Stop; 6 * 4];
    let (mut captures, mut cut) = (0, 0);
    for _ in 0..600 {
        venv.step(&actions).unwrap();
        for e in 0..6 {
            let phi = venv.potentials[e];
            assert_eq!(phi, Potential::Trap.of(venv.env(e)));
            assert!(
                (0.0..1.0).contains(&phi),
                "a live state is not a capture: {phi}"
            );
            if venv.terminated[e] {
                assert_eq!(venv.final_potentials[e], 1.0);
                captures += 1;
            }
            if venv.truncated[e] {
                assert!(venv.final_potentials[e] < 1.0);
                cut += 1;
            }
        }
    }
    assert!(
        captures > 0 && cut > 0,
        "{captures} captures, {cut} cut off"
    );
}

#[test]
fn rewards_follow_the_spec() {
    let mut out = [0f32; 4];
    // Captor 0 closed in by 0.1 m and touches; captor 1 fell back 0.2 m and
    // collided; captor 2 unchanged; not captured.
    rewards(
        3,
        &[-0.1, 0.2, 0.0],
        &[true, false, false],
        &[false, true, false, true],
        false,
        &mut out,
    );
    assert!((out[0] - (5.0 + 5.0 - 0.4)).abs() < 1e-5);
    assert!((out[1] - (-10.0 - 1.0 - 0.4)).abs() < 1e-5);
    assert!((out[2] - (-0.4)).abs() < 1e-5);
    // Target: +50 * mean(0.0333) - 5/3 * 1 contact - 1 collided - 0.4
    assert!((out[3] - (50.0 * 0.1 / 3.0 - 5.0 / 3.0 - 1.0 - 0.4)).abs() < 1e-4);
    rewards(3, &[0.0; 3], &[false; 3], &[false; 4], true, &mut out);
    assert!((out[0] - 199.6).abs() < 1e-4 && (out[3] + 200.4).abs() < 1e-4);
}

#[test]
fn placement_respects_the_distances_and_fails_cleanly() {
    let mut env = TrapEnv::new(cfg(4), big_room()).unwrap();
    for seed in 0..200 {
        env.reset(seed).unwrap();
        let r = &env.robots;
        for i in 0..5 {
            assert!(env.map().clearance_at(r[i].pos) > 0.4);
            assert!(
                r[i].theta >= 0.0 && r[i].theta < std::f64::consts::TAU && r[i].vel == [0.0, 0.0]
            );
            for j in 0..i {
                let d = physics::dist(r[i].pos, r[j].pos);
                assert!(d >= 1.0, "seed {seed}: robots {i},{j} only {d} m apart");
                if i < 4 {
                    assert!(d <= 4.0, "captors within 4 m");
                } else {
                    assert!(d <= 10.0, "target within 10 m of every captor");
                }
            }
        }
    }
    // A 1 m x 1 m room has no room for 3 captors 1 m apart.
    let mut env = TrapEnv::new(cfg(3), maps(room(150, 170, 150, 170))).unwrap();
    let e = env.reset(1).unwrap_err().to_string();
    assert!(
        e.contains("room") && e.contains("no valid initial placement"),
        "{e}"
    );
    // Impossible settings name the field.
    let e = TrapEnv::new(
        EnvConfig {
            target_speed: -1.0,
            ..cfg(3)
        },
        big_room(),
    )
    .err()
    .unwrap();
    match &e {
        t2e_core::error::EnvError::Config(c) => {
            assert_eq!(
                (c.field.as_str(), c.value.as_deref()),
                ("target_speed", Some("-1"))
            )
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().starts_with("target_speed = -1: "), "{e}");
    let no_maps = TrapEnv::new(cfg(3), std::sync::Arc::new(Vec::new())).err();
    assert_eq!(no_maps, Some(t2e_core::error::EnvError::NoMaps));
}

#[test]
fn observations_have_the_reference_layout() {
    let mut env = env_with(
        cfg(3),
        big_room(),
        vec![
            robot(0.0, 0.0, 0.0),
            robot(2.0, 0.0, 1.0),
            robot(0.0, 2.0, 0.5),
            robot(-2.0, -1.0, 3.0),
        ],
    );
    env.step(&[
        Action::Forward,
        Action::Forward,
        Action::Stop,
        Action::Forward,
    ]);
    let obs = env.observations();
    assert_eq!(obs.len(), 4);
    assert_eq!(obs[0].vector.len(), 20, "3v1: 20 numbers");
    let r = &env.robots;
    let v = &obs[0].vector;
    assert_eq!(
        &v[..5],
        &[
            r[0].vel[0] as f32,
            r[0].vel[1] as f32,
            r[0].pos[0] as f32,
            r[0].pos[1] as f32,
            r[0].theta as f32
        ]
    );
    // Then, as the reference groups them: the others' velocities (captor 1,
    // captor 2, target), their positions relative to robot 0, their heading
    // differences.
    assert_eq!(&v[5..7], &[r[1].vel[0] as f32, r[1].vel[1] as f32]);
    assert_eq!(&v[7..9], &[r[2].vel[0] as f32, r[2].vel[1] as f32]);
    // The target's velocity is hidden from everyone.
    assert_ne!(r[3].vel, [0.0, 0.0]);
    assert_eq!(&v[9..11], &[0.0, 0.0]);
    for (k, j) in [1, 2, 3].into_iter().enumerate() {
        assert!((v[11 + 2 * k] - (r[j].pos[0] - r[0].pos[0]) as f32).abs() < 1e-6);
        assert!((v[12 + 2 * k] - (r[j].pos[1] - r[0].pos[1]) as f32).abs() < 1e-6);
        assert!((v[17 + k] - (r[j].theta - r[0].theta) as f32).abs() < 1e-6);
    }
    // The target sees its own velocity, and the three captors' after it.
    let t = &obs[3].vector;
    assert_eq!(t[0], r[3].vel[0] as f32);
    assert_eq!(&t[5..7], &[r[0].vel[0] as f32, r[0].vel[1] as f32]);
    assert!((t[11] - (r[0].pos[0] - r[3].pos[0]) as f32).abs() < 1e-6);
}

#[test]
fn patch_is_binary_egocentric_and_rotates_with_the_robot() {
    // Wall 0.6 m east of the robot (room x in [-5, 0.6]).
    let m = maps(room(60, 260, 60, 172));
    let mut patch = vec![0u8; PATCH_LEN];
    let count_rows = |p: &[u8], rows: std::ops::Range<usize>| {
        rows.map(|a| {
            p[a * PATCH..(a + 1) * PATCH]
                .iter()
                .map(|&x| x as usize)
                .sum::<usize>()
        })
        .sum::<usize>()
    };
    // Facing east: the wall is ahead, at the top of the patch (row a is
    // 24 - a cells ahead: rows 0..=12 are 12 to 24 cells ahead).
    let mut env = env_with(
        cfg(1),
        m.clone(),
        vec![robot(0.0, 0.0, 0.0), robot(-3.0, 0.0, 0.0)],
    );
    env.write_observation(0, &mut [0.0; 10], &mut patch);
    assert!(patch.iter().all(|&x| x <= 1));
    assert_eq!(count_rows(&patch, 0..13), 13 * 48, "ahead is all wall");
    assert_eq!(count_rows(&patch, 13..48), 0, "behind is free");
    // Facing west: the wall is behind, at the bottom.
    env.set_robots(
        0,
        vec![robot(0.0, 0.0, std::f64::consts::PI), robot(-3.0, 0.0, 0.0)],
    );
    env.write_observation(0, &mut [0.0; 10], &mut patch);
    assert_eq!(count_rows(&patch, 36..48), 12 * 48);
    assert_eq!(count_rows(&patch, 0..36), 0);
    // Facing north: the wall is on the right, columns 36..48.
    env.set_robots(
        0,
        vec![
            robot(0.0, 0.0, std::f64::consts::FRAC_PI_2),
            robot(-3.0, 0.0, 0.0),
        ],
    );
    env.write_observation(0, &mut [0.0; 10], &mut patch);
    let right: usize = (0..48)
        .map(|a| {
            patch[a * 48 + 36..a * 48 + 48]
                .iter()
                .map(|&x| x as usize)
                .sum::<usize>()
        })
        .sum();
    assert_eq!(right, 12 * 48);
    assert_eq!(patch.iter().map(|&x| x as usize).sum::<usize>(), 12 * 48);
    // At 45 degrees the wall cuts a triangle off the top-right corner.
    env.set_robots(
        0,
        vec![
            robot(0.0, 0.0, std::f64::consts::FRAC_PI_4),
            robot(-3.0, 0.0, 0.0),
        ],
    );
    env.write_observation(0, &mut [0.0; 10], &mut patch);
    assert_eq!(
        patch[47], 1,
        "top-right corner is ahead-right: past the wall"
    );
    assert_eq!(patch[47 * 48], 0);
    assert_eq!(
        patch[47 * 48 + 47],
        0,
        "bottom-right is 0.85 m behind-right: west of the wall"
    );
}

/// Plays one episode with rule-based target and random captors; returns every state.
fn play(seed: u64, m: Arc<Vec<Arc<PreparedMap>>>) -> Vec<(Vec<Robot>, Vec<f32>)> {
    let mut env = TrapEnv::new(cfg(3), m).unwrap();
    env.reset(seed).unwrap();
    let mut captors = RandomActions::new();
    captors.reset(&env, seed);
    let mut trace = Vec::new();
    loop {
        let mut acts = [Action::Stop; 4];
        captors.act(&env, Side::Captors, &mut acts[..3]);
        Heuristic.act(&env, Side::Target, &mut acts[3..]);
        let s = env.step(&acts);
        trace.push((env.robots.clone(), s.rewards.clone()));
        if s.terminations[0] || s.truncations[0] {
            return trace;
        }
    }
}

#[test]
fn same_seed_same_episode_bit_for_bit() {
    let m = big_room();
    let a = play(7, m.clone());
    let b = play(7, m.clone());
    assert_eq!(a.len(), 200, "truncated at the training length");
    assert!(a == b, "replaying seed 7 differs");
    assert!(play(8, m) != a);
}

#[test]
fn vec_env_matches_single_envs_and_auto_resets() {
    let m = big_room();
    let short = EnvConfig {
        episode_length: 30,
        ..cfg(3)
    };
    let mut venv = VecEnv::new(short.clone(), m.clone(), 3, 99).unwrap();
    venv.script(Side::Target, || Box::new(Heuristic));
    venv.reset().unwrap();
    let mut singles: Vec<TrapEnv> = (0..3)
        .map(|e| {
            let mut env = TrapEnv::new(short.clone(), m.clone()).unwrap();
            env.reset(episode_seed(99, e, 0)).unwrap();
            env
        })
        .collect();
    let mut finished = 0;
    for t in 0..45 {
        let acts: Vec<Action> = (0..12)
            .map(|i| Action::from_index((i * 7 + t * 3) % 5))
            .collect();
        venv.step(&acts).unwrap();
        for (e, env) in singles.iter_mut().enumerate() {
            let mut a = acts[e * 4..e * 4 + 4].to_vec();
            a[3] = t2e_core::heuristics::target_action(env);
            let s = env.step(&a);
            assert_eq!(
                &venv.rewards[e * 4..e * 4 + 4],
                &s.rewards[..],
                "env {e} step {t}"
            );
            if s.truncations[0] || s.terminations[0] {
                assert!(venv.terminated[e] || venv.truncated[e]);
                // The state the episode ended in stays readable after the auto-reset.
                for (i, o) in s.observations.iter().enumerate() {
                    let r = e * 4 + i;
                    assert_eq!(&venv.final_vectors[r * 20..(r + 1) * 20], &o.vector[..]);
                    assert_eq!(
                        &venv.final_patches[r * PATCH_LEN..(r + 1) * PATCH_LEN],
                        &o.patch[..]
                    );
                }
                finished += 1;
                env.reset(episode_seed(99, e, 1)).unwrap();
            }
            let obs = env.observations();
            let vl = 20;
            for (i, o) in obs.iter().enumerate() {
                assert_eq!(
                    &venv.vectors[(e * 4 + i) * vl..(e * 4 + i + 1) * vl],
                    &o.vector[..]
                );
                assert_eq!(
                    &venv.patches[(e * 4 + i) * PATCH_LEN..(e * 4 + i + 1) * PATCH_LEN],
                    &o.patch[..]
                );
            }
        }
    }
    assert!(
        finished >= 3,
        "every world finished its first episode and restarted"
    );
}

/// The fast fixed-point patch agrees with a direct f64 rotation of the grid
/// (nearest cell, robot's cell at pixel (24, 24)) on a real floor plan, up to
/// pixels whose source point lies within rounding distance of a cell edge.
#[test]
fn patch_matches_a_direct_rotation_on_a_floor_plan() {
    use rand::{Rng, SeedableRng};
    let entries = t2e_core::map::resolve("shipped:medium").unwrap();
    let m = PreparedMap::new(entries[0].load().unwrap());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut patch = vec![0u8; PATCH_LEN];
    let (mut mismatches, mut total) = (0usize, 0usize);
    for _ in 0..200 {
        let cell = m.spawn_cells[rng.gen_range(0..m.spawn_cells.len())] as usize;
        let centre = m.grid.cell_center(cell / m.side(), cell % m.side());
        let pos = [
            centre[0] + rng.gen_range(-0.02..0.02),
            centre[1] + rng.gen_range(-0.02..0.02),
        ];
        let theta: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
        t2e_core::env::observe::write_patch(&m, pos, theta, &mut patch);
        let (r0, c0) = m.grid.cell_of(pos);
        for a in 0..PATCH {
            for b in 0..PATCH {
                let (right, forward) = (b as f64 - 24.0, 24.0 - a as f64);
                let dc = right * theta.sin() + forward * theta.cos();
                let dr = right * theta.cos() - forward * theta.sin();
                let expect = !m
                    .grid
                    .is_free(r0 + dr.round() as isize, c0 + dc.round() as isize)
                    as u8;
                total += 1;
                if patch[a * PATCH + b] != expect {
                    mismatches += 1;
                    let near_edge = |x: f64| (x - x.floor() - 0.5).abs() < 1e-3;
                    assert!(
                        near_edge(dc) || near_edge(dr),
                        "pixel ({a},{b}) differs away from a cell edge"
                    );
                }
            }
        }
    }
    assert!(
        mismatches * 1000 < total,
        "{mismatches} of {total} pixels differ"
    );
}

#[test]
fn the_asz_potential_rises_as_the_captors_close_in() {
    // A 4 m x 4 m room, the target in its middle. Captors bunched in a
    // corner leave it most of the room; captors around it leave it almost
    // nothing; one captor moved from the corner to the target's side
    // takes some of its zone away.
    let m = maps(room(120, 200, 120, 200));
    let at = |captors: [(f64, f64); 3]| {
        let mut robots: Vec<Robot> = captors.iter().map(|&(x, y)| robot(x, y, 0.0)).collect();
        robots.push(robot(0.0, 0.0, 0.0));
        Potential::Asz.of(&env_with(cfg(3), m.clone(), robots))
    };
    let corner = at([(1.5, 1.5), (1.0, 1.5), (1.5, 1.0)]);
    let one_closer = at([(1.5, 1.5), (1.0, 1.5), (0.7, 0.0)]);
    let around = at([(0.45, 0.0), (-0.23, 0.39), (-0.23, -0.39)]);
    assert!(0.0 < corner && corner < 0.5, "corner {corner}");
    assert!(corner < one_closer, "{corner} then {one_closer}");
    assert!(
        one_closer < around && around > 0.95 && around <= 1.0,
        "around {around}"
    );
    // The same state gives the same potential, whichever maps the thread saw between.
    let other = maps(room(100, 220, 100, 220));
    let _ = Potential::Asz.of(&env_with(
        cfg(3),
        other,
        vec![
            robot(1.0, 1.0, 0.0),
            robot(-1.0, 1.0, 0.0),
            robot(1.0, -1.0, 0.0),
            robot(0.0, 0.0, 0.0),
        ],
    ));
    assert_eq!(at([(1.5, 1.5), (1.0, 1.5), (1.5, 1.0)]), corner);
}

/// `MAX_CAPTORS` is a count every map places: for each shipped map and
/// each Gibson map (when present), 40 seeds at K = MAX_CAPTORS all reset.
/// A larger K is refused by `EnvConfig::validate`, so no episode of an
/// accepted setting fails at its reset.
#[test]
fn the_most_captors_are_placed_on_every_map() {
    use t2e_core::map::catalog::load_prepared;
    let mut sets = vec!["shipped"];
    if t2e_core::map::catalog::gibson_dir().is_some() {
        sets.push("gibson");
    }
    let mut failures = Vec::new();
    for set in sets {
        for map in load_prepared(set).unwrap().iter() {
            let mut env = TrapEnv::new(cfg(MAX_CAPTORS), Arc::new(vec![map.clone()])).unwrap();
            for seed in 0..40 {
                if let Err(e) = env.reset_state(seed) {
                    failures.push(format!("{} seed {seed}: {e}", map.grid.name));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} resets failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(cfg(MAX_CAPTORS + 1).validate().is_err());
}
