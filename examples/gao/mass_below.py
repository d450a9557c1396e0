#!/usr/bin/python3
"""mass_below.py DIR HEIGHT [FRAME]: the share of a run's mass below y = HEIGHT in its last frame
(or frame FRAME)
(frame_NNNN.vtu, the `mass` point array), e.g. the goo pressed through the slits of
goo_slits*.json (the table's underside is at y = 0.28) or cut through by the wires of
goo_wires*.json (below y = 0.394). Run with Debian's /usr/bin/python3 (python3-vtk9):

    /usr/bin/python3 examples/gao/mass_below.py out/goo_slits_adaptive 0.28
"""
import glob
import os
import sys

import vtk

frames = sorted(glob.glob(os.path.join(sys.argv[1], "frame_*.vtu")))
path = frames[-1] if len(sys.argv) < 4 else os.path.join(sys.argv[1], "frame_%04d.vtu" % int(sys.argv[3]))
height = float(sys.argv[2])
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(path)
r.Update()
g = r.GetOutput()
mass = g.GetPointData().GetArray("mass")
below = total = 0.0
for i in range(g.GetNumberOfPoints()):
    m = mass.GetValue(i)
    total += m
    if g.GetPoint(i)[1] < height:
        below += m
print("%s: %.1f%% of %.4g kg below y = %g" % (os.path.basename(path), 100 * below / total, total,
                                             height))
