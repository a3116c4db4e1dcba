#!/usr/bin/env python3
"""Independent cross-check of nephele's Mie engine against miepython and colour-science.

Three groups of checks, each printed as a table (compared quantity, worst relative
difference, tolerance, PASS/FAIL); the script exits with status 1 if any check fails.

a. Single spheres (``nephele sphere``) against ``miepython`` for random and hand-picked
   (m, x): Q_ext, Q_sca, Q_back, g and the amplitudes S1, S2 at 20 angles.
b. Polydisperse product-rule tables (``nephele mie --sizes 41``) against the same rule
   evaluated with miepython: p_lambda, the wavelength mean, the 650/510/440 nm channels,
   g and the mean scattering cross-section.
c. sRGB channel phase functions recomputed from nephele's own p_lambda with the CIE
   tables, D65 and the sRGB matrix taken from colour-science.

Conventions. nephele follows Bohren & Huffman (m = n + ik). miepython takes m = n - ik and
``S1_S2(..., norm='wiscombe')`` returns the complex conjugate of the B&H amplitudes with
the same normalisation (Q_ext = 4 Re S(0) / x^2); the efficiencies and g are identical.

Usage: scripts/check_mie.py [--bin PATH] [--quick] [--seed N]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

# miepython picks its backend at import time.
os.environ["MIEPYTHON_USE_JIT"] = "1"

import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BIN = REPO / "target" / "release" / "nephele"

# Angles of the single-sphere comparison (degrees): both ends, the forward lobe, the rest.
SPHERE_ANGLES_DEG = [0, 0.25, 0.5, 1, 2, 5, 10, 20, 30, 45, 60, 75, 90, 105, 120,
                     135, 150, 165, 175, 179, 180]

# Hand-picked hard cases: (n, k, x, why).
HARD_CASES = [
    (1.333, 0.0, 2.0e4, "largest x, water"),
    (1.5, 1.0, 100.0, "strong absorption"),
    (1.0001, 0.0, 1000.0, "nearly index-matched"),
    (2.0, 0.0, 500.0, "high index"),
    (1.0001, 0.0, 0.1, "smallest x, nearly index-matched"),
    (2.0, 1.0, 2.0e4, "largest x, strongest absorption"),
]

TOL_SPHERE = 1e-9
TOL_PHASE = 1e-7
TOL_INTEGRAL = 1e-9
TOL_COLOUR = 1e-4

# Polydisperse job of check b (spec 10 product rule).
SIGMA = 0.25
N_SIZES = 41
Z_MAX = 4.0
WAVELENGTHS = (400.0, 700.0, 31)
LUT_NM = (650.0, 510.0, 440.0)
WATER = 1.333
CMFS_NAME = "CIE 1931 2 Degree Standard Observer"


# --------------------------------------------------------------------------- results


@dataclasses.dataclass
class Row:
    """One line of a result table."""

    check: str
    what: str
    worst: float
    tol: float | None  # None: informational only
    where: str = ""

    @property
    def status(self) -> str:
        """PASS, FAIL or INFO."""
        if self.tol is None:
            return "INFO"
        return "PASS" if self.worst <= self.tol else "FAIL"


def print_table(title: str, rows: list[Row]) -> None:
    """Prints rows under a heading, one per line, aligned."""
    print(f"\n{title}")
    w_check = max(len(r.check) for r in rows)
    w_what = max(len(r.what) for r in rows)
    header = f"  {'check':<{w_check}}  {'compared':<{w_what}}  {'worst rel':>10}  {'tol':>7}  status  worst at"
    print(header)
    print("  " + "-" * (len(header) - 2))
    for r in rows:
        tol = "-" if r.tol is None else f"{r.tol:.0e}"
        print(f"  {r.check:<{w_check}}  {r.what:<{w_what}}  {r.worst:10.2e}  {tol:>7}  {r.status:<6}  {r.where}")


def rel(ours, ref) -> np.ndarray:
    """Pointwise |ours - ref| / |ref| (inf where ref is 0 and ours is not)."""
    ours = np.asarray(ours, dtype=float)
    ref = np.asarray(ref, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.abs(ours - ref) / np.abs(ref)
    return np.where(ours == ref, 0.0, r)


# --------------------------------------------------------------------------- nephele


class Nephele:
    """Runs the nephele binary."""

    def __init__(self, binary: Path):
        self.binary = binary

    def sphere(self, n: float, k: float, x: float, angles: list[float]) -> dict:
        """Single sphere: parsed JSON of `nephele sphere`."""
        cmd = [str(self.binary), "sphere", "--index", f"{n!r}+{k!r}i", "--x", repr(x),
               "--angles", ",".join(repr(float(a)) for a in angles)]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        return json.loads(out)

    def mie(self, out: Path, *args: str) -> tuple[dict, dict]:
        """Runs `nephele mie ... --out OUT --no-plot`; returns (npz arrays, phase.json)."""
        cmd = [str(self.binary), "mie", *args, "--out", str(out), "--no-plot"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        with np.load(out / "phase.npz") as z:
            arrays = {k: z[k] for k in z.files}
        return arrays, json.loads((out / "phase.json").read_text())


# --------------------------------------------------------------------------- reference helpers


def import_miepython():
    """Imports miepython (JIT backend) and triggers compilation; returns the module."""
    t0 = time.perf_counter()
    import miepython as mp

    assert mp.USE_JIT, "MIEPYTHON_USE_JIT=1 must be set before importing miepython"
    mp.S1_S2(1.5 - 0.1j, 3.0, np.array([1.0, 0.0]), norm="wiscombe")
    mp.efficiencies_mx(1.5 - 0.1j, 3.0)
    mp.an_bn(1.5 - 0.1j, 3.0, 5)
    print(f"miepython {mp.__version__ if hasattr(mp, '__version__') else ''} imported "
          f"(JIT, compile/cache load {time.perf_counter() - t0:.1f} s)")
    return mp


def miepython_terms(x: float) -> int:
    """Number of terms miepython sums (Wiscombe's criterion as miepython writes it)."""
    return int(x + 4.05 * x**0.33333 + 2.0)


def series_sums(a: np.ndarray, b: np.ndarray, x: float, mu: np.ndarray):
    """Q_ext, Q_sca, Q_back, g, S1, S2 from B&H coefficients a_n, b_n (n = 1..N).

    Plain textbook sums (Bohren & Huffman ch. 4) with the angular functions from the
    upward recurrence; used to compare at a matched truncation.
    """
    n = np.arange(1, len(a) + 1, dtype=float)
    c = 2 * n + 1
    qext = 2 / x**2 * np.sum(c * (a + b).real)
    qsca = 2 / x**2 * np.sum(c * (np.abs(a) ** 2 + np.abs(b) ** 2))
    sign = np.where(n % 2 == 1, -1.0, 1.0)
    qback = np.abs(np.sum(c * sign * (a - b))) ** 2 / x**2
    g1 = np.sum(n[:-1] * (n[:-1] + 2) / (n[:-1] + 1) * (a[:-1] * a[1:].conj() + b[:-1] * b[1:].conj()).real)
    g2 = np.sum(c / (n * (n + 1)) * (a * b.conj()).real)
    g = 4 / (x**2 * qsca) * (g1 + g2)
    pi_prev = np.zeros_like(mu)
    pi_n = np.ones_like(mu)
    s1 = np.zeros(mu.shape, complex)
    s2 = np.zeros(mu.shape, complex)
    for i, nn in enumerate(n):
        tau_n = nn * mu * pi_n - (nn + 1) * pi_prev
        f = c[i] / (nn * (nn + 1))
        s1 += f * (a[i] * pi_n + b[i] * tau_n)
        s2 += f * (a[i] * tau_n + b[i] * pi_n)
        pi_prev, pi_n = pi_n, ((2 * nn + 1) * mu * pi_n - (nn + 1) * pi_prev) / nn
    return qext, qsca, qback, g, s1, s2


# --------------------------------------------------------------------------- check a


def sphere_cases(n_random: int, seed: int) -> list[tuple[float, float, float, str]]:
    """Random (n, k, x) plus the hand-picked hard cases."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n_random):
        x = float(np.exp(rng.uniform(np.log(0.1), np.log(2.0e4))))
        n = float(rng.uniform(1.0001, 2.0))
        k = 0.0 if rng.random() < 0.5 else float(np.exp(rng.uniform(np.log(1e-8), np.log(1.0))))
        cases.append((n, k, x, "random"))
    return cases + list(HARD_CASES)


def compare_sphere(mp, nep: Nephele, n: float, k: float, x: float) -> dict:
    """One sphere: relative differences nephele vs miepython."""
    ours = nep.sphere(n, k, x, SPHERE_ANGLES_DEG)
    theta = np.asarray(ours["theta_deg"], float)
    mu = np.cos(np.radians(theta))
    m_mp = complex(n, -k)
    qext, qsca, qback, g = (float(v) for v in mp.efficiencies_mx(m_mp, x))
    r1, r2 = mp.S1_S2(m_mp, x, mu, norm="wiscombe")
    ref = dict(qext=qext, qsca=qsca, qback=qback, g=g, s1=np.conj(r1), s2=np.conj(r2))
    s1 = np.array([complex(*p) for p in ours["s1"]])
    s2 = np.array([complex(*p) for p in ours["s2"]])
    errs = diffs(ours, s1, s2, ref)
    rec = dict(n=n, k=k, x=x, n_ours=int(ours["n_terms"]), n_mp=miepython_terms(x), **errs)
    if rec["n_ours"] != rec["n_mp"]:
        # Same coefficients (miepython's) summed to nephele's truncation.
        a, b = mp.an_bn(m_mp, x, rec["n_ours"])
        qe, qs, qb, gg, t1, t2 = series_sums(np.conj(a), np.conj(b), x, mu)
        matched = dict(qext=qe, qsca=qs, qback=qb, g=gg, s1=t1, s2=t2)
        rec["matched"] = diffs(ours, s1, s2, matched)
    return rec


def diffs(ours: dict, s1: np.ndarray, s2: np.ndarray, ref: dict) -> dict:
    """Relative differences of the four efficiencies and the amplitudes."""
    out = {q: float(rel(ours[q], ref[q])) for q in ("qext", "qsca", "qback", "g")}
    amp = 0.0
    point = 0.0
    for mine, theirs in ((s1, ref["s1"]), (s2, ref["s2"])):
        d = np.abs(mine - theirs)
        amp = max(amp, float(d.max() / np.abs(theirs).max()))
        point = max(point, float(rel(d, 0 * d + np.abs(theirs)).max()))
    out["amp"] = amp
    out["amp_pointwise"] = point
    return out


def case_label(r: dict) -> str:
    """Short label of a case."""
    return f"m={r['n']:.6g}+{r['k']:.3g}i x={r['x']:.6g}"


def check_spheres(mp, nep: Nephele, n_random: int, seed: int) -> tuple[list[Row], list[str], bool]:
    """Check a. Returns table rows, notes and whether it passed."""
    t0 = time.perf_counter()
    recs = [compare_sphere(mp, nep, *c[:3]) for c in sphere_cases(n_random, seed)]
    elapsed = time.perf_counter() - t0
    quantities = [("qext", "Q_ext", TOL_SPHERE), ("qsca", "Q_sca", TOL_SPHERE),
                  ("qback", "Q_back", TOL_SPHERE), ("g", "g", TOL_SPHERE),
                  ("amp", "S1,S2: max|dS| / max_theta|S_ref|", TOL_SPHERE),
                  ("amp_pointwise", "S1,S2: pointwise |dS|/|S_ref|", None)]
    rows = []
    for key, what, tol in quantities:
        worst = max(recs, key=lambda r: r[key])
        rows.append(Row("a sphere", what, worst[key], tol, case_label(worst)))

    notes = [f"{len(recs)} spheres ({n_random} random, seed {seed}, + {len(HARD_CASES)} fixed), "
             f"{len(SPHERE_ANGLES_DEG)} angles 0..180 deg, {elapsed:.1f} s."]
    mismatched = [r for r in recs if r["n_ours"] != r["n_mp"]]
    notes.append(f"n_terms differs (nephele floor(x+4.05 cbrt x+2) vs miepython int(x+4.05 x^0.33333+2)) "
                 f"in {len(mismatched)} of {len(recs)} cases"
                 + (": " + "; ".join(f"{case_label(r)} {r['n_ours']} vs {r['n_mp']}" for r in mismatched[:8])
                    if mismatched else "."))
    keys = [q[0] for q in quantities if q[2] is not None]
    failed = [r for r in recs if any(r[q] > TOL_SPHERE for q in keys)]
    explained = [r for r in failed
                 if "matched" in r and all(r["matched"][q] <= TOL_SPHERE for q in keys)]
    real = [r for r in failed if r not in explained]
    for r in explained:
        worst_q = max(keys, key=lambda q: r[q])
        notes.append(f"FAIL only from n_terms ({r['n_ours']} vs {r['n_mp']}): {case_label(r)}: "
                     f"{worst_q} differs {r[worst_q]:.2e}; summing miepython's a_n, b_n to nephele's "
                     f"{r['n_ours']} terms agrees to {max(r['matched'][q] for q in keys):.2e}. "
                     "Counted as explained, not as a failure.")
    for r in real:
        notes.append(f"FAIL {case_label(r)} n_terms {r['n_ours']}/{r['n_mp']}: "
                     + ", ".join(f"{q} {r[q]:.2e}" for q in keys))
    if explained and not real:
        # Re-state the table rows without the truncation-explained cases.
        for row, (key, _, tol) in zip(rows, quantities):
            kept = [r for r in recs if r not in explained]
            if tol is not None and row.worst > tol and kept:
                w = max(kept, key=lambda r: r[key])
                row.worst, row.where = w[key], case_label(w) + " (excl. n_terms-explained)"
    notes.append("Amplitude error per case: max over theta of |S_ours - S_ref| / max over theta of |S_ref| "
                 "(S1 and S2 separately); the pointwise |dS|/|S| row is informational.")
    return rows, notes, not real


# --------------------------------------------------------------------------- check b


def product_rule(d_med: float, sigma: float = SIGMA, n: int = N_SIZES):
    """Spec-10 product rule: diameters (um) and number weights summing to 1."""
    z = np.linspace(-Z_MAX, Z_MAX, n)
    w = np.exp(-0.5 * z**2)
    return d_med * np.exp(sigma * z), w / w.sum()


def reference_table(mp, d_med: float, wavelengths_nm, mu: np.ndarray, m: complex) -> dict:
    """The product-rule table evaluated with miepython, one row per wavelength."""
    d, w = product_rule(d_med)
    m_mp = complex(m.real, -m.imag)
    area = np.pi * (d / 2) ** 2  # um^2
    p, g_l, c_l = [], [], []
    for lam in wavelengths_nm:
        num = np.zeros_like(mu)
        den = csca = csca_g = 0.0
        for wi, di, a in zip(w, d, area):
            x = float(np.pi * di * 1000.0 / lam)
            s1, s2 = mp.S1_S2(m_mp, x, mu, norm="wiscombe")
            _, qsca, _, g = mp.efficiencies_mx(m_mp, x)
            num += wi * 0.5 * (np.abs(s1) ** 2 + np.abs(s2) ** 2)
            den += wi * np.pi * x**2 * qsca
            csca += wi * qsca * a
            csca_g += wi * qsca * a * g
        p.append(num / den)
        g_l.append(csca_g / csca)
        c_l.append(csca)
    return dict(phase_spectral=np.array(p), g_spectral=np.array(g_l),
                c_sca_spectral_um2=np.array(c_l), d=d, w=w)


def expected_angles() -> np.ndarray:
    """The default 2251-angle grid: 0-5 deg by 0.01, 5-180 deg by 0.1."""
    return np.concatenate([np.arange(500) * 0.01, 5.0 + np.arange(1751) * 0.1])


def check_polydisperse(mp, nep: Nephele, tmp: Path, diameters) -> tuple[list[Row], list[str], dict]:
    """Check b. Returns rows, notes and nephele's outputs per diameter (reused by check c)."""
    rows, notes, runs = [], [], {}
    lo, hi, nl = WAVELENGTHS
    for d_med in diameters:
        out = tmp / f"b_d{d_med:g}"
        t0 = time.perf_counter()
        arr, meta = nep.mie(out, "--diameter", f"{d_med:g}", "--sizes", str(N_SIZES),
                            "--wavelengths", f"{lo:g}:{hi:g}:{nl}")
        t_ours = time.perf_counter() - t0
        runs[d_med] = (arr, meta)
        theta = arr["theta_deg"]
        mu = np.cos(np.radians(theta))
        lam = arr["wavelength_nm"]
        t0 = time.perf_counter()
        ref = reference_table(mp, d_med, lam, mu, complex(WATER, 0))
        ref3 = reference_table(mp, d_med, LUT_NM, mu, complex(WATER, 0))
        t_ref = time.perf_counter() - t0
        tag = f"b d={d_med:g}um"

        def add(what, ours, theirs, tol, labels=None):
            r = rel(ours, theirs)
            i = np.unravel_index(int(np.argmax(r)), r.shape)
            where = labels(i) if labels else ""
            rows.append(Row(tag, what, float(r.max()), tol, where))

        at = lambda i: f"theta={theta[i[-1]]:g}" + (f" lambda={lam[i[0]]:g}" if len(i) == 2 else "")
        rows.append(Row(tag, "theta grid vs 0-5/0.01, 5-180/0.1 (abs deg)",
                        float(np.abs(theta - expected_angles()).max()) if theta.shape == (2251,) else math.inf,
                        1e-9))
        rows.append(Row(tag, "wavelength grid (abs nm)",
                        float(np.abs(lam - np.linspace(lo, hi, nl)).max()) if lam.shape == (nl,) else math.inf,
                        1e-9))
        rows.append(Row(tag, "npz mu vs cos(theta) (abs)", float(np.abs(arr["mu"] - mu).max()), 1e-15))
        add("phase_spectral (every lambda, theta)", arr["phase_spectral"], ref["phase_spectral"], TOL_PHASE, at)
        add("phase (mean over lambda)", arr["phase"], ref["phase_spectral"].mean(0), TOL_PHASE, at)
        add("phase_rgb_3wl (650/510/440 nm)", arr["phase_rgb_3wl"], ref3["phase_spectral"].T, TOL_PHASE,
            lambda i: f"theta={theta[i[0]]:g} lambda={LUT_NM[i[1]]:g}")
        add("g_spectral", arr["g_spectral"], ref["g_spectral"], TOL_INTEGRAL,
            lambda i: f"lambda={lam[i[0]]:g}")
        add("c_sca_spectral_um2", arr["c_sca_spectral_um2"], ref["c_sca_spectral_um2"], TOL_INTEGRAL,
            lambda i: f"lambda={lam[i[0]]:g}")
        add("phase.json g", meta["g"], ref["g_spectral"].mean(), TOL_INTEGRAL)
        add("phase.json c_sca_um2", meta["c_sca_um2"], ref["c_sca_spectral_um2"].mean(), TOL_INTEGRAL)
        d, w = ref["d"], ref["w"]
        add("phase.json q_sca = c_sca / <pi r^2>", meta["q_sca"],
            ref["c_sca_spectral_um2"].mean() / np.sum(w * np.pi * (d / 2) ** 2), TOL_INTEGRAL)
        add("phase.json effective_diameter_um", meta["effective_diameter_um"],
            np.sum(w * d**3) / np.sum(w * d**2), TOL_INTEGRAL)
        rows.extend(self_consistency(tag, arr, meta))
        notes.append(f"{tag}: nephele {t_ours:.2f} s wall; miepython reference "
                     f"{len(lam) + len(LUT_NM)}x{N_SIZES} spheres x {len(mu)} angles in {t_ref:.1f} s.")
    notes.append("Rule: z_i = linspace(-4, 4, 41), d_i = d_med exp(0.25 z_i), w_i ~ exp(-z_i^2/2), sum 1; "
                 "x = pi d / lambda; p_lambda = sum w (|S1|^2+|S2|^2)/2 / sum w pi x^2 Q_sca; "
                 "phase = plain mean over the 31 wavelengths.")
    return rows, notes, runs


def self_consistency(tag: str, arr: dict, meta: dict) -> list[Row]:
    """Informational: nephele's derived outputs recomputed from its own phase, per its stated conventions."""
    theta = np.radians(arr["theta_deg"])
    p = arr["phase"]
    f = 2 * np.pi * p * np.sin(theta)
    seg = 0.5 * (f[1:] + f[:-1]) * np.diff(theta)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    rows = [Row(tag, "[self] normalisation_by_quadrature vs trapezoid", float(rel(meta["normalisation_by_quadrature"], cum[-1])), None),
            Row(tag, "[self] cdf vs trapezoid(2 pi p sin)/last (abs)", float(np.abs(arr["cdf"] - cum / cum[-1]).max()), None)]
    mu = np.cos(theta)
    chi = []
    p_prev, p_l = np.zeros_like(mu), np.ones_like(mu)
    for ell in range(len(arr["legendre"])):
        h = 2 * np.pi * p * p_l * np.sin(theta)
        chi.append(np.sum(0.5 * (h[1:] + h[:-1]) * np.diff(theta)))
        p_prev, p_l = p_l, ((2 * ell + 1) * mu * p_l - ell * p_prev) / (ell + 1)
    rows.append(Row(tag, "[self] legendre chi_l vs trapezoid (abs)", float(np.abs(arr["legendre"] - np.array(chi)).max()), None))
    rows.append(Row(tag, "[self] chi_1 / chi_0 vs analytic g", float(rel(arr["legendre"][1] / arr["legendre"][0], meta["g"])), None))
    return rows


# --------------------------------------------------------------------------- check c


def colour_weights(colour, wavelengths_nm: np.ndarray, illuminant: str) -> tuple[np.ndarray, str]:
    """sRGB channel weights (n_lambda x 3, columns sum to 1) from colour-science."""
    step = (wavelengths_nm[-1] - wavelengths_nm[0]) / (len(wavelengths_nm) - 1)
    shape = colour.SpectralShape(wavelengths_nm[0], wavelengths_nm[-1], step)
    cmfs = colour.MSDS_CMFS[CMFS_NAME].copy().align(shape)
    sd = colour.SDS_ILLUMINANTS[illuminant].copy().align(shape)
    if not (np.allclose(cmfs.wavelengths, wavelengths_nm, atol=1e-9)
            and np.allclose(sd.wavelengths, wavelengths_nm, atol=1e-9)):
        raise RuntimeError("colour's aligned wavelengths differ from nephele's grid")
    M = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB)
    w = (sd.values[:, None] * cmfs.values) @ M.T
    how = (f"{illuminant} {type(sd.interpolator).__name__}, CMFs {type(cmfs.interpolator).__name__} "
           "(SpectralDistribution.align)")
    return w / w.sum(axis=0), how


def check_colour(nep: Nephele, tmp: Path, runs_b: dict, quick: bool) -> tuple[list[Row], list[str]]:
    """Check c: nephele's phase_rgb vs colour-science weights applied to nephele's phase_spectral."""
    import colour

    jobs = [(5.0, "400:700:31", "D65", True), (5.0, "400:700:31", "E", True)]
    if not quick:
        jobs += [(20.0, "400:700:61", "D65", True), (20.0, "400:700:61", "E", True),
                 (5.0, "400:700:41", "D65", False)]  # 7.5 nm: off the 1-nm CIE nodes
    rows, notes, hows = [], [], set()
    for d_med, grid, ill, exact in jobs:
        if grid == "400:700:31" and ill == "D65" and d_med in runs_b:
            arr = runs_b[d_med][0]
        else:
            out = tmp / f"c_d{d_med:g}_{grid.replace(':', '_')}_{ill}"
            arr, _ = nep.mie(out, "--diameter", f"{d_med:g}", "--sizes", str(N_SIZES),
                             "--wavelengths", grid, "--illuminant", ill.lower())
        w, how = colour_weights(colour, arr["wavelength_nm"], ill)
        hows.add(how)
        mine = w.T @ arr["phase_spectral"]  # 3 x n_theta
        r = rel(arr["phase_rgb"], mine.T)
        i = np.unravel_index(int(np.argmax(r)), r.shape)
        step = 300 / (int(grid.split(":")[2]) - 1)
        rows.append(Row(f"c d={d_med:g}um", f"phase_rgb {ill}, {step:g} nm grid" + ("" if exact else " (off-node)"),
                        float(r.max()), TOL_COLOUR if exact else None,
                        f"theta={arr['theta_deg'][i[0]]:g} ch={'RGB'[i[1]]}"))
    notes.append("Weights: w_c(lambda_j) = sum_i M_ci S(lambda_j) cmf_i(lambda_j), each channel normalised to sum 1; "
                 "M = colour sRGB matrix_XYZ_to_RGB; CMFs = colour '" + CMFS_NAME + "'.")
    for how in sorted(hows):
        notes.append("Interpolation: " + how + ".")
    notes.append("D65 is tabulated at 5 nm; colour's D65 uses a LinearInterpolator, and nephele linearly "
                 "interpolates a 1-nm table that is itself linear between the 5-nm values, so the two agree "
                 "on any 5-nm point (and on 1-nm points). The CMFs are tabulated at 1 nm; between 1-nm nodes colour "
                 "interpolates them with Sprague, nephele linearly, hence the informational 7.5 nm row.")
    return rows, notes


# --------------------------------------------------------------------------- main


def parse_args(argv=None) -> argparse.Namespace:
    """Command line."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=DEFAULT_BIN, help="nephele binary (default: %(default)s)")
    ap.add_argument("--quick", action="store_true", help="fewer spheres, d = 5 um only, fewer colour grids")
    ap.add_argument("--seed", type=int, default=20240611, help="seed of the random spheres (default: %(default)s)")
    ap.add_argument("--spheres", type=int, default=None, help="number of random spheres (default 200, quick 40)")
    return ap.parse_args(argv)


def main(argv=None) -> int:
    """Runs all checks; returns the exit status."""
    args = parse_args(argv)
    binary = args.bin.resolve()
    if not binary.is_file():
        print(f"error: nephele binary not found at {binary} (build it: cargo build --release)", file=sys.stderr)
        return 2
    t_start = time.perf_counter()
    nep = Nephele(binary)
    mp = import_miepython()
    n_random = args.spheres if args.spheres is not None else (40 if args.quick else 200)
    all_rows = []
    ok_a = True
    with tempfile.TemporaryDirectory(prefix="nephele-check-mie-") as tmpdir:
        tmp = Path(tmpdir)
        rows, notes, ok_a = check_spheres(mp, nep, n_random, args.seed)
        print_table(f"a. Single spheres: nephele sphere vs miepython (tol {TOL_SPHERE:g})", rows)
        for n in notes:
            print("  * " + n)
        all_rows += rows

        diameters = [5.0] if args.quick else [5.0, 20.0]
        rows, notes, runs = check_polydisperse(mp, nep, tmp, diameters)
        print_table(f"b. Polydisperse product rule (sigma {SIGMA}, {N_SIZES} sizes, 31 wavelengths, "
                    f"2251 angles, m = {WATER}) vs miepython", rows)
        for n in notes:
            print("  * " + n)
        all_rows += rows

        rows, notes = check_colour(nep, tmp, runs, args.quick)
        print_table(f"c. sRGB channels: nephele phase_rgb vs colour-science weights on nephele's phase_spectral "
                    f"(tol {TOL_COLOUR:g})", rows)
        for n in notes:
            print("  * " + n)
        all_rows += rows

    # Check a's sphere-level verdict accounts for n_terms-explained cases.
    failed = [r for r in all_rows if r.status == "FAIL" and not (r.check.startswith("a ") and ok_a)]
    if not ok_a:
        failed.append(Row("a sphere", "see FAIL notes", math.inf, 0))
    print(f"\n{len(all_rows)} rows, {sum(r.status == 'PASS' for r in all_rows)} PASS, "
          f"{sum(r.status == 'INFO' for r in all_rows)} INFO, {len(failed)} FAIL "
          f"({time.perf_counter() - t_start:.0f} s)")
    print("check_mie: " + ("FAIL" if failed else "PASS"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
