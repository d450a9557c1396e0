/* vdb_shim.h - the C face of OpenVDB (Museth 2013; the library Houdini and Blender use): particles
 * to a narrow-band level set, level-set smoothing, level set to a triangle mesh, and .vdb files
 * written and read back.
 *
 * The C++ stays in vdb_shim.cpp. Handles are opaque; every call returns MPM_VDB_OK or
 * MPM_VDB_FAIL and, on failure, writes a message into msg (cap bytes, may be NULL). No C++
 * exception crosses this boundary: the shim catches them all and reports them as messages.
 * Each call runs on at most `threads` TBB workers (0: TBB's default). A handle is not safe to
 * use from two threads at once. */
#ifndef MPM_SURFACE_VDB_SHIM_H
#define MPM_SURFACE_VDB_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum { MPM_VDB_OK = 0, MPM_VDB_FAIL = -1 };

/* The smoothing filter of one pass (openvdb::tools::LevelSetFilter). */
typedef enum mpm_vdb_filter {
  MPM_VDB_FILTER_MEAN_CURVATURE = 0, /* mean-curvature flow: flattens bumps, keeps volume best */
  MPM_VDB_FILTER_GAUSSIAN = 1,       /* Gaussian of width 1 voxel */
  MPM_VDB_FILTER_LAPLACIAN = 2,      /* Laplacian flow */
} mpm_vdb_filter;

/* The grid classes of a .vdb grid (openvdb::GridClass). */
typedef enum mpm_vdb_class {
  MPM_VDB_CLASS_UNKNOWN = 0,
  MPM_VDB_CLASS_LEVEL_SET = 1,
  MPM_VDB_CLASS_FOG_VOLUME = 2,
  MPM_VDB_CLASS_STAGGERED = 3,
} mpm_vdb_class;

/* A float grid (openvdb::FloatGrid), owned by the caller. */
typedef struct mpm_vdb_grid mpm_vdb_grid;

/// 1 when the library was built with OpenVDB and its module (libmpmvdb.so) loads; 0 for the
/// stub (vdb_stub.c) or a module that cannot be found, when every other call fails with a
/// message saying so.
int mpm_vdb_available(void);

/// The narrow-band signed distance (negative inside) of the CSG union of the spheres of n
/// particles: centre xyz[3i..3i+2] and radius radius[i] (m), on voxels of `voxel` m, with a
/// band of half_width voxels each side (>= 2). Spheres smaller than a voxel are still drawn
/// (OpenVDB's limit of 1.5 voxels is lowered to 0.5). The grid is named "surface" and has class
/// level set. *out is NULL on failure.
int mpm_vdb_levelset_from_spheres(const double *xyz, const double *radius, size_t n, double voxel,
                                  double half_width, int threads, mpm_vdb_grid **out, char *msg,
                                  size_t cap);

/// The narrow band rebuilt as an exact signed distance of half-width 3 voxels
/// (openvdb::tools::levelSetRebuild), `passes` passes of `filter`, then the surface moved inward
/// by `offset` m (outward for offset < 0).
int mpm_vdb_smooth(mpm_vdb_grid *grid, int passes, mpm_vdb_filter filter, double offset,
                   int threads, char *msg, size_t cap);

/// The zero isosurface as triangles (openvdb::tools::volumeToMesh, adaptivity 0, its quads
/// split along a diagonal): *points gets 3 floats per vertex (m), *triangles 3 vertex indices
/// per triangle, counter-clockwise seen from outside (outward normals). Both arrays come from
/// the engine's allocator (the table's set_allocator: mpm_alloc) and are freed by the caller
/// with mpm_free; zero triangles is not a failure.
int mpm_vdb_mesh(const mpm_vdb_grid *grid, int threads, float **points, size_t *point_count,
                 uint32_t **triangles, size_t *triangle_count, char *msg, size_t cap);

/// Number of active voxels (the narrow band), for figures.
uint64_t mpm_vdb_active_voxels(const mpm_vdb_grid *grid);

/* A vector grid (openvdb::Vec3SGrid), owned by the caller. */
typedef struct mpm_vdb_vector_grid mpm_vdb_vector_grid;

/// The particles' velocity as a vector grid "vel" (the name Houdini's and Blender's volume
/// tools look for) on voxels of `voxel` m, indexed like the level set's (voxel ijk at world
/// ijk * voxel): every voxel within one voxel of a particle holds the mass-weighted trilinear
/// average sum_p w_ip m_p v_p / sum_p w_ip m_p (a linear-kernel P2G: a rigid translation is
/// reproduced exactly). Particle p is centred at xyz[3p..3p+2] with velocity v[3p..3p+2] (m/s)
/// and mass mass[p]. Vector type contravariant-relative (a displacement per time). Serial.
int mpm_vdb_velocity_from_particles(const double *xyz, const double *v, const double *mass,
                                    size_t n, double voxel, mpm_vdb_vector_grid **out, char *msg,
                                    size_t cap);

/// Write the level set to a .vdb file at `path` (created or replaced; the caller renames it
/// into place for atomicity). With `density` set, a second grid "density" (class fog volume:
/// 0 outside, rising to 1 one band half-width inside) is written beside it; with `velocity`
/// non-NULL, that vector grid too.
int mpm_vdb_write(const mpm_vdb_grid *grid, const char *path, int density,
                  const mpm_vdb_vector_grid *velocity, char *msg, size_t cap);

/// Read the grid called `name` of the .vdb file at `path` (a float grid). *out is NULL on
/// failure, which names the file and the grids it holds.
int mpm_vdb_read(const char *path, const char *name, mpm_vdb_grid **out, char *msg, size_t cap);

/// The grid's name (into name, cap bytes), class and voxel size (m, along x).
void mpm_vdb_grid_info(const mpm_vdb_grid *grid, char *name, size_t cap, mpm_vdb_class *cls,
                       double *voxel);

/// The grid's value at the world point x (trilinear), m for a level set.
double mpm_vdb_sample(const mpm_vdb_grid *grid, const double x[3]);

void mpm_vdb_grid_destroy(mpm_vdb_grid *grid);

/// Read the vector grid called `name` of the .vdb file at `path` (a Vec3f grid); *out is NULL
/// on failure, which names the file and what it holds.
int mpm_vdb_read_vector(const char *path, const char *name, mpm_vdb_vector_grid **out, char *msg,
                        size_t cap);

/// The vector grid's value at the world point x (trilinear) into v, its active voxel count, and
/// its name (into name, cap bytes).
void mpm_vdb_vector_sample(const mpm_vdb_vector_grid *grid, const double x[3], double v[3]);
uint64_t mpm_vdb_vector_active_voxels(const mpm_vdb_vector_grid *grid);
void mpm_vdb_vector_name(const mpm_vdb_vector_grid *grid, char *name, size_t cap);

void mpm_vdb_vector_grid_destroy(mpm_vdb_vector_grid *grid);

/* The module (libmpmvdb.so, vdb_shim.cpp) exports one function, mpm_vdb_module_table, that
 * returns these entry points; vdb_load.c opens it with dlopen at the first call above, so that a
 * run without surfaces does not load OpenVDB and its libraries (42 of the program's 55 ms of
 * start-up: the relocations of libopenvdb and its dependencies). The version changes whenever
 * the table does. */
#define MPM_VDB_TABLE_VERSION 2
typedef struct mpm_vdb_table {
  int version;
  int (*levelset_from_spheres)(const double *, const double *, size_t, double, double, int,
                               mpm_vdb_grid **, char *, size_t);
  int (*smooth)(mpm_vdb_grid *, int, mpm_vdb_filter, double, int, char *, size_t);
  int (*mesh)(const mpm_vdb_grid *, int, float **, size_t *, uint32_t **, size_t *, char *, size_t);
  uint64_t (*active_voxels)(const mpm_vdb_grid *);
  int (*velocity_from_particles)(const double *, const double *, const double *, size_t, double,
                                 mpm_vdb_vector_grid **, char *, size_t);
  int (*write)(const mpm_vdb_grid *, const char *, int, const mpm_vdb_vector_grid *, char *,
               size_t);
  int (*read)(const char *, const char *, mpm_vdb_grid **, char *, size_t);
  void (*grid_info)(const mpm_vdb_grid *, char *, size_t, mpm_vdb_class *, double *);
  double (*sample)(const mpm_vdb_grid *, const double[3]);
  void (*grid_destroy)(mpm_vdb_grid *);
  int (*read_vector)(const char *, const char *, mpm_vdb_vector_grid **, char *, size_t);
  void (*vector_sample)(const mpm_vdb_vector_grid *, const double[3], double[3]);
  uint64_t (*vector_active_voxels)(const mpm_vdb_vector_grid *);
  void (*vector_name)(const mpm_vdb_vector_grid *, char *, size_t);
  void (*vector_grid_destroy)(mpm_vdb_vector_grid *);
  /* the allocator of the arrays the module gives the engine (mesh's), set once at load */
  void (*set_allocator)(void *(*alloc)(size_t), void (*release)(void *));
} mpm_vdb_table;

#ifdef __cplusplus
}
#endif

#endif
