#!/usr/bin/env python3
"""Check vrpt against Mitsuba 3 on a vrpt scene with diffuse walls, area lights, smooth glass and
perfect mirrors (the shipped ``scenes/glass``).

What it does, in order (every step prints what it found):

1. convert  Reads the scene's ``scene.toml``, OBJ and MTL as vrpt reads them and builds the same
            scene for Mitsuba: the OBJ's faces as fans (``f a b c d`` -> (a,b,c), (a,c,d)), one
            PLY per material (and per shading kind: vertex normals where all three corners of a
            triangle give a ``vn``, else flat), every triangle's winding kept. Materials:
            ``Kd`` only -> ``twosided`` ``diffuse``; ``Ke`` -> an ``area`` emitter on that mesh
            (one-sided, on the counter-clockwise side, as vrpt's); ``illum 3`` with black ``Kd``
            -> ``twosided`` ``conductor`` (``material: none``, ``specular_reflectance = Ks``);
            ``illum`` 4/6/7/9 with ``Tf`` below 1 -> ``dielectric`` (``int_ior = Ni``,
            ``ext_ior = 1``, ``specular_transmittance = 1 - Tf``). Anything else (a ``Ks`` on a
            diffuse material, textures, dissolve, Schlick mirrors, a mirror over a diffuse base,
            emitting glass, ...) is refused rather than guessed. Camera: ``perspective`` with the
            vertical ``fov`` (``fov_axis: y``), ``look_at(eye, target, up)``, a ``box`` pixel
            filter (vrpt's pixel integral); ``path`` integrator with the scene's ``max_depth``
            (vrpt's segments counting the camera ray, as Mitsuba counts them).
2. orient   A small render of each; both must show the left wall red-dominant on the image's
            left and the right wall green-dominant on its right (a mirrored camera would swap
            them), else the z-scores are not computed.
3. agree    Converged references of both (``--spp`` samples in ``--passes`` passes of their own
            seeds; Mitsuba's ``independent`` sampler, vrpt's default strategy). The image mean
            and the means of a 4x4 grid of regions are compared per channel with
            ``mitsuba_race.agreement``: z = (a - b) / sqrt(se_a^2 + se_b^2), each standard error
            from the spread of that renderer's pass means. The check passes when every |z| < 4.

Both converged images are written to the output folder as linear ``.npy`` and as tone-mapped
sRGB PNGs (clamped to [0, 1], the sRGB curve): ``glass-vrpt.png``, ``glass-mitsuba.png``
(named after the scene folder); ``--docs`` also copies them to ``docs/``.

    python3 tools/peers/mitsuba_check.py                         # scenes/glass, about 15 min
    python3 tools/peers/mitsuba_check.py scenes/glass --spp 1024 --passes 8   # a quick look

Needs: ``pip install -r tools/peers/requirements.txt`` (mitsuba, numpy); vrpt: ``cargo build
--release`` (or ``--vrpt PATH``). References are cached in the output folder while their
settings match; ``--fresh`` renders them again.
"""

import argparse
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mitsuba_race as race  # noqa: E402  (region_means, reference, agreement; imports mitsuba)
from mitsuba_race import mi  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(HERE))
Z_BOUND = 4.0


def refuse(message):
    sys.exit(f"mitsuba_check.py: {message}")


# ------------------------------------------------------------------------------ scene.toml
def read_toml(path):
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        import tomli as tomllib  # type: ignore
    with open(path, "rb") as f:
        return tomllib.load(f)


# ------------------------------------------------------------------------------------- MTL
MTL_USED = {"newmtl", "Kd", "Ks", "Ke", "Tf", "Ni", "Ns", "illum", "d", "Tr"}
# statements that change nothing vrpt renders (ambient colour)
MTL_HARMLESS = {"Ka"}


def parse_mtl(path):
    """{name: {key: value}} of an MTL file; colours as 3-tuples (one number is a grey)."""
    mats, cur = {}, None
    with open(path, encoding="utf-8-sig") as f:
        for no, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            tag, *rest = line.split()
            if tag == "newmtl":
                cur = " ".join(rest)
                mats[cur] = {}
                continue
            if cur is None:
                continue
            if tag in ("Kd", "Ks", "Ke", "Tf"):
                vals = [float(x) for x in rest[:3]]
                mats[cur][tag] = np.array(vals * 3 if len(vals) == 1 else vals, dtype=np.float64)
            elif tag in ("Ni", "Ns", "d"):
                mats[cur][tag] = float(rest[0])
            elif tag == "Tr":
                mats[cur]["Tr"] = float(rest[0])
            elif tag == "illum":
                mats[cur]["illum"] = int(float(rest[0]))
            elif tag in MTL_HARMLESS:
                continue
            else:
                refuse(f"{path}:{no}: '{tag}' (textures and other statements are not mapped)")
    return mats


def zero(c):
    return c is None or float(np.max(c)) <= 0.0


def rgb(c):
    return {"type": "rgb", "value": [float(x) for x in c]}


def mitsuba_material(name, m):
    """(kind, Mitsuba BSDF dict, emitted radiance or None) for MTL block `m`, as vrpt renders
    it; refuses what has no exact counterpart."""
    kd, ks, ke, tf = m.get("Kd"), m.get("Ks"), m.get("Ke"), m.get("Tf")
    illum = m.get("illum", 2)
    dissolve = m.get("d", 1.0 - m["Tr"] if "Tr" in m else 1.0)
    emits = not zero(ke)
    if illum in (4, 6, 7, 9):
        if tf is None or float(np.min(tf)) >= 1.0:
            refuse(f"material '{name}': illum {illum} without Tf below 1 (vrpt renders it opaque "
                   "Phong, or glass by dissolve: not mapped)")
        if "Ni" not in m or not m["Ni"] > 1.0:
            refuse(f"material '{name}': glass needs Ni > 1 (vrpt substitutes 1.5: not mapped)")
        if not zero(kd) or not zero(ks) or emits:
            refuse(f"material '{name}': glass with Kd, Ks or Ke (vrpt drops them or adds "
                   "emission: not mapped)")
        trans = np.clip(1.0 - tf, 0.0, 1.0)
        bsdf = {"type": "dielectric", "int_ior": float(m["Ni"]), "ext_ior": 1.0,
                "specular_transmittance": rgb(trans)}
        return f"glass Ni {m['Ni']} transmittance {trans.tolist()}", bsdf, None
    if illum == 3:
        if ks is None:
            refuse(f"material '{name}': illum 3 without Ks (vrpt assumes 1: not mapped)")
        if not zero(kd) or emits:
            refuse(f"material '{name}': a mirror over a diffuse Kd, or emitting: not mapped")
        if float(np.max(ks)) > 1.0:
            refuse(f"material '{name}': mirror Ks > 1 (vrpt scales it down: not mapped)")
        bsdf = {"type": "twosided", "bsdf": {"type": "conductor", "material": "none",
                                             "specular_reflectance": rgb(ks)}}
        return f"mirror Ks {ks.tolist()}", bsdf, None
    if illum not in (0, 1, 2):
        refuse(f"material '{name}': illum {illum} is not mapped")
    if not zero(ks):
        refuse(f"material '{name}': Ks > 0 on a diffuse material (vrpt's Phong lobe has no "
               "exact Mitsuba counterpart)")
    if dissolve < 1.0:
        refuse(f"material '{name}': dissolve below 1 is not mapped")
    if kd is None:
        refuse(f"material '{name}': no Kd (vrpt substitutes a default: not mapped)")
    if float(np.max(kd)) > 1.0:
        refuse(f"material '{name}': Kd > 1 (vrpt scales it down: not mapped)")
    bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(kd)}}
    kind = f"diffuse Kd {kd.tolist()}" + (f", emits Ke {ke.tolist()}" if emits else "")
    return kind, bsdf, (ke if emits else None)


# ------------------------------------------------------------------------------------- OBJ
def parse_obj(path):
    """(positions, normals, mtllibs, {material: [(corners, has_normals)]}): each triangle of
    the fans as three (v, vn) index pairs (0-based; vn -1 where absent)."""
    pos, nrm, libs, groups = [], [], [], {}
    mat = None
    with open(path, encoding="utf-8-sig") as f:
        for no, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            tag, *rest = line.split()
            if tag == "v":
                pos.append([float(x) for x in rest[:3]])
            elif tag == "vn":
                nrm.append([float(x) for x in rest[:3]])
            elif tag == "mtllib":
                libs.append(" ".join(rest))
            elif tag == "usemtl":
                mat = " ".join(rest)
            elif tag == "f":
                corners = []
                for w in rest:
                    parts = w.split("/")
                    v = int(parts[0])
                    v = v - 1 if v > 0 else len(pos) + v
                    vn = -1
                    if len(parts) >= 3 and parts[2]:
                        vn = int(parts[2])
                        vn = vn - 1 if vn > 0 else len(nrm) + vn
                    corners.append((v, vn))
                if mat is None:
                    refuse(f"{path}:{no}: a face without usemtl (vrpt's grey default: not mapped)")
                for k in range(1, len(corners) - 1):
                    groups.setdefault(mat, []).append((corners[0], corners[k], corners[k + 1]))
            elif tag in ("vt", "o", "g", "s"):
                continue
            else:
                refuse(f"{path}:{no}: OBJ statement '{tag}' is not mapped")
    return np.array(pos, dtype=np.float64), np.array(nrm, dtype=np.float64), libs, groups


def write_ply(path, p, n, faces):
    """A binary little-endian PLY of float positions (and normals where `n` is given) and
    int faces."""
    header = ["ply", "format binary_little_endian 1.0", f"element vertex {len(p)}",
              "property float x", "property float y", "property float z"]
    if n is not None:
        header += ["property float nx", "property float ny", "property float nz"]
    header += [f"element face {len(faces)}", "property list uchar int vertex_indices",
               "end_header"]
    vert = np.hstack([p, n]) if n is not None else p
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, faces
    with open(path, "wb") as out:
        out.write(("\n".join(header) + "\n").encode())
        out.write(vert.astype("<f4").tobytes())
        out.write(face.tobytes())


def convert(scene_dir, work):
    """The Mitsuba shapes of a vrpt scene folder (dict entries), its camera and render
    settings; prints what it mapped."""
    toml = read_toml(os.path.join(scene_dir, "scene.toml"))
    env = toml.get("environment", {}).get("radiance", [0.0, 0.0, 0.0])
    if any(float(x) != 0.0 for x in env) or set(toml.get("environment", {})) - {"radiance"}:
        refuse("a non-black environment is not mapped")
    obj_path = os.path.join(scene_dir, toml["obj"])
    pos, nrm, libs, groups = parse_obj(obj_path)
    mats = {}
    for lib in libs:
        mats.update(parse_mtl(os.path.join(os.path.dirname(obj_path), lib)))
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    centre = 0.5 * (lo + hi)
    shapes = {}
    os.makedirs(work, exist_ok=True)
    for mat, tris in groups.items():
        if mat not in mats:
            refuse(f"usemtl '{mat}' names no material of {libs}")
        kind, bsdf, emission = mitsuba_material(mat, mats[mat])
        smooth, flat, skipped, flipped = [], [], 0, 0
        for t in tris:
            p = pos[[c[0] for c in t]]
            ng = np.cross(p[1] - p[0], p[2] - p[0])
            if np.linalg.norm(ng) <= 0.0:
                skipped += 1
                continue
            vn = [c[1] for c in t]
            if all(k >= 0 for k in vn):
                n = nrm[vn]
                ln = np.linalg.norm(n, axis=1)
                if np.all(np.isfinite(n)) and np.all(ln > 0):
                    n = n / ln[:, None]
                    # vrpt turns the interpolated normal to the winding's side; Mitsuba does not:
                    # the two agree only where the vertex normals lie on the winding's side
                    if np.dot(n.sum(axis=0), ng) <= 0 or np.any(n @ ng <= 0):
                        flipped += 1
                    smooth.append((p, n))
                    continue
            flat.append(p)
        if flipped:
            refuse(f"material '{mat}': {flipped} triangles whose vertex normals face away from "
                   "their winding (vrpt and Mitsuba would disagree on their inside)")
        for label, items, normals in (("smooth", smooth, True), ("flat", flat, False)):
            if not items:
                continue
            if normals:
                p = np.concatenate([it[0] for it in items])
                n = np.concatenate([it[1] for it in items])
            else:
                p, n = np.concatenate(items), None
            faces = np.arange(len(p), dtype=np.int32).reshape(-1, 3)
            ply = os.path.join(work, f"{mat}-{label}.ply")
            write_ply(ply, p, n, faces)
            shape = {"type": "ply", "filename": ply, "bsdf": bsdf, "face_normals": not normals}
            note = ""
            if emission is not None:
                shape["emitter"] = {"type": "area", "radiance": rgb(emission)}
                tri = p.reshape(-1, 3, 3)
                ng = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                into = np.einsum("ij,ij->i", centre - tri.mean(axis=1), ng)
                ngm = ng.sum(axis=0)
                note = (f"; emits on the winding side, mean normal "
                        f"{np.round(ngm / np.linalg.norm(ngm), 3).tolist()}, "
                        f"{int((into > 0).sum())}/{len(tri)} triangles facing the scene's centre")
                if np.any(into <= 0):
                    print(f"  warning: emitter '{mat}' has triangles facing away from the "
                          "scene's centre (both renderers emit on the winding side)")
            shapes[f"{mat}-{label}"] = shape
            print(f"  {mat}: {len(faces)} {label} triangles, {kind}{note}")
        if skipped:
            print(f"  {mat}: {skipped} zero-area triangles skipped (as vrpt skips them)")
    cam, ren = toml["camera"], toml.get("render", {})
    return shapes, cam, ren


def mitsuba_dict(shapes, cam, width, height, max_depth):
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth)},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(cam["fov"]),
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[float(x) for x in cam["eye"]],
                target=[float(x) for x in cam["target"]],
                up=[float(x) for x in cam["up"]]),
            "sampler": {"type": "independent", "sample_count": 4},
            "film": {"type": "hdrfilm", "width": int(width), "height": int(height),
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
        },
    }
    d.update(shapes)
    return d


# ------------------------------------------------------------------------------- renderers
class MitsubaRenderer:
    """Renders a pass of `spp` samples as chunks of at most `chunk` spp (one wavefront each),
    every chunk with its own seed."""

    def __init__(self, scene, chunk):
        self.scene, self.chunk = scene, chunk

    def render(self, spp, seed):
        acc, done, c = None, 0, 0
        while done < spp:
            n = min(self.chunk, spp - done)
            img = np.array(mi.render(self.scene, spp=n, seed=seed * 4099 + c), dtype=np.float64)
            acc = img * n if acc is None else acc + img * n
            done, c = done + n, c + 1
        return acc / spp


class VrptRenderer:
    def __init__(self, exe, scene_dir, work, width, height, max_depth):
        self.exe, self.scene_dir, self.work = exe, scene_dir, work
        self.width, self.height = width, height
        self.flags = ["--width", str(width), "--height", str(height),
                      "--max-depth", str(max_depth)]

    def render(self, spp, seed):
        out = os.path.join(self.work, "vrpt-pass.exr")
        subprocess.run([self.exe, "render", self.scene_dir, "--spp", str(spp), "--seed",
                        str(seed), *self.flags, "-o", out, "-q"], check=True)
        bmp = mi.Bitmap(out)
        st = bmp.struct_()
        names = [st[i].name for i in range(len(st))]
        img = np.array(bmp, dtype=np.float64)
        if names[:3] != ["R", "G", "B"] or img.shape[:2] != (self.height, self.width):
            refuse(f"vrpt's EXR has an unexpected layout: {img.shape}, channels {names}")
        return img[:, :, :3]


# ---------------------------------------------------------------------------------- images
def srgb_png(img, path):
    """Linear RGB -> clamped, sRGB-encoded 8-bit PNG."""
    x = np.clip(img, 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    u8 = np.ascontiguousarray(np.round(s * 255.0).astype(np.uint8))
    mi.Bitmap(u8, pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def orientation(img):
    """(red/green of the left edge strip, green/red of the right edge strip) over the middle
    half of the rows: both above 1 when the red wall is on the left and the green on the right."""
    h, w = img.shape[:2]
    rows = slice(h // 4, 3 * h // 4)
    k = max(1, w // 16)
    left = img[rows, :k].reshape(-1, 3).mean(axis=0)
    right = img[rows, w - k:].reshape(-1, 3).mean(axis=0)
    return left[0] / max(left[1], 1e-12), right[1] / max(right[0], 1e-12)


PROBE = """
import sys, numpy as np, mitsuba as mi
mi.set_variant(sys.argv[1])
d = mi.cornell_box()
d["sensor"]["film"]["width"] = d["sensor"]["film"]["height"] = 8
print(float(np.array(mi.render(mi.load_dict(d), spp=4)).mean()))
"""


def choose_variant(wanted):
    """`wanted` if a tiny render works with it, else scalar_rgb. The probe runs in a child
    process: a JIT backend that cannot compile a kernel (LLVM 15 fails on drjit's fmaximum, for
    one) aborts the process rather than raising."""
    for variant in dict.fromkeys((wanted, "scalar_rgb")):
        r = subprocess.run([sys.executable, "-c", PROBE, variant], capture_output=True,
                           text=True, timeout=600)
        if r.returncode == 0:
            mi.set_variant(variant)
            return variant
        why = [x for x in (r.stderr.strip().splitlines() or ["?"]) if x.strip()]
        print(f"warning: Mitsuba variant {variant} unusable here (exit {r.returncode}: "
              f"{(why[0] if why else '?')[:100]}); for llvm_ad_rgb install a newer LLVM "
              "(Debian: apt install libllvm19) or set DRJIT_LIBLLVM_PATH")
    refuse("no usable Mitsuba variant")


# ------------------------------------------------------------------------------------ main
def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", default=os.path.join(ROOT, "scenes", "glass"))
    ap.add_argument("--spp", type=int, default=4096, help="spp of each converged reference")
    ap.add_argument("--passes", type=int, default=16, help="passes (seeds) per reference")
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "peers", "mitsuba-check"))
    ap.add_argument("--vrpt", default=os.path.join(ROOT, "target", "release", "vrpt"))
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--width", type=int, help="default: scene.toml's")
    ap.add_argument("--height", type=int, help="default: scene.toml's")
    ap.add_argument("--max-depth", type=int, help="default: scene.toml's")
    ap.add_argument("--chunk", type=int, default=64,
                    help="Mitsuba spp per mi.render call of a JIT variant (memory of one "
                    "wavefront)")
    ap.add_argument("--fresh", action="store_true", help="render the references again")
    ap.add_argument("--docs", action="store_true",
                    help="also copy the two PNGs to docs/<scene>-vrpt.png, -mitsuba.png")
    a = ap.parse_args()
    if a.spp % a.passes:
        refuse("--spp must be a multiple of --passes")
    if a.passes < 2:
        refuse("--passes must be at least 2 (the standard errors come from their spread)")
    if not os.path.exists(a.vrpt):
        refuse(f"no vrpt binary at {a.vrpt}: cargo build --release, or --vrpt PATH")
    scene_dir = os.path.abspath(a.scene)
    name = os.path.basename(os.path.normpath(scene_dir))
    os.makedirs(a.out, exist_ok=True)
    work = os.path.join(a.out, "mitsuba-scene")

    t0 = time.perf_counter()
    variant = choose_variant(a.variant)
    mi.set_log_level(mi.LogLevel.Error)
    print(f"== convert {scene_dir} for Mitsuba {mi.__version__} ({variant})")
    shapes, cam, ren = convert(scene_dir, work)
    width = a.width or int(ren.get("width", 256))
    height = a.height or int(ren.get("height", 256))
    depth = a.max_depth or int(ren.get("max_depth", 8))
    print(f"  camera eye {cam['eye']} target {cam['target']} up {cam['up']}, vertical fov "
          f"{cam['fov']} deg; {width}x{height}, max depth {depth} (segments, camera ray included)")
    scene = mi.load_dict(mitsuba_dict(shapes, cam, width, height, depth))
    # a JIT variant renders a call's samples as one wavefront: chunks bound its memory
    mitsuba = MitsubaRenderer(scene, a.chunk if not variant.startswith("scalar") else 1 << 30)
    vrpt = VrptRenderer(a.vrpt, scene_dir, a.out, width, height, depth)
    version = subprocess.run([a.vrpt, "--version"], capture_output=True, text=True).stdout.strip()
    print(f"  {version}; {os.cpu_count()} CPUs")

    # ---- 2. orientation (also compiles Mitsuba's kernel before anything is timed)
    print("\n== orientation: red/green of the left edge, green/red of the right edge")
    ok = True
    for label, r in (("vrpt", vrpt), ("Mitsuba", mitsuba)):
        lr, rg = orientation(r.render(16, 999))
        good = lr > 1.0 and rg > 1.0
        ok &= good
        print(f"  {label:8s} left R/G {lr:.2f}, right G/R {rg:.2f}: "
              f"{'red left, green right' if good else 'NOT red left / green right'}")
    if not ok:
        refuse("the two images are not oriented alike: fix the camera conversion")

    # ---- 3. converged references
    per = a.spp // a.passes
    print(f"\n== converged references: {a.spp} spp in {a.passes} passes of {per} spp each")
    if a.fresh:
        for f in os.listdir(a.out):
            if f.startswith("ref-"):
                os.remove(os.path.join(a.out, f))
    settings = {"scene": scene_dir, "spp": a.spp, "passes": a.passes, "width": width,
                "height": height, "depth": depth}
    seeds = [7919 * k + 1 for k in range(a.passes)]
    times = {}
    t = time.perf_counter()
    m_ref, m_reg = race.reference(a.out, f"check-mitsuba-{variant}",
                                  dict(settings, v=mi.__version__, chunk=a.chunk), a.passes,
                                  lambda k: mitsuba.render(per, seeds[k]))
    times["Mitsuba"] = time.perf_counter() - t
    t = time.perf_counter()
    v_ref, v_reg = race.reference(a.out, "check-vrpt", dict(settings, v=version), a.passes,
                                  lambda k: vrpt.render(per, seeds[k]))
    times["vrpt"] = time.perf_counter() - t
    for label, img in (("vrpt", v_ref), ("Mitsuba", m_ref)):
        lr, rg = orientation(img)
        if not (lr > 1.0 and rg > 1.0):
            refuse(f"the converged {label} image is not red left / green right")

    z, rel = race.agreement(v_ref, v_reg, m_ref, m_reg)
    mv, mm = race.region_means(v_ref), race.region_means(m_ref)
    se_v = v_reg.std(axis=0, ddof=1) / math.sqrt(len(v_reg))
    se_m = m_reg.std(axis=0, ddof=1) / math.sqrt(len(m_reg))
    regions = ["image"] + [f"r{j}c{i}" for j in range(4) for i in range(4)]
    print("\n| region | channel | vrpt mean | Mitsuba mean | difference | z |")
    print("|---|---|---:|---:|---:|---:|")
    for r, reg in enumerate(regions):
        for c, ch in enumerate("RGB"):
            d = (mv[r, c] - mm[r, c]) / mm[r, c] * 100 if mm[r, c] else float("nan")
            flag = " **" if abs(z[r, c]) >= Z_BOUND else ""
            print(f"| {reg} | {ch} | {mv[r, c]:.5f} ± {se_v[r, c]:.5f} | "
                  f"{mm[r, c]:.5f} ± {se_m[r, c]:.5f} | {d:+.2f} % | {z[r, c]:+.2f}{flag} |")
    worst = np.unravel_index(np.argmax(np.abs(z)), z.shape)
    max_z = float(np.abs(z).max())
    agree = max_z < Z_BOUND
    print(f"\n(regions r<row>c<column> of a 4x4 grid, row 0 at the top; ± the standard error "
          f"of the mean from the spread of {a.passes} passes)")
    print(f"reference times: vrpt {times['vrpt']:.0f} s, Mitsuba {times['Mitsuba']:.0f} s "
          f"(0 when cached); total {time.perf_counter() - t0:.0f} s")

    # ---- images
    pngs = {}
    for label, img in (("vrpt", v_ref), ("mitsuba", m_ref)):
        np.save(os.path.join(a.out, f"{name}-{label}.npy"), img.astype(np.float32))
        pngs[label] = os.path.join(a.out, f"{name}-{label}.png")
        srgb_png(img, pngs[label])
    print(f"wrote {pngs['vrpt']} and {pngs['mitsuba']}")
    if a.docs:
        for label, p in pngs.items():
            dst = os.path.join(ROOT, "docs", f"{name}-{label}.png")
            shutil.copyfile(p, dst)
            print(f"copied to {dst}")

    print(f"\nverdict: {'AGREE' if agree else 'DISAGREE'}: {regions[worst[0]]} "
          f"{'RGB'[worst[1]]} has the largest |z| = {max_z:.2f} (bound {Z_BOUND:g}; "
          f"{3 * len(regions)} tests); image means differ by {np.round(rel * 100, 3).tolist()} %")
    if not agree:
        sys.exit(1)


if __name__ == "__main__":
    main()
