/* mesh.h - triangle meshes read from OBJ and PLY files, and a point-in-mesh test.
 *
 * A mesh is a plain caller-owned struct of vertex and triangle arrays (`_load` / `_free`).
 * Polygons are fan-triangulated on load. Bodies made from meshes are sampled in
 * scene/sample.c, which has its own lattice-column accelerator; `mpm_mesh_inside` here is the
 * single-point reference (generalized winding number, Jacobson et al. 2013), robust to small
 * holes, O(triangles) per query. */
#ifndef MPM_SCENE_MESH_H
#define MPM_SCENE_MESH_H

#include "core/error.h"
#include "core/mesh.h"

#include <stddef.h>

/// Read a triangle mesh; the format is chosen by the extension (.obj or .ply, any case).
/// OBJ: `v` and `f` records (f accepts i, i/t, i//n, i/t/n and negative indices), everything
/// else ignored. PLY: ascii, binary_little_endian or binary_big_endian; element `vertex` with
/// scalar x y z (other properties skipped), element `face` with a list property (the one named
/// vertex_indices / vertex_index, else the first list). On failure *mesh is empty and err
/// names the file and the line (OBJ, PLY header and ascii data) or element, and what was
/// expected. A mesh without triangles is an error (MPM_ERR_PARSE). mesh is owned by the caller.
mpm_status mpm_mesh_load(const char *path, mpm_mesh *mesh, mpm_error *err);
/// The same, refusing a file of more than max_bytes (it is read whole into memory, so a 2 GB
/// file would be before anything else could refuse it) with MPM_ERR_INVALID naming its size,
/// the limit and the key max_file_mb that raises it.
mpm_status mpm_mesh_load_max(const char *path, double max_bytes, mpm_mesh *mesh, mpm_error *err);

/// The file formats mpm_mesh_parse reads.
typedef enum mpm_mesh_format {
  MPM_MESH_OBJ = 0,
  MPM_MESH_PLY = 1,
} mpm_mesh_format;

/// Parse a mesh from memory: data[0, len) holds the bytes of an OBJ or PLY file (it need not
/// be NUL-terminated; it is copied, not kept). Messages name path_for_messages (NULL:
/// "<mesh>") where mpm_mesh_load names the file; otherwise the same contract as
/// mpm_mesh_load, which reads the file and calls this parser.
mpm_status mpm_mesh_parse(const char *data, size_t len, mpm_mesh_format format,
                          const char *path_for_messages, mpm_mesh *mesh, mpm_error *err);

/// Release the arrays of a mesh and zero it; a zeroed mesh is fine.
void mpm_mesh_free(mpm_mesh *mesh);

/// Axis-aligned bounding box of all vertices (zeros for a mesh without vertices).
void mpm_mesh_bounds(const mpm_mesh *mesh, double lo[3], double hi[3]);

/// Number of edges used by exactly one triangle (0 for a closed, watertight mesh).
/// Allocates a temporary edge list; returns -1 when out of memory.
long mpm_mesh_boundary_edges(const mpm_mesh *mesh);

/// The edges of a mesh by the number of triangles that share them: `boundary` edges of one
/// triangle (a hole), `non_manifold` edges of more than two (surfaces that meet along a line:
/// inside and outside are not defined there), and the first such edge (its zero-based
/// vertices a, b) with up to 4 of its triangles (zero-based, `shared` of them in all).
typedef struct mpm_mesh_edges {
  long boundary, non_manifold;
  int a, b;
  int triangles[4], shared;
} mpm_mesh_edges;

/// Count the edges as above; MPM_OK, or MPM_ERR_NOMEM when out of memory.
mpm_status mpm_mesh_edge_check(const mpm_mesh *mesh, mpm_mesh_edges *out);

/// 1 when p is inside the mesh: |generalized winding number| > 1/2. Exact 0/1 for closed
/// meshes away from the surface, and a sensible answer for meshes with small holes; the
/// orientation of the triangles does not matter as long as it is consistent.
int mpm_mesh_inside(const mpm_mesh *mesh, const double p[3]);

/// The generalized winding number itself (sum of signed solid angles / 4 pi).
double mpm_mesh_winding_number(const mpm_mesh *mesh, const double p[3]);

#endif
