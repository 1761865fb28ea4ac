//! The rule-based robots of spec §7: the target that flees every captor
//! and keeps off the walls, and the expert captors (with their constants
//! drawn per episode for `expert:SEED`).

use crate::env::physics::dist;
use crate::env::{Action, Controller, Side, TrapEnv};
use crate::map::prepared::ray_dirs;
use crate::map::PreparedMap;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Weight of the wall term against the robot term.
const WALL_WEIGHT: f64 = 0.6;

/// Wall force of the rule-based robots: -sum_m (D / d_m) u_m over the 12 world
/// rays, d_m the first 0.1 m sample along ray m inside an obstacle (searched
/// up to D). The sampling, not the exact distance, is what the reference's
/// robots use: exact distances push them harder off the walls and change
/// about 5% of their decisions (tests/integration/conformance.rs).
pub fn wall_force(map: &PreparedMap, pos: [f64; 2], d: f64) -> [f64; 2] {
    let mut f = [0.0, 0.0];
    let distances = map.stepped_wall_distances(pos, d);
    for (u, dm) in ray_dirs().iter().zip(distances) {
        f[0] -= d / dm * u[0];
        f[1] -= d / dm * u[1];
    }
    f
}

/// Turns a desired force into an action: project on the forward and right
/// axes; drive along the larger one, or turn towards it.
pub fn force_to_action(theta: f64, f: [f64; 2]) -> Action {
    let forward = f[0] * theta.cos() + f[1] * theta.sin();
    let right = f[0] * theta.sin() - f[1] * theta.cos();
    if forward.abs() > right.abs() {
        if forward > 0.0 {
            Action::Forward
        } else {
            Action::Backward
        }
    } else if right > 0.0 {
        Action::TurnRight
    } else {
        Action::TurnLeft
    }
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    if n == 0.0 {
        [0.0, 0.0]
    } else {
        [v[0] / n, v[1] / n]
    }
}

/// The paper's rule-based target (after Janosov et al.): flee every captor,
/// keep off the walls.
pub fn target_action(env: &TrapEnv) -> Action {
    let map = env.map();
    let d = map.long_ray_max();
    let me = env.target();
    let k = env.num_captors() as f64;
    let mut f = [0.0, 0.0];
    for c in env.captors() {
        let u = unit([me.pos[0] - c.pos[0], me.pos[1] - c.pos[1]]);
        f[0] += d * u[0] / k;
        f[1] += d * u[1] / k;
    }
    let w = wall_force(map, me.pos, d);
    f[0] += WALL_WEIGHT * w[0];
    f[1] += WALL_WEIGHT * w[1];
    force_to_action(me.theta, f)
}

/// The expert captor: head for the target, keep a little apart from the other
/// captors, keep off the walls.
pub fn expert_captor_action(env: &TrapEnv, i: usize) -> Action {
    expert_captor_action_with(env, i, &ExpertParams::SPEC)
}

/// The expert captor's free constants. The spec's are `SPEC`; a
/// randomised expert (`RandomisedExpert`) draws them per episode, a team
/// the league never trained against that still plays like the expert.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpertParams {
    /// Weight of the wall term (the spec's 0.6).
    pub wall_weight: f64,
    /// Factor on the spec's separation term between captors (1).
    pub separation: f64,
    /// Metres ahead of the target, along its heading, the captor aims at
    /// (0: at the target itself).
    pub lead_m: f64,
    /// Chance per step that a captor takes a uniformly random action.
    pub noise: f64,
}

impl ExpertParams {
    pub const SPEC: ExpertParams = ExpertParams {
        wall_weight: WALL_WEIGHT,
        separation: 1.0,
        lead_m: 0.0,
        noise: 0.0,
    };

    /// Draws one team's constants: each around the spec's, wide enough
    /// that the teams differ in how they chase, not so wide that they stop
    /// being experts.
    pub fn draw(rng: &mut impl Rng) -> ExpertParams {
        ExpertParams {
            wall_weight: rng.gen_range(0.3..1.2),
            separation: rng.gen_range(0.5..20.0),
            lead_m: rng.gen_range(0.0..1.0),
            noise: rng.gen_range(0.0..0.1),
        }
    }
}

/// The expert captor with its constants given. With `ExpertParams::SPEC`
/// every sum is the spec's to the bit (a lead of 0.0 and a factor of 1.0
/// change no float), which tests/integration/heuristics.rs pins.
pub fn expert_captor_action_with(env: &TrapEnv, i: usize, p: &ExpertParams) -> Action {
    let map = env.map();
    let d = map.long_ray_max();
    let me = &env.robots[i];
    let target = env.target();
    let t = [
        target.pos[0] + p.lead_m * target.theta.cos(),
        target.pos[1] + p.lead_m * target.theta.sin(),
    ];
    let u = unit([t[0] - me.pos[0], t[1] - me.pos[1]]);
    let mut f = [d * u[0], d * u[1]];
    for (j, other) in env.captors().iter().enumerate() {
        let r = dist(me.pos, other.pos);
        if j != i && r > 0.0 {
            let s = 0.01 * p.separation * crate::env::config::RADIUS / r;
            f[0] += s * (me.pos[0] - other.pos[0]);
            f[1] += s * (me.pos[1] - other.pos[1]);
        }
    }
    let w = wall_force(map, me.pos, d);
    f[0] += p.wall_weight * w[0];
    f[1] += p.wall_weight * w[1];
    force_to_action(me.theta, f)
}

/// `expert:SEED`: expert captors whose constants (`ExpertParams::draw`)
/// are drawn anew each episode from SEED and the episode's seed. A
/// validation team: the league never meets it, and no test panel holds it.
pub struct RandomisedExpert {
    pub seed: u64,
    params: ExpertParams,
    rng: ChaCha8Rng,
}

impl RandomisedExpert {
    pub fn new(seed: u64) -> RandomisedExpert {
        RandomisedExpert {
            seed,
            params: ExpertParams::SPEC,
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    pub fn params(&self) -> ExpertParams {
        self.params
    }
}

impl Controller for RandomisedExpert {
    fn name(&self) -> String {
        format!("expert:{}", self.seed)
    }
    fn reset(&mut self, _env: &TrapEnv, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed ^ self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        self.params = ExpertParams::draw(&mut self.rng);
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        debug_assert_eq!(side, Side::Captors, "expert:SEED plays captors only");
        for (i, a) in out.iter_mut().enumerate() {
            *a = if self.rng.gen_bool(self.params.noise) {
                Action::from_index(self.rng.gen_range(0..Action::COUNT))
            } else {
                expert_captor_action_with(env, i, &self.params)
            };
        }
    }
}

/// Rule-based robots for either side: the expert captors or the rule-based target.
pub struct Heuristic;

impl Controller for Heuristic {
    fn name(&self) -> String {
        "heuristic".into()
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        match side {
            Side::Captors => {
                for (i, a) in out.iter_mut().enumerate() {
                    *a = expert_captor_action(env, i);
                }
            }
            Side::Target => out[0] = target_action(env),
        }
    }
}
