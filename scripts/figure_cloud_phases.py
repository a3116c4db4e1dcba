#!/usr/bin/env python3
"""The default cloud rendered with the Mie table, HG+Draine and a single HG side by side (the
comparison of Jendersie & d'Eon's Figure 1), with one shared exposure, into docs/img/.

    .venv/bin/python scripts/figure_cloud_phases.py [--spp 128]

Needs the release binary (cargo build --release) and Mitsuba 3 from scripts/requirements.txt
(its Bitmap writes the PNG). The HG asymmetry is the Mie table's g (from phase.json).
"""
import argparse
import json
import subprocess
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
BIN = REPO / "target" / "release" / "nephele"


def render(scene: dict, tmp: Path, name: str) -> np.ndarray:
    path = tmp / f"{name}.json"
    path.write_text(json.dumps(scene))
    out = tmp / name
    subprocess.run([str(BIN), "render", "--scene", str(path), "--out", str(out)], check=True,
                   capture_output=True)
    return np.load(out / "beauty.npy")


def tone_map(img: np.ndarray) -> np.ndarray:
    """As nephele's beauty.png: the 90th percentile of luminance at 0.75 of 1 - exp(-x), sRGB."""
    lum = img @ np.array([0.2126, 0.7152, 0.0722])
    k = np.log(4.0) / max(np.percentile(lum, 90), 1e-12)
    x = 1.0 - np.exp(-k * np.clip(img, 0, None))
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    return np.clip(s * 255 + 0.5, 0, 255).astype(np.uint8)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "img" / "cloud_phases.png")
    args = ap.parse_args()
    base = json.loads((REPO / "fit-configs" / "scenes" / "cloud.json").read_text())
    base["spp"] = args.spp
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run([str(BIN), "mie", "--diameter", "10", "--out", str(tmp / "mie"), "--no-plot"],
                       check=True, capture_output=True)
        g = json.loads((tmp / "mie" / "phase.json").read_text())["g"]
        images = []
        for name, phase in [("mie", {"kind": "mie", "diameter_um": 10}),
                            ("hg_draine", {"kind": "hg_draine", "diameter_um": 10}),
                            ("hg", {"kind": "hg", "g": g})]:
            images.append(render(dict(base, phase=phase), tmp, name))
    strip = tone_map(np.concatenate(images, axis=1))
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    mi.Bitmap(strip).write(str(args.out))
    print(f"wrote {args.out}: Mie 10 um | HG+Draine (Jendersie & d'Eon preset) | HG g = {g:.4f}; {args.spp} spp")


if __name__ == "__main__":
    main()
