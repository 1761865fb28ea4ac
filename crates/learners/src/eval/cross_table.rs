//! The paper's Table V laid out from eval summaries: captors against several
//! targets (the rule-based one and learned ones), one row per (captors,
//! target) pair with SR, Time and Path Len per map class and pooled over the
//! classes, a grid of the pooled SR for a glance, and the paper's Table V
//! cells for each learner beside ours. Markdown.
//!
//! The paper's Table V has one number per cell ("all" maps): co-evolved
//! captors against the rule-based target and against the target they
//! co-evolved with. Pooling here is over the episodes actually played, so a
//! pooled cell is one binomial sample with its own Wilson interval.

use super::paper_table::{differences, paper_cells, same_play, Sourced, TableError, CLASSES};
use super::{ratio_label, wilson_interval, Summary};
use std::collections::BTreeMap;
use std::fmt::Write;
use t2e_core::env::CaptureRule;

/// One (captors, target) pair at one K and speed ratio: its summaries per
/// class.
struct Pair<'a> {
    captors: String,
    learner: String,
    protocol: String,
    target: String,
    cells: [Option<&'a Sourced>; 3],
}

/// A pair's cells pooled over the classes it was evaluated on.
#[derive(Clone, Debug, PartialEq)]
pub struct Pooled {
    pub captures: usize,
    pub episodes: usize,
    /// SR % and its 95% Wilson interval.
    pub sr: f64,
    pub sr_low: f64,
    pub sr_high: f64,
    /// Episode-weighted means.
    pub time: f64,
    pub path_len: f64,
}

/// Captures of one summary: SR is captures / episodes x 100 in f64, so the
/// rounding recovers the count exactly.
fn captures(s: &Summary) -> usize {
    (s.sr * s.episodes as f64 / 100.0).round() as usize
}

/// Pools summaries of one setting over map classes (every episode counts
/// once), or None for none.
pub fn pool<'a>(cells: impl IntoIterator<Item = &'a Summary>) -> Option<Pooled> {
    let (mut caught, mut n, mut time, mut path) = (0usize, 0usize, 0.0, 0.0);
    for s in cells {
        caught += captures(s);
        n += s.episodes;
        time += s.time * s.episodes as f64;
        path += s.path_len * s.episodes as f64;
    }
    if n == 0 {
        return None;
    }
    let (low, high) = wilson_interval(caught, n);
    Some(Pooled {
        captures: caught,
        episodes: n,
        sr: 100.0 * caught as f64 / n as f64,
        sr_low: 100.0 * low,
        sr_high: 100.0 * high,
        time: time / n as f64,
        path_len: path / n as f64,
    })
}

/// How a controller spec reads in the table: the rule-based target and
/// the expert captors by their names in the paper.
fn target_name(spec: &str) -> String {
    match spec {
        "heuristic" => "rule-based".into(),
        other => other.into(),
    }
}

/// The paper's Table V cell of a learner: (SR, Time, Path Len) against the
/// rule-based target when `learned` is false, else against the target it
/// co-evolved with. None for a learner the paper does not have.
pub fn paper_cell(learner: &str, learned: bool) -> Option<(f64, f64, f64)> {
    let target = if learned { "learned" } else { "rule-based" };
    paper_cells()
        .iter()
        .find(|c| c.table == "V" && c.learner.eq_ignore_ascii_case(learner) && c.target == target)
        .map(|c| (c.sr, c.time, c.path_len))
}

type Sections<'a> = BTreeMap<(usize, u64), Vec<Pair<'a>>>;

/// Groups the summaries into pairs, per (K, speed ratio). Refused, naming
/// both files: two different results for one cell, and cells of one pair
/// that cannot be pooled (other episode lengths or capture rules, other
/// captors behind one name). Unlike Tables II and III, the episode counts
/// of a pair's classes may differ: pooling weighs each episode once.
fn pairs(summaries: &[Sourced]) -> Result<(Sections<'_>, usize), TableError> {
    let mut sections: Sections = BTreeMap::new();
    let mut left_out = 0;
    for sourced in summaries {
        let (_, s) = sourced;
        let Some(class) = CLASSES.iter().position(|c| *c == s.maps) else {
            left_out += 1;
            continue;
        };
        let pairs = sections
            .entry((s.num_captors, s.speed_ratio.to_bits()))
            .or_default();
        // One pair per (captors, target), whatever the protocol says: two
        // protocols under one name are refused below, not shown as two
        // lines of which the grid would show one.
        let at = pairs
            .iter()
            .position(|p| p.captors == s.captors && p.target == s.target);
        let i = at.unwrap_or_else(|| {
            pairs.push(Pair {
                captors: s.captors.clone(),
                learner: s.captors_learner.clone(),
                protocol: s.protocol.clone(),
                target: s.target.clone(),
                cells: [None; 3],
            });
            pairs.len() - 1
        });
        let what = format!(
            "{}:1 at v_p:v_e 1.0:{}, captors {} ({}) against {}",
            s.num_captors,
            ratio_label(s.speed_ratio),
            s.captors,
            s.protocol,
            target_name(&s.target)
        );
        if !admits(&pairs[i], class, sourced, what)? {
            continue;
        }
        pairs[i].cells[class] = Some(sourced);
    }
    for pairs in sections.values_mut() {
        sort_pairs(pairs);
    }
    Ok((sections, left_out))
}

/// Whether `sourced` may fill `class` of `pair`: `false` for the same result
/// met twice, an error for a conflict. Apart from `pairs` so each refusal
/// reads beside its message.
fn admits(pair: &Pair, class: usize, sourced: &Sourced, what: String) -> Result<bool, TableError> {
    let (source, s) = sourced;
    if pair.protocol != s.protocol {
        let (other_source, _) = pair.cells.iter().flatten().next().expect("a cell");
        return Err(TableError::NotOneSetting {
            row: what,
            conflict: format!(
                "pool results of players trained under the {} protocol ({other_source}) and the {} protocol ({source}): other weights behind one name; give one of them",
                pair.protocol, s.protocol
            ),
        });
    }
    if let Some((other_source, other)) = pair.cells[class] {
        if other == s {
            return Ok(false);
        }
        return Err(TableError::TwoResults {
            cell: format!("{what}, {}", CLASSES[class]),
            first: other_source.to_string(),
            second: source.to_string(),
            differences: differences(other, s),
        });
    }
    for (other_source, other) in pair.cells.iter().flatten() {
        if !same_play(other, s) {
            return Err(TableError::NotOneSetting {
                row: what,
                conflict: format!(
                    "pool {} from {other_source} and {} from {source}, which differ in {}: pooled classes must be one setting; evaluate them alike",
                    other.maps,
                    s.maps,
                    differences(other, s)
                ),
            });
        }
    }
    Ok(true)
}

/// The order a section's pairs are shown in; one place so the grid and the
/// full rows agree.
fn sort_pairs(pairs: &mut [Pair]) {
    pairs.sort_by(|a, b| {
        a.captors
            .cmp(&b.captors)
            // The rule-based target first, as in the paper.
            .then((a.target != "heuristic").cmp(&(b.target != "heuristic")))
            .then(a.target.cmp(&b.target))
            .then(a.protocol.cmp(&b.protocol))
    });
}

fn pooled_of(p: &Pair) -> Option<Pooled> {
    pool(p.cells.iter().flatten().map(|(_, s)| s))
}

/// A section's grid of pooled SR, captors by target; apart from `markdown`
/// so each of its two tables is one function.
fn write_grid(out: &mut String, pairs: &[Pair]) {
    // The grid: one line per captors (and protocol), one column per target.
    let mut targets: Vec<&str> = pairs.iter().map(|p| p.target.as_str()).collect();
    targets.sort_by(|a, b| (*a != "heuristic").cmp(&(*b != "heuristic")).then(a.cmp(b)));
    targets.dedup();
    out.push_str(
        "SR % pooled over the classes played [95% Wilson interval]:\n\n| captors | protocol |",
    );
    for t in &targets {
        let _ = write!(out, " vs {} |", target_name(t));
    }
    out.push_str("\n|---|---|");
    out.push_str(&"---|".repeat(targets.len()));
    out.push('\n');
    // One line per captors: a heuristic's pairs say "-" against the
    // rule-based target and the learned target's protocol otherwise.
    let mut lines: Vec<&str> = pairs.iter().map(|p| p.captors.as_str()).collect();
    lines.dedup();
    for captors in &lines {
        let mut protocols: Vec<&str> = pairs
            .iter()
            .filter(|p| p.captors == *captors && p.protocol != "-")
            .map(|p| p.protocol.as_str())
            .collect();
        protocols.sort();
        protocols.dedup();
        let protocols = if protocols.is_empty() {
            "-".to_string()
        } else {
            protocols.join(", ")
        };
        let _ = write!(out, "| {captors} | {protocols} |");
        for t in &targets {
            let cell = pairs
                .iter()
                .find(|p| p.captors == *captors && p.target == *t)
                .and_then(pooled_of);
            match cell {
                Some(c) => {
                    let _ = write!(out, " {:.1} [{:.1}, {:.1}] |", c.sr, c.sr_low, c.sr_high);
                }
                None => out.push_str(" - |"),
            }
        }
        out.push('\n');
    }
}

/// One pair's line of the full table; apart from `markdown` because its
/// per-class columns are the bulk of the formatting.
fn write_full_row(out: &mut String, p: &Pair) {
    let sr: Vec<String> = p
        .cells
        .iter()
        .map(|c| match c {
            Some((_, s)) => format!("{:.1} [{:.1}, {:.1}]", s.sr, s.sr_low, s.sr_high),
            None => "-".into(),
        })
        .collect();
    let per_class = |f: &dyn Fn(&Summary) -> String| -> Vec<String> {
        p.cells
            .iter()
            .map(|c| c.map(|(_, s)| f(s)).unwrap_or_else(|| "-".into()))
            .collect()
    };
    let pooled = pooled_of(p).expect("a pair holds at least one cell");
    let mut time = per_class(&|s| format!("{:.0}", s.time));
    time.push(format!("{:.0}", pooled.time));
    let mut path = per_class(&|s| format!("{:.1}", s.path_len));
    path.push(format!("{:.1}", pooled.path_len));
    let episodes = per_class(&|s| s.episodes.to_string()).join(" / ");
    let (_, first) = p.cells.iter().flatten().next().expect("a cell");
    let length = format!(
        "{episodes} x {} steps{}",
        first.episode_length,
        match first.capture_rule {
            CaptureRule::Fast => "",
            CaptureRule::Strict => ", strict capture",
        }
    );
    let paper = match paper_cell(&p.learner, p.target != "heuristic") {
        Some((sr, time, path)) => format!("{sr:.1} / {time:.0} / {path:.1}"),
        None => "-".into(),
    };
    let _ = writeln!(
        out,
        "| {} | {} | {} | {} | {} | {} | {} | {:.1} [{:.1}, {:.1}] | {} | {} | {length} | {paper} |",
        p.captors,
        p.learner,
        p.protocol,
        target_name(&p.target),
        sr[0],
        sr[1],
        sr[2],
        pooled.sr,
        pooled.sr_low,
        pooled.sr_high,
        time.join(" / "),
        path.join(" / "),
    );
}

/// Markdown: per (K, speed ratio) a grid of the pooled SR (rows captors,
/// columns targets), the rows in full, and the paper's Table V cells of
/// every learner that appears. Refuses summaries that do not lay out
/// (`pairs`); summaries on maps other than the three Gibson classes are
/// counted and left out.
pub fn markdown(summaries: &[Sourced]) -> Result<String, TableError> {
    let (sections, left_out) = pairs(summaries)?;
    if sections.is_empty() {
        return Err(TableError::NoGibsonClass(summaries.len()));
    }
    let mut out = String::new();
    for ((k, ratio), pairs) in &sections {
        let ratio = ratio_label(f64::from_bits(*ratio));
        let _ = writeln!(
            out,
            "### {k}:1 at v_p:v_e 1.0:{ratio}, captors against each target (paper Table V)\n"
        );
        write_grid(&mut out, pairs);
        out.push_str("\nEvery pair in full (- where a class was not played):\n\n");
        out.push_str("| captors | learner | protocol | target | SR % small | SR % medium | SR % large | SR % pooled | Time (steps) s / m / l / pooled | Path Len (m) s / m / l / pooled | episodes per class | paper's Table V, same learner: SR / Time / Path Len |\n");
        out.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for p in pairs {
            write_full_row(&mut out, p);
        }
        out.push('\n');
    }
    out.push_str("Paper's Table V: the same learner's captors after naive co-evolution (paper protocol: trained and tested on the Gibson maps, 30 M steps), all classes together; against the rule-based target on rows against it, else against the target they co-evolved with. - where the paper has no such learner (a heuristic).\n");
    if left_out > 0 {
        let _ = writeln!(
            out,
            "\n{left_out} summaries left out: on maps other than the three Gibson classes."
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(captors: &str, target: &str, maps: &str, caught: usize, n: usize) -> Sourced {
        let (low, high) = wilson_interval(caught, n);
        let s = Summary {
            captors: captors.into(),
            captors_learner: if captors.starts_with("ckpt:") {
                "MAPPO".into()
            } else {
                "expert heuristic".into()
            },
            captors_sha256: None,
            target: target.into(),
            num_captors: 3,
            speed_ratio: 1.0,
            maps: maps.into(),
            protocol: if captors.starts_with("ckpt:") || target.starts_with("ckpt:") {
                "held-out".into()
            } else {
                "-".into()
            },
            episodes: n,
            episode_length: 500,
            seed: 0,
            capture_rule: CaptureRule::Fast,
            soa_every: 0,
            time: if maps == "small" { 200.0 } else { 400.0 },
            sr: 100.0 * caught as f64 / n as f64,
            sr_low: 100.0 * low,
            sr_high: 100.0 * high,
            path_len: if maps == "small" { 10.0 } else { 30.0 },
            mean_soa_m2: None,
            target_departure: None,
            target_departure_places: None,
            soa_curve: Vec::new(),
        };
        (format!("{captors}-{target}-{maps}/summary.json"), s)
    }

    #[test]
    fn pooling_counts_every_episode_once() {
        // 50 of 100 small, 30 of 100 medium, 7 of 50 large: 87 of 250.
        let cells = [
            summary("ckpt:a", "heuristic", "small", 50, 100),
            summary("ckpt:a", "heuristic", "medium", 30, 100),
            summary("ckpt:a", "heuristic", "large", 7, 50),
        ];
        let p = pool(cells.iter().map(|(_, s)| s)).unwrap();
        assert_eq!((p.captures, p.episodes), (87, 250));
        assert!((p.sr - 34.8).abs() < 1e-9);
        // Time: (200 x 100 + 400 x 150) / 250 = 320; Path Len (10 x 100 + 30 x 150) / 250 = 22.
        assert!((p.time - 320.0).abs() < 1e-9 && (p.path_len - 22.0).abs() < 1e-9);
        let (low, high) = wilson_interval(87, 250);
        assert_eq!((p.sr_low, p.sr_high), (100.0 * low, 100.0 * high));
        assert!(pool(std::iter::empty()).is_none());
    }

    #[test]
    fn the_grid_puts_the_rule_based_target_first_and_the_papers_cells_beside() {
        let s = vec![
            summary("ckpt:league", "ckpt:coevo-target", "medium", 28, 100),
            summary("ckpt:league", "heuristic", "medium", 44, 100),
            summary("ckpt:league", "heuristic", "small", 60, 100),
            summary("heuristic", "ckpt:coevo-target", "medium", 29, 100),
            summary("ckpt:league", "heuristic", "shipped", 1, 10),
        ];
        let md = markdown(&s).unwrap();
        assert!(
            md.contains("| captors | protocol | vs rule-based | vs ckpt:coevo-target |"),
            "{md}"
        );
        // 104 of 200 pooled over small and medium.
        let (low, high) = wilson_interval(104, 200);
        let pooled = format!("52.0 [{:.1}, {:.1}]", 100.0 * low, 100.0 * high);
        assert!(
            md.contains(&format!("| ckpt:league | held-out | {pooled} | 28.0 [")),
            "{md}"
        );
        // The expert never played the rule-based target here: a dash.
        assert!(md.contains("| heuristic | held-out | - | 29.0 ["), "{md}");
        // A heuristic against both: one line, "-" (no training) dropped.
        let both = markdown(&[
            summary("heuristic", "heuristic", "medium", 75, 100),
            summary("heuristic", "ckpt:t", "medium", 66, 100),
        ])
        .unwrap();
        assert!(both.contains("| heuristic | held-out | 75.0 ["), "{both}");
        // MAPPO's own Table V cells: 95.8 against the rule-based target, 99.8
        // against its co-evolved one; none for a heuristic.
        assert!(
            md.contains("| 100 / 100 / - x 500 steps | 95.8 / 159 / 15.7 |"),
            "{md}"
        );
        assert!(
            md.contains("| - / 100 / - x 500 steps | 99.8 / 46 / 4.4 |"),
            "{md}"
        );
        assert!(md.contains("| rule-based | 60.0 ["), "{md}");
        assert!(md.contains("| 200 / 400 / - / 300 |"), "{md}");
        assert!(md.contains("1 summaries left out"), "{md}");
        assert!(paper_cell("expert heuristic", false).is_none());
        assert_eq!(paper_cell("maddpg", false), Some((27.2, 433.98, 39.919)));
    }

    #[test]
    fn a_pair_pools_one_setting_and_a_cell_holds_one_result() {
        let base = summary("ckpt:a", "heuristic", "small", 50, 100);
        let twice = markdown(&[base.clone(), base.clone()]).unwrap();
        assert_eq!(twice.matches("| ckpt:a | MAPPO |").count(), 1, "{twice}");
        let mut other = base.clone();
        other.0 = "elsewhere/summary.json".into();
        other.1.sr = 40.0;
        let err = markdown(&[base.clone(), other]).unwrap_err().to_string();
        assert!(
            err.contains("two results for one table cell")
                && err.contains("ckpt:a-heuristic-small/summary.json and elsewhere/summary.json"),
            "{err}"
        );
        let mut longer = summary("ckpt:a", "heuristic", "large", 10, 100);
        longer.1.episode_length = 300;
        let err = markdown(&[base.clone(), longer]).unwrap_err().to_string();
        assert!(
            err.contains("would pool small from") && err.contains("episode_length 500 vs 300"),
            "{err}"
        );
        // Other episode counts per class pool fine: each episode once.
        let mut paper = summary("ckpt:a", "heuristic", "medium", 10, 100);
        paper.1.protocol = "paper".into();
        let err = markdown(&[base.clone(), paper]).unwrap_err().to_string();
        assert!(
            err.contains("the held-out protocol") && err.contains("the paper protocol"),
            "{err}"
        );
        let fewer = summary("ckpt:a", "heuristic", "large", 10, 50);
        assert!(markdown(&[base, fewer])
            .unwrap()
            .contains("| 100 / - / 50 x 500 steps |"));
        let err = markdown(&[summary("ckpt:a", "heuristic", "shipped", 1, 10)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("none of the 1 summaries"), "{err}");
    }
}
