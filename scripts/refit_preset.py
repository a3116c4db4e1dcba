#!/usr/bin/env python3
"""Print the Rust constants of `nephele_runtime::presets::nephele_refit` from fit runs.

    nephele fit --config fit-configs/paper.json --out outputs/fit
    nephele fit --config fit-configs/small-droplets.json --out outputs/fit-small
    python scripts/refit_preset.py outputs/fit/fits.json outputs/fit-small/fits.json

Every curve branch of the given runs becomes one `Branch` (lowest diameter first); paste the
output over the `REFIT` table in runtime/src/presets.rs. Only the standard library is used.
"""
import json
import sys

PARAMS = ["g_hg", "g_d", "alpha", "w_d"]


def curve(c):
    form, k = c["form"], c["coefficients"]
    if form == "exp_rational":
        return f"Curve::ExpRational {{ a: {k['A']!r}, b: {k['B']!r}, c: {k['C']!r} }}"
    if form == "exp_rational_no_offset":
        return f"Curve::ExpRational {{ a: 0.0, b: {k['B']!r}, c: {k['C']!r} }}"
    coef = [k[f"c{i}"] for i in range(len(k) - 1)]
    return f"Curve::PolyLnD {{ l0: {k['L0']!r}, c: &{coef!r} }}"


def main(paths):
    branches = []
    for path in paths:
        with open(path) as f:
            doc = json.load(f)
        for b in doc["result"]["branches"]:
            branches.append((b["range_um"], b["curves"]))
    branches.sort(key=lambda b: b[0][0])
    print(f"const REFIT: [Branch; {len(branches)}] = [")
    for (lo, hi), curves in branches:
        print(f"    // {lo}–{hi} µm")
        print(f"    Branch {{\n        d_min: {float(lo)!r},")
        for p in PARAMS:
            print(f"        {p}: {curve(curves[p])},")
        print("    },")
    print("];")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: refit_preset.py FITS_JSON [FITS_JSON ...]")
    main(sys.argv[1:])
