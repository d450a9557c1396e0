/* material_desc.h - a material as a scene describes it: the constitutive model and its
 * parameters, the strength schedule, heat and melting (material.h builds the runtime material). */
#ifndef MPM_MATERIAL_MATERIAL_DESC_H
#define MPM_MATERIAL_MATERIAL_DESC_H

#include "core/limits.h"

#include <stddef.h>

typedef enum mpm_model_kind {
  MPM_MODEL_FIXED_COROTATED = 0, /* Stomakhin et al. 2012; Gao sec. 4.1 */
  MPM_MODEL_NEO_HOOKEAN = 1,     /* compressible neo-Hookean with clamped singular values
                                    (Zhu sec. 5.3 and 7, Irving et al. 2004) */
  MPM_MODEL_HENCKY_STVK = 2,     /* St. Venant-Kirchhoff in Hencky strain (Gao eq. 7) */
  MPM_MODEL_DRUCKER_PRAGER = 3,  /* Hencky elasticity + Drucker-Prager sand (Klar et al. 2016,
                                    volume correction of Tampubolon et al. 2017; Gao 4.2.1) */
  MPM_MODEL_VON_MISES = 4,       /* Hencky elasticity + von Mises plasticity (Gao 4.2.2) */
  MPM_MODEL_SNOW = 5,            /* fixed-corotated + snow plasticity (Stomakhin et al. 2013) */
  MPM_MODEL_COUNT
} mpm_model_kind;

#define MPM_STRENGTH_KEYS 16

typedef struct mpm_material_desc {
  char name[MPM_NAME_MAX];
  mpm_model_kind model;
  double E;              /* Young's modulus, Pa (> 0) */
  double nu;             /* Poisson's ratio, (-1, 0.5) */
  double density;        /* kg/m^3 (> 0) */
  double min_stretch;    /* neo-Hookean: singular values clamped below this (Zhu 5.3); (0, 1] */
  double friction_angle; /* Drucker-Prager: degrees, [0, 90); default 30 */
  double cohesion;       /* Drucker-Prager: Pa, >= 0; default 0 (dry sand) */
  double yield_stress;   /* von Mises: Pa, > 0 */
  double theta_c;        /* snow: critical compression, (0, 1); default 2.5e-2 */
  double theta_s;        /* snow: critical stretch, > 0; default 7.5e-3 */
  double hardening;      /* snow: hardening coefficient xi, >= 0; default 10 */
  /* strength schedule (Zhu Fig. 5): the moduli scaled by a factor interpolated linearly between
   * keyframes (time s, factor >= 0), held before the first and after the last; none: 1 */
  int strength_count;
  double strength[MPM_STRENGTH_KEYS][2];
  /* heat (scene `heat`; heat/heat.h) */
  double specific_heat; /* c, J/(kg K), > 0; default 1000 */
  double conductivity;  /* k, W/(m K), >= 0; default 0 (no conduction) */
  /* melting (Zhu Fig. 11, a simplified Stomakhin et al. 2014): from `melt_point` on, the shear
   * modulus falls linearly over `melt_range` degrees to melt_shear times its value, and the
   * bulk part (lambda) to melt_bulk times its value; domain particles leave their domains when
   * they pass melt_point. melting 0: none */
  int melting;
  double melt_point, melt_range, melt_shear, melt_bulk;
  int heat_keys; /* the scene gave one of the heat keys (they need `heat`) */
} mpm_material_desc;

/* Lamé parameters from E and nu, and Young's modulus back from them (the one place the relations
 * are written; 0 when mu + lambda is not positive, as a schedule that zeroes the moduli makes
 * them). */
static inline void mpm_lame(double E, double nu, double *mu, double *lambda) {
  *mu = E / (2.0 * (1.0 + nu));
  *lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

static inline double mpm_young_from_lame(double mu, double lambda) {
  return mu + lambda > 0 ? mu * (3 * lambda + 2 * mu) / (lambda + mu) : 0;
}

#endif
