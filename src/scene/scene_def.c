/* scene_def.c - a scene built in code (include/mpm/scene_def.h): the defaults of the def
 * structs, the whole def as the scene format's JSON tree (its parts: scene_def_write.c and
 * scene_def_options.c), and the one validated scene made from that tree by the format's own
 * reader (mpm_scene_parse_tree), so that every check and message of the scene format is the
 * def's too (the format's key paths are the def's field paths). No text is parsed on the way;
 * the text is printed only for mpm_scene_def_to_json, the source hash and the output folder's
 * copy.
 *
 * Only what the JSON cannot carry is checked by the def: NULL pointers and negative counts,
 * enum values out of range, names longer than the format's 63 bytes (a C string has no length),
 * a material index out of range, and fields that the JSON leaves out for the object's model,
 * shape type, rule kind, integrator or switch yet were changed from their defaults. The format
 * refuses such keys because they would have no effect; dropping them silently would hide the
 * same mistake.
 *
 * Numbers are the def's doubles in the tree and are printed with the fewest digits that read
 * back as the same double, so a def and its JSON text make bit-identical simulations. A
 * non-finite number is null, which the format's check then names by its path. */
#include "mpm/mpm.h"
#include "core/alloc.h"
#include "core/hash.h"
#include "scene/json_check.h"
#include "scene/scene.h"
#include "scene/scene_def_parts.h"

#include <cjson/cJSON.h>
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
  s.max_file_mb = 64; /* MPM_MESH_MAX_MB */
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
  d.enrichment = b.enrichment;
  d.enrichment_exit = 0; /* not written: the format's follows enrichment */
  d.enrichment_metric = (mpm_def_enrichment_metric)b.enrichment_metric;
  d.enrichment_hourglass = b.enrichment_hourglass;
  d.enrichment_contact = b.enrichment_contact;
  d.enrichment_surface_contact = b.enrichment_surface_contact;
  d.enrichment_self_contact = b.enrichment_self_contact;
  d.enrichment_exit_wait = b.enrichment_exit_wait;
  d.hourglass = (mpm_def_hourglass)b.hourglass;
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
  d.active[0] = c.active[0];
  d.active[1] = c.active[1];
  return d;
}

mpm_force_def mpm_force_def_default(void) {
  const mpm_force_desc f = mpm_force_desc_default();
  mpm_force_def d;
  memset(&d, 0, sizeof d);
  d.shape = mpm_shape_def_default((mpm_def_shape_type)f.region.shape.kind);
  d.inside_out = f.region.inside_out;
  for (int k = 0; k < 3; ++k) {
    d.motion.axis[k] = f.region.motion.axis[k];
    d.acceleration[k] = f.acceleration[k];
  }
  d.motion.angular_speed = f.region.motion.angular_speed;
  d.active[0] = f.region.active[0];
  d.active[1] = f.region.active[1];
  return d;
}

mpm_keyframe_def mpm_keyframe_def_default(void) {
  mpm_keyframe_def d;
  memset(&d, 0, sizeof d); /* the format's: no translation, no angle; time is required */
  return d;
}

mpm_release_def mpm_release_def_default(void) {
  mpm_release_def d;
  memset(&d, 0, sizeof d); /* its keys are all required */
  return d;
}

mpm_refine_def mpm_refine_def_default(void) {
  mpm_refine_def d;
  memset(&d, 0, sizeof d);
  d.kind = MPM_DEF_REFINE_BOX;
  d.level = 1; /* required: the first level finer than 0 */
  d.collider = -1;
  d.body = -1;
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
    d.domain.min[k] = s.box_min[k];
    d.domain.max[k] = s.box_max[k];
    d.gravity[k] = s.gravity[k];
  }
  d.domain.dx = s.dx;
  d.domain.walls.rule = (mpm_def_rule)s.wall_rule;
  d.domain.walls.friction = s.wall_friction;
  d.domain.walls.cells = s.wall_cells;
  d.domain.resolution = 0;
  d.domain.levels = s.levels;
  d.domain.refine_every = s.refine_every;
  const mpm_resample_desc r = mpm_resample_desc_default();
  d.domain.resample.enabled = r.enabled;
  d.domain.resample.split = r.split;
  d.domain.resample.merge = r.merge;
  d.domain.resample.every = r.every;
  d.domain.resample.merge_margin = r.merge_margin;
  d.domain.resample.max_per_cell = r.max_per_cell;
  d.domain.resample.min_per_cell = r.min_per_cell;
  d.domain.resample.seed = r.seed;
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
  d.solver.grid = (mpm_def_grid)s.solver.grid;
  d.solver.gimp_length = s.solver.gimp_length;
  d.solver.on_instability = (mpm_def_instability)s.solver.on_instability;
  d.solver.max_retries = s.solver.max_retries;
  d.solver.domain_kernel = (mpm_def_kernel)s.solver.domain_kernel;
  d.solver.cg_tolerance = s.solver.cg_tolerance;
  d.solver.cg_max_iterations = s.solver.cg_max_iterations;
  d.solver.on_cg_failure = (mpm_def_cg_failure)s.solver.on_cg_failure;
  d.solver.preconditioner = (mpm_def_preconditioner)s.solver.preconditioner;
  d.solver.scheme = (mpm_def_scheme)s.solver.scheme;
  d.output.directory = "out"; /* mpm_scene_default's, as a string of static storage */
  d.output.vtu = s.output.vtu;
  d.output.ply = s.output.ply;
  d.output.stats = s.output.stats;
  d.output.checkpoint_every = s.output.checkpoint_every;
  d.output.fields = s.output.fields;
  d.output.surface.enabled = s.output.surface.enabled;
  d.output.surface.voxel = s.output.surface.voxel;
  d.output.surface.radius = s.output.surface.radius;
  d.output.surface.smoothing = s.output.surface.smoothing;
  d.output.surface.filter = (mpm_def_surface_filter)s.output.surface.filter;
  d.output.surface.per_body = s.output.surface.per_body;
  d.output.vdb = s.output.vdb;
  d.output.vdb_density = s.output.vdb_density;
  d.output.vdb_velocity = s.output.vdb_velocity;
  d.heat.enabled = s.heat.enabled;
  d.heat.temperature = s.heat.temperature;
  d.heat.pic = s.heat.pic;
  d.camera.enabled = s.camera.set;
  for (int k = 0; k < 3; ++k) {
    d.camera.eye[k] = s.camera.eye[k];
    d.camera.target[k] = s.camera.target[k];
  }
  d.camera.fov = s.camera.fov;
  return d;
}

/* The public enums are numbered as the internal ones, which the spellings below follow. */
_Static_assert((int)MPM_DEF_SNOW == (int)MPM_MODEL_SNOW &&
                   (int)MPM_DEF_SEPARATE == (int)MPM_BOUNDARY_SEPARATE &&
                   (int)MPM_DEF_REVOLVE == (int)MPM_SHAPE_REVOLVE &&
                   (int)MPM_DEF_KERNEL_UGIMP == (int)MPM_KERNEL_UGIMP &&
                   (int)MPM_DEF_FLIP == (int)MPM_TRANSFER_FLIP &&
                   (int)MPM_DEF_IMPLICIT == (int)MPM_INTEGRATOR_IMPLICIT &&
                   (int)MPM_DEF_GRID_DENSE == (int)MPM_GRID_DENSE &&
                   (int)MPM_DEF_INSTABILITY_RETRY == (int)MPM_INSTABILITY_RETRY &&
                   (int)MPM_DEF_CG_STOP == (int)MPM_CG_FAILURE_STOP &&
                   (int)MPM_DEF_PRECONDITIONER_MULTIGRID == (int)MPM_PRECONDITIONER_MULTIGRID &&
                   (int)MPM_DEF_FILTER_LAPLACIAN == (int)MPM_SURFACE_LAPLACIAN &&
                   (int)MPM_DEF_REFINE_STRAIN == (int)MPM_REFINE_STRAIN &&
                   (int)MPM_DEF_FIELD_F == (int)MPM_FIELD_F && MPM_FIELD_F + 1 == MPM_FIELD_COUNT,
               "scene_def.h's enums must match scene.h's");

/* ---- the whole scene ------------------------------------------------------------------ */

/* The def as a JSON tree; NULL with c's message (or status MPM_ERR_NOMEM) on failure. */
static cJSON *build(mpm_def_ctx *c, const mpm_scene_def *def) {
  if (!def) {
    mpm_def_fail(c, "no scene def given (NULL)");
    return NULL;
  }
  if (mpm_def_check_array(c, "materials", "material_count", def->materials, def->material_count) <
          0 ||
      mpm_def_check_array(c, "bodies", "body_count", def->bodies, def->body_count) < 0 ||
      mpm_def_check_array(c, "colliders", "collider_count", def->colliders, def->collider_count) <
          0 ||
      mpm_def_check_array(c, "forces", "force_count", def->forces, def->force_count) < 0 ||
      mpm_def_check_name(c, "name", def->name) < 0)
    return NULL;
  char(*names)[MPM_NAME_MAX] = mpm_calloc((size_t)def->material_count + 1, sizeof *names);
  cJSON *root = cJSON_CreateObject();
  if (!names || !root) {
    mpm_free(names);
    cJSON_Delete(root);
    c->status = MPM_ERR_NOMEM;
    return NULL;
  }
  mpm_def_writer w = {c, 0};
  int bad = 0;
  for (int i = 0; i < def->material_count && !bad; ++i) {
    char p[64];
    snprintf(p, sizeof p, "materials[%d].name", i);
    bad = mpm_def_check_name(c, p, def->materials[i].name) < 0;
    if (def->materials[i].name)
      snprintf(names[i], sizeof names[i], "%s", def->materials[i].name);
    else
      snprintf(names[i], sizeof names[i], "material%d", i);
  }
  mpm_def_add_string(&w, root, "name", def->name);
  bad = bad || mpm_def_write_domain(&w, &def->domain, root) < 0;
  mpm_def_add_vec3(&w, root, "gravity", def->gravity);
  cJSON *time = mpm_def_add_object(&w, root, "time");
  mpm_def_add_number(&w, time, "end", def->time.end);
  mpm_def_add_number(&w, time, "fps", def->time.fps);
  bad = bad || mpm_def_write_solver(&w, &def->solver, root) < 0;
  cJSON *mats = mpm_def_add_array(&w, root, "materials");
  for (int i = 0; i < def->material_count && !bad; ++i)
    bad = mpm_def_write_material(&w, i, &def->materials[i], names[i], def->heat.enabled, mats) < 0;
  cJSON *bodies = mpm_def_add_array(&w, root, "bodies");
  for (int i = 0; i < def->body_count && !bad; ++i)
    bad = mpm_def_write_body(&w, i, &def->bodies[i], def, (const char(*)[MPM_NAME_MAX])names,
                             bodies) < 0;
  if (def->collider_count > 0) {
    cJSON *cols = mpm_def_add_array(&w, root, "colliders");
    for (int i = 0; i < def->collider_count && !bad; ++i)
      bad = mpm_def_write_collider(&w, i, &def->colliders[i], def->heat.enabled, cols) < 0;
  }
  if (def->force_count > 0) {
    cJSON *forces = mpm_def_add_array(&w, root, "forces");
    for (int i = 0; i < def->force_count && !bad; ++i)
      bad = mpm_def_write_force(&w, i, &def->forces[i], forces) < 0;
  }
  bad = bad || mpm_def_write_output(&w, &def->output, root) < 0 ||
        mpm_def_write_heat(&w, &def->heat, root) < 0 ||
        mpm_def_write_camera(&w, &def->camera, root) < 0;
  mpm_free(names);
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
  mpm_def_ctx c = {err, errlen, MPM_OK};
  if (!json_out) {
    mpm_def_fail(&c, "no place for the text given (json_out is NULL)");
    return c.status;
  }
  *json_out = NULL;
  cJSON *root = build(&c, def);
  if (!root) return c.status;
  *json_out = mpm_json_print_exact(root, 1);
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

mpm_status mpm_scene_from_def(const mpm_scene_def *def, const char *base_dir, mpm_scene *scene,
                              cJSON **tree, mpm_error *err) {
  mpm_error local;
  mpm_error_clear(&local);
  if (tree) *tree = NULL;
  mpm_scene_default(scene);
  mpm_def_ctx c = {local.message, sizeof local.message, MPM_OK};
  cJSON *root = build(&c, def);
  if (!root) {
    local.status = c.status;
    if (err) *err = local;
    return local.status;
  }
  /* the scene's name in messages; its folder resolves the mesh files */
  char path[MPM_PATH_MAX + 16];
  if (base_dir && base_dir[0])
    snprintf(path, sizeof path, "%.*s/<def>", MPM_PATH_MAX, base_dir);
  else
    snprintf(path, sizeof path, "<def>");
  mpm_status st = mpm_scene_parse_tree(root, path, scene, &local);
  if (st == MPM_OK) {
    /* the hash a file holding the def's text would give (a checkpoint resumes the same scene) */
    char *text = mpm_json_print_exact(root, 0);
    if (text) {
      scene->source_hash = mpm_fnv1a64(text, strlen(text));
      cJSON_free(text);
    } else {
      mpm_scene_free(scene);
      mpm_scene_default(scene);
      st = mpm_error_set(&local, MPM_ERR_NOMEM, "%s: out of memory printing the scene's JSON text",
                         path);
    }
  }
  if (st == MPM_OK && tree)
    *tree = root;
  else
    cJSON_Delete(root);
  if (err) *err = local;
  return st;
}
