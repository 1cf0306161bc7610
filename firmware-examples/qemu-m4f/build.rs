//! Puts `memory.x` where the linker finds it, and rebuilds when the embedded files change.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::copy("memory.x", out.join("memory.x")).expect("memory.x is beside build.rs");
    println!("cargo:rustc-link-search={}", out.display());
    for file in [
        "memory.x",
        "../../coaches/driver.pcr",
        "../../coaches/iron.pcr",
        "../../tests/logs/device_h36m_30hz.pclog",
        "../../tests/logs/device_h36m_30hz.device.bin",
        "../../tests/logs/device_h36m_30hz.int8.device.bin",
        "../../tests/logs/hostile_h36m_30hz.pclog",
        "../../tests/logs/hostile_h36m_30hz.device.bin",
        "../../tests/logs/hostile_h36m_30hz.int8.device.bin",
        "../../weights/distilled-int8.pcw",
        "../../weights/distilled-int8.golden-in.pcr",
        "../../weights/distilled-int8.golden-out.pcr",
    ] {
        println!("cargo:rerun-if-changed={file}");
    }
}
