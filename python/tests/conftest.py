"""Shared fixtures of the Python module's tests: run from the repository root (ctest does), with
the build tree's python/ on PYTHONPATH and MPM_BIN naming the mpm program."""

import json
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def small_scene(**changes):
    """A jelly block falling onto a slip floor, a few thousand particles, 24 fps."""
    scene = {
        "name": "py_block",
        "domain": {"min": [0, 0, 0], "max": [0.5, 0.5, 0.5], "dx": 0.025},
        "gravity": [0, -9.81, 0],
        "time": {"end": 0.5, "fps": 24},
        "solver": {"kernel": "quadratic", "transfer": "apic", "cfl": 0.5},
        "materials": [{"name": "jelly", "model": "neo_hookean", "E": 2e4, "nu": 0.3,
                       "density": 1000}],
        "bodies": [{"name": "block", "shape": {"type": "box", "center": [0.25, 0.25, 0.25],
                                               "half_extent": [0.08, 0.06, 0.07]},
                    "material": "jelly", "velocity": [0.2, 0, 0]}],
        "colliders": [{"name": "floor", "shape": {"type": "halfspace", "point": [0, 0.1, 0],
                                                  "normal": [0, 1, 0]}, "rule": "slip"}],
        "output": {"vtu": True, "ply": False, "stats": True},
    }
    scene.update(changes)
    return scene


@pytest.fixture
def scene():
    return small_scene()


@pytest.fixture
def mpm_bin():
    path = os.environ.get("MPM_BIN")
    if not path:
        pytest.fail("MPM_BIN is not set (ctest sets it to the mpm program)")
    return path


def load_example(name):
    with open(os.path.join(ROOT, "examples", name)) as f:
        return json.load(f)
