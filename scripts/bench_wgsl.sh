#!/bin/bash
# The WGSL tables' throughput on this machine's Vulkan device (lavapipe without a GPU): T, c and
# σ of every group per point by nephele_evaluate_all against eight nephele_evaluate(g, at)
# calls, T alone likewise, and an earlier version's kernel (default: the last commit whose port
# took one group per call).
#   scripts/bench_wgsl.sh [COMMIT]
set -euo pipefail
cd "$(dirname "$0")/.."
commit=${1:-156a694}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
for f in math ntt order1 phase transport collector; do
  git show "$commit:wgsl/src/$f.wgsl" > "$dir/$f.wgsl"
done
git show "$commit:wgsl/tests/tables_kernel.wgsl" > "$dir/tables_kernel.wgsl"
NEPHELE_WGSL_BASELINE=$dir cargo test --release -p nephele-wgsl --test tables \
  all_groups_per_call_throughput_record -- --ignored --nocapture 2>&1 | grep -E "points/s|x the"
