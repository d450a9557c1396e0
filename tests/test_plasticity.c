/* test_plasticity.c - the Hencky-based and plastic models (hencky_stvk.c, drucker_prager.c,
 * von_mises.c, snow.c) and the definiteness fix of all six models, against independent truth.
 *
 *  - P equals central differences of Psi and dpdf_action equals central differences of P
 *    (well-conditioned F, also inverted F for the Hencky models, hardened moduli for snow);
 *  - dpdf_action_definite: the 9x9 matrix built from its actions on the basis directions is
 *    symmetric and positive semi-definite (eigenvalues by a double Jacobi sweep) for all six
 *    models at well-conditioned, compressed, stretched and inverted F, and equals dpdf_action
 *    wherever that one is already positive definite, and equals the eigenvalue-clamped
 *    (nearest semi-definite) 9x9 matrix of dpdf_action everywhere;
 *  - return maps: the projected state is admissible (Drucker-Prager cone in Hencky strain,
 *    also checked in stress with alpha and k computed here; von Mises cylinder; snow's
 *    singular-value box), a second projection changes nothing, an admissible state is left
 *    bitwise unchanged, Drucker-Prager expansion goes to the tip and the volume correction
 *    (Tampubolon et al. 2017) gives back the stored separation on recompression (no volume
 *    gain), cohesion moves the tip to tr(tau)/3 = c cot(phi), von Mises keeps tr(eps), snow
 *    keeps Jp det F^E;
 *  - kirchhoff_batch equals pk1 F^T (snow: with mpm_material_at) on chunks of 64 and 37.
 * Singular values of the results are recomputed in double from F^T F (Jacobi), independent of
 * the library's SVD. The worst errors are printed. */
#include "support.h"
#include "core/mat3.h"
#include "material/material.h"

#include <math.h>
#include <string.h>

static const double FD_H = TOL(2e-3, 1e-6);
static const double TOL_FD_P = TOL(2e-3, 2e-8);
static const double TOL_FD_DP = TOL(3e-3, 2e-8);

typedef struct worst {
  double p_fd, dp_fd, psd, sym, same, proj, dp_cone, dp_conserve, dp_twice, vm_radius, vm_trace,
      snow_box, snow_j, batch;
  int indefinite_seen;
} worst;
static worst W;

/* ---- double helpers --------------------------------------------------------------------- */

static void rand_rotation(uint64_t *rng, double Q[9]) {
  double q[4], n;
  do {
    n = 0;
    for (int i = 0; i < 4; ++i) {
      q[i] = test_rand(rng, -1, 1);
      n += q[i] * q[i];
    }
  } while (n > 1 || n < 1e-4);
  n = sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  memcpy(Q, R, sizeof R);
}

static void compose(const double Q1[9], const double s[3], const double Q2[9], double F[9]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      F[3 * r + c] = Q1[3 * r] * s[0] * Q2[3 * c] + Q1[3 * r + 1] * s[1] * Q2[3 * c + 1] +
                     Q1[3 * r + 2] * s[2] * Q2[3 * c + 2];
}

/* F = Q1 diag(s) Q2^T with random rotations, rounded to the real type */
static void rand_F(uint64_t *rng, const double s[3], mpm_real F[9]) {
  double Q1[9], Q2[9], Fd[9];
  rand_rotation(rng, Q1);
  rand_rotation(rng, Q2);
  compose(Q1, s, Q2, Fd);
  for (int i = 0; i < 9; ++i) F[i] = (mpm_real)Fd[i];
}

static void sorted_sigma(uint64_t *rng, double lo, double hi, double s[3]) {
  double a = test_rand(rng, lo, hi), b = test_rand(rng, lo, hi);
  s[0] = fmax(a, b);
  s[1] = fmin(a, b);
  s[2] = test_rand(rng, lo, s[1]);
}

/* Eigen-decomposition A = Q diag(eig) Q^T of a symmetric n x n matrix (n <= 9) by cyclic
 * Jacobi, in double; Q may be NULL. */
static void jacobi_eigv(int n, const double *A, double *eig, double *Q) {
  double a[81], q[81];
  memcpy(a, A, sizeof(double) * (size_t)(n * n));
  for (int i = 0; i < n * n; ++i) q[i] = i % (n + 1) == 0;
  for (int sweep = 0; sweep < 60; ++sweep) {
    double off = 0, tot = 0;
    for (int p = 0; p < n; ++p)
      for (int r = 0; r < n; ++r) {
        tot += a[p * n + r] * a[p * n + r];
        if (p != r) off += a[p * n + r] * a[p * n + r];
      }
    if (off <= 1e-30 * tot) break;
    for (int p = 0; p < n; ++p)
      for (int r = p + 1; r < n; ++r) {
        const double apr = a[p * n + r];
        if (apr == 0) continue;
        const double th = (a[r * n + r] - a[p * n + p]) / (2 * apr);
        const double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
        const double c = 1 / sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; ++k) {
          const double akp = a[k * n + p], akr = a[k * n + r];
          a[k * n + p] = c * akp - s * akr;
          a[k * n + r] = s * akp + c * akr;
          const double qkp = q[k * n + p], qkr = q[k * n + r];
          q[k * n + p] = c * qkp - s * qkr;
          q[k * n + r] = s * qkp + c * qkr;
        }
        for (int k = 0; k < n; ++k) {
          const double apk = a[p * n + k], ark = a[r * n + k];
          a[p * n + k] = c * apk - s * ark;
          a[r * n + k] = s * apk + c * ark;
        }
      }
  }
  for (int i = 0; i < n; ++i) eig[i] = a[i * n + i];
  if (Q) memcpy(Q, q, sizeof(double) * (size_t)(n * n));
}

static void jacobi_eig(int n, const double *A, double *eig) {
  jacobi_eigv(n, A, eig, NULL);
}

/* The nearest (Frobenius) positive semi-definite matrix to a symmetric 9x9 K: eigenvalues
 * clamped at 0. Since F -> U^T F V is orthogonal on R^9 and block-diagonalizes the Hessian of
 * an isotropic energy, this equals the blockwise projection of Teran et al. 2005. */
static void psd_project9(const double K[81], double Kp[81]) {
  double eig[9], Q[81];
  jacobi_eigv(9, K, eig, Q);
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) {
      double acc = 0;
      for (int k = 0; k < 9; ++k) acc += Q[9 * a + k] * fmax(eig[k], 0) * Q[9 * b + k];
      Kp[9 * a + b] = acc;
    }
}

/* Unsigned singular values of F (descending) from the eigenvalues of F^T F, and det F. */
static void sing_vals(const mpm_real F[9], double s[3], double *det) {
  double FtF[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double acc = 0;
      for (int k = 0; k < 3; ++k) acc += (double)F[3 * k + r] * F[3 * k + c];
      FtF[3 * r + c] = acc;
    }
  double e[3];
  jacobi_eig(3, FtF, e);
  for (int i = 0; i < 3; ++i) e[i] = sqrt(fmax(e[i], 0));
  for (int i = 0; i < 3; ++i) /* sort descending */
    for (int j = i + 1; j < 3; ++j)
      if (e[j] > e[i]) {
        const double t = e[i];
        e[i] = e[j];
        e[j] = t;
      }
  memcpy(s, e, sizeof e);
  *det = (double)F[0] * ((double)F[4] * F[8] - (double)F[5] * F[7]) -
         (double)F[1] * ((double)F[3] * F[8] - (double)F[5] * F[6]) +
         (double)F[2] * ((double)F[3] * F[7] - (double)F[4] * F[6]);
}

/* Principal Hencky strain of F (log of unsigned singular values). */
static void hencky_of(const mpm_real F[9], double e[3]) {
  double s[3], det;
  sing_vals(F, s, &det);
  for (int i = 0; i < 3; ++i) e[i] = log(s[i]);
}

static double dev_norm(const double e[3]) {
  const double m = (e[0] + e[1] + e[2]) / 3;
  return sqrt((e[0] - m) * (e[0] - m) + (e[1] - m) * (e[1] - m) + (e[2] - m) * (e[2] - m));
}

static double maxabs(const double *a, int n) {
  double m = 0;
  for (int i = 0; i < n; ++i) m = fmax(m, fabs(a[i]));
  return m;
}

static void check_err(double err, double tol, double *worst_slot, const char *what, int trial) {
  if (worst_slot) *worst_slot = fmax(*worst_slot, err);
  if (!(err <= tol)) fail_msg("%s (trial %d): error %.3g > %.3g", what, trial, err, tol);
}

static mpm_material make(mpm_model_kind kind) {
  mpm_material_desc d;
  memset(&d, 0, sizeof d);
  d.model = kind;
  d.E = 3.0;
  d.nu = 0.3;
  d.density = 1000;
  d.min_stretch = 0.3;
  d.friction_angle = 30;
  d.cohesion = 0;
  d.yield_stress = 0.1;
  d.theta_c = 2.5e-2;
  d.theta_s = 7.5e-3;
  d.hardening = 10;
  mpm_material m;
  mpm_material_init(&m, &d);
  return m;
}

/* ---- finite differences ----------------------------------------------------------------- */

static void fd_pk1(const mpm_material *m, const mpm_real F[9], double P[9]) {
  for (int i = 0; i < 9; ++i) {
    mpm_real Fp[9], Fm[9];
    mpm_m3_copy(F, Fp);
    mpm_m3_copy(F, Fm);
    Fp[i] = (mpm_real)(F[i] + FD_H);
    Fm[i] = (mpm_real)(F[i] - FD_H);
    P[i] = ((double)m->model->energy(m, Fp) - (double)m->model->energy(m, Fm)) /
           ((double)Fp[i] - (double)Fm[i]);
  }
}

static void fd_dp(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9], double dP[9]) {
  mpm_real Fp[9], Fm[9], Pp[9], Pm[9];
  for (int i = 0; i < 9; ++i) {
    Fp[i] = (mpm_real)(F[i] + FD_H * dF[i]);
    Fm[i] = (mpm_real)(F[i] - FD_H * dF[i]);
  }
  m->model->pk1(m, Fp, Pp);
  m->model->pk1(m, Fm, Pm);
  for (int i = 0; i < 9; ++i) dP[i] = ((double)Pp[i] - (double)Pm[i]) / (2 * FD_H);
}

static double rel_err(const mpm_real *a, const double *b, int n, double scale) {
  double e = 0;
  for (int i = 0; i < n; ++i) e = fmax(e, fabs((double)a[i] - b[i]));
  return e / scale;
}

/* ---- tests ------------------------------------------------------------------------------ */

static void test_init_and_table(void **state) {
  (void)state;
  const mpm_model_kind kinds[4] = {MPM_MODEL_HENCKY_STVK, MPM_MODEL_DRUCKER_PRAGER,
                                   MPM_MODEL_VON_MISES, MPM_MODEL_SNOW};
  const mpm_model *models[4] = {&mpm_model_hencky_stvk, &mpm_model_drucker_prager,
                                &mpm_model_von_mises, &mpm_model_snow};
  const char *names[4] = {"hencky_stvk", "drucker_prager", "von_mises", "snow"};
  for (int k = 0; k < 4; ++k) {
    assert_true(mpm_model_of(kinds[k]) == models[k]);
    const mpm_material m = make(kinds[k]);
    assert_true(m.model == models[k]);
    assert_string_equal(models[k]->name, names[k]);
    assert_non_null(models[k]->energy);
    assert_non_null(models[k]->pk1);
    assert_non_null(models[k]->dpdf_action);
    assert_non_null(models[k]->dpdf_action_definite);
    assert_non_null(models[k]->kirchhoff_batch);
    assert_true((models[k]->return_map == NULL) == (k == 0));
  }
  assert_non_null(mpm_model_fixed_corotated.dpdf_action_definite);
  assert_non_null(mpm_model_neo_hookean.dpdf_action_definite);
  assert_true(mpm_model_drucker_prager.plastic_initial == 0);
  assert_true(mpm_model_snow.plastic_initial == 1);
  assert_true(mpm_model_von_mises.plastic_initial == 1);
  const mpm_material m = make(MPM_MODEL_SNOW);
  assert_close(m.friction_angle, 3.14159265358979323846 / 6, TOL(1e-6, 1e-15));
  assert_close(m.yield_stress, 0.1, TOL(1e-8, 1e-16));
  assert_close(m.theta_c, 2.5e-2, TOL(1e-9, 1e-17));
  assert_close(m.theta_s, 7.5e-3, TOL(1e-9, 1e-17));
  assert_close(m.hardening, 10, 0);
  /* snow hardening: exp(xi (1 - Jp)) on both moduli; other models unchanged */
  const mpm_material h = mpm_material_at(&m, (mpm_real)0.95);
  assert_close(h.mu / m.mu, exp(0.5), TOL(1e-6, 1e-13));
  assert_close(h.lambda / m.lambda, exp(0.5), TOL(1e-6, 1e-13));
  assert_close(h.wave_speed / m.wave_speed, exp(0.25), TOL(1e-6, 1e-13));
  const mpm_material dp = make(MPM_MODEL_DRUCKER_PRAGER);
  const mpm_material dq = mpm_material_at(&dp, (mpm_real)0.5);
  assert_true(dq.mu == dp.mu && dq.lambda == dp.lambda);
}

/* Stress and tangent against finite differences. */
static void test_fd(void **state) {
  (void)state;
  uint64_t rng = 31;
  const mpm_model_kind kinds[4] = {MPM_MODEL_HENCKY_STVK, MPM_MODEL_DRUCKER_PRAGER,
                                   MPM_MODEL_VON_MISES, MPM_MODEL_SNOW};
  for (int k = 0; k < 4; ++k) {
    const mpm_material base = make(kinds[k]);
    for (int t = 0; t < 1000; ++t) {
      const mpm_material m =
          mpm_material_at(&base, (mpm_real)test_rand(&rng, 0.9, 1.1)); /* snow: hardened */
      double s[3];
      sorted_sigma(&rng, 0.6, 1.6, s);
      if (kinds[k] != MPM_MODEL_SNOW && t % 3 == 0) { /* inverted, clear of |s2| = |s3| */
        s[2] = -test_rand(&rng, 0.3, s[1] - 0.1 > 0.31 ? s[1] - 0.1 : 0.31);
      }
      mpm_real F[9], P[9], dF[9], dP[9];
      double Pfd[9], dPfd[9], Pd[9];
      rand_F(&rng, s, F);
      m.model->pk1(&m, F, P);
      for (int i = 0; i < 9; ++i) Pd[i] = P[i];
      fd_pk1(&m, F, Pfd);
      const double sc = fmax(maxabs(Pd, 9), (double)(m.mu + m.lambda));
      check_err(rel_err(P, Pfd, 9, sc), TOL_FD_P, &W.p_fd, m.model->name, t);
      for (int r = 0; r < 2; ++r) {
        for (int i = 0; i < 9; ++i) dF[i] = (mpm_real)test_rand(&rng, -1, 1);
        m.model->dpdf_action(&m, F, dF, dP);
        fd_dp(&m, F, dF, dPfd);
        const double sd = fmax(maxabs(dPfd, 9), (double)(m.mu + m.lambda));
        check_err(rel_err(dP, dPfd, 9, sd), TOL_FD_DP, &W.dp_fd, m.model->name, t);
      }
    }
  }
}

/* K_ab = e_a : action(e_b) in double */
typedef void (*action_fn)(const mpm_material *, const mpm_real *, const mpm_real *, mpm_real *);
static void build_matrix(action_fn f, const mpm_material *m, const mpm_real F[9], double K[81]) {
  for (int b = 0; b < 9; ++b) {
    mpm_real e[9] = {0}, dP[9];
    e[b] = 1;
    f(m, F, e, dP);
    for (int a = 0; a < 9; ++a) K[9 * a + b] = dP[a];
  }
}

static void test_definite(void **state) {
  (void)state;
  uint64_t rng = 32;
  const mpm_model_kind kinds[6] = {MPM_MODEL_FIXED_COROTATED, MPM_MODEL_NEO_HOOKEAN,
                                   MPM_MODEL_HENCKY_STVK,     MPM_MODEL_DRUCKER_PRAGER,
                                   MPM_MODEL_VON_MISES,       MPM_MODEL_SNOW};
  for (int k = 0; k < 6; ++k) {
    const mpm_material m = make(kinds[k]);
    int indefinite = 0;
    for (int t = 0; t < 1200; ++t) {
      double s[3];
      switch (t % 5) {
      case 0:
        sorted_sigma(&rng, 0.9, 1.1, s);
        break; /* near rest */
      case 1:
        sorted_sigma(&rng, 0.05, 0.6, s);
        break; /* compressed */
      case 2:
        sorted_sigma(&rng, 1.2, 3.0, s);
        break; /* stretched */
      case 3:  /* inverted */
        sorted_sigma(&rng, 0.2, 2.0, s);
        s[2] = -test_rand(&rng, 0.01, s[1]);
        break;
      default:
        sorted_sigma(&rng, 0.2, 2.5, s);
        break;
      }
      mpm_real F[9];
      rand_F(&rng, s, F);
      double K[81], K0[81], eig[9], eig0[9];
      build_matrix(m.model->dpdf_action_definite, &m, F, K);
      build_matrix(m.model->dpdf_action, &m, F, K0);
      const double sc = fmax(maxabs(K0, 81), (double)(m.mu + m.lambda));
      double asym = 0;
      for (int a = 0; a < 9; ++a)
        for (int b = 0; b < a; ++b) asym = fmax(asym, fabs(K[9 * a + b] - K[9 * b + a]));
      check_err(asym / sc, TOL(1e-5, 1e-12), &W.sym, "definite action symmetric", t);
      for (int a = 0; a < 9; ++a) /* symmetrize before the eigen-solve */
        for (int b = 0; b < a; ++b)
          K[9 * a + b] = K[9 * b + a] = 0.5 * (K[9 * a + b] + K[9 * b + a]);
      jacobi_eig(9, K, eig);
      double mn = eig[0];
      for (int i = 1; i < 9; ++i) mn = fmin(mn, eig[i]);
      check_err(fmax(-mn, 0) / sc, TOL(2e-5, 1e-11), &W.psd, m.model->name, t);
      /* where the plain Hessian is positive definite the fix changes nothing */
      double K0s[81];
      for (int a = 0; a < 9; ++a)
        for (int b = 0; b < 9; ++b) K0s[9 * a + b] = 0.5 * (K0[9 * a + b] + K0[9 * b + a]);
      jacobi_eig(9, K0s, eig0);
      double mn0 = eig0[0];
      for (int i = 1; i < 9; ++i) mn0 = fmin(mn0, eig0[i]);
      if (mn0 < -1e-3 * sc) ++indefinite;
      /* independent truth: the eigenvalue-clamped 9x9 matrix */
      {
        double Kp[81];
        mpm_real Kr[81];
        psd_project9(K0s, Kp);
        build_matrix(m.model->dpdf_action_definite, &m, F, K);
        for (int i = 0; i < 81; ++i) Kr[i] = (mpm_real)K[i];
        check_err(rel_err(Kr, Kp, 81, sc), TOL(5e-5, 1e-10), &W.proj, "definite = PSD(K)", t);
      }
      if (mn0 > 1e-3 * sc) {
        mpm_real Kr[81];
        build_matrix(m.model->dpdf_action_definite, &m, F, K);
        for (int i = 0; i < 81; ++i) Kr[i] = (mpm_real)K[i];
        check_err(rel_err(Kr, K0, 81, sc), TOL(2e-5, 1e-11), &W.same, "definite = plain", t);
      }
    }
    /* the cases above do include indefinite Hessians, so the projection was exercised */
    if (indefinite == 0) fail_msg("%s: no indefinite Hessian sampled", m.model->name);
    W.indefinite_seen += indefinite;
  }
  /* F = I: every model's Hessian at rest is semi-definite; the fix must not change it */
  for (int k = 0; k < 6; ++k) {
    const mpm_material m = make(kinds[k]);
    mpm_real F[9];
    mpm_m3_identity(F);
    double K[81], K0[81];
    build_matrix(m.model->dpdf_action_definite, &m, F, K);
    build_matrix(m.model->dpdf_action, &m, F, K0);
    for (int i = 0; i < 81; ++i) assert_close(K[i] / m.mu, K0[i] / m.mu, TOL(1e-5, 1e-12));
  }
}

/* ---- Drucker-Prager -------------------------------------------------------------------- */

typedef struct dp_ref {
  double alpha, k, cone, shift, tip;
} dp_ref;

static dp_ref dp_reference(const mpm_material *m) {
  const double phi = m->friction_angle, mu = m->mu, l = m->lambda;
  dp_ref r;
  r.alpha = sqrt(2.0 / 3.0) * 2 * sin(phi) / (3 - sin(phi));
  r.k = sqrt(2.0 / 3.0) * 6 * m->cohesion * cos(phi) / (3 - sin(phi));
  r.cone = r.alpha * (3 * l + 2 * mu) / (2 * mu);
  r.shift = r.k / (2 * mu);
  r.tip = r.k > 0 ? r.k / (r.alpha * (3 * l + 2 * mu)) : 0;
  return r;
}

/* one particle through the return map */
static void project1(const mpm_material *m, mpm_real F[9], mpm_real *plastic) {
  mpm_real c[9][1];
  mpm_real *Fp[9];
  for (int i = 0; i < 9; ++i) {
    c[i][0] = F[i];
    Fp[i] = c[i];
  }
  m->model->return_map(m, 1, Fp, plastic);
  for (int i = 0; i < 9; ++i) F[i] = c[i][0];
}

static void uniform(mpm_real a, mpm_real F[9]) {
  const mpm_real G[9] = {a, 0, 0, 0, a, 0, 0, 0, a};
  mpm_m3_copy(G, F);
}

static void test_drucker_prager(void **state) {
  (void)state;
  uint64_t rng = 33;
  for (int variant = 0; variant < 2; ++variant) {
    mpm_material m = make(MPM_MODEL_DRUCKER_PRAGER);
    if (variant == 1) m.cohesion = (mpm_real)(0.02 * m.mu); /* cohesive */
    const dp_ref r = dp_reference(&m);
    int cases[3] = {0, 0, 0};
    for (int t = 0; t < 3000; ++t) {
      double s[3];
      sorted_sigma(&rng, 0.7, 1.3, s);
      if (t % 7 == 0) s[2] = -test_rand(&rng, 0.5, s[1]);
      mpm_real F[9], F0[9];
      rand_F(&rng, s, F);
      mpm_m3_copy(F, F0);
      mpm_real v = t % 3 == 0 ? (mpm_real)test_rand(&rng, 0, 0.2) : 0;
      const mpm_real v0 = v;
      double e0[3], e1[3];
      hencky_of(F0, e0);
      const double teff0 = e0[0] + e0[1] + e0[2] + v0;
      const double dg0 = dev_norm(e0) + r.cone * (e0[0] + e0[1] + e0[2]) - r.shift;
      project1(&m, F, &v);
      hencky_of(F, e1);
      const double tr1 = e1[0] + e1[1] + e1[2];
      /* admissible: on or inside the cone */
      const double dg = dev_norm(e1) + r.cone * tr1 - r.shift;
      check_err(fmax(dg, 0), TOL(2e-5, 1e-12), &W.dp_cone, "DP cone", t);
      assert_true(v >= 0);
      /* tr(eps) + v conserved */
      check_err(fabs(tr1 + v - teff0), TOL(2e-5, 1e-12), &W.dp_conserve, "DP tr + v", t);
      if (teff0 >= r.tip) { /* tip: stress-free for c = 0, eps = tip/3 */
        ++cases[0];
        for (int i = 0; i < 3; ++i) assert_close(e1[i], r.tip / 3, TOL(2e-6, 1e-12));
      } else if (v0 == 0 && dg0 <= -TOL(1e-5, 1e-12)) { /* elastic: bitwise */
        ++cases[1];
        assert_memory_equal(F, F0, sizeof F);
        assert_true(v == 0);
      } else if (v0 == 0 && dg0 > TOL(1e-5, 1e-12)) { /* on the cone, trace kept */
        ++cases[2];
        check_err(fabs(dg), TOL(2e-5, 1e-12), &W.dp_cone, "DP on the cone", t);
        assert_close(tr1, teff0, TOL(2e-5, 1e-12));
        /* in stress: ||dev tau|| + alpha tr(tau) = k */
        mpm_real P[9], T[9];
        m.model->pk1(&m, F, P);
        mpm_m3_mul_bt(P, F, T);
        double Td[9];
        for (int i = 0; i < 9; ++i) Td[i] = T[i];
        const double p = (Td[0] + Td[4] + Td[8]) / 3;
        double dd = 0;
        for (int i = 0; i < 9; ++i) {
          const double x = Td[i] - (i % 4 == 0 ? p : 0);
          dd += x * x;
        }
        assert_close((sqrt(dd) + r.alpha * 3 * p - r.k) / m.mu, 0, TOL(5e-5, 1e-11));
      }
      /* a second projection changes nothing */
      mpm_real F2[9], v2 = v;
      mpm_m3_copy(F, F2);
      project1(&m, F2, &v2);
      double d = fabs((double)v2 - v);
      for (int i = 0; i < 9; ++i) d = fmax(d, fabs((double)F2[i] - F[i]));
      check_err(d, TOL(2e-5, 1e-12), &W.dp_twice, "DP twice", t);
    }
    for (int c = 0; c < 3; ++c) assert_true(cases[c] > 20);
  }

  /* expand, then compress back (Tampubolon et al. 2017): no volume gain */
  mpm_material m = make(MPM_MODEL_DRUCKER_PRAGER);
  mpm_real F[9], v = 0, P[9];
  uniform((mpm_real)1.1, F); /* trial after an expansion by 1.1 */
  project1(&m, F, &v);
  for (int i = 0; i < 9; ++i) assert_close(F[i], i % 4 == 0, TOL(1e-6, 1e-14)); /* tip: I */
  assert_close(v, 3 * log(1.1), TOL(1e-6, 1e-14));
  /* half the way back: still separated, still stress-free */
  uniform((mpm_real)(1 / 1.05), F);
  project1(&m, F, &v);
  for (int i = 0; i < 9; ++i) assert_close(F[i], i % 4 == 0, TOL(1e-6, 1e-14));
  assert_close(v, 3 * log(1.1 / 1.05), TOL(1e-6, 1e-14));
  m.model->pk1(&m, F, P);
  for (int i = 0; i < 9; ++i) assert_close(P[i] / m.mu, 0, TOL(1e-5, 1e-13));
  /* the rest of the way plus 2 %: the separation is used up and the last 2 % compress the
   * sand elastically, as they would have without the excursion: F^E = 0.98 I, v = 0 */
  uniform((mpm_real)(1.05 / 1.1 * 0.98), F);
  project1(&m, F, &v);
  for (int i = 0; i < 9; ++i) assert_close(F[i], (i % 4 == 0) * 0.98, TOL(2e-6, 1e-13));
  assert_true(v == 0);
  m.model->pk1(&m, F, P);
  assert_true(P[0] < 0 && P[4] < 0 && P[8] < 0); /* pressure */
  /* (without the correction the tip would have dropped the separation and the same history
   * would leave F^E = 0.98 / 1.1 I: 10 % too compressed, pushing the sand apart, i.e. volume
   * gain) */

  /* cohesion: the tip carries the Mohr-Coulomb apex stress tr(tau)/3 = c cot(phi) */
  m.cohesion = (mpm_real)(0.01 * m.mu);
  v = 0;
  uniform((mpm_real)1.2, F);
  project1(&m, F, &v);
  mpm_real T[9];
  m.model->pk1(&m, F, P);
  mpm_m3_mul_bt(P, F, T);
  const double pt = (T[0] + T[4] + T[8]) / 3.0;
  assert_close(pt / m.cohesion, 1 / tan(m.friction_angle), TOL(1e-4, 1e-10));
  assert_true(v > 0);
  /* a small tension below the apex is carried elastically */
  v = 0;
  uniform((mpm_real)1.001, F);
  mpm_real G[9];
  mpm_m3_copy(F, G);
  project1(&m, F, &v);
  assert_memory_equal(F, G, sizeof F);
}

/* ---- von Mises ------------------------------------------------------------------------- */

static void test_von_mises_map(void **state) {
  (void)state;
  uint64_t rng = 34;
  const mpm_material m = make(MPM_MODEL_VON_MISES);
  const double radius = m.yield_stress / (2.0 * m.mu);
  int inside = 0, outside = 0;
  for (int t = 0; t < 3000; ++t) {
    double s[3];
    sorted_sigma(&rng, 0.85, 1.15, s);
    if (t % 7 == 0) s[2] = -test_rand(&rng, 0.5, s[1]);
    mpm_real F[9], F0[9], pl = 1;
    rand_F(&rng, s, F);
    mpm_m3_copy(F, F0);
    double e0[3], e1[3], det0, det1, sv[3];
    hencky_of(F0, e0);
    sing_vals(F0, sv, &det0);
    project1(&m, F, &pl);
    assert_true(pl == 1);
    hencky_of(F, e1);
    sing_vals(F, sv, &det1);
    const double n0 = dev_norm(e0), n1 = dev_norm(e1);
    check_err(fmax(n1 - radius, 0) / radius, TOL(2e-4, 1e-10), &W.vm_radius, "VM radius", t);
    const double tr0 = e0[0] + e0[1] + e0[2], tr1 = e1[0] + e1[1] + e1[2];
    /* float: three logs of singular values each good to a few eps, the array exponential and
     * the rounding of the new F: about 30 eps in all */
    check_err(fabs(tr1 - tr0), TOL(4e-6, 1e-13), &W.vm_trace, "VM keeps tr(eps)", t);
    assert_close(fabs(det1), fabs(det0), TOL(1e-5, 1e-12));
    if (n0 < radius * (1 - TOL(1e-4, 1e-10))) {
      ++inside;
      assert_memory_equal(F, F0, sizeof F);
    } else if (n0 > radius * (1 + TOL(1e-4, 1e-10))) {
      ++outside;
      check_err(fabs(n1 - radius) / radius, TOL(2e-4, 1e-10), &W.vm_radius, "VM on surface", t);
      /* radial return: dev eps_new parallel to dev eps_trial */
      const double mt0 = tr0 / 3, mt1 = tr1 / 3;
      double dot = 0;
      for (int i = 0; i < 3; ++i) dot += (e0[i] - mt0) * (e1[i] - mt1);
      assert_close(dot / (n0 * n1), 1, TOL(1e-4, 1e-10));
    }
    mpm_real F2[9];
    mpm_m3_copy(F, F2);
    project1(&m, F2, &pl);
    double d = 0;
    for (int i = 0; i < 9; ++i) d = fmax(d, fabs((double)F2[i] - F[i]));
    check_err(d, TOL(3e-6, 1e-13), NULL, "VM twice", t);
  }
  assert_true(inside > 100 && outside > 100);
}

/* ---- snow ------------------------------------------------------------------------------ */

static void test_snow_map(void **state) {
  (void)state;
  uint64_t rng = 35;
  const mpm_material m = make(MPM_MODEL_SNOW);
  const double lo = 1 - m.theta_c, hi = 1 + m.theta_s;
  int inside = 0, outside = 0;
  for (int t = 0; t < 3000; ++t) {
    double s[3];
    if (t % 2)
      sorted_sigma(&rng, lo + 1e-3, hi - 1e-3, s);
    else
      sorted_sigma(&rng, 0.9, 1.05, s);
    mpm_real F[9], F0[9], Jp = (mpm_real)test_rand(&rng, 0.8, 1.2);
    const mpm_real Jp0 = Jp;
    rand_F(&rng, s, F);
    mpm_m3_copy(F, F0);
    double sv[3], det0, det1;
    sing_vals(F0, sv, &det0);
    const int in = sv[0] <= hi - 1e-5 && sv[2] >= lo + 1e-5;
    project1(&m, F, &Jp);
    sing_vals(F, sv, &det1);
    double box = fmax(sv[0] - hi, lo - sv[2]);
    check_err(fmax(box, 0), TOL(3e-6, 1e-13), &W.snow_box, "snow box", t);
    check_err(fabs((double)Jp * det1 - (double)Jp0 * det0) / fabs(Jp0 * det0), TOL(1e-5, 1e-12),
              &W.snow_j, "snow Jp det F^E", t);
    if (in) {
      ++inside;
      assert_memory_equal(F, F0, sizeof F);
      assert_true(Jp == Jp0);
    } else {
      ++outside;
    }
    mpm_real F2[9], Jp2 = Jp;
    mpm_m3_copy(F, F2);
    project1(&m, F2, &Jp2);
    double d = fabs((double)Jp2 - Jp);
    for (int i = 0; i < 9; ++i) d = fmax(d, fabs((double)F2[i] - F[i]));
    check_err(d, TOL(3e-6, 1e-13), NULL, "snow twice", t);
  }
  assert_true(inside > 100 && outside > 100);
  /* compression hardens: Jp < 1 after a compressive clamp, and the moduli grow */
  mpm_real F[9], Jp = 1;
  uniform((mpm_real)0.9, F);
  project1(&m, F, &Jp);
  assert_close(Jp, pow(0.9 / lo, 3), TOL(1e-6, 1e-13));
  assert_true(mpm_material_at(&m, Jp).mu > m.mu);
  /* Jp stays in a sane range under repeated extreme compression (no overflow) */
  for (int k = 0; k < 100; ++k) {
    uniform((mpm_real)0.5, F);
    project1(&m, F, &Jp);
  }
  const mpm_material h = mpm_material_at(&m, Jp);
  assert_true(Jp > 0 && isfinite(h.mu) && isfinite(h.lambda));
}

/* ---- batch ------------------------------------------------------------------------------ */

static void check_batch(const mpm_material *m, uint64_t *rng, int n, int with_plastic) {
  mpm_real Fc[9][MPM_STRESS_CHUNK], tau[9][MPM_STRESS_CHUNK], pl[MPM_STRESS_CHUNK];
  const mpm_real *Fp[9];
  for (int c = 0; c < 9; ++c) Fp[c] = Fc[c];
  for (int i = 0; i < n; ++i) {
    double s[3];
    sorted_sigma(rng, 0.5, 1.8, s);
    if (i % 4 == 1) s[2] = -test_rand(rng, 0.1, s[1]);
    if (i % 4 == 2) s[2] = test_rand(rng, 0.01, 0.3);
    mpm_real F[9];
    rand_F(rng, s, F);
    for (int c = 0; c < 9; ++c) Fc[c][i] = F[c];
    pl[i] = with_plastic ? (mpm_real)test_rand(rng, 0.7, 1.3) : m->model->plastic_initial;
  }
  for (int c = 0; c < 9; ++c)
    for (int i = 0; i < MPM_STRESS_CHUNK; ++i) tau[c][i] = (mpm_real)1e30;
  m->model->kirchhoff_batch(m, n, Fp, with_plastic ? pl : NULL, tau);
  for (int i = 0; i < n; ++i) {
    const mpm_material mi = mpm_material_at(m, pl[i]);
    mpm_real F[9], P[9], T[9], got[9];
    double Te[9];
    for (int c = 0; c < 9; ++c) F[c] = Fc[c][i];
    mi.model->pk1(&mi, F, P);
    mpm_m3_mul_bt(P, F, T);
    for (int c = 0; c < 9; ++c) {
      Te[c] = T[c];
      got[c] = tau[c][i];
    }
    check_err(rel_err(got, Te, 9, fmax(maxabs(Te, 9), (double)(mi.mu + mi.lambda))),
              TOL(5e-5, 1e-12), &W.batch, m->model->name, i);
  }
  for (int c = 0; c < 9; ++c)
    for (int i = n; i < MPM_STRESS_CHUNK; ++i) assert_true(tau[c][i] == (mpm_real)1e30);
}

static void test_batch(void **state) {
  (void)state;
  uint64_t rng = 36;
  const mpm_model_kind kinds[4] = {MPM_MODEL_HENCKY_STVK, MPM_MODEL_DRUCKER_PRAGER,
                                   MPM_MODEL_VON_MISES, MPM_MODEL_SNOW};
  for (int k = 0; k < 4; ++k) {
    const mpm_material m = make(kinds[k]);
    for (int rep = 0; rep < 20; ++rep) {
      check_batch(&m, &rng, MPM_STRESS_CHUNK, rep & 1);
      check_batch(&m, &rng, 37, !(rep & 1));
    }
  }
}

static void test_report(void **state) {
  (void)state;
  print_message("plasticity (%s), worst errors:\n"
                "  P vs FD(Psi) %.3g, dP vs FD(P) %.3g (relative)\n"
                "  definite: negative eigenvalue %.3g, asymmetry %.3g, vs plain where PD %.3g, vs "
                "eigenvalue-clamped 9x9 %.3g (relative; %d indefinite Hessians projected)\n"
                "  Drucker-Prager: cone %.3g, tr + v conservation %.3g, second projection %.3g\n"
                "  von Mises: radius %.3g (relative), tr(eps) change %.3g\n"
                "  snow: box %.3g, Jp det F^E %.3g (relative)\n"
                "  kirchhoff_batch vs pk1 F^T %.3g\n",
                MPM_REAL_NAME, W.p_fd, W.dp_fd, W.psd, W.sym, W.same, W.proj, W.indefinite_seen,
                W.dp_cone, W.dp_conserve, W.dp_twice, W.vm_radius, W.vm_trace, W.snow_box, W.snow_j,
                W.batch);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_init_and_table), cmocka_unit_test(test_fd),
      cmocka_unit_test(test_definite),       cmocka_unit_test(test_drucker_prager),
      cmocka_unit_test(test_von_mises_map),  cmocka_unit_test(test_snow_map),
      cmocka_unit_test(test_batch),          cmocka_unit_test(test_report),
  };
  return cmocka_run_group_tests_name("plasticity", tests, NULL, NULL);
}
