/* rest_error_frames.c - the rest-state error between two frame files (mpm/mpm.h
 * mpm_rest_error_frames; `mpm error`): both frames' positions, ids and masses are read back
 * (io/vtu_read.c), optionally kept to one body, and handed to mpm_rest_error_compute
 * (rest_error.c: matched by id, rigid motion removed by shape matching). */
#include "analysis/rest_error.h"
#include "core/alloc.h"
#include "io/io.h"
#include "mpm/mpm.h"

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
  mpm_free(c->x);
  mpm_free(c->id);
  mpm_free(c->mass);
  memset(c, 0, sizeof *c);
}

static mpm_status load(const char *path, int body, cloud_data *c, mpm_error *err) {
  memset(c, 0, sizeof *c);
  mpm_vtu_frame f;
  mpm_status st = mpm_read_vtu(path, &f, err);
  if (st != MPM_OK) return st;
  const mpm_vtu_array *pts = mpm_vtu_frame_array(&f, "Points");
  const mpm_vtu_array *id = mpm_vtu_frame_array(&f, "id");
  const mpm_vtu_array *mass = mpm_vtu_frame_array(&f, "mass");
  const mpm_vtu_array *bodies = mpm_vtu_frame_array(&f, "body");
  if (!id || id->components != 1 || !pts || pts->components != 3)
    st = mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: expected the Points and the id array of an mpm frame", path);
  else if (body >= 0 && (!bodies || bodies->components != 1))
    st = mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: a body was chosen, but the frame lacks the body array", path);
  const size_t n = f.point_count > 0 ? (size_t)f.point_count : 0;
  const int masses = mass && mass->components == 1;
  if (st == MPM_OK) {
    c->x = mpm_alloc((n + 1) * sizeof *c->x);
    c->id = mpm_alloc((n + 1) * sizeof *c->id);
    c->mass = masses ? mpm_alloc((n + 1) * sizeof *c->mass) : NULL;
    if (!c->x || !c->id || (masses && !c->mass))
      st = mpm_error_set(err, MPM_ERR_NOMEM, "out of memory reading %s", path);
  }
  size_t k = 0;
  for (size_t i = 0; st == MPM_OK && i < n; ++i) {
    if (body >= 0 && bodies->data[i] != body) continue;
    for (int d = 0; d < 3; ++d) c->x[k][d] = pts->data[3 * i + (size_t)d];
    const double v = id->data[i];
    if (!(v >= 0 && v < MAX_EXACT_ID))
      st = mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: particle %zu has id %.0f; ids from 0 to 2^24 can be matched", path, i,
                         v);
    c->id[k] = (uint32_t)v;
    if (c->mass) c->mass[k] = mass->data[i];
    ++k;
  }
  c->n = k;
  mpm_vtu_frame_free(&f);
  if (st != MPM_OK) cloud_free(c);
  return st;
}

mpm_status mpm_rest_error_frames(const char *rest_path, const char *final_path, int body,
                                 mpm_rest_error_result *out, char *errbuf, size_t errlen) {
  mpm_error err;
  mpm_error_clear(&err);
  cloud_data r, f;
  memset(&f, 0, sizeof f);
  mpm_status st = !rest_path || !final_path || !out
                      ? mpm_error_set(&err, MPM_ERR_INVALID,
                                      "mpm_rest_error_frames: a path or the result is NULL")
                      : load(rest_path, body, &r, &err);
  if (st == MPM_OK) {
    st = load(final_path, body, &f, &err);
    if (st != MPM_OK) cloud_free(&r);
  }
  if (st == MPM_OK) {
    memset(out, 0, sizeof *out);
    const mpm_point_cloud rc = {r.n, (const double(*)[3])r.x, r.id, r.mass};
    const mpm_point_cloud fc = {f.n, (const double(*)[3])f.x, f.id, f.mass};
    mpm_rest_error e;
    const mpm_status computed = mpm_rest_error_compute(&rc, &fc, &e);
    if (computed == MPM_ERR_NOMEM) {
      st = mpm_error_set(&err, MPM_ERR_NOMEM, "out of memory");
    } else if (computed != MPM_OK) {
      st = mpm_error_set(&err, MPM_ERR_INVALID,
                         "%s and %s: no particle id is in both frames%s, or the rest shape has "
                         "no extent",
                         rest_path, final_path, body >= 0 ? " (of that body)" : "");
    } else {
      out->mean = e.mean;
      out->max = e.max;
      out->diagonal = e.diagonal;
      out->matched = e.matched;
      out->rest_particles = r.n;
      memcpy(out->rotation, e.R, sizeof out->rotation);
      memcpy(out->translation, e.translation, sizeof out->translation);
      const double tr = e.R[0] + e.R[4] + e.R[8];
      out->rotation_degrees = acos(fmax(-1.0, fmin(1.0, (tr - 1) / 2))) * 180 / 3.14159265358979;
    }
    cloud_free(&r);
    cloud_free(&f);
  }
  if (st != MPM_OK && errbuf && errlen) snprintf(errbuf, errlen, "%s", err.message);
  return st;
}
