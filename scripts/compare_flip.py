#!/usr/bin/env python3
"""Mean FLIP (NVIDIA's flip-evaluator, LDR, 67 pixels per degree) of the beauty images a
`nephele compare` run wrote (reference.png and candidate<k>.png, tone-mapped with the
reference's exposure), added to its report.json as flip_mean per candidate (atomically), with
the FLIP error maps as flip<k>.png.

Usage: scripts/compare_flip.py OUT_DIR
"""
import json
import os
import sys
import tempfile

import flip_evaluator as flip
import numpy as np
from matplotlib import image as mpimg


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    path = os.path.join(out, "report.json")
    try:
        with open(path) as f:
            report = json.load(f)
    except OSError as e:
        sys.exit(f"cannot read {path}: {e} (run nephele compare first)")
    ref = mpimg.imread(os.path.join(out, "reference.png"))[..., :3].astype(np.float32)
    for k, cand in enumerate(report["candidates"]):
        test = mpimg.imread(os.path.join(out, f"candidate{k}.png"))[..., :3].astype(np.float32)
        err, mean, _ = flip.evaluate(ref, test, "LDR")
        cand["flip_mean"] = float(mean)
        mpimg.imsave(os.path.join(out, f"flip{k}.png"), np.clip(err, 0, 1))
        print(f"{cand['dir']} ({cand['method']}): mean FLIP {mean:.4f}")
    fd, tmp = tempfile.mkstemp(dir=out, suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(report, f, indent=2)
        f.write("\n")
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
