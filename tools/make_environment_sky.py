#!/usr/bin/env python3
"""Writes scenes/environment-map/sky.hdr: a 64 x 32 latitude-longitude sky in Radiance RGBE
(uncompressed scanlines), small enough to commit. Row 0 is the top of the image, the +y pole
(Tungsten's InfiniteSphere). The sky brightens towards the zenith, the lower half is a dim brown
ground, and a sun of 3 x 2 texels (radiance 1000) stands about 43 degrees above the horizon:
a peaky map for importance sampling.

Usage: python3 tools/make_environment_sky.py [output path]
"""
import math
import sys

W, H = 64, 32


def texel(x, y):
    if 40 <= x < 43 and 8 <= y < 10:
        return (1000.0, 1000.0, 1000.0)
    if y >= H // 2:
        return (0.10, 0.08, 0.05)
    elevation = 1.0 - (y + 0.5) / (H // 2)  # 1 at the zenith row, about 0 at the horizon
    return (0.25 + 0.35 * elevation, 0.35 + 0.45 * elevation, 0.6 + 0.6 * elevation)


def rgbe(rgb):
    m = max(rgb)
    if m < 1e-32:
        return bytes((0, 0, 0, 0))
    f, e = math.frexp(m)  # m = f 2^e, f in [0.5, 1)
    scale = f * 256.0 / m
    return bytes(tuple(min(255, int(c * scale)) for c in rgb) + (e + 128,))


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "scenes/environment-map/sky.hdr"
    with open(path, "wb") as out:
        out.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        out.write(f"-Y {H} +X {W}\n".encode())
        for y in range(H):
            out.write(b"".join(rgbe(texel(x, y)) for x in range(W)))


if __name__ == "__main__":
    main()
