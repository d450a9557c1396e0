/* sim_edit.c - what a script changes between two steps (include/mpm/mpm.h): particles'
 * velocities and positions, chosen by their stable ids; a collider's pose; a new body.
 *
 * Every request is checked before anything changes (ids simulated now, on material points,
 * finite values, positions inside the domain), so a refused call leaves the state as it was. */
#define _DEFAULT_SOURCE /* realpath */
#include "sim/grid_stack.h"
#include "sim/sim.h"
#include "core/alloc.h"
#include "core/hash.h"
#include "io/input_file.h"
#include "scene/sample.h"

#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A simulation whose state a failed step lost takes no changes either (frame.c's latch). */
static mpm_status refuse_failed(mpm_sim *sim, const char *what) {
  return mpm_error_set(&sim->error, sim->failed,
                       "%s: the simulation failed at step %lld and cannot go on (%s)", what,
                       (long long)sim->steps, sim->failed_message);
}

/* The material point index of every requested id in *index (count entries), or an error naming
 * the first id that is not a material point simulated now. */
static mpm_status find_ids(mpm_sim *sim, const char *what, size_t count, const uint32_t *ids,
                           uint32_t **index) {
  const mpm_particles *p = &sim->particles;
  *index = NULL;
  if (sim->failed != MPM_OK) return refuse_failed(sim, what);
  if (count && !ids) return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%s: ids is NULL", what);
  uint32_t top = 0;
  for (size_t i = 0; i < p->count; ++i)
    if (p->id[i] > top) top = p->id[i];
  /* id -> index + 1 (0: not a material point); ids past the largest are none */
  uint32_t *slot = mpm_calloc((size_t)top + 1, sizeof *slot);
  uint32_t *out = mpm_alloc((count + 1) * sizeof *out);
  if (!slot || !out) {
    mpm_free(slot);
    mpm_free(out);
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  }
  for (size_t i = 0; i < p->count; ++i) slot[p->id[i]] = (uint32_t)i + 1;
  for (size_t k = 0; k < count; ++k) {
    if (ids[k] <= top && slot[ids[k]]) {
      out[k] = slot[ids[k]] - 1;
      continue;
    }
    int domain = 0; /* a particle whose domain is on moves with its corners */
    const mpm_particles *d = &sim->domains.particles;
    for (size_t q = 0; q < d->count && !domain; ++q)
      domain = d->id[q] == ids[k] && sim->domains.active[q];
    mpm_free(slot);
    mpm_free(out);
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         domain ? "%s: particle id %u has its domain on: it moves with its "
                                  "domain's corners (release its domain first)"
                                : "%s: no particle with id %u is simulated now",
                         what, ids[k]);
  }
  mpm_free(slot);
  *index = out;
  return MPM_OK;
}

/* Velocities (positions 0) or positions (1) of the particles with the given ids: every value
 * checked before any is written. */
static mpm_status set_vectors(mpm_sim *sim, const char *what, size_t count, const uint32_t *ids,
                              const double *values, int positions) {
  uint32_t *index;
  mpm_status st = find_ids(sim, what, count, ids, &index);
  if (st != MPM_OK) return st;
  const mpm_scene *sc = &sim->scene;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) {
      const double c = values[3 * k + d];
      /* a position inside the domain (the step's wall band takes particles near the walls);
         a velocity finite */
      const int ok =
          positions ? c > sc->box_min[d] && c < sc->box_max[d] : isfinite(c) && fabs(c) <= 1e30;
      if (ok) continue;
      mpm_free(index);
      if (positions)
        return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                             "%s: particle id %u: coordinate %d is %g; expected a number inside "
                             "the domain, %g to %g (m)",
                             what, ids[k], d, c, sc->box_min[d], sc->box_max[d]);
      return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                           "%s: particle id %u: velocity component %d is %g; expected a finite "
                           "number (m/s)",
                           what, ids[k], d, c);
    }
  mpm_particles *p = &sim->particles;
  for (size_t k = 0; k < count; ++k)
    for (int d = 0; d < 3; ++d) {
      if (positions) {
        p->x[d][index[k]] = (mpm_real)values[3 * k + d];
        p->xc[d][index[k]] = 0; /* a jump: nothing left of the old position's rounding */
      } else {
        p->v[d][index[k]] = (mpm_real)values[3 * k + d];
      }
    }
  mpm_free(index);
  if (positions) sim->stack->particles_moved(sim); /* what the sort kept may not hold */
  return MPM_OK;
}

mpm_status mpm_sim_set_velocities(mpm_sim *sim, size_t count, const uint32_t *ids,
                                  const double *v) {
  return set_vectors(sim, "mpm_sim_set_velocities", count, ids, v, 0);
}

mpm_status mpm_sim_set_positions(mpm_sim *sim, size_t count, const uint32_t *ids, const double *x) {
  return set_vectors(sim, "mpm_sim_set_positions", count, ids, x, 1);
}

mpm_status mpm_sim_set_collider_pose(mpm_sim *sim, int index, const double center[3],
                                     const double rotation[9]) {
  const char *what = "mpm_sim_set_collider_pose";
  if (sim->failed != MPM_OK) return refuse_failed(sim, what);
  if (index < 0 || index >= sim->collider_count)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "%s: collider %d does not exist (the scene has %d)", what, index,
                         sim->collider_count);
  if (!center) return mpm_error_set(&sim->error, MPM_ERR_INVALID, "%s: center is NULL", what);
  mpm_collider *c = &sim->colliders[index];
  for (int d = 0; d < 3; ++d)
    if (!isfinite(center[d]) || fabs(center[d]) > 1e15)
      return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                           "%s: collider '%s': center[%d] is %g; expected a finite number (m)",
                           what, c->desc.name, d, center[d]);
  double R[9];
  if (rotation) {
    memcpy(R, rotation, sizeof R);
    /* a rotation: R R^T = I within 1e-6, det +1 */
    double worst = 0;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        const double dot =
            R[3 * r] * R[3 * k] + R[3 * r + 1] * R[3 * k + 1] + R[3 * r + 2] * R[3 * k + 2];
        const double e = fabs(dot - (r == k));
        if (!isfinite(e))
          worst = INFINITY;
        else if (e > worst)
          worst = e;
      }
    const double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                       R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (!(worst <= 1e-6) || !(det > 0))
      return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                           "%s: collider '%s': the rotation is not a rotation (|R R^T - I| = %g, "
                           "det R = %g); expected an orthonormal matrix, row-major, det +1",
                           what, c->desc.name, worst, det);
  } else { /* the rotation it has now */
    const mpm_collider_pose p = mpm_collider_pose_at(c, sim->time);
    for (int k = 0; k < 9; ++k) R[k] = c->script.on ? c->script.R[k] : (double)p.R[k];
  }
  mpm_collider_script_set(c, sim->time, center, R);
  return MPM_OK;
}

/* ---- a body added between steps ---------------------------------------------------------
 * The body is one entry of the scene's `bodies` list. It is checked as the scene's own bodies
 * are, by loading the scene's text (the copy the simulation keeps, mesh files by absolute path)
 * with the body appended, so every message names its key path; then it is sampled into the
 * material points with new ids, and the simulation's scene, its text (scene.json in the output
 * folder, which a resume reads) and its mesh digests take it in. */

/* A mesh body's `shape.file` made absolute (against base_dir, else the working directory), so
 * that it resolves the same in the simulation's scene, whatever that scene's folder. */
static void absolute_mesh_file(cJSON *body, const char *base_dir) {
  cJSON *shape = cJSON_GetObjectItemCaseSensitive(body, "shape");
  const cJSON *file = cJSON_GetObjectItemCaseSensitive(shape, "file");
  if (!cJSON_IsString(file) || file->valuestring[0] == '/') return;
  char joined[2 * MPM_PATH_MAX], abs_path[PATH_MAX];
  snprintf(joined, sizeof joined, "%s%s%s", base_dir && base_dir[0] ? base_dir : ".", "/",
           file->valuestring);
  if (realpath(joined, abs_path))
    cJSON_ReplaceItemInObjectCaseSensitive(shape, "file", cJSON_CreateString(abs_path));
}

mpm_status mpm_sim_add_body(mpm_sim *sim, const char *body_json, const char *base_dir,
                            size_t *count) {
  const char *what = "mpm_sim_add_body";
  if (count) *count = 0;
  if (sim->failed != MPM_OK) return refuse_failed(sim, what);
  if (!sim->scene_copy)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "%s: the simulation keeps no scene text to add the body to", what);
  if (!sim->stack->adds_bodies)
    return mpm_error_set(&sim->error, MPM_ERR_INVALID,
                         "%s: bodies are added on the uniform grid only (this scene has "
                         "domain.levels; a body's refinement rules are the scene's)",
                         what);
  cJSON *body = body_json ? cJSON_Parse(body_json) : NULL;
  if (!cJSON_IsObject(body)) {
    cJSON_Delete(body);
    return mpm_error_set(&sim->error, MPM_ERR_PARSE,
                         "%s: expected the JSON object of one entry of the scene's bodies", what);
  }
  absolute_mesh_file(body, base_dir);
  cJSON *root = cJSON_Parse(sim->scene_copy);
  cJSON *bodies = root ? cJSON_GetObjectItemCaseSensitive(root, "bodies") : NULL;
  if (!cJSON_IsArray(bodies)) {
    cJSON_Delete(body);
    cJSON_Delete(root);
    return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  }
  cJSON_AddItemToArray(bodies, body);
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) return mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  mpm_scene next;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_scene_parse(text, "<json>", &next, &err);
  if (st != MPM_OK) {
    cJSON_free(text);
    return mpm_error_set(&sim->error, st, "%s: %s", what, err.message);
  }
  const int b = next.body_count - 1;
  const mpm_body_desc *bd = &next.bodies[b];
  if (next.body_count != sim->scene.body_count + 1 ||
      next.material_count != sim->scene.material_count)
    st = mpm_error_set(&sim->error, MPM_ERR_INVALID,
                       "%s: bodies[%d].material: an added body takes a material of the scene "
                       "by its name (an inline material would be a new one)",
                       what, b);
  else if (bd->domains)
    st = mpm_error_set(&sim->error, MPM_ERR_INVALID,
                       "%s: bodies[%d].domains: a body with particle domains cannot be added "
                       "during a run (its corners join the domain set at the start)",
                       what, b);
  mpm_body_desc *grown = NULL;
  uint64_t *digests = NULL;
  if (st == MPM_OK) {
    grown = mpm_realloc(sim->scene.bodies, (size_t)next.body_count * sizeof *grown);
    if (grown) sim->scene.bodies = grown;
    if (sim->mesh_digests || bd->shape.kind == MPM_SHAPE_MESH) {
      digests = mpm_calloc((size_t)next.body_count, sizeof *digests);
      if (digests && sim->mesh_digests)
        memcpy(digests, sim->mesh_digests, (size_t)sim->scene.body_count * sizeof *digests);
    }
    if (!grown || ((sim->mesh_digests || bd->shape.kind == MPM_SHAPE_MESH) && !digests))
      st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  }
  if (st == MPM_OK && bd->shape.kind == MPM_SHAPE_MESH) {
    char file[2 * MPM_PATH_MAX], why[128];
    mpm_scene_mesh_file(&next, bd->shape.mesh_path, file, sizeof file);
    if (mpm_input_digest(file, &digests[b], why, sizeof why))
      st = mpm_error_set(&sim->error, MPM_ERR_IO, "%s: bodies[%d].shape.file: cannot read '%s': %s",
                         what, b, file, why);
  }
  /* the scene's text from now on, and its hash as a resume will read it: the folder's
     scene.json holds the text and a newline */
  char *copy = st == MPM_OK ? mpm_scene_copy_text(text, &next) : NULL;
  char *file_text = copy ? mpm_alloc(strlen(copy) + 2) : NULL;
  const int hashed = file_text != NULL;
  uint64_t hash = 0;
  if (hashed) {
    const size_t len = strlen(copy);
    memcpy(file_text, copy, len);
    file_text[len] = '\n', file_text[len + 1] = 0;
    hash = mpm_fnv1a64(file_text, len + 1);
    mpm_free(file_text);
  }
  if (st == MPM_OK && !hashed)
    st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  const size_t first = sim->particles.count;
  if (st == MPM_OK) {
    st = mpm_sample_body(&next, b, &sim->particles, &err);
    if (st != MPM_OK) {
      sim->particles.count = first; /* nothing of it stays */
      st = mpm_error_set(&sim->error, st, "%s: %s", what, err.message);
    }
  }
  if (st == MPM_OK && mpm_sim_ensure_scratch(sim))
    st = mpm_error_set(&sim->error, MPM_ERR_NOMEM, "%s: out of memory", what);
  if (st != MPM_OK) {
    sim->particles.count = first;
    mpm_free(digests);
    mpm_free(copy);
    cJSON_free(text);
    mpm_scene_free(&next);
    return st;
  }
  for (size_t i = first; i < sim->particles.count; ++i) {
    sim->particles.id[i] = sim->next_id++;
    sim->particles.plastic[i] = sim->materials[sim->particles.material[i]].model->plastic_initial;
  }
  /* the scene takes the body: its description, its text and hash (a checkpoint names the scene
     with the body; scene.json in the output folder is that scene), its mesh's digest */
  sim->scene.bodies[b] = *bd;
  sim->scene.body_count = next.body_count;
  sim->scene.source_hash = hash;
  mpm_free(sim->scene_copy);
  sim->scene_copy = copy;
  if (digests) {
    mpm_free(sim->mesh_digests);
    sim->mesh_digests = digests;
  }
  cJSON_free(text);
  mpm_scene_free(&next);
  if (count) *count = sim->particles.count - first;
  if (sim->out.enabled) return mpm_sim_write_scene_copy(sim);
  return MPM_OK;
}
