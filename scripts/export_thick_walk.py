#!/usr/bin/env python3
"""Keeps the part of a one-slice slab walk (`nephele slab --config fit-configs/thick/slab-tN.json`
or `fit-configs/low-sun/slab-sunN.json`) that tests/thick_slabs.rs reads: T, its standard error
and sigma of the groups of orders >= 2 per (plane, mu_V bin, psi_V bin), float32, and the grid,
into OUT (default tests/data/thick/tN.npz).

    nephele slab --config fit-configs/thick/slab-t256.json --out /tmp/t256
    python3 scripts/export_thick_walk.py /tmp/t256/tables.npz
    nephele slab --config fit-configs/low-sun/slab-sun1.json --out /tmp/sun1
    python3 scripts/export_thick_walk.py /tmp/sun1/tables.npz tests/data/low_sun/sun1.npz
"""
import json
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent


def main(path: str, out: str = "") -> None:
    z = np.load(path)
    meta = json.loads((Path(path).parent / "tables.json").read_text())
    t = int(z["thickness"][0])
    f32 = lambda a: np.ascontiguousarray(a[1:, 0, 0], dtype=np.float32)  # noqa: E731
    out = Path(out) if out else REPO / "tests" / "data" / "thick" / f"t{t}.npz"
    np.savez(out, T=f32(z["T"]), T_se=f32(z["T_se"]), sigma=f32(z["sigma"]),
             depth=z["depth"][0].astype(np.float64), mu_v_edges=z["mu_v_edges"],
             psi_v_edges=z["psi_v_edges"], thickness=z["thickness"], mu_l=z["mu_l"],
             photons=np.array([meta["photons"]], dtype=np.float64),
             transmitted=np.array([meta["slices"][0]["transmitted"]], dtype=np.float64))
    print(f"wrote {out} ({out.stat().st_size} bytes; {meta['photons']} photons)")


if __name__ == "__main__":
    main(*sys.argv[1:3])
