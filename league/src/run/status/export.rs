//! `export`: a player's checkpoint copied out of the league, by name or as the validation panel's best.

use super::report::StatusReport;
use crate::error::{IoResultExt, LeagueError, Result};
use crate::run::folder::layout::LeagueDir;
use crate::run::folder::open::open_read_only as open;
use crate::store::{Kind, Player};
use std::fmt::Write as _;
use std::path::Path;
use t2e_core::env::Side;

/// Writes one player as a self-contained folder: its checkpoint files, the
/// league's config, its rating history and a SHA-256 manifest; `eval
/// --captors ckpt:OUT` (or `--target`) plays it on another machine.
pub fn export(dir: &LeagueDir, player: &str, out: &Path) -> Result<()> {
    let (cfg, store) = open(dir)?;
    let players = store.players()?;
    let p = players
        .iter()
        .find(|p| p.name == player || p.id.to_string() == player)
        .ok_or_else(|| LeagueError::UnknownPlayer {
            player: player.to_string(),
            league: dir.root.display().to_string(),
            players: crate::store::player_names(&players),
        })?;
    let Some((rel, meta_sha)) = &p.checkpoint else {
        return Err(LeagueError::NoWeights(format!(
            "{} is a heuristic member: it has no weights to export",
            p.name
        )));
    };
    let src = verified_source(dir, p, rel, meta_sha)?;
    if let Some(why) = &p.quarantined {
        tracing::info!(
            "note: {} is quarantined ({why}); its files verify against the hashes recorded with it, so they are exported",
            p.name
        );
    }
    if out.exists() {
        return Err(LeagueError::Refused(format!(
            "{}: already exists; pick a new --out",
            out.display()
        )));
    }
    if dir.contains(out) {
        return Err(LeagueError::Refused(format!(
            "--out {}: inside the league directory {}; the league owns what is there (players/ is reconciled at every start). Export outside it",
            out.display(),
            dir.root.display()
        )));
    }
    t2e_core::fs::write_dir_atomically(out, |tmp| {
        t2e_core::fs::copy_files(&src, tmp)?;
        // The config as the store holds it, byte for byte: what the league
        // ran with, in the words it was written in.
        let config_text = match store.stored_config()? {
            Some(text) => text,
            None => toml::to_string_pretty(&cfg).map_err(|cause| LeagueError::Toml {
                context: "cannot write the league's config".into(),
                cause,
            })?,
        };
        write(&tmp.join("league-config.toml"), config_text)?;
        let mut csv = String::from("match_id,mu,sigma,at_ms\n");
        for r in store.rating_history(p.id)? {
            let _ = writeln!(
                csv,
                "{},{},{},{}",
                r.match_id.map(|x| x.to_string()).unwrap_or_default(),
                r.mu,
                r.sigma,
                r.at_ms
            );
        }
        write(&tmp.join("ratings.csv"), csv)?;
        let info = serde_json::json!({
            "player": p.name, "id": p.id, "side": p.side.name(), "kind": p.kind.name(),
            "parent": p.parent, "env_steps": p.env_steps, "league": dir.root.display().to_string(),
        });
        let player_json = tmp.join("player.json");
        let text = serde_json::to_string_pretty(&info).map_err(|cause| LeagueError::Json {
            context: format!("cannot write {}", player_json.display()),
            cause,
        })?;
        write(&player_json, text)?;
        // Over the copied files, player.json and the config: the snapshot's
        // own manifest, copied with it, is replaced.
        t2e_learners::nn::checkpoint::write_manifest(tmp)?;
        Ok::<(), LeagueError>(())
    })?;
    Ok(())
}

/// The player's checkpoint folder in the pool, its files checked against
/// the store's record before anything is copied out.
fn verified_source(
    dir: &LeagueDir,
    p: &Player,
    rel: &str,
    meta_sha: &str,
) -> Result<std::path::PathBuf> {
    let src = dir.root.join(rel);
    let got = t2e_core::util::sha256_file(&src.join("meta.json"))
        .io_context(|| format!("{}: meta.json missing", src.display()))?;
    if got != meta_sha {
        return Err(LeagueError::Corrupt(format!("{}: meta.json does not match the store's sha256: refusing to export a corrupt checkpoint", src.display())));
    }
    // Loading verifies every weight file against meta.json and refuses NaN.
    t2e_learners::nn::PolicySnapshot::load_recorded(&src, p.side, meta_sha)?;
    Ok(src)
}

/// Writes one file of an export; the error names it.
fn write(path: &Path, text: impl AsRef<[u8]>) -> Result<()> {
    std::fs::write(path, text).io_context(|| format!("cannot write {}", path.display()))
}

/// The validation-best snapshot of a side's main learner, and the panel.
pub struct BestValidated {
    pub player: Player,
    /// Its win rate against the validation team it did worst against.
    pub worst_win_rate: f64,
    pub worst_opponent: String,
    pub win_rate: f64,
    pub mean_steps: f64,
    pub episodes: u64,
    /// The validation teams, comma-separated, and their maps.
    pub opponents: String,
}

/// The main learner's snapshot of `side` that did best on the validation
/// panel (`selection::rank_validated`), for `export --best`.
pub fn best_validated(dir: &LeagueDir, side: Side) -> Result<BestValidated> {
    let (cfg, store) = open(dir)?;
    let opponents: Vec<String> = cfg
        .evaluator
        .validation(side)
        .map_err(|e| {
            LeagueError::from(e.within("evaluator"))
                .context(dir.config_path().display().to_string())
        })?
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    let ranked = crate::rules::selection::rank_validated(
        &store.players()?,
        &store.held_out_results()?,
        side,
        &opponents,
        cfg.evaluator.episodes as u64,
    )
    .map_err(|e| match e {
        // "Wait for the evaluator" would wait for ever.
        crate::rules::selection::NoChoice::NoneComplete { .. } if !cfg.evaluator.enabled => {
            LeagueError::Refused(format!(
                "{}: no snapshot has a complete validation, and the league's evaluator is off ([evaluator] enabled = false), so none will; export a player by name",
                dir.root.display()
            ))
        }
        e => LeagueError::from(e).context(dir.root.display().to_string()),
    })?;
    let best = ranked
        .into_iter()
        .next()
        .expect("rank_validated never returns an empty list");
    Ok(BestValidated {
        player: best.player,
        worst_win_rate: best.worst_win_rate,
        worst_opponent: best.worst_opponent,
        win_rate: best.win_rate,
        mean_steps: best.mean_steps,
        episodes: best.episodes,
        opponents: format!(
            "{} on {}",
            opponents.join(", "),
            cfg.evaluator.validation_maps.as_deref().unwrap_or("?")
        ),
    })
}

/// The best player of a side by the Bradley-Terry fit, among those with weights.
pub fn best_player(r: &StatusReport, side: Side) -> Option<String> {
    r.players
        .iter()
        .filter(|p| {
            p.side == side && p.kind != Kind::Heuristic && p.quarantined.is_none() && p.games > 0
        })
        .max_by(|a, b| a.bt_elo.total_cmp(&b.bt_elo))
        .map(|p| p.name.clone())
}
