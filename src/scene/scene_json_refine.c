/* scene_json_refine.c - the multi-level grid's keys (Gao et al. 2017 sec. 5-7.1;
 * docs/adaptive-grid.md):
 *
 *   "domain": { ..., "levels": 3,
 *               "refine": [ {"level": 2, "box": {"min": [..], "max": [..]}},
 *                           {"level": 2, "collider": "blade", "distance": 0.05},
 *                           {"level": 1, "body": "jello"},
 *                           {"level": 2, "body": "jello", "distance": 0.02} ] }
 *
 * dx is the spacing of level 0, the coarsest; level L has dx / 2^L. A rule refines the cells it
 * selects until their leaves are of its level. A body rule with a distance refines only the
 * cells of the body's material within that distance of its surface (Gao sec. 7.1: fine near the
 * surface, coarse inside). The grid's transfers are uGIMP's (the basis the
 * levels share is the trilinear hat, Gao sec. 4), on the sparse grid, with the explicit
 * integrator, and bodies without particle domains: what is not built on the multi-level grid is
 * refused here, naming the key. */
#include "scene/scene_json_parts.h"
#include "core/alloc.h"

#include <stdlib.h>
#include <string.h>

static const char *const REFINE_KEYS[] = {"level",   "box",   "collider", "distance", "body",
                                          "surface", "types", "strain",   "within",   NULL};
static const char *const BOX_KEYS[] = {"min", "max", NULL};

/* obj[key] as an index of one of `count` named things (an integer, or one of their names). 1,
 * or -1 with the message written. */
static int parse_reference(mpm_json_ctx *c, const cJSON *obj, const char *key, const char *what,
                           int count, const char *(*name_of)(const mpm_scene *, int),
                           const mpm_scene *s, int *out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (count == 0) return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "the scene has no %s", what);
  if (cJSON_IsString(n)) {
    for (int k = 0; k < count; ++k)
      if (!strcmp(name_of(s, k), n->valuestring)) {
        *out = k;
        return 1;
      }
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID,
                            "expected the name of one of the scene's %d %s, got '%s'", count, what,
                            n->valuestring);
  }
  long long k = 0;
  if (count == 0) return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "the scene has no %s", what);
  if (mpm_json_integer(c, obj, key, 1, mpm_json_in('[', 0, count - 1, ']', what), &k) < 0)
    return -1;
  *out = (int)k;
  return 1;
}

static const char *collider_name(const mpm_scene *s, int k) {
  return s->colliders[k].name;
}
static const char *body_name(const mpm_scene *s, int k) {
  return s->bodies[k].name;
}

/* e[key], {"min": [..], "max": [..]} with max > min, into r->min and r->max. 1, or -1 with the
 * message written. */
static int parse_box(mpm_json_ctx *c, const cJSON *e, const char *key, mpm_refine_desc *r) {
  const cJSON *b = mpm_json_get(e, key);
  size_t o = mpm_json_push_key(c, key);
  if (mpm_json_expect_object(c, b, "an object with keys min and max") < 0 ||
      mpm_json_check_keys(c, b, BOX_KEYS, NULL) < 0 ||
      mpm_json_vec3(c, b, "min", 1, mpm_json_any("m"), r->min) < 0 ||
      mpm_json_vec3(c, b, "max", 1, mpm_json_any("m"), r->max) < 0)
    return -1;
  for (int d = 0; d < 3; ++d)
    if (!(r->max[d] > r->min[d]))
      return mpm_json_fail_at(c, "max", MPM_ERR_INVALID,
                              "expected max greater than min on every axis, got %g <= %g along "
                              "%c",
                              r->max[d], r->min[d], mpm_sj_axis_name[d]);
  mpm_json_pop(c, o);
  return 1;
}

static int parse_rule(mpm_json_ctx *c, const cJSON *e, mpm_scene *s, mpm_refine_desc *r) {
  memset(r, 0, sizeof *r);
  if (mpm_json_expect_object(c, e,
                             "a refinement rule: {\"level\": L, and one of \"box\", "
                             "\"collider\" (with \"distance\"), \"body\", \"surface\", "
                             "\"types\" or \"strain\"}") < 0 ||
      mpm_json_check_keys(c, e, REFINE_KEYS, NULL) < 0)
    return -1;
  long long level = 0;
  if (mpm_json_integer(c, e, "level", 1,
                       mpm_json_in('[', 1, s->levels - 1, ']',
                                   "a level finer than 0, below "
                                   "domain.levels"),
                       &level) < 0)
    return -1;
  r->level = (int)level;
  const int on_particles =
      !!mpm_json_get(e, "surface") + !!mpm_json_get(e, "types") + !!mpm_json_get(e, "strain");
  /* a surface rule may name its body */
  const int kinds = !!mpm_json_get(e, "box") + !!mpm_json_get(e, "collider") + on_particles +
                    (!!mpm_json_get(e, "body") && !mpm_json_get(e, "surface"));
  if (kinds != 1)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected exactly one of 'box', 'collider', 'body', 'surface', 'types' "
                         "or 'strain', got %d",
                         kinds);
  if (mpm_json_get(e, "distance") && (mpm_json_get(e, "box") || mpm_json_get(e, "surface")))
    return mpm_json_fail_at(c, "distance", MPM_ERR_INVALID,
                            "a key of collider, body, types and strain rules only; a surface "
                            "rule's distance is its value");
  r->body = -1;
  if (mpm_json_get(e, "surface")) {
    r->kind = MPM_REFINE_SURFACE;
    if (mpm_json_number(c, e, "surface", 1,
                        mpm_json_gt(0, "m: the band on both sides of the material's surface"),
                        &r->distance) < 0 ||
        (mpm_json_get(e, "body") &&
         parse_reference(c, e, "body", "bodies", s->body_count, body_name, s, &r->body) < 0))
      return -1;
  } else if (mpm_json_get(e, "types")) {
    r->kind = MPM_REFINE_TYPES;
    int on = 0;
    if (mpm_json_bool(c, e, "types", 1, &on) < 0) return -1;
    if (!on)
      return mpm_json_fail_at(c, "types", MPM_ERR_INVALID,
                              "expected true (the grid follows the particle types); remove the "
                              "rule to turn it off");
    if (mpm_json_number(c, e, "distance", 0,
                        mpm_json_ge(0, "m around the particles: room to move between rebuilds"),
                        &r->distance) < 0)
      return -1;
  } else if (mpm_json_get(e, "strain")) {
    r->kind = MPM_REFINE_STRAIN;
    if (mpm_json_number(c, e, "strain", 1, mpm_json_gt(0, "||F - I||, Frobenius norm"),
                        &r->strain) < 0 ||
        mpm_json_number(c, e, "distance", 0, mpm_json_ge(0, "m around the strained particles"),
                        &r->distance) < 0)
      return -1;
  } else if (mpm_json_get(e, "box")) {
    r->kind = MPM_REFINE_BOX;
    if (parse_box(c, e, "box", r) < 0) return -1;
  } else if (mpm_json_get(e, "collider")) {
    r->kind = MPM_REFINE_COLLIDER;
    if (parse_reference(c, e, "collider", "colliders", s->collider_count, collider_name, s,
                        &r->collider) < 0 ||
        mpm_json_number(c, e, "distance", 1, mpm_json_ge(0, "m from the collider's surface"),
                        &r->distance) < 0)
      return -1;
  } else {
    r->kind = MPM_REFINE_BODY;
    if (parse_reference(c, e, "body", "bodies", s->body_count, body_name, s, &r->body) < 0 ||
        mpm_json_number(c, e, "distance", 0,
                        mpm_json_gt(0, "m: only cells within it of the body's surface"),
                        &r->distance) < 0)
      return -1;
    /* Gao sec. 9: refining the whole free surface is what kept their speed-up modest; a body
       rule may refine only where contact will be */
    if (mpm_json_get(e, "within")) {
      if (parse_box(c, e, "within", r) < 0) return -1;
      r->within = 1;
    }
  }
  if (r->kind != MPM_REFINE_BODY && mpm_json_get(e, "within"))
    return mpm_json_fail_at(c, "within", MPM_ERR_INVALID,
                            "a key of body rules only (the part of the body's cells refined); "
                            "a box rule's cells are its 'box'");
  return 0;
}

static const char *const RESAMPLE_KEYS[] = {"split",        "merge",        "every",
                                            "merge_margin", "max_per_cell", "min_per_cell",
                                            "bodies",       "seed",         NULL};

/* domain.resample (Gao sec. 7.2): {"split": true, "merge": true, "every": 1, "merge_margin": 1,
 * "max_per_cell": 0, "min_per_cell": 0, "bodies": ["sand"], "seed": 0}, every key optional. */
static int parse_resample(mpm_json_ctx *c, const cJSON *dom, mpm_scene *s) {
  const cJSON *r = mpm_json_get(dom, "resample");
  if (!r) return 0;
  size_t o = mpm_json_push_key(c, "resample");
  mpm_resample_desc *d = &s->resample;
  if (s->levels < 2)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "particle resampling needs a multi-level grid: set domain.levels (2 or "
                         "more)");
  if (mpm_json_expect_object(c, r,
                             "an object: {\"split\": true, \"merge\": true, \"every\": 1, "
                             "...}") < 0 ||
      mpm_json_check_keys(c, r, RESAMPLE_KEYS, NULL) < 0)
    return -1;
  *d = mpm_resample_desc_default();
  d->enabled = 1;
  long long every = d->every, maxc = d->max_per_cell, minc = d->min_per_cell, seed = d->seed;
  if (mpm_json_bool(c, r, "split", 0, &d->split) < 0 ||
      mpm_json_bool(c, r, "merge", 0, &d->merge) < 0 ||
      mpm_json_integer(c, r, "every", 0, mpm_json_in('[', 1, 1e6, ']', "steps"), &every) < 0 ||
      mpm_json_number(c, r, "merge_margin", 0,
                      mpm_json_in('[', 0, 8, ']', "cells of the merged particles' level"),
                      &d->merge_margin) < 0 ||
      mpm_json_integer(c, r, "max_per_cell", 0,
                       mpm_json_in('[', 0, 1e6, ']', "particles; 0: 2 x particles_per_cell"),
                       &maxc) < 0 ||
      mpm_json_integer(c, r, "min_per_cell", 0,
                       mpm_json_in('[', 0, 1e6, ']', "particles; 0: 4 x particles_per_cell"),
                       &minc) < 0 ||
      mpm_json_integer(c, r, "seed", 0, mpm_json_in('[', 0, 4294967295.0, ']', "a seed"), &seed) <
          0)
    return -1;
  d->every = (int)every;
  d->max_per_cell = (int)maxc;
  d->min_per_cell = (int)minc;
  d->seed = (unsigned)seed;
  const cJSON *bodies = NULL;
  const int has = mpm_sj_get_array(c, r, "bodies", 0, "an array of body names or indices", &bodies);
  if (has < 0) return -1;
  for (int b = 0; b < s->body_count; ++b) s->bodies[b].resample = !has;
  if (has) {
    size_t ob = mpm_json_push_key(c, "bodies");
    int i = 0;
    for (const cJSON *e = bodies->child; e; e = e->next, ++i) {
      size_t oi = mpm_json_push_index(c, i);
      int b = -1;
      if (cJSON_IsString(e)) {
        for (int k = 0; k < s->body_count; ++k)
          if (!strcmp(s->bodies[k].name, e->valuestring)) b = k;
      } else if (cJSON_IsNumber(e) && e->valuedouble == (double)(int)e->valuedouble &&
                 e->valuedouble >= 0 && e->valuedouble < s->body_count) {
        b = (int)e->valuedouble;
      }
      if (b < 0) {
        char got[64];
        return mpm_json_fail(c, MPM_ERR_INVALID,
                             "expected the name or index of one of the scene's %d bodies, got %s",
                             s->body_count, mpm_json_describe(e, got, sizeof got));
      }
      s->bodies[b].resample = 1;
      mpm_json_pop(c, oi);
    }
    mpm_json_pop(c, ob);
  }
  mpm_json_pop(c, o);
  return 0;
}

int mpm_sj_parse_refinement(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *dom = mpm_json_get(root, "domain");
  size_t old = mpm_json_push_key(c, "domain");
  long long levels = 0;
  const int has = mpm_json_integer(
      c, dom, "levels", 0,
      mpm_json_in('[', 1, MPM_SCENE_LEVELS_MAX, ']', "grid levels, dx_L = dx / 2^L"), &levels);
  if (has < 0) return -1;
  const cJSON *arr = NULL;
  const int has_refine =
      mpm_sj_get_array(c, dom, "refine", 0, "an array of refinement rules", &arr);
  if (has_refine < 0) return -1;
  if (has_refine && !has)
    return mpm_json_fail_at(c, "refine", MPM_ERR_INVALID,
                            "refinement needs a multi-level grid: set domain.levels (2 or more)");
  s->levels = (int)levels;
  if (has_refine && cJSON_GetArraySize(arr) > 0) {
    const int n = cJSON_GetArraySize(arr);
    s->refine = mpm_calloc((size_t)n, sizeof *s->refine);
    if (!s->refine) return mpm_sj_fail_nomem(c, "refinement rules");
    size_t o = mpm_json_push_key(c, "refine");
    int i = 0;
    for (const cJSON *e = arr->child; e; e = e->next, ++i) {
      size_t o2 = mpm_json_push_index(c, i);
      if (s->levels < 2)
        return mpm_json_fail(c, MPM_ERR_INVALID,
                             "a refinement rule needs domain.levels of 2 or more, got %d",
                             s->levels);
      if (parse_rule(c, e, s, &s->refine[i]) < 0) return -1;
      s->refine_count = i + 1;
      mpm_json_pop(c, o2);
    }
    mpm_json_pop(c, o);
  }
  if (parse_resample(c, dom, s) < 0) return -1;
  long long every = 0;
  const int has_every = mpm_json_integer(c, dom, "refine_every", 0,
                                         mpm_json_in('[', 0, 1e6, ']', "steps; 0: static"), &every);
  if (has_every < 0) return -1;
  if (has_every && !has)
    return mpm_json_fail_at(c, "refine_every", MPM_ERR_INVALID,
                            "refinement needs a multi-level grid: set domain.levels (2 or more)");
  s->refine_every = (int)every;
  for (int k = 0; k < s->refine_count; ++k)
    if (s->refine[k].kind >= MPM_REFINE_SURFACE && !s->refine_every) {
      size_t o = mpm_json_push_key(c, "refine");
      mpm_json_push_index(c, k);
      const char *kind = s->refine[k].kind == MPM_REFINE_SURFACE ? "surface"
                         : s->refine[k].kind == MPM_REFINE_TYPES ? "types"
                                                                 : "strain";
      mpm_json_fail_at(c, kind, MPM_ERR_INVALID,
                       "a rule on the moving material: set domain.refine_every (steps between "
                       "rebuilds of the grid)");
      (void)o;
      return -1;
    }
  mpm_json_pop(c, old);
  if (!s->levels) return 0;

  /* what the multi-level grid asks of the rest of the scene */
  const cJSON *sv = mpm_json_get(root, "solver");
  size_t o = mpm_json_push_key(c, "solver");
  if (!mpm_json_get(sv, "kernel"))
    s->solver.kernel = MPM_KERNEL_UGIMP; /* Gao's transfers, the default on levels */
  else if (s->solver.kernel != MPM_KERNEL_UGIMP)
    return mpm_json_fail_at(c, "kernel", MPM_ERR_INVALID,
                            "expected \"ugimp\" with domain.levels: the levels share the "
                            "trilinear basis whose box average uGIMP is (Gao et al. sec. 4)");
  if (s->solver.grid != MPM_GRID_SPARSE)
    return mpm_json_fail_at(c, "grid", MPM_ERR_INVALID,
                            "expected \"sparse\" with domain.levels: the levels are sparse grids");
  if (s->solver.gimp_length > 0)
    return mpm_json_fail_at(c, "gimp_length", MPM_ERR_INVALID,
                            "not with domain.levels: a particle's box is the spacing of its "
                            "level (its particle type, Gao et al. sec. 7.1)");
  mpm_json_pop(c, o);
  for (int b = 0; b < s->body_count; ++b)
    if (s->bodies[b].domains) {
      mpm_json_push_key(c, "bodies");
      mpm_json_push_index(c, b);
      return mpm_json_fail_at(c, "domains", MPM_ERR_INVALID,
                              "not with domain.levels: particle domains on the multi-level grid "
                              "are not built yet");
    }
  return 0;
}
