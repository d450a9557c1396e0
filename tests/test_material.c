/* test_material.c - the constitutive models (src/material/) against independent truth.
 *
 * Matrices are built in double as F = Q1 diag(s) Q2^T from random rotations and chosen signed
 * singular values, so closed-form expectations are available without the library's SVD:
 *  - fixed-corotated (Stomakhin et al. 2012, Gao sec. 4.1): P = 2 mu (F - Q1 Q2^T) +
 *    lambda (J - 1) cof(F); neo-Hookean (Zhu sec. 7): the closed form, and with clamping
 *    (Zhu sec. 5.3) P = Q1 diag(p(c)) Q2^T;
 *  - consistency: P equals central differences of Psi, dpdf_action equals central differences
 *    of P along random dF (well-conditioned F, and for fixed-corotated near-singular and
 *    inverted F); for clamped neo-Hookean dpdf_action equals the double-precision difference
 *    quotient of the closed-form P at F_c = Q1 diag(c) Q2^T (Zhu eq. 16) and is symmetric,
 *    and dPsi along a clamped singular direction equals P there;
 *  - the clamped and unclamped paths agree at the threshold (continuity) and the fast path
 *    agrees with the SVD path; inverted, flat and zero F give finite output;
 *  - kirchhoff_batch equals pk1 F^T, and pk1_batch equals pk1, on chunks of 64 (and 37)
 *    particles (fixed corotated, neo-Hookean, Hencky StVK);
 *  - dpdf_action_definite (Teran et al. 2005) equals the eigenvalue-clamped 9x9 matrix of
 *    dpdf_action, is symmetric semi-definite, and is dpdf_action where that is definite;
 *  - rest state F = I (and any rotation) has zero energy and stress;
 *  - Lamé parameters and wave speed; von Mises of hydrostatic and uniaxial stresses.
 * The worst errors are printed. */
#include "support.h"
#include "core/mat3.h"
#include "material/material.h"

#include <math.h>
#include <string.h>

/* finite-difference step (F entries are O(1)) */
static const double FD_H = TOL(2e-3, 1e-6);
/* tolerances, relative to the stress (or stress-change) scale */
static const double TOL_FD_P = TOL(2e-3, 2e-8);   /* P vs differences of Psi */
static const double TOL_FD_DP = TOL(2e-3, 2e-8);  /* dP vs differences of P */
static const double TOL_EXACT = TOL(2e-5, 1e-11); /* against closed forms */

typedef struct worst {
  double fcr_p_fd, fcr_dp_fd, fcr_p_exact;
  double nh_p_fd, nh_dp_fd, nh_p_exact, nh_clamp_p, nh_clamp_dp, nh_clamp_dir, nh_psi_exact;
  double batch, pk1_batch, continuity, definite;
} worst;
static worst W;

/* ---- double-precision helpers --------------------------------------------------------- */

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

static double ddet(const double A[9]) {
  return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
         A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static void dcof(const double A[9], double C[9]) {
  C[0] = A[4] * A[8] - A[5] * A[7];
  C[1] = A[5] * A[6] - A[3] * A[8];
  C[2] = A[3] * A[7] - A[4] * A[6];
  C[3] = A[2] * A[7] - A[1] * A[8];
  C[4] = A[0] * A[8] - A[2] * A[6];
  C[5] = A[1] * A[6] - A[0] * A[7];
  C[6] = A[1] * A[5] - A[2] * A[4];
  C[7] = A[2] * A[3] - A[0] * A[5];
  C[8] = A[0] * A[4] - A[1] * A[3];
}

static double maxabs(const double *a, int n) {
  double m = 0;
  for (int i = 0; i < n; ++i) m = fmax(m, fabs(a[i]));
  return m;
}

static void to_real(const double A[9], mpm_real R[9], double Ar[9]) {
  for (int i = 0; i < 9; ++i) {
    R[i] = (mpm_real)A[i];
    if (Ar) Ar[i] = R[i];
  }
}

/* max |a - b| / scale */
static double rel_err(const mpm_real *a, const double *b, int n, double scale) {
  double e = 0;
  for (int i = 0; i < n; ++i) e = fmax(e, fabs((double)a[i] - b[i]));
  return e / scale;
}

static void check_err(double err, double tol, double *worst_slot, const char *what, int trial) {
  if (worst_slot) *worst_slot = fmax(*worst_slot, err);
  if (!(err <= tol)) fail_msg("%s (trial %d): relative error %.3g > %.3g", what, trial, err, tol);
}

static mpm_material make(mpm_model_kind kind, double E, double nu, double rho, double c) {
  mpm_material_desc d;
  memset(&d, 0, sizeof d);
  d.model = kind;
  d.E = E;
  d.nu = nu;
  d.density = rho;
  d.min_stretch = c;
  mpm_material m;
  mpm_material_init(&m, &d);
  return m;
}

/* ---- finite differences of the library functions (in the build's precision) ----------- */

/* dPsi/dF_i by central differences, each divided by the step actually taken. */
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

/* (P(F + h dF) - P(F - h dF)) / 2h */
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

static void rand_dir(uint64_t *rng, mpm_real dF[9]) {
  for (int i = 0; i < 9; ++i) dF[i] = (mpm_real)test_rand(rng, -1, 1);
}

/* P vs differences of Psi and dP vs differences of P at F; returns nothing, records worst. */
static void check_fd(const mpm_material *m, const mpm_real F[9], uint64_t *rng, double *wp,
                     double *wdp, const char *what, int trial) {
  mpm_real P[9], dF[9], dP[9];
  double Pfd[9], dPfd[9], Pd[9];
  m->model->pk1(m, F, P);
  for (int i = 0; i < 9; ++i) Pd[i] = P[i];
  fd_pk1(m, F, Pfd);
  const double sP = fmax(maxabs(Pd, 9), (double)(m->mu + m->lambda));
  check_err(rel_err(P, Pfd, 9, sP), TOL_FD_P, wp, what, trial);
  for (int k = 0; k < 2; ++k) {
    rand_dir(rng, dF);
    m->model->dpdf_action(m, F, dF, dP);
    fd_dp(m, F, dF, dPfd);
    const double sdP = fmax(maxabs(dPfd, 9), (double)(m->mu + m->lambda));
    check_err(rel_err(dP, dPfd, 9, sdP), TOL_FD_DP, wdp, what, trial);
  }
}

/* ---- closed forms in double ----------------------------------------------------------- */

static void fcr_expected(double mu, double la, const double Q1[9], const double s[3],
                         const double Q2[9], double P[9]) {
  double F[9], R[9], C[9];
  const double one[3] = {1, 1, 1};
  compose(Q1, s, Q2, F);
  compose(Q1, one, Q2, R);
  const double cs[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
  compose(Q1, cs, Q2, C);
  const double J = s[0] * s[1] * s[2];
  for (int i = 0; i < 9; ++i) P[i] = 2 * mu * (F[i] - R[i]) + la * (J - 1) * C[i];
}

/* P = mu F + (lambda ln J - mu) F^{-T} */
static void nh_closed(double mu, double la, const double F[9], double P[9]) {
  double C[9];
  dcof(F, C);
  const double J = ddet(F);
  const double k = (la * log(J) - mu) / J;
  for (int i = 0; i < 9; ++i) P[i] = mu * F[i] + k * C[i];
}

static double nh_psi_closed(double mu, double la, const double c[3]) {
  const double lnJ = log(c[0] * c[1] * c[2]);
  return 0.5 * mu * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] - 3) - mu * lnJ + 0.5 * la * lnJ * lnJ;
}

/* Clamped expectation: P = Q1 diag(p(c)) Q2^T; Psi = psi(c) + sum p_i (s_i - c_i). */
static void nh_clamped_expected(double mu, double la, double cmin, const double Q1[9],
                                const double s[3], const double Q2[9], double P[9], double *psi,
                                double cl[3]) {
  for (int i = 0; i < 3; ++i) cl[i] = fmax(s[i], cmin);
  const double lnJ = log(cl[0] * cl[1] * cl[2]);
  double p[3];
  for (int i = 0; i < 3; ++i) p[i] = mu * cl[i] + (la * lnJ - mu) / cl[i];
  compose(Q1, p, Q2, P);
  *psi = nh_psi_closed(mu, la, cl);
  for (int i = 0; i < 3; ++i) *psi += p[i] * (s[i] - cl[i]);
}

/* Signed singular values in the library's convention: s0 >= s1 >= |s2|. */
static void sorted_sigma(uint64_t *rng, double lo, double hi, double s[3]) {
  double a = test_rand(rng, lo, hi), b = test_rand(rng, lo, hi);
  s[0] = fmax(a, b);
  s[1] = fmin(a, b);
  s[2] = test_rand(rng, lo, s[1]);
}

/* ---- tests ---------------------------------------------------------------------------- */

static void test_lame_wave_speed(void **state) {
  (void)state;
  mpm_material m = make(MPM_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, 0.25);
  /* mu = E / 2.6, lambda = 0.3 E / (1.3 * 0.4), c = sqrt((lambda + 2 mu) / rho) */
  const double mu = 38461.538461538461, la = 57692.307692307692;
  assert_close(m.mu, mu, TOL(1e-2, 1e-9));
  assert_close(m.lambda, la, TOL(1e-2, 1e-9));
  assert_close(m.wave_speed, 11.602387022306427, TOL(1e-5, 1e-12));
  assert_close(m.density, 1000, 0);
  assert_close(m.min_stretch, 0.25, 0);
  assert_true(m.model == &mpm_model_neo_hookean);
  assert_int_equal(m.kind, MPM_MODEL_NEO_HOOKEAN);
  mpm_material f = make(MPM_MODEL_FIXED_COROTATED, 2e6, 0.45, 500, 0.1);
  /* nu = 0.45: mu = E / 2.9, lambda = 0.45 E / (1.45 * 0.1) */
  assert_close(f.mu / 1e6, 2.0 / 2.9, TOL(1e-6, 1e-14));
  assert_close(f.lambda / 1e6, 0.9 / 0.145, TOL(1e-6, 1e-14));
  assert_close(f.wave_speed, sqrt((2e6 / 2.9 * 2 + 0.9e6 / 0.145) / 500), TOL(1e-4, 1e-11));
  assert_true(f.model == &mpm_model_fixed_corotated);
  assert_true(mpm_model_of(MPM_MODEL_FIXED_COROTATED) == &mpm_model_fixed_corotated);
  assert_true(mpm_model_of(MPM_MODEL_NEO_HOOKEAN) == &mpm_model_neo_hookean);
  assert_null(mpm_model_of(MPM_MODEL_COUNT));
  const mpm_model *models[2] = {&mpm_model_fixed_corotated, &mpm_model_neo_hookean};
  for (int i = 0; i < 2; ++i) {
    assert_non_null(models[i]->name);
    assert_non_null(models[i]->energy);
    assert_non_null(models[i]->pk1);
    assert_non_null(models[i]->dpdf_action);
    assert_non_null(models[i]->kirchhoff_batch);
  }
  assert_string_equal(mpm_model_fixed_corotated.name, "fixed_corotated");
  assert_string_equal(mpm_model_neo_hookean.name, "neo_hookean");
}

static void test_rest_state(void **state) {
  (void)state;
  uint64_t rng = 21;
  const mpm_material mats[2] = {make(MPM_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, 0.3),
                                make(MPM_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, 0.3)};
  for (int k = 0; k < 2; ++k) {
    const mpm_material *m = &mats[k];
    for (int t = 0; t < 50; ++t) {
      double Q[9];
      rand_rotation(&rng, Q);
      mpm_real F[9], P[9], dP[9], dF[9];
      to_real(Q, F, NULL);
      if (t == 0) mpm_m3_identity(F);
      const double scale = m->mu; /* zero relative to the stiffness */
      assert_close(m->model->energy(m, F) / scale, 0, TOL(1e-6, 1e-14));
      m->model->pk1(m, F, P);
      for (int i = 0; i < 9; ++i) assert_close(P[i] / scale, 0, TOL(2e-6, 1e-14));
      mpm_real Fc[9][MPM_STRESS_CHUNK], tau[9][MPM_STRESS_CHUNK];
      const mpm_real *Fp[9];
      for (int c = 0; c < 9; ++c) {
        Fc[c][0] = F[c];
        Fp[c] = Fc[c];
      }
      m->model->kirchhoff_batch(m, 1, Fp, NULL, tau);
      for (int c = 0; c < 9; ++c) assert_close(tau[c][0] / scale, 0, TOL(2e-6, 1e-14));
      /* the tangent at rest is the linear-elasticity one: a pure rotation rate dF = W F
       * (W skew) produces no stress change */
      const double w[3] = {test_rand(&rng, -1, 1), test_rand(&rng, -1, 1), test_rand(&rng, -1, 1)};
      const double Wm[9] = {0, -w[2], w[1], w[2], 0, -w[0], -w[1], w[0], 0};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          double s = 0;
          for (int q = 0; q < 3; ++q) s += Wm[3 * r + q] * F[3 * q + c];
          dF[3 * r + c] = (mpm_real)s;
        }
      m->model->dpdf_action(m, F, dF, dP);
      for (int i = 0; i < 9; ++i) assert_close(dP[i] / scale, 0, TOL(2e-5, 1e-12));
    }
  }
}

static void test_fixed_corotated(void **state) {
  (void)state;
  uint64_t rng = 22;
  const mpm_material m = make(MPM_MODEL_FIXED_COROTATED, 3.0, 0.3, 1000, 0.3);
  for (int t = 0; t < 3000; ++t) {
    double s[3], Q1[9], Q2[9], Fd[9], Pe[9];
    const char *what;
    switch (t % 3) {
    case 0:
      what = "fixed-corotated, well-conditioned";
      sorted_sigma(&rng, 0.3, 2.5, s);
      break;
    case 1:
      what = "fixed-corotated, near-singular";
      sorted_sigma(&rng, 0.5, 2.0, s);
      s[2] = (t & 4) ? 1e-6 : -1e-6;
      if (t % 9 == 1) s[2] = 0;
      break;
    default:
      /* inverted, keeping sigma1 + sigma2 >= 0.3 (away from the kink of R) */
      what = "fixed-corotated, inverted";
      sorted_sigma(&rng, 0.5, 2.0, s);
      s[2] = -test_rand(&rng, 0.05, s[1] - 0.3 > 0.05 ? s[1] - 0.3 : 0.06);
      break;
    }
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    compose(Q1, s, Q2, Fd);
    mpm_real F[9], P[9];
    to_real(Fd, F, NULL);
    check_fd(&m, F, &rng, &W.fcr_p_fd, &W.fcr_dp_fd, what, t);
    /* against the closed form built from the known rotation */
    fcr_expected(m.mu, m.lambda, Q1, s, Q2, Pe);
    m.model->pk1(&m, F, P);
    const double sc = fmax(maxabs(Pe, 9), (double)(m.mu + m.lambda));
    check_err(rel_err(P, Pe, 9, sc), TOL_EXACT, &W.fcr_p_exact, what, t);
  }
  /* where R has its kink (sigma1 + sigma2 = 0) the derivative stays finite */
  const mpm_real F[9] = {1, 0, 0, 0, (mpm_real)0.5, 0, 0, 0, (mpm_real)-0.5};
  mpm_real dF[9], dP[9];
  rand_dir(&rng, dF);
  m.model->dpdf_action(&m, F, dF, dP);
  for (int i = 0; i < 9; ++i) assert_true(isfinite(dP[i]));
  const mpm_real Z[9] = {0};
  m.model->dpdf_action(&m, Z, dF, dP);
  for (int i = 0; i < 9; ++i) assert_true(isfinite(dP[i]));
}

static void test_neo_hookean_unclamped(void **state) {
  (void)state;
  uint64_t rng = 23;
  /* two clamps: c = 0.2 (mostly the SVD-free path) and c = 0.45 (mostly the SVD path with no
   * clamp active); both must agree with the closed form */
  const mpm_material ms[2] = {make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, 0.2),
                              make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, 0.45)};
  for (int t = 0; t < 3000; ++t) {
    const mpm_material *m = &ms[t & 1];
    double s[3], Q1[9], Q2[9], Fd[9], Fr[9], Pe[9];
    sorted_sigma(&rng, 0.5, 1.8, s);
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    compose(Q1, s, Q2, Fd);
    mpm_real F[9], P[9];
    to_real(Fd, F, Fr);
    check_fd(m, F, &rng, &W.nh_p_fd, &W.nh_dp_fd, "neo-Hookean, unclamped", t);
    nh_closed(m->mu, m->lambda, Fr, Pe);
    m->model->pk1(m, F, P);
    const double sc = fmax(maxabs(Pe, 9), (double)(m->mu + m->lambda));
    check_err(rel_err(P, Pe, 9, sc), TOL_EXACT, &W.nh_p_exact, "neo-Hookean closed form", t);
  }
  /* the same F through the fast path (c = 0.5) and the SVD path (c = 0.62): F = 0.9 Q */
  const mpm_material fast = make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, 0.5);
  const mpm_material slow = make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, 0.62);
  for (int t = 0; t < 100; ++t) {
    double Q1[9], Q2[9], Fd[9];
    const double s[3] = {0.9 + test_rand(&rng, 0, 0.01), 0.9, 0.9 - test_rand(&rng, 0, 0.01)};
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    compose(Q1, s, Q2, Fd);
    mpm_real F[9], Pf[9], Ps[9], dF[9], dPf[9], dPs[9];
    double Pfd[9], dPfd[9];
    to_real(Fd, F, NULL);
    fast.model->pk1(&fast, F, Pf);
    slow.model->pk1(&slow, F, Ps);
    rand_dir(&rng, dF);
    fast.model->dpdf_action(&fast, F, dF, dPf);
    slow.model->dpdf_action(&slow, F, dF, dPs);
    for (int i = 0; i < 9; ++i) {
      Pfd[i] = Pf[i];
      dPfd[i] = dPf[i];
    }
    const double sc = (double)(fast.mu + fast.lambda);
    check_err(rel_err(Ps, Pfd, 9, sc), TOL_EXACT, &W.nh_p_exact, "fast vs SVD path P", t);
    check_err(rel_err(dPs, dPfd, 9, sc), TOL_EXACT, &W.nh_p_exact, "fast vs SVD path dP", t);
    assert_close(fast.model->energy(&fast, F) / sc, slow.model->energy(&slow, F) / sc, TOL_EXACT);
  }
}

/* Clamped region: stress, energy, tangent against the closed forms; finite for inverted F. */
static void test_neo_hookean_clamped(void **state) {
  (void)state;
  uint64_t rng = 24;
  const double cmin = 0.4;
  const mpm_material m = make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, cmin);
  const double mu = m.mu, la = m.lambda, sc = mu + la;
  for (int t = 0; t < 3000; ++t) {
    double s[3], Q1[9], Q2[9], Fd[9], Pe[9], psi, cl[3];
    s[0] = test_rand(&rng, 0.6, 2.0);
    s[1] = test_rand(&rng, t % 4 == 0 ? 0.1 : 0.5, s[0]); /* sometimes two clamped */
    s[2] = test_rand(&rng, -s[1], fmin(s[1], 0.38));      /* flat, compressed or inverted */
    if (fabs(s[1] + s[2]) < 0.05) continue;               /* keep clear of the ambiguous SVD */
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    compose(Q1, s, Q2, Fd);
    mpm_real F[9], P[9], dF[9], dP[9];
    to_real(Fd, F, NULL);
    nh_clamped_expected(mu, la, cmin, Q1, s, Q2, Pe, &psi, cl);
    m.model->pk1(&m, F, P);
    check_err(rel_err(P, Pe, 9, fmax(maxabs(Pe, 9), sc)), TOL_EXACT, &W.nh_clamp_p, "clamped P", t);
    const double e = m.model->energy(&m, F);
    check_err(fabs(e - psi) / fmax(fabs(psi), sc), TOL_EXACT, &W.nh_psi_exact, "clamped Psi", t);

    /* tangent: Zhu eq. 16 = Hessian of the unclamped energy at F_c = Q1 diag(c) Q2^T,
     * checked by differences of the double closed form */
    double Fc[9], Fp[9], Fm[9], Pp[9], Pm[9], dPe[9];
    compose(Q1, cl, Q2, Fc);
    rand_dir(&rng, dF);
    const double h = 1e-6;
    for (int i = 0; i < 9; ++i) {
      Fp[i] = Fc[i] + h * dF[i];
      Fm[i] = Fc[i] - h * dF[i];
    }
    nh_closed(mu, la, Fp, Pp);
    nh_closed(mu, la, Fm, Pm);
    for (int i = 0; i < 9; ++i) dPe[i] = (Pp[i] - Pm[i]) / (2 * h);
    m.model->dpdf_action(&m, F, dF, dP);
    check_err(rel_err(dP, dPe, 9, fmax(maxabs(dPe, 9), sc)), TOL(5e-5, 1e-8), &W.nh_clamp_dp,
              "clamped dP (Zhu eq. 16)", t);
    /* ... which is symmetric: dF2 : A(dF1) = dF1 : A(dF2) */
    mpm_real dF2[9], dP2[9];
    rand_dir(&rng, dF2);
    m.model->dpdf_action(&m, F, dF2, dP2);
    const double a12 = mpm_m3_ddot(dF2, dP), a21 = mpm_m3_ddot(dF, dP2);
    check_err(fabs(a12 - a21) / (sc * 9), TOL(2e-5, 1e-12), NULL, "clamped dP symmetry", t);

    /* along the clamped singular direction u2 v2^T only s2 moves, and dPsi/ds2 = p_2 */
    double D[9];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) D[3 * r + c] = Q1[3 * r + 2] * Q2[3 * c + 2];
    mpm_real Fpr[9], Fmr[9];
    for (int i = 0; i < 9; ++i) {
      Fpr[i] = (mpm_real)(Fd[i] + FD_H * D[i]);
      Fmr[i] = (mpm_real)(Fd[i] - FD_H * D[i]);
    }
    const double dpsi = ((double)m.model->energy(&m, Fpr) - m.model->energy(&m, Fmr)) / (2 * FD_H);
    double PD = 0;
    for (int i = 0; i < 9; ++i) PD += (double)P[i] * D[i];
    check_err(fabs(dpsi - PD) / sc, TOL_FD_P, &W.nh_clamp_dir, "dPsi along a clamped direction", t);
  }

  /* inverted, flat and zero F: everything finite; an inverted element is pushed back */
  const double cases[][3] = {{1, 1, -0.5}, {1, 1, 0},        {1, 0, 0},     {0, 0, 0},
                             {1, 1, -1},   {2, 1e-8, -1e-8}, {1, 1, -1e-30}};
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
    double Q1[9], Q2[9], Fd[9];
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    compose(Q1, cases[k], Q2, Fd);
    mpm_real F[9], P[9], dF[9], dP[9];
    to_real(Fd, F, NULL);
    rand_dir(&rng, dF);
    m.model->pk1(&m, F, P);
    m.model->dpdf_action(&m, F, dF, dP);
    assert_true(isfinite(m.model->energy(&m, F)));
    for (int i = 0; i < 9; ++i) {
      assert_true(isfinite(P[i]));
      assert_true(isfinite(dP[i]));
    }
    if (k == 0) { /* P : u3 v3^T = p_3 < 0: the stress opposes further inversion */
      double PD = 0;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) PD += (double)P[3 * r + c] * Q1[3 * r + 2] * Q2[3 * c + 2];
      assert_true(PD < 0);
    }
  }
}

/* P and Psi are continuous across sigma_min = min_stretch. */
static void test_neo_hookean_threshold(void **state) {
  (void)state;
  uint64_t rng = 25;
  const double cmin = 0.5;
  const mpm_material m = make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, cmin);
  const double sc = m.mu + m.lambda;
  const double offs[] = {-1e-2, -1e-4, -1e-6, 0, 1e-6, 1e-4, 1e-2};
  for (int t = 0; t < 200; ++t) {
    double Q1[9], Q2[9];
    rand_rotation(&rng, Q1);
    rand_rotation(&rng, Q2);
    const double s0 = test_rand(&rng, 0.8, 1.5), s1 = test_rand(&rng, 0.6, s0);
    mpm_real Pprev[9];
    double eprev = 0;
    for (size_t k = 0; k < sizeof offs / sizeof offs[0]; ++k) {
      double s[3] = {s0, s1, cmin * (1 + offs[k])}, Fd[9], Pe[9], psi, cl[3];
      compose(Q1, s, Q2, Fd);
      mpm_real F[9], P[9];
      to_real(Fd, F, NULL);
      nh_clamped_expected(m.mu, m.lambda, cmin, Q1, s, Q2, Pe, &psi, cl);
      m.model->pk1(&m, F, P);
      check_err(rel_err(P, Pe, 9, sc), TOL_EXACT, &W.continuity, "P at the threshold", t);
      const double e = m.model->energy(&m, F);
      check_err(fabs(e - psi) / sc, TOL_EXACT, &W.continuity, "Psi at the threshold", t);
      if (k > 0) { /* Lipschitz across the step in sigma_min */
        const double ds = cmin * fabs(offs[k] - offs[k - 1]);
        double Pp[9];
        for (int i = 0; i < 9; ++i) Pp[i] = Pprev[i];
        assert_true(rel_err(P, Pp, 9, sc) <= 20 * ds + 2 * TOL_EXACT);
        assert_true(fabs(e - eprev) / sc <= 20 * ds + 2 * TOL_EXACT);
      }
      mpm_m3_copy(P, Pprev);
      eprev = e;
    }
  }
}

static void check_batch(const mpm_material *m, uint64_t *rng, int n, int mode) {
  mpm_real Fc[9][MPM_STRESS_CHUNK], tau[9][MPM_STRESS_CHUNK];
  const mpm_real *Fp[9];
  for (int c = 0; c < 9; ++c) Fp[c] = Fc[c];
  for (int i = 0; i < n; ++i) {
    double s[3], Q1[9], Q2[9], Fd[9];
    sorted_sigma(rng, 0.5, 1.8, s);
    if (i % 4 == 1) s[2] = -test_rand(rng, 0.1, s[1]); /* inverted */
    if (i % 4 == 2) s[2] = test_rand(rng, 0.01, 0.3);  /* compressed (clamped for NH) */
    if (mode == 1) sorted_sigma(rng, 0.9, 1.1, s);     /* all on the NH fast path */
    rand_rotation(rng, Q1);
    rand_rotation(rng, Q2);
    compose(Q1, s, Q2, Fd);
    for (int c = 0; c < 9; ++c) Fc[c][i] = (mpm_real)Fd[c];
  }
  for (int c = 0; c < 9; ++c)
    for (int i = 0; i < MPM_STRESS_CHUNK; ++i) tau[c][i] = (mpm_real)1e30; /* poison */
  m->model->kirchhoff_batch(m, n, Fp, NULL, tau);
  for (int i = 0; i < n; ++i) {
    mpm_real F[9], P[9], T[9];
    double Te[9];
    for (int c = 0; c < 9; ++c) F[c] = Fc[c][i];
    m->model->pk1(m, F, P);
    mpm_m3_mul_bt(P, F, T);
    for (int c = 0; c < 9; ++c) Te[c] = T[c];
    mpm_real got[9];
    for (int c = 0; c < 9; ++c) got[c] = tau[c][i];
    check_err(rel_err(got, Te, 9, fmax(maxabs(Te, 9), (double)(m->mu + m->lambda))),
              TOL(2e-5, 1e-12), &W.batch, m->model->name, i);
    for (int r = 0; r < 3; ++r) /* symmetric */
      for (int c = 0; c < r; ++c)
        assert_close(got[3 * r + c] / (m->mu + m->lambda), got[3 * c + r] / (m->mu + m->lambda),
                     TOL(2e-5, 1e-12));
  }
  for (int c = 0; c < 9; ++c) /* nothing written past n */
    for (int i = n; i < MPM_STRESS_CHUNK; ++i) assert_true(tau[c][i] == (mpm_real)1e30);
  /* pk1_batch against pk1, on the same chunk (inverted and clamped particles included) */
  assert_non_null(m->model->pk1_batch);
  mpm_real P[9][MPM_STRESS_CHUNK];
  for (int c = 0; c < 9; ++c)
    for (int i = 0; i < MPM_STRESS_CHUNK; ++i) P[c][i] = (mpm_real)1e30;
  m->model->pk1_batch(m, n, Fp, P);
  for (int i = 0; i < n; ++i) {
    mpm_real F[9], Pi[9], got[9];
    double Pe[9];
    for (int c = 0; c < 9; ++c) F[c] = Fc[c][i];
    m->model->pk1(m, F, Pi);
    for (int c = 0; c < 9; ++c) {
      Pe[c] = Pi[c];
      got[c] = P[c][i];
    }
    check_err(rel_err(got, Pe, 9, fmax(maxabs(Pe, 9), (double)(m->mu + m->lambda))),
              TOL(2e-5, 1e-12), &W.pk1_batch, m->model->name, i);
  }
  for (int c = 0; c < 9; ++c)
    for (int i = n; i < MPM_STRESS_CHUNK; ++i) assert_true(P[c][i] == (mpm_real)1e30);
}

static void test_kirchhoff_batch(void **state) {
  (void)state;
  uint64_t rng = 26;
  const mpm_material mats[3] = {make(MPM_MODEL_FIXED_COROTATED, 1e5, 0.3, 1000, 0.3),
                                make(MPM_MODEL_NEO_HOOKEAN, 1e5, 0.3, 1000, 0.3),
                                make(MPM_MODEL_HENCKY_STVK, 1e5, 0.3, 1000, 0.3)};
  for (int k = 0; k < 3; ++k)
    for (int rep = 0; rep < 20; ++rep) {
      check_batch(&mats[k], &rng, MPM_STRESS_CHUNK, rep % 3 == 2);
      check_batch(&mats[k], &rng, 37, 0);
    }
}

static void test_von_mises(void **state) {
  (void)state;
  uint64_t rng = 27;
  for (int t = 0; t < 200; ++t) {
    const double p = test_rand(&rng, -1e5, 1e5), J = test_rand(&rng, 0.2, 2) * (t & 1 ? 1 : -1);
    mpm_real tau[9] = {(mpm_real)p, 0, 0, 0, (mpm_real)p, 0, 0, 0, (mpm_real)p};
    assert_close(mpm_von_mises(tau, (mpm_real)J) / 1e5, 0, TOL(1e-6, 1e-14));
    /* rotated uniaxial Cauchy stress sigma = a n n^T (tau = J sigma): von Mises = |a| */
    double Q[9];
    rand_rotation(&rng, Q);
    const double a = test_rand(&rng, -1e5, 1e5);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) tau[3 * r + c] = (mpm_real)(J * a * Q[3 * r] * Q[3 * c]);
    assert_close(mpm_von_mises(tau, (mpm_real)J) / 1e5, fabs(a) / 1e5, TOL(2e-6, 1e-13));
    /* plus a hydrostatic part changes nothing */
    for (int i = 0; i < 3; ++i) tau[4 * i] += (mpm_real)(J * p);
    assert_close(mpm_von_mises(tau, (mpm_real)J) / 1e5, fabs(a) / 1e5, TOL(4e-6, 1e-13));
    /* pure shear k: von Mises = sqrt(3) |k| */
    const double k = test_rand(&rng, -1e5, 1e5);
    mpm_real sh[9] = {0, (mpm_real)(J * k), 0, (mpm_real)(J * k), 0, 0, 0, 0, 0};
    assert_close(mpm_von_mises(sh, (mpm_real)J) / 1e5, sqrt(3.0) * fabs(k) / 1e5, TOL(2e-6, 1e-13));
  }
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

/* The definiteness fix (Teran et al. 2005; Zhu eqs. 16, 19): the 9x9 matrix of
 * dpdf_action_definite on the basis directions equals the eigenvalue-clamped (nearest
 * semi-definite) 9x9 matrix of dpdf_action, is symmetric and semi-definite, and equals
 * dpdf_action where that is already positive definite. Compressed, clamped (neo-Hookean),
 * stretched and inverted F; indefinite Hessians must occur among them. */
static void test_definite(void **state) {
  (void)state;
  uint64_t rng = 28;
  const mpm_material mats[2] = {make(MPM_MODEL_FIXED_COROTATED, 3.0, 0.3, 1000, 0.3),
                                make(MPM_MODEL_NEO_HOOKEAN, 3.0, 0.3, 1000, 0.3)};
  for (int k = 0; k < 2; ++k) {
    const mpm_material *m = &mats[k];
    int indefinite = 0, definite = 0;
    for (int t = 0; t < 1500; ++t) {
      double s[3], Q1[9], Q2[9], Fd[9];
      switch (t % 4) {
      case 0:
        sorted_sigma(&rng, 0.9, 1.1, s);
        break;
      case 1:
        sorted_sigma(&rng, 0.05, 0.7, s);
        break;
      case 2:
        sorted_sigma(&rng, 1.2, 3.0, s);
        break;
      default:
        sorted_sigma(&rng, 0.2, 2.0, s);
        s[2] = -test_rand(&rng, 0.01, s[1]);
        break;
      }
      rand_rotation(&rng, Q1);
      rand_rotation(&rng, Q2);
      compose(Q1, s, Q2, Fd);
      mpm_real F[9], Kr[81];
      to_real(Fd, F, NULL);
      double K[81], K0[81], Kp[81], eig[9];
      for (int b = 0; b < 9; ++b) {
        mpm_real e[9] = {0}, dP[9], dP0[9];
        e[b] = 1;
        m->model->dpdf_action_definite(m, F, e, dP);
        m->model->dpdf_action(m, F, e, dP0);
        for (int a = 0; a < 9; ++a) {
          K[9 * a + b] = dP[a];
          K0[9 * a + b] = dP0[a];
        }
      }
      const double sc = fmax(maxabs(K0, 81), (double)(m->mu + m->lambda));
      for (int a = 0; a < 9; ++a)
        for (int b = 0; b < a; ++b) {
          check_err(fabs(K[9 * a + b] - K[9 * b + a]) / sc, TOL(1e-5, 1e-12), NULL,
                    "definite action symmetric", t);
          K0[9 * a + b] = K0[9 * b + a] = 0.5 * (K0[9 * a + b] + K0[9 * b + a]);
        }
      psd_project9(K0, Kp);
      for (int i = 0; i < 81; ++i) Kr[i] = (mpm_real)K[i];
      check_err(rel_err(Kr, Kp, 81, sc), TOL(5e-5, 1e-10), &W.definite, "definite = PSD(K)", t);
      for (int a = 0; a < 9; ++a) /* symmetrize for the eigen-solve */
        for (int b = 0; b < a; ++b)
          K[9 * a + b] = K[9 * b + a] = 0.5 * (K[9 * a + b] + K[9 * b + a]);
      jacobi_eig(9, K, eig);
      for (int i = 0; i < 9; ++i)
        check_err(fmax(-eig[i], 0) / sc, TOL(2e-5, 1e-11), &W.definite, "semi-definite", t);
      jacobi_eig(9, K0, eig);
      double mn = eig[0];
      for (int i = 1; i < 9; ++i) mn = fmin(mn, eig[i]);
      if (mn < -1e-3 * sc) ++indefinite;
      if (mn > 1e-3 * sc) {
        ++definite;
        double K0r[81];
        for (int b = 0; b < 9; ++b) {
          mpm_real e[9] = {0}, dP0[9];
          e[b] = 1;
          m->model->dpdf_action(m, F, e, dP0);
          for (int a = 0; a < 9; ++a) K0r[9 * a + b] = dP0[a];
        }
        check_err(rel_err(Kr, K0r, 81, sc), TOL(2e-5, 1e-11), &W.definite, "definite = plain", t);
      }
    }
    assert_true(indefinite > 50 && definite > 50);
  }
}

static void test_report(void **state) {
  (void)state;
  print_message("materials (%s), worst relative errors:\n"
                "  fixed-corotated: P vs FD(Psi) %.3g, dP vs FD(P) %.3g, P vs closed form %.3g\n"
                "  neo-Hookean unclamped: P vs FD(Psi) %.3g, dP vs FD(P) %.3g, closed form / "
                "fast vs SVD path %.3g\n"
                "  neo-Hookean clamped: P %.3g, Psi %.3g, dP vs eq. 16 %.3g, dPsi along clamped "
                "direction %.3g, threshold %.3g\n"
                "  kirchhoff_batch vs pk1 F^T %.3g, pk1_batch vs pk1 %.3g\n"
                "  definiteness fix vs eigenvalue-clamped 9x9 / semi-definite / plain %.3g\n",
                MPM_REAL_NAME, W.fcr_p_fd, W.fcr_dp_fd, W.fcr_p_exact, W.nh_p_fd, W.nh_dp_fd,
                W.nh_p_exact, W.nh_clamp_p, W.nh_psi_exact, W.nh_clamp_dp, W.nh_clamp_dir,
                W.continuity, W.batch, W.pk1_batch, W.definite);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_lame_wave_speed),
      cmocka_unit_test(test_rest_state),
      cmocka_unit_test(test_fixed_corotated),
      cmocka_unit_test(test_neo_hookean_unclamped),
      cmocka_unit_test(test_neo_hookean_clamped),
      cmocka_unit_test(test_neo_hookean_threshold),
      cmocka_unit_test(test_kirchhoff_batch),
      cmocka_unit_test(test_von_mises),
      cmocka_unit_test(test_definite),
      cmocka_unit_test(test_report),
  };
  return cmocka_run_group_tests_name("material", tests, NULL, NULL);
}
