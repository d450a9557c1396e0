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

/* _render(run_dir, options, png) -> (rgb bytes, height, width, frame, time): the picture of
 * frame options["frame"] (-1: the last) of the run folder. */
PyObject *pympm_render(PyObject *self, PyObject *args) {
  (void)self;
  const char *run_dir, *png = NULL;
  PyObject *options;
  if (!PyArg_ParseTuple(args, "sO!z", &run_dir, &PyDict_Type, &options, &png)) return NULL;
  mpm_render_options o = mpm_render_options_default();
  const char *field = NULL, *colormap = NULL, *framing = NULL;
  int frame = -1;
  if (opt_int(options, "width", &o.width) || opt_int(options, "height", &o.height) ||
      opt_str(options, "field", &field) || opt_str(options, "colormap", &colormap) ||
      opt_str(options, "framing", &framing) || opt_str(options, "scene", &o.scene) ||
      opt_double(options, "range_lo", &o.range_lo) ||
      opt_double(options, "range_hi", &o.range_hi) || opt_int(options, "shadow", &o.shadow) ||
      opt_int(options, "legend", &o.legend) || opt_int(options, "time_label", &o.time_label) ||
      opt_int(options, "particles", &o.particles) || opt_int(options, "threads", &o.threads) ||
      opt_vec3(options, "eye", o.eye) || opt_vec3(options, "target", o.target) ||
      opt_double(options, "fov", &o.fov) || opt_int(options, "frame", &frame))
    return NULL;
  if (field) {
    /* a field's name, or any point array of the run ("pressure", "velocity.y") */
    if (mpm_render_field_from_name(field, &o.field) != MPM_OK) {
      o.field = MPM_RENDER_FIELD_ARRAY;
      o.field_array = field;
    }
  }
  if (colormap && mpm_render_colormap_from_name(colormap, &o.colormap) != MPM_OK) {
    PyErr_Format(PyExc_ValueError, "colormap: unknown name '%s'", colormap);
    return NULL;
  }
  if (framing && mpm_render_framing_from_name(framing, &o.framing) != MPM_OK) {
    PyErr_Format(PyExc_ValueError, "framing: unknown name '%s'", framing);
    return NULL;
  }
  if (frame >= 0) o.first_frame = o.last_frame = frame;
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
