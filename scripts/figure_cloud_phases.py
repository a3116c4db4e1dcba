#!/usr/bin/env python3
"""The default cloud rendered with the Mie table, HG+Draine and a single HG side by side (the
comparison of Jendersie & d'Eon's Figure 1), lit from behind the camera (the scene's sun) and
from behind the cloud, one exposure per row, into docs/img/.

    .venv/bin/python scripts/figure_cloud_phases.py [--spp 512] [--width 200]

Prints, per lighting, the mean radiance of each phase function over the cloud's pixels
(opacity > 0.5) relative to Mie's, with a standard error from the spread over four renders
(seeds 1-4, spp/4 each; the figure shows their mean). Needs the
release binary (cargo build --release) and Mitsuba 3 from scripts/requirements.txt (its Bitmap
writes the PNG). The HG asymmetry is the Mie table's g (from phase.json).
"""
import argparse
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
BIN = REPO / "target" / "release" / "nephele"


def render(scene: dict, tmp: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    path = tmp / f"{name}.json"
    path.write_text(json.dumps(scene))
    out = tmp / name
    subprocess.run([str(BIN), "render", "--scene", str(path), "--out", str(out)], check=True,
                   capture_output=True)
    return np.load(out / "beauty.npy"), np.load(out / "opacity.npy")


def tone_map(img: np.ndarray, white: float) -> np.ndarray:
    """Luminance `white` at 0.8 of 1 - exp(-x), sRGB-encoded."""
    k = np.log(5.0) / max(white, 1e-12)
    x = 1.0 - np.exp(-k * np.clip(img, 0, None))
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.clip(s * 255 + 0.5, 0, 255).astype(np.uint8)


LUMA = np.array([0.2126, 0.7152, 0.0722])
LIGHTS = {
    "sun behind the camera": [-0.45, -0.65, 0.57],
    "sun behind the cloud": [0.35, 0.8, 0.45],
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=512)
    ap.add_argument("--width", type=int, default=200)
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "img" / "cloud_phases.png")
    args = ap.parse_args()
    base = json.loads((REPO / "fit-configs" / "scenes" / "cloud.json").read_text())
    base["spp"] = args.spp
    base["camera"].update(width=args.width, height=args.width * 3 // 4, fov_deg=34)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run([str(BIN), "mie", "--diameter", "10", "--out", str(tmp / "mie"), "--no-plot"],
                       check=True, capture_output=True)
        g = json.loads((tmp / "mie" / "phase.json").read_text())["g"]
        phases = [("Mie", {"kind": "mie", "diameter_um": 10}),
                  ("HG+Draine", {"kind": "hg_draine", "diameter_um": 10}),
                  (f"HG g={g:.3f}", {"kind": "hg", "g": g})]
        for light, sun in LIGHTS.items():
            scene = dict(base, sun=dict(base["sun"], direction=sun))
            # runs[phase][seed] = (beauty, opacity)
            runs = [[render(dict(scene, phase=phase, spp=max(args.spp // 4, 1), seed=seed), tmp,
                             f"{name.split()[0]}-{seed}") for seed in range(1, 5)]
                    for name, phase in phases]
            mask = np.mean([o for _, o in runs[0]], axis=0) > 0.5
            # The mean luminance over the cloud per phase and seed, relative to Mie's.
            lum = np.array([[(b @ LUMA)[mask].mean() for b, _ in r] for r in runs])
            ratio = lum / lum[0]
            report = [f"{name} {r.mean():.3f} +- {r.std(ddof=1) / 2:.3f}"
                      for (name, _), r in zip(phases, ratio)]
            print(f"{light}: mean cloud radiance relative to Mie (seed by seed): " + ", ".join(report))
            images = [np.mean([b for b, _ in r], axis=0) for r in runs]
            white = 2.5 * np.median((images[0] @ LUMA)[mask])
            rows.append(tone_map(np.concatenate(images, axis=1), white))
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    mi.Bitmap(np.concatenate(rows, axis=0)).write(str(args.out))
    print(f"wrote {args.out}: columns " + " | ".join(n for n, _ in phases) + "; rows "
          + " | ".join(LIGHTS) + f"; {args.spp} spp")


if __name__ == "__main__":
    main()
