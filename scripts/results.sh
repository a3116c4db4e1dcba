#!/usr/bin/env bash
# Regenerates docs/results.md: nephele's headline measurements, each stage's against its
# independent reference (miepython, colour-science, Mitsuba 3, DISORT, the path tracer) and the
# speed ratios against the named baselines, every result under the command that produced it,
# with the machine and the date of the run.
#
# Usage: scripts/results.sh [--quick] [--out FILE]
#   --quick     small sizes and few rounds (CI, a few minutes); writes to a temporary file
#               unless --out is given, and checks that the page has the sections of
#               docs/results.md, each with its command and output, every command exiting 0
#   --out FILE  write the page to FILE instead of docs/results.md
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
start=$(date +%s)
step() { echo "== [$(( $(date +%s) - start )) s] $*" >&2; }

QUICK=0
OUT=""
while (( $# )); do
    case "$1" in
        --quick) QUICK=1 ;;
        --out) OUT=${2:?--out needs a file}; shift ;;
        -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "results.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
    shift
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [[ -z "$OUT" ]]; then
    if (( QUICK )); then OUT="$work/results.md"; else OUT="$ROOT/docs/results.md"; fi
fi
# The figures go beside the page (docs/img/ for the committed page).
IMG="$(dirname "$OUT")/img"
(( QUICK )) && [[ "$OUT" == "$ROOT/docs/results.md" ]] && IMG="$work/img"
mkdir -p "$IMG"

source "$ROOT/scripts/python_env.sh"
step "cargo build --release --locked"
cargo build --release --locked --quiet
BIN="${CARGO_TARGET_DIR:-target}/release/nephele"
PYR=".venv/bin/python"
q() { (( QUICK )) && echo "$1" || echo "$2"; }

page="$work/page.md"
summary="$work/summary.md"
sections="$work/sections.md"
: >"$summary"
: >"$sections"
failed=()

# One result: a heading, the command (run from the repository root) and its output.
#   result STAGE TITLE COMMAND...
result() {
    local stage=$1 title=$2
    shift 2
    local shown="$*"
    step "$stage: $shown"
    local t0 rc=0
    t0=$(date +%s)
    "$@" >"$work/out.txt" 2>&1 || rc=$?
    local secs=$(( $(date +%s) - t0 ))
    (( rc == 0 )) || failed+=("$stage: $shown")
    echo "| $stage | \`$shown\` | $rc | $secs |" >>"$summary"
    {
        echo "### $title"
        echo
        echo "\`$shown\`: exit $rc, $secs s."
        echo
        echo '```text'
        # Progress bars and build noise are not results.
        grep -v -e '^\s*Compiling ' -e '^\s*Finished ' -e '^\s*Running ' -e $'\r' "$work/out.txt" \
            | sed -e 's/[[:space:]]*$//'
        echo '```'
        echo
    } >>"$sections"
}

# The collector and the octaves against the path tracer on the default cloud with its sky.
headline() {
    local size=$1 budget=$2 dir="$work/headline"
    rm -rf "$dir"
    "$BIN" render --scene fit-configs/scenes/cloud.json --size $size --time-budget "$budget" \
        --out "$dir/path" >/dev/null &&
    "$BIN" render --scene fit-configs/scenes/cloud.json --size $size --method collector \
        --rays 2 --out "$dir/collector" >/dev/null &&
    "$BIN" render --scene fit-configs/scenes/cloud.json --size $size --method octaves \
        --rays 2 --octaves $(octaves_fitted) --out "$dir/octaves" >/dev/null &&
    "$BIN" compare --reference "$dir/path" --candidate "$dir/collector" \
        --candidate "$dir/octaves" --out "$dir/compare" &&
    cp "$dir/compare/panel.png" "$IMG/results_panel.png" &&
    cp "$dir/compare/errors.png" "$IMG/results_errors.png"
}
octaves_fitted() {
    "$PY" -c 'import json; c = json.load(open("fit-configs/octaves-fitted.json")); print(*[c[k] for k in ("n", "a", "b", "c")])'
}

QARG=$(q --quick "")
result mie "Mie: nephele against miepython and colour-science" \
    "$PYR" scripts/check_mie.py --bin "$BIN" $QARG
result phase "Phase models: sampling and values against Mitsuba 3" \
    "$PYR" scripts/check_mitsuba.py --bin "$BIN" $QARG
result fit "Fitted phase functions against the Mie tables" \
    "$PYR" scripts/check_fit.py --bin "$BIN" $QARG
result slab "Slab transport against independent references" \
    "$PYR" scripts/check_slab.py --bin "$BIN" $QARG
result tables "Compressed tables against the slab walk" \
    "$PYR" scripts/check_transport.py --bin "$BIN" $QARG
result render "The path tracer against Mitsuba 3 (cloud)" \
    "$PYR" scripts/check_render_mitsuba.py --bin "$BIN" $QARG
result fog "The path tracer against Mitsuba 3 (fog and ground)" \
    "$PYR" scripts/check_fog_mitsuba.py --bin "$BIN" $QARG
result collector "The collector and the octaves against the path tracer: the default cloud with its sky" \
    headline $(q "40 30" "160 120") $(q 4 120)
cat >>"$sections" <<'EOF'
Rows: beauty, order 1, orders ≥ 2 and each order group; columns: the path tracer, the
collector with its default correction, the octaves fitted on another scene (the same
exposure per row). Then the signed relative error of order 1 and of orders ≥ 2.

![the default cloud: path tracer, collector, octaves, per order group](img/results_panel.png)

![their signed relative error](img/results_errors.png)

EOF
result speed-phase "Speed: phase models against renderer-style C (benches/baselines/phase_ref.c)" \
    bash scripts/bench_phase.sh $(q "1000000 3 1000000" "")
result speed-slab "Speed: the slab walk against a scalar C walk (benches/baselines/slab_ref.c)" \
    bash scripts/bench_slab.sh $(q "50000 3" "")
result speed-capi "Speed: the C ABI's batch entry on 2 threads against 1" \
    bash scripts/bench_capi_threads.sh $(q "20000 2 2 1" "")
result speed-frame "Speed: the collector's frame (320 × 240 and 640 × 480)" \
    bash scripts/bench_frame.sh $(q 1 5)
result speed-wgsl "Speed: the WGSL port on this machine's Vulkan device" \
    bash scripts/bench_wgsl.sh

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
{
    echo "# Results"
    echo
    echo "Every figure below is a command's output, printed under the command; \`scripts/results.sh\`"
    echo "reruns them all and rewrites this page (\`--quick\`: small sizes, for CI). Speed is given"
    echo "as ratios against the named baseline, both run on this machine in the same run."
    echo
    echo "- Run: $(date -u '+%Y-%m-%d %H:%M UTC'), $(( $(date +%s) - start )) s$( (( QUICK )) && echo ', quick')."
    echo "- Machine: $cpu, $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo); $(uname -sr)."
    echo "- Commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . ':!docs/results.md' || echo ' (with local changes)')."
    echo
    echo "| result | command | exit | s |"
    echo "|---|---|---|---|"
    cat "$summary"
    echo
    cat "$sections"
} >"$page"

# The page holds: every section heading of the committed page, each with its command and
# output; every command exited 0.
headings() { grep '^### ' "$1" || true; }
if (( QUICK )) && [[ -f docs/results.md ]] && ! diff <(headings docs/results.md) <(headings "$page") >&2; then
    failed+=("the sections differ from docs/results.md's (above)")
fi
if [[ $(headings "$page" | wc -l) -ne $(grep -c '^```text' "$page") ]]; then
    failed+=("a section lacks its output")
fi
mkdir -p "$(dirname "$OUT")"
mv "$page" "$OUT.tmp" && mv "$OUT.tmp" "$OUT"
step "wrote $OUT"
if (( ${#failed[@]} )); then
    printf 'results.sh: FAILED: %s\n' "${failed[@]}" >&2
    exit 1
fi
