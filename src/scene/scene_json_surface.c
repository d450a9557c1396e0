/* scene_json_surface.c - the scene key output.surface: which particles make a surface per frame
 * and how (src/surface/surface.h).
 *
 *   "surface": true
 *   "surface": {"bodies": ["sand", 2] | "all", "materials": ["goo"], "voxel": 0,
 *               "radius": 0.4, "smoothing": 1, "filter": "gaussian", "per_body": false}
 *
 * Bodies and materials are named by name or index; voxel and radius are in grid cells. */
#include "scene/scene_json_parts.h"

#include <stdio.h>
#include <string.h>

static const char *const SURFACE_KEYS[] = {"bodies",    "materials", "voxel",    "radius",
                                           "smoothing", "filter",    "per_body", NULL};
static const char *const FILTER_NAMES[] = {"mean_curvature", "gaussian", "laplacian", NULL};

/* A body or a material named by its name or its index. */
static int reference(mpm_json_ctx *c, const cJSON *e, int index, int count, const char *kind,
                     int is_body, const mpm_scene *s, int *out) {
  size_t old = mpm_json_push_index(c, index);
  char got[96];
  if (cJSON_IsNumber(e)) {
    const double v = e->valuedouble;
    if (v != (double)(int)v || v < 0 || v >= count)
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected the index of one of the %d %s, got %s",
                           count, kind, mpm_json_describe(e, got, sizeof got));
    *out = (int)v;
  } else if (cJSON_IsString(e)) {
    int found = -1;
    for (int k = 0; k < count && found < 0; ++k)
      if (!strcmp(is_body ? s->bodies[k].name : s->materials[k].name, e->valuestring)) found = k;
    if (found < 0) {
      char names[400] = "";
      size_t len = 0;
      for (int k = 0; k < count && len + 4 < sizeof names; ++k)
        len += (size_t)snprintf(names + len, sizeof names - len, "%s'%s'", k ? ", " : "",
                                is_body ? s->bodies[k].name : s->materials[k].name);
      return mpm_json_fail(c, MPM_ERR_INVALID, "no %s is called '%s' (the scene has %s)",
                           is_body ? "body" : "material", e->valuestring, count ? names : "none");
    }
    *out = found;
  } else {
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected a %s name or index, got %s",
                         is_body ? "body" : "material", mpm_json_describe(e, got, sizeof got));
  }
  mpm_json_pop(c, old);
  return 0;
}

/* obj[key]: an array of names or indices (or, for bodies, the string "all"). */
static int selection(mpm_json_ctx *c, const cJSON *obj, const char *key, int is_body,
                     const mpm_scene *s, int *list, int *n) {
  const cJSON *a = mpm_json_get(obj, key);
  if (!a) return 0;
  const int count = is_body ? s->body_count : s->material_count;
  size_t old = mpm_json_push_key(c, key);
  char got[96];
  if (is_body && cJSON_IsString(a) && !strcmp(a->valuestring, "all")) {
    *n = 0;
    mpm_json_pop(c, old);
    return 0;
  }
  if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) == 0)
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected %s, got %s",
                         is_body ? "\"all\" or a non-empty array of body names or indices"
                                 : "a non-empty array of material names or indices",
                         mpm_json_describe(a, got, sizeof got));
  if (cJSON_GetArraySize(a) > MPM_SURFACE_SELECT_MAX)
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected at most %d entries, got %d",
                         MPM_SURFACE_SELECT_MAX, cJSON_GetArraySize(a));
  int k = 0;
  for (const cJSON *e = a->child; e; e = e->next, ++k) {
    if (reference(c, e, k, count, is_body ? "bodies" : "materials", is_body, s, &list[k]) < 0)
      return -1;
    for (int j = 0; j < k; ++j)
      if (list[j] == list[k]) {
        size_t at = mpm_json_push_index(c, k);
        (void)at;
        return mpm_json_fail(c, MPM_ERR_INVALID, "expected each %s once; it is also entry %d",
                             is_body ? "body" : "material", j);
      }
  }
  *n = k;
  mpm_json_pop(c, old);
  return 0;
}

int mpm_sj_parse_surface(mpm_json_ctx *c, const cJSON *output, mpm_scene *s) {
  const cJSON *o = mpm_json_get(output, "surface");
  if (!o) return 0;
  mpm_surface_desc *d = &s->output.surface;
  if (cJSON_IsBool(o)) {
    d->enabled = cJSON_IsTrue(o);
    return 0;
  }
  size_t old = mpm_json_push_key(c, "surface");
  long long smoothing = d->smoothing;
  int filter = (int)d->filter;
  if (mpm_json_expect_object(c, o,
                             "true, false or an object with keys bodies, materials, voxel, "
                             "radius, smoothing, filter, per_body") < 0 ||
      mpm_json_check_keys(c, o, SURFACE_KEYS, NULL) < 0 ||
      selection(c, o, "bodies", 1, s, d->bodies, &d->body_count) < 0 ||
      selection(c, o, "materials", 0, s, d->materials, &d->material_count) < 0 ||
      mpm_json_number(c, o, "voxel", 0,
                      mpm_json_in('[', 0, 4, ']', "cells, 0 = the particle spacing"),
                      &d->voxel) < 0 ||
      mpm_json_number(c, o, "radius", 0,
                      mpm_json_in('[', 0, 8, ']', "cells, 0 = from each particle's volume"),
                      &d->radius) < 0 ||
      mpm_json_integer(c, o, "smoothing", 0, mpm_json_in('[', 0, 20, ']', "filter passes"),
                       &smoothing) < 0 ||
      mpm_json_enum(c, o, "filter", 0, FILTER_NAMES, &filter) < 0 ||
      mpm_json_bool(c, o, "per_body", 0, &d->per_body) < 0)
    return -1;
  if (d->body_count && d->material_count)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected 'bodies' or 'materials', not both (a surface is made of the "
                         "particles of some bodies or of some materials)");
  if (d->per_body && d->material_count)
    return mpm_json_fail_at(c, "per_body", MPM_ERR_INVALID,
                            "expected false with 'materials' (per_body splits by body)");
  if (d->voxel > 0 && d->voxel < 0.05)
    return mpm_json_fail_at(c, "voxel", MPM_ERR_INVALID,
                            "expected 0 (the particle spacing) or at least 0.05 cells, got %g",
                            d->voxel);
  d->smoothing = (int)smoothing;
  d->filter = (mpm_surface_filter)filter;
  d->enabled = 1;
  mpm_json_pop(c, old);
  return 0;
}
