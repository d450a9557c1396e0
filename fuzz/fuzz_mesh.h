/* fuzz_mesh.h - the body shared by the mesh loader targets fuzz_obj.c and fuzz_ply.c.
 *
 * Parses the input with mpm_mesh_parse (scene/mesh.c; the in-memory path of mpm_mesh_load)
 * and, when a mesh comes back, runs what the scene loader and the sampler run on it:
 * bounds, the open-edge count, and the inside test at the box centre and at a corner. */
#ifndef MPM_FUZZ_MESH_H
#define MPM_FUZZ_MESH_H

#include "scene/mesh.h"

#include <stddef.h>
#include <stdint.h>

static inline int mpm_fuzz_mesh(const uint8_t *data, size_t size, mpm_mesh_format format,
                                const char *name) {
  mpm_mesh mesh;
  mpm_error err;
  if (mpm_mesh_parse((const char *)data, size, format, name, &mesh, &err) != MPM_OK) return 0;
  double lo[3], hi[3];
  mpm_mesh_bounds(&mesh, lo, hi);
  (void)mpm_mesh_boundary_edges(&mesh);
  const double mid[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
  (void)mpm_mesh_inside(&mesh, mid);
  (void)mpm_mesh_inside(&mesh, lo);
  mpm_mesh_free(&mesh);
  return 0;
}

#endif
