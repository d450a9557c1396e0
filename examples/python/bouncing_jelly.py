"""A jelly cube thrown onto a floor, in a notebook's order: a scene built as a dict, a run with
a callback, the energy read back from the run's stats.csv and plotted, and a frame rendered.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/bouncing_jelly.py [OUT_DIR] [FRAMES]

Each cell below is one step of a notebook; in Jupyter, `plt.imshow(image)` shows the picture.
The energy plot needs matplotlib (Debian: python3-matplotlib); without it the energies are
printed as a table.
"""
import os
import sys

import numpy as np

import mpm

out = sys.argv[1] if len(sys.argv) > 1 else "out/python_jelly"
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 24

# %% the scene, as the keys of a scene file (docs/scene-format.md)
scene = {
    "name": "bouncing_jelly",
    "domain": {"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.025},
    "gravity": [0, -9.81, 0],
    "time": {"end": 1.0, "fps": 24},
    "materials": [{"name": "jelly", "model": "neo_hookean", "E": 2e4, "nu": 0.3,
                   "density": 1000}],
    "bodies": [{"name": "cube", "shape": {"type": "box", "center": [0.4, 0.55, 0.5],
                                          "half_extent": [0.1, 0.1, 0.1]},
                "material": "jelly", "velocity": [0.8, 0, 0]}],
    "colliders": [{"name": "floor", "shape": {"type": "halfspace", "point": [0, 0.1, 0],
                                              "normal": [0, 1, 0]}, "rule": "slip"}],
    "output": {"vtu": True, "ply": True, "stats": True},
}
sim = mpm.Simulation(scene)
print(sim, "-", sim.info["particles"], "particles, dx", sim.info["dx"])

# %% run, watching the lowest point of the cube after every frame
sim.open_output(out, overwrite=True)
lowest = []


def watch(s):
    p = s.particles  # numpy views of the engine's arrays, no copy
    lowest.append(float(p.x[:, 1].min()))


sim.run(frames=frames, callback=watch)
print(f"{sim.frame} frames, {sim.steps} steps, t = {sim.time:.3f} s; lowest point "
      f"{min(lowest):.4f} m (the floor is at 0.1 m)")

# %% the energies, from the run's stats.csv
stats = np.genfromtxt(os.path.join(out, "stats.csv"), delimiter=",", names=True)
t, kinetic, elastic = stats["time"], stats["kinetic_energy"], stats["elastic_energy"]
total = stats["total_energy"]
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for y, label in ((kinetic, "kinetic"), (elastic, "elastic"), (total, "total")):
        ax.plot(t, y, label=label)
    ax.set_xlabel("time, s")
    ax.set_ylabel("energy, J")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "energy.png"), dpi=100)
    print("energy plot:", os.path.join(out, "energy.png"))
except ImportError:
    print("(no matplotlib: the energies as a table)")
    print(" time s   kinetic J   elastic J     total J")
    for row in zip(t, kinetic, elastic, total):
        print(" %6.3f  %10.4f  %10.4f  %10.4f" % row)

# %% a frame, drawn by the engine's renderer (an image a notebook shows with plt.imshow)
image = mpm.render(sim, width=480, height=270, path=os.path.join(out, "last_frame.png"))
print("rendered", image.shape, "->", os.path.join(out, "last_frame.png"))
