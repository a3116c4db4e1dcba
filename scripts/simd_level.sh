#!/usr/bin/env bash
# Prints the CPU's model and the x86-64 SIMD level its flags allow (what the binaries'
# run-time dispatch can reach: the builds are for baseline x86-64, never -C target-cpu=native).
# Usage: scripts/simd_level.sh   (run by bench_slab.sh, bench_phase.sh and bench_mie.py)
set -euo pipefail
model=$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//' || true)
flags=" $(grep -m1 '^flags' /proc/cpuinfo 2>/dev/null | cut -d: -f2- || true) "
has() { [[ "$flags" == *" $1 "* ]]; }
if has avx512f && has avx512bw && has avx512vl && has avx512dq; then
    level="x86-64-v4 (AVX-512 F/BW/DQ/VL)"
elif has avx2 && has fma && has bmi2; then
    level="x86-64-v3 (AVX2, FMA)"
elif has sse4_2 && has popcnt; then
    level="x86-64-v2 (SSE4.2)"
elif [[ -n "${flags// /}" ]]; then
    level="x86-64 (SSE2)"
else
    level="unknown (no /proc/cpuinfo)"
fi
echo "CPU: ${model:-unknown}, $(getconf _NPROCESSORS_ONLN) logical CPUs; SIMD level: $level"
