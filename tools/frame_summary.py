#!/usr/bin/python3
"""frame_summary.py - extent and J range of every particle in each frame of a run (VTK reader).

    /usr/bin/python3 tools/frame_summary.py OUTDIR LAST_FRAME [EVERY]

Prints, per frame, the particles' extent along x, y, z (cm) and the smallest and largest J.
Used for examples/tunnel_squeeze.json: how far the ball is squeezed and whether it comes
back. Needs Debian's python3-vtk9 (run with /usr/bin/python3).
"""
import sys

from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


def main():
    if len(sys.argv) < 3:
        print(__doc__.strip().split("\n")[2].strip(), file=sys.stderr)
        return 2
    out, last = sys.argv[1], int(sys.argv[2])
    every = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    least_width, least_J = float("inf"), float("inf")
    for f in range(0, last + 1):
        r = vtkXMLUnstructuredGridReader()
        r.SetFileName("%s/frame_%04d.vtu" % (out, f))
        r.Update()
        g = r.GetOutput()
        pts, J = g.GetPoints(), g.GetPointData().GetArray("J")
        n = g.GetNumberOfPoints()
        lo, hi = [float("inf")] * 3, [-float("inf")] * 3
        jl, jh = float("inf"), -float("inf")
        for i in range(n):
            p = pts.GetPoint(i)
            lo = [min(lo[k], p[k]) for k in range(3)]
            hi = [max(hi[k], p[k]) for k in range(3)]
            j = J.GetValue(i)
            jl, jh = min(jl, j), max(jh, j)
        least_width, least_J = min(least_width, hi[0] - lo[0]), min(least_J, jl)
        if f % every == 0 or f == last:
            print("frame %3d: extent %5.1f x %5.1f x %5.1f cm, J %.3f .. %.3f"
                  % (f, *(100 * (hi[k] - lo[k]) for k in range(3)), jl, jh))
    print("smallest x extent %.1f cm, smallest J %.3f" % (100 * least_width, least_J))
    return 0


if __name__ == "__main__":
    sys.exit(main())
