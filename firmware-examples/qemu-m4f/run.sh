#!/usr/bin/env bash
# Cargo's runner for this crate: boots the ELF on QEMU's mps2-an386 (Cortex-M4F) with
# semihosting, one instruction per nanosecond of virtual time (-icount shift=0, which the
# firmware's instruction counts rely on), and decodes its defmt output with defmt-print.
# Exits with the firmware's own exit status.
set -euo pipefail
elf="$1"
qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -icount shift=0 -kernel "$elf" \
    | defmt-print -e "$elf"
