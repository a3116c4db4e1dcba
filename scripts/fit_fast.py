#!/usr/bin/env python3
"""Fits a fast method's free parameters to a path-traced reference on one training scene:
minimises the relative RMSE of orders >= 2 (luminance, over the reference's opaque pixels) of
`nephele render --method M` against the reference's groups.npy. Octaves: a, b, c (N fixed) by
Nelder-Mead from the engines' defaults (0.5, 0.5, 0.5), each kept in [0, 1]. Collector: the
thickness scale of the local slabs (an ablation of the published method, 1 = as published) by
a bounded scalar search on [0.1, 1]. Writes the result (and its provenance) as JSON; the
study then freezes it for every other scene.

Usage: scripts/fit_fast.py --scene S --reference DIR --out FILE [--method octaves|collector]
       [--bin PATH] [--n 4]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.optimize import minimize, minimize_scalar

LUM = np.array([0.2126, 0.7152, 0.0722])


def scattered(dir_):
    g = np.load(os.path.join(dir_, "groups.npy"))
    return (g[1:].sum(0) * LUM).sum(-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", required=True)
    ap.add_argument("--reference", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default="target/release/nephele")
    ap.add_argument("--n", type=int, default=4)
    ap.add_argument("--method", choices=["octaves", "collector"], default="octaves")
    a = ap.parse_args()
    ref = scattered(a.reference)
    opaque = np.load(os.path.join(a.reference, "opacity.npy")) > 0.5
    if not opaque.any():
        sys.exit("the reference has no opaque pixel")
    tmp = tempfile.mkdtemp()
    calls = []

    def error(extra):
        args = [a.bin, "render", "--scene", a.scene, "--method", a.method, "--out", tmp, *extra]
        subprocess.run(args, check=True, capture_output=True)
        c = scattered(tmp)
        return float(np.sqrt(np.mean((c[opaque] - ref[opaque]) ** 2)) / ref[opaque].mean())

    def loss(x):
        x = np.clip(x, 0.0, 1.0)
        e = error(["--octaves", str(a.n), *map(str, x)])
        calls.append((list(map(float, x)), e))
        print(f"a b c = {x[0]:.4f} {x[1]:.4f} {x[2]:.4f}: relative RMSE {e:.4f}", flush=True)
        return e

    if a.method == "collector":
        def scale_loss(k):
            e = error(["--thickness-scale", str(k)])
            calls.append((float(k), e))
            print(f"thickness scale {k:.4f}: relative RMSE {e:.4f}", flush=True)
            return e
        e1 = scale_loss(1.0)
        res = minimize_scalar(scale_loss, bounds=(0.1, 1.0), method="bounded",
                              options={"xatol": 0.01})
        write(a.out, {
            "what": "the collector renderer's local-slab thickness scale fitted to the path tracer on one training scene (scripts/fit_fast.py --method collector), frozen for every other scene; 1 is the published method",
            "thickness_scale": float(res.x), "training_scene": a.scene, "reference": a.reference,
            "objective": "relative RMSE of orders >= 2 (luminance) over the reference's opaque pixels",
            "rel_rmse_published": e1, "rel_rmse_fitted": float(res.fun), "evaluations": len(calls)})
        return

    start = [0.5, 0.5, 0.5]
    e0 = loss(np.array(start))
    res = minimize(loss, start, method="Nelder-Mead",
                   options={"xatol": 5e-3, "fatol": 1e-4, "maxfev": 80,
                            "initial_simplex": [start, [0.8, 0.5, 0.5], [0.5, 0.8, 0.5], [0.5, 0.5, 0.8]]})
    x = np.clip(res.x, 0, 1)
    out = {
        "what": "multi-octave baseline parameters fitted to the path tracer on one training scene (scripts/fit_fast.py), frozen for every other scene",
        "n": a.n, "a": float(x[0]), "b": float(x[1]), "c": float(x[2]),
        "training_scene": a.scene, "reference": a.reference,
        "objective": "relative RMSE of orders >= 2 (luminance) over the reference's opaque pixels",
        "rel_rmse_defaults": e0, "rel_rmse_fitted": float(res.fun), "evaluations": len(calls),
    }
    write(a.out, out)


def write(path, out):
    """Writes `out` as JSON at `path`, atomically, and prints it."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(out, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
