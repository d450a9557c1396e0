/* test_collider_reaction.c - the colliders' forces in stats.csv (issue 17, "outputs people
 * expect"): the momentum each collider's projection takes from the grid nodes and enriched
 * corners, over the frame's time (collider<c>_fx, _fy, _fz, N, the force the material exerts on
 * the collider).
 *
 * Independent truths: (1) momentum balance. Nothing but gravity and the colliders changes the
 * material's momentum (the transfers conserve it, the walls are far), so per frame the force on
 * the collider is M g - dp/dt, p the momentum column of stats.csv; (2) statics. A block resting
 * on a floor presses on it with its weight, -M g, once its bounce has died down; (3) a block in
 * free flight touches nothing: exactly 0. Explicit and implicit steps, material points and
 * particle domains; the sums do not depend on the thread count; and a scene without colliders
 * writes the columns it always wrote. */
#include "support.h"
#include "core/parallel.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define G 9.81
#define FPS 10

/* A 0.2 m cube of 1000 kg/m^3 (8 kg) centred at y = block_y over a slip floor at y = floor_y,
 * from rest; `extra` splices keys into the body ("domains") and the scene ("solver"). */
static struct mpm_sim *block_over_floor(double block_y, double floor_y, double end,
                                        const char *body_extra, const char *scene_extra) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"gravity\": [0,%g,0],"
           " \"time\": {\"end\": %g, \"fps\": %d},"
           " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 2e5, \"nu\": 0.3,"
           " \"density\": 1000}],"
           " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,%g,0.5],"
           " \"half_extent\": [0.1,0.1,0.1]}, \"material\": \"m\"%s}],"
           " \"colliders\": [{\"name\": \"far\", \"shape\": {\"type\": \"sphere\", \"center\":"
           " [0.15,0.5,0.15], \"radius\": 0.05}},"
           " {\"name\": \"floor\", \"shape\": {\"type\": \"halfspace\", \"point\": [0,%g,0],"
           " \"normal\": [0,1,0]}, \"rule\": \"slip\"}]%s}",
           -G, end, FPS, block_y, body_extra, floor_y, scene_extra);
  return test_sim_from_json(text, "reaction");
}

/* Resting on the floor: its bottom face on it. */
static struct mpm_sim *block_on_floor(double end, const char *body_extra, const char *scene_extra) {
  return block_over_floor(0.3, 0.2, end, body_extra, scene_extra);
}

static void run_all(struct mpm_sim *sim, const char *dir) {
  assert_int_equal(mpm_sim_enable_output(sim, test_temp_dir(dir)), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
}

/* The force on collider c in frame f's row, component e. */
static double force(const struct mpm_sim *sim, int f, int c, int e) {
  return sim->out
      .stats_forces[3 * ((size_t)f * (size_t)sim->collider_count + (size_t)c) + (size_t)e];
}

/* Frame by frame, the floor's force is M g - dp/dt within `balance_tol` of the weight (the
 * rounding of float sums; the implicit step's residual at free DOFs, to its CG tolerance), the
 * far sphere's 0; from frame `settled` on, the floor carries the weight within `spread` (each
 * frame), or on average over those frames within `mean_tol`. */
static void check_resting(const struct mpm_sim *sim, double balance_tol, int settled, double spread,
                          double mean_tol) {
  const int frames = mpm_sim_frame_count(sim);
  const double M = sim->out.stats[0].mass, W = M * G;
  assert_close(M, 8, 1e-3);
  double sum = 0;
  for (int f = 1; f <= frames; ++f) {
    const mpm_stats_row *a = &sim->out.stats[f - 1], *b = &sim->out.stats[f];
    const double dt = b->time - a->time;
    for (int e = 0; e < 3; ++e) {
      const double balance = (e == 1 ? -W : 0) - (b->momentum[e] - a->momentum[e]) / dt;
      assert_close(force(sim, f, 1, e), balance, balance_tol * W);
      assert_true(force(sim, f, 0, e) == 0);
    }
    if (f >= settled) {
      assert_close(force(sim, f, 1, 1), -W, spread * W);
      sum += force(sim, f, 1, 1);
    }
  }
  assert_close(sum / (frames - settled + 1), -W, mean_tol * W);
  print_message("floor force over frames %d..%d: mean %.6g N, weight %.6g N\n", settled, frames,
                sum / (frames - settled + 1), W);
}

static void test_resting_explicit(void **state) {
  (void)state;
  struct mpm_sim *sim = block_on_floor(2.0, "", "");
  run_all(sim, "rest-explicit");
  check_resting(sim, TOL(2e-4, 1e-6), 16, 0.03, 0.01);
  mpm_sim_destroy(sim);
}

static void test_resting_implicit(void **state) {
  (void)state;
  struct mpm_sim *sim =
      block_on_floor(1.0, "", ", \"solver\": {\"integrator\": \"implicit\", \"dt\": 0.005}");
  run_all(sim, "rest-implicit");
  /* the free DOFs' momentum out of balance: within cg_tolerance (1e-2) of the step's weight
     impulse (implicit.c's convergence test) */
  check_resting(sim, 1e-2, 5, 0.01, 0.005);
  mpm_sim_destroy(sim);
}

/* Particle domains bounce longer (Zhu's two-step transfer damps less): the mean carries the
 * weight. */
static void test_resting_domains(void **state) {
  (void)state;
  struct mpm_sim *sim = block_on_floor(2.0, ", \"domains\": true", "");
  run_all(sim, "rest-domains");
  check_resting(sim, TOL(2e-4, 1e-6), 11, 0.15, 0.02);
  mpm_sim_destroy(sim);
}

/* Falling freely for 0.2 s, high above the floor and the domain's walls (it drops 20 cm of the
 * 40): nothing. */
static void test_free_flight(void **state) {
  (void)state;
  struct mpm_sim *sim = block_over_floor(0.7, 0.1, 0.2, "", "");
  run_all(sim, "free-flight");
  for (int f = 0; f <= mpm_sim_frame_count(sim); ++f)
    for (int k = 0; k < 6; ++k) assert_true(sim->out.stats_forces[6 * f + k] == 0);
  assert_close(sim->out.stats[2].momentum[1], -8 * G * 0.2,
               1e-4 * 8 * G * 0.2); /* it fell freely */
  mpm_sim_destroy(sim);
}

/* The sums are per grid box, then over the boxes in order: 1 and 2 threads agree bitwise. */
static void test_threads_bitwise(void **state) {
  (void)state;
  double got[2][3 * 2 * 4];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    struct mpm_sim *sim = block_on_floor(0.3, "", "");
    run_all(sim, t ? "threads-2" : "threads-1");
    memcpy(got[t], sim->out.stats_forces, sizeof got[t]);
    mpm_sim_destroy(sim);
  }
  mpm_set_threads(2);
  assert_memory_equal(got[0], got[1], sizeof got[0]);
  assert_true(got[0][3 * 2 * 3 + 4] < 0); /* frame 3: the floor is pressed */
}

/* A run checkpointed a few steps into frame 3 and resumed ends with the forces of an
 * uninterrupted one, bit for bit: the frame in progress's sums and the rows are in the
 * checkpoint. */
static void test_resume_bitwise(void **state) {
  (void)state;
  struct mpm_sim *a = block_on_floor(0.5, "", "");
  run_all(a, "resume-full");
  struct mpm_sim *b = block_on_floor(0.5, "", "");
  char part[700];
  snprintf(part, sizeof part, "%s", test_temp_dir("resume-part"));
  assert_int_equal(mpm_sim_enable_output(b, part), MPM_OK);
  for (int f = 0; f < 3; ++f) assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  for (int k = 0; k < 5; ++k)
    assert_int_equal(mpm_sim_step(b, b->frame_dt - fmod(b->time, b->frame_dt)), MPM_OK);
  char path[1100];
  assert_int_equal(mpm_sim_write_checkpoint(b, path, sizeof path), MPM_OK);
  mpm_sim_destroy(b);
  struct mpm_sim *c = block_on_floor(0.5, "", "");
  char used[1100];
  assert_int_equal(mpm_sim_resume(c, part, used, sizeof used), MPM_OK);
  while (mpm_sim_frame(c) < mpm_sim_frame_count(c))
    assert_int_equal(mpm_sim_advance_frame(c), MPM_OK);
  const size_t n = (size_t)(mpm_sim_frame_count(a) + 1) * 3 * 2;
  assert_memory_equal(a->out.stats_forces, c->out.stats_forces, n * sizeof(double));
  assert_true(a->out.stats_forces[3 * 2 * 4 + 4] < 0); /* frame 4 presses the floor */
  mpm_sim_destroy(a);
  mpm_sim_destroy(c);
}

/* The header: the old columns, then the colliders' (none without colliders). */
static void read_header(const char *dir, char *line, size_t cap) {
  char path[700];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *fp = fopen(path, "r");
  assert_non_null(fp);
  assert_non_null(fgets(line, (int)cap, fp));
  fclose(fp);
}

static void test_header(void **state) {
  (void)state;
  char line[2048];
  struct mpm_sim *sim = block_on_floor(0.1, "", "");
  const char *dir = test_temp_dir("header-colliders");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  mpm_sim_destroy(sim);
  read_header(dir, line, sizeof line);
  const char *tail = ",gravitational_energy,total_energy,collider0_fx,collider0_fy,collider0_fz,"
                     "collider1_fx,collider1_fy,collider1_fz\n";
  assert_non_null(strstr(line, tail));
  assert_string_equal(strstr(line, tail), tail);

  sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.1}, \"time\": {\"end\": 0.1},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
      " \"density\": 1000}], \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\":"
      " [0.5,0.5,0.5], \"radius\": 0.2}, \"material\": \"m\"}]}",
      "no colliders");
  dir = test_temp_dir("header-none");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  mpm_sim_destroy(sim);
  read_header(dir, line, sizeof line);
  assert_string_equal(strstr(line, ",total_energy"), ",total_energy\n");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_resting_explicit), cmocka_unit_test(test_resting_implicit),
      cmocka_unit_test(test_resting_domains),  cmocka_unit_test(test_free_flight),
      cmocka_unit_test(test_threads_bitwise),  cmocka_unit_test(test_resume_bitwise),
      cmocka_unit_test(test_header),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
