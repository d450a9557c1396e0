/* pympm.h - the CPython extension mpm._mpm, on the public C API (include/mpm/mpm.h) only.
 *
 * module.c      the module, its exceptions and the status -> exception mapping
 * simulation.c  _Simulation: a handle, its calls (the long ones without the GIL, Ctrl-C
 *               stopping them between two steps) and the generation of its particle state
 * render.c      _render: a picture of a run folder (include/mpm/render.h)
 * buffer.c      _Buffer: one engine array exported through the buffer protocol (numpy reads it
 *               without a copy), tied to a generation: it refuses to export once the simulation
 *               has moved on, and it holds the simulation (and its arrays, through
 *               mpm_sim_hold_particle_arrays) for as long as any array made from it lives.
 * The numpy-facing API is Python (mpm/__init__.py): numpy is needed at run time only. */
#ifndef PYMPM_H
#define PYMPM_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "mpm/mpm.h"

#include <stdint.h>

typedef struct pympm_sim {
  PyObject_HEAD mpm_sim *sim;
  uint64_t generation; /* bumped by every call that may move, reorder or resize particles */
  int busy;            /* a call is running without the GIL: another thread must wait its turn */
  int deferred;        /* buffers freed during that call: their holds are released after it */
  PyObject *weakrefs;
} pympm_sim;

extern PyTypeObject pympm_sim_type;
extern unsigned long pympm_main_thread; /* where a Ctrl-C handler may be installed */
extern PyTypeObject pympm_buffer_type;
extern PyObject *pympm_scene_error;  /* mpm.SceneError (ValueError) */
extern PyObject *pympm_stale_error;  /* mpm.StaleViewError (RuntimeError) */
extern PyObject *pympm_engine_error; /* mpm.Error (RuntimeError): the engine's other failures */

/* Set the exception for status st with the message msg; returns NULL. scene: the failure is
 * the scene's (creation): a parse, invalid or I/O status (a mesh file missing) is
 * mpm.SceneError; else mpm.Error (a call the state does not allow, such as a frame past the
 * end) or OSError (a file that cannot be written). */
PyObject *pympm_raise(mpm_status st, const char *msg, int scene);

/* A _Buffer over `count` items of the array at ptr (format "f", "d", "i" or "I"; items of
 * itemsize bytes), shape (count) or (count, ncomp) with components `stride` bytes apart, or
 * (count, 3, 3) for a row-major tensor (ncomp 9). It holds sim and its arrays. */
PyObject *pympm_buffer_new(pympm_sim *sim, const void *ptr, Py_ssize_t count, int ncomp,
                           Py_ssize_t stride, char format, Py_ssize_t itemsize);

/* The GIL let go for a call of the engine on s, and taken back: meanwhile s is busy (another
 * thread's call is refused) and a buffer freed by another thread defers releasing its hold
 * until the call is over (the engine may be growing or freeing arrays under the hold). */
PyThreadState *pympm_unlock(pympm_sim *s);
void pympm_relock(pympm_sim *s, PyThreadState *t);

/* _render(run_dir, options, png): render.c */
PyObject *pympm_render(PyObject *self, PyObject *args);
/* _render_run(run_dir, options): render.c */
PyObject *pympm_render_run(PyObject *self, PyObject *args);

#endif
