#!/usr/bin/env python3
"""Generate the vrpt test scenes under scenes/.

Writes the scene folders, each holding NAME.obj, NAME.mtl and scene.toml:

  scenes/cornell-box/    the classic Cornell box from the published Cornell
                         measurements (mm), with a glossy tall box.
  scenes/glossy-plates/  Veach's multiple-importance-sampling scene: four
                         glossy plates (Phong Ns 10..10000) reflecting four
                         emitters of equal power and increasing size.
  scenes/checker-plane/  an emissive checkerboard plane seen at a slant
                         (a pure 2D pixel-integration / antialiasing test).
  scenes/lit-checker/    a diffuse checkerboard lit by one large, close area
                         light (a 4D pixel x light-point integral).
  scenes/night-hall/     a long hall lit by 160 lights of different sizes,
                         powers and facings (the many-light scene).
  scenes/door/           Veach's door: a dark room lit only through a door
                         standing ajar from a brightly lit second room
                         (the path-guiding scene).
  scenes/door-dark/      the door with room A darkened.
  scenes/gap/            a dark room lit through a 12 cm gap (guiding's
                         showcase).
  scenes/sun-sky/        blocks on a ground plane lit only by an HDR
                         lat-long environment (sky.exr, written here too): a
                         smooth sky and a small, bright sun disc (the
                         environment-map importance-sampling scene).
  scenes/textured/       a checker floor, a bump-mapped brick wall and a
                         cutout fence before a light (PNG textures, written
                         here too).
  scenes/glass/          smooth glass and a mirror: a glass sphere's caustic.
  scenes/lamp/           a room lit only through a lamp's glass shade (every
                         lit path a caustic; guiding's caustic scene).

The files under scenes/ are committed output of this script; edit the script
and rerun it rather than editing them by hand:

    python3 tools/make_scenes.py

Conventions: right-handed, y up.  Faces are triangles or quads given with
1-based vertex indices only, wound counter-clockwise seen from the side
their normal points to (n = (v1 - v0) x (v2 - v0)).  Emission is one-sided,
so every face is built from a corner list plus a point (or direction) it
must face, and the winding is flipped if needed and then asserted.
Standard library only.
"""

import math
import os
import struct
import sys
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes")


# ---------------------------------------------------------------- vectors
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def length(a):
    return math.sqrt(dot(a, a))


def norm(a):
    n = length(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def centroid(pts):
    n = float(len(pts))
    return (sum(p[0] for p in pts) / n,
            sum(p[1] for p in pts) / n,
            sum(p[2] for p in pts) / n)


def fan_normals(pts):
    """Winding normals of the fan triangles (v0, vi, vi+1) of a polygon."""
    return [cross(sub(pts[i], pts[0]), sub(pts[i + 1], pts[0]))
            for i in range(1, len(pts) - 1)]


def reflect(d, n):
    return sub(d, mul(n, 2.0 * dot(d, n)))


def angle_deg(a, b):
    c = dot(norm(a), norm(b))
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


# ---------------------------------------------------------------- formatting
def fmt(v):
    """At most 6 decimals, no trailing zeros, no negative zero."""
    s = "%.6f" % v
    s = s.rstrip("0").rstrip(".")
    if s in ("-0", ""):
        s = "0"
    return s


def tfloat(v):
    """A TOML float (always has a decimal point)."""
    s = fmt(v)
    if "." not in s:
        s += ".0"
    return s


def tvec(v):
    return "[" + ", ".join(tfloat(x) for x in v) + "]"


# ---------------------------------------------------------------- mesh
class Mesh:
    def __init__(self, name):
        self.name = name
        self.verts = []
        self.vindex = {}
        self.groups = []  # (group name, material, [faces as index lists])
        self.materials = []  # (name, dict)
        self.uvs = []  # texture coordinates, "vt" lines (1-based indices)
        self.face_uvs = {}  # (group index, face index) -> vt indices
        self.normals = []  # vertex normals, "vn" lines (1-based indices)
        self.face_normals = {}  # (group index, face index) -> vn indices

    def material(self, name, kd, ks=(0.0, 0.0, 0.0), ns=None, ke=None,
                 maps=()):
        """maps: raw MTL statements ("map_Kd -s 4 4 checker.png", "illum 7")."""
        for c in range(3):
            assert kd[c] + ks[c] <= 1.0 + 1e-9, (name, kd, ks)
        self.materials.append((name, dict(kd=kd, ks=ks, ns=ns, ke=ke,
                                          maps=list(maps))))

    def smooth_triangle(self, pts, normals):
        """A triangle with vertex normals, wound counter-clockwise about them."""
        n = fan_normals(pts)[0]
        if dot(n, add(add(normals[0], normals[1]), normals[2])) < 0.0:
            pts = [pts[0], pts[2], pts[1]]
            normals = [normals[0], normals[2], normals[1]]
        idx = []
        for v in normals:
            self.normals.append(tuple(fmt(x) for x in norm(v)))
            idx.append(len(self.normals))
        self.groups[-1][2].append([self.vertex(p) for p in pts])
        self.face_normals[(len(self.groups) - 1, len(self.groups[-1][2]) - 1)] = idx

    def group(self, gname, mat):
        assert any(m[0] == mat for m in self.materials), mat
        self.groups.append((gname, mat, []))

    def vertex(self, p):
        key = tuple(fmt(x) for x in p)
        if key not in self.vindex:
            self.verts.append(key)
            self.vindex[key] = len(self.verts)  # 1-based
        return self.vindex[key]

    def face(self, pts, toward=None, direction=None, away_from=None,
             uvs=None):
        """Add a polygon (3 or 4 corners).  Exactly one of:
        toward    -- a point the normal must point toward,
        direction -- a vector the normal must have a positive component along,
        away_from -- a point the normal must point away from (convex solids).
        The winding is reversed if needed, then every fan triangle's normal
        is asserted to point the intended way."""
        assert len(pts) in (3, 4)
        c = centroid(pts)
        if toward is not None:
            want = sub(toward, c)
        elif direction is not None:
            want = direction
        else:
            want = sub(c, away_from)
        if dot(fan_normals(pts)[0], want) < 0.0:
            pts = [pts[0]] + list(reversed(pts[1:]))
            if uvs is not None:
                uvs = [uvs[0]] + list(reversed(uvs[1:]))
        for n in fan_normals(pts):
            assert length(n) > 1e-12, ("degenerate face", pts)
            assert dot(n, want) > 0.0, ("bad winding", pts, n, want)
        self.groups[-1][2].append([self.vertex(p) for p in pts])
        if uvs is not None:
            idx = []
            for uv in uvs:
                self.uvs.append(tuple(fmt(x) for x in uv))
                idx.append(len(self.uvs))
            self.face_uvs[(len(self.groups) - 1, len(self.groups[-1][2]) - 1)] = idx

    def triangle_count(self):
        return sum(len(f) - 2 for g in self.groups for f in g[2])

    def all_triangles(self, mat_filter=None):
        out = []
        for gname, mat, faces in self.groups:
            if mat_filter and mat not in mat_filter:
                continue
            for f in faces:
                p = [tuple(float(x) for x in self.verts[i - 1]) for i in f]
                for i in range(1, len(p) - 1):
                    out.append((p[0], p[i], p[i + 1]))
        return out

    def write(self, folder):
        os.makedirs(folder, exist_ok=True)
        obj = os.path.join(folder, self.name + ".obj")
        mtl = os.path.join(folder, self.name + ".mtl")
        lines = ["mtllib %s.mtl" % self.name,
                 "# %s -- generated by tools/make_scenes.py, do not edit"
                 % self.name]
        for v in self.verts:
            lines.append("v " + " ".join(v))
        for t in self.uvs:
            lines.append("vt " + " ".join(t))
        for n in self.normals:
            lines.append("vn " + " ".join(n))
        for g, (gname, mat, faces) in enumerate(self.groups):
            lines.append("o " + gname)
            lines.append("g " + gname)
            lines.append("usemtl " + mat)
            for k, f in enumerate(faces):
                t = self.face_uvs.get((g, k))
                n = self.face_normals.get((g, k))
                if n is not None:
                    lines.append("f " + " ".join("%d//%d" % (i, j)
                                                 for i, j in zip(f, n)))
                elif t is None:
                    lines.append("f " + " ".join(str(i) for i in f))
                else:
                    lines.append("f " + " ".join("%d/%d" % (i, j)
                                                 for i, j in zip(f, t)))
        with open(obj, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        ml = ["# %s -- generated by tools/make_scenes.py, do not edit"
              % self.name]
        for name, m in self.materials:
            ml.append("")
            ml.append("newmtl " + name)
            ml.append("Kd " + " ".join(fmt(x) for x in m["kd"]))
            ml.append("Ks " + " ".join(fmt(x) for x in m["ks"]))
            if m["ns"] is not None:
                ml.append("Ns " + fmt(m["ns"]))
            if m["ke"] is not None:
                ml.append("Ke " + " ".join(fmt(x) for x in m["ke"]))
            ml.extend(m["maps"])
        with open(mtl, "w") as fh:
            fh.write("\n".join(ml) + "\n")
        for p in (obj, mtl):
            assert os.path.getsize(p) < 200 * 1024, p
        return obj, mtl


def write_toml(folder, name, eye, target, fov, radiance, width, height, spp,
               max_depth, up=(0.0, 1.0, 0.0), environment=None):
    text = "\n".join([
        "# generated by tools/make_scenes.py, do not edit",
        'obj = "%s.obj"' % name,
        "",
        "[camera]",
        "eye = " + tvec(eye),
        "target = " + tvec(target),
        "up = " + tvec(up),
        "fov = " + tfloat(fov),
        "",
        "[environment]",
        environment or "radiance = " + tvec(radiance),
        "",
        "[render]",
        "width = %d" % width,
        "height = %d" % height,
        "spp = %d" % spp,
        "max_depth = %d" % max_depth,
        "",
    ])
    with open(os.path.join(folder, "scene.toml"), "w") as fh:
        fh.write(text)


class Camera:
    """Pinhole camera with the renderer's conventions (right = fwd x up)."""

    def __init__(self, eye, target, fov, width, height, up=(0.0, 1.0, 0.0)):
        self.eye = eye
        self.f = norm(sub(target, eye))
        self.r = norm(cross(self.f, up))
        self.u = cross(self.r, self.f)
        self.t = math.tan(math.radians(fov) / 2.0)
        self.aspect = width / float(height)
        self.w, self.h = width, height

    def project(self, p):
        """Pixel (column, row) of a point, row 0 at the top."""
        d = sub(p, self.eye)
        z = dot(d, self.f)
        x = dot(d, self.r) / z / (self.t * self.aspect)
        y = dot(d, self.u) / z / self.t
        return ((x + 1.0) * 0.5 * self.w, (1.0 - y) * 0.5 * self.h)


def ray_triangle(o, d, tri):
    """Möller-Trumbore; returns t or None."""
    e1 = sub(tri[1], tri[0])
    e2 = sub(tri[2], tri[0])
    p = cross(d, e2)
    det = dot(e1, p)
    if abs(det) < 1e-12:
        return None
    inv = 1.0 / det
    s = sub(o, tri[0])
    u = dot(s, p) * inv
    if u < 0.0 or u > 1.0:
        return None
    q = cross(s, e1)
    v = dot(d, q) * inv
    if v < 0.0 or u + v > 1.0:
        return None
    t = dot(e2, q) * inv
    return t if t > 1e-6 else None


# ================================================================ 1. Cornell
def cornell_box():
    name = "cornell-box"
    m = Mesh(name)
    white = (0.725, 0.71, 0.68)
    m.material("white", white)
    m.material("red", (0.63, 0.065, 0.05))
    m.material("green", (0.14, 0.45, 0.091))
    m.material("short_box", white)
    m.material("tall_box", (0.4, 0.4, 0.4), ks=(0.5, 0.5, 0.5), ns=200.0)
    m.material("light", (0.0, 0.0, 0.0), ke=(17.0, 12.0, 4.0))

    # Published Cornell measurements (mm).
    room_center = (278.0, 274.4, 279.6)
    m.group("floor", "white")
    m.face([(552.8, 0.0, 0.0), (0.0, 0.0, 0.0),
            (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)], direction=(0, 1, 0))
    m.group("ceiling", "white")
    m.face([(556.0, 548.8, 0.0), (556.0, 548.8, 559.2),
            (0.0, 548.8, 559.2), (0.0, 548.8, 0.0)], direction=(0, -1, 0))
    m.group("back_wall", "white")
    m.face([(549.6, 0.0, 559.2), (0.0, 0.0, 559.2),
            (0.0, 548.8, 559.2), (556.0, 548.8, 559.2)], direction=(0, 0, -1))
    m.group("red_wall", "red")  # x ~ 550, faces -x (into the room)
    m.face([(552.8, 0.0, 0.0), (549.6, 0.0, 559.2),
            (556.0, 548.8, 559.2), (556.0, 548.8, 0.0)], direction=(-1, 0, 0))
    m.group("green_wall", "green")  # x = 0, faces +x
    m.face([(0.0, 0.0, 559.2), (0.0, 0.0, 0.0),
            (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)], direction=(1, 0, 0))
    # all room faces must also face the room centre
    for g in m.groups:
        for f in g[2]:
            p = [tuple(float(x) for x in m.verts[i - 1]) for i in f]
            for n in fan_normals(p):
                assert dot(n, sub(room_center, centroid(p))) > 0.0

    def block(gname, mat, top):
        bottom = [(p[0], 0.0, p[2]) for p in top]
        center = centroid(top + bottom)
        m.group(gname, mat)
        m.face(list(top), away_from=center)
        for i in range(4):
            j = (i + 1) % 4
            m.face([bottom[i], bottom[j], top[j], top[i]], away_from=center)

    block("short_box", "short_box",
          [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0),
           (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)])
    block("tall_box", "tall_box",
          [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0),
           (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)])

    m.group("light", "light")  # just below the ceiling, emitting down
    m.face([(343.0, 548.0, 227.0), (343.0, 548.0, 332.0),
            (213.0, 548.0, 332.0), (213.0, 548.0, 227.0)],
           direction=(0, -1, 0))

    folder = os.path.join(SCENES, name)
    m.write(folder)
    eye, target, fov = (278.0, 273.0, -800.0), (278.0, 273.0, 0.0), 39.3
    cam = Camera(eye, target, fov, 256, 256)
    # the red wall (x ~ 550) must be on the left of the image
    assert cam.project((552.8, 274.0, 300.0))[0] < 128.0
    assert cam.project((0.0, 274.0, 300.0))[0] > 128.0
    write_toml(folder, name, eye, target, fov, (0.0, 0.0, 0.0),
               256, 256, 64, 8)
    return m


# ================================================================ 2. Veach
def glossy_plates():
    name = "glossy-plates"
    m = Mesh(name)
    eye, target, fov = (0.0, 2.0, 15.0), (0.0, -2.0, 2.5), 28.0
    width, height = 256, 192
    cam = Camera(eye, target, fov, width, height)

    m.material("floor", (0.2, 0.2, 0.2))
    # back (top of image) = roughest, front (bottom of image) = sharpest
    exponents = [10, 100, 1000, 10000]
    for e in exponents:
        m.material("plate%d" % e, (0.05, 0.05, 0.05), ks=(0.9, 0.9, 0.9),
                   ns=float(e))

    # Emitters: icosahedra (circumradius r) in a row, equal power.
    light_y, light_z = 0.0, 0.0
    light_xs = [-3.75, -1.25, 1.25, 3.75]
    radii = [0.03, 0.1, 0.3, 0.9]
    power_k = 0.72  # Ke * r^2, constant over the four lights
    for i, r in enumerate(radii):
        ke = power_k / (r * r)
        m.material("light%d" % i, (0.0, 0.0, 0.0), ke=(ke, ke, ke))

    # Plates: 7.6 wide (x -3.8..3.8) so the outer lights' highlights land on
    # them while the front plate still fits in the frame;
    # 0.8 deep, stacked back (higher) to front (lower).
    plate_w, plate_d = 7.6, 0.8
    centers = [(0.0, -2.3, 0.0), (0.0, -2.7667, 1.3333),
               (0.0, -3.2333, 2.6667), (0.0, -3.7, 4.0)]
    aim = (0.0, light_y, light_z)  # middle of the light row
    plates = []
    print("glossy-plates: plate tilt check (mirror ray from the eye through "
          "each plate centre)")
    for c, e in zip(centers, exponents):
        # Tilt: the plate normal is the half vector between the directions to
        # the eye and to the light row, so the mirror direction hits it.
        n = norm(add(norm(sub(eye, c)), norm(sub(aim, c))))
        assert abs(n[0]) < 1e-12
        u = (1.0, 0.0, 0.0)
        v = norm(cross(n, u))  # in the y-z plane, along the plate's depth
        hw, hd = plate_w / 2.0, plate_d / 2.0
        corners = [add(add(c, mul(u, su * hw)), mul(v, sv * hd))
                   for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        m.group("plate%d" % e, "plate%d" % e)
        m.face(corners, direction=n)
        # must also face the camera
        assert dot(n, sub(eye, c)) > 0.0
        plates.append((c, n, u, v, corners, e))

        d = norm(sub(c, eye))
        rdir = reflect(d, n)
        t = (light_y - c[1]) / rdir[1]
        hit = add(c, mul(rdir, t))
        tilt = math.degrees(math.acos(n[1]))
        print("  plate%-5d centre (%.2f, %.3f, %.3f) tilt %.2f deg toward "
              "camera; reflected ray vs. direction to light row centre: "
              "%.4f deg; crosses y=%.1f at (x %.3f, z %.3f)"
              % (e, c[0], c[1], c[2], tilt, angle_deg(rdir, sub(aim, c)),
                 light_y, hit[0], hit[2]))
        assert angle_deg(rdir, sub(aim, c)) < 0.5
        assert abs(hit[2] - light_z) < 0.25

    # Where each light's mirror highlight falls on each plate.
    print("  mirror highlight of each light on each plate "
          "(plate-local x in -3.8..3.8, depth in -0.4..0.4):")
    for c, n, u, v, corners, e in plates:
        cells = []
        for lx, r in zip(light_xs, radii):
            L = (lx, light_y, light_z)
            Lm = sub(L, mul(n, 2.0 * dot(sub(L, c), n)))  # mirror image
            d = sub(Lm, eye)
            t = dot(sub(c, eye), n) / dot(d, n)
            p = add(eye, mul(d, t))
            lu, lv = dot(sub(p, c), u), dot(sub(p, c), v)
            on = abs(lu) <= plate_w / 2 and abs(lv) <= plate_d / 2
            cells.append("(%+.2f,%+.2f)%s" % (lu, lv, "" if on else "!OFF"))
            assert on, ("highlight off plate", e, lx)
        print("    plate%-5d " % e + " ".join(cells))

    # Visibility: each plate's centre is seen unoccluded, and its reflected
    # centre ray reaches the light row unoccluded by other plates.
    plate_tris = [(e, (p[0], p[i], p[i + 1]))
                  for (_, _, _, _, p, e) in plates for i in (1, 2)]
    for c, n, u, v, corners, e in plates:
        d = sub(c, eye)
        for oe, tri in plate_tris:
            if oe == e:
                continue
            t = ray_triangle(eye, d, tri)
            assert t is None or t > 1.0, ("plate occluded", e, oe)
            rd = sub(aim, c)
            t = ray_triangle(c, rd, tri)
            assert t is None or t > 1.0, ("reflection blocked", e, oe)
        cols = [cam.project(p) for p in corners]
        for col, row in cols:
            assert 0 <= col <= width and 0 <= row <= height, (e, col, row)
        print("  plate%-5d image rows %.1f..%.1f, columns %.1f..%.1f"
              % (e, min(r for _, r in cols), max(r for _, r in cols),
                 min(c_ for c_, _ in cols), max(c_ for c_, _ in cols)))

    # Lights.
    phi = (1.0 + math.sqrt(5.0)) / 2.0
    ico = []
    for a in (-1.0, 1.0):
        for b in (-phi, phi):
            ico += [(0.0, a, b), (a, b, 0.0), (b, 0.0, a)]
    ico = [norm(p) for p in ico]
    edge = min(length(sub(ico[i], ico[j]))
               for i in range(12) for j in range(i + 1, 12))
    adj = lambda i, j: abs(length(sub(ico[i], ico[j])) - edge) < 1e-9
    ico_faces = [(i, j, k) for i in range(12) for j in range(i + 1, 12)
                 for k in range(j + 1, 12) if adj(i, j) and adj(j, k)
                 and adj(i, k)]
    assert len(ico_faces) == 20
    for i, (lx, r) in enumerate(zip(light_xs, radii)):
        center = (lx, light_y, light_z)
        m.group("light%d" % i, "light%d" % i)
        for f in ico_faces:
            m.face([add(center, mul(ico[k], r)) for k in f],
                   away_from=center)
        col, row = cam.project(center)
        print("  light%d x %+.2f r %.2f Ke %.3f (Ke*r^2 = %.2f) at image "
              "(%.1f, %.1f)" % (i, lx, r, power_k / (r * r), power_k, col,
                                row))
        assert 0 <= col <= width and 0 <= row <= height

    # Dark floor and back wall.
    fy, wz = -4.5, -6.0
    m.group("floor", "floor")
    m.face([(-30.0, fy, wz), (30.0, fy, wz), (30.0, fy, 20.0),
            (-30.0, fy, 20.0)], direction=(0, 1, 0))
    m.group("back_wall", "floor")
    m.face([(-30.0, fy, wz), (30.0, fy, wz), (30.0, 15.0, wz),
            (-30.0, 15.0, wz)], direction=(0, 0, 1))
    # plates are above the floor
    for _, _, _, _, corners, _ in plates:
        assert min(p[1] for p in corners) > fy

    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, eye, target, fov, (0.0, 0.0, 0.0),
               width, height, 64, 4)
    return m


# ================================================================ 3. checker
def checkerboard(m, nx, nz, x0, z0):
    """Unit squares in the plane y = 0, nx along +x from x0 and nz along -z
    from z0, alternating materials check_a / check_b, normals up."""
    squares = {"check_a": [], "check_b": []}
    for j in range(nz):
        for i in range(nx):
            xa, xb = x0 + i, x0 + i + 1
            za, zb = z0 - j, z0 - j - 1
            quad = [(xa, 0.0, za), (xb, 0.0, za), (xb, 0.0, zb),
                    (xa, 0.0, zb)]
            squares["check_a" if (i + j) % 2 == 0 else "check_b"].append(quad)
    for mat in ("check_a", "check_b"):
        m.group(mat, mat)
        for q in squares[mat]:
            m.face(q, direction=(0, 1, 0))
    assert len(squares["check_a"]) + len(squares["check_b"]) == nx * nz


def checker_plane():
    name = "checker-plane"
    m = Mesh(name)
    m.material("check_a", (0.0, 0.0, 0.0), ke=(1.0, 1.0, 1.0))
    m.material("check_b", (0.0, 0.0, 0.0), ke=(0.05, 0.05, 0.05))
    checkerboard(m, 24, 40, -12.0, -2.0)

    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, (0.0, 1.5, 0.0), (0.0, 0.0, -8.0), 40.0,
               (0.0, 0.0, 0.0), 128, 96, 16, 2)
    return m


def lit_checker():
    """A diffuse checkerboard lit by one large, close square light.

    The light (2 x 2, one unit above the plane, facing down) is as large as
    its distance, so the geometric term varies strongly across it: with
    next-event estimation and max depth 2 every pixel is a 4D integral (pixel
    area x point on the light) with edges in the pixel dimensions, where
    per-dimension (padded) strata stratify each pair but not their product.
    """
    name = "lit-checker"
    m = Mesh(name)
    m.material("check_a", (0.8, 0.8, 0.8))
    m.material("check_b", (0.05, 0.05, 0.05))
    m.material("light", (0.0, 0.0, 0.0), ke=(3.0, 3.0, 3.0))
    checkerboard(m, 12, 12, -6.0, 1.0)
    m.group("light", "light")
    ly, lz = 1.0, -4.0
    m.face([(-1.0, ly, lz - 1.0), (1.0, ly, lz - 1.0), (1.0, ly, lz + 1.0),
            (-1.0, ly, lz + 1.0)], direction=(0, -1, 0))

    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, (0.0, 0.9, 0.5), (0.0, 0.0, -4.5), 45.0,
               (0.0, 0.0, 0.0), 128, 96, 16, 2)
    return m


def night_hall():
    """A long hall lit by 160 lights of different sizes, powers and facings.

    60 m long, 8 m wide, 5 m high, along -z from the camera.  Two rows of
    30 small ceiling lamps (0.4 x 0.4, facing down) every 2 m; 20 warm wall
    sconces on each side (0.3 x 0.2, facing into the hall) every 3 m at
    1.8 m; and cove lights: 30 strips on each side (1.8 x 0.3, on a ledge
    0.5 m below the ceiling, facing up), which wash the ceiling.  The coves
    carry ~90% of the power, yet nothing below the ledges sees them (they
    face away), and a point near the camera gets most of its light from the
    few lamps near it: a light chosen by power alone is mostly wasted.  Every
    light is a rectangle, so its two triangles are sampled as one.
    """
    name = "night-hall"
    m = Mesh(name)
    m.material("floor", (0.45, 0.42, 0.38))
    m.material("wall", (0.6, 0.6, 0.6))
    m.material("ceiling", (0.3, 0.3, 0.3))
    m.material("ledge", (0.5, 0.5, 0.5))
    m.material("lamp", (0.0, 0.0, 0.0), ke=(6.0, 6.0, 5.4))
    m.material("sconce", (0.0, 0.0, 0.0), ke=(6.0, 3.6, 1.6))
    m.material("cove", (0.0, 0.0, 0.0), ke=(11.0, 12.0, 14.0))
    x0, x1, y1, z0, z1 = -4.0, 4.0, 5.0, 2.0, -60.0
    inside = (0.0, 2.5, -30.0)
    m.group("floor", "floor")
    m.face([(x0, 0.0, z0), (x1, 0.0, z0), (x1, 0.0, z1), (x0, 0.0, z1)],
           direction=(0, 1, 0))
    m.group("ceiling", "ceiling")
    m.face([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
           direction=(0, -1, 0))
    m.group("walls", "wall")
    m.face([(x0, 0.0, z0), (x0, y1, z0), (x0, y1, z1), (x0, 0.0, z1)],
           direction=(1, 0, 0))
    m.face([(x1, 0.0, z0), (x1, y1, z0), (x1, y1, z1), (x1, 0.0, z1)],
           direction=(-1, 0, 0))
    m.face([(x0, 0.0, z1), (x1, 0.0, z1), (x1, y1, z1), (x0, y1, z1)],
           direction=(0, 0, 1))
    m.face([(x0, 0.0, z0), (x1, 0.0, z0), (x1, y1, z0), (x0, y1, z0)],
           direction=(0, 0, -1))
    # the ledges under the coves: a slab 0.4 wide along each wall, its top at
    # yl (the coves lie on it), its underside and edge seen from the hall
    yl, ledge = 4.5, 0.4
    m.group("ledges", "ledge")
    for xw, xe in ((x0, x0 + ledge), (x1, x1 - ledge)):
        into = 1.0 if xe > xw else -1.0
        m.face([(xw, yl - 0.1, z0), (xe, yl - 0.1, z0), (xe, yl - 0.1, z1),
                (xw, yl - 0.1, z1)], direction=(0, -1, 0))
        m.face([(xe, yl - 0.1, z0), (xe, yl, z0), (xe, yl, z1),
                (xe, yl - 0.1, z1)], direction=(into, 0, 0))
        m.face([(xw, yl, z0), (xe, yl, z0), (xe, yl, z1), (xw, yl, z1)],
               direction=(0, 1, 0))
    lights = 0
    m.group("lamps", "lamp")
    for i in range(30):
        z = -1.0 - 2.0 * i
        for x in (-2.0, 2.0):
            m.face([(x - 0.2, y1 - 0.01, z - 0.2), (x + 0.2, y1 - 0.01, z - 0.2),
                    (x + 0.2, y1 - 0.01, z + 0.2), (x - 0.2, y1 - 0.01, z + 0.2)],
                   direction=(0, -1, 0))
            lights += 1
    m.group("sconces", "sconce")
    for i in range(20):
        z = -2.5 - 3.0 * i
        for x, facing in ((x0 + 0.01, 1.0), (x1 - 0.01, -1.0)):
            m.face([(x, 1.7, z - 0.15), (x, 1.9, z - 0.15), (x, 1.9, z + 0.15),
                    (x, 1.7, z + 0.15)], direction=(facing, 0, 0))
            lights += 1
    m.group("coves", "cove")
    for i in range(30):
        z = -1.0 - 2.0 * i
        for xa, xb in ((x0 + 0.05, x0 + 0.35), (x1 - 0.35, x1 - 0.05)):
            m.face([(xa, yl + 0.01, z - 0.9), (xb, yl + 0.01, z - 0.9),
                    (xb, yl + 0.01, z + 0.9), (xa, yl + 0.01, z + 0.9)],
                   direction=(0, 1, 0))
            lights += 1
    assert lights == 160, lights
    # the power split the docstring states (area x mean of Ke)
    power = {"lamps": 60 * 0.16 * 5.8, "sconces": 40 * 0.06 * 3.73,
             "coves": 60 * 0.54 * 12.3}
    assert power["coves"] / sum(power.values()) > 0.85, power
    # the room faces face the inside
    for g in m.groups[:3]:
        for f in g[2]:
            p = [tuple(float(x) for x in m.verts[i - 1]) for i in f]
            for n in fan_normals(p):
                assert dot(n, sub(inside, centroid(p))) > 0.0

    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, (0.0, 1.7, 1.0), (0.0, 1.4, -30.0), 60.0,
               (0.0, 0.0, 0.0), 192, 108, 16, 5)
    return m


def box_room(m, W, H, prefix, z0, z1, center, floor_mat, wall_mat):
    """A room of width W (x from 0) and height H between z0 and z1, its faces
    toward `center`: floor, ceiling, the side walls and the far wall (the one
    away from z = 0); the wall at z = 0 is left to the caller."""
    m.group(prefix + "_floor", floor_mat)
    m.face([(0, 0, z0), (W, 0, z0), (W, 0, z1), (0, 0, z1)], toward=center)
    m.group(prefix + "_ceiling", wall_mat)
    m.face([(0, H, z0), (W, H, z0), (W, H, z1), (0, H, z1)], toward=center)
    m.group(prefix + "_walls", wall_mat)
    m.face([(0, 0, z0), (0, 0, z1), (0, H, z1), (0, H, z0)], toward=center)
    m.face([(W, 0, z0), (W, 0, z1), (W, H, z1), (W, H, z0)], toward=center)
    zf = z1 if abs(z1) > abs(z0) else z0  # the far wall
    m.face([(0, 0, zf), (W, 0, zf), (W, H, zf), (0, H, zf)], toward=center)


def wall_with_opening(m, W, H, x0, x1, top, sides):
    """The wall at z = 0 between two rooms, open from x0 to x1 up to `top`:
    for each (group, center, material) of `sides`, its three faces toward
    that room's center."""
    for group, center, mat in sides:
        m.group(group, mat)
        m.face([(0, 0, 0), (x0, 0, 0), (x0, H, 0), (0, H, 0)], toward=center)
        m.face([(x1, 0, 0), (W, 0, 0), (W, H, 0), (x1, H, 0)], toward=center)
        m.face([(x0, top, 0), (x1, top, 0), (x1, H, 0), (x0, H, 0)],
               toward=center)


def floor_box(m, lo, hi):
    """An axis-aligned box standing on the floor: five faces (no bottom),
    facing out."""
    c = centroid([lo, hi])
    for axis in range(3):
        for side in (0, 1):
            if axis == 1 and side == 0:
                continue  # the bottom lies on the floor
            v = (lo, hi)[side][axis]
            others = [i for i in range(3) if i != axis]
            pts = []
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                pt = [0.0, 0.0, 0.0]
                pt[axis] = v
                pt[others[0]] = (lo, hi)[a][others[0]]
                pt[others[1]] = (lo, hi)[b][others[1]]
                pts.append(tuple(pt))
            m.face(pts, away_from=c)


# ================================================================ 6. door
def door(name="door", dark=False):
    """Veach's "door" setting: room A (the camera's, no light) and room B (a
    bright ceiling light) share a wall at z = 0 whose doorway stands ajar:
    the door, hinged at its right post, is turned 12 degrees into room B, so
    light reaches room A only through a slit about 0.19 m wide.  A point in
    room A sees the light itself only from a thin wedge of floor behind the
    slit; next-event estimation elsewhere finds the light occluded, and BSDF
    sampling finds the slit in a small fraction of its directions.

    dark=True (scenes/door-dark): room A's walls at albedo 0.25 and its floor
    Kd 0.15 / Ks 0.1, so the broad multi-bounce light of room A, which cosine
    sampling handles, no longer hides the light through the slit, which
    path guiding exists to find."""
    m = Mesh(name)
    if dark:
        m.material("wall", (0.25, 0.25, 0.24))
        m.material("floor", (0.15, 0.125, 0.1), ks=(0.1, 0.1, 0.1), ns=60.0)
    else:
        m.material("wall", (0.7, 0.7, 0.68))
        m.material("floor", (0.3, 0.25, 0.2), ks=(0.3, 0.3, 0.3), ns=60.0)
    m.material("bright_wall", (0.75, 0.72, 0.65))
    m.material("door", (0.55, 0.4, 0.3))
    m.material("table", (0.15, 0.15, 0.2), ks=(0.6, 0.6, 0.6), ns=400.0)
    m.material("box", (0.6, 0.2, 0.15))
    m.material("light", (0.0, 0.0, 0.0), ke=(1600.0, 1440.0, 1200.0))
    W, H, DA, DB = 4.0, 2.6, 5.0, 4.0  # width, height, depth of A (z>0) and B
    x0, x1, dh = 2.5, 3.4, 2.1  # doorway
    a_center = (W / 2, H / 2, DA / 2)
    b_center = (W / 2, H / 2, -DB / 2)

    box_room(m, W, H, "a", 0.0, DA, a_center, "floor", "wall")
    box_room(m, W, H, "b", -DB, 0.0, b_center, "bright_wall", "bright_wall")
    # the shared wall at z = 0, with the doorway; each side faces its room
    wall_with_opening(m, W, H, x0, x1, dh,
                      (("a_door_wall", a_center, "wall"),
                       ("b_door_wall", b_center, "bright_wall")))
    # the door: a 4 cm slab hinged at x1, turned into room B
    ang = math.radians(12.0)
    wdoor, t = x1 - x0, 0.04
    u = (-math.cos(ang), 0.0, -math.sin(ang))  # from the hinge to the free edge
    nrm = (math.sin(ang), 0.0, -math.cos(ang))  # toward room B
    hinge = (x1, 0.0, 0.0)
    corners = []
    for a in (0.0, wdoor):
        for b in (0.0, -t):
            corners.append(add(add(hinge, mul(u, a)), mul(nrm, -b - 0.001)))
    # corners: (hinge, front), (hinge, back), (free, front), (free, back)
    c = centroid(corners + [add(p, (0, dh - 0.005, 0)) for p in corners])
    m.group("door", "door")

    def slab_face(pts):
        m.face(pts, away_from=c)

    top = [add(p, (0, dh - 0.005, 0)) for p in corners]
    hf, hb, ff, fb = corners
    thf, thb, tff, tfb = top
    slab_face([hf, ff, tff, thf])
    slab_face([hb, fb, tfb, thb])
    slab_face([ff, fb, tfb, tff])
    slab_face([hf, hb, thb, thf])
    slab_face([thf, tff, tfb, thb])
    # the slit: from the free edge to the doorway's left post
    slit = length(sub((x0, 0.0, 0.0), ff))
    assert 0.1 < slit < 0.3, slit
    # room A: a glossy dark table top and a diffuse box
    m.group("table", "table")
    ty, tc = 0.75, (1.3, 0.75, 2.4)
    m.face([(0.7, ty, 1.9), (1.9, ty, 1.9), (1.9, ty, 2.9), (0.7, ty, 2.9)],
           direction=(0, 1, 0))
    m.group("box", "box")
    floor_box(m, (2.85, 0.0, 1.35), (3.35, 0.5, 1.85))
    _ = tc
    # room B's light: a 0.6 m square just below its ceiling, facing down
    m.group("light", "light")
    lx, lz, s2 = 1.3, -2.2, 0.3
    m.face([(lx - s2, H - 0.01, lz - s2), (lx + s2, H - 0.01, lz - s2),
            (lx + s2, H - 0.01, lz + s2), (lx - s2, H - 0.01, lz + s2)],
           direction=(0, -1, 0))
    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, (0.5, 1.5, 4.8), (2.6, 0.9, 0.0), 65.0,
               (0.0, 0.0, 0.0), 256, 192, 64, 10)
    print("%s: slit %.3f m wide" % (name, slit))
    return m


# ================================================================ 7. gap
def gap():
    """Path guiding's showcase: a dark receiving room A (z > 0; walls of
    albedo 0.2, a glossy dark floor) lit only through a vertical gap 12 cm
    wide in the wall it shares with a bright diffuse room B (z < 0, albedo
    0.8).  B's lamp hangs on the shared wall's B side, above and beside the
    gap, and faces away from it, into B: no point of A can see its emitting
    side, so next-event estimation from A finds nothing, and all of A's light
    arrives through the gap after at least one bounce in B, from a few
    hundredths of a steradian that BSDF sampling rarely finds."""
    name = "gap"
    m = Mesh(name)
    m.material("dark_wall", (0.2, 0.2, 0.19))
    m.material("dark_floor", (0.12, 0.1, 0.08), ks=(0.15, 0.15, 0.15), ns=80.0)
    m.material("bright", (0.8, 0.78, 0.72))
    m.material("box", (0.3, 0.12, 0.08))
    m.material("lamp", (0.0, 0.0, 0.0), ke=(4000.0, 3600.0, 3000.0))
    W, H, DA, DB = 4.0, 2.6, 5.0, 3.0
    g0, g1, gh = 2.0, 2.12, 2.1  # the gap: x from g0 to g1, floor to gh
    a_center = (W / 2, H / 2, DA / 2)
    b_center = (W / 2, H / 2, -DB / 2)

    box_room(m, W, H, "a", 0.0, DA, a_center, "dark_floor", "dark_wall")
    box_room(m, W, H, "b", -DB, 0.0, b_center, "bright", "bright")
    # the shared wall at z = 0 with the gap; each side faces its room
    wall_with_opening(m, W, H, g0, g1, gh,
                      (("a_shared", a_center, "dark_wall"),
                       ("b_shared", b_center, "bright")))
    # a box in room A, for shadows
    m.group("box", "box")
    floor_box(m, (0.7, 0.0, 1.7), (1.3, 0.6, 2.3))
    # B's lamp: 0.8 x 0.4 m on the shared wall's B side, 5 cm off it, facing
    # -z (into B, away from A), left of the gap and above it
    m.group("lamp", "lamp")
    zl = -0.05
    m.face([(0.6, 2.1, zl), (1.4, 2.1, zl), (1.4, 2.5, zl), (0.6, 2.5, zl)],
           direction=(0, 0, -1))
    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, (0.4, 1.4, 4.8), (2.4, 0.8, 0.0), 65.0,
               (0.0, 0.0, 0.0), 256, 192, 64, 10)
    return m


def write_png(path, width, height, pixels, channels):
    """An 8-bit PNG (RGB or RGBA); pixels is a row-major list of tuples of
    ints 0..255, row 0 at the top."""
    def chunk(kind, data):
        c = kind + data
        return (struct.pack(">I", len(data)) + c
                + struct.pack(">I", zlib.crc32(c) & 0xffffffff))

    color_type = {3: 2, 4: 6}[channels]
    raw = b"".join(b"\0" + bytes(v for p in pixels[y * width:(y + 1) * width]
                                   for v in p)
                   for y in range(height))
    data = (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8,
                                         color_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))
    with open(path, "wb") as fh:
        fh.write(data)


def write_exr_half(path, width, height, pixels):
    """A scanline OpenEXR file, uncompressed, channels B, G, R as half floats;
    pixels is a row-major list of (r, g, b), row 0 at the top."""
    def attr(name, kind, data):
        return (name.encode() + b"\0" + kind.encode() + b"\0"
                + struct.pack("<i", len(data)) + data)

    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1)
                      for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (struct.pack("<ii", 20000630, 2)
              + attr("channels", "chlist", chlist)
              + attr("compression", "compression", b"\0")
              + attr("dataWindow", "box2i", box)
              + attr("displayWindow", "box2i", box)
              + attr("lineOrder", "lineOrder", b"\0")
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
              + b"\0")
    line_bytes = 3 * 2 * width
    start = len(header) + 8 * height
    offsets = b"".join(struct.pack("<Q", start + y * (8 + line_bytes))
                       for y in range(height))
    body = []
    for y in range(height):
        row = pixels[y * width:(y + 1) * width]
        data = b"".join(struct.pack("<%de" % width, *[p[c] for p in row])
                        for c in (2, 1, 0))
        body.append(struct.pack("<ii", y, line_bytes) + data)
    with open(path, "wb") as fh:
        fh.write(header + offsets + b"".join(body))


# The sun of sun-sky: direction (elevation, azimuth from -z toward +x),
# angular radius, radiance.
SUN_ELEVATION, SUN_AZIMUTH = 35.0, 60.0
SUN_RADIUS_DEG = 1.5
SUN_RADIANCE = (1500.0, 1400.0, 1250.0)


def sky_map(width, height):
    """The lat-long sky of sun-sky (vrpt's convention, src/environment.rs:
    u = phi/2pi + 1/2 with phi = 0 toward -z and pi/2 toward +x, v = theta/pi
    from +y): a horizon-to-zenith gradient, a glow about the sun, a dim ground
    below the horizon, and the sun disc (its edge antialiased by 4x4
    supersamples per texel)."""
    e, a = math.radians(SUN_ELEVATION), math.radians(SUN_AZIMUTH)
    sun = (math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a))
    cos_r = math.cos(math.radians(SUN_RADIUS_DEG))

    def direction(u, v):
        phi, theta = 2 * math.pi * (u - 0.5), math.pi * v
        st = math.sin(theta)
        return (st * math.sin(phi), math.cos(theta), -st * math.cos(phi))

    px = []
    for y in range(height):
        for x in range(width):
            d = direction((x + 0.5) / width, (y + 0.5) / height)
            if d[1] > 0.0:
                t = math.sqrt(d[1])
                base = [0.45 + (0.12 - 0.45) * t, 0.5 + (0.25 - 0.5) * t,
                        0.55 + (0.6 - 0.55) * t]
                glow = 1.0 * math.exp(-math.acos(min(1.0, dot(d, sun))) / 0.15)
                c = [b + glow * w for b, w in zip(base, (1.0, 0.85, 0.6))]
            else:
                c = [0.12, 0.1, 0.08]
            inside = 0
            for j in range(4):
                for i in range(4):
                    q = direction((x + (i + 0.5) / 4) / width,
                                  (y + (j + 0.5) / 4) / height)
                    inside += dot(q, sun) >= cos_r
            if inside:
                c = [ci + s * inside / 16.0 for ci, s in zip(c, SUN_RADIANCE)]
            px.append(tuple(c))
    return px


def sun_sky():
    """Blocks and a thin fence on a grey ground, lit only by sky.exr."""
    name = "sun-sky"
    m = Mesh(name)
    m.material("ground", (0.5, 0.5, 0.5))
    m.material("stone", (0.7, 0.65, 0.6))
    m.material("paint", (0.15, 0.3, 0.6), ks=(0.2, 0.2, 0.2), ns=200.0)
    m.group("ground", "ground")
    m.face([(-40.0, 0.0, 20.0), (40.0, 0.0, 20.0), (40.0, 0.0, -60.0),
            (-40.0, 0.0, -60.0)], direction=(0, 1, 0))

    def block(gname, mat, x0, z0, sx, sz, h, y0=0.0):
        top = [(x0, h, z0), (x0 + sx, h, z0), (x0 + sx, h, z0 - sz),
               (x0, h, z0 - sz)]
        bottom = [(p[0], y0, p[2]) for p in top]
        center = centroid(top + bottom)
        m.group(gname, mat)
        m.face(list(top), away_from=center)
        for i in range(4):
            j = (i + 1) % 4
            m.face([bottom[i], bottom[j], top[j], top[i]], away_from=center)

    block("cube", "stone", -2.2, -3.0, 1.2, 1.2, 1.2)
    block("tower", "paint", 0.6, -4.5, 0.9, 0.9, 2.6)
    for k in range(7):
        block("post%d" % k, "stone", -1.0 + 0.45 * k, -1.6, 0.12, 0.12, 0.9)
    block("rail", "stone", -1.0, -1.6, 2.82, 0.12, 0.8, y0=0.7)

    folder = os.path.join(SCENES, name)
    m.write(folder)
    width, height = 256, 128
    exr = os.path.join(folder, "sky.exr")
    write_exr_half(exr, width, height, sky_map(width, height))
    assert os.path.getsize(exr) < 200 * 1024, exr
    write_toml(folder, name, (0.0, 2.2, 3.0), (0.0, 0.5, -3.0), 50.0,
               None, 128, 96, 16, 6,
               environment='map = "sky.exr"\nrotation = 0.0\nscale = 1.0')
    return m


def textured():
    """A checker floor, a bump-mapped brick wall, and a lattice fence cut
    out by its alpha channel standing in front of an area light, which throws
    the lattice's shadow onto the floor."""
    name = "textured"
    folder = os.path.join(SCENES, name)
    os.makedirs(folder, exist_ok=True)
    # the floor's checker: 2x2 squares per tile, sRGB
    n = 64
    write_png(os.path.join(folder, "checker.png"), n, n,
              [(200, 190, 170) if ((x * 2 // n) + (y * 2 // n)) % 2 == 0
               else (60, 70, 90) for y in range(n) for x in range(n)], 3)
    # bricks: 4 rows of 2 bricks per tile (offset by half a brick every other
    # row), 3-texel mortar; colour (sRGB) and height (mortar 0, brick 1)
    n = 128
    bricks, height = [], []
    for y in range(n):
        for x in range(n):
            row = y // (n // 4)
            bx = (x + (n // 4 if row % 2 else 0)) % (n // 2)
            mortar = y % (n // 4) < 3 or bx < 3
            shade = 150 + 40 * ((row * 7 + (x + (n // 4) * (row % 2)) // (n // 2) * 3) % 3) // 2
            bricks.append((185, 180, 170) if mortar else (shade, 70, 50))
            height.append((0, 0, 0) if mortar else (255, 255, 255))
    write_png(os.path.join(folder, "bricks.png"), n, n, bricks, 3)
    write_png(os.path.join(folder, "bricks-height.png"), n, n, height, 3)
    # the fence: a lattice of 8 x 8 bars, opaque on the bars, clear between
    n = 64
    fence = []
    for y in range(n):
        for x in range(n):
            bar = x % 8 < 2 or y % 8 < 2
            fence.append((90, 60, 40, 255) if bar else (90, 60, 40, 0))
    write_png(os.path.join(folder, "fence.png"), n, n, fence, 4)

    m = Mesh(name)
    m.material("floor", (1.0, 1.0, 1.0), maps=["map_Kd -s 5 5 checker.png"])
    m.material("wall", (1.0, 1.0, 1.0),
               maps=["map_Kd -s 3 1.5 bricks.png",
                     "bump -s 3 1.5 -bm 0.004 bricks-height.png"])
    m.material("fence", (1.0, 1.0, 1.0),
               maps=["map_Kd fence.png", "map_d fence.png"])
    m.material("light", (0.0, 0.0, 0.0), ke=(400.0, 360.0, 300.0))
    m.group("floor", "floor")
    m.face([(-5.0, 0.0, 3.0), (5.0, 0.0, 3.0), (5.0, 0.0, -5.0),
            (-5.0, 0.0, -5.0)], direction=(0, 1, 0),
           uvs=[(0, 0), (1, 0), (1, 1), (0, 1)])
    m.group("wall", "wall")
    m.face([(-5.0, 0.0, -5.0), (5.0, 0.0, -5.0), (5.0, 4.0, -5.0),
            (-5.0, 4.0, -5.0)], direction=(0, 0, 1),
           uvs=[(0, 0), (1, 0), (1, 1), (0, 1)])
    m.group("fence", "fence")
    m.face([(-1.5, 0.0, -2.0), (1.5, 0.0, -2.0), (1.5, 2.0, -2.0),
            (-1.5, 2.0, -2.0)], direction=(0, 0, 1),
           uvs=[(0, 0), (1.5, 0), (1.5, 1), (0, 1)])
    m.group("light", "light")
    c = (0.0, 3.2, -3.6)
    m.face([(c[0] - 0.15, c[1], c[2] - 0.15), (c[0] + 0.15, c[1], c[2] - 0.15),
            (c[0] + 0.15, c[1], c[2] + 0.15), (c[0] - 0.15, c[1], c[2] + 0.15)],
           direction=(0, -1, 0))
    m.write(folder)
    write_toml(folder, name, (0.0, 2.2, 4.5), (0.0, 0.9, -2.0), 50.0,
               (0.01, 0.01, 0.012), 128, 96, 16, 6)
    return m


README = """\
# vrpt test scenes

Generated by `tools/make_scenes.py` (committed output; regenerate with
`python3 tools/make_scenes.py` from the repository root, do not edit by hand).

- `cornell-box/`: the classic Cornell box (published measurements, mm) with a
  glossy tall box; the general-purpose test scene.
- `glossy-plates/`: Veach's plates scene, for importance sampling of glossy
  lobes (BSDF vs. light sampling, MIS): four plates of Phong exponent
  10..10000 reflecting four equal-power lights of increasing size.
- `checker-plane/`: an emissive checkerboard plane seen at a slant; a pure 2D
  pixel (antialiasing) integral with many edges, where stratification shows.
- `lit-checker/`: a diffuse checkerboard lit by one large, close area light;
  with `--lights nee` and max depth 2 each pixel is a 4D integral (pixel area
  x point on the light), where per-dimension strata stall and joint (Sobol)
  points do not.
- `night-hall/`: a 60 m hall lit by 160 lights (ceiling lamps, wall sconces,
  and cove strips on ledges that carry most of the power but face up, away
  from everything below them); the many-light scene, where choosing lights by power fails and the
  light tree (`--light-choice tree`) does not.
- `door/`: Veach's door: a dark room lit only through a door standing ajar
  from a brightly lit second room; next-event estimation almost never reaches
  the light and BSDF sampling rarely finds the slit. The path-guiding scene
  (`--directions guided`).
- `door-dark/`: the door with room A darkened (walls 0.25, floor Kd 0.15 /
  Ks 0.1): the light through the slit is then most of room A's light, not a
  share hidden under broad multi-bounce light that cosine sampling handles.
- `gap/`: path guiding's showcase: a dark room (albedo 0.2, a glossy dark
  floor) lit only through a 12 cm gap in the wall it shares with a bright
  diffuse room whose lamp faces away from the gap: next-event estimation
  finds nothing and BSDF sampling rarely finds the gap.
- `sun-sky/`: blocks, a tower and a fence on a grey ground under an HDR sky
  (`sky.exr`, 256x128 lat-long): a smooth sky and a 1.5-degree sun that
  carries most of the light. Environment-map importance sampling
  (`--light-points projected`, the default) against the cosine
  (`--light-points area`).
- `textured/`: textures from the MTL: a checker floor (`map_Kd -s 5 5`), a
  brick wall with `map_Kd` and a `bump` height map, and a lattice fence cut
  out by the alpha channel of its `map_d`, standing in front of an area
  light that throws the lattice's shadow onto the floor.
- `glass/`: smooth glass and a mirror from the MTL (`illum 7` with `Ni 1.5`,
  `illum 3`): a box lit by a small ceiling light, a glass sphere that throws a
  caustic onto the floor, and a mirror panel on the left wall. Light sampling
  cannot reach through glass, so the caustic comes from BSDF-sampled paths
  alone: the scene where guiding has most to learn.
- `lamp/`: a room lit only through glass: a ceiling lamp inside a hollow glass
  shade (2 cm walls, index 1.5) above two diffuse blocks. No light sample
  reaches through glass, so every lit path is a caustic (a diffuse bounce,
  then through the shade to the lamp) that BSDF sampling rarely finds: path
  guiding's caustic scene (`--directions guided`).
"""


def icosphere(level):
    """Unit icosphere vertices and triangles, subdivided `level` times."""
    t = (1.0 + 5.0 ** 0.5) / 2.0
    verts = [norm(v) for v in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0),
                               (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
                               (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11),
             (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8),
             (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9),
             (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                verts.append(norm(mul(add(verts[a], verts[b]), 0.5)))
                mid[key] = len(verts) - 1
            return mid[key]
        new = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


# ================================================================ glass
def glass_room_materials(m, light_ke):
    """The materials the glass and lamp scenes share: the white, red and green
    walls', the light's (emitting `light_ke`) and smooth glass of index 1.5."""
    m.material("white", (0.75, 0.75, 0.75))
    m.material("red", (0.63, 0.065, 0.05))
    m.material("green", (0.14, 0.45, 0.091))
    m.material("light", (0.0, 0.0, 0.0), ke=light_ke)
    # Tf is 1 - transmission (3ds Max's convention, the Cornell box files')
    m.material("glass", (0.0, 0.0, 0.0),
               maps=["Ni 1.5", "Tf 0 0 0", "illum 7"])


def write_glass_room(m, name, size):
    """Write the glass or lamp scene `name` (mesh `m`): the same camera at the
    room's open side, no environment, `size`² at 64 spp, depth 12."""
    folder = os.path.join(SCENES, name)
    m.write(folder)
    write_toml(folder, name, eye=(0.0, 1.0, 3.9), target=(0.0, 1.0, 0.0),
               fov=39.3, radiance=(0.0, 0.0, 0.0), width=size, height=size,
               spp=64, max_depth=12)


def glass_room_walls(m):
    """The glass and lamp scenes' room: a 2 m box from y = 0 to 2, open at
    z = +1 toward the camera, red on the left, green on the right."""
    centre = (0.0, 1.0, 0.0)
    m.group("floor", "white")
    m.face([(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], toward=centre)
    m.group("ceiling", "white")
    m.face([(-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)], toward=centre)
    m.group("back", "white")
    m.face([(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)], toward=centre)
    m.group("left", "red")
    m.face([(-1, 0, -1), (-1, 0, 1), (-1, 2, 1), (-1, 2, -1)], toward=centre)
    m.group("right", "green")
    m.face([(1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)], toward=centre)


def glass():
    """A box of diffuse walls lit by a small ceiling light, with a smooth glass
    sphere (index 1.5) that throws a caustic onto the floor, and a mirror on
    the left wall (MTL illum 7 with Tf and Ni, and illum 3): the scene of smooth
    dielectrics and mirrors, whose caustic only BSDF-sampled paths find."""
    name = "glass"
    m = Mesh(name)
    glass_room_materials(m, light_ke=(20.0, 18.0, 14.0))
    m.material("mirror", (0.0, 0.0, 0.0), ks=(0.9, 0.9, 0.9),
               maps=["illum 3"])
    glass_room_walls(m)
    m.group("light", "light")
    m.face([(-0.2, 1.99, -0.2), (0.2, 1.99, -0.2), (0.2, 1.99, 0.2),
            (-0.2, 1.99, 0.2)], direction=(0, -1, 0))
    # the mirror: a panel standing off the left wall, turned toward the camera
    m.group("mirror", "mirror")
    m.face([(-0.98, 0.3, -0.8), (-0.98, 0.3, 0.1), (-0.9, 1.5, 0.1),
            (-0.9, 1.5, -0.8)], direction=(1, 0, 0))
    m.group("sphere", "glass")
    r, c = 0.4, (0.25, 0.4, 0.1)
    verts, faces = icosphere(3)
    for f in faces:
        pts = [add(c, mul(verts[i], r)) for i in f]
        m.smooth_triangle(pts, [verts[i] for i in f])
    write_glass_room(m, name, size=256)
    return m


def lamp():
    """A room lit only through glass: a ceiling lamp inside a hollow glass
    shade (two nested boxes, 2 cm walls, index 1.5), two diffuse blocks on the
    floor.  No light sample reaches through glass, so next-event estimation
    finds nothing: every lit path is a caustic (diffuse, then through the
    shade to the lamp), found by BSDF sampling alone unless a guide learns the
    lamp's direction.  Path guiding's caustic scene."""
    name = "lamp"
    m = Mesh(name)
    glass_room_materials(m, light_ke=(25.0, 22.5, 17.5))
    glass_room_walls(m)

    def cuboid(lo, hi, outward):
        """The six faces of an axis-aligned box, their normals pointing out
        of it (outward) or into it."""
        c = centroid([lo, hi])
        for axis in range(3):
            for side in (lo, hi):
                pts = []
                for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = [0.0, 0.0, 0.0]
                    p[axis] = side[axis]
                    others = [i for i in range(3) if i != axis]
                    p[others[0]] = (lo, hi)[a][others[0]]
                    p[others[1]] = (lo, hi)[b][others[1]]
                    pts.append(tuple(p))
                if outward:
                    m.face(pts, away_from=c)
                else:
                    m.face(pts, toward=c)

    m.group("short_block", "white")
    cuboid((0.15, 0.0, -0.35), (0.65, 0.5, 0.15), True)
    m.group("tall_block", "white")
    cuboid((-0.65, 0.0, -0.75), (-0.2, 1.1, -0.3), True)
    # the shade: glass between an outer box (normals out) and an inner one
    # (normals into the hollow), so every face's normal leaves the glass
    m.group("shade", "glass")
    cuboid((-0.3, 1.6, -0.3), (0.3, 1.96, 0.3), True)
    cuboid((-0.28, 1.62, -0.28), (0.28, 1.94, 0.28), False)
    m.group("light", "light")
    m.face([(-0.18, 1.9, -0.18), (0.18, 1.9, -0.18), (0.18, 1.9, 0.18),
            (-0.18, 1.9, 0.18)], direction=(0, -1, 0))
    write_glass_room(m, name, size=128)
    return m


def main():
    os.makedirs(SCENES, exist_ok=True)
    counts = [("cornell-box", cornell_box()),
              ("glossy-plates", glossy_plates()),
              ("checker-plane", checker_plane()),
              ("lit-checker", lit_checker()),
              ("night-hall", night_hall()),
              ("door", door()),
              ("door-dark", door("door-dark", dark=True)),
              ("gap", gap()),
              ("sun-sky", sun_sky()),
              ("textured", textured()),
              ("glass", glass()),
              ("lamp", lamp())]
    with open(os.path.join(SCENES, "README.md"), "w") as fh:
        fh.write(README)
    for name, mesh in counts:
        print("%-14s %5d vertices %5d triangles"
              % (name, len(mesh.verts), mesh.triangle_count()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
