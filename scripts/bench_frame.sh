#!/usr/bin/env bash
# Frame cost of the collector renderer (docs/collector.md, "Frame cost"): the default cumulus
# at 320 × 240 and 640 × 480, VIEWS views on an orbit from one set of light maps
# (`nephele render --orbit`), on all cores. Prints the whole command's wall time (start-up,
# the Mie phase function from the cache after the first run, writing the outputs), the maps'
# seconds once, the first frame's, and the frames with the maps reused (mean, frames/s).
# Usage: scripts/bench_frame.sh [VIEWS] [METHOD] [RENDER FLAGS...]
# (e.g. `scripts/bench_frame.sh 4 collector --search-block 2`: one search per 2 × 2 pixels)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
views=${1:-5}
method=${2:-collector}
shift $(( $# < 2 ? $# : 2 ))
extra=("$@")
cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "cores: $(nproc); CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
# The Mie phase function of the scene is computed once and cached (src/mie/cache.rs).
${CARGO_TARGET_DIR:-target}/release/nephele render --scene fit-configs/scenes/cloud.json --method "$method" \
    --size 40 30 --out "$tmp/warm" > /dev/null
for size in "320 240" "640 480"; do
    read -r w h <<< "$size"
    start=$(date +%s%N)
    ${CARGO_TARGET_DIR:-target}/release/nephele render --scene fit-configs/scenes/cloud.json --method "$method" \
        --size "$w" "$h" "${extra[@]}" --out "$tmp/one" > /dev/null
    wall_ms=$(( ($(date +%s%N) - start) / 1000000 ))
    ${CARGO_TARGET_DIR:-target}/release/nephele render --scene fit-configs/scenes/cloud.json --method "$method" \
        --size "$w" "$h" --orbit "$views" "${extra[@]}" --out "$tmp/orbit" > /dev/null
    python3 - "$tmp/orbit/views.json" "$w" "$h" "$wall_ms" "${extra[*]}" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s, v = d["seconds"], d["views"]
pixels = [x["seconds_per_stage"]["pixels"] for x in v[1:]]
print(f"{sys.argv[2]}×{sys.argv[3]} {d['method']} {sys.argv[5]}: whole command (one frame) {int(sys.argv[4]) / 1000:.2f} s; "
      f"setup (medium, phase functions, table check) {s['setup_medium_phase_tables']:.3f} s, light maps {s['light_maps_once']:.3f} s, "
      f"sky table {s['sky_table_once']:.3f} s (once); first frame {v[0]['frame_seconds']:.3f} s; "
      f"maps reused: frame {s['mean_frame_with_maps_reused']:.3f} s "
      f"(pixels {min(pixels):.3f}–{max(pixels):.3f} s), {d['frames_per_second_with_maps_reused']:.2f} frames/s")
PY
done
