//! The front page's figures are the pages' figures: every number in a row
//! of a table under README.md's "Results at a glance" appears on the page
//! that row links to (a row without a link answers to the link in the
//! paragraph above its table). A figure updated on its page and not on the
//! front page, or the reverse, fails here.

use super::links::link_targets;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Number tokens: digits with inner `.` or `,` between digits (`1,378`,
/// `99.4`, `2026`); a trailing `.` or `,` ends the number.
pub fn numbers(text: &str) -> Vec<String> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        if chars[i].is_ascii_digit() && (i == 0 || !chars[i - 1].is_alphanumeric()) {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit()
                    || ((chars[i] == '.' || chars[i] == ',')
                        && chars.get(i + 1).is_some_and(|c| c.is_ascii_digit())))
            {
                i += 1;
            }
            out.push(chars[start..i].iter().collect());
        } else {
            i += 1;
        }
    }
    out
}

/// The rows of the tables in README.md's results section, each with the
/// pages it answers to.
fn result_rows() -> Vec<(String, Vec<PathBuf>)> {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let start = readme
        .find("\n## Results at a glance")
        .expect("README.md has a 'Results at a glance' section");
    let section = &readme[start + 1..];
    let end = section[3..].find("\n## ").map_or(section.len(), |e| e + 3);
    let section = &section[..end];
    let docs_links = |text: &str| -> Vec<PathBuf> {
        link_targets(text)
            .into_iter()
            .filter(|t| t.starts_with("docs/") && !t.contains("://"))
            .map(|t| root().join(t.split('#').next().unwrap()))
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect()
    };
    let mut rows = Vec::new();
    let mut paragraph_links: Vec<PathBuf> = Vec::new();
    let mut in_table = false;
    for line in section.lines() {
        let t = line.trim();
        if t.starts_with('|') {
            // A table's first line is its header.
            let is_header = !in_table;
            in_table = true;
            let is_rule = t.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '));
            if is_rule || is_header {
                continue;
            }
            let own = docs_links(t);
            let pages = if own.is_empty() {
                paragraph_links.clone()
            } else {
                own
            };
            rows.push((t.to_string(), pages));
        } else {
            in_table = false;
        }
        if !t.starts_with('|') && !t.is_empty() {
            let links = docs_links(t);
            if !links.is_empty() {
                paragraph_links = links;
            }
        }
    }
    rows
}

#[test]
fn every_results_figure_on_the_front_page_is_on_its_page() {
    let rows = result_rows();
    assert!(rows.len() >= 10, "only {} result rows found", rows.len());
    let mut missing = Vec::new();
    for (row, pages) in &rows {
        assert!(!pages.is_empty(), "a results row links to no page: {row}");
        let texts: Vec<String> = pages
            .iter()
            .map(|p| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())))
            .collect();
        // The link text itself is not a figure.
        let row_text: String = strip_link_targets(row);
        for n in numbers(&row_text) {
            if !texts.iter().any(|t| numbers(t).contains(&n)) {
                missing.push(format!(
                    "{n} (row '{}…') on {}",
                    row.chars().take(60).collect::<String>(),
                    pages
                        .iter()
                        .map(|p| p.strip_prefix(root()).unwrap_or(p).display().to_string())
                        .collect::<Vec<_>>()
                        .join(" or ")
                ));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "{} front-page figures that their page does not give:\n{}",
        missing.len(),
        missing.join("\n")
    );
}

/// `[text](target)` becomes `text`: numbers in a path are not figures.
fn strip_link_targets(row: &str) -> String {
    let mut out = String::new();
    let mut rest = row;
    while let Some(p) = rest.find("](") {
        out.push_str(&rest[..p + 1]);
        let after = &rest[p + 2..];
        rest = after.find(')').map_or("", |q| &after[q + 1..]);
    }
    out.push_str(rest);
    out
}

#[test]
fn numbers_are_read_as_a_reader_reads_them() {
    assert_eq!(
        numbers("99.4 / 1,378–1,456 us, 2026-11-25, [41.8, 53.0]. x2 3:1"),
        ["99.4", "1,378", "1,456", "2026", "11", "25", "41.8", "53.0", "3", "1"]
    );
    assert_eq!(strip_link_targets("a [b 1](docs/x-2.md) c"), "a [b 1] c");
    let _ = Path::new("");
}
