/* scene.c - defaults of the scene descriptor structs, freeing a scene, and the Lamé
 * parameters of a material.
 *
 * The defaults here are the ones docs/scene-format.md promises for keys a scene file leaves
 * out; the JSON loader (scene_json.c) starts from them and overwrites what the file gives. */
#include "scene/scene.h"
#include "core/alloc.h"

#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <stdarg.h>
#include <string.h>

static mpm_shape_desc shape_default(mpm_shape_kind kind) {
  mpm_shape_desc s;
  memset(&s, 0, sizeof s);
  s.kind = kind;
  s.axis[1] = 1.0; /* cylinder axis / half-space normal: +y */
  s.half_height = 0.0;
  s.mesh_scale = 1.0;
  s.mesh_max_mb = MPM_MESH_MAX_MB;
  return s;
}

mpm_material_desc mpm_material_desc_default(void) {
  mpm_material_desc m;
  memset(&m, 0, sizeof m);
  m.model = MPM_MODEL_FIXED_COROTATED;
  m.E = 1e5;
  m.nu = 0.3;
  m.density = 1000.0;
  m.min_stretch = 0.2;
  m.friction_angle = 30.0; /* degrees */
  m.cohesion = 0.0;
  m.yield_stress = 0.0; /* no default: required for von_mises */
  m.theta_c = 2.5e-2;   /* Stomakhin et al. 2013 */
  m.theta_s = 7.5e-3;
  m.hardening = 10.0;
  m.specific_heat = 1000.0;
  m.conductivity = 0.0;
  m.melt_range = 0.0;
  m.melt_shear = 0.01;
  m.melt_bulk = 1.0;
  return m;
}

mpm_body_desc mpm_body_desc_default(void) {
  mpm_body_desc b;
  memset(&b, 0, sizeof b);
  b.shape = shape_default(MPM_SHAPE_BOX);
  b.material = 0;
  b.particles_per_cell = 8.0;
  b.jitter = 0.0;
  b.seed = 1u;
  b.enrichment_surface_contact = 1; /* enriched surfaces meet (domain/enrich_surface_contact.h) */
  b.enrichment_self_contact = 1;
  return b;
}

mpm_collider_desc mpm_collider_desc_default(void) {
  mpm_collider_desc c;
  memset(&c, 0, sizeof c);
  c.shape = shape_default(MPM_SHAPE_HALFSPACE);
  c.inside_out = 0;
  c.rule = MPM_BOUNDARY_SLIP;
  c.friction = 0.0;
  c.motion.axis[2] = 1.0; /* rotation about +z */
  c.motion.angular_speed = 0.0;
  c.motion.keyframe_count = 0;
  c.motion.keyframes = NULL;
  c.active[0] = 0;
  c.active[1] = HUGE_VAL;
  return c;
}

mpm_force_desc mpm_force_desc_default(void) {
  mpm_force_desc f;
  memset(&f, 0, sizeof f);
  f.region = mpm_collider_desc_default();
  f.region.shape = shape_default(MPM_SHAPE_BOX);
  return f;
}

mpm_resample_desc mpm_resample_desc_default(void) {
  mpm_resample_desc r;
  memset(&r, 0, sizeof r);
  r.split = r.merge = 1;
  r.every = 1;
  r.merge_margin = 1;
  return r;
}

/* Append one line of advice to buf (after a '\n' when it holds some already). */
static void advise(char *buf, size_t cap, size_t *len, int *count, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void advise(char *buf, size_t cap, size_t *len, int *count, const char *fmt, ...) {
  ++*count;
  if (!buf || *len + 1 >= cap) return;
  if (*len) buf[(*len)++] = '\n';
  va_list ap;
  va_start(ap, fmt);
  const int n = vsnprintf(buf + *len, cap - *len, fmt, ap);
  va_end(ap);
  if (n > 0) *len += (size_t)n < cap - *len ? (size_t)n : cap - *len - 1;
}

int mpm_scene_advice(const mpm_scene *scene, char *buf, size_t cap) {
  size_t len = 0;
  int count = 0;
  if (buf && cap) buf[0] = 0;
  int points = 0; /* bodies of material points */
  for (int b = 0; b < scene->body_count; ++b) points |= !scene->bodies[b].domains;
  if (scene->solver.kernel == MPM_KERNEL_LINEAR && points)
    advise(buf, cap, &len, &count, "%s",
           "solver.kernel \"linear\": the linear kernel's weight gradient jumps when a particle "
           "crosses a cell face (the cell-crossing instability), so stressed bodies of material "
           "points ring and can blow up once their particles cross into new cells, whatever the "
           "transfer or time step; use \"ugimp\" (as cheap on this grid, Gao et al. 2017) or "
           "\"quadratic\" for anything but a quick preview");
  for (int m = 0; m < scene->material_count; ++m) {
    const mpm_material_desc *md = &scene->materials[m];
    if (md->model == MPM_MODEL_DRUCKER_PRAGER && md->friction_angle < 2)
      advise(buf, cap, &len, &count,
             "materials[%d].friction_angle is %g degrees (the key takes degrees): sand of so small "
             "a friction angle flows like a liquid; if radians were meant, that is %.3g degrees "
             "(typical sand: 30 to 35)",
             m, md->friction_angle, md->friction_angle * 57.29577951308232);
  }
  return count;
}

void mpm_scene_default(mpm_scene *scene) {
  memset(scene, 0, sizeof *scene);
  snprintf(scene->name, sizeof scene->name, "scene");
  for (int d = 0; d < 3; ++d) {
    scene->box_min[d] = 0.0;
    scene->box_max[d] = 1.0;
  }
  scene->dx = 1.0 / 64.0;
  scene->gravity[1] = -9.81;
  scene->wall_rule = MPM_BOUNDARY_SLIP;
  scene->wall_friction = 0.0;
  scene->wall_cells = 3;
  scene->end_time = 1.0;
  scene->fps = 24.0;
  scene->solver.kernel = MPM_KERNEL_QUADRATIC;
  scene->solver.transfer = MPM_TRANSFER_APIC;
  scene->solver.grid = MPM_GRID_SPARSE;
  scene->solver.flip_alpha = 0.95;
  scene->solver.cfl = 0.4;
  scene->solver.max_dt = 0.0;
  scene->solver.gimp_length = 0.0;
  scene->solver.on_instability = MPM_INSTABILITY_STOP;
  scene->solver.max_retries = 8;
  scene->solver.integrator = MPM_INTEGRATOR_EXPLICIT;
  scene->solver.dt = 0;
  scene->solver.newton_iterations = 2;
  scene->output.surface.smoothing = 1;
  scene->output.surface.filter = MPM_SURFACE_MEAN_CURVATURE;
  scene->solver.cg_tolerance = 0; /* automatic: see mpm_solver_desc */
  scene->solver.cg_max_iterations = 500;
  scene->solver.on_cg_failure = MPM_CG_FAILURE_WARN;
  scene->solver.domain_kernel = MPM_KERNEL_LINEAR;
  snprintf(scene->output.directory, sizeof scene->output.directory, "out");
  scene->output.vtu = 1;
  scene->output.ply = 1; /* Houdini, Blender (and the add-on) read these */
  scene->output.stats = 1;
  scene->output.checkpoint_every = 10;
  scene->camera.set = 0;
  scene->camera.fov = 35;
  scene->heat.pic = 1; /* heat.h: the particles follow the grid's field within a cell's time */
}

void mpm_scene_free(mpm_scene *scene) {
  if (!scene) return;
  if (scene->colliders)
    for (int c = 0; c < scene->collider_count; ++c) {
      mpm_free(scene->colliders[c].motion.keyframes);
      scene->colliders[c].motion.keyframes = NULL;
      scene->colliders[c].motion.keyframe_count = 0;
    }
  if (scene->forces)
    for (int f = 0; f < scene->force_count; ++f) mpm_free(scene->forces[f].region.motion.keyframes);
  mpm_free(scene->materials);
  mpm_free(scene->bodies);
  mpm_free(scene->colliders);
  mpm_free(scene->forces);
  mpm_free(scene->refine);
  scene->refine = NULL;
  scene->refine_count = 0;
  scene->materials = NULL;
  scene->bodies = NULL;
  scene->colliders = NULL;
  scene->forces = NULL;
  scene->material_count = scene->body_count = scene->collider_count = scene->force_count = 0;
}

double mpm_solver_cg_tolerance(const mpm_solver_desc *d) {
  if (d->cg_tolerance > 0) return d->cg_tolerance;
  return d->newton_iterations == 1 ? 1e-4 : 1e-2;
}

double mpm_schedule_at(const double (*keys)[2], int n, double t) {
  if (n <= 0) return 1;
  if (t <= keys[0][0]) return keys[0][1];
  for (int k = 1; k < n; ++k)
    if (t < keys[k][0]) {
      const double t0 = keys[k - 1][0], t1 = keys[k][0];
      const double a = (t - t0) / (t1 - t0);
      return (1 - a) * keys[k - 1][1] + a * keys[k][1];
    }
  return keys[n - 1][1];
}

double mpm_material_strength(const mpm_material_desc *m, double t) {
  return mpm_schedule_at((const double(*)[2])m->strength, m->strength_count, t);
}
