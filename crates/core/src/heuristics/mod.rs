//! Rule-based robots (spec §7), the ASZ-greedy captor, and random and still
//! robots, each behind the one `Controller` trait. The names users give
//! controllers live one floor up, in `t2e_learners::controllers`.

mod lookahead;
mod robust;
mod rule_based;
mod tuned;

pub use lookahead::Lookahead;
pub use robust::RobustLookahead;
pub use rule_based::{
    expert_captor_action, expert_captor_action_with, force_to_action, target_action, wall_force,
    ExpertParams, Heuristic, RandomisedExpert,
};
pub use tuned::{tuned_target_action, TargetParams, TunedTarget};

use crate::asz::{AszFields, CoarseLattice, FastMarching, Lattice, Source};
use crate::env::physics;
use crate::env::{Action, Controller, Side, TrapEnv};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

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
