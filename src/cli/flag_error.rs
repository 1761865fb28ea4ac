//! A library's typed option error (`ConfigError`: field, value, rule) shown
//! as the flag a user typed: `threads = 0` reads `--threads 0`.

use t2e_core::error::ConfigError;

pub fn as_flag(e: ConfigError) -> anyhow::Error {
    let flag = e.field.replace('_', "-");
    match &e.value {
        Some(v) => anyhow::anyhow!("--{flag} {v}: {}", e.rule),
        None => anyhow::anyhow!("--{flag}: {}", e.rule),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_reads_as_its_flag() {
        let e = ConfigError::new("episode_length", 0, "at least 1");
        assert_eq!(as_flag(e).to_string(), "--episode-length 0: at least 1");
        let e = ConfigError::about("maps", "name at least one map set");
        assert_eq!(as_flag(e).to_string(), "--maps: name at least one map set");
    }
}
