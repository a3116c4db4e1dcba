#!/usr/bin/env python3
"""Benchmark nephele's polydisperse Mie job against miepython (numba JIT) on this machine.

The job (spec 10 product rule): log-normal, d_med = 5 and 20 um, sigma = 0.25, 41 sizes,
31 wavelengths 400-700 nm, the 2251-angle reference grid, m = 1.333; the phase function
p_lambda(theta) = sum_i w_i (|S1|^2 + |S2|^2)/2 / sum_i w_i pi x_i^2 Q_sca,i at every wavelength.

* nephele: `nephele --threads T mie --diameter D --sizes 41 --wavelengths 400:700:31`, best of
  N runs; wall time of the process and the compute time it reports in phase.json.
* miepython: the same table (all 41 x 31 spheres' S1, S2 at 2251 angles, Q_sca, g and the
  weighted sums), best of 3 after a warm-up that compiles the JIT kernels.
* single-core DGEMM rate of numpy's BLAS (2048 x 2048, best of 5), the yardstick for
  nephele's GFLOP/s.
* wall times of the converged default at d = 20 um and of the 46-diameter paper range.

Speed targets: >= 30x miepython on one thread (>= 35x on two),
nephele's one-thread GFLOP/s >= 70% of DGEMM. They are reported as PASS/MISS and never fail
the script. On a VM whose clock drifts, scripts/bench_mie_gemm.py gives the steadier DGEMM
fraction (the two interleaved, best of N each).

Usage: scripts/bench_mie.py [--bin PATH] [--repeats N] [--json PATH] [--skip-range]
"""

from __future__ import annotations

import os

# BLAS and numba thread counts must be fixed before numpy / numba load.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
             "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"
os.environ["MIEPYTHON_USE_JIT"] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_mie  # noqa: E402  (shared product rule and miepython reference table)

REPO = Path(__file__).resolve().parent.parent
DIAMETERS = (5.0, 20.0)
WAVELENGTHS = "400:700:31"
TARGET_1T = 30.0
TARGET_2T = 35.0
TARGET_DGEMM_FRACTION = 0.7


def cpu_name() -> str:
    """CPU model from /proc/cpuinfo (or platform)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def dgemm_gflops(n: int = 2048, repeats: int = 5) -> float:
    """Best-of-`repeats` single-thread DGEMM rate of numpy's BLAS, GFLOP/s (2 n^3 flops)."""
    rng = np.random.default_rng(1)
    a = rng.random((n, n))
    b = rng.random((n, n))
    a @ b  # warm-up
    best = min(timed(lambda: a @ b)[0] for _ in range(repeats))
    return 2.0 * n**3 / best / 1e9


def timed(fn):
    """(seconds, result) of one call."""
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def run_nephele(binary: Path, threads: int, out: Path, *args: str) -> dict:
    """One `nephele --threads T mie ... --out OUT --no-plot` run: wall and reported timings."""
    cmd = [str(binary), "--threads", str(threads), "mie", *args, "--out", str(out), "--no-plot"]
    wall, _ = timed(lambda: subprocess.run(cmd, check=True, capture_output=True))
    json_path = out / "phase.json"
    if not json_path.exists():  # several diameters: one sub-directory per table
        json_path = sorted(out.glob("*/phase.json"))[0]
    t = json.loads(json_path.read_text())["timings"]
    return dict(wall_s=wall, compute_s=t["compute_s"], gflop=t["gflop"],
                gflop_with_padding=t.get("gflop_with_padding", t["gflop"]),
                gflop_per_s=t["gflop_per_s"], gemm_gflop_per_s=t.get("gemm_gflop_per_s", 0.0),
                spheres=t["spheres"], threads=t["threads"])


def best_nephele(binary: Path, threads: int, out: Path, repeats: int, *args: str) -> dict:
    """Best of `repeats` runs: minimum wall and minimum compute time (each over all runs)."""
    runs = [run_nephele(binary, threads, out, *args) for _ in range(repeats)]
    fastest = min(runs, key=lambda r: r["compute_s"])
    return dict(fastest, wall_s=min(r["wall_s"] for r in runs), runs=len(runs),
                all_wall_s=[r["wall_s"] for r in runs], all_compute_s=[r["compute_s"] for r in runs])


def miepython_job(mp, d_med: float, mu: np.ndarray, lam: np.ndarray) -> float:
    """Seconds for the full product-rule table with miepython (best of 3)."""
    return min(timed(lambda: check_mie.reference_table(mp, d_med, lam, mu, complex(check_mie.WATER, 0)))[0]
               for _ in range(3))


def unpadded_gflop(d_med: float, n_angles: int) -> float:
    """GEMM work of the job without padding: the documented S1 +/- S2 products of nephele's batch
    (2 real products of 2 rows x N_i terms x n_angles per sphere: 8 N_i n_angles flops) over its
    34 x 41 spheres (31 grid + 3 LUT wavelengths), plus the weighted sums (2 x 41 x n_angles per row)."""
    d, _ = check_mie.product_rule(d_med)
    lam = np.concatenate([np.linspace(400.0, 700.0, 31), check_mie.LUT_NM])
    x = np.pi * d[None, :] * 1000.0 / lam[:, None]
    n_terms = np.floor(x + 4.05 * np.cbrt(x) + 2.0)
    return (8.0 * n_terms.sum() * n_angles + 2.0 * x.size * n_angles) / 1e9


def verdict(value: float, target: float) -> str:
    """PASS if value >= target, else MISS."""
    return "PASS" if value >= target else "MISS"


def parse_args(argv=None) -> argparse.Namespace:
    """Command line."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=check_mie.DEFAULT_BIN, help="nephele binary (default: %(default)s)")
    ap.add_argument("--repeats", type=int, default=5, help="nephele runs per configuration (default: %(default)s)")
    ap.add_argument("--json", type=Path, default=REPO / "outputs" / "bench" / "bench_mie.json",
                    help="where to write the results (default: %(default)s)")
    ap.add_argument("--skip-range", action="store_true", help="skip the 46-diameter run (about a minute)")
    return ap.parse_args(argv)


def main(argv=None) -> int:
    """Runs the benchmark, prints the tables and writes the JSON."""
    args = parse_args(argv)
    binary = args.bin.resolve()
    if not binary.is_file():
        print(f"error: nephele binary not found at {binary}", file=sys.stderr)
        return 2
    load = os.getloadavg()
    print(f"machine: {cpu_name()}, {os.cpu_count()} logical CPUs, load average {load[0]:.2f} {load[1]:.2f}")
    simd = subprocess.run(["bash", str(Path(__file__).resolve().parent / "simd_level.sh")],
                          capture_output=True, text=True)
    print("  " + (simd.stdout.strip() or "SIMD level: unknown"))
    if load[0] > 0.5:
        print("  warning: the machine is busy; timings may be pessimistic")
    version = subprocess.run([str(binary), "--version"], capture_output=True, text=True).stdout.strip()
    print(f"nephele: {binary} ({version})")

    gemm = dgemm_gflops()
    print(f"numpy DGEMM 2048x2048, 1 thread (best of 5): {gemm:.1f} GFLOP/s")

    t_imp, mp = timed(check_mie.import_miepython)
    mu = np.cos(np.radians(check_mie.expected_angles()))
    lam = np.linspace(400.0, 700.0, 31)
    # Warm-up: compile / load every kernel the job uses, on the largest sphere of the job.
    x_max = float(np.pi * max(DIAMETERS) * np.exp(check_mie.SIGMA * check_mie.Z_MAX) * 1000 / 400)
    mp.S1_S2(complex(check_mie.WATER, 0), x_max, mu, norm="wiscombe")
    mp.efficiencies_mx(complex(check_mie.WATER, 0), x_max)

    jobs = []
    with tempfile.TemporaryDirectory(prefix="nephele-bench-") as tmpdir:
        tmp = Path(tmpdir)
        for d in DIAMETERS:
            margs = ("--diameter", f"{d:g}", "--sizes", str(check_mie.N_SIZES), "--wavelengths", WAVELENGTHS)
            t_mp = miepython_job(mp, d, mu, lam)
            one = best_nephele(binary, 1, tmp / "job", args.repeats, *margs)
            two = best_nephele(binary, 2, tmp / "job", args.repeats, *margs)
            jobs.append(dict(d_med_um=d, miepython_s=t_mp, nephele_1t=one, nephele_2t=two,
                             unpadded_gflop=unpadded_gflop(d, len(mu)),
                             ratio_1t_wall=t_mp / one["wall_s"], ratio_1t_compute=t_mp / one["compute_s"],
                             ratio_2t_wall=t_mp / two["wall_s"], ratio_2t_compute=t_mp / two["compute_s"]))
            print(f"  d = {d:g} um done (miepython {t_mp:.2f} s)", flush=True)

        conv = best_nephele(binary, 2, tmp / "conv", 3, "--diameter", "20")
        rng = None if args.skip_range else run_nephele(binary, 2, tmp / "range", "--diameter", "5:50:46")

    print_report(jobs, gemm, conv, rng, args.repeats)
    result = dict(
        machine=dict(cpu=cpu_name(), logical_cpus=os.cpu_count(), loadavg_at_start=load,
                     python=platform.python_version(), numpy=np.__version__),
        nephele=dict(binary=str(binary), version=version),
        miepython=dict(version=getattr(mp, "__version__", None), jit=True, import_s=t_imp),
        job=dict(sigma=check_mie.SIGMA, sizes=check_mie.N_SIZES, wavelengths=WAVELENGTHS, angles=len(mu),
                 index=check_mie.WATER, note="nephele also computes 650/510/440 nm: 34 wavelength rows, not 31"),
        dgemm_1t_gflop_per_s=gemm,
        jobs=jobs,
        converged_d20_2t=conv,
        range_5_50_46_2t=rng,
        targets=dict(ratio_1t=TARGET_1T, ratio_2t=TARGET_2T, dgemm_fraction=TARGET_DGEMM_FRACTION),
    )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(f"\nwritten {args.json}")
    return 0


def print_report(jobs: list[dict], gemm: float, conv: dict, rng: dict | None, repeats: int) -> None:
    """The result tables."""
    print("\nPolydisperse product-rule job (sigma 0.25, 41 sizes, 31 wavelengths 400-700 nm, 2251 angles, m 1.333)")
    print(f"miepython: best of 3 after warm-up; nephele: best of {repeats}; "
          "ratio = miepython s / nephele s, by process wall time (by reported compute time)")
    head = (f"  {'job':<10} {'miepython s':>11}  {'nephele 1T s':>14} {'ratio 1T':>13} {'':4}"
            f"  {'nephele 2T s':>14} {'ratio 2T':>13} {'':4}  {'GFLOP/s 1T/2T':>13}")
    print(head)
    print("  " + "-" * (len(head) - 2))
    for j in jobs:
        one, two = j["nephele_1t"], j["nephele_2t"]
        print(f"  d={j['d_med_um']:>4g} um {j['miepython_s']:11.3f}  "
              f"{one['wall_s']:6.3f} ({one['compute_s']:.3f}) {j['ratio_1t_wall']:5.1f} ({j['ratio_1t_compute']:5.1f}) "
              f"{verdict(j['ratio_1t_wall'], TARGET_1T):4}  "
              f"{two['wall_s']:6.3f} ({two['compute_s']:.3f}) {j['ratio_2t_wall']:5.1f} ({j['ratio_2t_compute']:5.1f}) "
              f"{verdict(j['ratio_2t_wall'], TARGET_2T):4}  "
              f"{one['gflop_per_s']:5.1f} / {two['gflop_per_s']:5.1f}")
    tot_mp = sum(j["miepython_s"] for j in jobs)
    tot1 = sum(j["nephele_1t"]["wall_s"] for j in jobs)
    tot2 = sum(j["nephele_2t"]["wall_s"] for j in jobs)
    print(f"  {'both':<10} {tot_mp:11.3f}  {tot1:6.3f} {'':7} {tot_mp / tot1:5.1f} {'':7} "
          f"{verdict(tot_mp / tot1, TARGET_1T):4}  {tot2:6.3f} {'':7} {tot_mp / tot2:5.1f} {'':7} "
          f"{verdict(tot_mp / tot2, TARGET_2T):4}")
    print(f"  Targets: >= {TARGET_1T:g}x on 1 thread, >= {TARGET_2T:g}x on 2 threads (PASS/MISS judged on wall time).")
    print("  Note: nephele's job also computes the 650/510/440 nm LUT wavelengths (34 wavelength rows "
          "instead of 31, about 10% more spheres); its times include that work, miepython's do not.")

    print(f"\nGEMM efficiency: numpy DGEMM 1 thread {gemm:.1f} GFLOP/s (2048x2048, best of 5)")
    for j in jobs:
        part = j["nephele_1t"]["gemm_gflop_per_s"] / gemm
        frac = j["nephele_1t"]["gflop_per_s"] / gemm
        print(f"  d={j['d_med_um']:g} um: nephele 1 thread, GEMM part {j['nephele_1t']['gemm_gflop_per_s']:.1f} GFLOP/s "
              f"= {100 * part:.0f}% of DGEMM (target >= {100 * TARGET_DGEMM_FRACTION:.0f}%: "
              f"{verdict(part, TARGET_DGEMM_FRACTION)}); whole job {j['nephele_1t']['gflop_per_s']:.1f} GFLOP/s "
              f"= {100 * frac:.0f}%")
    print("  (GEMM part = the flops of nephele's GEMM calls over the time inside them; whole job = matrix-product")
    print("   flops on non-zero data, without the zero padding of short series and zero weights, over the whole")
    print("   compute time)")
    for j in jobs:
        one = j["nephele_1t"]
        useful = j["unpadded_gflop"] / one["compute_s"]
        print(f"  d={j['d_med_um']:g} um: nephele reports {one['gflop']:.3f} GFLOP of useful work (this script's independent "
              f"count: {j['unpadded_gflop']:.3f}); it performed {one['gflop_with_padding']:.3f} GFLOP; "
              f"useful rate by the independent count, 1 thread: {useful:.1f} GFLOP/s = {100 * useful / gemm:.0f}% of DGEMM")

    print("\nConverged default rule, 2 threads:")
    print(f"  nephele mie --diameter 20            wall {conv['wall_s']:7.2f} s  compute {conv['compute_s']:7.2f} s  "
          f"{conv['spheres']} spheres  {conv['gflop_per_s']:.1f} GFLOP/s  (best of {conv['runs']})")
    if rng is not None:
        print(f"  nephele mie --diameter 5:50:46       wall {rng['wall_s']:7.2f} s  compute {rng['compute_s']:7.2f} s  "
              f"{rng['spheres']} spheres  {rng['gflop_per_s']:.1f} GFLOP/s  (one run)")


if __name__ == "__main__":
    sys.exit(main())
