#!/usr/bin/env python3
"""Time vrpt against Mitsuba 3 on Mitsuba's Cornell box with a large mesh in it (issue 49).

Mitsuba's ``mi.cornell_box()`` is exported for vrpt as ``mitsuba_race.py`` exports it, and a
bumpy sphere of many triangles is added in front of the boxes: an icosphere subdivided
``--level`` times (20·4^level triangles: 6 → 81,920, 7 → 327,680, 8 → 1,310,720), each vertex
pushed out along its normal by a sum of three sines (the lumps of a scanned statue, not a
smooth ball), with per-vertex normals of the displaced surface. The same file is both
renderers' mesh: vrpt reads the box and the mesh from one OBJ, Mitsuba reads the mesh's own OBJ
(an ``obj`` shape with the box's white BSDF), so they trace the same triangles.

Both render at equal spp with their independent-or-default samplers (vrpt's default strategy;
Mitsuba's ``independent``, box filter), ``--runs`` times in turn (vrpt, Mitsuba, vrpt, ...).
Times exclude loading and the BVH builds on both sides: vrpt's own render time (recorded in its
EXR), and the wall time of ``mi.render`` with the scene loaded and its kernel compiled by a
warm-up render. Printed: each renderer's median time, and vrpt/Mitsuba as the median of the
pairwise ratios. As a check that both saw the mesh, the image means are printed too (they agree
to the noise of two renders at that spp, not better).

    python3 tools/peers/mitsuba_mesh.py --level 7            # 327,680 triangles, 64 spp

Needs what ``mitsuba_race.py`` needs (``pip install -r tools/peers/requirements.txt``).
"""

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [HERE, os.path.dirname(HERE)]
import mitsuba_race as race  # noqa: E402  (sets Dr.Jit's LLVM path, imports mitsuba)
from make_big_scene import icosphere  # noqa: E402  (the large-scene tool's subdivided sphere)

mi = race.mi

CENTRE = np.array([0.05, -0.25, 0.35])
RADIUS = 0.32


def bumpy_mesh(level):
    """World-space vertices, unit vertex normals and faces of the displaced sphere."""
    verts, faces = icosphere(level)
    u, f = np.array(verts, dtype=np.float64), np.array(faces, dtype=np.int64)
    bump = 1.0 + 0.08 * (np.sin(9 * u[:, 0]) * np.sin(7 * u[:, 1]) * np.sin(8 * u[:, 2])) \
        + 0.03 * np.sin(23 * u[:, 0] + 17 * u[:, 1])
    p = CENTRE + RADIUS * u * bump[:, None]
    n = np.zeros_like(p)
    face_n = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], face_n)
    n /= np.linalg.norm(n, axis=1)[:, None]
    return p, n, f


def write_mesh(path, p, n, f, first_vertex=1, header=True):
    """OBJ lines of the mesh (vertices, normals, faces `v//vn`) appended to `path`, whose
    vertices so far number `first_vertex - 1` (and its normals none)."""
    fmt = race.fmt
    with open(path, "a") as out:
        if header:
            out.write("# a bumpy icosphere, written by tools/peers/mitsuba_mesh.py\n")
        out.write("".join(f"v {fmt(x)} {fmt(y)} {fmt(z)}\n" for x, y, z in p))
        out.write("".join(f"vn {fmt(x)} {fmt(y)} {fmt(z)}\n" for x, y, z in n))
        out.write("g mesh\nusemtl white\n")
        o = first_vertex
        out.write("".join(f"f {a + o}//{a + 1} {b + o}//{b + 1} {c + o}//{c + 1}\n"
                          for a, b, c in f))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(race.ROOT, "target", "peers", "mitsuba-mesh"))
    ap.add_argument("--vrpt", default=os.path.join(race.ROOT, "target", "release", "vrpt"))
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--level", type=int, default=7, help="icosphere subdivisions (7: 327,680)")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--runs", type=int, default=5)
    a = ap.parse_args()
    if not os.path.exists(a.vrpt):
        sys.exit(f"mitsuba_mesh.py: no vrpt binary at {a.vrpt}: run cargo build --release")

    scene_dir = os.path.join(a.out, race.NAME)
    mi.set_variant("scalar_rgb")
    race.export_scene(scene_dir, a.size, a.size, a.spp, a.max_depth)
    obj = os.path.join(scene_dir, race.NAME + ".obj")
    box_vertices = sum(1 for line in open(obj) if line.startswith("v "))
    p, n, f = bumpy_mesh(a.level)
    write_mesh(obj, p, n, f, first_vertex=box_vertices + 1, header=False)
    mesh_obj = os.path.join(a.out, "mesh.obj")
    if os.path.exists(mesh_obj):
        os.remove(mesh_obj)
    write_mesh(mesh_obj, p, n, f)
    print(f"box + mesh of {len(f)} triangles in {scene_dir}; the mesh alone in {mesh_obj}")

    mi.set_variant(a.variant)
    mi.set_log_level(mi.LogLevel.Error)
    d = mi.cornell_box()
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    d["sensor"]["film"]["width"] = d["sensor"]["film"]["height"] = a.size
    d["sensor"]["sampler"] = {"type": "independent", "sample_count": a.spp}
    d["integrator"]["max_depth"] = a.max_depth
    d["mesh"] = {"type": "obj", "filename": mesh_obj, "bsdf": {"type": "ref", "id": "white"}}
    scene = mi.load_dict(d)
    np.array(mi.render(scene, spp=a.spp, seed=10**6))  # the JIT compiles

    vrpt = race.Vrpt(a.vrpt, scene_dir, a.out)
    times = {"vrpt": [], "mitsuba": []}
    means = {"vrpt": [], "mitsuba": []}
    for r in range(a.runs):
        img, t, spp = vrpt.render("mis", a.spp, 100 + r)
        assert spp == a.spp, f"vrpt would round {a.spp} spp to {spp}: give a square"
        times["vrpt"].append(t)
        means["vrpt"].append(img.mean())
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=a.spp, seed=100 + r), dtype=np.float64)
        times["mitsuba"].append(time.perf_counter() - t0)
        means["mitsuba"].append(img[:, :, :3].mean())
        print(f"  run {r}: vrpt {times['vrpt'][-1]:.3f} s, Mitsuba {times['mitsuba'][-1]:.3f} s",
              flush=True)
    ratios = [v / m for v, m in zip(times["vrpt"], times["mitsuba"])]
    print(f"\n{len(f)} triangles, {a.size}x{a.size}, {a.spp} spp, max depth {a.max_depth}, "
          f"{os.cpu_count()} CPUs, Mitsuba {mi.__version__} {a.variant}")
    for who in ("vrpt", "mitsuba"):
        m = statistics.mean(means[who])
        print(f"  {who:8s} median {statistics.median(times[who]):.3f} s "
              f"({min(times[who]):.3f}..{max(times[who]):.3f}); image mean {m:.5f}")
    print(f"  vrpt / Mitsuba render time: {statistics.median(ratios):.2f}x "
          f"(median of {len(ratios)} pairs, {min(ratios):.2f}..{max(ratios):.2f})")
    rel = abs(statistics.mean(means["vrpt"]) / statistics.mean(means["mitsuba"]) - 1)
    if rel > 0.02 or not math.isfinite(rel):
        sys.exit(f"mitsuba_mesh.py: the image means differ by {rel:.1%}: do both see the mesh?")


if __name__ == "__main__":
    main()
