#!/usr/bin/env bash
# Phase-model speed: nephele-runtime (examples/bench_phase.rs) next to the renderer-style f32
# closed forms of benches/baselines/phase_ref.c, built with cc -O3 -march=native, in one run.
# First one full run of each; then, for the in-process comparisons, refbench/ (nephele-refbench):
# the C baseline compiled unchanged into the same process as nephele, the two loops run one
# right after the other ROUNDS times (default 30) on CALLS calls each (default 10⁷), the order
# swapped every round. On a VM whose clock drifts within a minute the ratio of two runs a few
# milliseconds apart is what holds, and the median of many such ratios (with its quartiles) is
# the figure to quote.
# Usage: scripts/bench_phase.sh [N [ROUNDS [CALLS]]]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
n=${1:-10000000}
rounds=${2:-30}
calls=${3:-10000000}
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
${CARGO_TARGET_DIR:-target}/release/examples/bench_phase "$n"
echo
echo "== $rounds rounds in one process: phase_ref.c (compiled unchanged) and nephele alternately"
cargo run --release --quiet -p nephele-refbench -- phase "$calls" "$rounds"
