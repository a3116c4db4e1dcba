#!/usr/bin/env python3
"""Speed of `nephele render` against Mitsuba 3 (scalar_rgb, volpath) on the scene of
check_render_mitsuba.py: camera paths per second, same machine, same run.

    .venv/bin/python scripts/bench_render_mitsuba.py [--rounds 3] [--spp 128] [--json FILE]

The two renderers alternate, round after round (so that a slower period of the machine hits
both), on the 24^3 voxel cloud (hg 0.7 and the tabulated 1 um Mie table), at the check's image
size; both with every core (nephele's rayon pool, Mitsuba's thread pool) and with one
(RAYON_NUM_THREADS=1, drjit.set_thread_count(1)). Reported: the median paths/s of each and the
ratio of the medians (nephele / Mitsuba; above 1: nephele is faster). nephele's time is its own
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


def nephele_rate(bin_path: Path, tmp: Path, phase: dict, w: int, h: int, spp: int,
                 threads: int | None) -> float:
    env = dict(os.environ)
    env.pop("RAYON_NUM_THREADS", None)
    if threads:
        env["RAYON_NUM_THREADS"] = str(threads)
    path = check.write_scene(tmp, check.density_grid(), phase, w, h, spp, 1)
    out = tmp / "bench"
    subprocess.run([str(bin_path), "render", "--scene", str(path), "--out", str(out)],
                   check=True, capture_output=True, env=env)
    doc = json.loads((out / "render.json").read_text())
    return doc["paths"] / doc["seconds"]


def mitsuba_rate(phase: dict, w: int, h: int, spp: int, threads: int | None) -> float:
    import drjit as dr
    dr.set_thread_count(threads or os.cpu_count())
    _, seconds = check.render_mitsuba(check.density_grid(), phase, w, h, spp, 1)
    return w * h * spp / seconds


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=check.DEFAULT_BIN)
    ap.add_argument("--rounds", type=int, default=3)
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
                rn, rm = [], []
                for _ in range(args.rounds):
                    rn.append(nephele_rate(args.bin, tmp, phase_n, w, h, spp, threads))
                    rm.append(mitsuba_rate(phase_m, w, h, spp, threads))
                n, m = statistics.median(rn), statistics.median(rm)
                label = f"{threads or os.cpu_count()} thread{'s' if (threads or os.cpu_count()) > 1 else ''}"
                print(f"{case:20} {label:10} nephele {n:>11,.0f} paths/s   mitsuba {m:>11,.0f} paths/s   "
                      f"ratio {n / m:5.2f}   (rounds: nephele {', '.join(f'{x:,.0f}' for x in rn)}; "
                      f"mitsuba {', '.join(f'{x:,.0f}' for x in rm)})")
                results.append({"case": case, "threads": threads or os.cpu_count(), "spp": spp,
                                "width": w, "height": h, "nephele_paths_per_s": n,
                                "mitsuba_paths_per_s": m, "ratio": n / m,
                                "rounds_nephele": rn, "rounds_mitsuba": rm})
    if args.json:
        import mitsuba as mi
        args.json.write_text(json.dumps({"mitsuba": mi.__version__, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
