#!/usr/bin/env bash
# The C ABI's batch entry on the caller's threads: points per second on one thread and on
# THREADS threads sharing one tables handle, alternately in one process (examples/c/
# nephele_threads.c, the fastest of ROUNDS passes of each), RUNS times.
#   bash scripts/bench_capi_threads.sh [POINTS] [THREADS] [ROUNDS] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
points=${1:-100000}
threads=${2:-2}
rounds=${3:-8}
runs=${4:-5}
cargo build --release --locked -q -p nephele-c
exe=$(mktemp -d)/nephele_threads
cc -O2 -std=c99 -I capi/include examples/c/nephele_threads.c ${CARGO_TARGET_DIR:-target}/release/libnephele_c.a \
    -lm -lpthread -ldl -o "$exe"
for _ in $(seq "$runs"); do
    "$exe" runtime/tables/mie10um/transport.ntt "$points" "$threads" "$rounds" | tr '\n' ' '
    echo
done
