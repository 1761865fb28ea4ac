//! The two evaluation protocols. The paper trained on the 26 Gibson maps and
//! tested on the same maps (in distribution); this project's default trains
//! on generated maps and tests on Gibson (maps never seen in training).
//! Both are legitimate, and their numbers must never be read one for the
//! other: a training config names its protocol, the training maps must fit
//! it (the Gibson maps are recognised by content, `map::testset`), and
//! checkpoints, eval tables and summaries carry it.

use crate::error::{ConfigError, ConfigFileError, ConfigLoadError, MapsRefused};
use crate::map::PreparedMap;
use serde::{Deserialize, Serialize};
use std::fmt;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Protocol {
    /// Train on generated (or your own) maps; evaluate on Gibson, unseen.
    #[default]
    #[serde(rename = "held-out")]
    HeldOut,
    /// As the paper: train on the 26 Gibson maps, evaluate on them.
    #[serde(rename = "paper")]
    Paper,
}

impl Protocol {
    pub fn name(self) -> &'static str {
        match self {
            Protocol::HeldOut => "held-out",
            Protocol::Paper => "paper",
        }
    }

    /// What the protocol means, for error messages and table notes.
    pub fn describe(self) -> &'static str {
        match self {
            Protocol::HeldOut => {
                "held-out: trained on generated maps, tested on the unseen Gibson maps"
            }
            Protocol::Paper => {
                "paper: trained on the 26 Gibson maps and tested on them, as the paper did"
            }
        }
    }

    /// Refuses, before any map is loaded, a training `maps` value that names
    /// the test set under held-out: a Gibson class (`small`, `medium:x`),
    /// `gibson`, or a folder inside the Gibson maps. The maps' content is
    /// checked after loading (`check_training_maps`); this catches the
    /// name first, so the message says what the user wrote.
    pub fn refuse_test_map_names(self, spec: &str) -> Result<(), ConfigError> {
        if self == Protocol::Paper {
            return Ok(());
        }
        let head = spec.split(':').next().unwrap_or("");
        let named_test = ["small", "medium", "large", "gibson"].contains(&head);
        let gibson = crate::map::catalog::gibson_dir().and_then(|d| d.canonicalize().ok());
        let in_gibson_dir = std::path::Path::new(head)
            .canonicalize()
            .ok()
            .is_some_and(|p| gibson.as_ref().is_some_and(|g| p.starts_with(g)));
        if named_test || in_gibson_dir {
            return Err(ConfigError::new(
                "maps",
                format!("\"{spec}\""),
                "the Gibson maps are the test set of protocol = \"held-out\"; train on generated maps (generated:N, shipped or a folder of your own), or set protocol = \"paper\" to train on them as the paper did",
            ));
        }
        Ok(())
    }

    /// Checks that the training maps fit the protocol: none of the Gibson
    /// test maps under held-out, neither as they are (recognised by content)
    /// nor as near-copies (mirrored, turned, padded, shifted or a few pixels
    /// changed: `map::testset::resembled_test_map`); only the 26 Gibson maps
    /// themselves, unmodified, under paper. `spec` is the config's `maps`
    /// value, for the message. The maps are compared in parallel; the error
    /// names the first offending map in order (and how many more there are).
    pub fn check_training_maps(
        self,
        spec: &str,
        maps: &[std::sync::Arc<PreparedMap>],
    ) -> Result<(), MapsRefused> {
        use crate::map::testset::{
            gibson_class, gibson_name, resembled_test_map, NEAR_COPY_THRESHOLD,
        };
        use rayon::prelude::*;
        let errors: Vec<String> = maps
            .par_iter()
            .filter_map(|m| {
                let name = &m.grid.name;
                match (self, gibson_name(&m.grid)) {
                    (Protocol::HeldOut, Some(test)) => Some(format!(
                        "map '{name}' is the Gibson test map {test} ({}; recognised by its content), in the test set of protocol = \"held-out\"; train on generated maps (generated:N, shipped or a folder of your own), or set protocol = \"paper\" to train on the test maps as the paper did",
                        gibson_class(test).map_or("no class", |c| c.name())
                    )),
                    (Protocol::HeldOut, None) => resembled_test_map(&m.grid, NEAR_COPY_THRESHOLD).map(|r| format!(
                        "map '{name}' is a near-copy of {r}: an edited copy of a test map (mirrored, turned, padded, shifted or a few pixels changed) is still the test set of protocol = \"held-out\"; train on generated maps (generated:N, shipped or a folder of your own), or set protocol = \"paper\" and maps = \"gibson\" to train on the test maps as the paper did"
                    )),
                    (Protocol::Paper, None) => Some(match resembled_test_map(&m.grid, NEAR_COPY_THRESHOLD) {
                        Some(r) => format!(
                            "map '{name}' is not one of the 26 Gibson maps but a near-copy of {r}; protocol = \"paper\" trains on exactly those maps, unmodified (maps = \"gibson\"); use protocol = \"held-out\" for other training maps (and no copies of the test maps)"
                        ),
                        None => format!(
                            "map '{name}' is not one of the 26 Gibson maps, and protocol = \"paper\" trains on exactly those (maps = \"gibson\"); use protocol = \"held-out\" for other training maps"
                        ),
                    }),
                    (Protocol::Paper, Some(_)) => None,
                }
            })
            .collect();
        first_error(
            spec,
            &errors,
            &format!("of its maps do not fit protocol = \"{}\"", self.name()),
        )
    }
}

/// Checks training-only extra maps (`[extra_maps]`): never a Gibson test
/// map nor a near-copy of one, under either protocol. `spec` is their
/// `maps` value, for the message.
pub fn check_extra_maps(
    spec: &str,
    maps: &[std::sync::Arc<PreparedMap>],
) -> Result<(), MapsRefused> {
    use crate::map::testset::{gibson_class, gibson_name, resembled_test_map, NEAR_COPY_THRESHOLD};
    use rayon::prelude::*;
    const USE: &str = "extra maps are never test maps, under either protocol (protocol = \"paper\" trains on the 26 Gibson maps through `maps`); use generated:N, shipped or a folder of your own";
    let errors: Vec<String> = maps
        .par_iter()
        .filter_map(|m| {
            let name = &m.grid.name;
            match gibson_name(&m.grid) {
                Some(test) => Some(format!(
                    "map '{name}' is the Gibson test map {test} ({}; recognised by its content): {USE}",
                    gibson_class(test).map_or("no class", |c| c.name())
                )),
                None => resembled_test_map(&m.grid, NEAR_COPY_THRESHOLD).map(|r| {
                    format!("map '{name}' is a near-copy of {r} (mirrored, turned, padded, shifted or a few pixels changed): {USE}")
                }),
            }
        })
        .collect();
    first_error(spec, &errors, "of them are test maps")
}

/// The first of a map set's errors, and how many more there are (`more`
/// says what they are).
fn first_error(spec: &str, errors: &[String], more: &str) -> Result<(), MapsRefused> {
    match errors.split_first() {
        None => Ok(()),
        Some((first, rest)) => Err(MapsRefused {
            spec: spec.to_string(),
            first: first.clone(),
            more: rest.len(),
            more_what: more.to_string(),
        }),
    }
}

impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Reads a config file: its text, the protocol it must name (a user's
/// file; a run's own `config.toml` from before configs named one reads as
/// held-out), then `parse`. Every error names the file.
pub fn read_config<T>(
    path: &std::path::Path,
    require_protocol: bool,
    parse: impl FnOnce(&str) -> Result<T, ConfigFileError>,
) -> Result<T, ConfigLoadError> {
    let text = std::fs::read_to_string(path).map_err(|cause| ConfigLoadError::Unreadable {
        path: path.to_path_buf(),
        cause,
    })?;
    let invalid = |cause: ConfigFileError| ConfigLoadError::Invalid {
        path: path.to_path_buf(),
        cause,
    };
    if require_protocol {
        require_named(&text).map_err(|e| invalid(e.into()))?;
    }
    parse(&text).map_err(invalid)
}

/// Refuses a config text (TOML) that does not name its protocol: a default
/// would let a figure be read under the wrong one. `what` names the file.
pub fn require_named(text: &str) -> Result<(), ConfigError> {
    // Text that does not parse is left to the parse that follows, which
    // names the line.
    let Ok(value) = toml::from_str::<toml::Value>(text) else {
        return Ok(());
    };
    if value.get("protocol").is_none() {
        return Err(ConfigError::missing(
            "protocol",
            "name the evaluation protocol: protocol = \"held-out\" (train on generated maps, test on the unseen Gibson maps) or protocol = \"paper\" (train and test on the 26 Gibson maps, as the paper did)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_test_maps_are_refused_for_training_by_name() {
        for spec in ["small", "medium:x", "gibson", "large"] {
            let err = Protocol::HeldOut
                .refuse_test_map_names(spec)
                .unwrap_err()
                .to_string();
            assert!(err.starts_with(&format!("maps = \"{spec}\": ")), "{err}");
            assert!(err.contains("test set"), "{spec}: {err}");
            assert!(Protocol::Paper.refuse_test_map_names(spec).is_ok());
        }
        assert!(Protocol::HeldOut
            .refuse_test_map_names("generated:20")
            .is_ok());
        assert!(Protocol::HeldOut.refuse_test_map_names("shipped").is_ok());
        if let Some(g) = crate::map::catalog::gibson_dir() {
            let inside = g.display().to_string();
            assert!(Protocol::HeldOut.refuse_test_map_names(&inside).is_err());
        }
    }

    #[test]
    fn configs_must_name_it_and_names_round_trip() {
        assert!(require_named("seed = 1\n")
            .unwrap_err()
            .to_string()
            .starts_with("protocol: missing; name the evaluation protocol"));
        assert!(require_named("protocol = \"paper\"\nseed = 1\n").is_ok());
        #[derive(Deserialize)]
        struct C {
            protocol: Protocol,
        }
        let c: C = toml::from_str("protocol = \"held-out\"").unwrap();
        assert_eq!(c.protocol, Protocol::HeldOut);
        let c: C = toml::from_str("protocol = \"paper\"").unwrap();
        assert_eq!(c.protocol, Protocol::Paper);
        assert!(toml::from_str::<C>("protocol = \"heldout\"").is_err());
        assert_eq!(Protocol::Paper.to_string(), "paper");
    }
}
