/* survey.c - what a renderer (renderer.c) decides before drawing: from a sample of the frames
 * to draw, the box the material moves in (for a steady camera over the whole movie), whether
 * its velocity is uniform (then colour by speed would paint everything one colour, so the
 * default colours by material instead), the labels present and the field's colour range
 * (2nd to 98th percentile, so that a few outliers do not wash out the picture). */
#include "render/renderer.h"
#include "core/alloc.h"

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

const char *const MPM_RENDER_FIELD_NAMES[MPM_RENDER_FIELDS] = {
    "velocity", "J", "stress", "plastic", "material", "body", "temperature", "melt"};

static int cmp_float(const void *a, const void *b) {
  const float x = *(const float *)a, y = *(const float *)b;
  return x < y ? -1 : x > y;
}

mpm_status mpm_render_field_parse(const char *text, render_field_spec *spec) {
  static const char *const comps[] = {"x",  "y",  "z",  "xx", "xy", "xz",
                                      "yx", "yy", "yz", "zx", "zy", "zz"};
  const size_t len = text ? strlen(text) : 0;
  if (len == 0 || len >= sizeof spec->array) return MPM_ERR_INVALID;
  spec->field = MPM_RENDER_FIELD_ARRAY;
  spec->component = -1;
  snprintf(spec->label, sizeof spec->label, "%s", text);
  snprintf(spec->array, sizeof spec->array, "%s", text);
  char *dot = strrchr(spec->array, '.');
  if (dot && dot != spec->array)
    for (int k = 0; k < 12; ++k)
      if (!strcmp(dot + 1, comps[k])) {
        spec->component = k < 3 ? k : k - 3;
        *dot = '\0';
        /* .x .. .z name a vector's components, .xx .. .zz a tensor's (9 + k - 3 >= 9) */
        if (k >= 3) spec->component += 100;
        break;
      }
  return MPM_OK;
}

/* The frame's arrays by name, for a message: "velocity, mass, J". */
static void array_names(const mpm_vtu_frame *fr, char *buf, size_t cap) {
  size_t at = 0;
  buf[0] = '\0';
  for (int k = 0; k < fr->array_count && at < cap; ++k) {
    if (!strcmp(fr->arrays[k].name, "Points")) continue;
    at += (size_t)snprintf(buf + at, cap - at, "%s%s", at ? ", " : "", fr->arrays[k].name);
  }
}

mpm_status mpm_render_field_values(const mpm_vtu_frame *fr, const char *path,
                                   const render_field_spec *spec, float *out, mpm_error *err) {
  const int field = spec->field, array = field == MPM_RENDER_FIELD_ARRAY;
  const char *name = array ? spec->array : MPM_RENDER_FIELD_NAMES[field];
  const mpm_vtu_array *a = mpm_vtu_frame_array(fr, name);
  if (!a || !strcmp(name, "Points")) {
    char have[1024];
    array_names(fr, have, sizeof have);
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: the frames have no '%s' array (they have: %s%s)", path, name, have,
                         array ? "; output.fields lists what a run writes" : "");
  }
  const int nc = a->components;
  if (array && spec->component >= 0) {
    const int tensor = spec->component >= 100, c = spec->component % 100;
    if ((tensor && nc != 9) || (!tensor && nc != 3))
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "%s: '%s' has %d component%s: no component '%s' (a vector's are .x .y "
                           ".z, a tensor's .xx .. .zz)",
                           path, name, nc, nc == 1 ? "" : "s", spec->label + strlen(name) + 1);
    for (long i = 0; i < fr->point_count; ++i) out[i] = a->data[(size_t)nc * (size_t)i + (size_t)c];
    return MPM_OK;
  }
  for (long i = 0; i < fr->point_count; ++i) {
    if (nc == 1) {
      out[i] = a->data[i];
    } else { /* the magnitude: |v| for a vector (the speed), the Frobenius norm for a tensor */
      const float *v = a->data + (size_t)nc * (size_t)i;
      float m = 0;
      for (int c = 0; c < nc; ++c) m += v[c] * v[c];
      out[i] = sqrtf(m);
    }
  }
  return MPM_OK;
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

static mpm_status read_frame(const char *dir, int k, mpm_vtu_frame *fr, char *path, size_t cap,
                             mpm_error *err) {
  snprintf(path, cap, "%s/frame_%04d.vtu", dir, k);
  return mpm_read_vtu(path, fr, err);
}

/* One sampled frame (read from path) into sv; field AUTO: the speed's range. */
static mpm_status survey_frame(const render_field_spec *asked, const mpm_vtu_frame *fr,
                               const char *path, render_survey *sv, mpm_error *err) {
  const int field_asked = asked->field;
  const render_field_spec speed = {MPM_RENDER_FIELD_VELOCITY, "", -1, ""};
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
  if (n == 0) return MPM_OK;
  float *v = mpm_alloc(n * sizeof *v);
  if (!v) return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for %zu particles", path, n);
  double p2, p98;
  mpm_status st;
  const int field = field_asked < 0 ? MPM_RENDER_FIELD_VELOCITY : field_asked;
  if (field_asked < 0 || field_asked == MPM_RENDER_FIELD_VELOCITY) {
    if ((st = mpm_render_field_values(fr, path, &speed, v, err)) != MPM_OK) {
      mpm_free(v);
      return st;
    }
    percentiles(v, n, &p2, &p98);
    if (p98 - p2 > UNIFORM_ABS + UNIFORM_REL * p98) sv->uniform_speed = 0;
  }
  if (field != MPM_RENDER_FIELD_MATERIAL && field != MPM_RENDER_FIELD_BODY) {
    if (field != MPM_RENDER_FIELD_VELOCITY) {
      if ((st = mpm_render_field_values(fr, path, asked, v, err)) != MPM_OK) {
        mpm_free(v);
        return st;
      }
      percentiles(v, n, &p2, &p98);
    }
    sv->field_lo = fmin(sv->field_lo, p2);
    sv->field_hi = fmax(sv->field_hi, p98);
  }
  mpm_free(v);
  return MPM_OK;
}

mpm_status mpm_render_survey(const char *dir, const render_field_spec *field, int every,
                             const int *frames, int nf, render_survey *sv, mpm_error *err) {
  memset(sv, 0, sizeof *sv);
  for (int d = 0; d < 3; ++d) sv->lo[d] = INFINITY, sv->hi[d] = -INFINITY;
  sv->uniform_speed = 1;
  sv->field_lo = INFINITY, sv->field_hi = -INFINITY;
  const int rendered = (nf - 1) / every + 1;
  mpm_vtu_frame fr;
  char path[4200];
  mpm_status st = read_frame(dir, frames[0], &fr, path, sizeof path, err);
  if (st != MPM_OK) return st;
  sv->first_time = fr.time;
  /* small frames are all read: a fast body between two samples would leave the picture */
  const long per = fr.point_count > 0 ? fr.point_count : 1;
  long want = SURVEY_POINTS / per;
  if (want < SURVEY_SAMPLES) want = SURVEY_SAMPLES;
  const int samples = rendered < want ? rendered : (int)want;
  st = survey_frame(field, &fr, path, sv, err);
  mpm_vtu_frame_free(&fr);
  for (int s = 1; st == MPM_OK && s < samples; ++s) {
    const long r = (long)s * (rendered - 1) / (samples - 1); /* a rendered frame's rank */
    st = read_frame(dir, frames[r * every], &fr, path, sizeof path, err);
    if (st != MPM_OK) return st;
    st = survey_frame(field, &fr, path, sv, err);
    mpm_vtu_frame_free(&fr);
  }
  sv->sampled = samples;
  return st;
}
