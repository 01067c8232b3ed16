#!/usr/bin/env python3
"""Write a large OBJ scene for vrpt's scale tests and benchmarks: many displaced, scaled copies
of an icosphere (level 5: 10,242 vertices, 20,480 triangles each, vertex normals), on a grid
over a ground plane, lit by one area light, with a scene.toml beside it.

    python3 tools/make_big_scene.py --triangles 10000000 --out /tmp/big10m

Every copy has its own vertices (nothing is shared between copies), so the file holds as many
vertices as a scanned scene of that size would. The output is deterministic.
"""
import argparse
import math
import os


def icosphere(level):
    t = (1.0 + 5.0 ** 0.5) / 2.0
    def norm(v):
        l = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return (v[0] / l, v[1] / l, v[2] / l)
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
                p, q = verts[a], verts[b]
                verts.append(norm(((p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2)))
                mid[key] = len(verts) - 1
            return mid[key]
        new = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--out", default="/tmp/big")
    a = ap.parse_args()
    verts, faces = icosphere(5)
    copies = max(1, round(a.triangles / len(faces)))
    side = math.ceil(math.sqrt(copies))
    os.makedirs(a.out, exist_ok=True)
    # the same displacement of the unit sphere for every copy: a bumpy blob
    bump = [1.0 + 0.15 * math.sin(7 * v[0]) * math.sin(5 * v[1] + 1) * math.sin(6 * v[2] + 2)
            for v in verts]
    shape_v = ["%.5f %.5f %.5f" % (v[0] * b, v[1] * b, v[2] * b) for v, b in zip(verts, bump)]
    shape_n = ["vn %.4f %.4f %.4f" % v for v in verts]
    n = len(verts)
    with open(os.path.join(a.out, "big.obj"), "w") as f:
        f.write("mtllib big.mtl\n")
        f.write("v -1e4 0 -1e4\nv -1e4 0 1e4\nv 1e4 0 1e4\nv 1e4 0 -1e4\n")
        f.write("v -20 %g -20\nv 20 %g -20\nv 20 %g 20\nv -20 %g 20\n" % ((4 * side,) * 4))
        f.write("usemtl ground\nf 1 2 3 4\nusemtl light\nf 5 6 7 8\nusemtl blob\n")
        base = 8
        normals = "\n".join(shape_n) + "\n"
        for k in range(copies):
            x, z = (k % side) * 3.0 - 1.5 * side, (k // side) * 3.0 - 1.5 * side
            s = 0.8 + 0.4 * ((k * 7919) % 100) / 100.0
            f.write("\n".join("v %.5f %.5f %.5f" % (float(p[0]) * s + x, float(p[1]) * s + s, float(p[2]) * s + z)
                              for p in (q.split() for q in shape_v)))
            f.write("\n")
            f.write(normals)
            f.write("\n".join("f %d//%d %d//%d %d//%d" % (base + i + 1, k * n + i + 1, base + j + 1, k * n + j + 1,
                                                         base + l + 1, k * n + l + 1)
                              for i, j, l in faces))
            f.write("\n")
            base += n
    with open(os.path.join(a.out, "big.mtl"), "w") as f:
        f.write("newmtl ground\nKd 0.5 0.5 0.5\nnewmtl blob\nKd 0.6 0.5 0.4\nKs 0.2 0.2 0.2\nNs 50\n"
                "newmtl light\nKd 0 0 0\nKe 5 5 5\n")
    c = 1.5 * side
    with open(os.path.join(a.out, "scene.toml"), "w") as f:
        f.write('obj = "big.obj"\n[camera]\neye = [%g, %g, %g]\ntarget = [0.0, 0.0, 0.0]\nfov = 45.0\n'
                "[environment]\nradiance = [0.2, 0.2, 0.25]\n" % (1.2 * c, 0.8 * c, 1.6 * c))
    print("%d copies, %d triangles" % (copies, copies * len(faces) + 2))


if __name__ == "__main__":
    main()
