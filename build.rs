//! Embeds the libtorch library folder as an rpath so `t2e-league`, the tests
//! and the benches run without LD_LIBRARY_PATH, and keeps libtorch's CUDA
//! library linked into the binary so `tch` sees a GPU where there is one.
//! (The code version that checkpoints record is embedded by
//! crates/learners/build.rs, beside the checkpoint code.)
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_TCH_LIBTORCH_LIB");
    if let Ok(lib) = std::env::var("DEP_TCH_LIBTORCH_LIB") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{lib}");
        // Also rpath-link so the linker resolves libtorch's own dependencies.
        println!("cargo:rustc-link-arg=-Wl,-rpath-link,{lib}");
        // Nothing in our code references libtorch_cuda, so `--as-needed`
        // would drop it and CUDA would look absent. Binaries only: the test
        // binaries stay on the CPU and skip loading the CUDA libraries.
        if std::path::Path::new(&lib).join("libtorch_cuda.so").exists() {
            println!("cargo:rustc-link-arg-bins=-Wl,--no-as-needed,-ltorch_cuda,--as-needed");
        }
    }
}
