/* output_fields.c - the point arrays a particle frame holds when output.fields is not given. */
#include "io/io.h"

unsigned mpm_output_fields_default(int heat) {
  unsigned bits = 0;
  for (int f = MPM_FIELD_ID; f <= MPM_FIELD_ENRICHMENT; ++f) bits |= 1u << f;
  if (heat) bits |= 1u << MPM_FIELD_TEMPERATURE | 1u << MPM_FIELD_MELT;
  return bits;
}
