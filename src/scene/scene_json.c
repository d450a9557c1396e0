/* scene_json.c - the JSON scene format: reading a scene file, parsing it with cJSON and
 * checking every key into the descriptor structs of scene.h.
 *
 * The format is documented key by key in docs/scene-format.md. Checking is strict: unknown
 * and duplicate keys, wrong types, out-of-range and non-finite numbers, unknown enum values
 * and material names, material keys of another model (they would have no effect), bodies that
 * leave the usable domain and unreadable mesh files are all errors whose message starts with
 * the file and the key path ("bodies[2].material.E") and says what was expected and what was
 * found. The typed getters live in json_check.c.
 * On any error the scene is left empty (arrays freed, defaults filled).
 *
 * This file holds the entry points (mpm_scene_parse, mpm_scene_load), the top level, the
 * domain, time, solver and output objects, and the tables and helpers the other parts share;
 * materials are checked in scene_json_material.c, shapes, bodies and colliders in
 * scene_json_shape.c (shared declarations: scene_json_parts.h). */
#include "core/hash.h"
#include "core/alloc.h"
#include "core/real.h"
#include "io/input_file.h"
#include "scene/json_check.h"
#include "scene/scene.h"
#include "scene/scene_json_parts.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Grid coordinates must stay well inside the sparse grid's block keys and an int. */
#define MAX_CELLS_PER_AXIS (1 << 20)
/* A scene is a small text: anything larger is a mistake (a mesh or a device given as scene). */
#define SCENE_MAX_BYTES (64 << 20)
/* The simulation keeps per-frame records. */
#define MAX_FRAMES 10000000.0

static const char *const TOP_KEYS[] = {"name",      "domain", "gravity",   "time",   "solver",
                                       "materials", "bodies", "colliders", "forces", "output",
                                       "camera",    "heat",   NULL};
static const char *const DOMAIN_KEYS[] = {"min",    "max",    "dx",       "resolution",   "walls",
                                          "levels", "refine", "resample", "refine_every", NULL};
static const char *const WALL_KEYS[] = {"rule", "friction", "cells", NULL};
static const char *const TIME_KEYS[] = {"end", "fps", NULL};
static const char *const SOLVER_KEYS[] = {
    "kernel", "transfer", "flip_alpha", "cfl", "max_dt", "grid", "gimp_length", "on_instability",
    "max_retries", "domain_kernel",
    /* implicit integration */
    "integrator", "dt", "newton_iterations", "cg_tolerance", "cg_max_iterations", "on_cg_failure",
    "preconditioner", "scheme", NULL};
/* The keys that only the implicit integrator reads. */
static const char *const IMPLICIT_KEYS[] = {"dt",
                                            "newton_iterations",
                                            "cg_tolerance",
                                            "cg_max_iterations",
                                            "on_cg_failure",
                                            "preconditioner",
                                            "scheme",
                                            NULL};
static const char *const OUTPUT_KEYS[] = {"directory",        "vtu",     "ply", "stats",
                                          "checkpoint_every", "surface", "vdb", "vdb_density",
                                          "vdb_velocity",     "fields",  NULL};
static const char *const CAMERA_KEYS[] = {"eye", "target", "fov", NULL};

/* Enum spellings, in the order of the enum values of scene.h. */
const char *const mpm_sj_rule_names[] = {"sticky", "slip", "separate", NULL};
static const char *const KERNEL_NAMES[] = {"linear", "quadratic", "cubic", "ugimp", NULL};
static const char *const TRANSFER_NAMES[] = {"apic", "flip", NULL};
static const char *const GRID_NAMES[] = {"sparse", "dense", NULL};
static const char *const INSTABILITY_NAMES[] = {"stop", "retry", NULL};
static const char *const DOMAIN_KERNEL_NAMES[] = {"linear", "quadratic", "cubic", NULL};
static const char *const INTEGRATOR_NAMES[] = {"explicit", "implicit", NULL};
static const char *const CG_FAILURE_NAMES[] = {"warn", "stop", NULL};
static const char *const PRECONDITIONER_NAMES[] = {"jacobi", "multigrid", NULL};
static const char *const SCHEME_NAMES[] = {"backward_euler", "newmark", NULL};

const char mpm_sj_axis_name[3] = {'x', 'y', 'z'};

/* ---- small helpers -------------------------------------------------------------------- */

int mpm_sj_fail_nomem(mpm_json_ctx *c, const char *what) {
  return mpm_json_fail(c, MPM_ERR_NOMEM, "out of memory allocating %s", what);
}

/* The array at obj[key] (required or not); 0 absent, 1 present, -1 wrong type. */
int mpm_sj_get_array(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
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

/* ---- domain, time, solver, output ----------------------------------------------------- */

int mpm_sj_parse_schedule(mpm_json_ctx *c, const cJSON *node, const char *key,
                          double keys[MPM_STRENGTH_KEYS][2], int *count) {
  const cJSON *a = mpm_json_get(node, key);
  if (!a) return 0;
  char buf[64];
  const int n = cJSON_IsArray(a) ? cJSON_GetArraySize(a) : 0;
  if (n < 1 || n > MPM_STRENGTH_KEYS)
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID,
                            "expected an array of 1 to %d [time, factor] keyframes, got %s",
                            MPM_STRENGTH_KEYS, mpm_json_describe(a, buf, sizeof buf));
  size_t old = mpm_json_push_key(c, key);
  int k = 0;
  for (const cJSON *e = a->child; e; e = e->next, ++k) {
    const int ok = cJSON_IsArray(e) && cJSON_GetArraySize(e) == 2 && cJSON_IsNumber(e->child) &&
                   cJSON_IsNumber(e->child->next);
    const double t = ok ? e->child->valuedouble : 0, f = ok ? e->child->next->valuedouble : 0;
    size_t o2 = mpm_json_push_index(c, k);
    if (!ok)
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected [time, factor] (two numbers), got %s",
                           mpm_json_describe(e, buf, sizeof buf));
    if (!isfinite(t) || t < 0 || (k > 0 && !(t > keys[k - 1][0])))
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "expected a time >= 0 (s) after the previous keyframe's, got %g", t);
    if (!isfinite(f) || f < 0 || f > 1e6)
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected a factor from 0 to 1e6, got %g", f);
    keys[k][0] = t;
    keys[k][1] = f;
    mpm_json_pop(c, o2);
  }
  *count = n;
  mpm_json_pop(c, old);
  return 0;
}

static int parse_walls(mpm_json_ctx *c, const cJSON *domain, mpm_scene *s) {
  const cJSON *w = mpm_json_get(domain, "walls");
  if (!w) return 0;
  size_t old = mpm_json_push_key(c, "walls");
  if (mpm_json_expect_object(c, w, "an object with keys rule, friction, cells") < 0 ||
      mpm_json_check_keys(c, w, WALL_KEYS, NULL) < 0)
    return -1;
  int rule = (int)s->wall_rule;
  long long cells = s->wall_cells;
  if (mpm_json_enum(c, w, "rule", 0, mpm_sj_rule_names, &rule) < 0 ||
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
  if (mpm_json_vec3(c, dom, "min", 1, mpm_json_any("m"), s->box_min) < 0 ||
      mpm_json_vec3(c, dom, "max", 1, mpm_json_any("m"), s->box_max) < 0)
    return -1;
  char key[16], note[160], lo[40];
  for (int d = 0; d < 3; ++d)
    if (!(s->box_max[d] > s->box_min[d])) {
      snprintf(key, sizeof key, "max[%d]", d);
      snprintf(note, sizeof note, "m, greater than min[%d]", d);
      char want[256], got[40];
      mpm_json_range r = mpm_json_gt(s->box_min[d], note);
      return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected %s, got %s",
                              mpm_json_describe_range(&r, 0, want, sizeof want),
                              mpm_json_format_number(s->box_max[d], got, sizeof got));
    }
  double extent[3], longest = 0;
  for (int d = 0; d < 3; ++d) {
    extent[d] = s->box_max[d] - s->box_min[d];
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
  /* the float build holds positions to the spacing of floats near them: far from the origin
     that spacing outgrows the particles' (a domain at 1e7 m with dx = 5 cm put 912 particles
     on 8 points) */
  if (sizeof(mpm_real) == 4)
    for (int e = 0; e < 6; ++e) {
      const double x = e < 3 ? s->box_min[e] : s->box_max[e - 3];
      const float xf = (float)fabs(x);
      const double spacing = (double)nextafterf(xf, INFINITY) - (double)xf;
      if (spacing > dx / 8) {
        char got[40], sp[40], lim[40];
        snprintf(key, sizeof key, "%s[%d]", e < 3 ? "min" : "max", e % 3);
        return mpm_json_fail_at(
            c, key, MPM_ERR_INVALID,
            "%s m is too far from the origin for the float build: floats there are %s m apart, "
            "more than dx / 8 = %s m, so particles would share positions; move the scene near "
            "the origin, or use the double build (make build-double)",
            mpm_json_format_number(x, got, sizeof got),
            mpm_json_format_short(spacing, sp, sizeof sp),
            mpm_json_format_short(dx / 8, lim, sizeof lim));
      }
    }
  for (int d = 0; d < 3; ++d)
    if (!(extent[d] > 8.0 * dx)) {
      snprintf(key, sizeof key, "max[%d]", d);
      snprintf(note, sizeof note,
               "m: min[%d] + 8*dx with dx = %s m%s; the domain must be "
               "more than 8 cells wide on every axis",
               d, mpm_json_format_short(dx, lo, sizeof lo), has_res ? " from the resolution" : "");
      mpm_json_range r = mpm_json_gt(s->box_min[d] + 8.0 * dx, note);
      char want[400], got[40];
      return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected %s, got %s",
                              mpm_json_describe_range(&r, 0, want, sizeof want),
                              mpm_json_format_number(s->box_max[d], got, sizeof got));
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
                           mpm_json_format_short(extent[d], ext, sizeof ext), mpm_sj_axis_name[d]);
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
  int on_instability = (int)d->on_instability;
  long long retries = d->max_retries;
  int domain_kernel = (int)d->domain_kernel;
  int integrator = (int)d->integrator, on_cg_failure = (int)d->on_cg_failure;
  int preconditioner = (int)d->preconditioner, scheme = (int)d->scheme;
  long long newton = d->newton_iterations, cg_max = d->cg_max_iterations;
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
                      mpm_json_in('[', 0, 2 * s->dx, ']', "m, at most 2 dx; 0 = automatic"),
                      &d->gimp_length) < 0 ||
      mpm_json_enum(c, sv, "on_instability", 0, INSTABILITY_NAMES, &on_instability) < 0 ||
      mpm_json_integer(c, sv, "max_retries", 0, mpm_json_in('[', 1, 30, ']', "halvings of dt"),
                       &retries) < 0 ||
      mpm_json_enum(c, sv, "domain_kernel", 0, DOMAIN_KERNEL_NAMES, &domain_kernel) < 0 ||
      mpm_json_enum(c, sv, "integrator", 0, INTEGRATOR_NAMES, &integrator) < 0)
    return -1;
  if (integrator != MPM_INTEGRATOR_IMPLICIT) {
    for (int k = 0; IMPLICIT_KEYS[k]; ++k)
      if (mpm_json_get(sv, IMPLICIT_KEYS[k]))
        return mpm_json_fail_at(c, IMPLICIT_KEYS[k], MPM_ERR_INVALID,
                                "a key of the implicit integrator only; set solver.integrator "
                                "to \"implicit\" or remove it");
  }
  if (mpm_json_number(c, sv, "dt", 0, mpm_json_ge(0, "s, 0 = CFL on particle speed"), &d->dt) < 0 ||
      mpm_json_integer(c, sv, "newton_iterations", 0,
                       mpm_json_in('[', 1, 100, ']', "1 = one linearized step"), &newton) < 0 ||
      mpm_json_number(c, sv, "cg_tolerance", 0, mpm_json_in('(', 0, 1, ')', "relative residual"),
                      &d->cg_tolerance) < 0 ||
      mpm_json_integer(c, sv, "cg_max_iterations", 0, mpm_json_in('[', 1, 100000, ']', NULL),
                       &cg_max) < 0 ||
      mpm_json_enum(c, sv, "on_cg_failure", 0, CG_FAILURE_NAMES, &on_cg_failure) < 0 ||
      mpm_json_enum(c, sv, "preconditioner", 0, PRECONDITIONER_NAMES, &preconditioner) < 0 ||
      mpm_json_enum(c, sv, "scheme", 0, SCHEME_NAMES, &scheme) < 0)
    return -1;
  d->scheme = (mpm_scheme_kind)scheme;
  d->integrator = (mpm_integrator_kind)integrator;
  d->on_cg_failure = (mpm_cg_failure_action)on_cg_failure;
  d->preconditioner = (mpm_preconditioner_kind)preconditioner;
  d->newton_iterations = (int)newton;
  d->cg_max_iterations = (int)cg_max;
  d->max_retries = (int)retries;
  d->domain_kernel = (mpm_kernel_kind)domain_kernel;
  d->on_instability = (mpm_instability_action)on_instability;
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
  long long every = s->output.checkpoint_every;
  if (mpm_json_expect_object(
          c, o,
          "an object with keys directory, vtu, ply, stats, checkpoint_every, surface, vdb, "
          "vdb_density, vdb_velocity, fields") < 0 ||
      mpm_json_check_keys(c, o, OUTPUT_KEYS, NULL) < 0 ||
      mpm_json_string(c, o, "directory", 0, s->output.directory, sizeof s->output.directory) < 0 ||
      mpm_json_bool(c, o, "vtu", 0, &s->output.vtu) < 0 ||
      mpm_json_bool(c, o, "ply", 0, &s->output.ply) < 0 ||
      mpm_json_bool(c, o, "stats", 0, &s->output.stats) < 0 ||
      mpm_json_integer(c, o, "checkpoint_every", 0,
                       mpm_json_in('[', 0, 1000000, ']', "frames, 0 = only on a signal"),
                       &every) < 0 ||
      mpm_sj_parse_surface(c, o, s) < 0 || mpm_json_bool(c, o, "vdb", 0, &s->output.vdb) < 0 ||
      mpm_json_bool(c, o, "vdb_density", 0, &s->output.vdb_density) < 0 ||
      mpm_json_bool(c, o, "vdb_velocity", 0, &s->output.vdb_velocity) < 0 ||
      mpm_sj_parse_fields(c, o, s) < 0)
    return -1;
  if ((s->output.vdb || s->output.vdb_density || s->output.vdb_velocity) &&
      !s->output.surface.enabled)
    return mpm_json_fail_at(c,
                            s->output.vdb           ? "vdb"
                            : s->output.vdb_density ? "vdb_density"
                                                    : "vdb_velocity",
                            MPM_ERR_INVALID,
                            "expected output.surface too (the .vdb holds the surface's level set)");
  /* the density and velocity grids go into the level set's file: either asks for it */
  if (s->output.vdb_density || s->output.vdb_velocity) s->output.vdb = 1;
  s->output.checkpoint_every = (int)every;
  mpm_json_pop(c, old);
  return 0;
}

/* camera: {"eye": [x, y, z], "target": [x, y, z], "fov": degrees} for `mpm render`. */
static int parse_camera(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *o = mpm_json_get(root, "camera");
  if (!o) return 0;
  size_t old = mpm_json_push_key(c, "camera");
  mpm_camera_desc *cam = &s->camera;
  if (mpm_json_expect_object(c, o, "an object with keys eye, target, fov") < 0 ||
      mpm_json_check_keys(c, o, CAMERA_KEYS, NULL) < 0 ||
      mpm_json_vec3(c, o, "eye", 1, mpm_json_any("m"), cam->eye) < 0 ||
      mpm_json_vec3(c, o, "target", 1, mpm_json_any("m"), cam->target) < 0 ||
      mpm_json_number(c, o, "fov", 0, mpm_json_in('(', 1, 170, ')', "degrees"), &cam->fov) < 0)
    return -1;
  if (cam->eye[0] == cam->target[0] && cam->eye[1] == cam->target[1] &&
      cam->eye[2] == cam->target[2])
    return mpm_json_fail_at(c, "target", MPM_ERR_INVALID,
                            "expected a point other than the eye (the camera needs a direction)");
  cam->set = 1;
  mpm_json_pop(c, old);
  return 0;
}

/* Newmark's positions (solver.scheme) move material points by the mean of the step's grid
 * velocities; particle domains move their corners by the new one (domain_transfer.c), which
 * would leave their F short of the state the solve balanced. */
static int check_scheme(mpm_json_ctx *c, const mpm_scene *s) {
  if (s->solver.scheme != MPM_SCHEME_NEWMARK) return 0;
  for (int i = 0; i < s->body_count; ++i)
    if (s->bodies[i].domains) {
      mpm_json_push_key(c, "solver");
      mpm_json_fail_at(c, "scheme", MPM_ERR_INVALID,
                       "\"newmark\" moves material points only; bodies[%d] has particle domains "
                       "(use \"backward_euler\" there)",
                       i);
      return -1;
    }
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
      mpm_sj_parse_materials(c, root, s) < 0 || mpm_sj_parse_bodies(c, root, s) < 0 ||
      mpm_sj_parse_colliders(c, root, s) < 0 || mpm_sj_parse_forces(c, root, s) < 0 ||
      parse_output(c, root, s) < 0 || parse_camera(c, root, s) < 0 ||
      mpm_sj_parse_refinement(c, root, s) < 0 || mpm_sj_parse_heat(c, root, s) < 0 ||
      mpm_sj_check_fields_heat(c, root, s) < 0 || check_scheme(c, s) < 0)
    return -1;
  return 0;
}

/* The common start of a parse: the defaults, the path for messages and mesh files, and the name
 * the path gives; 0, or -1 with the message when the path is too long. */
static int begin(mpm_json_ctx *ctx, mpm_error *local, const char *path_for_messages,
                 mpm_scene *scene) {
  const char *file = path_for_messages ? path_for_messages : "<scene>";
  mpm_error_clear(local);
  mpm_json_ctx_init(ctx, file, local);
  mpm_scene_default(scene);
  if (strlen(file) >= sizeof scene->path) {
    mpm_error_set(local, MPM_ERR_INVALID, "%.100s...: the scene path is longer than %d bytes", file,
                  MPM_PATH_MAX - 1);
    return -1;
  }
  snprintf(scene->path, sizeof scene->path, "%s", path_for_messages ? file : "");
  if (path_for_messages) stem_of(file, scene->name, sizeof scene->name);
  return 0;
}

/* On failure the scene is the defaults again, with nothing to free. */
static mpm_status end(const mpm_error *local, mpm_scene *scene, mpm_error *err) {
  if (local->status != MPM_OK) {
    mpm_scene_free(scene);
    mpm_scene_default(scene);
  }
  if (err) *err = *local;
  return local->status;
}

mpm_status mpm_scene_parse(const char *json_text, const char *path_for_messages, mpm_scene *scene,
                           mpm_error *err) {
  mpm_error local;
  mpm_json_ctx ctx;
  if (!json_text) json_text = "";
  if (begin(&ctx, &local, path_for_messages, scene) == 0) {
    size_t len = strlen(json_text);
    if (mpm_json_check_syntax(&ctx, json_text, len) == 0) {
      const char *end_at = NULL;
      cJSON *root = cJSON_ParseWithLengthOpts(json_text, len + 1, &end_at, 1);
      if (!root)
        mpm_json_syntax_error(&ctx, json_text, len, end_at);
      else
        parse_root(&ctx, root, scene);
      cJSON_Delete(root);
    }
  }
  scene->source_hash = mpm_fnv1a64(json_text, strlen(json_text));
  return end(&local, scene, err);
}

mpm_status mpm_scene_parse_tree(const cJSON *root, const char *path_for_messages, mpm_scene *scene,
                                mpm_error *err) {
  mpm_error local;
  mpm_json_ctx ctx;
  if (begin(&ctx, &local, path_for_messages, scene) == 0) parse_root(&ctx, root, scene);
  return end(&local, scene, err);
}

mpm_status mpm_scene_load(const char *path, mpm_scene *scene, mpm_error *err) {
  return mpm_scene_load_text(path, scene, NULL, err);
}

mpm_status mpm_scene_load_text(const char *path, mpm_scene *scene, char **text, mpm_error *err) {
  if (text) *text = NULL;
  mpm_scene_default(scene);
  if (!path || !path[0])
    return mpm_error_set(err, MPM_ERR_IO, "cannot read a scene file: no path given");
  char why[128];
  FILE *f = mpm_open_input(path, NULL, why, sizeof why);
  if (!f) return mpm_error_set(err, MPM_ERR_IO, "%s: cannot open the scene file: %s", path, why);
  size_t cap = 1 << 16, len = 0;
  char *buf = mpm_alloc(cap);
  int read_errno = 0;
  while (buf) {
    if (len + 1 >= cap) {
      char *bigger = mpm_realloc(buf, cap * 2);
      if (!bigger) {
        mpm_free(buf);
        buf = NULL;
        break;
      }
      buf = bigger;
      cap *= 2;
    }
    errno = 0;
    size_t got = fread(buf + len, 1, cap - 1 - len, f);
    const int has_nul = memchr(buf + len, '\0', got) != NULL;
    len += got;
    if (got == 0) {
      if (ferror(f)) read_errno = errno ? errno : EIO;
      break;
    }
    if (has_nul) break; /* binary data (or /dev/zero): reported below, with its position */
    if (len > SCENE_MAX_BYTES) {
      mpm_free(buf);
      fclose(f);
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "%s: the scene file is larger than %d MiB; expected a JSON scene (mesh "
                           "data belongs in mesh files)",
                           path, SCENE_MAX_BYTES >> 20);
    }
  }
  fclose(f);
  if (!buf)
    return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory reading the scene file", path);
  if (read_errno) {
    mpm_free(buf);
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
    mpm_free(buf);
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: line %d, column %d: expected JSON text, got a NUL byte (is this a "
                         "binary file?)",
                         path, line, col);
  }
  mpm_status st = mpm_scene_parse(buf, path, scene, err);
  if (st == MPM_OK && text)
    *text = buf; /* the caller's now */
  else
    mpm_free(buf);
  return st;
}
