//! The paper's Tables II (3:1) and III (4:1) laid out from eval summaries:
//! captors against the rule-based target, one row per (speed ratio, captors)
//! with SR [95% CI], Time and Path Len per map class, the protocol the
//! captors were trained under, and the paper's SR for the cell beside ours.
//! Markdown and LaTeX.

use super::{ratio_label, Summary};
use std::collections::BTreeMap;
use std::fmt::Write;
use t2e_core::env::CaptureRule;

/// Why eval results cannot be laid out as a table: two results for one
/// cell, or a row that would join results of different settings.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TableError {
    #[error("two results for one table cell ({cell}): {first} and {second}, which differ in {differences}; give only the eval folder whose result belongs in the table")]
    TwoResults {
        cell: String,
        first: String,
        second: String,
        differences: String,
    },
    /// A row would join results that are not one setting; `conflict` says
    /// which and how to fix it.
    #[error("one table row ({row}) would {conflict}")]
    NotOneSetting { row: String, conflict: String },
    #[error("none of the {0} summaries is on the Gibson classes (--maps small,medium,large): Table V pools those")]
    NoGibsonClass(usize),
    /// The embedded copy of the paper's tables does not parse.
    #[error("paper tables line {line}: {what}: {text}")]
    PaperCsv {
        line: usize,
        what: String,
        text: String,
    },
}

/// Every cell of the paper's Tables II, III and V (a copy of
/// ../shared/paper/tables.csv; a test keeps them equal): per table, K,
/// speed ratio, learner, target and map class, the paper's Time (steps),
/// SR % and Path Len (m). Paper protocol: trained and tested on the Gibson
/// maps, 30 M steps per run.
const PAPER_TABLES: &str = include_str!("paper_tables.csv");

/// One cell of the paper's tables.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperCell {
    pub table: String,
    pub num_captors: usize,
    pub speed_ratio: f64,
    pub learner: String,
    pub target: String,
    pub map_class: String,
    pub time: f64,
    pub sr: f64,
    pub path_len: f64,
}

/// The paper's cells, parsed once from the embedded CSV.
pub fn paper_cells() -> &'static [PaperCell] {
    static CELLS: std::sync::OnceLock<Vec<PaperCell>> = std::sync::OnceLock::new();
    CELLS.get_or_init(|| parse_paper_tables(PAPER_TABLES).expect("the embedded paper tables parse"))
}

fn parse_paper_tables(text: &str) -> Result<Vec<PaperCell>, TableError> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let bad = |what: &str| TableError::PaperCsv {
            line: n + 1,
            what: what.to_string(),
            text: line.to_string(),
        };
        if f.len() != 9 {
            return Err(bad("expected 9 fields"));
        }
        let num = |x: &str| -> Result<f64, TableError> {
            x.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(&format!("'{x}' is not a number")))
        };
        let ratio = f[2]
            .strip_prefix("1.0:")
            .ok_or_else(|| bad("speed ratio is not 1.0:R"))?;
        out.push(PaperCell {
            table: f[0].into(),
            num_captors: f[1].parse().map_err(|_| bad("K"))?,
            speed_ratio: num(ratio)?,
            learner: f[3].into(),
            target: f[4].into(),
            map_class: f[5].into(),
            time: num(f[6])?,
            sr: num(f[7])?,
            path_len: num(f[8])?,
        });
    }
    Ok(out)
}

pub(super) const CLASSES: [&str; 3] = ["small", "medium", "large"];

/// The paper's own cell for a row's learner against the rule-based target
/// (Table II or III): (SR, Time) per class, or None where the paper has no
/// such learner (a heuristic) or no such setting. Never another learner's.
pub fn paper_row(k: usize, ratio: f64, learner: &str) -> Option<[(f64, f64); 3]> {
    let mut row = [(f64::NAN, f64::NAN); 3];
    for (i, class) in CLASSES.iter().enumerate() {
        let cell = paper_cells().iter().find(|c| {
            c.table != "V"
                && c.num_captors == k
                && (c.speed_ratio - ratio).abs() < 1e-9
                && c.learner.eq_ignore_ascii_case(learner)
                && c.target == "rule-based"
                && c.map_class == *class
        })?;
        row[i] = (cell.sr, cell.time);
    }
    Some(row)
}

/// The paper's SR and Time for a row, as two cells of text ("-" where the
/// paper has no cell for this learner).
fn paper_text(k: usize, ratio: f64, learner: &str) -> (String, String) {
    match paper_row(k, ratio, learner) {
        Some(r) => (
            format!("{:.1} / {:.1} / {:.1}", r[0].0, r[1].0, r[2].0),
            format!("{:.0} / {:.0} / {:.0}", r[0].1, r[1].1, r[2].1),
        ),
        None => ("-".into(), "-".into()),
    }
}

/// A summary and where it was read (its eval folder's summary.json), so a
/// conflict can name both files.
pub type Sourced = (String, Summary);

/// One row: a (speed ratio, captors) pair and its summaries per class.
struct Row<'a> {
    ratio: f64,
    captors: String,
    learner: String,
    protocol: String,
    cells: [Option<&'a Sourced>; 3],
}

/// What differs between two summaries (the fields a reader cannot see in
/// the table), for conflict messages.
pub(super) fn differences(a: &Summary, b: &Summary) -> String {
    let mut d = Vec::new();
    let mut field = |name: &str, x: String, y: String| {
        if x != y {
            d.push(format!("{name} {x} vs {y}"));
        }
    };
    field("episodes", a.episodes.to_string(), b.episodes.to_string());
    field(
        "episode_length",
        a.episode_length.to_string(),
        b.episode_length.to_string(),
    );
    field(
        "capture_rule",
        format!("{:?}", a.capture_rule).to_lowercase(),
        format!("{:?}", b.capture_rule).to_lowercase(),
    );
    field("seed", a.seed.to_string(), b.seed.to_string());
    field(
        "learner",
        a.captors_learner.clone(),
        b.captors_learner.clone(),
    );
    if let (Some(x), Some(y)) = (&a.captors_sha256, &b.captors_sha256) {
        field(
            "captor weights (actor sha256)",
            x[..12.min(x.len())].to_string(),
            y[..12.min(y.len())].to_string(),
        );
    }
    if d.is_empty() {
        d.push(format!(
            "the same options but other results (SR {:.1} vs {:.1}, Time {:.1} vs {:.1}): other weights, maps or code behind the same names (compare setting.json in their setting folders)",
            a.sr, b.sr, a.time, b.time
        ));
    }
    d.join(", ")
}

/// Two summaries of one row (or one pooled pair) played by the same rules
/// with the same captors: episode length, capture rule, learner, and the
/// captor weights where both name them.
pub(super) fn same_play(a: &Summary, b: &Summary) -> bool {
    let other_weights = matches!(
        (&a.captors_sha256, &b.captors_sha256),
        (Some(x), Some(y)) if x != y
    );
    a.episode_length == b.episode_length
        && a.capture_rule == b.capture_rule
        && a.captors_learner == b.captors_learner
        && !other_weights
}

/// Groups the summaries into the paper's rows. Summaries against anything
/// but the rule-based target, or on maps other than the three classes, do
/// not belong in these tables: they are counted in the second value.
///
/// A table cell holds one result and a row one setting over the three
/// classes, so inputs that do not fit are refused, naming both files and
/// what differs, rather than one of them being picked or two settings being
/// shown as one: two different summaries for one cell (keeping either would
/// hide the other), and cells of one row with different episode counts,
/// episode lengths or capture rules (SR and Time would not compare across
/// the row), or of other captors behind one name (another learner, other
/// weights: `ckpt:RUN` is the run's newest checkpoint, which moves on while
/// the run trains). The same summary given twice (the same folder named twice) is
/// one result and is shown once. Rows may differ from each other in episode
/// count and length: the last column says it for each row.
type RowsByK<'a> = BTreeMap<usize, Vec<Row<'a>>>;

fn rows(summaries: &[Sourced]) -> Result<(RowsByK<'_>, usize), TableError> {
    let mut by_k: BTreeMap<usize, Vec<Row>> = BTreeMap::new();
    let mut left_out = 0;
    for sourced in summaries {
        let (source, s) = sourced;
        let class = CLASSES.iter().position(|c| *c == s.maps);
        let Some(class) = class.filter(|_| s.target == "heuristic") else {
            left_out += 1;
            continue;
        };
        let rows = by_k.entry(s.num_captors).or_default();
        let at = rows.iter().position(|r| {
            (r.ratio - s.speed_ratio).abs() < 1e-12
                && r.captors == s.captors
                && r.protocol == s.protocol
        });
        let i = match at {
            Some(i) => i,
            None => {
                rows.push(Row {
                    ratio: s.speed_ratio,
                    captors: s.captors.clone(),
                    learner: s.captors_learner.clone(),
                    protocol: s.protocol.clone(),
                    cells: [None; 3],
                });
                rows.len() - 1
            }
        };
        let what = format!(
            "{}:1 at v_p:v_e 1.0:{}, captors {} ({}), {}",
            s.num_captors,
            ratio_label(s.speed_ratio),
            s.captors,
            s.protocol,
            CLASSES[class]
        );
        if let Some((other_source, other)) = rows[i].cells[class] {
            if other == s {
                continue;
            }
            return Err(TableError::TwoResults {
                cell: what,
                first: other_source.to_string(),
                second: source.to_string(),
                differences: differences(other, s),
            });
        }
        for (other_source, other) in rows[i].cells.iter().flatten() {
            if other.episodes != s.episodes || !same_play(other, s) {
                return Err(TableError::NotOneSetting {
                    row: format!(
                        "{}:1 at v_p:v_e 1.0:{}, captors {} ({})",
                        s.num_captors,
                        ratio_label(s.speed_ratio),
                        s.captors,
                        s.protocol
                    ),
                    conflict: format!(
                        "join {} from {other_source} and {} from {source}, which differ in {}: a row is one setting over the three classes; evaluate the classes alike",
                        other.maps,
                        s.maps,
                        differences(other, s)
                    ),
                });
            }
        }
        rows[i].cells[class] = Some(sourced);
    }
    for rows in by_k.values_mut() {
        rows.sort_by(|a, b| a.ratio.total_cmp(&b.ratio).then(a.captors.cmp(&b.captors)));
    }
    Ok((by_k, left_out))
}

/// The row's episodes per class and their length, and the capture rule
/// when it is not the paper's fast one (the same for every cell of a row).
fn episodes_cell(cells: &[Option<&Sourced>; 3]) -> String {
    let Some((_, s)) = cells.iter().flatten().next() else {
        return "-".into();
    };
    format!(
        "{} x {} steps{}",
        s.episodes,
        s.episode_length,
        match s.capture_rule {
            CaptureRule::Fast => "",
            CaptureRule::Strict => ", strict capture",
        }
    )
}

fn triple(cells: &[Option<&Sourced>; 3], f: impl Fn(&Summary) -> String) -> Vec<String> {
    cells
        .iter()
        .map(|c| c.map(|(_, s)| f(s)).unwrap_or_else(|| "-".into()))
        .collect()
}

/// Markdown: one table per K, and a line per left-out summary count.
/// Refuses summaries that do not lay out as the paper's tables (`rows`).
pub fn markdown(summaries: &[Sourced]) -> Result<String, TableError> {
    let (by_k, left_out) = rows(summaries)?;
    let mut out = String::new();
    for (k, rows) in &by_k {
        let _ = writeln!(
            out,
            "### {k}:1 against the rule-based target (paper Table {})\n",
            if *k == 3 { "II" } else { "III" }
        );
        out.push_str("| v_p:v_e | captors | learner | protocol | SR % small | SR % medium | SR % large | paper SR % small / medium / large | Time (steps) s / m / l | paper Time s / m / l | Path Len (m) s / m / l | episodes per class |\n");
        out.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in rows {
            let sr = triple(&r.cells, |s| {
                format!("{:.1} [{:.1}, {:.1}]", s.sr, s.sr_low, s.sr_high)
            });
            let time = triple(&r.cells, |s| format!("{:.0}", s.time)).join(" / ");
            let path = triple(&r.cells, |s| format!("{:.1}", s.path_len)).join(" / ");
            let (paper, paper_time) = paper_text(*k, r.ratio, &r.learner);
            let episodes = episodes_cell(&r.cells);
            let _ = writeln!(
                out,
                "| 1.0:{} | {} | {} | {} | {} | {} | {} | {paper} | {time} | {paper_time} | {path} | {episodes} |",
                ratio_label(r.ratio),
                r.captors,
                r.learner,
                r.protocol,
                sr[0],
                sr[1],
                sr[2]
            );
        }
        out.push('\n');
    }
    out.push_str("Paper SR and Time: the same learner's cell of the paper's Table II / III (paper protocol: trained and tested on the Gibson maps, 30 M steps); - where the paper has no such learner (a heuristic).\n");
    if left_out > 0 {
        let _ = writeln!(out, "\n{left_out} summaries left out: against another target than the rule-based one, or on maps other than the three Gibson classes.");
    }
    Ok(out)
}

fn latex_escape(s: &str) -> String {
    s.replace('\\', "\\textbackslash{}")
        .replace('_', "\\_")
        .replace('%', "\\%")
        .replace('&', "\\&")
        .replace('#', "\\#")
}

/// LaTeX (booktabs): one tabular per K, SR with its interval, paper SR beside.
pub fn latex(summaries: &[Sourced]) -> Result<String, TableError> {
    let (by_k, _) = rows(summaries)?;
    let mut out = String::from("% t2e-league table: captors against the rule-based target; requires \\usepackage{booktabs}\n");
    for (k, rows) in &by_k {
        let _ = writeln!(out, "\\begin{{table}}[t]\n\\centering\n\\caption{{{k}:1 against the rule-based target. SR \\% [95\\% CI] per map class; paper SR from its Table {} (paper protocol).}}", if *k == 3 { "II" } else { "III" });
        out.push_str("\\begin{tabular}{lllllllll}\n\\toprule\n$v_p{:}v_e$ & Learner & Protocol & Small & Medium & Large & Paper (S / M / L) & Time (S / M / L) & Episodes per class \\\\\n\\midrule\n");
        for r in rows {
            let sr = triple(&r.cells, |s| {
                format!("{:.1} [{:.1}, {:.1}]", s.sr, s.sr_low, s.sr_high)
            });
            let time = triple(&r.cells, |s| format!("{:.0}", s.time)).join(" / ");
            let (paper, _) = paper_text(*k, r.ratio, &r.learner);
            let _ = writeln!(
                out,
                "1.0:{} & {} & {} & {} & {} & {} & {} & {} & {} \\\\",
                ratio_label(r.ratio),
                latex_escape(&r.learner),
                latex_escape(&r.protocol),
                sr[0],
                sr[1],
                sr[2],
                latex_escape(&paper),
                time,
                latex_escape(&episodes_cell(&r.cells))
            );
        }
        out.push_str("\\bottomrule\n\\end{tabular}\n\\end{table}\n\n");
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sourced(s: Vec<Summary>) -> Vec<Sourced> {
        s.into_iter()
            .enumerate()
            .map(|(i, s)| (format!("eval{i}/summary.json"), s))
            .collect()
    }

    fn summary(k: usize, ratio: f64, maps: &str, target: &str, learner: &str, sr: f64) -> Summary {
        Summary {
            captors: format!("ckpt:runs/{learner}"),
            captors_learner: learner.into(),
            captors_sha256: None,
            target: target.into(),
            num_captors: k,
            speed_ratio: ratio,
            maps: maps.into(),
            protocol: "held-out".into(),
            episodes: 500,
            episode_length: 500,
            seed: 0,
            capture_rule: CaptureRule::Fast,
            soa_every: 0,
            time: 300.0,
            sr,
            sr_low: sr - 4.0,
            sr_high: sr + 4.0,
            path_len: 25.0,
            mean_soa_m2: None,
            target_departure: None,
            target_departure_places: None,
            soa_curve: Vec::new(),
        }
    }

    #[test]
    fn rows_gather_the_classes_and_put_the_papers_number_beside_ours() {
        let s = vec![
            summary(3, 1.0, "small", "heuristic", "MAPPO", 85.8),
            summary(3, 1.0, "large", "heuristic", "MAPPO", 63.0),
            summary(3, 1.0, "medium", "heuristic", "MAPPO", 74.6),
            summary(3, 1.2, "medium", "heuristic", "IPPO", 40.0),
            summary(3, 1.0, "medium", "ckpt:runs/x", "MAPPO", 10.0),
            summary(4, 1.4, "small", "heuristic", "IPPO", 50.0),
        ];
        let s = sourced(s);
        let md = markdown(&s).unwrap();
        assert!(md.contains("| 1.0:1.0 | ckpt:runs/MAPPO | MAPPO | held-out | 85.8 [81.8, 89.8] | 74.6 [70.6, 78.6] | 63.0 [59.0, 67.0] | 99.8 / 99.8 / 94.8 | 300 / 300 / 300 | 101 / 130 / 185 |"), "{md}");
        // IPPO at 3:1, 1.2: IPPO's own cell (Table II), never MAPPO's.
        assert!(md.contains("| IPPO | held-out | - | 40.0 [36.0, 44.0] | - | 84.8 / 64.8 / 68.4 | - / 300 / - | 222 / 319 / 323 |"), "{md}");
        // A heuristic has no cell in the paper: none is borrowed.
        let heuristic = Summary {
            captors: "heuristic".into(),
            captors_learner: "expert heuristic".into(),
            ..summary(3, 1.0, "small", "heuristic", "x", 78.4)
        };
        let hmd = markdown(&sourced(vec![heuristic])).unwrap();
        assert!(hmd.contains("| - | 300 / - / - | - |"), "{hmd}");
        assert!(!hmd.contains("99.8"), "{hmd}");
        assert!(md.contains("| 1.0:1.4 | ckpt:runs/IPPO | IPPO | held-out | 50.0 [46.0, 54.0] | - | - | 94.0 / 86.2 / 87.6 |"), "{md}");
        assert!(md.contains("Table II") && md.contains("Table III"));
        assert!(md.contains("1 summaries left out"), "{md}");
        assert!(md.contains("| 500 x 500 steps |"), "{md}");
        let tex = latex(&s).unwrap();
        assert!(
            tex.contains("1.0:1.0 & MAPPO & held-out & 85.8 [81.8, 89.8]"),
            "{tex}"
        );
        assert_eq!(tex.matches("\\begin{tabular}").count(), 2);
    }

    #[test]
    fn every_paper_cell_is_there_once_and_matches_the_shared_copy() {
        let cells = paper_cells();
        assert_eq!(cells.len(), 80);
        // Tables II and III: 4 learners x 3 ratios x 3 classes, per K.
        for k in [3, 4] {
            for ratio in [1.0, 1.2, 1.4] {
                for learner in ["MAPPO", "IPPO", "MADDPG", "MAAC"] {
                    assert!(
                        paper_row(k, ratio, learner).is_some(),
                        "{k} {ratio} {learner}"
                    );
                }
            }
        }
        assert_eq!(
            paper_row(3, 1.0, "mappo").unwrap(),
            [(99.8, 100.71), (99.8, 129.52), (94.8, 185.44)]
        );
        assert!(paper_row(3, 1.0, "expert heuristic").is_none());
        assert!(
            parse_paper_tables("h\nII,3,1.0:1.0,MAPPO,rule-based,small,x,1,1\n")
                .unwrap_err()
                .to_string()
                .contains("line 2")
        );
        let shared =
            std::path::Path::new(t2e_core::PROJECT_ROOT).join("../shared/paper/tables.csv");
        if let Ok(text) = std::fs::read_to_string(&shared) {
            assert_eq!(
                text,
                PAPER_TABLES,
                "crates/learners/src/eval/paper_tables.csv differs from {}",
                shared.display()
            );
        }
    }

    #[test]
    fn a_cell_holds_one_result_and_a_row_one_setting() {
        let base = summary(3, 1.0, "small", "heuristic", "MAPPO", 85.8);
        // The same summary twice (one folder named twice): shown once.
        let md = markdown(&sourced(vec![base.clone(), base.clone()])).unwrap();
        assert_eq!(md.matches("| 85.8 [").count(), 1, "{md}");
        // Two results for one cell: refused, naming both files and the difference.
        let other = Summary {
            episodes: 100,
            seed: 3,
            sr: 80.0,
            ..base.clone()
        };
        let err = markdown(&sourced(vec![base.clone(), other]))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("two results for one table cell (3:1 at v_p:v_e 1.0:1.0, captors ckpt:runs/MAPPO (held-out), small)")
                && err.contains("eval0/summary.json and eval1/summary.json")
                && err.contains("episodes 500 vs 100, seed 0 vs 3"),
            "{err}"
        );
        let same_options = Summary {
            sr: 80.0,
            ..base.clone()
        };
        let err = latex(&sourced(vec![base.clone(), same_options]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("SR 85.8 vs 80.0"), "{err}");
        // Cells of one row from settings of other lengths or counts: refused.
        for other in [
            Summary {
                maps: "large".into(),
                episode_length: 300,
                ..base.clone()
            },
            Summary {
                maps: "large".into(),
                episodes: 50,
                ..base.clone()
            },
            Summary {
                maps: "large".into(),
                capture_rule: CaptureRule::Strict,
                ..base.clone()
            },
        ] {
            let err = markdown(&sourced(vec![base.clone(), other]))
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("one table row")
                    && err.contains(
                        "small from eval0/summary.json and large from eval1/summary.json"
                    ),
                "{err}"
            );
        }
        // Other weights behind the same checkpoint name, in one row: refused.
        let weights = |maps: &str, sha: &str| Summary {
            maps: maps.into(),
            captors_sha256: Some(sha.repeat(64)),
            ..base.clone()
        };
        let err = markdown(&sourced(vec![weights("small", "a"), weights("large", "b")]))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("captor weights (actor sha256) aaaaaaaaaaaa vs bbbbbbbbbbbb"),
            "{err}"
        );
        // Rows may differ from each other; each says its episodes and length.
        let strict = Summary {
            captors: "ckpt:runs/strict".into(),
            capture_rule: CaptureRule::Strict,
            episode_length: 300,
            ..base.clone()
        };
        let md = markdown(&sourced(vec![base, strict])).unwrap();
        assert!(md.contains("| 500 x 300 steps, strict capture |"), "{md}");
    }
}
