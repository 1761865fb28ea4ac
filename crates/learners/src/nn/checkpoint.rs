//! Checkpoints: a folder per snapshot with the weights in safetensors files
//! and `meta.json`, the sidecar that says what network and setting the
//! weights belong to, with the SHA-256 of every weight file.
//!
//! ```text
//! runs/NAME/checkpoints/captors-000001024000/
//!     meta.json            side, algorithm, net sizes, K, speed ratio, steps, file hashes
//!     actor.safetensors    the policy (all a controller needs)
//!     critic.safetensors   the value function   (to resume training)
//!     optimizer.safetensors Adam moments        (to resume training)
//!     SHA256SUMS           the SHA-256 of every other file, meta.json included
//! ```
//!
//! Invariants:
//! - A checkpoint folder is written whole or not at all (`t2e_core::fs`): a
//!   complete checkpoint is never removed before its replacement is in
//!   place, and an identical one is not rewritten.
//! - Loading verifies each weight file against its hash in `meta.json` and
//!   refuses non-finite weights: a flipped byte or a NaN never plays.
//! - Every folder carries `SHA256SUMS`, which covers `meta.json` too: an
//!   edited side, sight or protocol is refused, not played. A folder
//!   without one is refused, unless its `meta.json` is the one a league's
//!   store recorded (`verify_recorded`).

use super::config::NetConfig;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use t2e_core::algorithm::Algorithm;
use t2e_core::env::sight::WALL_RAY_RANGE_M;
use t2e_core::env::{EnvConfig, Side, Sight};
use t2e_core::fs::{write_dir_atomically, write_new_dir_atomically, FsError, Written};
use t2e_core::util::sha256_file;
use tch::{nn, Device, Tensor};

/// Version of the checkpoint layout; bumped when it changes incompatibly.
/// 2: `meta.json` carries the SHA-256 of every weight file.
pub const FORMAT: u32 = 2;

/// The sidecar of a checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointMeta {
    pub format: u32,
    pub side: Side,
    /// "mappo" or "ippo".
    pub algorithm: Algorithm,
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
    /// The protocol it was trained under (`t2e_core::protocol`). Checkpoints
    /// written before the field existed were trained held-out: the Gibson
    /// maps were refused for training from the start.
    #[serde(default)]
    pub protocol: t2e_core::protocol::Protocol,
    /// Crate version and git commit of the code that wrote it.
    pub code_version: String,
    /// Learner state that is not a tensor: value normaliser and Adam step.
    #[serde(default)]
    pub learner_state: Option<serde_json::Value>,
    /// SHA-256 (hex) of every file of the folder but this one, by file name.
    pub files: BTreeMap<String, String>,
    /// What the writer of a new folder says it is (`SideHandle::save_new`;
    /// a league's snapshot: its pool, its player and parent), kept as
    /// given and never read by this crate. Stored as `league` in meta.json,
    /// the name it has always had there.
    #[serde(rename = "league", default, skip_serializing_if = "Option::is_none")]
    pub pool_label: Option<serde_json::Value>,
    /// How far the wall rays of `net.sight` read, in metres
    /// (`WALL_RAY_RANGE_M`); written by the checkpoint writer whenever the
    /// network reads rays. Absent on a network with rays, it was trained
    /// when a ray was divided by each map's extent, and is refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_ray_range_m: Option<f64>,
}

impl CheckpointMeta {
    /// The vector its network reads: 5 + 5 K, then its sight's numbers.
    pub fn vector_len(&self) -> usize {
        5 + 5 * self.num_captors + self.net.sight.len()
    }

    /// Whether this policy can play `side` in environments configured as `cfg`.
    pub fn check_fits(&self, side: Side, cfg: &EnvConfig) -> Result<(), DoesNotFit> {
        if self.side != side {
            return Err(DoesNotFit::Side {
                holds: self.side,
                asked: side,
            });
        }
        if self.num_captors != cfg.num_captors {
            return Err(DoesNotFit::Captors {
                trained: self.num_captors,
                vector_len: self.vector_len(),
                asked: cfg.num_captors,
            });
        }
        Ok(())
    }

    /// `check_fits`, for a network fed the env's own observations (a
    /// league opponent) rather than its own: its sight must be the env's.
    pub fn check_reads(&self, side: Side, cfg: &EnvConfig) -> Result<(), DoesNotFit> {
        self.check_fits(side, cfg)?;
        if self.net.sight != cfg.sight {
            return Err(DoesNotFit::Sight {
                trained: self.net.sight,
                env: cfg.sight,
            });
        }
        Ok(())
    }
}

/// Why a checkpoint folder cannot be read or written; each message names
/// the file (a cause follows it in the message, as in `t2e_core::fs`).
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{}: missing", .0.display())]
    Missing(PathBuf),
    #[error("{}: not a regular file (a FIFO, device or folder in a checkpoint file's place)", .0.display())]
    NotARegularFile(PathBuf),
    #[error("{}: missing: {} is not a checkpoint folder (a checkpoint holds meta.json beside its .safetensors files)", .meta.display(), .dir.display())]
    NoMeta { meta: PathBuf, dir: PathBuf },
    #[error("{}: cannot read: {cause}", .path.display())]
    Unreadable {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: not a readable safetensors file: {cause}", .path.display())]
    NotSafetensors { path: PathBuf, cause: tch::TchError },
    #[error("cannot write {}: {cause}", .path.display())]
    CannotWrite { path: PathBuf, cause: tch::TchError },
    #[error("{}: has no tensor '{name}' that the network needs: the weights do not match the architecture in meta.json", .file.display())]
    MissingTensor { file: PathBuf, name: String },
    #[error("{}: tensor '{name}' has shape {got:?}, the network described by meta.json needs {want:?}", .file.display())]
    WrongShape {
        file: PathBuf,
        name: String,
        got: Vec<i64>,
        want: Vec<i64>,
    },
    #[error("{}: meta.json records no hash for {file}", .dir.display())]
    NoHash { dir: PathBuf, file: String },
    #[error("{}: sha256 {got} differs from the {want} recorded in meta.json: the file is corrupt or was changed after it was written", .path.display())]
    HashMismatch {
        path: PathBuf,
        got: String,
        want: String,
    },
    #[error("{}: tensor '{name}' holds NaN or infinite values", .file.display())]
    NonFinite { file: PathBuf, name: String },
    #[error("refusing to write a checkpoint with non-finite weights: {0}")]
    WouldWriteNonFinite(Box<CheckpointError>),
    #[error("{}: checkpoint format {format}; this build reads format {FORMAT} (format 2 added the weight files' hashes)", .path.display())]
    Format { path: PathBuf, format: u32 },
    #[error("{}: algorithm \"{algorithm}\" is not one this build can load ({known})", .path.display())]
    UnknownAlgorithm {
        path: PathBuf,
        algorithm: String,
        known: String,
    },
    #[error("{}: not a checkpoint sidecar: {cause}", .path.display())]
    NotASidecar {
        path: PathBuf,
        cause: serde_json::Error,
    },
    /// A sidecar value out of its range (`field = value: rule`).
    #[error("{}: {what}", .path.display())]
    Invalid { path: PathBuf, what: String },
    #[error("{}: not inside a checkpoint folder (no meta.json beside it)", .0.display())]
    NotInCheckpointFolder(PathBuf),
    #[error("{}: has no meta.json: not a complete checkpoint folder", .0.display())]
    Incomplete(PathBuf),
    #[error("{}: no meta.json, and no {side} checkpoint inside (folders named {side}-<steps> with a meta.json)", .path.display())]
    NoCheckpointInside { path: PathBuf, side: &'static str },
    #[error("{}: no such checkpoint", .0.display())]
    NoSuchCheckpoint(PathBuf),
    /// An exported folder's `SHA256SUMS` disagrees with a file it lists.
    #[error("{}: {what} ({})", .path.display(), .manifest.display())]
    Manifest {
        path: PathBuf,
        manifest: PathBuf,
        what: String,
    },
    /// A folder without `SHA256SUMS`: nothing covers its `meta.json`.
    #[error("{}: missing: every checkpoint folder carries a manifest of its files, meta.json included (written by t2e-league 0.2.0 and later); without it an edited meta.json (its side, sight or protocol) cannot be told. A folder you trust that was written before: `t2e-league seal {}`", .manifest.display(), .dir.display())]
    NoManifest { manifest: PathBuf, dir: PathBuf },
    /// `player.json` (an export's) and `meta.json` name different sides.
    #[error("{}: side \"{player}\", but {} says \"{meta}\": the folder was edited", .player_json.display(), .meta_json.display())]
    SideDisagrees {
        player_json: PathBuf,
        meta_json: PathBuf,
        player: String,
        meta: String,
    },
    /// A network whose prior leans on a planner, loaded without it.
    #[error("{}: net.prior_teacher = \"{planner}\": the network leans on that planner's move and plays only beside it; load it by name (ckpt:PATH), which builds the planner", .meta.display())]
    NeedsPlanner { meta: PathBuf, planner: String },
    #[error(transparent)]
    Fs(#[from] FsError),
}

/// Why a checkpoint cannot play where it was asked to.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DoesNotFit {
    #[error("it holds a {} policy, asked to play the {}", holds.name(), asked.name())]
    Side { holds: Side, asked: Side },
    #[error("it was trained with sight {} (net.sight in meta.json) and would be fed observations with sight {}: a network reads only the inputs it was trained on", trained.label(), env.label())]
    Sight { trained: Sight, env: Sight },
    #[error("it was trained with K = {trained} captors and its observations have {vector_len} numbers; this setting has K = {asked}")]
    Captors {
        trained: usize,
        vector_len: usize,
        asked: usize,
    },
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

pub fn save_tensors(path: &Path, tensors: &[(String, Tensor)]) -> Result<(), CheckpointError> {
    Tensor::write_safetensors(tensors, path).map_err(|cause| CheckpointError::CannotWrite {
        path: path.to_path_buf(),
        cause,
    })
}

/// Copies weights read from `file` into `vs`; every variable of the network
/// must be there with its shape, or the error says which is not.
pub fn load_into(
    vs: &mut nn::VarStore,
    weights: &[(String, Tensor)],
    file: &Path,
) -> Result<(), CheckpointError> {
    let mut vars: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
    vars.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, var) in &mut vars {
        let Some((_, w)) = weights.iter().find(|(n, _)| n == name) else {
            return Err(CheckpointError::MissingTensor {
                file: file.to_path_buf(),
                name: name.clone(),
            });
        };
        if w.size() != var.size() {
            return Err(CheckpointError::WrongShape {
                file: file.to_path_buf(),
                name: name.clone(),
                got: w.size(),
                want: var.size(),
            });
        }
        tch::no_grad(|| var.copy_(&w.to_kind(var.kind())));
    }
    Ok(())
}

pub fn read_tensors(path: &Path) -> Result<Vec<(String, Tensor)>, CheckpointError> {
    if !path.is_file() {
        return Err(CheckpointError::Missing(path.to_path_buf()));
    }
    let mut t =
        Tensor::read_safetensors(path).map_err(|cause| CheckpointError::NotSafetensors {
            path: path.to_path_buf(),
            cause,
        })?;
    t.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(t)
}

/// Checks a checkpoint file against the SHA-256 its `meta.json` recorded.
pub fn verify_file(dir: &Path, meta: &CheckpointMeta, file: &str) -> Result<(), CheckpointError> {
    let path = dir.join(file);
    let Some(want) = meta.files.get(file) else {
        return Err(CheckpointError::NoHash {
            dir: dir.to_path_buf(),
            file: file.to_string(),
        });
    };
    match std::fs::metadata(&path) {
        Err(_) => return Err(CheckpointError::Missing(path)),
        Ok(m) if !m.is_file() => return Err(CheckpointError::NotARegularFile(path)),
        Ok(_) => {}
    }
    let got = match sha256_file(&path) {
        Ok(got) => got,
        Err(cause) => return Err(CheckpointError::Unreadable { path, cause }),
    };
    if &got != want {
        return Err(CheckpointError::HashMismatch {
            path,
            got,
            want: want.clone(),
        });
    }
    Ok(())
}

/// Errors unless every value of every tensor is finite.
pub fn check_finite(tensors: &[(String, Tensor)], file: &Path) -> Result<(), CheckpointError> {
    for (name, t) in tensors {
        let all_finite = tch::no_grad(|| t.isfinite().all().int64_value(&[]) == 1);
        if !all_finite {
            return Err(CheckpointError::NonFinite {
                file: file.to_path_buf(),
                name: name.clone(),
            });
        }
    }
    Ok(())
}

/// Reads one weight file of a checkpoint: hash verified, values finite.
pub fn read_checked(
    dir: &Path,
    meta: &CheckpointMeta,
    file: &str,
) -> Result<Vec<(String, Tensor)>, CheckpointError> {
    verify_file(dir, meta, file)?;
    let path = dir.join(file);
    let tensors = read_tensors(&path)?;
    check_finite(&tensors, &path)?;
    Ok(tensors)
}

/// Writes a checkpoint folder: the weight files, their hashes into `meta`,
/// then `meta.json`, all atomically (see `write_dir_atomically`).
pub fn write_checkpoint(
    dir: &Path,
    meta: CheckpointMeta,
    files: &[(&str, Vec<(String, Tensor)>)],
) -> Result<Written, CheckpointError> {
    write_dir_atomically(dir, |tmp| fill_checkpoint(tmp, dir, meta, files))
}

/// Writes a checkpoint folder that must not exist yet (a league snapshot).
pub fn write_new_checkpoint(
    dir: &Path,
    meta: CheckpointMeta,
    files: &[(&str, Vec<(String, Tensor)>)],
) -> Result<Written, CheckpointError> {
    write_new_dir_atomically(dir, |tmp| fill_checkpoint(tmp, dir, meta, files))
}

fn fill_checkpoint(
    tmp: &Path,
    dir: &Path,
    mut meta: CheckpointMeta,
    files: &[(&str, Vec<(String, Tensor)>)],
) -> Result<(), CheckpointError> {
    meta.files.clear();
    for (file, tensors) in files {
        check_finite(tensors, &dir.join(file))
            .map_err(|e| CheckpointError::WouldWriteNonFinite(Box::new(e)))?;
        let path = tmp.join(file);
        save_tensors(&path, tensors)?;
        let sha = match sha256_file(&path) {
            Ok(sha) => sha,
            Err(cause) => return Err(CheckpointError::Unreadable { path, cause }),
        };
        meta.files.insert(file.to_string(), sha);
    }
    meta.wall_ray_range_m = (meta.net.sight.wall_rays > 0).then_some(WALL_RAY_RANGE_M);
    let text = serde_json::to_string_pretty(&meta).expect("a checkpoint's sidecar serialises");
    let path = tmp.join("meta.json");
    std::fs::write(&path, text).map_err(|cause| {
        CheckpointError::Fs(FsError::Io {
            what: format!("cannot write {}", path.display()),
            cause,
        })
    })?;
    write_manifest(tmp)
}

/// Writes the manifest a checkpoint folder written before manifests
/// existed lacks, once its meta.json parses and every file it lists
/// matches its hash: from then on an edit to meta.json is refused. It
/// vouches for meta.json as it is now, so it is for folders one trusts (a
/// training run of one's own), and refuses an export, which carries its
/// manifest from `export` and is exported again instead.
pub fn seal(dir: &Path) -> Result<(), CheckpointError> {
    let manifest = dir.join("SHA256SUMS");
    if let Ok(m) = std::fs::symlink_metadata(&manifest) {
        let what = if m.is_file() && m.len() == 0 {
            "already there, but empty (a write that did not finish?): remove it and seal again"
                .into()
        } else if m.is_file() {
            "already there: the folder is sealed".into()
        } else {
            "already there, and not a regular file (a link, FIFO or folder): remove it and seal again".into()
        };
        return Err(CheckpointError::Manifest {
            path: manifest.clone(),
            manifest,
            what,
        });
    }
    if let Some(mark) = ["player.json", "league-config.toml"]
        .into_iter()
        .find(|m| dir.join(m).exists())
    {
        return Err(CheckpointError::Manifest {
            path: manifest.clone(),
            manifest,
            what: format!("missing from an export (it holds {mark}): an export's manifest is written by `export` and covers player.json; export the player again"),
        });
    }
    let meta = read_meta(dir)?;
    for file in meta.files.keys() {
        verify_file(dir, &meta, file)?;
    }
    write_manifest(dir)
}

/// Writes `dir/SHA256SUMS`: `<sha256>  <file>` for every other regular
/// file of the folder, sorted by name (the `sha256sum -c` format). Written
/// under a temporary name and renamed over the old one, so a kill or a full
/// disk leaves the old manifest or none, never a part of one, and a link
/// in its place is replaced rather than written through.
pub fn write_manifest(dir: &Path) -> Result<(), CheckpointError> {
    let io = |what: String, cause| CheckpointError::Fs(FsError::Io { what, cause });
    let mut names = Vec::new();
    for entry in
        std::fs::read_dir(dir).map_err(|e| io(format!("cannot list {}", dir.display()), e))?
    {
        let entry = entry.map_err(|e| io(format!("cannot list {}", dir.display()), e))?;
        let path = entry.path();
        let Some(name) = entry.file_name().to_str().map(str::to_string) else {
            return Err(CheckpointError::Invalid {
                path,
                what:
                    "its name is not UTF-8, so a manifest line cannot name it; rename or remove it"
                        .into(),
            });
        };
        if name == "SHA256SUMS" || name.starts_with(".SHA256SUMS.") || !path.is_file() {
            continue;
        }
        if name.contains(['\n', '\r', '\\']) {
            return Err(CheckpointError::Invalid {
                path,
                what: "its name holds a line break or a backslash, which a manifest line cannot hold; rename or remove it".into(),
            });
        }
        names.push(name);
    }
    names.sort();
    let mut text = String::new();
    for name in names {
        let path = dir.join(&name);
        let sha =
            sha256_file(&path).map_err(|cause| CheckpointError::Unreadable { path, cause })?;
        text.push_str(&format!("{sha}  {name}\n"));
    }
    let path = dir.join("SHA256SUMS");
    let tmp = dir.join(format!(".SHA256SUMS.tmp-{}", std::process::id()));
    let written = std::fs::File::create(&tmp)
        .and_then(|mut f| {
            use std::io::Write;
            f.write_all(text.as_bytes())?;
            f.sync_all()
        })
        .and_then(|()| std::fs::rename(&tmp, &path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(format!("cannot write {}", path.display()), e));
    }
    Ok(())
}

pub fn read_meta(dir: &Path) -> Result<CheckpointMeta, CheckpointError> {
    Ok(read_meta_hashed(dir)?.0)
}

/// `read_meta`, and the SHA-256 of the exact bytes it parsed: what an eval
/// setting's identity records, so an edited sidecar (its protocol, say) is
/// another setting.
pub fn read_meta_hashed(dir: &Path) -> Result<(CheckpointMeta, String), CheckpointError> {
    let path = dir.join("meta.json");
    if !path.is_file() {
        return Err(CheckpointError::NoMeta {
            meta: path,
            dir: dir.to_path_buf(),
        });
    }
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(cause) => return Err(CheckpointError::Unreadable { path, cause }),
    };
    let sha256 = t2e_core::util::sha256_hex(text.as_bytes());
    #[derive(Deserialize)]
    struct Format {
        format: u32,
    }
    if let Ok(Format { format }) = serde_json::from_str::<Format>(&text) {
        if format != FORMAT {
            return Err(CheckpointError::Format { path, format });
        }
    }
    // The algorithm first, by name: an unknown one is refused as such,
    // not as a sidecar that does not parse.
    #[derive(Deserialize)]
    struct Named {
        algorithm: String,
    }
    if let Ok(Named { algorithm }) = serde_json::from_str::<Named>(&text) {
        if Algorithm::parse(&algorithm).is_none() {
            let known: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
            return Err(CheckpointError::UnknownAlgorithm {
                path,
                algorithm,
                known: known.join(", "),
            });
        }
    }
    let meta: CheckpointMeta = match serde_json::from_str(&text) {
        Ok(meta) => meta,
        Err(cause) => return Err(CheckpointError::NotASidecar { path, cause }),
    };
    let invalid = |what: String| CheckpointError::Invalid {
        path: path.clone(),
        what,
    };
    if !(meta.speed_ratio.is_finite() && meta.speed_ratio > 0.0) {
        return Err(invalid(format!(
            "speed_ratio = {}: not a speed ratio",
            meta.speed_ratio
        )));
    }
    if meta.num_captors == 0 || meta.num_captors > t2e_core::env::MAX_CAPTORS {
        return Err(invalid(format!(
            "num_captors = {}: must be between 1 and {}",
            meta.num_captors,
            t2e_core::env::MAX_CAPTORS
        )));
    }
    meta.net
        .validate()
        .map_err(|e| invalid(format!("net.{e}")))?;
    if meta.net.sight.wall_rays > 0 {
        match meta.wall_ray_range_m {
            None => {
                return Err(invalid(format!(
                    "net.sight.wall_rays = {}, but no wall_ray_range_m: the network was trained when a wall ray was divided by each map's extent; this build reads rays out to a fixed {WALL_RAY_RANGE_M} m, so its inputs would mean other distances. Train it again",
                    meta.net.sight.wall_rays
                )))
            }
            Some(range) if range != WALL_RAY_RANGE_M => {
                return Err(invalid(format!(
                    "wall_ray_range_m = {range}: this build's wall rays read out to {WALL_RAY_RANGE_M} m"
                )))
            }
            Some(_) => {}
        }
    }
    Ok((meta, sha256))
}

/// Checks a checkpoint folder against its `SHA256SUMS`: every file it
/// lists is a regular file with that hash, and meta.json is among them; an
/// export's `player.json` names meta.json's side. A folder without a
/// manifest is refused (`CheckpointError::NoManifest`).
pub fn verify_manifest(dir: &Path) -> Result<(), CheckpointError> {
    verify_folder(dir, None)
}

/// `verify_manifest` for a folder whose `meta.json` SHA-256 a league's store
/// recorded when the folder became a player: that record covers meta.json,
/// so a folder written before manifests existed plays if its meta.json is
/// the recorded one, byte for byte.
pub fn verify_recorded(dir: &Path, meta_sha256: &str) -> Result<(), CheckpointError> {
    verify_folder(dir, Some(meta_sha256))
}

fn verify_folder(dir: &Path, recorded: Option<&str>) -> Result<(), CheckpointError> {
    check_player_side(dir)?;
    let manifest = dir.join("SHA256SUMS");
    if manifest.exists() && !manifest.is_file() {
        return Err(CheckpointError::Manifest {
            path: manifest.clone(),
            manifest,
            what: "not a regular file: a checkpoint's manifest lists `<sha256>  <file>`".into(),
        });
    }
    if !manifest.is_file() {
        return verify_without_manifest(dir, manifest, recorded);
    }
    let refuse = |path: PathBuf, what: String| CheckpointError::Manifest {
        path,
        manifest: manifest.clone(),
        what,
    };
    let text = std::fs::read_to_string(&manifest).map_err(|cause| CheckpointError::Unreadable {
        path: manifest.clone(),
        cause,
    })?;
    let mut listed_meta = false;
    let mut listed = Vec::new();
    for (i, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let name = verify_manifest_line(dir, &manifest, i, line)?;
        listed_meta |= name == "meta.json";
        listed.push(name.to_string());
    }
    if !listed_meta {
        return Err(refuse(dir.join("meta.json"), "not listed".into()));
    }
    // An export's own files say which player it is: edited, they would
    // name another.
    for mark in ["player.json", "league-config.toml"] {
        if dir.join(mark).exists() && !listed.iter().any(|n| n == mark) {
            return Err(refuse(
                dir.join(mark),
                "not listed, though the folder holds it".into(),
            ));
        }
    }
    Ok(())
}

/// A folder without a manifest plays only on a store's record of its
/// meta.json; apart from `verify_folder` because it is the legacy path.
fn verify_without_manifest(
    dir: &Path,
    manifest: PathBuf,
    recorded: Option<&str>,
) -> Result<(), CheckpointError> {
    let meta = dir.join("meta.json");
    match recorded {
        Some(want) if meta.is_file() => {
            let got = sha256_file(&meta).map_err(|cause| CheckpointError::Unreadable {
                path: meta.clone(),
                cause,
            })?;
            if got != want {
                return Err(CheckpointError::HashMismatch {
                    path: meta,
                    got,
                    want: want.to_string(),
                });
            }
            Ok(())
        }
        _ => Err(CheckpointError::NoManifest {
            manifest,
            dir: dir.to_path_buf(),
        }),
    }
}

/// Checks one `<sha256>  <file>` line (0-based `i`) against the folder and
/// returns the file it names; apart so each refusal reads beside its rule.
fn verify_manifest_line<'l>(
    dir: &Path,
    manifest: &Path,
    i: usize,
    line: &'l str,
) -> Result<&'l str, CheckpointError> {
    let refuse = |path: PathBuf, what: String| CheckpointError::Manifest {
        path,
        manifest: manifest.to_path_buf(),
        what,
    };
    let Some((want, name)) = line.split_once("  ") else {
        return Err(refuse(
            manifest.to_path_buf(),
            format!("line {} is not `<sha256>  <file>`", i + 1),
        ));
    };
    if name.is_empty() {
        return Err(refuse(
            manifest.to_path_buf(),
            format!("line {} names no file", i + 1),
        ));
    }
    if name == "SHA256SUMS" {
        return Err(refuse(
            manifest.to_path_buf(),
            format!(
                "line {} lists the manifest itself, whose hash it cannot hold",
                i + 1
            ),
        ));
    }
    if name.contains('/') || name.contains('\\') || name == ".." || name == "." {
        return Err(refuse(
            manifest.to_path_buf(),
            format!("line {} names {name:?}, not a file of the folder", i + 1),
        ));
    }
    let path = dir.join(name);
    // Asked before reading, so a FIFO listed here cannot block the read.
    match std::fs::metadata(&path) {
        Err(_) => return Err(refuse(path, "listed, but missing".into())),
        Ok(m) if !m.is_file() => return Err(refuse(path, "listed, but not a regular file".into())),
        Ok(_) => {}
    }
    let got = t2e_core::util::sha256_file(&path)
        .map_err(|e| refuse(path.clone(), format!("listed but unreadable ({e})")))?;
    if got != want.trim().to_ascii_lowercase() {
        return Err(refuse(
            path,
            format!(
                "SHA-256 {got} is not the {} listed: the folder changed after its manifest was written",
                want.trim()
            ),
        ));
    }
    Ok(name)
}

/// An export's `player.json` and its `meta.json` must name one side: the
/// side a player is listed as is the side its weights play.
fn check_player_side(dir: &Path) -> Result<(), CheckpointError> {
    let player_json = dir.join("player.json");
    if !player_json.is_file() {
        return Ok(());
    }
    let meta_json = dir.join("meta.json");
    let side_of = |path: &Path| -> Result<Option<String>, CheckpointError> {
        let text = std::fs::read_to_string(path).map_err(|cause| CheckpointError::Unreadable {
            path: path.to_path_buf(),
            cause,
        })?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| CheckpointError::Invalid {
                path: path.to_path_buf(),
                what: format!("not JSON ({e})"),
            })?;
        Ok(value
            .get("side")
            .and_then(|s| s.as_str())
            .map(str::to_string))
    };
    let player = side_of(&player_json)?.ok_or_else(|| CheckpointError::Invalid {
        path: player_json.clone(),
        what: "has no string `side` (captors or target)".into(),
    })?;
    let meta = if meta_json.is_file() {
        side_of(&meta_json)?.unwrap_or_default()
    } else {
        return Ok(());
    };
    if player != meta {
        return Err(CheckpointError::SideDisagrees {
            player_json,
            meta_json,
            player,
            meta,
        });
    }
    Ok(())
}
