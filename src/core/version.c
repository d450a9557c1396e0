/* version.c - library version and build configuration. */
#include "mpm/mpm.h"
#include "core/alloc.h"
#include "core/real.h"

const char *mpm_version(void) {
  return MPM_VERSION_STRING;
}
const char *mpm_real_type(void) {
  return MPM_REAL_NAME;
}

size_t mpm_live_bytes(void) {
  return mpm_alloc_live_bytes();
}

mpm_status mpm_set_allocator(const mpm_allocator *a) {
  if (a && (!a->alloc || !a->free)) return MPM_ERR_INVALID;
  if (mpm_alloc_live_bytes() != 0) return MPM_ERR_INVALID;
  mpm_alloc_set_hook(a ? a->alloc : NULL, a ? a->free : NULL, a ? a->user : NULL);
  return MPM_OK;
}
