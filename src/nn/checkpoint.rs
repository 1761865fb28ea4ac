//! Checkpoints: a folder per snapshot with the weights in safetensors files
//! and `meta.json`, the sidecar that says what network and setting the
//! weights belong to. Folders are written under a temporary name and renamed
//! into place, so a killed run never leaves half a checkpoint.
//!
//! ```text
//! runs/NAME/checkpoints/captors-000001024000/
//!     meta.json            side, algorithm, net sizes, K, speed ratio, steps, hashes
//!     actor.safetensors    the policy (all a controller needs)
//!     critic.safetensors   the value function   (to resume training)
//!     optimizer.safetensors Adam moments        (to resume training)
//! ```

use super::{obs_tensors, pool_patch, Actor, NetConfig};
use crate::env::{Action, Controller, EnvConfig, Side, TrapEnv, PATCH_LEN};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tch::{nn, Device, Kind, Tensor};

/// Version of the checkpoint layout; bumped when it changes incompatibly.
pub const FORMAT: u32 = 1;

/// The sidecar of a checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointMeta {
    pub format: u32,
    pub side: Side,
    /// "mappo" or "ippo".
    pub algorithm: String,
    pub net: NetConfig,
    /// K, which fixes the observation vector's length (5 + 5 K).
    pub num_captors: usize,
    /// Observations the critic reads at once (K for MAPPO captors, else 1).
    pub critic_agents: usize,
    /// v_e / v_p the policy was trained at.
    pub speed_ratio: f64,
    /// Environment steps (all worlds together) of training behind these weights.
    pub env_steps: u64,
    pub iteration: u64,
    /// Hash of the training configuration (same hash, same settings).
    pub config_hash: String,
    /// Crate version and git commit of the code that wrote it.
    pub code_version: String,
    /// Learner state that is not a tensor: value normaliser and Adam step.
    #[serde(default)]
    pub learner_state: Option<serde_json::Value>,
}

impl CheckpointMeta {
    pub fn vector_len(&self) -> usize {
        5 + 5 * self.num_captors
    }

    /// Whether this policy can play `side` in environments configured as `cfg`.
    pub fn check_fits(&self, side: Side, cfg: &EnvConfig) -> Result<(), String> {
        if self.side != side {
            return Err(format!(
                "it holds a {} policy, asked to play the {}",
                self.side.name(),
                side.name()
            ));
        }
        if self.num_captors != cfg.num_captors {
            return Err(format!(
                "it was trained with K = {} captors and its observations have {} numbers; this setting has K = {}",
                self.num_captors,
                self.vector_len(),
                cfg.num_captors
            ));
        }
        Ok(())
    }
}

pub fn code_version() -> String {
    format!(
        "{}+{}",
        env!("CARGO_PKG_VERSION"),
        option_env!("T2E_GIT_COMMIT").unwrap_or("unknown")
    )
}

/// Name of the checkpoint folder of `side` after `env_steps` steps; zero
/// padded so names sort by steps.
pub fn checkpoint_name(side: Side, env_steps: u64) -> String {
    format!("{}-{env_steps:012}", side.name())
}

/// Writes a folder atomically: `fill` writes into a temporary sibling, which
/// then replaces `dir`.
pub fn write_dir_atomically(dir: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let parent = dir.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent)
        .with_context(|| format!("cannot create {}", parent.display()))?;
    let name = dir.file_name().context("checkpoint path has no name")?;
    let tmp = parent.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp)?;
    }
    std::fs::create_dir_all(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    fill(&tmp)?;
    if dir.exists() {
        std::fs::remove_dir_all(dir)
            .with_context(|| format!("cannot replace {}", dir.display()))?;
    }
    std::fs::rename(&tmp, dir).with_context(|| format!("cannot move {} into place", dir.display()))
}

/// Writes a file atomically (temporary sibling, then rename).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path)
        .with_context(|| format!("cannot move {} into place", path.display()))
}

/// Named tensors of a var store, sorted by name, on the CPU.
pub fn named_cpu_tensors(vs: &nn::VarStore) -> Vec<(String, Tensor)> {
    let mut v: Vec<(String, Tensor)> = vs
        .variables()
        .into_iter()
        .map(|(n, t)| (n, t.detach().to_device(Device::Cpu)))
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

pub fn save_tensors(path: &Path, tensors: &[(String, Tensor)]) -> Result<()> {
    Tensor::write_safetensors(tensors, path)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Copies weights read from `file` into `vs`; every variable of the network
/// must be there with its shape, or the error says which is not.
pub fn load_into(vs: &mut nn::VarStore, weights: &[(String, Tensor)], file: &Path) -> Result<()> {
    let mut vars: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
    vars.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, var) in &mut vars {
        let Some((_, w)) = weights.iter().find(|(n, _)| n == name) else {
            bail!(
                "{}: has no tensor '{name}' that the network needs: the weights do not match the architecture in meta.json",
                file.display()
            );
        };
        if w.size() != var.size() {
            bail!(
                "{}: tensor '{name}' has shape {:?}, the network described by meta.json needs {:?}",
                file.display(),
                w.size(),
                var.size()
            );
        }
        tch::no_grad(|| var.copy_(&w.to_kind(var.kind())));
    }
    Ok(())
}

pub fn read_tensors(path: &Path) -> Result<Vec<(String, Tensor)>> {
    if !path.is_file() {
        bail!("{}: missing", path.display());
    }
    let mut t = Tensor::read_safetensors(path)
        .with_context(|| format!("{}: not a readable safetensors file", path.display()))?;
    t.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(t)
}

pub fn read_meta(dir: &Path) -> Result<CheckpointMeta> {
    let path = dir.join("meta.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let meta: CheckpointMeta = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a checkpoint sidecar", path.display()))?;
    if meta.format != FORMAT {
        bail!(
            "{}: checkpoint format {} (this build reads format {FORMAT})",
            path.display(),
            meta.format
        );
    }
    meta.net
        .validate()
        .map_err(|e| anyhow::anyhow!("{}: net.{e}", path.display()))?;
    Ok(meta)
}

/// The newest checkpoint of `side` in a run folder or a `checkpoints` folder.
pub fn latest_checkpoint(run_or_checkpoints: &Path, side: Side) -> Option<PathBuf> {
    let dir = if run_or_checkpoints.join("checkpoints").is_dir() {
        run_or_checkpoints.join("checkpoints")
    } else {
        run_or_checkpoints.to_path_buf()
    };
    let prefix = format!("{}-", side.name());
    let mut found: Vec<PathBuf> = std::fs::read_dir(&dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix))
                && p.join("meta.json").is_file()
        })
        .collect();
    found.sort();
    found.pop()
}

/// Resolves what a user wrote after `ckpt:`: a checkpoint folder, a file in
/// one, or a run folder (its newest checkpoint of `side`).
pub fn resolve_checkpoint(path: &Path, side: Side) -> Result<PathBuf> {
    if path.is_file() {
        let dir = path.parent().unwrap_or(Path::new("."));
        if dir.join("meta.json").is_file() {
            return Ok(dir.to_path_buf());
        }
        bail!(
            "{}: not inside a checkpoint folder (no meta.json beside it)",
            path.display()
        );
    }
    if path.join("meta.json").is_file() {
        return Ok(path.to_path_buf());
    }
    if path.is_dir() {
        return latest_checkpoint(path, side).with_context(|| {
            format!(
                "{}: holds no {} checkpoint (folders named {}-<steps> with a meta.json)",
                path.display(),
                side.name(),
                side.name()
            )
        });
    }
    bail!("{}: no such checkpoint", path.display())
}

/// A policy read from disk once and kept as plain tensors on the CPU; every
/// controller built from it gets its own copy of the network (tch modules
/// are not shared between threads).
#[derive(Debug)]
pub struct PolicySnapshot {
    pub dir: PathBuf,
    pub meta: CheckpointMeta,
    weights: Vec<(String, Vec<i64>, Vec<f32>)>,
}

impl PolicySnapshot {
    pub fn load(path: &Path, side: Side) -> Result<PolicySnapshot> {
        let dir = resolve_checkpoint(path, side)?;
        let meta = read_meta(&dir)?;
        let file = dir.join("actor.safetensors");
        let tensors = read_tensors(&file)?;
        let weights = tensors
            .into_iter()
            .map(|(n, t)| {
                let t = t.to_kind(Kind::Float).contiguous();
                let mut data = vec![0f32; t.numel()];
                t.copy_data(&mut data, t.numel());
                (n, t.size(), data)
            })
            .collect();
        let snap = PolicySnapshot { dir, meta, weights };
        // Fail now, with the file's name, rather than inside an episode.
        snap.build_actor(Device::Cpu)?;
        Ok(snap)
    }

    /// A fresh network with these weights.
    pub fn build_actor(&self, device: Device) -> Result<(nn::VarStore, Actor)> {
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
/// the paper's evaluation.
pub struct CheckpointController {
    snapshot: Arc<PolicySnapshot>,
    _vs: nn::VarStore,
    actor: Actor,
    hidden: Option<Tensor>,
    vectors: Vec<f32>,
    patch: Vec<u8>,
    patches: Vec<u8>,
}

impl CheckpointController {
    pub fn new(snapshot: Arc<PolicySnapshot>) -> Result<CheckpointController> {
        let (vs, actor) = snapshot.build_actor(Device::Cpu)?;
        Ok(CheckpointController {
            snapshot,
            _vs: vs,
            actor,
            hidden: None,
            vectors: Vec::new(),
            patch: vec![0; PATCH_LEN],
            patches: Vec::new(),
        })
    }
}

impl Controller for CheckpointController {
    fn name(&self) -> String {
        format!("ckpt:{}", self.snapshot.dir.display())
    }

    fn reset(&mut self, _env: &TrapEnv, _seed: u64) {
        self.hidden = None;
    }

    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        let agents = side.agents(env.num_captors());
        let n = agents.len();
        let vl = env.cfg.vector_len();
        let net = &self.snapshot.meta.net;
        let pl = net.input_len();
        self.vectors.resize(n * vl, 0.0);
        self.patches.resize(n * pl, 0);
        for (row, i) in agents.enumerate() {
            env.write_observation(
                i,
                &mut self.vectors[row * vl..(row + 1) * vl],
                &mut self.patch,
            );
            pool_patch(
                &self.patch,
                net.patch_pool as usize,
                &mut self.patches[row * pl..(row + 1) * pl],
            );
        }
        let h = self.hidden.take().unwrap_or_else(|| {
            Tensor::zeros([n as i64, self.actor.hidden], (Kind::Float, Device::Cpu))
        });
        let (p, v) = obs_tensors(
            &self.patches,
            &self.vectors,
            n,
            1,
            net.input_side(),
            Device::Cpu,
        );
        let (logits, h) = tch::no_grad(|| self.actor.step(&p, &v, &h));
        self.hidden = Some(h);
        let best = logits.argmax(1, false);
        let mut idx = vec![0i64; n];
        best.copy_data(&mut idx, n);
        for (o, a) in out.iter_mut().zip(idx) {
            *o = Action::from_index(a as usize);
        }
    }
}
