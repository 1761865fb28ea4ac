//! A checkpoint as a player: the user's path resolved to a checkpoint
//! folder (a run folder gives its named or newest checkpoint), the actor's
//! weights read and verified once (`PolicySnapshot`), and the controller
//! that plays them (`CheckpointController`). It stands above both the
//! checkpoint format (checkpoint.rs) and the run folder (run_dir.rs), which
//! know nothing of each other's callers.

use super::checkpoint::{
    load_into, read_checked, read_meta_hashed, verify_manifest, verify_recorded, CheckpointError,
    CheckpointMeta,
};
use super::net::{obs_tensors, Actor};
use super::run_dir::{latest_checkpoint, RunDir, RunDirError};
use super::seeding::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use t2e_core::env::features::pool_patch;
use t2e_core::env::{Action, Controller, Side, TrapEnv, PATCH_LEN};
use tch::{nn, Device, Kind, Tensor};

/// Why a checkpoint cannot be loaded as a player: the folder itself, or the
/// run folder it was looked up in.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error(transparent)]
    RunDir(#[from] RunDirError),
}

/// Resolves what a user wrote after `ckpt:`: a checkpoint folder, a file in
/// one, or a run folder (its newest checkpoint of `side`).
pub fn resolve_checkpoint(path: &Path, side: Side) -> Result<PathBuf, PolicyError> {
    if path.is_file() {
        let dir = path.parent().unwrap_or(Path::new("."));
        if dir.join("meta.json").is_file() {
            return Ok(dir.to_path_buf());
        }
        return Err(CheckpointError::NotInCheckpointFolder(path.to_path_buf()).into());
    }
    if path.join("meta.json").is_file() {
        return Ok(path.to_path_buf());
    }
    if let Some(named) = RunDir::new(path).named_checkpoint(side)? {
        return Ok(named);
    }
    let looks_like_a_checkpoint = path
        .file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.starts_with(&format!("{}-", side.name())));
    if path.is_dir() && looks_like_a_checkpoint {
        return Err(CheckpointError::Incomplete(path.to_path_buf()).into());
    }
    if path.is_dir() {
        return latest_checkpoint(path, side).ok_or_else(|| {
            CheckpointError::NoCheckpointInside {
                path: path.to_path_buf(),
                side: side.name(),
            }
            .into()
        });
    }
    Err(CheckpointError::NoSuchCheckpoint(path.to_path_buf()).into())
}

/// A policy read from disk once and kept as plain tensors on the CPU; every
/// controller built from it gets its own copy of the network (tch modules
/// are not shared between threads).
#[derive(Debug)]
pub struct PolicySnapshot {
    pub dir: PathBuf,
    pub meta: CheckpointMeta,
    /// SHA-256 of the `meta.json` bytes `meta` was read from.
    pub meta_sha256: String,
    weights: Vec<(String, Vec<i64>, Vec<f32>)>,
}

impl PolicySnapshot {
    /// The checkpoint at `path` (resolved as `ckpt:` resolves it), its
    /// manifest verified.
    pub fn load(path: &Path, side: Side) -> Result<PolicySnapshot, PolicyError> {
        Self::load_checked(path, side, None)
    }

    /// A league player's checkpoint, whose meta.json SHA-256 the store
    /// recorded: that record stands for the manifest a folder written
    /// before manifests existed lacks, and meta.json must match it.
    pub fn load_recorded(
        path: &Path,
        side: Side,
        meta_sha256: &str,
    ) -> Result<PolicySnapshot, PolicyError> {
        Self::load_checked(path, side, Some(meta_sha256))
    }

    fn load_checked(
        path: &Path,
        side: Side,
        recorded: Option<&str>,
    ) -> Result<PolicySnapshot, PolicyError> {
        let dir = resolve_checkpoint(path, side)?;
        match recorded {
            None => verify_manifest(&dir)?,
            Some(sha) => verify_recorded(&dir, sha)?,
        }
        let (meta, meta_sha256) = read_meta_hashed(&dir)?;
        if let Some(want) = recorded.filter(|want| *want != meta_sha256) {
            return Err(CheckpointError::HashMismatch {
                path: dir.join("meta.json"),
                got: meta_sha256,
                want: want.to_string(),
            }
            .into());
        }
        let tensors = read_checked(&dir, &meta, "actor.safetensors")?;
        let weights = tensors
            .into_iter()
            .map(|(n, t)| {
                let t = t.to_kind(Kind::Float).contiguous();
                let mut data = vec![0f32; t.numel()];
                t.copy_data(&mut data, t.numel());
                (n, t.size(), data)
            })
            .collect();
        let snap = PolicySnapshot {
            dir,
            meta,
            meta_sha256,
            weights,
        };
        // Fail now, with the file's name, rather than inside an episode.
        snap.build_actor(Device::Cpu)?;
        Ok(snap)
    }

    /// A fresh network with these weights.
    pub fn build_actor(&self, device: Device) -> Result<(nn::VarStore, Actor), CheckpointError> {
        let mut vs = nn::VarStore::new(device);
        let actor = Actor::new(&vs.root(), &self.meta.net, self.meta.vector_len());
        let tensors: Vec<(String, Tensor)> = self
            .weights
            .iter()
            .map(|(n, shape, data)| (n.clone(), Tensor::from_slice(data).view(shape.as_slice())))
            .collect();
        load_into(&mut vs, &tensors, &self.dir.join("actor.safetensors"))?;
        vs.freeze();
        Ok((vs, actor))
    }
}

/// A checkpoint playing one side, greedily (the most likely action), as in
/// the paper's evaluation, or sampling its actions (`sampling`).
pub struct CheckpointController {
    snapshot: Arc<PolicySnapshot>,
    /// Some when actions are sampled: drawn afresh from each episode's seed,
    /// so the same seed plays the same episode.
    sampler: Option<ChaCha8Rng>,
    _vs: nn::VarStore,
    actor: Actor,
    hidden: Option<Tensor>,
    vectors: Vec<f32>,
    patch: Vec<u8>,
    patches: Vec<u8>,
    /// The planner whose move the prior leans on (`NetConfig::prior_teacher`),
    /// built by whoever builds the player; None: the rule-based target.
    prior_teacher: Option<Box<dyn Controller>>,
}

impl CheckpointController {
    /// The player of `snapshot`; refused when its prior leans on a planner
    /// (`leaning_on` builds that one), which it would otherwise play without.
    pub fn new(snapshot: Arc<PolicySnapshot>) -> Result<CheckpointController, CheckpointError> {
        if let Some(planner) = &snapshot.meta.net.prior_teacher {
            return Err(CheckpointError::NeedsPlanner {
                meta: snapshot.dir.join("meta.json"),
                planner: planner.clone(),
            });
        }
        Self::build(snapshot, None)
    }

    /// The player of `snapshot` whose prior follows `planner`, the
    /// controller of its `NetConfig::prior_teacher`; it is reset with each
    /// episode and asked once per real step, as it would be playing.
    pub fn leaning_on(
        snapshot: Arc<PolicySnapshot>,
        planner: Box<dyn Controller>,
    ) -> Result<CheckpointController, CheckpointError> {
        Self::build(snapshot, Some(planner))
    }

    fn build(
        snapshot: Arc<PolicySnapshot>,
        prior_teacher: Option<Box<dyn Controller>>,
    ) -> Result<CheckpointController, CheckpointError> {
        let (vs, actor) = snapshot.build_actor(Device::Cpu)?;
        Ok(CheckpointController {
            snapshot,
            sampler: None,
            _vs: vs,
            actor,
            hidden: None,
            vectors: Vec::new(),
            patch: vec![0; PATCH_LEN],
            patches: Vec::new(),
            prior_teacher,
        })
    }
}

impl CheckpointController {
    /// Samples each action from the policy instead of taking the most likely.
    pub fn sampling(mut self) -> CheckpointController {
        self.sampler = Some(ChaCha8Rng::seed_from_u64(0));
        self
    }
}

impl Controller for CheckpointController {
    fn name(&self) -> String {
        let how = if self.sampler.is_some() {
            "sample"
        } else {
            "ckpt"
        };
        format!("{how}:{}", self.snapshot.dir.display())
    }

    fn reset(&mut self, env: &TrapEnv, seed: u64) {
        self.hidden = None;
        if let Some(teacher) = &mut self.prior_teacher {
            teacher.reset(env, seed);
        }
        if let Some(rng) = &mut self.sampler {
            // Apart from the streams the environment draws from the seed.
            *rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5a4d_504c_4520_6163);
        }
    }

    /// The GRU state of its robots, [robots x hidden] row by row; zeros
    /// before its first step, which is what that step starts from.
    fn memory(&self) -> Option<Vec<f32>> {
        Some(match &self.hidden {
            Some(h) => {
                let h = h.to_kind(Kind::Float).contiguous();
                let mut data = vec![0f32; h.numel()];
                h.copy_data(&mut data, h.numel());
                data
            }
            None => Vec::new(),
        })
    }

    fn has_memory(&self) -> bool {
        true
    }

    /// Empty (no step taken yet) leaves it as a fresh episode's.
    fn set_memory(&mut self, memory: &[f32]) {
        self.hidden = (!memory.is_empty()).then(|| {
            Tensor::from_slice(memory)
                .view([memory.len() as i64 / self.actor.hidden, self.actor.hidden])
        });
    }

    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        let n = side.agents(env.num_captors()).len();
        let h = self.hidden.take().unwrap_or_else(|| {
            Tensor::zeros([n as i64, self.actor.hidden], (Kind::Float, Device::Cpu))
        });
        let (logits, h) = self.forward(&[env], side, &h);
        self.hidden = Some(h);
        self.choose(logits, &[env], side, out);
    }

    /// One forward for every game's robots: the rows of game after game,
    /// each game's GRU state from its memory (zeros when empty).
    fn act_batch(
        &mut self,
        envs: &[&TrapEnv],
        side: Side,
        memories: &mut [Vec<f32>],
        out: &mut [Action],
    ) {
        assert_eq!(envs.len(), memories.len(), "one memory per game");
        let Some(first) = envs.first() else {
            return;
        };
        let n = side.agents(first.num_captors()).len();
        let hidden = self.actor.hidden as usize;
        let mut rows = vec![0f32; envs.len() * n * hidden];
        for (memory, rows) in memories.iter().zip(rows.chunks_exact_mut(n * hidden)) {
            if !memory.is_empty() {
                rows.copy_from_slice(memory);
            }
        }
        let h = Tensor::from_slice(&rows).view([(envs.len() * n) as i64, hidden as i64]);
        let (logits, h) = self.forward(envs, side, &h);
        h.to_kind(Kind::Float)
            .contiguous()
            .copy_data(&mut rows, envs.len() * n * hidden);
        for (memory, rows) in memories.iter_mut().zip(rows.chunks_exact(n * hidden)) {
            memory.clear();
            memory.extend_from_slice(rows);
        }
        self.choose(logits, envs, side, out);
    }
}

impl CheckpointController {
    /// The network's logits and next GRU state for `side`'s robots in each
    /// of `envs`, rows game after game, from GRU state `h`.
    fn forward(&mut self, envs: &[&TrapEnv], side: Side, h: &Tensor) -> (Tensor, Tensor) {
        // Its own inputs, whatever the env's: a policy trained with sight
        // sees with it in any env.
        let net = &self.snapshot.meta.net;
        let vl = self.snapshot.meta.vector_len();
        let pl = net.input_len();
        let n = envs
            .first()
            .map_or(0, |env| side.agents(env.num_captors()).len());
        let rows = envs.len() * n;
        self.vectors.resize(rows * vl, 0.0);
        self.patches.resize(rows * pl, 0);
        let mut row = 0;
        for env in envs {
            for i in side.agents(env.num_captors()) {
                env.write_observation_with(
                    net.sight,
                    i,
                    &mut self.vectors[row * vl..(row + 1) * vl],
                    &mut self.patch,
                );
                pool_patch(
                    &self.patch,
                    net.patch_pool as usize,
                    &mut self.patches[row * pl..(row + 1) * pl],
                );
                row += 1;
            }
        }
        let (p, v) = obs_tensors(
            &self.patches,
            &self.vectors,
            rows,
            1,
            net.input_side(),
            Device::Cpu,
        );
        tch::no_grad(|| self.actor.step(&p, &v, h))
    }

    /// Each robot's action from `logits` (rows game after game): the most
    /// likely, or drawn when it samples.
    fn choose(&mut self, logits: Tensor, envs: &[&TrapEnv], side: Side, out: &mut [Action]) {
        let net = &self.snapshot.meta.net;
        let rows = out.len();
        // A checkpoint's prior is validated to be a target's (one robot).
        let logits = if net.heuristic_prior > 0.0 && side == Side::Target {
            let hints: Vec<i64> = match &mut self.prior_teacher {
                // A planner keeps per-episode state: one game, its own.
                Some(teacher) => {
                    assert_eq!(
                        envs.len(),
                        1,
                        "a target whose prior is a planner plays one game at a time"
                    );
                    let mut move_ = [Action::Stop];
                    teacher.act(envs[0], Side::Target, &mut move_);
                    vec![move_[0].index() as i64]
                }
                None => envs
                    .iter()
                    .map(|env| super::prior::target_hint(env))
                    .collect(),
            };
            super::prior::add_prior(logits, &Tensor::from_slice(&hints), net.heuristic_prior)
        } else {
            logits
        };
        if let Some(rng) = &mut self.sampler {
            let probs = logits.softmax(-1, Kind::Float);
            let mut p = vec![0f32; rows * Action::COUNT];
            probs.copy_data(&mut p, rows * Action::COUNT);
            for (o, row) in out.iter_mut().zip(p.chunks_exact(Action::COUNT)) {
                *o = Action::from_index(sample(row, rng));
            }
            return;
        }
        let best = logits.argmax(1, false);
        let mut idx = vec![0i64; rows];
        best.copy_data(&mut idx, rows);
        for (o, a) in out.iter_mut().zip(idx) {
            *o = Action::from_index(a as usize);
        }
    }
}
