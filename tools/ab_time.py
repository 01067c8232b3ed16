#!/usr/bin/env python3
"""Time two commands the way this project's timings are made: interleaved (A B A B ...) on the
same machine, the median of the pairwise ratios B/A (the machines are shared and drift by 30 %
within minutes, so separate medians of A and of B mislead).

    python3 tools/ab_time.py [--runs 9] [--time-from render] -- "A command" "B command"

`--time-from render` takes each run's time from vrpt's own summary line ("... in 1.234 s:"),
i.e. the render without scene loading; otherwise the wall time of the whole command.
Prints the medians of A and B, and the median of B/A with its min..max.
"""
import argparse
import re
import shlex
import statistics
import subprocess
import sys
import time


def timed(cmd, render):
    t = time.perf_counter()
    r = subprocess.run(shlex.split(cmd), capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed: {cmd}\n{r.stderr}")
    if render:
        m = re.search(r" in ([0-9.]+) s: ", r.stderr)
        if not m:
            sys.exit(f"no render time in the output of: {cmd}\n{r.stderr}")
        return float(m.group(1))
    return wall


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--time-from", choices=["wall", "render"], default="render")
    ap.add_argument("a")
    ap.add_argument("b")
    a = ap.parse_args()
    render = a.time_from == "render"
    timed(a.a, render), timed(a.b, render)  # warm caches
    ta, tb = [], []
    for _ in range(a.runs):
        ta.append(timed(a.a, render))
        tb.append(timed(a.b, render))
    ratios = [b / x for x, b in zip(ta, tb)]
    print(f"A median {statistics.median(ta):.4f} s, B median {statistics.median(tb):.4f} s; "
          f"B/A median {statistics.median(ratios):.4f} (min {min(ratios):.4f}, max {max(ratios):.4f}, "
          f"{a.runs} pairs)")


if __name__ == "__main__":
    main()
