#!/usr/bin/env bash
# Regenerates docs/results.md: nephele's headline measurements, each stage's against its
# independent reference (miepython, colour-science, Mitsuba 3, DISORT, the path tracer) and the
# speed ratios against the named baselines, every result under the command that produced it,
# with the machine and the date of the run.
#
# Usage: scripts/results.sh [--quick] [--out FILE] [--checks-from DIR]
#   --quick            small sizes and few rounds (CI); writes to a temporary file unless --out
#                      is given, and checks that the page has the sections of docs/results.md,
#                      each with its command and output, every command exiting 0
#   --out FILE         write the page to FILE instead of docs/results.md
#   --checks-from DIR  take the cross-checks' outputs from `scripts/check.sh --log-dir DIR`
#                      (their full runs) instead of running them again
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
start=$(date +%s)
step() { echo "== [$(( $(date +%s) - start )) s] $*" >&2; }

QUICK=0
OUT=""
CHECKS_FROM=""
while (( $# )); do
    case "$1" in
        --quick) QUICK=1 ;;
        --out) OUT=${2:?--out needs a file}; shift ;;
        --checks-from) CHECKS_FROM=${2:?--checks-from needs a directory}; shift ;;
        -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
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
    local t0 rc=0 secs
    t0=$(date +%s)
    if [[ $1 == from-check-sh ]]; then
        # The full run check.sh made of script $2: its output, exit status and seconds.
        cp "$CHECKS_FROM/$2.txt" "$work/out.txt"
        rc=$(cat "$CHECKS_FROM/$2.rc")
        secs=$(cat "$CHECKS_FROM/$2.s")
        shown="$PYR scripts/$2 --bin $BIN (run in full by scripts/check.sh)"
    else
        "$@" >"$work/out.txt" 2>&1 || rc=$?
        secs=$(( $(date +%s) - t0 ))
    fi
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
            | sed -e 's/[[:space:]]*$//' -e "s#$work/##g"
        echo '```'
        echo
    } >>"$sections"
}

# The collector (as published, and corrected for the finite cloud) and the fitted octaves
# against the path tracer on the default cloud with its sky; the README's picture.
headline() {
    local size="$1 $2" budget=$3 dir="$work/headline" scene=fit-configs/scenes/cloud.json
    rm -rf "$dir"
    "$BIN" render --scene $scene --size $size --time-budget "$budget" --out "$dir/path" \
        >/dev/null &&
    "$BIN" render --scene $scene --size $size --method collector --rays 2 --correction none \
        --out "$dir/collector_as_published" >/dev/null &&
    "$BIN" render --scene $scene --size $size --method collector --rays 2 \
        --out "$dir/collector_corrected" >/dev/null &&
    "$BIN" render --scene $scene --size $size --method octaves --rays 2 \
        --octaves $(octaves_fitted) --out "$dir/octaves_fitted" >/dev/null &&
    "$BIN" compare --reference "$dir/path" --candidate "$dir/collector_as_published" \
        --candidate "$dir/collector_corrected" --candidate "$dir/octaves_fitted" \
        --out "$dir/compare" &&
    cp "$dir/compare/panel.png" "$IMG/results_panel.png" &&
    cp "$dir/compare/errors.png" "$IMG/results_errors.png" &&
    "$PY" scripts/compare_flip.py "$dir/compare" &&
    if (( ! QUICK )); then
        "$PY" scripts/figure_collector.py "$dir/compare" "$IMG/collector.png"
    fi
}
octaves_fitted() {
    "$PY" -c 'import json; c = json.load(open("fit-configs/octaves-fitted.json")); print(*[c[k] for k in ("n", "a", "b", "c")])'
}

# A cross-check of scripts/check.sh: run here, or taken from its full run (--checks-from).
check() {
    if [[ -n "$CHECKS_FROM" ]]; then
        result "$1" "$2" from-check-sh "$3"
    else
        result "$1" "$2" "$PYR" "scripts/$3" --bin "$BIN" $(q --quick "")
    fi
}

check mie "Mie: nephele against miepython and colour-science" check_mie.py
check phase "Phase models: sampling and values against Mitsuba 3" check_mitsuba.py
check fit "Fitted phase functions against the Mie tables" check_fit.py
check slab "Slab transport against independent references" check_slab.py
check tables "Compressed tables against the slab walk" check_transport.py
check render "The path tracer against Mitsuba 3 (cloud)" check_render_mitsuba.py
check fog "The path tracer against Mitsuba 3 (fog and ground)" check_fog_mitsuba.py
result collector "The collector and the octaves against the path tracer: the default cloud with its sky" \
    headline $(q "80 60" "160 120") $(q 10 120)
cat >>"$sections" <<'EOF'
Rows: beauty, order 1, orders ≥ 2 and each order group; columns: the path tracer, the
collector as published, the collector with its default finite-cloud correction, the octaves
fitted on another scene (fit-configs/octaves-fitted.json), each row at one exposure. Then the
signed relative error of order 1 and of orders ≥ 2. A full run (not `--quick`) also draws the
README's picture from these renders (`scripts/figure_collector.py`).

![the default cloud: path tracer, collector, octaves, per order group](img/results_panel.png)

![their signed relative error](img/results_errors.png)

EOF
result speed-phase "Speed: phase models against renderer-style C (benches/baselines/phase_ref.c)" \
    bash scripts/bench_phase.sh $(q "200000 2 200000" "")
result speed-slab "Speed: the slab walk against a scalar C walk (benches/baselines/slab_ref.c)" \
    bash scripts/bench_slab.sh $(q "20000 2" "")
result speed-capi "Speed: the C ABI's batch entry on 2 threads against 1" \
    bash scripts/bench_capi_threads.sh $(q "20000 2 2 1" "")
result speed-frame "Speed: the collector's frame (320 × 240 and 640 × 480)" \
    bash scripts/bench_frame.sh $(q 2 5)
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
    echo "- Commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . ':!docs/results.md' ':!docs/img' || echo ' (with local changes)')."
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
