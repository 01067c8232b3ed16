#!/usr/bin/env python3
"""Measure every table the README's chapters (docs/*.md) show, in one run on one machine, and print
them as markdown.

    python3 tools/readme_numbers.py                 # every section (a few hours on 2 cores)
    python3 tools/readme_numbers.py --only speed,error
    python3 tools/readme_numbers.py --list

Each section prints a heading, the commands behind it, and its table(s); the chapters' numbers are
pasted from one run of this script, and the first section names the machine. Timings are medians
of interleaved runs (A B A B ...), because the machines here are shared and drift by 30 % within
minutes. The race against Mitsuba needs `pip install -r tools/peers/requirements.txt`; without
it that section says so and is skipped.
"""
import argparse
import json
import os
import pathlib
import platform
import math
import re
import statistics
import subprocess
import sys
import time
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
# VRPT_BIN=PATH measures another binary (a copy, so that a build meanwhile does not change it).
VRPT = os.environ.get("VRPT_BIN") or str(ROOT / "target/release/vrpt")
# References are rendered once per run into WORK; VRPT_NUMBERS_WORK=DIR keeps them across runs.
WORK = pathlib.Path(os.environ.get("VRPT_NUMBERS_WORK") or tempfile.mkdtemp(prefix="vrpt-numbers-"))
WORK.mkdir(parents=True, exist_ok=True)
SECTIONS = {}


def section(name):
    def register(f):
        SECTIONS[name] = f
        return f
    return register


def run(args, **kw):
    r = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, **kw)
    if r.returncode != 0:
        sys.exit(f"failed: {' '.join(map(str, args))}\n{r.stderr}")
    return r


def vrpt(*args):
    return run([VRPT, *map(str, args)])


def cached_render(name, *args):
    """A reference EXR rendered once per run of this script."""
    path = WORK / f"{name}.exr"
    if not path.exists():
        vrpt("render", *args, "-q", "-o", path)
    return path


def compare_json(*args):
    out = WORK / "compare.json"
    vrpt("compare", *args, "-q", "--json", out)
    return json.loads(out.read_text())


def converge_json(*args):
    out = WORK / "converge.json"
    vrpt("converge", *args, "-q", "--json", out)
    return json.loads(out.read_text())


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---:" if i else "---" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def g(x, d=3):
    """A number to `d` significant digits, exponent form below 1e-2."""
    if x is None or (isinstance(x, float) and x != x):
        return "—"
    return f"{x:.{d - 1}e}" if abs(x) < 1e-2 and x != 0 else f"{x:.{d}g}"


PRESET_LIGHTS = {"independent": "bsdf", "stratified": "bsdf", "importance": "bsdf", "combined": "bsdf",
                 "nee": "nee", "mis": "mis"}


def lights_of(strategy):
    """The light strategy of a strategy's name (a preset, or SAMPLER+DIRECTIONS+LIGHTS[+POINTS+CHOICE])."""
    return strategy.split("+")[2] if "+" in strategy else PRESET_LIGHTS[strategy]


def render_speed(scene, strategy, extra=()):
    """(M samples/s, Mrays/s, rays per sample, (camera, bounce, shadow) per sample) of one render,
    from its summary lines."""
    r = vrpt("render", scene, "--strategy" if "+" not in strategy else "--sampler", *strategy_flags(strategy),
             *extra, "-o", WORK / "speed.exr")
    text = r.stderr
    sps = float(re.search(r"([0-9.]+) M samples/s", text).group(1))
    mrays = float(re.search(r"([0-9.]+) Mrays/s", text).group(1))
    m = re.search(r"rays: (\d+) \((\d+) camera, (\d+) bounce, (\d+) shadow[^;]*; ([0-9.]+) per sample[;)]", text)
    total, cam, bounce, shadow = (int(m.group(i)) for i in range(1, 5))
    per = float(m.group(5))
    n = total / per
    return sps, mrays, per, (cam / n, bounce / n, shadow / n)


def strategy_flags(strategy):
    if "+" not in strategy:
        return [strategy]
    s, d, l = strategy.split("+")
    return [s, "--directions", d, "--lights", l]


@section("machine")
def machine():
    cpu = "unknown CPU"
    flags = ""
    try:
        info = pathlib.Path("/proc/cpuinfo").read_text()
        cpu = re.search(r"model name\s*:\s*(.+)", info).group(1).strip()
        flags = re.search(r"flags\s*:\s*(.+)", info).group(1).split()
    except (OSError, AttributeError):
        pass
    simd = next((w for w, f in (("AVX-512", "avx512f"), ("AVX2", "avx2"), ("SSE4.2", "sse4_2")) if f in flags), "SSE2")
    rustc = run(["rustc", "--version"]).stdout.strip()
    print(f"Measured on {cpu}, {os.cpu_count()} cores, widest SIMD {simd}; {rustc}; "
          f"{platform.system()} {platform.release()}.")


@section("speed")
def speed():
    scene = "scenes/cornell-box"
    strategies = ["combined", "nee", "mis"]
    print("Cornell box, 256×256, 64 spp, max depth 8, all cores; median of 3 interleaved runs:\n")
    print(f"`vrpt render {scene} --strategy S -o x.exr`\n")
    runs = {s: [] for s in strategies}
    for _ in range(3):
        for s in strategies:
            runs[s].append(render_speed(scene, s))
    rows = []
    for s in strategies:
        med = sorted(runs[s], key=lambda r: r[0])[1]
        sps, mrays, per, (c, b, sh) = med
        rows.append([s, f"{sps:.2f}", f"{mrays:.2f}", f"{per:.2f} ({c:.0f} + {b:.2f} + {sh:.2f})"])
    print(table(["strategy", "M samples/s", "Mrays/s", "rays per sample (camera + bounce + shadow)"], rows))


@section("error")
def error():
    scene = "scenes/cornell-box"
    ref = cached_render("cb-ref", scene, "--spp", 4096, "--seed", 77)
    strategies = "combined,nee,mis"
    print(f"Against a 4096-spp reference (`vrpt render {scene} --spp 4096 --seed 77`); "
          f"`vrpt compare {scene} --reference cb-ref.exr --strategies {strategies} --spp 64 --runs 4` "
          "and the same with `--spp 16 --equal-time 2`:\n")
    a = compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", 64, "--runs", 4)
    b = compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", 16, "--runs", 4,
                     "--equal-time", 2)
    rows = []
    for ra, rb in zip(a["rows"], b["rows"]):
        rows.append([ra["strategy"], g(ra["mse"]), f"{ra['mse_reduction']:.1f}×", f"{g(rb['mse'])} ({rb['spp']:.0f} spp)",
                     f"{rb['mse_reduction']:.1f}×"])
    print(table(["strategy", "MSE at 64 spp", "MSE reduction", "MSE at equal time (2 s)", "reduction at equal time"], rows))


@section("veach")
def veach():
    scene = "scenes/glossy-plates"
    ref = cached_render("gp-ref", scene, "--spp", 1024)
    strategies = "stratified+phong+bsdf,stratified+phong+nee,stratified+phong+mis"
    print(f"`vrpt compare {scene} --reference gp-ref.exr --spp 16 --runs 8 --strategies {strategies} "
          f"--regions {scene}/regions.txt` (reference: 1024 spp, MIS):\n")
    c = compare_json(scene, "--reference", ref, "--spp", 16, "--runs", 8, "--strategies", strategies,
                     "--regions", f"{scene}/regions.txt")
    regions = {}
    for r in c["regions"]:
        regions.setdefault(r["region"], {})[lights_of(r["strategy"])] = r["mse"]
    rows = []
    for n in ("10", "100", "1000", "10000"):
        row = [f"n = {n}"]
        for l in range(4):
            m = regions[f"p{n}-l{l}"]
            best = min(m.values())
            row.append(" / ".join(f"**{g(m[k])}**" if m[k] == best else g(m[k]) for k in ("bsdf", "nee", "mis")))
        rows.append(row)
    print(table(["plate \\ light", "l0 (smallest) bsdf / nee / mis", "l1", "l2", "l3 (largest)"], rows))
    whole = {lights_of(r["strategy"]): r["mse"] for r in c["rows"]}
    print(f"\nWhole image: bsdf {g(whole['bsdf'])}, nee {g(whole['nee'])}, mis {g(whole['mis'])} "
          f"({whole['bsdf'] / whole['mis']:.1f}× lower than bsdf).")


@section("lit-checker")
def lit_checker():
    scene = "scenes/lit-checker"
    ref = cached_render("lc-ref", scene, "--spp", 16384, "--sampler", "sobol", "--lights", "nee", "--seed", 1000)
    strategies = ",".join(f"{s}+cosine+nee+area+power" for s in ("independent", "stratified", "sobol"))
    print(f"`vrpt converge {scene} --reference lc-ref.exr --runs 4 --strategies {strategies} "
          "--spp 4,16,64,256,1024` (reference: 16384 spp, Sobol, NEE):\n")
    c = converge_json(scene, "--reference", ref, "--runs", 4, "--strategies", strategies, "--spp", "4,16,64,256,1024")
    rows = []
    for s in c["slopes"]:
        at = {p["spp"]: p["mse"] for p in c["points"] if p["strategy"] == s["strategy"]}
        rows.append([s["strategy"].split("+")[0], f"{s['mse_slope']:+.2f}", g(at[4]), g(at[64]), g(at[1024])])
    print(table(["sampler", "MSE slope", "MSE at 4 spp", "at 64", "at 1024"], rows))


@section("lights")
def lights():
    """Points on a light (area, solid angle, projected solid angle) on the Cornell box and
    lit-checker, and the choice of light (uniform, power, tree) on the night hall and the glossy
    plates, at equal spp and equal time; and what a light sample costs (the `lights` bench)."""
    points = ("area", "solid-angle", "projected", "auto")
    cases = [("scenes/cornell-box", cached_render("cb-ref", "scenes/cornell-box", "--spp", 4096, "--seed", 77),
              "stratified+phong+mis", "cb-ref.exr"),
             ("scenes/lit-checker",
              cached_render("lc-ref", "scenes/lit-checker", "--spp", 16384, "--sampler", "sobol", "--lights", "nee",
                            "--seed", 1000),
              "sobol+cosine+nee", "lc-ref.exr")]
    for scene, ref, base, refname in cases:
        strategies = ",".join(f"{base}+{p}+tree" for p in points)
        print(f"`vrpt compare {scene} --reference {refname} --strategies {strategies} --spp N --runs 4` "
              "for N = 16 and 256, and `--spp 16 --equal-time 2`:\n")
        at = {n: compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", n, "--runs", 4)
              for n in (16, 256)}
        et = compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", 16, "--runs", 4,
                          "--equal-time", 2)
        rows = []
        for k, p in enumerate(points):
            a, b, t = at[16]["rows"][k], at[256]["rows"][k], et["rows"][k]
            rows.append([p, g(a["mse"]), g(b["mse"]), f"{g(t['mse'])} ({t['spp']:.0f} spp)"])
        # (no time column: the runs of one strategy follow each other, so a drift of the
        # machine would show as a cost; the equal-time runs show the cost in spp reached)
        print(table(["points", "MSE at 16 spp", "at 256 spp", "MSE at equal time (2 s)"], rows) + "\n")
    choices = ("uniform", "power", "tree")
    hall_ref = cached_render("nh-ref", "scenes/night-hall", "--spp", 4096, "--seed", 999)
    gp_ref = cached_render("gp-ref", "scenes/glossy-plates", "--spp", 1024)
    for scene, ref, refname in (("scenes/night-hall", hall_ref, "nh-ref.exr"),
                                ("scenes/glossy-plates", gp_ref, "gp-ref.exr")):
        for lights in ("nee", "mis"):
            strategies = ",".join(f"stratified+phong+{lights}+projected+{c}" for c in choices)
            print(f"`vrpt compare {scene} --reference {refname} --strategies {strategies} --spp 16 --runs 4`, "
                  "and with `--equal-time 2`:\n")
            a = compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", 16, "--runs", 4)
            b = compare_json(scene, "--reference", ref, "--strategies", strategies, "--spp", 16, "--runs", 4,
                             "--equal-time", 2)
            power = next(x for x in a["rows"] if x["strategy"].endswith("+power"))["mse"]
            power_t = next(x for x in b["rows"] if x["strategy"].endswith("+power"))["mse"]
            rows = []
            for c, ra, rb in zip(choices, a["rows"], b["rows"]):
                rows.append([c, g(ra["mse"]), f"{power / ra['mse']:.1f}×", f"{ra['seconds']:.2f}",
                             f"{g(rb['mse'])} ({rb['spp']:.0f} spp)", f"{power_t / rb['mse']:.1f}×"])
            print(table([f"choice ({lights})", "MSE at 16 spp", "vs power", "time (s)", "MSE at equal time (2 s)",
                         "vs power"], rows) + "\n")
    print("`cargo bench --bench sampling -- lights` (one light sample per receiver, 160 emitters):\n")
    r = run(["cargo", "bench", "-q", "--bench", "sampling", "--", "lights"])
    rows = []
    for name, lo in re.findall(r"lights/(\S+)\s+time:\s+\[[0-9.]+ \S+ ([0-9.]+ \S+)", r.stdout):
        value, unit = lo.split()
        ns = float(value) * {"ns": 1, "µs": 1e3, "us": 1e3, "ms": 1e6}[unit] / 4096
        rows.append([name, f"{ns:.0f}"])
    print(table(["operation", "ns per receiver"], rows))


# The shipped scenes at a size where every reference takes seconds: (scene, width, height).
EFFICIENCY_SCENES = [("cornell-box", 128, 128), ("glossy-plates", 128, 96), ("lit-checker", 128, 96),
                     ("checker-plane", 128, 96), ("night-hall", 128, 72), ("door", 128, 96),
                     ("sun-sky", 128, 96), ("textured", 128, 96)]
# The default, then one axis changed at a time: (label, extra flags of `vrpt render`).
EFFICIENCY_CONFIGS = [("default", []), ("--replicates 4", ["--replicates", 4]),
                      ("--sampler sobol", ["--sampler", "sobol"]),
                      ("--sampler independent", ["--sampler", "independent"]),
                      ("--lights nee", ["--lights", "nee"]),
                      ("--light-points area", ["--light-points", "area"]),
                      ("--light-points projected", ["--light-points", "projected"]),
                      ("--light-choice power", ["--light-choice", "power"]),
                      ("--edge-rays 0", ["--edge-rays", 0]), ("--edge-rays 16", ["--edge-rays", 16])]


def efficiency_ref(scene, w, h, spp=4096):
    """An independent-points reference: its per-sample variance of the mean is unbiased, so it
    is the floor that `vrpt diff` prints ("reference variance") and the measured MSE sheds. With
    64 edge rays: without them the reference's own noise at a light's edge (one camera ray a
    sample sees the light or not) exceeds the error of a render with them (on checker-plane its
    MSE less the floor came out negative); with them the edge term's per-sample variance is
    1/64 or less of that, so the floor it overstates (its points are stratified) is negligible.
    Solid-angle points (not area): an environment map is then sampled by its luminance."""
    return cached_render(f"eff-{scene}-{w}x{h}", f"scenes/{scene}", "--width", w, "--height", h, "--spp", spp,
                         "--sampler", "independent", "--light-points", "solid-angle", "--light-choice", "power",
                         "--edge-rays", 64, "--seed", 4242)


def measure_efficiency(configs, scenes=EFFICIENCY_SCENES, spp=64, seeds=(1, 2, 3, 4, 5), env=None):
    """{(scene, label): (MSE, seconds)}: each config's MSE against the scene's reference (mean over
    seeds, the reference's own variance subtracted) and its render time (median), the configs
    interleaved seed by seed (A B C ... A B C ...) so a drifting machine costs every config alike.
    `env`: optional {label: environment overrides}."""
    out = {}
    for scene, w, h in scenes:
        ref = efficiency_ref(scene, w, h)
        got = {label: ([], []) for label, _ in configs}
        for seed in seeds:
            for label, flags in configs:
                img = WORK / "eff.exr"
                e = dict(os.environ, **(env or {}).get(label, {}))
                r = run([VRPT, "render", f"scenes/{scene}", "--width", str(w), "--height", str(h), "--spp", str(spp),
                         "--seed", str(seed), *map(str, flags), "-o", str(img)], env=e)
                secs = float(re.search(r" in ([0-9.]+) s", r.stderr).group(1))
                d = vrpt("diff", img, ref).stdout
                mse = float(re.search(r"^MSE\s+(\S+)", d, re.M).group(1))
                floor = float(re.search(r"^reference variance\s+(\S+)", d, re.M).group(1))
                got[label][0].append(mse - floor)
                got[label][1].append(secs)
        for label, (m, t) in got.items():
            out[(scene, label)] = (statistics.mean(m), statistics.median(t))
    return out


@section("efficiency")
def efficiency():
    """The defaults' choice: every shipped scene at 64 spp, the default strategy against one axis
    changed at a time, by efficiency 1/(MSE × time) relative to the default."""
    print("Every shipped scene (128 wide), 64 spp, seeds 1–5 interleaved, MSE against a 4096-spp "
          "independent reference with its own variance subtracted; `vrpt render SCENE --width W --height H "
          "--spp 64 --seed S [FLAGS]` then `vrpt diff`. Efficiency `1/(MSE × time)` relative to the defaults "
          "(stratified+phong+mis, `--light-points auto`, `--light-choice tree`, one set of points); above 1 "
          "would beat them:\n")
    res = measure_efficiency(EFFICIENCY_CONFIGS)
    labels = [l for l, _ in EFFICIENCY_CONFIGS]
    rows, logs = [], {l: [] for l in labels}
    for scene, _, _ in EFFICIENCY_SCENES:
        m0, t0 = res[(scene, "default")]
        row = [scene, f"{g(m0)}, {t0:.2f} s"]
        for l in labels[1:]:
            m, t = res[(scene, l)]
            e = (m0 * t0) / (m * t)
            logs[l].append(e)
            row.append(f"{e:.2f}")
        rows.append(row)
    geo = lambda xs: statistics.geometric_mean(xs)
    rows.append(["**geometric mean**", ""] + [f"**{geo(logs[l]):.2f}**" for l in labels[1:]])
    print(table(["scene", "default: MSE, time"] + labels[1:], rows))


def long_ref(scene, w, h, spp):
    """A long independent-points phong+MIS reference whose own variance `vrpt diff` subtracts."""
    return cached_render(f"ref-{scene}-{w}x{h}-{spp}", f"scenes/{scene}", "--width", w, "--height", h,
                         "--spp", spp, "--sampler", "independent", "--edge-rays", 0, "--seed", 4242)


def equal_time(scene, w, h, seconds, ref, configs, seeds=(1, 2, 3), metric="MSE"):
    """{label: (error, final spp, last stderr)}: each config rendered with `--time-limit`
    (training included), seeds interleaved (A B A B ...), the error against `ref`, mean over the
    seeds: MSE with the reference's own variance subtracted, or relMSE (eps 0.01) with the
    reference's relative variance subtracted (`vrpt diff` states both floors)."""
    got = {label: ([], [], "") for label, _ in configs}
    for seed in seeds:
        for label, flags in configs:
            img = WORK / "eq.exr"
            r = vrpt("render", f"scenes/{scene}", "--width", w, "--height", h, "--spp", 1 << 20, "--time-limit",
                     seconds, "--seed", seed, "--stats", *flags, "-o", img)
            spp = int(re.search(r"at (\d+) spp", r.stderr).group(1))
            d = vrpt("diff", img, ref).stdout
            mse = float(re.search(r"^MSE\s+(\S+)", d, re.M).group(1))
            floor = float(re.search(r"^reference variance\s+(\S+)", d, re.M).group(1))
            if metric == "relMSE":
                mse = float(re.search(r"^relMSE \(eps 0.01\)\s+(\S+)", d, re.M).group(1))
                floor = float(re.search(r"^reference relative variance\s+(\S+)", d, re.M).group(1))
            m, n, _ = got[label]
            got[label] = (m + [mse - floor], n + [spp], r.stderr)
    return {l: (statistics.mean(m), statistics.median(n), e) for l, (m, n, e) in got.items()}


def pair_denominator(scene, w, h, seconds):
    """The image whose pixels are the relMSE's `r` for every config's seed pairs of `scene`
    (`vrpt diff --pair-denominator`): a render of the default strategy for twice the configs'
    time with a seed none of them uses, so it is independent of all of them and the same for
    all."""
    size = ["--width", w, "--height", h] if w else []
    return cached_render(f"denominator-{scene}-{w}x{h}-{seconds}", f"scenes/{scene}", *size, "--spp", 1 << 20,
                         "--time-limit", 2 * seconds, "--seed", 7777)


def pair_rel_mse(a, b, denominator):
    """The relMSE of one render estimated from two independent renders `a`, `b` of it against the
    shared `denominator` image (`vrpt diff --pair-denominator`)."""
    d = vrpt("diff", a, b, "--pair-denominator", denominator).stdout
    return float(re.search(r"^relMSE of one \(pair\)\s+(\S+)", d, re.M).group(1))


def auto_pick(stderr):
    """The candidate `--strategy auto --stats` chose, as its table names it ("(its guided twin)"
    after it where the twin rendered), or None."""
    m = re.search(r"^  (\S+)\s.*<- chosen(, with guided directions)?", stderr, re.M)
    if m:
        return m.group(1) + (" (its guided twin)" if m.group(2) else "")
    # no pilot: the first candidate, or its guided twin where the probe found caustics
    m = re.search(r"^auto: (\S+) chosen without a pilot", stderr, re.M)
    return m and m.group(1)


def equal_time_pairs(scene, w, h, seconds, configs, pairs=((1, 2), (3, 4)), log=None):
    """{label: (relMSE, final spp, last stderr)} measured without a converged reference: each
    config rendered with `--time-limit` for two seeds of each pair (configs interleaved), and the
    relMSE of one render estimated from the pair, `mean((a − b)²/(2(c² + 0.01)))`
    (`E[(a − b)²] = 2 Var` for two independent unbiased renders), `c` from
    [pair_denominator]: one image for every config, so all weigh the pixels alike. A reference's
    own noise would be a floor under the error that hides the gain once the renders near its spp
    (adaptive renders of the glossy plates at 60 s, or of lit-checker, whose 30 s renders exceed
    an 8192-spp reference); the pair has none. Before 2026-11-27 the denominator was one render
    of the pair, `b² + 0.01`, which divides by whichever render was low: on textured two
    light-edge pixels carried 82–99% of the relMSE that way."""
    got = {label: ([], [], "") for label, _ in configs}
    denominator = pair_denominator(scene, w, h, seconds)
    for pair in pairs:
        for label, flags in configs:
            imgs, spps, err = [], [], ""
            for seed in pair:
                img = WORK / f"pair-{seed}.exr"
                size = ["--width", w, "--height", h] if w else []  # no size: the scene's own
                r = vrpt("render", f"scenes/{scene}", *size, "--spp", 1 << 20, "--time-limit",
                         seconds, "--seed", seed, "--stats", *flags, "-o", img)
                spps.append(int(re.search(r"at (\d+) spp", r.stderr).group(1)))
                imgs.append(img)
                err = r.stderr
                if log is not None:
                    log.append((label, r.stderr))
            rel = pair_rel_mse(imgs[0], imgs[1], denominator)
            m, n, _ = got[label]
            got[label] = (m + [rel], n + spps, err)
    return {l: (statistics.mean(m), statistics.median(n), e) for l, (m, n, e) in got.items()}


# (scene, width, height, seconds, reference spp, target): the issue's equal-time targets
GUIDING_TARGETS = [("gap", 96, 64, 60, 65536, 5.0), ("door", 96, 64, 60, 65536, 3.0),
                   ("door-dark", 96, 64, 30, 65536, 2.0), ("cornell-box", 64, 64, 20, 16384, 1.0),
                   ("glossy-plates", 96, 72, 20, 32768, 0.9)]


@section("guiding")
def guiding():
    """Path guiding against Phong directions, both with MIS and stratified points, at equal time
    as a user renders (`--time-limit`, training included), against long references whose own
    noise is subtracted; the targets of issue 36 beside the measured ratios, and the cost."""
    print("`vrpt render SCENE --width W --height H --time-limit T --seed S --directions phong|guided`, seeds 1–3 "
          "interleaved, then `vrpt diff` against a long `--sampler independent` phong+MIS reference (its own "
          "variance subtracted); ratio = phong MSE / guided MSE, above 1 means guiding wins:\n")
    rows, last = [], ""
    for scene, w, h, secs, ref_spp, target in GUIDING_TARGETS:
        ref = long_ref(scene, w, h, ref_spp)
        r = equal_time(scene, w, h, secs, ref, [("phong", ["--directions", "phong"]),
                                                ("guided", ["--directions", "guided"])])
        (mp, sp, _), (mg, sg, err) = r["phong"], r["guided"]
        ratio = mp / mg
        rows.append([f"{scene} {w}×{h}", f"{secs} s", f"{g(mp)} ({sp} spp)", f"{g(mg)} ({sg} spp)",
                     f"**{ratio:.2f}×**", f"≥ {target}×", "met" if ratio >= target else "not met"])
        m = re.search(r"guiding: .*", err)
        if scene == "gap" and m:
            last = m.group(0)
    print(table(["scene", "time", "phong+mis MSE", "guided+mis MSE", "phong / guided", "target", ""], rows))
    if last:
        print(f"\nThe gap's guided render at 60 s (`--stats`): {last}")


# (scene, width, height, seconds, target ratio): issue 38's equal-time targets; a size of None
# is the scene's own (scene.toml), as a user renders it; every shipped scene at 10 s
SHIPPED = ["cornell-box", "glossy-plates", "lit-checker", "checker-plane", "night-hall", "door", "door-dark",
           "gap", "sun-sky", "textured"]
ADAPTIVE_TARGETS = ([("glossy-plates", None, None, 3, 1.2), ("glossy-plates", None, None, 60, 2.0),
                     ("lit-checker", None, None, 30, 2.0)]
                    + [(s, None, None, 10, 2.0 if s == "glossy-plates" else 0.95) for s in SHIPPED])


AUTO_SCENES = ["cornell-box", "glossy-plates", "lit-checker", "checker-plane", "night-hall", "door", "door-dark",
               "gap", "sun-sky", "textured", "glass", "lamp"]


@section("reuse")
def reuse():
    """docs/reuse.md's table: path reuse (`--reuse K`, K = 2, 3, 4) against the default at equal
    time, 10 s, every scene of the efficiency table at its size there, relMSE from seed pairs."""
    print("`vrpt render scenes/SCENE --width W --height H --spp 1048576 --time-limit 10 --seed S` "
          "with and without `--reuse K`, seed pairs (1, 2) and (3, 4), configs interleaved, relMSE of one "
          "render from its pair with one denominator render shared by every config (`vrpt diff --pair-denominator`); gain = "
          "relMSE(default) / relMSE(--reuse K):\n")
    ks = (2, 3, 4)
    configs = [("default", [])] + [(f"reuse {k}", ["--reuse", k]) for k in ks]
    rows, gains = [], {k: [] for k in ks}
    for scene, w, h in EFFICIENCY_SCENES:
        r = equal_time_pairs(scene, w, h, 10, configs)
        base = r["default"][0]
        for k in ks:
            gains[k].append(base / r[f"reuse {k}"][0])
        rows.append([scene, g(base)] + [f"{base / r[f'reuse {k}'][0]:.2f}" for k in ks])
        print(f"  {scene}: {rows[-1]}", file=sys.stderr, flush=True)
    print(table(["scene", "default relMSE"] + [f"`--reuse {k}`" for k in ks], rows))
    geo = {k: math.exp(statistics.mean(math.log(x) for x in v)) for k, v in gains.items()}
    print("\nGeometric mean of the gain: " + ", ".join(f"K = {k} {geo[k]:.2f}×" for k in ks) + ".")


@section("reuse-door")
def reuse_door():
    """docs/reuse.md's 60-s door: the default, guided directions, `--reuse 4` and both at the
    door's own size, relMSE from seed pairs against one shared denominator."""
    print("`vrpt render scenes/door --spp 1048576 --time-limit 60 --seed S [--directions guided] "
          "[--reuse 4]`, the door at its own size, seed pairs (1, 2) and (3, 4), configs interleaved, "
          "relMSE of one render from its pair with one denominator render shared by every config "
          "(`vrpt diff --pair-denominator`); gain = relMSE(default) / relMSE(config):\n")
    configs = [("default", []), ("guided", ["--directions", "guided"]), ("reuse 4", ["--reuse", 4]),
               ("guided + reuse 4", ["--directions", "guided", "--reuse", 4])]
    r = equal_time_pairs("door", None, None, 60, configs)
    base = r["default"][0]
    rows = [[label, g(m), f"{n:.0f}", f"**{base / m:.2f}×**"] for label, (m, n, _) in r.items()]
    print(table(["config", "relMSE of one render", "spp (median)", "gain"], rows))


ROULETTE_SCENES = ["cornell-box", "night-hall", "gap", "door", "glossy-plates", "sun-sky"]


@section("roulette")
def roulette():
    """docs/roulette.md's table: `--roulette ears` against classic roulette at equal time, 10 s,
    each shipped scene at its own size, relMSE from seed pairs, EARS's continuations at the
    first vertex from `--stats`."""
    print("`vrpt render scenes/SCENE --spp 1048576 --time-limit 10 --seed S [--roulette ears]`, seed "
          "pairs (1, 2) and (3, 4), configs interleaved, relMSE of one render from its pair with one "
          "denominator render shared by both (`vrpt diff --pair-denominator`); ratio = relMSE(classic) / relMSE(ears):\n")
    configs = [("classic", []), ("ears", ["--roulette", "ears"])]
    rows, ratios = [], []
    for scene in ROULETTE_SCENES:
        log = []
        r = equal_time_pairs(scene, None, None, 10, configs, log=log)
        c, e = r["classic"][0], r["ears"][0]
        splits = [float(m.group(1)) for label, err in log if label == "ears"
                  for m in [re.search(r"([0-9.]+) continuations at the first vertex", err)] if m]
        ratios.append(c / e)
        rows.append([scene, g(c), g(e), f"{c / e:.2f}×", f"{statistics.mean(splits):.2f}"])
        print(f"  {scene}: {rows[-1]}", file=sys.stderr, flush=True)
    print(table(["scene", "classic", "ears", "ratio", "continuations at the first vertex"], rows))
    geo = math.exp(statistics.mean(math.log(x) for x in ratios))
    print(f"\nGeometric mean of the ratio: {geo:.2f}×.")


@section("auto")
def auto():
    """`--strategy auto` against its candidates and guided directions at equal time as a user
    renders (`--time-limit 10`, pilots included), each shipped scene at its own size, relMSE from
    seed pairs."""
    print("`vrpt render scenes/SCENE --spp 1048576 --time-limit 10 --seed S` with `--strategy mis`, "
          "`--strategy mis --reuse 4`, `--directions guided`, `--directions guided --reuse 4` or "
          "`--strategy auto` (its default candidates mis, mis+reuse4 and their guided twins, the twin "
          "of the pilots' choice rendered with its gate where reuse wins or light is caustic), seed pairs (1, 2), (3, 4) and (5, 6), configs "
          "interleaved; relMSE of one render from its pair, `mean((a − b)²/(2(c² + 0.01)))`, c one "
          "more render shared by every config (`vrpt diff --pair-denominator`); ratio above 1 means "
          "auto wins:\n")
    configs = [("mis", ["--strategy", "mis"]), ("reuse", ["--strategy", "mis", "--reuse", 4]),
               ("guided", ["--directions", "guided"]),
               ("guided+reuse", ["--directions", "guided", "--reuse", 4]),
               ("auto", ["--strategy", "auto"])]
    rows, vs_mis, vs_best = [], [], []
    for scene in AUTO_SCENES:
        log = []
        r = equal_time_pairs(scene, None, None, 10, configs, pairs=((1, 2), (3, 4), (5, 6)), log=log)
        chosen = [auto_pick(e) for l, e in log if l == "auto"]
        mm, mr, mg, mgr = (r[k][0] for k in ("mis", "reuse", "guided", "guided+reuse"))
        ma, sa, _ = r["auto"]
        best = min(mm, mr, mg, mgr)
        vs_mis.append(mm / ma)
        vs_best.append(best / ma)
        picks = ", ".join(f"{chosen.count(c)}× {c}" for c in sorted(set(chosen)))
        rows.append([scene, g(mm), g(mr), g(mg), g(mgr), f"{g(ma)} ({sa} spp)", picks, f"{mm / ma:.2f}×",
                     f"{best / ma:.2f}×"])
        print(f"  {scene}: {rows[-1]}", file=sys.stderr, flush=True)
    print(table(["scene", "mis relMSE", "mis+reuse4 relMSE", "guided relMSE", "guided+reuse4 relMSE",
                 "auto relMSE", "auto chose", "mis / auto", "best / auto"], rows))
    geo = math.exp(statistics.mean(math.log(x) for x in vs_mis))
    print(f"\nGeometric mean of mis / auto: {geo:.2f}×; worst best / auto: {min(vs_best):.2f}× "
          f"({AUTO_SCENES[vs_best.index(min(vs_best))]}).")


@section("auto-default")
def auto_default():
    """`--strategy auto` against the default (`mis`) at each scene's own render (its
    `scene.toml`'s size and spp, no time limit): efficiency 1/(relMSE × wall time), relMSE from
    seed pairs, time the whole process's (pilots, loading and writing included)."""
    print("`vrpt render scenes/SCENE --seed S [--strategy auto]` (each scene's own size and spp), seed "
          "pairs (1, 2), (3, 4) and (5, 6), the two interleaved; relMSE of one render from its pair "
          "(`vrpt diff --pair-denominator`, the denominator `equal_time_pairs`' one), time the process's "
          "wall clock; ratio = (relMSE × time) of mis over auto's, above 1 means auto wins:\n")
    rows, ratios = [], []
    for scene in AUTO_SCENES:
        denominator = pair_denominator(scene, None, None, 10)
        got = {}
        for pair in ((1, 2), (3, 4), (5, 6)):
            for label, flags in (("mis", []), ("auto", ["--strategy", "auto"])):
                imgs, rels, times, picks = [], *got.get(label, ([], [], []))
                for seed in pair:
                    img = WORK / f"default-{seed}.{label}.exr"
                    t0 = time.monotonic()
                    r = vrpt("render", f"scenes/{scene}", "--seed", seed, "--stats", *flags, "-o", img)
                    times.append(time.monotonic() - t0)
                    imgs.append(img)
                    if label == "auto":
                        picks.append(auto_pick(r.stderr))
                rels.append(pair_rel_mse(imgs[0], imgs[1], denominator))
                got[label] = (rels, times, picks)
        (rm, tm, _), (ra, ta, picks) = ((statistics.mean(a), statistics.mean(b), c)
                                        for a, b, c in (got["mis"], got["auto"]))
        ratios.append(rm * tm / (ra * ta))
        chosen = ", ".join(f"{picks.count(c)}× {c}" for c in sorted(set(picks)))
        rows.append([scene, f"{g(rm)}, {tm:.2f} s", f"{g(ra)}, {ta:.2f} s", chosen, f"{ratios[-1]:.2f}×"])
        print(f"  {scene}: {rows[-1]}", file=sys.stderr, flush=True)
    print(table(["scene", "mis relMSE, time", "auto relMSE, time", "auto chose", "auto / mis efficiency"], rows))
    geo = math.exp(statistics.mean(math.log(x) for x in ratios))
    print(f"\nGeometric mean: {geo:.2f}×; worst: {min(ratios):.2f}× ({AUTO_SCENES[ratios.index(min(ratios))]}).")


@section("adaptive")
def adaptive():
    """Adaptive sampling against uniform at equal time as a user renders (`--time-limit`), relMSE
    from pairs of independent renders, and `--target-error` with and without `--adaptive`."""
    print("`vrpt render SCENE --time-limit T --seed S [--adaptive]` (each scene at its own size) for seeds 1–4, uniform and "
          "adaptive interleaved; a render's relMSE (eps 0.01) is estimated from seed 1 against seed 2 "
          "(and 3 against 4): two independent unbiased renders differ by twice the variance of one, so no "
          "reference's noise sits under the error (`vrpt diff --pair-denominator`, the r² from one more render "
          "shared by both configs); ratio = uniform relMSE / adaptive relMSE; the gains at "
          "equal spp are what the adaptive render prints (the ideal `mean(e²)/mean(e)²`, its schedule's bound, "
          "and the cross-validated gain of a round allocated from estimates as noisy as its own), or the "
          "cross-validated gain after the first round that made it finish uniformly:\n")
    rows = []
    for scene, w, h, secs, target in ADAPTIVE_TARGETS:
        r = equal_time_pairs(scene, w, h, secs, [("uniform", []), ("adaptive", ["--adaptive"])])
        (mu, su, _), (ma, sa, err) = r["uniform"], r["adaptive"]
        ratio = mu / ma
        b = re.search(r"ideal \(n ∝ e\) ([0-9.]+), this schedule .*?\) ([0-9.]+); .*cross-validated ([0-9.]+)", err)
        f = re.search(r"cross-validated gain of allocating was ([0-9.]+)", err)
        bound = (f"{b.group(1)} / {b.group(2)} / {b.group(3)}" if b
                 else f"uniform after round 1 ({f.group(1)})" if f else "?")
        size = f"{w}×{h}" if w else "(own size)"
        rows.append([f"{scene} {size}", f"{secs} s", f"{g(mu)} ({su} spp)", f"{g(ma)} ({sa} spp)",
                     f"**{ratio:.2f}×**", bound, f"≥ {target}×", "met" if ratio >= target else "not met"])
    print(table(["scene", "time", "uniform relMSE", "adaptive relMSE", "uniform / adaptive",
                 "ideal / schedule / cross-validated", "target", ""], rows))
    print("\n`vrpt render scenes/glossy-plates --target-error 2e-4 --seed S [--adaptive]`, seeds 1–2 interleaved, "
          "seconds to stop (median):\n")
    t = {"uniform": [], "adaptive": []}
    for seed in (1, 2):
        for label, flags in (("uniform", []), ("adaptive", ["--adaptive"])):
            out = vrpt("render", "scenes/glossy-plates", "--target-error", "2e-4", "--seed", seed, *flags,
                       "-o", WORK / "te.exr").stderr
            t[label].append(float(re.search(r" in ([0-9.]+) s", out).group(1)))
    tu, ta = statistics.median(t["uniform"]), statistics.median(t["adaptive"])
    print(table(["uniform s", "adaptive s", "uniform / adaptive", "target"],
                [[f"{tu:.1f}", f"{ta:.1f}", f"**{tu / ta:.2f}×**", "≥ 1.5×"]]))


@section("sampler")
def sampler():
    print("`cargo run --release --example custom_sampler`:\n")
    r = run(["cargo", "run", "--release", "-q", "--example", "custom_sampler"])
    print(r.stdout.strip())


@section("scaling")
def scaling():
    print("`cargo run --release --example scaling`:\n")
    r = run(["cargo", "run", "--release", "-q", "--example", "scaling"])
    print(r.stdout.strip())


@section("race")
def race():
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        print("skipped: `pip install -r tools/peers/requirements.txt` for the race against Mitsuba 3")
        return
    print("`python3 tools/peers/mitsuba_race.py`:\n")
    r = run([sys.executable, "tools/peers/mitsuba_race.py"])
    print(r.stdout.strip())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", help="comma-separated sections")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args()
    if a.list:
        print("\n".join(SECTIONS))
        return
    names = a.only.split(",") if a.only else list(SECTIONS)
    unknown = [n for n in names if n not in SECTIONS]
    if unknown:
        sys.exit(f"unknown sections {unknown}; --list shows them")
    run(["cargo", "build", "--release", "-q"])
    if "machine" not in names:
        names.insert(0, "machine")
    for n in names:
        print(f"\n### {n}\n", flush=True)
        SECTIONS[n]()
        sys.stdout.flush()


if __name__ == "__main__":
    main()
