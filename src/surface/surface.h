/* surface.h - a triangle surface from particles, per frame (issue 14; Zhu et al. 2017 Fig. 11
 * reconstruct the melting bunny's surface from its particles).
 *
 * The particles become the union of one sphere each, as an OpenVDB narrow-band level set
 * (vdb_shim.h), which is rebuilt as an exact signed distance, smoothed by a few filter passes
 * and moved inward so that a flat face of the material ends half a particle spacing beyond its
 * outermost particles (the body's own boundary when it was sampled), then meshed and its quads
 * split into triangles. The mesh is closed and outward facing (counter-clockwise seen from
 * outside). Writers: OBJ, binary PLY, and the level set as .vdb, each atomically (a temporary
 * in the same folder, renamed). */
#ifndef MPM_SURFACE_SURFACE_H
#define MPM_SURFACE_SURFACE_H

#include "core/error.h"
#include "io/triangle_mesh.h"
#include "surface/vdb_shim.h"

#include <stddef.h>
#include <stdint.h>

/* A sphere's radius over the particle spacing cbrt(V) when the scene gives none: the spheres
 * of the particles' own volumes (radius 0.62 cbrt(V)) leave gaps at the centres of the
 * lattice's cubes, 0.87 cbrt(V) from their particles; at 1.0 neighbours overlap and the
 * union has no holes or inner bubbles. */
#define MPM_SURFACE_RADIUS_SCALE 1.0

typedef struct mpm_surface_params {
  double voxel;  /* m; 0: the median particle spacing */
  double radius; /* m; 0: MPM_SURFACE_RADIUS_SCALE cbrt(V) of each particle */
  int smoothing; /* filter passes */
  mpm_vdb_filter filter;
  int threads; /* TBB workers; 0: all */
} mpm_surface_params;

mpm_surface_params mpm_surface_params_default(void);

/* A triangle mesh, caller-owned (mpm_surface_mesh_free). */
typedef struct mpm_surface_mesh {
  size_t vertex_count, triangle_count;
  float *vertices;     /* 3 per vertex, m */
  uint32_t *triangles; /* 3 vertex indices per triangle */
} mpm_surface_mesh;

void mpm_surface_mesh_free(mpm_surface_mesh *m);

/* What one reconstruction cost and used. */
typedef struct mpm_surface_figures {
  size_t particles;
  double voxel, radius_mean, offset; /* m */
  uint64_t voxels;                   /* active voxels after filtering */
  double levelset_seconds, filter_seconds, mesh_seconds;
} mpm_surface_figures;

/// The surface of n particles at xyz[3i..3i+2] (m) with volumes volume[i] (m^3, current).
/// With grid non-NULL the level set is handed to the caller (mpm_vdb_grid_destroy); figures
/// may be NULL. n = 0 gives an empty mesh.
mpm_status mpm_surface_build(const double *xyz, const double *volume, size_t n,
                             const mpm_surface_params *p, mpm_surface_mesh *mesh,
                             mpm_vdb_grid **grid, mpm_surface_figures *figures, mpm_error *err);

/// The mean height (m) of the union of spheres of radius r on a cubic lattice of spacing s above
/// the centres of a flat face's outermost particles, over the square one particle covers. The
/// surface is moved inward by this less s / 2 (at least 0): a face then ends half a spacing
/// beyond its outermost particles, where the sampled body's boundary was.
double mpm_surface_face_height(double r, double s);

/// The mesh as the triangle writers take it (io/triangle_mesh.h: OBJ, PLY).
mpm_triangle_mesh mpm_surface_mesh_view(const mpm_surface_mesh *m);
/// The level set "surface" as a VDB file, atomically (and with density a fog volume "density",
/// with velocity that vector grid "vel").
mpm_status mpm_surface_write_vdb(const char *path, const mpm_vdb_grid *grid, int density,
                                 const mpm_vdb_vector_grid *velocity, mpm_error *err);

#endif
