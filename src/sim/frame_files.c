/* frame_files.c - the default frame writer (frame_writer.h): this process writes every file of
 * a frame, each atomically through the io module: frame_NNNN.vtu (+ frames.pvd), the multi-level
 * grid's leaves (the grid stack's), with particle domains domains_NNNN.vtu, the embedded surfaces
 * (OBJ, PLY and VTP), the particle surfaces of output.surface (sim_surface.c), run.pvd (every VTK
 * file of every frame), frame_NNNN.ply and stats.csv; and the checkpoints (io/checkpoint.h). */
#include "sim/frame_writer.h"

#include "core/alloc.h"
#include "domain/enrich.h"
#include "io/triangle_mesh.h"
#include "sim/grid_stack.h"
#include "sim/sim.h"

#include <stdio.h>
#include <string.h>

/* run.pvd: per frame its particles, its domains and its embedded surfaces, one part each, so
 * that ParaView opens every file of the run from one index. The names follow from the frame
 * number (as the writers below make them), so a resumed run lists its earlier frames too. */
static mpm_status write_run_pvd(mpm_sim *sim, int frames, int has_domains) {
  const char *grid = sim->stack->frame_part(sim); /* the grid's file per frame, if any */
  const int parts = 1 + has_domains + sim->surface_count + (grid != NULL);
  enum { NAME = 64 };
  char(*names)[NAME] = mpm_alloc((size_t)parts * NAME);
  char(*text)[NAME] = mpm_alloc((size_t)frames * (size_t)parts * NAME);
  const char **name_of = mpm_alloc((size_t)parts * sizeof *name_of);
  const char **files = mpm_alloc((size_t)frames * (size_t)parts * sizeof *files);
  mpm_status st = MPM_OK;
  if (!names || !text || !name_of || !files) {
    st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing run.pvd");
    goto done;
  }
  int k = 0;
  snprintf(names[k++], NAME, "particles");
  if (has_domains) snprintf(names[k++], NAME, "domains");
  for (int s = 0; s < sim->surface_count; ++s)
    snprintf(names[k++], NAME, "surface_body%d", sim->surfaces[s].body);
  if (grid) snprintf(names[k++], NAME, "%s", grid);
  for (k = 0; k < parts; ++k) name_of[k] = names[k];
  for (int f = 0; f < frames; ++f) {
    char(*row)[NAME] = text + (size_t)f * (size_t)parts;
    k = 0;
    snprintf(row[k++], NAME, "%s", sim->out.frame_files[f]);
    if (has_domains) snprintf(row[k++], NAME, "domains_%04d.vtu", f);
    for (int s = 0; s < sim->surface_count; ++s)
      snprintf(row[k++], NAME, "surface_body%d_%04d.vtp", sim->surfaces[s].body, f);
    if (grid) snprintf(row[k++], NAME, "%s_%04d.vtu", grid, f);
    for (k = 0; k < parts; ++k) files[(size_t)f * (size_t)parts + (size_t)k] = row[k];
  }
  char path[MPM_PATH_MAX + 64];
  snprintf(path, sizeof path, "%s/run.pvd", sim->out.dir);
  st = mpm_write_pvd_parts(path, frames, parts, sim->out.frame_times, name_of, files, &sim->error);
done:
  mpm_free(names);
  mpm_free(text);
  mpm_free(name_of);
  mpm_free(files);
  return st;
}

static mpm_status write_frame(mpm_sim *sim, const mpm_frame_record *r) {
  const mpm_frame_fields ff = r->ff;
  const mpm_particles *p = ff.particles;
  const mpm_real *J = ff.J, *stress = ff.stress, *melt = ff.melt, *cauchy = ff.cauchy,
                 *pressure = ff.pressure;
  const int32_t *category = ff.enrichment;
  const int heat = ff.heat, frame = r->frame, records = r->records, has_domains = r->has_domains;
  const char *dir = r->dir;
  const mpm_output_desc *o = &sim->scene.output;
  char vtu_name[32], path[MPM_PATH_MAX + 64];
  mpm_status st = MPM_OK;
  if (o->vtu) {
    snprintf(vtu_name, sizeof vtu_name, "frame_%04d.vtu", frame);
    snprintf(path, sizeof path, "%s/%s", dir, vtu_name);
    st = mpm_write_vtu(path, &ff, &sim->error);
    if (st != MPM_OK) return st;
  }
  if (o->vtu && records) {
    snprintf(sim->out.frame_files[frame], sizeof sim->out.frame_files[frame], "%s", vtu_name);
    sim->out.frame_times[frame] = sim->time;
    const char *files[frame + 1];
    for (int f = 0; f <= frame; ++f) files[f] = sim->out.frame_files[f];
    snprintf(path, sizeof path, "%s/frames.pvd", sim->out.dir);
    st = mpm_write_pvd(path, frame + 1, sim->out.frame_times, files, &sim->error);
    if (st != MPM_OK) return st;
  }
  if (o->vtu && records && (st = sim->stack->write_frame(sim, frame)) != MPM_OK) return st;
  if (o->vtu && has_domains) {
    snprintf(path, sizeof path, "%s/domains_%04d.vtu", dir, frame);
    /* the domain particles' part of the frame's arrays (after the material points, in the
       set's order of its active domains, as the domain file's cells are) for output.fields */
    const size_t first = sim->particles.count;
    mpm_particles dp = *p;
    dp.count = p->count - first;
    for (int d = 0; d < 3; ++d) {
      dp.x[d] += first;
      dp.v[d] += first;
    }
    for (int c = 0; c < 9; ++c) {
      dp.F[c] += first;
      dp.B[c] += first;
    }
    dp.plastic += first;
    dp.mass += first;
    dp.vol0 += first;
    dp.temperature += first;
    dp.material += first;
    dp.body += first;
    dp.level += first;
    dp.id += first;
    const mpm_frame_fields cells = {&dp,
                                    J ? J + first : NULL,
                                    stress ? stress + first : NULL,
                                    sim->time,
                                    category ? category + first : NULL,
                                    heat,
                                    melt ? melt + first : NULL,
                                    o->fields, /* 0 without output.fields: the file's own only */
                                    cauchy ? cauchy + 9 * first : NULL,
                                    pressure ? pressure + first : NULL};
    st = mpm_write_domain_vtu(path, &sim->domains, sim->time, &cells, &sim->error);
    if (st != MPM_OK) return st;
  }
  for (int k = 0; k < sim->surface_count; ++k) { /* embedded surfaces (Zhu sec. 4.1) */
    const mpm_embedded_surface *e = &sim->surfaces[k];
    double *x = mpm_alloc(3 * (size_t)(e->vertex_count + 1) * sizeof *x);
    if (!x) {
      st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "out of memory writing frame %d", frame);
      return st;
    }
    mpm_embedded_positions(e, &sim->domains, x);
    mpm_triangle_mesh m = {(size_t)e->vertex_count,
                           (size_t)e->triangle_count,
                           x,
                           NULL,
                           (const uint32_t *)e->triangles,
                           ""}; /* the indices are >= 0 */
    snprintf(m.title, sizeof m.title, "mpm embedded surface (Zhu et al. 2017 sec. 4.1), body %d",
             e->body);
    snprintf(path, sizeof path, "%s/surface_body%d_%04d.obj", dir, e->body, frame);
    st = mpm_write_mesh_obj(path, &m, &sim->error);
    if (st == MPM_OK) {
      snprintf(path, sizeof path, "%s/surface_body%d_%04d.ply", dir, e->body, frame);
      st = mpm_write_mesh_ply(path, &m, &sim->error);
    }
    if (st == MPM_OK && o->vtu) { /* for ParaView, with the VTU files */
      snprintf(path, sizeof path, "%s/surface_body%d_%04d.vtp", dir, e->body, frame);
      st = mpm_write_mesh_vtp(path, &m, sim->time, &sim->error);
    }
    mpm_free(x);
    if (st != MPM_OK) return st;
  }
  if (o->surface.enabled) { /* particle surfaces (issue 14) */
    st = mpm_sim_write_surfaces(sim, p, dir, frame, records);
    if (st != MPM_OK) return st;
  }
  /* after every file it names exists */
  if (o->vtu && records) {
    st = write_run_pvd(sim, frame + 1, has_domains);
    if (st != MPM_OK) return st;
  }
  if (o->ply) {
    snprintf(path, sizeof path, "%s/frame_%04d.ply", dir, frame);
    st = mpm_write_ply_points(path, &ff, &sim->error);
    if (st != MPM_OK) return st;
  }
  if (r->stats_rows > 0) st = mpm_sim_write_stats(sim, r->stats_rows);
  return st;
}

mpm_status mpm_sim_write_stats(mpm_sim *sim, int rows) {
  char path[MPM_PATH_MAX + 64];
  snprintf(path, sizeof path, "%s/stats.csv", sim->out.dir);
  return mpm_write_stats_csv_forces(path, rows, sim->out.stats, sim->collider_count,
                                    sim->out.stats_forces, &sim->error);
}

static mpm_status write_checkpoint(mpm_sim *sim, const char *path, const mpm_checkpoint *c) {
  return mpm_checkpoint_write(path, c, &sim->error);
}

const mpm_frame_writer mpm_frame_files = {
    .name = "files",
    .frame = write_frame,
    .checkpoint = write_checkpoint,
};
