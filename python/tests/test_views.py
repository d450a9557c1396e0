"""The particle views: zero-copy numpy arrays of the engine's memory, with the values the frame
files hold, read-only, invalidated by a step, alive as long as an array needs them."""

import gc
import os
import re
import subprocess
import weakref

import numpy as np
import pytest

import mpm
from conftest import small_scene


def test_no_copy(scene):
    sim = mpm.Simulation(scene)
    p = sim.particles
    buffers = sim._state()
    for name in ("x", "v", "F", "mass", "volume0", "material", "body", "id"):
        a = getattr(p, name)
        assert a.__array_interface__["data"][0] == buffers[name].address, name
        assert not a.flags.writeable and not a.flags.owndata, name
        with pytest.raises(ValueError):
            a[0] = 0
    # the components of a vector are one strided array: x[:, 1] starts one stride after x[:, 0]
    assert p.x.shape == (len(p), 3) and p.x.strides[0] == p.x.itemsize
    assert p.F.shape == (len(p), 3, 3)
    assert np.shares_memory(p.x, sim.particles.x)
    # the derived fields are copies the arrays own
    assert p.J.flags.owndata and p.stress.shape == (len(p), 3, 3)
    assert np.allclose(p.J, 1) and np.allclose(p.stress, 0, atol=1e-3)
    assert p.temperature is None  # no heat in this scene


def test_dtype_follows_the_build(scene, mpm_bin):
    out = subprocess.run([mpm_bin, "--version"], capture_output=True, text=True).stdout
    build = re.search(r"\((float|double)[;)]", out).group(1)
    assert mpm.real_type() == build
    p = mpm.Simulation(scene).particles
    assert p.x.dtype == mpm.dtype == np.dtype(np.float32 if build == "float" else np.float64)
    assert p.id.dtype == np.uint32 and p.material.dtype == np.int32


def test_values_equal_the_frame_file(tmp_path, scene):
    vtk = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    sim = mpm.Simulation(scene)
    sim.open_output(str(tmp_path))
    sim.run(frames=2)
    p = sim.particles
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(tmp_path / "frame_0002.vtu"))
    reader.Update()
    grid = reader.GetOutput()
    ids = vtk_to_numpy(grid.GetPointData().GetArray("id"))
    points = vtk_to_numpy(grid.GetPoints().GetData())
    assert len(ids) == len(p)
    order = np.argsort(p.id)
    file_order = np.argsort(ids)
    assert np.array_equal(p.id[order], ids[file_order])
    assert np.array_equal(p.x[order].astype(points.dtype), points[file_order])
    v = vtk_to_numpy(grid.GetPointData().GetArray("velocity"))
    assert np.array_equal(p.v[order].astype(v.dtype), v[file_order])


def test_stale_after_a_step(scene):
    sim = mpm.Simulation(scene)
    p = sim.particles
    kept = p.x  # an array taken before the step
    buffer = sim._state()["x"]
    sim.step()
    assert not p.valid and not buffer.valid
    with pytest.raises(mpm.StaleViewError):
        p.x
    with pytest.raises(mpm.StaleViewError):
        len(p)
    with pytest.raises(mpm.StaleViewError):
        np.asarray(memoryview(buffer))
    # the array taken before stays readable: its memory is held, its values are stale
    assert np.isfinite(kept).all()
    q = sim.particles
    assert q.valid and len(q) == sim.particle_count


def test_a_view_outlives_its_simulation(scene):
    sim = mpm.Simulation(scene)
    sim.run(frames=1)
    x = sim.particles.x
    expected = x.copy()
    ref = weakref.ref(sim)
    del sim
    gc.collect()
    assert ref() is not None  # the array keeps the simulation alive
    assert np.array_equal(x, expected)
    del x
    gc.collect()
    assert ref() is None  # and lets it go with the last array


def test_domain_particles_and_setters_of_views():
    sim = mpm.Simulation.from_file(os.path.join(os.path.dirname(__file__), "..", "..",
                                                "examples", "ball_bunny.json"))
    p = sim.particles
    assert len(p) == sim.info["particles"] and sim.info["domain_particles"] > 0
    assert len(np.unique(p.id)) == len(p)


def test_create_destroy_cycles_leak_nothing():
    import tracemalloc
    scene = small_scene(bodies=[{"shape": {"type": "box", "center": [0.25, 0.25, 0.25],
                                           "half_extent": [0.02, 0.02, 0.02]},
                                 "material": "jelly"}])

    def rss():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

    def cycle(n):
        for _ in range(n):
            sim = mpm.Simulation(scene)
            sim.step()
            p = sim.particles
            p.x.sum(), p.J.sum()
            del p, sim

    cycle(100)  # warm: allocator pools, imports
    gc.collect()
    tracemalloc.start()
    before_py = tracemalloc.get_traced_memory()[0]
    before_rss = rss()
    before_engine = mpm.live_bytes()
    cycle(1000)
    gc.collect()
    grown_py = tracemalloc.get_traced_memory()[0] - before_py
    tracemalloc.stop()
    grown_rss = rss() - before_rss
    print(f"1000 cycles: Python heap {grown_py} bytes, engine {mpm.live_bytes() - before_engine} "
          f"bytes, resident set {grown_rss} bytes")
    assert mpm.live_bytes() == before_engine  # every engine array given back
    assert grown_py < 64 * 1024
    assert grown_rss < 8 * 1024 * 1024  # a leaked simulation would be ~1 MB each


def test_domains_view():
    sim = mpm.Simulation.from_file(os.path.join(os.path.dirname(__file__), "..", "..",
                                                "examples", "ball_bunny.json"))
    d = sim.domains
    p = sim.particles
    assert len(d) == sim.info["domain_particles"] and d.first + len(d) == len(p)
    assert d.enriched is None  # no step yet
    # every domain particle at the mean of its eight corners (lattice cubes)
    mean = d.x[d.corner].mean(axis=1)
    assert np.allclose(mean, p.x[d.first:], atol=1e-5)
    h = d.X[d.corner[:, 7]] - d.X[d.corner[:, 0]]
    assert np.allclose(h, h[0, 0], rtol=1e-5)
    sim.step()
    d2 = sim.domains
    assert d2.enriched is not None and d2.enriched.shape == (len(d2.x),)
    # the hexahedra stay the same (the step may number the corners anew)
    assert np.array_equal(d.X[d.corner], d2.X[d2.corner])
    assert np.allclose(d2.x[d2.corner].mean(axis=1), sim.particles.x[d2.first:], atol=1e-5)
    none = mpm.Simulation(small_scene()).domains
    assert len(none) == 0 and none.x.shape == (0, 3)


def test_arrays_dropped_while_a_call_runs():
    # another thread drops the last array of a view while the engine runs a frame without the
    # GIL: the release waits for the call's end (the engine may be growing its arrays then)
    import threading
    import time
    baseline = mpm.live_bytes()
    sim = mpm.Simulation(small_scene(domain={"min": [0, 0, 0], "max": [0.5, 0.5, 0.5],
                                             "dx": 0.0125}, time={"end": 1, "fps": 4}))
    x = sim.particles.x
    worker = threading.Thread(target=sim.advance_frame)
    worker.start()
    time.sleep(0.05)
    assert worker.is_alive()
    del x
    gc.collect()
    worker.join()
    assert sim.frame == 1 and np.isfinite(sim.particles.x).all()
    del sim
    gc.collect()
    assert mpm.live_bytes() == baseline
