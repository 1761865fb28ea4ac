//! `VectorInput::Egocentric`: the agent vector turned into each robot's own
//! frame before the network reads it.
//!
//! The spec's vector (§5) gives the other robots' offsets and velocities in
//! the world's axes and the robot's heading as one angle, while the obstacle
//! patch is already turned so that the heading points up. A policy whose
//! actions are "forward" and "turn" has to learn that rotation from the
//! heading itself before "the target is ahead and to the left" is one
//! number. Here the network's first layer does it instead: the observation
//! never changes, only what the first linear layer is given.

use tch::Tensor;

/// Metres by which positions and distances are divided (half the 16 m map).
const POSITION_SCALE: f64 = 8.0;

/// Below this distance (metres) a bearing is taken at this distance: robots
/// never overlap by that much, and it keeps the division finite.
const MIN_DISTANCE: f64 = 1e-3;

/// The fixed map from vectors of `agents` robots' observations, each in
/// `write_vector`'s layout (own velocity, position, heading; then the N
/// others' velocities, offsets, relative headings: 5 + 5N numbers), to
/// per robot:
/// - own velocity as (forward, left) speed, own position / 8 m, sine and
///   cosine of the heading: 6 numbers;
/// - per other robot: its offset as (forward, left) / 8 m, its distance /
///   8 m, its bearing as (cosine, sine), its velocity as (forward, left),
///   sine and cosine of its heading relative to ours: 9 numbers.
#[derive(Debug)]
pub(crate) struct EgocentricVector {
    /// Indices, one per robot: velocity x, y, position x, y, heading.
    own: [Tensor; 5],
    /// Indices, N per robot: velocity x, y, offset x, y, relative heading.
    others: [Tensor; 5],
    /// Indices of the sight's numbers (passed on as they are), robot by robot.
    sight: Option<Tensor>,
    agents: i64,
    per_other: i64,
    /// Width of the output: agents x (6 + 9N).
    pub width: i64,
}

impl EgocentricVector {
    /// `sight`: the numbers after each robot's 5 + 5N (wall rays, already
    /// in the robot's frame and in [0, 1]), appended as they are.
    pub(crate) fn new(vector_len: i64, agents: i64, sight: usize) -> EgocentricVector {
        let (per, n) = super::vector::vector_layout(vector_len, agents, sight as i64);
        let own = std::array::from_fn(|k| {
            Tensor::from_slice(&(0..agents).map(|a| a * per + k as i64).collect::<Vec<_>>())
        });
        // Offsets within a robot's block of the others' numbers: velocities
        // interleaved (x, y) from 5, offsets from 5 + 2N, headings from 5 + 4N.
        let other_index = |k: usize, j: i64| -> i64 {
            match k {
                0 => 5 + 2 * j,
                1 => 5 + 2 * j + 1,
                2 => 5 + 2 * n + 2 * j,
                3 => 5 + 2 * n + 2 * j + 1,
                _ => 5 + 4 * n + j,
            }
        };
        let others = std::array::from_fn(|k| {
            let idx: Vec<i64> = (0..agents)
                .flat_map(|a| (0..n).map(move |j| a * per + other_index(k, j)))
                .collect();
            Tensor::from_slice(&idx)
        });
        let sight_idx: Vec<i64> = (0..agents)
            .flat_map(|a| (0..sight as i64).map(move |k| a * per + 5 + 5 * n + k))
            .collect();
        EgocentricVector {
            own,
            others,
            sight: (sight > 0).then(|| Tensor::from_slice(&sight_idx)),
            agents,
            per_other: n,
            width: Self::width_of(vector_len as usize, agents as usize, sight) as i64,
        }
    }

    /// The output width for `vector_len` numbers of `agents` robots.
    pub(crate) fn width_of(vector_len: usize, agents: usize, sight: usize) -> usize {
        let per = vector_len / agents.max(1);
        let n = per.saturating_sub(5 + sight) / 5;
        agents * (6 + 9 * n + sight)
    }

    /// `vectors` [..., vector_len] -> [..., width].
    pub(crate) fn apply(&self, vectors: &Tensor) -> Tensor {
        let dev = vectors.device();
        let last = vectors.dim() as i64 - 1;
        let pick = |idx: &Tensor| vectors.index_select(last, &idx.to_device(dev));
        let [vx, vy, px, py, heading] = self.own.each_ref().map(pick);
        let (cos, sin) = (heading.cos(), heading.sin());
        // World axes to the robot's (forward, left): forward = (cos, sin),
        // left = (-sin, cos).
        let turn = |x: &Tensor, y: &Tensor, c: &Tensor, s: &Tensor| (x * c + y * s, y * c - x * s);
        let (own_forward, own_left) = turn(&vx, &vy, &cos, &sin);

        let mut batch = vectors.size();
        batch.pop();
        let grid: Vec<i64> = batch
            .iter()
            .copied()
            .chain([self.agents, self.per_other])
            .collect();
        let [ovx, ovy, ox, oy, oheading] = self.others.each_ref().map(|i| pick(i).view(&grid[..]));
        let (c, s) = (cos.unsqueeze(-1), sin.unsqueeze(-1));
        let (off_forward, off_left) = turn(&ox, &oy, &c, &s);
        let distance = (&off_forward * &off_forward + &off_left * &off_left).sqrt();
        let reach = distance.clamp_min(MIN_DISTANCE);
        let (vel_forward, vel_left) = turn(&ovx, &ovy, &c, &s);
        let flat = |t: Tensor| t.flatten(-2, -1);
        let mut parts = vec![
            own_forward,
            own_left,
            px / POSITION_SCALE,
            py / POSITION_SCALE,
            sin,
            cos,
            flat(&off_forward / POSITION_SCALE),
            flat(&off_left / POSITION_SCALE),
            flat(&distance / POSITION_SCALE),
            flat(&off_forward / &reach),
            flat(&off_left / &reach),
            flat(vel_forward),
            flat(vel_left),
            flat(oheading.sin()),
            flat(oheading.cos()),
        ];
        parts.extend(self.sight.as_ref().map(pick));
        Tensor::cat(&parts, last)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;
    use t2e_core::env::observe::write_vector;
    use t2e_core::env::physics::Robot;

    fn robot(pos: [f64; 2], vel: [f64; 2], theta: f64) -> Robot {
        Robot {
            pos,
            vel,
            theta,
            collided: false,
        }
    }

    /// Captor 0 faces +y (heading pi/2) at (2, 3); the target sits 1 m to
    /// its left in world x = 1 (the robot's left is world -x when it faces
    /// +y), captor 1 is 2 m ahead moving along +y. Every number worked by hand.
    #[test]
    fn features_are_in_the_robots_own_frame() {
        let robots = [
            robot([2.0, 3.0], [0.0, 0.5], FRAC_PI_2),
            robot([2.0, 5.0], [0.0, 1.0], FRAC_PI_2),
            robot([1.0, 3.0], [0.3, 0.3], 0.0),
        ];
        let mut v = vec![0f32; 15];
        write_vector(&robots, 0, 2, &mut v);
        let ego = EgocentricVector::new(15, 1, 0);
        assert_eq!(ego.width, 24);
        let out = Vec::<f32>::try_from(ego.apply(&Tensor::from_slice(&v).unsqueeze(0)).view([-1]))
            .unwrap();
        #[rustfmt::skip]
        let want: [f32; 24] = [
            0.5, 0.0,              // own velocity: straight ahead
            0.25, 0.375,           // own position / 8
            1.0, 0.0,              // sin, cos of the heading
            0.25, 0.0,             // offsets forward: captor 1 (2 m), target (0 m)
            0.0, 0.125,            // offsets left: captor 1 (0 m), target (1 m)
            0.25, 0.125,           // distances / 8
            1.0, 0.0,              // bearings' cosines
            0.0, 1.0,              // bearings' sines
            1.0, 0.0,              // velocities forward (the target's hidden: 0)
            0.0, 0.0,              // velocities left
            0.0, -1.0,             // sines of the relative headings (0, -pi/2)
            1.0, 0.0,              // their cosines
        ];
        for (k, (got, want)) in out.iter().zip(want).enumerate() {
            assert!((got - want).abs() < 1e-6, "feature {k}: {got} != {want}");
        }
    }

    /// The core's one-robot version (Python's observation options) gives
    /// the same numbers as the network's batched one.
    #[test]
    fn the_core_egocentric_vector_is_the_networks() {
        use t2e_core::env::features::{egocentric_vector, egocentric_width};
        let robots = [
            robot([2.0, 3.0], [0.4, -0.2], 0.3),
            robot([4.0, 1.0], [-0.1, 0.7], 2.0),
            robot([2.5, 5.0], [0.0, 0.0], -1.0),
            robot([2.5, 5.0], [0.6, 0.6], 1.1),
        ];
        let ego = EgocentricVector::new(20, 1, 0);
        for i in 0..4 {
            let mut v = vec![0f32; 20];
            write_vector(&robots, i, 3, &mut v);
            let batched =
                Vec::<f32>::try_from(ego.apply(&Tensor::from_slice(&v).unsqueeze(0)).view([-1]))
                    .unwrap();
            let mut one = vec![0f32; egocentric_width(3)];
            egocentric_vector(&v, &mut one);
            assert_eq!(one.len(), batched.len());
            for (k, (a, b)) in one.iter().zip(&batched).enumerate() {
                assert!((a - b).abs() < 1e-6, "robot {i}, feature {k}: {a} != {b}");
            }
        }
    }

    /// Turning the whole scene about the origin changes the robot's own
    /// position and heading but none of the other features.
    #[test]
    fn relative_features_do_not_depend_on_the_worlds_axes() {
        let scene = |turn: f64| {
            let (c, s) = (turn.cos(), turn.sin());
            let rot = |p: [f64; 2]| [c * p[0] - s * p[1], s * p[0] + c * p[1]];
            [
                robot(rot([2.0, 3.0]), rot([0.4, -0.2]), 0.3 + turn),
                robot(rot([4.0, 1.0]), rot([-0.1, 0.7]), 2.0 + turn),
                robot(rot([2.5, 5.0]), rot([0.0, 0.0]), -1.0 + turn),
                robot(rot([0.5, 2.0]), rot([0.6, 0.6]), 1.1 + turn),
            ]
        };
        let features = |turn: f64| {
            let robots = scene(turn);
            let mut v = vec![0f32; 40];
            for i in 0..2 {
                write_vector(&robots, i, 3, &mut v[20 * i..20 * (i + 1)]);
            }
            let ego = EgocentricVector::new(40, 2, 0);
            Vec::<f32>::try_from(ego.apply(&Tensor::from_slice(&v).view([1, 40])).view([-1]))
                .unwrap()
        };
        let (a, b) = (features(0.0), features(0.9));
        assert_eq!(a.len(), EgocentricVector::width_of(40, 2, 0));
        // Own velocity (2 per robot) and everything about the others are
        // frame-free; own position and heading (4 per robot) are not.
        let agents = 2;
        let frame_free = |k: usize| !(2 * agents..6 * agents).contains(&k);
        for k in (0..a.len()).filter(|&k| frame_free(k)) {
            assert!(
                (a[k] - b[k]).abs() < 1e-5,
                "feature {k}: {} != {}",
                a[k],
                b[k]
            );
        }
        assert!((0..a.len()).any(|k| !frame_free(k) && (a[k] - b[k]).abs() > 1e-2));
    }
}
