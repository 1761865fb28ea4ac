//! Rule-based robots (spec §7), the ASZ-greedy captor, and random and still
//! robots, each behind the one `Controller` trait. The names users give
//! controllers live one level up, in `crate::controllers`.

mod lookahead;

pub use lookahead::Lookahead;

use crate::asz::{AszFields, CoarseLattice, FastMarching, Lattice, Source};
use crate::env::physics::{self, dist};
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
    for (m, u) in ray_dirs().iter().enumerate() {
        let dm = map.stepped_wall_distance(pos, m, d);
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

/// The ASZ-greedy captor, as the spec states it (not the reference's broken
/// version): try each of forward, backward, turn right, turn left for this
/// captor alone, keep the one that leaves the smallest ASZ; when no action
/// changes |ASZ|, the one that most shortens the geodesic distance to the target.
/// Playing the target, the same rule mirrored (`target_action`): the
/// largest ASZ, else the rule-based target's action.
///
/// `coarsening` 1 takes |ASZ| from the per-robot fields on the map's own
/// 0.05 m cells (`asz::AszFields`), as the spec says. A larger factor
/// takes it from the one-pass labelled march on cells of that many map
/// cells per side (`asz::CoarseLattice`), each front started from the 2 x 2
/// cells around its robot: about factor^2 fewer cells per march, for a
/// controller that plays many episodes (held-out panels, league members).
/// The fields on coarse cells, each started in the cell holding its
/// robot, made `greedy:2` much weaker (10.0% of medium-map episodes
/// against the rule-based target, 52.0% on the march; 2026-11-28): a move
/// inside one coarse cell changes no field.
/// docs/guide/render-bench.md (the `greedy:K` decision timings) measures what it changes.
pub struct AszGreedy {
    coarsening: usize,
    coarse: Option<CoarseLattice>,
    /// The robots' arrival fields (on the map's own cells), kept across the
    /// four moves of each captor of one decision: only the moving robot's
    /// field is marched.
    fields: AszFields,
    /// The one-pass labelled march, for coarse cells (see `new`).
    marching: FastMarching,
    distance: FastMarching,
    /// The lattice and point `distance` holds the geodesic field of: the
    /// captors of one decision share the target's field, so the fallback
    /// marches it once per state, not once per captor.
    distance_from: Option<(u64, [u64; 2])>,
}

impl Default for AszGreedy {
    fn default() -> Self {
        AszGreedy::new(1)
    }
}

const GREEDY_ACTIONS: [Action; 4] = [
    Action::Forward,
    Action::Backward,
    Action::TurnRight,
    Action::TurnLeft,
];

impl AszGreedy {
    /// The largest coarsening accepted: cells of 0.4 m, two robot diameters.
    pub const MAX_COARSENING: usize = 8;

    pub fn new(coarsening: usize) -> AszGreedy {
        assert!(
            (1..=Self::MAX_COARSENING).contains(&coarsening),
            "ASZ-greedy coarsening {coarsening} outside 1..={}",
            Self::MAX_COARSENING
        );
        AszGreedy {
            coarsening,
            coarse: None,
            fields: AszFields::new(),
            marching: FastMarching::new(),
            distance: FastMarching::new(),
            distance_from: None,
        }
    }

    /// Where each of `GREEDY_ACTIONS` takes robot `i` alone, the others still.
    fn moves_of(env: &TrapEnv, i: usize) -> [[f64; 2]; 4] {
        let spec = env.spec(i);
        GREEDY_ACTIONS.map(|action| {
            let mut alone = [env.robots[i]];
            physics::step(
                env.map(),
                &mut alone,
                &[spec],
                &[action],
                env.cfg.drive_force,
                &mut [0.0],
            );
            alone[0].pos
        })
    }

    /// The target's mirror of the captors' rule (not in the spec, which has
    /// only the rule-based target): the action that leaves the target the
    /// largest ASZ; when no action changes |ASZ|, the rule-based target's.
    pub fn target_action(&mut self, env: &TrapEnv) -> Action {
        let moved = Self::moves_of(env, env.target_index());
        let (captors, target) = env.asz_sources();
        let sizes = if self.coarsening == 1 {
            moved.map(|pos| {
                self.fields
                    .with_moved_target(&**env.map(), target, &captors, pos)
            })
        } else {
            self.lattice(env);
            let lattice = self.coarse.as_ref().unwrap();
            moved.map(|pos| {
                self.marching
                    .asz_cells(lattice, Source { pos, ..target }, &captors)
            })
        };
        if sizes.iter().all(|&s| s == sizes[0]) {
            return target_action(env);
        }
        // The first of equals, as the captors' rule takes it.
        let best = (0..4)
            .rev()
            .max_by_key(|&a| sizes[a])
            .expect("four actions");
        GREEDY_ACTIONS[best]
    }

    /// The coarse lattice of the current map, built when the map changes.
    fn lattice(&mut self, env: &TrapEnv) -> &CoarseLattice {
        let map = env.map();
        if !self
            .coarse
            .as_ref()
            .is_some_and(|c| c.covers(map, self.coarsening))
        {
            self.coarse = Some(CoarseLattice::new(map, self.coarsening));
        }
        self.coarse.as_ref().unwrap()
    }

    pub fn captor_action(&mut self, env: &TrapEnv, i: usize) -> Action {
        let map = env.map();
        let moved = Self::moves_of(env, i);
        let (mut captors, target) = env.asz_sources();
        let best = if self.coarsening == 1 {
            let sizes = moved.map(|pos| {
                self.fields
                    .with_moved_captor(&**map, target, &captors, i, pos)
            });
            greedy_choice(
                sizes,
                (&mut self.distance, &mut self.distance_from),
                &**map,
                target,
                &moved,
            )
        } else {
            self.lattice(env);
            let lattice = self.coarse.as_ref().unwrap();
            let speed = env.spec(i).max_speed;
            let sizes = moved.map(|pos| {
                captors[i] = Source { pos, speed };
                self.marching.asz_cells(lattice, target, &captors)
            });
            greedy_choice(
                sizes,
                (&mut self.distance, &mut self.distance_from),
                lattice,
                target,
                &moved,
            )
        };
        GREEDY_ACTIONS[best]
    }
}

/// The index of the greedy action, given the |ASZ| each action of the
/// captor leaves and where it takes the captor.
fn greedy_choice<L: Lattice>(
    sizes: [usize; 4],
    (distance, distance_from): (&mut FastMarching, &mut Option<(u64, [u64; 2])>),
    lattice: &L,
    target: Source,
    moved: &[[f64; 2]; 4],
) -> usize {
    if sizes.iter().any(|&s| s != sizes[0]) {
        return (0..4).min_by_key(|&a| sizes[a]).unwrap();
    }
    let from = (lattice.lattice_id(), target.pos.map(f64::to_bits));
    if *distance_from != Some(from) {
        distance.distance_field(lattice, target.pos);
        *distance_from = Some(from);
    }
    let geodesic = |p: [f64; 2]| lattice.distance_at(distance, p);
    (0..4)
        .min_by(|&a, &b| geodesic(moved[a]).total_cmp(&geodesic(moved[b])))
        .unwrap()
}

impl Controller for AszGreedy {
    fn name(&self) -> String {
        match self.coarsening {
            1 => "greedy".into(),
            k => format!("greedy:{k}"),
        }
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        match side {
            Side::Captors => {
                for (i, a) in out.iter_mut().enumerate() {
                    *a = self.captor_action(env, i);
                }
            }
            Side::Target => out[0] = self.target_action(env),
        }
    }
}

/// Uniformly random actions, drawn from the episode's seed.
pub struct RandomActions {
    rng: ChaCha8Rng,
}

impl RandomActions {
    pub fn new() -> RandomActions {
        RandomActions {
            rng: ChaCha8Rng::seed_from_u64(0),
        }
    }
}

impl Default for RandomActions {
    fn default() -> Self {
        Self::new()
    }
}

impl Controller for RandomActions {
    fn name(&self) -> String {
        "random".into()
    }
    fn reset(&mut self, _env: &TrapEnv, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_EED0_F4A1_1D00);
    }
    fn act(&mut self, _env: &TrapEnv, _side: Side, out: &mut [Action]) {
        for a in out {
            *a = Action::from_index(self.rng.gen_range(0..Action::COUNT));
        }
    }
}

/// Robots that never move (tests, baselines).
pub struct Still;

impl Controller for Still {
    fn name(&self) -> String {
        "still".into()
    }
    fn act(&mut self, _env: &TrapEnv, _side: Side, out: &mut [Action]) {
        out.fill(Action::Stop);
    }
}
