/* sim_surface.c - output.surface per frame (issue 14): the particles of the selected bodies or
 * materials become a closed triangle surface (src/surface/surface.h), written as
 * surface_NNNN.obj and surface_NNNN.ply (or surface_bB_NNNN.* per body B with per_body), and
 * with output.vdb its level set as levelset_NNNN.vdb (levelset_bB_NNNN.vdb; with vdb_velocity the
 * same particles' velocity beside it as the vector grid "vel"). A mesh body with
 * particle domains keeps its embedded mesh (Zhu sec. 4.1, surface_bodyB_NNNN.*): "all bodies"
 * leaves it out. */
#include "sim/sim.h"
#include "core/alloc.h"
#include "core/mat3.h"
#include "core/parallel.h"
#include "surface/surface.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Which bodies and materials make surfaces: flags per body and per material. */
static void selection(const mpm_sim *sim, unsigned char *body, unsigned char *material) {
  const mpm_surface_desc *d = &sim->scene.output.surface;
  const int nb = sim->scene.body_count, nm = sim->scene.material_count;
  memset(body, 0, (size_t)nb + 1);
  memset(material, 0, (size_t)nm + 1);
  if (d->material_count) {
    for (int k = 0; k < d->material_count; ++k) material[d->materials[k]] = 1;
    for (int b = 0; b < nb; ++b) body[b] = 1;
    return;
  }
  for (int m = 0; m < nm; ++m) material[m] = 1;
  if (d->body_count) {
    for (int k = 0; k < d->body_count; ++k) body[d->bodies[k]] = 1;
    return;
  }
  for (int b = 0; b < nb; ++b) body[b] = 1;
  for (int s = 0; s < sim->surface_count; ++s) body[sim->surfaces[s].body] = 0;
}

/* The buffers of one surface's particles: centres and volumes, and with vdb_velocity their
   velocities and masses (NULL otherwise). */
typedef struct surface_buffers {
  double *xyz, *vol, *vel, *mass;
} surface_buffers;

/* The velocity grid of the n particles gathered in b, on the level set's voxels (the surface's
   voxel key, or the particle spacing the surface chose when it is 0). */
static mpm_status velocity_grid(mpm_sim *sim, const surface_buffers *b, size_t n, double voxel,
                                int frame, mpm_vdb_vector_grid **out) {
  char msg[512];
  if (mpm_vdb_velocity_from_particles(b->xyz, b->vel, b->mass, n, voxel, out, msg, sizeof msg) !=
      MPM_VDB_OK)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID, "frame %d: %s", frame, msg);
  return MPM_OK;
}

/* One surface of the particles of p with body == only (or any selected body when only < 0); its
 * triangles added to *triangles. */
static mpm_status one_surface(mpm_sim *sim, const mpm_particles *p, const char *dir,
                              const unsigned char *body, const unsigned char *material, int only,
                              int frame, const surface_buffers *buf, size_t *triangles) {
  double *xyz = buf->xyz, *vol = buf->vol;
  const mpm_output_desc *o = &sim->scene.output;
  const double dx = sim->scene.dx;
  size_t n = 0;
  for (size_t i = 0; i < p->count; ++i) {
    const int b = p->body[i];
    if (!(only < 0 ? body[b] : b == only) || !material[p->material[i]]) continue;
    mpm_real F[9];
    for (int c = 0; c < 9; ++c) F[c] = p->F[c][i];
    for (int d = 0; d < 3; ++d) xyz[3 * n + (size_t)d] = p->x[d][i];
    if (buf->vel) {
      for (int d = 0; d < 3; ++d) buf->vel[3 * n + (size_t)d] = p->v[d][i];
      buf->mass[n] = p->mass[i];
    }
    vol[n++] = (double)p->vol0[i] * (double)mpm_m3_det(F);
  }
  mpm_surface_params par = mpm_surface_params_default();
  par.voxel = o->surface.voxel * dx;
  par.radius = o->surface.radius * dx;
  par.smoothing = o->surface.smoothing;
  par.filter = (mpm_vdb_filter)o->surface.filter;
  par.threads = mpm_thread_count();
  mpm_surface_mesh mesh;
  mpm_vdb_grid *grid = NULL;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_surface_figures fig;
  mpm_status st = mpm_surface_build(xyz, vol, n, &par, &mesh, o->vdb ? &grid : NULL, &fig, &err);
  if (st != MPM_OK) return mpm_error_set(&sim->error, st, "frame %d: %s", frame, err.message);
  char tag[32] = "", path[MPM_PATH_MAX + 64];
  if (only >= 0) snprintf(tag, sizeof tag, "b%d_", only);
  snprintf(path, sizeof path, "%s/surface_%s%04d.obj", dir, tag, frame);
  const mpm_triangle_mesh view = mpm_surface_mesh_view(&mesh);
  st = mpm_write_mesh_obj(path, &view, &sim->error);
  if (st == MPM_OK) {
    snprintf(path, sizeof path, "%s/surface_%s%04d.ply", dir, tag, frame);
    st = mpm_write_mesh_ply(path, &view, &sim->error);
  }
  mpm_vdb_vector_grid *velocity = NULL;
  if (st == MPM_OK && grid && buf->vel)
    st = velocity_grid(sim, buf, n, fig.voxel, frame, &velocity);
  if (st == MPM_OK && grid) {
    snprintf(path, sizeof path, "%s/levelset_%s%04d.vdb", dir, tag, frame);
    st = mpm_surface_write_vdb(path, grid, o->vdb_density, velocity, &sim->error);
  }
  mpm_vdb_vector_grid_destroy(velocity);
  *triangles += mesh.triangle_count;
  mpm_surface_mesh_free(&mesh);
  mpm_vdb_grid_destroy(grid);
  return st;
}

mpm_status mpm_sim_write_surfaces(mpm_sim *sim, const mpm_particles *p, const char *dir, int frame,
                                  int records) {
  const double t0 = mpm_wall_seconds();
  size_t triangles = 0;
  const int nb = sim->scene.body_count;
  unsigned char *body = mpm_alloc((size_t)nb + 1);
  unsigned char *material = mpm_alloc((size_t)sim->scene.material_count + 1);
  const int with_velocity = sim->scene.output.vdb_velocity;
  surface_buffers buf = {mpm_alloc((3 * p->count + 3) * sizeof(double)),
                         mpm_alloc((p->count + 1) * sizeof(double)),
                         with_velocity ? mpm_alloc((3 * p->count + 3) * sizeof(double)) : NULL,
                         with_velocity ? mpm_alloc((p->count + 1) * sizeof(double)) : NULL};
  mpm_status st = MPM_OK;
  if (!body || !material || !buf.xyz || !buf.vol || (with_velocity && (!buf.vel || !buf.mass))) {
    st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory for the surfaces of frame %d",
                       frame);
  } else {
    selection(sim, body, material);
    if (sim->scene.output.surface.per_body) {
      for (int b = 0; b < nb && st == MPM_OK; ++b)
        if (body[b]) st = one_surface(sim, p, dir, body, material, b, frame, &buf, &triangles);
    } else {
      st = one_surface(sim, p, dir, body, material, -1, frame, &buf, &triangles);
    }
  }
  mpm_free(body);
  mpm_free(material);
  mpm_free(buf.xyz);
  mpm_free(buf.vol);
  mpm_free(buf.vel);
  mpm_free(buf.mass);
  if (records) { /* the run's figures (mpm_sim_info); a one-off frame leaves them */
    sim->out.surface_triangles = triangles;
    sim->out.surface_seconds = mpm_wall_seconds() - t0;
    sim->out.surface_seconds_total += sim->out.surface_seconds;
    sim->out.surface_frames++;
  }
  return st;
}
