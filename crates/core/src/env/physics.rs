//! One physics step of spec §2: rotate, forces from the positions at the start
//! of the step (drive, wall repulsion, soft robot contact), then integrate
//! with damping, speed clamp and obstacle blocking.

use super::action::Action;
use super::config::*;
use crate::map::prepared::{ray_dirs, NUM_RAYS};
use crate::map::PreparedMap;

/// The robots physics moves (their type is a leaf: robot.rs).
pub use super::robot::Robot;

pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let w = a.rem_euclid(two_pi);
    if w >= two_pi {
        0.0
    } else {
        w
    }
}

#[inline]
pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Numerically safe ln(1 + e^x).
#[inline]
fn softplus(x: f64) -> f64 {
    if x > 30.0 {
        x
    } else {
        x.exp().ln_1p()
    }
}

/// The artificial potential field of the walls: -sum_m (1 - ln(d_m / 1.5r)) u_m
/// over the rays shorter than 1.5 r (exact grid traversal, only near walls).
pub fn wall_repulsion(map: &PreparedMap, pos: [f64; 2]) -> [f64; 2] {
    // A cell whose centre is farther than 1.5 r + one cell diagonal from any
    // obstacle cannot have a ray shorter than 1.5 r.
    if map.clearance_at(pos) >= REPULSION_RANGE + crate::map::CELL_SIZE * std::f64::consts::SQRT_2 {
        return [0.0, 0.0];
    }
    let mut f = [0.0, 0.0];
    for dir in ray_dirs().iter().take(NUM_RAYS) {
        let d = map.ray_distance(pos, *dir, REPULSION_RAY_MAX);
        if d <= REPULSION_RANGE {
            let w = 1.0 - (d.max(1e-3) / REPULSION_RANGE).ln();
            f[0] -= w * dir[0];
            f[1] -= w * dir[1];
        }
    }
    f
}

/// Advances all robots by one step. `specs[i]` are robot i's limits.
/// Returns each robot's travelled distance.
pub fn step(
    map: &PreparedMap,
    robots: &mut [Robot],
    specs: &[RobotSpec],
    actions: &[Action],
    drive: DriveForce,
    travelled: &mut [f64],
) {
    let n = robots.len();
    debug_assert!(n <= 33);
    let mut force = [[0.0f64; 2]; 33];
    for i in 0..n {
        let (u_drive, u_turn) = actions[i].command();
        let r = &mut robots[i];
        if u_turn != 0.0 {
            r.theta = wrap_angle(r.theta + u_turn.signum() * TURN);
        }
        let spec = specs[i];
        let gain = match drive {
            DriveForce::Squared => spec.mass * spec.accel * spec.accel,
            DriveForce::Single => spec.mass * spec.accel,
        };
        let h = r.heading();
        force[i] = [gain * u_drive * h[0], gain * u_drive * h[1]];
        let fv = wall_repulsion(map, r.pos);
        r.collided = fv != [0.0, 0.0];
        let g = spec.mass * spec.accel * 3.0;
        force[i][0] += fv[0] * g;
        force[i][1] += fv[1] * g;
    }
    for i in 0..n {
        for j in i + 1..n {
            let dx = robots[i].pos[0] - robots[j].pos[0];
            let dy = robots[i].pos[1] - robots[j].pos[1];
            let d = dx.hypot(dy);
            if d == 0.0 || d > CONTACT_DIST + 40.0 * CONTACT_MARGIN {
                continue; // beyond 40 margins the soft contact is below 1e-19
            }
            let penetration = softplus(-(d - CONTACT_DIST) / CONTACT_MARGIN) * CONTACT_MARGIN;
            let f = CONTACT_FORCE * penetration / d;
            force[i][0] += f * dx;
            force[i][1] += f * dy;
            force[j][0] -= f * dx;
            force[j][1] -= f * dy;
        }
    }
    for i in 0..n {
        let spec = specs[i];
        let r = &mut robots[i];
        let mut v = [
            r.vel[0] * (1.0 - DAMPING) + force[i][0] / spec.mass * DT,
            r.vel[1] * (1.0 - DAMPING) + force[i][1] / spec.mass * DT,
        ];
        let speed = v[0].hypot(v[1]);
        if speed > spec.max_speed {
            v[0] *= spec.max_speed / speed;
            v[1] *= spec.max_speed / speed;
        }
        let next = [r.pos[0] + v[0] * DT, r.pos[1] + v[1] * DT];
        if map.disc_touches_obstacle(next, RADIUS) {
            r.vel = [0.0, 0.0];
            r.collided = true;
            travelled[i] = 0.0;
        } else {
            travelled[i] = dist(r.pos, next);
            r.pos = next;
            r.vel = v;
        }
    }
}

/// The fast capture rule: all 12 probe positions 1.5 r around the target are
/// blocked by an obstacle or by another robot.
pub fn target_is_trapped(map: &PreparedMap, target: [f64; 2], captors: &[Robot]) -> bool {
    ray_dirs()
        .iter()
        .all(|u| probe_is_blocked(map, target, captors, u))
}

/// How many of the 12 capture probes are blocked (12: captured).
pub fn blocked_probes(map: &PreparedMap, target: [f64; 2], captors: &[Robot]) -> usize {
    ray_dirs()
        .iter()
        .filter(|u| probe_is_blocked(map, target, captors, u))
        .count()
}

fn probe_is_blocked(map: &PreparedMap, target: [f64; 2], captors: &[Robot], u: &[f64; 2]) -> bool {
    let probe = [target[0] + PROBE_DIST * u[0], target[1] + PROBE_DIST * u[1]];
    captors.iter().any(|c| dist(c.pos, probe) < CONTACT_DIST)
        || map.disc_touches_obstacle(probe, RADIUS)
}
