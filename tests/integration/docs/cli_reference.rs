//! docs/reference/cli.md and the man pages in docs/reference/man/ are what
//! the clap definitions generate now: an option added, renamed or
//! re-documented without regenerating them fails here.

use std::path::PathBuf;
use t2e::cli::docs::{cli_markdown, man_pages, REGENERATE};

fn reference() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/reference")
}

/// The first line where `a` and `b` differ, for the failure message.
fn first_difference(a: &str, b: &str) -> String {
    let (mut la, mut lb) = (a.lines(), b.lines());
    for n in 1.. {
        match (la.next(), lb.next()) {
            (None, None) => break,
            (x, y) if x == y => continue,
            (x, y) => {
                return format!(
                    "line {n}:\n  committed: {}\n  generated: {}",
                    x.unwrap_or("(end of file)"),
                    y.unwrap_or("(end of file)")
                )
            }
        }
    }
    "only in line endings".into()
}

#[test]
fn the_cli_reference_is_what_the_code_generates() {
    let path = reference().join("cli.md");
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    let generated = cli_markdown::<t2e::cli::Cli>();
    assert!(
        committed == generated,
        "{} is out of date ({}); regenerate it with `{REGENERATE}`",
        path.display(),
        first_difference(&committed, &generated)
    );
    assert!(
        generated.contains("Regenerate with") && generated.contains("t2e-league status"),
        "the generated reference lacks its note or a subcommand"
    );
}

#[test]
fn the_man_pages_are_what_the_code_generates() {
    let dir = reference().join("man");
    let pages = man_pages::<t2e::cli::Cli>().unwrap();
    let mut stale = Vec::new();
    for (name, generated) in &pages {
        let committed = std::fs::read_to_string(dir.join(name)).unwrap_or_default();
        if &committed != generated {
            stale.push(format!(
                "{name} ({})",
                first_difference(&committed, generated)
            ));
        }
    }
    // A page of a subcommand that no longer exists.
    for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".1") && !pages.iter().any(|(n, _)| *n == name) {
            stale.push(format!("{name} (no such subcommand)"));
        }
    }
    assert!(
        pages.iter().any(|(n, _)| n == "t2e-league.1"),
        "no t2e-league.1 among {:?}",
        pages.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    assert!(
        stale.is_empty(),
        "man pages in {} out of date:\n{}\nregenerate them with `{REGENERATE}`",
        dir.display(),
        stale.join("\n")
    );
}
