#!/usr/bin/env python3
"""The collector renderer's study (docs/collector.md): every study scene rendered by the fast
methods (collector, single, octaves with the engines' defaults and with the fitted parameters)
and compared with its path-traced reference by `nephele compare`; the ablations on the
default cumulus; the speed of a 320 x 240 frame. Writes study.json and study.md (the tables
of docs/collector.md) into OUT.

References: REFS/<scene>_pt, rendered by `nephele render --scene fit-configs/scenes/<scene>.json
--time-budget 240 --out REFS/<scene>_pt` (or longer; their spp and seconds are reported).

Usage: scripts/study_collector.py --refs DIR --out DIR --octaves FILE --collector FILE
       [--bin PATH] [--scenes ...]
"""
import argparse
import json
import os
import subprocess
import sys

SCENES = ["slab", "sphere10", "sphere40", "sphere160", "cloud_front", "cloud_side",
          "cloud_behind", "cloud_high", "cloud_low", "cloud_inside", "voxels"]
GROUPS = ["order 1", "order 2", "orders 3-4", "orders 5-6", "orders 7-8", "orders 9-12",
          "orders 13-18", "orders 19-30", "orders 31+", "orders >= 2", "beauty"]


def run(args, **kw):
    r = subprocess.run(args, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"{' '.join(args)}:\n{r.stderr}")
    return r.stdout


def render(b, scene, method, out, extra=()):
    if not os.path.exists(os.path.join(out, "render.json")):
        run([b, "render", "--scene", f"fit-configs/scenes/{scene}.json", "--method", method,
             "--out", out, *extra])
    return json.load(open(os.path.join(out, "render.json")))


def compare(b, ref, cands, out, py):
    run([b, "compare", "--reference", ref, *sum((["--candidate", c] for c in cands), []),
         "--out", out])
    run([py, "scripts/compare_flip.py", out])
    return json.load(open(os.path.join(out, "report.json")))


def stat(cand, quantity, region="opaque"):
    for q in cand["quantities"]:
        if q["quantity"] == quantity:
            return q["regions"].get(region)
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--octaves", required=True, help="fitted octave parameters (fit_octaves.py)")
    ap.add_argument("--collector", required=True,
                    help="fitted thickness scale of the collector (fit_fast.py --method collector)")
    ap.add_argument("--bin", default="target/release/nephele")
    ap.add_argument("--scenes", nargs="*", default=SCENES)
    a = ap.parse_args()
    py = sys.executable
    fit = json.load(open(a.octaves))
    fitted = ["--octaves", str(fit["n"]), str(fit["a"]), str(fit["b"]), str(fit["c"])]
    cfit = json.load(open(a.collector))
    methods = [("collector", "collector", []),
               ("collector_fitted", "collector", ["--thickness-scale", str(cfit["thickness_scale"])]),
               ("octaves", "octaves", []), ("octaves_fitted", "octaves", fitted),
               ("single", "single", [])]
    study = {"octaves_fitted": fit, "collector_fitted": cfit, "scenes": {}, "ablations": {},
             "speed": {}}
    for scene in a.scenes:
        ref = os.path.join(a.refs, f"{scene}_pt")
        if not os.path.exists(os.path.join(ref, "render.json")):
            print(f"{scene}: no reference in {ref}, skipped", flush=True)
            continue
        dirs, meta = [], {}
        for name, method, extra in methods:
            d = os.path.join(a.out, scene, name)
            meta[name] = render(a.bin, scene, method, d, extra)
            dirs.append(d)
        rep = compare(a.bin, ref, dirs, os.path.join(a.out, scene, "compare"), py)
        study["scenes"][scene] = {"report": rep, "details": {k: v["details"] for k, v in meta.items()}}
        c = rep["candidates"][0]
        ms = stat(c, "orders >= 2")
        print(f"{scene}: collector orders>=2 bias {100 * ms['bias']:+.1f} % rmse "
              f"{100 * ms['rel_rmse_corrected']:.1f} %, FLIP {c['flip_mean']:.3f}", flush=True)
    # Ablations on the default cumulus (sun only).
    ref = os.path.join(a.refs, "cloud_front_pt")
    abl = [("iterations 1", ["--iterations", "1"]), ("iterations 2", ["--iterations", "2"]),
           ("iterations 4", ["--iterations", "4"]), ("iterations 8 (default)", []),
           ("no filtering", ["--no-filter"]), ("no step clamp", ["--no-step-clamp"]),
           ("map 64", ["--map-resolution", "64"]), ("map 128", ["--map-resolution", "128"]),
           ("map 512", ["--map-resolution", "512"]), ("thickness × 0.75", ["--thickness-scale", "0.75"]),
           ("thickness × 0.5", ["--thickness-scale", "0.5"]),
           ("thickness × 0.35", ["--thickness-scale", "0.35"]), ("2 × 2 rays per pixel", ["--rays", "2"])]
    if os.path.exists(os.path.join(ref, "render.json")):
        dirs = []
        for i, (name, extra) in enumerate(abl):
            d = os.path.join(a.out, "ablations", f"a{i}")
            m = render(a.bin, "cloud_front", "collector", d, extra)
            dirs.append(d)
            study["ablations"][name] = {"dir": d, "details": m["details"]}
        rep = compare(a.bin, ref, dirs, os.path.join(a.out, "ablations", "compare"), py)
        for (name, _), c in zip(abl, rep["candidates"]):
            study["ablations"][name]["report"] = c
    # Speed: the default cumulus at 320 x 240, three frames, the fastest counted.
    for method in ["collector", "single", "octaves"]:
        secs = []
        for k in range(3):
            d = os.path.join(a.out, "speed", f"{method}{k}")
            m = render(a.bin, "cloud", method, d, ["--size", "320", "240"])
            secs.append(m["details"]["seconds_per_stage"])
        study["speed"][method] = secs
    with open(os.path.join(a.out, "study.json"), "w") as f:
        json.dump(study, f, indent=2)
    write_tables(study, os.path.join(a.out, "study.md"))


def pct(x, signed=True):
    return "—" if x is None else (f"{100 * x:+.1f}" if signed else f"{100 * x:.1f}")


def write_tables(study, path):
    names = {"collector": "collector", "collector_fitted": "collector (thickness fitted)",
             "octaves": "octaves (defaults)",
             "octaves_fitted": "octaves (fitted)", "single": "single"}
    lines = []
    lines.append("| scene | method | order 1 bias | orders ≥ 2 bias | orders ≥ 2 rel. RMSE (ref. noise) | beauty rel. RMSE | FLIP | PSNR dB | s/frame | path tracer s to the same beauty RMSE | reads/search |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, s in study["scenes"].items():
        rep = s["report"]
        for c, key in zip(rep["candidates"], names):
            o1, ms, b = stat(c, "order 1"), stat(c, "orders >= 2"), stat(c, "beauty")
            reads = "—"
            if key.startswith("collector"):
                gs = s["details"][key]["groups"]
                n = sum(g["searches"] - g["empty"] for g in gs)
                reads = f"{sum(g['reads'] for g in gs) / max(n, 1):.2f}"
            # The path tracer's pixel noise falls as 1/sqrt(time): it reaches the candidate's
            # corrected beauty RMSE E after t_ref (N/E)^2.
            same = "—"
            if b and b["rel_rmse_corrected"] > 0:
                same = f"{rep['reference_seconds'] * (b['reference_noise'] / b['rel_rmse_corrected']) ** 2:.1f}"
            lines.append(
                f"| {scene} ({rep['reference_spp']} spp) | {names[key]} | {pct(o1 and o1['bias'])} % | "
                f"{pct(ms and ms['bias'])} % | {pct(ms and ms['rel_rmse_corrected'], False)} % "
                f"({pct(ms and ms['reference_noise'], False)} %) | {pct(b and b['rel_rmse_corrected'], False)} % | "
                f"{c['flip_mean']:.3f} | {c['psnr_db']:.1f} | {c['seconds']:.2f} | {same} | {reads} |")
    lines.append("")
    lines.append("Per group, collector, bias % (corrected relative RMSE %):")
    lines.append("")
    lines.append("| scene | " + " | ".join(GROUPS[:-2]) + " |")
    lines.append("|---|" + "---|" * (len(GROUPS) - 2))
    for scene, s in study["scenes"].items():
        c = s["report"]["candidates"][0]
        cells = []
        for g in GROUPS[:-2]:
            x = stat(c, g)
            cells.append("—" if x is None else f"{pct(x['bias'])} ({pct(x['rel_rmse_corrected'], False)})")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append("Orders ≥ 2 by region, collector, bias % (corrected relative RMSE %; pixels):")
    lines.append("")
    lines.append("| scene | lit face | shadowed face | silhouette |")
    lines.append("|---|---|---|---|")
    for scene, s in study["scenes"].items():
        c = s["report"]["candidates"][0]
        cells = []
        for r in ["lit", "shadowed", "silhouette"]:
            x = stat(c, "orders >= 2", r)
            cells.append("—" if x is None else f"{pct(x['bias'])} ({pct(x['rel_rmse_corrected'], False)}; {x['pixels']})")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    if study["ablations"]:
        lines.append("")
        lines.append("Ablations, default cumulus (sun only), collector:")
        lines.append("")
        lines.append("| variant | orders ≥ 2 bias | rel. RMSE | order 2 bias | orders 31+ bias | reads/search | converged | s/frame |")
        lines.append("|---|---|---|---|---|---|---|---|")
        for name, x in study["ablations"].items():
            c = x["report"]
            ms, o2, o31 = stat(c, "orders >= 2"), stat(c, "order 2"), stat(c, "orders 31+")
            gs = x["details"]["groups"]
            n = sum(g["searches"] - g["empty"] for g in gs)
            conv = sum(g["converged"] for g in gs) / max(sum(g["searches"] for g in gs), 1)
            lines.append(
                f"| {name} | {pct(ms['bias'])} % | {pct(ms['rel_rmse_corrected'], False)} % | "
                f"{pct(o2['bias'])} % | {pct(o31['bias'])} % | {sum(g['reads'] for g in gs) / max(n, 1):.2f} | "
                f"{100 * conv:.0f} % | {c['seconds']:.2f} |")
    if study["speed"]:
        lines.append("")
        lines.append("Speed, default cumulus at 320 × 240 (fastest of three frames, seconds):")
        lines.append("")
        lines.append("| method | light maps | sky table | pixels | frame |")
        lines.append("|---|---|---|---|---|")
        for m, secs in study["speed"].items():
            best = min(secs, key=lambda s: s["frame"])
            lines.append(f"| {m} | {best['light_maps']:.3f} | {best['sky_table']:.3f} | {best['pixels']:.3f} | {best['frame']:.3f} |")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
