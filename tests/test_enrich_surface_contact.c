/* test_enrich_surface_contact.c - enriched parts meet enriched parts
 * (domain/enrich_surface_contact.h, bodies[].enrichment_surface_contact):
 *  - two blocks whose domains are all enriched, thrown at each other at 2 m/s each, pass
 *    through each other without the contact and bounce off each other with it: the relative
 *    velocity reversed, no corner of one inside the other's hexahedra at any step, linear
 *    momentum conserved, no energy gained;
 *  - a C-shaped body (all enriched) whose upper arm sags onto its lower arm under gravity
 *    passes through itself without self-contact (bodies[].enrichment_self_contact false) and
 *    not with it (the default);
 *  - 1 and 2 threads give bitwise the same state;
 *  - the key's errors. */
#include "support.h"
#include "core/mat3.h"
#include "core/parallel.h"
#include "domain/hex.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Block 0 at x = 0.38 m coming at 2 m/s, block 1 at x = 0.62 m at -2 m/s, each 8 x 8 x 8
 * domains of 0.02 m, every one enriched (epsilon 1); no gravity. Block 1 turns (at [2, 3, 0]
 * rad/s), so that corners meet faces, not the corners of the same lattice. */
static mpm_sim *blocks(int contact) {
  char text[2048];
  const char *key = contact ? "" : ", \"enrichment_surface_contact\": false";
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.04},"
           " \"gravity\": [0, 0, 0], \"time\": {\"end\": 1.0, \"fps\": 10},"
           " \"solver\": {\"transfer\": \"flip\", \"flip_alpha\": 0.95},"
           " \"materials\": [{\"name\": \"rubber\", \"model\": \"neo_hookean\", \"E\": 1e5, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"name\": \"left\", \"shape\": {\"type\": \"box\", \"center\": "
           "[0.38, 0.5, 0.5], \"half_extent\": [0.08, 0.08, 0.08]}, \"material\": \"rubber\", "
           "\"velocity\": [2, 0, 0], \"domains\": true, \"enrichment\": 1%s},"
           " {\"name\": \"right\", \"shape\": {\"type\": \"box\", \"center\": [0.62, 0.5, 0.5], "
           "\"half_extent\": [0.08, 0.08, 0.08]}, \"material\": \"rubber\", \"velocity\": [-2, "
           "0, 0], \"angular_velocity\": [2, 3, 0], \"domains\": true, \"enrichment\": 1%s}]}",
           key, key);
  return test_sim_from_json(text, "blocks.json");
}

/* The mass-weighted mean x and x velocity of body b's domain particles. */
static void body_motion(const mpm_sim *sim, int b, double *x, double *v) {
  const mpm_particles *p = &sim->domains.particles;
  double m = 0;
  *x = *v = 0;
  for (size_t i = 0; i < p->count; ++i) {
    if (p->body[i] != b) continue;
    *x += p->mass[i] * p->x[0][i];
    *v += p->mass[i] * p->v[0][i];
    m += p->mass[i];
  }
  *x /= m;
  *v /= m;
}

/* The body of corner c (its first particle's). */
static int corner_body(const mpm_domain_set *s, size_t c) {
  if (s->adj_start[c] == s->adj_start[c + 1]) return -1;
  return s->particles.body[s->adj[s->adj_start[c]] / MPM_HEX_CORNERS];
}

/* Whether x (inside q's bounding box) lies inside the trilinear hexahedron q (corner order of
 * hex.h), deeper than `skin` in its reference coordinates (Newton on the trilinear map). */
static int inside_hex(const double q[MPM_HEX_CORNERS][3], const double x[3], double skin) {
  double xi[3] = {0, 0, 0};
  for (int it = 0; it < 20; ++it) {
    double N[MPM_HEX_CORNERS], dN[MPM_HEX_CORNERS][3], r[3] = {0, 0, 0}, J[3][3] = {{0}};
    mpm_hex_shape(xi, N, dN);
    for (int a = 0; a < MPM_HEX_CORNERS; ++a)
      for (int d = 0; d < 3; ++d) {
        r[d] += N[a] * q[a][d];
        for (int e = 0; e < 3; ++e) J[d][e] += q[a][d] * dN[a][e];
      }
    for (int d = 0; d < 3; ++d) r[d] -= x[d];
    mpm_real A[9], inv[9]; /* the Newton step through J's inverse */
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) A[3 * d + e] = (mpm_real)J[d][e];
    if (!(fabs((double)mpm_m3_inverse(A, inv)) > 0)) return 0;
    for (int d = 0; d < 3; ++d)
      xi[d] -= inv[3 * d] * r[0] + inv[3 * d + 1] * r[1] + inv[3 * d + 2] * r[2];
  }
  for (int d = 0; d < 3; ++d)
    if (fabs(xi[d]) > 1 - skin) return 0;
  return 1;
}

/* The corners of one body inside another body's hexahedra (deeper than a tenth of the
 * hexahedron's half width). */
static size_t corners_inside(const mpm_sim *sim) {
  const mpm_domain_set *s = &sim->domains;
  size_t inside = 0;
  for (size_t p = 0; p < s->particles.count; ++p) {
    if (!s->active[p]) continue;
    double q[MPM_HEX_CORNERS][3], lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
    for (int a = 0; a < MPM_HEX_CORNERS; ++a)
      for (int d = 0; d < 3; ++d) {
        q[a][d] = s->cx[d][s->corner[p][a]];
        lo[d] = q[a][d] < lo[d] ? q[a][d] : lo[d];
        hi[d] = q[a][d] > hi[d] ? q[a][d] : hi[d];
      }
    for (size_t c = 0; c < s->corner_count; ++c) {
      const double x[3] = {s->cx[0][c], s->cx[1][c], s->cx[2][c]};
      if (x[0] < lo[0] || x[0] > hi[0] || x[1] < lo[1] || x[1] > hi[1] || x[2] < lo[2] ||
          x[2] > hi[2] || !s->corner_use[c] || corner_body(s, c) == s->particles.body[p])
        continue;
      inside += (size_t)inside_hex(q, x, 0.1);
    }
  }
  return inside;
}

static double energy(const mpm_sim *sim) {
  const mpm_diagnostics d = mpm_sim_diagnostics(sim);
  return d.kinetic + d.elastic;
}

static void test_blocks_bounce(void **state) {
  (void)state;
  double x[2][2], v[2][2], drift[2], gain[2];
  size_t worst[2];
  for (int on = 0; on < 2; ++on) {
    mpm_sim *sim = blocks(on);
    const mpm_diagnostics d0 = mpm_sim_diagnostics(sim);
    double left_x, left_v;
    body_motion(sim, 0, &left_x, &left_v);
    const double scale = fabs(left_v) * d0.mass / 2; /* one block's momentum */
    const double e0 = energy(sim);
    worst[on] = 0;
    gain[on] = 0;
    long long step = 0;
    while (sim->time < 0.12) {
      if (mpm_sim_step(sim, 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
      if (++step % 4 == 0) {
        const size_t in = corners_inside(sim);
        if (in > worst[on]) worst[on] = in;
      }
      gain[on] = fmax(gain[on], (energy(sim) - e0) / e0);
    }
    const mpm_diagnostics d1 = mpm_sim_diagnostics(sim);
    drift[on] = 0;
    for (int d = 0; d < 3; ++d) drift[on] = fmax(drift[on], fabs(d1.momentum[d] - d0.momentum[d]));
    drift[on] /= scale;
    for (int b = 0; b < 2; ++b) body_motion(sim, b, &x[on][b], &v[on][b]);
    print_message("surface contact %s: %lld steps, %lld contacts; blocks at x = %.3f, %.3f m "
                  "moving at %.3f, %.3f m/s; at most %zu corners inside the other block; "
                  "momentum drift %.2e of a block's; largest energy gain %.2e\n",
                  on ? "on" : "off", step, sim->surface_contacts, x[on][0], x[on][1], v[on][0],
                  v[on][1], worst[on], drift[on], gain[on]);
    if (on) assert_true(sim->surface_contacts > 0);
    if (!on) assert_int_equal(sim->surface_contacts, 0);
    mpm_sim_destroy(sim);
  }
  /* without the contact the blocks pass through each other */
  assert_true(x[0][0] > x[0][1]);
  assert_true(worst[0] > 100);
  /* with it they bounce off each other: the relative velocity reversed, no corner inside the
     other block, momentum kept, no energy gained */
  assert_true(x[1][0] < x[1][1]);
  assert_true(v[1][0] < 0 && v[1][1] > 0);
  assert_int_equal(worst[1], 0);
  assert_true(drift[1] < TOL(1e-6, 1e-12));
  assert_true(gain[1] < TOL(1e-5, 1e-10));
}

/* A C-shaped body (an extruded polygon: a back 0.04 m wide, a lower arm 0.24 m and an upper arm
 * 0.16 m long, both 0.04 m thick, 0.06 m apart, 0.12 m deep) lying on a floor, every domain
 * enriched; soft, so its upper arm sags onto its lower arm under gravity. */
static mpm_sim *folding(int contact, char *mesh, size_t mesh_size) {
  snprintf(mesh, mesh_size, "/tmp/mpm_test_c_shape_%ld.obj", (long)getpid());
  FILE *f = fopen(mesh, "w");
  assert_non_null(f);
  const double t = 0.04, g = 0.06, L = 0.24, Lu = 0.16, W = 0.12;
  const double P[8][2] = {{0, 0},     {L, 0},      {L, t},          {t, t},
                          {t, t + g}, {Lu, t + g}, {Lu, 2 * t + g}, {0, 2 * t + g}};
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < 8; ++k) fprintf(f, "v %.6f %.6f %.6f\n", P[k][0], P[k][1], z * W);
  /* the caps: the polygon in six triangles (z = 0 facing -z, z = W facing +z) */
  static const int T[6][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 7}, {4, 5, 6}, {4, 6, 7}};
  for (int k = 0; k < 6; ++k) {
    fprintf(f, "f %d %d %d\n", T[k][0] + 1, T[k][2] + 1, T[k][1] + 1);
    fprintf(f, "f %d %d %d\n", T[k][0] + 9, T[k][1] + 9, T[k][2] + 9);
  }
  for (int k = 0; k < 8; ++k) { /* the sides, outward for a counter-clockwise polygon */
    const int a = k + 1, b = (k + 1) % 8 + 1;
    fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, b + 8, a, b + 8, a + 8);
  }
  fclose(f);
  char text[2048];
  snprintf(text, sizeof text,
           "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.04},"
           " \"gravity\": [0, -9.81, 0], \"time\": {\"end\": 1.0, \"fps\": 10},"
           " \"solver\": {\"transfer\": \"flip\", \"flip_alpha\": 0.95},"
           " \"materials\": [{\"name\": \"soft\", \"model\": \"neo_hookean\", \"E\": 2e4, "
           "\"nu\": 0.3, \"density\": 1000}],"
           " \"bodies\": [{\"name\": \"c\", \"shape\": {\"type\": \"mesh\", \"file\": \"%s\", "
           "\"center\": [0.5, 0.29, 0.5], \"scale\": 1}, \"material\": \"soft\", \"domains\": "
           "true, \"enrichment\": 1%s}],"
           " \"colliders\": [{\"name\": \"floor\", \"shape\": {\"type\": \"halfspace\", \"point\": "
           "[0, 0.2, 0], \"normal\": [0, 1, 0]}, \"rule\": \"separate\", \"friction\": 0.5}]}",
           mesh, contact ? "" : ", \"enrichment_self_contact\": false");
  return test_sim_from_json(text, "folding.json");
}

/* How deep the upper arm's lower corners are below the lower arm's upper surface, m (negative:
 * above it): for each such corner, the surface's height at its x between the two nearest of
 * the lower arm's upper corners on either side in its row (within half a lattice spacing in z).
 * Corners by their reference positions: the mesh's centre is at [0.5, 0.29, 0.5], its origin
 * at [0.38, 0.22, 0.44]; the arms from 0.06 m beyond the back's outer face. */
static double sag_depth(const mpm_sim *sim) {
  const mpm_domain_set *s = &sim->domains;
  const double h = 0.02, x0 = 0.38, y0 = 0.22;
  double depth = -1e30;
  for (size_t u = 0; u < s->corner_count; ++u) {
    if (!s->corner_use[u] || s->cX[0][u] - x0 < 0.06 || fabs(s->cX[1][u] - y0 - 0.10) > 1e-4)
      continue;
    const double xu = s->cx[0][u];
    double left = -1e30, right = 1e30, yl = 0, yr = 0;
    for (size_t l = 0; l < s->corner_count; ++l) {
      if (!s->corner_use[l] || s->cX[0][l] - x0 < 0.06 || fabs(s->cX[1][l] - y0 - 0.04) > 1e-4 ||
          fabs(s->cx[2][u] - s->cx[2][l]) > h / 2)
        continue;
      const double xl = s->cx[0][l];
      if (xl <= xu && xl > left) left = xl, yl = s->cx[1][l];
      if (xl >= xu && xl < right) right = xl, yr = s->cx[1][l];
    }
    if (left < -1e29 || right > 1e29) continue; /* beyond the lower arm's ends */
    const double y = right > left ? yl + (yr - yl) * (xu - left) / (right - left) : yl;
    depth = fmax(depth, y - s->cx[1][u]);
  }
  return depth;
}

static void test_c_shape_does_not_pass_through_itself(void **state) {
  (void)state;
  double depth[2];
  long long contacts[2];
  char mesh[128];
  for (int on = 0; on < 2; ++on) {
    mpm_sim *sim = folding(on, mesh, sizeof mesh);
    depth[on] = -1e30;
    while (sim->time < 0.5) {
      if (mpm_sim_step(sim, 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(sim));
      depth[on] = fmax(depth[on], sag_depth(sim));
    }
    contacts[on] = sim->surface_contacts;
    print_message("self-contact %s: the upper arm at most %.4f m into the lower one, %lld "
                  "contacts\n",
                  on ? "on" : "off", depth[on], contacts[on]);
    mpm_sim_destroy(sim);
  }
  unlink(mesh);
  /* without self-contact the upper arm sinks through the lower one */
  assert_true(depth[0] > 0.03);
  /* with it the upper arm rests on the lower one: a corner that slides in past a turning face
     of its own body is not pushed back out (enrich_surface_contact.c: from behind its own
     body's faces it would tear a crushed body), so the arm may sink in by less than a third of
     a lattice spacing (0.02 m), against its whole thickness (0.04 m) without */
  assert_true(contacts[1] > 0);
  assert_true(depth[1] < 0.006);
}

static void test_threads_bitwise(void **state) {
  (void)state;
  mpm_sim *run[2];
  for (int t = 0; t < 2; ++t) {
    mpm_set_threads(t + 1);
    run[t] = blocks(1);
    while (run[t]->time < 0.05)
      if (mpm_sim_step(run[t], 0) != MPM_OK) fail_msg("%s", mpm_sim_last_error(run[t]));
  }
  mpm_set_threads(0);
  assert_true(run[0]->surface_contacts > 0);
  assert_int_equal(run[0]->surface_contacts, run[1]->surface_contacts);
  const mpm_domain_set *sa = &run[0]->domains, *sb = &run[1]->domains;
  assert_int_equal(sa->corner_count, sb->corner_count);
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(sa->cx[d], sb->cx[d], sa->corner_count * sizeof(mpm_real));
    assert_memory_equal(sa->particles.v[d], sb->particles.v[d],
                        sa->particles.count * sizeof(mpm_real));
  }
  mpm_sim_destroy(run[0]);
  mpm_sim_destroy(run[1]);
}

static void test_scene_key(void **state) {
  (void)state;
  static const char *const bad[] = {
      "\"domains\": true, \"enrichment_surface_contact\": 0",
      "\"enrichment_surface_contact\": false",
      "\"domains\": true, \"enrichment_self_contact\": \"yes\"",
      "\"enrichment_self_contact\": true",
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
    const char *key =
        k < 2 ? "bodies[0].enrichment_surface_contact" : "bodies[0].enrichment_self_contact";
    if (!strstr(err.message, key)) fail_msg("'%s' lacks '%s'", err.message, key);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_blocks_bounce),
      cmocka_unit_test(test_c_shape_does_not_pass_through_itself),
      cmocka_unit_test(test_threads_bitwise),
      cmocka_unit_test(test_scene_key),
  };
  return test_cleanup(cmocka_run_group_tests_name("enrich_surface_contact", tests, NULL, NULL));
}
