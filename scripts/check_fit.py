#!/usr/bin/env python3
"""Cross-check of nephele's fits (stage 3) with NumPy and SciPy, written independently.

Runs `nephele fit` on fit-configs/quick.json (5-20 um) and on small droplets (0.2-2.5 um, where
the HG+Draine optimum jumps between modes and a global start matters most) and, on the Mie
tables it writes (the tables themselves are cross-checked against miepython by check_mie.py):

  a. recomputes E_AS = sum_i |cos t_i| sin t_i dt_i (ln p(t_i) - ln p_Mie(t_i))^2 (trapezoid
     dt_i in radians) of every reported optimum with NumPy formulas of the five models and
     compares it with fits.json, to 1e-9 relative;
  b. minimises the same loss with SciPy (L-BFGS-B with finite-difference gradients, box bounds)
     from nephele's optimum and from random starts: nephele's optimum must not be beaten by
     more than 1e-6 relative;
  c. checks that the paper's HG+Draine parameters (Jendersie & d'Eon eqs. 4-7, typed in here)
     give an E_AS no lower than nephele's optimum.
"""
import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BIN = REPO / "target" / "release" / "nephele"
G = 1.0 - 1e-6
ALPHA_MAX = 250.0


def hg(mu, g):
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * mu) ** 1.5)


def draine(mu, g, a):
    return hg(mu, g) * (1.0 + a * mu * mu) / (1.0 + a * (1.0 + 2.0 * g * g) / 3.0)


MODELS = {
    "hg": (lambda mu, t: hg(mu, t[0]), [(-G, G)]),
    "two_term_hg": (
        lambda mu, t: t[2] * hg(mu, t[0]) + (1.0 - t[2]) * hg(mu, t[1]),
        [(-G, G), (-G, G), (0.0, 1.0)],
    ),
    "cornette_shanks": (lambda mu, t: draine(mu, t[0], 1.0), [(-G, G)]),
    "draine": (lambda mu, t: draine(mu, t[0], t[1]), [(-G, G), (0.0, ALPHA_MAX)]),
    "hg_draine": (
        lambda mu, t: (1.0 - t[3]) * hg(mu, t[0]) + t[3] * draine(mu, t[1], t[2]),
        [(-G, G), (-G, G), (0.0, ALPHA_MAX), (0.0, 1.0)],
    ),
}


def paper(d):
    """Jendersie & d'Eon 2023, eqs. 4-7 (d >= 5 um)."""
    return [
        math.exp(-0.0990567 / (d - 1.67154)),
        math.exp(-2.20679 / (d + 3.91029) - 0.428934),
        math.exp(3.62489 - 8.29288 / (d + 5.52825)),
        math.exp(-0.599085 / (d - 0.641583) - 0.665888),
    ]


def make_loss(theta_deg, phase):
    t = np.radians(theta_deg)
    dt = np.empty_like(t)
    dt[1:-1] = 0.5 * (t[2:] - t[:-2])
    dt[0] = 0.5 * (t[1] - t[0])
    dt[-1] = 0.5 * (t[-1] - t[-2])
    w = np.abs(np.cos(t)) * np.sin(t) * dt
    mu, ln_mie = np.cos(t), np.log(phase)

    def loss(model, theta):
        p = MODELS[model][0](mu, theta)
        if np.any(~(p > 0)) or not np.all(np.isfinite(p)):
            return 1e30
        r = np.log(p) - ln_mie
        return float(np.sum(w * r * r))

    return loss


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=DEFAULT_BIN)
    ap.add_argument("--quick", action="store_true", help="fewer random starts")
    args = ap.parse_args(argv)
    starts = 6 if args.quick else 20
    rng = np.random.default_rng(1)
    failures = []
    small = {
        "description": "check_fit.py: small droplets",
        "mie": {"diameter": "0.2,0.5,0.85,1.2,2.5", "sigma": 0.25, "index": 1.333,
                "wavelengths": "400:700:11", "sizes": 41},
        "fit": {"figure_diameters_um": [0.2, 0.5, 0.85, 1.2, 2.5]},
    }
    with tempfile.TemporaryDirectory() as tmp:
        small_cfg = Path(tmp) / "small.json"
        small_cfg.write_text(json.dumps(small))
        for name, cfg in [("quick", REPO / "fit-configs" / "quick.json"), ("small", small_cfg)]:
            failures += check_run(args.bin, cfg, Path(tmp) / name, starts, rng)
    if failures:
        print("check_fit: FAILED: " + ", ".join(failures))
        return 1
    print("check_fit: all passed")
    return 0


def check_run(bin_path, cfg, out, starts, rng):
    """Checks a, b, c on one `nephele fit` run; returns the failures."""
    failures = []
    cmd = [str(bin_path), "fit", "--config", str(cfg), "--out", str(out), "--no-plot"]
    subprocess.run(cmd, check=True, capture_output=True)
    doc = json.loads((out / "fits.json").read_text())
    fits = {f["d_um"]: f for f in doc["result"]["fits"]}
    tables = sorted((out / "mie").glob("d*um/phase.npz"))
    if not tables:
        return [f"no Mie tables written by {cfg.name}"]
    for npz in tables:
        d = float(re.search(r"d([0-9.]+)um", npz.parent.name).group(1))
        z = np.load(npz)
        loss = make_loss(z["theta_deg"], z["phase"])
        f = fits[min(fits, key=lambda x: abs(x - d))]
        print(f"d = {d} um")
        for model, (_, bounds) in MODELS.items():
            ours = f["models"][model]
            theta, e_ours = ours["theta"], ours["loss"]
            e_np = loss(model, theta)
            rel = abs(e_np - e_ours) / e_ours
            best = math.inf
            inits = [np.array(theta)] + [
                np.array([rng.uniform(lo + 0.05 * (hi - lo), hi - 0.05 * (hi - lo)) for lo, hi in bounds])
                for _ in range(starts)
            ]
            for x0 in inits:
                r = minimize(lambda x: loss(model, x), x0, method="L-BFGS-B", bounds=bounds,
                             options={"maxiter": 2000, "ftol": 1e-15, "gtol": 1e-12})
                best = min(best, r.fun)
            beaten = (e_ours - best) / e_ours
            ok = rel <= 1e-9 and beaten <= 1e-6
            print(f"  {model:16s} E_AS nephele {e_ours:.10e}  numpy {e_np:.10e} (rel {rel:.1e})  "
                  f"scipy best {best:.10e} (nephele lower by {-beaten:+.1e})  {'ok' if ok else 'FAIL'}")
            if not ok:
                failures.append(f"{model} at {d} um")
        if d >= 5.0:
            e_paper = loss("hg_draine", paper(d))
            e_opt = f["models"]["hg_draine"]["loss"]
            ok = e_paper >= e_opt * (1.0 - 1e-9)
            print(f"  paper's HG+Draine E_AS {e_paper:.10e} >= optimum {e_opt:.10e}: {'ok' if ok else 'FAIL'}")
            if not ok:
                failures.append(f"paper below optimum at {d} um")
    return failures


if __name__ == "__main__":
    sys.exit(main())
