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
