/* scene_def_options.c - the scene def written as JSON, part two (scene_def_parts.h): the domain
 * with its multi-level grid (levels, refinement rules, resampling; scene_json_refine.c), the
 * solver, the output with its surface (scene_json_surface.c), heat and the camera.
 *
 * Objects with a switch (resample, surface, heat, camera: `enabled`) are written only when it is
 * on, and their fields are refused by name when changed with it off; fields of another rule kind
 * or of the implicit integrator likewise. Everything the JSON carries is left to the format's
 * check, whose messages name the same paths. */
#include "scene/scene.h"
#include "scene/scene_def_parts.h"

#include <stdio.h>
#include <string.h>

/* ---- domain --------------------------------------------------------------------------- */

enum {
  R_BOX = 1 << 0,
  R_COLLIDER = 1 << 1,
  R_BODY = 1 << 2,
  R_DISTANCE = 1 << 3,
  R_SURFACE = 1 << 4,
  R_STRAIN = 1 << 5,
};
/* The fields of each mpm_def_refine_kind (scene_json_refine.c's rules). */
static const unsigned RULE_FIELDS[] = {
    R_BOX,                       /* box */
    R_COLLIDER | R_DISTANCE,     /* collider */
    R_BODY | R_DISTANCE | R_BOX, /* body: the box is its `within` */
    R_SURFACE | R_BODY,          /* surface: the body is optional */
    R_DISTANCE,                  /* types */
    R_STRAIN | R_DISTANCE,       /* strain */
};

/* A body, collider... given by name (when not NULL) or index (-1: none). */
static void add_reference(mpm_def_writer *w, cJSON *o, const char *key, const char *name,
                          int index) {
  if (name)
    mpm_def_add_string(w, o, key, name);
  else
    mpm_def_add_number(w, o, key, index);
}

static int write_rule(mpm_def_writer *w, int i, const mpm_refine_def *r, cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "domain.refine[%d].kind", i);
  const char *kind = mpm_def_spell(w->c, p, (int)r->kind, &mpm_def_refine_kinds);
  if (!kind) return -1;
  snprintf(p, sizeof p, "domain.refine[%d]", i);
  const mpm_refine_def d = mpm_refine_def_default();
  const unsigned has = RULE_FIELDS[r->kind];
  const struct {
    unsigned bit;
    const char *key;
    int changed;
  } fields[] = {
      {R_BOX, "box",
       !mpm_def_vec3_equal(r->box.min, d.box.min) || !mpm_def_vec3_equal(r->box.max, d.box.max)},
      {R_COLLIDER, "collider", r->collider != d.collider || r->collider_name},
      {R_BODY, "body", r->body != d.body || r->body_name},
      {R_DISTANCE, "distance", r->distance != d.distance},
      {R_SURFACE, "surface", r->surface != d.surface},
      {R_STRAIN, "strain", r->strain != d.strain},
  };
  for (size_t k = 0; k < sizeof fields / sizeof fields[0]; ++k)
    if (!(has & fields[k].bit) && fields[k].changed)
      return mpm_def_fail(w->c,
                          "%s.%s: not a field of a %s rule (it would have no effect); leave it at "
                          "its default or change %s.kind",
                          p, fields[k].key, kind, p);
  /* the rule's kind is the key it has: without its object the format could not tell it */
  if (r->kind == MPM_DEF_REFINE_COLLIDER && r->collider < 0 && !r->collider_name)
    return mpm_def_fail(w->c,
                        "%s.collider: a collider rule needs its collider; give an index into the "
                        "def's colliders or collider_name",
                        p);
  if (r->kind == MPM_DEF_REFINE_BODY && r->body < 0 && !r->body_name)
    return mpm_def_fail(w->c,
                        "%s.body: a body rule needs its body; give an index into the def's "
                        "bodies or body_name",
                        p);
  cJSON *o = mpm_def_append_object(w, arr);
  mpm_def_add_number(w, o, "level", r->level);
  switch (r->kind) {
  case MPM_DEF_REFINE_BOX: {
    cJSON *box = mpm_def_add_object(w, o, "box");
    mpm_def_add_vec3(w, box, "min", r->box.min);
    mpm_def_add_vec3(w, box, "max", r->box.max);
    break;
  }
  case MPM_DEF_REFINE_COLLIDER:
    add_reference(w, o, "collider", r->collider_name, r->collider);
    mpm_def_add_number(w, o, "distance", r->distance);
    break;
  case MPM_DEF_REFINE_BODY:
    add_reference(w, o, "body", r->body_name, r->body);
    if (r->distance != d.distance) mpm_def_add_number(w, o, "distance", r->distance);
    if (fields[0].changed) {
      cJSON *box = mpm_def_add_object(w, o, "within");
      mpm_def_add_vec3(w, box, "min", r->box.min);
      mpm_def_add_vec3(w, box, "max", r->box.max);
    }
    break;
  case MPM_DEF_REFINE_SURFACE:
    mpm_def_add_number(w, o, "surface", r->surface);
    if (r->body != d.body || r->body_name) add_reference(w, o, "body", r->body_name, r->body);
    break;
  case MPM_DEF_REFINE_TYPES:
    mpm_def_add_bool(w, o, "types", 1);
    mpm_def_add_number(w, o, "distance", r->distance);
    break;
  case MPM_DEF_REFINE_STRAIN:
    mpm_def_add_number(w, o, "strain", r->strain);
    mpm_def_add_number(w, o, "distance", r->distance);
    break;
  }
  return 0;
}

static int write_resample(mpm_def_writer *w, const mpm_resample_def *r, cJSON *dom) {
  if (mpm_def_check_array(w->c, "domain.resample.bodies", "body_count", r->bodies, r->body_count) <
      0)
    return -1;
  const mpm_resample_def d = mpm_scene_def_default().domain.resample;
  if (!r->enabled) {
    const char *changed = r->split != d.split                 ? "split"
                          : r->merge != d.merge               ? "merge"
                          : r->every != d.every               ? "every"
                          : r->merge_margin != d.merge_margin ? "merge_margin"
                          : r->max_per_cell != d.max_per_cell ? "max_per_cell"
                          : r->min_per_cell != d.min_per_cell ? "min_per_cell"
                          : r->body_count != 0                ? "bodies"
                          : r->seed != d.seed                 ? "seed"
                                                              : NULL;
    if (changed)
      return mpm_def_fail(w->c,
                          "domain.resample.%s: given with domain.resample.enabled 0 (it would "
                          "have no effect); set enabled or leave it at its default",
                          changed);
    return 0;
  }
  cJSON *o = mpm_def_add_object(w, dom, "resample");
  mpm_def_add_bool(w, o, "split", r->split);
  mpm_def_add_bool(w, o, "merge", r->merge);
  mpm_def_add_number(w, o, "every", r->every);
  mpm_def_add_number(w, o, "merge_margin", r->merge_margin);
  mpm_def_add_number(w, o, "max_per_cell", r->max_per_cell);
  mpm_def_add_number(w, o, "min_per_cell", r->min_per_cell);
  if (r->body_count > 0) mpm_def_add_indices(w, o, "bodies", r->bodies, r->body_count);
  mpm_def_add_number(w, o, "seed", (double)r->seed);
  return 0;
}

int mpm_def_write_domain(mpm_def_writer *w, const mpm_domain_def *d, cJSON *root) {
  const char *wall_rule =
      mpm_def_spell(w->c, "domain.walls.rule", (int)d->walls.rule, &mpm_def_rules);
  if (!wall_rule ||
      mpm_def_check_array(w->c, "domain.refine", "refine_count", d->refine, d->refine_count) < 0)
    return -1;
  const mpm_domain_def dd = mpm_scene_def_default().domain;
  if (d->resolution != dd.resolution && d->dx != dd.dx)
    return mpm_def_fail(w->c,
                        "domain.dx: given with domain.resolution %d (the format takes one of "
                        "them); leave dx at its default or set resolution to 0",
                        d->resolution);
  cJSON *dom = mpm_def_add_object(w, root, "domain");
  mpm_def_add_vec3(w, dom, "min", d->min);
  mpm_def_add_vec3(w, dom, "max", d->max);
  if (d->resolution != dd.resolution)
    mpm_def_add_number(w, dom, "resolution", d->resolution);
  else
    mpm_def_add_number(w, dom, "dx", d->dx);
  cJSON *walls = mpm_def_add_object(w, dom, "walls");
  mpm_def_add_string(w, walls, "rule", wall_rule);
  mpm_def_add_number(w, walls, "friction", d->walls.friction);
  mpm_def_add_number(w, walls, "cells", d->walls.cells);
  /* the grid's keys are written when given: without levels the format refuses them by name */
  if (d->levels != dd.levels) mpm_def_add_number(w, dom, "levels", d->levels);
  if (d->refine_count > 0) {
    cJSON *arr = mpm_def_add_array(w, dom, "refine");
    for (int i = 0; i < d->refine_count; ++i)
      if (write_rule(w, i, &d->refine[i], arr) < 0) return -1;
  }
  if (write_resample(w, &d->resample, dom) < 0) return -1;
  if (d->refine_every != dd.refine_every)
    mpm_def_add_number(w, dom, "refine_every", d->refine_every);
  return 0;
}

/* ---- solver --------------------------------------------------------------------------- */

int mpm_def_write_solver(mpm_def_writer *w, const mpm_solver_def *s, cJSON *root) {
  const struct {
    const char *path;
    int value;
    const mpm_def_enum *table;
  } enums[] = {
      {"solver.integrator", (int)s->integrator, &mpm_def_integrators},
      {"solver.kernel", (int)s->kernel, &mpm_def_kernels},
      {"solver.transfer", (int)s->transfer, &mpm_def_transfers},
      {"solver.grid", (int)s->grid, &mpm_def_grids},
      {"solver.on_instability", (int)s->on_instability, &mpm_def_instabilities},
      {"solver.domain_kernel", (int)s->domain_kernel, &mpm_def_kernels},
      {"solver.on_cg_failure", (int)s->on_cg_failure, &mpm_def_cg_failures},
      {"solver.preconditioner", (int)s->preconditioner, &mpm_def_preconditioners},
      {"solver.scheme", (int)s->scheme, &mpm_def_schemes},
  };
  const char *names[sizeof enums / sizeof enums[0]];
  for (size_t k = 0; k < sizeof enums / sizeof enums[0]; ++k)
    if (!(names[k] = mpm_def_spell(w->c, enums[k].path, enums[k].value, enums[k].table))) return -1;
  const int implicit = s->integrator == MPM_DEF_IMPLICIT;
  const mpm_solver_def d = mpm_scene_def_default().solver;
  const char *implicit_only = s->dt != d.dt                                 ? "dt"
                              : s->newton_iterations != d.newton_iterations ? "newton_iterations"
                              : s->cg_tolerance != d.cg_tolerance           ? "cg_tolerance"
                              : s->cg_max_iterations != d.cg_max_iterations ? "cg_max_iterations"
                              : s->on_cg_failure != d.on_cg_failure         ? "on_cg_failure"
                              : s->preconditioner != d.preconditioner       ? "preconditioner"
                              : s->scheme != d.scheme                       ? "scheme"
                                                                            : NULL;
  if (!implicit && implicit_only)
    return mpm_def_fail(w->c,
                        "solver.%s: a field of the implicit integrator only (it would have no "
                        "effect); set solver.integrator to MPM_DEF_IMPLICIT or leave it at its "
                        "default",
                        implicit_only);
  cJSON *o = mpm_def_add_object(w, root, "solver");
  mpm_def_add_string(w, o, "integrator", names[0]);
  mpm_def_add_string(w, o, "kernel", names[1]);
  mpm_def_add_string(w, o, "transfer", names[2]);
  mpm_def_add_number(w, o, "flip_alpha", s->flip_alpha);
  mpm_def_add_number(w, o, "cfl", s->cfl);
  mpm_def_add_number(w, o, "max_dt", s->max_dt);
  mpm_def_add_string(w, o, "grid", names[3]);
  mpm_def_add_number(w, o, "gimp_length", s->gimp_length);
  mpm_def_add_string(w, o, "on_instability", names[4]);
  mpm_def_add_number(w, o, "max_retries", s->max_retries);
  mpm_def_add_string(w, o, "domain_kernel", names[5]);
  if (implicit) {
    mpm_def_add_number(w, o, "dt", s->dt);
    mpm_def_add_number(w, o, "newton_iterations", s->newton_iterations);
    /* 0, automatic, is the key left out (the format takes a tolerance in (0, 1)) */
    if (s->cg_tolerance != d.cg_tolerance)
      mpm_def_add_number(w, o, "cg_tolerance", s->cg_tolerance);
    mpm_def_add_number(w, o, "cg_max_iterations", s->cg_max_iterations);
    mpm_def_add_string(w, o, "on_cg_failure", names[6]);
    mpm_def_add_string(w, o, "preconditioner", names[7]);
    mpm_def_add_string(w, o, "scheme", names[8]);
  }
  return 0;
}

/* ---- output --------------------------------------------------------------------------- */

static int write_surface(mpm_def_writer *w, const mpm_surface_def *s, cJSON *out) {
  if (mpm_def_check_array(w->c, "output.surface.bodies", "body_count", s->bodies, s->body_count) <
          0 ||
      mpm_def_check_array(w->c, "output.surface.materials", "material_count", s->materials,
                          s->material_count) < 0)
    return -1;
  const mpm_surface_def d = mpm_scene_def_default().output.surface;
  if (!s->enabled) {
    const char *changed = s->body_count != 0            ? "bodies"
                          : s->material_count != 0      ? "materials"
                          : s->voxel != d.voxel         ? "voxel"
                          : s->radius != d.radius       ? "radius"
                          : s->smoothing != d.smoothing ? "smoothing"
                          : s->filter != d.filter       ? "filter"
                          : s->per_body != d.per_body   ? "per_body"
                                                        : NULL;
    if (changed)
      return mpm_def_fail(w->c,
                          "output.surface.%s: given with output.surface.enabled 0 (it would have "
                          "no effect); set enabled or leave it at its default",
                          changed);
    return 0;
  }
  const char *filter =
      mpm_def_spell(w->c, "output.surface.filter", (int)s->filter, &mpm_def_filters);
  if (!filter) return -1;
  cJSON *o = mpm_def_add_object(w, out, "surface");
  if (s->body_count > 0) mpm_def_add_indices(w, o, "bodies", s->bodies, s->body_count);
  if (s->material_count > 0)
    mpm_def_add_indices(w, o, "materials", s->materials, s->material_count);
  mpm_def_add_number(w, o, "voxel", s->voxel);
  mpm_def_add_number(w, o, "radius", s->radius);
  mpm_def_add_number(w, o, "smoothing", s->smoothing);
  mpm_def_add_string(w, o, "filter", filter);
  mpm_def_add_bool(w, o, "per_body", s->per_body);
  return 0;
}

int mpm_def_write_output(mpm_def_writer *w, const mpm_output_def *o, cJSON *root) {
  if (o->fields >> MPM_FIELD_COUNT)
    return mpm_def_fail(w->c,
                        "output.fields: bits above (1u << MPM_DEF_FIELD_F) are no mpm_def_field, "
                        "got 0x%x",
                        o->fields);
  cJSON *out = mpm_def_add_object(w, root, "output");
  mpm_def_add_string(w, out, "directory", o->directory);
  mpm_def_add_bool(w, out, "vtu", o->vtu);
  mpm_def_add_bool(w, out, "ply", o->ply);
  mpm_def_add_bool(w, out, "stats", o->stats);
  mpm_def_add_number(w, out, "checkpoint_every", o->checkpoint_every);
  if (write_surface(w, &o->surface, out) < 0) return -1;
  /* without a surface the format refuses these by name (the .vdb holds its level set) */
  mpm_def_add_bool(w, out, "vdb", o->vdb);
  mpm_def_add_bool(w, out, "vdb_density", o->vdb_density);
  mpm_def_add_bool(w, out, "vdb_velocity", o->vdb_velocity);
  if (o->fields) { /* in the enum's order, which is the file's */
    cJSON *list = mpm_def_add_array(w, out, "fields");
    for (int f = 0; f < MPM_FIELD_COUNT; ++f)
      if (o->fields >> f & 1u) {
        cJSON *name = cJSON_CreateString(mpm_output_field_names[f]);
        if (!name || !cJSON_AddItemToArray(list, name)) {
          cJSON_Delete(name);
          w->nomem = 1;
        }
      }
  }
  return 0;
}

/* ---- heat and camera ------------------------------------------------------------------ */

int mpm_def_write_heat(mpm_def_writer *w, const mpm_heat_def *h, cJSON *root) {
  const mpm_heat_def d = mpm_scene_def_default().heat;
  if (!h->enabled && (h->temperature != d.temperature || h->pic != d.pic))
    return mpm_def_fail(w->c,
                        "heat.%s: given with heat.enabled 0 (it would have no effect); set "
                        "heat.enabled or leave it at its default",
                        h->temperature != d.temperature ? "temperature" : "pic");
  if (!h->enabled) return 0;
  cJSON *heat = mpm_def_add_object(w, root, "heat");
  mpm_def_add_number(w, heat, "temperature", h->temperature);
  mpm_def_add_number(w, heat, "pic", h->pic);
  return 0;
}

int mpm_def_write_camera(mpm_def_writer *w, const mpm_camera_def *cam, cJSON *root) {
  const mpm_camera_def d = mpm_scene_def_default().camera;
  if (!cam->enabled) {
    const char *changed = !mpm_def_vec3_equal(cam->eye, d.eye)         ? "eye"
                          : !mpm_def_vec3_equal(cam->target, d.target) ? "target"
                          : cam->fov != d.fov                          ? "fov"
                                                                       : NULL;
    if (changed)
      return mpm_def_fail(w->c,
                          "camera.%s: given with camera.enabled 0 (it would have no effect); set "
                          "camera.enabled or leave it at its default",
                          changed);
    return 0;
  }
  cJSON *o = mpm_def_add_object(w, root, "camera");
  mpm_def_add_vec3(w, o, "eye", cam->eye);
  mpm_def_add_vec3(w, o, "target", cam->target);
  mpm_def_add_number(w, o, "fov", cam->fov);
  return 0;
}
