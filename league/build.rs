//! Embeds the libtorch library folder as an rpath so this crate's own test
//! binaries run without LD_LIBRARY_PATH, and rebuilds when a migration
//! changes (`sqlx::migrate!` embeds them).
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_TCH_LIBTORCH_LIB");
    println!("cargo:rerun-if-changed=migrations");
    if let Ok(lib) = std::env::var("DEP_TCH_LIBTORCH_LIB") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{lib}");
        println!("cargo:rustc-link-arg=-Wl,-rpath-link,{lib}");
    }
}
