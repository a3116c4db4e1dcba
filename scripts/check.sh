#!/usr/bin/env bash
# Independent cross-checks of nephele against reference implementations.
#
# Usage: scripts/check.sh [--no-build] [--quick] [--log-dir DIR]
#   --no-build     use the existing target/release/nephele instead of running cargo
#   --quick        pass --quick to every check script
#   --log-dir DIR  also keep each check's output, exit status and seconds in DIR (as
#                  scripts/results.sh --checks-from reads them)
#
# Creates .venv at the repository root if missing, installs scripts/requirements.txt into it
# (skipped when the requirements file is unchanged since the last install, or when pip freeze
# already satisfies every pin), builds the release binary, then runs every check script listed
# in CHECKS. Exits non-zero if any check fails.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
start=$(date +%s)
# Prints a step with the seconds since the start, so a slow step shows in the log.
step() { echo "== [$(( $(date +%s) - start )) s] $*"; }

# Check scripts, run in this order; add new ones here (e.g. check_mitsuba.py).
CHECKS=(
    check_mie.py
    check_mitsuba.py
    check_fit.py
    check_slab.py
    check_transport.py
    check_render_mitsuba.py
    check_fog_mitsuba.py
)

BUILD=1
ARGS=()
LOG_DIR=""
while (( $# )); do
    arg=$1
    shift
    case "$arg" in
        --no-build) BUILD=0 ;;
        --quick) ARGS+=(--quick) ;;
        --log-dir) LOG_DIR=${1:?--log-dir needs a directory}; shift; mkdir -p "$LOG_DIR" ;;
        -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "check.sh: unknown option '$arg'" >&2; exit 2 ;;
    esac
done

source "$ROOT/scripts/python_env.sh"

if [[ $BUILD == 1 ]]; then
    step "cargo build --release --locked"
    cargo build --release --locked
fi
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/nephele"
if [[ ! -x "$BIN" ]]; then
    echo "check.sh: $BIN not found (run without --no-build)" >&2
    exit 2
fi

failed=()
# The Python module (python/, PyO3): an abi3 wheel built by maturin, installed with pip into a
# fresh venv as a user would install it, then its tests there, which compare it with the CLI
# above and with closed forms.
echo
step "python module: an abi3 wheel (maturin build), pip install into a fresh venv, python/tests/test_nephele.py"
WHEELS=$(mktemp -d)
if ! ("$VENV/bin/maturin" build --release --locked -m "$ROOT/python/Cargo.toml" -o "$WHEELS" --quiet \
      && python3 -m venv "$WHEELS/venv" \
      && "$WHEELS/venv/bin/pip" install --quiet "$WHEELS"/nephele-*-abi3-*.whl \
            "$(grep '^numpy==' "$REQ")" "$(grep '^scipy==' "$REQ")" \
      && (cd "$WHEELS" && "$WHEELS/venv/bin/python" "$ROOT/python/tests/test_nephele.py" --bin "$BIN")); then
    failed+=("python module")
fi
rm -rf "$WHEELS"
for check in "${CHECKS[@]}"; do
    echo
    step "scripts/$check"
    t0=$(date +%s)
    rc=0
    if [[ -n "$LOG_DIR" ]]; then
        "$PY" "$ROOT/scripts/$check" --bin "$BIN" ${ARGS[@]+"${ARGS[@]}"} 2>&1 \
            | tee "$LOG_DIR/$check.txt" || rc=$?
        echo "$rc" >"$LOG_DIR/$check.rc"
        echo $(( $(date +%s) - t0 )) >"$LOG_DIR/$check.s"
    else
        "$PY" "$ROOT/scripts/$check" --bin "$BIN" ${ARGS[@]+"${ARGS[@]}"} || rc=$?
    fi
    (( rc == 0 )) || failed+=("$check")
done

echo
if (( ${#failed[@]} )); then
    echo "check.sh: FAILED: ${failed[*]}"
    exit 1
fi
echo "check.sh: the python module and all ${#CHECKS[@]} check(s) passed in $(( $(date +%s) - start )) s"
