"""bench_python.py - what driving the engine from Python costs, against the engine's own loop.

    PYTHONPATH=build/python /usr/bin/python3 python/bench/bench_python.py [--particles N]
        [--frames F] [--rounds R] [--threads T]

A jelly block of about N particles (default 1e5) falling onto a floor. Each round runs F frames
twice on fresh simulations, alternately: once with advance_frame() (the steps looped in C) and
once with step() called from Python for every step; both take the same steps. It prints the
time per step of each and the difference, the Python overhead per step, in percent of the step,
and what reading the particles costs (sim.particles and its x array: no copy).
"""
import argparse
import os
import platform
import time

# (before the engine loads OpenMP) threads that sleep when idle and no thread-count tuning: with
# busy-waiting threads and the tuner, this 2-core VM's step times fall in two bands 60% apart
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
os.environ.setdefault("MPM_THREADS_TUNE", "0")

import numpy as np  # noqa: E402

import mpm  # noqa: E402


def scene(n):
    # particles at 2 per cell and axis: side = (n / 8)^(1/3) cells
    cells = max(4, round((n / 8) ** (1 / 3)))
    dx = 0.01
    side = cells * dx
    return {
        "domain": {"min": [0, 0, 0], "max": [side + 0.2, side + 0.3, side + 0.2], "dx": dx},
        "gravity": [0, -9.81, 0],
        "time": {"end": 10, "fps": 60},
        "materials": [{"name": "jelly", "model": "neo_hookean", "E": 1e5, "nu": 0.3,
                       "density": 1000}],
        "bodies": [{"shape": {"type": "box",
                              "center": [0.1 + side / 2, 0.12 + side / 2, 0.1 + side / 2],
                              "half_extent": [side / 2, side / 2, side / 2]},
                    "material": "jelly"}],
        "colliders": [{"shape": {"type": "halfspace", "point": [0, 0.06, 0],
                                 "normal": [0, 1, 0]}, "rule": "slip"}],
        "output": {"vtu": False, "ply": False, "stats": False},
    }


def run(s, frames, threads, from_python):
    sim = mpm.Simulation(s)
    sim.threads = threads
    sim.advance_frame()  # warm: first-touch of the arrays, the grid's pages
    steps0 = sim.steps
    t0 = time.perf_counter()
    if from_python:
        end = sim.frame + frames
        while sim.frame < end:
            sim.step()
    else:
        for _ in range(frames):
            sim.advance_frame()
    return time.perf_counter() - t0, sim.steps - steps0, sim


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=float, default=1e5)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    s = scene(int(a.particles))
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f
                       if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    print(f"machine: {platform.node()}, {os.cpu_count()} cores, {cpu}; "
          f"mpm {mpm.version()} ({mpm.real_type()}), {a.threads} threads")
    c_times, py_times = [], []
    for r in range(a.rounds):
        tc, nc, sim = run(s, a.frames, a.threads, False)
        tp, npy, _ = run(s, a.frames, a.threads, True)
        assert nc == npy, (nc, npy)
        c_times.append(tc / nc)
        py_times.append(tp / npy)
        print(f"round {r + 1}: {sim.particle_count} particles, {nc} steps: advance_frame "
              f"{1e3 * tc / nc:.3f} ms a step, step() from Python {1e3 * tp / npy:.3f} ms "
              f"({100 * (tp / npy / (tc / nc) - 1):+.2f}%)")
    c, py = np.median(c_times), np.median(py_times)
    print(f"median: {1e3 * c:.3f} ms a step in C's loop, {1e3 * py:.3f} from Python: "
          f"{100 * (py / c - 1):+.2f}% (rounds {min(py_times) / max(c_times) - 1:+.2%} to "
          f"{max(py_times) / min(c_times) - 1:+.2%})")
    # reading the state
    reps = 2000
    t0 = time.perf_counter()
    for _ in range(reps):
        p = sim.particles
        x = p.x
    t = (time.perf_counter() - t0) / reps
    print(f"sim.particles then .x ({x.shape[0]} x 3, no copy): {1e6 * t:.1f} us; a copy of x "
          f"would move {x.nbytes / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
