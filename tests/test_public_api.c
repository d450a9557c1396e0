/* test_public_api.c - the embedding API of include/mpm/mpm.h as a program linking the library
 * would use it (issue 17, defect 3): the particle view of a scene with particle domains holds
 * every particle (it held none of the domain particles), and a checkpoint can be written from
 * the public API once output is enabled there (mpm_sim_enable_output was internal). */
#include "support.h"
#include "mpm/mpm.h"

#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static void test_view_holds_domain_particles(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/ball_bunny.json", &sim, err, sizeof err),
                   MPM_OK);
  mpm_particle_view v = mpm_sim_particles(sim);
  print_message("ball_bunny: %zu particles in the view\n", v.count);
  assert_true(v.count > 10000); /* mpm check: 13,020, all with domains */
  assert_true(v.real_size == sizeof(float) || v.real_size == sizeof(double));
  /* ids unique and every position inside the domain [0, 1] x [0, 0.6] x [0, 0.6] */
  static unsigned char seen[1 << 20];
  memset(seen, 0, sizeof seen);
  for (size_t i = 0; i < v.count; ++i) {
    assert_true(v.id[i] < sizeof seen);
    assert_false(seen[v.id[i]]);
    seen[v.id[i]] = 1;
    const double x = v.real_size == 4 ? ((const float *)v.x[0])[i] : ((const double *)v.x[0])[i];
    assert_true(x > 0 && x < 1);
  }
  /* it follows the simulation */
  const double x0 = v.real_size == 4 ? ((const float *)v.x[0])[0] : ((const double *)v.x[0])[0];
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  v = mpm_sim_particles(sim);
  const double x1 = v.real_size == 4 ? ((const float *)v.x[0])[0] : ((const double *)v.x[0])[0];
  assert_true(x1 != x0);
  mpm_sim_destroy(sim);
}

static void test_checkpoint_from_the_api(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/bar_stretch.json", &sim, err, sizeof err),
                   MPM_OK);
  char path[1200];
  /* without output there is nowhere to write: a clear error, no file */
  assert_int_not_equal(mpm_sim_write_checkpoint(sim, path, sizeof path), MPM_OK);
  assert_non_null(strstr(mpm_sim_last_error(sim), "output"));
  const char *dir = test_temp_dir("public_api");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_int_equal(mpm_sim_write_checkpoint(sim, path, sizeof path), MPM_OK);
  struct stat st;
  assert_int_equal(stat(path, &st), 0);
  assert_true(st.st_size > 0);
  print_message("checkpoint written from the public API: %s (%lld bytes)\n", path,
                (long long)st.st_size);
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_view_holds_domain_particles),
      cmocka_unit_test(test_checkpoint_from_the_api),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
