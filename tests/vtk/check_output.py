#!/usr/bin/python3
"""check_output.py - read the engine's frames back with VTK's own reader and cross-check them.

Runs `mpm run SCENE -o TMP --frames N --quiet` for each scene given and then checks, frame by
frame, that what ParaView would load is what the engine computed:

  frames.pvd  parsed with xml.etree (VTK 9.1 has no PVD reader outside ParaView): one DataSet
              per frame, every file present, timesteps strictly increasing, one row per
              DataSet in stats.csv with the same frame number.
  frame_NNNN.vtu
              read with vtkXMLUnstructuredGridReader; any message the reader prints is a
              failure. Points = cells = stats.csv `particles`; every cell a VTK_VERTEX with
              the point of its own index; the arrays are exactly FieldData TIME (Float64) and
              PointData id (UInt32), velocity (3 comps), mass, volume, J, stress, plastic
              (the build's real, Float32 or Float64 as read from the Points) and material,
              body, level (the particle type: 0 .. domain.levels - 1), enrichment (Int32; -1
              for material points, 0-2 for domain particles), or, for a scene with
              output.fields (which must keep those), the ones it lists: cauchy_stress and F
              (9 comps), pressure (the real), checked for sigma symmetric, pressure = -tr
              sigma / 3, stress = the von Mises of sigma and J = det F. Values: TIME equals the PVD timestep and stats.csv time as written
              (%.9g or exact); all reals finite; mass, volume, J > 0; stress >= 0; ids unique
              and the same set in every frame; body indices 0..bodies-1, one material per body
              and, for bodies naming a material of the scene's list, that material's index.
  frame_NNNN.ply
              an independent writer (src/io/ply_points.c), parsed with the struct module:
              properties x y z vx vy vz pscale (the build's real) id (uint) material body
              (int); positions, velocities, ids, materials and bodies equal the VTU's exactly,
              particle by particle, and pscale is the radius of the sphere of the VTU's volume
              (1e-6 relative). Read again with VTK's own vtkPLYReader: the same point count and
              positions (rounded to float, which that reader makes them), nothing printed.
  stats.csv   sum(mass) within 1e-6 relative; 0.5 sum(m |v|^2) from the VTU arrays within
              1e-4 relative; sum(m v) within 1e-6 of sum(m |v|). With colliders: the row ends
              with collider<c>_fx, _fy, _fz per collider of the scene, finite, 0 in frame 0.
  grid_cells.vtu (scenes with domain.levels), and grid_cells_NNNN.vtu per frame (with
              domain.refine_every, also a "grid_cells" part of run.pvd)
              every cell a VTK_VOXEL of edge dx / 2^level with CellData level in
              1 .. levels - 1, inside the domain; their total volume is what the refine boxes
              of the scene cover (box rules only; cells overlapping a box, clipped to the
              domain).
  domains_NNNN.vtu (scenes with particle domains)
              every cell a VTK_HEXAHEDRON, one per domain particle, ids among the frame's;
              frame 0's hexahedra all of one positive volume by VTK's HexVolume (corner order);
              with output.fields, the optional arrays the frame file has (cauchy_stress,
              pressure, F) are CellData of the domains too, and every array beyond the
              domain file's own (id, J, material, body, enrichment) holds, per cell, exactly
              its particle's values in the frame file (matched by id).
  run.pvd     parsed with xml.etree: per timestep of frames.pvd, part 0 "particles" is that
              frame's VTU, part 1 "domains" its domains_NNNN.vtu exactly when the run wrote
              one, then one "surface_body<i>" part per surface_body<i>_NNNN.obj the run wrote,
              naming surface_body<i>_NNNN.vtp; nothing else. Every file it names exists and
              VTK's XML readers read it without a message (vtkXMLUnstructuredGridReader,
              vtkXMLPolyDataReader: a surface has triangles only, as many points and triangles
              as its OBJ, and the OBJ's positions within 1e-6 m).

Run with Debian's interpreter, which has python3-vtk9 (a pyenv `python3` on PATH has no vtk):

  /usr/bin/python3 tests/vtk/check_output.py --mpm build/mpm --frames 2 \
      examples/jello_cubes.json examples/snowball.json

Exit status: 0 when every check passes; 1 with one line naming the scene, file, frame and
array of the first mismatch (or a missing vtk module, or a failed run); 2 for usage errors.
"""
import argparse
import csv
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

try:
    from vtkmodules.vtkCommonCore import (VTK_DOUBLE, VTK_FLOAT, VTK_INT, VTK_UNSIGNED_INT,
                                          vtkLogger, vtkOutputWindow, vtkStringOutputWindow,
                                          vtkVersion)
    from vtkmodules.vtkCommonDataModel import VTK_HEXAHEDRON, VTK_VERTEX, VTK_VOXEL
    from vtkmodules.vtkFiltersVerdict import vtkMeshQuality
    from vtkmodules.vtkIOPLY import vtkPLYReader
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
except ImportError as e:
    print("check_output.py: FAIL: cannot import VTK in %s (%s); install it with "
          "`apt-get install python3-vtk9` and run this script with /usr/bin/python3"
          % (sys.executable, e), file=sys.stderr)
    sys.exit(1)

# VTK XML type names as the writer declares them -> the VTK type the reader must create.
VTK_TYPES = {"Float32": VTK_FLOAT, "Float64": VTK_DOUBLE, "UInt32": VTK_UNSIGNED_INT,
             "Int32": VTK_INT}
REAL = "real"  # placeholder for the build's real type, Float32 or Float64

# name -> (components, type), as src/io/vtu.c writes them
FIELD_ARRAYS = {"TIME": (1, "Float64")}
POINT_ARRAYS = {"id": (1, "UInt32"), "velocity": (3, REAL), "mass": (1, REAL),
                "volume": (1, REAL), "J": (1, REAL), "stress": (1, REAL),
                "plastic": (1, REAL), "material": (1, "Int32"), "body": (1, "Int32"),
                "level": (1, "Int32"), "enrichment": (1, "Int32")}
# what output.fields can add
OPTIONAL_ARRAYS = {"cauchy_stress": (9, REAL), "pressure": (1, REAL), "F": (9, REAL)}
# cauchy_stress against itself, relative to the frame's largest component: a float build's
# stress is P F^T with R of the SVD good to ~1e-7, which leaves 2 mu 1e-7 |F| of asymmetry
# (mu >> |sigma| for a body near rest), so 1e-3 in float; 1e-7 in double
TENSOR_RTOL = {"Float32": 1e-3, "Float64": 1e-7}
DET_RTOL = {"Float32": 1e-5, "Float64": 1e-12}
PLY_PROPERTIES = ["x", "y", "z", "vx", "vy", "vz", "pscale", "id", "material", "body"]
PLY_INTS = {"id": "uint", "material": "int", "body": "int"}
PLY_STRUCT = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i",
              "uint": "I", "float": "f", "double": "d", "int32": "i", "uint32": "I",
              "float32": "f", "float64": "d"}

MASS_RTOL = 1e-6
KINETIC_RTOL = 1e-4
MOMENTUM_RTOL = 1e-6


class Mismatch(Exception):
    """One failed check: where (scene, file, frame, array) and what."""

    def __init__(self, where, what):
        super().__init__("%s: %s" % (where, what))


class Where:
    """The location a message names: scene, file, frame, array."""

    def __init__(self, scene, path, frame=None):
        self.scene, self.path, self.frame = scene, path, frame

    def fail(self, array, what):
        parts = [self.scene, os.path.basename(self.path)]
        if self.frame is not None:
            parts.append("frame %d" % self.frame)
        if array:
            parts.append("array '%s'" % array)
        raise Mismatch(": ".join(parts), what)


def rel_close(a, b, rtol):
    return abs(a - b) <= rtol * max(abs(a), abs(b))


def same_as_written(text, value):
    """True when `text` (a %.9g or round-trip rendering) is what a writer prints for value."""
    t = float(text)
    return t == value or t == float("%.9g" % value)


# ---- the run ------------------------------------------------------------------------------

def run_scene(mpm, scene, outdir, frames):
    cmd = [mpm, "run", scene, "-o", outdir, "--frames", str(frames), "--quiet"]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if proc.returncode != 0:
        tail = "\n".join(proc.stdout.strip().splitlines()[-20:])
        raise Mismatch(scene, "`%s` exited with %d:\n%s" % (" ".join(cmd), proc.returncode, tail))


# ---- frames.pvd and stats.csv -------------------------------------------------------------

def read_pvd(where, path):
    """[(timestep text, file path)] of the Collection, in file order."""
    if not os.path.isfile(path):
        where.fail(None, "missing")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        where.fail(None, "not well-formed XML: %s" % e)
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        where.fail(None, "root is <%s type=%r>, expected <VTKFile type=\"Collection\">"
                   % (root.tag, root.get("type")))
    coll = root.find("Collection")
    if coll is None:
        where.fail(None, "no <Collection> element")
    entries = []
    for k, ds in enumerate(coll.findall("DataSet")):
        step, file = ds.get("timestep"), ds.get("file")
        if step is None or file is None:
            where.fail(None, "DataSet %d lacks timestep or file" % k)
        full = os.path.join(os.path.dirname(path), file)
        if not os.path.isfile(full):
            where.fail(None, "DataSet %d names '%s', which does not exist" % (k, file))
        if entries and not float(step) > float(entries[-1][0]):
            where.fail(None, "DataSet %d timestep %s does not increase (previous %s)"
                       % (k, step, entries[-1][0]))
        entries.append((step, full))
    return entries


def read_stats(where, path):
    """{frame: row dict with the text of every column}."""
    if not os.path.isfile(path):
        where.fail(None, "missing")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    need = {"frame", "time", "kinetic_energy", "momentum_x", "momentum_y", "momentum_z",
            "mass", "particles"}
    if not rows:
        where.fail(None, "no rows")
    missing = need - set(rows[0])
    if missing:
        where.fail(None, "header lacks %s" % ", ".join(sorted(missing)))
    return {int(r["frame"]): r for r in rows}


# ---- frame_NNNN.ply -----------------------------------------------------------------------

def read_ply(where, path):
    """(real type name 'float'/'double', comment time text or None, {property: values})."""
    if not os.path.isfile(path):
        where.fail(None, "missing")
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        where.fail(None, "not a PLY file (no 'ply' magic or 'end_header')")
    header = data[:end].decode("ascii").splitlines()
    body = data[end + len(b"end_header\n"):]
    if "format binary_little_endian 1.0" not in header:
        where.fail(None, "not binary_little_endian 1.0")
    count, props, comment_time, elements = None, [], None, 0
    for line in header[1:]:
        w = line.split()
        if w[0] == "element":
            elements += 1
            if w[1] != "vertex":
                where.fail(None, "unexpected element '%s'" % w[1])
            count = int(w[2])
        elif w[0] == "property":
            if w[1] == "list" or w[1] not in PLY_STRUCT:
                where.fail(None, "unsupported property '%s'" % line)
            props.append((w[2], w[1]))
        elif w[0] == "comment":
            m = re.search(r"time (\S+) s", line)
            comment_time = m.group(1) if m else comment_time
    if elements != 1 or count is None:
        where.fail(None, "expected exactly one 'element vertex'")
    names = [p[0] for p in props]
    if names != PLY_PROPERTIES:
        where.fail(None, "properties %s, expected %s" % (names, PLY_PROPERTIES))
    fmt = "<" + "".join(PLY_STRUCT[t] for _, t in props)
    size = struct.calcsize(fmt)
    if len(body) != count * size:
        where.fail(None, "%d bytes of vertex data, expected %d x %d" % (len(body), count, size))
    cols = list(zip(*struct.iter_unpack(fmt, body))) if count else [()] * len(props)
    real = props[0][1]
    if any(t != real for _, t in props[:7]) or real not in ("float", "double"):
        where.fail(None, "x..pscale are not all float or all double")
    for name, t in props[7:]:
        if t != PLY_INTS[name]:
            where.fail(name, "type %s, expected %s" % (t, PLY_INTS[name]))
    return real, comment_time, {n: list(c) for n, c in zip(names, cols)}


def read_ply_with_vtk(where, path, cols, messages):
    """VTK's own PLY reader takes the file: the same points, in order, and no message."""
    reader = vtkPLYReader()
    if not reader.CanReadFile(path):
        where.fail(None, "vtkPLYReader cannot read it: %s" % messages.new())
    reader.SetFileName(path)
    reader.Update()
    said = messages.new()
    if said:
        where.fail(None, "vtkPLYReader reported:\n%s" % said)
    poly = reader.GetOutput()
    n = len(cols["x"])
    if poly.GetNumberOfPoints() != n:
        where.fail("Points", "vtkPLYReader read %d points, the file has %d"
                   % (poly.GetNumberOfPoints(), n))
    if n:
        pts = values(poly.GetPoints().GetData())
        for k, axis in enumerate("xyz"):
            # vtkPLYReader makes float points: a double build's file is compared rounded
            want = cols[axis]
            if poly.GetPoints().GetDataType() == VTK_FLOAT:
                want = list(struct.unpack("<%df" % n, struct.pack("<%df" % n, *want)))
            i = first_difference(pts[k::3], want)
            if i is not None:
                where.fail("Points", "vtkPLYReader's point %d %s is %r, the file's %r"
                           % (i, axis, pts[3 * i + k], want[i]))


# ---- frame_NNNN.vtu -----------------------------------------------------------------------

class VtkMessages:
    """Collects everything VTK would print, so that any reader warning or error fails."""

    def __init__(self):
        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
        self.window = vtkStringOutputWindow()
        vtkOutputWindow.SetInstance(self.window)
        self.seen = 0

    def new(self):
        text = self.window.GetOutput() or ""
        fresh, self.seen = text[self.seen:], len(text)
        return "\n".join(line for line in fresh.splitlines() if line.strip())


def values(arr):
    """A VTK data array's values as a flat list of Python numbers (exact widening)."""
    mv = memoryview(arr)
    return mv.cast("B").cast(mv.format).tolist() if mv.ndim > 1 else mv.tolist()


def read_vtu(where, path, messages):
    if not os.path.isfile(path):
        where.fail(None, "missing")
    reader = vtkXMLUnstructuredGridReader()
    if not reader.CanReadFile(path):
        where.fail(None, "vtkXMLUnstructuredGridReader cannot read it: %s" % messages.new())
    reader.SetFileName(path)
    reader.Update()
    said = messages.new()
    if said:
        where.fail(None, "VTK reader reported:\n%s" % said)
    return reader.GetOutput()


def check_arrays(where, data, expected, real, n, kind):
    """Names, components, types and tuple counts of one attribute block; {name: array}."""
    got = {data.GetArrayName(i): data.GetAbstractArray(i)
           for i in range(data.GetNumberOfArrays())}
    if set(got) != set(expected):
        missing, extra = set(expected) - set(got), set(got) - set(expected)
        where.fail(None, "%s arrays are %s; missing %s, unexpected %s"
                   % (kind, sorted(got), sorted(missing) or "none", sorted(extra) or "none"))
    for name, (comps, type_name) in expected.items():
        a = got[name]
        type_name = real if type_name == REAL else type_name
        if a.GetNumberOfComponents() != comps:
            where.fail(name, "%d components, expected %d" % (a.GetNumberOfComponents(), comps))
        if a.GetDataType() != VTK_TYPES[type_name]:
            where.fail(name, "type %s, expected %s" % (a.GetDataTypeAsString(), type_name))
        if a.GetNumberOfTuples() != n:
            where.fail(name, "%d tuples, expected %d" % (a.GetNumberOfTuples(), n))
    return got


def check_tensors(where, pd, reals, ids, n, real):
    """cauchy_stress symmetric, pressure = -tr / 3, stress its von Mises; J = det F."""
    rtol = TENSOR_RTOL[real]
    if "cauchy_stress" in pd:
        sig = values(pd["cauchy_stress"])
        if not all(math.isfinite(y) for y in sig):
            where.fail("cauchy_stress", "a value is not finite")
        scale = rtol * max([abs(y) for y in sig] + [1e-30])
        for i in range(n):
            s = sig[9 * i:9 * i + 9]
            for a, b in ((1, 3), (2, 6), (5, 7)):
                if abs(s[a] - s[b]) > scale:
                    where.fail("cauchy_stress", "particle %d (id %d) is not symmetric: %r"
                               % (i, ids[i], s))
            mean = (s[0] + s[4] + s[8]) / 3
            dev = [s[k] - (mean if k in (0, 4, 8) else 0) for k in range(9)]
            vm = math.sqrt(1.5 * math.fsum(d * d for d in dev))
            if abs(vm - reals["stress"][i]) > scale:
                where.fail("stress", "particle %d (id %d): %r, the von Mises of cauchy_stress "
                           "is %r" % (i, ids[i], reals["stress"][i], vm))
            if "pressure" in pd and abs(pd["pressure"].GetValue(i) + mean) > scale:
                where.fail("pressure", "particle %d (id %d): %r, -tr(cauchy_stress)/3 is %r"
                           % (i, ids[i], pd["pressure"].GetValue(i), -mean))
    if "F" in pd:
        F = values(pd["F"])
        for i in range(n):
            a = F[9 * i:9 * i + 9]
            det = (a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
                   + a[2] * (a[3] * a[7] - a[4] * a[6]))
            if not rel_close(det, reals["J"][i], DET_RTOL[real]):
                where.fail("F", "particle %d (id %d): det F = %r, J is %r"
                           % (i, ids[i], det, reals["J"][i]))


def check_collider_columns(where, stats, colliders):
    """collider<c>_fx, _fy, _fz for every collider of the scene, finite, 0 in frame 0."""
    for c in range(colliders):
        for e in "xyz":
            name = "collider%d_f%s" % (c, e)
            for frame, row in sorted(stats.items()):
                if name not in row:
                    where.fail(None, "no column %s for collider %d" % (name, c))
                v = float(row[name])
                if not math.isfinite(v) or (frame == 0 and v != 0):
                    where.fail(None, "%s of frame %d is %r" % (name, frame, v))
    extra = [k for k in next(iter(stats.values())) if k.startswith("collider")]
    if len(extra) != 3 * colliders:
        where.fail(None, "%d collider columns, the scene has %d colliders"
                   % (len(extra), colliders))


def first_difference(a, b):
    for i, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return i
    return None if len(a) == len(b) else min(len(a), len(b))


def check_frame(where, grid, ply, pvd_step, stats, scene_info, real_seen):
    """Every check of one frame; returns (real type, sorted ids)."""
    n = grid.GetNumberOfPoints()
    particles = int(stats["particles"])
    if n != particles:
        where.fail("Points", "%d points, stats.csv says %d particles" % (n, particles))
    if grid.GetNumberOfCells() != particles:
        where.fail("types", "%d cells, stats.csv says %d particles"
                   % (grid.GetNumberOfCells(), particles))

    # the build's real type, from the Points, the same in every frame and in the PLY
    pts = grid.GetPoints().GetData()
    real = {VTK_FLOAT: "Float32", VTK_DOUBLE: "Float64"}.get(pts.GetDataType())
    if real is None:
        where.fail("Points", "type %s, expected Float32 or Float64" % pts.GetDataTypeAsString())
    if real_seen and real != real_seen:
        where.fail("Points", "type %s, but earlier frames are %s" % (real, real_seen))
    if pts.GetNumberOfComponents() != 3:
        where.fail("Points", "%d components, expected 3" % pts.GetNumberOfComponents())
    ply_real, ply_time, ply_cols = ply
    if {"float": "Float32", "double": "Float64"}[ply_real] != real:
        where.fail("Points", "type %s, but the PLY stores %s" % (real, ply_real))

    # cells: vertex i holds point i
    types = bytes(memoryview(grid.GetCellTypesArray()).cast("B"))
    if types != bytes([VTK_VERTEX]) * n:
        bad = next(i for i, t in enumerate(types) if t != VTK_VERTEX) if len(types) == n else -1
        where.fail("types", "cell %d is not VTK_VERTEX (%d)" % (bad, VTK_VERTEX))
    cells = grid.GetCells()
    if values(cells.GetConnectivityArray()) != list(range(n)):
        where.fail("connectivity", "vertex i does not hold point i")
    if values(cells.GetOffsetsArray()) != list(range(n + 1)):
        where.fail("offsets", "not 0, 1, ..., %d" % n)

    # arrays: names, components, types
    fd = check_arrays(where, grid.GetFieldData(), FIELD_ARRAYS, real, 1, "FieldData")
    expected = dict(POINT_ARRAYS)
    fields = scene_info[4] if scene_info is not None else None
    if fields is not None:
        if not set(POINT_ARRAYS) <= set(fields):
            where.fail(None, "check_output.py checks scenes whose output.fields keeps %s"
                       % sorted(POINT_ARRAYS))
        expected.update({k: v for k, v in OPTIONAL_ARRAYS.items() if k in fields})
    pd = check_arrays(where, grid.GetPointData(), expected, real, n, "PointData")
    active = grid.GetPointData().GetScalars(), grid.GetPointData().GetVectors()
    if active[0] is None or active[0].GetName() != "stress":
        where.fail("stress", "not the active scalars (PointData Scalars=\"stress\")")
    if active[1] is None or active[1].GetName() != "velocity":
        where.fail("velocity", "not the active vectors (PointData Vectors=\"velocity\")")

    # TIME = PVD timestep = stats.csv time (= PLY comment time)
    t = fd["TIME"].GetValue(0)
    for source, text in (("frames.pvd timestep", pvd_step), ("stats.csv time", stats["time"]),
                         ("PLY comment time", ply_time)):
        if text is not None and not same_as_written(text, t):
            where.fail("TIME", "%.17g, but %s is %s" % (t, source, text))

    x, v = values(pts), values(pd["velocity"])
    ids = values(pd["id"])
    m = values(pd["mass"])
    reals = {"Points": x, "velocity": v, "mass": m}
    for name in ("volume", "J", "stress", "plastic"):
        reals[name] = values(pd[name])
    for name, vals in reals.items():
        bad = next((i for i, y in enumerate(vals) if not math.isfinite(y)), None)
        if bad is not None:
            comps = 3 if name in ("Points", "velocity") else 1
            where.fail(name, "value %r of particle %d is not finite" % (vals[bad], bad // comps))
    for name, ok, rule in (("mass", lambda y: y > 0, "> 0"), ("volume", lambda y: y > 0, "> 0"),
                           ("J", lambda y: y > 0, "> 0"), ("stress", lambda y: y >= 0, ">= 0")):
        bad = next((i for i, y in enumerate(reals[name]) if not ok(y)), None)
        if bad is not None:
            where.fail(name, "particle %d (id %d) has %r, expected %s"
                       % (bad, ids[bad], reals[name][bad], rule))

    check_tensors(where, pd, reals, ids, n, real)

    # PLY (independent writer): the same floats, bit for bit, and the same ids
    for name, col, comps, k in (("Points", "x", 3, 0), ("Points", "y", 3, 1),
                                ("Points", "z", 3, 2), ("velocity", "vx", 3, 0),
                                ("velocity", "vy", 3, 1), ("velocity", "vz", 3, 2),
                                ("id", "id", 1, 0)):
        mine = (x if name == "Points" else v if name == "velocity" else ids)[k::comps]
        i = first_difference(mine, ply_cols[col])
        if i is not None:
            theirs = ply_cols[col][i] if i < len(ply_cols[col]) else "nothing"
            where.fail(name, "particle %d: VTU %s, PLY %s %s"
                       % (i, mine[i] if i < len(mine) else "nothing", col, theirs))

    mat, body = values(pd["material"]), values(pd["body"])
    for name, mine in (("material", mat), ("body", body)):
        i = first_difference(mine, ply_cols[name])
        if i is not None:
            where.fail(name, "particle %d: VTU %s, PLY %s" % (i, mine[i], ply_cols[name][i]))
    # pscale: the radius of the sphere of the particle's current volume
    for i, (vol, r) in enumerate(zip(reals["volume"], ply_cols["pscale"])):
        want = (3 * vol / (4 * math.pi)) ** (1 / 3)
        if not rel_close(r, want, 1e-6):
            where.fail("pscale", "particle %d: PLY pscale %r, the sphere of the VTU volume %r "
                       "has radius %r" % (i, r, vol, want))

    if len(set(ids)) != n:
        where.fail("id", "ids are not unique")

    # the particle type: a level of the scene's grid
    levels = scene_info[2] if scene_info is not None else None
    for i, q in enumerate(values(pd["level"])):
        if q < 0 or (levels is not None and q >= max(levels, 1)):
            where.fail("level", "particle %d has type %d, expected 0 .. %d"
                       % (i, q, max(levels or 1, 1) - 1))

    # the enrichment category: -1 (material point), 0, 1, 2 (Zhu sec. 5.2)
    for i, e in enumerate(values(pd["enrichment"])):
        if e not in (-1, 0, 1, 2):
            where.fail("enrichment", "particle %d has category %d, expected -1, 0, 1 or 2" % (i, e))

    # material and body against the scene
    if scene_info is not None:
        bodies, named = scene_info[0], scene_info[1]
        body_mat = {}
        for i, (b, mt) in enumerate(zip(body, mat)):
            if not 0 <= b < len(bodies):
                where.fail("body", "particle %d has body %d, the scene has %d"
                           % (i, b, len(bodies)))
            if body_mat.setdefault(b, mt) != mt:
                where.fail("material", "body %d has particles of materials %d and %d"
                           % (b, body_mat[b], mt))
        if len(body_mat) != len(bodies):
            where.fail("body", "bodies %s have no particles"
                       % sorted(set(range(len(bodies))) - set(body_mat)))
        for b, mt in body_mat.items():
            want = named.get(bodies[b].get("material")) if isinstance(
                bodies[b].get("material"), str) else None
            if want is not None and mt != want:
                where.fail("material", "body %d ('%s') has material %d, the scene's '%s' is %d"
                           % (b, bodies[b].get("name", ""), mt, bodies[b]["material"], want))
    elif any(y < 0 for y in mat + body):
        where.fail("material", "negative material or body index")

    # stats.csv: mass, kinetic energy, momentum, recomputed in double from the VTU arrays
    mass = math.fsum(m)
    ke = 0.5 * math.fsum(mi * (v[3 * i] ** 2 + v[3 * i + 1] ** 2 + v[3 * i + 2] ** 2)
                         for i, mi in enumerate(m))
    if not rel_close(mass, float(stats["mass"]), MASS_RTOL):
        where.fail("mass", "sum %.17g, stats.csv mass %s (rtol %g)" % (mass, stats["mass"],
                                                                         MASS_RTOL))
    if not rel_close(ke, float(stats["kinetic_energy"]), KINETIC_RTOL):
        where.fail("velocity", "0.5 sum m|v|^2 = %.9g, stats.csv kinetic_energy %s (rtol %g)"
                   % (ke, stats["kinetic_energy"], KINETIC_RTOL))
    scale = math.fsum(mi * math.sqrt(v[3 * i] ** 2 + v[3 * i + 1] ** 2 + v[3 * i + 2] ** 2)
                      for i, mi in enumerate(m))
    for d, axis in enumerate("xyz"):
        p = math.fsum(mi * v[3 * i + d] for i, mi in enumerate(m))
        if abs(p - float(stats["momentum_" + axis])) > MOMENTUM_RTOL * scale:
            where.fail("velocity", "sum m v_%s = %.17g, stats.csv momentum_%s %s (tol %g)"
                       % (axis, p, axis, stats["momentum_" + axis], MOMENTUM_RTOL * scale))
    return real, sorted(ids)


# ---- one scene ----------------------------------------------------------------------------

def scene_bodies(path):
    """(bodies, {material name: index}, domain.levels, domain) from the scene JSON, or None
    when it cannot be read."""
    try:
        with open(path) as f:
            s = json.load(f)
        bodies = s["bodies"]
        named = {mt["name"]: k for k, mt in enumerate(s.get("materials", []))
                 if isinstance(mt, dict) and "name" in mt}
        return (bodies, named, s["domain"].get("levels", 0), s["domain"],
                s.get("output", {}).get("fields"), len(s.get("colliders", []))) \
            if isinstance(bodies, list) else None
    except (OSError, ValueError, KeyError, TypeError):
        return None


def check_cells(where, path, domain, messages):
    """grid_cells.vtu: the leaves finer than level 0 as voxels of their level's size."""
    grid = read_vtu(where, path, messages)
    cells = grid.GetNumberOfCells()
    level = grid.GetCellData().GetArray("level")
    if cells == 0 or level is None or level.GetNumberOfTuples() != cells:
        where.fail("level", "expected one level per cell, and cells")
    levels, dx = domain["levels"], domain["dx"]
    lo, hi = domain["min"], domain["max"]
    volume = 0.0
    for c in range(cells):
        if grid.GetCellType(c) != VTK_VOXEL:
            where.fail("types", "cell %d has type %d, expected VTK_VOXEL (11)"
                       % (c, grid.GetCellType(c)))
        q = int(level.GetValue(c))
        if not 1 <= q < levels:
            where.fail("level", "cell %d has level %d, expected 1 .. %d" % (c, q, levels - 1))
        b = grid.GetCell(c).GetBounds()
        for d in range(3):
            if abs((b[2 * d + 1] - b[2 * d]) - dx / 2 ** q) > 1e-6:
                where.fail("Points", "cell %d of level %d has edge %r along axis %d, expected %r"
                           % (c, q, b[2 * d + 1] - b[2 * d], d, dx / 2 ** q))
            if b[2 * d] < lo[d] - 1e-6 or b[2 * d + 1] > hi[d] + 1e-6:
                where.fail("Points", "cell %d lies outside the domain" % c)
        volume += (dx / 2 ** q) ** 3
    rules = domain.get("refine", [])
    if rules and all("box" in r for r in rules) and len(rules) == 1:
        box = rules[0]["box"]
        want = 1.0
        for d in range(3):  # cells of the coarser level overlapping the clipped box
            c0 = dx / 2 ** (rules[0]["level"] - 1)
            a, e = max(box["min"][d], lo[d]), min(box["max"][d], hi[d])
            want *= (math.ceil((e - lo[d]) / c0 - 1e-5) - math.floor((a - lo[d]) / c0 + 1e-5)) * c0
        if not rel_close(volume, want, 1e-6):
            where.fail(None, "the leaves cover %r m^3, the refine box's cells %r" % (volume, want))
    return cells


DOMAIN_OWN_ARRAYS = {"id", "J", "material", "body", "enrichment"}


def check_domain_fields(where, grid, frame):
    """output.fields' arrays in domains_NNNN.vtu: every optional array the frame has (they are
    there only when output.fields lists them) is CellData of the domains too, and each cell's
    values are its particle's in the frame file, found by id."""
    pd, cd = frame.GetPointData(), grid.GetCellData()
    index = {v: i for i, v in enumerate(values(pd.GetArray("id")))} if pd.GetArray("id") else None
    names = [cd.GetArrayName(k) for k in range(cd.GetNumberOfArrays())]
    for name in OPTIONAL_ARRAYS:
        if pd.GetArray(name) is not None and name not in names:
            where.fail(name, "the frame file has it (output.fields) but the domains file does not")
    if index is None:
        return
    ids = values(cd.GetArray("id"))
    for name in names:
        if name in DOMAIN_OWN_ARRAYS:
            continue
        mine, theirs = cd.GetArray(name), pd.GetArray(name)
        if theirs is None:
            where.fail(name, "CellData the frame file does not have")
        comps = mine.GetNumberOfComponents()
        if comps != theirs.GetNumberOfComponents():
            where.fail(name, "%d components, the frame file's %d"
                       % (comps, theirs.GetNumberOfComponents()))
        for c, pid in enumerate(ids):
            i = index[pid]
            a = [mine.GetComponent(c, k) for k in range(comps)]
            b = [theirs.GetComponent(i, k) for k in range(comps)]
            if a != b:
                where.fail(name, "domain %d (id %d): %r, its particle's in the frame file %r"
                           % (c, pid, a, b))


def check_domains(where, path, frame_ids, first, messages, frame=None):
    """domains_NNNN.vtu: VTK_HEXAHEDRON cells over the corner points, one per domain particle,
    ids among the frame's; in frame 0 every hexahedron has the same positive volume (VTK's own
    HexVolume: a wrong corner order gives a negative or twisted one); output.fields' arrays as
    in the frame file (check_domain_fields)."""
    grid = read_vtu(where, path, messages)
    if frame is not None:
        check_domain_fields(where, grid, frame)
    cells = grid.GetNumberOfCells()
    if cells == 0:
        where.fail(None, "no domain cells")
    for c in range(cells):
        if grid.GetCellType(c) != VTK_HEXAHEDRON:
            where.fail("types", "cell %d has type %d, expected VTK_HEXAHEDRON (12)"
                       % (c, grid.GetCellType(c)))
    ids = values(grid.GetCellData().GetArray("id"))
    if not set(ids) <= frame_ids or len(set(ids)) != len(ids):
        where.fail("id", "domain ids are not unique ids of the frame's particles")
    enr = grid.GetCellData().GetArray("enrichment")
    if enr is None or not set(values(enr)) <= {0, 1, 2}:
        where.fail("enrichment", "expected an enrichment category 0, 1 or 2 per domain")
    if first:
        q = vtkMeshQuality()
        q.SetInputData(grid)
        q.SetHexQualityMeasureToVolume()
        q.Update()
        vol = values(q.GetOutput().GetCellData().GetArray("Quality"))
        lo, hi = min(vol), max(vol)
        if not (lo > 0 and hi - lo <= 1e-4 * hi):
            where.fail("connectivity", "hexahedron volumes %g..%g, expected one positive volume"
                       % (lo, hi))
    return cells


def read_obj(path):
    """(vertices [(x, y, z)], triangle count) of a surface OBJ as the engine writes it."""
    verts, tris = [], 0
    with open(path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                verts.append(tuple(float(c) for c in w[1:4]))
            elif w and w[0] == "f":
                tris += 1
    return verts, tris


def check_run_pvd(name, outdir, entries, messages):
    """run.pvd against frames.pvd and the files of the output folder; (parts, files read)."""
    path = os.path.join(outdir, "run.pvd")
    where = Where(name, path)
    if not os.path.isfile(path):
        where.fail(None, "missing")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        where.fail(None, "not well-formed XML: %s" % e)
    coll = root.find("Collection")
    if root.tag != "VTKFile" or root.get("type") != "Collection" or coll is None:
        where.fail(None, "not a VTKFile Collection")
    by_step = {}
    order = []
    for ds in coll.findall("DataSet"):
        step = ds.get("timestep")
        if step not in by_step:
            order.append(step)
        by_step.setdefault(step, []).append(ds)
    if order != [step for step, _ in entries]:
        where.fail(None, "timesteps %s, frames.pvd has %s" % (order, [s for s, _ in entries]))
    read, parts = 0, 0
    for k, (step, vtu) in enumerate(entries):
        want = [("particles", os.path.basename(vtu))]
        if os.path.exists(os.path.join(outdir, "domains_%04d.vtu" % k)):
            want.append(("domains", "domains_%04d.vtu" % k))
        for obj in sorted(os.listdir(outdir)):
            m = re.fullmatch(r"surface_body(\d+)_%04d\.obj" % k, obj)
            if m:
                want.append(("surface_body" + m.group(1), obj[:-4] + ".vtp"))
        if os.path.exists(os.path.join(outdir, "grid_cells_%04d.vtu" % k)):
            want.append(("grid_cells", "grid_cells_%04d.vtu" % k))
        got = [(ds.get("name"), ds.get("file")) for ds in by_step[step]]
        if got != want:
            where.fail(None, "timestep %s lists %s, expected %s" % (step, got, want))
        for p, ds in enumerate(by_step[step]):
            if ds.get("part") != str(p):
                where.fail(None, "timestep %s: %s has part %s, expected %d"
                           % (step, ds.get("file"), ds.get("part"), p))
        parts = max(parts, len(want))
        for part, file in want[1:]:
            full = os.path.join(outdir, file)
            fw = Where(name, full, k)
            if not os.path.isfile(full):
                fw.fail(None, "run.pvd names it, but it does not exist")
            if file.endswith(".vtu"):
                if read_vtu(fw, full, messages).GetNumberOfCells() == 0:
                    fw.fail(None, "no cells")
            else:
                reader = vtkXMLPolyDataReader()
                if not reader.CanReadFile(full):
                    fw.fail(None, "vtkXMLPolyDataReader cannot read it: %s" % messages.new())
                reader.SetFileName(full)
                reader.Update()
                said = messages.new()
                if said:
                    fw.fail(None, "VTK reader reported:\n%s" % said)
                poly = reader.GetOutput()
                verts, tris = read_obj(full[:-4] + ".obj")
                if (poly.GetNumberOfPoints(), poly.GetNumberOfPolys()) != (len(verts), tris):
                    fw.fail(None, "%d points, %d polygons; its OBJ has %d and %d"
                            % (poly.GetNumberOfPoints(), poly.GetNumberOfPolys(), len(verts),
                               tris))
                if poly.GetNumberOfCells() != tris or any(
                        poly.GetCell(c).GetNumberOfPoints() != 3 for c in range(tris)):
                    fw.fail(None, "cells other than triangles")
                pts = values(poly.GetPoints().GetData())
                for i, v in enumerate(verts):
                    if any(abs(pts[3 * i + d] - v[d]) > 1e-6 for d in range(3)):
                        fw.fail("Points", "vertex %d at %s, the OBJ's %s"
                                % (i, pts[3 * i:3 * i + 3], v))
            read += 1
    return parts, read


def check_scene(mpm, scene, outdir, frames, messages):
    name = os.path.splitext(os.path.basename(scene))[0]
    t0 = time.monotonic()
    run_scene(mpm, scene, outdir, frames)
    t1 = time.monotonic()
    entries = read_pvd(Where(name, "frames.pvd"), os.path.join(outdir, "frames.pvd"))
    stats = read_stats(Where(name, "stats.csv"), os.path.join(outdir, "stats.csv"))
    if len(entries) != frames + 1:
        Where(name, "frames.pvd").fail(None, "%d DataSets, expected %d (frame 0 and --frames %d)"
                                       % (len(entries), frames + 1, frames))
    if sorted(stats) != list(range(len(entries))):
        Where(name, "stats.csv").fail(None, "frames %s, expected 0..%d"
                                      % (sorted(stats), len(entries) - 1))
    info = scene_bodies(scene)
    if info is not None:
        check_collider_columns(Where(name, "stats.csv"), stats, info[5])
    real, ids0, n, domain_cells = None, None, 0, 0
    for k, (step, vtu) in enumerate(entries):
        m = re.fullmatch(r"frame_(\d+)\.vtu", os.path.basename(vtu))
        if not m or int(m.group(1)) != k:
            Where(name, "frames.pvd").fail(None, "DataSet %d is '%s', expected frame_%04d.vtu"
                                           % (k, os.path.basename(vtu), k))
        where = Where(name, vtu, k)
        grid = read_vtu(where, vtu, messages)
        ply_path = vtu[:-4] + ".ply"
        ply = read_ply(Where(name, ply_path, k), ply_path)
        read_ply_with_vtk(Where(name, ply_path, k), ply_path, ply[2], messages)
        real, ids = check_frame(where, grid, ply, step, stats[k], info, real)
        dom = os.path.join(outdir, "domains_%04d.vtu" % k)
        if os.path.exists(dom):
            domain_cells = check_domains(Where(name, dom, k), dom, set(ids), k == 0, messages,
                                         grid)
        cells_k = os.path.join(outdir, "grid_cells_%04d.vtu" % k)
        if os.path.exists(cells_k):  # a grid rebuilt during the run: its tree per frame
            check_cells(Where(name, cells_k, k), cells_k, info[3], messages)
        resampled = info is not None and "resample" in info[3]
        if len(ids) != len(set(ids)):
            where.fail("id", "an id appears twice")
        if ids0 is not None and ids != ids0 and not resampled:
            where.fail("id", "the set of ids differs from frame 0's")
        ids0, n = ids, len(ids)
    cells_path = os.path.join(outdir, "grid_cells.vtu")
    grid_cells = 0
    if info is not None and info[2]:
        if not os.path.exists(cells_path):
            Where(name, "grid_cells.vtu").fail(None, "missing for a scene with domain.levels")
        grid_cells = check_cells(Where(name, "grid_cells.vtu"), cells_path, info[3], messages)
    parts, extra = check_run_pvd(name, outdir, entries, messages)
    t2 = time.monotonic()
    bodies = "%d bodies" % len(info[0]) if info else "bodies not checked (scene unreadable)"
    domains = ", %d domain hexahedra" % domain_cells if domain_cells else ""
    domains += ", %d grid cells finer than level 0" % grid_cells if grid_cells else ""
    print("%s: %d frames x %d particles%s, %s, %s, run.pvd %d parts (%d more files read); "
          "run %.1f s, check %.1f s: ok"
          % (name, len(entries), n, domains, real, bodies, parts, extra, t1 - t0, t2 - t1))
    return len(entries)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mpm", required=True, help="the mpm program (build/mpm)")
    ap.add_argument("--frames", type=int, default=2, help="frames to run per scene (default 2)")
    ap.add_argument("--keep", metavar="DIR",
                    help="write each scene's output to DIR/<scene> and keep it")
    ap.add_argument("scenes", nargs="+", help="scene JSON files")
    args = ap.parse_args()
    if args.frames < 1:
        ap.error("--frames must be >= 1")
    mpm = os.path.abspath(args.mpm)
    if not os.access(mpm, os.X_OK):
        ap.error("--mpm %s is not an executable" % args.mpm)

    messages = VtkMessages()
    base = args.keep or tempfile.mkdtemp(prefix="mpm-vtk-check-")
    total = 0
    try:
        for scene in args.scenes:
            out = os.path.join(base, os.path.splitext(os.path.basename(scene))[0])
            if os.path.isdir(out):
                shutil.rmtree(out)
            total += check_scene(mpm, scene, out, args.frames, messages)
    except Mismatch as e:
        print("check_output.py: FAIL: %s" % e, file=sys.stderr)
        if args.keep:
            print("check_output.py: output kept in %s" % base, file=sys.stderr)
        return 1
    finally:
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)
    print("vtk_reader_check: %d scenes, %d frames read back with VTK %s: all checks passed"
          % (len(args.scenes), total, vtkVersion.GetVTKVersion()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
