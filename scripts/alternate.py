#!/usr/bin/env python3
"""Two benchmark commands run alternately, for ratios that hold on a drifting clock.

On a VM whose clock drifts by ±25 % within a minute, two runs a fraction of a second apart see
the same clock, and runs seconds apart do not. So A and B run alternately ROUNDS times (the
order swapped every round), each QUANTITY is read from both outputs by its pattern, and the
median of the rounds' ratios B/A is printed with its quartiles.

Usage: scripts/alternate.py --rounds N --a 'CMD …' --b 'CMD …' \\
           --quantity NAME PATTERN_IN_A PATTERN_IN_B [--quantity …] [--label TEXT]
(each PATTERN a regular expression whose first group is the number, searched line by line)
"""
import argparse
import re
import shlex
import statistics
import subprocess


def read(output: str, pattern: str) -> float:
    for line in output.splitlines():
        m = re.search(pattern, line)
        if m:
            return float(m.group(1))
    raise SystemExit(f"alternate.py: no line matches {pattern!r} in:\n{output}")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rounds", type=int, default=30)
    p.add_argument("--a", required=True, help="command A (the reference)")
    p.add_argument("--b", required=True, help="command B")
    p.add_argument("--quantity", nargs=3, action="append", required=True,
                   metavar=("NAME", "PATTERN_IN_A", "PATTERN_IN_B"))
    p.add_argument("--label", default="B / A")
    args = p.parse_args()
    run = lambda cmd: subprocess.run(shlex.split(cmd), check=True, capture_output=True, text=True).stdout
    ratios = {name: [] for name, _, _ in args.quantity}
    for r in range(args.rounds):
        if r % 2 == 0:
            a, b = run(args.a), run(args.b)
        else:
            b, a = run(args.b), run(args.a)
        for name, pa, pb in args.quantity:
            ratios[name].append(read(b, pb) / read(a, pa))
    print(f"   {args.label}, over {args.rounds} rounds: median (quartiles, range)")
    for name, r in ratios.items():
        r.sort()
        q = lambda f: r[min(len(r) - 1, int(f * len(r)))]
        print(f"   {name:36s} {statistics.median(r):.3f} ({q(0.25):.3f}–{q(0.75):.3f}, "
              f"{r[0]:.3f}–{r[-1]:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
