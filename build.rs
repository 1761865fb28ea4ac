//! Embeds the libtorch library folder as an rpath so `t2e-league`, the tests
//! and the benches run without LD_LIBRARY_PATH.
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_TCH_LIBTORCH_LIB");
    if let Ok(lib) = std::env::var("DEP_TCH_LIBTORCH_LIB") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{lib}");
        // Also rpath-link so the linker resolves libtorch's own dependencies.
        println!("cargo:rustc-link-arg=-Wl,-rpath-link,{lib}");
    }
}
