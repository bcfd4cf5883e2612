#!/usr/bin/env python3
"""Writes the example edit maps of scenes/drape-edits.json into examples/edits/
(standard library only): a printed logo (colour map and its mask) and a faded,
worn stripe (a pale colour and a flattened heightfield, both through one grey
mask with soft edges). Maps cover the cloth's UV square, top row
at v = 1. Usage: scripts/make_edit_maps.py [OUT_DIR]"""
import math
import os
import struct
import sys
import zlib

N = 256


def write_png(path, rows, channels):
    """rows: list of lists of 0..255 ints (channels values per pixel)."""
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    colour = {1: 0, 3: 2}[channels]
    raw = b"".join(b"\0" + bytes(r) for r in rows)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", N, N, 8, colour, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)


def smooth(a, b, x):
    t = min(1.0, max(0.0, (x - a) / (b - a)))
    return t * t * (3 - 2 * t)


def logo(u, v):
    """A round badge: a red disc with a white ring and a white diamond; returns (rgb, coverage)."""
    cu, cv, r = 0.45, 0.24, 0.13
    d = math.hypot(u - cu, v - cv)
    cover = 1 - smooth(r - 0.006, r, d)
    ring = smooth(0.70 * r, 0.72 * r, d) * (1 - smooth(0.80 * r, 0.82 * r, d))
    diamond = 1 - smooth(0.40 * r, 0.42 * r, abs(u - cu) + abs(v - cv))
    white = max(ring, diamond)
    red = (0.72, 0.08, 0.10)
    return [red[i] * (1 - white) + 0.92 * white for i in range(3)], cover


def stripe(u, v):
    """A band across the cloth along u, 0.12 UV wide around v = 0.07, soft edges."""
    return 1 - smooth(0.04, 0.08, abs(v - 0.07))


def srgb(x):
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "examples", "edits")
    os.makedirs(out, exist_ok=True)
    logo_rgb, logo_mask, stripe_mask = [], [], []
    for y in range(N):
        v = 1 - (y + 0.5) / N
        a, b, c = [], [], []
        for x in range(N):
            u = (x + 0.5) / N
            rgb, cover = logo(u, v)
            a += [round(255 * srgb(ch)) for ch in rgb]
            b.append(round(255 * cover))
            c.append(round(255 * stripe(u, v)))
        logo_rgb.append(a), logo_mask.append(b), stripe_mask.append(c)
    write_png(os.path.join(out, "logo.png"), logo_rgb, 3)
    write_png(os.path.join(out, "logo_mask.png"), logo_mask, 1)
    write_png(os.path.join(out, "stripe_mask.png"), stripe_mask, 1)
    pale = [round(255 * srgb(ch)) for ch in (0.62, 0.60, 0.52)]
    write_png(os.path.join(out, "stripe_colour.png"), [pale * N for _ in range(N)], 3)
    write_png(os.path.join(out, "stripe_height.png"), [[round(255 * 0.3)] * N for _ in range(N)], 1)


if __name__ == "__main__":
    main()
