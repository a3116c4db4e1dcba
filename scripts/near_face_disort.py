#!/usr/bin/env python3
"""DISORT's diffuse radiance near the far (unlit) face of thick slabs: tests/data/near-face-disort.json.

Where a viewpoint lies within a few mean free paths of the far face of a thick slab and looks
at it (light travelling up, mu_V > 0), the light comes from the thin layer in between and
changes fast with depth; the slab tables' planes are sparse there (the default grid crowds them
toward the lit face), so the runtime continues the form beyond its fitted depths
(docs/compress.md, "Near the far face"). This script computes the independent reference for
those points: PythonicDISORT's intensity for the paper's medium (Mie, 10 um droplets, set up as
check_slab.py: the table's own Legendre moments, 256 streams, delta-M with the Nakajima-Tanaka
corrections) at t = 16, 32, 64, 128 mfp, mu_L = 0.5 and 1, d/t = 0.9, 0.95, 0.97, 0.98,
mu_V = +0.08, +0.15, +0.25, +0.5 and, for comparison, -0.15 and -0.5, psi_V = 60 deg.
DISORT's value is order 1 + every order >= 2, as `tests/shipped.rs` sums the runtime's.

Usage: scripts/near_face_disort.py [--bin target/release/nephele] [--out tests/data/near-face-disort.json]
"""
import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_slab import NQUAD_MIE, MIE_MOMENTS, MIE_D, disort, table_moments  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
THICKNESSES = [16.0, 32.0, 64.0, 128.0]
SUN_COSINES = [0.5, 1.0]
DEPTH_FRACTIONS = [0.9, 0.95, 0.97, 0.98]
VIEW_COSINES = [0.08, 0.15, 0.25, 0.5, -0.15, -0.5]
PSI_DEG = 60.0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=REPO / "target" / "release" / "nephele")
    ap.add_argument("--out", type=Path, default=REPO / "tests" / "data" / "near-face-disort.json")
    args = ap.parse_args(argv)
    points = []
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([str(args.bin), "mie", "--diameter", str(MIE_D), "--out", str(Path(tmp) / "mie")],
                       check=True, capture_output=True)
        chi = table_moments(Path(tmp) / "mie" / "phase.npz", MIE_MOMENTS)
        for t in THICKNESSES:
            for mu_l in SUN_COSINES:
                _, _, ui = disort(t, mu_l, chi, NQUAD_MIE)
                for f in DEPTH_FRACTIONS:
                    for mu_v in VIEW_COSINES:
                        d = f * t
                        value = float(np.asarray(ui(np.array([mu_v]), d, math.radians(PSI_DEG))).ravel()[0])
                        points.append([t, mu_l, d, mu_v, math.radians(PSI_DEG), value])
                print(f"t = {t:g}, mu_L = {mu_l:g}: done", file=sys.stderr)
    doc = {
        "about": "PythonicDISORT intensity (diffuse radiance per unit incident flux on a plane normal "
                 "to the beam, all orders: order 1 + orders >= 2) in a slab of the paper's medium (Mie, "
                 "10 um droplets, lognormal as `nephele mie --diameter 10`, albedo 1), 256 streams, "
                 f"{MIE_MOMENTS} Legendre moments, delta-M with Nakajima-Tanaka corrections, near the far "
                 "face of thick slabs. Written by scripts/near_face_disort.py.",
        "columns": ["t_mfp", "mu_l", "depth_mfp", "mu_v", "psi_v_rad", "disort"],
        "points": points,
    }
    tmp_out = args.out.with_suffix(".json.tmp")
    tmp_out.write_text(json.dumps(doc, indent=1) + "\n")
    tmp_out.replace(args.out)
    print(f"{len(points)} points -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
