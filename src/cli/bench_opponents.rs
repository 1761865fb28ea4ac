//! `t2e-league bench --opponents`: the cost per robot row of a league
//! learner's opponent inference (one pass per opponent, or all opponents
//! stacked in one pass) beside the learner's own inference, at the league's
//! default sizes. One libtorch thread, as in a league process.

use anyhow::Result;
use std::time::Instant;
use t2e_core::env::EnvConfig;
use t2e_learners::nn::stacked::{PreparedActor, StackedActors};
use t2e_learners::nn::{Actor, Critic, NetConfig};
use tch::{nn, Device, Kind, Tensor};

/// Times `op` for about `secs` seconds; returns microseconds per call.
fn per_call_us(secs: f64, mut op: impl FnMut()) -> f64 {
    op();
    let (start, mut calls) = (Instant::now(), 0u64);
    while start.elapsed().as_secs_f64() < secs {
        op();
        calls += 1;
    }
    1e6 * start.elapsed().as_secs_f64() / calls as f64
}

fn random_actor(net: &NetConfig, vector_len: usize) -> (nn::VarStore, Actor) {
    let vs = nn::VarStore::new(Device::Cpu);
    let actor = Actor::new(&vs.root(), net, vector_len);
    (vs, actor)
}

/// Rows of `worlds` worlds (one robot each, as target opponents) split as
/// evenly as possible among `groups` opponents.
fn split(worlds: usize, groups: usize) -> Vec<usize> {
    (0..groups)
        .map(|g| worlds / groups + usize::from(g < worlds % groups))
        .collect()
}

/// Random inputs of the nets' shapes: `side` x `side` patches, then
/// vectors; one place for the shapes the rows share.
#[derive(Clone, Copy)]
struct Inputs {
    side: i64,
}

impl Inputs {
    fn patches(self, rows: i64, ch: i64) -> Tensor {
        Tensor::randint(
            2,
            [rows, ch, self.side, self.side],
            (Kind::Uint8, Device::Cpu),
        )
    }
    fn vectors(self, rows: i64, len: i64) -> Tensor {
        Tensor::randn([rows, len], (Kind::Float, Device::Cpu))
    }
}

pub fn run(secs: f64, worlds: usize) -> Result<()> {
    tch::set_num_threads(1);
    let net = NetConfig::default();
    let cfg = EnvConfig {
        num_captors: 3,
        ..EnvConfig::default()
    };
    let (vl, side) = (cfg.vector_len(), net.input_side() as i64);
    let h = net.hidden;
    let inputs = Inputs { side };

    println!("opponent inference per robot row, 1 libtorch thread, hidden {h}, {worlds} worlds\n");
    println!("| what | rows per step | passes | us per step | us per row |");
    println!("|---|---|---|---|---|");
    own_learner_row(secs, worlds, &net, vl, inputs);

    let actors: Vec<(nn::VarStore, Actor)> = (0..8).map(|_| random_actor(&net, vl)).collect();
    let prepared: Vec<PreparedActor> = actors
        .iter()
        .map(|(_, a)| PreparedActor::new(a, &net, vl))
        .collect();
    for groups in [1usize, 2, 4, 8] {
        let rows = split(worlds, groups);
        let total = rows.iter().sum::<usize>() as f64;
        let batches: Vec<(Tensor, Tensor, Tensor)> = rows
            .iter()
            .map(|&n| {
                let n = n as i64;
                (
                    inputs.patches(n, 1),
                    inputs.vectors(n, vl as i64),
                    Tensor::zeros([n, h], (Kind::Float, Device::Cpu)),
                )
            })
            .collect();
        let us = per_call_us(secs, || {
            tch::no_grad(|| {
                for (g, (p, v, hh)) in batches.iter().enumerate() {
                    let _ = actors[g].1.step(p, v, hh);
                }
            });
        });
        println!(
            "| {groups} opponents, one pass each | {total} | {groups} | {us:.0} | {:.2} |",
            us / total
        );
        let r = *rows.iter().max().unwrap() as i64;
        stacked_rows(secs, &prepared[..groups], (r, total), (vl, h), inputs)?;
    }
    Ok(())
}

/// The captor learner's own step, actor and MAPPO critic over its 3 robots
/// per world: the row the opponents' cost is read against.
fn own_learner_row(secs: f64, worlds: usize, net: &NetConfig, vl: usize, inputs: Inputs) {
    let h = net.hidden;
    let own_rows = (worlds * 3) as i64;
    let (_vsa, actor) = random_actor(net, vl);
    let vsc = nn::VarStore::new(Device::Cpu);
    let critic = Critic::new(&vsc.root(), net, vl, 3);
    let (pa, va, ha) = (
        inputs.patches(own_rows, 1),
        inputs.vectors(own_rows, vl as i64),
        Tensor::zeros([own_rows, h], (Kind::Float, Device::Cpu)),
    );
    let (pc, vc) = (
        inputs.patches(own_rows, 3),
        inputs.vectors(own_rows, 3 * vl as i64),
    );
    let us = per_call_us(secs, || {
        tch::no_grad(|| {
            let _ = actor.step(&pa, &va, &ha);
            let _ = critic.step(&pc, &vc, &ha);
        });
    });
    println!(
        "| captor learner's own actor + critic | {own_rows} | 2 | {us:.0} | {:.2} |",
        us / own_rows as f64
    );
}

/// The same opponents stacked in one pass (`r` rows each, `total` in all),
/// and the cost of restacking them; apart from `run` so each way of running
/// the opponents is one block.
fn stacked_rows(
    secs: f64,
    prepared: &[PreparedActor],
    (r, total): (i64, f64),
    (vl, h): (usize, i64),
    inputs: Inputs,
) -> Result<()> {
    let groups = prepared.len();
    let stacked =
        StackedActors::new(&prepared.iter().collect::<Vec<_>>()).map_err(anyhow::Error::msg)?;
    let g = groups as i64;
    let side = inputs.side;
    let (ps, vs, hs) = (
        inputs.patches(g * r, 1).view([g, r, side, side]),
        inputs.vectors(g * r, vl as i64).view([g, r, -1]),
        Tensor::zeros([g, r, h], (Kind::Float, Device::Cpu)),
    );
    let us = per_call_us(secs, || {
        tch::no_grad(|| {
            let _ = stacked.step(&ps, &vs, &hs);
        });
    });
    println!(
        "| {groups} opponents, stacked | {total} | 1 | {us:.0} | {:.2} |",
        us / total
    );
    let us = per_call_us(secs, || {
        let _ = StackedActors::new(&prepared.iter().collect::<Vec<_>>());
    });
    println!("| (restacking {groups} opponents' weights, when the set in play changes) | - | - | {us:.0} | - |");
    Ok(())
}
