//! A rollout: every world stepped `rollout_steps` times, each learning
//! side acting batched over all its robots, the states episodes were cut
//! off in kept for bootstrapping, and the states after the rollout valued.

use super::super::acting::{gather_side, gather_worlds, sample};
use super::super::shaping::shaping_term;
use super::hooks::RolloutHooks;
use super::metrics::RolloutTally;
use super::trainer::{LearnerSide, Trainer};
use crate::error::{Result, ResultExt};
use crate::nn::obs_tensors;
use crate::nn::prior::{add_prior, target_hint};
use std::time::Instant;
use t2e_core::env::{Action, VecEnv};
use tch::{Device, Kind, Tensor};

impl Trainer {
    /// Plays `rollout_steps` in every world: each learning side acts from
    /// its actor (and values the states with its critic) batched over all
    /// its robots, `hooks` act for the rest, and every step's observations,
    /// actions and rewards (plus any shaping) go into the sides' rollouts.
    // Long on purpose: the rollout hot loop; its per-step buffers and
    // tensors are borrowed across act, step and store, and splitting it
    // would pass a dozen of them through each helper for no reader's gain.
    pub(super) fn collect(&mut self, hooks: &mut dyn RolloutHooks) -> Result<RolloutTally> {
        let k = self.cfg.env.num_captors;
        let na = k + 1;
        let vl = self.venv.cfg.vector_len();
        let mut tally = RolloutTally::default();
        for t in 0..self.cfg.rollout_steps {
            let t0 = Instant::now();
            for ls in &mut self.learners {
                let ro = &mut ls.rollout;
                let rows = ls.rows;
                let base = t * rows;
                let pl = ls.learner.net().input_len();
                gather_side(
                    &self.venv,
                    ls.side,
                    ls.learner.net(),
                    &mut ro.vectors[base * vl..(base + rows) * vl],
                    &mut ro.patches[base * pl..(base + rows) * pl],
                );
                ro.masks[base..base + rows].copy_from_slice(&ls.next_mask);
                let l = ro.chunk_len;
                // A critic that values the rollout afterwards leaves its
                // state as it was, and stores its chunk starts itself.
                let critic_steps = !ls.learner.values_after_rollout();
                if t % l == 0 {
                    let c = t / l;
                    let hsz = rows * ro.hidden;
                    ls.actor_h
                        .to_device(Device::Cpu)
                        .copy_data(&mut ro.actor_h[c * hsz..(c + 1) * hsz], hsz);
                    if critic_steps {
                        ls.critic_h
                            .to_device(Device::Cpu)
                            .copy_data(&mut ro.critic_h[c * hsz..(c + 1) * hsz], hsz);
                    }
                }
                let (p, v) = obs_tensors(
                    &ro.patches[base * pl..(base + rows) * pl],
                    &ro.vectors[base * vl..(base + rows) * vl],
                    rows,
                    1,
                    ro.patch_side,
                    self.device,
                );
                let m = Tensor::from_slice(&ls.next_mask)
                    .to_device(self.device)
                    .unsqueeze(1);
                let lr = &ls.learner;
                let prior = lr.net().heuristic_prior;
                // Validated: only a target (one robot per world) leans on it.
                let hints = lr.wants_hints().then(|| {
                    let out = &mut ro.hints[base..base + rows];
                    if ls.prior_teachers.is_empty() {
                        for (e, hint) in out.iter_mut().enumerate() {
                            *hint = target_hint(self.venv.env(e));
                        }
                    } else {
                        crate::learn::teacher::label_worlds(
                            &mut ls.prior_teachers,
                            &self.venv,
                            out,
                        );
                    }
                    Tensor::from_slice(&ro.hints[base..base + rows])
                });
                if !ls.teachers.is_empty() {
                    crate::learn::teacher::label_worlds(
                        &mut ls.teachers,
                        &self.venv,
                        &mut ro.teacher_hints[base..base + rows],
                    );
                }
                let (probs, values, ha, hc) = tch::no_grad(|| {
                    let (logits, ha) = lr.actor().step(&p, &v, &(&ls.actor_h * &m));
                    let logits = match &hints {
                        Some(hints) => add_prior(logits, hints, prior),
                        None => logits,
                    };
                    let (values, hc) = if critic_steps {
                        let (values, hc) = lr.critic_step(&p, &v, &(&ls.critic_h * &m));
                        (values.map(|v| v.to_device(Device::Cpu)), Some(hc))
                    } else {
                        (None, None)
                    };
                    (
                        logits.softmax(-1, Kind::Float).to_device(Device::Cpu),
                        values,
                        ha,
                        hc,
                    )
                });
                ls.actor_h = ha;
                if let Some(hc) = hc {
                    ls.critic_h = hc;
                }
                let mut pr = vec![0f32; rows * Action::COUNT];
                probs.copy_data(&mut pr, rows * Action::COUNT);
                if let Some(values) = values {
                    values.copy_data(&mut ro.values[base..base + rows], rows);
                }
                let epsilon = lr.exploration() as f32;
                if epsilon > 0.0 {
                    let uniform = epsilon / Action::COUNT as f32;
                    pr.iter_mut()
                        .for_each(|p| *p = (1.0 - epsilon) * *p + uniform);
                }
                for row in 0..rows {
                    let p = &pr[row * Action::COUNT..(row + 1) * Action::COUNT];
                    let a = sample(p, &mut self.rng);
                    ro.actions[base + row] = a as i64;
                    ro.logp[base + row] = p[a].max(1e-12).ln();
                    let (e, j) = (row / ls.team, row % ls.team);
                    self.actions[e * na + ls.side.agents(k).start + j] = Action::from_index(a);
                }
            }
            let t1 = Instant::now();
            // Opponents acting count as environment time, like the scripted
            // controllers that act inside the vector env.
            hooks.before_step(&mut self.venv, &mut self.actions)?;
            let phi_before = self.venv.potentials.clone();
            self.venv.step(&self.actions).context("placing robots")?;
            hooks.after_step(&mut self.venv)?;
            let truncated_worlds: Vec<usize> = (0..self.cfg.num_envs)
                .filter(|&e| self.venv.truncated[e])
                .collect();
            for ls in &mut self.learners {
                let base = t * ls.rows;
                for row in 0..ls.rows {
                    let (e, j) = (row / ls.team, row % ls.team);
                    let done = self.venv.terminated[e] || self.venv.truncated[e];
                    let mut reward = self.venv.rewards[e * na + ls.side.agents(k).start + j];
                    if let Some((weight, gamma)) = ls.shaping {
                        reward += weight
                            * shaping_term(
                                phi_before[e],
                                self.venv.potentials[e],
                                self.venv.final_potentials[e],
                                self.venv.terminated[e],
                                self.venv.truncated[e],
                                gamma,
                            );
                    }
                    ls.rollout.rewards[base + row] = reward;
                    ls.rollout.dones[base + row] = done as u8 as f32;
                    ls.rollout.truncated[base + row] = self.venv.truncated[e] as u8 as f32;
                    ls.next_mask[row] = (!done) as u8 as f32;
                }
                if !truncated_worlds.is_empty() {
                    keep_truncated_states(&self.venv, ls, &truncated_worlds, base, self.device);
                }
            }
            for s in &self.venv.finished {
                tally.episodes += 1;
                tally.captures += s.captured as usize;
                tally.len_sum += s.steps as f64;
                tally.captor_return += s.returns[..k].iter().sum::<f64>() / k as f64;
                tally.target_return += s.returns[k];
            }
            tally.time_inference += (t1 - t0).as_secs_f64();
            tally.time_env += t1.elapsed().as_secs_f64();
        }
        Ok(tally)
    }

    /// The states after the rollout, and their values where a learner
    /// needs them: GAE and the TD targets bootstrap from them.
    pub(super) fn bootstrap(&mut self) {
        for ls in &mut self.learners {
            let ro = &mut ls.rollout;
            let rows = ls.rows;
            gather_side(
                &self.venv,
                ls.side,
                ls.learner.net(),
                &mut ro.last_vectors,
                &mut ro.last_patches,
            );
            ro.last_masks.copy_from_slice(&ls.next_mask);
            if ls.learner.values_after_rollout() {
                ls.critic_h = ls.learner.value_rollout(ro, &ls.critic_h);
                continue;
            }
            if !ls.learner.needs_values() {
                continue;
            }
            let (p, v) = obs_tensors(
                &ro.last_patches,
                &ro.last_vectors,
                rows,
                1,
                ro.patch_side,
                self.device,
            );
            let m = Tensor::from_slice(&ls.next_mask)
                .to_device(self.device)
                .unsqueeze(1);
            let values = tch::no_grad(|| {
                ls.learner
                    .critic_step(&p, &v, &(&ls.critic_h * &m))
                    .0
                    .expect("a learner that needs values gives them")
                    .to_device(Device::Cpu)
            });
            values.copy_data(&mut ro.last_values, rows);
        }
    }
}

/// The states that episodes cut off by the step limit reached (the vector
/// env's final observations) into the rollout at step offset `base`, and,
/// for a learner that needs values, the critic's values of them, continuing
/// each row's recurrent state, into `final_values`: truncation is not the
/// end of the game, so GAE and TD targets bootstrap there.
fn keep_truncated_states(
    venv: &VecEnv,
    ls: &mut LearnerSide,
    worlds: &[usize],
    base: usize,
    device: Device,
) {
    let net = ls.learner.net();
    let (vl, pl, team) = (venv.cfg.vector_len(), net.input_len(), ls.team);
    let n = worlds.len() * team;
    let mut vectors = vec![0f32; n * vl];
    let mut patches = vec![0u8; n * pl];
    gather_worlds(
        venv,
        &venv.final_vectors,
        &venv.final_patches,
        worlds,
        ls.side,
        net,
        &mut vectors,
        &mut patches,
    );
    let rows: Vec<i64> = worlds
        .iter()
        .flat_map(|&e| (0..team).map(move |j| (e * team + j) as i64))
        .collect();
    let ro = &mut ls.rollout;
    for (i, &row) in rows.iter().enumerate() {
        let at = base + row as usize;
        ro.final_patches[at * pl..(at + 1) * pl].copy_from_slice(&patches[i * pl..(i + 1) * pl]);
        ro.final_vectors[at * vl..(at + 1) * vl].copy_from_slice(&vectors[i * vl..(i + 1) * vl]);
    }
    if !ls.learner.needs_values() || ls.learner.values_after_rollout() {
        return;
    }
    let (p, v) = obs_tensors(&patches, &vectors, n, 1, ls.rollout.patch_side, device);
    let values = tch::no_grad(|| {
        let h = ls
            .critic_h
            .index_select(0, &Tensor::from_slice(&rows).to_device(device));
        ls.learner
            .critic_step(&p, &v, &h)
            .0
            .expect("a learner that needs values gives them")
            .to_device(Device::Cpu)
    });
    let mut out = vec![0f32; n];
    values.copy_data(&mut out, n);
    for (row, value) in rows.iter().zip(out) {
        ls.rollout.final_values[base + *row as usize] = value;
    }
}
