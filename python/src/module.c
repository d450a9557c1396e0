/* module.c - the extension module mpm._mpm (see pympm.h). */
#include "pympm.h"

PyObject *pympm_scene_error;
PyObject *pympm_stale_error;
PyObject *pympm_engine_error;

PyObject *pympm_raise(mpm_status st, const char *msg, int scene) {
  PyObject *type = pympm_engine_error;
  switch (st) {
  case MPM_ERR_PARSE:
  case MPM_ERR_INVALID:
    type = scene ? pympm_scene_error : pympm_engine_error;
    break;
  case MPM_ERR_IO:
    type = scene ? pympm_scene_error : PyExc_OSError;
    break;
  case MPM_ERR_NOMEM:
    type = PyExc_MemoryError;
    break;
  case MPM_ERR_INTERRUPTED:
    type = PyExc_KeyboardInterrupt;
    break;
  default:
    break;
  }
  PyErr_SetString(type, msg && *msg ? msg : mpm_status_string(st));
  return NULL;
}

static PyObject *mod_version(PyObject *self, PyObject *unused) {
  (void)self, (void)unused;
  return PyUnicode_FromString(mpm_version());
}

static PyObject *mod_real_type(PyObject *self, PyObject *unused) {
  (void)self, (void)unused;
  return PyUnicode_FromString(mpm_real_type());
}

static PyObject *mod_live_bytes(PyObject *self, PyObject *unused) {
  (void)self, (void)unused;
  return PyLong_FromSize_t(mpm_live_bytes());
}

static PyObject *mod_set_main_thread(PyObject *self, PyObject *arg) {
  (void)self;
  pympm_main_thread = PyLong_AsUnsignedLong(arg);
  if (PyErr_Occurred()) return NULL;
  Py_RETURN_NONE;
}

static PyMethodDef module_methods[] = {
    {"version", mod_version, METH_NOARGS, "The engine library's version, MAJOR.MINOR.PATCH."},
    {"real_type", mod_real_type, METH_NOARGS,
     "The engine's real type, 'float' or 'double' (the particle arrays' dtype)."},
    {"_set_main_thread", mod_set_main_thread, METH_O, "The main thread's ident."},
    {"live_bytes", mod_live_bytes, METH_NOARGS,
     "Bytes the engine holds now for its large arrays, over every simulation (mpm_live_bytes)."},
    {"_render", pympm_render, METH_VARARGS, "One picture of a run folder."},
    {"_render_run", pympm_render_run, METH_VARARGS, "Every picture of a run folder."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT,
                                    "mpm._mpm",
                                    "The C extension of the mpm package (use `import mpm`).",
                                    -1,
                                    module_methods,
                                    NULL,
                                    NULL,
                                    NULL,
                                    NULL};

PyMODINIT_FUNC PyInit__mpm(void) {
  if (PyType_Ready(&pympm_sim_type) < 0 || PyType_Ready(&pympm_buffer_type) < 0) return NULL;
  PyObject *m = PyModule_Create(&module);
  if (!m) return NULL;
  pympm_engine_error = PyErr_NewExceptionWithDoc(
      "mpm.Error", "A failure of the engine: the message names the step, particle or file.",
      PyExc_RuntimeError, NULL);
  pympm_scene_error = PyErr_NewExceptionWithDoc(
      "mpm.SceneError",
      "A scene the engine refuses: the message names the file (or <json>), the key path and "
      "what was expected, as `mpm check` prints it; also a scene file or a mesh it names that "
      "cannot be read.",
      PyExc_ValueError, NULL);
  pympm_stale_error = PyErr_NewExceptionWithDoc(
      "mpm.StaleViewError",
      "A particle view used after the simulation advanced (its arrays were reordered or "
      "resized): read sim.particles again.",
      PyExc_RuntimeError, NULL);
  if (!pympm_engine_error || !pympm_scene_error || !pympm_stale_error) return NULL;
  Py_INCREF(&pympm_sim_type);
  Py_INCREF(&pympm_buffer_type);
  if (PyModule_AddObject(m, "_Simulation", (PyObject *)&pympm_sim_type) ||
      PyModule_AddObject(m, "_Buffer", (PyObject *)&pympm_buffer_type) ||
      PyModule_AddObject(m, "Error", pympm_engine_error) ||
      PyModule_AddObject(m, "SceneError", pympm_scene_error) ||
      PyModule_AddObject(m, "StaleViewError", pympm_stale_error)) {
    Py_DECREF(m);
    return NULL;
  }
  Py_INCREF(pympm_engine_error);
  Py_INCREF(pympm_scene_error);
  Py_INCREF(pympm_stale_error);
  return m;
}
