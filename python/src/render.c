/* render.c - mpm._mpm._render: one picture of a run folder through the engine's renderer
 * (include/mpm/render.h), as RGB bytes and written as a PNG when asked. */
#include "pympm.h"

#include <math.h>

/* options[name] as a string (NULL when absent); -1 with an exception when not a string */
static int opt_str(PyObject *options, const char *name, const char **out) {
  PyObject *v = PyDict_GetItemString(options, name);
  *out = NULL;
  if (!v || v == Py_None) return 0;
  *out = PyUnicode_AsUTF8(v);
  return *out ? 0 : -1;
}

static int opt_int(PyObject *options, const char *name, int *out) {
  PyObject *v = PyDict_GetItemString(options, name);
  if (!v || v == Py_None) return 0;
  const long x = PyLong_AsLong(v);
  if (x == -1 && PyErr_Occurred()) return -1;
  *out = (int)x;
  return 0;
}

static int opt_double(PyObject *options, const char *name, double *out) {
  PyObject *v = PyDict_GetItemString(options, name);
  if (!v || v == Py_None) return 0;
  const double x = PyFloat_AsDouble(v);
  if (x == -1 && PyErr_Occurred()) return -1;
  *out = x;
  return 0;
}

static int opt_vec3(PyObject *options, const char *name, double out[3]) {
  PyObject *v = PyDict_GetItemString(options, name);
  if (!v || v == Py_None) return 0;
  PyObject *seq = PySequence_Fast(v, "expected three numbers");
  if (!seq) return -1;
  int rc = 0;
  if (PySequence_Fast_GET_SIZE(seq) != 3) {
    PyErr_Format(PyExc_ValueError, "%s: expected three numbers", name);
    rc = -1;
  }
  for (int d = 0; d < 3 && !rc; ++d) {
    out[d] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(seq, d));
    if (out[d] == -1 && PyErr_Occurred()) rc = -1;
  }
  Py_DECREF(seq);
  return rc;
}

/* The renderer's options from the dict the Python side passes (None: the default); -1 with an
 * exception for a wrong type or name. */
static int parse_options(PyObject *options, mpm_render_options *o, int *frame) {
  const char *field = NULL, *colormap = NULL, *framing = NULL;
  if (opt_int(options, "width", &o->width) || opt_int(options, "height", &o->height) ||
      opt_str(options, "field", &field) || opt_str(options, "colormap", &colormap) ||
      opt_str(options, "framing", &framing) || opt_str(options, "scene", &o->scene) ||
      opt_str(options, "out_dir", &o->out_dir) || opt_double(options, "range_lo", &o->range_lo) ||
      opt_double(options, "range_hi", &o->range_hi) || opt_int(options, "shadow", &o->shadow) ||
      opt_int(options, "legend", &o->legend) || opt_int(options, "time_label", &o->time_label) ||
      opt_int(options, "particles", &o->particles) || opt_int(options, "threads", &o->threads) ||
      opt_int(options, "every", &o->every) || opt_vec3(options, "eye", o->eye) ||
      opt_vec3(options, "target", o->target) || opt_double(options, "fov", &o->fov) ||
      opt_int(options, "frame", frame))
    return -1;
  if (field) {
    /* a field's name, or any point array of the run ("pressure", "velocity.y") */
    if (mpm_render_field_from_name(field, &o->field) != MPM_OK) {
      o->field = MPM_RENDER_FIELD_ARRAY;
      o->field_array = field;
    }
  }
  if (colormap && mpm_render_colormap_from_name(colormap, &o->colormap) != MPM_OK) {
    PyErr_Format(PyExc_ValueError, "colormap: unknown name '%s'", colormap);
    return -1;
  }
  if (framing && mpm_render_framing_from_name(framing, &o->framing) != MPM_OK) {
    PyErr_Format(PyExc_ValueError, "framing: unknown name '%s'", framing);
    return -1;
  }
  if (*frame >= 0) o->first_frame = o->last_frame = *frame;
  return 0;
}

/* _render(run_dir, options, png) -> (rgb bytes, height, width, frame, time): the picture of
 * frame options["frame"] (-1: the last) of the run folder. */
PyObject *pympm_render(PyObject *self, PyObject *args) {
  (void)self;
  const char *run_dir, *png = NULL;
  PyObject *options;
  if (!PyArg_ParseTuple(args, "sO!z", &run_dir, &PyDict_Type, &options, &png)) return NULL;
  mpm_render_options o = mpm_render_options_default();
  int frame = -1;
  if (parse_options(options, &o, &frame)) return NULL;
  char err[2048];
  err[0] = 0;
  mpm_renderer *r = NULL;
  mpm_status st;
  PyObject *rgb = NULL;
  mpm_render_info info;
  Py_BEGIN_ALLOW_THREADS;
  st = mpm_renderer_create(run_dir, &o, &r, err, sizeof err);
  if (st == MPM_OK) {
    mpm_renderer_get_info(r, &info, sizeof info);
    st = info.pictures > 0 ? mpm_renderer_draw(r, info.pictures - 1) : MPM_ERR_INVALID;
    if (st == MPM_OK && png) st = mpm_renderer_write_png(r, png);
    if (st == MPM_OK) mpm_renderer_get_info(r, &info, sizeof info);
    if (st != MPM_OK) snprintf(err, sizeof err, "%s", mpm_renderer_last_error(r));
  }
  Py_END_ALLOW_THREADS;
  if (st == MPM_OK) {
    const size_t bytes = (size_t)info.width * (size_t)info.height * 3;
    rgb = PyBytes_FromStringAndSize(NULL, (Py_ssize_t)bytes);
    if (rgb) st = mpm_renderer_pixels(r, (unsigned char *)PyBytes_AS_STRING(rgb), bytes);
  }
  if (st != MPM_OK || !rgb) {
    Py_XDECREF(rgb);
    mpm_renderer_destroy(r);
    if (PyErr_Occurred()) return NULL;
    return pympm_raise(st, err[0] ? err : "the picture could not be drawn", 0);
  }
  PyObject *out = Py_BuildValue("Niiid", rgb, info.height, info.width, info.frame, info.time);
  mpm_renderer_destroy(r);
  return out;
}

typedef struct run_list {
  PyObject *paths; /* the PNGs written, in order */
  int failed;
} run_list;

static void on_picture(void *ctx, const mpm_renderer *r, const char *png, double seconds) {
  (void)r, (void)seconds;
  run_list *l = ctx;
  PyGILState_STATE g = PyGILState_Ensure();
  PyObject *p = PyUnicode_DecodeFSDefault(png);
  if (!p || PyList_Append(l->paths, p)) l->failed = 1;
  Py_XDECREF(p);
  PyGILState_Release(g);
}

/* _render_run(run_dir, options) -> [png paths]: every picture of the run folder (mpm render). */
PyObject *pympm_render_run(PyObject *self, PyObject *args) {
  (void)self;
  const char *run_dir;
  PyObject *options;
  if (!PyArg_ParseTuple(args, "sO!", &run_dir, &PyDict_Type, &options)) return NULL;
  mpm_render_options o = mpm_render_options_default();
  int frame = -1;
  if (parse_options(options, &o, &frame)) return NULL;
  run_list l = {PyList_New(0), 0};
  if (!l.paths) return NULL;
  char err[2048];
  err[0] = 0;
  mpm_status st;
  Py_BEGIN_ALLOW_THREADS;
  st = mpm_render_run(run_dir, &o, on_picture, &l, err, sizeof err);
  Py_END_ALLOW_THREADS;
  if (l.failed) {
    Py_DECREF(l.paths);
    return PyErr_Occurred() ? NULL : PyErr_NoMemory();
  }
  if (st != MPM_OK) {
    Py_DECREF(l.paths);
    return pympm_raise(st, err[0] ? err : "the pictures could not be drawn", 0);
  }
  return l.paths;
}
