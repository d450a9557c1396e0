/* triangle_mesh.h - the one writer of triangle meshes: Wavefront OBJ, binary PLY and VTK XML
 * PolyData (.vtp), each atomic (io.h). The surfaces embedded in particle domains (Zhu et al. 2017
 * sec. 4.1) and the particle surfaces (OpenVDB's) both write through it. */
#ifndef MPM_IO_TRIANGLE_MESH_H
#define MPM_IO_TRIANGLE_MESH_H

#include "core/error.h"

#include <stddef.h>
#include <stdint.h>

/* A view of a mesh: the vertices as doubles or as floats (3 per vertex, m), the triangles as 3
 * zero-based vertex indices each, and a title for the files' comment. */
typedef struct mpm_triangle_mesh {
  size_t vertex_count, triangle_count;
  const double *xd; /* or NULL, and the floats */
  const float *xf;
  const uint32_t *triangles;
  char title[128];
} mpm_triangle_mesh;

/* OBJ: a comment with the title, v records (%.9g: floats round-trip), f records, 1-based. */
mpm_status mpm_write_mesh_obj(const char *path, const mpm_triangle_mesh *m, mpm_error *err);
/* PLY: binary little endian, float x y z and a uchar-counted int list vertex_indices. */
mpm_status mpm_write_mesh_ply(const char *path, const mpm_triangle_mesh *m, mpm_error *err);
/* VTK XML PolyData, ASCII (a surface has a few thousand vertices, small enough as text), with
 * the frame's time as TIME, float32 points as the PLY: run.pvd lists it with the frame. */
mpm_status mpm_write_mesh_vtp(const char *path, const mpm_triangle_mesh *m, double time,
                              mpm_error *err);

#endif
