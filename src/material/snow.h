/* snow.h - private to src/material/: the snow hardening factor (Stomakhin et al. 2013 eq. 3),
 * shared by snow.c and mpm_material_at (material.c). */
#ifndef MPM_MATERIAL_SNOW_H
#define MPM_MATERIAL_SNOW_H

#include "material/material.h"

/* exp(xi (1 - Jp)) with Jp clamped to the range the return map keeps it in (snow.c). */
mpm_real mpm_snow_hardening(const mpm_material *m, mpm_real Jp);

/* The fixed-corotated Kirchhoff stress of a chunk (fixed_corotated.c) with both Lamé
 * parameters of particle i multiplied by scale[i] (scale NULL: by 1). */
void mpm_fcr_kirchhoff_scaled(const mpm_material *m, int n, const mpm_real *const F[9],
                              const mpm_real *scale, mpm_real tau[9][MPM_STRESS_CHUNK]);

#endif
