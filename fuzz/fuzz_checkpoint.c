/* fuzz_checkpoint.c - libFuzzer target for the checkpoint reader (io/checkpoint.c).
 *
 * Two halves of the input space, chosen by the first byte:
 *  - even: the bytes are a checkpoint file as found on disk, read by mpm_checkpoint_parse
 *    (what `mpm run --resume` does with a damaged or foreign file): the guard header must
 *    refuse anything it did not seal.
 *  - odd: the rest is sealed first (mpm_checkpoint_seal writes a valid header over its first
 *    512 bytes, as the writer does), so the input reaches HDF5 and the reader's own checks of
 *    attributes, dimensions, counts and checksums. This half explores HDF5 1.10's parser
 *    itself, which is known to crash on some damaged files (the reason for the header); set
 *    MPM_FUZZ_SEALED=1 to fuzz it, otherwise odd inputs are treated like even ones.
 * Every allocation is released; nothing is printed. */
#include "io/checkpoint.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static int sealed_mode = -1;
  if (sealed_mode < 0) {
    const char *e = getenv("MPM_FUZZ_SEALED");
    sealed_mode = e && e[0] == '1';
  }
  if (size < 1) return 0;
  const int seal = sealed_mode && (data[0] & 1);
  unsigned char *copy = malloc(size);
  if (!copy) return 0;
  memcpy(copy, data + 1, size - 1);
  if (seal) mpm_checkpoint_seal(copy, size - 1);
  mpm_checkpoint c;
  mpm_error err;
  mpm_checkpoint_parse(copy, size - 1, "fuzz.h5", &c, &err);
  mpm_checkpoint_free(&c);
  free(copy);
  return 0;
}
