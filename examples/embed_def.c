/* embed_def.c - mpm as a library, with the scene built in code (include/mpm/scene_def.h)
 * instead of JSON: a rubber ball thrown sideways over a sand floor of a box, falling under
 * gravity onto a sticky plane, and its JSON printed for saving as a scene file.
 *
 * It includes <mpm/mpm.h> only and links libmpm (README "Using mpm as a library"):
 *   cc embed_def.c $(pkg-config --cflags --libs mpm) -o embed_def
 * ctest runs it as example_embed_def; it exits 0 when the physical checks at the end hold. */
#include <mpm/mpm.h>

#include <stdio.h>
#include <string.h>

/* One entry of a view array, whatever the library's real type (float or double). */
static double at(const mpm_particle_view *v, const void *array, size_t i) {
  return v->real_size == sizeof(float) ? ((const float *)array)[i] : ((const double *)array)[i];
}

/* The lowest particle of body b, and the body's mean velocity (mass-weighted). */
static double lowest_of(const mpm_particle_view *v, int b, double mean_v[3]) {
  double low = 1e30, m = 0;
  mean_v[0] = mean_v[1] = mean_v[2] = 0;
  for (size_t i = 0; i < v->count; ++i) {
    if (v->body[i] != b) continue;
    const double y = at(v, v->x[1], i), mi = at(v, v->mass, i);
    if (y < low) low = y;
    for (int d = 0; d < 3; ++d) mean_v[d] += mi * at(v, v->v[d], i);
    m += mi;
  }
  for (int d = 0; d < 3 && m > 0; ++d) mean_v[d] /= m;
  return low;
}

int main(void) {
  /* every struct starts from its defaults (the scene format's), then says what differs */
  mpm_material_def materials[2] = {mpm_material_def_default(), mpm_material_def_default()};
  materials[0].name = "rubber";
  materials[0].model = MPM_DEF_NEO_HOOKEAN;
  materials[0].E = 5e4;
  materials[1].name = "sand";
  materials[1].model = MPM_DEF_DRUCKER_PRAGER;
  materials[1].E = 3.5e5;
  materials[1].density = 1600;
  materials[1].friction_angle = 35;

  mpm_body_def bodies[2] = {mpm_body_def_default(), mpm_body_def_default()};
  bodies[0].name = "ball";
  bodies[0].shape = mpm_shape_def_default(MPM_DEF_SPHERE);
  bodies[0].shape.center[0] = 0.2, bodies[0].shape.center[1] = 0.4, bodies[0].shape.center[2] = 0.3;
  bodies[0].shape.radius = 0.06;
  bodies[0].material = 0;
  bodies[0].velocity[0] = 1.0; /* thrown along +x */
  bodies[1].name = "sand";
  bodies[1].shape.center[0] = 0.3, bodies[1].shape.center[1] = 0.15,
  bodies[1].shape.center[2] = 0.3;
  bodies[1].shape.half_extent[0] = 0.15, bodies[1].shape.half_extent[1] = 0.03;
  bodies[1].shape.half_extent[2] = 0.15;
  bodies[1].material_name = "sand"; /* by name rather than by index */

  mpm_collider_def floor = mpm_collider_def_default(); /* a half-space with normal +y */
  floor.name = "floor";
  floor.shape.point[1] = 0.12;
  floor.rule = MPM_DEF_STICKY;

  mpm_scene_def def = mpm_scene_def_default();
  def.name = "embed_def";
  def.domain.max[0] = def.domain.max[1] = def.domain.max[2] = 0.6;
  def.domain.dx = 0.03;
  def.time.end = 0.2;
  def.time.fps = 20;
  def.materials = materials, def.material_count = 2;
  def.bodies = bodies, def.body_count = 2;
  def.colliders = &floor, def.collider_count = 1;

  char err[1024];
  char *json = NULL;
  if (mpm_scene_def_to_json(&def, &json, err, sizeof err) != MPM_OK) {
    fprintf(stderr, "embed_def: %s\n", err);
    return 1;
  }
  printf("the scene as JSON (%zu bytes; save it to run it with `mpm run`)\n", strlen(json));
  mpm_free_string(json);

  mpm_sim *sim = NULL;
  if (mpm_sim_create_from_def(&def, NULL, &sim, err, sizeof err) != MPM_OK) {
    fprintf(stderr, "embed_def: %s\n", err); /* e.g. <def>: bodies[0].shape.radius: ... */
    return 1;
  }
  printf("mpm %s (%s reals)\n", mpm_version(), mpm_real_type());
  mpm_particle_view v = mpm_sim_particles(sim);
  double v0[3];
  const double low0 = lowest_of(&v, 0, v0);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    if (mpm_sim_advance_frame(sim) != MPM_OK) {
      fprintf(stderr, "embed_def: %s\n", mpm_sim_last_error(sim));
      mpm_sim_destroy(sim);
      return 1;
    }
  }
  v = mpm_sim_particles(sim);
  double v1[3], vs[3];
  const double low1 = lowest_of(&v, 0, v1);
  const double sand_low = lowest_of(&v, 1, vs);
  const double t = mpm_sim_time(sim);
  printf("t = %.3f s: ball's lowest particle %.4f -> %.4f m, velocity (%.3f, %.3f, %.3f) m/s; "
         "sand's lowest at %.4f m\n",
         t, low0, low1, v1[0], v1[1], v1[2], sand_low);

  /* the checks that make this example a test: the ball fell under gravity (a free fall of
   * 0.2 s would take it 0.196 m down, but the sand at y = 0.18 stops it first), it still moves
   * along +x, its velocity points down or it has landed, and the sand stays on the floor */
  const int ok = low1 < low0 - 0.05 && low1 > 0.12 && v1[0] > 0.05 && v1[1] < 0.5 &&
                 sand_low > 0.1 && sand_low < 0.13;
  mpm_sim_destroy(sim);
  if (!ok) fprintf(stderr, "embed_def: unexpected state (see above)\n");
  return ok ? 0 : 1;
}
