//! A robot's state: position, velocity, heading and whether it hit a wall
//! this step. A leaf, so that what a robot sees (sight.rs) needs no physics.

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Robot {
    pub pos: [f64; 2],
    pub vel: [f64; 2],
    /// Heading (rad) from +x, counter-clockwise, in [0, 2 pi).
    pub theta: f64,
    /// Hit a wall this step (repulsion fired or the move was blocked).
    pub collided: bool,
}

impl Robot {
    pub fn heading(&self) -> [f64; 2] {
        [self.theta.cos(), self.theta.sin()]
    }
}
