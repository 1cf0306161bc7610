#!/usr/bin/env bash
# The layering docs/ARCHITECTURE.md states, checked on the source: exits 1 and names every
# import that breaks it.
#   - core imports no other posecoach crate;
#   - adapters imports only core; io imports only core;
#   - core::wire imports nothing from core::score (the wire is the ground floor; a report
#     turns itself into its wire form), and outside its tests names from the core only config,
#     joint, format and band;
#   - teachfile (the float weights files' layout, which inspect reads without learn) imports no
#     posecoach crate and no burn;
#   - no import circle among a crate's modules (tests, at the bottom of each file, left out);
#   - the default build of posecoach-cli and the tests that do not train link no burn: every
#     use of the trainer or burn in host-tools and tests sits behind the `learn` feature.
set -euo pipefail
cd "$(dirname "$0")/.."
status=0
fail() { echo "layering: $*"; status=1; }

forbid() { # forbid DIR PATTERN WHY
    local hits
    hits=$(grep -rnE "$2" "$1" --include='*.rs' || true)
    [ -z "$hits" ] || fail "$3:"$'\n'"$hits"
}
forbid core/src 'posecoach_(adapters|io|cli|train|tests)\b' "core imports another posecoach crate"
forbid adapters/src 'posecoach_(io|cli|train|tests)\b' "adapters imports more than core"
forbid io/src 'posecoach_(adapters|cli|train|tests)\b' "io imports more than core"
forbid teachfile/src '\b(posecoach_[a-z]+|burn)::' "teachfile imports another posecoach crate or burn"
forbid core/src/wire.rs '(crate|super)::score\b' "core::wire imports core::score"
# What core::wire names from the core outside comments and its tests module: config, joint,
# format and band only (a grouped `crate::{...}` counts as another, so each module is written
# out).
wire_imports=$(sed '/^mod tests {/,$d; s|^ *//.*||' core/src/wire.rs |
    grep -noE '\b(crate|super)::(\{|[A-Za-z_0-9]+)' |
    grep -vE ':(crate|super)::(config|joint|format|band)$' | sed 's|^|core/src/wire.rs:|' || true)
[ -z "$wire_imports" ] ||
    fail "core::wire imports from the core more than config, joint, format and band:"$'\n'"$wire_imports"

grep -nE '^(burn|posecoach-)' teachfile/Cargo.toml && fail "teachfile/Cargo.toml depends on burn or a posecoach crate"
for manifest in core/Cargo.toml adapters/Cargo.toml io/Cargo.toml; do
    if grep -nE '^posecoach-(adapters|io|cli|train)' "$manifest" | grep -v '^.*posecoach-core'; then
        fail "$manifest depends on a crate above it"
    fi
done

# burn and the trainer only behind `learn`: in the manifests as optional dependencies, in the
# sources only in files or items gated on the feature.
for manifest in host-tools/Cargo.toml tests/Cargo.toml; do
    grep -nE '^(burn|posecoach-train) ' "$manifest" | grep -v 'optional = true' &&
        fail "$manifest links burn or the trainer outside the learn feature"
done
for file in $(grep -rlE '\b(burn|posecoach_train)::' host-tools/src tests --include='*.rs' || true); do
    case "$file" in
    host-tools/src/learn.rs) ;; # the module itself is declared under cfg(feature = "learn")
    *) grep -q 'cfg(feature = "learn")' "$file" || fail "$file uses burn or the trainer without the learn feature" ;;
    esac
done
grep -q '#\[cfg(feature = "learn")\]' <(grep -B1 '^pub mod learn;' host-tools/src/lib.rs) ||
    fail "host-tools/src/lib.rs declares learn without the feature"

# Import circles: every `crate::module` / `super::module` a module names outside comments and
# tests is an edge, grouped ones too (`use crate::{a, b::c}` names a and b); tsort finds the
# loops.
# The first path segment after each `crate::` or `super::` on standard input, one a line; a
# group `{a, b::{c, d}}` gives a and b.
named_modules() {
    perl -0777 -ne '
        while (/\b(?:crate|super)::(\{|[a-z_0-9]+)/g) {
            if ($1 ne "{") { print "$1\n"; next }
            my ($depth, $at) = (1, pos);
            my $end = $at;
            while ($depth && $end < length) {
                my $c = substr($_, $end++, 1);
                $depth += ($c eq "{") - ($c eq "}");
            }
            my $group = substr($_, $at, $end - $at - 1);
            1 while $group =~ s/\{[^{}]*\}//g;
            print "$1\n" while $group =~ /(?:^|,)\s*([a-z_0-9]+)/g;
        }'
}
module_edges() {
    local dir=$1 file module target
    for file in $(find "$dir" -name '*.rs'); do
        module=${file#"$dir"/}
        module=${module%.rs}
        module=${module%/mod}
        module=${module%%/*}
        [ "$module" = lib ] || [ "$module" = main ] && continue
        sed '/#\[cfg(test)\]/,$d' "$file" | grep -v '^ *//' | named_modules | sort -u |
            while read -r target; do
                if [ "$target" != "$module" ] && { [ -e "$dir/$target.rs" ] || [ -e "$dir/$target/mod.rs" ]; }; then
                    echo "$module $target"
                fi
            done
    done
}
for dir in core/src adapters/src io/src host-tools/src trainer/src teachfile/src; do
    loops=$(module_edges "$dir" | tsort 2>&1 >/dev/null || true)
    [ -z "$loops" ] || fail "import circle among the modules of $dir:"$'\n'"$loops"
done

[ "$status" -eq 0 ] && echo "layering: ok"
exit "$status"
