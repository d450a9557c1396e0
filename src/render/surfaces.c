/* surfaces.c - the particle surfaces of output.surface in a renderer's pictures: the per-frame
 * PLY meshes drawn as shaded triangles, and which particles they stand for. */
#include "render/renderer.h"
#include "core/alloc.h"
#include "scene/mesh.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The particle surfaces of frame k (output.surface): surface_NNNN.ply, or surface_bB_NNNN.ply
 * per body B < bodies. Each one found is drawn; *drawn counts them. The status with err on a
 * bad file or no memory. */
mpm_status mpm_render_draw_surfaces(const char *dir, int k, int bodies, mpm_image *img,
                                    const mpm_camera *cam, int *drawn, mpm_error *err) {
  *drawn = 0;
  for (int b = -1; b < bodies; ++b) {
    char path[4300];
    if (b < 0)
      snprintf(path, sizeof path, "%s/surface_%04d.ply", dir, k);
    else
      snprintf(path, sizeof path, "%s/surface_b%d_%04d.ply", dir, b, k);
    struct stat sb;
    if (stat(path, &sb) != 0) continue;
    mpm_mesh m;
    mpm_error load_err;
    mpm_error_clear(&load_err);
    if (mpm_mesh_load(path, &m, &load_err) != MPM_OK) {
      if (strstr(load_err.message, "no faces")) continue; /* an empty surface */
      return mpm_error_set(err, load_err.status, "%s", load_err.message);
    }
    float *xyz = mpm_alloc((3 * (size_t)m.vertex_count + 1) * sizeof *xyz);
    uint32_t *tri = mpm_alloc((3 * (size_t)m.triangle_count + 1) * sizeof *tri);
    mpm_status st = MPM_OK;
    if (!xyz || !tri) {
      st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for the surface", path);
    } else {
      for (size_t i = 0; i < 3 * (size_t)m.vertex_count; ++i) xyz[i] = (float)m.vertices[i];
      for (size_t i = 0; i < 3 * (size_t)m.triangle_count; ++i) tri[i] = (uint32_t)m.triangles[i];
      float rgb[3] = {0.80f, 0.70f, 0.52f}; /* one surface: sand; one per body: its colour */
      if (b >= 0) mpm_colormap_eval(MPM_CMAP_CATEGORY, b, rgb);
      st = mpm_render_triangles(img, cam, (size_t)m.vertex_count, xyz, (size_t)m.triangle_count,
                                tri, rgb, err);
      ++*drawn;
    }
    mpm_free(xyz);
    mpm_free(tri);
    mpm_mesh_free(&m);
    if (st != MPM_OK) return st;
  }
  return MPM_OK;
}

/* Whether a particle of body b and material m is drawn by a surface (output.surface of the
 * scene), so that its splat is left out. */
int mpm_render_on_surface(const mpm_scene *s, int b, int m) {
  const mpm_surface_desc *d = &s->output.surface;
  if (!d->enabled || b < 0 || b >= s->body_count) return 0;
  if (d->material_count) {
    for (int k = 0; k < d->material_count; ++k)
      if (d->materials[k] == m) return 1;
    return 0;
  }
  if (d->body_count) {
    for (int k = 0; k < d->body_count; ++k)
      if (d->bodies[k] == b) return 1;
    return 0;
  }
  /* all bodies but those that keep their embedded mesh (a mesh body with domains) */
  return !(s->bodies[b].domains && s->bodies[b].shape.kind == MPM_SHAPE_MESH);
}
