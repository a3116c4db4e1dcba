#!/usr/bin/env python3
"""Per-pixel noise of `nephele render` against wall time, per order group.

Renders a scene (default: the default cloud, fit-configs/scenes/cloud.json) with N independent
seeds, for two lightings — the scene's own sun ("front": behind the camera) and the sun mirrored
behind the cloud ("back") — and reports, over the opaque pixels (opacity > 0.5), the relative
noise of ONE render, s/m (s the standard deviation over the seeds of the green channel, m their
mean): median, RMS and 99th percentile, for the beauty image and for each order group (the
group's standard deviation relative to the pixel's total, so that groups add up), the seconds
per render, and the efficiency 1 / (mean relative variance x seconds). A heavy tail (RMS and the
99th percentile far above the median) is what fireflies look like.

    .venv/bin/python scripts/bench_render_noise.py --seeds 4 --spp 64 --out bench.json

The efficiency ratio between two versions of the renderer, measured the same way on the same
machine in the same run, is the number to compare (wall time depends on the machine).
"""
import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BIN = REPO / "target" / "release" / "nephele"
DEFAULT_SCENE = REPO / "fit-configs" / "scenes" / "cloud.json"


def lightings(scene):
    """The scene's own sun, and the sun mirrored behind the cloud (same elevation)."""
    front = dict(scene)
    back = dict(scene)
    x, y, z = scene["sun"]["direction"]
    back["sun"] = dict(scene["sun"], direction=[-x, -y, z])
    return {"front": front, "back": back}


def render(binary, scene, seed, spp, tmp):
    """One render: (groups [G, H, W, 3], beauty [H, W, 3], opacity [H, W], render seconds,
    wall seconds). The render seconds (render.json) leave out the start-up (building the Mie
    tables: ~2.5 s for the default cloud), which does not grow with the samples."""
    cfg = dict(scene, seed=seed, spp=spp)
    path = Path(tmp) / f"scene_{seed}.json"
    path.write_text(json.dumps(cfg))
    out = Path(tmp) / f"render_{seed}"
    t0 = time.perf_counter()
    subprocess.run([str(binary), "render", "--scene", str(path), "--out", str(out)],
                   check=True, capture_output=True)
    wall = time.perf_counter() - t0
    seconds = json.loads((out / "render.json").read_text())["seconds"]
    return (np.load(out / "groups.npy"), np.load(out / "beauty.npy"), np.load(out / "opacity.npy"),
            seconds, wall)


def stats(rel):
    """Median, RMS and 99th percentile of relative noises."""
    return {"median": float(np.median(rel)), "rms": float(np.sqrt(np.mean(rel ** 2))),
            "p99": float(np.quantile(rel, 0.99))}


def measure(binary, scene, seeds, spp, tmp):
    runs = [render(binary, scene, s + 1, spp, tmp) for s in range(seeds)]
    all_beauty = np.stack([r[1] for r in runs])  # [seed, H, W, 3]
    groups = np.stack([r[0][..., 1] for r in runs])  # [seed, group, H, W], green
    beauty = np.stack([r[1][..., 1] for r in runs])  # [seed, H, W]
    opaque = np.mean([r[2] for r in runs], axis=0) > 0.5
    seconds = float(np.mean([r[3] for r in runs]))
    wall = float(np.mean([r[4] for r in runs]))
    mean = beauty.mean(axis=0)
    ok = opaque & (mean > 0)
    rel = beauty.std(axis=0, ddof=1)[ok] / mean[ok]
    out = {"pixels": int(ok.sum()), "seconds_per_render": seconds, "wall_seconds_per_render": wall,
           "spp": spp, "seeds": seeds,
           "beauty": stats(rel), "efficiency": float(1.0 / (np.mean(rel ** 2) * seconds)),
           "channels": {}, "groups": []}
    for c, name in enumerate("RGB"):
        m = all_beauty[..., c].mean(axis=0)
        okc = ok & (m > 0)
        out["channels"][name] = stats(all_beauty[..., c].std(axis=0, ddof=1)[okc] / m[okc])
    for g in range(groups.shape[1]):
        rg = groups[:, g].std(axis=0, ddof=1)[ok] / mean[ok]
        share = float(groups[:, g].mean(axis=0)[ok].sum() / mean[ok].sum())
        out["groups"].append({"group": g, "share_of_light": share, **stats(rg)})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=DEFAULT_BIN)
    ap.add_argument("--scene", type=Path, default=DEFAULT_SCENE)
    ap.add_argument("--seeds", type=int, default=4, help="independent renders per lighting (>= 2)")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--lighting", choices=["front", "back", "both"], default="both")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=JSON",
                    help="override a scene key, e.g. --set sun_lobe_steps=0 (repeatable)")
    ap.add_argument("--out", type=Path, help="write the results as JSON here")
    args = ap.parse_args(argv)
    if args.seeds < 2:
        ap.error("--seeds must be at least 2 (the noise is the spread between seeds)")
    scene = json.loads(args.scene.read_text())
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            ap.error(f"--set wants KEY=JSON, got '{item}'")
        scene[key] = json.loads(value)
    chosen = lightings(scene)
    if args.lighting != "both":
        chosen = {args.lighting: chosen[args.lighting]}
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, sc in chosen.items():
            r = measure(args.bin, sc, args.seeds, args.spp, tmp)
            results[name] = r
            b = r["beauty"]
            print(f"{name}: {r['pixels']} opaque pixels, {r['seconds_per_render']:.1f} s per render "
                  f"({r['spp']} spp): relative noise median {100 * b['median']:.2f} %, RMS "
                  f"{100 * b['rms']:.2f} %, p99 {100 * b['p99']:.2f} %; efficiency "
                  f"{r['efficiency']:.3g} /s")
            print("   channels: " + ", ".join(
                f"{k} median {100 * v['median']:.2f} % RMS {100 * v['rms']:.2f} % p99 {100 * v['p99']:.2f} %"
                for k, v in r["channels"].items()))
            for g in r["groups"]:
                print(f"   group {g['group']}: {100 * g['share_of_light']:5.1f} % of the light, noise "
                      f"median {100 * g['median']:.2f} %, RMS {100 * g['rms']:.2f} %, "
                      f"p99 {100 * g['p99']:.2f} %")
    if args.out:
        args.out.write_text(json.dumps({"scene": str(args.scene), "results": results}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
