//! MAPPO: PPO with a centralised critic. Teammates share one actor that sees
//! only its own robot's observation, and one critic that sees the whole
//! team's: for robot i of a world, its own patch and vector first, then its
//! teammates' in index order, so every robot gets its own value estimate.
//! Everything else is the PPO of `ppo.rs`.

use super::ppo::{CriticView, PpoKind};
use t2e_core::algorithm::Algorithm;
use tch::{Device, Kind, Tensor};

pub struct Mappo;

pub const KIND: PpoKind = PpoKind {
    algorithm: Algorithm::Mappo,
    view: || Box::new(Mappo),
};

impl CriticView for Mappo {
    fn critic_agents(&self, team: usize) -> usize {
        team
    }

    fn critic_inputs(&self, patches: &Tensor, vectors: &Tensor, team: usize) -> (Tensor, Tensor) {
        let rows = patches.size()[0];
        let index = team_index(rows as usize, team, patches.device());
        let p = patches.index_select(0, &index).view([
            rows,
            team as i64,
            patches.size()[2],
            patches.size()[3],
        ]);
        let v = vectors.index_select(0, &index).view([rows, -1]);
        (p, v)
    }
}

/// Row indices that put, for each row, the row itself and then its
/// teammates (the other rows of its world) in order.
pub fn team_index(rows: usize, team: usize, device: Device) -> Tensor {
    let mut idx = Vec::with_capacity(rows * team);
    for row in 0..rows {
        let world = row / team * team;
        idx.push(row as i64);
        for mate in world..world + team {
            if mate != row {
                idx.push(mate as i64);
            }
        }
    }
    Tensor::from_slice(&idx)
        .to_kind(Kind::Int64)
        .to_device(device)
}

/// Row indices of each row's teammates (the other rows of its world), in
/// order: [rows * (team - 1)].
pub fn mates_index(rows: usize, team: usize, device: Device) -> Tensor {
    let mut idx = Vec::with_capacity(rows * team.saturating_sub(1));
    for row in 0..rows {
        let world = row / team * team;
        idx.extend(
            (world..world + team)
                .filter(|&m| m != row)
                .map(|m| m as i64),
        );
    }
    Tensor::from_slice(&idx)
        .to_kind(Kind::Int64)
        .to_device(device)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_row_sees_itself_first_then_its_teammates() {
        let idx = team_index(6, 3, Device::Cpu);
        let mut v = [0i64; 18];
        idx.copy_data(&mut v, 18);
        assert_eq!(v, [0, 1, 2, 1, 0, 2, 2, 0, 1, 3, 4, 5, 4, 3, 5, 5, 3, 4]);
        let mates = mates_index(6, 3, Device::Cpu);
        let mut m = [0i64; 12];
        mates.copy_data(&mut m, 12);
        assert_eq!(m, [1, 2, 0, 2, 0, 1, 4, 5, 3, 5, 3, 4]);
        let patches = Tensor::arange(6, (Kind::Uint8, Device::Cpu))
            .view([6, 1, 1, 1])
            .expand([6, 1, 24, 24], false)
            .contiguous();
        let vectors = Tensor::arange(12, (Kind::Float, Device::Cpu)).view([6, 2]);
        let (p, v) = Mappo.critic_inputs(&patches, &vectors, 3);
        assert_eq!(p.size(), vec![6, 3, 24, 24]);
        assert_eq!(v.size(), vec![6, 6]);
        let mut row4 = [0f32; 6];
        v.get(4).copy_data(&mut row4, 6);
        assert_eq!(row4, [8.0, 9.0, 6.0, 7.0, 10.0, 11.0]);
        assert_eq!(p.get(4).get(1).get(0).get(0).int64_value(&[]), 3);
    }
}
