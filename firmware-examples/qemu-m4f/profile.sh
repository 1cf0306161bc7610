#!/usr/bin/env bash
# Where the firmware's instructions go: runs it under QEMU with the instruction-counting TCG
# plugin (plugin/insns.c, built here with cc), then sums the counts per function of the ELF.
# Prints the exact total and the TOP (default 25) functions. Functions inlined into others
# count as their callers.
# Usage: firmware-examples/qemu-m4f/profile.sh [TOP]   (needs qemu-system-arm, cc, nm)
set -euo pipefail
cd "$(dirname "$0")"
top="${1:-25}"
cargo build --release
elf=target/thumbv7em-none-eabihf/release/posecoach-qemu-m4f
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cc -shared -fPIC -O2 -Wall -o "$work/libinsns.so" plugin/insns.c
qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -icount shift=0 \
    -plugin "$work/libinsns.so,out=$work/counts.txt" -kernel "$elf" >/dev/null
total=$(awk '$1 == "total" { print $2 }' "$work/counts.txt")
echo "instructions executed, whole run (boot, checks, replay, printing): $total"
# Function start addresses (the Thumb bit some symbols carry cleared: a function's first
# block would otherwise count as its neighbour's), then each block's count added to the function
# that starts at or before it.
# ARM mapping symbols ($t, $d) mark code and data runs, not functions.
nm -C -n --defined-only "$elf" | awk '$2 ~ /^[tTwW]$/ && $3 !~ /^\$/ { $2 = ""; print }' >"$work/symbols.txt"
grep -v '^total' "$work/counts.txt" | sort >"$work/blocks.txt"
awk -v total="$total" '
    function hex(s,    i, v) {
        v = 0
        for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", substr(tolower(s), i, 1)) - 1
        return v
    }
    NR == FNR { addr[NR] = hex($1); if (addr[NR] % 2 == 1) addr[NR] -= 1; $1 = ""; sub(/^ +/, ""); name[NR] = $0; n = NR; next }
    {
        at = hex($1); lo = 1; hi = n
        while (lo < hi) { mid = int((lo + hi + 1) / 2); if (addr[mid] <= at) lo = mid; else hi = mid - 1 }
        sum[name[lo]] += $2
    }
    END { for (f in sum) printf "%12d %5.1f%%  %s\n", sum[f], 100 * sum[f] / total, f }
' "$work/symbols.txt" "$work/blocks.txt" | sort -rn | head -n "$top"
