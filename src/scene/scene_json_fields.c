/* scene_json_fields.c - the scene key output.fields: which point arrays frame_NNNN.vtu holds.
 *
 *   "fields": ["velocity", "cauchy_stress", "pressure", "F", "plastic"]
 *
 * A non-empty list of names of mpm_output_field_names, each once, written in the file's own
 * order whatever the order of the list. Absent, the frames hold the arrays they held before the
 * key existed (mpm_output_fields_default), so that old scenes write the same bytes. Points,
 * TIME and the cells are always written: without them the file is not a particle frame. */
#include "scene/scene_json_parts.h"

#include <stdio.h>
#include <string.h>

const char *const mpm_output_field_names[MPM_FIELD_COUNT + 1] = {
    "id",      "velocity",      "mass",     "volume", "J",          "stress",
    "plastic", "material",      "body",     "level",  "enrichment", "temperature",
    "melt",    "cauchy_stress", "pressure", "F",      NULL};

/* "id, velocity, ..., F" for messages. */
static void field_list(char *out, size_t cap) {
  size_t len = 0;
  out[0] = 0;
  for (int f = 0; f < MPM_FIELD_COUNT && len + 1 < cap; ++f)
    len += (size_t)snprintf(out + len, cap - len, "%s%s", f ? ", " : "", mpm_output_field_names[f]);
}

static int field_of(const char *name) {
  for (int f = 0; f < MPM_FIELD_COUNT; ++f)
    if (!strcmp(mpm_output_field_names[f], name)) return f;
  return -1;
}

int mpm_sj_parse_fields(mpm_json_ctx *c, const cJSON *output, mpm_scene *s) {
  const cJSON *a = mpm_json_get(output, "fields");
  if (!a) return 0;
  size_t old = mpm_json_push_key(c, "fields");
  char list[300], got[96];
  field_list(list, sizeof list);
  if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) == 0)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected a non-empty array of field names (%s), got %s", list,
                         mpm_json_describe(a, got, sizeof got));
  unsigned bits = 0;
  int k = 0;
  for (const cJSON *e = a->child; e; e = e->next, ++k) {
    const size_t at = mpm_json_push_index(c, k);
    if (!cJSON_IsString(e) || !e->valuestring)
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected one of %s, got %s", list,
                           mpm_json_describe(e, got, sizeof got));
    const int f = field_of(e->valuestring);
    if (f < 0) {
      const char *hint = mpm_json_suggest(e->valuestring, mpm_output_field_names);
      char suffix[96] = "";
      if (hint) snprintf(suffix, sizeof suffix, "; did you mean '%s'?", hint);
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected one of %s, got '%.60s'%s", list,
                           e->valuestring, suffix);
    }
    if (bits & 1u << f)
      return mpm_json_fail(c, MPM_ERR_INVALID, "'%s' is listed twice", e->valuestring);
    bits |= 1u << f;
    mpm_json_pop(c, at);
  }
  s->output.fields = bits;
  mpm_json_pop(c, old);
  return 0;
}

/* temperature and melt exist only in a run with heat; runs after the heat object is read. */
int mpm_sj_check_fields_heat(mpm_json_ctx *c, const cJSON *root, const mpm_scene *s) {
  const unsigned heat_only = 1u << MPM_FIELD_TEMPERATURE | 1u << MPM_FIELD_MELT;
  if (s->heat.enabled || !(s->output.fields & heat_only)) return 0;
  const cJSON *a = mpm_json_get(mpm_json_get(root, "output"), "fields");
  int k = 0;
  for (const cJSON *e = a ? a->child : NULL; e; e = e->next, ++k)
    if (heat_only & 1u << field_of(e->valuestring)) {
      mpm_json_push_key(c, "output");
      mpm_json_push_key(c, "fields");
      mpm_json_push_index(c, k);
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "'%s' needs heat: the scene has no `heat` object (docs/scene-format.md "
                           "\"heat\")",
                           e->valuestring);
    }
  return 0;
}
