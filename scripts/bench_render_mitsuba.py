#!/usr/bin/env python3
"""Speed of `nephele render` against Mitsuba 3 (scalar_rgb, volpath) on the scene of
check_render_mitsuba.py: camera paths per second, same machine, same run.

    .venv/bin/python scripts/bench_render_mitsuba.py [--rounds 3] [--spp 128] [--json FILE]

The renderers alternate, round after round (so that a slower period of the machine hits
all), on the 24^3 voxel cloud (hg 0.7 and the tabulated 1 um Mie table), at the check's image
size, seed r in round r; both with every core (nephele's rayon pool, Mitsuba's thread pool)
and with one (RAYON_NUM_THREADS=1, drjit.set_thread_count(1)). nephele runs twice: with its
two-vertex next-event estimation (the default: more work per path, less noise) and without
(the same estimator as Mitsuba's volpath). Reported: the median paths/s of each and the ratios
of the medians (nephele / Mitsuba; above 1: nephele is faster); and the efficiency
1 / (relative variance x seconds), the variance per pixel over the rounds averaged over the
cloud's pixels — what a user waits for a given noise — and its ratio. nephele's time is its own
render.json's (the render loop, no start-up or file output); Mitsuba's the mi.render call (no
scene loading). Needs the release binary (cargo build --release) and scripts/requirements.txt.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_render_mitsuba as check  # noqa: E402  (the shared scene)


def nephele_run(bin_path: Path, tmp: Path, phase: dict, w: int, h: int, spp: int, seed: int,
                threads: int | None, guided: bool) -> tuple[np.ndarray, float]:
    """(image, seconds) of one nephele render."""
    env = dict(os.environ)
    env.pop("RAYON_NUM_THREADS", None)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    path = check.write_scene(tmp, check.density_grid(), phase, w, h, spp, seed)
    scene = json.loads(path.read_text())
    if not guided:
        scene["sun_lobe_steps"] = 0  # plain next-event estimation; else the scene's default
    path.write_text(json.dumps(scene))
    out = tmp / "bench"
    subprocess.run([str(bin_path), "render", "--scene", str(path), "--out", str(out)],
                   check=True, capture_output=True, env=env)
    doc = json.loads((out / "render.json").read_text())
    return np.load(out / "beauty.npy").astype(np.float64), doc["seconds"]


def mitsuba_run(phase: dict, w: int, h: int, spp: int, seed: int,
                threads: int | None) -> tuple[np.ndarray, float]:
    import drjit as dr
    dr.set_thread_count(threads or os.cpu_count())
    return check.render_mitsuba(check.density_grid(), phase, w, h, spp, seed)


def efficiency(runs: list[tuple[np.ndarray, float]]) -> float:
    """1 / (mean relative variance per pixel x mean seconds) over the lit pixels."""
    a = np.stack([img[..., 1] for img, _ in runs])
    mean = a.mean(axis=0)
    lit = mean > 0.05 * mean.max()
    rel_var = (a.var(axis=0, ddof=1)[lit]).mean() / mean[lit].mean() ** 2
    return 1.0 / (rel_var * statistics.mean(s for _, s in runs))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=check.DEFAULT_BIN)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--json", type=Path, help="also write the results here")
    args = ap.parse_args(argv)
    w, h = 96, 72
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for case, phase_n, phase_m in check.cases(args.bin, tmp):
            for threads in [None, 1]:
                spp = args.spp if threads is None else max(args.spp // 4, 1)
                runs = {"nephele": [], "nephele, sun-lobe NEE off": [], "mitsuba": []}
                for r in range(1, args.rounds + 1):
                    runs["nephele"].append(nephele_run(args.bin, tmp, phase_n, w, h, spp, r, threads, True))
                    runs["nephele, sun-lobe NEE off"].append(
                        nephele_run(args.bin, tmp, phase_n, w, h, spp, r, threads, False))
                    runs["mitsuba"].append(mitsuba_run(phase_m, w, h, spp, r, threads))
                paths = w * h * spp
                rate = {k: statistics.median(paths / s for _, s in v) for k, v in runs.items()}
                eff = {k: efficiency(v) for k, v in runs.items()}
                n_threads = threads or os.cpu_count()
                for k in ["nephele", "nephele, sun-lobe NEE off"]:
                    print(f"{case:20} {n_threads} thread(s)  {k:24} {rate[k]:>11,.0f} paths/s vs mitsuba "
                          f"{rate['mitsuba']:>11,.0f}: ratio {rate[k] / rate['mitsuba']:5.2f};  efficiency "
                          f"ratio {eff[k] / eff['mitsuba']:5.2f}")
                results.append({"case": case, "threads": n_threads, "spp": spp, "width": w, "height": h,
                                "rounds": args.rounds, "paths_per_s": rate, "efficiency": eff,
                                "ratio_paths_per_s": {k: rate[k] / rate["mitsuba"] for k in rate},
                                "ratio_efficiency": {k: eff[k] / eff["mitsuba"] for k in eff}})
    if args.json:
        import mitsuba as mi
        args.json.write_text(json.dumps({"mitsuba": mi.__version__, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
