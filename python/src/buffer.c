/* buffer.c - _Buffer: one engine array through the buffer protocol (see pympm.h). */
#include "pympm.h"

#include <stddef.h>

typedef struct pympm_buffer {
  PyObject_HEAD pympm_sim *owner;
  uint64_t generation;
  const void *ptr;
  int ndim;
  Py_ssize_t shape[3], strides[3], itemsize;
  char format[2];
} pympm_buffer;

PyObject *pympm_buffer_new(pympm_sim *sim, const void *ptr, Py_ssize_t count, int ncomp,
                           Py_ssize_t stride, char format, Py_ssize_t itemsize) {
  pympm_buffer *b = PyObject_New(pympm_buffer, &pympm_buffer_type);
  if (!b) return NULL;
  Py_INCREF(sim);
  b->owner = sim;
  b->generation = sim->generation;
  b->ptr = ptr;
  b->itemsize = itemsize;
  b->format[0] = format;
  b->format[1] = 0;
  b->shape[0] = count;
  b->strides[0] = itemsize;
  if (ncomp == 1) {
    b->ndim = 1;
  } else if (ncomp == 9) { /* F[3 r + c]: (count, 3, 3) */
    b->ndim = 3;
    b->shape[1] = b->shape[2] = 3;
    b->strides[1] = 3 * stride;
    b->strides[2] = stride;
  } else {
    b->ndim = 2;
    b->shape[1] = ncomp;
    b->strides[1] = stride;
  }
  /* the arrays stay allocated while this object lives (the engine keeps what it would free) */
  mpm_sim_hold_particle_arrays(sim->sim, 1);
  return (PyObject *)b;
}

static void buffer_dealloc(PyObject *self) {
  pympm_buffer *b = (pympm_buffer *)self;
  if (b->owner) {
    if (b->owner->busy)
      b->owner->deferred++; /* released when the running call is over (pympm_relock) */
    else if (b->owner->sim)
      mpm_sim_hold_particle_arrays(b->owner->sim, -1);
    Py_DECREF(b->owner);
  }
  PyObject_Free(self);
}

static int buffer_get(PyObject *self, Py_buffer *view, int flags) {
  pympm_buffer *b = (pympm_buffer *)self;
  if (b->generation != b->owner->generation) {
    PyErr_SetString(pympm_stale_error,
                    "this particle array belongs to an earlier state: the simulation has "
                    "advanced (or its particles changed) since; read sim.particles again");
    view->obj = NULL;
    return -1;
  }
  if (flags & PyBUF_WRITABLE) {
    PyErr_SetString(PyExc_BufferError, "the particle arrays are read-only: write state with "
                                       "the Simulation's setters");
    view->obj = NULL;
    return -1;
  }
  if ((flags & PyBUF_STRIDES) != PyBUF_STRIDES && b->ndim > 1) {
    PyErr_SetString(PyExc_BufferError, "the particle array is strided (its components are "
                                       "apart): ask for a strided buffer");
    view->obj = NULL;
    return -1;
  }
  view->buf = (void *)b->ptr;
  view->obj = self;
  Py_INCREF(self);
  view->len =
      b->shape[0] * b->itemsize * (b->ndim > 1 ? b->shape[1] : 1) * (b->ndim > 2 ? b->shape[2] : 1);
  view->readonly = 1;
  view->itemsize = b->itemsize;
  view->format = (flags & PyBUF_FORMAT) ? b->format : NULL;
  view->ndim = b->ndim;
  view->shape = b->shape;
  view->strides = (flags & PyBUF_STRIDES) == PyBUF_STRIDES ? b->strides : NULL;
  view->suboffsets = NULL;
  view->internal = NULL;
  return 0;
}

static PyBufferProcs buffer_procs = {.bf_getbuffer = buffer_get, .bf_releasebuffer = NULL};

static PyObject *buffer_valid(PyObject *self, void *closure) {
  (void)closure;
  pympm_buffer *b = (pympm_buffer *)self;
  return PyBool_FromLong(b->generation == b->owner->generation);
}

static PyObject *buffer_address(PyObject *self, void *closure) {
  (void)closure;
  return PyLong_FromVoidPtr((void *)((pympm_buffer *)self)->ptr);
}

static PyGetSetDef buffer_getset[] = {
    {"valid", buffer_valid, NULL, "whether the simulation is still at this array's state", NULL},
    {"address", buffer_address, NULL, "the engine array's address (for tests)", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

PyTypeObject pympm_buffer_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "mpm._mpm._Buffer",
    .tp_basicsize = sizeof(pympm_buffer),
    .tp_dealloc = buffer_dealloc,
    .tp_as_buffer = &buffer_procs,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "One of the engine's particle arrays, read-only through the buffer protocol "
              "(numpy.asarray reads it without a copy). Exports only while the simulation is "
              "at the state it was taken from.",
    .tp_getset = buffer_getset,
};
