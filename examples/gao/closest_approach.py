#!/usr/bin/python3
"""closest_approach.py DIR: the closest approach between the particles of body 0 and body 1 of a
run (its frame_NNNN.vtu files), frame by frame with VTK's k-d tree point locator; prints the
least distance over the frames and its frame. Run with Debian's /usr/bin/python3 (python3-vtk9):

    /usr/bin/python3 examples/gao/closest_approach.py out/jello_collision_adaptive
"""
import sys, glob, os
import vtk
best = (1e9, -1)
for path in sorted(glob.glob(os.path.join(sys.argv[1], "frame_*.vtu"))):
    r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(path); r.Update(); g = r.GetOutput()
    body = g.GetPointData().GetArray("body")
    a = vtk.vtkPoints(); bpts = []
    for i in range(g.GetNumberOfPoints()):
        if body.GetValue(i) == 1: a.InsertNextPoint(g.GetPoint(i))
        else: bpts.append(i)
    pd = vtk.vtkPolyData(); pd.SetPoints(a)
    loc = vtk.vtkKdTreePointLocator(); loc.SetDataSet(pd); loc.BuildLocator()
    m = 1e9
    for i in bpts:
        x = g.GetPoint(i)
        j = loc.FindClosestPoint(x)
        y = a.GetPoint(j)
        d = ((x[0]-y[0])**2 + (x[1]-y[1])**2 + (x[2]-y[2])**2) ** 0.5
        if d < m: m = d
    k = int(os.path.basename(path)[6:10])
    if m < best[0]: best = (m, k)
print("closest approach %.5f m at frame %d" % best)
