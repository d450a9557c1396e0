#!/usr/bin/python3
"""surface_deviation.py - how far one run's embedded surface is from another's, frame by frame.

    tools/surface_deviation.py RUN_A RUN_B BODY FRAME [FRAME ...]

Reads RUN_A/surface_body<BODY>_NNNN.obj and the same file of RUN_B (the same mesh, the same
vertex order), aligns their centroids and prints the rms and largest vertex distance. Used for
examples/ball_bunny.json against the same scene without the ball: how much of the impact's
deformation is left. Plain Python, no third-party modules.
"""
import math
import sys


def load(path):
    with open(path) as f:
        return [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]


def main():
    if len(sys.argv) < 5:
        print(__doc__.strip().split("\n")[2].strip(), file=sys.stderr)
        return 2
    a, b, body = sys.argv[1], sys.argv[2], int(sys.argv[3])
    for frame in map(int, sys.argv[4:]):
        name = "surface_body%d_%04d.obj" % (body, frame)
        x, y = load("%s/%s" % (a, name)), load("%s/%s" % (b, name))
        if len(x) != len(y) or not x:
            print("%s: %d and %d vertices" % (name, len(x), len(y)), file=sys.stderr)
            return 1
        n = len(x)
        cx = [sum(p[k] for p in x) / n for k in range(3)]
        cy = [sum(p[k] for p in y) / n for k in range(3)]
        d = [math.dist([p[k] - cx[k] for k in range(3)], [q[k] - cy[k] for k in range(3)])
             for p, q in zip(x, y)]
        print("frame %d: rms %.2f mm, max %.2f mm, centroids %.1f mm apart"
              % (frame, 1000 * math.sqrt(sum(e * e for e in d) / n), 1000 * max(d),
                 1000 * math.dist(cx, cy)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
