/* main.c - the `mpm` command line program (being written; see issue 2). */
#include "mpm/mpm.h"
#include <stdio.h>
int main(void) {
  printf("mpm %s\n", MPM_VERSION_STRING);
  return 0;
}
