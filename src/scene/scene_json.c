/* scene_json.c - the JSON scene format: reading a scene file, parsing it with cJSON and
 * checking every key into the descriptor structs of scene.h.
 *
 * The format is documented key by key in docs/scene-format.md. Checking is strict: unknown
 * and duplicate keys, wrong types, out-of-range and non-finite numbers, unknown enum values
 * and material names, material keys of another model (they would have no effect), bodies that
 * leave the usable domain and unreadable mesh files are all errors whose message starts with
 * the file and the key path ("bodies[2].material.E") and says what was expected and what was
 * found. The typed getters live in json_check.c.
 * On any error the scene is left empty (arrays freed, defaults filled). */
#include "scene/json_check.h"
#include "scene/mesh.h"
#include "scene/scene.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Grid coordinates must stay well inside the sparse grid's block keys and an int. */
#define MAX_CELLS_PER_AXIS (1 << 20)
/* The simulation keeps per-frame records. */
#define MAX_FRAMES 10000000.0

static const char *const TOP_KEYS[] = {"name",      "domain", "gravity",   "time",   "solver",
                                       "materials", "bodies", "colliders", "output", NULL};
static const char *const DOMAIN_KEYS[] = {"min", "max", "dx", "resolution", "walls", NULL};
static const char *const WALL_KEYS[] = {"rule", "friction", "cells", NULL};
static const char *const TIME_KEYS[] = {"end", "fps", NULL};
static const char *const SOLVER_KEYS[] = {"kernel", "transfer", "flip_alpha",  "cfl",
                                          "max_dt", "grid",     "gimp_length", NULL};
static const char *const MATERIAL_KEYS[] = {
    "name",     "model",        "E",       "nu",      "density",   "min_stretch", "friction_angle",
    "cohesion", "yield_stress", "theta_c", "theta_s", "hardening", NULL};
static const char *const BODY_KEYS[] = {
    "name",   "shape", "material", "velocity", "angular_velocity", "particles_per_cell",
    "jitter", "seed",  NULL};
static const char *const COLLIDER_KEYS[] = {"name",     "shape",  "inside_out", "rule",
                                            "friction", "motion", NULL};
static const char *const MOTION_KEYS[] = {"velocity", "axis", "angular_speed", "keyframes", NULL};
static const char *const KEYFRAME_KEYS[] = {"time", "translation", "angle", NULL};
static const char *const OUTPUT_KEYS[] = {"directory", "vtu", "ply", "stats", NULL};

static const char *const BOX_KEYS[] = {"type", "center", "half_extent", NULL};
static const char *const SPHERE_KEYS[] = {"type", "center", "radius", NULL};
static const char *const CYLINDER_KEYS[] = {"type", "center",      "radius",
                                            "axis", "half_height", NULL};
static const char *const MESH_KEYS[] = {"type", "file", "center", "scale", NULL};
static const char *const HALFSPACE_KEYS[] = {"type", "point", "normal", NULL};

/* Enum spellings, in the order of the enum values of scene.h. */
static const char *const RULE_NAMES[] = {"sticky", "slip", "separate", NULL};
static const char *const KERNEL_NAMES[] = {"linear", "quadratic", "cubic", "ugimp", NULL};
static const char *const TRANSFER_NAMES[] = {"apic", "flip", NULL};
static const char *const GRID_NAMES[] = {"sparse", "dense", NULL};
static const char *const MODEL_NAMES[] = {
    "fixed_corotated", "neo_hookean", "hencky_stvk", "drucker_prager", "von_mises", "snow", NULL};
_Static_assert(sizeof MODEL_NAMES / sizeof MODEL_NAMES[0] == MPM_MODEL_COUNT + 1,
               "MODEL_NAMES must name every mpm_model_kind, in order");
static const char *const BODY_SHAPE_NAMES[] = {"box", "sphere", "cylinder", "mesh", NULL};
static const mpm_shape_kind BODY_SHAPE_KINDS[] = {MPM_SHAPE_BOX, MPM_SHAPE_SPHERE,
                                                  MPM_SHAPE_CYLINDER, MPM_SHAPE_MESH};
static const char *const COLLIDER_SHAPE_NAMES[] = {"box", "sphere", "cylinder", "halfspace", NULL};
static const mpm_shape_kind COLLIDER_SHAPE_KINDS[] = {MPM_SHAPE_BOX, MPM_SHAPE_SPHERE,
                                                      MPM_SHAPE_CYLINDER, MPM_SHAPE_HALFSPACE};

static const char AXIS_NAME[3] = {'x', 'y', 'z'};

/* ---- small helpers -------------------------------------------------------------------- */

static int fail_nomem(mpm_json_ctx *c, const char *what) {
  return mpm_json_fail(c, MPM_ERR_NOMEM, "out of memory allocating %s", what);
}

/* The array at obj[key] (required or not); 0 absent, 1 present, -1 wrong type. */
static int get_array(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                     const char *what, const cJSON **out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  if (!cJSON_IsArray(n)) {
    char got[96];
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected %s, got %s", what,
                            mpm_json_describe(n, got, sizeof got));
  }
  *out = n;
  return 1;
}

/* Resolve `file` against the directory of the scene file; -1 when it does not fit. */
static int resolve_path(const char *scene_path, const char *file, char *out, size_t cap) {
  const char *slash = strrchr(scene_path, '/');
  int n;
  if (file[0] == '/' || !slash)
    n = snprintf(out, cap, "%s", file);
  else
    n = snprintf(out, cap, "%.*s/%s", (int)(slash - scene_path), scene_path, file);
  return (n < 0 || (size_t)n >= cap) ? -1 : 0;
}

/* "[0.1, 0.2, 0.3]" with '.' decimals. */
static const char *format_vec3(const double v[3], char *buf, size_t cap) {
  char a[40], b[40], d[40];
  snprintf(buf, cap, "[%s, %s, %s]", mpm_json_format_short(v[0], a, sizeof a),
           mpm_json_format_short(v[1], b, sizeof b), mpm_json_format_short(v[2], d, sizeof d));
  return buf;
}

/* ---- domain, time, solver, output ----------------------------------------------------- */

static int parse_walls(mpm_json_ctx *c, const cJSON *domain, mpm_scene *s) {
  const cJSON *w = mpm_json_get(domain, "walls");
  if (!w) return 0;
  size_t old = mpm_json_push_key(c, "walls");
  if (mpm_json_expect_object(c, w, "an object with keys rule, friction, cells") < 0 ||
      mpm_json_check_keys(c, w, WALL_KEYS, NULL) < 0)
    return -1;
  int rule = (int)s->wall_rule;
  long long cells = s->wall_cells;
  if (mpm_json_enum(c, w, "rule", 0, RULE_NAMES, &rule) < 0 ||
      mpm_json_number(c, w, "friction", 0, mpm_json_ge(0, "Coulomb coefficient"),
                      &s->wall_friction) < 0 ||
      mpm_json_integer(c, w, "cells", 0, mpm_json_in('[', 2, 16, ']', "cells"), &cells) < 0)
    return -1;
  s->wall_rule = (mpm_boundary_rule)rule;
  s->wall_cells = (int)cells;
  mpm_json_pop(c, old);
  return 0;
}

static int parse_domain(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *dom = mpm_json_get(root, "domain");
  if (!dom) return mpm_json_missing(c, "domain");
  size_t old = mpm_json_push_key(c, "domain");
  if (mpm_json_expect_object(c, dom, "an object with keys min, max and dx (or resolution)") < 0 ||
      mpm_json_check_keys(c, dom, DOMAIN_KEYS, NULL) < 0)
    return -1;
  if (mpm_json_vec3(c, dom, "min", 1, mpm_json_any("m"), s->domain_min) < 0 ||
      mpm_json_vec3(c, dom, "max", 1, mpm_json_any("m"), s->domain_max) < 0)
    return -1;
  char key[16], note[160], lo[40];
  for (int d = 0; d < 3; ++d)
    if (!(s->domain_max[d] > s->domain_min[d])) {
      snprintf(key, sizeof key, "max[%d]", d);
      snprintf(note, sizeof note, "m, greater than min[%d]", d);
      char want[256], got[40];
      mpm_json_range r = mpm_json_gt(s->domain_min[d], note);
      return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected %s, got %s",
                              mpm_json_describe_range(&r, 0, want, sizeof want),
                              mpm_json_format_number(s->domain_max[d], got, sizeof got));
    }
  double extent[3], longest = 0;
  for (int d = 0; d < 3; ++d) {
    extent[d] = s->domain_max[d] - s->domain_min[d];
    if (extent[d] > longest) longest = extent[d];
  }
  if (!isfinite(longest))
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected a domain of finite size, got max - min "
                         "overflowing to infinity");
  double dx = 0;
  long long res = 0;
  int has_dx = mpm_json_number(c, dom, "dx", 0, mpm_json_gt(0, "m"), &dx);
  if (has_dx < 0) return -1;
  int has_res = mpm_json_integer(
      c, dom, "resolution", 0,
      mpm_json_in('[', 8, MAX_CELLS_PER_AXIS, ']', "cells along the longest axis"), &res);
  if (has_res < 0) return -1;
  if (has_dx && has_res)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected exactly one of 'dx' or 'resolution', got both");
  if (!has_dx && !has_res)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "missing required key 'dx' (cell size, m) or 'resolution' (cells "
                         "along the longest axis)");
  if (has_res) dx = longest / (double)res;
  if (has_dx && longest / dx > MAX_CELLS_PER_AXIS) {
    mpm_json_range r = mpm_json_ge(longest / MAX_CELLS_PER_AXIS, "m, at most 1048576 cells "
                                                                 "along the longest axis");
    char want[256], got[40];
    return mpm_json_fail_at(c, "dx", MPM_ERR_INVALID, "expected %s, got %s",
                            mpm_json_describe_range(&r, 0, want, sizeof want),
                            mpm_json_format_number(dx, got, sizeof got));
  }
  s->dx = dx;
  for (int d = 0; d < 3; ++d)
    if (!(extent[d] > 8.0 * dx)) {
      snprintf(key, sizeof key, "max[%d]", d);
      snprintf(note, sizeof note,
               "m: min[%d] + 8*dx with dx = %s m%s; the domain must be "
               "more than 8 cells wide on every axis",
               d, mpm_json_format_short(dx, lo, sizeof lo), has_res ? " from the resolution" : "");
      mpm_json_range r = mpm_json_gt(s->domain_min[d] + 8.0 * dx, note);
      char want[400], got[40];
      return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected %s, got %s",
                              mpm_json_describe_range(&r, 0, want, sizeof want),
                              mpm_json_format_number(s->domain_max[d], got, sizeof got));
    }
  if (parse_walls(c, dom, s) < 0) return -1;
  for (int d = 0; d < 3; ++d)
    if (!(extent[d] > 2.0 * s->wall_cells * dx)) {
      char band[40], ext[40], dxs[40];
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "expected every axis to be longer than the two wall bands (2 * %d "
                           "cells * %s m = %s m), got %s m along %c",
                           s->wall_cells, mpm_json_format_short(dx, dxs, sizeof dxs),
                           mpm_json_format_short(2.0 * s->wall_cells * dx, band, sizeof band),
                           mpm_json_format_short(extent[d], ext, sizeof ext), AXIS_NAME[d]);
    }
  mpm_json_pop(c, old);
  return 0;
}

static int parse_time(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *t = mpm_json_get(root, "time");
  if (!t) return mpm_json_missing(c, "time");
  size_t old = mpm_json_push_key(c, "time");
  if (mpm_json_expect_object(c, t, "an object with keys end and fps") < 0 ||
      mpm_json_check_keys(c, t, TIME_KEYS, NULL) < 0 ||
      mpm_json_number(c, t, "end", 1, mpm_json_gt(0, "s"), &s->end_time) < 0 ||
      mpm_json_number(c, t, "fps", 0, mpm_json_gt(0, "frames per second"), &s->fps) < 0)
    return -1;
  if (s->end_time * s->fps > MAX_FRAMES) {
    char n[40];
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected at most 10000000 frames (end * fps), got %s",
                         mpm_json_format_short(s->end_time * s->fps, n, sizeof n));
  }
  mpm_json_pop(c, old);
  return 0;
}

static int parse_solver(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *sv = mpm_json_get(root, "solver");
  if (!sv) return 0;
  size_t old = mpm_json_push_key(c, "solver");
  mpm_solver_desc *d = &s->solver;
  int kernel = (int)d->kernel, transfer = (int)d->transfer, grid = (int)d->grid;
  if (mpm_json_expect_object(c, sv, "an object of solver options") < 0 ||
      mpm_json_check_keys(c, sv, SOLVER_KEYS, NULL) < 0 ||
      mpm_json_enum(c, sv, "kernel", 0, KERNEL_NAMES, &kernel) < 0 ||
      mpm_json_enum(c, sv, "transfer", 0, TRANSFER_NAMES, &transfer) < 0 ||
      mpm_json_number(c, sv, "flip_alpha", 0, mpm_json_in('[', 0, 1, ']', NULL), &d->flip_alpha) <
          0 ||
      mpm_json_number(c, sv, "cfl", 0, mpm_json_in('(', 0, 1, ']', NULL), &d->cfl) < 0 ||
      mpm_json_number(c, sv, "max_dt", 0, mpm_json_ge(0, "s, 0 = no limit"), &d->max_dt) < 0 ||
      mpm_json_enum(c, sv, "grid", 0, GRID_NAMES, &grid) < 0 ||
      mpm_json_number(c, sv, "gimp_length", 0,
                      mpm_json_in('[', 0, s->dx, ']', "m, at most dx; 0 = automatic"),
                      &d->gimp_length) < 0)
    return -1;
  d->kernel = (mpm_kernel_kind)kernel;
  d->transfer = (mpm_transfer_kind)transfer;
  d->grid = (mpm_grid_kind)grid;
  mpm_json_pop(c, old);
  return 0;
}

static int parse_output(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *o = mpm_json_get(root, "output");
  if (!o) return 0;
  size_t old = mpm_json_push_key(c, "output");
  if (mpm_json_expect_object(c, o, "an object with keys directory, vtu, ply, stats") < 0 ||
      mpm_json_check_keys(c, o, OUTPUT_KEYS, NULL) < 0 ||
      mpm_json_string(c, o, "directory", 0, s->output.directory, sizeof s->output.directory) < 0 ||
      mpm_json_bool(c, o, "vtu", 0, &s->output.vtu) < 0 ||
      mpm_json_bool(c, o, "ply", 0, &s->output.ply) < 0 ||
      mpm_json_bool(c, o, "stats", 0, &s->output.stats) < 0)
    return -1;
  mpm_json_pop(c, old);
  return 0;
}

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
                      &m->hardening) < 0)
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

static int parse_materials(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  if (get_array(c, root, "materials", 1, "an array of material objects", &arr) < 0) return -1;
  const cJSON *bodies = mpm_json_get(root, "bodies");
  int n = cJSON_GetArraySize(arr);
  int extra = cJSON_IsArray(bodies) ? cJSON_GetArraySize(bodies) : 0; /* inline materials */
  s->materials = malloc((size_t)(n + extra + 1) * sizeof *s->materials);
  if (!s->materials) return fail_nomem(c, "materials");
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
static int parse_body_material(mpm_json_ctx *c, const cJSON *body, int named, mpm_scene *s,
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

/* ---- shapes --------------------------------------------------------------------------- */

/* Bounding box of a mesh body: the mesh's box scaled about its centre, moved to `center`. */
static int mesh_bounds(mpm_json_ctx *c, mpm_shape_desc *sh, double lo[3], double hi[3], char *note,
                       size_t note_cap) {
  FILE *f = fopen(sh->mesh_path, "rb");
  if (!f) {
    int e = errno;
    return mpm_json_fail_at(c, "file", MPM_ERR_IO, "cannot open mesh file '%s': %s", sh->mesh_path,
                            strerror(e));
  }
  errno = 0;
  (void)fgetc(f);
  int bad = ferror(f), e = errno;
  fclose(f);
  if (bad)
    return mpm_json_fail_at(c, "file", MPM_ERR_IO, "cannot read mesh file '%s': %s", sh->mesh_path,
                            strerror(e ? e : EIO));
  mpm_mesh mesh;
  memset(&mesh, 0, sizeof mesh);
  mpm_error merr;
  mpm_error_clear(&merr);
  mpm_status st = mpm_mesh_load(sh->mesh_path, &mesh, &merr);
  if (st != MPM_OK)
    return mpm_json_fail_at(c, "file", st, "cannot use mesh file '%s': %s", sh->mesh_path,
                            merr.message);
  double mlo[3], mhi[3];
  mpm_mesh_bounds(&mesh, mlo, mhi);
  mpm_mesh_free(&mesh);
  char ex[3][40], sc[40];
  for (int d = 0; d < 3; ++d) mpm_json_format_short(mhi[d] - mlo[d], ex[d], sizeof ex[d]);
  snprintf(note, note_cap, " (the mesh is %s x %s x %s in file units, times scale %s)", ex[0],
           ex[1], ex[2], mpm_json_format_short(sh->mesh_scale, sc, sizeof sc));
  for (int d = 0; d < 3; ++d) {
    double half = 0.5 * sh->mesh_scale * (mhi[d] - mlo[d]);
    lo[d] = sh->center[d] - half;
    hi[d] = sh->center[d] + half;
  }
  return 0;
}

/* obj.shape at the current path (for_body: bodies allow meshes, colliders half-spaces).
 * scene_path resolves mesh files. */
static int parse_shape(mpm_json_ctx *c, const cJSON *parent, int for_body, const char *scene_path,
                       mpm_shape_desc *sh) {
  const cJSON *n = mpm_json_get(parent, "shape");
  if (!n) return mpm_json_missing(c, "shape");
  size_t old = mpm_json_push_key(c, "shape");
  const char *const *names = for_body ? BODY_SHAPE_NAMES : COLLIDER_SHAPE_NAMES;
  const mpm_shape_kind *kinds = for_body ? BODY_SHAPE_KINDS : COLLIDER_SHAPE_KINDS;
  if (mpm_json_expect_object(c, n, "a shape object with a 'type'") < 0) return -1;
  const cJSON *type = mpm_json_get(n, "type");
  if (!type)
    return mpm_json_fail(c, MPM_ERR_INVALID, "missing required key 'type' (one of %s)",
                         for_body ? "box, sphere, cylinder, mesh"
                                  : "box, sphere, cylinder, halfspace");
  if (cJSON_IsString(type) && type->valuestring) {
    if (!for_body && strcmp(type->valuestring, "mesh") == 0)
      return mpm_json_fail_at(c, "type", MPM_ERR_INVALID,
                              "expected one of box, sphere, cylinder, halfspace, got 'mesh' "
                              "(meshes can only be bodies)");
    if (for_body && strcmp(type->valuestring, "halfspace") == 0)
      return mpm_json_fail_at(c, "type", MPM_ERR_INVALID,
                              "expected one of box, sphere, cylinder, mesh, got 'halfspace' "
                              "(a half-space is infinite; it can only be a collider)");
  }
  int t = 0;
  if (mpm_json_enum(c, n, "type", 1, names, &t) < 0) return -1;
  sh->kind = kinds[t];
  const mpm_json_range any_m = mpm_json_any("m"), pos_m = mpm_json_gt(0, "m");
  switch (sh->kind) {
  case MPM_SHAPE_BOX:
    if (mpm_json_check_keys(c, n, BOX_KEYS, "for a box shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_vec3(c, n, "half_extent", 1, pos_m, sh->half_extent) < 0)
      return -1;
    break;
  case MPM_SHAPE_SPHERE:
    if (mpm_json_check_keys(c, n, SPHERE_KEYS, "for a sphere shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "radius", 1, pos_m, &sh->radius) < 0)
      return -1;
    break;
  case MPM_SHAPE_CYLINDER:
    if (mpm_json_check_keys(c, n, CYLINDER_KEYS, "for a cylinder shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "radius", 1, pos_m, &sh->radius) < 0 ||
        mpm_json_direction(c, n, "axis", 0, sh->axis) < 0)
      return -1;
    if (for_body ? mpm_json_number(c, n, "half_height", 1, pos_m, &sh->half_height) < 0
                 : mpm_json_number(c, n, "half_height", 0, mpm_json_ge(0, "m, 0 = infinite"),
                                   &sh->half_height) < 0)
      return -1;
    break;
  case MPM_SHAPE_MESH: {
    char file[MPM_PATH_MAX];
    if (mpm_json_check_keys(c, n, MESH_KEYS, "for a mesh shape") < 0 ||
        mpm_json_string(c, n, "file", 1, file, sizeof file) < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "scale", 0, mpm_json_gt(0, "factor"), &sh->mesh_scale) < 0)
      return -1;
    if (resolve_path(scene_path, file, sh->mesh_path, sizeof sh->mesh_path) < 0)
      return mpm_json_fail_at(c, "file", MPM_ERR_INVALID,
                              "expected a path of at most %d bytes once resolved against the "
                              "scene file's directory, got a longer one",
                              MPM_PATH_MAX - 1);
    break;
  }
  case MPM_SHAPE_HALFSPACE:
    if (mpm_json_check_keys(c, n, HALFSPACE_KEYS, "for a halfspace shape") < 0 ||
        mpm_json_vec3(c, n, "point", 1, any_m, sh->center) < 0 ||
        mpm_json_direction(c, n, "normal", 1, sh->axis) < 0)
      return -1;
    break;
  }
  mpm_json_pop(c, old);
  return 0;
}

/* Axis-aligned bounding box of a box, sphere or cylinder. */
static void shape_bounds(const mpm_shape_desc *sh, double lo[3], double hi[3]) {
  for (int d = 0; d < 3; ++d) {
    double h = 0;
    if (sh->kind == MPM_SHAPE_BOX) h = sh->half_extent[d];
    if (sh->kind == MPM_SHAPE_SPHERE) h = sh->radius;
    if (sh->kind == MPM_SHAPE_CYLINDER) {
      double a = sh->axis[d];
      h = sh->half_height * fabs(a) + sh->radius * sqrt(fmax(0.0, 1.0 - a * a));
    }
    lo[d] = sh->center[d] - h;
    hi[d] = sh->center[d] + h;
  }
}

/* The body's bounding box must lie inside the domain minus the wall band; the current path
 * is the body. */
static int check_inside(mpm_json_ctx *c, const mpm_scene *s, const double lo[3], const double hi[3],
                        const char *note) {
  double blo[3], bhi[3], longest = 0;
  for (int d = 0; d < 3; ++d) {
    blo[d] = s->domain_min[d] + s->wall_cells * s->dx;
    bhi[d] = s->domain_max[d] - s->wall_cells * s->dx;
    longest = fmax(longest, s->domain_max[d] - s->domain_min[d]);
  }
  const double tol = 1e-9 * longest;
  char out[400], num[40];
  size_t o = 0;
  out[0] = '\0';
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      double over = side ? hi[d] - bhi[d] : blo[d] - lo[d];
      if (!(over > tol)) continue;
      int w =
          snprintf(out + o, sizeof out - o, "%s%s m on %c%c", o ? ", " : "",
                   mpm_json_format_short(over, num, sizeof num), side ? '+' : '-', AXIS_NAME[d]);
      if (w > 0 && (size_t)w < sizeof out - o) o += (size_t)w;
    }
  if (o == 0) return 0;
  char a[128], b[128], la[128], lb[128], dxs[40];
  return mpm_json_fail_at(
      c, "shape", MPM_ERR_INVALID,
      "expected the body's bounding box to lie inside the domain minus the wall band of %d "
      "cells of %s m, i.e. inside %s .. %s m, got %s .. %s m%s: it sticks out by %s",
      s->wall_cells, mpm_json_format_short(s->dx, dxs, sizeof dxs), format_vec3(blo, la, sizeof la),
      format_vec3(bhi, lb, sizeof lb), format_vec3(lo, a, sizeof a), format_vec3(hi, b, sizeof b),
      note, out);
}

/* ---- bodies --------------------------------------------------------------------------- */

static int parse_body(mpm_json_ctx *c, const cJSON *node, int index, int named, mpm_scene *s,
                      mpm_body_desc *b) {
  if (mpm_json_expect_object(c, node, "a body object") < 0 ||
      mpm_json_check_keys(c, node, BODY_KEYS, NULL) < 0)
    return -1;
  snprintf(b->name, sizeof b->name, "body%d", index);
  long long seed = b->seed;
  if (mpm_json_string(c, node, "name", 0, b->name, sizeof b->name) < 0 ||
      parse_shape(c, node, 1, s->path, &b->shape) < 0 ||
      parse_body_material(c, node, named, s, b) < 0 ||
      mpm_json_vec3(c, node, "velocity", 0, mpm_json_any("m/s"), b->velocity) < 0 ||
      mpm_json_vec3(c, node, "angular_velocity", 0, mpm_json_any("rad/s"), b->angular_velocity) <
          0 ||
      mpm_json_number(c, node, "particles_per_cell", 0,
                      mpm_json_in('(', 0, 1000, ']', "particles per grid cell"),
                      &b->particles_per_cell) < 0 ||
      mpm_json_number(c, node, "jitter", 0,
                      mpm_json_in('[', 0, 1, ']', "fraction of the particle spacing"),
                      &b->jitter) < 0 ||
      mpm_json_integer(c, node, "seed", 0, mpm_json_in('[', 0, 4294967295.0, ']', NULL), &seed) < 0)
    return -1;
  b->seed = (unsigned)seed;
  double lo[3], hi[3];
  char note[200] = "";
  if (b->shape.kind == MPM_SHAPE_MESH) {
    size_t old = mpm_json_push_key(c, "shape");
    if (mesh_bounds(c, &b->shape, lo, hi, note, sizeof note) < 0) return -1;
    mpm_json_pop(c, old);
  } else {
    shape_bounds(&b->shape, lo, hi);
  }
  return check_inside(c, s, lo, hi, note);
}

static int parse_bodies(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  if (get_array(c, root, "bodies", 1, "an array of body objects", &arr) < 0) return -1;
  int n = cJSON_GetArraySize(arr);
  if (n == 0)
    return mpm_json_fail_at(c, "bodies", MPM_ERR_INVALID,
                            "expected at least one body, got an empty array");
  s->bodies = malloc((size_t)n * sizeof *s->bodies);
  if (!s->bodies) return fail_nomem(c, "bodies");
  const int named = s->material_count;
  size_t old = mpm_json_push_key(c, "bodies");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_body_desc b = mpm_body_desc_default();
    if (parse_body(c, e, i, named, s, &b) < 0) return -1;
    s->bodies[s->body_count++] = b;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

/* ---- colliders ------------------------------------------------------------------------ */

static int parse_keyframes(mpm_json_ctx *c, const cJSON *arr, mpm_motion_desc *m) {
  int n = cJSON_GetArraySize(arr);
  if (n == 0) return 0;
  m->keyframes = malloc((size_t)n * sizeof *m->keyframes);
  if (!m->keyframes) return fail_nomem(c, "keyframes");
  size_t old = mpm_json_push_key(c, "keyframes");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_keyframe k;
    memset(&k, 0, sizeof k);
    char note[64];
    snprintf(note, sizeof note, "s, later than keyframes[%d].time", i - 1);
    mpm_json_range tr = i == 0 ? mpm_json_ge(0, "s") : mpm_json_gt(m->keyframes[i - 1].time, note);
    if (mpm_json_expect_object(c, e, "a keyframe object with keys time, translation, angle") < 0 ||
        mpm_json_check_keys(c, e, KEYFRAME_KEYS, NULL) < 0 ||
        mpm_json_number(c, e, "time", 1, tr, &k.time) < 0 ||
        mpm_json_vec3(c, e, "translation", 0, mpm_json_any("m"), k.translation) < 0 ||
        mpm_json_number(c, e, "angle", 0, mpm_json_any("rad"), &k.angle) < 0)
      return -1;
    m->keyframes[m->keyframe_count++] = k;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

static int parse_motion(mpm_json_ctx *c, const cJSON *collider, mpm_motion_desc *m) {
  const cJSON *n = mpm_json_get(collider, "motion");
  if (!n) return 0;
  size_t old = mpm_json_push_key(c, "motion");
  if (mpm_json_expect_object(c, n, "a motion object") < 0 ||
      mpm_json_check_keys(c, n, MOTION_KEYS, NULL) < 0)
    return -1;
  int has_v = mpm_json_vec3(c, n, "velocity", 0, mpm_json_any("m/s"), m->velocity);
  if (has_v < 0 || mpm_json_direction(c, n, "axis", 0, m->axis) < 0) return -1;
  int has_w = mpm_json_number(c, n, "angular_speed", 0, mpm_json_any("rad/s"), &m->angular_speed);
  if (has_w < 0) return -1;
  const cJSON *kf = NULL;
  int has_k = get_array(c, n, "keyframes", 0, "an array of keyframe objects", &kf);
  if (has_k < 0) return -1;
  if (has_k && cJSON_GetArraySize(kf) > 0 && (has_v || has_w))
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected either 'keyframes' or 'velocity'/'angular_speed', got both "
                         "(with keyframes the motion follows them alone)");
  if (has_k && parse_keyframes(c, kf, m) < 0) return -1;
  mpm_json_pop(c, old);
  return 0;
}

static int parse_colliders(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  int has = get_array(c, root, "colliders", 0, "an array of collider objects", &arr);
  if (has <= 0) return has;
  int n = cJSON_GetArraySize(arr);
  if (n == 0) return 0;
  s->colliders = malloc((size_t)n * sizeof *s->colliders);
  if (!s->colliders) return fail_nomem(c, "colliders");
  size_t old = mpm_json_push_key(c, "colliders");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    /* counted before parsing so that mpm_scene_free releases its keyframes on error */
    mpm_collider_desc *d = &s->colliders[s->collider_count++];
    *d = mpm_collider_desc_default();
    snprintf(d->name, sizeof d->name, "collider%d", i);
    int rule = (int)d->rule;
    if (mpm_json_expect_object(c, e, "a collider object") < 0 ||
        mpm_json_check_keys(c, e, COLLIDER_KEYS, NULL) < 0 ||
        mpm_json_string(c, e, "name", 0, d->name, sizeof d->name) < 0 ||
        parse_shape(c, e, 0, s->path, &d->shape) < 0 ||
        mpm_json_bool(c, e, "inside_out", 0, &d->inside_out) < 0 ||
        mpm_json_enum(c, e, "rule", 0, RULE_NAMES, &rule) < 0 ||
        mpm_json_number(c, e, "friction", 0, mpm_json_ge(0, "Coulomb coefficient"), &d->friction) <
            0 ||
        parse_motion(c, e, &d->motion) < 0)
      return -1;
    d->rule = (mpm_boundary_rule)rule;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

/* ---- the whole file ------------------------------------------------------------------- */

/* Default name: the file name without directory and extension. */
static void stem_of(const char *path, char *out, size_t cap) {
  const char *base = strrchr(path, '/');
  base = base ? base + 1 : path;
  const char *dot = strrchr(base, '.');
  size_t n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
  if (n == 0) {
    snprintf(out, cap, "scene");
    return;
  }
  if (n >= cap) n = cap - 1;
  memcpy(out, base, n);
  out[n] = '\0';
}

static int parse_root(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  if (mpm_json_expect_object(c, root, "a JSON object ({ ... }) at the top level") < 0 ||
      mpm_json_check_keys(c, root, TOP_KEYS, NULL) < 0 ||
      mpm_json_string(c, root, "name", 0, s->name, sizeof s->name) < 0 ||
      parse_domain(c, root, s) < 0 ||
      mpm_json_vec3(c, root, "gravity", 0, mpm_json_any("m/s^2"), s->gravity) < 0 ||
      parse_time(c, root, s) < 0 || parse_solver(c, root, s) < 0 ||
      parse_materials(c, root, s) < 0 || parse_bodies(c, root, s) < 0 ||
      parse_colliders(c, root, s) < 0 || parse_output(c, root, s) < 0)
    return -1;
  return 0;
}

mpm_status mpm_scene_parse(const char *json_text, const char *path_for_messages, mpm_scene *scene,
                           mpm_error *err) {
  const char *file = path_for_messages ? path_for_messages : "<scene>";
  mpm_error local;
  mpm_error_clear(&local);
  mpm_json_ctx ctx;
  mpm_json_ctx_init(&ctx, file, &local);
  mpm_scene_default(scene);
  if (!json_text) json_text = "";
  if (strlen(file) >= sizeof scene->path) {
    mpm_error_set(&local, MPM_ERR_INVALID, "%.100s...: the scene path is longer than %d bytes",
                  file, MPM_PATH_MAX - 1);
  } else {
    snprintf(scene->path, sizeof scene->path, "%s", path_for_messages ? file : "");
    if (path_for_messages) stem_of(file, scene->name, sizeof scene->name);
    size_t len = strlen(json_text);
    if (mpm_json_check_syntax(&ctx, json_text, len) == 0) {
      const char *end = NULL;
      cJSON *root = cJSON_ParseWithLengthOpts(json_text, len + 1, &end, 1);
      if (!root)
        mpm_json_syntax_error(&ctx, json_text, len, end);
      else
        parse_root(&ctx, root, scene);
      cJSON_Delete(root);
    }
  }
  if (local.status != MPM_OK) {
    mpm_scene_free(scene);
    mpm_scene_default(scene);
  }
  if (err) *err = local;
  return local.status;
}

mpm_status mpm_scene_load(const char *path, mpm_scene *scene, mpm_error *err) {
  mpm_scene_default(scene);
  if (!path || !path[0])
    return mpm_error_set(err, MPM_ERR_IO, "cannot read a scene file: no path given");
  FILE *f = fopen(path, "rb");
  if (!f) {
    int e = errno;
    return mpm_error_set(err, MPM_ERR_IO, "%s: cannot open the scene file: %s", path, strerror(e));
  }
  size_t cap = 1 << 16, len = 0;
  char *buf = malloc(cap);
  int read_errno = 0;
  while (buf) {
    if (len + 1 >= cap) {
      char *bigger = realloc(buf, cap * 2);
      if (!bigger) {
        free(buf);
        buf = NULL;
        break;
      }
      buf = bigger;
      cap *= 2;
    }
    errno = 0;
    size_t got = fread(buf + len, 1, cap - 1 - len, f);
    len += got;
    if (got == 0) {
      if (ferror(f)) read_errno = errno ? errno : EIO;
      break;
    }
  }
  fclose(f);
  if (!buf)
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory reading the scene file", path);
  if (read_errno) {
    free(buf);
    return mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the scene file: %s", path,
                         strerror(read_errno));
  }
  buf[len] = '\0';
  const char *nul = memchr(buf, '\0', len);
  if (nul) {
    int line = 1, col = 1;
    for (const char *p = buf; p < nul; ++p) {
      if (*p == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    free(buf);
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: line %d, column %d: expected JSON text, got a NUL byte (is this a "
                         "binary file?)",
                         path, line, col);
  }
  mpm_status st = mpm_scene_parse(buf, path, scene, err);
  free(buf);
  return st;
}
