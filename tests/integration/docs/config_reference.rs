//! The config references (docs/reference/train-config.md and
//! league-config.md) list every field of the structs `train --config` and
//! `run --config` read, and no field that does not exist; the status
//! reference (docs/reference/status-json.md) lists every field of
//! `status --json`.
//!
//! A config's fields are found by walking its type, not a value: serde's
//! derived `Deserialize` names every field of a struct (and every variant
//! of an enum) when it asks for one, so `FieldWalker` below hands each
//! struct a value for every field it names and records the dotted path of
//! every leaf. Fields the stored config leaves out while they are off
//! (`skip_serializing_if`), and `Option` fields, are found like the rest.
//!
//! A reference documents a field as a table row whose first cell is the
//! field's path in backticks (`captors.ppo.clip`), in a table whose header
//! starts with `| Field`. The two sides of a config share their struct, so
//! a field under `captors.` counts as documented by the same row under
//! `target.` and the other way round (the target-only fields are written
//! under `target.`).

use league::rules::config::LeagueConfig;
use serde::de::{
    self, DeserializeSeed, EnumAccess, IntoDeserializer, MapAccess, SeqAccess, VariantAccess,
    Visitor,
};
use serde::Deserialize;
use std::cell::RefCell;
use std::collections::BTreeSet;
use std::path::Path;
use t2e_learners::learn::run_config::TrainConfig;

type Error = de::value::Error;

// ---------------------------------------------------------------------------
// The fields of a config type.

/// A deserializer that stands for a value of any type at `path`: it gives
/// each struct every field the struct names, and records `path` for every
/// leaf (a number, a string, a bool, an enum, a list).
struct FieldWalker<'a> {
    path: String,
    leaves: &'a RefCell<BTreeSet<String>>,
    /// False for the elements of a fixed-size array (`conv_channels`),
    /// which are part of their leaf.
    record: bool,
}

impl<'a> FieldWalker<'a> {
    fn leaf(&self) {
        if self.record {
            self.leaves.borrow_mut().insert(self.path.clone());
        }
    }

    fn child(&self, name: &str) -> FieldWalker<'a> {
        FieldWalker {
            path: if self.path.is_empty() {
                name.to_string()
            } else {
                format!("{}.{name}", self.path)
            },
            leaves: self.leaves,
            record: true,
        }
    }
}

macro_rules! leaves {
    ($($method:ident => $visit:ident($($value:expr)?);)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
                self.leaf();
                visitor.$visit($($value)?)
            }
        )*
    };
}

impl<'de, 'a> de::Deserializer<'de> for FieldWalker<'a> {
    type Error = Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_unit()
    }

    // Strings are visited as "still": every string field takes it, and a
    // typed one (`play`, parsed as it is read) needs a name it knows.
    leaves! {
        deserialize_bool => visit_bool(false);
        deserialize_i8 => visit_i64(0);
        deserialize_i16 => visit_i64(0);
        deserialize_i32 => visit_i64(0);
        deserialize_i64 => visit_i64(0);
        deserialize_u8 => visit_u64(0);
        deserialize_u16 => visit_u64(0);
        deserialize_u32 => visit_u64(0);
        deserialize_u64 => visit_u64(0);
        deserialize_f32 => visit_f64(0.0);
        deserialize_f64 => visit_f64(0.0);
        deserialize_char => visit_char('x');
        deserialize_str => visit_str("still");
        deserialize_string => visit_str("still");
        deserialize_bytes => visit_bytes(&[]);
        deserialize_byte_buf => visit_bytes(&[]);
        deserialize_unit => visit_unit();
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_some(self)
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_unit()
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Error> {
        visitor.visit_newtype_struct(self)
    }

    /// A list is a leaf (an empty one: no config holds a list of tables).
    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_seq(Elements {
            left: 0,
            walker: self,
        })
    }

    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_seq(Elements {
            left: len,
            walker: self,
        })
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Error> {
        self.deserialize_tuple(len, visitor)
    }

    fn deserialize_map<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_map(Fields {
            walker: self,
            fields: &[],
            next: 0,
        })
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Error> {
        visitor.visit_map(Fields {
            walker: self,
            fields,
            next: 0,
        })
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Error> {
        self.leaf();
        visitor.visit_enum(FirstVariant(variants[0]))
    }

    fn deserialize_identifier<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_str("")
    }

    fn deserialize_ignored_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_unit()
    }
}

/// Every field a struct names, each with a walker one level down.
struct Fields<'a> {
    walker: FieldWalker<'a>,
    fields: &'static [&'static str],
    next: usize,
}

/// Other names a field also reads as (`#[serde(alias)]`), each with the
/// field's own name: serde lists them among a struct's fields, but they
/// are the same field, documented once under its own name.
const ALIASES: &[(&str, &str)] = &[("algorithm", "play")];

impl Fields<'_> {
    fn skip_aliases(&mut self) {
        while let Some(name) = self.fields.get(self.next) {
            let alias_here = ALIASES
                .iter()
                .any(|(alias, of)| alias == name && self.fields.contains(of));
            if !alias_here {
                break;
            }
            self.next += 1;
        }
    }
}

impl<'de, 'a> MapAccess<'de> for Fields<'a> {
    type Error = Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Error> {
        self.skip_aliases();
        match self.fields.get(self.next) {
            None => Ok(None),
            Some(&name) => seed
                .deserialize(IntoDeserializer::<'de, Error>::into_deserializer(name))
                .map(Some),
        }
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, Error> {
        let name = self.fields[self.next];
        self.next += 1;
        seed.deserialize(self.walker.child(name))
    }
}

/// The elements of a fixed-size array.
struct Elements<'a> {
    left: usize,
    walker: FieldWalker<'a>,
}

impl<'de, 'a> SeqAccess<'de> for Elements<'a> {
    type Error = Error;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Error> {
        if self.left == 0 {
            return Ok(None);
        }
        self.left -= 1;
        seed.deserialize(FieldWalker {
            path: format!("{}[]", self.walker.path),
            leaves: self.walker.leaves,
            record: false,
        })
        .map(Some)
    }
}

/// An enum's first variant (every config enum is a plain list of names).
struct FirstVariant(&'static str);

impl<'de> EnumAccess<'de> for FirstVariant {
    type Error = Error;
    type Variant = FirstVariant;

    fn variant_seed<V: DeserializeSeed<'de>>(self, seed: V) -> Result<(V::Value, Self), Error> {
        let value = seed.deserialize(IntoDeserializer::<'de, Error>::into_deserializer(self.0))?;
        Ok((value, self))
    }
}

impl<'de> VariantAccess<'de> for FirstVariant {
    type Error = Error;

    fn unit_variant(self) -> Result<(), Error> {
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, _seed: T) -> Result<T::Value, Error> {
        Err(de::Error::custom(format!(
            "variant {} holds data: teach the walker about it",
            self.0
        )))
    }

    fn tuple_variant<V: Visitor<'de>>(self, _len: usize, _visitor: V) -> Result<V::Value, Error> {
        self.newtype_variant_seed(std::marker::PhantomData::<()>)
            .map(|_| unreachable!())
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        _fields: &'static [&'static str],
        _visitor: V,
    ) -> Result<V::Value, Error> {
        self.newtype_variant_seed(std::marker::PhantomData::<()>)
            .map(|_| unreachable!())
    }
}

/// The dotted path of every field of `T`, leaves only.
fn fields_of<'de, T: Deserialize<'de>>() -> BTreeSet<String> {
    let leaves = RefCell::new(BTreeSet::new());
    T::deserialize(FieldWalker {
        path: String::new(),
        leaves: &leaves,
        record: true,
    })
    .unwrap_or_else(|e| {
        panic!(
            "cannot walk the fields of {}: {e}",
            std::any::type_name::<T>()
        )
    });
    leaves.into_inner()
}

// ---------------------------------------------------------------------------
// The fields of a serialised value.

/// The dotted path of every leaf of `value`; an array's elements are
/// described once, as `name[].field`.
fn value_paths(value: &serde_json::Value) -> BTreeSet<String> {
    fn walk(path: &str, value: &serde_json::Value, out: &mut BTreeSet<String>) {
        match value {
            serde_json::Value::Object(map) => {
                for (k, v) in map {
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    walk(&p, v, out);
                }
            }
            serde_json::Value::Array(items) if items.iter().any(|v| v.is_object()) => {
                for v in items {
                    walk(&format!("{path}[]"), v, out);
                }
            }
            _ => {
                out.insert(path.to_string());
            }
        }
    }
    let mut out = BTreeSet::new();
    walk("", value, &mut out);
    out
}

// ---------------------------------------------------------------------------
// The references.

fn reference(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/reference")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The paths a reference documents: the backticked first cell of every row
/// of every table whose header starts with `| Field`.
fn documented(markdown: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut in_field_table = false;
    let mut previous_was_table = false;
    for line in markdown.lines() {
        let line = line.trim();
        let is_table = line.starts_with('|');
        if is_table && !previous_was_table {
            in_field_table = line.starts_with("| Field");
        }
        previous_was_table = is_table;
        if !(is_table && in_field_table) {
            continue;
        }
        let first = line
            .trim_start_matches('|')
            .split('|')
            .next()
            .unwrap_or("")
            .trim();
        if let Some(path) = first
            .strip_prefix('`')
            .and_then(|rest| rest.strip_suffix('`'))
        {
            out.insert(path.to_string());
        }
    }
    out
}

/// `path` with its side table swapped (`captors.x` <-> `target.x`).
fn other_side(path: &str) -> Option<String> {
    if let Some(rest) = path.strip_prefix("captors.") {
        Some(format!("target.{rest}"))
    } else {
        path.strip_prefix("target.")
            .map(|rest| format!("captors.{rest}"))
    }
}

fn covered(path: &str, set: &BTreeSet<String>) -> bool {
    set.contains(path) || other_side(path).is_some_and(|p| set.contains(&p))
}

/// Fields the reference misses, and rows that name no field.
fn compare(fields: &BTreeSet<String>, rows: &BTreeSet<String>) -> (Vec<String>, Vec<String>) {
    let missing = fields
        .iter()
        .filter(|f| !covered(f, rows))
        .cloned()
        .collect();
    let stale = rows
        .iter()
        .filter(|r| !covered(r, fields))
        .cloned()
        .collect();
    (missing, stale)
}

fn check(page: &str, fields: &BTreeSet<String>) {
    let rows = documented(&reference(page));
    let (missing, stale) = compare(fields, &rows);
    assert!(
        missing.is_empty(),
        "docs/reference/{page} misses {} field(s); add a row `| `PATH` | type | default | range | meaning |` for each: {missing:#?}",
        missing.len()
    );
    assert!(
        stale.is_empty(),
        "docs/reference/{page} documents {} path(s) that are no field of the config (renamed or removed?): {stale:#?}",
        stale.len()
    );
}

// ---------------------------------------------------------------------------
// The tests.

#[test]
fn the_walker_finds_every_field_a_config_serialises_and_the_ones_it_leaves_out() {
    // Everything the default config writes to its stored config.toml...
    let train = fields_of::<TrainConfig>();
    let stored = value_paths(&serde_json::to_value(TrainConfig::default()).unwrap());
    let unseen: Vec<_> = stored.difference(&train).collect();
    assert!(unseen.is_empty(), "walker missed {unseen:?}");
    // ...and the fields left out of it while off.
    for hidden in [
        "extra_maps.maps",
        "map_sampling",
        "captors.maddpg.tau",
        "captors.maac.attention_heads",
        "captors.shaping.potential",
        "captors.ppo.lr_anneal",
        "target.ppo.heuristic_kl",
        "target.net.vector_input",
        "target.net.heuristic_prior",
    ] {
        assert!(
            train.contains(hidden) && !stored.contains(hidden),
            "{hidden}"
        );
    }
    let league = fields_of::<LeagueConfig>();
    let stored = value_paths(&serde_json::to_value(LeagueConfig::default()).unwrap());
    let unseen: Vec<_> = stored.difference(&league).collect();
    assert!(unseen.is_empty(), "walker missed {unseen:?}");
    for hidden in [
        "curriculum.captors_replay_share",
        "members.captors",
        "evaluator.held_out_targets",
        "matchmaking.members_share",
    ] {
        assert!(
            league.contains(hidden) && !stored.contains(hidden),
            "{hidden}"
        );
    }
}

#[test]
fn the_train_config_reference_lists_every_field() {
    check("train-config.md", &fields_of::<TrainConfig>());
}

#[test]
fn the_league_config_reference_lists_every_field() {
    check("league-config.md", &fields_of::<LeagueConfig>());
}

#[test]
fn a_missing_or_stale_row_is_caught() {
    let fields = fields_of::<TrainConfig>();
    let mut rows = documented(&reference("train-config.md"));
    assert!(rows.remove("captors.ppo.clip"), "the clip row is there");
    rows.insert("captors.ppo.clip_range".into());
    let (missing, stale) = compare(&fields, &rows);
    assert_eq!(missing, ["captors.ppo.clip", "target.ppo.clip"]);
    assert_eq!(stale, ["captors.ppo.clip_range"]);
}

/// A status report with one row of every kind and every optional field
/// set, so that every field appears in its JSON.
fn full_status_report() -> league::run::status::StatusReport {
    use league::run::status::*;
    use league::store::Kind;
    use t2e_core::env::Side;
    StatusReport {
        league: "default".into(),
        dir: "runs/league/default".into(),
        matches: 1,
        players: vec![PlayerRow {
            id: 3,
            name: "captors-snap-000000040000".into(),
            side: Side::Captors,
            kind: Kind::Snapshot,
            parent: Some(1),
            env_steps: 40_000,
            curriculum_stage: 0,
            rating: 25.0,
            rating_sigma: 8.3,
            bt_elo: 0.0,
            games: 1,
            wins: 1,
            win_rate: Some(1.0),
            quarantined: Some("why".into()),
        }],
        curriculum: Curriculum {
            stage: 0,
            speed_ratio: 1.0,
            history: vec![StageRow {
                stage: 0,
                speed_ratio: 1.0,
                reason: "start".into(),
                at_ms: 0,
            }],
        },
        learners: vec![LearnerRow {
            name: "captors-main".into(),
            pid: 1,
            host: Some("host".into()),
            state: "training".into(),
            env_steps: 1,
            steps_per_s: 1.0,
            heartbeat_age_s: 1.0,
        }],
        payoff: vec![PayoffRow {
            captor: 1,
            target: 2,
            captor_wins: 1,
            games: 1,
        }],
        crashes: vec![CrashRow {
            learner: "target-main".into(),
            exit_status: "signal 9".into(),
            message: "tail".into(),
            at_ms: 0,
        }],
        seats: vec![SeatStatus {
            name: "captors-main".into(),
            state: "open".into(),
            host: Some("host".into()),
            lease_left_s: Some(1.0),
            claims: 1,
            reason: Some("why".into()),
        }],
        panel: vec![PanelRow {
            member: 3,
            member_name: "captors-snap-000000040000".into(),
            opponent: 2,
            opponent_name: "rule-based-target".into(),
            episodes: 1,
            member_wins: 1,
            win_rate: 1.0,
            win_rate_low: 0.2,
            win_rate_high: 1.0,
            held_out: false,
            validation: false,
            mean_steps: Some(120.0),
        }],
        exploits: vec![ExploitRow {
            player: 3,
            player_name: "captors-snap-000000040000".into(),
            player_sha256: Some("0".repeat(64)),
            player_env_steps: Some(40_000),
            outdated: false,
            side: "captors".into(),
            best_response: "mappo".into(),
            budget: "10m".into(),
            env_steps: 1,
            train_s: 1.0,
            seed: 0,
            maps: "small".into(),
            speed_ratio: 1.0,
            episodes: 1,
            best_response_wins: 1,
            win_rate: 1.0,
            win_rate_low: 0.2,
            win_rate_high: 1.0,
        }],
    }
}

#[test]
fn the_status_reference_lists_every_field_of_the_json() {
    let fields = value_paths(&serde_json::to_value(full_status_report()).unwrap());
    check("status-json.md", &fields);
}

#[test]
fn the_status_example_parses_and_shows_only_documented_fields() {
    let page = reference("status-json.md");
    let start = page
        .find("```json\n")
        .expect("an example in a ```json block")
        + 8;
    let end = start + page[start..].find("```").expect("the block ends");
    let example: serde_json::Value =
        serde_json::from_str(&page[start..end]).expect("the example is JSON");
    let fields = value_paths(&serde_json::to_value(full_status_report()).unwrap());
    for path in value_paths(&example) {
        // An empty list shows as its own name.
        let known =
            fields.contains(&path) || fields.iter().any(|f| f.starts_with(&format!("{path}[].")));
        assert!(
            known,
            "the example shows {path}, which StatusReport has not"
        );
    }
}
