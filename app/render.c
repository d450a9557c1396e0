/* render.c - `mpm render OUTDIR`: draw every frame of a finished (or running) run to PNG with
 * the software renderer (src/render), and optionally assemble a movie with ffmpeg.
 *
 * Frames are read back from OUTDIR/frame_NNNN.vtu; the domain and the colliders come from
 * OUTDIR/scene.json, which `mpm run` writes (or --scene). Before drawing, a sample of the
 * frames (render_survey.c) fixes what must not change from picture to picture: the colour
 * range of the field, the field itself when none is asked for (speed, or material where the
 * velocity is uniform), and the camera, which is the scene's (key `camera`) or frames the box
 * the material moves in over the whole sequence, clear of the legend and the time label. Each
 * picture: background (cached while the colliders stand still), the ground's shadow, the
 * particle surfaces and particles, the grid, then the colour bar and the time. */
#include "cli.h"
#include "core/parallel.h"
#include "render/overlay.h"
#include "render_cmd.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

/* The colour bar's title per field: the quantity and its units (temperature: the scene's). */
static const char *const FIELD_TITLES[FIELDS] = {
    "speed (m/s)", "J (volume ratio)", "von Mises stress (Pa)", "plastic state", "material",
    "body",        "temperature",      "melt fraction"};
#define KEY_MAX 10 /* categories in the key: the category map's colours repeat after 10 */

static const char *const FRAMING_NAMES[] = {"material", "follow", "domain"};

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_int(const void *a, const void *b) {
  return *(const int *)a - *(const int *)b;
}

/* Frame numbers of dir/frame_NNNN.vtu, sorted; NULL and *n = 0 when there are none. */
static int *list_frames(const char *dir, int *n) {
  *n = 0;
  DIR *d = opendir(dir);
  if (!d) return NULL;
  int cap = 64, *f = malloc((size_t)cap * sizeof *f);
  for (struct dirent *e; f && (e = readdir(d));) {
    int k;
    char tail[8];
    if (sscanf(e->d_name, "frame_%d.%7s", &k, tail) == 2 && !strcmp(tail, "vtu") && k >= 0) {
      if (*n == cap) {
        int *g = realloc(f, (size_t)(cap *= 2) * sizeof *f);
        if (!g) break;
        f = g;
      }
      f[(*n)++] = k;
    }
  }
  closedir(d);
  if (f) qsort(f, (size_t)*n, sizeof *f, cmp_int);
  return f;
}
static int usage(void) {
  fprintf(stderr, "usage: mpm render OUTDIR [--field velocity|J|stress|plastic|material|body|\n"
                  "                                     temperature|melt]\n"
                  "                  [--size WxH] [--colormap viridis|coolwarm|category]\n"
                  "                  [--range LO:HI] [--every N] [--scene SCENE.json] [--out DIR]\n"
                  "                  [--frame material|follow|domain] [--margin F] [--no-shadow]\n"
                  "                  [--no-legend] [--no-time]\n"
                  "                  [--movie] [--grid] [--particles] [--quiet]\n"
                  "(mpm render --help says what each does)\n");
  return MPM_EXIT_USAGE;
}

static int parse_args(int argc, char **argv, render_opts *o) {
  memset(o, 0, sizeof *o);
  o->field = -1;
  o->colormap = -1;
  o->width = 1280;
  o->height = 720;
  o->every = 1;
  o->lo = 1, o->hi = 0;
  o->framing = FRAMING_MATERIAL;
  o->margin = 0.06;
  o->shadow = o->legend = o->time_label = 1;
  for (int i = 0; i < argc; ++i) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--field") && v) {
      o->field = -1;
      for (int k = 0; k < FIELDS; ++k)
        if (!strcmp(v, MPM_RENDER_FIELD_NAMES[k])) o->field = k;
      if (o->field < 0) {
        fprintf(stderr,
                "mpm render: --field expects one of velocity, J, stress, plastic, "
                "material, body, temperature, melt, got '%s'\n",
                v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--colormap") && v) {
      if ((o->colormap = mpm_colormap_of(v)) < 0) {
        fprintf(stderr, "mpm render: --colormap expects viridis, coolwarm or category, got '%s'\n",
                v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--size") && v) {
      char x;
      if (sscanf(v, "%d%c%d", &o->width, &x, &o->height) != 3 || x != 'x' || o->width < 16 ||
          o->height < 16 || o->width > 8192 || o->height > 8192) {
        fprintf(stderr, "mpm render: --size expects WxH with 16..8192 pixels each, got '%s'\n", v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--range") && v) {
      if (sscanf(v, "%lf:%lf", &o->lo, &o->hi) != 2 || !(o->lo < o->hi)) {
        fprintf(stderr, "mpm render: --range expects LO:HI with LO < HI, got '%s'\n", v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--frame") && v) {
      o->framing = -1;
      for (int k = 0; k < 3; ++k)
        if (!strcmp(v, FRAMING_NAMES[k])) o->framing = k;
      if (o->framing < 0) {
        fprintf(stderr, "mpm render: --frame expects material, follow or domain, got '%s'\n", v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--margin") && v) {
      char *end;
      o->margin = strtod(v, &end);
      if (*end || end == v || !(o->margin >= 0 && o->margin <= 0.4)) {
        fprintf(stderr,
                "mpm render: --margin expects a fraction of the height, 0 to 0.4, got '%s'\n", v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--every")) {
      if (mpm_cli_parse_int("--every", v, 1, 1000000, &o->every)) return -1;
      ++i;
    } else if (!strcmp(a, "--scene") && v) {
      o->scene = argv[++i];
    } else if (!strcmp(a, "--out") && v) {
      o->out = argv[++i];
    } else if (!strcmp(a, "--grid")) {
      o->grid = 1;
    } else if (!strcmp(a, "--particles")) {
      o->particles = 1;
    } else if (!strcmp(a, "--no-shadow")) {
      o->shadow = 0;
    } else if (!strcmp(a, "--no-legend")) {
      o->legend = 0;
    } else if (!strcmp(a, "--no-time")) {
      o->time_label = 0;
    } else if (!strcmp(a, "--movie")) {
      o->movie = 1;
    } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
      o->quiet = 1;
    } else if (a[0] == '-') {
      fprintf(stderr, "mpm render: unknown option or missing value '%s'\n", a);
      return -1;
    } else if (!o->dir) {
      o->dir = a;
    } else {
      fprintf(stderr, "mpm render: more than one folder given ('%s' and '%s')\n", o->dir, a);
      return -1;
    }
  }
  return o->dir ? 0 : -1;
}

/* The field when none was asked for: speed, unless the particles all move alike in every
 * sampled frame (a run at rest, a body in free flight), where speed would paint everything one
 * colour; then material, or body when the bodies share one material. */
static void choose_field(render_opts *o, const render_survey *sv) {
  if (o->field < 0)
    o->field = !sv->uniform_speed                          ? FIELD_VELOCITY
               : sv->max_material > 0 || sv->max_body == 0 ? FIELD_MATERIAL
                                                           : FIELD_BODY;
  if (o->colormap < 0)
    o->colormap = o->field == FIELD_MATERIAL || o->field == FIELD_BODY ? MPM_CMAP_CATEGORY
                  : o->field == FIELD_J                                ? MPM_CMAP_COOLWARM
                                                                       : MPM_CMAP_VIRIDIS;
}

/* The colour range from the survey unless --range gave one: speed and stress from 0, the melt
 * fraction 0 to 1, J centred on 1; labels map directly. */
static void choose_range(render_opts *o, const render_survey *sv) {
  if (o->lo < o->hi) return;
  if (o->field == FIELD_MATERIAL || o->field == FIELD_BODY) {
    o->lo = 0, o->hi = 1;
    return;
  }
  double lo = sv->field_lo, hi = sv->field_hi;
  if (!isfinite(lo) || !isfinite(hi)) lo = 0, hi = 1;
  if (o->field == FIELD_VELOCITY || o->field == FIELD_STRESS) lo = 0;
  if (o->field == FIELD_MELT) lo = 0, hi = 1;
  if (o->field == FIELD_J) {
    const double d = fmax(fmax(fabs(hi - 1), fabs(1 - lo)), 1e-3);
    lo = 1 - d, hi = 1 + d;
  }
  if (!(hi > lo)) hi = lo + 1;
  o->lo = lo, o->hi = hi;
}

/* The ground's height: the domain's floor, or an upward half-space collider above it. */
static double floor_height(const mpm_scene *scene, double lowest) {
  double y = scene ? scene->domain_min[1] : lowest;
  for (int k = 0; scene && k < scene->collider_count; ++k) {
    const mpm_shape_desc *s = &scene->colliders[k].shape;
    if (s->kind == MPM_SHAPE_HALFSPACE && !scene->colliders[k].inside_out && s->axis[1] > 0.99)
      y = fmax(y, s->center[1]);
  }
  return y;
}

/* The camera on the box [lo, hi] of the material: down to the ground when the material is
 * not far above it (so its shadow shows), fitted into the picture less the margin, the
 * legend's corner and the time label's strip. */
static mpm_camera fit_material(const render_opts *o, const double box_lo[3], const double box_hi[3],
                               double floor_y, const mpm_legend *legend, const char *label) {
  double lo[3], hi[3], size = 0;
  for (int d = 0; d < 3; ++d) {
    lo[d] = box_lo[d], hi[d] = box_hi[d];
    if (!(hi[d] > lo[d])) { /* no particles, or a flat sheet */
      const double c = isfinite(lo[d] + hi[d]) ? 0.5 * (lo[d] + hi[d]) : 0.5;
      lo[d] = c - 1e-3, hi[d] = c + 1e-3;
    }
    size = fmax(size, hi[d] - lo[d]);
  }
  if (lo[1] > floor_y && lo[1] - floor_y <= size) lo[1] = floor_y;
  const int w = o->width, h = o->height, m = (int)lround(o->margin * h);
  int rect[4] = {m, m, w - m, h - m};
  if (o->legend) rect[2] -= w - mpm_legend_box(legend, w, h).x0;
  if (o->time_label) rect[1] += mpm_label_box(label, w, h).y1;
  if (rect[2] - rect[0] < w / 4) rect[0] = w / 2 - w / 8, rect[2] = w / 2 + w / 8;
  if (rect[3] - rect[1] < h / 4) rect[1] = h / 2 - h / 8, rect[3] = h / 2 + h / 8;
  return mpm_camera_fit_box(lo, hi, w, h, rect);
}

static int make_movie(const render_opts *o, const char *out, double fps) {
  if (system("command -v ffmpeg >/dev/null 2>&1") != 0) {
    fprintf(stderr,
            "mpm render: ffmpeg not found, so no movie was made; install it with: "
            "apt-get install ffmpeg (the PNG frames are in %s/)\n",
            out);
    return MPM_EXIT_FAILURE;
  }
  char cmd[9000];
  snprintf(cmd, sizeof cmd,
           "ffmpeg -y -loglevel error -framerate %g -pattern_type glob -i '%s/frame_*.png' "
           "-c:v libx264 -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '%s/movie.mp4'",
           fps, out, out);
  if (system(cmd) != 0) {
    fprintf(stderr, "mpm render: ffmpeg failed making %s/movie.mp4\n", out);
    return MPM_EXIT_FAILURE;
  }
  if (!o->quiet) printf("%s/movie.mp4\n", out);
  return MPM_EXIT_OK;
}
/* The time label's text: the frame's time with as many decimals as the frame rate needs. */
static void time_text(char *buf, size_t cap, double t, int frame, double fps) {
  int decimals = fps > 0 ? (int)ceil(log10(fps)) : 3;
  decimals = decimals < 3 ? 3 : (decimals > 6 ? 6 : decimals);
  snprintf(buf, cap, "t = %.*f s, frame %d", decimals, t, frame);
}

int mpm_cmd_render(int argc, char **argv) {
  render_opts o;
  if (parse_args(argc, argv, &o)) return usage();
  struct stat sb;
  if (stat(o.dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
    fprintf(stderr, "mpm render: %s: no such folder\n", o.dir);
    return MPM_EXIT_USAGE;
  }
  int nf = 0, *frames = list_frames(o.dir, &nf);
  if (nf == 0) {
    free(frames);
    fprintf(stderr,
            "mpm render: %s: no frame_NNNN.vtu files (render needs the run's VTU output, "
            "output.vtu true)\n",
            o.dir);
    return MPM_EXIT_USAGE;
  }
  int code = MPM_EXIT_OK;
  mpm_error err;
  mpm_error_clear(&err);
  /* the scene: domain and colliders */
  char scene_path[4200], out[4200], why[1200] = "";
  if (o.scene)
    snprintf(scene_path, sizeof scene_path, "%s", o.scene);
  else
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", o.dir);
  snprintf(out, sizeof out, "%s", o.out ? o.out : "");
  if (!o.out) snprintf(out, sizeof out, "%s/render", o.dir);
  mpm_scene scene;
  memset(&scene, 0, sizeof scene);
  int have_scene = 0;
  if (o.scene || stat(scene_path, &sb) == 0) {
    if (mpm_scene_load(scene_path, &scene, &err) != MPM_OK) {
      fprintf(stderr, "mpm render: %s\n", err.message);
      free(frames);
      return MPM_EXIT_USAGE;
    }
    have_scene = 1;
  }
  mpm_collider *colliders = have_scene && scene.collider_count
                                ? calloc((size_t)scene.collider_count, sizeof *colliders)
                                : NULL;
  int nc = 0;
  for (int k = 0; have_scene && colliders && k < scene.collider_count; ++k)
    if (mpm_collider_init(&colliders[nc], &scene.colliders[k]) == 0) ++nc;
  mpm_collider_pose *poses = nc ? calloc((size_t)nc, sizeof *poses) : NULL;

  mpm_image img = {0}, bg = {0};
  mpm_vtu_frame fr = {0};
  float *xyz = NULL, *rad = NULL, *rgb = NULL, *val = NULL;
  float *edges = NULL, *edge_rgb = NULL; /* --grid: the multi-level grid's cell edges */
  size_t edge_count = 0;
  render_survey sv;
  if (mpm_render_survey(&o, frames, nf, &sv, why, sizeof why)) {
    fprintf(stderr, "mpm render: %s\n", why);
    code = MPM_EXIT_USAGE;
    goto done;
  }
  choose_field(&o, &sv);
  choose_range(&o, &sv);
  /* the legend: a colour bar, or a key of the labels with the scene's names */
  const char *names[KEY_MAX] = {NULL};
  mpm_legend legend = {(mpm_colormap)o.colormap, FIELD_TITLES[o.field], o.lo, o.hi, 0, names};
  if (o.colormap == MPM_CMAP_CATEGORY) {
    const int top = o.field == FIELD_BODY ? sv.max_body : sv.max_material;
    legend.count = top + 1 < KEY_MAX ? top + 1 : KEY_MAX;
    for (int k = 0; have_scene && k < legend.count; ++k) {
      if (o.field == FIELD_MATERIAL && k < scene.material_count) names[k] = scene.materials[k].name;
      if (o.field == FIELD_BODY && k < scene.body_count && scene.bodies[k].name[0])
        names[k] = scene.bodies[k].name;
    }
    if (o.field != FIELD_MATERIAL && o.field != FIELD_BODY) legend.count = 0; /* no names */
  }
  const double fps = have_scene ? scene.fps : 0;
  /* the domain (the ground's checkers, the scale of the background) and the ground */
  double dom_lo[3], dom_hi[3];
  for (int d = 0; d < 3; ++d) {
    dom_lo[d] = have_scene ? scene.domain_min[d] : sv.lo[d];
    dom_hi[d] = have_scene ? scene.domain_max[d] : sv.hi[d];
    if (!(dom_hi[d] > dom_lo[d])) dom_lo[d] -= 0.5, dom_hi[d] += 0.5;
  }
  const double floor_y = floor_height(have_scene ? &scene : NULL, dom_lo[1]);
  const int own_camera = have_scene && scene.camera.set;
  if (mpm_make_dirs(out, &err) != MPM_OK || mpm_image_init(&img, o.width, o.height, &err) ||
      mpm_image_init(&bg, o.width, o.height, &err)) {
    fprintf(stderr, "mpm render: %s\n", err.message);
    code = MPM_EXIT_FAILURE;
    goto done;
  }
  if (o.grid) {
    if (mpm_render_grid_edges(o.dir, frames[0], &edges, &edge_rgb, &edge_count, why, sizeof why)) {
      fprintf(stderr, "mpm render: %s\n", why);
      code = MPM_EXIT_USAGE;
      goto done;
    }
    if (!edge_count) {
      fprintf(stderr,
              "mpm render: --grid: %s has no grid_cells.vtu (a run on a multi-level grid "
              "with output.vtu writes it)\n",
              o.dir);
      code = MPM_EXIT_USAGE;
      goto done;
    }
  }
  double bg_key = NAN; /* colliders' poses of the cached background */
  int rendered = 0;
  double total = 0;
  mpm_camera cam;
  char label[160];
  for (int fi = 0; fi < nf; fi += o.every) {
    const double t0 = now();
    char path[4300];
    snprintf(path, sizeof path, "%s/frame_%04d.vtu", o.dir, frames[fi]);
    if (o.grid && fi > 0) { /* a grid rebuilt during the run has a file per frame */
      free(edges), free(edge_rgb);
      edges = edge_rgb = NULL;
      if (mpm_render_grid_edges(o.dir, frames[fi], &edges, &edge_rgb, &edge_count, why,
                                sizeof why)) {
        fprintf(stderr, "mpm render: %s\n", why);
        code = MPM_EXIT_USAGE;
        goto done;
      }
    }
    mpm_vtu_frame_free(&fr);
    if (mpm_read_vtu(path, &fr, &err) != MPM_OK) {
      fprintf(stderr, "mpm render: %s\n", err.message);
      code = MPM_EXIT_USAGE;
      goto done;
    }
    const size_t n = (size_t)fr.point_count;
    const mpm_vtu_array *pts = mpm_vtu_frame_array(&fr, "Points");
    const mpm_vtu_array *vol = mpm_vtu_frame_array(&fr, "volume");
    time_text(label, sizeof label, fr.time, frames[fi], fps);
    if (own_camera) {
      if (rendered == 0) {
        memcpy(cam.eye, scene.camera.eye, sizeof cam.eye);
        memcpy(cam.target, scene.camera.target, sizeof cam.target);
        cam.fov_deg = scene.camera.fov;
        mpm_camera_setup(&cam, o.width, o.height);
      }
    } else if (o.framing == FRAMING_DOMAIN) {
      if (rendered == 0) { /* the domain, but only up to a little above the material */
        double lo[3], hi[3];
        for (int d = 0; d < 3; ++d) lo[d] = dom_lo[d], hi[d] = dom_hi[d];
        if (have_scene) hi[1] = fmin(hi[1], sv.hi[1] + 0.3 * (hi[0] - lo[0]));
        if (!(hi[1] > lo[1])) hi[1] = lo[1] + 1;
        cam = mpm_camera_frame_box(lo, hi, o.width, o.height);
      }
    } else if (o.framing == FRAMING_FOLLOW || rendered == 0) {
      double lo[3], hi[3];
      if (o.framing == FRAMING_FOLLOW) {
        mpm_render_frame_box(&fr, lo, hi);
        bg_key = NAN; /* the view moves */
      } else {
        memcpy(lo, sv.lo, sizeof lo), memcpy(hi, sv.hi, sizeof hi);
      }
      cam = fit_material(&o, lo, hi, floor_y, &legend, label);
    }
    free(xyz), free(rad), free(rgb), free(val);
    xyz = malloc((3 * n + 1) * sizeof *xyz);
    rad = malloc((n + 1) * sizeof *rad);
    rgb = malloc((3 * n + 1) * sizeof *rgb);
    val = malloc((n + 1) * sizeof *val);
    if (!xyz || !rad || !rgb || !val) {
      fprintf(stderr, "mpm render: out of memory for %zu particles\n", n);
      code = MPM_EXIT_FAILURE;
      goto done;
    }
    if (mpm_render_field_values(&fr, o.field, val, why, sizeof why)) {
      fprintf(stderr, "mpm render: %s: %s\n", path, why);
      code = MPM_EXIT_USAGE;
      goto done;
    }
    for (size_t i = 0; i < n; ++i) {
      memcpy(xyz + 3 * i, pts->data + 3 * i, 3 * sizeof(float));
      /* spheres of 0.75 of the particle spacing cbrt(V): touching neighbours overlap a little,
         so a body reads as a surface */
      rad[i] = vol ? 0.75f * cbrtf(fmaxf(vol->data[i], 0)) : 0.005f;
      const double t = o.colormap == MPM_CMAP_CATEGORY ? val[i] : (val[i] - o.lo) / (o.hi - o.lo);
      mpm_colormap_eval((mpm_colormap)o.colormap, t, rgb + 3 * i);
    }
    /* background: recomputed only when a collider (or the view) moved */
    double key = 0;
    int na = 0; /* the colliders acting at this frame's time (a grip's `active` window) */
    for (int k = 0; k < nc; ++k) {
      const double *w = colliders[k].desc.active;
      if (!(fr.time >= w[0] && fr.time < w[1])) continue;
      poses[na] = mpm_collider_pose_at(&colliders[k], fr.time);
      for (int d = 0; d < 3; ++d) key += (d + 1.0) * (k + 1.0) * poses[na].center[d];
      for (int d = 0; d < 9; ++d) key += (d + 2.0) * (k + 3.0) * poses[na].R[d];
      key += 1e3 * (k + 1.0);
      ++na;
    }
    if (!(key == bg_key)) {
      mpm_render_background(&bg, &cam, floor_y, dom_lo, dom_hi, poses, na);
      bg_key = o.framing == FRAMING_FOLLOW && !own_camera ? NAN : key;
    }
    const size_t pix = (size_t)o.width * (size_t)o.height;
    memcpy(img.rgb, bg.rgb, 3 * pix * sizeof(float));
    memcpy(img.depth, bg.depth, pix * sizeof(float));
    /* the shadow of every particle, those a surface stands for too */
    if (o.shadow && mpm_render_ground_shadow(&img, &cam, floor_y, n, xyz, rad, 0, &err) != MPM_OK) {
      fprintf(stderr, "mpm render: %s\n", err.message);
      code = MPM_EXIT_FAILURE;
      goto done;
    }
    /* the particle surfaces first; the particles they stand for are then left out */
    int surfaces = 0;
    if (mpm_render_draw_surfaces(o.dir, frames[fi], have_scene ? scene.body_count : 64, &img, &cam,
                                 &surfaces, why, sizeof why)) {
      fprintf(stderr, "mpm render: %s\n", why);
      code = MPM_EXIT_USAGE;
      goto done;
    }
    size_t drawn = n;
    if (surfaces && have_scene && !o.particles) {
      const mpm_vtu_array *body = mpm_vtu_frame_array(&fr, "body");
      const mpm_vtu_array *mat = mpm_vtu_frame_array(&fr, "material");
      drawn = 0;
      for (size_t i = 0; i < n; ++i) {
        if (body && mat && mpm_render_on_surface(&scene, (int)body->data[i], (int)mat->data[i]))
          continue;
        memmove(xyz + 3 * drawn, xyz + 3 * i, 3 * sizeof *xyz);
        memmove(rgb + 3 * drawn, rgb + 3 * i, 3 * sizeof *rgb);
        rad[drawn++] = rad[i];
      }
    }
    if (mpm_render_particles(&img, &cam, drawn, xyz, rad, 0, rgb, &err) != MPM_OK) {
      fprintf(stderr, "mpm render: %s\n", err.message);
      code = MPM_EXIT_FAILURE;
      goto done;
    }
    if (edge_count) mpm_render_lines(&img, &cam, edge_count, edges, edge_rgb, 0.3f);
    /* no colour bar when every particle is drawn as a surface, which is not coloured by it */
    if (o.legend && (o.colormap != MPM_CMAP_CATEGORY || legend.count > 0) && (drawn || !n))
      mpm_render_legend(&img, &legend);
    if (o.time_label) mpm_render_label(&img, label);
    char png[4400];
    snprintf(png, sizeof png, "%s/frame_%04d.png", out, frames[fi]);
    if (mpm_image_write_png(&img, png, &err) != MPM_OK) {
      fprintf(stderr, "mpm render: %s\n", err.message);
      code = MPM_EXIT_FAILURE;
      goto done;
    }
    const double dt = now() - t0;
    total += dt;
    ++rendered;
    if (!o.quiet) {
      if (surfaces)
        printf("%s (%zu particles, %d surface%s, %.2f s)\n", png, drawn, surfaces,
               surfaces > 1 ? "s" : "", dt);
      else
        printf("%s (%zu particles, %.2f s)\n", png, n, dt);
    }
  }
  if (!o.quiet)
    printf("mpm render: %d frames, %.2f s per frame (%dx%d, %s %g..%g, %s, %d threads)\n", rendered,
           total / rendered, o.width, o.height, MPM_RENDER_FIELD_NAMES[o.field], o.lo, o.hi,
           own_camera ? "the scene's camera" : FRAMING_NAMES[o.framing], mpm_thread_count());
  if (o.movie) {
    const double movie_fps = (have_scene && scene.fps > 0 ? scene.fps : 24) / o.every;
    code = make_movie(&o, out, movie_fps);
  }
done:
  mpm_vtu_frame_free(&fr);
  free(xyz), free(rad), free(rgb), free(val);
  free(edges), free(edge_rgb);
  mpm_image_free(&img);
  mpm_image_free(&bg);
  for (int k = 0; k < nc; ++k) mpm_collider_free(&colliders[k]);
  free(colliders);
  free(poses);
  if (have_scene) mpm_scene_free(&scene);
  free(frames);
  return code;
}
