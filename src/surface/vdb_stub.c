/* vdb_stub.c - vdb_shim.h for a build without OpenVDB (cmake -DMPM_OPENVDB=OFF: the fuzz and
 * ThreadSanitizer builds): every call fails with a message saying how to get surfaces. */
#ifndef MPM_HAVE_OPENVDB
#include "surface/vdb_shim.h"

#include <stdio.h>

static int unavailable(char *msg, size_t cap) {
  if (msg && cap)
    snprintf(msg, cap,
             "this mpm was built without OpenVDB (cmake -DMPM_OPENVDB=OFF), so it "
             "makes no surfaces: rebuild with libopenvdb-dev installed");
  return MPM_VDB_FAIL;
}

int mpm_vdb_available(void) {
  return 0;
}

int mpm_vdb_levelset_from_spheres(const double *xyz, const double *radius, size_t n, double voxel,
                                  double half_width, int threads, mpm_vdb_grid **out, char *msg,
                                  size_t cap) {
  (void)xyz, (void)radius, (void)n, (void)voxel, (void)half_width, (void)threads;
  *out = NULL;
  return unavailable(msg, cap);
}

int mpm_vdb_smooth(mpm_vdb_grid *grid, int passes, mpm_vdb_filter filter, double offset,
                   int threads, char *msg, size_t cap) {
  (void)grid, (void)passes, (void)filter, (void)offset, (void)threads;
  return unavailable(msg, cap);
}

int mpm_vdb_mesh(const mpm_vdb_grid *grid, int threads, float **points, size_t *point_count,
                 uint32_t **triangles, size_t *triangle_count, char *msg, size_t cap) {
  (void)grid, (void)threads;
  *points = NULL, *triangles = NULL, *point_count = *triangle_count = 0;
  return unavailable(msg, cap);
}

uint64_t mpm_vdb_active_voxels(const mpm_vdb_grid *grid) {
  (void)grid;
  return 0;
}

int mpm_vdb_velocity_from_particles(const double *xyz, const double *v, const double *mass,
                                    size_t n, double voxel, mpm_vdb_vector_grid **out, char *msg,
                                    size_t cap) {
  (void)xyz, (void)v, (void)mass, (void)n, (void)voxel;
  *out = NULL;
  return unavailable(msg, cap);
}

int mpm_vdb_write(const mpm_vdb_grid *grid, const char *path, int density,
                  const mpm_vdb_vector_grid *velocity, char *msg, size_t cap) {
  (void)grid, (void)path, (void)density, (void)velocity;
  return unavailable(msg, cap);
}

int mpm_vdb_read(const char *path, const char *name, mpm_vdb_grid **out, char *msg, size_t cap) {
  (void)path, (void)name;
  *out = NULL;
  return unavailable(msg, cap);
}

void mpm_vdb_grid_info(const mpm_vdb_grid *grid, char *name, size_t cap, mpm_vdb_class *cls,
                       double *voxel) {
  (void)grid;
  if (name && cap) name[0] = 0;
  if (cls) *cls = MPM_VDB_CLASS_UNKNOWN;
  if (voxel) *voxel = 0;
}

double mpm_vdb_sample(const mpm_vdb_grid *grid, const double x[3]) {
  (void)grid, (void)x;
  return 0;
}

void mpm_vdb_grid_destroy(mpm_vdb_grid *grid) {
  (void)grid;
}

int mpm_vdb_read_vector(const char *path, const char *name, mpm_vdb_vector_grid **out, char *msg,
                        size_t cap) {
  (void)path, (void)name;
  *out = NULL;
  return unavailable(msg, cap);
}

void mpm_vdb_vector_sample(const mpm_vdb_vector_grid *grid, const double x[3], double v[3]) {
  (void)grid, (void)x;
  v[0] = v[1] = v[2] = 0;
}

uint64_t mpm_vdb_vector_active_voxels(const mpm_vdb_vector_grid *grid) {
  (void)grid;
  return 0;
}

void mpm_vdb_vector_name(const mpm_vdb_vector_grid *grid, char *name, size_t cap) {
  (void)grid;
  if (name && cap) name[0] = 0;
}

void mpm_vdb_vector_grid_destroy(mpm_vdb_vector_grid *grid) {
  (void)grid;
}
#else
typedef int mpm_vdb_stub_unused; /* ISO C wants a translation unit to declare something */
#endif
