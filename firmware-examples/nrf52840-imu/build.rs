//! Puts `memory.x` where the linker finds it, and rebuilds when it or an embedded coach changes.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::copy("memory.x", out.join("memory.x")).expect("memory.x is beside build.rs");
    println!("cargo:rustc-link-search={}", out.display());
    for file in [
        "memory.x",
        "../../coaches/driver.pcr",
        "../../coaches/iron.pcr",
    ] {
        println!("cargo:rerun-if-changed={file}");
    }
}
