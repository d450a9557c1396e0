/* vdb_load.c - vdb_shim.h in a build with OpenVDB: the shim is the module libmpmvdb.so, opened
 * with dlopen at the first call and reached through its table of entry points (vdb_shim.h,
 * mpm_vdb_module_table). A process that makes no surface never loads OpenVDB, TBB, Boost and
 * their libraries, which cost every start of the program 42 ms. Where the module is looked for,
 * in order:
 *   1. the file the environment variable MPM_VDB_MODULE names;
 *   2. beside the file holding this code (the program, libmpm.so, or a program linking
 *      libmpm.a), and in ../lib and ../<libdir> from there (bin/mpm of an installed prefix);
 *   3. the installed library folder (MPM_VDB_MODULE_INSTALL) and the build tree's module
 *      (MPM_VDB_MODULE_BUILD), both compiled in;
 *   4. libmpmvdb.so through the dynamic linker's own search (LD_LIBRARY_PATH, ld.so.conf).
 * When none loads, every call fails with a message listing what was tried. */
#ifdef MPM_HAVE_OPENVDB
#define _GNU_SOURCE /* dladdr */
#include "surface/vdb_shim.h"
#include "core/alloc.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef MPM_VDB_MODULE_INSTALL
#define MPM_VDB_MODULE_INSTALL ""
#endif
#ifndef MPM_VDB_MODULE_BUILD
#define MPM_VDB_MODULE_BUILD ""
#endif
#ifndef MPM_VDB_LIBDIR
#define MPM_VDB_LIBDIR "lib"
#endif
#define MODULE_NAME "libmpmvdb.so"

static pthread_once_t once = PTHREAD_ONCE_INIT;
static const mpm_vdb_table *table;
static char why[2048]; /* what was tried, when nothing loaded */

/* Open one candidate; 1 when it gave a table of this version. */
static int try_open(const char *path) {
  if (!path || !path[0]) return 0;
  void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
  const size_t len = strlen(why);
  if (!h) {
    const char *e = dlerror();
    snprintf(why + len, sizeof why - len, "%s%s", len ? "; " : "", e ? e : path);
    return 0;
  }
  const mpm_vdb_table *(*get)(void) = NULL;
  void *sym = dlsym(h, "mpm_vdb_module_table");
  memcpy(&get, &sym, sizeof get); /* a data pointer to a function pointer, as POSIX allows */
  const mpm_vdb_table *t = get ? get() : NULL;
  if (!t || t->version != MPM_VDB_TABLE_VERSION) {
    snprintf(why + len, sizeof why - len, "%s%s: %s", len ? "; " : "", path,
             t ? "a module of another version" : "no mpm_vdb_module_table");
    dlclose(h);
    return 0;
  }
  t->set_allocator(mpm_alloc, mpm_free); /* the arrays it gives us are ours to mpm_free */
  table = t;                             /* the module stays loaded for the process's life */
  return 1;
}

static void load(void) {
  if (try_open(getenv("MPM_VDB_MODULE"))) return;
  Dl_info info;
  if (dladdr((const void *)&load, &info) && info.dli_fname && strchr(info.dli_fname, '/')) {
    char dir[4096], path[4200];
    snprintf(dir, sizeof dir, "%s", info.dli_fname);
    *strrchr(dir, '/') = '\0';
    static const char *const rel[] = {"", "/../lib", "/../" MPM_VDB_LIBDIR};
    for (size_t k = 0; k < sizeof rel / sizeof rel[0]; ++k) {
      snprintf(path, sizeof path, "%s%s/" MODULE_NAME, dir, rel[k]);
      if (try_open(path)) return;
    }
  }
  if (try_open(MPM_VDB_MODULE_INSTALL) || try_open(MPM_VDB_MODULE_BUILD)) return;
  try_open(MODULE_NAME);
}

static const mpm_vdb_table *module(void) {
  pthread_once(&once, load);
  return table;
}

static int unavailable(char *msg, size_t cap) {
  if (msg && cap)
    snprintf(msg, cap,
             "the OpenVDB module (%s) that makes surfaces could not be loaded: %s (set "
             "MPM_VDB_MODULE to its path, or reinstall mpm)",
             MODULE_NAME, why);
  return MPM_VDB_FAIL;
}

int mpm_vdb_available(void) {
  return module() != NULL;
}

int mpm_vdb_levelset_from_spheres(const double *xyz, const double *radius, size_t n, double voxel,
                                  double half_width, int threads, mpm_vdb_grid **out, char *msg,
                                  size_t cap) {
  const mpm_vdb_table *t = module();
  if (!t) {
    *out = NULL;
    return unavailable(msg, cap);
  }
  return t->levelset_from_spheres(xyz, radius, n, voxel, half_width, threads, out, msg, cap);
}

int mpm_vdb_smooth(mpm_vdb_grid *grid, int passes, mpm_vdb_filter filter, double offset,
                   int threads, char *msg, size_t cap) {
  const mpm_vdb_table *t = module();
  return t ? t->smooth(grid, passes, filter, offset, threads, msg, cap) : unavailable(msg, cap);
}

int mpm_vdb_mesh(const mpm_vdb_grid *grid, int threads, float **points, size_t *point_count,
                 uint32_t **triangles, size_t *triangle_count, char *msg, size_t cap) {
  const mpm_vdb_table *t = module();
  if (!t) {
    *points = NULL, *triangles = NULL, *point_count = *triangle_count = 0;
    return unavailable(msg, cap);
  }
  return t->mesh(grid, threads, points, point_count, triangles, triangle_count, msg, cap);
}

/* The calls on a grid: a grid exists only when the module made it. */
uint64_t mpm_vdb_active_voxels(const mpm_vdb_grid *grid) {
  return module() ? table->active_voxels(grid) : 0;
}

int mpm_vdb_velocity_from_particles(const double *xyz, const double *v, const double *mass,
                                    size_t n, double voxel, mpm_vdb_vector_grid **out, char *msg,
                                    size_t cap) {
  const mpm_vdb_table *t = module();
  if (!t) {
    *out = NULL;
    return unavailable(msg, cap);
  }
  return t->velocity_from_particles(xyz, v, mass, n, voxel, out, msg, cap);
}

int mpm_vdb_write(const mpm_vdb_grid *grid, const char *path, int density,
                  const mpm_vdb_vector_grid *velocity, char *msg, size_t cap) {
  const mpm_vdb_table *t = module();
  return t ? t->write(grid, path, density, velocity, msg, cap) : unavailable(msg, cap);
}

int mpm_vdb_read(const char *path, const char *name, mpm_vdb_grid **out, char *msg, size_t cap) {
  const mpm_vdb_table *t = module();
  if (!t) {
    *out = NULL;
    return unavailable(msg, cap);
  }
  return t->read(path, name, out, msg, cap);
}

void mpm_vdb_grid_info(const mpm_vdb_grid *grid, char *name, size_t cap, mpm_vdb_class *cls,
                       double *voxel) {
  if (module()) table->grid_info(grid, name, cap, cls, voxel);
}

double mpm_vdb_sample(const mpm_vdb_grid *grid, const double x[3]) {
  return module() ? table->sample(grid, x) : 0;
}

void mpm_vdb_grid_destroy(mpm_vdb_grid *grid) {
  if (grid && module()) table->grid_destroy(grid);
}

int mpm_vdb_read_vector(const char *path, const char *name, mpm_vdb_vector_grid **out, char *msg,
                        size_t cap) {
  const mpm_vdb_table *t = module();
  if (!t) {
    *out = NULL;
    return unavailable(msg, cap);
  }
  return t->read_vector(path, name, out, msg, cap);
}

void mpm_vdb_vector_sample(const mpm_vdb_vector_grid *grid, const double x[3], double v[3]) {
  if (module())
    table->vector_sample(grid, x, v);
  else
    v[0] = v[1] = v[2] = 0;
}

uint64_t mpm_vdb_vector_active_voxels(const mpm_vdb_vector_grid *grid) {
  return module() ? table->vector_active_voxels(grid) : 0;
}

void mpm_vdb_vector_name(const mpm_vdb_vector_grid *grid, char *name, size_t cap) {
  if (module())
    table->vector_name(grid, name, cap);
  else if (name && cap)
    name[0] = '\0';
}

void mpm_vdb_vector_grid_destroy(mpm_vdb_vector_grid *grid) {
  if (grid && module()) table->vector_grid_destroy(grid);
}
#endif
