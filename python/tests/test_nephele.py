"""Tests of the Python module (`import nephele`), run by scripts/check.sh after `maturin develop`.

Each test compares with something the module did not compute: the CLI's batch (`nephele
transport --points`, the same runtime from the other side), closed forms (HG), or the model's
own CDF (chi-square of the samples). Run: python python/tests/test_nephele.py [--bin PATH]
"""
import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.stats import chi2 as chi2_dist

import nephele

REPO = Path(__file__).resolve().parents[2]


def points(n: int, seed: int = 5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = 0.5 * 256.0 ** rng.random(n)
    pts = np.stack([t, 0.125 + 0.875 * rng.random(n), t * rng.random(n), 2 * rng.random(n) - 1,
                    np.pi * (2 * rng.random(n) - 1)], axis=1)
    pts[:4] = [[4, 0.5, 0, -0.3, 0.1], [4, 0.5, 4, 0.3, 3.0], [4, 0.5, 2, 0.0, 0.0],
               [500, 0.05, 10, 0.5, 0.7]]  # past the thickest slab, the sun below the lowest
    return pts


def test_transport_matches_the_cli_batch(binary: Path) -> None:
    """The module's answers are the CLI's, bit for bit, for float64 and float32 input."""
    tab = nephele.Tables()
    pts = points(5000)
    with tempfile.TemporaryDirectory() as tmp:
        # The CLI takes psi in degrees and converts each row to f32 radians through f64; the
        # module takes radians. Both are given the same f32 radians.
        cli_pts = pts.copy()
        cli_pts[:, 4] = np.degrees(pts[:, 4])
        same = pts.astype(np.float32)
        same[:, 4] = np.radians(cli_pts[:, 4]).astype(np.float32)
        np.save(Path(tmp) / "p.npy", cli_pts)
        for collector in (False, True):
            got = tab.evaluate(same, collector=collector)
            args = [str(binary), "transport", "--points", str(Path(tmp) / "p.npy"),
                    "--out", str(Path(tmp) / "a.npy")] + (["--collector"] if collector else [])
            subprocess.run(args, check=True, capture_output=True)
            cli = np.load(Path(tmp) / "a.npy")
            assert cli.dtype == np.float32 and got.shape == cli.shape
            assert np.array_equal(got.view(np.uint32), cli.view(np.uint32)), "module != CLI"
            names = json.loads((Path(tmp) / "a.json").read_text())["columns"]
            assert names == tab.columns(collector=collector)
            flags = np.load(Path(tmp) / "a.outside.npy")
            assert np.array_equal(tab.outside(same), flags), "outside flags != CLI"
    assert tab.outside(pts)[3] == 1 | 4 and tab.outside(pts)[:3].max() == 0
    assert tab.groups == 8 and tab.group_first_orders[0] == 2.0
    assert tab.domain["t"] == (0.5, 128.0) and tab.domain["mu_l"] == (0.125, 1.0)
    assert 0.8 < tab.domain["mean_cosine"] < 0.9
    f32 = tab.evaluate(pts.astype(np.float32))
    assert np.array_equal(f32, tab.evaluate(pts)), "float32 and float64 input (f32 inside)"


def test_errors_are_exceptions_with_the_runtimes_message() -> None:
    tab = nephele.Tables()
    cases = [
        (lambda: tab.evaluate(np.zeros((3, 4))), ValueError, "shape (3, 4), expected (N, 5)"),
        (lambda: tab.evaluate(np.zeros((3, 5), dtype=np.int64)), TypeError, "dtype int64"),
        (lambda: tab.evaluate([[1, 2, 3, 4, 5]]), TypeError, "got list"),
        (lambda: nephele.Tables("/nonexistent.ntt"), ValueError, "cannot read tables"),
        (lambda: nephele.Tables.from_bytes(b"NTT garbage"), ValueError, "transport tables (bytes)"),
        (lambda: nephele.phase_eval("hg", np.zeros(3), g=1.5), ValueError, "g must lie in (-1, 1), got 1.5"),
        (lambda: nephele.phase_eval("hg", np.zeros(3)), ValueError, "model hg needs g"),
        (lambda: nephele.phase_eval("hg", np.zeros(3), g=0.5, k=1), ValueError, "does not take k"),
        (lambda: nephele.phase_eval("mie", np.zeros(3)), ValueError, "unknown model `mie` (valid: hg, two-term-hg"),
        (lambda: nephele.phase_eval("hg", np.array([2.0]), g=0.5), ValueError, "outside [-1, 1]"),
        (lambda: nephele.phase_sample("hg", np.zeros((2, 2)), g=0.5), TypeError, "1-D"),
        (lambda: nephele.phase_eval("vmf", np.zeros(3), kappa=-1.0), ValueError, "kappa must lie in [0, 10000000], got -1"),
        (lambda: nephele.phase_eval("tabulated", np.zeros(3), theta=np.array([0.0, 90.0]),
                                    p=np.ones(2)), ValueError, "not increasing from 0 to 180"),
        (lambda: nephele.phase_eval("tabulated", np.zeros(3)), ValueError, "tabulated needs theta="),
        (lambda: nephele.Tables.from_bytes(42), TypeError, "the bytes of a .ntt expected"),
    ]
    # Points outside the slab raise, naming the row and the coordinate, from every method.
    good = [4.0, 0.5, 1.0, 0.3, 0.0]
    for bad, says in [([4, 1.5, 1, 0.3, 0], "row 1: mu_L = 1.5 is not a sun cosine"),
                      ([4, 0.5, 1, 2.0, 0], "row 1: mu_V = 2 is not a cosine"),
                      ([4, np.nan, 1, 0.3, 0], "row 1: mu_L = NaN"),
                      ([np.inf, 0.5, 1, 0.3, 0], "row 1: t = inf mfp is not a thickness"),
                      ([4, 0.5, 5, 0.3, 0], "row 1: depth = 5 mfp is outside the slab"),
                      ([4, 0.5, 1, 0.3, -np.inf], "row 1: psi_V = -inf rad")]:
        cases.append((lambda b=bad: tab.evaluate(np.array([good, b])), ValueError, says))
        cases.append((lambda b=bad: tab.outside(np.array([good, b])), ValueError, says))
    for call, kind, text in cases:
        try:
            call()
        except kind as e:
            assert text in str(e), f"{text!r} not in {e!r}"
        else:
            raise AssertionError(f"no {kind.__name__} for {text!r}")
    data = (REPO / "runtime/tables/mie10um/transport.ntt").read_bytes()
    try:
        nephele.Tables.from_bytes(data[:1000])
    except ValueError as e:
        assert "truncated transport tables" in str(e), e
    else:
        raise AssertionError("truncated tables accepted")
    # Any buffer holds tables: bytes, bytearray, memoryview, a uint8 array.
    pts = points(100)
    want = nephele.Tables(str(REPO / "runtime/tables/mie10um/transport.ntt")).evaluate(pts)
    for buf in (data, bytearray(data), memoryview(data), np.frombuffer(data, dtype=np.uint8)):
        got = nephele.Tables.from_bytes(buf).evaluate(pts)
        assert np.array_equal(got, want), type(buf)


def test_every_public_name_has_a_docstring() -> None:
    assert nephele.__doc__ and "transport tables" in nephele.__doc__, nephele.__doc__
    names = [nephele.Tables, nephele.phase_eval, nephele.phase_sample]
    names += [getattr(nephele.Tables, m) for m in dir(nephele.Tables) if not m.startswith("_")]
    for obj in names:
        assert obj.__doc__ and len(obj.__doc__.strip()) > 20, f"{obj!r} has no docstring"


def test_phase_models_against_closed_forms_and_chi_square() -> None:
    mu = np.linspace(-1, 1, 1001)
    g = 0.7
    hg = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * mu) ** 1.5)
    assert np.allclose(nephele.phase_eval("hg", mu, g=g), hg, rtol=1e-13, atol=0)
    k = 8.0
    vmf = k * np.exp(k * (mu - 1)) / (2 * np.pi * (1 - np.exp(-2 * k)))
    assert np.allclose(nephele.phase_eval("vmf", mu, kappa=k), vmf, rtol=1e-12, atol=0)
    # Cornette-Shanks is Draine at alpha = 1, whichever spelling names it.
    cs = nephele.phase_eval("cornette_shanks", mu, g=g)
    assert np.array_equal(cs, nephele.phase_eval("draine", mu, g=g, alpha=1.0))
    # A tabulated HG (g = 0.7, every 0.25 degrees) is HG within its linear interpolation.
    theta_hg = np.linspace(0.0, 180.0, 721)
    p_hg = (1 - g * g) / (4 * np.pi * (1 + g * g - 2 * g * np.cos(np.radians(theta_hg))) ** 1.5)
    tab = nephele.phase_eval("tabulated", mu, theta=theta_hg, p=p_hg)
    assert np.allclose(tab, hg, rtol=2e-3, atol=0), np.max(np.abs(tab / hg - 1))
    rng = np.random.default_rng(9)
    for model, params in [("hg", {"g": 0.7}), ("hg_draine", {"diameter": 10.0}),
                          ("two_term_hg", {"g": 0.9, "g2": -0.3, "w": 0.8}),
                          ("draine", {"g": 0.5, "alpha": 1.0}), ("rayleigh", {}), ("schlick", {"k": 0.6}),
                          ("vmf", {"kappa": 8.0}), ("tabulated", {"theta": theta_hg, "p": p_hg}),
                          ("cornette-shanks", {"g": 0.6}), ("reynolds_mccormick", {"g": 0.6, "alpha": 1.2}),
                          ("xlf", {"g": 0.4}),
                          ("hg_draine", {"diameter": 20.0, "preset": "nephele"})]:
        # Normalised over the sphere.
        x, w = np.polynomial.legendre.leggauss(400)
        cuts = [-1.0, 0.99, 0.9999, 1.0]  # finer toward the forward peak
        fine = np.concatenate([a + 0.5 * (b - a) * (x + 1) for a, b in zip(cuts[:-1], cuts[1:])])
        wts = np.concatenate([0.5 * (b - a) * w for a, b in zip(cuts[:-1], cuts[1:])])
        total = 2 * np.pi * np.sum(wts * nephele.phase_eval(model, fine, **params))
        assert abs(total - 1) < 2e-3, f"{model}: {total}"
        # Samples against the pdf: chi-square on 50 bins of mu, p > 1e-3.
        s = nephele.phase_sample(model, rng.random(200_000), **params)
        edges = np.linspace(-1, 1, 51)
        obs, _ = np.histogram(s, edges)
        exp = []
        for a, b in zip(edges[:-1], edges[1:]):
            xm = 0.5 * (b - a) * x + 0.5 * (a + b)
            exp.append(2 * np.pi * 0.5 * (b - a) * np.sum(w * nephele.phase_eval(model, xm, **params)))
        exp = np.array(exp) / np.sum(exp) * len(s)
        keep = exp >= 5
        stat = np.sum((obs[keep] - exp[keep]) ** 2 / exp[keep])
        p = chi2_dist.sf(stat, keep.sum() - 1)
        assert p > 1e-3, f"{model}: chi-square p = {p:.2e}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=REPO / "target" / "release" / "nephele")
    args = ap.parse_args(argv)
    test_transport_matches_the_cli_batch(args.bin)
    test_errors_are_exceptions_with_the_runtimes_message()
    test_every_public_name_has_a_docstring()
    test_phase_models_against_closed_forms_and_chi_square()
    rate = speed()
    print(f"python module: all tests pass ({nephele.__version__}); T of all groups at {rate:.2e} points/s")
    return 0


def speed() -> float:
    """Points per second of Tables.evaluate (T, all groups, order 1) on all cores."""
    import time
    tab, pts = nephele.Tables(), points(1_000_000, seed=2)
    start = time.perf_counter()
    tab.evaluate(pts)
    return len(pts) / (time.perf_counter() - start)


if __name__ == "__main__":
    sys.exit(main())
