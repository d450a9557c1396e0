/* scene_json_material.c - the materials of the JSON scene format: the 'materials' array,
 * each material object checked against the keys of its model, and a body's 'material' (a
 * name among materials[] or an inline material object, appended to the scene's materials).
 *
 * A key that only some models use is an error on any other model: the value would have no
 * effect while the user believes it acts. Part of the scene parser of scene_json.c (shared
 * declarations: scene_json_parts.h). */
#include "scene/json_check.h"
#include "core/alloc.h"
#include "scene/scene.h"
#include "scene/scene_json_parts.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

static const char *const MATERIAL_KEYS[] = {"name",
                                            "model",
                                            "E",
                                            "nu",
                                            "density",
                                            "min_stretch",
                                            "friction_angle",
                                            "cohesion",
                                            "yield_stress",
                                            "theta_c",
                                            "theta_s",
                                            "hardening",
                                            "strength",
                                            "specific_heat",
                                            "conductivity",
                                            "melting",
                                            NULL};

/* Model spellings, in the order of mpm_model_kind (scene.h). */
static const char *const MODEL_NAMES[] = {
    "fixed_corotated", "neo_hookean", "hencky_stvk", "drucker_prager", "von_mises", "snow", NULL};
_Static_assert(sizeof MODEL_NAMES / sizeof MODEL_NAMES[0] == MPM_MODEL_COUNT + 1,
               "MODEL_NAMES must name every mpm_model_kind, in order");

/* ---- materials ------------------------------------------------------------------------ */

#define MODEL_BIT(kind) (1u << (unsigned)(kind))

/* Material keys that only some models use, and which models (MODEL_BIT mask). Giving one to
 * another model is an error: the value would be ignored while the user believes it acts. */
typedef struct model_key {
  const char *key;
  unsigned models;
} model_key;

static const model_key MODEL_ONLY_KEYS[] = {
    {"min_stretch", MODEL_BIT(MPM_MODEL_NEO_HOOKEAN)},
    {"friction_angle", MODEL_BIT(MPM_MODEL_DRUCKER_PRAGER)},
    {"cohesion", MODEL_BIT(MPM_MODEL_DRUCKER_PRAGER)},
    {"yield_stress", MODEL_BIT(MPM_MODEL_VON_MISES)},
    {"theta_c", MODEL_BIT(MPM_MODEL_SNOW)},
    {"theta_s", MODEL_BIT(MPM_MODEL_SNOW)},
    {"hardening", MODEL_BIT(MPM_MODEL_SNOW)},
};

/* Every model-specific key of the material object at the current path must apply to `model`;
 * the first one (in file order) that does not is reported with the models it applies to. */
static int check_model_keys(mpm_json_ctx *c, const cJSON *node, int model) {
  const size_t count = sizeof MODEL_ONLY_KEYS / sizeof MODEL_ONLY_KEYS[0];
  for (const cJSON *ch = node->child; ch; ch = ch->next) {
    const model_key *mk = NULL;
    for (size_t k = 0; k < count && ch->string; ++k)
      if (strcmp(MODEL_ONLY_KEYS[k].key, ch->string) == 0) mk = &MODEL_ONLY_KEYS[k];
    if (!mk || (mk->models & MODEL_BIT(model))) continue;
    char list[200];
    size_t o = 0;
    int n = 0;
    list[0] = '\0';
    for (int i = 0; MODEL_NAMES[i]; ++i) {
      if (!(mk->models & MODEL_BIT(i))) continue;
      int w = snprintf(list + o, sizeof list - o, "%s%s", n ? ", " : "", MODEL_NAMES[i]);
      if (w < 0 || (size_t)w >= sizeof list - o) break;
      o += (size_t)w;
      ++n;
    }
    return mpm_json_fail_at(c, mk->key, MPM_ERR_INVALID,
                            "applies only to model%s %s, not to '%s' (it would have no effect); "
                            "remove it or change 'model'",
                            n > 1 ? "s" : "", list, MODEL_NAMES[model]);
  }
  return 0;
}

/* "strength": Zhu Fig. 5: a body's strength switched off and on. */
static int parse_strength(mpm_json_ctx *c, const cJSON *node, mpm_material_desc *m) {
  return mpm_sj_parse_schedule(c, node, "strength", m->strength, &m->strength_count);
}

/* One material object at the current path. */
static int parse_material(mpm_json_ctx *c, const cJSON *node, int name_required,
                          mpm_material_desc *m) {
  int model = (int)m->model;
  if (mpm_json_expect_object(c, node, "a material object") < 0 ||
      mpm_json_check_keys(c, node, MATERIAL_KEYS, NULL) < 0 ||
      mpm_json_string(c, node, "name", name_required, m->name, sizeof m->name) < 0 ||
      mpm_json_enum(c, node, "model", 1, MODEL_NAMES, &model) < 0 ||
      check_model_keys(c, node, model) < 0 ||
      mpm_json_number(c, node, "E", 1, mpm_json_gt(0, "Pa"), &m->E) < 0 ||
      mpm_json_number(c, node, "nu", 1, mpm_json_in('(', -1, 0.5, ')', NULL), &m->nu) < 0 ||
      mpm_json_number(c, node, "density", 1, mpm_json_gt(0, "kg/m^3"), &m->density) < 0 ||
      mpm_json_number(c, node, "min_stretch", 0, mpm_json_in('(', 0, 1, ']', NULL),
                      &m->min_stretch) < 0 ||
      mpm_json_number(c, node, "friction_angle", 0, mpm_json_in('[', 0, 90, ')', "degrees"),
                      &m->friction_angle) < 0 ||
      mpm_json_number(c, node, "cohesion", 0, mpm_json_ge(0, "Pa"), &m->cohesion) < 0 ||
      mpm_json_number(c, node, "theta_c", 0, mpm_json_in('(', 0, 1, ')', "critical compression"),
                      &m->theta_c) < 0 ||
      mpm_json_number(c, node, "theta_s", 0, mpm_json_gt(0, "critical stretch"), &m->theta_s) < 0 ||
      mpm_json_number(c, node, "hardening", 0, mpm_json_ge(0, "hardening coefficient"),
                      &m->hardening) < 0 ||
      parse_strength(c, node, m) < 0 || mpm_sj_parse_material_heat(c, node, model, m) < 0)
    return -1;
  const mpm_json_range yield = mpm_json_gt(0, "Pa");
  int has_yield = mpm_json_number(c, node, "yield_stress", 0, yield, &m->yield_stress);
  if (has_yield < 0) return -1;
  if (!has_yield && model == MPM_MODEL_VON_MISES) {
    char want[128];
    return mpm_json_fail_at(c, "yield_stress", MPM_ERR_INVALID,
                            "required for model 'von_mises'; expected %s",
                            mpm_json_describe_range(&yield, 0, want, sizeof want));
  }
  m->model = (mpm_model_kind)model;
  return 0;
}

int mpm_sj_parse_materials(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  if (mpm_sj_get_array(c, root, "materials", 1, "an array of material objects", &arr) < 0)
    return -1;
  const cJSON *bodies = mpm_json_get(root, "bodies");
  int n = cJSON_GetArraySize(arr);
  int extra = cJSON_IsArray(bodies) ? cJSON_GetArraySize(bodies) : 0; /* inline materials */
  s->materials = mpm_alloc((size_t)(n + extra + 1) * sizeof *s->materials);
  if (!s->materials) return mpm_sj_fail_nomem(c, "materials");
  size_t old = mpm_json_push_key(c, "materials");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_material_desc m = mpm_material_desc_default();
    if (parse_material(c, e, 1, &m) < 0) return -1;
    for (int j = 0; j < i; ++j)
      if (strcmp(s->materials[j].name, m.name) == 0)
        return mpm_json_fail_at(c, "name", MPM_ERR_INVALID,
                                "expected a unique material name, got '%s' (materials[%d] has "
                                "it too)",
                                m.name, j);
    s->materials[s->material_count++] = m;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

/* body.material: a name among materials[] (the first `named` entries) or an inline object. */
int mpm_sj_parse_body_material(mpm_json_ctx *c, const cJSON *body, int named, mpm_scene *s,
                               mpm_body_desc *b) {
  const cJSON *n = mpm_json_get(body, "material");
  if (!n) return mpm_json_missing(c, "material");
  size_t old = mpm_json_push_key(c, "material");
  if (cJSON_IsString(n) && n->valuestring) {
    for (int j = 0; j < named; ++j)
      if (strcmp(s->materials[j].name, n->valuestring) == 0) {
        b->material = j;
        mpm_json_pop(c, old);
        return 0;
      }
    if (named == 0)
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "no material named '%.64s'; the 'materials' array is empty (add the "
                           "material there, or give an inline material object here)",
                           n->valuestring);
    const char *names[65];
    char known[600];
    size_t o = 0;
    known[0] = '\0';
    int k = 0;
    for (int j = 0; j < named; ++j) {
      if (k < 64) names[k++] = s->materials[j].name;
      int w = snprintf(known + o, sizeof known - o, "%s%s", j ? ", " : "", s->materials[j].name);
      if (w < 0 || (size_t)w >= sizeof known - o) break;
      o += (size_t)w;
    }
    names[k] = NULL;
    const char *hint = mpm_json_suggest(n->valuestring, names);
    char suffix[100] = "";
    if (hint) snprintf(suffix, sizeof suffix, "; did you mean '%s'?", hint);
    return mpm_json_fail(c, MPM_ERR_INVALID, "no material named '%.64s'; known: %s%s",
                         n->valuestring, known, suffix);
  }
  if (!cJSON_IsObject(n)) {
    char got[96];
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected a material name (a string) or a material object, got %s",
                         mpm_json_describe(n, got, sizeof got));
  }
  mpm_material_desc m = mpm_material_desc_default();
  if (parse_material(c, n, 0, &m) < 0) return -1;
  if (!m.name[0]) snprintf(m.name, sizeof m.name, "%s", b->name);
  b->material = s->material_count;
  s->materials[s->material_count++] = m;
  mpm_json_pop(c, old);
  return 0;
}
