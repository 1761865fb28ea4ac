//! Every relative link in README.md and docs/ resolves, every page of docs/
//! is in docs/SUMMARY.md, and no page speaks of how the work was organised.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown file under docs/, sorted.
pub fn pages() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut out = vec![root().join("README.md")];
    walk(&root().join("docs"), &mut out);
    out.sort();
    out
}

/// The text of a Markdown page outside fenced code blocks and inline code,
/// where links are not links.
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            out.push('\n');
            continue;
        }
        if fenced {
            out.push('\n');
            continue;
        }
        let mut in_code = false;
        for c in line.chars() {
            if c == '`' {
                in_code = !in_code;
            } else if !in_code {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// Link targets: `[text](target)`, `![alt](target)`, `[label]: target` and
/// HTML `src="target"` / `href="target"`.
pub fn link_targets(text: &str) -> Vec<String> {
    let text = prose(text);
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(at) = text[i..].find("](") {
        let start = i + at + 2;
        let mut depth = 1;
        let mut end = start;
        while end < bytes.len() && bytes[end] != b'\n' {
            match bytes[end] {
                b'(' => depth += 1,
                b')' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                _ => {}
            }
            end += 1;
        }
        let inner = text[start..end].trim();
        // `[a](<path with spaces>)` and `[a](path "title")`
        let target = if let Some(rest) = inner.strip_prefix('<') {
            rest.split('>').next().unwrap_or("")
        } else {
            inner.split_whitespace().next().unwrap_or("")
        };
        out.push(target.to_string());
        i = end.max(start);
    }
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with('[') {
            if let Some(pos) = t.find("]: ") {
                if !t[..pos].contains("](") {
                    out.push(
                        t[pos + 3..]
                            .split_whitespace()
                            .next()
                            .unwrap_or("")
                            .to_string(),
                    );
                }
            }
        }
        for attr in ["src=\"", "href=\""] {
            let mut rest = line;
            while let Some(p) = rest.find(attr) {
                rest = &rest[p + attr.len()..];
                out.push(rest.split('"').next().unwrap_or("").to_string());
            }
        }
    }
    out
}

fn is_external(target: &str) -> bool {
    target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:")
}

/// `target` as a path from the page's folder, without its anchor.
fn resolve(page: &Path, target: &str) -> PathBuf {
    let path = target.split('#').next().unwrap();
    page.parent().unwrap().join(path)
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in link_targets(&text) {
            if is_external(&target) {
                continue;
            }
            checked += 1;
            if !resolve(&page, &target).exists() {
                broken.push(format!(
                    "{}: {target}",
                    page.strip_prefix(root()).unwrap().display()
                ));
            }
        }
    }
    assert!(
        checked > 100,
        "only {checked} relative links found: is the parser broken?"
    );
    assert!(
        broken.is_empty(),
        "{} broken links:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn every_page_is_in_the_summary_and_every_summary_entry_exists() {
    let docs = root().join("docs");
    let summary_path = docs.join("SUMMARY.md");
    let summary = std::fs::read_to_string(&summary_path).expect("docs/SUMMARY.md");
    let listed: BTreeSet<PathBuf> = link_targets(&summary)
        .iter()
        .filter(|t| !is_external(t))
        .map(|t| normalise(&resolve(&summary_path, t)))
        .collect();
    let missing_files: Vec<_> = listed.iter().filter(|p| !p.exists()).collect();
    assert!(
        missing_files.is_empty(),
        "SUMMARY.md lists pages that do not exist: {missing_files:?}"
    );
    let unlisted: Vec<String> = pages()
        .into_iter()
        .filter(|p| p.starts_with(&docs) && *p != summary_path)
        .filter(|p| !listed.contains(&normalise(p)))
        .map(|p| p.strip_prefix(root()).unwrap().display().to_string())
        .collect();
    assert!(
        unlisted.is_empty(),
        "pages missing from docs/SUMMARY.md:\n{}",
        unlisted.join("\n")
    );
}

/// GitHub's anchor for a heading: lowercase, punctuation other than `-`
/// and `_` dropped, spaces to `-`.
pub fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors a page offers: its headings' slugs (a repeated heading gets
/// `-1`, `-2`, ... as on GitHub) and explicit `id="..."` / `name="..."`.
pub fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut seen: std::collections::BTreeMap<String, usize> = Default::default();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if let Some(heading) = line.strip_prefix('#') {
            let heading = heading.trim_start_matches('#');
            if heading.starts_with(' ') {
                // Inline code and links keep their text, not their markup.
                let text: String = heading.replace('`', "");
                let base = slug(&text);
                let n = seen.entry(base.clone()).or_insert(0);
                out.insert(if *n == 0 {
                    base.clone()
                } else {
                    format!("{base}-{n}")
                });
                *n += 1;
            }
        }
        for attr in ["id=\"", "name=\""] {
            let mut rest = line;
            while let Some(p) = rest.find(attr) {
                rest = &rest[p + attr.len()..];
                out.insert(rest.split('"').next().unwrap_or("").to_string());
            }
        }
    }
    out
}

#[test]
fn every_anchor_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    let mut cache: std::collections::BTreeMap<PathBuf, BTreeSet<String>> = Default::default();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in link_targets(&text) {
            let Some((path, anchor)) = target.split_once('#') else {
                continue;
            };
            if target.contains("://") || anchor.is_empty() {
                continue;
            }
            let file = if path.is_empty() {
                page.clone()
            } else {
                resolve(&page, path)
            };
            if file.extension().is_none_or(|e| e != "md") || !file.exists() {
                continue;
            }
            let have = cache
                .entry(normalise(&file))
                .or_insert_with(|| anchors(&std::fs::read_to_string(&file).unwrap()));
            checked += 1;
            if !have.contains(anchor) {
                broken.push(format!(
                    "{}: {target}",
                    page.strip_prefix(root()).unwrap().display()
                ));
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} anchors found: is the parser broken?"
    );
    assert!(
        broken.is_empty(),
        "{} links to anchors that no heading of the page gives:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn slugs_are_githubs() {
    assert_eq!(
        slug("A lever: a main target exploiter, three seeds"),
        "a-lever-a-main-target-exploiter-three-seeds"
    );
    assert_eq!(slug("`greedy:K` and 1.0:1.2"), "greedyk-and-1012");
    let a = anchors(
        "# Title\n## Reproduce\n## Reproduce\n```\n# not a heading\n```\n<a id=\"x\"></a>\n",
    );
    assert_eq!(
        a.into_iter().collect::<Vec<_>>(),
        ["reproduce", "reproduce-1", "title", "x"]
    );
}

fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// Words about how the work was organised, which mean nothing to a reader.
pub fn process_words(text: &str) -> Vec<String> {
    let lower = text.to_lowercase();
    let mut found = Vec::new();
    for word in ["stop", "stops", "issue", "issues", "goal"] {
        let needle = format!("{word} ");
        let mut from = 0;
        while let Some(p) = lower[from..].find(&needle) {
            let at = from + p;
            let before = lower[..at].chars().next_back();
            let after = &lower[at + needle.len()..];
            let boundary = before.is_none_or(|c| !c.is_alphanumeric() && c != '-');
            if boundary && after.starts_with(|c: char| c.is_ascii_digit()) {
                let digits: String = after.chars().take_while(|c| c.is_ascii_digit()).collect();
                found.push(format!("{word} {digits}"));
            }
            from = at + needle.len();
        }
    }
    if lower.contains("session") {
        found.push("session".to_string());
    }
    found
}

#[test]
fn no_page_or_config_speaks_of_stops_issues_or_sessions() {
    let mut files = pages();
    for dir in ["configs", "docs"] {
        fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
            for entry in std::fs::read_dir(dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    walk(&path, out);
                } else if path.extension().is_some_and(|e| e == "toml" || e == "sh") {
                    out.push(path);
                }
            }
        }
        walk(&root().join(dir), &mut files);
    }
    let mut hits = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        for word in process_words(&text) {
            hits.push(format!(
                "{}: {word}",
                file.strip_prefix(root()).unwrap().display()
            ));
        }
    }
    assert!(
        hits.is_empty(),
        "{} mentions:\n{}",
        hits.len(),
        hits.join("\n")
    );
}

#[test]
fn the_parsers_find_what_they_should() {
    let text = "see [a](x.md) and ![p](img/a.png \"t\"), `[no](code.md)`\n\
                ```\n[no](fenced.md)\n```\n[ref]: y.md\n<img src=\"z.png\">";
    assert_eq!(
        link_targets(text),
        vec!["x.md", "img/a.png", "y.md", "z.png"]
    );
    assert_eq!(
        process_words("Stop 29's run; issue 17; non-stop 4; a session"),
        vec!["stop 29", "issue 17", "session"]
    );
}
