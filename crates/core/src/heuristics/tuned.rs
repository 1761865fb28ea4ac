//! A family of hand-made targets around the paper's rule-based target
//! (`target_action`), for asking whether any hand-made target is harder to
//! catch than the rule: each member is the rule with five constants set
//! otherwise, searched by a derivative-free optimiser (`eval::tune`).
//! `TargetParams::RULE` is the rule itself, decision for decision
//! (tests/integration/heuristics.rs pins it).

use super::rule_based::force_to_action;
use crate::env::{Action, Controller, Side, TrapEnv};
use crate::map::prepared::ray_dirs;

/// The free constants of a hand-made target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetParams {
    /// How a captor's push falls off with its distance r: each captor
    /// pushes with weight (r_nearest / r)^falloff, so 0 (the rule) weighs
    /// all captors alike and a large value flees the nearest alone.
    pub falloff: f64,
    /// Weight of the wall term against the captors' (the rule's 0.6).
    pub wall_weight: f64,
    /// How far the wall rays look, as a share of the map's extent (the
    /// rule's 1): walls beyond it do not push.
    pub wall_range: f64,
    /// Seconds ahead along each captor's velocity the target flees from
    /// (0: where the captor is; negative: where it was).
    pub lead_s: f64,
    /// Weight of a pull along the longest of the 12 wall rays, towards
    /// open space (0: none).
    pub open_pull: f64,
}

impl TargetParams {
    /// The rule-based target of the spec.
    pub const RULE: TargetParams = TargetParams {
        falloff: 0.0,
        wall_weight: 0.6,
        wall_range: 1.0,
        lead_s: 0.0,
        open_pull: 0.0,
    };

    /// Each constant's name and the range it is accepted in.
    pub const RANGES: [(&'static str, f64, f64); 5] = [
        ("falloff", 0.0, 8.0),
        ("wall_weight", 0.0, 10.0),
        ("wall_range", 0.05, 1.0),
        ("lead_s", -3.0, 3.0),
        ("open_pull", 0.0, 10.0),
    ];

    pub fn to_array(self) -> [f64; 5] {
        [
            self.falloff,
            self.wall_weight,
            self.wall_range,
            self.lead_s,
            self.open_pull,
        ]
    }

    /// The constants in the order of `RANGES`, each checked against its
    /// range; the error names the first one outside it.
    pub fn from_array(v: [f64; 5]) -> Result<TargetParams, String> {
        for (x, (name, low, high)) in v.iter().zip(Self::RANGES) {
            if !(x.is_finite() && (low..=high).contains(x)) {
                return Err(format!("{name} = {x}: must be in [{low}, {high}]"));
            }
        }
        Ok(TargetParams {
            falloff: v[0],
            wall_weight: v[1],
            wall_range: v[2],
            lead_s: v[3],
            open_pull: v[4],
        })
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

/// The hand-made target's action. With `TargetParams::RULE` every sum is
/// the rule's to the bit: a weight of (r/r)^0 is 1.0, a lead of 0.0 moves
/// no captor, a range of 1.0 rescales by 1.0, and no pull is added.
pub fn tuned_target_action(env: &TrapEnv, p: &TargetParams) -> Action {
    let map = env.map();
    let d = map.long_ray_max();
    let me = env.target();
    let k = env.num_captors() as f64;
    let predicted: Vec<[f64; 2]> = env
        .captors()
        .iter()
        .map(|c| {
            [
                c.pos[0] + p.lead_s * c.vel[0],
                c.pos[1] + p.lead_s * c.vel[1],
            ]
        })
        .collect();
    let nearest = predicted
        .iter()
        .map(|c| (me.pos[0] - c[0]).hypot(me.pos[1] - c[1]))
        .fold(f64::INFINITY, f64::min);
    let mut f = [0.0, 0.0];
    for c in &predicted {
        let away = [me.pos[0] - c[0], me.pos[1] - c[1]];
        let u = unit(away);
        let w = if p.falloff == 0.0 {
            1.0
        } else {
            let r = away[0].hypot(away[1]);
            if r > 0.0 {
                (nearest / r).powf(p.falloff)
            } else {
                1.0
            }
        };
        f[0] += d * u[0] / k * w;
        f[1] += d * u[1] / k * w;
    }
    let range = d * p.wall_range;
    let distances = map.stepped_wall_distances(me.pos, range);
    let scale = d / range;
    let mut wall = [0.0, 0.0];
    for (u, dm) in ray_dirs().iter().zip(distances) {
        wall[0] -= range / dm * u[0];
        wall[1] -= range / dm * u[1];
    }
    f[0] += p.wall_weight * (wall[0] * scale);
    f[1] += p.wall_weight * (wall[1] * scale);
    if p.open_pull != 0.0 {
        let (longest, _) =
            distances
                .iter()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |best, (m, &dm)| {
                    if dm > best.1 {
                        (m, dm)
                    } else {
                        best
                    }
                });
        let u = ray_dirs()[longest];
        f[0] += p.open_pull * d * u[0];
        f[1] += p.open_pull * d * u[1];
    }
    force_to_action(me.theta, f)
}

/// `tuned:FALLOFF,WALL,RANGE,LEAD,OPEN`: a hand-made target; target only.
pub struct TunedTarget {
    pub params: TargetParams,
}

impl Controller for TunedTarget {
    fn name(&self) -> String {
        let v = self.params.to_array().map(|x| x.to_string());
        format!("tuned:{}", v.join(","))
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        debug_assert_eq!(side, Side::Target, "tuned:... plays the target only");
        out[0] = tuned_target_action(env, &self.params);
    }
}
