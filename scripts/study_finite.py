#!/usr/bin/env python3
"""The finite-cloud study (docs/collector.md, "Finite clouds"): every study scene rendered by the
collector as published, with the finite-cloud correction (the default: lateral leakage counted
by the walk's spread across the light, R from the larger of the cloud's sections across the
light and along its lit surface; no fitted constant) and its ablations (coverage alone, leakage
and coverage, R from each section alone or from the whole projection, the correction of
2 Dec: leakage order by order with R from the projection, and the local slab not cut to p's
depth to the sun: `--no-sun-depth`), and the octaves
fitted on cloud_side; each compared with its path-traced reference by
`nephele compare`. Writes finite.json, finite.md (the tables of docs/collector.md) and
finite_orders.png (per group: truth / slab against the correction's share, on the spheres)
into OUT.

References: REFS/<scene>_pt (`nephele render --scene fit-configs/scenes/<scene>.json
--time-budget 150 --out REFS/<scene>_pt`).

Usage: scripts/study_finite.py --refs DIR --out DIR [--bin PATH] [--scenes ...] [--tables NTT]
       [--only VARIANT ...]
"""
import argparse
import json
import os
import subprocess
import sys

TRAINING = ["cloud_side"]
SEEN = ["sphere10", "sphere40", "sphere160", "cloud_front", "cloud_front_smooth", "cloud_side",
        "cloud_behind", "cloud_high", "cloud_low"]
HELD_OUT = ["strato", "tower", "fair_cumulus"]
ABSORBING = ["slab_w9", "slab_w99", "sphere40_w9", "slab"]
VARIANTS = {
    "published": ["--correction", "none"],
    "leakage": [],
    "coverage": ["--correction", "coverage"],
    "leakage+coverage": ["--correction", "both"],
    "leakage, R from the projection": ["--lateral", "projection"],
    "leakage, R across the light": ["--lateral", "sections"],
    "leakage, R along the surface": ["--lateral", "surface"],
    "leakage by order, R from the projection (2 Dec)": ["--leakage-count", "orders",
                                                        "--lateral", "projection"],
    "leakage, slab not cut to the sun's depth": ["--no-sun-depth"],
    "leakage, the sun's depth not spread": ["--no-sun-spread"],
}
GROUPS = ["order 2", "orders 3-4", "orders 5-6", "orders 7-8", "orders 9-12", "orders 13-18",
          "orders 19-30", "orders 31+"]
FIRST = [2, 3, 5, 7, 9, 13, 19, 31]


def octaves_args(path):
    """--octaves N A B C from the frozen fit (fit-configs/octaves-fitted.json: fitted on
    cloud_side alone by scripts/fit_fast.py)."""
    with open(path) as f:
        fit = json.load(f)
    return ["--octaves", str(fit["n"]), str(fit["a"]), str(fit["b"]), str(fit["c"])]


def run(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(args)}:\n{r.stderr}")
    return r.stdout


def quantity(cand, name):
    """The regions of one quantity (None where the candidate does not split it: the octaves)."""
    return next((q["regions"] for q in cand["quantities"] if q["quantity"] == name), None)


def render_and_compare(binary, scene, refs, out, variants, tables=None):
    dirs = []
    tables = ["--tables", tables] if tables else []
    for name, extra in variants.items():
        d = os.path.join(out, "renders", f"{scene}-{name.replace(' ', '_').replace(',', '')}")
        method = ["--method", "octaves"] if name == "octaves (fitted)" else ["--method", "collector"]
        run([binary, "render", "--scene", f"fit-configs/scenes/{scene}.json", *method, *extra,
             *tables, "--out", d])
        dirs.append(d)
    cmp_dir = os.path.join(out, "compare", scene)
    args = [binary, "compare", "--reference", os.path.join(refs, f"{scene}_pt"), "--out", cmp_dir]
    for d in dirs:
        args += ["--candidate", d]
    run(args)
    with open(os.path.join(cmp_dir, "report.json")) as f:
        return json.load(f)


def row(scene, name, report, cand):
    ge2 = quantity(cand, "orders >= 2")
    beauty = quantity(cand, "beauty")
    split = [g for g in GROUPS if quantity(cand, g)]
    light = {g: quantity(cand, g)["opaque"]["mean_reference"] for g in split}
    total = sum(light.values())
    groups = {g: quantity(cand, g)["opaque"]["bias"] for g in split}
    worst = max(((abs(groups[g]), g) for g in split if light[g] >= 0.01 * total),
                default=(0.0, None))
    reg = {r: ge2[r]["bias"] if ge2.get(r, {}).get("pixels") else None
           for r in ["lit", "shadowed", "silhouette"]}
    # The path tracer's time to the same beauty error: its own noise falls as 1/sqrt(time).
    noise = beauty["opaque"]["reference_noise"]
    err = max(beauty["opaque"]["rel_rmse_corrected"], 1e-9)
    pt_seconds = report["reference_seconds"] * (noise / err) ** 2
    return {
        "scene": scene, "method": name, "spp": report["reference_spp"],
        "ge2_bias": ge2["opaque"]["bias"], "ge2_bias_noise": ge2["opaque"]["bias_noise"],
        "ge2_rmse": ge2["opaque"]["rel_rmse_corrected"],
        "ge2_noise": ge2["opaque"]["reference_noise"],
        "beauty_rmse": err, "lit": reg["lit"], "shadowed": reg["shadowed"],
        "silhouette": reg["silhouette"], "worst_group": worst[1] or "—",
        "worst_group_bias": groups.get(worst[1]),
        "groups": groups, "group_light": light, "seconds": cand["seconds"],
        "pt_seconds_to_same_beauty_error": pt_seconds,
    }


def pct(x):
    return "—" if x is None else f"{100 * x:+.1f} %"


def table(rows):
    out = ["| scene | method | ≥ 2 bias | ≥ 2 rel. RMSE corr. (ref. noise) | lit | shadowed | "
           "silhouette | worst group ≥ 1 % | beauty RMSE | s/frame | path tracer s to it |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(
            f"| {r['scene']} ({r['spp']} spp) | {r['method']} | {pct(r['ge2_bias'])} | "
            f"{100 * r['ge2_rmse']:.1f} % ({100 * r['ge2_noise']:.1f} %) | {pct(r['lit'])} | "
            f"{pct(r['shadowed'])} | {pct(r['silhouette'])} | {r['worst_group']} "
            f"{pct(r['worst_group_bias'])} | {100 * r['beauty_rmse']:.1f} % | {r['seconds']:.2f} | "
            f"{r['pt_seconds_to_same_beauty_error']:.1f} |")
    return "\n".join(out)


def group_table(rows):
    out = ["| scene | method | " + " | ".join(GROUPS) + " |", "|---|---|" + "---|" * len(GROUPS)]
    for r in rows:
        out.append(f"| {r['scene']} | {r['method']} | " +
                   " | ".join(pct(r["groups"].get(g)) for g in GROUPS) + " |")
    return "\n".join(out)


def figure(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    mid = [2, 3.5, 5.5, 7.5, 10.5, 15.5, 24.5, 45]
    for scene, colour in [("sphere10", "C0"), ("sphere40", "C1"), ("sphere160", "C2"),
                          ("cloud_front", "C3"), ("cloud_side", "C4")]:
        pub = next((r for r in rows if r["scene"] == scene and r["method"] == "published"), None)
        leak = next((r for r in rows if r["scene"] == scene and r["method"] == "leakage"), None)
        if not pub or not leak:
            continue
        truth = [1 / (1 + pub["groups"][g]) for g in GROUPS]
        model = [(1 + leak["groups"][g]) / (1 + pub["groups"][g]) for g in GROUPS]
        ax.semilogy(mid, truth, "o-", color=colour, label=f"{scene}: path tracer / slab")
        ax.semilogy(mid, model, "x--", color=colour, label=f"{scene}: leakage's share")
    ax.set_xlabel("scattering order (group mid; 31+ drawn at 45)")
    ax.set_ylabel("share of the slab's light")
    ax.set_title("Light a finite cloud keeps, per order group")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=130)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--refs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default="target/release/nephele")
    ap.add_argument("--scenes", nargs="*", default=SEEN + HELD_OUT + ABSORBING)
    ap.add_argument("--octaves", default="fit-configs/octaves-fitted.json",
                    help="the octaves' frozen fit (scripts/fit_fast.py on cloud_side)")
    ap.add_argument("--tables", help="a .ntt to render with (default: the embedded tables)")
    ap.add_argument("--only", nargs="*", help="render only these variants (names as in "
                    "VARIANTS, e.g. leakage for the default; 'octaves (fitted)')")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for scene in a.scenes:
        if not os.path.isdir(os.path.join(a.refs, f"{scene}_pt")):
            print(f"{scene}: no reference, skipped", file=sys.stderr)
            continue
        variants = dict(VARIANTS)
        if scene in ABSORBING:
            variants = {"leakage": []}
        else:
            variants["octaves (fitted)"] = octaves_args(a.octaves)
        if a.only:
            variants = {k: v for k, v in variants.items() if k in a.only}
        report = render_and_compare(a.bin, scene, a.refs, a.out, variants, a.tables)
        for name, cand in zip(variants, report["candidates"]):
            rows.append(row(scene, name, report, cand))
        print(f"{scene}: done", file=sys.stderr)
    with open(os.path.join(a.out, "finite.json"), "w") as f:
        json.dump(rows, f, indent=1)
    held = [r for r in rows if r["scene"] in HELD_OUT]
    seen = [r for r in rows if r["scene"] in SEEN]
    absorbing = [r for r in rows if r["scene"] in ABSORBING]
    md = ["## Study scenes (cloud_side is the training scene)", table(seen),
          "## Held out: shapes nobody tuned on", table(held),
          "## Absorbing media (collector, leakage; ϖ in the scene)", table(absorbing),
          "## Per group, orders ≥ 2 bias", group_table(seen + held)]
    with open(os.path.join(a.out, "finite.md"), "w") as f:
        f.write("\n\n".join(md) + "\n")
    figure(rows, os.path.join(a.out, "finite_orders.png"))
    print(f"wrote {a.out}/finite.json, finite.md, finite_orders.png", file=sys.stderr)


if __name__ == "__main__":
    main()
