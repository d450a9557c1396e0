/* test_public_api.c - the embedding API of include/mpm/mpm.h as a program linking the library
 * would use it (issue 17). Defect 3: the particle view of a scene with particle domains holds
 * every particle (it held none of the domain particles), and a checkpoint can be written from
 * the public API once output is enabled there (mpm_sim_enable_output was internal). Then the
 * rest of the embedding API: a scene from a JSON string, the thread count, the view's J,
 * Cauchy stress, plastic state and temperature, and the colliders' poses. */
#include "support.h"
#include "mpm/mpm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>

/* one entry of a view array, whatever the real type */
static double at(const mpm_particle_view *v, const void *a, size_t i) {
  return v->real_size == 4 ? ((const float *)a)[i] : ((const double *)a)[i];
}

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
    const double x = at(&v, v.x[0], i);
    assert_true(x > 0 && x < 1);
  }
  /* it follows the simulation */
  const double x0 = at(&v, v.x[0], 0);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  v = mpm_sim_particles(sim);
  const double x1 = at(&v, v.x[0], 0);
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

static void test_create_from_json(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err), MPM_OK);
  mpm_particle_view v = mpm_sim_particles(sim);
  assert_true(v.count > 0); /* every particle has a domain: the view has them all */
  assert_int_equal(mpm_sim_frame_count(sim), 2);
  mpm_sim_destroy(sim);
  /* a broken text: the status and a message that names the scene and the base folder */
  assert_int_equal(mpm_sim_create_from_json("{\"domain\": ", "/some/dir", &sim, err, sizeof err),
                   MPM_ERR_PARSE);
  assert_null(sim);
  print_message("broken JSON: %s\n", err);
  assert_non_null(strstr(err, "/some/dir/<json>"));
  /* a well-formed text with a bad value: the key path */
  assert_int_not_equal(
      mpm_sim_create_from_json("{\"domain\": {\"dx\": -1}}", NULL, &sim, err, sizeof err), MPM_OK);
  assert_null(sim);
  assert_non_null(strstr(err, "<json>"));
  assert_int_equal(mpm_sim_create_from_json(NULL, NULL, &sim, err, sizeof err), MPM_ERR_INVALID);
}

/* The positions after one frame, as doubles (the caller frees). */
static double *run_frame(int threads, size_t *count) {
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/jello_cubes.json", &sim, err, sizeof err),
                   MPM_OK);
  assert_int_equal(mpm_sim_set_threads(sim, threads), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  mpm_particle_view v = mpm_sim_particles(sim);
  double *x = malloc(3 * v.count * sizeof *x);
  assert_non_null(x);
  for (size_t i = 0; i < v.count; ++i)
    for (int d = 0; d < 3; ++d) x[3 * i + (size_t)d] = at(&v, v.x[d], i);
  *count = v.count;
  mpm_sim_destroy(sim);
  return x;
}

static void test_set_threads(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err), MPM_OK);
  assert_int_equal(mpm_sim_set_threads(sim, -1), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "thread"));
  mpm_sim_destroy(sim);
  /* the same state on one thread and on two, bit for bit */
  size_t n1, n2;
  double *a = run_frame(1, &n1), *b = run_frame(2, &n2);
  assert_int_equal(n1, n2);
  assert_memory_equal(a, b, 3 * n1 * sizeof *a);
  free(a);
  free(b);
}

/* At rest the view's J is 1 and the stress 0; squeezed, J = det F and the stress is symmetric
 * and compressive. */
static void test_view_fields(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/ball_bunny.json", &sim, err, sizeof err),
                   MPM_OK);
  mpm_particle_view v = mpm_sim_particles(sim);
  assert_non_null(v.J);
  assert_null(v.temperature); /* no heat in this scene */
  for (size_t i = 0; i < v.count; ++i) {
    assert_close(at(&v, v.J, i), 1, 1e-6);
    for (int c = 0; c < 9; ++c) assert_close(at(&v, v.stress[c], i), 0, 1e-3);
    assert_close(at(&v, v.plastic, i), 1, 0); /* neo-Hookean: the unused state, 1 */
  }
  /* the ball hits the bunny during the first frames */
  for (int f = 0; f < 2; ++f) assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  v = mpm_sim_particles(sim);
  double worst_det = 0, worst_sym = 0, smax = 0;
  for (size_t i = 0; i < v.count; ++i) {
    double F[9], s[9];
    for (int c = 0; c < 9; ++c) F[c] = at(&v, v.F[c], i), s[c] = at(&v, v.stress[c], i);
    const double det = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                       F[2] * (F[3] * F[7] - F[4] * F[6]);
    worst_det = fmax(worst_det, fabs(det - at(&v, v.J, i)));
    for (int c = 0; c < 9; ++c) smax = fmax(smax, fabs(s[c]));
    worst_sym = fmax(worst_sym, fabs(s[1] - s[3]) + fabs(s[2] - s[6]) + fabs(s[5] - s[7]));
  }
  print_message("after 2 frames: largest stress %.4g Pa, |J - det F| <= %.3g, asymmetry %.3g\n",
                smax, worst_det, worst_sym);
  assert_true(smax > 10);                    /* the impact stresses the bodies */
  assert_true(worst_det < TOL(1e-5, 1e-12)); /* J is det F */
  assert_true(worst_sym < TOL(1e-4, 1e-9) * smax);
  mpm_sim_destroy(sim);
}

/* The state view (no J, no stress) shares the full view's arrays; vector components are
 * component_stride bytes apart (one strided array each), stress components stress_stride; a
 * held simulation keeps the arrays of an earlier view readable across steps and frees them
 * with the last release. */
static void test_view_state_and_strides(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err), MPM_OK);
  const mpm_particle_view s = mpm_sim_particle_state(sim);
  assert_true(s.count > 0);
  assert_null(s.J);
  for (int c = 0; c < 9; ++c) assert_null(s.stress[c]);
  assert_int_equal(s.stress_stride, 0);
  assert_true(s.component_stride >= s.count * s.real_size);
  const char *x0 = s.x[0], *v0 = s.v[0], *F0 = s.F[0];
  for (int d = 0; d < 3; ++d) {
    assert_ptr_equal(s.x[d], x0 + (size_t)d * s.component_stride);
    assert_ptr_equal(s.v[d], v0 + (size_t)d * s.component_stride);
  }
  for (int c = 0; c < 9; ++c) assert_ptr_equal(s.F[c], F0 + (size_t)c * s.component_stride);
  const mpm_particle_view v = mpm_sim_particles(sim);
  assert_int_equal(v.count, s.count);
  assert_ptr_equal(v.x[0], s.x[0]);
  assert_ptr_equal(v.id, s.id);
  assert_int_equal(v.component_stride, s.component_stride);
  assert_non_null(v.J);
  assert_true(v.stress_stride >= v.count * v.real_size);
  for (int c = 0; c < 9; ++c)
    assert_ptr_equal(v.stress[c], (const char *)v.stress[0] + (size_t)c * v.stress_stride);
  /* held: the frame's reorders move the arrays within their block, the old pointers stay
     readable; the values there are stale but finite numbers of the state */
  mpm_sim_hold_particle_arrays(sim, 1);
  const mpm_particle_view old = mpm_sim_particle_state(sim);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  double sum = 0;
  for (size_t i = 0; i < old.count; ++i) sum += at(&old, old.x[0], i);
  assert_true(isfinite(sum));
  mpm_sim_hold_particle_arrays(sim, -1);
  mpm_sim_hold_particle_arrays(sim, 0); /* no change */
  mpm_sim_destroy(sim);
}

/* A jelly block of material points at rest in zero gravity, nothing around it (the domain's
 * walls' band, three cells, far from it). */
static const char *const points_json =
    "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.05},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 0.1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
    "  \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.5, 0.5],"
    "  \"half_extent\": [0.1, 0.1, 0.1]}, \"material\": \"m\"}]}";

/* Velocities set between steps carry their momentum into the step: with nothing outside the
 * body, the momentum after a step is what was set (APIC conserves it); positions jump where
 * set; a refused call names the id or value and changes nothing. */
static void test_set_velocities_and_positions(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(points_json, NULL, &sim, err, sizeof err), MPM_OK);
  mpm_particle_view v = mpm_sim_particle_state(sim);
  const size_t n = v.count;
  uint32_t *ids = malloc(n * sizeof *ids);
  double *vel = malloc(3 * n * sizeof *vel);
  size_t chosen = 0;
  for (size_t i = 0; i < n; ++i) {
    if (v.id[i] % 3) continue; /* a third of the particles */
    ids[chosen] = v.id[i];
    const double u[3] = {1.0 + 0.001 * (double)(i % 7), 0.5, -0.25};
    for (int d = 0; d < 3; ++d) vel[3 * chosen + d] = u[d];
    ++chosen;
  }
  assert_int_equal(mpm_sim_set_velocities(sim, chosen, ids, vel), MPM_OK);
  v = mpm_sim_particle_state(sim);
  double P[3] = {0, 0, 0}; /* the momentum set (the others are at rest) */
  for (size_t i = 0; i < n; ++i) {
    assert_true(at(&v, v.v[1], i) == (v.id[i] % 3 == 0 ? 0.5 : 0));
    for (int d = 0; d < 3; ++d) P[d] += at(&v, v.mass, i) * at(&v, v.v[d], i);
  }
  assert_int_equal(mpm_sim_step(sim, 0), MPM_OK);
  v = mpm_sim_particle_state(sim);
  double Q[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) Q[d] += at(&v, v.mass, i) * at(&v, v.v[d], i);
  print_message("momentum set %.9g %.9g %.9g, after the step %.9g %.9g %.9g\n", P[0], P[1], P[2],
                Q[0], Q[1], Q[2]);
  for (int d = 0; d < 3; ++d) assert_close(Q[d], P[d], TOL(2e-6, 1e-12) * fabs(P[0]));
  /* a position, exactly where set */
  const double to[3] = {0.45, 0.55, 0.56};
  assert_int_equal(mpm_sim_set_positions(sim, 1, &ids[1], to), MPM_OK);
  v = mpm_sim_particle_state(sim);
  for (size_t i = 0; i < n; ++i)
    if (v.id[i] == ids[1])
      for (int d = 0; d < 3; ++d)
        assert_true(at(&v, v.x[d], i) == (v.real_size == 4 ? (double)(float)to[d] : to[d]));
  /* refusals name what is wrong and change nothing */
  const double outside[3] = {0.5, 1.5, 0.5}, nan3[3] = {0, NAN, 0};
  assert_int_equal(mpm_sim_set_positions(sim, 1, &ids[2], outside), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "coordinate 1 is 1.5"));
  assert_int_equal(mpm_sim_set_velocities(sim, 1, &ids[2], nan3), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "velocity component 1"));
  const uint32_t missing = 4000000000u;
  assert_int_equal(mpm_sim_set_velocities(sim, 1, &missing, vel), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "no particle with id 4000000000"));
  /* a request with one bad id changes none of the good ones */
  const uint32_t two[2] = {ids[3], missing};
  const double zero[6] = {0, 0, 0, 0, 0, 0};
  assert_int_equal(mpm_sim_set_velocities(sim, 2, two, zero), MPM_ERR_INVALID);
  v = mpm_sim_particle_state(sim);
  for (size_t i = 0; i < n; ++i)
    if (v.id[i] == ids[3]) assert_true(at(&v, v.v[1], i) != 0);
  mpm_sim_destroy(sim);
  /* a particle with its domain on */
  assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err), MPM_OK);
  v = mpm_sim_particle_state(sim);
  assert_int_equal(mpm_sim_set_velocities(sim, 1, v.id, vel), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "has its domain on"));
  mpm_sim_destroy(sim);
  free(ids);
  free(vel);
}

/* A call that must succeed, its message printed when it does not. */
#define OK(sim, call)                                                                              \
  do {                                                                                             \
    const mpm_status st_ = (call);                                                                 \
    if (st_ != MPM_OK) print_error("%s: %s\n", #call, mpm_sim_last_error(sim));                    \
    assert_int_equal(st_, MPM_OK);                                                                 \
  } while (0)

/* A jelly block in zero gravity with a sticky sphere inside it that a script moves. */
static const char *const scripted_json =
    "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.04},"
    " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1, \"fps\": 20},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3,"
    "  \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5, 0.5, 0.5],"
    "  \"half_extent\": [0.2, 0.2, 0.2]}, \"material\": \"m\"}],"
    " \"colliders\": [{\"name\": \"grip\", \"shape\": {\"type\": \"sphere\", \"center\": "
    "[0.5, 0.5, 0.5], \"radius\": 0.14}, \"rule\": \"sticky\"}]}";

/* The state of every particle, sorted by id, as doubles: x, v, F. */
static double *state_by_id(mpm_sim *sim, size_t *n) {
  const mpm_particle_view v = mpm_sim_particle_state(sim);
  double *out = calloc(v.count * 15 + 1, sizeof *out);
  for (size_t i = 0; i < v.count; ++i) {
    double *o = out + 15 * (size_t)v.id[i];
    for (int d = 0; d < 3; ++d) o[d] = at(&v, v.x[d], i), o[3 + d] = at(&v, v.v[d], i);
    for (int c = 0; c < 9; ++c) o[6 + c] = at(&v, v.F[c], i);
  }
  *n = v.count;
  return out;
}

/* The script of test_scripted_collider: step k's pose, a slide in x and a turn about y. */
static void script_pose(int k, double c[3], double R[9]) {
  const double a = 0.01 * k;
  c[0] = 0.5 + 0.001 * k, c[1] = 0.5, c[2] = 0.5;
  const double Ry[9] = {cos(a), 0, sin(a), 0, 1, 0, -sin(a), 0, cos(a)};
  memcpy(R, Ry, sizeof Ry);
}

/* A scripted collider's velocity is its pose change over the step: the material it holds moves
 * with it; it stands still when not set; bad poses are refused; a resumed run that sets the same
 * poses continues bit-identically. */
static void test_scripted_collider(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(scripted_json, NULL, &sim, err, sizeof err), MPM_OK);
  const double c1[3] = {0.502, 0.5, 0.5};
  OK(sim, mpm_sim_set_collider_pose(sim, 0, c1, NULL));
  double t0 = mpm_sim_time(sim);
  OK(sim, mpm_sim_step(sim, 0));
  double dt = mpm_sim_time(sim) - t0;
  mpm_collider_state cs;
  OK(sim, mpm_sim_collider_pose(sim, 0, &cs));
  assert_close(cs.center[0], 0.502, 1e-6);
  assert_close(cs.velocity[0], 0.002 / dt, 1e-9 / dt);
  assert_close(cs.velocity[1], 0, 1e-12);
  /* the particles deep inside the sticky sphere move with it: those whose stencil (1.5 dx on
     each axis) lies inside it, 0.03 + 0.06 sqrt(3) < 0.14 from its centre */
  mpm_particle_view v = mpm_sim_particle_state(sim);
  size_t inside = 0;
  for (size_t i = 0; i < v.count; ++i) {
    double r2 = 0;
    for (int d = 0; d < 3; ++d) r2 += pow(at(&v, v.x[d], i) - 0.5, 2);
    if (r2 > 0.03 * 0.03) continue;
    ++inside;
    assert_close(at(&v, v.v[0], i), 0.002 / dt, TOL(1e-5, 1e-10) * 0.002 / dt);
    assert_close(at(&v, v.v[1], i), 0, TOL(1e-6, 1e-12) * 0.002 / dt);
  }
  print_message("scripted grip: dt %.4g s, %zu particles inside move at %.5g m/s\n", dt, inside,
                0.002 / dt);
  assert_true(inside >= 8); /* (particles 0.02 m apart) */
  /* not set again: it stands */
  OK(sim, mpm_sim_step(sim, 0));
  OK(sim, mpm_sim_collider_pose(sim, 0, &cs));
  assert_close(cs.center[0], 0.502, 1e-6);
  assert_true(cs.velocity[0] == 0 && cs.angular_velocity[1] == 0);
  /* a turn about y by 0.03 rad over a step */
  const double a = 0.03, Ry[9] = {cos(a), 0, sin(a), 0, 1, 0, -sin(a), 0, cos(a)};
  t0 = mpm_sim_time(sim);
  OK(sim, mpm_sim_set_collider_pose(sim, 0, c1, Ry));
  OK(sim, mpm_sim_step(sim, 0));
  dt = mpm_sim_time(sim) - t0;
  OK(sim, mpm_sim_collider_pose(sim, 0, &cs));
  assert_close(cs.angular_velocity[1], a / dt, 1e-9 / dt);
  assert_close(cs.angular_velocity[0], 0, 1e-9 / dt);
  for (int k = 0; k < 9; ++k) assert_close(cs.rotation[k], Ry[k], 1e-6);
  /* refusals */
  const double skew[9] = {1, 0.1, 0, 0, 1, 0, 0, 0, 1}, mirror[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double nan3[3] = {0.5, NAN, 0.5};
  assert_int_equal(mpm_sim_set_collider_pose(sim, 0, c1, skew), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "is not a rotation"));
  assert_int_equal(mpm_sim_set_collider_pose(sim, 0, c1, mirror), MPM_ERR_INVALID);
  assert_int_equal(mpm_sim_set_collider_pose(sim, 0, nan3, NULL), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "center[1]"));
  assert_int_equal(mpm_sim_set_collider_pose(sim, 1, c1, NULL), MPM_ERR_INVALID);
  mpm_sim_destroy(sim);

  /* a checkpoint between two scripted steps, resumed: the same state as straight through */
  char dir_a[512], dir_b[512]; /* (test_temp_dir's buffer is static) */
  snprintf(dir_a, sizeof dir_a, "%s", test_temp_dir("scripted_a"));
  snprintf(dir_b, sizeof dir_b, "%s", test_temp_dir("scripted_b"));
  double c[3], R[9];
  size_t na = 0, nb = 0;
  assert_int_equal(mpm_sim_create_from_json(scripted_json, NULL, &sim, err, sizeof err), MPM_OK);
  OK(sim, mpm_sim_enable_output(sim, dir_a));
  for (int k = 1; k <= 12; ++k) {
    script_pose(k, c, R);
    OK(sim, mpm_sim_set_collider_pose(sim, 0, c, R));
    OK(sim, mpm_sim_step(sim, 0));
  }
  double *a_state = state_by_id(sim, &na);
  mpm_sim_destroy(sim);
  assert_int_equal(mpm_sim_create_from_json(scripted_json, NULL, &sim, err, sizeof err), MPM_OK);
  OK(sim, mpm_sim_enable_output(sim, dir_b));
  for (int k = 1; k <= 6; ++k) {
    script_pose(k, c, R);
    OK(sim, mpm_sim_set_collider_pose(sim, 0, c, R));
    OK(sim, mpm_sim_step(sim, 0));
  }
  script_pose(7, c, R); /* set before the checkpoint: the pending pose is state too */
  OK(sim, mpm_sim_set_collider_pose(sim, 0, c, R));
  OK(sim, mpm_sim_write_checkpoint(sim, NULL, 0));
  mpm_sim_destroy(sim);
  assert_int_equal(mpm_sim_create_from_json(scripted_json, NULL, &sim, err, sizeof err), MPM_OK);
  OK(sim, mpm_sim_resume(sim, dir_b, NULL, 0));
  assert_int_equal(mpm_sim_steps(sim), 6);
  OK(sim, mpm_sim_step(sim, 0)); /* step 7, to the pose set before */
  for (int k = 8; k <= 12; ++k) {
    script_pose(k, c, R);
    OK(sim, mpm_sim_set_collider_pose(sim, 0, c, R));
    OK(sim, mpm_sim_step(sim, 0));
  }
  double *b_state = state_by_id(sim, &nb);
  assert_int_equal(na, nb);
  assert_memory_equal(a_state, b_state, 15 * na * sizeof(double));
  mpm_sim_destroy(sim);
  free(a_state);
  free(b_state);
}

/* The domains' view: each active domain particle (after the material points in the particle
 * view) sits at the mean of its hexahedron's eight corners (lattice cubes: omega = 1/8), whose
 * reference positions span one lattice cell; a scene without domains has none. */
static void test_domain_view(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_file("examples/ball_bunny.json", &sim, err, sizeof err),
                   MPM_OK);
  for (int round = 0; round < 2; ++round) {
    const mpm_particle_view p = mpm_sim_particle_state(sim);
    const mpm_domain_view d = mpm_sim_domain_view(sim);
    mpm_sim_info info;
    mpm_sim_get_info(sim, &info, sizeof info);
    assert_int_equal(d.particles, info.domain_particles);
    assert_int_equal(d.first + d.particles, p.count);
    assert_true(d.corners > d.particles / 8);
    if (round == 0) assert_null(d.enriched); /* no step yet: no marks */
    double worst = 0, h = -1;
    for (size_t j = 0; j < d.particles; ++j) {
      const uint32_t *c = d.corner + 8 * j;
      for (int a = 0; a < 8; ++a) assert_true(c[a] < d.corners);
      for (int e = 0; e < 3; ++e) {
        double mean = 0;
        for (int a = 0; a < 8; ++a) mean += at(&p, d.x[e], c[a]) / 8;
        worst = fmax(worst, fabs(mean - at(&p, p.x[e], d.first + j)));
        /* corner 7 is corner 0 plus one cell on every axis, at rest */
        const double side = at(&p, d.X[e], c[7]) - at(&p, d.X[e], c[0]);
        if (h < 0) h = side;
        assert_close(side, h, 1e-6);
      }
    }
    print_message("domain view (round %d): %zu particles, %zu corners, cell %.4g m, particles "
                  "off their corners' mean by <= %.3g m\n",
                  round, d.particles, d.corners, h, worst);
    assert_true(h > 0);
    assert_true(worst < TOL(1e-5, 1e-12));
    OK(sim, mpm_sim_step(sim, 0));
  }
  mpm_sim_destroy(sim);
  assert_int_equal(mpm_sim_create_from_json(points_json, NULL, &sim, err, sizeof err), MPM_OK);
  const mpm_domain_view none = mpm_sim_domain_view(sim);
  assert_int_equal(none.particles, 0);
  assert_int_equal(none.corners, 0);
  mpm_sim_destroy(sim);
}

/* A body added between steps: sampled with new ids and its velocity, checked with key paths
 * (nothing changes on a refusal), and a run with it resumes from its folder's scene.json
 * bit-identically. */
static void test_add_body(void **state) {
  (void)state;
  const char *ball = "{\"name\": \"ball\", \"shape\": {\"type\": \"sphere\", \"center\": "
                     "[0.5, 0.72, 0.5], \"radius\": 0.1}, \"material\": \"m\", "
                     "\"velocity\": [0, -1, 0]}";
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(points_json, NULL, &sim, err, sizeof err), MPM_OK);
  OK(sim, mpm_sim_step(sim, 0));
  const size_t before = mpm_sim_particle_count(sim);
  /* refusals change nothing */
  const char *bad[][2] = {
      {"{\"shape\": {\"type\": \"sphere\", \"center\": [0.5, 0.72, 0.5], \"radius\": 0.06}, "
       "\"material\": \"nope\"}",
       "bodies[1].material"},
      {"{\"shape\": {\"type\": \"sphere\", \"center\": [0.5, 0.99, 0.5], \"radius\": 0.06}, "
       "\"material\": \"m\"}",
       "bodies[1].shape"},
      {"{\"shape\": {\"type\": \"sphere\", \"center\": [0.5, 0.72, 0.5], \"radius\": 0.06}, "
       "\"material\": {\"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3, \"density\": 1000}}",
       "takes a material of the scene"},
      {"{\"shape\": {\"type\": \"sphere\", \"center\": [0.5, 0.72, 0.5], \"radius\": 0.06}, "
       "\"material\": \"m\", \"domains\": true, \"jitter\": 0}",
       "particle domains cannot be added"},
      {"[1, 2]", "expected the JSON object"},
  };
  for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
    assert_int_not_equal(mpm_sim_add_body(sim, bad[k][0], NULL, NULL), MPM_OK);
    if (!strstr(mpm_sim_last_error(sim), bad[k][1]))
      print_error("expected '%s' in: %s\n", bad[k][1], mpm_sim_last_error(sim));
    assert_non_null(strstr(mpm_sim_last_error(sim), bad[k][1]));
    assert_int_equal(mpm_sim_particle_count(sim), before);
  }
  size_t added = 0;
  OK(sim, mpm_sim_add_body(sim, ball, NULL, &added));
  assert_true(added > 100);
  assert_int_equal(mpm_sim_particle_count(sim), before + added);
  mpm_sim_info info;
  mpm_sim_get_info(sim, &info, sizeof info);
  assert_int_equal(info.bodies, 2);
  const mpm_particle_view v = mpm_sim_particle_state(sim);
  size_t new_ones = 0;
  for (size_t i = 0; i < v.count; ++i) {
    if (v.body[i] != 1) continue;
    ++new_ones;
    assert_true(v.id[i] >= before); /* ids never reused */
    assert_true(at(&v, v.v[1], i) == -1);
  }
  assert_int_equal(new_ones, added);
  OK(sim, mpm_sim_step(sim, 0));
  mpm_sim_destroy(sim);

  /* straight through, and with a checkpoint after the body, resumed from the folder's scene */
  char dir_a[512], dir_b[512], scene_b[600];
  snprintf(dir_a, sizeof dir_a, "%s", test_temp_dir("add_body_a"));
  snprintf(dir_b, sizeof dir_b, "%s", test_temp_dir("add_body_b"));
  snprintf(scene_b, sizeof scene_b, "%s/scene.json", dir_b);
  size_t na = 0, nb = 0;
  double *a_state = NULL, *b_state = NULL;
  for (int run = 0; run < 2; ++run) {
    assert_int_equal(mpm_sim_create_from_json(points_json, NULL, &sim, err, sizeof err), MPM_OK);
    OK(sim, mpm_sim_enable_output(sim, run ? dir_b : dir_a));
    for (int k = 0; k < 3; ++k) OK(sim, mpm_sim_step(sim, 0));
    OK(sim, mpm_sim_add_body(sim, ball, NULL, NULL));
    for (int k = 0; k < (run ? 2 : 5); ++k) OK(sim, mpm_sim_step(sim, 0));
    if (run == 0) {
      a_state = state_by_id(sim, &na);
    } else {
      OK(sim, mpm_sim_write_checkpoint(sim, NULL, 0));
      mpm_sim_destroy(sim);
      if (mpm_sim_create_from_file(scene_b, &sim, err, sizeof err) != MPM_OK)
        print_error("%s\n", err);
      assert_non_null(sim);
      OK(sim, mpm_sim_resume(sim, dir_b, NULL, 0));
      for (int k = 0; k < 3; ++k) OK(sim, mpm_sim_step(sim, 0));
      b_state = state_by_id(sim, &nb);
    }
    mpm_sim_destroy(sim);
  }
  assert_int_equal(na, nb);
  assert_memory_equal(a_state, b_state, 15 * na * sizeof(double));
  free(a_state);
  free(b_state);
}

static void test_view_temperature(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(
      mpm_sim_create_from_file("examples/zhu/melting_bunny.json", &sim, err, sizeof err), MPM_OK);
  const mpm_particle_view v = mpm_sim_particles(sim);
  assert_non_null(v.temperature);
  assert_true(v.count > 0);
  for (size_t i = 0; i < v.count; ++i) assert_true(isfinite(at(&v, v.temperature, i)));
  mpm_sim_destroy(sim);
}

static void test_collider_pose(void **state) {
  (void)state;
  mpm_sim *sim = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err), MPM_OK);
  assert_int_equal(mpm_sim_collider_count(sim), 1);
  mpm_collider_state c;
  assert_int_equal(mpm_sim_collider_pose(sim, 0, &c), MPM_OK);
  assert_string_equal(c.name, "pusher");
  assert_false(c.active); /* its window opens at 0.05 s */
  assert_close(c.center[0], 0.05, 1e-7);
  assert_close(c.rotation[0], 1, 1e-7);
  assert_close(c.rotation[4], 1, 1e-7);
  assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK); /* to t = 0.05 */
  assert_int_equal(mpm_sim_collider_pose(sim, 0, &c), MPM_OK);
  assert_true(c.active);
  assert_close(c.center[0], 0.05 + 0.5 * mpm_sim_time(sim), 1e-6);
  assert_close(c.velocity[0], 0.5, 1e-7);
  assert_int_equal(mpm_sim_collider_pose(sim, 1, &c), MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "collider 1"));
  mpm_sim_destroy(sim);
}

/* The bytes of a file (the caller frees), NULL when it cannot be read. */
static char *file_bytes(const char *path, long *size) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  *size = ftell(f);
  rewind(f);
  char *b = malloc((size_t)*size + 1);
  if (b && fread(b, 1, (size_t)*size, f) != (size_t)*size) {
    free(b);
    b = NULL;
  }
  fclose(f);
  return b;
}

static void assert_same_file(const char *dir_a, const char *dir_b, const char *name) {
  char a[700], b[700];
  snprintf(a, sizeof a, "%s/%s", dir_a, name);
  snprintf(b, sizeof b, "%s/%s", dir_b, name);
  long na = -1, nb = -2;
  char *ba = file_bytes(a, &na), *bb = file_bytes(b, &nb);
  if (!ba || !bb || na != nb || memcmp(ba, bb, (size_t)na) != 0)
    print_error("%s and %s differ\n", a, b);
  assert_true(ba && bb && na == nb && memcmp(ba, bb, (size_t)na) == 0);
  free(ba);
  free(bb);
}

static int by_name(const void *a, const void *b) {
  return strcmp((const char *)a, (const char *)b);
}

/* The entries of a folder but "." and "..", sorted, one per line. */
static void folder_listing(const char *dir, char *out, size_t cap) {
  char names[32][256];
  int n = 0;
  DIR *d = opendir(dir);
  assert_non_null(d);
  for (struct dirent *e; (e = readdir(d)) && n < 32;)
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
      snprintf(names[n++], sizeof names[0], "%s", e->d_name);
  closedir(d);
  qsort(names, (size_t)n, sizeof names[0], by_name);
  out[0] = 0;
  for (int k = 0; k < n; ++k) {
    const size_t used = strlen(out);
    snprintf(out + used, cap - used, "%s\n", names[k]);
  }
}

/* A one-off frame (mpm_sim_write_frame_to): the run's own files for the same state, byte for
 * byte, with nothing of the run's records, nothing counted; a name already there refuses the
 * whole unless overwriting, and a user's file beside it is never touched; the run's own folder
 * and a folder another simulation holds are refused. */
static void test_write_frame_to(void **state) {
  (void)state;
  char text[2048];
  snprintf(text, sizeof text, "%.*s, \"output\": {\"ply\": true}}",
           (int)strlen(test_block_json) - 1, test_block_json);
  char run[512], snap[512], held[512], written[512], listing[2048], path[700];
  snprintf(run, sizeof run, "%s", test_temp_dir("one_off_run"));
  snprintf(snap, sizeof snap, "%s/snapshots/a", test_temp_dir("one_off_snap"));
  snprintf(held, sizeof held, "%s", test_temp_dir("one_off_held"));
  mpm_sim *sim = NULL, *other = NULL;
  char err[1024];
  assert_int_equal(mpm_sim_create_from_json(text, NULL, &sim, err, sizeof err), MPM_OK);
  OK(sim, mpm_sim_open_output(sim, run, MPM_OUTPUT_NEW));
  OK(sim, mpm_sim_advance_frame(sim));
  mpm_sim_info before, after;
  mpm_sim_get_info(sim, &before, sizeof before);
  OK(sim, mpm_sim_write_frame_to(sim, snap, MPM_OUTPUT_NEW, written, sizeof written));
  print_message("one-off frame wrote:\n%s", written);
  assert_string_equal(written, "domains_0001.vtu\nframe_0001.ply\nframe_0001.vtu\n");
  folder_listing(snap, listing, sizeof listing); /* no index, no stats, nothing staged left */
  assert_string_equal(listing, ".mpm.lock\ndomains_0001.vtu\nframe_0001.ply\nframe_0001.vtu\n");
  assert_same_file(run, snap, "frame_0001.vtu");
  assert_same_file(run, snap, "frame_0001.ply");
  assert_same_file(run, snap, "domains_0001.vtu");
  mpm_sim_get_info(sim, &after, sizeof after);
  assert_int_equal(after.written_frames, before.written_frames);
  assert_int_equal(mpm_sim_frame(sim), 1);

  /* a name already there: refused whole, naming it; the user's file beside them untouched */
  snprintf(path, sizeof path, "%s/notes.txt", snap);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs("mine", f);
  fclose(f);
  OK(sim, mpm_sim_step(sim, 0)); /* mid-frame: a state the run never writes */
  assert_int_equal(mpm_sim_write_frame_to(sim, snap, MPM_OUTPUT_NEW, NULL, 0), MPM_ERR_INVALID);
  print_message("refused: %s\n", mpm_sim_last_error(sim));
  assert_non_null(strstr(mpm_sim_last_error(sim), "frame_0001.vtu"));
  assert_same_file(run, snap, "frame_0001.vtu");
  folder_listing(snap, listing, sizeof listing);
  assert_string_equal(listing,
                      ".mpm.lock\ndomains_0001.vtu\nframe_0001.ply\nframe_0001.vtu\nnotes.txt\n");
  /* overwriting replaces the frame's files only */
  OK(sim, mpm_sim_write_frame_to(sim, snap, MPM_OUTPUT_OVERWRITE, NULL, 0));
  folder_listing(snap, listing, sizeof listing);
  assert_string_equal(listing,
                      ".mpm.lock\ndomains_0001.vtu\nframe_0001.ply\nframe_0001.vtu\nnotes.txt\n");
  long n = 0, m = 0;
  char *mine = file_bytes(path, &n);
  assert_true(mine && n == 4 && memcmp(mine, "mine", 4) == 0);
  free(mine);
  snprintf(path, sizeof path, "%s/frame_0001.vtu", run);
  char *ran = file_bytes(path, &n);
  snprintf(path, sizeof path, "%s/frame_0001.vtu", snap);
  char *mid = file_bytes(path, &m);
  assert_true(ran && mid && (n != m || memcmp(ran, mid, (size_t)n) != 0)); /* a later state */
  free(ran);
  free(mid);

  /* the run's own folder, and a folder another simulation holds */
  assert_int_equal(mpm_sim_write_frame_to(sim, run, MPM_OUTPUT_OVERWRITE, NULL, 0),
                   MPM_ERR_INVALID);
  assert_non_null(strstr(mpm_sim_last_error(sim), "output folder"));
  assert_int_equal(mpm_sim_create_from_json(points_json, NULL, &other, err, sizeof err), MPM_OK);
  OK(other, mpm_sim_open_output(other, held, MPM_OUTPUT_NEW));
  assert_int_equal(mpm_sim_write_frame_to(sim, held, MPM_OUTPUT_OVERWRITE, NULL, 0), MPM_ERR_IO);
  print_message("held: %s\n", mpm_sim_last_error(sim));
  mpm_sim_destroy(other);
  /* the run goes on as if nothing had been written */
  OK(sim, mpm_sim_advance_frame(sim));
  assert_int_equal(mpm_sim_frame(sim), 2);
  mpm_sim_destroy(sim);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_view_holds_domain_particles),
      cmocka_unit_test(test_checkpoint_from_the_api),
      cmocka_unit_test(test_create_from_json),
      cmocka_unit_test(test_set_threads),
      cmocka_unit_test(test_view_fields),
      cmocka_unit_test(test_view_state_and_strides),
      cmocka_unit_test(test_set_velocities_and_positions),
      cmocka_unit_test(test_scripted_collider),
      cmocka_unit_test(test_domain_view),
      cmocka_unit_test(test_add_body),
      cmocka_unit_test(test_view_temperature),
      cmocka_unit_test(test_collider_pose),
      cmocka_unit_test(test_write_frame_to),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
