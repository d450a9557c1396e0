/* material.c - the model table, materials built from scene descriptions, and the von Mises
 * equivalent stress used by the writers.
 *
 * Lamé parameters from Young's modulus and Poisson's ratio (mu = E / (2 (1 + nu)),
 * lambda = E nu / ((1 + nu)(1 - 2 nu))); the dilatational wave speed sqrt((lambda + 2 mu) /
 * rho) bounds the explicit time step (Gao et al. 2017 sec. 3.2, CFL). The models themselves
 * live in one file each (fixed_corotated.c, neo_hookean.c, hencky_stvk.c, drucker_prager.c,
 * von_mises.c, snow.c). Scene units are converted here: the friction angle from degrees to
 * radians; cohesion and yield stress stay in Pa. */
#include "material/material.h"
#include "material/isotropic.h"
#include "material/snow.h"

#include "core/mat3.h"

const mpm_model *mpm_model_of(mpm_model_kind kind) {
  switch (kind) {
  case MPM_MODEL_FIXED_COROTATED:
    return &mpm_model_fixed_corotated;
  case MPM_MODEL_NEO_HOOKEAN:
    return &mpm_model_neo_hookean;
  case MPM_MODEL_HENCKY_STVK:
    return &mpm_model_hencky_stvk;
  case MPM_MODEL_DRUCKER_PRAGER:
    return &mpm_model_drucker_prager;
  case MPM_MODEL_VON_MISES:
    return &mpm_model_von_mises;
  case MPM_MODEL_SNOW:
    return &mpm_model_snow;
  default:
    return NULL;
  }
}

void mpm_material_init(mpm_material *m, const mpm_material_desc *d) {
  /* in double, then rounded once to the real type */
  double mu, lambda;
  mpm_lame(d->E, d->nu, &mu, &lambda);
  m->model = mpm_model_of(d->model);
  m->kind = d->model;
  m->mu = (mpm_real)mu;
  m->lambda = (mpm_real)lambda;
  m->density = (mpm_real)d->density;
  m->min_stretch = (mpm_real)d->min_stretch;
  m->wave_speed = (mpm_real)sqrt((lambda + 2.0 * mu) / d->density);
  m->friction_angle = (mpm_real)(d->friction_angle * (3.14159265358979323846 / 180.0));
  m->cohesion = (mpm_real)d->cohesion;
  m->yield_stress = (mpm_real)d->yield_stress;
  m->theta_c = (mpm_real)d->theta_c;
  m->theta_s = (mpm_real)d->theta_s;
  m->hardening = (mpm_real)d->hardening;
  m->specific_heat = (mpm_real)d->specific_heat;
  m->conductivity = (mpm_real)d->conductivity;
  m->melting = d->melting;
  m->melt_point = (mpm_real)d->melt_point;
  m->melt_range = (mpm_real)d->melt_range;
  m->melt_shear = (mpm_real)d->melt_shear;
  m->melt_bulk = (mpm_real)d->melt_bulk;
}

/* sqrt(3/2 s:s) with s the deviatoric part of sigma = tau / J. Von Mises is homogeneous of
 * degree one, so it is evaluated on tau and divided by |J| (the sign of J does not matter);
 * J = 0 is replaced by the smallest normal number so the result stays finite-or-inf, never
 * NaN. Only the symmetric part of tau counts (tau = P F^T is symmetric for isotropic models). */
void mpm_stress_hessian_action(const mpm_stress_hessian *H, const mpm_real dF[9], mpm_real dP[9]) {
  mpm_iso_action(H, dF, dP);
}

mpm_real mpm_von_mises(const mpm_real tau[9], mpm_real J) {
  const mpm_real p = mpm_m3_trace(tau) / 3;
  const mpm_real d0 = tau[0] - p, d1 = tau[4] - p, d2 = tau[8] - p;
  const mpm_real s01 = R_(0.5) * (tau[1] + tau[3]), s02 = R_(0.5) * (tau[2] + tau[6]);
  const mpm_real s12 = R_(0.5) * (tau[5] + tau[7]);
  const mpm_real ss = d0 * d0 + d1 * d1 + d2 * d2 + 2 * (s01 * s01 + s02 * s02 + s12 * s12);
#ifdef MPM_USE_DOUBLE
  const mpm_real jmin = DBL_MIN;
#else
  const mpm_real jmin = FLT_MIN;
#endif
  return mpm_sqrt(R_(1.5) * ss) / mpm_fmax(mpm_fabs(J), jmin);
}

/* Snow (Stomakhin et al. 2013 eq. 3): mu and lambda scaled by exp(xi (1 - Jp)), and the wave
 * speed with them (by the square root). Every other model: *m. */
mpm_material mpm_material_at(const mpm_material *m, mpm_real plastic) {
  mpm_material r = *m;
  if (m->kind == MPM_MODEL_SNOW) {
    const mpm_real h = mpm_snow_hardening(m, plastic);
    r.mu *= h;
    r.lambda *= h;
    r.wave_speed *= mpm_sqrt(h);
  }
  return r;
}

mpm_real mpm_material_melt_fraction(const mpm_material *m, mpm_real T) {
  if (!m->melting || !(T > m->melt_point)) return 0;
  if (!(m->melt_range > 0)) return 1;
  const mpm_real f = (T - m->melt_point) / m->melt_range;
  return f < 1 ? f : 1;
}

mpm_material mpm_material_at_temperature(const mpm_material *m, mpm_real plastic, mpm_real T) {
  mpm_material r = mpm_material_at(m, plastic);
  const mpm_real f = mpm_material_melt_fraction(m, T);
  if (f > 0) {
    const mpm_real mu = r.mu * (1 + f * (m->melt_shear - 1));
    const mpm_real lambda = r.lambda * (1 + f * (m->melt_bulk - 1));
    /* the wave speed goes with sqrt(lambda + 2 mu) */
    const mpm_real before = r.lambda + 2 * r.mu, after = lambda + 2 * mu;
    if (before > 0) r.wave_speed *= mpm_sqrt(after / before);
    r.mu = mu;
    r.lambda = lambda;
  }
  return r;
}
