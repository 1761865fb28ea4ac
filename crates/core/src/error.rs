//! The core's typed errors. A setting out of range is a `ConfigError`
//! naming the field, the value and the rule, so every config file's
//! message reads the same way ("env.num_captors = 0: must be between 1 and
//! 32"); `in_range` is the one range check every config uses for numbers.

use std::fmt::{self, Display};
use std::ops::RangeInclusive;

/// A setting that cannot be honoured: `field = value: rule`, or
/// `field: rule` for a field that is missing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// The field's path in its file (`env.num_captors`).
    pub field: String,
    /// The value as given; None when the field is missing.
    pub value: Option<String>,
    /// What the value must be.
    pub rule: String,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.value {
            Some(v) => write!(f, "{} = {v}: {}", self.field, self.rule),
            None => write!(f, "{}: {}", self.field, self.rule),
        }
    }
}

impl std::error::Error for ConfigError {}

impl ConfigError {
    pub fn new(field: impl Into<String>, value: impl Display, rule: impl Into<String>) -> Self {
        ConfigError {
            field: field.into(),
            value: Some(value.to_string()),
            rule: rule.into(),
        }
    }

    /// A field that must be there and is not.
    pub fn missing(field: impl Into<String>, rule: impl Into<String>) -> Self {
        ConfigError {
            field: field.into(),
            value: None,
            rule: format!("missing; {}", rule.into()),
        }
    }

    /// A rule about a field that no single value breaks (two settings
    /// that do not fit together, a side with nothing to do).
    pub fn about(field: impl Into<String>, rule: impl Into<String>) -> Self {
        ConfigError {
            field: field.into(),
            value: None,
            rule: rule.into(),
        }
    }

    /// The same error seen from the table above: `num_captors` in `env`
    /// becomes `env.num_captors`.
    pub fn within(mut self, table: &str) -> Self {
        self.field = format!("{table}.{}", self.field);
        self
    }
}

/// `value` must lie in `range` (and be finite, for floats: NaN is in no
/// range); else the error says `field = value: rule`.
pub fn in_range<T: PartialOrd + Display>(
    field: &str,
    value: T,
    range: RangeInclusive<T>,
    rule: &str,
) -> Result<(), ConfigError> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(ConfigError::new(field, value, rule))
    }
}

/// A real number within (lo, hi], or [lo, hi] when `closed`; NaN and the
/// infinities are in no interval. The rule reads `must be in (0, 1]`.
pub fn in_interval(
    field: &str,
    value: f64,
    lo: f64,
    hi: f64,
    closed: bool,
) -> Result<(), ConfigError> {
    let above = if closed { value >= lo } else { value > lo };
    if above && value <= hi && value.is_finite() {
        Ok(())
    } else {
        let bracket = if closed { "[" } else { "(" };
        Err(ConfigError::new(
            field,
            value,
            format!("must be in {bracket}{lo}, {hi}]"),
        ))
    }
}

/// An error and its causes (each `source()` in turn), each after `: `:
/// how the command line prints a chain of errors (`{:#}`). An error that
/// holds a cause prints it this way and does not hand it on as its own
/// `source()`, so a chain printed whole names each part once.
pub struct Chain<'a>(pub &'a (dyn std::error::Error + 'static));

impl fmt::Display for Chain<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)?;
        let mut next = self.0.source();
        while let Some(e) = next {
            write!(f, ": {e}")?;
            next = e.source();
        }
        Ok(())
    }
}

/// Writes a library crate's `ResultExt` for its error type: `.context(..)`
/// and `.with_context(|| ..)` on any result whose error converts into it,
/// the error becoming `context: error` through the type's own `context`
/// method. A macro and not one trait generic over the error, because with
/// the error a type parameter `?` could not tell which one a call means.
#[macro_export]
macro_rules! result_ext {
    ($error:ty) => {
        /// `.context(...)` and `.with_context(|| ...)` on a result whose
        /// error converts into this crate's error: the error becomes
        /// `context: error`.
        pub trait ResultExt<T> {
            fn context(self, context: impl Into<String>) -> std::result::Result<T, $error>;
            fn with_context<C: Into<String>>(
                self,
                context: impl FnOnce() -> C,
            ) -> std::result::Result<T, $error>;
        }

        impl<T, E: Into<$error>> ResultExt<T> for std::result::Result<T, E> {
            fn context(self, context: impl Into<String>) -> std::result::Result<T, $error> {
                self.map_err(|e| e.into().context(context))
            }

            fn with_context<C: Into<String>>(
                self,
                context: impl FnOnce() -> C,
            ) -> std::result::Result<T, $error> {
                self.map_err(|e| e.into().context(context()))
            }
        }
    };
}

/// A map set that does not fit its protocol, or extra maps that are test
/// maps: the first offending map, and how many more there are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapsRefused {
    /// The config's `maps` value.
    pub spec: String,
    /// Why the first offending map (in the set's order) is refused.
    pub first: String,
    /// How many more maps are refused, and what they are.
    pub more: usize,
    pub more_what: String,
}

impl fmt::Display for MapsRefused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "maps = \"{}\": {}", self.spec, self.first)?;
        if self.more > 0 {
            write!(f, " (and {} more {})", self.more, self.more_what)?;
        }
        Ok(())
    }
}

impl std::error::Error for MapsRefused {}

/// A config file's text that cannot be read as its schema, or whose values
/// cannot be honoured.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConfigFileError {
    #[error(transparent)]
    Toml(#[from] crate::util::TomlError),
    #[error(transparent)]
    Invalid(#[from] ConfigError),
}

/// A config file that cannot be used; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigLoadError {
    #[error("{}: cannot read: {cause}", .path.display())]
    Unreadable {
        path: std::path::PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: {cause}", .path.display())]
    Invalid {
        path: std::path::PathBuf,
        cause: ConfigFileError,
    },
}

/// Why an environment cannot be built or changed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EnvError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("no map to play on")]
    NoMaps,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_range_error_names_field_value_and_rule_and_nan_is_in_no_range() {
        assert_eq!(in_range("k", 3usize, 1..=32, "between 1 and 32"), Ok(()));
        let e = in_range("k", 0usize, 1..=32, "must be between 1 and 32").unwrap_err();
        assert_eq!(e.to_string(), "k = 0: must be between 1 and 32");
        assert_eq!(
            e.within("env").to_string(),
            "env.k = 0: must be between 1 and 32"
        );
        assert!(in_range("v", f64::NAN, 0.0..=10.0, "a speed").is_err());
        assert!(in_range("v", f64::INFINITY, 0.0..=10.0, "a speed").is_err());
        assert!(in_range("v", 10.0, 0.0..=10.0, "a speed").is_ok());
        assert_eq!(
            in_interval("clip", 0.0, 0.0, 1.0, false)
                .unwrap_err()
                .to_string(),
            "clip = 0: must be in (0, 1]"
        );
        assert!(in_interval("gamma", 0.0, 0.0, 1.0, true).is_ok());
        assert!(in_interval("gamma", f64::NAN, 0.0, 1.0, true).is_err());
        assert!(in_interval("gamma", 1.5, 0.0, 1.0, true).is_err());
        assert_eq!(
            ConfigError::missing("protocol", "name it").to_string(),
            "protocol: missing; name it"
        );
    }
}
