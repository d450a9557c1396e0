/* scene_def.c - a scene built in code (include/mpm/scene_def.h): the defaults of the def
 * structs, the def written as the scene's JSON text, and the simulation made from that text by
 * mpm_sim_create_from_json, so that every check and message of the scene format is the def's
 * too (the format's key paths are the def's field paths).
 *
 * Only what the JSON text cannot carry is checked here: NULL pointers and negative counts, enum
 * values out of range, names longer than the format's 63 bytes (a C string has no length), a
 * material index out of range, and fields that the JSON leaves out for the object's model, shape
 * type or integrator yet were changed from their defaults. The format refuses such keys because
 * they would have no effect; dropping them silently would hide the same mistake.
 *
 * Numbers are written with the fewest digits that read back as the same double, so a def and
 * its JSON make bit-identical simulations (cJSON's own printer accepts a 15-digit form within
 * an epsilon, which can be one bit off). A non-finite number is written as null, which the
 * format's check then names by its path. */
#include "mpm/mpm.h"
#include "scene/json_check.h"
#include "scene/scene.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- defaults ------------------------------------------------------------------------- */

mpm_shape_def mpm_shape_def_default(mpm_def_shape_type type) {
  mpm_shape_def s;
  memset(&s, 0, sizeof s);
  s.type = type;
  s.axis[1] = 1.0; /* scene.c's shape default: cylinder axis +y */
  s.scale = 1.0;
  s.normal[1] = 1.0;
  return s;
}

mpm_material_def mpm_material_def_default(void) {
  const mpm_material_desc m = mpm_material_desc_default();
  mpm_material_def d;
  memset(&d, 0, sizeof d);
  d.model = MPM_DEF_FIXED_COROTATED;
  d.E = m.E;
  d.nu = m.nu;
  d.density = m.density;
  d.min_stretch = m.min_stretch;
  d.friction_angle = m.friction_angle;
  d.cohesion = m.cohesion;
  d.yield_stress = m.yield_stress;
  d.theta_c = m.theta_c;
  d.theta_s = m.theta_s;
  d.hardening = m.hardening;
  d.specific_heat = m.specific_heat;
  d.conductivity = m.conductivity;
  d.melting = m.melting;
  d.melt_point = m.melt_point;
  d.melt_range = m.melt_range;
  d.melt_shear = m.melt_shear;
  d.melt_bulk = m.melt_bulk;
  return d;
}

mpm_body_def mpm_body_def_default(void) {
  const mpm_body_desc b = mpm_body_desc_default();
  mpm_body_def d;
  memset(&d, 0, sizeof d);
  d.shape = mpm_shape_def_default(MPM_DEF_BOX);
  d.material = 0;
  d.particles_per_cell = b.particles_per_cell;
  d.jitter = b.jitter;
  d.seed = b.seed;
  d.domains = b.domains;
  d.has_temperature = b.has_temperature;
  d.temperature = b.temperature;
  return d;
}

mpm_collider_def mpm_collider_def_default(void) {
  const mpm_collider_desc c = mpm_collider_desc_default();
  mpm_collider_def d;
  memset(&d, 0, sizeof d);
  d.shape = mpm_shape_def_default(MPM_DEF_HALFSPACE);
  d.inside_out = c.inside_out;
  d.rule = (mpm_def_rule)c.rule;
  d.friction = c.friction;
  for (int k = 0; k < 3; ++k) d.motion.axis[k] = c.motion.axis[k];
  d.motion.angular_speed = c.motion.angular_speed;
  d.heat_source = c.heat_source;
  d.temperature = c.temperature;
  return d;
}

/* Taken from mpm_scene_default, the struct the parser starts from, so that a default here
 * cannot drift from the format's; the required keys (domain, time.end) get its values too. */
mpm_scene_def mpm_scene_def_default(void) {
  mpm_scene s;
  mpm_scene_default(&s);
  mpm_scene_def d;
  memset(&d, 0, sizeof d);
  for (int k = 0; k < 3; ++k) {
    d.domain.min[k] = s.domain_min[k];
    d.domain.max[k] = s.domain_max[k];
    d.gravity[k] = s.gravity[k];
  }
  d.domain.dx = s.dx;
  d.domain.walls.rule = (mpm_def_rule)s.wall_rule;
  d.domain.walls.friction = s.wall_friction;
  d.domain.walls.cells = s.wall_cells;
  d.time.end = s.end_time;
  d.time.fps = s.fps;
  d.solver.integrator = (mpm_def_integrator)s.solver.integrator;
  d.solver.kernel = (mpm_def_kernel)s.solver.kernel;
  d.solver.transfer = (mpm_def_transfer)s.solver.transfer;
  d.solver.flip_alpha = s.solver.flip_alpha;
  d.solver.cfl = s.solver.cfl;
  d.solver.max_dt = s.solver.max_dt;
  d.solver.dt = s.solver.dt;
  d.solver.newton_iterations = s.solver.newton_iterations;
  d.output.directory = "out"; /* mpm_scene_default's, as a string of static storage */
  d.output.vtu = s.output.vtu;
  d.output.ply = s.output.ply;
  d.output.stats = s.output.stats;
  d.output.checkpoint_every = s.output.checkpoint_every;
  d.output.fields = s.output.fields;
  d.heat.enabled = s.heat.enabled;
  d.heat.temperature = s.heat.temperature;
  d.heat.pic = s.heat.pic;
  return d;
}

/* The public enums are numbered as the internal ones, which the spellings below follow. */
_Static_assert((int)MPM_DEF_SNOW == (int)MPM_MODEL_SNOW &&
                   (int)MPM_DEF_SEPARATE == (int)MPM_BOUNDARY_SEPARATE &&
                   (int)MPM_DEF_KERNEL_UGIMP == (int)MPM_KERNEL_UGIMP &&
                   (int)MPM_DEF_FLIP == (int)MPM_TRANSFER_FLIP &&
                   (int)MPM_DEF_IMPLICIT == (int)MPM_INTEGRATOR_IMPLICIT &&
                   (int)MPM_DEF_FIELD_F == (int)MPM_FIELD_F && MPM_FIELD_F + 1 == MPM_FIELD_COUNT,
               "scene_def.h's enums must match scene.h's");

/* ---- checks --------------------------------------------------------------------------- */

typedef struct def_ctx {
  char *err;
  size_t errlen;
  mpm_status status;
} def_ctx;

__attribute__((format(printf, 2, 3))) static int fail(def_ctx *c, const char *fmt, ...) {
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

typedef struct enum_table {
  const char *type; /* the C enum, for messages */
  const char *const *names;
  int count;
} enum_table;

static const char *const MODEL_NAMES[] = {"fixed_corotated", "neo_hookean", "hencky_stvk",
                                          "drucker_prager",  "von_mises",   "snow"};
static const char *const RULE_NAMES[] = {"sticky", "slip", "separate"};
static const char *const SHAPE_NAMES[] = {"box", "sphere", "cylinder", "mesh", "halfspace"};
static const char *const KERNEL_NAMES[] = {"linear", "quadratic", "cubic", "ugimp"};
static const char *const TRANSFER_NAMES[] = {"apic", "flip"};
static const char *const INTEGRATOR_NAMES[] = {"explicit", "implicit"};
#define TABLE(type, names)                                                                         \
  { type, names, (int)(sizeof names / sizeof names[0]) }
static const enum_table MODELS = TABLE("mpm_def_model", MODEL_NAMES);
static const enum_table RULES = TABLE("mpm_def_rule", RULE_NAMES);
static const enum_table SHAPES = TABLE("mpm_def_shape_type", SHAPE_NAMES);
static const enum_table KERNELS = TABLE("mpm_def_kernel", KERNEL_NAMES);
static const enum_table TRANSFERS = TABLE("mpm_def_transfer", TRANSFER_NAMES);
static const enum_table INTEGRATORS = TABLE("mpm_def_integrator", INTEGRATOR_NAMES);

/* The format's spelling of value v of an enum; NULL with the message when it has no such
 * value (an enum object may hold any int). */
static const char *spell(def_ctx *c, const char *path, int v, const enum_table *t) {
  if (v >= 0 && v < t->count) return t->names[v];
  char list[160];
  size_t o = 0;
  list[0] = '\0';
  for (int i = 0; i < t->count; ++i) {
    int w = snprintf(list + o, sizeof list - o, "%s%d %s", i ? ", " : "", i, t->names[i]);
    if (w < 0 || (size_t)w >= sizeof list - o) break;
    o += (size_t)w;
  }
  fail(c, "%s: expected an %s (%s), got %d", path, t->type, list, v);
  return NULL;
}

static int check_name(def_ctx *c, const char *path, const char *s) {
  const size_t max = MPM_NAME_MAX - 1;
  if (s && strlen(s) > max)
    return fail(c, "%s: expected a name of at most %zu bytes, got %zu ('%.20s...')", path, max,
                strlen(s), s);
  return 0;
}

/* ---- writing JSON --------------------------------------------------------------------- */

/* Builders that remember an allocation failure instead of returning it at every call: cJSON's
 * Add* functions take a NULL object (and free what they made), so writing goes on harmlessly
 * and the failure is reported once at the end. */
typedef struct writer {
  def_ctx *c;
  int nomem;
} writer;

static cJSON *add_object(writer *w, cJSON *parent, const char *key) {
  cJSON *o = cJSON_AddObjectToObject(parent, key);
  if (!o) w->nomem = 1;
  return o;
}

static cJSON *add_array(writer *w, cJSON *parent, const char *key) {
  cJSON *a = cJSON_AddArrayToObject(parent, key);
  if (!a) w->nomem = 1;
  return a;
}

static cJSON *number_item(writer *w, double v) {
  char buf[64];
  if (isfinite(v))
    mpm_json_format_number(v, buf, sizeof buf);
  else
    snprintf(buf, sizeof buf, "null");
  cJSON *n = cJSON_CreateRaw(buf);
  if (!n) w->nomem = 1;
  return n;
}

static void add_number(writer *w, cJSON *obj, const char *key, double v) {
  cJSON *n = number_item(w, v);
  if (n && !cJSON_AddItemToObject(obj, key, n)) {
    cJSON_Delete(n);
    w->nomem = 1;
  }
}

static void add_vec3(writer *w, cJSON *obj, const char *key, const double v[3]) {
  cJSON *a = add_array(w, obj, key);
  for (int k = 0; k < 3; ++k) {
    cJSON *n = number_item(w, v[k]);
    if (n && !cJSON_AddItemToArray(a, n)) {
      cJSON_Delete(n);
      w->nomem = 1;
    }
  }
}

static void add_bool(writer *w, cJSON *obj, const char *key, int v) {
  if (!cJSON_AddBoolToObject(obj, key, v != 0)) w->nomem = 1;
}

static void add_string(writer *w, cJSON *obj, const char *key, const char *s) {
  if (s && !cJSON_AddStringToObject(obj, key, s)) w->nomem = 1;
}

/* ---- the parts ------------------------------------------------------------------------ */

static int vec3_equal(const double a[3], const double b[3]) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

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
};
/* The fields of each mpm_def_shape_type: its keys in the format. */
static const unsigned SHAPE_FIELDS[] = {
    F_CENTER | F_HALF_EXTENT,                     /* box */
    F_CENTER | F_RADIUS,                          /* sphere */
    F_CENTER | F_RADIUS | F_AXIS | F_HALF_HEIGHT, /* cylinder */
    F_FILE | F_CENTER | F_SCALE,                  /* mesh */
    F_POINT | F_NORMAL,                           /* halfspace */
};

static int write_shape(writer *w, const char *path, const mpm_shape_def *s, cJSON *parent) {
  char p[128];
  snprintf(p, sizeof p, "%s.type", path);
  const char *type = spell(w->c, p, (int)s->type, &SHAPES);
  if (!type) return -1;
  const mpm_shape_def d = mpm_shape_def_default(s->type);
  const unsigned has = SHAPE_FIELDS[s->type];
  const struct {
    unsigned bit;
    const char *key;
    int changed;
  } fields[] = {
      {F_CENTER, "center", !vec3_equal(s->center, d.center)},
      {F_HALF_EXTENT, "half_extent", !vec3_equal(s->half_extent, d.half_extent)},
      {F_RADIUS, "radius", s->radius != d.radius},
      {F_AXIS, "axis", !vec3_equal(s->axis, d.axis)},
      {F_HALF_HEIGHT, "half_height", s->half_height != d.half_height},
      {F_FILE, "file", s->file != NULL},
      {F_SCALE, "scale", s->scale != d.scale},
      {F_POINT, "point", !vec3_equal(s->point, d.point)},
      {F_NORMAL, "normal", !vec3_equal(s->normal, d.normal)},
  };
  for (size_t k = 0; k < sizeof fields / sizeof fields[0]; ++k)
    if (!(has & fields[k].bit) && fields[k].changed)
      return fail(w->c,
                  "%s.%s: not a field of a %s shape (it would have no effect); leave it at its "
                  "default or change %s.type",
                  path, fields[k].key, type, path);
  cJSON *o = add_object(w, parent, "shape");
  add_string(w, o, "type", type);
  if (has & F_FILE) add_string(w, o, "file", s->file);
  if (has & F_CENTER) add_vec3(w, o, "center", s->center);
  if (has & F_HALF_EXTENT) add_vec3(w, o, "half_extent", s->half_extent);
  if (has & F_RADIUS) add_number(w, o, "radius", s->radius);
  if (has & F_AXIS) add_vec3(w, o, "axis", s->axis);
  if (has & F_HALF_HEIGHT) add_number(w, o, "half_height", s->half_height);
  if (has & F_SCALE) add_number(w, o, "scale", s->scale);
  if (has & F_POINT) add_vec3(w, o, "point", s->point);
  if (has & F_NORMAL) add_vec3(w, o, "normal", s->normal);
  return 0;
}

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
static int no_heat(writer *w, const char *path, const char *field) {
  return fail(w->c,
              "%s.%s: a heat field, and the def's heat is off (it would have no effect); set "
              "heat.enabled or leave it at its default",
              path, field);
}

static int write_material(writer *w, int i, const mpm_material_def *m, const char *name, int heat,
                          cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "materials[%d].model", i);
  const char *model = spell(w->c, p, (int)m->model, &MODELS);
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
      return fail(w->c,
                  "materials[%d].%s: applies only to model %s, not to '%s' (it would have no "
                  "effect); leave it at its default (%s) or change materials[%d].model",
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
    return fail(w->c,
                "%s.melt_*: melting values with melting 0 (they would have no effect); set "
                "%s.melting to 1 or leave them at their defaults",
                where, where);
  cJSON *o = cJSON_CreateObject();
  if (!o || !cJSON_AddItemToArray(arr, o)) {
    cJSON_Delete(o);
    w->nomem = 1;
    return 0;
  }
  add_string(w, o, "name", name);
  add_string(w, o, "model", model);
  if (heat) {
    add_number(w, o, "specific_heat", m->specific_heat);
    add_number(w, o, "conductivity", m->conductivity);
  }
  if (m->melting) {
    cJSON *melt = add_object(w, o, "melting");
    add_number(w, melt, "point", m->melt_point);
    add_number(w, melt, "range", m->melt_range);
    add_number(w, melt, "shear", m->melt_shear);
    add_number(w, melt, "bulk", m->melt_bulk);
  }
  add_number(w, o, "E", m->E);
  add_number(w, o, "nu", m->nu);
  add_number(w, o, "density", m->density);
  for (size_t k = 0; k < sizeof MODEL_ONLY / sizeof MODEL_ONLY[0]; ++k)
    if (MODEL_ONLY[k].models & bit)
      add_number(w, o, MODEL_ONLY[k].key, field_at(m, MODEL_ONLY[k].offset));
  return 0;
}

static int write_body(writer *w, int i, const mpm_body_def *b, const mpm_scene_def *def,
                      char (*material_names)[MPM_NAME_MAX], cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "bodies[%d].name", i);
  if (check_name(w->c, p, b->name) < 0) return -1;
  snprintf(p, sizeof p, "bodies[%d].material_name", i);
  if (check_name(w->c, p, b->material_name) < 0) return -1;
  const char *material = b->material_name;
  if (!material) {
    if (def->material_count == 0)
      return fail(w->c,
                  "bodies[%d].material: the def has no materials for index %d; add one to "
                  "materials, or name one with material_name",
                  i, b->material);
    if (b->material < 0 || b->material >= def->material_count)
      return fail(w->c,
                  "bodies[%d].material: expected an index into the def's materials (0 .. %d), "
                  "got %d",
                  i, def->material_count - 1, b->material);
    material = material_names[b->material];
  }
  cJSON *o = cJSON_CreateObject();
  if (!o || !cJSON_AddItemToArray(arr, o)) {
    cJSON_Delete(o);
    w->nomem = 1;
    return 0;
  }
  snprintf(p, sizeof p, "bodies[%d].shape", i);
  add_string(w, o, "name", b->name);
  if (write_shape(w, p, &b->shape, o) < 0) return -1;
  add_string(w, o, "material", material);
  add_vec3(w, o, "velocity", b->velocity);
  add_vec3(w, o, "angular_velocity", b->angular_velocity);
  add_number(w, o, "particles_per_cell", b->particles_per_cell);
  add_number(w, o, "jitter", b->jitter);
  add_number(w, o, "seed", (double)b->seed);
  add_bool(w, o, "domains", b->domains);
  snprintf(p, sizeof p, "bodies[%d]", i);
  if (b->has_temperature && !def->heat.enabled) return no_heat(w, p, "temperature");
  if (!b->has_temperature && b->temperature != mpm_body_def_default().temperature)
    return fail(w->c,
                "%s.temperature: given with has_temperature 0 (it would have no effect); set "
                "%s.has_temperature to 1 or leave it at its default",
                p, p);
  if (b->has_temperature) add_number(w, o, "temperature", b->temperature);
  return 0;
}

static int write_collider(writer *w, int i, const mpm_collider_def *cd, int heat, cJSON *arr) {
  char p[64];
  snprintf(p, sizeof p, "colliders[%d].name", i);
  if (check_name(w->c, p, cd->name) < 0) return -1;
  snprintf(p, sizeof p, "colliders[%d].rule", i);
  const char *rule = spell(w->c, p, (int)cd->rule, &RULES);
  if (!rule) return -1;
  cJSON *o = cJSON_CreateObject();
  if (!o || !cJSON_AddItemToArray(arr, o)) {
    cJSON_Delete(o);
    w->nomem = 1;
    return 0;
  }
  snprintf(p, sizeof p, "colliders[%d].shape", i);
  add_string(w, o, "name", cd->name);
  if (write_shape(w, p, &cd->shape, o) < 0) return -1;
  add_bool(w, o, "inside_out", cd->inside_out);
  add_string(w, o, "rule", rule);
  add_number(w, o, "friction", cd->friction);
  cJSON *m = add_object(w, o, "motion");
  add_vec3(w, m, "velocity", cd->motion.velocity);
  add_vec3(w, m, "axis", cd->motion.axis);
  add_number(w, m, "angular_speed", cd->motion.angular_speed);
  snprintf(p, sizeof p, "colliders[%d]", i);
  if (cd->heat_source && !heat) return no_heat(w, p, "temperature");
  if (!cd->heat_source && cd->temperature != mpm_collider_def_default().temperature)
    return fail(w->c,
                "%s.temperature: given with heat_source 0 (it would have no effect); set "
                "%s.heat_source to 1 or leave it at its default",
                p, p);
  if (cd->heat_source) add_number(w, o, "temperature", cd->temperature);
  return 0;
}

static int write_solver(writer *w, const mpm_solver_def *s, cJSON *root) {
  const char *integrator = spell(w->c, "solver.integrator", (int)s->integrator, &INTEGRATORS);
  const char *kernel = integrator ? spell(w->c, "solver.kernel", (int)s->kernel, &KERNELS) : NULL;
  const char *transfer =
      kernel ? spell(w->c, "solver.transfer", (int)s->transfer, &TRANSFERS) : NULL;
  if (!transfer) return -1;
  const int implicit = s->integrator == MPM_DEF_IMPLICIT;
  const mpm_solver_def d = mpm_scene_def_default().solver;
  if (!implicit && (s->dt != d.dt || s->newton_iterations != d.newton_iterations))
    return fail(w->c,
                "solver.%s: a field of the implicit integrator only (it would have no effect); "
                "set solver.integrator to MPM_DEF_IMPLICIT or leave it at its default",
                s->dt != d.dt ? "dt" : "newton_iterations");
  cJSON *o = add_object(w, root, "solver");
  add_string(w, o, "integrator", integrator);
  add_string(w, o, "kernel", kernel);
  add_string(w, o, "transfer", transfer);
  add_number(w, o, "flip_alpha", s->flip_alpha);
  add_number(w, o, "cfl", s->cfl);
  add_number(w, o, "max_dt", s->max_dt);
  if (implicit) {
    add_number(w, o, "dt", s->dt);
    add_number(w, o, "newton_iterations", s->newton_iterations);
  }
  return 0;
}

/* An array of the def: NULL only when empty, and a count >= 0. */
static int check_array(def_ctx *c, const char *key, const char *count_key, const void *array,
                       int count) {
  if (count < 0) return fail(c, "%s: expected %s >= 0, got %d", key, count_key, count);
  if (count > 0 && !array)
    return fail(c, "%s: NULL with %s %d (give the array or a count of 0)", key, count_key, count);
  return 0;
}

/* The def as a JSON tree; NULL with c's message (or status MPM_ERR_NOMEM) on failure. */
static cJSON *build(def_ctx *c, const mpm_scene_def *def) {
  if (!def) {
    fail(c, "no scene def given (NULL)");
    return NULL;
  }
  if (check_array(c, "materials", "material_count", def->materials, def->material_count) < 0 ||
      check_array(c, "bodies", "body_count", def->bodies, def->body_count) < 0 ||
      check_array(c, "colliders", "collider_count", def->colliders, def->collider_count) < 0 ||
      check_name(c, "name", def->name) < 0)
    return NULL;
  const char *wall_rule = spell(c, "domain.walls.rule", (int)def->domain.walls.rule, &RULES);
  if (!wall_rule) return NULL;
  char(*names)[MPM_NAME_MAX] = calloc((size_t)def->material_count + 1, sizeof *names);
  cJSON *root = cJSON_CreateObject();
  if (!names || !root) {
    free(names);
    cJSON_Delete(root);
    c->status = MPM_ERR_NOMEM;
    return NULL;
  }
  writer w = {c, 0};
  int bad = 0;
  for (int i = 0; i < def->material_count && !bad; ++i) {
    char p[64];
    snprintf(p, sizeof p, "materials[%d].name", i);
    bad = check_name(c, p, def->materials[i].name) < 0;
    snprintf(names[i], sizeof names[i], "%s", def->materials[i].name ? def->materials[i].name : "");
    if (!def->materials[i].name) snprintf(names[i], sizeof names[i], "material%d", i);
  }
  add_string(&w, root, "name", def->name);
  cJSON *dom = add_object(&w, root, "domain");
  add_vec3(&w, dom, "min", def->domain.min);
  add_vec3(&w, dom, "max", def->domain.max);
  add_number(&w, dom, "dx", def->domain.dx);
  cJSON *walls = add_object(&w, dom, "walls");
  add_string(&w, walls, "rule", wall_rule);
  add_number(&w, walls, "friction", def->domain.walls.friction);
  add_number(&w, walls, "cells", def->domain.walls.cells);
  add_vec3(&w, root, "gravity", def->gravity);
  cJSON *time = add_object(&w, root, "time");
  add_number(&w, time, "end", def->time.end);
  add_number(&w, time, "fps", def->time.fps);
  bad = bad || write_solver(&w, &def->solver, root) < 0;
  cJSON *mats = add_array(&w, root, "materials");
  for (int i = 0; i < def->material_count && !bad; ++i)
    bad = write_material(&w, i, &def->materials[i], names[i], def->heat.enabled, mats) < 0;
  cJSON *bodies = add_array(&w, root, "bodies");
  for (int i = 0; i < def->body_count && !bad; ++i)
    bad = write_body(&w, i, &def->bodies[i], def, names, bodies) < 0;
  if (def->collider_count > 0) {
    cJSON *cols = add_array(&w, root, "colliders");
    for (int i = 0; i < def->collider_count && !bad; ++i)
      bad = write_collider(&w, i, &def->colliders[i], def->heat.enabled, cols) < 0;
  }
  cJSON *out = add_object(&w, root, "output");
  add_string(&w, out, "directory", def->output.directory);
  add_bool(&w, out, "vtu", def->output.vtu);
  add_bool(&w, out, "ply", def->output.ply);
  add_bool(&w, out, "stats", def->output.stats);
  add_number(&w, out, "checkpoint_every", def->output.checkpoint_every);
  if (!bad && def->output.fields >> MPM_FIELD_COUNT)
    bad = fail(c,
               "output.fields: bits above (1u << MPM_DEF_FIELD_F) are no mpm_def_field, got "
               "0x%x",
               def->output.fields) < 0;
  if (!bad && def->output.fields) { /* in the enum's order, which is the file's */
    cJSON *list = add_array(&w, out, "fields");
    for (int f = 0; f < MPM_FIELD_COUNT; ++f)
      if (def->output.fields >> f & 1u) {
        cJSON *name = cJSON_CreateString(mpm_output_field_names[f]);
        if (!name || !cJSON_AddItemToArray(list, name)) {
          cJSON_Delete(name);
          w.nomem = 1;
        }
      }
  }
  const mpm_heat_def dh = mpm_scene_def_default().heat;
  if (!bad && !def->heat.enabled &&
      (def->heat.temperature != dh.temperature || def->heat.pic != dh.pic))
    bad = fail(c,
               "heat.%s: given with heat.enabled 0 (it would have no effect); set "
               "heat.enabled or leave it at its default",
               def->heat.temperature != dh.temperature ? "temperature" : "pic") < 0;
  if (!bad && def->heat.enabled) {
    cJSON *heat = add_object(&w, root, "heat");
    add_number(&w, heat, "temperature", def->heat.temperature);
    add_number(&w, heat, "pic", def->heat.pic);
  }
  free(names);
  if (!bad && w.nomem) {
    c->status = MPM_ERR_NOMEM;
    if (c->err && c->errlen)
      snprintf(c->err, c->errlen, "<def>: out of memory writing the scene's JSON text");
  }
  if (bad || w.nomem) {
    cJSON_Delete(root);
    return NULL;
  }
  return root;
}

/* ---- the entry points ----------------------------------------------------------------- */

mpm_status mpm_scene_def_to_json(const mpm_scene_def *def, char **json_out, char *err,
                                 size_t errlen) {
  def_ctx c = {err, errlen, MPM_OK};
  if (!json_out) {
    fail(&c, "no place for the text given (json_out is NULL)");
    return c.status;
  }
  *json_out = NULL;
  cJSON *root = build(&c, def);
  if (!root) return c.status;
  *json_out = cJSON_Print(root);
  cJSON_Delete(root);
  if (!*json_out) {
    if (err && errlen) snprintf(err, errlen, "<def>: out of memory printing the scene's JSON text");
    return MPM_ERR_NOMEM;
  }
  return MPM_OK;
}

void mpm_free_string(char *s) {
  cJSON_free(s); /* cJSON_Print allocated it, with cJSON's allocator */
}

/* mpm_sim_create_from_json names the scene "<json>" ("BASE/<json>" with a base_dir) at the
 * start of its messages: say "<def>" there, since the def is what the caller wrote. */
static void relabel(const char *msg, const char *base_dir, char *err, size_t errlen) {
  if (!err || !errlen) return;
  static const char tag[] = "<json>";
  const size_t tl = sizeof tag - 1;
  size_t at = 0;
  if (base_dir && base_dir[0]) {
    const size_t bl = strlen(base_dir);
    at = strncmp(msg, base_dir, bl) == 0 && msg[bl] == '/' ? bl + 1 : (size_t)-1;
  }
  if (at != (size_t)-1 && strncmp(msg + at, tag, tl) == 0)
    snprintf(err, errlen, "%.*s<def>%s", (int)at, msg, msg + at + tl);
  else
    snprintf(err, errlen, "%s", msg);
}

mpm_status mpm_sim_create_from_def(const mpm_scene_def *def, const char *base_dir, mpm_sim **out,
                                   char *err, size_t errlen) {
  def_ctx c = {err, errlen, MPM_OK};
  if (!out) {
    fail(&c, "no place for the simulation given (out is NULL)");
    return c.status;
  }
  *out = NULL;
  cJSON *root = build(&c, def);
  if (!root) return c.status;
  char *text = cJSON_PrintUnformatted(root);
  cJSON_Delete(root);
  if (!text) {
    if (err && errlen) snprintf(err, errlen, "<def>: out of memory printing the scene's JSON text");
    return MPM_ERR_NOMEM;
  }
  char msg[sizeof(((mpm_error *)0)->message) + MPM_PATH_MAX];
  msg[0] = '\0';
  const mpm_status st = mpm_sim_create_from_json(text, base_dir, out, msg, sizeof msg);
  cJSON_free(text);
  if (st != MPM_OK) relabel(msg, base_dir, err, errlen);
  return st;
}
