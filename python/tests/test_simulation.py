"""The Python module against the engine: a dict scene and its file give the same frames, a run
driven from Python equals `mpm run`, checkpoints resume bit-identically, threads do not change
results, Ctrl-C and callbacks stop a run cleanly."""

import filecmp
import json
import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import mpm
from conftest import ROOT, load_example, small_scene


def frame_files(directory):
    return sorted(f for f in os.listdir(directory)
                  if f.startswith("frame_") and f.endswith((".vtu", ".ply")))


def same_frames(a, b, count):
    fa, fb = frame_files(a), frame_files(b)
    assert fa == fb and len(fa) >= count, (fa, fb)
    for name in fa:
        assert filecmp.cmp(os.path.join(a, name), os.path.join(b, name), shallow=False), name


def test_dict_scene_equals_its_file(tmp_path):
    path = os.path.join(ROOT, "examples", "sphere_bounce.json")
    from_file = mpm.Simulation.from_file(path)
    from_dict = mpm.Simulation(load_example("sphere_bounce.json"),
                               base_dir=os.path.join(ROOT, "examples"))
    from_file.open_output(str(tmp_path / "file"))
    from_dict.open_output(str(tmp_path / "dict"))
    from_file.run(frames=2)
    from_dict.run(frames=2)
    same_frames(tmp_path / "file", tmp_path / "dict", 3)
    a, b = from_file.particles, from_dict.particles
    assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v)


def test_steps_from_python_equal_mpm_run(tmp_path, mpm_bin):
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(small_scene()))
    subprocess.run([mpm_bin, "run", str(scene_path), "-o", str(tmp_path / "cli"), "--frames",
                    "3", "--quiet"], check=True)
    sim = mpm.Simulation.from_file(str(scene_path))
    sim.frame_count = 3
    sim.open_output(str(tmp_path / "py"))
    steps = 0
    while sim.frame < 3:
        assert sim.step() > 0
        steps += 1
    assert steps == sim.steps and steps > 3
    same_frames(tmp_path / "cli", tmp_path / "py", 4)


def test_time_frame_info(scene):
    sim = mpm.Simulation(scene)
    info = sim.info
    assert info["fps"] == 24 and info["frame_count"] == 12 and info["colliders"] == 1
    assert info["particles"] == sim.particle_count == len(sim.particles) > 1000
    assert sim.time == 0 and sim.frame == 0 and sim.steps == 0
    dt = sim.next_dt()
    assert 0 < dt < 1 / 24
    assert sim.advance_frame() == 1
    assert sim.time == pytest.approx(1 / 24)
    assert sim.steps >= 1
    c = sim.colliders
    assert [k.name for k in c] == ["floor"]
    assert np.allclose(c[0].center, [0, 0.1, 0]) and np.allclose(c[0].rotation, np.eye(3))
    assert c[0].active
    sim.frame_count = 2
    sim.run()
    assert sim.frame == 2
    with pytest.raises(mpm.Error):
        sim.advance_frame()  # past the frames asked for


def test_checkpoint_resume_bitwise(tmp_path, scene):
    straight = mpm.Simulation(scene)
    straight.open_output(str(tmp_path / "straight"))
    straight.run(frames=4)
    first = mpm.Simulation(scene)
    first.open_output(str(tmp_path / "resumed"))
    first.run(frames=2)
    path = first.checkpoint()
    assert os.path.basename(path).startswith("checkpoint_") and os.path.exists(path)
    del first  # unlocks the folder
    resumed = mpm.Simulation.resume(scene, tmp_path / "resumed")
    assert resumed.frame == 2 and resumed.info["last_checkpoint"] == path
    resumed.run(frames=2)
    same_frames(tmp_path / "straight", tmp_path / "resumed", 5)


def test_write_frame(tmp_path, scene):
    """A one-off frame is the run's own frame of the same state, byte for byte, from a
    simulation that writes no run; a name already there is refused unless overwrite."""
    ran = mpm.Simulation(scene)
    ran.open_output(str(tmp_path / "run"))
    ran.run(frames=2)
    sim = mpm.Simulation(scene)
    sim.run(frames=2)
    paths = sim.write_frame(tmp_path / "snap")
    assert [os.path.basename(p) for p in paths] == ["frame_0002.vtu"]
    assert sorted(os.listdir(tmp_path / "snap")) == [".mpm.lock", "frame_0002.vtu"]
    assert filecmp.cmp(paths[0], tmp_path / "run" / "frame_0002.vtu", shallow=False)
    assert sim.info["written_frames"] == 0 and sim.frame == 2
    sim.step()
    with pytest.raises(mpm.Error, match="frame_0002.vtu"):
        sim.write_frame(tmp_path / "snap")
    assert filecmp.cmp(paths[0], tmp_path / "run" / "frame_0002.vtu", shallow=False)
    assert sim.write_frame(tmp_path / "snap", overwrite=True) == paths
    assert not filecmp.cmp(paths[0], tmp_path / "run" / "frame_0002.vtu", shallow=False)
    with pytest.raises(mpm.Error, match="output folder"):
        ran.write_frame(tmp_path / "run", overwrite=True)

def test_threads_do_not_change_results(scene):
    runs = []
    for threads in (1, 2):
        sim = mpm.Simulation(scene)
        sim.threads = threads
        assert sim.threads == threads
        sim.run(frames=2)
        p = sim.particles
        order = np.argsort(p.id)
        runs.append((p.x[order].copy(), p.v[order].copy(), p.F[order].copy()))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


def test_callback_stops_the_run(scene):
    sim = mpm.Simulation(scene)
    seen = []

    def callback(s):
        seen.append(s.frame)
        if s.frame == 2:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        sim.run(callback=callback)
    assert seen == [1, 2] and sim.frame == 2
    sim.run(frames=1)  # still usable
    assert sim.frame == 3


def test_ctrl_c_stops_between_steps(scene):
    # a long frame: a fine grid and a stiff material make many steps
    heavy = small_scene(domain={"min": [0, 0, 0], "max": [0.5, 0.5, 0.5], "dx": 0.0125},
                        time={"end": 2, "fps": 1},
                        materials=[{"name": "jelly", "model": "neo_hookean", "E": 1e7,
                                    "nu": 0.3, "density": 1000}])
    sim = mpm.Simulation(heavy)
    sim.threads = 1
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.advance_frame()
    finally:
        timer.cancel()
    elapsed = time.monotonic() - start
    assert sim.frame == 0 and 0 < sim.time < 1 and sim.steps > 0
    assert elapsed < 30
    steps = sim.steps
    p = sim.particles
    assert np.isfinite(p.x).all()
    sim.step()  # still usable
    assert sim.steps == steps + 1
    # Python's own handler is back: Ctrl-C outside a call is a KeyboardInterrupt as usual
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_release_domains(tmp_path):
    sim = mpm.Simulation.from_file(os.path.join(ROOT, "examples", "ball_bunny.json"))
    before = sim.info["domain_particles"]
    assert before > 0
    released = sim.release_domains((-10, -10, -10), (10, 10, 10))
    assert released == before and sim.info["domain_particles"] == 0
    assert len(sim.particles) == sim.particle_count


def test_gil_released_during_a_frame(scene):
    heavy = small_scene(domain={"min": [0, 0, 0], "max": [0.5, 0.5, 0.5], "dx": 0.0125},
                        time={"end": 1, "fps": 4})
    sim = mpm.Simulation(heavy)
    sim.threads = 1
    ticks = []
    worker = threading.Thread(target=sim.advance_frame)
    worker.start()
    while worker.is_alive():
        ticks.append(time.monotonic())
        time.sleep(0.001)
    worker.join()
    assert sim.frame == 1
    assert len(ticks) > 20  # the main thread ran while the frame did


def test_set_velocities_carries_momentum_into_the_step():
    # zero gravity, nothing around the body: the momentum after a step is what was set
    scene = small_scene(gravity=[0, 0, 0], colliders=[],
                        domain={"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.05},
                        bodies=[{"shape": {"type": "box", "center": [0.5, 0.5, 0.5],
                                           "half_extent": [0.1, 0.1, 0.1]},
                                 "material": "jelly"}])
    sim = mpm.Simulation(scene)
    p = sim.particles
    chosen = p.id[p.id % 3 == 0]
    v = np.tile([1.0, 0.5, -0.25], (len(chosen), 1))
    v[:, 0] += 0.001 * (np.arange(len(chosen)) % 7)
    sim.set_velocities(chosen, v)
    p = sim.particles
    mass = p.mass.astype(np.float64)
    expected = (mass[:, None] * p.v).sum(axis=0)
    assert np.allclose(expected[1], 0.5 * mass[p.id % 3 == 0].sum())
    sim.step()
    p = sim.particles
    after = (p.mass.astype(np.float64)[:, None] * p.v).sum(axis=0)
    assert np.allclose(after, expected, rtol=2e-6 if mpm.dtype == np.float32 else 1e-12)
    # positions: exactly where set, in the engine's type
    target = np.array([0.45, 0.55, 0.56])
    sim.set_positions(chosen[:1], target)
    p = sim.particles
    assert np.array_equal(p.x[p.id == chosen[0]][0], target.astype(mpm.dtype))
    with pytest.raises(mpm.Error, match="coordinate 1 is 1.5"):
        sim.set_positions(chosen[1:2], [0.5, 1.5, 0.5])
    with pytest.raises(mpm.Error, match="no particle with id"):
        sim.set_velocities([4000000000], [0, 0, 0])
    with pytest.raises(ValueError):
        sim.set_velocities(chosen[:2], np.zeros((3, 3)))


def test_scripted_collider_moves_what_it_holds():
    scene = small_scene(gravity=[0, 0, 0],
                        domain={"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.04},
                        bodies=[{"shape": {"type": "box", "center": [0.5, 0.5, 0.5],
                                           "half_extent": [0.2, 0.2, 0.2]},
                                 "material": "jelly"}],
                        colliders=[{"name": "grip", "shape": {"type": "sphere",
                                                              "center": [0.5, 0.5, 0.5],
                                                              "radius": 0.14},
                                    "rule": "sticky"}])
    sim = mpm.Simulation(scene)
    t0 = sim.time
    sim.set_collider_pose("grip", [0.502, 0.5, 0.5])
    sim.step()
    dt = sim.time - t0
    grip = sim.colliders[0]
    assert np.allclose(grip.center, [0.502, 0.5, 0.5])
    assert grip.velocity[0] == pytest.approx(0.002 / dt, rel=1e-6)
    p = sim.particles
    deep = np.linalg.norm(p.x - 0.5, axis=1) < 0.03  # stencils inside the sphere
    assert deep.sum() >= 8
    assert np.allclose(p.v[deep, 0], 0.002 / dt, rtol=1e-5)
    # a quarter turn over a few steps about z, held after
    a = 0.02
    Rz = [[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]
    t0 = sim.time
    sim.set_collider_pose(0, [0.502, 0.5, 0.5], Rz)
    sim.step()
    assert sim.colliders[0].angular_velocity[2] == pytest.approx(a / (sim.time - t0), rel=1e-6)
    sim.step()
    assert np.all(sim.colliders[0].angular_velocity == 0)
    with pytest.raises(mpm.Error, match="not a rotation"):
        sim.set_collider_pose(0, [0.5, 0.5, 0.5], np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(mpm.Error, match="no collider named"):
        sim.set_collider_pose("nothing", [0, 0, 0])


def test_add_body_between_steps(tmp_path):
    scene = small_scene(gravity=[0, 0, 0], colliders=[],
                        domain={"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.05},
                        bodies=[{"shape": {"type": "box", "center": [0.5, 0.4, 0.5],
                                           "half_extent": [0.1, 0.1, 0.1]},
                                 "material": "jelly"}])
    ball = {"name": "ball", "shape": {"type": "sphere", "center": [0.5, 0.72, 0.5],
                                      "radius": 0.1},
            "material": "jelly", "velocity": [0, -1, 0]}
    sim = mpm.Simulation(scene)
    sim.open_output(str(tmp_path / "run"))
    sim.step()
    before = sim.particle_count
    with pytest.raises(mpm.SceneError, match=r"bodies\[1\]\.material"):
        sim.add_body(dict(ball, material="nope"))
    assert sim.particle_count == before
    made = sim.add_body(ball)
    assert made > 100 and sim.particle_count == before + made
    p = sim.particles
    new = p.body == 1
    assert new.sum() == made and p.id[new].min() >= before
    assert np.all(p.v[new, 1] == -1)
    sim.step()
    assert sim.info["bodies"] == 2
    # the folder's scene.json has the ball: the run resumes from it
    path = sim.checkpoint()
    steps = sim.steps
    sim.step()
    after = sim.particles
    x_straight = after.x[np.argsort(after.id)].copy()
    del sim, p, after
    import gc
    gc.collect()
    resumed = mpm.Simulation.resume(tmp_path / "run" / "scene.json", tmp_path / "run")
    assert resumed.steps == steps and resumed.info["last_checkpoint"] == path
    resumed.step()
    q = resumed.particles
    assert np.array_equal(q.x[np.argsort(q.id)], x_straight)


def test_ctrl_c_during_single_steps_is_not_lost():
    # a loop of step() calls: a SIGINT that lands inside a step still raises KeyboardInterrupt
    heavy = small_scene(domain={"min": [0, 0, 0], "max": [0.5, 0.5, 0.5], "dx": 0.0125},
                        time={"end": 5, "fps": 1})
    sim = mpm.Simulation(heavy)
    sim.threads = 1
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            while time.monotonic() - start < 20:
                sim.step()
    finally:
        timer.cancel()
    assert time.monotonic() - start < 20
    steps = sim.steps
    sim.step()  # still usable
    assert sim.steps == steps + 1
