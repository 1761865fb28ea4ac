//! The four learning algorithms by name, below the networks that carry
//! them, so a checkpoint's sidecar, a config's `play` and the league's
//! learners name an algorithm by type. What each one does lives with the
//! learners (`t2e::learn`): each algorithm's file there implements
//! `LearnerKind`, and `learn::kind` maps a variant to it.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    Mappo,
    Ippo,
    Maddpg,
    Maac,
}

impl Algorithm {
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Mappo => "mappo",
            Algorithm::Ippo => "ippo",
            Algorithm::Maddpg => "maddpg",
            Algorithm::Maac => "maac",
        }
    }

    pub const ALL: [Algorithm; 4] = [
        Algorithm::Mappo,
        Algorithm::Ippo,
        Algorithm::Maddpg,
        Algorithm::Maac,
    ];

    /// The algorithm a config or sidecar names, if any.
    pub fn parse(name: &str) -> Option<Algorithm> {
        Algorithm::ALL.into_iter().find(|a| a.name() == name)
    }
}

impl std::fmt::Display for Algorithm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_serialise_as_written() {
        for a in Algorithm::ALL {
            assert_eq!(Algorithm::parse(a.name()), Some(a));
            assert_eq!(
                serde_json::to_string(&a).unwrap(),
                format!("\"{}\"", a.name())
            );
        }
        assert_eq!(Algorithm::parse("MAPPO"), None);
        // ALL lists every variant once: the match below is exhaustive, so
        // a new variant fails to compile here until it is placed.
        for (i, a) in Algorithm::ALL.into_iter().enumerate() {
            let place = match a {
                Algorithm::Mappo => 0,
                Algorithm::Ippo => 1,
                Algorithm::Maddpg => 2,
                Algorithm::Maac => 3,
            };
            assert_eq!(place, i);
        }
    }
}
