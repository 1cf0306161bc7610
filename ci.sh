#!/usr/bin/env bash
# The one test command: everything CI checks, runnable on a fresh Debian machine that has only
# the Rust toolchain (rustup). Usage: ./ci.sh
set -euo pipefail
cd "$(dirname "$0")"

# Each step prints the minutes since the start, so a slow step shows in the log.
start=$SECONDS
step() { printf '\n==> [%d min] %s\n' "$(((SECONDS - start) / 60))" "$*"; }

step "toolchain (rust-toolchain.toml: pinned version, rustfmt, clippy, thumbv7em-none-eabihf)"
rustup toolchain install
rustup show active-toolchain

step "format"
cargo fmt --all -- --check

step "layering (scripts/check_layers.sh: what each crate and core::wire may import; burn only behind learn)"
scripts/check_layers.sh

step "clippy, default features and with the learned retargeter (learn)"
cargo clippy --workspace --all-targets -- -D warnings
cargo clippy --workspace --all-targets --features posecoach-cli/learn,posecoach-tests/learn -- -D warnings

# Installs Debian packages when this user may (root or password-less sudo); else says why not.
apt_install() {
    if [ "$(id -u)" -eq 0 ]; then sudo=""; elif sudo -n true 2>/dev/null; then sudo="sudo"; else sudo="none"; fi
    if [ "$sudo" = none ] || ! command -v apt-get >/dev/null 2>&1; then
        echo "no apt-get or no root: cannot install $*"
        return 1
    fi
    $sudo apt-get update -qq && $sudo apt-get install -y -qq "$@" >/dev/null
}

step "chromium for the HTML report's rendering test (skipped, with a message, where it cannot be installed)"
if ! command -v chromium >/dev/null 2>&1; then
    apt_install chromium || echo "could not install chromium: the report rendering test will skip"
fi

step "tests"
cargo test --workspace

step "coaching benchmark, small configuration (planted flaws, phone noise, the device's session), optimized: unoptimized it takes some 19 min"
cargo run -q --release -p posecoach-cli -- bench coaching --quick

step "tests of the learned retargeter's commands (the learn feature: train, export, eval, --weights)"
# --workspace keeps every dependency's features as in the step above: only our two crates rebuild.
cargo test --workspace --features posecoach-cli/learn,posecoach-tests/learn --test learned --test int8

step "installs as a Rust tool: cargo install --locked --path host-tools, then the installed posecoach runs the demo"
install_root="$(mktemp -d)"
cargo install --quiet --locked --path host-tools --root "$install_root" --target-dir target
"$install_root/bin/posecoach" demo --out-dir "$install_root/demo" >/dev/null
"$install_root/bin/posecoach" --version

step "one host binary for every CPU: the DTW's cell costs chosen at run time (its tests and the demo under qemu-x86_64 as a Nehalem, SSE4.2 without AVX, and a Haswell, AVX2), and an aarch64 build (the demo under qemu-aarch64); every demo report the bytes this machine writes"
if ! { command -v qemu-x86_64 && command -v qemu-aarch64 && command -v aarch64-linux-gnu-gcc; } >/dev/null 2>&1; then
    apt_install qemu-user gcc-aarch64-linux-gnu libc6-dev-arm64-cross
fi
rustup target add aarch64-unknown-linux-gnu
cargo build --release -q -p posecoach-cli
dtw_tests="$(cargo test -p posecoach-core --lib --no-run 2>&1 | sed -n 's/.*Executable unittests src\/lib.rs (\(.*\))/\1/p')"
CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc cargo build --release -q -p posecoach-cli --target aarch64-unknown-linux-gnu
cpus="$(mktemp -d)"
target/release/posecoach demo --out-dir "$cpus/here" >/dev/null
for cpu in Nehalem Haswell; do
    qemu-x86_64 -cpu "$cpu" "$dtw_tests" dtw 2>/dev/null
    qemu-x86_64 -cpu "$cpu" target/release/posecoach demo --out-dir "$cpus/$cpu" >/dev/null 2>&1
    cmp "$cpus/here/report.json" "$cpus/$cpu/report.json"
done
qemu-aarch64 -L /usr/aarch64-linux-gnu target/aarch64-unknown-linux-gnu/release/posecoach demo --out-dir "$cpus/aarch64" >/dev/null
cmp "$cpus/here/report.json" "$cpus/aarch64/report.json"

step "thumbv7em-none-eabihf: core and adapters without std, with and without defmt"
cargo build -p posecoach-core -p posecoach-adapters --target thumbv7em-none-eabihf
cargo build -p posecoach-core -p posecoach-adapters --target thumbv7em-none-eabihf --features posecoach-core/defmt,posecoach-adapters/defmt

step "no alloc: link both crates into a Cortex-M4F static library with no global allocator"
(cd firmware-examples/no-alloc-check && cargo build --release && cargo build --release --features defmt)

step "Cortex-M4F firmware on QEMU mps2-an386: the whole pipeline on a recorded session and on a hostile one, every reply equal to the host's, every message within its instruction budget, and its costs"
command -v qemu-system-arm >/dev/null 2>&1 && command -v size >/dev/null 2>&1 || apt_install qemu-system-arm binutils
command -v defmt-print >/dev/null 2>&1 || cargo install defmt-print --locked --version 1.2.0
firmware-examples/qemu-m4f/measure.sh

step "nRF52840 board example (XIAO nRF52840 Sense: LSM6DS3 IMU over I2C, UART to the phone): builds"
(cd firmware-examples/nrf52840-imu && cargo build --release && size target/thumbv7em-none-eabihf/release/posecoach-nrf52840-imu)

step "fuzz: every byte parser for 30 s from its committed corpus (nightly, cargo-fuzz)"
rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked
fuzz/run.sh 30

step "Miri: the core's unit tests (no asm! on this host; one case per property test, the heaviest on smaller inputs, the network's whole windows and the sequence's noisy swings left out)"
# libm's x86 square root is an asm! block, which Miri cannot run: its software one rounds the
# same. Isolation off: proptest looks up the working directory for its failure file. Under
# cfg(miri) the heaviest tests take fewer frames, swings or rows (docs/HOSTILE.md, Miri).
rustup component add --toolchain nightly miri rust-src
MIRIFLAGS="-Zmiri-disable-isolation" PROPTEST_CASES=1 \
    cargo +nightly miri test -p posecoach-core --lib --features libm/force-soft-floats

step "docs"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps

step "all checks passed"
