#!/usr/bin/env python3
"""Writes the block means of a float EXR as a text table (tests/data/*_blocks.txt).

    make_block_means.py REF.exr BLOCK_PIXELS OUT.txt "note"

Reads the image with OpenImageIO's oiiotool (--dumpdata), averages R, G, B over square blocks of
BLOCK_PIXELS x BLOCK_PIXELS pixels (row-major blocks, top row first, as Telescope's films) and
writes one line per block: bx by R G B (%.9g). Lines starting with # are comments.
"""
import re
import subprocess
import sys


def main():
    path, block, out, note = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
    lines = subprocess.run(["oiiotool", "--dumpdata", path], capture_output=True, text=True, check=True).stdout.splitlines()
    w, h = map(int, re.search(r":\s+(\d+) x\s+(\d+),", lines[0]).groups())
    px = [list(map(float, l.split(":", 1)[1].split()[:3])) for l in lines[1:] if "Pixel" in l]
    assert len(px) == w * h and w % block == 0 and h % block == 0
    with open(out, "w") as f:
        f.write(f"# {note}\n# made by tests/data/make_block_means.py from a {w}x{h} image, blocks of {block}x{block} pixels\n")
        f.write(f"# blocks {w // block} {h // block}\n# bx by R G B (block means, linear radiance)\n")
        for by in range(h // block):
            for bx in range(w // block):
                s = [0.0, 0.0, 0.0]
                for y in range(by * block, (by + 1) * block):
                    for x in range(bx * block, (bx + 1) * block):
                        for c in range(3):
                            s[c] += px[y * w + x][c]
                n = block * block
                f.write(f"{bx} {by} {s[0] / n:.9g} {s[1] / n:.9g} {s[2] / n:.9g}\n")


if __name__ == "__main__":
    main()
