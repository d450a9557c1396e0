#!/usr/bin/python3
"""adversary.py - try the engine as an adversary would, and count what goes wrong.

    /usr/bin/python3 tools/adversary.py [--mpm build/mpm] [--cases 600] [--kills 20]
                                        [--seed 1] [--work DIR] [--keep]

Five families, each case run under a timeout, deterministic for a seed:
  scenes   every shipped example scene mutated so that it is certainly wrong (a number made a
           string, a required key removed, an unknown key added, a vector shortened, a number out
           of range or past the float range, the text truncated or given bytes that are not
           JSON), then `mpm check`
  meshes   the shipped meshes mutated (truncated, a face removed so that the surface opens, a
           face doubled, an index out of range, a NaN coordinate, overlapping copies), then
           `mpm check` of a scene that uses them
  folders  user files whose names look like a run's, a folder or a link named like a run file,
           the scene inside the output folder, run with --overwrite; named pipes where a file is
           read; two runs into one folder at once
  specials the defects a first campaign found one by one: numbers a float cannot hold, a
           domain far from the origin, an angle in radians, a conductivity that needs a million
           substeps, a mesh changed before a resume, a folder named like a checkpoint
  kills    a run killed with SIGKILL at a random moment and resumed until done, against the
           same run straight through: every frame byte for byte
It prints each case that went wrong and the totals: cases tried, refused cleanly (exit 2 naming
the file), crashes (a signal, a sanitizer report), hangs (the timeout), silent acceptances (exit
0 on a certainly wrong input), files lost (a user's file changed or gone, frames of two runs
mixed) and resumes that differ. Exit status 1 when any of the last five is not zero.
"""
import argparse
import filecmp
import glob
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMEOUT = 30


class Totals:
    def __init__(self):
        self.tried = self.refused = self.crashes = self.hangs = 0
        self.silent = self.lost = self.resume_diff = self.other = 0
        self.notes = []

    def bad(self, what, case, detail):
        self.notes.append("%s: %s: %s" % (what, case, detail.strip().splitlines()[-1][:200]
                                          if detail.strip() else "(no output)"))


def run(cmd, timeout=TIMEOUT, env=None):
    """(exit code, output); exit -1 for a timeout, -signal for a signal."""
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           timeout=timeout, env=env)
        return p.returncode, p.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired as e:
        return -1000, (e.stdout or b"").decode("utf-8", "replace")


def classify(tot, case, code, out, must_refuse=True, may_stop=False):
    """may_stop: a run that stops with exit 1, naming what went wrong, is a clean refusal too
    (a value a double build holds at load but that overflows in the step)."""
    tot.tried += 1
    crashed = code < 0 and code != -1000 or code >= 128 or "Sanitizer" in out or \
        "runtime error:" in out
    if code == -1000:
        tot.hangs += 1
        tot.bad("hang", case, out)
    elif crashed:
        tot.crashes += 1
        tot.bad("crash (exit %d)" % code, case, out)
    elif code == 0 and must_refuse:
        tot.silent += 1
        tot.bad("silently accepted", case, out)
    elif code == 2 or (code == 1 and may_stop):
        tot.refused += 1
    elif code != 0:
        tot.other += 1
        tot.bad("exit %d" % code, case, out)


# ---- scenes --------------------------------------------------------------------------------

def paths(node, prefix=()):
    """Every (path, value) of a JSON tree."""
    yield prefix, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from paths(v, prefix + (i,))


def parent_of(tree, path):
    node = tree
    for k in path[:-1]:
        node = node[k]
    return node


REQUIRED = [("domain", "dx"), ("domain", "min"), ("domain", "max")]


def mutate_scene(text, rng):
    """A certainly wrong variant of a scene's text, and what was done."""
    tree = json.loads(text)
    kind = rng.choice(["string", "remove", "unknown", "short", "range", "overflow", "truncate",
                       "bytes", "nan", "material", "shape"])
    nums = [(p, v) for p, v in paths(tree) if isinstance(v, (int, float)) and
            not isinstance(v, bool) and p and not isinstance(p[-1], int)]
    vecs = [(p, v) for p, v in paths(tree) if isinstance(v, list) and len(v) == 3 and
            all(isinstance(x, (int, float)) for x in v) and p and not isinstance(p[-1], int)]
    if kind == "string" and nums:
        p, v = rng.choice(nums)
        parent_of(tree, p)[p[-1]] = "%s" % v
        return json.dumps(tree), "%s made a string" % "/".join(map(str, p))
    if kind == "remove":
        mats = tree.get("materials", [])
        choices = list(REQUIRED)
        for i, m in enumerate(mats):
            if isinstance(m, dict) and "E" in m:
                choices.append(("materials", i, "E"))
        for i, b in enumerate(tree.get("bodies", [])):
            choices.append(("bodies", i, "shape"))
        p = rng.choice(choices)
        try:
            del parent_of(tree, p)[p[-1]]
        except (KeyError, IndexError, TypeError):
            return None
        return json.dumps(tree), "required %s removed" % "/".join(map(str, p))
    if kind == "unknown":
        objs = [(p, v) for p, v in paths(tree) if isinstance(v, dict) and v]
        p, v = rng.choice(objs)
        k = rng.choice(list(v.keys()))
        v[k + "x"] = v[k]
        return json.dumps(tree), "unknown key %s added" % "/".join(map(str, p + (k + "x",)))
    if kind == "short" and vecs:
        p, v = rng.choice(vecs)
        parent_of(tree, p)[p[-1]] = v[:2]
        return json.dumps(tree), "%s given 2 numbers" % "/".join(map(str, p))
    if kind == "range":
        choices = [("domain", "dx", rng.choice([0, -0.01])), ("time", "fps", 0),
                   ("time", "end", -1)]
        for i, m in enumerate(tree.get("materials", [])):
            if isinstance(m, dict):
                choices += [("materials", i, "nu", rng.choice([0.5, 0.7, -1])),
                            ("materials", i, "density", rng.choice([0, -1000])),
                            ("materials", i, "E", rng.choice([0, -1e5]))]
        *p, value = rng.choice(choices)
        try:
            parent_of(tree, p)[p[-1]] = value
        except (KeyError, IndexError, TypeError):
            return None
        return json.dumps(tree), "%s = %s" % ("/".join(map(str, p)), value)
    if kind == "overflow" and nums:
        p, v = rng.choice(nums)
        s = json.dumps(tree)
        marker = "__OVERFLOW__"
        parent_of(tree, p)[p[-1]] = marker
        s = json.dumps(tree).replace('"%s"' % marker, rng.choice(["1e400", "-1e400", "1e999"]))
        return s, "%s past the double range" % "/".join(map(str, p))
    if kind == "truncate":
        cut = rng.randrange(1, max(2, len(text) - 2))
        return text[:cut], "truncated at byte %d" % cut
    if kind == "bytes":
        at = rng.randrange(0, len(text))
        junk = rng.choice(["\0", "\x01\x02", "}", "]]", ",,", "\"", "\ufeff{"])
        body = text[:at] + junk + text[at:]
        try:  # inside a string it may still be a valid scene: not certainly wrong
            json.loads(body)
            return None
        except ValueError:
            return body, "%r inserted at byte %d" % (junk, at)
    if kind == "nan" and nums:
        p, v = rng.choice(nums)
        marker = "__NAN__"
        parent_of(tree, p)[p[-1]] = marker
        return json.dumps(tree).replace('"%s"' % marker, rng.choice(["NaN", "Infinity", "nan"])), \
            "%s = NaN" % "/".join(map(str, p))
    if kind == "material":
        bodies = tree.get("bodies", [])
        if bodies:
            b = rng.randrange(len(bodies))
            bodies[b]["material"] = rng.choice(["no_such_material", 99, -1])
            return json.dumps(tree), "bodies/%d/material names none" % b
    if kind == "shape":
        bodies = tree.get("bodies", [])
        if bodies:
            b = rng.randrange(len(bodies))
            shape = bodies[b].get("shape", {})
            shape["type"] = rng.choice(["cube", "Sphere", "", 3])
            return json.dumps(tree), "bodies/%d/shape/type unknown" % b
    return None


def scenes(tot, mpm, work, rng, count):
    seeds = sorted(glob.glob(os.path.join(ROOT, "examples", "*.json")) +
                   glob.glob(os.path.join(ROOT, "examples", "*", "*.json")))
    # the seeds themselves are accepted (a control: the check is not refusing everything)
    for s in seeds[:3]:
        code, out = run([mpm, "check", s])
        if code != 0:
            tot.bad("a shipped scene refused", s, out)
            tot.other += 1
    made = 0
    while made < count:
        seed = rng.choice(seeds)
        text = open(seed, encoding="utf-8").read()
        m = mutate_scene(text, rng)
        if not m:
            continue
        body, what = m
        # mesh paths stay resolvable: the case lives beside its seed's folder's meshes
        case = os.path.join(work, "scene_%04d.json" % made)
        body = body.replace('"meshes/', '"%s/' % os.path.join(os.path.dirname(seed), "meshes"))
        with open(case, "w", encoding="utf-8") as f:
            f.write(body)
        code, out = run([mpm, "check", case])
        classify(tot, "%s (%s: %s)" % (os.path.basename(case), os.path.relpath(seed, ROOT), what),
                 code, out)
        made += 1


# ---- meshes --------------------------------------------------------------------------------

def mutate_mesh(lines, rng):
    vs = [i for i, l in enumerate(lines) if l.startswith("v ")]
    fs = [i for i, l in enumerate(lines) if l.startswith("f ")]
    kind = rng.choice(["truncate", "open", "double", "index", "nan", "overlap", "zero"])
    if kind == "truncate":
        cut = rng.randrange(len(vs) // 2, len(vs))
        return lines[:cut], "truncated in the vertices (faces gone)"
    if kind == "open":
        k = rng.choice(fs)
        return lines[:k] + lines[k + 1:], "face at line %d removed (open)" % (k + 1)
    if kind == "double":
        k = rng.choice(fs)
        return lines[:k + 1] + [lines[k]] + lines[k + 1:], "face at line %d doubled" % (k + 1)
    if kind == "index":
        k = rng.choice(fs)
        parts = lines[k].split()
        parts[1] = str(len(vs) + rng.randrange(1, 1000))
        return lines[:k] + [" ".join(parts) + "\n"] + lines[k + 1:], "index out of range"
    if kind == "nan":
        k = rng.choice(vs)
        return lines[:k] + ["v nan 0 0\n"] + lines[k + 1:], "vertex NaN"
    if kind == "zero":
        return [l for l in lines if not l.startswith("f ")], "no faces"
    # two copies, the second moved by a tenth of the mesh: overlapping shells
    n = len(vs)
    out = list(lines)
    xyz = [[float(t) for t in lines[i].split()[1:4]] for i in vs]
    size = max(max(v[d] for v in xyz) - min(v[d] for v in xyz) for d in range(3))
    for x, y, z in xyz:
        out.append("v %.9g %.9g %.9g\n" % (x + 0.1 * size, y + 0.07 * size, z + 0.05 * size))
    for i in fs:
        idx = [str(int(t.split("/")[0]) + n) for t in lines[i].split()[1:]]
        out.append("f " + " ".join(idx) + "\n")
    return out, "a second, overlapping copy"


MESH_SCENE = """{"domain": {"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.02},
 "time": {"end": 0.1, "fps": 10},
 "materials": [{"name": "m", "model": "neo_hookean", "E": 1e5, "nu": 0.3, "density": 1000}],
 "bodies": [{"material": "m", "shape": {"type": "mesh", "file": "%s", "center": [0.5, 0.5, 0.5],
   "scale": %g}}]}"""


def meshes(tot, mpm, work, rng, count):
    seeds = {"bunny.obj": 0.03, "torus.obj": 0.1}  # the scale that makes each about 0.3 m
    for made in range(count):
        name = rng.choice(sorted(seeds))
        lines = open(os.path.join(ROOT, "examples", "meshes", name), encoding="utf-8").readlines()
        lines, what = mutate_mesh(lines, rng)
        mesh = os.path.join(work, "mesh_%04d.obj" % made)
        with open(mesh, "w", encoding="utf-8") as f:
            f.writelines(lines)
        scene = os.path.join(work, "mesh_%04d.json" % made)
        with open(scene, "w", encoding="utf-8") as f:
            f.write(MESH_SCENE % (mesh, seeds[name]))
        code, out = run([mpm, "check", scene])
        # a doubled face makes four triangles of its edges: certainly wrong too
        classify(tot, "%s (%s: %s)" % (os.path.basename(scene), name, what), code, out)


# ---- output folders --------------------------------------------------------------------------

SMALL = """{"domain": {"min": [0, 0, 0], "max": [1, 1, 1], "dx": 0.05},
 "time": {"end": %g, "fps": 10},
 "materials": [{"name": "m", "model": "neo_hookean", "E": 1e4, "nu": 0.3, "density": 1000}],
 "bodies": [{"material": "m", "shape": {"type": "box", "center": [0.5, 0.5, 0.5],
   "half_extent": [0.15, 0.15, 0.15]}}],
 "output": {"checkpoint_every": 1}}"""

USER_FILES = ["frame_notes.txt", "frame_0001.vtu.bak", "surface_scan.stl", "checkpoint_plan.md",
              "domains_list.txt", "levelset_ideas.txt", "grid_cells_todo.txt", "stats.csv.old",
              "frames.pvd~", "scene.json.orig", "run_notes.pvd.txt"]


def folders(tot, mpm, work, rng):
    """Each user file must come out byte for byte; each check counts as a case."""
    scene = os.path.join(work, "small.json")
    with open(scene, "w", encoding="utf-8") as f:
        f.write(SMALL % 0.3)
    # 1. user files with run-like names, then --overwrite
    out = os.path.join(work, "run_user")
    os.makedirs(out)
    for n in USER_FILES:
        with open(os.path.join(out, n), "w") as f:
            f.write("the user's own %s\n" % n)
    os.makedirs(os.path.join(out, "frame_backup_full"))
    with open(os.path.join(out, "frame_backup_full", "keep.txt"), "w") as f:
        f.write("keep\n")
    for attempt in range(2):
        code, text = run([mpm, "run", scene, "-o", out, "--overwrite", "--quiet"])
        tot.tried += 1
        if code not in (0, 2):
            tot.other += 1
            tot.bad("exit %d" % code, "--overwrite over user files", text)
    lost = [n for n in USER_FILES if not os.path.exists(os.path.join(out, n)) or
            open(os.path.join(out, n)).read() != "the user's own %s\n" % n]
    if not os.path.exists(os.path.join(out, "frame_backup_full", "keep.txt")):
        lost.append("frame_backup_full/keep.txt")
    if lost:
        tot.lost += len(lost)
        tot.bad("files lost", "--overwrite", " ".join(lost))
    # 2. the scene inside the output folder, --overwrite
    out2 = os.path.join(work, "run_self")
    os.makedirs(out2)
    inner = os.path.join(out2, "scene.json")
    shutil.copy(scene, inner)
    before = open(inner).read()
    code, text = run([mpm, "run", inner, "-o", out2, "--overwrite", "--quiet"])
    tot.tried += 1
    if not os.path.exists(inner) or open(inner).read() != before:
        tot.lost += 1
        tot.bad("files lost", "the scene run from its output folder", text)
    # 3. a link named like a run file, pointing at a user file outside
    out3 = os.path.join(work, "run_link")
    os.makedirs(out3)
    victim = os.path.join(work, "victim.txt")
    with open(victim, "w") as f:
        f.write("precious\n")
    os.symlink(victim, os.path.join(out3, "frame_0001.vtu"))
    code, text = run([mpm, "run", scene, "-o", out3, "--overwrite", "--quiet"])
    tot.tried += 1
    if open(victim).read() != "precious\n":
        tot.lost += 1
        tot.bad("files lost", "a link named frame_0001.vtu", text)
    # 4. named pipes where the engine reads a file: the scene, a mesh, a checkpoint to resume
    fifo = os.path.join(work, "pipe.json")
    os.mkfifo(fifo)
    code, text = run([mpm, "check", fifo], 10)
    classify(tot, "a FIFO as the scene", code, text)
    pipe_mesh = os.path.join(work, "pipe.obj")
    os.mkfifo(pipe_mesh)
    scene_pm = os.path.join(work, "pipe_mesh.json")
    with open(scene_pm, "w", encoding="utf-8") as f:
        f.write(MESH_SCENE % (pipe_mesh, 0.1))
    code, text = run([mpm, "check", scene_pm], 10)
    classify(tot, "a FIFO as a mesh", code, text)
    out5 = os.path.join(work, "run_pipe")
    code, text = run([mpm, "run", scene, "-o", out5, "--quiet", "--frames", "2"])
    for c in glob.glob(os.path.join(out5, "checkpoint_*.h5")):
        os.remove(c)
    os.mkfifo(os.path.join(out5, "checkpoint_000000000099.h5"))
    code, text = run([mpm, "run", scene, "--resume", out5, "--quiet"], 10)
    classify(tot, "a FIFO named like a checkpoint", code, text, must_refuse=False)
    # 5. two runs into one folder at once, several times: one must be refused or the frames
    #    must all be one run's
    with open(scene, "w", encoding="utf-8") as f:
        f.write(SMALL % 1.0)
    for trial in range(6):
        out4 = os.path.join(work, "run_twice_%d" % trial)
        a = subprocess.Popen([mpm, "run", scene, "-o", out4, "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        time.sleep(rng.random() * 0.05)
        b = subprocess.Popen([mpm, "run", scene, "-o", out4, "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        ca, cb = a.wait(TIMEOUT), b.wait(TIMEOUT)
        tot.tried += 1
        if ca == 0 and cb == 0:
            tot.lost += 1
            tot.bad("files lost", "two runs into %s" % out4, "both exited 0: frames mixed")


# ---- the defects found by hand, as cases -------------------------------------------------------

def specials(tot, mpm, work):
    """Inputs a first campaign found wrong one by one: each must be refused, or warned of."""
    def scene_with(name, text):
        path = os.path.join(work, name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        return path
    base = json.loads(SMALL % 0.2)
    _, version = run([mpm, "--version"])
    single = "(float" in version  # the float build: what a float cannot hold is refused at load
    cases = []
    t = json.loads(json.dumps(base))
    t["materials"][0]["density"] = 1e308  # mass overflows a float
    cases.append(("density 1e308", scene_with("sp_density.json", json.dumps(t)), "refuse"))
    t = json.loads(json.dumps(base))
    t["heat"] = {"temperature": 1e308}
    cases.append(("heat temperature 1e308", scene_with("sp_heat.json", json.dumps(t)), "refuse"))
    if single:  # floats 1 m apart there; a double holds it
        t = json.loads(json.dumps(base))
        t["domain"]["min"] = [1e7, 0, 0]
        t["domain"]["max"] = [1e7 + 1, 1, 1]
        t["bodies"][0]["shape"]["center"] = [1e7 + 0.5, 0.5, 0.5]
        cases.append(("a domain at 1e7 m", scene_with("sp_far.json", json.dumps(t)), "refuse"))
    t = json.loads(json.dumps(base))
    t["materials"][0].update({"model": "drucker_prager", "friction_angle": 0.61})
    cases.append(("friction_angle in radians", scene_with("sp_angle.json", json.dumps(t)),
                  "warn:friction_angle"))
    t = json.loads(json.dumps(base))
    t["heat"] = {"temperature": 20}
    t["materials"][0].update({"conductivity": 1e30})
    cases.append(("conductivity 1e30", scene_with("sp_kappa.json", json.dumps(t)),
                  "warn:substeps"))
    for what, path, expect in cases:
        code, out = run([mpm, "check", path])
        if code == 0 and expect == "refuse":
            # `check` accepted it: does a run of one frame write non-finite values?
            code, out = run([mpm, "run", path, "-o", path + ".out", "--frames", "1", "--quiet",
                             "--overwrite"])
        if expect.startswith("warn:"):
            tot.tried += 1
            if code == 0 and expect[5:] not in out:
                tot.silent += 1
                tot.bad("silently accepted", what, out or "(no warning)")
            elif code != 0:
                classify(tot, what, code, out, must_refuse=False)
                tot.tried -= 1
            continue
        classify(tot, what, code, out, may_stop=not single)
    # a checkpoint's mesh changed before the resume
    mesh = os.path.join(work, "sp_mesh.obj")
    shutil.copy(os.path.join(ROOT, "examples", "meshes", "torus.obj"), mesh)
    t = json.loads(MESH_SCENE % (mesh, 0.1))
    t["time"] = {"end": 0.5, "fps": 10}
    t["bodies"][0]["domains"] = True
    t["output"] = {"checkpoint_every": 1}
    path = scene_with("sp_mesh.json", json.dumps(t))
    out_dir = os.path.join(work, "sp_mesh_run")
    run([mpm, "run", path, "-o", out_dir, "--frames", "2", "--quiet"], 120)
    lines = open(mesh).readlines()
    with open(mesh, "w") as f:  # a smaller torus: every vertex scaled
        for l in lines:
            if l.startswith("v "):
                x, y, z = (float(v) * 0.7 for v in l.split()[1:4])
                f.write("v %g %g %g\n" % (x, y, z))
            else:
                f.write(l)
    code, out = run([mpm, "run", path, "--resume", out_dir, "--quiet"], 120)
    classify(tot, "resume after the mesh changed", code, out)
    # a folder named like a checkpoint beside the real ones
    t = json.loads(SMALL % 0.5)
    t["output"] = {"checkpoint_every": 1}
    path = scene_with("sp_dir.json", json.dumps(t))
    out_dir = os.path.join(work, "sp_dir_run")
    run([mpm, "run", path, "-o", out_dir, "--frames", "2", "--quiet"], 120)
    os.makedirs(os.path.join(out_dir, "checkpoint_000000099999.h5"))
    code, out = run([mpm, "run", path, "--resume", out_dir, "--quiet"], 120)
    classify(tot, "a folder named like a checkpoint", code, out, must_refuse=False)
    if code == 2:  # refusing the run is not what a resume should do: the checkpoints are valid
        tot.refused -= 1
        tot.other += 1
        tot.bad("exit 2", "a folder named like a checkpoint", out)


# ---- kill and resume ---------------------------------------------------------------------

def kills(tot, mpm, work, rng, count):
    scene = os.path.join(work, "kill.json")
    with open(scene, "w", encoding="utf-8") as f:
        f.write((SMALL % 3.0).replace('"dx": 0.05', '"dx": 0.03'))
    straight = os.path.join(work, "kill_straight")
    t0 = time.time()
    code, text = run([mpm, "run", scene, "-o", straight, "--quiet", "--threads", "1"], 600)
    length = time.time() - t0
    if code != 0:
        tot.other += 1
        tot.bad("exit %d" % code, "the straight run", text)
        return
    frames = sorted(os.path.basename(p) for p in glob.glob(os.path.join(straight, "frame_*")))
    for trial in range(count):
        out = os.path.join(work, "kill_%02d" % trial)
        p = subprocess.Popen([mpm, "run", scene, "-o", out, "--quiet", "--threads", "1"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep((0.05 + 0.85 * rng.random()) * length) # somewhere in the run
        p.send_signal(signal.SIGKILL)
        p.wait()
        for _ in range(50):
            args = [mpm, "run", scene, "--quiet", "--threads", "1"]
            args += ["--resume", out] if glob.glob(os.path.join(out, "checkpoint_*.h5")) else \
                ["-o", out, "--overwrite"]
            code, text = run(args, 600)
            if code == 0:
                break
        tot.tried += 1
        diff = [f for f in frames if not os.path.exists(os.path.join(out, f)) or
                not filecmp.cmp(os.path.join(straight, f), os.path.join(out, f), shallow=False)]
        if diff:
            tot.resume_diff += 1
            tot.bad("resume differs", out, "%d frames differ, first %s" % (len(diff), diff[0]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mpm", default=os.path.join(ROOT, "build", "mpm"))
    ap.add_argument("--cases", type=int, default=600, help="scene and mesh cases together")
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--work", default=None)
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    a = ap.parse_args()
    mpm = os.path.abspath(a.mpm)
    work = a.work or tempfile.mkdtemp(prefix="mpm-adversary-")
    os.makedirs(work, exist_ok=True)
    rng = random.Random(a.seed)
    tot = Totals()
    t0 = time.time()
    meshes_n = a.cases // 6
    scenes(tot, mpm, work, rng, a.cases - meshes_n)
    meshes(tot, mpm, work, rng, meshes_n)
    folders(tot, mpm, work, rng)
    specials(tot, mpm, work)
    kills(tot, mpm, work, rng, a.kills)
    for n in tot.notes:
        print(n)
    print("mpm: %s (seed %d, %.0f s)" % (mpm, a.seed, time.time() - t0))
    print("cases tried %d: refused cleanly %d, crashes %d, hangs %d, silent acceptances %d, "
          "files lost %d, resumes that differ %d (of %d kills), other exits %d" %
          (tot.tried, tot.refused, tot.crashes, tot.hangs, tot.silent, tot.lost,
           tot.resume_diff, a.kills, tot.other))
    if not a.keep and not a.work:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if tot.crashes or tot.hangs or tot.silent or tot.lost or tot.resume_diff else 0


if __name__ == "__main__":
    sys.exit(main())
