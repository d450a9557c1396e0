/* embed.c - mpm as a library: a program that builds a scene from a JSON string, runs it on two
 * threads and reads the particles back, including a body with particle domains (Zhu et al.
 * 2017) and the J, stress and collider pose the view gives.
 *
 * It includes <mpm/mpm.h> only and links libmpm (README "Using mpm as a library"):
 *   cc embed.c $(pkg-config --cflags --libs mpm) -o embed
 * ctest runs it as example_embed; tests/install/ builds it against an installed copy. It exits
 * 0 when every check below holds, so that it is a test as well as an example. */
#include <mpm/mpm.h>

#include <stdio.h>

/* A jelly cube with particle domains dropped on a floor, and a small sphere of material points
 * beside it; the floor moves sideways, so that its pose changes. */
static const char *const scene_json =
    "{\"name\": \"embed\","
    " \"domain\": {\"min\": [0, 0, 0], \"max\": [0.6, 0.6, 0.6], \"dx\": 0.03},"
    " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 0.25, \"fps\": 20},"
    " \"materials\": [{\"name\": \"jelly\", \"model\": \"neo_hookean\", \"E\": 4e4, \"nu\": 0.3,"
    "                  \"density\": 1000}],"
    " \"bodies\": ["
    "   {\"name\": \"cube\", \"shape\": {\"type\": \"box\", \"center\": [0.25, 0.22, 0.3],"
    "    \"half_extent\": [0.07, 0.07, 0.07]}, \"material\": \"jelly\", \"domains\": true},"
    "   {\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": [0.45, 0.3, 0.3],"
    "    \"radius\": 0.05}, \"material\": \"jelly\"}],"
    " \"colliders\": [{\"name\": \"floor\", \"shape\": {\"type\": \"halfspace\","
    "   \"point\": [0, 0.1, 0], \"normal\": [0, 1, 0]}, \"rule\": \"sticky\","
    "   \"motion\": {\"velocity\": [0.1, 0, 0]}}]}";

/* (written out here, so that the example needs no libm on its link line) */
static double min2(double a, double b) {
  return a < b ? a : b;
}
static double max2(double a, double b) {
  return a > b ? a : b;
}

/* One entry of a view array, whatever the library's real type (float or double). */
static double at(const mpm_particle_view *v, const void *array, size_t i) {
  return v->real_size == sizeof(float) ? ((const float *)array)[i] : ((const double *)array)[i];
}

int main(void) {
  char err[1024];
  mpm_sim *sim = NULL;
  /* NULL base_dir: the scene names no mesh files, so no folder to resolve them against */
  if (mpm_sim_create_from_json(scene_json, NULL, &sim, err, sizeof err) != MPM_OK) {
    fprintf(stderr, "embed: %s\n", err);
    return 1;
  }
  printf("mpm %s (%s reals)\n", mpm_version(), mpm_real_type());
  mpm_sim_set_threads(sim, 2); /* this simulation's calls run on two OpenMP threads */

  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    if (mpm_sim_advance_frame(sim) != MPM_OK) {
      fprintf(stderr, "embed: %s\n", mpm_sim_last_error(sim));
      mpm_sim_destroy(sim);
      return 1;
    }
  }

  /* the view lists every particle: material points and domain particles alike; each has a
   * body index (0 the cube, 1 the ball, in the scene's order) */
  const mpm_particle_view v = mpm_sim_particles(sim);
  size_t n[2] = {0, 0};
  double lowest[2] = {1e30, 1e30}, J_min = 1e30, J_max = -1e30, p_max = 0;
  for (size_t i = 0; i < v.count; ++i) {
    const int b = v.body[i];
    if (b < 0 || b > 1) continue;
    n[b]++;
    const double y = at(&v, v.x[1], i);
    if (y < lowest[b]) lowest[b] = y;
    const double J = at(&v, v.J, i);
    J_min = min2(J_min, J);
    J_max = max2(J_max, J);
    /* pressure -tr(sigma)/3 */
    const double p =
        -(at(&v, v.stress[0], i) + at(&v, v.stress[4], i) + at(&v, v.stress[8], i)) / 3;
    p_max = max2(p_max, p);
  }
  mpm_collider_state floor;
  mpm_sim_collider_pose(sim, 0, &floor);
  printf("t = %.3f s after %lld steps: %zu particles (cube %zu with domains, ball %zu)\n",
         mpm_sim_time(sim), (long long)mpm_sim_steps(sim), v.count, n[0], n[1]);
  printf("lowest cube particle at y = %.4f m, ball at %.4f m; J in [%.4f, %.4f]; largest "
         "pressure %.1f Pa\n",
         lowest[0], lowest[1], J_min, J_max, p_max);
  printf("collider '%s' centre at x = %.4f m, moving at %.2f m/s\n", floor.name, floor.center[0],
         floor.velocity[0]);

  /* the checks that make this example a test: both bodies present, fallen onto the floor
   * (y = 0.1) but not through it, compressed under their weight, and the floor moved */
  const int ok = n[0] > 0 && n[1] > 0 && lowest[0] < 0.15 && lowest[0] > 0.07 && lowest[1] < 0.25 &&
                 lowest[1] > 0.07 && J_min > 0.5 && J_max < 1.5 && p_max > 0 &&
                 max2(floor.center[0] - 0.1 * mpm_sim_time(sim),
                      0.1 * mpm_sim_time(sim) - floor.center[0]) < 1e-6;
  mpm_sim_destroy(sim);
  if (!ok) fprintf(stderr, "embed: unexpected state (see above)\n");
  return ok ? 0 : 1;
}
