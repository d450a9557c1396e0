/* version.c - library version and build configuration. */
#include "mpm/mpm.h"
#include "core/real.h"

const char *mpm_version(void) {
  return MPM_VERSION_STRING;
}
const char *mpm_real_type(void) {
  return MPM_REAL_NAME;
}
