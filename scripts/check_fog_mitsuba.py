#!/usr/bin/env python3
"""Cross-check of the path tracer's fog scenes (seed 004) against Mitsuba 3 (scalar_rgb, volpath).

Five scenes, each built the same way in both renderers:

  1. spot beam: a box of homogeneous fog (HG phase) with a spot light above it pointing down
     (Mitsuba's spot falloff: full to the beam width, linear in the angle to the cutoff), no
     sun, seen from outside the box;
  2. fog over a ground: a box of fog 1 mm above a diffuse ground plane (nephele's infinite
     `ground`, Mitsuba's rectangle 400 m across with a diffuse BSDF), lit by a point light above
     the fog and by the sun (fog shadows on the ground, light reflected into the fog);
  3. area lights: scene 2's fog and ground lit by a rectangle panel above the fog facing down
     and a sphere of light inside it (Mitsuba's area emitters on null-BSDF shapes, rendered
     with hide_emitters: transparent and unseen by camera rays, as nephele's);
  4. fog in a mesh: a torus of fog (a closed, non-convex OBJ: nephele's fog `mesh`, Mitsuba's
     obj shape with a null BSDF and an interior medium) beside a diffuse box (an OBJ surface,
     flat-shaded) on the ground, lit by a point light and the sun;
  5. fog over a mirror: scene 2 with a mirror for a ground (Mitsuba's conductor with material
     none) under a constant sky, which the camera sees only in the mirror.

Each renderer renders K independent seeds; the statistics are check_render_mitsuba.py's:
image means within 3 combined SE, 4x4-pixel blocks with no |z| > 5 and mean z^2 < 2, and the
mean absolute pixel difference against what the two images' noise alone gives.
"""
import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_render_mitsuba import DEFAULT_BIN, compare  # noqa: E402

GAP = 1e-3  # the fog's floor above the ground (m): no coplanar faces for Mitsuba


def spot_beam() -> dict:
    """Scene 1 in a renderer-neutral form."""
    return {
        "box": ([-4.0, -4.0, 0.0], [4.0, 4.0, 6.0]), "sigma_t": 0.3, "albedo": 0.8, "g": 0.5,
        "sun": None, "ground": None,
        # Half a metre above the fog: no collision comes closer (1/r^2 stays below 4).
        "lights": [{"kind": "spot", "position": [0.0, 0.0, 6.5], "direction": [0.2, 0.0, -1.0],
                    "intensity": [40.0, 30.0, 20.0], "cutoff_deg": 20.0, "beam_width_deg": 12.0}],
        "camera": {"position": [0.5, -12.0, 3.0], "look_at": [0.0, 0.0, 2.5],
                   "up": [0.0, 0.0, 1.0], "fov_deg": 45.0},
    }


def fog_over_ground() -> dict:
    """Scene 2 in a renderer-neutral form."""
    sun = np.array([0.5, 0.3, 0.8])
    return {
        "box": ([-4.0, -4.0, GAP], [4.0, 4.0, 3.0]), "sigma_t": 0.25, "albedo": 0.9, "g": 0.3,
        "sun": {"direction": (sun / np.linalg.norm(sun)).tolist(), "irradiance": [0.3, 0.3, 0.3]},
        "ground": [0.6, 0.5, 0.4],
        # Half a metre above the fog, as the spot: a light inside it would put heavy tails
        # (1/r^2 at collisions beside it) into both renderers' pixels.
        "lights": [{"kind": "point", "position": [1.0, 0.5, 3.5], "intensity": [20.0, 20.0, 20.0]}],
        # The horizon out of view: every camera ray meets the ground within 40 m.
        "camera": {"position": [0.0, -10.0, 6.0], "look_at": [0.0, 0.0, 0.5],
                   "up": [0.0, 0.0, 1.0], "fov_deg": 40.0},
    }


def area_lights() -> dict:
    """Scene 3 in a renderer-neutral form."""
    sc = fog_over_ground()
    sc.update({
        "sigma_t": 0.3, "albedo": 0.85, "g": 0.4, "sun": None,
        # A 2 m x 1 m panel above the fog facing down (edge_u x edge_v = -z), and a ball of
        # light inside the fog.
        "lights": [{"kind": "rectangle", "corner": [-1.0, -0.5, 3.5], "edge_u": [0.0, 1.0, 0.0],
                    "edge_v": [2.0, 0.0, 0.0], "radiance": [5.0, 4.0, 3.0]},
                   {"kind": "sphere", "center": [-1.5, 1.0, 1.2], "radius": 0.4,
                    "radiance": [10.0, 10.0, 10.0]}],
    })
    return sc


def torus_obj(centre, major: float, minor: float, nu: int = 48, nv: int = 24) -> str:
    """A closed torus about the vertical through `centre`, quads counter-clockwise from outside
    (d/du x d/dv points outward)."""
    lines = []
    for i in range(nu):
        u = 2 * np.pi * i / nu
        for j in range(nv):
            v = 2 * np.pi * j / nv
            rr = major + minor * np.cos(v)
            p = (centre[0] + rr * np.cos(u), centre[1] + rr * np.sin(u), centre[2] + minor * np.sin(v))
            lines.append("v " + " ".join(repr(float(x)) for x in p))
    idx = lambda i, j: (i % nu) * nv + (j % nv) + 1  # noqa: E731
    for i in range(nu):
        for j in range(nv):
            lines.append(f"f {idx(i, j)} {idx(i + 1, j)} {idx(i + 1, j + 1)} {idx(i, j + 1)}")
    return "\n".join(lines) + "\n"


def box_obj(lo, hi) -> str:
    """An axis-aligned box, faces counter-clockwise from outside."""
    corner = lambda i: [hi[k] if (i >> k) & 1 else lo[k] for k in range(3)]  # noqa: E731
    lines = ["v " + " ".join(repr(float(x)) for x in corner(i)) for i in range(8)]
    for q in [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]:
        lines.append("f " + " ".join(str(i + 1) for i in q))
    return "\n".join(lines) + "\n"


def mesh_fog() -> dict:
    """Scene 4 in a renderer-neutral form: fog in a torus (a non-convex mesh) beside a diffuse
    block (a mesh surface) on the ground, lit by a point light and the sun."""
    sc = fog_over_ground()
    sc.update({
        "sigma_t": 0.8, "albedo": 0.9, "g": 0.5, "box": None,
        "fog_mesh": torus_obj([0.0, 0.0, 1.2], 1.5, 0.6),
        "blocks": [(box_obj([1.8, -1.6, 0.0], [2.6, -0.8, 1.4]), [0.7, 0.6, 0.5])],
        "lights": [{"kind": "point", "position": [-1.0, -1.0, 3.5],
                    "intensity": [15.0, 15.0, 15.0]}],
    })
    return sc


def mirror_ground() -> dict:
    """Scene 5 in a renderer-neutral form: scene 2 over a mirror (its ground reflectance) under a
    constant sky (out of the camera's direct view; seen in the mirror)."""
    sc = fog_over_ground()
    sc.update({"mirror": True, "sky": [0.05, 0.08, 0.12]})
    return sc


def mitsuba_light(light: dict, T, rgb) -> dict:
    """One light of a neutral scene as a Mitsuba 3 emitter (area lights on null-BSDF shapes:
    transparent, as nephele's)."""
    kind = light["kind"]
    if kind == "spot":
        target = np.array(light["position"]) + np.array(light["direction"])
        up = [1.0, 0.0, 0.0] if abs(light["direction"][0]) < 0.9 else [0.0, 1.0, 0.0]
        return {"type": "spot", "intensity": rgb(light["intensity"]),
                "cutoff_angle": light["cutoff_deg"], "beam_width": light["beam_width_deg"],
                "to_world": T().look_at(origin=light["position"], target=target.tolist(), up=up)}
    if kind == "point":
        return {"type": "point", "position": light["position"], "intensity": rgb(light["intensity"])}
    area = {"type": "area", "radiance": rgb(light["radiance"])}
    if kind == "sphere":
        return {"type": "sphere", "center": light["center"], "radius": light["radius"],
                "bsdf": {"type": "null"}, "emitter": area}
    # Mitsuba's rectangle is [-1, 1]^2 at z = 0 facing +z: its x and y axes become half the
    # edges, its z axis the unit normal edge_u x edge_v.
    eu, ev = np.array(light["edge_u"]), np.array(light["edge_v"])
    n = np.cross(eu, ev)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = eu / 2, ev / 2, n / np.linalg.norm(n)
    m[:3, 3] = np.array(light["corner"]) + (eu + ev) / 2
    return {"type": "rectangle", "to_world": T(m.tolist()), "bsdf": {"type": "null"},
            "emitter": area}


def render_nephele(bin_path: Path, tmp: Path, sc: dict, w: int, h: int, spp: int,
                   seed: int) -> tuple[np.ndarray, float, int]:
    if sc.get("fog_mesh"):
        (tmp / "fog.obj").write_text(sc["fog_mesh"])
        medium = {"kind": "fog", "mesh": str(tmp / "fog.obj")}
    else:
        lo, hi = sc["box"]
        medium = {"kind": "fog", "min": lo, "max": hi}
    scene = {
        "medium": medium,
        "sigma_t": sc["sigma_t"], "albedo": sc["albedo"], "phase": {"kind": "hg", "g": sc["g"]},
        "sun": sc["sun"] or {"direction": [0.0, 0.0, 1.0], "irradiance": [0.0, 0.0, 0.0]},
        "lights": sc["lights"],
        "camera": dict(sc["camera"], width=w, height=h), "spp": spp, "seed": seed,
    }
    surfaces = []
    if sc["ground"] is not None:
        surfaces.append({"kind": "ground", "height": 0.0, "reflectance": sc["ground"],
                         "material": "mirror" if sc.get("mirror") else "diffuse"})
    if sc.get("sky"):
        scene["sky"] = sc["sky"]
    for i, (obj, rho) in enumerate(sc.get("blocks", [])):
        (tmp / f"block{i}.obj").write_text(obj)
        surfaces.append({"kind": "mesh", "obj": str(tmp / f"block{i}.obj"), "reflectance": rho})
    if surfaces:
        scene["surfaces"] = surfaces
    path = tmp / "scene.json"
    path.write_text(json.dumps(scene))
    out = tmp / f"nephele-{seed}"
    subprocess.run([str(bin_path), "render", "--scene", str(path), "--out", str(out)], check=True,
                   capture_output=True)
    doc = json.loads((out / "render.json").read_text())
    return np.load(out / "beauty.npy").astype(np.float64), doc["seconds"], doc["paths"]


def render_mitsuba(sc: dict, w: int, h: int, spp: int, seed: int,
                   tmp: Path) -> tuple[np.ndarray, float]:
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    T = mi.ScalarTransform4f
    cam = sc["camera"]
    rgb = lambda v: {"type": "rgb", "value": list(v)}  # noqa: E731
    d = {
        "type": "scene",
        # Area lights are invisible to camera rays in nephele: hidden here too (only where
        # there are some: Mitsuba also hides an emitter seen by way of a mirror).
        "integrator": {"type": "volpath", "max_depth": -1, "rr_depth": 1_000_000,
                       "hide_emitters": any(l["kind"] in ("sphere", "rectangle")
                                            for l in sc["lights"])},
        "sensor": {
            "type": "perspective", "fov": cam["fov_deg"], "fov_axis": "y",
            "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=cam["up"]),
            "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
    }
    interior = {"type": "homogeneous", "sigma_t": sc["sigma_t"], "albedo": sc["albedo"],
                "phase": {"type": "hg", "g": sc["g"]}}
    if sc.get("fog_mesh"):
        (tmp / "fog.obj").write_text(sc["fog_mesh"])
        d["fog"] = {"type": "obj", "filename": str(tmp / "fog.obj"), "bsdf": {"type": "null"},
                    "interior": interior}
    else:
        lo, hi = (np.array(v) for v in sc["box"])
        d["fog"] = {"type": "cube", "bsdf": {"type": "null"}, "interior": interior,
                    "to_world": T().translate(((lo + hi) / 2).tolist()).scale(((hi - lo) / 2).tolist())}
    for i, (obj, rho) in enumerate(sc.get("blocks", [])):
        (tmp / f"block{i}.obj").write_text(obj)
        # Flat faces, as nephele's geometric normals.
        d[f"block{i}"] = {"type": "obj", "filename": str(tmp / f"block{i}.obj"),
                          "face_normals": True, "bsdf": {"type": "diffuse", "reflectance": rgb(rho)}}
    for i, light in enumerate(sc["lights"]):
        d[f"light{i}"] = mitsuba_light(light, T, rgb)
    if sc["sun"] is not None:
        d["sun"] = {"type": "directional", "direction": (-np.array(sc["sun"]["direction"])).tolist(),
                    "irradiance": rgb(sc["sun"]["irradiance"])}
    if sc["ground"] is not None:
        bsdf = ({"type": "conductor", "material": "none", "specular_reflectance": rgb(sc["ground"])}
                if sc.get("mirror") else {"type": "diffuse", "reflectance": rgb(sc["ground"])})
        d["ground"] = {"type": "rectangle", "to_world": T().scale([200.0, 200.0, 1.0]),
                       "bsdf": bsdf}
    if sc.get("sky"):
        d["sky"] = {"type": "constant", "radiance": rgb(sc["sky"])}
    scene = mi.load_dict(d)
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, seed=seed), dtype=np.float64)
    return img[..., :3], time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", type=Path, default=DEFAULT_BIN)
    ap.add_argument("--quick", action="store_true", help="smaller images")
    args = ap.parse_args(argv)
    w, h, spp, k = (24, 18, 64, 6) if args.quick else (48, 36, 256, 12)
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for name, sc in [("spot beam in fog", spot_beam()), ("fog over a ground", fog_over_ground()),
                         ("area lights", area_lights()), ("fog in a mesh", mesh_fog()),
                         ("fog over a mirror", mirror_ground())]:
            runs_n = [render_nephele(args.bin, tmp, sc, w, h, spp, s + 1) for s in range(k)]
            runs_m = [render_mitsuba(sc, w, h, spp, s + 1, tmp) for s in range(k)]
            failures += compare(name, runs_n, runs_m, k, w, h, spp)
    if failures:
        print("check_fog_mitsuba: FAILED: " + ", ".join(failures))
        return 1
    print("check_fog_mitsuba: all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
