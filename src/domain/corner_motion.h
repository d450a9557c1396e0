/* corner_motion.h - a domain corner's velocity and position at the end of a step, from the
 * grid's velocity at it (Zhu eq. 9 and sec. 7).
 *
 * Shared by G2P's corner loop (domain_transfer.c) and the pads' gather (corner_pads.c), which
 * moves each corner as soon as it has the grid's velocity there: one pass over the corners'
 * memory instead of two, and the FLIP increment never stored (the corner update streams some
 * 60 bytes a corner, and waited on memory: 26 ns a corner at 1M corners, issue 13). */
#ifndef MPM_DOMAIN_CORNER_MOTION_H
#define MPM_DOMAIN_CORNER_MOTION_H

#include "collide/boundary.h"
#include "core/compensated.h"
#include "domain/domain.h"
#include "transfer/transfer_lanes.h"

#include <string.h>

/* What moves every corner of a step. */
typedef struct mpm_corner_motion {
  const mpm_boundary *boundary;        /* at the end of the step */
  mpm_real dt;                         /* s */
  mpm_real alpha;                      /* the PIC/FLIP blend (not with apic) */
  int apic;                            /* the corner takes the grid's velocity */
  const mpm_real *clamp_lo, *clamp_hi; /* the box corners are kept in, m */
} mpm_corner_motion;

/* Corner c of s from the grid's velocity vnew at it and (FLIP) the increment dv = sum_i E_ai
 * (v_i^{n+1} - v_i^n): its velocity (PIC/FLIP blend, or vnew with apic) obeying the boundary,
 * its position moved by the grid velocity v^g (for an enriched corner, projected back to any
 * surface it would cross), and its packed copy for the particles (corner_pack). Returns |v^g|^2,
 * which bounds the next step. */
MPM_ALWAYS_INLINE mpm_real mpm_corner_move(mpm_domain_set *s, const mpm_corner_motion *m, size_t c,
                                           const mpm_real vnew[3], const mpm_real dv[3]) {
  mpm_real v[3];
  for (int d = 0; d < 3; ++d)
    v[d] = m->apic ? vnew[d] : m->alpha * (s->cv[d][c] + dv[d]) + (1 - m->alpha) * vnew[d];
  /* colliders and walls on the corners (Zhu sec. 7, Algorithm 1 line 24): the corner velocity
   * obeys the boundary rules, and the particles take their velocities from the corners, which
   * applies the collision impulse to them. The corner moves with the grid velocity (which the
   * grid update already made obey the boundary), as F does: F stays the gradient of the corner
   * positions (F = sum_a x_a g_ap^T) */
  mpm_real vg[3] = {vnew[0], vnew[1], vnew[2]};
  const mpm_real xn[3] = {s->cx[0][c], s->cx[1][c], s->cx[2][c]};
  mpm_boundary_apply(m->boundary, xn, 0, 1, v);
  /* an enriched corner moves with its own velocity, which obeyed the obstacles only where the
   * step began: its motion is projected back to any surface it would cross (Zhu sec. 7), in
   * the velocity F takes too */
  const mpm_domain_enrichment *en = &s->enrich;
  if (en->count > 0 && en->enriched[c]) mpm_boundary_project_motion(m->boundary, xn, m->dt, vg);
  for (int d = 0; d < 3; ++d) {
    s->cv[d][c] = v[d];
    /* Zhu eq. 9, summed with compensation (core/compensated.h) */
    s->cx[d][c] = mpm_compensated_move(s->cx[d][c], m->dt * vg[d], m->clamp_lo[d], m->clamp_hi[d],
                                       &s->cxc[d][c]);
  }
  mpm_real *pk = s->corner_pack[c]; /* what the particles read of the corner, together */
  for (int d = 0; d < 3; ++d) {
    pk[d] = s->cx[d][c];
    pk[3 + d] = s->cv[d][c];
    pk[6 + d] = vg[d];
  }
  return vg[0] * vg[0] + vg[1] * vg[1] + vg[2] * vg[2];
}

/* mpm_corner_move for a batch of MPM_LANES consecutive corners c0 .. c0 + MPM_LANES - 1 of the pads
 * (not enriched) at once, lane by lane the same operations, so the same results bit for bit. Only
 * where nothing in the boundary acts on them: no colliders, and no corner in a wall band
 * (checked here). Returns 0 (nothing done: move them one by one) or 1, with *max_v2 raised to
 * the largest |v^g|^2. */
MPM_ALWAYS_INLINE int mpm_corner_move_lanes(mpm_domain_set *s, const mpm_corner_motion *m,
                                            uint32_t c0, const mpm_vl vnew[3], const mpm_vl dv[3],
                                            mpm_real *max_v2) {
  const mpm_boundary *b = m->boundary;
  if (b->collider_count > 0) return 0;
  mpm_vl x[3];
  mpm_vl_index band = {0};
  for (int d = 0; d < 3; ++d) {
    memcpy(&x[d], s->cx[d] + c0, sizeof x[d]);
    band |= (x[d] < mpm_vl_splat(b->wall_lo[d])) | (x[d] > mpm_vl_splat(b->wall_hi[d]));
  }
  for (int l = 0; l < MPM_LANES; ++l)
    if (band[l]) return 0;
  mpm_vl vg2 = {0};
  for (int d = 0; d < 3; ++d) {
    mpm_vl cv, rem;
    memcpy(&cv, s->cv[d] + c0, sizeof cv);
    memcpy(&rem, s->cxc[d] + c0, sizeof rem);
    const mpm_vl v = m->apic ? vnew[d] : m->alpha * (cv + dv[d]) + (1 - m->alpha) * vnew[d];
    const mpm_vl t =
        mpm_compensated_move_lanes(x[d], m->dt * vnew[d], m->clamp_lo[d], m->clamp_hi[d], &rem);
    memcpy(s->cv[d] + c0, &v, sizeof v);
    memcpy(s->cx[d] + c0, &t, sizeof t);
    memcpy(s->cxc[d] + c0, &rem, sizeof rem);
    for (int l = 0; l < MPM_LANES; ++l) {
      mpm_real *pk = s->corner_pack[c0 + (uint32_t)l];
      pk[d] = t[l];
      pk[3 + d] = v[l];
      pk[6 + d] = vnew[d][l];
    }
    vg2 += vnew[d] * vnew[d];
  }
  for (int l = 0; l < MPM_LANES; ++l)
    if (vg2[l] > *max_v2) *max_v2 = vg2[l];
  return 1;
}

#endif
