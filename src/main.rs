fn main() {
    if let Err(e) = t2e::cli::main() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
