/* renderer_draw.c - one picture of a renderer (mpm/render.h: mpm_renderer_draw, _pixels,
 * _write_png) and a whole run's pictures to PNG (mpm_render_run).
 *
 * Each picture: the background (cached while the colliders stand still and the view does not
 * move), the ground's shadow, the particle surfaces and the particles as spheres (those a
 * surface stands for left out), the grid, then the colour bar and the time. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include "render/renderer.h"
#include "core/alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The background of the colliders acting at time t (a grip's `active` window), recomputed
 * only when one of them moved or the view did. */
static void background(mpm_renderer *r, const mpm_camera *cam, double t) {
  double key = 0;
  int na = 0, ground = -1;
  for (int k = 0; k < r->collider_count; ++k) {
    const double *w = r->colliders[k].desc.active;
    if (!(t >= w[0] && t < w[1])) continue;
    if (k == r->ground_collider) ground = na;
    r->poses[na] = mpm_collider_pose_at(&r->colliders[k], t);
    for (int d = 0; d < 3; ++d) key += (d + 1.0) * (k + 1.0) * r->poses[na].center[d];
    for (int d = 0; d < 9; ++d) key += (d + 2.0) * (k + 3.0) * r->poses[na].R[d];
    key += 1e3 * (k + 1.0);
    ++na;
  }
  if (!(key == r->bg_key)) {
    mpm_render_background(&r->bg, cam, &r->ground, r->dom_lo, r->dom_hi, r->poses, na, ground);
    r->bg_key = r->opts.framing == MPM_RENDER_FRAMING_FOLLOW && !r->own_camera ? NAN : key;
  }
  const size_t pix = (size_t)r->opts.width * (size_t)r->opts.height;
  memcpy(r->img.rgb, r->bg.rgb, 3 * pix * sizeof(float));
  memcpy(r->img.depth, r->bg.depth, pix * sizeof(float));
}

/* The particles of fr as spheres with the field's colours, after the shadow and the surfaces. */
static mpm_status draw_frame(mpm_renderer *r, const mpm_vtu_frame *fr, const char *path, int frame,
                             const mpm_camera *cam, float *xyz, float *rad, float *rgb,
                             float *val) {
  const mpm_render_options *o = &r->opts;
  mpm_error *err = &r->error;
  const size_t n = (size_t)fr->point_count;
  const mpm_vtu_array *pts = mpm_vtu_frame_array(fr, "Points");
  const mpm_vtu_array *vol = mpm_vtu_frame_array(fr, "volume");
  mpm_status st = mpm_render_field_values(fr, path, &r->spec, val, err);
  if (st != MPM_OK) return st;
  for (size_t i = 0; i < n; ++i) {
    memcpy(xyz + 3 * i, pts->data + 3 * i, 3 * sizeof(float));
    /* spheres of 0.75 of the particle spacing cbrt(V): touching neighbours overlap a little,
       so a body reads as a surface */
    rad[i] = vol ? 0.75f * cbrtf(fmaxf(vol->data[i], 0)) : 0.005f;
    const double t = r->colormap == MPM_CMAP_CATEGORY ? val[i] : (val[i] - r->lo) / (r->hi - r->lo);
    mpm_colormap_eval(r->colormap, t, rgb + 3 * i);
  }
  background(r, cam, fr->time);
  /* the shadow of every particle, those a surface stands for too */
  if (o->shadow &&
      (st = mpm_render_ground_shadow(&r->img, cam, &r->ground, n, xyz, rad, 0, err)) != MPM_OK)
    return st;
  /* the particle surfaces first; the particles they stand for are then left out */
  int surfaces = 0;
  st = mpm_render_draw_surfaces(r->run_dir, frame, r->have_scene ? r->scene.body_count : 64,
                                &r->img, cam, &surfaces, err);
  if (st != MPM_OK) return st;
  size_t drawn = n;
  if (surfaces && r->have_scene && !o->particles) {
    const mpm_vtu_array *body = mpm_vtu_frame_array(fr, "body");
    const mpm_vtu_array *mat = mpm_vtu_frame_array(fr, "material");
    drawn = 0;
    for (size_t i = 0; i < n; ++i) {
      if (body && mat && mpm_render_on_surface(&r->scene, (int)body->data[i], (int)mat->data[i]))
        continue;
      memmove(xyz + 3 * drawn, xyz + 3 * i, 3 * sizeof *xyz);
      memmove(rgb + 3 * drawn, rgb + 3 * i, 3 * sizeof *rgb);
      rad[drawn++] = rad[i];
    }
  }
  if ((st = mpm_render_particles(&r->img, cam, drawn, xyz, rad, 0, rgb, err)) != MPM_OK) return st;
  if (r->edge_count) mpm_render_lines(&r->img, cam, r->edge_count, r->edges, r->edge_rgb, 0.3f);
  /* no colour bar when every particle is drawn as a surface, which is not coloured by it */
  if (o->legend && (r->colormap != MPM_CMAP_CATEGORY || r->legend.count > 0) && (drawn || !n))
    mpm_render_legend(&r->img, &r->legend);
  r->drawn_spheres = drawn;
  r->drawn_surfaces = surfaces;
  return MPM_OK;
}

static mpm_status draw(mpm_renderer *r, int index) {
  const mpm_render_options *o = &r->opts;
  mpm_error *err = &r->error;
  const int frame = r->frames[index * o->every];
  mpm_status st;
  if (o->grid && frame != r->edges_frame) { /* a grid rebuilt during the run: a file per frame */
    mpm_free(r->edges), mpm_free(r->edge_rgb);
    r->edges = r->edge_rgb = NULL;
    r->edge_count = 0;
    r->edges_frame = -1;
    st = mpm_render_grid_edges(r->run_dir, frame, &r->edges, &r->edge_rgb, &r->edge_count, err);
    if (st != MPM_OK) return st;
    r->edges_frame = frame;
  }
  char path[4300];
  snprintf(path, sizeof path, "%s/frame_%04d.vtu", r->run_dir, frame);
  mpm_vtu_frame fr;
  if ((st = mpm_read_vtu(path, &fr, err)) != MPM_OK) return st;
  char label[160];
  mpm_renderer_time_text(label, sizeof label, fr.time, frame, r->fps);
  mpm_camera cam = r->cam;
  if (!r->own_camera && o->framing == MPM_RENDER_FRAMING_FOLLOW) {
    double lo[3], hi[3];
    mpm_render_frame_box(&fr, lo, hi);
    cam = mpm_renderer_fit_material(r, lo, hi, label);
    r->bg_key = NAN; /* the view moves */
  }
  const size_t n = (size_t)fr.point_count;
  float *xyz = mpm_alloc((3 * n + 1) * sizeof *xyz), *rad = mpm_alloc((n + 1) * sizeof *rad);
  float *rgb = mpm_alloc((3 * n + 1) * sizeof *rgb), *val = mpm_alloc((n + 1) * sizeof *val);
  if (!xyz || !rad || !rgb || !val)
    st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for %zu particles", path, n);
  else
    st = draw_frame(r, &fr, path, frame, &cam, xyz, rad, rgb, val);
  mpm_free(xyz), mpm_free(rad), mpm_free(rgb), mpm_free(val);
  if (st == MPM_OK) {
    if (o->time_label) mpm_render_label(&r->img, label);
    r->drawn_frame = frame;
    r->drawn_time = fr.time;
    r->drawn_particles = n;
  }
  mpm_vtu_frame_free(&fr);
  return st;
}

mpm_status mpm_renderer_draw(mpm_renderer *r, int index) {
  if (!r) return MPM_ERR_INVALID;
  mpm_error_clear(&r->error);
  if (index < 0 || index >= r->pictures)
    return mpm_error_set(&r->error, MPM_ERR_INVALID,
                         "mpm_renderer_draw: picture %d out of range (0 to %d)", index,
                         r->pictures - 1);
  r->drawn_frame = -1; /* the image is not a whole picture until the draw succeeds */
  const int saved = mpm_renderer_threads_enter(r);
  const mpm_status st = draw(r, index);
  mpm_renderer_threads_leave(r, saved);
  return st;
}

mpm_status mpm_renderer_pixels(const mpm_renderer *r, unsigned char *rgb, size_t cap) {
  if (!r || !rgb) return MPM_ERR_INVALID;
  const size_t need = 3 * (size_t)r->img.width * (size_t)r->img.height;
  if (r->drawn_frame < 0 || cap < need) return MPM_ERR_INVALID;
  mpm_image_to_srgb8(&r->img, rgb);
  return MPM_OK;
}

mpm_status mpm_renderer_write_png(mpm_renderer *r, const char *path) {
  if (!r) return MPM_ERR_INVALID;
  mpm_error_clear(&r->error);
  if (!path || !path[0])
    return mpm_error_set(&r->error, MPM_ERR_INVALID, "mpm_renderer_write_png: no path given");
  if (r->drawn_frame < 0)
    return mpm_error_set(&r->error, MPM_ERR_INVALID,
                         "mpm_renderer_write_png: %s: no picture drawn (mpm_renderer_draw)", path);
  /* the folders on the way */
  const char *slash = strrchr(path, '/');
  if (slash && slash > path) {
    char dir[4200];
    const size_t len = (size_t)(slash - path);
    if (len >= sizeof dir)
      return mpm_error_set(&r->error, MPM_ERR_IO, "cannot write '%s': path too long", path);
    memcpy(dir, path, len);
    dir[len] = '\0';
    const mpm_status st = mpm_make_dirs(dir, &r->error);
    if (st != MPM_OK) return st;
  }
  return mpm_image_write_png(&r->img, path, &r->error);
}

mpm_status mpm_render_run(const char *run_dir, const mpm_render_options *opts,
                          mpm_render_callback callback, void *ctx, char *err, size_t errlen) {
  mpm_renderer *r;
  mpm_status st = mpm_renderer_create(run_dir, opts, &r, err, errlen);
  if (st != MPM_OK) return st;
  for (int i = 0; i < r->pictures && st == MPM_OK; ++i) {
    const double t0 = now();
    st = mpm_renderer_draw(r, i);
    char png[4400];
    if (st == MPM_OK) {
      snprintf(png, sizeof png, "%s/frame_%04d.png", r->out_dir, r->drawn_frame);
      st = mpm_renderer_write_png(r, png);
    }
    if (st == MPM_OK && callback) callback(ctx, r, png, now() - t0);
  }
  if (st != MPM_OK && err && errlen) snprintf(err, errlen, "%s", r->error.message);
  mpm_renderer_destroy(r);
  return st;
}
