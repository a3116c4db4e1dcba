#!/usr/bin/env bash
# Phase-model speed: nephele-runtime (examples/bench_phase.rs) next to the renderer-style f32
# closed forms of benches/baselines/phase_ref.c, built with cc -O3 -march=native, in one run.
# First one full run of each; then, for issue 30's comparisons, the two binaries alternately
# ROUNDS times (default 30) on N/5 calls each (nephele's f32 models only), the order swapped
# every round: on a VM whose clock drifts within a minute the ratio of two runs a fraction of a
# second apart is what holds, and the median of many such ratios (with its quartiles) is the
# figure to quote.
# Usage: scripts/bench_phase.sh [N [ROUNDS]]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
n=${1:-10000000}
rounds=${2:-30}
ref=benches/baselines/phase_ref.c
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bash scripts/simd_level.sh
cc -O3 -march=native -o "$tmp/phase_ref" "$ref" -lm
cargo build --release --quiet --example bench_phase
echo "== benches/baselines/phase_ref.c (f32 closed forms, d = 20 µm blend)"
"$tmp/phase_ref" "$n"
echo
echo "== nephele-runtime (same loop shape; models behind a trait object)"
target/release/examples/bench_phase "$n"
echo
short=$(( n / 5 ))
echo "== $rounds rounds, the two binaries alternately ($short calls each)"
ns='\s+([0-9.]+) ns'
python3 scripts/alternate.py --rounds "$rounds" --a "$tmp/phase_ref $short" \
    --b "target/release/examples/bench_phase $short f32" \
    --quantity "HG eval" "^hg eval$ns" "^f32 hg eval \(static\)$ns" \
    --quantity "HG+Draine eval" "^hg\+draine eval$ns" "^f32 hg\+draine \(d = 20 µm\) eval \(static\)$ns" \
    --quantity "HG+Draine sample" "^hg\+draine sample$ns" "^f32 hg\+draine \(d = 20 µm\) sample \(static\)$ns" \
    --quantity "Draine sample (lobe, trait object)" "^draine sample$ns" "^f32 draine \(d = 20 µm lobe\) sample$ns" \
    --label "nephele / C, time per call (issue 30: ≤ 1.0 each)"
