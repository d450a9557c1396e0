/* simulation.c - _Simulation, the handle's type (see pympm.h). The Python class mpm.Simulation
 * (mpm/__init__.py) derives from it and adds the numpy-facing API. */
#include "pympm.h"

#include <signal.h>
#include <string.h>

/* ---- Ctrl-C during a call without the GIL ---------------------------------------------
 * Python's own SIGINT handler only notes the signal for the interpreter, which cannot run while
 * the engine holds the thread. For the call, on the main thread, a handler of ours raises the
 * engine's interrupt flag (mpm_sim_set_interrupt): the engine stops between two steps with the
 * state consistent, and the call raises KeyboardInterrupt. */
static volatile int interrupt_flag;
unsigned long pympm_main_thread; /* the interpreter's main thread (mpm/__init__.py sets it) */

static void on_sigint(int sig) {
  (void)sig;
  interrupt_flag = 1;
}

typedef struct call_state {
  PyOS_sighandler_t previous;
  int installed;
  PyThreadState *thread;
} call_state;

PyThreadState *pympm_unlock(pympm_sim *s) {
  s->busy = 1;
  return PyEval_SaveThread();
}

void pympm_relock(pympm_sim *s, PyThreadState *t) {
  PyEval_RestoreThread(t);
  s->busy = 0;
  for (; s->deferred > 0; --s->deferred) mpm_sim_hold_particle_arrays(s->sim, -1);
}

/* Catch SIGINT (main thread) and release the GIL, s busy (the caller checked ready()). */
static void call_begin(pympm_sim *s, call_state *c) {
  interrupt_flag = 0;
  c->installed = PyThread_get_thread_ident() == pympm_main_thread;
  if (c->installed) c->previous = PyOS_setsig(SIGINT, on_sigint);
  c->thread = pympm_unlock(s);
}

/* The GIL back, SIGINT's handler restored. A Ctrl-C the engine did not stop for (it came
 * during a call's last step, or a single step) goes to Python, which raises KeyboardInterrupt
 * at its next instruction, as it would have without our handler. */
static void call_end(pympm_sim *s, call_state *c, mpm_status st) {
  pympm_relock(s, c->thread);
  if (c->installed) PyOS_setsig(SIGINT, c->previous);
  if (interrupt_flag && st != MPM_ERR_INTERRUPTED) PyErr_SetInterrupt();
  interrupt_flag = 0;
}

/* The exception for a failed call of the engine (KeyboardInterrupt for an interrupt). */
static PyObject *failed(pympm_sim *s, mpm_status st) {
  if (st == MPM_ERR_INTERRUPTED) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    return NULL;
  }
  return pympm_raise(st, mpm_sim_last_error(s->sim), 0);
}

static int ready(pympm_sim *s) {
  if (!s->sim) {
    PyErr_SetString(PyExc_RuntimeError, "the simulation was not created (its __init__ failed)");
    return 0;
  }
  if (s->busy) {
    PyErr_SetString(PyExc_RuntimeError,
                    "the simulation is running a call in another thread; one call at a time");
    return 0;
  }
  return 1;
}

/* ---- creation -------------------------------------------------------------------------- */

static int sim_init(PyObject *self, PyObject *args, PyObject *kw) {
  pympm_sim *s = (pympm_sim *)self;
  static char *names[] = {"json", "path", "base_dir", NULL};
  const char *json = NULL, *path = NULL, *base = NULL;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "|zzz", names, &json, &path, &base)) return -1;
  if (s->sim) {
    PyErr_SetString(PyExc_RuntimeError, "the simulation is already created");
    return -1;
  }
  if ((json == NULL) == (path == NULL)) {
    PyErr_SetString(PyExc_TypeError, "give the scene as json= (text) or path= (a file)");
    return -1;
  }
  char err[4096];
  err[0] = 0;
  mpm_sim *sim = NULL;
  mpm_status st;
  Py_BEGIN_ALLOW_THREADS;
  st = path ? mpm_sim_create_from_file(path, &sim, err, sizeof err)
            : mpm_sim_create_from_json(json, base, &sim, err, sizeof err);
  Py_END_ALLOW_THREADS;
  if (st != MPM_OK) {
    pympm_raise(st, err, 1);
    return -1;
  }
  s->sim = sim;
  mpm_sim_set_interrupt(sim, &interrupt_flag);
  return 0;
}

static void sim_dealloc(PyObject *self) {
  pympm_sim *s = (pympm_sim *)self;
  if (s->weakrefs) PyObject_ClearWeakRefs(self);
  mpm_sim_destroy(s->sim); /* no buffer lives: each holds a reference to this object */
  s->sim = NULL;
  Py_TYPE(self)->tp_free(self);
}

/* ---- advancing ------------------------------------------------------------------------- */

static PyObject *sim_step(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  double max_dt = 0;
  if (!PyArg_ParseTuple(args, "|d", &max_dt) || !ready(s)) return NULL;
  const double t0 = mpm_sim_time(s->sim);
  call_state c;
  call_begin(s, &c);
  const mpm_status st = mpm_sim_step(s->sim, max_dt);
  call_end(s, &c, st);
  s->generation++;
  if (st != MPM_OK) return failed(s, st);
  return PyFloat_FromDouble(mpm_sim_time(s->sim) - t0);
}

static PyObject *sim_advance_frame(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  call_state c;
  call_begin(s, &c);
  const mpm_status st = mpm_sim_advance_frame(s->sim);
  call_end(s, &c, st);
  s->generation++;
  if (st != MPM_OK) return failed(s, st);
  return PyLong_FromLong(mpm_sim_frame(s->sim));
}

static PyObject *sim_next_dt(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  double dt = 0;
  const mpm_status st = mpm_sim_next_dt(s->sim, &dt);
  if (st != MPM_OK) return failed(s, st);
  return PyFloat_FromDouble(dt);
}

/* ---- output, checkpoints --------------------------------------------------------------- */

static PyObject *sim_open_output(PyObject *self, PyObject *args, PyObject *kw) {
  pympm_sim *s = (pympm_sim *)self;
  static char *names[] = {"dir", "overwrite", NULL};
  const char *dir = NULL;
  int overwrite = 0;
  if (!PyArg_ParseTupleAndKeywords(args, kw, "|zp", names, &dir, &overwrite) || !ready(s))
    return NULL;
  mpm_status st;
  PyThreadState *unlocked = pympm_unlock(s);
  st = mpm_sim_open_output(s->sim, dir, overwrite ? MPM_OUTPUT_OVERWRITE : MPM_OUTPUT_NEW);
  pympm_relock(s, unlocked);
  if (st != MPM_OK) return failed(s, st);
  Py_RETURN_NONE;
}

static PyObject *sim_write_frame_to(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  const char *dir;
  int overwrite = 0;
  if (!PyArg_ParseTuple(args, "sp", &dir, &overwrite) || !ready(s)) return NULL;
  char names[4096];
  mpm_status st;
  PyThreadState *unlocked = pympm_unlock(s);
  st = mpm_sim_write_frame_to(s->sim, dir, overwrite ? MPM_OUTPUT_OVERWRITE : MPM_OUTPUT_NEW, names,
                              sizeof names);
  pympm_relock(s, unlocked);
  if (st != MPM_OK) return failed(s, st);
  return PyUnicode_DecodeFSDefault(names);
}

static PyObject *sim_checkpoint(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  char path[4096];
  mpm_status st;
  PyThreadState *unlocked = pympm_unlock(s);
  st = mpm_sim_write_checkpoint(s->sim, path, sizeof path);
  pympm_relock(s, unlocked);
  if (st != MPM_OK) return failed(s, st);
  return PyUnicode_DecodeFSDefault(path);
}

static PyObject *sim_resume_from(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  const char *dir;
  if (!PyArg_ParseTuple(args, "s", &dir) || !ready(s)) return NULL;
  char path[4096];
  mpm_status st;
  PyThreadState *unlocked = pympm_unlock(s);
  st = mpm_sim_resume(s->sim, dir, path, sizeof path);
  pympm_relock(s, unlocked);
  s->generation++;
  if (st != MPM_OK) return failed(s, st);
  return PyUnicode_DecodeFSDefault(path);
}

/* ---- state ----------------------------------------------------------------------------- */

static PyObject *sim_release_domains(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  double lo[3], hi[3];
  if (!PyArg_ParseTuple(args, "(ddd)(ddd)", &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2]) ||
      !ready(s))
    return NULL;
  size_t count = 0;
  const mpm_status st = mpm_sim_release_domains(s->sim, lo, hi, &count);
  s->generation++;
  if (st != MPM_OK) return failed(s, st);
  return PyLong_FromSize_t(count);
}

/* _set(which, ids, values): which 0 velocities, 1 positions; ids a contiguous buffer of uint32,
 * values of 3 doubles per id (mpm/__init__.py converts). */
static PyObject *sim_set(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  int which;
  Py_buffer ids, values;
  if (!PyArg_ParseTuple(args, "iy*y*", &which, &ids, &values)) return NULL;
  PyObject *out = NULL;
  const size_t count = (size_t)ids.len / sizeof(uint32_t);
  if (!ready(s)) {
    /* (the exception is set) */
  } else if ((size_t)values.len != 3 * count * sizeof(double)) {
    PyErr_SetString(PyExc_ValueError, "expected three values for each id");
  } else {
    const mpm_status st = which == 0 ? mpm_sim_set_velocities(s->sim, count, ids.buf, values.buf)
                                     : mpm_sim_set_positions(s->sim, count, ids.buf, values.buf);
    s->generation++; /* (a refusal changed nothing, but the views are cheap to take again) */
    if (st != MPM_OK) {
      failed(s, st);
    } else {
      out = Py_None;
      Py_INCREF(out);
    }
  }
  PyBuffer_Release(&ids);
  PyBuffer_Release(&values);
  return out;
}

/* _set_collider_pose(index, (cx, cy, cz), rotation: 9 numbers or None) */
static PyObject *sim_set_collider_pose(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  int index;
  double c[3], R[9];
  PyObject *rot;
  if (!PyArg_ParseTuple(args, "i(ddd)O", &index, &c[0], &c[1], &c[2], &rot) || !ready(s))
    return NULL;
  if (rot != Py_None && !PyArg_ParseTuple(rot, "ddddddddd", &R[0], &R[1], &R[2], &R[3], &R[4],
                                          &R[5], &R[6], &R[7], &R[8]))
    return NULL;
  const mpm_status st = mpm_sim_set_collider_pose(s->sim, index, c, rot == Py_None ? NULL : R);
  if (st != MPM_OK) return failed(s, st);
  Py_RETURN_NONE;
}

/* _add_body(json, base_dir) -> particles made */
static PyObject *sim_add_body(PyObject *self, PyObject *args) {
  pympm_sim *s = (pympm_sim *)self;
  const char *json, *base = NULL;
  if (!PyArg_ParseTuple(args, "s|z", &json, &base) || !ready(s)) return NULL;
  size_t count = 0;
  mpm_status st;
  PyThreadState *unlocked = pympm_unlock(s);
  st = mpm_sim_add_body(s->sim, json, base, &count);
  pympm_relock(s, unlocked);
  s->generation++;
  if (st != MPM_OK) return pympm_raise(st, mpm_sim_last_error(s->sim), 1);
  return PyLong_FromSize_t(count);
}

/* The state arrays as _Buffers in a dict (mpm_sim_particle_state: no stress evaluation). */
static PyObject *sim_state(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  const mpm_particle_view v = mpm_sim_particle_state(s->sim);
  if (v.count == 0 && mpm_sim_particle_count(s->sim) > 0)
    return pympm_raise(MPM_ERR_NOMEM, "out of memory reading the particles", 0);
  const char rf = v.real_size == 4 ? 'f' : 'd';
  const Py_ssize_t n = (Py_ssize_t)v.count, rs = (Py_ssize_t)v.real_size,
                   cs = (Py_ssize_t)v.component_stride;
  PyObject *d = PyDict_New();
  if (!d) return NULL;
  struct {
    const char *name;
    const void *ptr;
    int ncomp;
    char format;
    Py_ssize_t size;
  } a[] = {
      {"x", v.x[0], 3, rf, rs},
      {"v", v.v[0], 3, rf, rs},
      {"F", v.F[0], 9, rf, rs},
      {"mass", v.mass, 1, rf, rs},
      {"volume0", v.volume0, 1, rf, rs},
      {"plastic", v.plastic, 1, rf, rs},
      {"temperature", v.temperature, 1, rf, rs},
      {"material", v.material, 1, 'i', 4},
      {"body", v.body, 1, 'i', 4},
      {"id", v.id, 1, 'I', 4},
  };
  for (size_t k = 0; k < sizeof a / sizeof a[0]; ++k) {
    if (!a[k].ptr) continue;
    PyObject *b = pympm_buffer_new(s, a[k].ptr, n, a[k].ncomp, cs, a[k].format, a[k].size);
    if (!b || PyDict_SetItemString(d, a[k].name, b)) {
      Py_XDECREF(b);
      Py_DECREF(d);
      return NULL;
    }
    Py_DECREF(b);
  }
  return d;
}

/* The domains' view as a dict of _Buffers (mpm/__init__.py copies them). */
static PyObject *sim_domains(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  const mpm_domain_view d = mpm_sim_domain_view(s->sim);
  const char rf = d.real_size == 4 ? 'f' : 'd';
  const Py_ssize_t rs = (Py_ssize_t)d.real_size, nc = (Py_ssize_t)d.corners;
  PyObject *out = Py_BuildValue("{s:n,s:n,s:n}", "corners", nc, "particles",
                                (Py_ssize_t)d.particles, "first", (Py_ssize_t)d.first);
  if (!out || d.corners == 0) return out;
  const struct {
    const char *name;
    const void *const *a;
  } vec[] = {{"x", d.x}, {"v", d.v}, {"X", d.X}};
  for (int k = 0; k < 3; ++k) {
    PyObject *t = PyTuple_New(3);
    if (!t) goto fail;
    for (int c = 0; c < 3; ++c) {
      PyObject *b = pympm_buffer_new(s, vec[k].a[c], nc, 1, 0, rf, rs);
      if (!b) {
        Py_DECREF(t);
        goto fail;
      }
      PyTuple_SET_ITEM(t, c, b);
    }
    if (PyDict_SetItemString(out, vec[k].name, t)) {
      Py_DECREF(t);
      goto fail;
    }
    Py_DECREF(t);
  }
  PyObject *corner = pympm_buffer_new(s, d.corner, 8 * (Py_ssize_t)d.particles, 1, 0, 'I', 4);
  if (!corner || PyDict_SetItemString(out, "corner", corner)) {
    Py_XDECREF(corner);
    goto fail;
  }
  Py_DECREF(corner);
  if (d.enriched) {
    PyObject *e = pympm_buffer_new(s, d.enriched, nc, 1, 0, 'B', 1);
    if (!e || PyDict_SetItemString(out, "enriched", e)) {
      Py_XDECREF(e);
      goto fail;
    }
    Py_DECREF(e);
  }
  return out;
fail:
  Py_DECREF(out);
  return NULL;
}

/* J and the Cauchy stress as _Buffers over the simulation's buffers (filled by this call: copy
 * them before the next). */
static PyObject *sim_derived(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  mpm_particle_view v;
  PyThreadState *unlocked = pympm_unlock(s);
  v = mpm_sim_particles(s->sim);
  pympm_relock(s, unlocked);
  if (!v.J) return pympm_raise(MPM_ERR_NOMEM, "out of memory deriving the particles' stress", 0);
  const char rf = v.real_size == 4 ? 'f' : 'd';
  const Py_ssize_t n = (Py_ssize_t)v.count, rs = (Py_ssize_t)v.real_size;
  PyObject *J = pympm_buffer_new(s, v.J, n, 1, 0, rf, rs);
  PyObject *sigma = pympm_buffer_new(s, v.stress[0], n, 9, (Py_ssize_t)v.stress_stride, rf, rs);
  if (!J || !sigma) {
    Py_XDECREF(J);
    Py_XDECREF(sigma);
    return NULL;
  }
  return Py_BuildValue("NN", J, sigma);
}

static PyObject *sim_colliders(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  const int n = mpm_sim_collider_count(s->sim);
  PyObject *list = PyList_New(n);
  if (!list) return NULL;
  for (int i = 0; i < n; ++i) {
    mpm_collider_state c;
    const mpm_status st = mpm_sim_collider_pose(s->sim, i, &c);
    if (st != MPM_OK) {
      Py_DECREF(list);
      return failed(s, st);
    }
    const double *R = c.rotation;
    PyObject *item = Py_BuildValue(
        "{s:s,s:(ddd),s:((ddd)(ddd)(ddd)),s:(ddd),s:(ddd),s:O}", "name", c.name ? c.name : "",
        "center", c.center[0], c.center[1], c.center[2], "rotation", R[0], R[1], R[2], R[3], R[4],
        R[5], R[6], R[7], R[8], "velocity", c.velocity[0], c.velocity[1], c.velocity[2],
        "angular_velocity", c.angular_velocity[0], c.angular_velocity[1], c.angular_velocity[2],
        "active", c.active ? Py_True : Py_False);
    if (!item) {
      Py_DECREF(list);
      return NULL;
    }
    PyList_SET_ITEM(list, i, item);
  }
  return list;
}

/* mpm_sim_info as a dict of its members. */
static PyObject *sim_info(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  mpm_sim_info in;
  const mpm_status st = mpm_sim_get_info(s->sim, &in, sizeof in);
  if (st != MPM_OK) return failed(s, st);
  return Py_BuildValue(
      "{s:n,s:n,s:i,s:i,s:i,s:d,s:d,s:d,s:d,s:d,s:i,s:O,s:O,s:i,s:d,s:O,s:s,s:i,s:s,"
      "s:L,s:L,s:L,s:L,s:i,s:d,s:O,s:d,s:n,s:d,s:i,s:O,s:L,s:d,s:O,s:L,s:L,s:(ddd),s:O,s:n,"
      "s:i,s:L}",
      "particles", (Py_ssize_t)in.particles, "domain_particles", (Py_ssize_t)in.domain_particles,
      "bodies", in.bodies, "materials", in.materials, "colliders", in.colliders, "dx", in.dx,
      "finest_dx", in.finest_dx, "fps", in.fps, "frame_dt", in.frame_dt, "end_time", in.end_time,
      "frame_count", in.frame_count, "implicit", in.implicit ? Py_True : Py_False, "fixed_dt",
      in.fixed_dt ? Py_True : Py_False, "threads", in.threads, "memory_bytes", in.memory_bytes,
      "output_enabled", in.output_enabled ? Py_True : Py_False, "output_dir",
      in.output_dir ? in.output_dir : "", "written_frames", in.written_frames, "last_checkpoint",
      in.last_checkpoint ? in.last_checkpoint : "", "solver_steps", in.solver_steps,
      "cg_iterations", in.cg_iterations, "newton_iterations", in.newton_iterations,
      "cg_unconverged", in.cg_unconverged, "cg_max", in.cg_max, "cg_residual_max",
      in.cg_residual_max, "surfaces", in.surfaces ? Py_True : Py_False, "surface_seconds",
      in.surface_seconds, "surface_triangles", (Py_ssize_t)in.surface_triangles,
      "surface_seconds_total", in.surface_seconds_total, "surface_frames", in.surface_frames,
      "refining", in.refining ? Py_True : Py_False, "refinements", in.refinements,
      "refinement_seconds", in.refinement_seconds, "resampling", in.resampling ? Py_True : Py_False,
      "splits", in.splits, "merges", in.merges, "angular_momentum_change",
      in.angular_momentum_change[0], in.angular_momentum_change[1], in.angular_momentum_change[2],
      "heat", in.heat ? Py_True : Py_False, "melted_domains", (Py_ssize_t)in.melted_domains,
      "conduction_substeps", in.conduction_substeps, "refinements_unchanged",
      in.refinements_unchanged);
}

static PyObject *sim_warnings(PyObject *self, PyObject *unused) {
  (void)unused;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  const int n = mpm_sim_warnings(s->sim, NULL, 0);
  if (n <= 0) return PyList_New(0);
  char buf[16384];
  mpm_sim_warnings(s->sim, buf, sizeof buf);
  PyObject *text = PyUnicode_FromString(buf);
  if (!text) return NULL;
  PyObject *lines = PyUnicode_Splitlines(text, 0);
  Py_DECREF(text);
  return lines;
}

/* ---- attributes ------------------------------------------------------------------------ */

static PyObject *get_time(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  return ready(s) ? PyFloat_FromDouble(mpm_sim_time(s->sim)) : NULL;
}
static PyObject *get_frame(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  return ready(s) ? PyLong_FromLong(mpm_sim_frame(s->sim)) : NULL;
}
static PyObject *get_frame_count(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  return ready(s) ? PyLong_FromLong(mpm_sim_frame_count(s->sim)) : NULL;
}
static int set_frame_count(PyObject *self, PyObject *value, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return -1;
  if (!value) {
    PyErr_SetString(PyExc_AttributeError, "frame_count cannot be deleted");
    return -1;
  }
  const long frames = PyLong_AsLong(value);
  if (frames == -1 && PyErr_Occurred()) return -1;
  const mpm_status st = mpm_sim_set_frame_limit(s->sim, (int)frames);
  if (st != MPM_OK) {
    failed(s, st);
    return -1;
  }
  return 0;
}
static PyObject *get_steps(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  return ready(s) ? PyLong_FromLongLong((long long)mpm_sim_steps(s->sim)) : NULL;
}
static PyObject *get_threads(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return NULL;
  mpm_sim_info in;
  mpm_sim_get_info(s->sim, &in, sizeof in);
  return PyLong_FromLong(in.threads);
}
static int set_threads(PyObject *self, PyObject *value, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  if (!ready(s)) return -1;
  if (!value) {
    PyErr_SetString(PyExc_AttributeError, "threads cannot be deleted");
    return -1;
  }
  const long t = PyLong_AsLong(value);
  if (t == -1 && PyErr_Occurred()) return -1;
  const mpm_status st = mpm_sim_set_threads(s->sim, (int)t);
  if (st != MPM_OK) {
    failed(s, st);
    return -1;
  }
  return 0;
}
static PyObject *get_particle_count(PyObject *self, void *c) {
  (void)c;
  pympm_sim *s = (pympm_sim *)self;
  return ready(s) ? PyLong_FromSize_t(mpm_sim_particle_count(s->sim)) : NULL;
}
static PyObject *get_generation(PyObject *self, void *c) {
  (void)c;
  return PyLong_FromUnsignedLongLong(((pympm_sim *)self)->generation);
}

static PyGetSetDef sim_getset[] = {
    {"time", get_time, NULL, "Simulated time, s.", NULL},
    {"frame", get_frame, NULL, "Frames completed (0 before the first).", NULL},
    {"frame_count", get_frame_count, set_frame_count,
     "Frames to run: the scene's end time times fps, or fewer when set (it may only be "
     "lowered once output is open).",
     NULL},
    {"steps", get_steps, NULL, "Time steps taken.", NULL},
    {"threads", get_threads, set_threads,
     "OpenMP threads of this simulation's calls (0: the process's setting). Results do not "
     "depend on it.",
     NULL},
    {"particle_count", get_particle_count, NULL,
     "Particles simulated now (material points and particles whose domains are on).", NULL},
    {"_generation", get_generation, NULL, "Bumped by every call that changes the particles.", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyMethodDef sim_methods[] = {
    {"step", sim_step, METH_VARARGS,
     "step(max_dt=0) -> float\n\nAdvance by one time step of at most max_dt seconds (0: the "
     "CFL bound or the implicit solver's dt only), never past the frame in progress (a step "
     "that lands on it completes the frame). Returns the time advanced."},
    {"advance_frame", sim_advance_frame, METH_NOARGS,
     "advance_frame() -> int\n\nRun the steps to the end of the frame in progress and complete "
     "it (written when output is open). Returns the frames completed. Ctrl-C stops it between "
     "two steps (KeyboardInterrupt; the simulation stays usable)."},
    {"next_dt", sim_next_dt, METH_NOARGS,
     "next_dt() -> float\n\nThe step the next step() would take before clipping to the frame."},
    {"open_output", (PyCFunction)(void (*)(void))sim_open_output, METH_VARARGS | METH_KEYWORDS,
     "open_output(dir=None, overwrite=False)\n\nWrite the current state as a frame into dir "
     "(None: the scene's output.directory) and every completed frame after it; the folder is "
     "locked for this simulation. overwrite removes an earlier run's files there (only "
     "those)."},
    {"_checkpoint", sim_checkpoint, METH_NOARGS, "Write a checkpoint into the output folder."},
    {"_write_frame_to", sim_write_frame_to, METH_VARARGS, "A one-off frame; the names written."},
    {"_resume_from", sim_resume_from, METH_VARARGS, "Resume a fresh simulation from a folder."},
    {"release_domains", sim_release_domains, METH_VARARGS,
     "release_domains(lo, hi) -> int\n\nSwitch off the particle domains (Zhu et al.) of the "
     "domain particles inside the box [lo, hi]; they go on as material points. Returns how "
     "many."},
    {"_state", sim_state, METH_NOARGS, "The state arrays as buffers."},
    {"_set", sim_set, METH_VARARGS, "Set velocities (0) or positions (1) by id."},
    {"_set_collider_pose", sim_set_collider_pose, METH_VARARGS, "Script a collider's pose."},
    {"_add_body", sim_add_body, METH_VARARGS, "Add a body (its JSON) between steps."},
    {"_derived", sim_derived, METH_NOARGS, "J and the Cauchy stress as buffers."},
    {"_domains", sim_domains, METH_NOARGS, "The particle domains' view as buffers."},
    {"_colliders", sim_colliders, METH_NOARGS, "The colliders' poses as dicts."},
    {"_info", sim_info, METH_NOARGS, "mpm_sim_info as a dict."},
    {"warnings", sim_warnings, METH_NOARGS,
     "warnings() -> list of str\n\nWhat is likely a mistake in the scene though not an error."},
    {NULL, NULL, 0, NULL}};

PyTypeObject pympm_sim_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "mpm._mpm._Simulation",
    .tp_basicsize = sizeof(pympm_sim),
    .tp_dealloc = sim_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "The engine's simulation handle (use mpm.Simulation).",
    .tp_weaklistoffset = offsetof(pympm_sim, weakrefs),
    .tp_methods = sim_methods,
    .tp_getset = sim_getset,
    .tp_init = sim_init,
    .tp_new = PyType_GenericNew,
};
