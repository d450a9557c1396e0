#!/usr/bin/python3
"""neighbour_gap.py - the largest distance, in a late frame, between particles that started as
lattice neighbours (numerical fracture opens it far beyond the stretch).

    /usr/bin/python3 tools/neighbour_gap.py OUTDIR FRAME SPACING

SPACING is the bodies' lattice spacing h = dx / cbrt(particles_per_cell), m. Particles are
matched by id between frame 0 and FRAME. Used for examples/bar_stretch.json with and without
particle domains. Needs Debian's python3-vtk9 (run with /usr/bin/python3).
"""
import math
import sys

from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


def positions(path):
    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    ids = g.GetPointData().GetArray("id")
    return {ids.GetValue(i): g.GetPoints().GetPoint(i) for i in range(g.GetNumberOfPoints())}


def main():
    if len(sys.argv) != 4:
        print(__doc__.strip().split("\n")[3].strip(), file=sys.stderr)
        return 2
    out, frame, h = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    x0 = positions("%s/frame_0000.vtu" % out)
    x1 = positions("%s/frame_%04d.vtu" % (out, frame))
    # neighbours through a hash of lattice cells
    cells = {}
    for i, p in x0.items():
        cells.setdefault(tuple(int(math.floor(c / h)) for c in p), []).append(i)
    worst, pairs = 0.0, 0
    for key, members in cells.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for j in cells.get((key[0] + dx, key[1] + dy, key[2] + dz), []):
                        for i in members:
                            if i < j and math.dist(x0[i], x0[j]) < 1.01 * h:
                                pairs += 1
                                worst = max(worst, math.dist(x1[i], x1[j]))
    xs = [p[0] for p in x1.values()]
    print("%s frame %d: %d particles, %d neighbour pairs, x extent %.3f m, largest gap %.4f m "
          "= %.1f spacings" % (out, frame, len(x1), pairs, max(xs) - min(xs), worst, worst / h))
    return 0


if __name__ == "__main__":
    sys.exit(main())
