/* material.h - the constitutive-model seam: one file per model behind one table.
 *
 * A model (fixed_corotated.c, neo_hookean.c, and later Hencky-StVK, Drucker-Prager, von
 * Mises, snow) fills an mpm_model table. The solver groups particles by material and calls
 * the batch entry on runs of particles of one material, so inner loops never branch per
 * particle on the model. Plastic models will add a return map entry to the same table. */
#ifndef MPM_MATERIAL_MATERIAL_H
#define MPM_MATERIAL_MATERIAL_H

#include "core/real.h"
#include "material/material_desc.h"

/* Particles per batch call: small enough for a stack buffer, large enough to vectorize. */
#define MPM_STRESS_CHUNK 64

typedef struct mpm_model mpm_model;

/* The stress derivative dP/dF of an isotropic model at one F, factored in the diagonal (SVD)
 * space (material/isotropic.h): F = U diag(sigma) V^T, the 3x3 block A = d2 psi / dsigma^2
 * and the twist/flip eigenvalues lsym, lskew of the pairs (0,1), (0,2), (1,2). The implicit
 * solve builds it once per particle and Newton iteration and applies it at every CG
 * iteration (mpm_stress_hessian_action), so the SVD and the definiteness fix are not redone
 * per action. */
typedef struct mpm_stress_hessian {
  mpm_real U[9], V[9];
  mpm_real A[9]; /* symmetric, row-major */
  mpm_real lsym[3], lskew[3];
} mpm_stress_hessian;

/* A material as the solver sees it: the model and its parameters in the real type. */
typedef struct mpm_material {
  const mpm_model *model;
  mpm_model_kind kind;
  mpm_real mu, lambda;  /* Lamé parameters, Pa */
  mpm_real density;     /* kg/m^3 */
  mpm_real min_stretch; /* neo-Hookean singular-value clamp (Zhu sec. 5.3) */
  mpm_real wave_speed;  /* sqrt((lambda + 2 mu) / density), m/s: the CFL bound */
  /* plasticity parameters, converted from the scene (unused by elastic models) */
  mpm_real friction_angle;              /* Drucker-Prager, rad */
  mpm_real cohesion;                    /* Drucker-Prager, Pa */
  mpm_real yield_stress;                /* von Mises, Pa */
  mpm_real theta_c, theta_s, hardening; /* snow (Stomakhin et al. 2013) */
  /* heat (heat/heat.h) and melting (scene.h, mpm_material_desc) */
  mpm_real specific_heat, conductivity; /* J/(kg K), W/(m K) */
  int melting;
  mpm_real melt_point, melt_range, melt_shear, melt_bulk;
} mpm_material;

struct mpm_model {
  const char *name;
  /* Energy density Psi(F), J/m^3. */
  mpm_real (*energy)(const mpm_material *m, const mpm_real F[9]);
  /* First Piola-Kirchhoff stress P = dPsi/dF, Pa. */
  void (*pk1)(const mpm_material *m, const mpm_real F[9], mpm_real P[9]);
  /* dP = (dP/dF) : dF, the action of the stress derivative on a direction (Zhu sec. 6). */
  void (*dpdf_action)(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                      mpm_real dP[9]);
  /* The same with the Hessian made positive semi-definite in the diagonal (SVD) space (Teran
   * et al. 2005; Zhu eqs. 16 and 19), for the implicit solve. NULL until a model provides it. */
  void (*dpdf_action_definite)(const mpm_material *m, const mpm_real F[9], const mpm_real dF[9],
                               mpm_real dP[9]);
  /* The definite derivative above, factored (for repeated actions): dpdf_action_definite(F,
   * dF) equals mpm_stress_hessian_action(H, dF) with H from here, bitwise. */
  void (*hessian_definite)(const mpm_material *m, const mpm_real F[9], mpm_stress_hessian *H);
  /* The same from F's SVD F = U diag(s) V^T (core/svd3.h's signs) taken by the caller, which
   * hessian_definite is after its own mpm_svd3 (bitwise): for callers that take the SVDs of many
   * particles at once (mpm_svd3_batch). NULL: no such entry. */
  void (*hessian_definite_svd)(const mpm_material *m, const mpm_real U[9], const mpm_real s[3],
                               const mpm_real V[9], mpm_stress_hessian *H);
  /* Batch: for n <= MPM_STRESS_CHUNK particles whose F components start at F[0..8][0] and
   * whose plastic state starts at plastic[0] (NULL: every particle at plastic_initial), write
   * the Kirchhoff stress tau = P F^T into tau[c][i] (component c, particle i). */
  void (*kirchhoff_batch)(const mpm_material *m, int n, const mpm_real *const F[9],
                          const mpm_real *plastic, mpm_real tau[9][MPM_STRESS_CHUNK]);
  /* Batch: the first Piola-Kirchhoff stress P of n <= MPM_STRESS_CHUNK particles, as pk1 gives
   * it, into P[c][i] (the particle domains' forces need P, Zhu eq. 8; P from tau F^-T would
   * lose accuracy where F is nearly singular). The material's own moduli: callers of models
   * whose moduli vary per particle (mpm_material_varies) use pk1. NULL: no batch entry. */
  void (*pk1_batch)(const mpm_material *m, int n, const mpm_real *const F[9],
                    mpm_real P[9][MPM_STRESS_CHUNK]);
  /* Plastic models: project the trial elastic F of n particles (components F[0..8][0..n))
   * back to the yield surface in place and update their plastic state (Gao sec. 4.2). NULL
   * for purely elastic models. */
  void (*return_map)(const mpm_material *m, int n, mpm_real *const F[9], mpm_real *plastic);
  /* The plastic state of a particle at rest (J_p = 1 for snow; unused state is 1 too). */
  mpm_real plastic_initial;
};

extern const mpm_model mpm_model_fixed_corotated;
extern const mpm_model mpm_model_neo_hookean;
extern const mpm_model mpm_model_hencky_stvk;
extern const mpm_model mpm_model_drucker_prager;
extern const mpm_model mpm_model_von_mises;
extern const mpm_model mpm_model_snow;

/* Table lookup by kind; NULL for an unknown kind. */
const mpm_model *mpm_model_of(mpm_model_kind kind);

/* Build the solver's material from a scene description (Lamé parameters, wave speed). */
void mpm_material_init(mpm_material *m, const mpm_material_desc *d);

/* The material as one particle with plastic state `plastic` sees it: hardening models (snow)
 * scale their moduli, every other model returns *m. For the per-particle entries (energy,
 * pk1, dpdf_action), which take no plastic state. */
mpm_material mpm_material_at(const mpm_material *m, mpm_real plastic);

/* How far a particle at temperature T has melted: 0 at or below the melting point, rising
 * linearly to 1 over melt_range degrees (at once when the range is 0); 0 for a material that
 * does not melt. */
mpm_real mpm_material_melt_fraction(const mpm_material *m, mpm_real T);

/* mpm_material_at, then the moduli softened by melting at temperature T: mu scaled by
 * 1 + f (melt_shear - 1) and lambda by 1 + f (melt_bulk - 1), f the melt fraction. */
mpm_material mpm_material_at_temperature(const mpm_material *m, mpm_real plastic, mpm_real T);

/* Whether a particle's moduli can differ from the material's (snow hardening, melting): where
 * not, mpm_material_at_temperature returns *m, and a loop over particles may skip the copy. */
static inline int mpm_material_varies(const mpm_material *m) {
  return m->melting || m->kind == MPM_MODEL_SNOW;
}

/* dP = (dP/dF) : dF with a factored derivative: U dP^(U^T dF V) V^T (material/isotropic.h). */
void mpm_stress_hessian_action(const mpm_stress_hessian *H, const mpm_real dF[9], mpm_real dP[9]);

/* Von Mises equivalent of the Cauchy stress sigma = tau / J, Pa (a scalar for outputs). */
mpm_real mpm_von_mises(const mpm_real tau[9], mpm_real J);

#endif
