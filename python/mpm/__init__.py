"""mpm: a Material Point Method engine (Zhu et al. 2017, Gao et al. 2017) from Python.

A simulation is built from a JSON scene, as a file or as a dict with the same keys
(docs/scene-format.md), advanced step by step or frame by frame, and read back as numpy
arrays that share the engine's memory::

    import mpm
    sim = mpm.Simulation.from_file("examples/sphere_bounce.json")
    while sim.frame < 10:
        sim.advance_frame()
    p = sim.particles          # a snapshot of the state now
    print(p.x.mean(axis=0))    # positions, (n, 3), no copy

The particle arrays are valid until the simulation advances: the engine reorders its particles
every step. Read ``sim.particles`` again after each step; a ``Particles`` object of an earlier
state raises ``StaleViewError``. An array you keep from before stays readable (its memory is
kept for it) but holds values of no particular particle: copy it (``p.x.copy()``) to keep it.

Errors: a scene the engine refuses raises ``SceneError`` naming the key path, a failure of the
engine ``mpm.Error`` (naming step, particle and quantity), a file that cannot be written
``OSError``; Ctrl-C during a long call raises ``KeyboardInterrupt`` between two steps with the
simulation still usable.
"""

import json as _json
import math as _math
import os as _os
import re as _re
import threading as _threading

import numpy as _np

from . import _mpm
from ._mpm import Error, SceneError, StaleViewError

__all__ = ["Simulation", "Particles", "Domains", "Collider", "Error", "SceneError", "StaleViewError",
           "render", "render_frames", "version", "real_type", "dtype", "live_bytes"]

_mpm._set_main_thread(_threading.main_thread().ident)


def version():
    """The engine library's version, "MAJOR.MINOR.PATCH"."""
    return _mpm.version()


def live_bytes():
    """Bytes the engine holds now for its large arrays, over every simulation: what a leak
    check compares before and after."""
    return _mpm.live_bytes()


def real_type():
    """The engine's real type, "float" or "double": the dtype of the real particle arrays."""
    return _mpm.real_type()


#: numpy dtype of the real particle arrays (float32 or float64, as the engine was built).
dtype = _np.dtype(_np.float32 if _mpm.real_type() == "float" else _np.float64)


def _view(buffer):
    """A read-only numpy array over an engine buffer, no copy (its base keeps the buffer)."""
    return _np.asarray(memoryview(buffer))


def _scene_json(scene):
    """The JSON text of a scene given as a dict. A dict holds numbers, not their text: an
    infinite float (a number too large, 1e400 read by json.load) is written as 1e999, so that the
    engine names its key path as it does for the file's own text; NaN has no JSON form and is
    refused here, naming the key path as the engine would."""
    def find_nan(value, path):
        if isinstance(value, float) and _math.isnan(value):
            raise SceneError(f"<json>: {path}: expected a number, got NaN (not a number)")
        if isinstance(value, dict):
            for k, v in value.items():
                find_nan(v, f"{path}.{k}" if path else str(k))
        elif isinstance(value, (list, tuple)):
            for i, v in enumerate(value):
                find_nan(v, f"{path}[{i}]")
    find_nan(scene, "")
    text = _json.dumps(scene, allow_nan=True)
    # Infinity outside strings -> 1e999 (the strings are matched first and kept)
    return _re.sub(r'"(?:\\.|[^"\\])*"|(-?)Infinity',
                   lambda m: m.group(0) if m.group(0).startswith('"') else m.group(1) + "1e999",
                   text)


class Particles:
    """The particles of a simulation at one state (``Simulation.particles``).

    State arrays, numpy views of the engine's own memory (zero-copy, read-only):
      x (n, 3) position m, v (n, 3) velocity m/s, F (n, 3, 3) deformation gradient, mass (n,)
      kg, volume0 (n,) initial volume m^3, plastic (n,) plastic state (snow's J_p,
      Drucker-Prager's log volume correction; 1 and unused otherwise), temperature (n,) (scenes
      with heat only, else None), material, body (n,) int32 indices into the scene's lists,
      id (n,) uint32 stable particle ids.
    Derived fields, computed on first access and owned by the array (a copy of the engine's
    buffer): J (n,) det F, stress (n, 3, 3) Cauchy stress Pa.

    With particle domains (Zhu et al.) the state arrays are a copy the simulation makes in its
    own buffers (material points first, then the domain particles whose domains are on).

    Every access checks that the simulation is still at this state, and raises StaleViewError
    once it has advanced.
    """

    _STATE = ("x", "v", "F", "mass", "volume0", "plastic", "temperature", "material", "body",
              "id")

    def __init__(self, sim):
        self._sim = sim
        self._generation = sim._generation
        self._buffers = sim._state()
        self._arrays = {}
        self._derived = None

    def _check(self):
        if self._sim._generation != self._generation:
            raise StaleViewError(
                "these particles belong to an earlier state: the simulation has advanced (or "
                "its particles changed) since; read sim.particles again")

    @property
    def valid(self):
        """Whether the simulation is still at this state."""
        return self._sim._generation == self._generation

    def __len__(self):
        self._check()
        return len(self.x)

    def __getattr__(self, name):
        if name in Particles._STATE:
            self._check()
            a = self._arrays.get(name)
            if a is None:
                b = self._buffers.get(name)
                if b is None:
                    return None  # temperature without heat
                a = self._arrays[name] = _view(b)
            return a
        if name in ("J", "stress"):
            self._check()
            if self._derived is None:
                J, stress = self._sim._derived()
                self._derived = (_np.array(memoryview(J)), _np.array(memoryview(stress)))
            return self._derived[0] if name == "J" else self._derived[1]
        raise AttributeError(name)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(Particles._STATE) | {"J", "stress"})

    def __repr__(self):
        if not self.valid:
            return "<mpm.Particles of an earlier state (stale)>"
        return f"<mpm.Particles: {len(self)} particles>"


class Domains:
    """The particle domains (Zhu et al. 2017) at the state it was taken (Simulation.domains):
    arrays the simulation copied for this object (they stay valid after the simulation advances).

      x, v, X       (corners, 3) each corner's position m, velocity m/s, reference position m
      enriched      (corners,) bool: a DOF of its own in the last step (None before one)
      corner        (particles, 8) uint32: each active domain particle's hexahedron, corner
                    a = i + 2 j + 4 k at the reference cube's (2i - 1, 2j - 1, 2k - 1)
      first         the index of the first domain particle in Simulation.particles (they come
                    after the material points, in this order)
    """

    def __init__(self, sim):
        d = sim._domains()
        self.first = d["first"]
        n, nc = d["particles"], d["corners"]
        real = dtype

        def vec(key):
            if nc == 0:
                return _np.zeros((0, 3), dtype=real)
            return _np.stack([_np.array(memoryview(b)) for b in d[key]], axis=1)

        self.x, self.v, self.X = vec("x"), vec("v"), vec("X")
        self.corner = (_np.array(memoryview(d["corner"])).reshape(n, 8) if nc
                       else _np.zeros((0, 8), dtype=_np.uint32))
        self.enriched = (_np.array(memoryview(d["enriched"])).astype(bool)
                         if "enriched" in d else None)

    def __len__(self):
        return len(self.corner)

    def __repr__(self):
        return f"<mpm.Domains: {len(self)} domain particles, {len(self.x)} corners>"


class Collider:
    """A collider of the scene at the simulation's time: name, center (3,), rotation (3, 3)
    (local to world), velocity (3,) of the centre m/s, angular_velocity (3,) rad/s, and
    whether it is active now."""

    __slots__ = ("name", "center", "rotation", "velocity", "angular_velocity", "active")

    def __init__(self, d):
        self.name = d["name"]
        self.center = _np.array(d["center"])
        self.rotation = _np.array(d["rotation"])
        self.velocity = _np.array(d["velocity"])
        self.angular_velocity = _np.array(d["angular_velocity"])
        self.active = d["active"]

    def __repr__(self):
        return f"<mpm.Collider {self.name!r} at {self.center.tolist()}>"


class Simulation(_mpm._Simulation):
    """A simulation of one scene.

    Simulation(scene, base_dir=None): scene is a dict with the keys of a JSON scene file
    (docs/scene-format.md); relative mesh files resolve against base_dir (None: the current
    folder). Simulation.from_file(path) reads a scene file. A scene the engine refuses raises
    SceneError whose message names the key path, as `mpm check` does.

    Advance with step(), advance_frame() or run(); read the state with particles, time, frame,
    info and colliders; write every frame with open_output(), one with write_frame(), checkpoints
    with checkpoint(), and continue a run with Simulation.resume().
    """

    def __init__(self, scene=None, base_dir=None, *, path=None):
        if path is not None:
            super().__init__(path=_os.fspath(path))
        elif isinstance(scene, (dict, list)):
            super().__init__(json=_scene_json(scene),
                             base_dir=None if base_dir is None else _os.fspath(base_dir))
        elif isinstance(scene, str):
            super().__init__(json=scene,
                             base_dir=None if base_dir is None else _os.fspath(base_dir))
        else:
            raise TypeError("Simulation(scene): scene is a dict of a scene's keys (or its JSON "
                            "text); Simulation.from_file(path) reads a file")

    @classmethod
    def from_file(cls, path):
        """The simulation of the scene file at path."""
        return cls(path=path)

    @classmethod
    def resume(cls, scene, directory, base_dir=None):
        """The simulation of scene (a file path or a dict) continued from the newest valid
        checkpoint in directory, writing its frames there; it continues bit-identically to an
        uninterrupted run. The checkpoint used is in info["last_checkpoint"] afterwards."""
        if isinstance(scene, (str, _os.PathLike)) and not str(scene).lstrip().startswith("{"):
            sim = cls.from_file(scene)
        else:
            sim = cls(scene, base_dir)
        sim._resume_from(_os.fspath(directory))
        return sim

    @property
    def particles(self):
        """The particles now, as numpy views of the engine's arrays (a Particles object; valid
        until the simulation advances)."""
        return Particles(self)

    @property
    def domains(self):
        """The particle domains now: their corners and each domain particle's eight (a Domains
        object of copies)."""
        return Domains(self)

    @property
    def info(self):
        """What the engine reports: counts, dx, fps, frame count, threads, memory, output
        folder, the implicit solver's iterations over the last frame, refinement and
        resampling counts (a dict; mpm_sim_info's members)."""
        return self._info()

    @property
    def colliders(self):
        """The scene's colliders at the current time (a list of Collider)."""
        return [Collider(d) for d in self._colliders()]

    def _set_by_id(self, which, ids, values, what):
        ids = _np.ascontiguousarray(_np.atleast_1d(ids), dtype=_np.int64)
        if ids.ndim != 1 or (ids.size and (ids.min() < 0 or ids.max() > 0xFFFFFFFF)):
            raise ValueError(f"{what}: ids are particle ids (Particles.id), 0 to 2^32 - 1")
        values = _np.asarray(values, dtype=_np.float64)
        if values.shape == (3,):
            values = _np.broadcast_to(values, (len(ids), 3))
        if values.shape != (len(ids), 3):
            raise ValueError(f"{what}: expected one 3-vector per id (shape ({len(ids)}, 3) or "
                             f"(3,)), got shape {values.shape}")
        self._set(which, ids.astype(_np.uint32).tobytes(),
                  _np.ascontiguousarray(values).tobytes())

    def set_velocities(self, ids, v):
        """Set the velocity (m/s) of the particles with these ids (Particles.id), now: the next
        step starts from it (the momentum m v it carries to the grid). v is one 3-vector per id,
        or one for all. Material points only (a particle whose domain is on moves with its
        domain's corners). Raises mpm.Error naming the id or value, changing nothing."""
        self._set_by_id(0, ids, v, "set_velocities")

    def set_positions(self, ids, x):
        """Move the particles with these ids to x (m, inside the domain), now; their velocities
        are not changed. As set_velocities otherwise."""
        self._set_by_id(1, ids, x, "set_positions")

    def add_body(self, body, base_dir=None):
        """Add a body now, between steps: body is one entry of a scene's "bodies" list (a dict:
        shape, a material of the scene by name, velocity, ...), checked as the scene's own bodies
        are (SceneError naming its key path, bodies[N]) and sampled into material points with new
        ids. Returns how many particles it made. The scene then has the body: with output open,
        the folder's scene.json is rewritten with it, and that file is the scene to resume the
        run from (Simulation.resume(dir + "/scene.json", dir)). Not with particle domains, an
        inline material, or on the multi-level grid."""
        text = body if isinstance(body, str) else _scene_json(body)
        return self._add_body(text, None if base_dir is None else _os.fspath(base_dir))

    def set_collider_pose(self, collider, center, rotation=None):
        """Move a collider by a script: it ends the next step at this pose (center (3,) m;
        rotation (3, 3), local to world; None keeps its rotation), moving there at a constant
        velocity over the step (its pose change over dt is the velocity the material it touches
        gets), and stands there after it until set again. collider is its index in the scene's
        list or its name. From the first call it follows the script, not its scene motion;
        checkpoints keep the script's state."""
        if isinstance(collider, str):
            names = [c["name"] for c in self._colliders()]
            if collider not in names:
                raise Error(f"set_collider_pose: no collider named {collider!r} (the scene has "
                            f"{names})")
            collider = names.index(collider)
        c = tuple(float(x) for x in _np.asarray(center, dtype=_np.float64).reshape(3))
        R = None
        if rotation is not None:
            R = tuple(float(x) for x in _np.asarray(rotation, dtype=_np.float64).reshape(9))
        self._set_collider_pose(int(collider), c, R)

    def write_frame(self, directory, overwrite=False):
        """Write the state now, once, as a frame's files into directory (made if missing) and
        return their paths: the files the scene's output keys choose for a frame (frame_NNNN.vtu
        and .ply, domains_NNNN.vtu, the surfaces), numbered with sim.frame, apart from any run's
        records (no PVD index, no stats.csv, no frame counted); any time, output open or not.
        All are written before any is moved into the folder: a name already there refuses the
        whole (Error) unless overwrite, which replaces those files and nothing else. The
        simulation's own output folder is refused (its frames are the run's)."""
        directory = _os.fspath(directory)
        names = self._write_frame_to(directory, bool(overwrite)).splitlines()
        return [_os.path.join(directory, n) for n in names]

    def checkpoint(self, directory=None):
        """Write a checkpoint of the whole state (HDF5) into the output folder and return its
        path. With directory and output not yet open, open it there first (open_output)."""
        if directory is not None and not self.info["output_enabled"]:
            self.open_output(_os.fspath(directory))
        return self._checkpoint()

    def run(self, frames=None, callback=None):
        """Advance frame by frame: `frames` more frames (None: to the scene's end). After each
        frame callback(sim) is called when given; an exception it raises stops the run and
        propagates. Ctrl-C stops it between two steps (KeyboardInterrupt). Returns the frames
        completed."""
        end = self.frame_count if frames is None else min(self.frame + int(frames),
                                                           self.frame_count)
        while self.frame < end:
            self.advance_frame()
            if callback is not None:
                callback(self)
        return self.frame

    def __repr__(self):
        return (f"<mpm.Simulation: {self.particle_count} particles, frame {self.frame} of "
                f"{self.frame_count}, t = {self.time:.6g} s>")


def _render_args(what, source, width, height, field, colormap, framing, eye, target, fov,
                 range, shadow, legend, time_label, particles, scene, threads):
    """The run folder of source (a Simulation whose output is open, or a folder) and the
    renderer's options as the extension takes them (render.c)."""
    if isinstance(source, _mpm._Simulation):
        info = source._info()
        if not info["output_enabled"]:
            raise Error(f"{what}: the simulation writes no frames; call open_output(dir) first")
        run_dir = info["output_dir"]
    else:
        run_dir = _os.fspath(source)
    options = {"width": width, "height": height, "field": field, "colormap": colormap,
               "framing": framing, "eye": eye, "target": target, "fov": fov,
               "shadow": int(bool(shadow)), "legend": int(bool(legend)),
               "time_label": int(bool(time_label)), "particles": int(bool(particles)),
               "scene": None if scene is None else _os.fspath(scene), "threads": threads}
    if range is not None:
        options["range_lo"], options["range_hi"] = float(range[0]), float(range[1])
    return run_dir, options


def render(source, frame=-1, path=None, *, width=640, height=360, field=None, colormap=None,
           framing=None, eye=None, target=None, fov=None, range=None, shadow=True, legend=True,
           time_label=True, particles=False, scene=None, threads=0):
    """A picture of a run drawn by the engine's renderer (`mpm render`), as a numpy array of
    shape (height, width, 3), dtype uint8, sRGB: what a notebook shows with
    matplotlib.pyplot.imshow.

    source   a Simulation whose output is open (open_output; its folder is drawn) or the path
             of a run folder
    frame    the frame number of frame_NNNN.vtu to draw (-1: the last one written)
    path     also write the picture there as a PNG
    field    "velocity", "J", "stress", "plastic", "material", "body", "temperature", "melt",
             or any point array of the frames ("pressure", "velocity.y"); None: automatic
    colormap, framing: by their names in `mpm render --help`; eye, target (m) and fov
             (degrees) place the camera; range = (lo, hi) fixes the colours' range
    """
    run_dir, options = _render_args("render", source, width, height, field, colormap, framing,
                                    eye, target, fov, range, shadow, legend, time_label,
                                    particles, scene, threads)
    options["frame"] = frame
    rgb, h, w, _frame, _time = _mpm._render(run_dir, options,
                                            None if path is None else _os.fspath(path))
    return _np.frombuffer(rgb, dtype=_np.uint8).reshape(h, w, 3)


def render_frames(source, out_dir=None, *, width=1280, height=720, field=None, colormap=None,
                  framing=None, eye=None, target=None, fov=None, range=None, every=1,
                  shadow=True, legend=True, time_label=True, particles=False, scene=None,
                  threads=0):
    """Every frame of a run drawn to PNGs, as `mpm render` draws them: out_dir/frame_NNNN.png
    (None: RUN_DIR/render), with one camera, field and colour range for the whole run. source is
    a Simulation whose output is open or a run folder; the options are render()'s, and `every`
    draws every Nth frame. Returns the paths written, in order."""
    run_dir, options = _render_args("render_frames", source, width, height, field, colormap,
                                    framing, eye, target, fov, range, shadow, legend,
                                    time_label, particles, scene, threads)
    options["every"] = every
    options["out_dir"] = None if out_dir is None else _os.fspath(out_dir)
    return _mpm._render_run(run_dir, options)
