//! `status --plot`: ratings over matches, the panel's curves over env steps, and the payoff heat map.

use super::report::{PanelRow, PlayerRow, StatusReport};
use crate::error::Result;
use crate::run::folder::layout::LeagueDir;
use crate::run::folder::open::open_read_only as open;
use crate::store::Kind;
use std::path::Path;
use t2e_core::env::Side;

/// One line of the ratings plot.
#[derive(Clone, Debug, PartialEq)]
pub struct RatingLine {
    /// Index into the players.
    pub player: usize,
    /// Colour group: a learner with its snapshots, or a heuristic.
    pub group: usize,
    /// 0 for a learner or heuristic; towards 0.7 for its older snapshots.
    pub lightness: f64,
    /// The legend's entry; empty for a snapshot folded into its group's
    /// entry.
    pub label: String,
}

/// Past this many legend entries, each learner's snapshots share one entry.
const MAX_LEGEND: usize = 14;

/// The ratings plot's lines, grouped: each learner (or heuristic) gets a
/// colour, its snapshots lighter tints of it (the oldest lightest), and
/// lines come learner first, then its snapshots by env steps. Every line is
/// labelled (`captors-main @240k`) while the legend fits; past MAX_LEGEND
/// entries a learner's snapshots share one (`captors-main snapshots (12)`).
/// Players without rating points get no line.
pub fn rating_lines(players: &[PlayerRow], has_points: &[bool]) -> Vec<RatingLine> {
    let by_id = |id: i64| players.iter().position(|p| p.id == id);
    // A snapshot's group is its parent's; a snapshot whose parent is not in
    // the league (never in practice) heads a group of its own.
    let head = |i: usize| match players[i].parent.and_then(by_id) {
        Some(parent) if players[i].kind == Kind::Snapshot => parent,
        _ => i,
    };
    let mut heads: Vec<usize> = (0..players.len()).filter(|&i| head(i) == i).collect();
    heads.sort_by_key(|&i| players[i].id);
    let mut lines = Vec::new();
    let drawn = |i: usize| has_points.get(i).copied().unwrap_or(false);
    let groups: Vec<(usize, Vec<usize>)> = heads
        .iter()
        .enumerate()
        .map(|(g, &h)| {
            let mut snaps: Vec<usize> = (0..players.len())
                .filter(|&i| i != h && head(i) == h && drawn(i))
                .collect();
            snaps.sort_by_key(|&i| (players[i].env_steps, players[i].id));
            (g, snaps)
        })
        .collect();
    let entries: usize = heads.iter().filter(|&&h| drawn(h)).count()
        + groups.iter().map(|(_, s)| s.len()).sum::<usize>();
    let fold = entries > MAX_LEGEND;
    for (&h, (g, snaps)) in heads.iter().zip(&groups) {
        if drawn(h) {
            lines.push(RatingLine {
                player: h,
                group: *g,
                lightness: 0.0,
                label: players[h].name.clone(),
            });
        }
        for (k, &i) in snaps.iter().enumerate() {
            // Newest snapshot 0.25, oldest 0.7.
            let age = if snaps.len() > 1 {
                1.0 - k as f64 / (snaps.len() - 1) as f64
            } else {
                0.0
            };
            let label = if !fold {
                format!("{} @{}", players[h].name, short_steps(players[i].env_steps))
            } else if k == 0 {
                format!("{} snapshots ({})", players[h].name, snaps.len())
            } else {
                String::new()
            };
            lines.push(RatingLine {
                player: i,
                group: *g,
                lightness: 0.25 + 0.45 * age,
                label,
            });
        }
    }
    lines
}

/// 240000 -> "240k", 1500000 -> "1.5M".
pub(super) fn short_steps(steps: u64) -> String {
    if steps >= 1_000_000 {
        let m = format!("{:.2}", steps as f64 / 1e6);
        format!("{}M", m.trim_end_matches('0').trim_end_matches('.'))
    } else if steps >= 1000 {
        format!("{}k", steps / 1000)
    } else {
        steps.to_string()
    }
}

/// One line of the panel plot: one learner's snapshots against one panel
/// opponent, as (the snapshot's env steps, its win %), oldest first.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelCurve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// The evaluator's panel as learning curves: each member counts for the
/// learner it was taken from (a snapshot's parent, else itself), so a line
/// shows how that learner's snapshots fared against one opponent as it
/// trained. Lines in the order of first appearance in `players`, league
/// opponents before held-out ones.
pub fn panel_curves(players: &[PlayerRow], panel: &[PanelRow]) -> Vec<PanelCurve> {
    let find = |id: i64| players.iter().find(|p| p.id == id);
    let mut keyed: Vec<((usize, bool, bool, String), PanelCurve)> = Vec::new();
    for row in panel {
        let Some(member) = find(row.member) else {
            continue;
        };
        let learner = member.parent.and_then(find).unwrap_or(member);
        let order = players
            .iter()
            .position(|p| p.id == learner.id)
            .unwrap_or(usize::MAX);
        let key = (
            order,
            row.held_out,
            row.validation,
            row.opponent_name.clone(),
        );
        let point = (member.env_steps as f64, 100.0 * row.win_rate);
        match keyed.iter_mut().find(|(k, _)| *k == key) {
            Some((_, curve)) => curve.points.push(point),
            None => keyed.push((
                key,
                PanelCurve {
                    label: format!("{} vs {}", learner.name, row.opponent_label()),
                    points: vec![point],
                },
            )),
        }
    }
    keyed.sort_by(|a, b| a.0.cmp(&b.0));
    keyed
        .into_iter()
        .map(|(_, mut curve)| {
            curve.points.sort_by(|a, b| a.0.total_cmp(&b.0));
            curve
        })
        .collect()
}

/// `status --plot`: live ratings over the league's matches (one labelled
/// line per player, snapshots in tints of their learner's colour), the
/// evaluator's panel as curves over the snapshots' env steps (when it has
/// played), then the payoff matrix as a heat map (captor win rate, rows
/// captors, columns targets).
// Long on purpose: one image whose three panels share its size, its palette and the players' order.
pub fn plot(dir: &LeagueDir, r: &StatusReport, path: &Path) -> Result<()> {
    use image::{Rgb, RgbImage};
    use t2e_learners::plots::heat_map::{heat_map, HeatMap};
    use t2e_learners::plots::line::{line_plot, palette, save_png, Series};
    let (cfg, store) = open(dir)?;
    let mut history = Vec::new();
    for p in &r.players {
        let points: Vec<(f64, f64)> = store
            .rating_history(p.id)?
            .iter()
            .filter_map(|r| r.match_id.map(|m| (m as f64, r.mu)))
            .collect();
        history.push(points);
    }
    let has_points: Vec<bool> = history.iter().map(|h| !h.is_empty()).collect();
    let series: Vec<Series> = rating_lines(&r.players, &has_points)
        .into_iter()
        .map(|line| {
            let base = palette(line.group);
            // Snapshots in lighter tints of their learner's colour, older lighter.
            let tint = |c: u8| (c as f64 + (255.0 - c as f64) * line.lightness).round() as u8;
            Series::new(
                line.label,
                std::mem::take(&mut history[line.player]),
                base.map(tint),
            )
        })
        .collect();
    let ratings = line_plot(
        &series,
        &format!("live ratings, league {}", r.league),
        "match",
        "Weng-Lin rating",
        900,
        420,
    );
    let curves: Vec<Series> = panel_curves(&r.players, &r.panel)
        .into_iter()
        .enumerate()
        .map(|(i, c)| Series::new(c.label, c.points, palette(i)))
        .collect();
    let panel = (!curves.is_empty()).then(|| {
        line_plot(
            &curves,
            &format!(
                "panel: each snapshot's win % ({}, 1.0:{}, {} steps{})",
                cfg.maps,
                t2e_learners::eval::ratio_label(cfg.curriculum.stages[0]),
                cfg.episode_length,
                match &cfg.evaluator.validation_maps {
                    Some(v) => format!(
                        "; validation: {v}, {} steps",
                        t2e_learners::eval::EvalSetting::default().episode_length
                    ),
                    None => String::new(),
                }
            ),
            "env steps of the snapshot",
            "win %",
            900,
            320,
        )
    });
    let captors: Vec<&PlayerRow> = r
        .players
        .iter()
        .filter(|p| p.side == Side::Captors)
        .collect();
    let targets: Vec<&PlayerRow> = r
        .players
        .iter()
        .filter(|p| p.side == Side::Target)
        .collect();
    let heat = heat_map(&HeatMap {
        title: "payoff: captor win rate (rows captors, columns targets; blank = no games)".into(),
        // Row labels whole, with the id the columns use: an exploiter's
        // snapshots share their first 27 characters ("captors-exploiter-snap-0000").
        row_labels: captors
            .iter()
            .map(|c| format!("#{} {}", c.id, c.name))
            .collect(),
        column_labels: targets.iter().map(|t| format!("#{}", t.id)).collect(),
        cells: captors
            .iter()
            .map(|c| {
                targets
                    .iter()
                    .map(|t| {
                        r.payoff
                            .iter()
                            .find(|p| p.captor == c.id && p.target == t.id)
                            .map(|p| p.captor_wins as f64 / p.games.max(1) as f64)
                    })
                    .collect()
            })
            .collect(),
        notes: targets
            .iter()
            .map(|t| format!("#{} {}", t.id, t.name))
            .collect(),
    });
    let parts: Vec<&RgbImage> = [Some(&ratings), panel.as_ref(), Some(&heat)]
        .into_iter()
        .flatten()
        .collect();
    let mut img = RgbImage::from_pixel(
        parts.iter().map(|p| p.width()).max().unwrap_or(1),
        parts.iter().map(|p| p.height()).sum(),
        Rgb([255, 255, 255]),
    );
    let mut y = 0i64;
    for part in parts {
        image::imageops::replace(&mut img, part, 0, y);
        y += part.height() as i64;
    }
    Ok(save_png(&img, path)?)
}
