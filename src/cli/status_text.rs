//! `status` as text: the tables a person reads in a terminal.

use league::rules::players::EVALUATOR;
use league::run::status::*;
use std::fmt::Write as _;
use t2e_core::env::Side;

/// The report as text: players, exploitability, learners, curriculum,
/// payoff matrix, panel, seats, crashes; each section its own function.
pub fn render(r: &StatusReport) -> String {
    let mut s = String::new();
    let sections: [fn(&mut String, &StatusReport); 7] =
        [players, exploits, learners, payoff, panel, seats, crashes];
    for section in sections {
        section(&mut s, r);
    }
    s
}

/// The players, best Bradley-Terry Elo first.
fn players(s: &mut String, r: &StatusReport) {
    let _ = writeln!(
        s,
        "league {} ({}), {} matches\n",
        r.league, r.dir, r.matches
    );
    let _ = writeln!(
        s,
        "{:>3}  {:<26} {:<8} {:<9} {:>6} {:>11} {:>15} {:>8} {:>6} {:>7}",
        "id", "player", "side", "kind", "parent", "env steps", "rating", "BT Elo", "games", "win %"
    );
    let mut players = r.players.clone();
    players.sort_by(|a, b| b.bt_elo.total_cmp(&a.bt_elo));
    for p in &players {
        let _ = writeln!(
            s,
            "{:>3}  {:<26} {:<8} {:<9} {:>6} {:>11} {:>8.2} ± {:<4.2} {:>8.0} {:>6} {:>7}{}",
            p.id,
            p.name,
            p.side.name(),
            p.kind.name(),
            p.parent
                .map(|x| x.to_string())
                .unwrap_or_else(|| "-".into()),
            p.env_steps,
            p.rating,
            p.rating_sigma,
            p.bt_elo,
            p.games,
            p.win_rate
                .map(|w| format!("{:.1}", 100.0 * w))
                .unwrap_or_else(|| "-".into()),
            p.quarantined
                .as_ref()
                .map(|q| format!("  QUARANTINED: {q}"))
                .unwrap_or_default()
        );
    }
}

/// Each `exploit` result with its interval.
fn exploits(s: &mut String, r: &StatusReport) {
    if !r.exploits.is_empty() {
        let _ = writeln!(
            s,
            "\nexploitability (`exploit`: a fresh best response trained against the frozen player; its win %):"
        );
        let _ = writeln!(
            s,
            "  {:<26} {:<26} {:<14} {:<16} {:>11} {:<10} {:>8} {:>7}  95% interval",
            "player",
            "frozen weights",
            "best response",
            "budget",
            "BR steps",
            "maps",
            "episodes",
            "win %"
        );
        for e in &r.exploits {
            let _ = writeln!(
                s,
                "  {:<26} {:<26} {:<14} {:<16} {:>11} {:<10} {:>8} {:>7.1}  [{:.1}, {:.1}]{}",
                e.player_name,
                frozen_label(e),
                e.best_response,
                e.budget,
                e.env_steps,
                e.maps,
                e.episodes,
                100.0 * e.win_rate,
                100.0 * e.win_rate_low,
                100.0 * e.win_rate_high,
                if e.outdated {
                    "  OLDER VERSION of the player"
                } else {
                    ""
                }
            );
        }
    }
}

/// Each learner's progress and heartbeat, then the curriculum.
fn learners(s: &mut String, r: &StatusReport) {
    let _ = writeln!(s, "\nlearners:");
    for l in &r.learners {
        if l.name == EVALUATOR {
            let _ = writeln!(
                s,
                "  {:<14} {:<9} {:>11} panel episodes                last heartbeat {:.0} s ago (pid {} on {})",
                l.name, l.state, l.env_steps, l.heartbeat_age_s, l.pid, l.host.as_deref().unwrap_or("?")
            );
            continue;
        }
        let _ = writeln!(
            s,
            "  {:<14} {:<9} {:>11} env steps {:>7.0} steps/s  last heartbeat {:.0} s ago (pid {} on {})",
            l.name, l.state, l.env_steps, l.steps_per_s, l.heartbeat_age_s, l.pid, l.host.as_deref().unwrap_or("?")
        );
    }
    let _ = writeln!(
        s,
        "\ncurriculum: stage {} (speed ratio 1.0:{})",
        r.curriculum.stage,
        t2e_learners::eval::ratio_label(r.curriculum.speed_ratio)
    );
    for h in &r.curriculum.history {
        let _ = writeln!(
            s,
            "  -> stage {} (1.0:{}): {}",
            h.stage, h.speed_ratio, h.reason
        );
    }
}

/// Captor win % per (captors, target) pair.
fn payoff(s: &mut String, r: &StatusReport) {
    let name = |id: i64| {
        r.players
            .iter()
            .find(|p| p.id == id)
            .map(|p| p.name.clone())
            .unwrap_or_else(|| id.to_string())
    };
    let captors: Vec<i64> = r
        .players
        .iter()
        .filter(|p| p.side == Side::Captors)
        .map(|p| p.id)
        .collect();
    let targets: Vec<i64> = r
        .players
        .iter()
        .filter(|p| p.side == Side::Target)
        .map(|p| p.id)
        .collect();
    let _ = writeln!(
        s,
        "\npayoff (captor win % / games; rows captors, columns targets):"
    );
    let _ = write!(s, "{:<26}", "");
    for t in &targets {
        let _ = write!(s, " {:>14}", format!("#{t}"));
    }
    let _ = writeln!(s);
    for c in &captors {
        let _ = write!(s, "{:<26}", name(*c));
        for t in &targets {
            let cell = r
                .payoff
                .iter()
                .find(|p| p.captor == *c && p.target == *t)
                .map(|p| {
                    format!(
                        "{:.0}% / {}",
                        100.0 * p.captor_wins as f64 / p.games as f64,
                        p.games
                    )
                })
                .unwrap_or_else(|| "-".into());
            let _ = write!(s, " {cell:>14}");
        }
        let _ = writeln!(s);
    }
    for t in &targets {
        let _ = writeln!(s, "  #{t} = {}", name(*t));
    }
}

/// The evaluator's panel games.
fn panel(s: &mut String, r: &StatusReport) {
    if !r.panel.is_empty() {
        let _ = writeln!(
            s,
            "\npanel (the evaluator's episodes only; the opponents are league members, or held out: never met in the league; validation teams play the validation maps and choose `export --best`):"
        );
        let _ = writeln!(
            s,
            "  {:<30} {:<24} {:>8} {:>7}  95% interval",
            "member", "opponent", "episodes", "win %"
        );
        for p in &r.panel {
            let _ = writeln!(
                s,
                "  {:<30} {:<24} {:>8} {:>7.1}  [{:.1}, {:.1}]",
                p.member_name,
                p.opponent_label(),
                p.episodes,
                100.0 * p.win_rate,
                100.0 * p.win_rate_low,
                100.0 * p.win_rate_high
            );
        }
    }
}

/// Seats run by workers.
fn seats(s: &mut String, r: &StatusReport) {
    if !r.seats.is_empty() {
        let _ = writeln!(s, "\nseats (run by workers):");
        for seat in &r.seats {
            let _ = writeln!(
                s,
                "  {:<18} {:<7} {}taken {} times{}",
                seat.name,
                seat.state,
                match (&seat.host, seat.lease_left_s) {
                    (Some(h), Some(left)) => format!("on {h}, lease {left:.0} s left; "),
                    _ => String::new(),
                },
                seat.claims,
                seat.reason
                    .as_deref()
                    .map(|r| format!(": {r}"))
                    .unwrap_or_default()
            );
        }
    }
}

/// Each crash's last line.
fn crashes(s: &mut String, r: &StatusReport) {
    if !r.crashes.is_empty() {
        let _ = writeln!(s, "\ncrashes:");
        for c in &r.crashes {
            let _ = writeln!(
                s,
                "  {} ({}): {}",
                c.learner,
                c.exit_status,
                c.message.lines().last().unwrap_or("")
            );
        }
    }
}
