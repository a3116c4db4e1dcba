#!/usr/bin/env python3
"""Cross-check of `nephele render` against Mitsuba 3 (scalar_rgb, volpath) on a voxel cloud.

The same scene for both: a 24^3 density grid (a smooth blob with structure, deterministic) over a
box, exported as a nephele voxel scene (.npy) and as Mitsuba's gridvolume (the same values, the
same box, trilinear between voxel centres), extinction scale, albedo and a phase function (hg,
and a tabulated 1 um Mie table: Mitsuba's tabphase),
a directional sun, a pinhole camera with the same vertical field of view and a box pixel filter.
Each renderer renders K independent seeds; per-pixel means and their standard errors come from
the spread across seeds. Compared, per channel:

  a. the image means: |mean_N - mean_M| < 3 SE;
  b. the 4x4-pixel blocks the cloud covers: z = (block_N - block_M) / SE; no |z| > 5 and
     mean z^2 < 2 (with SEs from K seeds, z follows Student's t with K - 1 degrees of freedom
     roughly, E z^2 = (K - 1)/(K - 3));
  c. the mean absolute pixel difference against what the two images' noise alone gives,
     E|d| = sqrt(2/pi) * sqrt(se_N^2 + se_M^2) per pixel (Gaussian), within 3 of its SE.

nephele's beauty.exr, read by Mitsuba's OpenEXR reader, must equal its beauty.npy. It also
reports camera paths per second of both on this machine and the ratio (nephele's
multi-threaded render against Mitsuba's scalar_rgb, which also uses every core).
"""
import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from mie_tabphase import regular_mu_table  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
DEFAULT_BIN = REPO / "target" / "release" / "nephele"

N = 24                       # voxels per axis
ORIGIN = [-1.0, -1.0, -1.0]  # the box (m)
SIZE = [2.0, 2.0, 2.0]
SIGMA_T = 6.0                # 1/m at density 1
ALBEDO = 0.95
G = 0.7
SUN = np.array([0.4, -0.5, 0.77])
SUN = SUN / np.linalg.norm(SUN)
CAMERA = {"position": [0.3, -4.5, 0.8], "look_at": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0],
          "fov_deg": 36.0}


def density_grid() -> np.ndarray:
    """A blob of three overlapping Gaussians with a sinusoidal texture, [z, y, x], float32."""
    c = (np.arange(N) + 0.5) / N * 2.0 - 1.0
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    d = np.zeros_like(x)
    for (cx, cy, cz, r) in [(0.0, 0.0, -0.1, 0.55), (0.35, 0.1, 0.2, 0.4), (-0.3, -0.15, 0.15, 0.35)]:
        d += np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (2 * r * r))
    d *= 0.75 + 0.25 * np.sin(7 * x) * np.cos(5 * y + 1) * np.sin(6 * z + 2)
    d = np.clip(d - 0.15, 0.0, None)
    return (d / d.max()).astype(np.float32)


def write_scene(tmp: Path, grid: np.ndarray, phase: dict, w: int, h: int, spp: int,
                seed: int) -> Path:
    """The nephele scene (and its grid.npy) in tmp."""
    np.save(tmp / "grid.npy", grid)
    scene = {
        "medium": {"kind": "voxels", "npy": "grid.npy", "origin": ORIGIN, "size": SIZE},
        "sigma_t": SIGMA_T, "albedo": ALBEDO, "phase": phase,
        "sun": {"direction": SUN.tolist(), "irradiance": [1.0, 1.0, 1.0]},
        "camera": dict(CAMERA, width=w, height=h), "spp": spp, "seed": seed,
    }
    path = tmp / "scene.json"
    path.write_text(json.dumps(scene))
    return path


def cases(bin_path: Path, tmp: Path) -> list[tuple[str, dict, dict]]:
    """(name, nephele phase, Mitsuba phase) of the compared cases."""
    _, values = regular_mu_table(bin_path, tmp)
    return [
        (f"hg {G}", {"kind": "hg", "g": G}, {"type": "hg", "g": G}),
        ("tabulated 1 um Mie", {"kind": "table", "path": str(tmp / "tab.npz")},
         {"type": "tabphase", "values": ",".join(repr(float(v)) for v in values[::-1])}),
    ]


def render_nephele(bin_path: Path, tmp: Path, grid: np.ndarray, phase: dict, w: int, h: int,
                   spp: int, seed: int) -> tuple[np.ndarray, float, int]:
    path = write_scene(tmp, grid, phase, w, h, spp, seed)
    out = tmp / f"nephele-{seed}"
    subprocess.run([str(bin_path), "render", "--scene", str(path), "--out", str(out)], check=True,
                   capture_output=True)
    doc = json.loads((out / "render.json").read_text())
    beauty = np.load(out / "beauty.npy").astype(np.float64)
    # The OpenEXR file, read by Mitsuba's own reader, holds the same linear image.
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    exr = np.array(mi.Bitmap(str(out / "beauty.exr")), dtype=np.float64)[..., :3]
    if exr.shape != beauty.shape or np.abs(exr - beauty).max() > 0:
        raise SystemExit("check_render_mitsuba: beauty.exr differs from beauty.npy")
    return beauty, doc["seconds"], doc["paths"]


def render_mitsuba(grid: np.ndarray, phase: dict, w: int, h: int, spp: int,
                   seed: int) -> tuple[np.ndarray, float]:
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    T = mi.ScalarTransform4f
    centre = [o + s / 2 for o, s in zip(ORIGIN, SIZE)]
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 1_000_000},
        "sensor": {
            "type": "perspective", "fov": CAMERA["fov_deg"], "fov_axis": "y",
            "to_world": T().look_at(origin=CAMERA["position"], target=CAMERA["look_at"], up=CAMERA["up"]),
            "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sun": {"type": "directional", "direction": (-SUN).tolist(),
                "irradiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
        "cloud": {
            "type": "cube",
            "to_world": T().translate(centre).scale([s / 2 for s in SIZE]),
            "bsdf": {"type": "null"},
            "interior": {
                "type": "heterogeneous", "albedo": ALBEDO, "scale": SIGMA_T,
                "sigma_t": {"type": "gridvolume", "grid": mi.VolumeGrid(grid[..., None]),
                            "to_world": T().translate(ORIGIN).scale(SIZE)},
                "phase": phase,
            },
        },
    })
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, seed=seed), dtype=np.float64)
    return img[..., :3], time.perf_counter() - t0


def stats(images: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    a = np.stack(images)
    return a.mean(axis=0), a.std(axis=0, ddof=1) / math.sqrt(len(images))


def blocks(img: np.ndarray, b: int) -> np.ndarray:
    h, w = img.shape[0] // b * b, img.shape[1] // b * b
    return img[:h, :w].reshape(h // b, b, w // b, b, -1).mean(axis=(1, 3))


def compare(name: str, runs_n, runs_m, k: int, w: int, h: int, spp: int) -> list[str]:
    """Prints the statistics of one case; the names of the failed channels."""
    failures = []
    mean_n, se_n = stats([r[0] for r in runs_n])
    mean_m, se_m = stats([r[0] for r in runs_m])
    # Block statistics: the spread of block means across seeds.
    bn, bm = [blocks(r[0], 4) for r in runs_n], [blocks(r[0], 4) for r in runs_m]
    (bmn, bsn), (bmm, bsm) = stats(bn), stats(bm)
    for c, channel in enumerate("RGB"):
        gn = np.array([r[0][..., c].mean() for r in runs_n])
        gm = np.array([r[0][..., c].mean() for r in runs_m])
        se = math.sqrt(gn.var(ddof=1) / k + gm.var(ddof=1) / k)
        z_mean = (gn.mean() - gm.mean()) / se
        # Blocks the cloud covers (empty ones are 0 in both, with no noise).
        lit = (bsn[..., c] > 0) & (bsm[..., c] > 0)
        zb = (bmn[..., c] - bmm[..., c])[lit] / np.sqrt(bsn[..., c] ** 2 + bsm[..., c] ** 2)[lit]
        d = np.abs(mean_n[..., c] - mean_m[..., c])
        expect = math.sqrt(2 / math.pi) * np.sqrt(se_n[..., c] ** 2 + se_m[..., c] ** 2)
        # The SE of a mean of |d| over pixels: the spread of |d| over pixels / sqrt(pixels).
        z_abs = (d.mean() - expect.mean()) / (d.std(ddof=1) / math.sqrt(d.size))
        ok = abs(z_mean) < 3 and np.abs(zb).max() < 5 and (zb ** 2).mean() < 2 and abs(z_abs) < 3
        print(f"{name}, {channel}: image mean nephele {gn.mean():.5f} mitsuba {gm.mean():.5f} "
              f"(z = {z_mean:+.2f}, SE {se / gm.mean():.2%}); {zb.size} lit blocks max |z| "
              f"{np.abs(zb).max():.2f}, mean z^2 {(zb ** 2).mean():.2f}; mean |difference| {d.mean():.5f} "
              f"vs noise {expect.mean():.5f} (z = {z_abs:+.2f})  {'ok' if ok else 'FAILED'}")
        if not ok:
            failures.append(f"{name} {channel}")
    paths = sum(r[2] for r in runs_n)
    rate_n = paths / sum(r[1] for r in runs_n)
    rate_m = k * w * h * spp / sum(r[1] for r in runs_m)
    print(f"{name}, speed: nephele {rate_n:,.0f} camera paths/s, mitsuba scalar_rgb volpath "
          f"{rate_m:,.0f} paths/s: ratio {rate_n / rate_m:.2f}")
    return failures


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=DEFAULT_BIN)
    ap.add_argument("--quick", action="store_true", help="smaller images")
    args = ap.parse_args(argv)
    w, h, spp, k = (48, 36, 32, 6) if args.quick else (96, 72, 128, 16)
    grid = density_grid()
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, phase_n, phase_m in cases(args.bin, tmp):
            runs_n = [render_nephele(args.bin, tmp, grid, phase_n, w, h, spp, s + 1) for s in range(k)]
            runs_m = [render_mitsuba(grid, phase_m, w, h, spp, s + 1) for s in range(k)]
            failures += compare(name, runs_n, runs_m, k, w, h, spp)
    if failures:
        print("check_render_mitsuba: FAILED: " + ", ".join(failures))
        return 1
    print("check_render_mitsuba: all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
