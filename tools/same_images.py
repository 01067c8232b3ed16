#!/usr/bin/env python3
"""Render every shipped scene with every strategy using two vrpt binaries, and say which images
differ: the check that a refactor or an optimisation leaves images bit-identical.

    python3 tools/same_images.py OLD_VRPT NEW_VRPT [--size 24] [--spp 4] [--scenes a,b]
                                 [--flags "--adaptive --spp 64"]
                                 [--extra-flags "--light-points area"]

Each image is a small EXR (default 24x24 at 4 spp, seed 7); the two are compared pixel by pixel
with NEW_VRPT's `diff` ("max relative difference"). `--flags` go to both binaries (to compare
replicates, adaptive rounds, passes); `--extra-flags` to the new one only (a value the old
binary lacks). Prints one line per (scene, strategy) that
differs and a summary; exits 1 if any differs. Strategies: every SAMPLER+DIRECTIONS+LIGHTS that
NEW_VRPT's `render --help` lists, so a new axis value is covered (an old binary that does not
know a value is reported as such, not as a difference).
"""
import argparse
import itertools
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent


def values(vrpt, flag):
    """The possible values of a render flag, from --help ('[possible values: a, b]')."""
    text = subprocess.run([vrpt, "render", "--help"], capture_output=True, text=True).stdout
    block = text.split(f"--{flag} <")[1]
    m = re.search(r"Possible values:\s*\n((?:\s+- [^\n]+\n)+)", block)
    if m:
        return [l.strip()[2:].split(":")[0] for l in m.group(1).strip().splitlines()]
    m = re.search(r"\[possible values: ([^\]]+)\]", block)
    return [v.strip() for v in m.group(1).split(",")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--size", default="24")
    ap.add_argument("--spp", default="4")
    ap.add_argument("--scenes", default=None)
    ap.add_argument("--flags", default="")
    ap.add_argument("--extra-flags", default="")
    a = ap.parse_args()
    scenes = (
        a.scenes.split(",")
        if a.scenes
        else sorted(p.name for p in (ROOT / "scenes").iterdir() if (p / "scene.toml").exists())
    )
    axes = [values(a.new, f) for f in ("sampler", "directions", "lights")]
    differ, same, unknown = [], 0, []
    with tempfile.TemporaryDirectory() as d:
        for scene in scenes:
            for sampler, directions, lights in itertools.product(*axes):
                name = f"{sampler}+{directions}+{lights}"
                out = []
                for tag, vrpt in (("old", a.old), ("new", a.new)):
                    path = f"{d}/{scene}-{name}-{tag}.exr"
                    args = [vrpt, "render", str(ROOT / "scenes" / scene), "-q", "-o", path,
                            "--width", a.size, "--height", a.size, "--spp", a.spp, "--seed", "7",
                            "--sampler", sampler, "--directions", directions, "--lights", lights]
                    args += a.flags.split()
                    args += a.extra_flags.split() if tag == "new" else []
                    r = subprocess.run(args, capture_output=True, text=True)
                    if r.returncode != 0:
                        out = None
                        unknown.append(f"{scene} {name} ({tag}): {r.stderr.strip()[:120]}")
                        break
                    out.append(path)
                if out is None:
                    continue
                r = subprocess.run([a.new, "diff", out[1], out[0]], capture_output=True, text=True)
                m = re.search(r"max relative difference ([0-9.e+-]+)", r.stdout)
                if m is None:
                    sys.exit(f"diff failed: {r.stderr}")
                if float(m.group(1)) != 0.0:
                    differ.append(f"{scene} {name}: max relative difference {m.group(1)}")
                else:
                    same += 1
    for line in differ:
        print("DIFFERS", line)
    for line in unknown:
        print("NOT RENDERED", line)
    print(f"{same} identical, {len(differ)} differ, {len(unknown)} not rendered by both")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
