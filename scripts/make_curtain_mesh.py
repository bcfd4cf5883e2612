#!/usr/bin/env python3
"""Writes scenes/meshes/curtain.obj (standard library only), the hanging sheet of
scenes/curtain-window.json: a curtain 600 mm wide and 800 mm high in the xy plane
(its top edge at y = 800, x centred on 0), gathered into six pleats along x,
z = A(y) sin(2 pi x / 100 mm), the pleats' depth A growing from 12 mm at the top
to 24 mm at the hem. UVs are millimetres / 1000 of fabric: u the arc length
along each row from the left edge, v the height, so the scene's uv_mm is 1000
and the yarns keep their density over the folds. Usage:
scripts/make_curtain_mesh.py [OUT.obj]"""
import math
import sys

W, H, WAVE = 600.0, 800.0, 100.0
NX, NY = 120, 8


def depth(y):
    return 24.0 - 12.0 * y / H


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/meshes/curtain.obj"
    lines = ["# scripts/make_curtain_mesh.py: a pleated curtain, %g x %g mm, %d x %d cells" % (W, H, NX, NY)]
    uvs = []
    for j in range(NY + 1):
        y = H * j / NY
        a, k = depth(y), 2 * math.pi / WAVE
        s, px, pz = 0.0, None, None
        for i in range(NX + 1):
            x = -W / 2 + W * i / NX
            z = a * math.sin(k * x)
            if px is not None:
                s += math.hypot(x - px, z - pz)
            px, pz = x, z
            lines.append("v %.4f %.4f %.4f" % (x, y, z))
            uvs.append("vt %.6f %.6f" % (s / 1000.0, y / 1000.0))
    lines += uvs
    for j in range(NY):
        for i in range(NX):
            a = j * (NX + 1) + i + 1
            b, c, d = a + 1, a + NX + 2, a + NX + 1
            lines.append("f %d/%d %d/%d %d/%d" % (a, a, b, b, c, c))
            lines.append("f %d/%d %d/%d %d/%d" % (a, a, c, c, d, d))
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
