//! The pool on disk: snapshot folders in `players/` and the store rows that
//! name them.
//!
//! Invariants (each has a test in tests/integration/league_faults.rs):
//! - A recorded member never changes: a snapshot folder is written under a
//!   new name only (`write_new_checkpoint`), never over an existing folder,
//!   and a name the store already records is never written again.
//! - Nothing that verifies is ever deleted: at start, only temporaries of
//!   dead processes (`.NAME.tmp-PID`) are removed. A complete folder without
//!   a row (its writer died between the rename and the insert) is adopted
//!   from its own sidecar when it verifies and names this league; any other
//!   unrecorded folder is left where it is, with a warning.
//! - Rows whose files are missing or fail their hashes are quarantined: the
//!   league goes on without them.

use crate::error::{IoResultExt, LeagueError, Result, ResultExt};
use crate::rules::config::LeagueConfig;
use crate::rules::players::{learner_name, Seat};
use crate::run::folder::layout::LeagueDir;
use crate::store::{Kind, NewPlayer, Player, Store};
use t2e_core::env::Side;
use t2e_core::protocol::Protocol;
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::learn::train::Trainer;
use t2e_learners::nn::checkpoint::{read_meta, CheckpointMeta};
use t2e_learners::nn::PolicySnapshot;

/// Which league pool a snapshot belongs to, and as whom: the label a
/// snapshot's meta.json carries (`CheckpointMeta::pool_label`, under
/// `league`), so its folder can be matched to its store row, or the row
/// rebuilt, from its own files.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoolMembership {
    /// The league's identity (`league.json`).
    pub league_id: String,
    /// The snapshot's player name.
    pub player: String,
    /// The player name of the learner it is a snapshot of.
    pub parent: String,
    pub curriculum_stage: usize,
}

impl PoolMembership {
    /// The membership a checkpoint's sidecar names: none for a folder that
    /// is no snapshot (a main learner's checkpoint, a `train` run's), an
    /// error for a label that is not a membership.
    pub fn of(meta: &CheckpointMeta) -> Result<Option<PoolMembership>> {
        meta.pool_label
            .as_ref()
            .map(|label| {
                serde_json::from_value(label.clone()).map_err(|cause| LeagueError::Json {
                    context: "meta.json's `league` is not a pool membership".into(),
                    cause,
                })
            })
            .transpose()
    }
}

/// What a learner may draw from the pool.
#[derive(Clone, Debug, PartialEq)]
pub struct Playable {
    /// The other side's members that play: snapshots and heuristics, not
    /// quarantined.
    pub members: Vec<Player>,
    /// The other side's main learner's newest snapshot among them.
    pub main: Option<i64>,
    /// The other side's exploiter's newest snapshot among them (a main
    /// learner's only: an exploiter draws the main line alone).
    pub exploiter: Option<i64>,
}

/// The members a learner of `seat` may draw. A main learner draws every
/// playable member of the other side; an exploiter only the other main
/// learner's snapshots, and the heuristics to play until there is one.
pub fn playable(players: &[Player], seat: Seat) -> Playable {
    let other = seat.side.other();
    let id_of = |name: String| players.iter().find(|p| p.name == name).map(|p| p.id);
    let other_main = id_of(learner_name(other));
    let other_exploiter = id_of(Seat::exploiter(other).name());
    let of_other_main = |m: &Player| m.parent.is_some() && m.parent == other_main;
    let members: Vec<Player> = players
        .iter()
        .filter(|p| p.side == other && p.quarantined.is_none())
        .filter(|p| matches!(p.kind, Kind::Snapshot | Kind::Heuristic))
        .filter(|p| !seat.draws_main_line_only() || p.kind == Kind::Heuristic || of_other_main(p))
        .cloned()
        .collect();
    let newest_of = |parent: Option<i64>| {
        members
            .iter()
            .filter(|m| m.kind == Kind::Snapshot && parent.is_some() && m.parent == parent)
            .max_by_key(|m| m.env_steps)
            .map(|m| m.id)
    };
    Playable {
        main: newest_of(other_main),
        exploiter: newest_of(other_exploiter),
        members,
    }
}

use crate::rules::roles::snapshot_name;

/// What `add_snapshot` did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SnapshotOutcome {
    Added(String),
    /// The name is already recorded: nothing written.
    AlreadyInPool(String),
    /// Something the store does not record sits at the snapshot's path (put
    /// there by hand): it is left alone and this snapshot is skipped.
    Blocked(String),
}

/// A frozen copy of the learner joins the pool: files written (synced,
/// renamed into place, never over an existing folder) before the row that
/// names them. A name the pool already holds is left as it is.
pub fn add_snapshot(
    trainer: &mut Trainer,
    store: &Store,
    dir: &LeagueDir,
    league_id: &str,
    seat: Seat,
    learner_id: i64,
    stage: usize,
) -> Result<SnapshotOutcome> {
    let name = snapshot_name(seat, trainer.env_steps);
    let folder = dir.players_dir().join(&name);
    if store.players()?.iter().any(|p| p.name == name) {
        return Ok(SnapshotOutcome::AlreadyInPool(name));
    }
    if folder.symlink_metadata().is_ok() {
        return Ok(SnapshotOutcome::Blocked(name));
    }
    let membership = PoolMembership {
        league_id: league_id.to_string(),
        player: name.clone(),
        parent: seat.name(),
        curriculum_stage: stage,
    };
    let label = serde_json::to_value(&membership).map_err(|cause| LeagueError::Json {
        context: format!("{name}: its pool membership"),
        cause,
    })?;
    trainer.side(seat.side)?.save_new(&folder, label)?;
    let sha = sha256_of_meta(&folder)?;
    store.add_player(&NewPlayer {
        name: name.clone(),
        side: seat.side,
        kind: Kind::Snapshot,
        parent: Some(learner_id),
        env_steps: trainer.env_steps,
        curriculum_stage: stage,
        checkpoint: Some((dir.relative(&folder), sha)),
    })?;
    Ok(SnapshotOutcome::Added(name))
}

/// What `reconcile` found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reconciled {
    /// Temporaries of dead writers, removed.
    pub removed_temporaries: Vec<String>,
    /// Complete folders whose row was missing, added to the pool.
    pub adopted: Vec<String>,
    /// Folders without a row that could not be adopted (and why): left in place.
    pub unrecorded: Vec<(String, String)>,
    /// Rows whose files are missing or corrupt.
    pub quarantined: Vec<String>,
    /// Quarantined rows whose files verify again.
    pub reinstated: Vec<String>,
}

/// Checks a league directory's pool against its files at start (see the
/// module's invariants).
pub fn reconcile(dir: &LeagueDir, store: &Store, league_id: &str) -> Result<Reconciled> {
    let mut out = Reconciled::default();
    let players_dir = dir.players_dir();
    for p in t2e_core::fs::clean_stale_temporaries(&players_dir)? {
        out.removed_temporaries.push(dir.relative(&p));
    }
    for (rel, adopted) in adopt_unrecorded(dir, store, league_id, None)? {
        match adopted {
            Ok(()) => out.adopted.push(rel),
            Err(why) => out.unrecorded.push((rel, why.chain())),
        }
    }
    // Every snapshot row against its files: one whose files are missing or
    // corrupt leaves play; a quarantined one whose files are back and verify
    // against the hash recorded with it plays again (they are the very
    // weights that played its recorded matches).
    for p in store.players()?.iter().filter(|p| p.kind == Kind::Snapshot) {
        let Some((rel, sha)) = &p.checkpoint else {
            continue;
        };
        let folder = dir.root.join(rel);
        let meta = folder.join("meta.json");
        let recorded = t2e_core::util::sha256_file(&meta).is_ok_and(|got| &got == sha);
        if recorded && !folder.join("SHA256SUMS").exists() {
            // Written before checkpoints carried a manifest: the store's
            // record vouches for its meta.json, so the manifest is made
            // once here, after its weights verify against meta.json.
            if let Err(e) = t2e_learners::nn::checkpoint::seal(&folder) {
                tracing::warn!("{}: cannot write its manifest: {e}", folder.display());
            }
        }
        let ok = recorded && PolicySnapshot::load_recorded(&folder, p.side, sha).is_ok();
        match (ok, p.quarantined.is_some()) {
            (false, false) => {
                store.quarantine(p.id, "checkpoint files missing or corrupt at league start")?;
                out.quarantined.push(p.name.clone());
            }
            (true, true) => {
                store.reinstate(p.id)?;
                out.reinstated.push(p.name.clone());
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Snapshot folders in `players/` that no row names (of the learner
/// `parent` only, if given), each with the result of adopting it.
pub fn adopt_unrecorded(
    dir: &LeagueDir,
    store: &Store,
    league_id: &str,
    parent: Option<&str>,
) -> Result<Vec<(String, Result<()>)>> {
    let mut out = Vec::new();
    let mut entries: Vec<_> = match std::fs::read_dir(dir.players_dir()) {
        Ok(it) => it.flatten().map(|e| e.path()).collect(),
        Err(_) => Vec::new(),
    };
    entries.sort();
    for path in entries {
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        if name.starts_with('.') {
            continue; // a live writer's temporary
        }
        if let Some(parent) = parent {
            let mine = read_meta(&path)
                .ok()
                .and_then(|m| PoolMembership::of(&m).ok().flatten())
                .is_some_and(|m| m.parent == parent);
            if !mine {
                continue;
            }
        }
        let rel = dir.relative(&path);
        let players = store.players()?;
        if players
            .iter()
            .any(|p| p.checkpoint.as_ref().is_some_and(|(r, _)| *r == rel))
        {
            continue;
        }
        let adopted = adopt(dir, store, league_id, &path, &name, &players);
        out.push((rel, adopted));
    }
    Ok(out)
}

/// Adds the row of a complete snapshot folder from its own sidecar, if it
/// verifies and belongs to this league under its folder's name.
fn adopt(
    dir: &LeagueDir,
    store: &Store,
    league_id: &str,
    path: &std::path::Path,
    name: &str,
    players: &[crate::store::Player],
) -> Result<()> {
    let meta = read_meta(path)?;
    let member = PoolMembership::of(&meta)?.ok_or_else(|| {
        LeagueError::Pool(
            "its meta.json names no league pool (not a snapshot this league wrote)".into(),
        )
    })?;
    if member.league_id != league_id {
        return Err(LeagueError::Pool(format!(
            "it belongs to league {}, not this one ({league_id})",
            member.league_id
        )));
    }
    if member.player != name {
        return Err(LeagueError::Pool(format!(
            "its meta.json names it {}",
            member.player
        )));
    }
    if players.iter().any(|p| p.name == name) {
        return Err(LeagueError::Pool(format!(
            "the store records {name} with other files"
        )));
    }
    // Every weight file against its hash, and finite.
    PolicySnapshot::load(path, meta.side)?;
    let parent = players
        .iter()
        .find(|p| p.name == member.parent)
        .ok_or_else(|| {
            LeagueError::Pool(format!("its learner {} is not in the store", member.parent))
        })?;
    store.add_player(&NewPlayer {
        name: name.to_string(),
        side: meta.side,
        kind: Kind::Snapshot,
        parent: Some(parent.id),
        env_steps: meta.env_steps,
        curriculum_stage: member.curriculum_stage,
        checkpoint: Some((dir.relative(path), sha256_of_meta(path)?)),
    })?;
    Ok(())
}

/// The SHA-256 of a checkpoint folder's meta.json, which the store records
/// beside its row; the error names the file.
pub(crate) fn sha256_of_meta(folder: &std::path::Path) -> Result<String> {
    let meta = folder.join("meta.json");
    t2e_core::util::sha256_file(&meta).io_context(|| format!("cannot read {}", meta.display()))
}

/// Adds each side's permanent members (the default heuristic and the
/// config's extras) to the store, once: a heuristic as a row; a trained
/// team as a frozen copy in `players/` with a snapshot row that has no
/// parent (`import_member`). A member already recorded is left as it was
/// recorded, whatever its source folder holds now.
pub fn ensure_members(dir: &LeagueDir, store: &Store, cfg: &LeagueConfig) -> Result<()> {
    let recorded = store.players()?;
    for side in [Side::Captors, Side::Target] {
        let field = format!("members.{}", side.name());
        let members = cfg.members.of(side).map_err(|e| e.within("members"))?;
        for (name, spec) in members {
            match &spec {
                ControllerSpec::Checkpoint(c) => {
                    if recorded.iter().all(|p| p.name != name) {
                        import_member(dir, store, cfg, side, &name, &c.path)
                            .with_context(|| format!("{field} = \"{spec}\""))?;
                    }
                }
                _ => {
                    store.add_player(&NewPlayer {
                        name,
                        side,
                        kind: Kind::Heuristic,
                        parent: None,
                        env_steps: 0,
                        curriculum_stage: 0,
                        checkpoint: None,
                    })?;
                }
            }
        }
    }
    Ok(())
}

/// Checks every trained member of a league about to start, before
/// anything is written: a bad one is refused while the config can still be
/// mended (a started league keeps its config).
pub fn check_trained_members(cfg: &LeagueConfig) -> Result<()> {
    for side in [Side::Captors, Side::Target] {
        for (_, spec) in cfg.members.of(side).map_err(|e| e.within("members"))? {
            if let ControllerSpec::Checkpoint(c) = &spec {
                verified_member(cfg, side, &c.path)
                    .with_context(|| format!("members.{} = \"{spec}\"", side.name()))?;
            }
        }
    }
    Ok(())
}

/// A trained team loaded for `side` of this league: weights verified
/// (hashes, finite), its side and K the league's, and trained under a
/// protocol the league's allows (a held-out league never takes a team
/// trained on the Gibson test maps).
fn verified_member(
    cfg: &LeagueConfig,
    side: Side,
    source: &std::path::Path,
) -> Result<PolicySnapshot> {
    let snap = PolicySnapshot::load(source, side)?;
    let env = cfg.train_config(side.other()).learning_env();
    snap.meta
        .check_reads(side, &env)
        .map_err(|cause| LeagueError::DoesNotFit {
            checkpoint: snap.dir.clone(),
            cause,
        })?;
    if cfg.protocol == Protocol::HeldOut && snap.meta.protocol != Protocol::HeldOut {
        return Err(LeagueError::Pool(format!(
            "{}: trained under the {} protocol, on the Gibson maps a held-out league tests on",
            snap.dir.display(),
            snap.meta.protocol.name()
        )));
    }
    Ok(snap)
}

/// Copies a trained team (checked by `verified_member`) into
/// `players/NAME` and records it. A copy a killed start left complete is
/// taken if it is the same checkpoint; anything else there is refused.
fn import_member(
    dir: &LeagueDir,
    store: &Store,
    cfg: &LeagueConfig,
    side: Side,
    name: &str,
    source: &std::path::Path,
) -> Result<()> {
    let snap = verified_member(cfg, side, source)?;
    let target = dir.players_dir().join(name);
    if target.exists() {
        let same = t2e_core::util::sha256_file(&target.join("meta.json"))
            .is_ok_and(|sha| sha == snap.meta_sha256)
            && PolicySnapshot::load(&target, side).is_ok();
        if !same {
            return Err(LeagueError::Pool(format!(
                "{} exists and is not this checkpoint: move it away",
                target.display()
            )));
        }
    } else {
        t2e_core::fs::write_new_dir_atomically(&target, |tmp| {
            t2e_core::fs::copy_files(&snap.dir, tmp)
        })?;
        // The copy, not the source, is what the league plays.
        PolicySnapshot::load(&target, side)?;
    }
    store.add_player(&NewPlayer {
        name: name.to_string(),
        side,
        kind: Kind::Snapshot,
        parent: None,
        env_steps: snap.meta.env_steps,
        curriculum_stage: 0,
        checkpoint: Some((dir.relative(&target), sha256_of_meta(&target)?)),
    })?;
    tracing::info!(
        "{name}: {} joins the pool as a permanent member",
        snap.dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::test_player as player;

    #[test]
    fn a_main_learner_draws_every_playable_member_and_an_exploiter_only_the_main_line() {
        use Side::*;
        let mut players = vec![
            player(1, "expert-captors", Captors, Kind::Heuristic, None, 0),
            player(2, "rule-based-target", Target, Kind::Heuristic, None, 0),
            player(3, "captors-main", Captors, Kind::Learner, None, 300),
            player(4, "target-main", Target, Kind::Learner, None, 300),
            player(5, "captors-exploiter", Captors, Kind::Exploiter, None, 100),
            player(6, "captors-snap-100", Captors, Kind::Snapshot, Some(3), 100),
            player(7, "captors-snap-200", Captors, Kind::Snapshot, Some(3), 200),
            player(
                8,
                "captors-exploiter-snap-100",
                Captors,
                Kind::Snapshot,
                Some(5),
                100,
            ),
            player(9, "captors-snap-300", Captors, Kind::Snapshot, Some(3), 300),
        ];
        players[8].quarantined = Some("files gone".into());
        let ids = |p: &Playable| p.members.iter().map(|m| m.id).collect::<Vec<_>>();

        let main = playable(&players, Seat::main(Target));
        assert_eq!(
            ids(&main),
            [1, 6, 7, 8],
            "learners and quarantined members never play"
        );
        assert_eq!(main.main, Some(7), "the newest snapshot that plays");
        assert_eq!(main.exploiter, Some(8), "the exploiter's newest snapshot");

        let exploiter = playable(&players, Seat::exploiter(Target));
        assert_eq!(ids(&exploiter), [1, 6, 7]);
        assert_eq!(exploiter.main, Some(7));
        assert_eq!(
            exploiter.exploiter, None,
            "an exploiter draws the main line only"
        );

        // Before the other main learner has a snapshot: the heuristic only.
        let early = playable(&players[..5], Seat::exploiter(Target));
        assert_eq!(ids(&early), [1]);
        assert_eq!(early.main, None);

        let captors = playable(&players, Seat::main(Captors));
        assert_eq!(ids(&captors), [2]);
        assert_eq!(captors.exploiter, None, "the target has no exploiter");
    }
}
