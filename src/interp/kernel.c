/* kernel.c - kernel construction (the weights themselves are inline in kernel.h). */
#include "interp/kernel.h"

const char *mpm_kernel_name(mpm_kernel_kind kind) {
  switch (kind) {
  case MPM_KERNEL_LINEAR:
    return "linear";
  case MPM_KERNEL_QUADRATIC:
    return "quadratic";
  case MPM_KERNEL_CUBIC:
    return "cubic";
  case MPM_KERNEL_UGIMP:
  case MPM_KERNEL_UGIMP_WIDE:
  case MPM_KERNEL_UGIMP_PAIRED:
    return "ugimp";
  }
  return "unknown";
}

mpm_kernel mpm_kernel_make(mpm_kernel_kind kind, mpm_real dx, mpm_real gimp_length) {
  mpm_kernel k = {0};
  k.kind = kind;
  k.dx = dx;
  k.inv_dx = 1 / dx;
  switch (kind) {
  case MPM_KERNEL_LINEAR:
    k.width = 2;
    k.shift = 0;
    break;
  case MPM_KERNEL_QUADRATIC:
    k.width = 3;
    k.shift = R_(0.5);
    break;
  case MPM_KERNEL_CUBIC:
    k.width = 4;
    k.shift = 1;
    break;
  case MPM_KERNEL_UGIMP:
  case MPM_KERNEL_UGIMP_WIDE:
  case MPM_KERNEL_UGIMP_PAIRED:
    /* support |x_i - x_p| < dx + L_p/2: up to 1.5 dx, three nodes from floor(x/dx - 1/2); up
       to 2 dx, four nodes from floor(x/dx - 1) */
    k.half_len = gimp_length / (2 * dx);
    if (!(k.half_len > 0)) k.half_len = R_(0.5);
    if (k.half_len > 1) k.half_len = 1;
    /* the wide box is a kind of its own, so that the common one's code stays as it is */
    k.kind = k.half_len > R_(0.5) ? MPM_KERNEL_UGIMP_WIDE : MPM_KERNEL_UGIMP;
    k.width = k.half_len > R_(0.5) ? 4 : 3;
    k.shift = k.half_len > R_(0.5) ? 1 : R_(0.5);
    break;
  }
  return k;
}

mpm_kernel mpm_kernel_paired(mpm_kernel k) {
  if (k.kind != MPM_KERNEL_UGIMP) return k;
  k.kind = MPM_KERNEL_UGIMP_PAIRED;
  k.width = 4; /* the even node below and 3 from the base: both bases of a pair */
  return k;
}
