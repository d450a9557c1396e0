/* renderer.c - the renderer of a run folder (mpm/render.h; `mpm render`): its options and their
 * names, and what it fixes before any picture is drawn (renderer_draw.c draws them).
 *
 * Frames are read back from RUN_DIR/frame_NNNN.vtu; the domain and the colliders come from
 * RUN_DIR/scene.json, which `mpm run` writes (or opts.scene). A sample of the frames (survey.c)
 * fixes what must not change from picture to picture: the colour range of the field, the field
 * itself when none is asked for (speed, or material where the velocity is uniform), and the
 * camera, which is the scene's (key `camera`) or frames the box the material moves in over the
 * whole sequence, clear of the legend and the time label. */
#define _POSIX_C_SOURCE 200809L /* opendir */

#include "core/parallel.h"
#include "core/alloc.h"
#include "render/renderer.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The colour bar's title per field: the quantity and its units (temperature: the scene's). */
static const char *const FIELD_TITLES[MPM_RENDER_FIELDS] = {
    "speed (m/s)", "J (volume ratio)", "von Mises stress (Pa)", "plastic state", "material",
    "body",        "temperature",      "melt fraction"};
static const char *const COLORMAP_NAMES[] = {"viridis", "coolwarm", "category"};
static const char *const FRAMING_NAMES[] = {"material", "follow", "domain"};

/* the public colour maps are the renderer's own */
_Static_assert((int)MPM_RENDER_COLORMAP_VIRIDIS == (int)MPM_CMAP_VIRIDIS &&
                   (int)MPM_RENDER_COLORMAP_COOLWARM == (int)MPM_CMAP_COOLWARM &&
                   (int)MPM_RENDER_COLORMAP_CATEGORY == (int)MPM_CMAP_CATEGORY,
               "mpm_render_colormap and mpm_colormap differ");

/* ---- names ------------------------------------------------------------------------------- */

static mpm_status name_lookup(const char *const *names, int count, const char *name, int *out) {
  for (int k = 0; name && k < count; ++k)
    if (!strcmp(name, names[k])) {
      *out = k;
      return MPM_OK;
    }
  return MPM_ERR_INVALID;
}

const char *mpm_render_field_name(mpm_render_field field) {
  return field >= 0 && field < MPM_RENDER_FIELDS ? MPM_RENDER_FIELD_NAMES[field] : NULL;
}

mpm_status mpm_render_field_from_name(const char *name, mpm_render_field *out) {
  int k;
  const mpm_status st = name_lookup(MPM_RENDER_FIELD_NAMES, MPM_RENDER_FIELDS, name, &k);
  if (st == MPM_OK) *out = (mpm_render_field)k;
  return st;
}

const char *mpm_render_colormap_name(mpm_render_colormap map) {
  return map >= 0 && map < 3 ? COLORMAP_NAMES[map] : NULL;
}

mpm_status mpm_render_colormap_from_name(const char *name, mpm_render_colormap *out) {
  int k;
  const mpm_status st = name_lookup(COLORMAP_NAMES, 3, name, &k);
  if (st == MPM_OK) *out = (mpm_render_colormap)k;
  return st;
}

const char *mpm_render_framing_name(mpm_render_framing framing) {
  return framing >= 0 && framing < 3 ? FRAMING_NAMES[framing] : NULL;
}

mpm_status mpm_render_framing_from_name(const char *name, mpm_render_framing *out) {
  int k;
  const mpm_status st = name_lookup(FRAMING_NAMES, 3, name, &k);
  if (st == MPM_OK) *out = (mpm_render_framing)k;
  return st;
}

/* ---- options ----------------------------------------------------------------------------- */

static mpm_render_options defaults(void) {
  mpm_render_options o;
  memset(&o, 0, sizeof o);
  o.size = sizeof o;
  o.width = 1280, o.height = 720;
  o.field = MPM_RENDER_FIELD_AUTO;
  o.colormap = MPM_RENDER_COLORMAP_AUTO;
  o.range_lo = 1, o.range_hi = 0;
  o.framing = MPM_RENDER_FRAMING_MATERIAL;
  o.margin = 0.06;
  o.every = 1;
  o.shadow = o.legend = o.time_label = 1;
  o.last_frame = -1;
  for (int d = 0; d < 3; ++d) o.eye[d] = o.target[d] = NAN;
  return o;
}

void mpm_render_options_init(mpm_render_options *opts, size_t size) {
  if (!opts || size < sizeof opts->size) return;
  mpm_render_options o = defaults();
  o.size = size < sizeof o ? size : sizeof o;
  memcpy(opts, &o, o.size);
}

/* The caller's options (of opts->size bytes) over the defaults, checked. */
static mpm_status take_options(const mpm_render_options *in, mpm_render_options *o,
                               mpm_error *err) {
  *o = defaults();
  if (in) {
    if (in->size < sizeof in->size)
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "mpm_render_options.size: %zu (start from "
                           "mpm_render_options_default())",
                           in->size);
    memcpy(o, in, in->size < sizeof *o ? in->size : sizeof *o);
    o->size = sizeof *o;
  }
  if (o->width < 16 || o->height < 16 || o->width > 8192 || o->height > 8192)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.width, height: expected 16 to 8192 pixels each, got "
                         "%dx%d",
                         o->width, o->height);
  if (o->field < MPM_RENDER_FIELD_AUTO || o->field >= MPM_RENDER_FIELDS)
    return mpm_error_set(err, MPM_ERR_INVALID, "mpm_render_options.field: %d is no field",
                         (int)o->field);
  if (o->colormap < MPM_RENDER_COLORMAP_AUTO || o->colormap > MPM_RENDER_COLORMAP_CATEGORY)
    return mpm_error_set(err, MPM_ERR_INVALID, "mpm_render_options.colormap: %d is no colour map",
                         (int)o->colormap);
  if (o->framing < MPM_RENDER_FRAMING_MATERIAL || o->framing > MPM_RENDER_FRAMING_DOMAIN)
    return mpm_error_set(err, MPM_ERR_INVALID, "mpm_render_options.framing: %d is no framing",
                         (int)o->framing);
  if (!(o->margin >= 0 && o->margin <= 0.4))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.margin: expected a fraction of the height, 0 to 0.4, "
                         "got %g",
                         o->margin);
  if (o->every < 1)
    return mpm_error_set(err, MPM_ERR_INVALID, "mpm_render_options.every: expected >= 1, got %d",
                         o->every);
  if (o->threads < 0)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.threads: expected >= 0 (0: the caller's OpenMP "
                         "setting), got %d",
                         o->threads);
  if (o->first_frame < 0 || o->last_frame < -1 ||
      (o->last_frame >= 0 && o->last_frame < o->first_frame))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.first_frame, last_frame: expected 0 <= first <= last "
                         "(last -1: to the end), got %d and %d",
                         o->first_frame, o->last_frame);
  if (!(o->fov == 0 || (o->fov >= 1 && o->fov <= 170)))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.fov: expected 1 to 170 degrees (0: automatic), got %g",
                         o->fov);
  const double *pts[2] = {o->eye, o->target};
  const char *names[2] = {"eye", "target"};
  for (int k = 0; k < 2; ++k) {
    const int given = !isnan(pts[k][0]) + !isnan(pts[k][1]) + !isnan(pts[k][2]);
    if (given != 0 && (given != 3 || !isfinite(pts[k][0] + pts[k][1] + pts[k][2])))
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "mpm_render_options.%s: expected three finite coordinates (or all "
                           "NAN: automatic), got %g, %g, %g",
                           names[k], pts[k][0], pts[k][1], pts[k][2]);
  }
  if (!isnan(o->eye[0]) && !isnan(o->target[0]) && o->eye[0] == o->target[0] &&
      o->eye[1] == o->target[1] && o->eye[2] == o->target[2])
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "mpm_render_options.eye, target: the same point (%g, %g, %g): the camera "
                         "must look from somewhere else",
                         o->eye[0], o->eye[1], o->eye[2]);
  return MPM_OK;
}

int mpm_renderer_threads_enter(const mpm_renderer *r) {
  const int saved = mpm_thread_count();
  if (r->opts.threads > 0 && r->opts.threads != saved) mpm_set_threads(r->opts.threads);
  return saved;
}

void mpm_renderer_threads_leave(const mpm_renderer *r, int saved) {
  if (r->opts.threads > 0 && mpm_thread_count() != saved) mpm_set_threads(saved);
}

/* ---- what is fixed before drawing -------------------------------------------------------- */

static int cmp_int(const void *a, const void *b) {
  return *(const int *)a - *(const int *)b;
}

/* Frame numbers of dir/frame_NNNN.vtu, sorted, into r. */
static mpm_status list_frames(mpm_renderer *r) {
  r->frame_count = 0;
  DIR *d = opendir(r->run_dir);
  if (!d) return mpm_error_set(&r->error, MPM_ERR_IO, "%s: no such folder", r->run_dir);
  int cap = 64, n = 0, *f = mpm_alloc((size_t)cap * sizeof *f);
  for (struct dirent *e; f && (e = readdir(d));) {
    int k;
    char tail[8];
    if (sscanf(e->d_name, "frame_%d.%7s", &k, tail) == 2 && !strcmp(tail, "vtu") && k >= 0 &&
        k >= r->opts.first_frame && (r->opts.last_frame < 0 || k <= r->opts.last_frame)) {
      if (n == cap) {
        int *g = mpm_realloc(f, (size_t)(cap *= 2) * sizeof *f);
        if (!g) {
          mpm_free(f);
          f = NULL;
          break;
        }
        f = g;
      }
      f[n++] = k;
    }
  }
  closedir(d);
  if (!f)
    return mpm_error_set(&r->error, MPM_ERR_NOMEM, "%s: out of memory listing the frames",
                         r->run_dir);
  qsort(f, (size_t)n, sizeof *f, cmp_int);
  r->frames = f;
  r->frame_count = n;
  if (n == 0 && (r->opts.first_frame > 0 || r->opts.last_frame >= 0))
    return mpm_error_set(&r->error, MPM_ERR_INVALID,
                         "%s: no frame_NNNN.vtu files numbered %d to %d "
                         "(mpm_render_options.first_frame, last_frame)",
                         r->run_dir, r->opts.first_frame, r->opts.last_frame);
  if (n == 0)
    return mpm_error_set(&r->error, MPM_ERR_INVALID,
                         "%s: no frame_NNNN.vtu files (render needs the run's VTU output, "
                         "output.vtu true)",
                         r->run_dir);
  return MPM_OK;
}

/* The scene (the file `scene`, or RUN_DIR/scene.json when there is one) and its colliders. */
static mpm_status load_scene(mpm_renderer *r, const char *scene) {
  char path[4200];
  if (scene)
    snprintf(path, sizeof path, "%s", scene);
  else
    snprintf(path, sizeof path, "%s/scene.json", r->run_dir);
  struct stat sb;
  if (!scene && stat(path, &sb) != 0) return MPM_OK; /* the frames alone */
  const mpm_status st = mpm_scene_load(path, &r->scene, &r->error);
  if (st != MPM_OK) return st;
  r->have_scene = 1;
  const int n = r->scene.collider_count;
  r->colliders = n ? mpm_calloc((size_t)n, sizeof *r->colliders) : NULL;
  r->poses = n ? mpm_calloc((size_t)n, sizeof *r->poses) : NULL;
  if (n && (!r->colliders || !r->poses))
    return mpm_error_set(&r->error, MPM_ERR_NOMEM, "%s: out of memory for %d colliders", path, n);
  for (int k = 0; k < n; ++k)
    if (mpm_collider_init(&r->colliders[r->collider_count], &r->scene.colliders[k]) == MPM_OK)
      ++r->collider_count;
  return MPM_OK;
}

/* The units of an output.fields array in the colour bar's title. */
static const char *array_unit(const char *name) {
  static const char *const pa[] = {"pressure", "cauchy_stress", "stress", NULL};
  for (int k = 0; pa[k]; ++k)
    if (!strcmp(name, pa[k])) return " (Pa)";
  if (!strcmp(name, "velocity")) return " (m/s)";
  if (!strcmp(name, "mass")) return " (kg)";
  if (!strcmp(name, "volume")) return " (m3)";
  return "";
}

/* The field when none was asked for: speed, unless the particles all move alike in every
 * sampled frame (a run at rest, a body in free flight), where speed would paint everything one
 * colour; then material, or body when the bodies share one material. */
static void choose_field(mpm_renderer *r) {
  const render_survey *sv = &r->survey;
  r->field = (mpm_render_field)r->spec.field;
  if (r->field < 0)
    r->field = !sv->uniform_speed                          ? MPM_RENDER_FIELD_VELOCITY
               : sv->max_material > 0 || sv->max_body == 0 ? MPM_RENDER_FIELD_MATERIAL
                                                           : MPM_RENDER_FIELD_BODY;
  const int labels = r->field == MPM_RENDER_FIELD_MATERIAL || r->field == MPM_RENDER_FIELD_BODY;
  if (r->opts.colormap >= 0)
    r->colormap = (mpm_colormap)r->opts.colormap;
  else
    r->colormap = labels                           ? MPM_CMAP_CATEGORY
                  : r->field == MPM_RENDER_FIELD_J ? MPM_CMAP_COOLWARM
                                                   : MPM_CMAP_VIRIDIS;
  r->spec.field = r->field;
  if (r->field == MPM_RENDER_FIELD_ARRAY)
    snprintf(r->title, sizeof r->title, "%s%s", r->spec.label, array_unit(r->spec.array));
  else
    snprintf(r->title, sizeof r->title, "%s", FIELD_TITLES[r->field]);
}

/* The colour range from the survey unless the options gave one: speed and stress from 0, the
 * melt fraction 0 to 1, J centred on 1; labels map directly. */
static void choose_range(mpm_renderer *r) {
  r->lo = r->opts.range_lo, r->hi = r->opts.range_hi;
  if (r->lo < r->hi) return;
  const int f = r->field;
  if (f == MPM_RENDER_FIELD_MATERIAL || f == MPM_RENDER_FIELD_BODY) {
    r->lo = 0, r->hi = 1;
    return;
  }
  double lo = r->survey.field_lo, hi = r->survey.field_hi;
  if (!isfinite(lo) || !isfinite(hi)) lo = 0, hi = 1;
  if (f == MPM_RENDER_FIELD_VELOCITY || f == MPM_RENDER_FIELD_STRESS) lo = 0;
  if (f == MPM_RENDER_FIELD_MELT) lo = 0, hi = 1;
  if (f == MPM_RENDER_FIELD_J) {
    const double d = fmax(fmax(fabs(hi - 1), fabs(1 - lo)), 1e-3);
    lo = 1 - d, hi = 1 + d;
  }
  if (f == MPM_RENDER_FIELD_ARRAY && lo < 0 && hi > 0) { /* signed: centred on 0 */
    const double d = fmax(-lo, hi);
    lo = -d, hi = d;
    if (r->opts.colormap < 0) r->colormap = MPM_CMAP_COOLWARM;
  }
  if (!(hi > lo)) hi = lo + 1;
  r->lo = lo, r->hi = hi;
}

/* The legend: a colour bar, or a key of the labels with the scene's names. */
static void make_legend(mpm_renderer *r) {
  const mpm_scene *sc = &r->scene;
  const int f = r->field;
  mpm_legend lg = {r->colormap, r->title, r->lo, r->hi, 0, r->names};
  if (r->colormap == MPM_CMAP_CATEGORY) {
    const int top = f == MPM_RENDER_FIELD_BODY ? r->survey.max_body : r->survey.max_material;
    lg.count = top + 1 < MPM_RENDER_KEY_MAX ? top + 1 : MPM_RENDER_KEY_MAX;
    for (int k = 0; r->have_scene && k < lg.count; ++k) {
      if (f == MPM_RENDER_FIELD_MATERIAL && k < sc->material_count)
        r->names[k] = sc->materials[k].name;
      if (f == MPM_RENDER_FIELD_BODY && k < sc->body_count && sc->bodies[k].name[0])
        r->names[k] = sc->bodies[k].name;
    }
    if (f != MPM_RENDER_FIELD_MATERIAL && f != MPM_RENDER_FIELD_BODY) lg.count = 0; /* no names */
  }
  r->legend = lg;
}

/* Whether collider c may be the ground: a half-space facing up, tilted 60 degrees at most, that
 * never moves and acts all the time. */
static int ground_candidate(const mpm_collider_desc *c) {
  const mpm_shape_desc *s = &c->shape;
  const mpm_motion_desc *m = &c->motion;
  const double n =
      sqrt(s->axis[0] * s->axis[0] + s->axis[1] * s->axis[1] + s->axis[2] * s->axis[2]);
  return s->kind == MPM_SHAPE_HALFSPACE && !c->inside_out && n > 0 && s->axis[1] >= 0.5 * n &&
         m->velocity[0] == 0 && m->velocity[1] == 0 && m->velocity[2] == 0 &&
         m->angular_speed == 0 && m->keyframe_count == 0 && c->active[0] <= 0 &&
         isinf(c->active[1]);
}

/* The ground: the domain's floor, or the ground candidate highest over the domain's centre
 * above it (a floor collider, or a slope). A slope is seen across: the view turns about the
 * vertical until it looks along the slope's contour lines, from the side nearer the default
 * view, so that the slope shows in profile and from above. */
static void choose_ground(mpm_renderer *r) {
  mpm_ground_level(&r->ground, r->dom_lo[1]);
  r->ground_collider = -1;
  mpm_camera_default_view(r->view);
  if (!r->have_scene) return;
  const double cx = 0.5 * (r->dom_lo[0] + r->dom_hi[0]), cz = 0.5 * (r->dom_lo[2] + r->dom_hi[2]);
  double best = r->dom_lo[1];
  for (int k = 0; k < r->collider_count; ++k) {
    const mpm_collider_desc *c = &r->colliders[k].desc;
    if (!ground_candidate(c)) continue;
    mpm_ground g;
    mpm_ground_make(&g, c->shape.center, c->shape.axis);
    const double y = mpm_ground_y_at(&g, cx, cz);
    if (y > best || (r->ground_collider < 0 && y >= best)) {
      best = y;
      r->ground = g;
      r->ground_collider = k;
    }
  }
  const double *n = r->ground.normal;
  const double tilt = sqrt(n[0] * n[0] + n[2] * n[2]);
  if (tilt < 1e-3) return; /* level (within 0.06 degrees): the default view */
  /* the contour direction, horizontal and across the downhill one (n[0], n[2]) */
  double a[2] = {-n[2] / tilt, n[0] / tilt};
  const double *v = r->view, h = sqrt(v[0] * v[0] + v[2] * v[2]);
  if (a[0] * v[0] + a[1] * v[2] < 0) a[0] = -a[0], a[1] = -a[1];
  r->view[0] = a[0] * h, r->view[2] = a[1] * h; /* the default's elevation kept */
}

mpm_camera mpm_renderer_fit_material(const mpm_renderer *r, const double box_lo[3],
                                     const double box_hi[3], const char *label) {
  double lo[3], hi[3], size = 0;
  for (int d = 0; d < 3; ++d) {
    lo[d] = box_lo[d], hi[d] = box_hi[d];
    if (!(hi[d] > lo[d])) { /* no particles, or a flat sheet */
      const double c = isfinite(lo[d] + hi[d]) ? 0.5 * (lo[d] + hi[d]) : 0.5;
      lo[d] = c - 1e-3, hi[d] = c + 1e-3;
    }
    size = fmax(size, hi[d] - lo[d]);
  }
  /* down to the ground under the box's centre when it is near (a level floor: all of it) */
  const double gy = mpm_ground_y_at(&r->ground, 0.5 * (lo[0] + hi[0]), 0.5 * (lo[2] + hi[2]));
  if (lo[1] > gy && lo[1] - gy <= size) lo[1] = gy;
  const int w = r->opts.width, h = r->opts.height, m = (int)lround(r->opts.margin * h);
  int rect[4] = {m, m, w - m, h - m};
  if (r->opts.legend) rect[2] -= w - mpm_legend_box(&r->legend, w, h).x0;
  if (r->opts.time_label) rect[1] += mpm_label_box(label, w, h).y1;
  if (rect[2] - rect[0] < w / 4) rect[0] = w / 2 - w / 8, rect[2] = w / 2 + w / 8;
  if (rect[3] - rect[1] < h / 4) rect[1] = h / 2 - h / 8, rect[3] = h / 2 + h / 8;
  return mpm_camera_fit_box(lo, hi, w, h, rect, r->view, r->opts.fov);
}

void mpm_renderer_time_text(char *buf, size_t cap, double t, int frame, double fps) {
  int decimals = fps > 0 ? (int)ceil(log10(fps)) : 3;
  decimals = decimals < 3 ? 3 : (decimals > 6 ? 6 : decimals);
  snprintf(buf, cap, "t = %.*f s, frame %d", decimals, t, frame);
}

/* The camera of every picture but framing follow's: the scene's, the domain up to a little
 * above the material, or the material's box over the sample, fitted around the first picture's
 * time label. */
static void steady_camera(mpm_renderer *r) {
  const int w = r->opts.width, h = r->opts.height;
  if (r->have_scene && r->scene.camera.set) {
    memcpy(r->cam.eye, r->scene.camera.eye, sizeof r->cam.eye);
    memcpy(r->cam.target, r->scene.camera.target, sizeof r->cam.target);
    r->cam.fov_deg = r->opts.fov > 0 ? r->opts.fov : r->scene.camera.fov;
    mpm_camera_setup(&r->cam, w, h);
  } else if (r->opts.framing == MPM_RENDER_FRAMING_DOMAIN) {
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d] = r->dom_lo[d], hi[d] = r->dom_hi[d];
    if (r->have_scene) hi[1] = fmin(hi[1], r->survey.hi[1] + 0.3 * (hi[0] - lo[0]));
    if (!(hi[1] > lo[1])) hi[1] = lo[1] + 1;
    r->cam = mpm_camera_frame_box(lo, hi, w, h);
    if (r->opts.fov > 0) r->cam.fov_deg = r->opts.fov, mpm_camera_setup(&r->cam, w, h);
  } else {
    char label[160];
    mpm_renderer_time_text(label, sizeof label, r->survey.first_time, r->frames[0], r->fps);
    r->cam = mpm_renderer_fit_material(r, r->survey.lo, r->survey.hi, label);
  }
  /* the options' eye and target over the automatic ones; either alone keeps the other, or the
     automatic direction and distance */
  const double *eye = r->opts.eye, *target = r->opts.target;
  const int has_eye = !isnan(eye[0]), has_target = !isnan(target[0]);
  if (!has_eye && !has_target) return;
  double off[3];
  for (int d = 0; d < 3; ++d) off[d] = r->cam.eye[d] - r->cam.target[d];
  for (int d = 0; d < 3; ++d) {
    if (has_target) r->cam.target[d] = target[d];
    r->cam.eye[d] = has_eye ? eye[d] : r->cam.target[d] + off[d];
  }
  mpm_camera_setup(&r->cam, w, h);
}

static mpm_status setup(mpm_renderer *r, const mpm_render_options *opts, const char *run_dir) {
  mpm_status st = take_options(opts, &r->opts, &r->error);
  if (st != MPM_OK) return st;
  mpm_set_threads(r->opts.threads); /* 0: the caller's; mpm_renderer_create restores it */
  const char *scene = r->opts.scene;
  if (!run_dir || !run_dir[0])
    return mpm_error_set(&r->error, MPM_ERR_INVALID, "mpm_renderer_create: no run folder given");
  char out[4200];
  if (r->opts.out_dir)
    snprintf(out, sizeof out, "%s", r->opts.out_dir);
  else
    snprintf(out, sizeof out, "%s/render", run_dir);
  r->run_dir = mpm_strdup(run_dir);
  r->out_dir = mpm_strdup(out);
  if (!r->run_dir || !r->out_dir) return mpm_error_set(&r->error, MPM_ERR_NOMEM, "out of memory");
  r->opts.scene = r->opts.out_dir = NULL; /* the caller's strings are not kept */
  struct stat sb;
  if (stat(run_dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
    return mpm_error_set(&r->error, MPM_ERR_IO, "%s: no such folder", run_dir);
  if ((st = list_frames(r)) != MPM_OK) return st;
  r->pictures = (r->frame_count - 1) / r->opts.every + 1;
  if ((st = load_scene(r, scene)) != MPM_OK) return st;
  memset(&r->spec, 0, sizeof r->spec);
  r->spec.field = r->opts.field;
  r->spec.component = -1;
  if (r->opts.field_array && mpm_render_field_parse(r->opts.field_array, &r->spec) != MPM_OK)
    return mpm_error_set(&r->error, MPM_ERR_INVALID,
                         "mpm_render_options.field_array: '%.80s' is no array name (NAME, "
                         "NAME.x .. NAME.z or NAME.xx .. NAME.zz, at most %d bytes)",
                         r->opts.field_array, MPM_VTU_NAME_MAX - 1);
  r->opts.field_array = NULL; /* the caller's string is not kept */
  st = mpm_render_survey(r->run_dir, &r->spec, r->opts.every, r->frames, r->frame_count, &r->survey,
                         &r->error);
  if (st != MPM_OK) return st;
  choose_field(r);
  choose_range(r);
  make_legend(r);
  r->fps = r->have_scene ? r->scene.fps : 0;
  for (int d = 0; d < 3; ++d) {
    r->dom_lo[d] = r->have_scene ? r->scene.box_min[d] : r->survey.lo[d];
    r->dom_hi[d] = r->have_scene ? r->scene.box_max[d] : r->survey.hi[d];
    if (!(r->dom_hi[d] > r->dom_lo[d])) r->dom_lo[d] -= 0.5, r->dom_hi[d] += 0.5;
  }
  choose_ground(r);
  r->own_camera =
      (r->have_scene && r->scene.camera.set) || !isnan(r->opts.eye[0]) || !isnan(r->opts.target[0]);
  if ((st = mpm_image_init(&r->img, r->opts.width, r->opts.height, &r->error)) != MPM_OK ||
      (st = mpm_image_init(&r->bg, r->opts.width, r->opts.height, &r->error)) != MPM_OK)
    return st;
  if (r->opts.grid) {
    st = mpm_render_grid_edges(r->run_dir, r->frames[0], &r->edges, &r->edge_rgb, &r->edge_count,
                               &r->error);
    if (st != MPM_OK) return st;
    r->edges_frame = r->frames[0];
    if (!r->edge_count)
      return mpm_error_set(&r->error, MPM_ERR_INVALID,
                           "mpm_render_options.grid: %s has no grid_cells.vtu (a run on a "
                           "multi-level grid with output.vtu writes it)",
                           r->run_dir);
  }
  steady_camera(r);
  return MPM_OK;
}

mpm_status mpm_renderer_create(const char *run_dir, const mpm_render_options *opts,
                               mpm_renderer **out, char *err, size_t errlen) {
  if (err && errlen) err[0] = '\0';
  if (!out) return MPM_ERR_INVALID;
  *out = NULL;
  mpm_renderer *r = mpm_calloc(1, sizeof *r);
  if (!r) {
    if (err && errlen) snprintf(err, errlen, "out of memory for a renderer");
    return MPM_ERR_NOMEM;
  }
  mpm_error_clear(&r->error);
  r->bg_key = NAN;
  r->edges_frame = r->drawn_frame = -1;
  const int saved = mpm_thread_count(); /* setup sets opts.threads' count */
  const mpm_status st = setup(r, opts, run_dir);
  if (mpm_thread_count() != saved) mpm_set_threads(saved);
  if (st != MPM_OK) {
    if (err && errlen) snprintf(err, errlen, "%s", r->error.message);
    mpm_renderer_destroy(r);
    return st;
  }
  mpm_error_clear(&r->error);
  *out = r;
  return MPM_OK;
}

void mpm_renderer_destroy(mpm_renderer *r) {
  if (!r) return;
  mpm_image_free(&r->img);
  mpm_image_free(&r->bg);
  mpm_free(r->edges);
  mpm_free(r->edge_rgb);
  for (int k = 0; k < r->collider_count; ++k) mpm_collider_free(&r->colliders[k]);
  mpm_free(r->colliders);
  mpm_free(r->poses);
  if (r->have_scene) mpm_scene_free(&r->scene);
  mpm_free(r->frames);
  mpm_free(r->run_dir);
  mpm_free(r->out_dir);
  mpm_free(r);
}

const char *mpm_renderer_last_error(const mpm_renderer *r) {
  return r ? r->error.message : "";
}

mpm_status mpm_renderer_get_info(const mpm_renderer *r, mpm_render_info *info, size_t size) {
  if (!r || !info) return MPM_ERR_INVALID;
  mpm_render_info in;
  memset(&in, 0, sizeof in);
  in.pictures = r->pictures;
  in.width = r->opts.width, in.height = r->opts.height;
  in.field = r->field;
  in.colormap = (mpm_render_colormap)r->colormap;
  in.range_lo = r->lo, in.range_hi = r->hi;
  in.scene_camera = r->own_camera;
  in.framing = r->opts.framing;
  in.every = r->opts.every;
  in.fps = r->fps;
  in.threads = r->opts.threads > 0 ? r->opts.threads : mpm_thread_count();
  in.run_dir = r->run_dir;
  in.out_dir = r->out_dir;
  in.frame = r->drawn_frame;
  in.time = r->drawn_time;
  in.particles = r->drawn_particles;
  in.particles_drawn = r->drawn_spheres;
  in.surfaces = r->drawn_surfaces;
  in.field_label =
      r->field == MPM_RENDER_FIELD_ARRAY ? r->spec.label : MPM_RENDER_FIELD_NAMES[r->field];
  const mpm_camera *cam = &r->cam;
  for (int d = 0; d < 3; ++d) in.eye[d] = cam->eye[d], in.target[d] = cam->target[d];
  in.fov = cam->fov_deg;
  in.first_frame = r->frames[0];
  in.last_frame = r->frames[(r->pictures - 1) * r->opts.every];
  memcpy(info, &in, size < sizeof in ? size : sizeof in);
  return MPM_OK;
}
