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
 * that is not a frame of mpm, no common particles) exit 2 with the file named. */
#include "analysis/rest_error.h"
#include "cli.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Ids are read back as float (io.h): exact only below 2^24. */
#define MAX_EXACT_ID 16777216.0

typedef struct cloud_data {
  double (*x)[3];
  uint32_t *id;
  double *mass;
  size_t n;
} cloud_data;

static void cloud_free(cloud_data *c) {
  free(c->x);
  free(c->id);
  free(c->mass);
  memset(c, 0, sizeof *c);
}

static int load(const char *path, int body, cloud_data *c) {
  memset(c, 0, sizeof *c);
  mpm_vtu_frame f;
  mpm_error err;
  if (mpm_read_vtu(path, &f, &err) != MPM_OK) {
    fprintf(stderr, "mpm error: %s\n", err.message);
    return -1;
  }
  const mpm_vtu_array *pts = mpm_vtu_frame_array(&f, "Points");
  const mpm_vtu_array *id = mpm_vtu_frame_array(&f, "id");
  const mpm_vtu_array *mass = mpm_vtu_frame_array(&f, "mass");
  const mpm_vtu_array *bodies = mpm_vtu_frame_array(&f, "body");
  int rc = 0;
  if (!id || id->components != 1 || pts->components != 3) {
    fprintf(stderr, "mpm error: %s: expected the Points and the id array of an mpm frame\n", path);
    rc = -1;
  } else if (body >= 0 && (!bodies || bodies->components != 1)) {
    fprintf(stderr, "mpm error: %s: --body needs the frame's body array, which it lacks\n", path);
    rc = -1;
  }
  const size_t n = f.point_count > 0 ? (size_t)f.point_count : 0;
  if (!rc) {
    c->x = malloc((n + 1) * sizeof *c->x);
    c->id = malloc((n + 1) * sizeof *c->id);
    c->mass = mass && mass->components == 1 ? malloc((n + 1) * sizeof *c->mass) : NULL;
    if (!c->x || !c->id || (mass && mass->components == 1 && !c->mass)) {
      fprintf(stderr, "mpm error: out of memory reading %s\n", path);
      rc = -1;
    }
  }
  size_t k = 0;
  for (size_t i = 0; !rc && i < n; ++i) {
    if (body >= 0 && bodies->data[i] != body) continue;
    for (int d = 0; d < 3; ++d) c->x[k][d] = pts->data[3 * i + (size_t)d];
    const double v = id->data[i];
    if (!(v >= 0 && v < MAX_EXACT_ID)) {
      fprintf(stderr,
              "mpm error: %s: particle %zu has id %.0f; ids from 0 to 2^24 can be matched\n", path,
              i, v);
      rc = -1;
    }
    c->id[k] = (uint32_t)v;
    if (c->mass) c->mass[k] = mass->data[i];
    ++k;
  }
  c->n = k;
  mpm_vtu_frame_free(&f);
  if (rc) cloud_free(c);
  return rc;
}

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
  cloud_data r, f;
  if (load(rest_path, body, &r)) return MPM_EXIT_USAGE;
  if (load(final_path, body, &f)) {
    cloud_free(&r);
    return MPM_EXIT_USAGE;
  }
  const mpm_point_cloud rc = {r.n, (const double(*)[3])r.x, r.id, r.mass};
  const mpm_point_cloud fc = {f.n, (const double(*)[3])f.x, f.id, f.mass};
  mpm_rest_error e;
  const int st = mpm_rest_error_compute(&rc, &fc, &e);
  int code = MPM_EXIT_OK;
  if (st == -2) {
    fprintf(stderr, "mpm error: out of memory\n");
    code = MPM_EXIT_FAILURE;
  } else if (st) {
    fprintf(stderr,
            "mpm error: %s and %s: no particle id is in both frames, or the rest shape has no "
            "extent\n",
            rest_path, final_path);
    code = MPM_EXIT_USAGE;
  } else {
    const double tr = e.R[0] + e.R[4] + e.R[8];
    const double angle = acos(fmax(-1.0, fmin(1.0, (tr - 1) / 2))) * 180 / 3.14159265358979;
    printf("rest-state error: mean %.3e, max %.3e of the rest bounding-box diagonal %.4g m "
           "(%zu of %zu particles matched; rigid motion removed: %.2f degrees, translation "
           "%.4g %.4g %.4g m)\n",
           e.mean, e.max, e.diagonal, e.matched, r.n, angle, e.translation[0], e.translation[1],
           e.translation[2]);
  }
  cloud_free(&r);
  cloud_free(&f);
  return code;
}
