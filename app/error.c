/* error.c - `mpm error`: the rest-state error of a run (Zhu et al. 2017 sec. 7; see
 * src/analysis/rest_error.h).
 *
 *   mpm error REST.vtu FINAL.vtu [--body N]
 *   mpm error OUTDIR REST_FRAME FINAL_FRAME [--body N]    (OUTDIR/frame_NNNN.vtu)
 *
 * --body N keeps the particles of body N only (the frames' `body` array): the error of the
 * armadillo, not of the ball that hit it.
 * Reads both frames (positions, ids and masses), matches particles by id, removes the rigid
 * motion by shape matching and prints the mean and largest distance over the rest shape's
 * bounding-box diagonal, the particles matched and the rotation removed. Input errors (a file
 * that is not a frame of mpm, no common particles) exit 2 with the file named. On the public
 * API alone (mpm_rest_error_frames). */
#include "cli.h"
#include "mpm/mpm.h"

#include <stdio.h>
#include <string.h>

int mpm_cmd_error(int argc, char **argv) {
  char rest_path[4200], final_path[4200];
  int body = -1;
  char *args[3];
  int nargs = 0;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--body")) {
      if (mpm_cli_parse_int("--body", i + 1 < argc ? argv[i + 1] : NULL, 0, 1000000, &body))
        return MPM_EXIT_USAGE;
      ++i;
    } else if (nargs < 3) {
      args[nargs++] = argv[i];
    } else {
      nargs = 4;
    }
  }
  argc = nargs;
  argv = args;
  if (argc == 2) {
    snprintf(rest_path, sizeof rest_path, "%s", argv[0]);
    snprintf(final_path, sizeof final_path, "%s", argv[1]);
  } else if (argc == 3) {
    int a, b;
    if (mpm_cli_parse_int("REST_FRAME", argv[1], 0, 9999999, &a) ||
        mpm_cli_parse_int("FINAL_FRAME", argv[2], 0, 9999999, &b))
      return MPM_EXIT_USAGE;
    snprintf(rest_path, sizeof rest_path, "%s/frame_%04d.vtu", argv[0], a);
    snprintf(final_path, sizeof final_path, "%s/frame_%04d.vtu", argv[0], b);
  } else {
    fprintf(stderr, "usage: mpm error REST.vtu FINAL.vtu [--body N] | mpm error OUTDIR "
                    "REST_FRAME FINAL_FRAME [--body N]\n");
    return MPM_EXIT_USAGE;
  }
  mpm_rest_error_result e;
  char err[4400];
  const mpm_status st = mpm_rest_error_frames(rest_path, final_path, body, &e, err, sizeof err);
  if (st != MPM_OK) {
    fprintf(stderr, "mpm error: %s\n", err);
    return st == MPM_ERR_NOMEM ? MPM_EXIT_FAILURE : MPM_EXIT_USAGE;
  }
  printf("rest-state error: mean %.3e, max %.3e of the rest bounding-box diagonal %.4g m "
         "(%zu of %zu particles matched; rigid motion removed: %.2f degrees, translation "
         "%.4g %.4g %.4g m)\n",
         e.mean, e.max, e.diagonal, e.matched, e.rest_particles, e.rotation_degrees,
         e.translation[0], e.translation[1], e.translation[2]);
  return MPM_EXIT_OK;
}
