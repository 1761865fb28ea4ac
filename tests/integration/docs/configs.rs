//! The configs users start from: each loads as written, and each opens
//! with a header that says what it is for and names the protocol it
//! trains under (a figure must never be read under the wrong one).

use league::rules::config::LeagueConfig;
use std::path::PathBuf;
use t2e_learners::learn::run_config::TrainConfig;

#[test]
fn every_config_loads_and_its_header_names_its_protocol() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let league = text.lines().any(|l| l.starts_with("env_steps_per_learner"));
        let protocol = if league {
            LeagueConfig::load(&path)
                .unwrap_or_else(|e| panic!("{e:#}"))
                .protocol
        } else {
            TrainConfig::load(&path)
                .unwrap_or_else(|e| panic!("{e:#}"))
                .protocol
        };
        let header: String = text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .collect::<Vec<_>>()
            .join("\n")
            .to_lowercase();
        assert!(
            header.lines().count() >= 3,
            "{}: needs a header comment saying what it is for",
            path.display()
        );
        let named = match protocol.name() {
            "held-out" => header.contains("held-out") || header.contains("generated maps"),
            _ => header.contains("paper protocol") || header.contains("the 26 gibson maps"),
        };
        assert!(
            named,
            "{}: its header does not say it trains under the {} protocol",
            path.display(),
            protocol.name()
        );
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} configs found");
}
