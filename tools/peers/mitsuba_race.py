#!/usr/bin/env python3
"""Race vrpt against Mitsuba 3 on Mitsuba's own Cornell box.

What it does, in order (every step prints what it found):

1. export  Writes Mitsuba's built-in ``mi.cornell_box()`` as OBJ + MTL + scene.toml for vrpt:
           the five walls and the light are Mitsuba ``rectangle``s (corners (+-1, +-1, 0) under
           ``to_world``, normal +z), the two boxes are Mitsuba ``cube`` meshes (loaded through
           Mitsuba itself, so the triangles are Mitsuba's). Diffuse reflectances come from the
           dict; the light is one-sided, faces -y, emits the dict's radiance and reflects with the
           white BSDF. Camera: eye (0, 0, 3.9), target the origin, up +y, fov 39.3077 deg on the
           smaller (here both) axis. Every face's winding is checked against its normal.
2. agree   Converged references of both renderers (``--ref-spp`` samples, in ``--ref-passes``
           passes with their own seeds). The image mean and the means of a 4x4 grid of regions
           are compared per channel: z = (a - b) / sqrt(se_a^2 + se_b^2), with each standard
           error taken from the spread of that renderer's passes. 17 means x 3 channels = 51
           tests; the check passes when every |z| < 4 (Bonferroni for a family error of 1% on a
           normal gives 3.7; 4 allows for the t tails of 16 passes). Mitsuba renders with a box
           pixel filter (its default is a Gaussian), so both estimate the same pixel integral.
3. speed   Samples per second at equal spp (``--spp``, ``--runs`` runs each, the contestants
           taken in turn, run 0 of each, then run 1 of each, so a drift of the shared machine's
           speed falls on all alike; vrpt's speed against Mitsuba's is the median of the pairwise
           ratios of the same run), and the MSE of each as the mean over its runs with its
           standard error (a median of three heavy-tailed MSEs once read 1.2x where eight seeds
           read 0.99x): vrpt's own render
           time (recorded in its EXR; scene loading and the BVH build are outside it) against
           the wall time of ``mi.render`` with the scene loaded and its kernel compiled by a
           warm-up render of the same configuration.
4. race    MSE at equal time: each contestant gets spp chosen from its measured rate so that a
           render takes the budget ``--budget`` seconds (default: Mitsuba's independent sampler
           at ``--spp``), rounded as each sampler wants it (a square for vrpt's stratified, a
           power of two for Sobol and Mitsuba's ldsampler, p^2 for orthogonal), ``--runs`` runs with other seeds. The MSE is against the mean of the
           two references (whose own noise is printed next to it), and is reported scaled to the
           budget, MSE * t / budget, so a render that ran 3% long is not favoured; mean and standard
           error over the runs, the contestants again taken in turn.

Needs: ``pip install -r tools/peers/requirements.txt`` (mitsuba, numpy); the ``llvm_ad_rgb``
variant also needs LLVM's shared library (Debian: ``apt install libllvm19``), else the script
falls back to ``scalar_rgb`` and says so. vrpt itself: ``cargo build --release``.

    python3 tools/peers/mitsuba_race.py                  # everything, about 15 minutes
    python3 tools/peers/mitsuba_race.py --quick          # small references, 3 runs: minutes

References are kept in the output folder (default target/peers/mitsuba) and reused while their
settings match; ``--fresh`` renders them again. Results: a markdown table on stdout and
``results.json`` in the output folder.
"""

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np


def newest_llvm():
    """The newest versioned libLLVM in the system's library folders: Dr.Jit looks only for
    an unversioned libLLVM.so, which Debian's libllvm19 does not install (and LLVM 15, which
    it found here, crashed in the JIT)."""
    import glob
    import re
    found = []
    for f in glob.glob("/usr/lib/*/libLLVM-*.so") + glob.glob("/usr/lib/libLLVM-*.so"):
        m = re.search(r"libLLVM-(\d+)\.so$", f)
        if m:
            found.append((int(m.group(1)), f))
    return max(found)[1] if found else None


if "DRJIT_LIBLLVM_PATH" not in os.environ and newest_llvm():
    os.environ["DRJIT_LIBLLVM_PATH"] = newest_llvm()

try:
    import mitsuba as mi
except ImportError:
    sys.exit("mitsuba_race.py: needs the Python package mitsuba: "
             "pip install -r tools/peers/requirements.txt")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NAME = "mitsuba-cornell"

# vrpt contestants: (label, vrpt strategy, then any further flags of `vrpt render`). The first is
# vrpt's default.
VRPT_STRATEGIES = [
    ("vrpt mis (stratified+phong+mis)", "mis"),
    ("vrpt mis --edge-rays 0 (before edge rays)", "mis --edge-rays 0"),
    ("vrpt mis --reuse 2", "mis --reuse 2"),
    ("vrpt mis --reuse 3", "mis --reuse 3"),
    ("vrpt mis --reuse 4", "mis --reuse 4"),
    ("vrpt auto (mis, mis+reuse4)", "auto"),
    ("vrpt sobol+phong+mis", "sobol+phong+mis"),
    ("vrpt independent+phong+mis", "independent+phong+mis"),
    ("vrpt combined (bsdf only)", "combined"),
]
# Mitsuba's samplers raced; the best of the last three is "its best".
MITSUBA_SAMPLERS = ["independent", "multijitter", "ldsampler", "orthogonal"]


# ------------------------------------------------------------------------------------ export
def transform_point(m, p):
    v = m @ np.array([p[0], p[1], p[2], 1.0])
    return v[:3] / v[3]


def fmt(x):
    return f"{float(x):.9g}"


def export_scene(folder, width, height, spp, max_depth):
    """Mitsuba's Cornell box as vrpt scene files; returns the triangle count."""
    d = mi.cornell_box()
    os.makedirs(folder, exist_ok=True)
    bsdfs = {k: v for k, v in d.items() if isinstance(v, dict) and v.get("type") == "diffuse"}
    verts, groups = [], []  # groups: (material, [(i0, i1, i2)])

    def add_tri(tri_list, pts, normal):
        """Append a triangle wound counter-clockwise about `normal`."""
        p = [np.asarray(x, dtype=np.float64) for x in pts]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        if np.dot(n, normal) < 0:
            p[1], p[2] = p[2], p[1]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        assert np.dot(n, normal) > 0, "winding does not follow the normal"
        base = len(verts) + 1
        verts.extend(p)
        tri_list.append((base, base + 1, base + 2))

    shapes = 0
    for key, v in d.items():
        if not isinstance(v, dict) or v.get("type") not in ("rectangle", "cube"):
            continue
        shapes += 1
        m = np.array(v["to_world"].matrix, dtype=np.float64)
        mat = key if "emitter" in v else v["bsdf"]["id"]
        tris = []
        if v["type"] == "rectangle":
            c = [transform_point(m, q) for q in [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]]
            normal = np.linalg.inv(m[:3, :3]).T @ np.array([0.0, 0.0, 1.0])
            add_tri(tris, (c[0], c[1], c[2]), normal)
            add_tri(tris, (c[0], c[2], c[3]), normal)
        else:
            mesh = mi.load_dict({"type": "cube", "to_world": v["to_world"]})
            p = np.array(mesh.vertex_positions_buffer(), dtype=np.float64).reshape(-1, 3)
            f = np.array(mesh.faces_buffer()).reshape(-1, 3)
            centre = p.mean(axis=0)
            for a, b, cc in f:
                tri = (p[a], p[b], p[cc])
                outward = np.mean(tri, axis=0) - centre
                n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
                assert np.dot(n, outward) > 0, "a Mitsuba cube face winds inward"
                add_tri(tris, tri, n)
        groups.append((key, mat, tris))
    # every shape of the loaded scene was exported
    assert shapes == 8, f"expected 8 shapes (5 walls, light, 2 boxes), found {shapes}"

    with open(os.path.join(folder, NAME + ".mtl"), "w") as out:
        out.write("# Mitsuba 3's mi.cornell_box(), written by tools/peers/mitsuba_race.py\n")
        for bid, b in sorted(bsdfs.items()):
            out.write(f"\nnewmtl {bid}\nKd {' '.join(fmt(x) for x in b['reflectance']['value'])}\n")
        light = d["light"]
        white = bsdfs[light["bsdf"]["id"]]["reflectance"]["value"]
        out.write(f"\nnewmtl light\nKd {' '.join(fmt(x) for x in white)}\n")
        out.write(f"Ke {' '.join(fmt(x) for x in light['emitter']['radiance']['value'])}\n")
    with open(os.path.join(folder, NAME + ".obj"), "w") as out:
        out.write("# Mitsuba 3's mi.cornell_box(), written by tools/peers/mitsuba_race.py\n")
        out.write(f"mtllib {NAME}.mtl\n")
        for p in verts:
            out.write(f"v {fmt(p[0])} {fmt(p[1])} {fmt(p[2])}\n")
        for key, mat, tris in groups:
            out.write(f"g {key}\nusemtl {mat}\n")
            for t in tris:
                out.write(f"f {t[0]} {t[1]} {t[2]}\n")
    sensor = d["sensor"]
    cam = np.array(sensor["to_world"].matrix, dtype=np.float64)
    eye = transform_point(cam, (0, 0, 0))
    target = transform_point(cam, (0, 0, 1))
    target = eye + (target - eye) * (np.linalg.norm(eye) / np.linalg.norm(target - eye))
    up = cam[:3, 1]
    assert sensor["film"]["width"] == sensor["film"]["height"], "fov axis: square films only"
    with open(os.path.join(folder, "scene.toml"), "w") as out:
        out.write("# Mitsuba 3's mi.cornell_box(), written by tools/peers/mitsuba_race.py\n")
        out.write(f'obj = "{NAME}.obj"\n\n[camera]\n')
        out.write(f"eye = [{', '.join(fmt(x) for x in eye)}]\n")
        out.write(f"target = [{', '.join(fmt(round(x, 6)) for x in target)}]\n")
        out.write(f"up = [{', '.join(fmt(x) for x in up)}]\n")
        out.write(f"fov = {fmt(sensor['fov'])}\n\n")
        out.write("[environment]\nradiance = [0.0, 0.0, 0.0]\n\n")
        out.write(f"[render]\nwidth = {width}\nheight = {height}\nspp = {spp}\n")
        out.write(f"max_depth = {max_depth}\n")
    return sum(len(t) for _, _, t in groups)


# ------------------------------------------------------------------------------- renderers
class Mitsuba:
    def __init__(self, variant, width, height, max_depth):
        self.variant = variant
        self.width, self.height, self.max_depth = width, height, max_depth
        self.scenes = {}
        self.warm = set()

    def scene(self, sampler):
        if sampler not in self.scenes:
            d = mi.cornell_box()
            film = d["sensor"]["film"]
            film["rfilter"] = {"type": "box"}
            film["width"], film["height"] = self.width, self.height
            d["sensor"]["sampler"] = {"type": sampler, "sample_count": 4}
            d["integrator"]["max_depth"] = self.max_depth
            self.scenes[sampler] = mi.load_dict(d)
        return self.scenes[sampler]

    def spp_for(self, sampler, spp):
        """The spp Mitsuba's sampler really takes when asked for `spp`."""
        if sampler == "ldsampler":
            return 1 << max(0, int(round(math.log2(max(spp, 1)))))
        if sampler == "orthogonal":
            # strength-2 orthogonal arrays take p^2 samples, p prime
            r = max(2, int(round(math.sqrt(spp))))
            while any(r % q == 0 for q in range(2, int(math.sqrt(r)) + 1)):
                r += 1
            return r * r
        return max(1, spp)

    def render(self, sampler, spp, seed):
        """(image HxWx3 float64, seconds of mi.render)."""
        scene = self.scene(sampler)
        spp = self.spp_for(sampler, spp)
        if (sampler, spp) not in self.warm:  # the JIT compiles per configuration
            np.array(mi.render(scene, spp=spp, seed=10**6 + seed))
            self.warm.add((sampler, spp))
        t = time.perf_counter()
        img = np.array(mi.render(scene, spp=spp, seed=seed))
        return img.astype(np.float64), time.perf_counter() - t, spp


class Vrpt:
    def __init__(self, exe, scene_dir, work):
        self.exe, self.scene_dir, self.work = exe, scene_dir, work

    @staticmethod
    def spp_for(strategy, spp):
        """The spp a user would pick near `spp`: a square for the stratified sampler (its 2D
        strata form a k x k grid; 34 spp would make 2 x 17 slabs), a power of two for Sobol."""
        sampler = "stratified" if "+" not in strategy else strategy.split("+")[0]
        if sampler == "stratified":
            return max(1, int(round(math.sqrt(spp)))) ** 2
        if sampler == "sobol":
            return 1 << max(0, int(round(math.log2(max(spp, 1)))))
        return max(1, spp)

    def render(self, strategy, spp, seed, threads=None):
        """(image HxWx3 float64, render seconds recorded by vrpt, spp)."""
        strategy, *extra = strategy.split()
        spp = self.spp_for(strategy, spp)
        out = os.path.join(self.work, f"vrpt-{strategy.replace('+', '_')}{''.join(extra)}.exr")
        axes = strategy.split("+")
        flags = (["--strategy", strategy] if len(axes) == 1 else
                 ["--sampler", axes[0], "--directions", axes[1], "--lights", axes[2]]) + extra
        cmd = [self.exe, "render", self.scene_dir, *flags, "--spp", str(spp),
               "--seed", str(seed), "-o", out, "--quiet"]
        if threads:
            cmd += ["--threads", str(threads)]
        subprocess.run(cmd, check=True)
        bmp = mi.Bitmap(out)
        meta = bmp.metadata()
        img = np.array(bmp, dtype=np.float64)[:, :, :3]
        return img, float(meta["vrpt.render_seconds"]), spp


# -------------------------------------------------------------------------------- analysis
def region_means(img, grid=4):
    """The image mean and the means of a grid x grid partition, each per channel: (17, 3)."""
    h, w = img.shape[:2]
    out = [img.reshape(-1, 3).mean(axis=0)]
    for j in range(grid):
        for i in range(grid):
            out.append(img[j * h // grid:(j + 1) * h // grid,
                           i * w // grid:(i + 1) * w // grid].reshape(-1, 3).mean(axis=0))
    return np.array(out)


def reference(cache, label, settings, passes, render_pass):
    """Mean of `passes` pass images and the per-pass region means; cached as .npz."""
    path = os.path.join(cache, f"ref-{label}.npz")
    key = json.dumps(settings, sort_keys=True)
    if os.path.exists(path):
        z = np.load(path)
        if str(z["key"]) == key:
            print(f"  {label}: cached reference ({settings['spp']} spp)")
            return z["mean"], z["regions"]
    t = time.perf_counter()
    acc, regions = None, []
    for k in range(passes):
        img = render_pass(k)
        acc = img if acc is None else acc + img
        regions.append(region_means(img))
        print(f"  {label}: pass {k + 1}/{passes} ({time.perf_counter() - t:.0f} s)", flush=True)
    mean = acc / passes
    np.savez(path, key=key, mean=mean, regions=np.array(regions))
    return mean, np.array(regions)


def agreement(mean_a, regions_a, mean_b, regions_b):
    """z of the difference of every region mean (17 x 3) with pass-spread standard errors."""
    ma, mb = region_means(mean_a), region_means(mean_b)
    se_a = regions_a.std(axis=0, ddof=1) / math.sqrt(len(regions_a))
    se_b = regions_b.std(axis=0, ddof=1) / math.sqrt(len(regions_b))
    z = (ma - mb) / np.sqrt(se_a ** 2 + se_b ** 2)
    rel = (ma[0] - mb[0]) / mb[0]
    return z, rel


def mse(img, ref):
    return float(np.mean((img - ref) ** 2))


def summary(values):
    return statistics.median(values), min(values), max(values)


def mean_se(values):
    """The mean of `values` and its standard error (the runs are independent)."""
    n = len(values)
    m = float(np.mean(values))
    return m, (float(np.std(values, ddof=1)) / math.sqrt(n) if n > 1 else float("nan"))


def ratio_se(a, b):
    """a/b of two independent (mean, standard error) pairs and the ratio's standard error
    (first order: relative errors add in quadrature)."""
    r = a[0] / b[0]
    return r, r * math.sqrt((a[1] / a[0]) ** 2 + (b[1] / b[0]) ** 2)


def interleaved(contestants, runs, render):
    """Every contestant's `runs` renders, taken in turn (run 0 of each, then run 1 of each, ...)
    so that a drift of the machine's speed falls on all alike: {label: [render(...)...]}."""
    out = {label: [] for label, _, _ in contestants}
    for r in range(runs):
        for label, who, s in contestants:
            out[label].append(render(label, who, s, r))
    return out


# ------------------------------------------------------------------------------------ main
def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "peers", "mitsuba"))
    ap.add_argument("--vrpt", default=os.path.join(ROOT, "target", "release", "vrpt"))
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64, help="spp of the equal-spp speed runs")
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--runs", type=int, default=None, help="runs per contestant (default 5; 3 with --quick)")
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--ref-passes", type=int, default=16)
    ap.add_argument("--budget", type=float, default=None, help="equal-time budget, seconds")
    ap.add_argument("--quick", action="store_true",
                    help="1024-spp references in 8 passes, 3 runs unless --runs says")
    ap.add_argument("--fresh", action="store_true", help="render the references again")
    ap.add_argument("--export-only", action="store_true")
    a = ap.parse_args()
    if a.quick:
        a.ref_spp, a.ref_passes = 1024, 8
        a.runs = a.runs or 3
    a.runs = a.runs or 5
    if a.ref_spp % a.ref_passes:
        sys.exit("mitsuba_race.py: --ref-spp must be a multiple of --ref-passes")

    os.makedirs(a.out, exist_ok=True)
    scene_dir = os.path.join(a.out, NAME)
    mi.set_variant("scalar_rgb")
    tris = export_scene(scene_dir, a.size, a.size, a.spp, a.max_depth)
    print(f"exported mi.cornell_box() to {scene_dir}: {tris} triangles")
    if a.export_only:
        return
    if not os.path.exists(a.vrpt):
        sys.exit(f"mitsuba_race.py: no vrpt binary at {a.vrpt}: run cargo build --release")
    if a.fresh:
        for f in os.listdir(a.out):
            if f.startswith("ref-"):
                os.remove(os.path.join(a.out, f))

    variant = a.variant
    try:
        mi.set_variant(variant)
        np.array(mi.render(Mitsuba(variant, 4, 4, 2).scene("independent"), spp=1))
    except Exception as e:  # noqa: BLE001 -- any failure means the variant is unusable here
        print(f"warning: Mitsuba variant {variant} unusable ({str(e).splitlines()[0]}); "
              "falling back to scalar_rgb (for llvm_ad_rgb: apt install libllvm19)")
        variant = "scalar_rgb"
        mi.set_variant(variant)
    mi.set_log_level(mi.LogLevel.Error)  # not the sampler's "sample count rounded" notes
    mitsuba = Mitsuba(variant, a.size, a.size, a.max_depth)
    vrpt = Vrpt(a.vrpt, scene_dir, a.out)
    pixels = a.size * a.size
    version = subprocess.run([a.vrpt, "--version"], capture_output=True, text=True).stdout.strip()
    print(f"{version} against Mitsuba {mi.__version__} ({variant}); "
          f"{os.cpu_count()} CPUs, {a.size}x{a.size}, max depth {a.max_depth}")

    # ---- 2. agreement of converged images
    print(f"\n== converged references: {a.ref_spp} spp in {a.ref_passes} passes each")
    per = a.ref_spp // a.ref_passes
    settings = {"spp": a.ref_spp, "passes": a.ref_passes, "size": a.size, "depth": a.max_depth}
    m_ref, m_reg = reference(a.out, f"mitsuba-{variant}", dict(settings, v=mi.__version__),
                             a.ref_passes, lambda k: mitsuba.render("independent", per, 7919 * k + 1)[0])
    v_ref, v_reg = reference(a.out, "vrpt", dict(settings, v=version), a.ref_passes,
                             lambda k: vrpt.render("mis", per, 7919 * k + 1)[0])
    z, rel = agreement(v_ref, v_reg, m_ref, m_reg)
    worst = float(np.abs(z).max())
    agree = worst < 4.0
    print(f"image mean vrpt {v_ref.reshape(-1, 3).mean(axis=0).round(6)} "
          f"Mitsuba {m_ref.reshape(-1, 3).mean(axis=0).round(6)}: "
          f"relative difference {np.round(rel * 100, 3)} %")
    print(f"17 region means x 3 channels: largest |z| = {worst:.2f} "
          f"({'agree' if agree else 'DISAGREE'}: bound 4)")
    ref = 0.5 * (v_ref + m_ref)
    # the reference's own noise: the mean of two independent references of equal spp
    ref_noise = float(np.mean((v_ref - m_ref) ** 2)) / 4.0
    print(f"race reference: the mean of both; its own noise (MSE vs truth) ~ {ref_noise:.3g}")

    # ---- 3. samples/s at equal spp
    print(f"\n== samples/s and MSE at {a.spp} spp, {a.runs} runs each, contestants in turn "
          "(samples/s: median, min..max; MSE: mean +- standard error)")
    contestants = [(f"Mitsuba {variant} {s}", "mitsuba", s) for s in MITSUBA_SAMPLERS]
    contestants += [(label, "vrpt", s) for label, s in VRPT_STRATEGIES]
    base = f"Mitsuba {variant} independent"
    ours = VRPT_STRATEGIES[0][0]

    def render(who, s, spp, seed):
        return (mitsuba if who == "mitsuba" else vrpt).render(s, spp, seed)

    runs = interleaved(contestants, a.runs, lambda _, who, s, r: render(who, s, a.spp, 100 + r))
    speed = {}
    for label, _, _ in contestants:
        rates = [pixels * n / t / 1e6 for _, t, n in runs[label]]
        errs = [mse(img, ref) for img, _, _ in runs[label]]
        speed[label] = {"spp": runs[label][0][2], "msamples_per_s": summary(rates),
                        "mse": mean_se(errs), "rates": rates}
        med, lo, hi = summary(rates)
        m, se = speed[label]["mse"]
        print(f"  {label:42s} {speed[label]['spp']:5d} spp  {med:6.2f} M samples/s  "
              f"({lo:.2f}..{hi:.2f})  MSE {m:.3g} +- {se:.2g}", flush=True)
    # the speed ratio pair by pair (run r of both was taken minutes apart at most)
    pair = [o / b for o, b in zip(speed[ours]["rates"], speed[base]["rates"])]
    speed_ratio = summary(pair)

    # ---- 4. MSE at equal time
    budget = a.budget or pixels * a.spp / (speed[base]["msamples_per_s"][0] * 1e6)
    print(f"\n== MSE at equal time: budget {budget:.3f} s, {a.runs} runs each, in turn "
          "(MSE * t / budget: mean +- standard error)")
    spp_of = {label: max(1, int(round(budget * speed[label]["msamples_per_s"][0] * 1e6 / pixels)))
              for label, _, _ in contestants}
    runs = interleaved(contestants, a.runs,
                       lambda label, who, s, r: render(who, s, spp_of[label], 200 + r))
    race = {}
    for label, _, _ in contestants:
        errs = [mse(img, ref) * t / budget for img, t, _ in runs[label]]
        times = [t for _, t, _ in runs[label]]
        race[label] = {"spp": runs[label][0][2], "seconds": summary(times), "mse": mean_se(errs)}
        m, se = race[label]["mse"]
        print(f"  {label:42s} {race[label]['spp']:5d} spp  {statistics.median(times):6.3f} s  "
              f"MSE {m:.4g} +- {se:.2g}", flush=True)

    # ---- summary
    best_m = min((l for l, w, _ in contestants if w == "mitsuba" and l != base),
                 key=lambda l: race[l]["mse"][0])
    print("\n| renderer | spp | M samples/s at equal spp | MSE at equal spp | "
          "MSE at equal time | vs Mitsuba independent |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, _, _ in contestants:
        r, rse = ratio_se(race[label]["mse"], race[base]["mse"])
        print(f"| {label} | {speed[label]['spp']} | {speed[label]['msamples_per_s'][0]:.2f} | "
              f"{speed[label]['mse'][0]:.3g} +- {speed[label]['mse'][1]:.2g} | "
              f"{race[label]['mse'][0]:.3g} +- {race[label]['mse'][1]:.2g} | "
              f"{r:.2f}x +- {rse:.2f} |")
    eq, eq_se = ratio_se(race[ours]["mse"], race[base]["mse"])
    best, best_se = ratio_se(race[ours]["mse"], race[best_m]["mse"])
    print(f"\nvrpt mis / Mitsuba independent: samples/s {speed_ratio[0]:.2f}x "
          f"(pairwise median, {speed_ratio[1]:.2f}..{speed_ratio[2]:.2f}), "
          f"equal-time MSE {eq:.2f}x +- {eq_se:.2f}; "
          f"against Mitsuba's best sampler ({best_m}): {best:.2f}x +- {best_se:.2f}")
    results = {
        "vrpt": version, "mitsuba": mi.__version__, "variant": variant, "cpus": os.cpu_count(),
        "size": a.size, "max_depth": a.max_depth, "runs": a.runs, "spp": a.spp,
        "ref_spp": a.ref_spp, "ref_passes": a.ref_passes, "budget_seconds": budget,
        "agreement": {"max_abs_z": worst, "agree": agree,
                      "relative_mean_difference": rel.tolist(), "reference_noise": ref_noise},
        "speed": speed, "speed_ratio": speed_ratio, "equal_time": race,
    }
    with open(os.path.join(a.out, "results.json"), "w") as out:
        json.dump(results, out, indent=2)
    print(f"wrote {os.path.join(a.out, 'results.json')}")
    if not agree:
        sys.exit("mitsuba_race.py: the converged images disagree (see the z values above)")


if __name__ == "__main__":
    main()
