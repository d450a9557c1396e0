/* test_enrich_contact.c - enriched corners meet other material on the grid
 * (domain/enrich_contact.h, bodies[].enrichment_contact):
 *  - a ball of material points thrown at a block whose domains are all enriched (epsilon 1)
 *    passes into it without the contact (the block is not on the grid) and bounces off it with
 *    the contact; a ball with unenriched domains bounces off it too;
 *  - linear momentum of the two bodies is conserved through the contacts (the impulse a corner
 *    takes the grid gets back);
 *  - 1 and 2 threads give bitwise the same state;
 *  - the key's errors. */
#include "support.h"
#include "core/parallel.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The block (body 0: 8 x 8 x 8 domains of 0.02 m, every one enriched) at x = 0.6 m and the ball
 * (body 1: material points, radius 0.07 m) at x = 0.35 m coming at it at 2 m/s; no gravity. */
static mpm_sim *scene(int contact, int ball_domains) {
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.04},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1.0, \"fps\": 10},"
           " \"solver\": {\"transfer\": \"flip\", \"flip_alpha\": 0.95},"
           " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 2e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"name\": \"block\", \"shape\": {\"type\": \"box\", \"center\": "
           "[0.6, 0.5, 0.5], \"half_extent\": [0.08, 0.08, 0.08]}, \"material\": \"rubber\", "
           "\"domains\": true, \"enrichment\": 1, \"enrichment_contact\": %s},"
           " {\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": [0.35, 0.5, 0.5], "
           "\"radius\": 0.07}, \"material\": \"rubber\", \"velocity\": [2, 0, 0]%s}]}",
           contact ? "true" : "false", ball_domains ? ", \"domains\": true" : "");
  return test_sim_from_json(text, "contact.json");
}

/* The ball's (body 1's) mean x and x velocity, and the least x of the block's (body 0's)
 * particles. */
static void measure(const mpm_sim *sim, double *ball_x, double *ball_v, double *block_lo) {
  double x = 0, v = 0, m = 0, lo = 1e30;
  for (int set = 0; set < 2; ++set) {
    const mpm_particles *p = set ? &sim->domains.particles : &sim->particles;
    for (size_t i = 0; i < p->count; ++i) {
      if (p->body[i] == 0) {
        lo = fmin(lo, p->x[0][i]);
        continue;
      }
      x += p->mass[i] * p->x[0][i];
      v += p->mass[i] * p->v[0][i];
      m += p->mass[i];
    }
  }
  *ball_x = x / m;
  *ball_v = v / m;
  *block_lo = lo;
}

static void run_for(mpm_sim *sim, double seconds) {
  while (sim->time < seconds)
    if (mpm_sim_step(sim, 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
}

static void test_ball_bounces(void **state) {
  (void)state;
  double x[3], v[3], lo[3], drift[3];
  long long contacts[3];
  for (int on = 0; on < 3; ++on) {
    mpm_sim *sim = scene(on > 0, on == 2);
    const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
    run_for(sim, 0.25);
    const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
    measure(sim, &x[on], &v[on], &lo[on]);
    drift[on] = 0;
    for (int d = 0; d < 3; ++d) drift[on] = fmax(drift[on], fabs(d1.momentum[d] - d0.momentum[d]));
    drift[on] /= fabs(d0.momentum[0]);
    contacts[on] = sim->enriched_contacts;
    print_message("contact %s: ball at x = %.3f m moving at %.3f m/s, block from x = %.3f m; "
                  "momentum drift %.2e of the ball's; %lld corner contacts\n",
                  on == 2 ? "on, a ball with domains"
                  : on    ? "on"
                          : "off",
                  x[on], v[on], lo[on], drift[on], contacts[on]);
    mpm_sim_destroy(sim);
  }
  /* without contact the enriched block is not on the grid: the ball flies on through it (and
   * meets the domain's wall beyond) */
  assert_int_equal(contacts[0], 0);
  assert_true(x[0] > lo[0] + 0.1);
  /* with it the ball bounces back, and stays out of the block */
  assert_true(contacts[1] > 0);
  assert_true(v[1] < 0);
  assert_true(x[1] + 0.07 < lo[1] + 0.02);
  /* the impulses conserve linear momentum (FLIP transfers conserve it too) */
  assert_true(drift[1] < TOL(1e-4, 1e-10));
  /* a ball with domains (unenriched: on the grid through its corners) bounces off it too */
  assert_true(contacts[2] > 0);
  assert_true(v[2] < 0);
  assert_true(x[2] + 0.07 < lo[2] + 0.02);
  assert_true(drift[2] < TOL(1e-4, 1e-10));
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *run[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    run[t] = scene(1, 0);
    run_for(run[t], 0.15);
  }
  mpm_set_threads(0);
  assert_true(run[0]->enriched_contacts > 0);
  assert_int_equal(run[0]->enriched_contacts, run[1]->enriched_contacts);
  const mpm_particles *a = &run[0]->particles, *b = &run[1]->particles;
  assert_int_equal(a->count, b->count);
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(a->x[d], b->x[d], a->count * sizeof(mpm_real));
    assert_memory_equal(a->v[d], b->v[d], a->count * sizeof(mpm_real));
  }
  const mpm_domain_set *sa = &run[0]->domains, *sb = &run[1]->domains;
  for (int d = 0; d < 3; ++d)
    assert_memory_equal(sa->cx[d], sb->cx[d], sa->corner_count * sizeof(mpm_real));
  mpm_sim_destroy(run[0]);
  mpm_sim_destroy(run[1]);
}

static void test_scene_key(void **state) {
  (void)state;
  static const char *const bad[] = {
      "\"domains\": true, \"enrichment_contact\": 1",
      "\"domains\": true, \"enrichment_contact\": \"yes\"",
      "\"enrichment_contact\": true",
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    char text[1024];
    snprintf(text, sizeof text,
             "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.05}, \"time\": "
             "{\"end\": 1}, \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", "
             "\"E\": 1e4, \"nu\": 0.3, \"density\": 1000}], \"bodies\": [{\"shape\": {\"type\": "
             "\"box\", \"center\": [0.5, 0.5, 0.5], \"half_extent\": [0.1, 0.1, 0.1]}, "
             "\"material\": \"m\", %s}]}",
             bad[k]);
    mpm_scene scene;
    mpm_error err;
    assert_int_not_equal(mpm_scene_parse(text, "e.json", &scene, &err), MPM_OK);
    if (!strstr(err.message, "bodies[0].enrichment_contact"))
      fail_msg("'%s' lacks 'bodies[0].enrichment_contact'", err.message);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_ball_bounces),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_scene_key),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
