/* scene_def_write.c - the scene def written as JSON, part one (scene_def_parts.h): the message
 * and JSON helpers, then the objects: shapes, motions (constant or keyframed) and `active`
 * windows, materials, bodies, colliders and body-force regions.
 *
 * A field that the JSON leaves out for its object's model, shape type or switch, yet was changed
 * from its default, is refused naming it: the format refuses such keys because they would have
 * no effect, and dropping them silently would hide the same mistake. */
#include "scene/json_check.h"
#include "scene/scene.h"
#include "scene/scene_def_parts.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- messages ------------------------------------------------------------------------- */

int mpm_def_fail(mpm_def_ctx *c, const char *fmt, ...) {
  c->status = MPM_ERR_INVALID;
  if (c->err && c->errlen) {
    int n = snprintf(c->err, c->errlen, "<def>: ");
    if (n >= 0 && (size_t)n < c->errlen) {
      va_list ap;
      va_start(ap, fmt);
      vsnprintf(c->err + n, c->errlen - (size_t)n, fmt, ap);
      va_end(ap);
    }
  }
  return -1;
}

static const char *const RULE_NAMES[] = {"sticky", "slip", "separate"};
static const char *const KERNEL_NAMES[] = {"linear", "quadratic", "cubic", "ugimp"};
static const char *const INTEGRATOR_NAMES[] = {"explicit", "implicit"};
static const char *const TRANSFER_NAMES[] = {"apic", "flip"};
static const char *const GRID_NAMES[] = {"sparse", "dense"};
static const char *const INSTABILITY_NAMES[] = {"stop", "retry"};
static const char *const CG_FAILURE_NAMES[] = {"warn", "stop"};
static const char *const PRECONDITIONER_NAMES[] = {"jacobi", "multigrid"};
static const char *const SCHEME_NAMES[] = {"backward_euler", "newmark"};
static const char *const FILTER_NAMES[] = {"mean_curvature", "gaussian", "laplacian"};
static const char *const REFINE_NAMES[] = {"box", "collider", "body", "surface", "types", "strain"};
static const char *const MODEL_NAMES[] = {"fixed_corotated", "neo_hookean", "hencky_stvk",
                                          "drucker_prager",  "von_mises",   "snow"};
static const char *const SHAPE_NAMES[] = {"box",  "sphere",    "cylinder",
                                          "mesh", "halfspace", "revolve"};
static const char *const METRIC_NAMES[] = {"condition", "frobenius"};
static const char *const HOURGLASS_NAMES[] = {"enriched", "all"};
#define TABLE(type, names)                                                                         \
  { type, names, (int)(sizeof names / sizeof names[0]) }
const mpm_def_enum mpm_def_rules = TABLE("mpm_def_rule", RULE_NAMES);
const mpm_def_enum mpm_def_kernels = TABLE("mpm_def_kernel", KERNEL_NAMES);
const mpm_def_enum mpm_def_integrators = TABLE("mpm_def_integrator", INTEGRATOR_NAMES);
const mpm_def_enum mpm_def_transfers = TABLE("mpm_def_transfer", TRANSFER_NAMES);
const mpm_def_enum mpm_def_grids = TABLE("mpm_def_grid", GRID_NAMES);
const mpm_def_enum mpm_def_instabilities = TABLE("mpm_def_instability", INSTABILITY_NAMES);
const mpm_def_enum mpm_def_cg_failures = TABLE("mpm_def_cg_failure", CG_FAILURE_NAMES);
const mpm_def_enum mpm_def_preconditioners = TABLE("mpm_def_preconditioner", PRECONDITIONER_NAMES);
const mpm_def_enum mpm_def_schemes = TABLE("mpm_def_scheme", SCHEME_NAMES);
const mpm_def_enum mpm_def_filters = TABLE("mpm_def_surface_filter", FILTER_NAMES);
const mpm_def_enum mpm_def_refine_kinds = TABLE("mpm_def_refine_kind", REFINE_NAMES);
static const mpm_def_enum MODELS = TABLE("mpm_def_model", MODEL_NAMES);
static const mpm_def_enum SHAPES = TABLE("mpm_def_shape_type", SHAPE_NAMES);
static const mpm_def_enum METRICS = TABLE("mpm_def_enrichment_metric", METRIC_NAMES);
static const mpm_def_enum HOURGLASSES = TABLE("mpm_def_hourglass", HOURGLASS_NAMES);

/* An enum object may hold any int: say which values the enum has. */
const char *mpm_def_spell(mpm_def_ctx *c, const char *path, int v, const mpm_def_enum *t) {
  if (v >= 0 && v < t->count) return t->names[v];
  char list[200];
  size_t o = 0;
  list[0] = '\0';
  for (int i = 0; i < t->count; ++i) {
    int n = snprintf(list + o, sizeof list - o, "%s%d %s", i ? ", " : "", i, t->names[i]);
    if (n < 0 || (size_t)n >= sizeof list - o) break;
    o += (size_t)n;
  }
  mpm_def_fail(c, "%s: expected an %s (%s), got %d", path, t->type, list, v);
  return NULL;
}

/* A C string has no length limit; the format's names have. */
int mpm_def_check_name(mpm_def_ctx *c, const char *path, const char *s) {
  const size_t max = MPM_NAME_MAX - 1;
  if (s && strlen(s) > max)
    return mpm_def_fail(c, "%s: expected a name of at most %zu bytes, got %zu ('%.20s...')", path,
                        max, strlen(s), s);
  return 0;
}

int mpm_def_check_array(mpm_def_ctx *c, const char *key, const char *count_key, const void *array,
                        int count) {
  if (count < 0) return mpm_def_fail(c, "%s: expected %s >= 0, got %d", key, count_key, count);
  if (count > 0 && !array)
    return mpm_def_fail(c, "%s: NULL with %s %d (give the array or a count of 0)", key, count_key,
                        count);
  return 0;
}

int mpm_def_vec3_equal(const double a[3], const double b[3]) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* ---- writing JSON --------------------------------------------------------------------- */

cJSON *mpm_def_add_object(mpm_def_writer *w, cJSON *parent, const char *key) {
  cJSON *o = cJSON_AddObjectToObject(parent, key);
  if (!o) w->nomem = 1;
  return o;
}

cJSON *mpm_def_add_array(mpm_def_writer *w, cJSON *parent, const char *key) {
  cJSON *a = cJSON_AddArrayToObject(parent, key);
  if (!a) w->nomem = 1;
  return a;
}

/* Adds `item` (may be NULL) to the array `arr`; frees it when that fails. */
static void append(mpm_def_writer *w, cJSON *arr, cJSON *item) {
  if (!item || !cJSON_AddItemToArray(arr, item)) {
    cJSON_Delete(item);
    w->nomem = 1;
  }
}

cJSON *mpm_def_append_object(mpm_def_writer *w, cJSON *arr) {
  cJSON *o = cJSON_CreateObject();
  if (!o || !cJSON_AddItemToArray(arr, o)) {
    cJSON_Delete(o);
    w->nomem = 1;
    return NULL;
  }
  return o;
}

/* A number node holds the def's double itself; a non-finite one is null, which the format's
 * check names by its path. Printing goes through mpm_json_print_exact, which keeps the digits. */
static cJSON *number_item(mpm_def_writer *w, double v) {
  cJSON *n = isfinite(v) ? cJSON_CreateNumber(v) : cJSON_CreateNull();
  if (!n) w->nomem = 1;
  return n;
}

void mpm_def_add_number(mpm_def_writer *w, cJSON *obj, const char *key, double v) {
  cJSON *n = number_item(w, v);
  if (n && !cJSON_AddItemToObject(obj, key, n)) {
    cJSON_Delete(n);
    w->nomem = 1;
  }
}

void mpm_def_add_vec3(mpm_def_writer *w, cJSON *obj, const char *key, const double v[3]) {
  cJSON *a = mpm_def_add_array(w, obj, key);
  for (int k = 0; k < 3; ++k) append(w, a, number_item(w, v[k]));
}

void mpm_def_add_pairs(mpm_def_writer *w, cJSON *obj, const char *key, const double (*v)[2],
                       int n) {
  cJSON *a = mpm_def_add_array(w, obj, key);
  for (int i = 0; i < n; ++i) {
    cJSON *pair = cJSON_CreateArray();
    append(w, pair, number_item(w, v[i][0]));
    append(w, pair, number_item(w, v[i][1]));
    append(w, a, pair);
  }
}

void mpm_def_add_indices(mpm_def_writer *w, cJSON *obj, const char *key, const int *v, int n) {
  cJSON *a = mpm_def_add_array(w, obj, key);
  for (int i = 0; i < n; ++i) append(w, a, number_item(w, (double)v[i]));
}

void mpm_def_add_bool(mpm_def_writer *w, cJSON *obj, const char *key, int v) {
  if (!cJSON_AddBoolToObject(obj, key, v != 0)) w->nomem = 1;
}

void mpm_def_add_string(mpm_def_writer *w, cJSON *obj, const char *key, const char *s) {
  if (s && !cJSON_AddStringToObject(obj, key, s)) w->nomem = 1;
}

/* ---- shapes --------------------------------------------------------------------------- */

enum {
  F_CENTER = 1 << 0,
  F_HALF_EXTENT = 1 << 1,
  F_RADIUS = 1 << 2,
  F_AXIS = 1 << 3,
  F_HALF_HEIGHT = 1 << 4,
  F_FILE = 1 << 5,
  F_SCALE = 1 << 6,
  F_POINT = 1 << 7,
  F_NORMAL = 1 << 8,
  F_PROFILE = 1 << 9,
  F_MAX_FILE = 1 << 10,
};
/* The fields of each mpm_def_shape_type: its keys in the format. */
static const unsigned SHAPE_FIELDS[] = {
    F_CENTER | F_HALF_EXTENT,                     /* box */
    F_CENTER | F_RADIUS,                          /* sphere */
    F_CENTER | F_RADIUS | F_AXIS | F_HALF_HEIGHT, /* cylinder */
    F_FILE | F_CENTER | F_SCALE | F_MAX_FILE,     /* mesh */
    F_POINT | F_NORMAL,                           /* halfspace */
    F_CENTER | F_AXIS | F_PROFILE,                /* revolve */
};

static int write_shape(mpm_def_writer *w, const char *path, const mpm_shape_def *s, cJSON *parent) {
  char p[128];
  snprintf(p, sizeof p, "%s.type", path);
  const char *type = mpm_def_spell(w->c, p, (int)s->type, &SHAPES);
  if (!type) return -1;
  const mpm_shape_def d = mpm_shape_def_default(s->type);
  const unsigned has = SHAPE_FIELDS[s->type];
  const struct {
    unsigned bit;
    const char *key;
    int changed;
  } fields[] = {
      {F_CENTER, "center", !mpm_def_vec3_equal(s->center, d.center)},
      {F_HALF_EXTENT, "half_extent", !mpm_def_vec3_equal(s->half_extent, d.half_extent)},
      {F_RADIUS, "radius", s->radius != d.radius},
      {F_AXIS, "axis", !mpm_def_vec3_equal(s->axis, d.axis)},
      {F_HALF_HEIGHT, "half_height", s->half_height != d.half_height},
      {F_FILE, "file", s->file != NULL},
      {F_SCALE, "scale", s->scale != d.scale},
      {F_POINT, "point", !mpm_def_vec3_equal(s->point, d.point)},
      {F_NORMAL, "normal", !mpm_def_vec3_equal(s->normal, d.normal)},
      {F_PROFILE, "profile", s->profile != NULL || s->profile_count != 0},
      {F_MAX_FILE, "max_file_mb", s->max_file_mb != d.max_file_mb},
  };
  for (size_t k = 0; k < sizeof fields / sizeof fields[0]; ++k)
    if (!(has & fields[k].bit) && fields[k].changed)
      return mpm_def_fail(w->c,
                          "%s.%s: not a field of a %s shape (it would have no effect); leave it at "
                          "its default or change %s.type",
                          path, fields[k].key, type, path);
  snprintf(p, sizeof p, "%s.profile", path);
  if (mpm_def_check_array(w->c, p, "profile_count", s->profile, s->profile_count) < 0) return -1;
  cJSON *o = mpm_def_add_object(w, parent, "shape");
  mpm_def_add_string(w, o, "type", type);
  if (has & F_FILE) mpm_def_add_string(w, o, "file", s->file);
  if (has & F_CENTER) mpm_def_add_vec3(w, o, "center", s->center);
  if (has & F_HALF_EXTENT) mpm_def_add_vec3(w, o, "half_extent", s->half_extent);
  if (has & F_RADIUS) mpm_def_add_number(w, o, "radius", s->radius);
  if (has & F_AXIS) mpm_def_add_vec3(w, o, "axis", s->axis);
  if (has & F_HALF_HEIGHT) mpm_def_add_number(w, o, "half_height", s->half_height);
  if (has & F_SCALE) mpm_def_add_number(w, o, "scale", s->scale);
  if (has & F_POINT) mpm_def_add_vec3(w, o, "point", s->point);
  if (has & F_NORMAL) mpm_def_add_vec3(w, o, "normal", s->normal);
  if (has & F_PROFILE) mpm_def_add_pairs(w, o, "profile", s->profile, s->profile_count);
  if ((has & F_MAX_FILE) && s->max_file_mb != d.max_file_mb)
    mpm_def_add_number(w, o, "max_file_mb", s->max_file_mb);
  return 0;
}

/* ---- motion and active ---------------------------------------------------------------- */

/* `path` is the collider or force region. With keyframes the format refuses velocity and
 * angular_speed even at 0 (the pose follows the keyframes alone): they are left out, and
 * refused when changed. */
static int write_motion(mpm_def_writer *w, const char *path, const mpm_motion_def *m,
                        cJSON *parent) {
  char p[96];
  snprintf(p, sizeof p, "%s.motion.keyframes", path);
  if (mpm_def_check_array(w->c, p, "keyframe_count", m->keyframes, m->keyframe_count) < 0)
    return -1;
  const mpm_motion_def d = mpm_collider_def_default().motion;
  const int keyed = m->keyframe_count > 0;
  if (keyed &&
      (!mpm_def_vec3_equal(m->velocity, d.velocity) || m->angular_speed != d.angular_speed))
    return mpm_def_fail(w->c,
                        "%s.motion.%s: given with keyframes (the pose follows the keyframes "
                        "alone: it would have no effect); leave it at its default or set "
                        "%s.motion.keyframe_count to 0",
                        path, m->angular_speed != d.angular_speed ? "angular_speed" : "velocity",
                        path);
  cJSON *o = mpm_def_add_object(w, parent, "motion");
  if (!keyed) mpm_def_add_vec3(w, o, "velocity", m->velocity);
  mpm_def_add_vec3(w, o, "axis", m->axis);
  if (!keyed) {
    mpm_def_add_number(w, o, "angular_speed", m->angular_speed);
    return 0;
  }
  cJSON *arr = mpm_def_add_array(w, o, "keyframes");
  for (int k = 0; k < m->keyframe_count; ++k) {
    cJSON *e = mpm_def_append_object(w, arr);
    mpm_def_add_number(w, e, "time", m->keyframes[k].time);
    mpm_def_add_vec3(w, e, "translation", m->keyframes[k].translation);
    mpm_def_add_number(w, e, "angle", m->keyframes[k].angle);
  }
  return 0;
}

/* The default window, always, is the key left out: the format has no open end. */
static int write_active(mpm_def_writer *w, const char *path, const double active[2],
                        cJSON *parent) {
  const mpm_collider_def d = mpm_collider_def_default();
  if (active[0] == d.active[0] && active[1] == d.active[1]) return 0;
  if (isinf(active[1]) && active[1] > 0)
    return mpm_def_fail(w->c,
                        "%s.active[1]: expected a finite end (s) with a start other than 0: the "
                        "format's window has no open end (give one past time.end)",
                        path);
  cJSON *a = mpm_def_add_array(w, parent, "active");
  append(w, a, number_item(w, active[0]));
  append(w, a, number_item(w, active[1]));
  return 0;
}

/* [time, factor] keyframes at `path`.`key` (none: the key left out, factor 1). */
static int write_schedule(mpm_def_writer *w, const char *path, const char *key,
                          const char *count_key, const double (*v)[2], int n, cJSON *parent) {
  char p[96];
  snprintf(p, sizeof p, "%s.%s", path, key);
  if (mpm_def_check_array(w->c, p, count_key, v, n) < 0) return -1;
  if (n > 0) mpm_def_add_pairs(w, parent, key, v, n);
  return 0;
}

/* ---- materials ------------------------------------------------------------------------ */

/* The keys of some models only (scene_json_material.c's MODEL_ONLY_KEYS, with yield_stress). */
static const struct {
  const char *key;
  size_t offset;
  unsigned models; /* bit (1 << mpm_def_model) */
} MODEL_ONLY[] = {
    {"min_stretch", offsetof(mpm_material_def, min_stretch), 1u << MPM_DEF_NEO_HOOKEAN},
    {"friction_angle", offsetof(mpm_material_def, friction_angle), 1u << MPM_DEF_DRUCKER_PRAGER},
    {"cohesion", offsetof(mpm_material_def, cohesion), 1u << MPM_DEF_DRUCKER_PRAGER},
    {"yield_stress", offsetof(mpm_material_def, yield_stress), 1u << MPM_DEF_VON_MISES},
    {"theta_c", offsetof(mpm_material_def, theta_c), 1u << MPM_DEF_SNOW},
    {"theta_s", offsetof(mpm_material_def, theta_s), 1u << MPM_DEF_SNOW},
    {"hardening", offsetof(mpm_material_def, hardening), 1u << MPM_DEF_SNOW},
};

static double field_at(const mpm_material_def *m, size_t offset) {
  double v;
  memcpy(&v, (const char *)m + offset, sizeof v);
  return v;
}

/* A heat field given without heat (it would do nothing: the format refuses it too). */
static int no_heat(mpm_def_writer *w, const char *path, const char *field) {
  return mpm_def_fail(w->c,
                      "%s.%s: a heat field, and the def's heat is off (it would have no effect); "
                      "set heat.enabled or leave it at its default",
                      path, field);
}

int mpm_def_write_material(mpm_def_writer *w, int i, const mpm_material_def *m, const char *name,
                           int heat, cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "materials[%d].model", i);
  const char *model = mpm_def_spell(w->c, p, (int)m->model, &MODELS);
  if (!model) return -1;
  const mpm_material_def d = mpm_material_def_default();
  const unsigned bit = 1u << (unsigned)m->model;
  for (size_t k = 0; k < sizeof MODEL_ONLY / sizeof MODEL_ONLY[0]; ++k)
    if (!(MODEL_ONLY[k].models & bit) &&
        field_at(m, MODEL_ONLY[k].offset) != field_at(&d, MODEL_ONLY[k].offset)) {
      const unsigned models = MODEL_ONLY[k].models;
      int owner = 0;
      while (!(models & (1u << (unsigned)owner))) ++owner;
      char dflt[48];
      return mpm_def_fail(
          w->c,
          "materials[%d].%s: applies only to model %s, not to '%s' (it would have no effect); "
          "leave it at its default (%s) or change materials[%d].model",
          i, MODEL_ONLY[k].key, MODEL_NAMES[owner], model,
          mpm_json_format_number(field_at(&d, MODEL_ONLY[k].offset), dflt, sizeof dflt), i);
    }
  char where[32];
  snprintf(where, sizeof where, "materials[%d]", i);
  if (!heat) {
    if (m->specific_heat != d.specific_heat) return no_heat(w, where, "specific_heat");
    if (m->conductivity != d.conductivity) return no_heat(w, where, "conductivity");
    if (m->melting) return no_heat(w, where, "melting");
  }
  if (!m->melting && (m->melt_point != d.melt_point || m->melt_range != d.melt_range ||
                      m->melt_shear != d.melt_shear || m->melt_bulk != d.melt_bulk))
    return mpm_def_fail(w->c,
                        "%s.melt_*: melting values with melting 0 (they would have no effect); "
                        "set %s.melting to 1 or leave them at their defaults",
                        where, where);
  cJSON *o = mpm_def_append_object(w, arr);
  mpm_def_add_string(w, o, "name", name);
  mpm_def_add_string(w, o, "model", model);
  if (heat) {
    mpm_def_add_number(w, o, "specific_heat", m->specific_heat);
    mpm_def_add_number(w, o, "conductivity", m->conductivity);
  }
  if (m->melting) {
    cJSON *melt = mpm_def_add_object(w, o, "melting");
    mpm_def_add_number(w, melt, "point", m->melt_point);
    mpm_def_add_number(w, melt, "range", m->melt_range);
    mpm_def_add_number(w, melt, "shear", m->melt_shear);
    mpm_def_add_number(w, melt, "bulk", m->melt_bulk);
  }
  mpm_def_add_number(w, o, "E", m->E);
  mpm_def_add_number(w, o, "nu", m->nu);
  mpm_def_add_number(w, o, "density", m->density);
  for (size_t k = 0; k < sizeof MODEL_ONLY / sizeof MODEL_ONLY[0]; ++k)
    if (MODEL_ONLY[k].models & bit)
      mpm_def_add_number(w, o, MODEL_ONLY[k].key, field_at(m, MODEL_ONLY[k].offset));
  return write_schedule(w, where, "strength", "strength_count", m->strength, m->strength_count, o);
}

/* ---- bodies --------------------------------------------------------------------------- */

/* The keys of particle domains (bodies[].domains): enrichment and releases. */
static int write_domain_keys(mpm_def_writer *w, const char *path, const mpm_body_def *b, cJSON *o) {
  char p[96];
  snprintf(p, sizeof p, "%s.domain_release", path);
  if (mpm_def_check_array(w->c, p, "domain_release_count", b->domain_release,
                          b->domain_release_count) < 0)
    return -1;
  const mpm_body_def d = mpm_body_def_default();
  const char *changed =
      b->enrichment != d.enrichment                                   ? "enrichment"
      : b->enrichment_exit != d.enrichment_exit                       ? "enrichment_exit"
      : b->enrichment_metric != d.enrichment_metric                   ? "enrichment_metric"
      : b->enrichment_hourglass != d.enrichment_hourglass             ? "enrichment_hourglass"
      : b->enrichment_contact != d.enrichment_contact                 ? "enrichment_contact"
      : b->enrichment_surface_contact != d.enrichment_surface_contact ? "enrichment_surface_contact"
      : b->enrichment_self_contact != d.enrichment_self_contact       ? "enrichment_self_contact"
      : b->enrichment_exit_wait != d.enrichment_exit_wait             ? "enrichment_exit_wait"
      : b->hourglass != d.hourglass                                   ? "hourglass"
      : b->domain_release_count != 0                                  ? "domain_release"
                                                                      : NULL;
  if (!b->domains) {
    if (!changed) return 0;
    return mpm_def_fail(w->c,
                        "%s.%s: a field of particle domains, and %s.domains is 0 (it would have "
                        "no effect); set %s.domains or leave it at its default",
                        path, changed, path, path);
  }
  snprintf(p, sizeof p, "%s.enrichment_metric", path);
  const char *metric = mpm_def_spell(w->c, p, (int)b->enrichment_metric, &METRICS);
  if (!metric) return -1;
  mpm_def_add_number(w, o, "enrichment", b->enrichment);
  if (b->enrichment_exit != d.enrichment_exit)
    mpm_def_add_number(w, o, "enrichment_exit", b->enrichment_exit);
  mpm_def_add_string(w, o, "enrichment_metric", metric);
  if (b->enrichment_hourglass != d.enrichment_hourglass) /* older files unchanged */
    mpm_def_add_number(w, o, "enrichment_hourglass", b->enrichment_hourglass);
  if (b->enrichment_contact != d.enrichment_contact)
    mpm_def_add_bool(w, o, "enrichment_contact", b->enrichment_contact);
  if (b->enrichment_surface_contact != d.enrichment_surface_contact)
    mpm_def_add_bool(w, o, "enrichment_surface_contact", b->enrichment_surface_contact);
  if (b->enrichment_self_contact != d.enrichment_self_contact)
    mpm_def_add_bool(w, o, "enrichment_self_contact", b->enrichment_self_contact);
  if (b->enrichment_exit_wait != d.enrichment_exit_wait)
    mpm_def_add_number(w, o, "enrichment_exit_wait", b->enrichment_exit_wait);
  if (b->hourglass != d.hourglass) { /* written when not the default: older files unchanged */
    snprintf(p, sizeof p, "%s.hourglass", path);
    const char *hourglass = mpm_def_spell(w->c, p, (int)b->hourglass, &HOURGLASSES);
    if (!hourglass) return -1;
    mpm_def_add_string(w, o, "hourglass", hourglass);
  }
  if (b->domain_release_count == 0) return 0;
  cJSON *arr = mpm_def_add_array(w, o, "domain_release");
  for (int k = 0; k < b->domain_release_count; ++k) {
    cJSON *e = mpm_def_append_object(w, arr);
    mpm_def_add_number(w, e, "time", b->domain_release[k].time);
    mpm_def_add_vec3(w, e, "min", b->domain_release[k].min);
    mpm_def_add_vec3(w, e, "max", b->domain_release[k].max);
  }
  return 0;
}

int mpm_def_write_body(mpm_def_writer *w, int i, const mpm_body_def *b, const mpm_scene_def *def,
                       const char (*material_names)[MPM_NAME_MAX], cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "bodies[%d].name", i);
  if (mpm_def_check_name(w->c, p, b->name) < 0) return -1;
  snprintf(p, sizeof p, "bodies[%d].material_name", i);
  if (mpm_def_check_name(w->c, p, b->material_name) < 0) return -1;
  const char *material = b->material_name;
  if (!material) {
    if (def->material_count == 0)
      return mpm_def_fail(w->c,
                          "bodies[%d].material: the def has no materials for index %d; add one "
                          "to materials, or name one with material_name",
                          i, b->material);
    if (b->material < 0 || b->material >= def->material_count)
      return mpm_def_fail(w->c,
                          "bodies[%d].material: expected an index into the def's materials (0 .. "
                          "%d), got %d",
                          i, def->material_count - 1, b->material);
    material = material_names[b->material];
  }
  cJSON *o = mpm_def_append_object(w, arr);
  snprintf(p, sizeof p, "bodies[%d].shape", i);
  mpm_def_add_string(w, o, "name", b->name);
  if (write_shape(w, p, &b->shape, o) < 0) return -1;
  mpm_def_add_string(w, o, "material", material);
  mpm_def_add_vec3(w, o, "velocity", b->velocity);
  mpm_def_add_vec3(w, o, "angular_velocity", b->angular_velocity);
  mpm_def_add_number(w, o, "particles_per_cell", b->particles_per_cell);
  mpm_def_add_number(w, o, "jitter", b->jitter);
  mpm_def_add_number(w, o, "seed", (double)b->seed);
  mpm_def_add_bool(w, o, "domains", b->domains);
  snprintf(p, sizeof p, "bodies[%d]", i);
  if (write_domain_keys(w, p, b, o) < 0) return -1;
  if (b->has_temperature && !def->heat.enabled) return no_heat(w, p, "temperature");
  if (!b->has_temperature && b->temperature != mpm_body_def_default().temperature)
    return mpm_def_fail(w->c,
                        "%s.temperature: given with has_temperature 0 (it would have no effect); "
                        "set %s.has_temperature to 1 or leave it at its default",
                        p, p);
  if (b->has_temperature) mpm_def_add_number(w, o, "temperature", b->temperature);
  return 0;
}

/* ---- colliders and force regions ------------------------------------------------------ */

int mpm_def_write_collider(mpm_def_writer *w, int i, const mpm_collider_def *cd, int heat,
                           cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "colliders[%d].name", i);
  if (mpm_def_check_name(w->c, p, cd->name) < 0) return -1;
  snprintf(p, sizeof p, "colliders[%d].rule", i);
  const char *rule = mpm_def_spell(w->c, p, (int)cd->rule, &mpm_def_rules);
  if (!rule) return -1;
  cJSON *o = mpm_def_append_object(w, arr);
  snprintf(p, sizeof p, "colliders[%d].shape", i);
  mpm_def_add_string(w, o, "name", cd->name);
  if (write_shape(w, p, &cd->shape, o) < 0) return -1;
  mpm_def_add_bool(w, o, "inside_out", cd->inside_out);
  mpm_def_add_string(w, o, "rule", rule);
  mpm_def_add_number(w, o, "friction", cd->friction);
  snprintf(p, sizeof p, "colliders[%d]", i);
  if (write_motion(w, p, &cd->motion, o) < 0 || write_active(w, p, cd->active, o) < 0) return -1;
  if (cd->heat_source && !heat) return no_heat(w, p, "temperature");
  if (!cd->heat_source && cd->temperature != mpm_collider_def_default().temperature)
    return mpm_def_fail(w->c,
                        "%s.temperature: given with heat_source 0 (it would have no effect); set "
                        "%s.heat_source to 1 or leave it at its default",
                        p, p);
  if (cd->heat_source) mpm_def_add_number(w, o, "temperature", cd->temperature);
  return 0;
}

int mpm_def_write_force(mpm_def_writer *w, int i, const mpm_force_def *f, cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "forces[%d].name", i);
  if (mpm_def_check_name(w->c, p, f->name) < 0) return -1;
  cJSON *o = mpm_def_append_object(w, arr);
  snprintf(p, sizeof p, "forces[%d].shape", i);
  mpm_def_add_string(w, o, "name", f->name);
  if (write_shape(w, p, &f->shape, o) < 0) return -1;
  mpm_def_add_bool(w, o, "inside_out", f->inside_out);
  snprintf(p, sizeof p, "forces[%d]", i);
  if (write_motion(w, p, &f->motion, o) < 0 || write_active(w, p, f->active, o) < 0) return -1;
  mpm_def_add_vec3(w, o, "acceleration", f->acceleration);
  if (f->drag != 0) mpm_def_add_number(w, o, "drag", f->drag);
  return write_schedule(w, p, "schedule", "schedule_count", f->schedule, f->schedule_count, o);
}
