//! Bad input never gives a wrong result: validation maps compared with the
//! training maps by content, every league setting checked before the first
//! env step, exported folders verified against their hashes before they are
//! used, and clear refusals for the worker's and the exporter's arguments.
//! Each test failed before its fix: the league trained and then validated
//! on its training maps (or died after training), `exploit` trained
//! against an edited or truncated folder, or a message misled.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn t2e(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_t2e-league"))
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The tiny league's config with `evaluator` lines added under
/// `[evaluator]` (and `extra` appended), written to ROOT/league.toml.
fn config(root: &Path, evaluator: &str, extra: &str) -> PathBuf {
    let text = common::league::TINY_LEAGUE
        .replace("[evaluator]\n", &format!("[evaluator]\n{evaluator}\n"));
    let path = root.join("league.toml");
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    path
}

/// `run` refuses the config before it writes the league's folder.
fn refused_before_start(root: &Path, evaluator: &str, extra: &str) -> String {
    let cfg = config(root, evaluator, extra);
    let dir = root.join("league");
    let _ = std::fs::remove_dir_all(&dir);
    refused_config(&cfg, &dir, &format!("{evaluator} / {extra}"))
}

/// `run --config CFG --dir DIR` fails, and nothing of a league was written.
fn refused_config(cfg: &Path, dir: &Path, what: &str) -> String {
    let o = t2e(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--dir",
        dir.to_str().unwrap(),
        "--for",
        "60s",
    ]);
    let err = stderr(&o);
    assert!(!o.status.success(), "accepted: {what}\n{err}");
    assert!(
        !dir.join("league.db").exists() && !dir.join("config.toml").exists(),
        "{what}: refused only after the league was written\n{err}"
    );
    err
}

#[test]
fn validation_maps_are_compared_with_the_training_maps_by_content() {
    let tmp = tempfile::tempdir().unwrap();
    let shipped = t2e_core::map::catalog::shipped_dir();
    let panel = "validation_captors = [\"expert:1\"]";
    // The shipped folder by path while training on "shipped".
    let err = refused_before_start(
        tmp.path(),
        &format!("validation_maps = \"{}\"\n{panel}", shipped.display()),
        "",
    );
    assert!(
        err.contains("evaluator.validation_maps") && err.contains("by content"),
        "{err}"
    );
    // One class of the training maps.
    let err = refused_before_start(
        tmp.path(),
        &format!("validation_maps = \"shipped:small\"\n{panel}"),
        "",
    );
    assert!(
        err.contains("evaluator.validation_maps") && err.contains("training maps"),
        "{err}"
    );
    // A folder generated with the training set's own seeds.
    let generated = tmp.path().join("regenerated");
    for class in ["small", "medium", "large"] {
        let o = t2e(&[
            "maps",
            "generate",
            "--class",
            class,
            "--seed",
            "1",
            "--count",
            "2",
            "--out",
            generated.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let training = common::league::TINY_LEAGUE
        .replace("maps = \"shipped\"", "maps = \"generated:2\"")
        .replace(
            "[evaluator]\n",
            &format!(
                "[evaluator]\nvalidation_maps = \"{}\"\n{panel}\n",
                generated.display()
            ),
        );
    let path = tmp.path().join("league-generated.toml");
    std::fs::write(&path, training).unwrap();
    let err = refused_config(
        &path,
        &tmp.path().join("league-generated"),
        "a folder of the training seeds",
    );
    assert!(err.contains("by content") && err.contains("gen-"), "{err}");
}

#[test]
fn validation_settings_that_need_loading_are_refused_before_training() {
    let tmp = tempfile::tempdir().unwrap();
    let panel = "validation_captors = [\"expert:1\"]";
    for (maps, says) in [
        ("/nonexistent", "nonexistent"),
        ("Small", "evaluator.validation_maps"),
    ] {
        let err = refused_before_start(
            tmp.path(),
            &format!("validation_maps = \"{maps}\"\n{panel}"),
            "",
        );
        assert!(err.contains(says), "{maps}: {err}");
    }
    if let Some(gibson) = t2e_core::map::catalog::gibson_dir() {
        let err = refused_before_start(
            tmp.path(),
            &format!("validation_maps = \"{}\"\n{panel}", gibson.display()),
            "",
        );
        assert!(err.contains("Gibson test map"), "{err}");
    }
}

#[test]
fn too_many_workers_and_odd_worker_arguments_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = config(tmp.path(), "", "");
    let store = tmp.path().join("store.db");
    let o = t2e(&[
        "run",
        "--config",
        cfg.to_str().unwrap(),
        "--dir",
        tmp.path().join("logs").to_str().unwrap(),
        "--store",
        store.to_str().unwrap(),
        "--pool",
        tmp.path().join("pool").to_str().unwrap(),
        "--workers",
        "300",
        "--for",
        "10s",
    ]);
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("--workers 300") && err.contains("at most 256"),
        "{err}"
    );
    assert!(!store.exists(), "the store was written before the refusal");

    let file = tmp.path().join("a-file");
    std::fs::write(&file, "x").unwrap();
    std::fs::create_dir_all(tmp.path().join("pool")).unwrap();
    let pool = tmp.path().join("pool");
    let logs = tmp.path().join("w");
    for (flag, value, says) in [
        ("--host", "a\nb", "--host"),
        ("--host", "a:b", "--host"),
        ("--dir", file.to_str().unwrap(), "a file, not a folder"),
    ] {
        let mut args = vec![
            "worker",
            "--store",
            store.to_str().unwrap(),
            "--pool",
            pool.to_str().unwrap(),
        ];
        if flag != "--dir" {
            args.extend(["--dir", logs.to_str().unwrap()]);
        }
        args.extend([flag, value]);
        let o = t2e(&args);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains(says),
            "{flag} {value:?}: {err}"
        );
    }
}

#[test]
fn one_checkpoint_in_two_roles_is_refused_however_it_is_spelled() {
    let tmp = tempfile::tempdir().unwrap();
    let stored =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/stored/export-captors");
    let team = tmp.path().join("team");
    let copy = tmp.path().join("copy");
    for d in [&team, &copy] {
        std::fs::create_dir_all(d).unwrap();
        for e in std::fs::read_dir(&stored).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), d.join(e.file_name())).unwrap();
        }
    }
    std::fs::create_dir_all(tmp.path().join("x")).unwrap();
    let member = format!("[members]\ncaptors = [\"ckpt:{}\"]", team.display());
    // The member again as a held-out team, through `x/..`.
    let err = refused_before_start(
        tmp.path(),
        &format!(
            "held_out_captors = [\"ckpt:{}/x/../team\"]",
            tmp.path().display()
        ),
        &member,
    );
    assert!(
        err.contains("evaluator.held_out_captors") && err.contains("same checkpoint"),
        "{err}"
    );
    // A byte copy of the member as a validation team.
    let err = refused_before_start(
        tmp.path(),
        &format!(
            "validation_maps = \"generated:2@1001\"\nvalidation_captors = [\"ckpt:{}\"]",
            copy.display()
        ),
        &member,
    );
    assert!(
        err.contains("evaluator.validation_captors") && err.contains("same checkpoint"),
        "{err}"
    );
}

#[test]
fn a_folder_of_other_files_is_not_made_a_league() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = config(tmp.path(), "", "");
    let dir = tmp.path().join("mine");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("thesis.tex"), "x").unwrap();
    let err = refused_config(&cfg, &dir, "a folder of the user's files");
    assert!(err.contains("thesis.tex"), "{err}");
}
