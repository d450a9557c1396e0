/* scene_json_heat.c - the heat keys of the JSON scene format (heat/heat.h):
 *   heat                  {"temperature": T0, "pic": f}: heat transfer on; T0 the initial
 *                         temperature of bodies without their own (default 0), f the PIC
 *                         fraction of the particles' temperature update (default 0: FLIP)
 *   materials[i]          specific_heat (J/(kg K)), conductivity (W/(m K)), melting {point,
 *                         range, shear, bulk}
 *   bodies[i].temperature its particles' initial temperature
 *   colliders[i].temperature  a heat source: the grid nodes inside its solid are held at it
 * Temperatures are in any one unit the scene keeps to (K or degrees C). A heat key in a scene
 * without `heat` is an error (it would do nothing), and so is melting on a model whose return
 * map would not see the softened moduli. Part of the scene parser of scene_json.c. */
#include "scene/json_check.h"
#include "scene/scene.h"
#include "scene/scene_json_parts.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <string.h>

static const char *const HEAT_KEYS[] = {"temperature", "pic", NULL};
static const char *const MELTING_KEYS[] = {"point", "range", "shear", "bulk", NULL};

int mpm_sj_parse_temperature(mpm_json_ctx *c, const cJSON *node, int *has, double *temperature) {
  const int got =
      mpm_json_number(c, node, "temperature", 0, mpm_json_any("the scene's unit"), temperature);
  if (got < 0) return -1;
  *has = got;
  return 0;
}

int mpm_sj_parse_material_heat(mpm_json_ctx *c, const cJSON *node, int model,
                               mpm_material_desc *m) {
  const int a =
      mpm_json_number(c, node, "specific_heat", 0, mpm_json_gt(0, "J/(kg K)"), &m->specific_heat);
  const int b = a < 0 ? -1
                      : mpm_json_number(c, node, "conductivity", 0, mpm_json_ge(0, "W/(m K)"),
                                        &m->conductivity);
  if (a < 0 || b < 0) return -1;
  m->heat_keys = a || b;
  const cJSON *melt = mpm_json_get(node, "melting");
  if (!melt) return 0;
  size_t old = mpm_json_push_key(c, "melting");
  if (mpm_json_expect_object(c, melt, "a melting object ({\"point\": T, ...})") < 0 ||
      mpm_json_check_keys(c, melt, MELTING_KEYS, NULL) < 0 ||
      mpm_json_number(c, melt, "point", 1, mpm_json_any("the melting temperature"),
                      &m->melt_point) < 0 ||
      mpm_json_number(c, melt, "range", 0, mpm_json_ge(0, "degrees over which the moduli fall"),
                      &m->melt_range) < 0 ||
      mpm_json_number(c, melt, "shear", 0,
                      mpm_json_in('[', 0, 1, ']', "the melted shear modulus over the solid's"),
                      &m->melt_shear) < 0 ||
      mpm_json_number(c, melt, "bulk", 0,
                      mpm_json_in('(', 0, 1, ']', "the melted lambda over the solid's"),
                      &m->melt_bulk) < 0)
    return -1;
  mpm_json_pop(c, old);
  if (model != MPM_MODEL_FIXED_COROTATED && model != MPM_MODEL_NEO_HOOKEAN &&
      model != MPM_MODEL_HENCKY_STVK)
    return mpm_json_fail_at(c, "melting", MPM_ERR_INVALID,
                            "applies only to the elastic models fixed_corotated, neo_hookean and "
                            "hencky_stvk (a plastic model's return map would not see the "
                            "softened moduli)");
  m->melting = 1;
  m->heat_keys = 1;
  return 0;
}

/* The first heat key of a scene without `heat`, as a key path; NULL when there is none. */
static const char *stray_heat_key(const mpm_scene *s, char *buf, size_t cap) {
  for (int i = 0; i < s->material_count; ++i)
    if (s->materials[i].heat_keys) {
      snprintf(buf, cap, "material '%s' (specific_heat, conductivity or melting)",
               s->materials[i].name);
      return buf;
    }
  for (int i = 0; i < s->body_count; ++i)
    if (s->bodies[i].has_temperature) {
      snprintf(buf, cap, "bodies[%d].temperature", i);
      return buf;
    }
  for (int i = 0; i < s->collider_count; ++i)
    if (s->colliders[i].heat_source) {
      snprintf(buf, cap, "colliders[%d].temperature", i);
      return buf;
    }
  return NULL;
}

int mpm_sj_parse_heat(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *heat = mpm_json_get(root, "heat");
  if (!heat) {
    char buf[160];
    const char *stray = stray_heat_key(s, buf, sizeof buf);
    if (stray)
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "%s is a heat key, but the scene has no \"heat\" object: add \"heat\": "
                           "{\"temperature\": T0} to turn heat transfer on, or remove the key",
                           stray);
    return 0;
  }
  size_t old = mpm_json_push_key(c, "heat");
  if (mpm_json_expect_object(c, heat, "a heat object ({\"temperature\": T0})") < 0 ||
      mpm_json_check_keys(c, heat, HEAT_KEYS, NULL) < 0 ||
      mpm_json_number(c, heat, "temperature", 0, mpm_json_any("the scene's unit"),
                      &s->heat.temperature) < 0 ||
      mpm_json_number(c, heat, "pic", 0,
                      mpm_json_in('[', 0, 100, ']',
                                  "the rate of the PIC share of the temperature update, in units "
                                  "of 4 alpha / dx^2"),
                      &s->heat.pic) < 0)
    return -1;
  if (s->levels > 0)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "heat transfer runs on the uniform grid; this scene has domain.levels "
                         "%d (remove one or the other)",
                         s->levels);
  mpm_json_pop(c, old);
  s->heat.enabled = 1;
  for (int i = 0; i < s->body_count; ++i)
    if (!s->bodies[i].has_temperature) s->bodies[i].temperature = s->heat.temperature;
  return 0;
}
