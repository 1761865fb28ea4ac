//! DAgger for a target with a teacher (`ppo.dagger_rollouts`): the learner
//! plays, the teacher labels every state of its play, the labelled states
//! of the last rollouts are kept together (the aggregate), and the actor
//! is fitted to the teacher's moves on all of them by cross-entropy, many
//! passes per state over its stay, instead of a KL beside the RL loss seen
//! for `epochs` passes of one rollout. Ross, Gordon and Bagnell (2011),
//! with beta = 0: the states are always the learner's own. No reward
//! enters the update; the critic is not trained.
//!
//! What the policy does on each new rollout, before it is fitted on it,
//! is measured against the teacher (`TeacherAgreement`,
//! `teacher.csv`): states the actor has never been fitted on, so the
//! share of the teacher's departures it follows there is its held-out
//! recall, and its strays the held-out false departures.

use super::adam::{backward_clipped, Adam};
use super::rollout::{BadUpdate, Rollout, UpdateStats};
use super::side_config::ppo::PpoConfig;
use super::teacher::TeacherAgreement;
use crate::nn::prior::add_prior;
use crate::nn::Actor;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::collections::VecDeque;
use tch::{Device, Kind, Tensor};

/// The labelled states of one rollout, as tensors on the learner's device,
/// time major as the rollout holds them ([step][row]).
struct Labelled {
    /// [steps * rows, C, S, S] u8.
    patches: Tensor,
    /// [steps * rows, V].
    vectors: Tensor,
    /// [steps * rows]: 0 where a step starts an episode.
    masks: Tensor,
    /// [chunks * rows, hidden]: the actor's state at each chunk start, as
    /// the policy that played had it.
    actor_h: Tensor,
    /// [steps * rows]: the teacher's move.
    teacher: Tensor,
    /// [steps * rows]: the rule-based target's move (the prior's hint).
    rule: Tensor,
}

/// The last `capacity` rollouts' labelled states, oldest first. Every
/// rollout of a run has the same steps, rows and chunk length.
pub struct Aggregate {
    capacity: usize,
    rollouts: VecDeque<Labelled>,
    steps: usize,
    rows: usize,
    chunk_len: usize,
}

impl Aggregate {
    pub fn new(capacity: usize) -> Aggregate {
        Aggregate {
            capacity,
            rollouts: VecDeque::new(),
            steps: 0,
            rows: 0,
            chunk_len: 1,
        }
    }

    /// Rollouts held.
    pub fn len(&self) -> usize {
        self.rollouts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rollouts.is_empty()
    }

    /// Labelled decisions held.
    pub fn decisions(&self) -> usize {
        self.rollouts.len() * self.steps * self.rows
    }

    /// Forgets every rollout (a resumed run starts a new aggregate).
    pub fn clear(&mut self) {
        self.rollouts.clear();
    }

    /// Adds `ro`'s states and labels, dropping the oldest rollout when full.
    fn push(&mut self, ro: &Rollout, dev: Device) {
        let n = ro.steps * ro.rows;
        let (patches, vectors) =
            crate::nn::obs_tensors(&ro.patches, &ro.vectors, n, 1, ro.patch_side, dev);
        let t = |v: &[i64]| Tensor::from_slice(v).to_device(dev);
        let labelled = Labelled {
            patches,
            vectors,
            masks: Tensor::from_slice(&ro.masks).to_device(dev),
            actor_h: Tensor::from_slice(&ro.actor_h)
                .to_device(dev)
                .view([-1, ro.hidden as i64]),
            teacher: t(&ro.teacher_hints),
            rule: t(&ro.hints),
        };
        (self.steps, self.rows, self.chunk_len) = (ro.steps, ro.rows, ro.chunk_len);
        if self.rollouts.len() == self.capacity {
            self.rollouts.pop_front();
        }
        self.rollouts.push_back(labelled);
    }

    /// Sequences (whole chunks of one row) of one rollout.
    fn sequences_per_rollout(&self) -> usize {
        (self.steps / self.chunk_len) * self.rows
    }

    /// Sequences held, the newest rollout's last.
    fn sequences(&self) -> usize {
        self.rollouts.len() * self.sequences_per_rollout()
    }

    /// The rollout, chunk and row of the aggregate's sequence `s`.
    fn locate(&self, s: usize) -> (usize, usize, usize) {
        let per_rollout = self.sequences_per_rollout();
        let (r, within) = (s / per_rollout, s % per_rollout);
        (r, within / self.rows, within % self.rows)
    }
}

/// A minibatch of whole chunks, time major: [l * m] rows of each input and
/// label, [m, hidden] starting states.
struct Batch {
    patches: Tensor,
    vectors: Tensor,
    masks: Tensor,
    h0: Tensor,
    teacher: Tensor,
    rule: Tensor,
}

/// The sequences `picked` of `agg` (indices as `Aggregate::locate` reads
/// them) gathered into one batch.
fn gather(agg: &Aggregate, picked: &[usize]) -> Batch {
    let l = agg.chunk_len;
    let mut by_rollout: Vec<Vec<(usize, usize)>> = vec![Vec::new(); agg.len()];
    for &s in picked {
        let (r, c, row) = agg.locate(s);
        by_rollout[r].push((c, row));
    }
    let mut parts: Vec<[Tensor; 6]> = Vec::new();
    for (r, seqs) in by_rollout.iter().enumerate().filter(|(_, s)| !s.is_empty()) {
        let lr = &agg.rollouts[r];
        let dev = lr.masks.device();
        let mut idx = Vec::with_capacity(l * seqs.len());
        for step in 0..l {
            for &(c, row) in seqs {
                idx.push(((c * l + step) * agg.rows + row) as i64);
            }
        }
        let idx = Tensor::from_slice(&idx).to_device(dev);
        let starts: Vec<i64> = seqs
            .iter()
            .map(|&(c, row)| (c * agg.rows + row) as i64)
            .collect();
        let starts = Tensor::from_slice(&starts).to_device(dev);
        let m = seqs.len() as i64;
        // [l, m, ...]: stacked along the batch dimension with the other
        // rollouts' sequences, then flattened back to time major.
        let timed = |x: &Tensor| {
            let mut shape = vec![l as i64, m];
            shape.extend_from_slice(&x.size()[1..]);
            x.index_select(0, &idx).view(shape.as_slice())
        };
        parts.push([
            timed(&lr.patches),
            timed(&lr.vectors),
            timed(&lr.masks),
            lr.actor_h.index_select(0, &starts),
            timed(&lr.teacher),
            timed(&lr.rule),
        ]);
    }
    let cat = |i: usize, dim: i64| {
        let ts: Vec<&Tensor> = parts.iter().map(|p| &p[i]).collect();
        Tensor::cat(&ts, dim)
    };
    let flat = |t: Tensor| {
        let mut shape = vec![-1];
        shape.extend_from_slice(&t.size()[2..]);
        t.view(shape.as_slice())
    };
    Batch {
        patches: flat(cat(0, 1)),
        vectors: flat(cat(1, 1)),
        masks: flat(cat(2, 1)),
        h0: cat(3, 0),
        teacher: flat(cat(4, 1)),
        rule: flat(cat(5, 1)),
    }
}

/// A PPO target's actor and what DAgger fits it with: its Adam, the
/// aggregate, its settings and the rule-based target's logit prior.
pub struct Imitator<'a> {
    pub actor: &'a Actor,
    pub adam: &'a mut Adam,
    pub aggregate: &'a mut Aggregate,
    pub cfg: &'a PpoConfig,
    pub prior: f64,
    pub device: Device,
}

impl Imitator<'_> {
    /// One DAgger round: the policy's greedy moves on `ro` measured against
    /// the teacher's, `ro` added to the aggregate, then `epochs x
    /// minibatches` gradient steps of the weighted cross-entropy to the
    /// teacher's moves, each on as many sequences as one of PPO's
    /// minibatches would hold, drawn uniformly from the aggregate.
    pub fn imitate(self, ro: &Rollout, rng: &mut ChaCha8Rng) -> Result<UpdateStats, BadUpdate> {
        let Imitator {
            actor,
            adam,
            aggregate,
            cfg,
            prior,
            device: dev,
        } = self;
        let mut stats = UpdateStats::default();

        // 1. Into the aggregate, then the new rollout measured before any
        // fit on it: all its sequences at once.
        aggregate.push(ro, dev);
        let total = aggregate.sequences();
        let newest: Vec<usize> = (total - aggregate.sequences_per_rollout()..total).collect();
        let b = gather(aggregate, &newest);
        let greedy = tch::no_grad(|| {
            let m = b.masks.view([ro.chunk_len as i64, -1]);
            let logits = actor.unroll(&b.patches, &b.vectors, &b.h0, &m);
            add_prior(logits, &b.rule, prior).argmax(-1, false)
        });
        let moves = |t: &Tensor| Vec::<i64>::try_from(t).expect("action indices");
        stats.teacher = Some(TeacherAgreement::count(
            &moves(&greedy),
            &moves(&b.teacher),
            &moves(&b.rule),
        ));

        // 2. The fit.
        let per_batch = aggregate.sequences_per_rollout().div_ceil(cfg.minibatches);
        let mut fitted = TeacherAgreement::default();
        for _ in 0..cfg.epochs * cfg.minibatches {
            let picked: Vec<usize> = (0..per_batch).map(|_| rng.gen_range(0..total)).collect();
            let b = gather(aggregate, &picked);
            let m = b.masks.view([ro.chunk_len as i64, -1]);
            let logits = actor.unroll(&b.patches, &b.vectors, &b.h0, &m);
            let logp_all = add_prior(logits, &b.rule, prior).log_softmax(-1, Kind::Float);
            let log_teacher = logp_all
                .gather(1, &b.teacher.unsqueeze(1), false)
                .squeeze_dim(1);
            fitted.add(TeacherAgreement::count(
                &moves(&logp_all.argmax(-1, false)),
                &moves(&b.teacher),
                &moves(&b.rule),
            ));
            let departs = b.teacher.ne_tensor(&b.rule).to_kind(Kind::Float);
            let weight = departs * (cfg.teacher_departure_weight - 1.0) + 1.0;
            let loss = -(log_teacher * weight).mean(Kind::Float);
            let loss_value = loss.double_value(&[]);
            if !loss_value.is_finite() {
                return Err(BadUpdate(format!("imitation loss = {loss_value}")));
            }
            let norm = backward_clipped(&loss, &mut [(&mut *adam, cfg.max_grad_norm)])[0];
            if !norm.is_finite() {
                return Err(BadUpdate(format!("actor gradient norm = {norm}")));
            }
            adam.step();
            let entropy = tch::no_grad(|| {
                -(logp_all.exp() * &logp_all)
                    .sum_dim_intlist(-1, false, Kind::Float)
                    .mean(Kind::Float)
                    .double_value(&[])
            });
            stats.add_step(loss_value, 0.0, entropy, (norm, 0.0));
        }
        stats.average();
        stats.fitted = Some(fitted);
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::NetConfig;

    fn rollout(steps: usize, rows: usize, chunk_len: usize, mark: i64) -> Rollout {
        let net = NetConfig::default();
        let mut ro = Rollout::new(steps, rows, 3, &net, chunk_len);
        for (i, t) in ro.teacher_hints.iter_mut().enumerate() {
            *t = mark * 1000 + i as i64;
        }
        for (i, h) in ro.actor_h.iter_mut().enumerate() {
            *h = (mark * 1000) as f32 + (i / ro.hidden) as f32;
        }
        ro
    }

    #[test]
    fn the_aggregate_keeps_the_newest_rollouts_and_gathers_whole_chunks_in_time_order() {
        // 4 steps x 3 rows, chunks of 2: 6 sequences per rollout.
        let mut agg = Aggregate::new(2);
        for mark in 1..=3 {
            agg.push(&rollout(4, 3, 2, mark), Device::Cpu);
        }
        assert_eq!((agg.len(), agg.decisions(), agg.sequences()), (2, 24, 12));
        // Sequence 7: the second rollout held (mark 3), chunk 0, row 1;
        // sequence 5: the first held (mark 2), chunk 1, row 2.
        assert_eq!(agg.locate(7), (1, 0, 1));
        assert_eq!(agg.locate(5), (0, 1, 2));
        let b = gather(&agg, &[7, 5]);
        let v = |t: &Tensor| Vec::<i64>::try_from(t).unwrap();
        // Time major, [step][sequence]; the rollouts in the order held.
        // Mark 2, chunk 1 row 2: steps 2, 3 -> rows 2*3+2 = 8, 11.
        // Mark 3, chunk 0 row 1: steps 0, 1 -> rows 1, 4.
        assert_eq!(v(&b.teacher), [2008, 3001, 2011, 3004]);
        let h: Vec<f32> = Vec::try_from(b.h0.select(1, 0)).unwrap();
        // Chunk starts: (chunk 1, row 2) -> 1*3+2 = 5; (chunk 0, row 1) -> 1.
        assert_eq!(h, [2005.0, 3001.0]);
        assert_eq!(b.patches.size()[0], 4);
        assert_eq!(b.masks.size(), vec![4]);
        agg.clear();
        assert!(agg.is_empty());
    }
}
