//! `t2e-league generate-docs` (hidden): the CLI reference
//! (docs/reference/cli.md) and the man pages (docs/reference/man/), both
//! generated from the clap definitions, so they cannot drift from the code
//! (tests/integration/docs/cli_reference.rs checks that the committed files are what
//! this writes).

use anyhow::{Context, Result};
use clap::CommandFactory;
use std::path::{Path, PathBuf};

/// The command that rewrites the generated reference files.
pub const REGENERATE: &str = "cargo run --release -- generate-docs --out docs/reference";

#[derive(clap::Args, Debug)]
pub struct GenerateDocsArgs {
    /// Folder to write cli.md and man/t2e-league*.1 into.
    #[arg(long, value_name = "DIR", default_value = "docs/reference")]
    pub out: PathBuf,
}

/// docs/reference/cli.md: every visible subcommand and option, as clap
/// knows them, under a note that says the file is generated.
pub fn cli_markdown<C: CommandFactory>() -> String {
    let options = clap_markdown::MarkdownOptions::new()
        .title("Command-line reference".into())
        .show_footer(false);
    let body = clap_markdown::help_markdown_custom::<C>(&options);
    // The title line first, then the note.
    let (title, rest) = body.split_once('\n').unwrap_or((&body, ""));
    format!(
        "{title}\n\n> Generated from the program's option definitions; do not edit. \
         Regenerate with `{REGENERATE}`.\n{rest}"
    )
}

/// The man pages: t2e-league.1 and one t2e-league-SUBCOMMAND.1 per
/// visible subcommand, as (file name, roff text), sorted by name.
pub fn man_pages<C: CommandFactory>() -> Result<Vec<(String, String)>> {
    let mut pages = Vec::new();
    // After `build`, each subcommand's display name is its man page's
    // name (t2e-league-eval), as clap_mangen::generate_to names them.
    fn walk(cmd: &clap::Command, pages: &mut Vec<(String, String)>) -> Result<()> {
        let man = clap_mangen::Man::new(cmd.clone());
        let mut roff = Vec::new();
        man.render(&mut roff)?;
        pages.push((man.get_filename(), String::from_utf8(roff)?));
        for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
            walk(sub, pages)?;
        }
        Ok(())
    }
    let mut cmd = C::command().disable_help_subcommand(true);
    cmd.build();
    walk(&cmd, &mut pages)?;
    pages.sort();
    Ok(pages)
}

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

pub fn run<C: CommandFactory>(args: GenerateDocsArgs) -> Result<()> {
    let man = args.out.join("man");
    std::fs::create_dir_all(&man).with_context(|| format!("cannot create {}", man.display()))?;
    write(&args.out.join("cli.md"), &cli_markdown::<C>())?;
    // Pages of subcommands that no longer exist go.
    for e in std::fs::read_dir(&man)?.flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        if n.starts_with("t2e-league") && n.ends_with(".1") {
            std::fs::remove_file(e.path())?;
        }
    }
    let pages = man_pages::<C>()?;
    for (name, text) in &pages {
        write(&man.join(name), text)?;
    }
    println!(
        "wrote {} and {} man pages in {}",
        args.out.join("cli.md").display(),
        pages.len(),
        man.display()
    );
    Ok(())
}
