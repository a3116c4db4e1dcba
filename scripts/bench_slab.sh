#!/usr/bin/env bash
# Slab walk speed: nephele's walk with full tallies (examples/bench_slab.rs) next to the plain
# scalar C walk of benches/baselines/slab_ref.c (cc -O3 -march=native), same problem (τ = 4,
# HG g = 0.9, normal incidence), one core each, in one run. The walk tallies what every table
# made from a config tallies: the cells' collector moments and the 9 aureole annuli around the
# beam. Last, the walk with the Mie phase function of 10 µm droplets (what the default tables
# walk with) at mu_L = 0.5.
# For the ratio, refbench/ (nephele-refbench) compiles slab_ref.c unchanged into one process
# with nephele's walk and runs the two alternately ROUNDS times (default 40) on PHOTONS photons
# each (default 500 000, about 0.1 s a walk), the order swapped every round: on a VM whose clock
# drifts by ±25 % within a minute, the ratio of two walks a tenth of a second apart is what
# holds, and the median of many such ratios (with its quartiles) is the figure to quote.
# (Rounds of 4·10⁶ photons, 1.5 s apart, gave medians 0.93 and 0.99 from the same binaries.)
# Usage: scripts/bench_slab.sh [PHOTONS [ROUNDS]]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
n=${1:-500000}
rounds=${2:-40}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bash scripts/simd_level.sh
cc -O3 -march=native -o "$tmp/slab_ref" benches/baselines/slab_ref.c -lm
cargo build --release --quiet --example bench_slab
echo "== benches/baselines/slab_ref.c (analog walk, totals and 10 μ bins), once:"
"$tmp/slab_ref" 4 0.9 "$n" | head -2
echo "== nephele slab walk (16 planes × 16 μ_V × 12 ψ_V × 9 groups, collector moments, 9 aureole annuli), once:"
${CARGO_TARGET_DIR:-target}/release/examples/bench_slab "$n"
echo "== $rounds rounds in one process: slab_ref.c (compiled unchanged) and nephele's walk alternately"
cargo run --release --quiet -p nephele-refbench -- slab "$n" "$rounds"
echo
echo "== the same at mu_L = 0.5 (the plain tally; slab_ref.c has normal incidence only)"
${CARGO_TARGET_DIR:-target}/release/examples/bench_slab "$n" 0.5
echo
echo "== the Mie phase function of 10 µm droplets at mu_L = 0.5 (the default tables' walk)"
${CARGO_TARGET_DIR:-target}/release/examples/bench_slab "$n" 0.5 mie10
