#!/usr/bin/env bash
# Phase-model speed: nephele-runtime (examples/bench_phase.rs) next to the renderer-style f32
# closed forms of benches/baselines/phase_ref.c, built with cc -O3 -march=native, in one run.
# Usage: scripts/bench_phase.sh [N]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
n=${1:-10000000}
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
