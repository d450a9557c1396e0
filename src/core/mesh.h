/* mesh.h - a triangle mesh as plain arrays: what the mesh readers (scene/mesh.h) make and the
 * embedded surfaces (domain/embed.h) take. */
#ifndef MPM_CORE_MESH_H
#define MPM_CORE_MESH_H

typedef struct mpm_mesh {
  int vertex_count, triangle_count;
  double *vertices; /* 3 per vertex: x y z, in the file's units */
  int *triangles;   /* 3 per triangle: zero-based vertex indices */
  /* per triangle, where the loader read its face: the OBJ line of its `f` record, or the
     index of its PLY `face` element (source_is_line 0); NULL for meshes made otherwise */
  int *triangle_source;
  int source_is_line;
} mpm_mesh;

#endif
