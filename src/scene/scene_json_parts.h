/* scene_json_parts.h - what the parts of the JSON scene parser share: scene_json.c (entry
 * points, top level, domain, time, solver, output), scene_json_material.c (materials) and
 * scene_json_shape.c (shapes, bodies, colliders, force regions).
 *
 * Each parse function reads its key of `root` (or of `body`) at the current key path of the
 * context, fills the scene and returns 0, or writes the error and returns -1; on an error
 * the caller empties the scene. Internal to src/scene; not part of the public API. */
#ifndef MPM_SCENE_JSON_PARTS_H
#define MPM_SCENE_JSON_PARTS_H

#include "scene/json_check.h"
#include "scene/scene.h"

#include <cjson/cJSON.h>

/* Boundary rule spellings, in the order of mpm_boundary_rule (scene.h); NULL-terminated. */
extern const char *const mpm_sj_rule_names[];
/* 'x', 'y', 'z': axis names for messages. */
extern const char mpm_sj_axis_name[3];

/* ---- helpers (scene_json.c) ------------------------------------------------------------ */

/* "out of memory allocating <what>"; returns -1. */
int mpm_sj_fail_nomem(mpm_json_ctx *c, const char *what);
/* The array at obj[key] (required or not); 0 absent, 1 present, -1 wrong type. */
int mpm_sj_get_array(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                     const char *what, const cJSON **out);
/* node[key] as a schedule [[time, factor], ...]: 1 to MPM_STRENGTH_KEYS keyframes, times >= 0
 * and increasing, factors in [0, 1e6]; absent: 0 and *count untouched. */
int mpm_sj_parse_schedule(mpm_json_ctx *c, const cJSON *node, const char *key,
                          double keys[MPM_STRENGTH_KEYS][2], int *count);

/* ---- the multi-level grid (scene_json_refine.c) ------------------------------------------ */

/* domain.levels and domain.refine, and what the multi-level grid asks of the solver and the
 * bodies. Runs last (rules name colliders and bodies). */
int mpm_sj_parse_refinement(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);

/* ---- output.surface (scene_json_surface.c) ---------------------------------------------- */

/* output.surface (true, false or an object) of the output object `output`. Runs after the
 * bodies and materials (it names them). */
int mpm_sj_parse_surface(mpm_json_ctx *c, const cJSON *output, mpm_scene *s);

/* ---- output.fields (scene_json_fields.c) ------------------------------------------------ */

/* output.fields of the output object `output`: the point arrays of the VTU frames. */
int mpm_sj_parse_fields(mpm_json_ctx *c, const cJSON *output, mpm_scene *s);
/* Fields that need heat (temperature, melt) in a scene without it; runs after the heat. */
int mpm_sj_check_fields_heat(mpm_json_ctx *c, const cJSON *root, const mpm_scene *s);

/* ---- materials (scene_json_material.c) ------------------------------------------------- */

/* root.materials; leaves room in s->materials for one inline material per body. Runs
 * before mpm_sj_parse_bodies. */
/* Heat (scene_json_heat.c): a material's specific_heat, conductivity and melting; a body's
 * or collider's temperature; the scene's `heat` object, then the checks that tie them
 * together (run last). */
int mpm_sj_parse_material_heat(mpm_json_ctx *c, const cJSON *node, int model, mpm_material_desc *m);
int mpm_sj_parse_temperature(mpm_json_ctx *c, const cJSON *node, int *has, double *temperature);
int mpm_sj_parse_heat(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);

int mpm_sj_parse_materials(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);
/* body.material: a name among materials[] (the first `named` entries) or an inline object. */
int mpm_sj_parse_body_material(mpm_json_ctx *c, const cJSON *body, int named, mpm_scene *s,
                               mpm_body_desc *b);

/* ---- bodies and colliders (scene_json_shape.c) ----------------------------------------- */

int mpm_sj_parse_bodies(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);
int mpm_sj_parse_colliders(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);
/* root.forces: body-force regions (a collider's shape, motion and window; an acceleration and
 * a schedule). */
int mpm_sj_parse_forces(mpm_json_ctx *c, const cJSON *root, mpm_scene *s);

#endif
