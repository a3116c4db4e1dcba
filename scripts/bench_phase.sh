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
for r in $(seq "$rounds"); do
    if (( r % 2 )); then
        "$tmp/phase_ref" "$short" > "$tmp/c_$r"
        target/release/examples/bench_phase "$short" f32 > "$tmp/ours_$r"
    else
        target/release/examples/bench_phase "$short" f32 > "$tmp/ours_$r"
        "$tmp/phase_ref" "$short" > "$tmp/c_$r"
    fi
done
python3 - "$tmp" "$rounds" <<'PY'
import re, statistics, sys
tmp, rounds = sys.argv[1], int(sys.argv[2])
def ns(path):
    out = {}
    for line in open(path):
        m = re.match(r"(.*?)\s+([0-9.]+) ns$", line.strip())
        if m:
            out[m.group(1).strip()] = float(m.group(2))
    return out
pairs = [
    ("HG eval", "f32 hg eval (static)", "hg eval"),
    ("HG+Draine eval", "f32 hg+draine (d = 20 µm) eval (static)", "hg+draine eval"),
    ("HG+Draine sample", "f32 hg+draine (d = 20 µm) sample (static)", "hg+draine sample"),
    ("Draine sample (lobe, trait object)", "f32 draine (d = 20 µm lobe) sample", "draine sample"),
]
runs = [(ns(f"{tmp}/ours_{r}"), ns(f"{tmp}/c_{r}")) for r in range(1, rounds + 1)]
print("   nephele / C, time per call (≤ 1: nephele as fast or faster; issue 30's target for each):")
for name, ours, c in pairs:
    r = sorted(o[ours] / k[c] for o, k in runs)
    q = lambda f: r[min(len(r) - 1, int(f * len(r)))]
    print(f"   {name:36s} median {statistics.median(r):.3f}, quartiles {q(0.25):.3f}–{q(0.75):.3f}")
PY
