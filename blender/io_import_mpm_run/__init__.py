"""Blender add-on: File > Import > mpm run (folder).

A run's folder of the mpm engine (frame_NNNN.ply particles, surface_*.obj meshes, levelset_*.vdb
grids; docs/houdini-blender.md) becomes, in the current scene:

  - one object "<run> particles": a vertex-only mesh whose points follow the frames, with the
    point attributes velocity (vector, m/s), pscale (radius, m), id, material and body (int) for
    Geometry Nodes, and a Geometry Nodes modifier that draws each point as a sphere of its
    pscale (Mesh to Points), so it renders in Cycles and Eevee;
  - one object per surface series (the particle surfaces surface_NNNN.obj and the embedded
    surfaces surface_body<i>_NNNN.obj), whose mesh follows the frames;
  - one volume object per level-set series (levelset_NNNN.vdb), a volume sequence.

The engine is y-up, Blender z-up: the objects are rotated +90 degrees about X (the engine's
(x, y, z) at Blender's (x, -z, y)), their data left as written. The scene's frame rate becomes the
scene's time.fps (from the run's scene.json) and its frame range the run's frames: mpm frame N is
Blender frame N.

Frames are read when the timeline reaches them (a frame_change_pre handler swaps each object's
mesh) and kept, so scrubbing back is free; a run's first frame is read at import.
"""

bl_info = {
    "name": "mpm run (folder)",
    "author": "the mpm developers",
    "version": (0, 3, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > mpm run (folder)",
    "description": "Import a run of the mpm engine: animated particles, surfaces and level sets",
    "category": "Import-Export",
}

import json
import math
import os
import re

import bpy
import numpy as np
from bpy.props import BoolProperty, StringProperty
from bpy.app.handlers import persistent

# ---- files ---------------------------------------------------------------------------------

_PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "<i2", "ushort": "<u2", "int": "<i4",
              "uint": "<u4", "float": "<f4", "double": "<f8", "int32": "<i4", "uint32": "<u4",
              "float32": "<f4", "float64": "<f8"}


def read_points_ply(path):
    """The vertex element of a binary little-endian PLY point file (no faces), as a numpy
    structured array with the file's properties."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise ValueError(f"{path}: not a PLY file")
        count, fields, fmt = None, [], None
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: the header has no end_header")
            words = line.decode("ascii", "replace").split()
            if not words:
                continue
            if words[0] == "format":
                fmt = words[1]
            elif words[0] == "element":
                if words[1] != "vertex":
                    raise ValueError(f"{path}: element {words[1]}: expected points only")
                count = int(words[2])
            elif words[0] == "property":
                if words[1] == "list":
                    raise ValueError(f"{path}: a list property: expected points only")
                fields.append((words[2], _PLY_TYPES[words[1]]))
            elif words[0] == "end_header":
                break
        if fmt != "binary_little_endian" or count is None:
            raise ValueError(f"{path}: expected a binary little-endian PLY of vertices")
        data = np.fromfile(f, dtype=np.dtype(fields), count=count)
        if len(data) != count:
            raise ValueError(f"{path}: {count} points announced, {len(data)} in the file")
        return data


def read_obj(path):
    """Vertices (n, 3) and triangles (m, 3), 0-based, of an OBJ of `v` and `f` lines."""
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(w.split("/")[0]) - 1 for w in line.split()[1:]])
    return np.array(verts, dtype=np.float32).reshape(-1, 3), faces


_NUMBERED = re.compile(r"^(?P<stem>.+?)_(?P<n>\d{4,})\.(?P<ext>ply|obj|vdb)$")


def scan_run(run_dir):
    """The run's file series: {(stem, ext): {frame: path}}, and its frames per second."""
    series = {}
    for name in os.listdir(run_dir):
        m = _NUMBERED.match(name)
        if m:
            series.setdefault((m["stem"], m["ext"]), {})[int(m["n"])] = os.path.join(run_dir, name)
    fps = 24.0
    scene_file = os.path.join(run_dir, "scene.json")
    if os.path.exists(scene_file):
        try:
            with open(scene_file) as f:
                fps = float(json.load(f).get("time", {}).get("fps", 24))
        except (ValueError, OSError):
            pass
    return series, fps


# ---- meshes from files ---------------------------------------------------------------------

def points_mesh(name, path):
    """A vertex-only mesh of a PLY point frame, with its point attributes."""
    data = read_points_ply(path)
    mesh = bpy.data.meshes.new(name)
    n = len(data)
    mesh.vertices.add(n)
    xyz = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)
    mesh.vertices.foreach_set("co", xyz.ravel())
    names = data.dtype.names
    if all(k in names for k in ("vx", "vy", "vz")):
        v = np.stack([data["vx"], data["vy"], data["vz"]], axis=1).astype(np.float32)
        mesh.attributes.new("velocity", "FLOAT_VECTOR", "POINT").data.foreach_set("vector",
                                                                                 v.ravel())
    if "pscale" in names:
        mesh.attributes.new("pscale", "FLOAT", "POINT").data.foreach_set(
            "value", data["pscale"].astype(np.float32))
    for key in ("id", "material", "body"):
        if key in names:
            mesh.attributes.new(key, "INT", "POINT").data.foreach_set(
                "value", data[key].astype(np.int32))
    mesh.update()
    return mesh


def surface_mesh(name, path):
    verts, faces = read_obj(path)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts.tolist(), [], faces)
    mesh.update()
    return mesh


def frame_mesh(obj, frame):
    """The mesh of obj's series at `frame` (the nearest written frame at or before it), read
    once and kept."""
    files = json.loads(obj["mpm_files"])
    frames = sorted(int(k) for k in files)
    if not frames:
        return None
    at = max([f for f in frames if f <= frame], default=frames[0])
    name = f"{obj['mpm_prefix']}_{at:04d}"
    mesh = bpy.data.meshes.get(name)
    if mesh is None:
        path = files[str(at)]
        mesh = points_mesh(name, path) if obj["mpm_kind"] == "points" else surface_mesh(name, path)
        mesh.use_fake_user = False
    return mesh


@persistent
def on_frame_change(scene, *args):
    for obj in scene.objects:
        if "mpm_files" not in obj or obj.type != "MESH":
            continue
        mesh = frame_mesh(obj, scene.frame_current)
        if mesh is not None and obj.data != mesh:
            obj.data = mesh


# ---- the points' look ----------------------------------------------------------------------

def points_node_group():
    """Geometry Nodes: each vertex a point of radius pscale (Mesh to Points), material set."""
    name = "mpm points"
    ng = bpy.data.node_groups.get(name)
    if ng is not None:
        return ng
    ng = bpy.data.node_groups.new(name, "GeometryNodeTree")
    ng.inputs.new("NodeSocketGeometry", "Geometry")
    ng.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = ng.nodes, ng.links
    gin = nodes.new("NodeGroupInput")
    gout = nodes.new("NodeGroupOutput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    radius = nodes.new("GeometryNodeInputNamedAttribute")
    radius.data_type = "FLOAT"
    radius.inputs["Name"].default_value = "pscale"
    material = nodes.new("GeometryNodeSetMaterial")
    material.inputs["Material"].default_value = points_material()
    links.new(gin.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(radius.outputs["Attribute"], to_points.inputs["Radius"])
    links.new(to_points.outputs["Points"], material.inputs["Geometry"])
    links.new(material.outputs["Geometry"], gout.inputs["Geometry"])
    return ng


def points_material():
    name = "mpm particles"
    mat = bpy.data.materials.get(name)
    if mat is None:
        mat = bpy.data.materials.new(name)
        mat.use_nodes = True
        bsdf = mat.node_tree.nodes.get("Principled BSDF")
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (0.85, 0.35, 0.15, 1.0)
    return mat


# ---- import ----------------------------------------------------------------------------------

def import_run(context, run_dir, surfaces=True, volumes=True, axis_conversion=True):
    """Import the run folder run_dir into context's scene; returns the objects made."""
    run_dir = os.path.abspath(run_dir)
    series, fps = scan_run(run_dir)
    points = series.get(("frame", "ply"))
    if not points:
        raise ValueError(f"{run_dir}: no frame_NNNN.ply files (the scene's output.ply writes "
                         "them)")
    run = os.path.basename(run_dir.rstrip(os.sep)) or "run"
    scene = context.scene
    collection = bpy.data.collections.new(f"mpm {run}")
    scene.collection.children.link(collection)
    made = []

    def animated(kind, stem, files):
        prefix = f"mpm_{run}_{stem}"
        obj = bpy.data.objects.new(f"{run} {stem if kind == 'surface' else 'particles'}",
                                   bpy.data.meshes.new(prefix + "_empty"))
        obj["mpm_files"] = json.dumps({str(k): v for k, v in files.items()})
        obj["mpm_prefix"] = prefix
        obj["mpm_kind"] = kind
        obj["mpm_run_dir"] = run_dir
        if axis_conversion:
            obj.rotation_euler = (math.pi / 2, 0, 0)
        collection.objects.link(obj)
        obj.data = frame_mesh(obj, min(files))
        made.append(obj)
        return obj

    obj = animated("points", "frame", points)
    mod = obj.modifiers.new("mpm points", "NODES")
    mod.node_group = points_node_group()
    if surfaces:
        for (stem, ext), files in sorted(series.items()):
            if ext == "obj" and stem.startswith("surface"):
                animated("surface", stem, files)
    if volumes:
        for (stem, ext), files in sorted(series.items()):
            if ext != "vdb":
                continue
            first = min(files)
            vol = bpy.data.volumes.new(f"mpm_{run}_{stem}")
            vol.filepath = files[first]
            vol.is_sequence = True
            vol.frame_start = first
            vol.frame_duration = max(files) - first + 1
            # Blender numbers a sequence's files from 1 at frame_start (plus the offset); the
            # run's start at `first`
            vol.frame_offset = first - 1
            vol.sequence_mode = "CLIP"
            vobj = bpy.data.objects.new(f"{run} {stem}", vol)
            if axis_conversion:
                vobj.rotation_euler = (math.pi / 2, 0, 0)
            collection.objects.link(vobj)
            made.append(vobj)
    # the timeline: the run's frames at the scene's rate
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    scene.frame_start = min(points)
    scene.frame_end = max(points)
    if on_frame_change not in bpy.app.handlers.frame_change_pre:
        bpy.app.handlers.frame_change_pre.append(on_frame_change)
    return made


class ImportMpmRun(bpy.types.Operator):
    """Import a run folder of the mpm engine: animated particles, surfaces and level sets"""
    bl_idname = "import_scene.mpm_run"
    bl_label = "Import mpm run"
    bl_options = {"REGISTER", "UNDO"}

    directory: StringProperty(name="Run folder", subtype="DIR_PATH")
    surfaces: BoolProperty(name="Surfaces", default=True,
                           description="The run's surface_*.obj series as animated meshes")
    volumes: BoolProperty(name="Level sets", default=True,
                          description="The run's levelset_*.vdb series as volume sequences")
    axis_conversion: BoolProperty(name="Y up to Z up", default=True,
                                  description="Rotate the objects +90 degrees about X")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        try:
            made = import_run(context, self.directory, self.surfaces, self.volumes,
                              self.axis_conversion)
        except (OSError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"mpm: {len(made)} objects from {self.directory}")
        return {"FINISHED"}


def menu_import(self, context):
    self.layout.operator(ImportMpmRun.bl_idname, text="mpm run (folder)")


def register():
    bpy.utils.register_class(ImportMpmRun)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)
    if on_frame_change not in bpy.app.handlers.frame_change_pre:
        bpy.app.handlers.frame_change_pre.append(on_frame_change)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    bpy.utils.unregister_class(ImportMpmRun)
    if on_frame_change in bpy.app.handlers.frame_change_pre:
        bpy.app.handlers.frame_change_pre.remove(on_frame_change)
