#!/usr/bin/env python3
"""The README's headline picture from a `nephele compare` directory: the reference and its
candidates side by side (tone-mapped with the reference's exposure), each titled with its
method as report.json names it (the collector's correction, the octaves' a, b, c), seconds a
frame, mean FLIP and the relative RMSE of the beauty image (corrected for the reference's
noise).

Usage: scripts/figure_collector.py COMPARE_DIR OUT.png
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib import image as mpimg


def seconds(s):
    """Seconds to three significant digits without an exponent (0.570 s, 12.3 s, 135 s)."""
    if s is None or not s > 0:  # report.json writes an unknown time as null
        return "? s"
    return f"{s:.{max(0, 2 - math.floor(math.log10(s)))}f} s"


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    d, out = sys.argv[1], sys.argv[2]
    rep = json.load(open(os.path.join(d, "report.json")))
    images = [(mpimg.imread(os.path.join(d, "reference.png")),
               f"path tracer\n{rep['reference_spp']} spp, {seconds(rep['reference_seconds'])}")]
    for k, c in enumerate(rep["candidates"]):
        beauty = next(q for q in c["quantities"] if q["quantity"] == "beauty")["regions"]["opaque"]
        flip = c.get("flip_mean")
        name = c.get("method") or os.path.basename(os.path.normpath(c["dir"]))
        images.append((mpimg.imread(os.path.join(d, f"candidate{k}.png")),
                       f"{name}\n{seconds(c['seconds'])}, FLIP {flip:.3f}, "
                       f"RMSE {100 * beauty['rel_rmse_corrected']:.0f} %"))
    fig, axes = plt.subplots(1, len(images), figsize=(3.3 * len(images), 2.9), dpi=150)
    for ax, (img, title) in zip(axes, images):
        ax.imshow(img)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(out, bbox_inches="tight")


if __name__ == "__main__":
    main()
