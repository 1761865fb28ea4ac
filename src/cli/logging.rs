//! Where the program's messages go: tracing to stderr, with levels
//! (`RUST_LOG`, default `info` for this program and `error` for sqlx),
//! as plain lines for people or one JSON object a line for a cluster's log
//! collector (`--log-format json`). The league's processes inherit the
//! format through `T2E_LOG_FORMAT`, so a whole league logs one way.

use std::fmt;
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::fmt::format::{FormatEvent, FormatFields, Writer};
use tracing_subscriber::fmt::FmtContext;
use tracing_subscriber::registry::LookupSpan;

/// How log lines are written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormat {
    /// The message alone, `warning:` or `error:` before a warning or an
    /// error (as the program has always written them).
    #[default]
    Text,
    /// One JSON object a line: timestamp, level, target and message.
    Json,
}

impl LogFormat {
    pub fn name(self) -> &'static str {
        match self {
            LogFormat::Text => "text",
            LogFormat::Json => "json",
        }
    }
}

/// The environment variable that carries the format to child processes.
pub const ENV: &str = "T2E_LOG_FORMAT";

/// Installs the subscriber; the child processes this one spawns log the
/// same way.
pub fn init(format: LogFormat) {
    // Set while this process is still single-threaded (the first thing
    // `main` does), so no other thread reads the environment meanwhile.
    std::env::set_var(ENV, format.name());
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        // sqlx warns of every statement that waited on another process's
        // write; the league's processes share one store by design.
        .unwrap_or_else(|_| "info,sqlx=error".into());
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        // A line that cannot be written (stderr on a full disk) is dropped:
        // reporting it would print to the same stderr, and panic there.
        .log_internal_errors(false);
    let _ = match format {
        LogFormat::Text => builder.event_format(Plain).try_init(),
        LogFormat::Json => builder.json().try_init(),
    };
}

/// The plain text format: the message, with the level where it is not
/// plain information.
struct Plain;

impl<S, N> FormatEvent<S, N> for Plain
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> fmt::Result {
        let meta = event.metadata();
        match *meta.level() {
            Level::ERROR => write!(writer, "error: ")?,
            Level::WARN => write!(writer, "warning: ")?,
            Level::INFO => {}
            level => write!(writer, "{level} {}: ", meta.target())?,
        }
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}
