fn main() {
    if let Err(e) = t2e::cli::main() {
        // Through the log, so `--log-format json` gets the cause as JSON
        // too; the text format writes `error: ...` as before.
        tracing::error!("{e:#}");
        std::process::exit(1);
    }
}
