#!/usr/bin/env bash
# Slab walk speed: nephele's walk with full tallies (examples/bench_slab.rs) next to the plain
# scalar C walk of benches/baselines/slab_ref.c (cc -O3 -march=native), same problem (τ = 4,
# HG g = 0.9, normal incidence), one core each, in one run. The walk tallies what every table
# made from a config tallies: the cells' collector moments and the 9 aureole annuli around the
# beam. Last, the walk with the Mie phase function of 10 µm droplets (what the default tables
# walk with) at mu_L = 0.5.
# The C walk and nephele's run alternately ROUNDS times (default 3): on a VM whose clock drifts
# between minutes, the ratio within a round is what holds; the median of the rounds' ratios is
# the figure to quote.
# Usage: scripts/bench_slab.sh [PHOTONS [ROUNDS]]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
n=${1:-2000000}
rounds=${2:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bash scripts/simd_level.sh
cc -O3 -march=native -o "$tmp/slab_ref" benches/baselines/slab_ref.c -lm
cargo build --release --quiet --example bench_slab
rate() { grep -o '[0-9.]* M events/s' | head -1 | cut -d' ' -f1; }
ratios=()
for r in $(seq "$rounds"); do
    echo "== round $r: benches/baselines/slab_ref.c (analog walk, totals and 10 μ bins)"
    c_out=$("$tmp/slab_ref" 4 0.9 "$n" | head -2)
    echo "$c_out"
    echo "== round $r: nephele slab walk (16 planes × 16 μ_V × 12 ψ_V × 9 groups, collector moments, 9 aureole annuli)"
    ours_out=$(target/release/examples/bench_slab "$n")
    echo "$ours_out"
    ratio=$(python3 -c "print(f'{$(rate <<< "$ours_out") / $(rate <<< "$c_out"):.3f}')")
    echo "   round $r: nephele / C = $ratio"
    ratios+=("$ratio")
done
python3 - "${ratios[@]}" <<'PY'
import statistics, sys
r = sorted(float(x) for x in sys.argv[1:])
print(f"== nephele / C walk, μ_L = 1, over {len(r)} rounds: median {statistics.median(r):.3f}, "
      f"range {r[0]:.3f}–{r[-1]:.3f} (issue 30: ≥ 1.0)")
PY
echo
echo "== the same at mu_L = 0.5 (the plain tally; slab_ref.c has normal incidence only)"
target/release/examples/bench_slab "$n" 0.5
echo
echo "== the Mie phase function of 10 µm droplets at mu_L = 0.5 (the default tables' walk)"
target/release/examples/bench_slab "$n" 0.5 mie10
