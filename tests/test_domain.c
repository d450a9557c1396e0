/* test_domain.c - Zhu et al. 2017's particle domains against independent truth: the weights
 * omega_ap (eq. 6) and their gradient averages (eq. 5) by partition of unity, linear
 * reproduction and a fine quadrature of the definitions; the two-step weights against the
 * directly integrated omega_ip; domains built from a body's lattice (shared corners, initial
 * velocity field reproduced); F from the reference-configuration update (eq. 7) exact for an
 * affine corner motion; mass and momentum conserved through the two-step transfers. */
#include "support.h"
#include "domain/domain.h"
#include "domain/domain_transfer.h"
#include "scene/sample.h"
#include "solver/explicit_update.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* 4-point Gauss-Legendre rule on [-1, 1]: exact to degree 7, so exact for every integrand here
 * (trilinear shape functions times the Jacobian determinant or its cofactors), and not the
 * 2-point rule the code under test uses. */
static const double GAUSS4_X[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                   0.8611363115940526};
static const double GAUSS4_W[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                   0.3478548451374538};

/* A hexahedron: the cube [0, h]^3 with its corners moved by up to `wobble` h at random. */
static void random_hex(uint64_t *rng, double h, double wobble, double X[8][3]) {
  for (int a = 0; a < 8; ++a)
    for (int d = 0; d < 3; ++d)
      X[a][d] = (((a >> d) & 1) ? h : 0) + test_rand(rng, -wobble, wobble) * h;
}

/* X(xi) and det dX/dxi of a trilinear hexahedron. */
static double map_point(const double X[8][3], const double xi[3], double x[3], double N[8],
                        double dN[8][3]) {
  mpm_hex_shape(xi, N, dN);
  double J[3][3] = {{0}};
  for (int d = 0; d < 3; ++d) x[d] = 0;
  for (int a = 0; a < 8; ++a)
    for (int r = 0; r < 3; ++r) {
      x[r] += N[a] * X[a][r];
      for (int c = 0; c < 3; ++c) J[r][c] += X[a][r] * dN[a][c];
    }
  return J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
         J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
         J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
}

/* inv = (dX/dxi)^-1 at a point with shape derivatives dN; returns det. */
static double inverse_jacobian(const double X[8][3], const double dN[8][3], double inv[3][3]) {
  double J[3][3] = {{0}};
  for (int a = 0; a < 8; ++a)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) J[r][c] += X[a][r] * dN[a][c];
  const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                     J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                     J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
  inv[0][0] = (J[1][1] * J[2][2] - J[1][2] * J[2][1]) / det;
  inv[0][1] = (J[0][2] * J[2][1] - J[0][1] * J[2][2]) / det;
  inv[0][2] = (J[0][1] * J[1][2] - J[0][2] * J[1][1]) / det;
  inv[1][0] = (J[1][2] * J[2][0] - J[1][0] * J[2][2]) / det;
  inv[1][1] = (J[0][0] * J[2][2] - J[0][2] * J[2][0]) / det;
  inv[1][2] = (J[0][2] * J[1][0] - J[0][0] * J[1][2]) / det;
  inv[2][0] = (J[1][0] * J[2][1] - J[1][1] * J[2][0]) / det;
  inv[2][1] = (J[0][1] * J[2][0] - J[0][0] * J[2][1]) / det;
  inv[2][2] = (J[0][0] * J[1][1] - J[0][1] * J[1][0]) / det;
  return det;
}

static void test_weights_cube(void **state) {
  (void)state;
  double X[8][3], w[8], g[8][3], V;
  uint64_t rng = 1;
  random_hex(&rng, 0.1, 0, X);
  assert_int_equal(mpm_domain_weights(X, w, g, &V), MPM_OK);
  assert_close(V, 1e-3, 1e-15);
  for (int a = 0; a < 8; ++a) {
    assert_close(w[a], 0.125, 1e-15);
    /* average of dN_a/dX_d over the cube: +-1/(4 h) */
    for (int d = 0; d < 3; ++d) assert_close(g[a][d], (((a >> d) & 1) ? 1 : -1) / 0.4, 1e-12);
  }
}

/* Partition of unity, linear reproduction and the definitions, on distorted hexahedra. */
static void test_weights_distorted(void **state) {
  (void)state;
  uint64_t rng = 12345;
  for (int trial = 0; trial < 20; ++trial) {
    double X[8][3], w[8], g[8][3], V;
    random_hex(&rng, 0.05, 0.2, X);
    assert_int_equal(mpm_domain_weights(X, w, g, &V), MPM_OK);
    double sw = 0, sg[3] = {0, 0, 0}, XG[3][3] = {{0}};
    for (int a = 0; a < 8; ++a) {
      sw += w[a];
      for (int r = 0; r < 3; ++r) {
        sg[r] += g[a][r];
        for (int c = 0; c < 3; ++c) XG[r][c] += X[a][r] * g[a][c];
      }
    }
    assert_close(sw, 1, 1e-14);
    for (int r = 0; r < 3; ++r) {
      assert_close(sg[r] * 0.05, 0, 1e-13);
      for (int c = 0; c < 3; ++c) assert_close(XG[r][c], r == c, 1e-13);
    }
    /* the definitions by the 4^3 Gauss rule in xi: V, int N_a / V, int grad N_a / V and the
     * centroid (linear reproduction: sum_a omega_ap X_a is the centroid of the domain) */
    const int M = 4;
    double Vq = 0, wq[8] = {0}, gq[8][3] = {{0}}, cq[3] = {0, 0, 0};
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < M; ++j)
        for (int k = 0; k < M; ++k) {
          const double xi[3] = {GAUSS4_X[i], GAUSS4_X[j], GAUSS4_X[k]};
          double x[3], N[8], dN[8][3];
          const double det = map_point(X, xi, x, N, dN);
          const double dv = det * GAUSS4_W[i] * GAUSS4_W[j] * GAUSS4_W[k];
          double inv[3][3]; /* grad_X N = J^-T grad_xi N */
          inverse_jacobian(X, dN, inv);
          Vq += dv;
          for (int d = 0; d < 3; ++d) cq[d] += x[d] * dv;
          for (int a = 0; a < 8; ++a) {
            wq[a] += N[a] * dv;
            for (int d = 0; d < 3; ++d) /* dN/dX_d = sum_c dN/dxi_c dxi_c/dX_d */
              gq[a][d] += (dN[a][0] * inv[0][d] + dN[a][1] * inv[1][d] + dN[a][2] * inv[2][d]) * dv;
          }
        }
    assert_close(V, Vq, 1e-12 * Vq);
    double c[3] = {0, 0, 0};
    for (int a = 0; a < 8; ++a) {
      assert_close(w[a], wq[a] / Vq, 1e-13);
      for (int d = 0; d < 3; ++d) {
        assert_close(g[a][d], gq[a][d] / Vq, 1e-12 * (fabs(g[a][d]) + 1));
        c[d] += w[a] * X[a][d];
      }
    }
    for (int d = 0; d < 3; ++d) assert_close(c[d], cq[d] / Vq, 1e-14);
  }
  /* an inverted hexahedron is refused */
  double X[8][3], w[8], g[8][3], V;
  random_hex(&rng, 0.05, 0, X);
  for (int a = 0; a < 8; ++a) X[a][0] = -X[a][0];
  assert_int_equal(mpm_domain_weights(X, w, g, &V), MPM_ERR_INVALID);
}

/* Linear hat weight of node i (index) at x, grid spacing dx (Zhu eqs. 2-3). */
static double hat(const int i[3], const double x[3], double dx) {
  double w = 1;
  for (int d = 0; d < 3; ++d) {
    const double r = fabs(x[d] / dx - i[d]);
    w *= r < 1 ? 1 - r : 0;
  }
  return w;
}

/* omega_ip = sum_a omega_ap omega_i(x_a) and its gradient (eq. 5) against the integral of
 * omega_i^*(X) = sum_a N_a(X) omega_i(x_a) over the reference domain (eq. 4), done directly. */
static void test_two_step_equals_direct(void **state) {
  (void)state;
  uint64_t rng = 777;
  const double dx = 0.1;
  for (int trial = 0; trial < 5; ++trial) {
    double X[8][3], x[8][3], w[8], g[8][3], V;
    random_hex(&rng, 0.04, 0.15, X);
    for (int a = 0; a < 8; ++a) /* deformed corners: shifted into the grid and distorted */
      for (int d = 0; d < 3; ++d) x[a][d] = 0.23 + 1.3 * X[a][d] + test_rand(&rng, -0.01, 0.01);
    mpm_domain_weights(X, w, g, &V);
    for (int i0 = 1; i0 <= 3; ++i0)
      for (int i1 = 1; i1 <= 3; ++i1)
        for (int i2 = 1; i2 <= 3; ++i2) {
          const int node[3] = {i0, i1, i2};
          double two = 0, two_g[3] = {0, 0, 0};
          for (int a = 0; a < 8; ++a) {
            const double wa = hat(node, x[a], dx);
            two += w[a] * wa;
            for (int d = 0; d < 3; ++d) two_g[d] += wa * g[a][d];
          }
          const int M = 4;
          double direct = 0, direct_g[3] = {0, 0, 0}, vol = 0;
          for (int i = 0; i < M; ++i)
            for (int j = 0; j < M; ++j)
              for (int k = 0; k < M; ++k) {
                const double xi[3] = {GAUSS4_X[i], GAUSS4_X[j], GAUSS4_X[k]};
                double p[3], N[8], dN[8][3];
                const double det = map_point(X, xi, p, N, dN);
                const double dv = det * GAUSS4_W[i] * GAUSS4_W[j] * GAUSS4_W[k];
                double star = 0, dstar[3] = {0, 0, 0}; /* omega_i^* and d/dxi of it */
                for (int a = 0; a < 8; ++a) {
                  const double wa = hat(node, x[a], dx);
                  star += N[a] * wa;
                  for (int c = 0; c < 3; ++c) dstar[c] += dN[a][c] * wa;
                }
                double inv[3][3];
                inverse_jacobian(X, dN, inv);
                for (int d = 0; d < 3; ++d)
                  direct_g[d] +=
                      (dstar[0] * inv[0][d] + dstar[1] * inv[1][d] + dstar[2] * inv[2][d]) * dv;
                direct += star * dv;
                vol += dv;
              }
          assert_close(two, direct / vol, 1e-13);
          for (int d = 0; d < 3; ++d)
            assert_close(two_g[d], direct_g[d] / vol, 1e-12 * (fabs(two_g[d]) + 1));
        }
  }
}

/* F = sum_a x_a g_ap^T after eq. 7 when the corners move affinely, x = A X + b. */
static void test_affine_motion_exact_F(void **state) {
  (void)state;
  mpm_domain_set s;
  mpm_domain_set_init(&s);
  mpm_particles p;
  mpm_particles_init(&p, 64);
  const double h = 0.05, origin[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) {
        const mpm_real x[3] = {(mpm_real)((i + 0.5) * h + 0.2), (mpm_real)((j + 0.5) * h + 0.2),
                               (mpm_real)((k + 0.5) * h + 0.2)};
        const mpm_real v[3] = {0, 0, 0};
        mpm_particles_push(&p, x, v, 1, (mpm_real)(h * h * h), 0, 0);
      }
  mpm_error err;
  assert_int_equal(mpm_domain_set_add_lattice(&s, &p, 0, origin, h, "bodies[0]", &err), MPM_OK);
  assert_int_equal(p.count, 0);
  assert_int_equal(s.particles.count, 12);
  assert_int_equal(s.corner_count, 4 * 3 * 3); /* (3+1)(2+1)(2+1) shared corners */
  const double A[3][3] = {{1.3, 0.2, -0.1}, {-0.15, 0.7, 0.05}, {0.1, 0.3, 0.9}};
  const double b[3] = {0.01, -0.02, 0.03}, dt = 1e-3;
  mpm_real vg[3][4 * 3 * 3];
  for (size_t c = 0; c < s.corner_count; ++c)
    for (int r = 0; r < 3; ++r) {
      double xn = b[r];
      for (int t = 0; t < 3; ++t) xn += A[r][t] * s.cX[t][c];
      vg[r][c] = (mpm_real)((xn - s.cX[r][c]) / dt);
    }
  const mpm_real *const v[3] = {vg[0], vg[1], vg[2]};
  for (size_t q = 0; q < s.particles.count; ++q) {
    mpm_domain_update_F(&s, q, (mpm_real)dt, v);
    for (int r = 0; r < 3; ++r)
      for (int t = 0; t < 3; ++t)
        assert_close(s.particles.F[3 * r + t][q], A[r][t], TOL(2e-3, 1e-11));
  }
  mpm_particles_free(&p);
  mpm_domain_set_free(&s);
}

/* Fragments (domain.h, MPM_DOMAIN_MIN_FRAGMENT): a 3 x 3 x 3 block with a particle touching it
 * at a corner, a pair touching it along an edge and a row of 8 touching it at a corner: the
 * single and the pair are dropped, the row (8 particles) and the block stay; a body that is
 * only a pair keeps it (its largest component). */
static void push_cell(mpm_particles *p, double h, int i, int j, int k, uint32_t id) {
  const mpm_real x[3] = {(mpm_real)((i + 0.5) * h + 0.2), (mpm_real)((j + 0.5) * h + 0.2),
                         (mpm_real)((k + 0.5) * h + 0.2)};
  const mpm_real v[3] = {0, 0, 0};
  mpm_particles_push(p, x, v, 1, (mpm_real)(h * h * h), 0, 0);
  p->id[p->count - 1] = id;
}

static void test_fragments_dropped(void **state) {
  (void)state;
  const double h = 0.05, origin[3] = {0, 0, 0};
  for (int alone = 0; alone < 2; ++alone) {
    mpm_domain_set s;
    mpm_domain_set_init(&s);
    mpm_particles p;
    mpm_particles_init(&p, 64);
    uint32_t id = 0;
    if (!alone)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) push_cell(&p, h, i, j, k, id++);
    push_cell(&p, h, 5, 5, 5, 100); /* a pair, alone or away from the block */
    push_cell(&p, h, 5, 5, 6, 101);
    if (!alone) {
      push_cell(&p, h, 3, 3, 1, 200); /* the edge pair */
      push_cell(&p, h, 3, 3, 2, 201);
      for (int i = 0; i < 8; ++i) push_cell(&p, h, -1 - i, -1, -1, 300 + (uint32_t)i); /* row */
    }
    mpm_error err;
    assert_int_equal(mpm_domain_set_add_lattice(&s, &p, 0, origin, h, "bodies[0]", &err), MPM_OK);
    assert_int_equal(p.count, 0);
    int kept[400] = {0};
    for (size_t q = 0; q < s.particles.count; ++q) kept[s.particles.id[q]] = 1;
    if (alone) {
      assert_int_equal(s.particles.count, 2);
    } else {
      /* the block, the row; not the pair at (5, 5, 5) that touches the block at no point nor
       * the edge pair */
      assert_int_equal(s.particles.count, 27 + 8);
      assert_true(kept[0] && kept[26] && kept[300] && kept[307]);
      assert_true(!kept[100] && !kept[101] && !kept[200] && !kept[201]);
    }
    mpm_particles_free(&p);
    mpm_domain_set_free(&s);
  }
}

/* A sphere body with a rigid rotation: corners shared, particles reproduced by their corners,
 * the rotation field carried over exactly; a body off the lattice is refused. */
static void test_build_from_body(void **state) {
  (void)state;
  const char *text =
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05},"
      " \"time\": {\"end\": 1, \"fps\": 10},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"fixed_corotated\", \"E\": 1e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.5,0.5,0.5], "
      "\"radius\": 0.12}, \"material\": \"m\", \"jitter\": %s, \"velocity\": [0.1,0,0],"
      " \"angular_velocity\": [0,0,2]}]}";
  char buf[1024];
  snprintf(buf, sizeof buf, text, "0");
  mpm_scene scene;
  mpm_error err;
  assert_int_equal(mpm_scene_parse(buf, "s.json", &scene, &err), MPM_OK);
  mpm_particles p;
  mpm_particles_init(&p, 64);
  assert_int_equal(mpm_sample_body(&scene, 0, &p, &err), MPM_OK);
  const size_t n = p.count;
  mpm_particles ref;
  mpm_particles_init(&ref, n);
  for (size_t i = 0; i < n; ++i) {
    const mpm_real x[3] = {p.x[0][i], p.x[1][i], p.x[2][i]};
    const mpm_real v[3] = {p.v[0][i], p.v[1][i], p.v[2][i]};
    mpm_particles_push(&ref, x, v, p.mass[i], p.vol0[i], 0, 0);
  }
  mpm_domain_set s;
  mpm_domain_set_init(&s);
  const double h = mpm_sample_spacing(&scene, 0);
  assert_int_equal(mpm_domain_set_add_lattice(&s, &p, 0, scene.box_min, h, "bodies[0]", &err),
                   MPM_OK);
  assert_int_equal(s.particles.count, n);
  assert_true(s.corner_count < 2 * n); /* shared: about one corner per particle */
  size_t shared8 = 0;
  for (size_t c = 0; c < s.corner_count; ++c) shared8 += s.adj_start[c + 1] - s.adj_start[c] == 8;
  assert_true(shared8 > n / 3);
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      assert_close(s.particles.x[d][i], ref.x[d][i], TOL(1e-6, 1e-14));
      assert_close(s.particles.v[d][i], ref.v[d][i], TOL(1e-6, 1e-13));
    }
  /* lattice cubes: the transfers take w = 1/8 and g = +-1/(4h) from cube_g, which holds the
   * stored g's magnitude bit for bit; a hexahedron off the pattern reads its stored values */
  for (size_t i = 0; i < n; ++i) {
    assert_true(s.cube_g[i] == s.g[i][7][0]);
    assert_close(s.cube_g[i], 1 / (4 * h), TOL(1e-6, 1e-13) / h);
  }
  s.g[1][3][1] *= (mpm_real)1.01;
  assert_int_equal(mpm_domain_set_rebuild(&s), MPM_OK);
  assert_true(s.cube_g[1] == 0);
  assert_true(s.cube_g[0] == s.g[0][7][0] && s.cube_g[2] == s.g[2][7][0]);
  mpm_domain_set_free(&s);
  mpm_scene_free(&scene);

  snprintf(buf, sizeof buf, text, "0.5");
  assert_int_equal(mpm_scene_parse(buf, "s.json", &scene, &err), MPM_OK);
  p.count = 0;
  assert_int_equal(mpm_sample_body(&scene, 0, &p, &err), MPM_OK);
  mpm_domain_set_init(&s);
  assert_int_equal(mpm_domain_set_add_lattice(&s, &p, 0, scene.box_min, h, "bodies[0]", &err),
                   MPM_ERR_INVALID);
  assert_non_null(strstr(err.message, "jitter"));
  mpm_domain_set_free(&s);
  mpm_scene_free(&scene);
  mpm_particles_free(&p);
  mpm_particles_free(&ref);
}

/* A randomly deformed, moving block of 6 x 5 x 4 domain particles (mass 0.5 to 1.5) on a sparse
 * grid, activated and laid out for one step of transfers. */
typedef struct block_fixture {
  mpm_domain_set s;
  mpm_particles p, none;
  mpm_material mat;
  mpm_transfer_ctx ctx;
  mpm_grid grid;
  mpm_arena scratch;
  mpm_dofs dofs;
  mpm_grid_values val;
  mpm_explicit_update u;
} block_fixture;

static void block_setup(block_fixture *fx, mpm_kernel_kind kind, mpm_transfer_kind transfer) {
  memset(fx, 0, sizeof *fx);
  mpm_domain_set *s = &fx->s;
  mpm_domain_set_init(s);
  mpm_particles_init(&fx->p, 64);
  const double h = 0.025, dx = 0.05, origin[3] = {0, 0, 0};
  uint64_t rng = 99;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 4; ++k) {
        const mpm_real x[3] = {(mpm_real)((i + 0.5) * h + 0.3), (mpm_real)((j + 0.5) * h + 0.3),
                               (mpm_real)((k + 0.5) * h + 0.3)};
        const mpm_real v[3] = {0, 0, 0};
        mpm_particles_push(&fx->p, x, v, (mpm_real)test_rand(&rng, 0.5, 1.5), (mpm_real)(h * h * h),
                           0, 0);
      }
  mpm_error err;
  assert_int_equal(mpm_domain_set_add_lattice(s, &fx->p, 0, origin, h, "b", &err), MPM_OK);
  for (size_t c = 0; c < s->corner_count; ++c)
    for (int d = 0; d < 3; ++d) {
      s->cv[d][c] = (mpm_real)test_rand(&rng, -1, 1);
      s->cx[d][c] += (mpm_real)test_rand(&rng, -0.2, 0.2) * (mpm_real)h;
    }
  for (size_t c = 0; c < s->corner_count; ++c) /* an affine moment, for APIC */
    for (int e = 0; e < 9; ++e) s->cB[e][c] = (mpm_real)test_rand(&rng, -1e-3, 1e-3);
  mpm_domain_set_sync_particles(s);
  for (size_t q = 0; q < s->particles.count; ++q)
    for (int e = 0; e < 9; ++e) s->particles.F[e][q] += (mpm_real)test_rand(&rng, -0.2, 0.2);

  mpm_material_desc md = mpm_material_desc_default();
  md.model = MPM_MODEL_FIXED_COROTATED;
  md.E = 1e5;
  mpm_material_init(&fx->mat, &md);
  mpm_transfer_ctx *ctx = &fx->ctx;
  ctx->kernel = mpm_kernel_make(kind, (mpm_real)dx, (mpm_real)dx);
  ctx->dt = (mpm_real)1e-3;
  ctx->transfer = transfer;
  ctx->flip_alpha = (mpm_real)0.95;
  ctx->materials = &fx->mat;
  ctx->material_count = 1;
  for (int d = 0; d < 3; ++d) {
    ctx->clamp_lo[d] = -10;
    ctx->clamp_hi[d] = 10;
  }
  mpm_grid_init_sparse(&fx->grid, 0, ctx->origin, (mpm_real)dx);
  mpm_particles_init(&fx->none, 16);
  mpm_arena_init(&fx->scratch);
  assert_int_equal(fx->grid.ops->activate(&fx->grid, &ctx->kernel, 1, &fx->none, &fx->scratch),
                   MPM_OK);
  assert_int_equal(mpm_domain_activate(s, &fx->grid, &ctx->kernel), MPM_OK);
  assert_int_equal(mpm_domain_plan(s, &fx->grid, &ctx->kernel, &fx->scratch), MPM_OK);
  mpm_dofs_init(&fx->dofs);
  mpm_dofs_begin_layout(&fx->dofs);
  assert_int_equal(mpm_dofs_add_grid(&fx->dofs, &fx->grid), MPM_OK);
  assert_int_equal(mpm_dofs_end_layout(&fx->dofs, MPM_DOF_ALL), MPM_OK);
  mpm_dofs_clear(&fx->dofs, MPM_DOF_ALL);
  fx->val = mpm_dofs_grid_values(&fx->dofs, &fx->grid);
  /* the grid update: no gravity, no walls */
  fx->u.dt = ctx->dt;
  for (int d = 0; d < 3; ++d) {
    fx->u.boundary.wall_lo[d] = -1000000;
    fx->u.boundary.wall_hi[d] = 1000000;
  }
}

static void block_free(block_fixture *fx) {
  mpm_grid_free(&fx->grid);
  mpm_dofs_free(&fx->dofs);
  mpm_arena_free(&fx->scratch);
  mpm_particles_free(&fx->none);
  mpm_particles_free(&fx->p);
  mpm_domain_set_free(&fx->s);
}

/* Mass, momentum and (zero) total internal force through particle -> corner -> grid, and
 * momentum back through grid -> corner -> particle, for a randomly deformed, moving block. */
static void run_conservation(mpm_kernel_kind kind) {
  block_fixture fx;
  block_setup(&fx, kind, MPM_TRANSFER_FLIP);
  mpm_domain_set *s = &fx.s;
  mpm_domain_p2g(&fx.ctx, s, &fx.grid, &fx.val, &fx.scratch);

  double m_p = 0, P_p[3] = {0, 0, 0};
  for (size_t q = 0; q < s->particles.count; ++q) {
    m_p += s->particles.mass[q];
    for (int d = 0; d < 3; ++d) P_p[d] += (double)s->particles.mass[q] * s->particles.v[d][q];
  }
  double m_g = 0, P_g[3] = {0, 0, 0}, f_g[3] = {0, 0, 0}, f_abs = 0;
  for (size_t n = 0; n < fx.dofs.count; ++n) {
    m_g += fx.dofs.mass[n];
    for (int d = 0; d < 3; ++d) {
      P_g[d] += fx.dofs.v0[d][n];
      f_g[d] += fx.dofs.f[d][n];
      f_abs += fabs(fx.dofs.f[d][n]);
    }
  }
  assert_close(m_g, m_p, TOL(1e-5, 1e-13) * m_p);
  for (int d = 0; d < 3; ++d) {
    assert_close(P_g[d], P_p[d], TOL(1e-5, 1e-13) * m_p);
    assert_close(f_g[d], 0, TOL(1e-5, 1e-13) * f_abs);
  }
  assert_true(f_abs > 0);

  /* grid update, then back */
  mpm_dofs_explicit_update(&fx.u, MPM_P2G_MOMENTUM_FORCE, &fx.dofs);
  mpm_g2p_result r = mpm_domain_g2p(&fx.ctx, s, &fx.val, &fx.u.boundary);
  assert_true(r.bad_particle < 0);
  double P_after[3] = {0, 0, 0};
  for (size_t q = 0; q < s->particles.count; ++q)
    for (int d = 0; d < 3; ++d) P_after[d] += (double)s->particles.mass[q] * s->particles.v[d][q];
  for (int d = 0; d < 3; ++d) assert_close(P_after[d], P_p[d], TOL(1e-4, 1e-12) * m_p);
  block_free(&fx);
}

/* |a - b| <= tol max |b| over n values. */
static void assert_arrays_close(const mpm_real *a, const mpm_real *b, size_t n, double tol,
                                const char *what) {
  double scale = 0, worst = 0;
  for (size_t i = 0; i < n; ++i) scale = fmax(scale, fabs(b[i]));
  for (size_t i = 0; i < n; ++i) worst = fmax(worst, fabs((double)a[i] - b[i]));
  if (worst > tol * scale)
    fail_msg("%s: differ by %g (scale %g, tolerance %g)", what, worst, scale, tol);
}

/* After P2G on two fixtures of the same DOFs: their grid values equal to tol, then the grid
 * update and G2P on both. */
static void same_grid_then_g2p(block_fixture *a, block_fixture *b, double tol) {
  const size_t nd = a->dofs.count;
  assert_int_equal(nd, b->dofs.count);
  assert_arrays_close(a->dofs.mass, b->dofs.mass, nd, tol, "grid mass");
  for (int d = 0; d < 3; ++d) {
    assert_arrays_close(a->dofs.v0[d], b->dofs.v0[d], nd, tol, "grid momentum");
    assert_arrays_close(a->dofs.f[d], b->dofs.f[d], nd, tol, "grid force");
  }
  mpm_dofs_explicit_update(&a->u, MPM_P2G_MOMENTUM_FORCE, &a->dofs);
  mpm_dofs_explicit_update(&b->u, MPM_P2G_MOMENTUM_FORCE, &b->dofs);
  mpm_domain_g2p(&a->ctx, &a->s, &a->val, &a->u.boundary);
  mpm_domain_g2p(&b->ctx, &b->s, &b->val, &b->u.boundary);
}

/* The corners' transfers through pads (domain/corner_pads.h, the explicit step on the sparse
 * grid) against the embedding's rows (s->corner_rows, the implicit step's path): the same
 * grid values after P2G, and the same corner velocities, affine moments and positions and
 * particle F after G2P, for FLIP and APIC with the linear and quadratic corner kernels. */
static void run_pads_match_rows(mpm_kernel_kind kind, mpm_transfer_kind transfer, double tol) {
  block_fixture a, b;
  block_setup(&a, kind, transfer);
  block_setup(&b, kind, transfer);
  b.s.corner_rows = 1; /* the implicit step's plan: rows */
  assert_int_equal(mpm_domain_plan(&b.s, &b.grid, &b.ctx.kernel, &b.scratch), MPM_OK);
  assert_int_equal(mpm_domain_p2g(&a.ctx, &a.s, &a.grid, &a.val, &a.scratch), MPM_OK);
  assert_int_equal(mpm_domain_p2g(&b.ctx, &b.s, &b.grid, &b.val, &b.scratch), MPM_OK);
  assert_true(a.s.pads.on);
  assert_false(b.s.pads.on);
  assert_true(a.s.corner_grid.rows == 0 && b.s.corner_grid.rows == b.s.corner_count);
  const size_t nc = a.s.corner_count;
  same_grid_then_g2p(&a, &b, tol);
  for (int d = 0; d < 3; ++d) {
    for (size_t c = 0; c < nc; ++c) /* v^g: in the packed copy */
      assert_close(a.s.corner_pack[c][6 + d], b.s.corner_pack[c][6 + d], tol);
    assert_arrays_close(a.s.cv[d], b.s.cv[d], nc, tol, "corner velocity");
    assert_arrays_close(a.s.cx[d], b.s.cx[d], nc, tol, "corner position");
  }
  if (transfer == MPM_TRANSFER_APIC) {
    double B = 0;
    for (size_t c = 0; c < nc; ++c) B = fmax(B, fabs(a.s.cB[0][c]) + fabs(a.s.cB[4][c]));
    assert_true(B > 0);
    /* B sums terms of |v| |a| D ~ |v| dx much larger than itself (a rotation's moment is
     * their difference): 10 times the tolerance */
    for (int e = 0; e < 9; ++e) assert_arrays_close(a.s.cB[e], b.s.cB[e], nc, 10 * tol, "corner B");
  }
  for (int e = 0; e < 9; ++e)
    assert_arrays_close(a.s.particles.F[e], b.s.particles.F[e], a.s.particles.count, tol,
                        "particle F");
  block_free(&a);
  block_free(&b);
}

static void test_pads_match_rows(void **state) {
  (void)state;
  /* the same terms, summed in another order (lanes, then nodes): equal to rounding */
  const double tol = TOL(1e-6, 1e-14);
  run_pads_match_rows(MPM_KERNEL_LINEAR, MPM_TRANSFER_FLIP, tol);
  run_pads_match_rows(MPM_KERNEL_LINEAR, MPM_TRANSFER_APIC, tol);
  run_pads_match_rows(MPM_KERNEL_QUADRATIC, MPM_TRANSFER_FLIP, tol);
  run_pads_match_rows(MPM_KERNEL_QUADRATIC, MPM_TRANSFER_APIC, tol);
}

/* Renumbered corners (mpm_domain_set_permute_corners, a random order) give the transfers the
 * same terms: grid values and the corners' and particles' state after G2P equal to rounding
 * (sums over a corner's particles and a cell's corners go in another order), the particles'
 * corners and the adjacency renumbered alike. Then the step's own renumbering
 * (mpm_domain_order_corners) into the pads' order: afterwards the positions run through the
 * corner numbers without a break. */
static void run_permuted_corners(mpm_transfer_kind transfer) {
  block_fixture a, b;
  block_setup(&a, MPM_KERNEL_LINEAR, transfer);
  block_setup(&b, MPM_KERNEL_LINEAR, transfer);
  const size_t nc = b.s.corner_count, np = b.s.particles.count;
  uint32_t *order = test_malloc(nc * sizeof *order), *inv = test_malloc(nc * sizeof *inv);
  for (size_t k = 0; k < nc; ++k) order[k] = (uint32_t)k;
  uint64_t rng = 99;
  for (size_t k = nc - 1; k > 0; --k) {
    const size_t j = (size_t)test_rand(&rng, 0, (double)k + 1) % (k + 1);
    const uint32_t t = order[k];
    order[k] = order[j];
    order[j] = t;
  }
  for (size_t k = 0; k < nc; ++k) inv[order[k]] = (uint32_t)k;
  assert_int_equal(mpm_domain_set_permute_corners(&b.s, order, &b.scratch), MPM_OK);
  for (size_t q = 0; q < np; ++q)
    for (int c = 0; c < 8; ++c) assert_int_equal(b.s.corner[q][c], inv[a.s.corner[q][c]]);
  for (size_t c = 0; c < nc; ++c) {
    const uint32_t k = inv[c];
    assert_int_equal(b.s.adj_start[k + 1] - b.s.adj_start[k],
                     a.s.adj_start[c + 1] - a.s.adj_start[c]);
    for (uint32_t j = 0; j < a.s.adj_start[c + 1] - a.s.adj_start[c]; ++j)
      assert_int_equal(b.s.adj[b.s.adj_start[k] + j], a.s.adj[a.s.adj_start[c] + j]);
    for (int d = 0; d < 3; ++d) assert_true(b.s.cx[d][k] == a.s.cx[d][c]);
  }
  assert_int_equal(mpm_domain_plan(&b.s, &b.grid, &b.ctx.kernel, &b.scratch), MPM_OK);
  assert_int_equal(mpm_domain_p2g(&a.ctx, &a.s, &a.grid, &a.val, &a.scratch), MPM_OK);
  assert_int_equal(mpm_domain_p2g(&b.ctx, &b.s, &b.grid, &b.val, &b.scratch), MPM_OK);
  const double tol = TOL(1e-6, 1e-14);
  same_grid_then_g2p(&a, &b, tol);
  mpm_real *back = test_malloc(nc * sizeof *back);
  for (int d = 0; d < 3; ++d) {
    for (size_t c = 0; c < nc; ++c) back[c] = b.s.cx[d][inv[c]];
    assert_arrays_close(back, a.s.cx[d], nc, tol, "corner position");
    for (size_t c = 0; c < nc; ++c) back[c] = b.s.cv[d][inv[c]];
    assert_arrays_close(back, a.s.cv[d], nc, tol, "corner velocity");
  }
  for (int e = 0; e < 9; ++e)
    assert_arrays_close(b.s.particles.F[e], a.s.particles.F[e], np, tol, "particle F");
  /* the step's renumbering: the lattice's numbers (a) break the pads' order everywhere */
  assert_int_equal(mpm_domain_plan(&a.s, &a.grid, &a.ctx.kernel, &a.scratch), MPM_OK);
  assert_true(a.s.pads.breaks > a.s.pads.grid_positions / 10);
  uint32_t *done = NULL;
  assert_int_equal(mpm_domain_order_corners(&a.s, &a.grid, &a.ctx.kernel, &a.scratch, &done),
                   MPM_OK);
  assert_non_null(done);
  assert_true(a.s.pads.on);
  assert_int_equal(a.s.pads.breaks, 0);
  for (size_t k = 0; k < a.s.pads.positions; ++k) assert_int_equal(a.s.pads.row[k], k);
  assert_int_equal(mpm_domain_order_corners(&a.s, &a.grid, &a.ctx.kernel, &a.scratch, &done),
                   MPM_OK);
  assert_null(done); /* in order: nothing to do */
  test_free(back);
  test_free(order);
  test_free(inv);
  block_free(&a);
  block_free(&b);
}

static void test_permuted_corners(void **state) {
  (void)state;
  run_permuted_corners(MPM_TRANSFER_FLIP);
  run_permuted_corners(MPM_TRANSFER_APIC);
}

static void test_conservation_linear(void **state) {
  (void)state;
  run_conservation(MPM_KERNEL_LINEAR);
}
static void test_conservation_quadratic(void **state) {
  (void)state;
  run_conservation(MPM_KERNEL_QUADRATIC);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_weights_cube),           cmocka_unit_test(test_weights_distorted),
      cmocka_unit_test(test_two_step_equals_direct), cmocka_unit_test(test_affine_motion_exact_F),
      cmocka_unit_test(test_build_from_body),        cmocka_unit_test(test_conservation_linear),
      cmocka_unit_test(test_conservation_quadratic), cmocka_unit_test(test_pads_match_rows),
      cmocka_unit_test(test_permuted_corners),       cmocka_unit_test(test_fragments_dropped),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
