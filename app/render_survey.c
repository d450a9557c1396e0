/* render_survey.c - what `mpm render` decides before drawing: from a sample of the frames to
 * render, the box the material moves in (for a steady camera over the whole movie), whether
 * its velocity is uniform (then colour by speed would paint everything one colour, so the
 * default colours by material instead), the labels present and the field's colour range
 * (2nd to 98th percentile, so that a few outliers do not wash out the picture). */
#include "render_cmd.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Frames of at most this many particles in all are all read; beyond it a sample. */
#define SURVEY_POINTS 12000000L
#define SURVEY_SAMPLES 12
/* Speeds within a frame that differ by less than this (m/s, or relative to the fastest) are
 * one colour on the map. */
#define UNIFORM_ABS 1e-3
#define UNIFORM_REL 0.01

const char *const MPM_RENDER_FIELD_NAMES[FIELDS] = {"velocity", "J",    "stress",      "plastic",
                                                    "material", "body", "temperature", "melt"};

static int cmp_float(const void *a, const void *b) {
  const float x = *(const float *)a, y = *(const float *)b;
  return x < y ? -1 : x > y;
}

int mpm_render_field_values(const mpm_vtu_frame *fr, int field, float *out, char *why, size_t cap) {
  const char *name = MPM_RENDER_FIELD_NAMES[field];
  const mpm_vtu_array *a = mpm_vtu_frame_array(fr, name);
  if (!a) {
    snprintf(why, cap, "the frames have no '%s' array", name);
    return -1;
  }
  for (long i = 0; i < fr->point_count; ++i) {
    if (field == FIELD_VELOCITY) {
      const float *v = a->data + 3 * i;
      out[i] = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    } else {
      out[i] = a->data[i];
    }
  }
  return 0;
}

void mpm_render_frame_box(const mpm_vtu_frame *fr, double lo[3], double hi[3]) {
  const mpm_vtu_array *pts = mpm_vtu_frame_array(fr, "Points");
  const mpm_vtu_array *vol = mpm_vtu_frame_array(fr, "volume");
  float l[3] = {INFINITY, INFINITY, INFINITY}, h[3] = {-INFINITY, -INFINITY, -INFINITY};
  float vmax = 0;
  for (long i = 0; pts && i < fr->point_count; ++i) {
    const float *p = pts->data + 3 * i;
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) continue;
    for (int d = 0; d < 3; ++d) {
      l[d] = p[d] < l[d] ? p[d] : l[d];
      h[d] = p[d] > h[d] ? p[d] : h[d];
    }
    if (vol && vol->data[i] > vmax) vmax = vol->data[i];
  }
  /* the largest sphere's radius all round: one cube root, not one per particle */
  const double r = vol ? 0.75 * cbrt((double)vmax) : 0.005;
  for (int d = 0; d < 3; ++d) lo[d] = l[d] - r, hi[d] = h[d] + r;
}

/* The 2nd and 98th percentiles of v[0..n) (sorted in place). */
static void percentiles(float *v, size_t n, double *p2, double *p98) {
  qsort(v, n, sizeof *v, cmp_float);
  *p2 = v[(size_t)(0.02 * (double)(n - 1))];
  *p98 = v[(size_t)(0.98 * (double)(n - 1))];
}

static int read_frame(const char *dir, int k, mpm_vtu_frame *fr, char *why, size_t cap) {
  char path[4200];
  snprintf(path, sizeof path, "%s/frame_%04d.vtu", dir, k);
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_read_vtu(path, fr, &err) != MPM_OK) {
    snprintf(why, cap, "%s", err.message);
    return -1;
  }
  return 0;
}

/* One sampled frame into sv. */
static int survey_frame(const render_opts *o, const mpm_vtu_frame *fr, render_survey *sv, char *why,
                        size_t cap) {
  double lo[3], hi[3];
  mpm_render_frame_box(fr, lo, hi);
  for (int d = 0; d < 3; ++d)
    sv->lo[d] = fmin(sv->lo[d], lo[d]), sv->hi[d] = fmax(sv->hi[d], hi[d]);
  const size_t n = (size_t)fr->point_count;
  const mpm_vtu_array *mat = mpm_vtu_frame_array(fr, "material");
  const mpm_vtu_array *body = mpm_vtu_frame_array(fr, "body");
  for (size_t i = 0; i < n; ++i) {
    if (mat && mat->data[i] > sv->max_material) sv->max_material = (int)mat->data[i];
    if (body && body->data[i] > sv->max_body) sv->max_body = (int)body->data[i];
  }
  if (n == 0) return 0;
  float *v = malloc(n * sizeof *v);
  if (!v) {
    snprintf(why, cap, "out of memory for %zu particles", n);
    return -1;
  }
  double p2, p98;
  const int field = o->field < 0 ? FIELD_VELOCITY : o->field;
  if (o->field < 0 || o->field == FIELD_VELOCITY) {
    if (mpm_render_field_values(fr, FIELD_VELOCITY, v, why, cap)) {
      free(v);
      return -1;
    }
    percentiles(v, n, &p2, &p98);
    if (p98 - p2 > UNIFORM_ABS + UNIFORM_REL * p98) sv->uniform_speed = 0;
  }
  if (field != FIELD_MATERIAL && field != FIELD_BODY) {
    if (field != FIELD_VELOCITY) {
      if (mpm_render_field_values(fr, field, v, why, cap)) {
        free(v);
        return -1;
      }
      percentiles(v, n, &p2, &p98);
    }
    sv->field_lo = fmin(sv->field_lo, p2);
    sv->field_hi = fmax(sv->field_hi, p98);
  }
  free(v);
  return 0;
}

int mpm_render_survey(const render_opts *o, const int *frames, int nf, render_survey *sv, char *why,
                      size_t cap) {
  memset(sv, 0, sizeof *sv);
  for (int d = 0; d < 3; ++d) sv->lo[d] = INFINITY, sv->hi[d] = -INFINITY;
  sv->uniform_speed = 1;
  sv->field_lo = INFINITY, sv->field_hi = -INFINITY;
  const int rendered = (nf - 1) / o->every + 1;
  mpm_vtu_frame fr;
  if (read_frame(o->dir, frames[0], &fr, why, cap)) return -1;
  /* small frames are all read: a fast body between two samples would leave the picture */
  const long per = fr.point_count > 0 ? fr.point_count : 1;
  long want = SURVEY_POINTS / per;
  if (want < SURVEY_SAMPLES) want = SURVEY_SAMPLES;
  const int samples = rendered < want ? rendered : (int)want;
  int st = survey_frame(o, &fr, sv, why, cap);
  mpm_vtu_frame_free(&fr);
  for (int s = 1; st == 0 && s < samples; ++s) {
    const long r = (long)s * (rendered - 1) / (samples - 1); /* a rendered frame's rank */
    if (read_frame(o->dir, frames[r * o->every], &fr, why, cap)) return -1;
    st = survey_frame(o, &fr, sv, why, cap);
    mpm_vtu_frame_free(&fr);
  }
  sv->sampled = samples;
  return st;
}
