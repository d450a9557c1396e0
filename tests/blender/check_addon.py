"""check_addon.py - run inside Blender (tests/blender/run.sh): the add-on blender/io_import_mpm_run
imports a run folder as the files say, and a frame of it renders with Cycles on the CPU.

    blender -b --factory-startup --python-exit-code 1 -P check_addon.py -- SRC RUN_DIR OUT_PNG

Checks, each against the files read here independently of the add-on:
  - the particles object's point count at frames 0 and 2 is the PLY's, its positions, velocity,
    pscale, id, material and body equal the file's (matched by id), and the mesh changes with
    the frame;
  - the timeline is the run's: fps from scene.json, frames 0 to the last file;
  - the objects are turned y-up to z-up (+90 degrees about X);
  - the Geometry Nodes modifier makes one point per particle with radius pscale;
  - the embedded and particle surface series are animated meshes with the files' vertex
    counts, and the level-set series a volume sequence whose grids load;
  - a 96 x 72 Cycles render of frame 2 differs from the background where the particles project.
"""
import math
import os
import struct
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
src, run_dir, out_png = argv
sys.path.insert(0, os.path.join(src, "blender"))
import io_import_mpm_run  # noqa: E402

io_import_mpm_run.register()


def fail(msg):
    print("check_addon: FAIL:", msg)
    sys.exit(1)


def read_ply(path):
    """The PLY's vertices as a dict of arrays (a reader of its own, not the add-on's)."""
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        props, count = [], 0
        for line in header.decode().splitlines():
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                count = int(w[2])
            if w and w[0] == "property":
                props.append((w[2], {"float": "f", "double": "d", "int": "i", "uint": "I"}[w[1]]))
        fmt = "<" + "".join(t for _, t in props)
        size = struct.calcsize(fmt)
        rows = [struct.unpack_from(fmt, f.read(size)) for _ in range(count)]
    return {name: np.array([r[k] for r in rows]) for k, (name, _) in enumerate(props)}


# the factory scene's cube (2 m, at the origin) would enclose the particles and the camera
for o in list(bpy.context.scene.objects):
    bpy.data.objects.remove(o)
bpy.ops.import_scene.mpm_run(directory=run_dir)
scene = bpy.context.scene
points = [o for o in scene.objects if o.get("mpm_kind") == "points"]
if len(points) != 1:
    fail(f"expected one particles object, found {[o.name for o in scene.objects]}")
obj = points[0]
if abs(obj.rotation_euler[0] - math.pi / 2) > 1e-6:
    fail(f"the particles are not turned y-up to z-up: {tuple(obj.rotation_euler)}")
if scene.frame_start != 0 or scene.frame_end != 2:
    fail(f"timeline {scene.frame_start}..{scene.frame_end}, expected 0..2 (three frames)")
if abs(scene.render.fps / scene.render.fps_base - 20) > 1e-9:
    fail(f"fps {scene.render.fps / scene.render.fps_base}, expected the scene's 20")

meshes = []
for frame in (0, 2):
    scene.frame_set(frame)
    ply = read_ply(os.path.join(run_dir, f"frame_{frame:04d}.ply"))
    mesh = obj.data
    n = len(mesh.vertices)
    if n != len(ply["x"]):
        fail(f"frame {frame}: {n} points, the file has {len(ply['x'])}")
    co = np.zeros(3 * n, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(n, 3)

    def attr(name, kind, width=1):
        a = mesh.attributes.get(name)
        if a is None:
            fail(f"frame {frame}: no point attribute {name}")
        out = np.zeros(n * width, dtype=np.float32 if kind != "INT" else np.int32)
        a.data.foreach_get("vector" if width == 3 else "value", out)
        return out.reshape(n, width) if width > 1 else out

    ids = attr("id", "INT")
    mine, theirs = np.argsort(ids), np.argsort(ply["id"])
    if not np.array_equal(ids[mine], ply["id"][theirs]):
        fail(f"frame {frame}: the ids differ from the file's")
    xyz = np.stack([ply["x"], ply["y"], ply["z"]], axis=1)
    if not np.allclose(co[mine], xyz[theirs], atol=1e-6):
        fail(f"frame {frame}: positions differ from the file's")
    v = np.stack([ply["vx"], ply["vy"], ply["vz"]], axis=1)
    if not np.allclose(attr("velocity", "FLOAT", 3)[mine], v[theirs], atol=1e-6):
        fail(f"frame {frame}: velocities differ from the file's")
    if not np.allclose(attr("pscale", "FLOAT")[mine], ply["pscale"][theirs], rtol=1e-6):
        fail(f"frame {frame}: pscale differs from the file's")
    for key in ("material", "body"):
        if not np.array_equal(attr(key, "INT")[mine], ply[key][theirs]):
            fail(f"frame {frame}: {key} differs from the file's")
    meshes.append((mesh.name, co[mine].copy()))
    print(f"check_addon: frame {frame}: {n} points match the file (mesh {mesh.name})")
if meshes[0][0] == meshes[1][0] or np.allclose(meshes[0][1], meshes[1][1]):
    fail("the particles did not move between frames 0 and 2")

# Geometry Nodes: one point per particle, radius pscale
deps = bpy.context.evaluated_depsgraph_get()
evaluated = obj.evaluated_get(deps)
cloud = evaluated.data if evaluated.type == "POINTCLOUD" else None
geometry = evaluated.evaluated_geometry() if hasattr(evaluated, "evaluated_geometry") else None
count = None
for inst in deps.object_instances:
    if inst.object.original == obj and inst.object.type == "POINTCLOUD":
        count = len(inst.object.data.points)
if count is None and cloud is not None:
    count = len(cloud.points)
if count is not None and count != len(obj.data.vertices):
    fail(f"the Geometry Nodes make {count} points of {len(obj.data.vertices)}")
print(f"check_addon: Geometry Nodes points: {count}")

# the embedded surface
surfaces = [o for o in scene.objects if o.get("mpm_kind") == "surface"]
if not surfaces:
    fail("no surface object (the run writes surface_body0_NNNN.obj)")
for s in surfaces:
    stem = s["mpm_prefix"][len("mpm_run_"):]
    with open(os.path.join(run_dir, f"{stem}_0002.obj")) as f:
        nv = sum(1 for line in f if line.startswith("v "))
    if len(s.data.vertices) != nv:
        fail(f"{s.name}: {len(s.data.vertices)} vertices at frame 2, the file has {nv}")
    print(f"check_addon: {s.name}: {nv} vertices at frame 2")

# the level-set series: a volume sequence over the run's frames, its grids readable
volumes = [o for o in scene.objects if o.type == "VOLUME"]
if len(volumes) != 1:
    fail(f"expected one volume object (levelset_NNNN.vdb), found {[o.name for o in volumes]}")
vol = volumes[0].data
if not vol.is_sequence or vol.frame_start != 0 or vol.frame_duration != 3:
    fail(f"the volume is not the sequence of frames 0..2 ({vol.is_sequence}, {vol.frame_start}, "
         f"{vol.frame_duration})")
deps = bpy.context.evaluated_depsgraph_get()
grids = volumes[0].evaluated_get(deps).data.grids
grids.load()
names = [g.name for g in grids]
if "surface" not in names:
    fail(f"the level set's grids are {names}, expected 'surface' among them "
         f"({grids.error_message!r}, frame file {grids.frame_filepath!r})")
if not grids.frame_filepath.endswith("levelset_0002.vdb"):
    fail(f"at frame 2 the volume reads {grids.frame_filepath!r}, expected levelset_0002.vdb")
print(f"check_addon: volume sequence {bpy.path.basename(vol.filepath)} x {vol.frame_duration}, "
      f"grids {names}")

# a small render of frame 2 from a camera looking at the particles
for o in surfaces + volumes:
    o.hide_render = True  # the particles alone, so the check below is about them
world_co = np.array([obj.matrix_world @ __import__("mathutils").Vector(c)
                     for c in meshes[1][1]])
centre = world_co.mean(axis=0)
extent = float(np.linalg.norm(world_co.max(axis=0) - world_co.min(axis=0)))
cam_data = bpy.data.cameras.new("check camera")
cam = bpy.data.objects.new("check camera", cam_data)
scene.collection.objects.link(cam)
cam.location = tuple(centre + np.array([0, -2.5 * extent, 0.8 * extent]))
direction = __import__("mathutils").Vector(tuple(centre)) - cam.location
cam.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
scene.camera = cam
sun_data = bpy.data.lights.new("check sun", "SUN")
sun_data.energy = 4.0
sun = bpy.data.objects.new("check sun", sun_data)
sun.rotation_euler = (0.6, 0.2, 0.3)
scene.collection.objects.link(sun)
if scene.world is None:
    scene.world = bpy.data.worlds.new("check world")
scene.world.use_nodes = False
scene.world.color = (0.05, 0.3, 0.05)  # a green background, unlike the particles' orange
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 8
scene.cycles.use_denoising = False  # (Debian builds Blender without OpenImageDenoise)
scene.render.resolution_x, scene.render.resolution_y = 96, 72
scene.render.resolution_percentage = 100
scene.render.filepath = out_png
scene.render.image_settings.file_format = "PNG"
scene.frame_set(2)
bpy.ops.render.render(write_still=True)
if not os.path.exists(out_png):
    fail(f"no picture at {out_png}")
img = bpy.data.images.load(out_png)
w, h = img.size
px = np.array(img.pixels[:]).reshape(h, w, 4)[:, :, :3]
from bpy_extras.object_utils import world_to_camera_view  # noqa: E402
p = world_to_camera_view(scene, cam, __import__("mathutils").Vector(tuple(centre)))
cx, cy = int(p.x * (w - 1)), int(p.y * (h - 1))
background = px[0, 0]
centre_px = px[cy, cx]
diff = float(np.abs(centre_px - background).max())
print(f"check_addon: render {w} x {h}: at the particles ({cx}, {cy}) {centre_px.round(3)}, "
      f"background {background.round(3)}, difference {diff:.3f}")
if diff < 0.05:
    fail("the particles do not show in the render")
print("check_addon: all passed")
