/* scene_def_parts.h - what the parts of the scene def's writer share (include/mpm/scene_def.h):
 * scene_def.c (the defaults, the whole scene and the entry points), scene_def_write.c (the
 * message and JSON helpers; shapes, motions, materials, bodies, colliders and force regions) and
 * scene_def_options.c (the domain with its multi-level grid, the solver, the output, the camera).
 *
 * Each write function checks what the JSON text cannot carry (see scene_def.c), adds its key to
 * `parent` and returns 0, or writes the message and returns -1. An allocation failure is not
 * returned: it is remembered in the writer and reported once at the end. Internal to src/scene;
 * not part of the public API. */
#ifndef MPM_SCENE_DEF_PARTS_H
#define MPM_SCENE_DEF_PARTS_H

#include "mpm/mpm.h"
#include "scene/scene.h"

#include <cjson/cJSON.h>
#include <stddef.h>

typedef struct mpm_def_ctx {
  char *err;
  size_t errlen;
  mpm_status status;
} mpm_def_ctx;

/* "<def>: " and the message, status MPM_ERR_INVALID; returns -1. */
__attribute__((format(printf, 2, 3))) int mpm_def_fail(mpm_def_ctx *c, const char *fmt, ...);

/* The C enum of a field and the format's spellings of its values, in their order. */
typedef struct mpm_def_enum {
  const char *type; /* the C enum, for messages */
  const char *const *names;
  int count;
} mpm_def_enum;

extern const mpm_def_enum mpm_def_rules, mpm_def_integrators, mpm_def_transfers, mpm_def_kernels,
    mpm_def_grids, mpm_def_instabilities, mpm_def_cg_failures, mpm_def_preconditioners,
    mpm_def_schemes, mpm_def_filters, mpm_def_refine_kinds;

/* The spelling of value v at `path`; NULL with the message when the enum has no such value. */
const char *mpm_def_spell(mpm_def_ctx *c, const char *path, int v, const mpm_def_enum *t);
/* A name of at most 63 bytes (NULL is fine); -1 with the message. */
int mpm_def_check_name(mpm_def_ctx *c, const char *path, const char *s);
/* An array of the def: NULL only when empty, and a count >= 0; -1 with the message. */
int mpm_def_check_array(mpm_def_ctx *c, const char *key, const char *count_key, const void *array,
                        int count);
int mpm_def_vec3_equal(const double a[3], const double b[3]);

/* Builders that remember an allocation failure: cJSON's Add* functions take a NULL parent (and
 * free what they made), so writing goes on harmlessly after one. */
typedef struct mpm_def_writer {
  mpm_def_ctx *c;
  int nomem;
} mpm_def_writer;

cJSON *mpm_def_add_object(mpm_def_writer *w, cJSON *parent, const char *key);
cJSON *mpm_def_add_array(mpm_def_writer *w, cJSON *parent, const char *key);
/* A new object appended to the array `arr` (NULL on failure, remembered). */
cJSON *mpm_def_append_object(mpm_def_writer *w, cJSON *arr);
/* Numbers as number nodes (printed with their exact digits by mpm_json_print_exact); non-finite
 * ones as null. */
void mpm_def_add_number(mpm_def_writer *w, cJSON *obj, const char *key, double v);
void mpm_def_add_vec3(mpm_def_writer *w, cJSON *obj, const char *key, const double v[3]);
/* [[a, b], ...]: keyframes [time, factor] or profile points [radius, height]. */
void mpm_def_add_pairs(mpm_def_writer *w, cJSON *obj, const char *key, const double (*v)[2], int n);
/* [i, ...]: indices into the def's arrays. */
void mpm_def_add_indices(mpm_def_writer *w, cJSON *obj, const char *key, const int *v, int n);
void mpm_def_add_bool(mpm_def_writer *w, cJSON *obj, const char *key, int v);
/* Nothing for a NULL string (the key is left out). */
void mpm_def_add_string(mpm_def_writer *w, cJSON *obj, const char *key, const char *s);

/* ---- the objects (scene_def_write.c) --------------------------------------------------- */

/* materials[i], named `name` (the def's or "material<i>"); heat: the scene's heat is on. */
int mpm_def_write_material(mpm_def_writer *w, int i, const mpm_material_def *m, const char *name,
                           int heat, cJSON *arr);
/* bodies[i]; material_names[k] is the name written for materials[k]. */
int mpm_def_write_body(mpm_def_writer *w, int i, const mpm_body_def *b, const mpm_scene_def *def,
                       const char (*material_names)[MPM_NAME_MAX], cJSON *arr);
int mpm_def_write_collider(mpm_def_writer *w, int i, const mpm_collider_def *cd, int heat,
                           cJSON *arr);
int mpm_def_write_force(mpm_def_writer *w, int i, const mpm_force_def *f, cJSON *arr);

/* ---- the options (scene_def_options.c) ------------------------------------------------- */

int mpm_def_write_domain(mpm_def_writer *w, const mpm_domain_def *d, cJSON *root);
int mpm_def_write_solver(mpm_def_writer *w, const mpm_solver_def *s, cJSON *root);
int mpm_def_write_output(mpm_def_writer *w, const mpm_output_def *o, cJSON *root);
int mpm_def_write_heat(mpm_def_writer *w, const mpm_heat_def *h, cJSON *root);
int mpm_def_write_camera(mpm_def_writer *w, const mpm_camera_def *cam, cJSON *root);

#endif
