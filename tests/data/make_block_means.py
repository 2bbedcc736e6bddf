#!/usr/bin/env python3
"""Writes the block means of a float EXR as a text table (tests/data/*_blocks.txt).

    make_block_means.py REF.exr BLOCK_PIXELS OUT.txt "note" [--drop-events]

Reads the image with OpenImageIO's oiiotool (--dumpdata), averages R, G, B over square blocks of
BLOCK_PIXELS x BLOCK_PIXELS pixels (row-major blocks, top row first, as Telescope's films) and
writes one line per block: bx by R G B (%.9g). Lines starting with # are comments.

--drop-events leaves out of the block means the pixels that hold a rare event: a pixel whose
R + G + B is above 10 times each of its (up to 8) neighbours' and above 10 times the image mean
(tests/tungsten_scenes_test.cpp applies the same rule to its renders: isolatedEvents). In a path
traced render of a scene whose light is tiny and seen through a dielectric, such a pixel is one
camera sample that hit the light through the specular chain (radiance ~1e6 / spp); the events are
listed as comments ("# event x y R+G+B") and each block line then averages its other pixels.
"""
import re
import subprocess
import sys

EVENT_NEIGHBOUR_FACTOR = 10.0
EVENT_MEAN_FACTOR = 10.0


def isolated_events(px, w, h):
    """Indices of the pixels (R + G + B in px) that the rule above calls events."""
    mean = sum(px) / len(px)
    out = []
    for y in range(h):
        for x in range(w):
            v = px[y * w + x]
            if not v > EVENT_MEAN_FACTOR * mean:
                continue
            nb = max(px[j * w + i] for j in range(max(y - 1, 0), min(y + 2, h))
                     for i in range(max(x - 1, 0), min(x + 2, w)) if (i, j) != (x, y))
            if v > EVENT_NEIGHBOUR_FACTOR * nb:
                out.append(y * w + x)
    return out


def main():
    args = [a for a in sys.argv[1:] if a != "--drop-events"]
    drop = len(args) != len(sys.argv) - 1
    path, block, out, note = args[0], int(args[1]), args[2], args[3]
    lines = subprocess.run(["oiiotool", "--dumpdata", path], capture_output=True, text=True, check=True).stdout.splitlines()
    w, h = map(int, re.search(r":\s+(\d+) x\s+(\d+),", lines[0]).groups())
    px = [list(map(float, l.split(":", 1)[1].split()[:3])) for l in lines[1:] if "Pixel" in l]
    assert len(px) == w * h and w % block == 0 and h % block == 0
    events = set(isolated_events([sum(p) for p in px], w, h)) if drop else set()
    with open(out, "w") as f:
        f.write(f"# {note}\n# made by tests/data/make_block_means.py from a {w}x{h} image, blocks of {block}x{block} pixels\n")
        if drop:
            f.write(f"# --drop-events: {len(events)} isolated event pixels left out of the block means:\n")
            for i in sorted(events):
                f.write(f"# event {i % w} {i // w} {sum(px[i]):.6g}\n")
        f.write(f"# blocks {w // block} {h // block}\n# bx by R G B (block means, linear radiance)\n")
        for by in range(h // block):
            for bx in range(w // block):
                s = [0.0, 0.0, 0.0]
                n = 0
                for y in range(by * block, (by + 1) * block):
                    for x in range(bx * block, (bx + 1) * block):
                        if y * w + x in events:
                            continue
                        n += 1
                        for c in range(3):
                            s[c] += px[y * w + x][c]
                f.write(f"{bx} {by} {s[0] / n:.9g} {s[1] / n:.9g} {s[2] / n:.9g}\n")


if __name__ == "__main__":
    main()
