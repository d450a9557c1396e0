/* render.c - `mpm render OUTDIR`: draw every frame of a finished (or running) run to PNG with
 * the software renderer (src/render), and optionally assemble a movie with ffmpeg.
 *
 * Frames are read back from OUTDIR/frame_NNNN.vtu; the domain and the colliders come from
 * OUTDIR/scene.json, which `mpm run` writes (or --scene). The colour range of a field is fixed
 * for the whole sequence (from a sample of up to 12 frames, 2nd to 98th percentile) so that
 * colours mean the same in every picture. The camera is the scene's (key `camera`) or frames
 * the domain. */
#include "cli.h"
#include "core/parallel.h"
#include "io/io.h"
#include "render/render.h"
#include "scene/mesh.h"
#include "scene/scene.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

enum {
  FIELD_VELOCITY,
  FIELD_J,
  FIELD_STRESS,
  FIELD_PLASTIC,
  FIELD_MATERIAL,
  FIELD_BODY,
  FIELD_TEMPERATURE, /* runs with heat (scene `heat`) */
  FIELD_MELT,
  FIELDS
};
static const char *const FIELD_NAMES[FIELDS] = {"velocity", "J",    "stress",      "plastic",
                                                "material", "body", "temperature", "melt"};

typedef struct render_opts {
  const char *dir, *scene, *out;
  int field, colormap, width, height, every, movie, quiet, grid;
  int particles; /* --particles: draw the particles of bodies that have surfaces too */
  double lo, hi; /* colour range; lo > hi: automatic */
} render_opts;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_int(const void *a, const void *b) {
  return *(const int *)a - *(const int *)b;
}
static int cmp_float(const void *a, const void *b) {
  const float x = *(const float *)a, y = *(const float *)b;
  return x < y ? -1 : x > y;
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

/* The field's value of every particle, for the colour map. */
static int field_values(const mpm_vtu_frame *fr, int field, float *out, char *why, size_t cap) {
  const char *name = field == FIELD_VELOCITY ? "velocity" : FIELD_NAMES[field];
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

static int usage(void) {
  fprintf(stderr, "usage: mpm render OUTDIR [--field velocity|J|stress|plastic|material|body|\n"
                  "                                     temperature|melt]\n"
                  "                  [--size WxH] [--colormap viridis|coolwarm|category]\n"
                  "                  [--range LO:HI] [--every N] [--scene SCENE.json] [--out DIR]\n"
                  "                  [--movie] [--grid] [--particles] [--quiet]\n");
  return MPM_EXIT_USAGE;
}

static int parse_args(int argc, char **argv, render_opts *o) {
  memset(o, 0, sizeof *o);
  o->field = FIELD_VELOCITY;
  o->colormap = -1;
  o->width = 1280;
  o->height = 720;
  o->every = 1;
  o->lo = 1, o->hi = 0;
  for (int i = 0; i < argc; ++i) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--field") && v) {
      o->field = -1;
      for (int k = 0; k < FIELDS; ++k)
        if (!strcmp(v, FIELD_NAMES[k])) o->field = k;
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
  if (!o->dir) return -1;
  if (o->colormap < 0)
    o->colormap = o->field == FIELD_MATERIAL || o->field == FIELD_BODY ? MPM_CMAP_CATEGORY
                  : o->field == FIELD_J                                ? MPM_CMAP_COOLWARM
                                                                       : MPM_CMAP_VIRIDIS;
  return 0;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* The edges of the multi-level grid's fine leaves (OUTDIR/grid_cells_NNNN.vtu of a frame when
 * the run rebuilt its grid, else OUTDIR/grid_cells.vtu: 8 corners per voxel)
 * on the surfaces of the levels' regions, each once, coloured by level (the edge length):
 * segments for mpm_render_lines. 0 with
 * *n = 0 when the run has no such file; -1 with `why` on a bad file. */
static int grid_edges(const char *dir, int frame, float **ab, float **rgb, size_t *n, char *why,
                      size_t cap) {
  *n = 0;
  char path[4200];
  snprintf(path, sizeof path, "%s/grid_cells_%04d.vtu", dir, frame);
  FILE *probe = fopen(path, "rb");
  if (!probe) {
    snprintf(path, sizeof path, "%s/grid_cells.vtu", dir);
    probe = fopen(path, "rb");
  }
  if (!probe) return 0;
  fclose(probe);
  mpm_vtu_frame fr;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_read_vtu(path, &fr, &err) != MPM_OK) {
    snprintf(why, cap, "%s", err.message);
    return -1;
  }
  const mpm_vtu_array *pts = mpm_vtu_frame_array(&fr, "Points");
  const size_t cells = pts ? (size_t)fr.point_count / 8 : 0;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, h = INFINITY;
  for (size_t c = 0; c < cells; ++c) {
    const float *p = pts->data + 24 * c;
    h = fmin(h, (double)(p[3] - p[0])); /* corner 1 is corner 0 + x */
    for (int d = 0; d < 3; ++d) lo[d] = fmin(lo[d], (double)p[d]);
  }
  /* an edge: its start on the finest lattice (18 bits per axis), axis and length exponent */
  uint64_t *key = malloc((12 * cells + 1) * sizeof *key);
  if (!key) {
    mpm_vtu_frame_free(&fr);
    snprintf(why, cap, "out of memory for the grid's edges");
    return -1;
  }
  size_t m = 0;
  static const int from[12] = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};
  static const int axis[12] = {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2};
  for (size_t c = 0; c < cells; ++c) {
    const float *p = pts->data + 24 * c;
    const double size = (double)(p[3] - p[0]);
    const int e = (int)lround(log2(size / h));
    for (int k = 0; k < 12; ++k) {
      uint64_t q = 0;
      for (int d = 0; d < 3; ++d)
        q = q << 18 | ((uint64_t)lround(((double)p[3 * from[k] + d] - lo[d]) / h) & 0x3ffff);
      key[m++] = (q << 2 | (uint64_t)axis[k]) << 4 | (uint64_t)(e & 15);
    }
  }
  qsort(key, m, sizeof *key, cmp_u64);
  /* each edge once, and only those on the surface of a level's region: an edge inside one is
   * shared by 4 cells of its size */
  size_t u = 0;
  for (size_t k = 0; k < m;) {
    size_t j = k;
    while (j < m && key[j] == key[k]) ++j;
    if (j - k < 4) key[u++] = key[k];
    k = j;
  }
  *ab = malloc((6 * u + 1) * sizeof **ab);
  *rgb = malloc((3 * u + 1) * sizeof **rgb);
  if (!*ab || !*rgb) {
    free(key);
    mpm_vtu_frame_free(&fr);
    snprintf(why, cap, "out of memory for the grid's edges");
    return -1;
  }
  for (size_t k = 0; k < u; ++k) {
    const int e = (int)(key[k] & 15), ax = (int)(key[k] >> 4 & 3);
    const uint64_t q = key[k] >> 6;
    const double len = h * (double)(1 << e);
    for (int d = 0; d < 3; ++d) {
      const double x = lo[d] + h * (double)((q >> (18 * (2 - d))) & 0x3ffff);
      (*ab)[6 * k + d] = (float)x;
      (*ab)[6 * k + 3 + d] = (float)(x + (d == ax ? len : 0));
    }
    /* the finest level light, coarser ones darker */
    mpm_colormap_eval(MPM_CMAP_VIRIDIS, 1 - 0.3 * e, *rgb + 3 * k);
  }
  *n = u;
  free(key);
  mpm_vtu_frame_free(&fr);
  return 0;
}

/* The particle surfaces of frame k (output.surface): surface_NNNN.ply, or surface_bB_NNNN.ply
 * per body B < bodies. Each one found is drawn; *drawn counts them. -1 with `why` on a bad
 * file or no memory. */
static int draw_surfaces(const char *dir, int k, int bodies, mpm_image *img, const mpm_camera *cam,
                         int *drawn, char *why, size_t cap) {
  *drawn = 0;
  for (int b = -1; b < bodies; ++b) {
    char path[4300];
    if (b < 0)
      snprintf(path, sizeof path, "%s/surface_%04d.ply", dir, k);
    else
      snprintf(path, sizeof path, "%s/surface_b%d_%04d.ply", dir, b, k);
    struct stat sb;
    if (stat(path, &sb) != 0) continue;
    mpm_mesh m;
    mpm_error err;
    mpm_error_clear(&err);
    if (mpm_mesh_load(path, &m, &err) != MPM_OK) {
      if (strstr(err.message, "no faces")) continue; /* an empty surface */
      snprintf(why, cap, "%s", err.message);
      return -1;
    }
    float *xyz = malloc((3 * (size_t)m.vertex_count + 1) * sizeof *xyz);
    uint32_t *tri = malloc((3 * (size_t)m.triangle_count + 1) * sizeof *tri);
    int st = 0;
    if (!xyz || !tri) {
      snprintf(why, cap, "out of memory for the surface of frame %d", k);
      st = -1;
    } else {
      for (size_t i = 0; i < 3 * (size_t)m.vertex_count; ++i) xyz[i] = (float)m.vertices[i];
      for (size_t i = 0; i < 3 * (size_t)m.triangle_count; ++i) tri[i] = (uint32_t)m.triangles[i];
      float rgb[3] = {0.80f, 0.70f, 0.52f}; /* one surface: sand; one per body: its colour */
      if (b >= 0) mpm_colormap_eval(MPM_CMAP_CATEGORY, b, rgb);
      if (mpm_render_triangles(img, cam, (size_t)m.vertex_count, xyz, (size_t)m.triangle_count, tri,
                               rgb, &err) != MPM_OK) {
        snprintf(why, cap, "%s", err.message);
        st = -1;
      }
      ++*drawn;
    }
    free(xyz);
    free(tri);
    mpm_mesh_free(&m);
    if (st) return st;
  }
  return 0;
}

/* Whether a particle of body b and material m is drawn by a surface (output.surface of the
 * scene), so that its splat is left out. */
static int on_surface(const mpm_scene *s, int b, int m) {
  const mpm_surface_desc *d = &s->output.surface;
  if (!d->enabled || b < 0 || b >= s->body_count) return 0;
  if (d->material_count) {
    for (int k = 0; k < d->material_count; ++k)
      if (d->materials[k] == m) return 1;
    return 0;
  }
  if (d->body_count) {
    for (int k = 0; k < d->body_count; ++k)
      if (d->bodies[k] == b) return 1;
    return 0;
  }
  /* all bodies but those that keep their embedded mesh (a mesh body with domains) */
  return !(s->bodies[b].domains && s->bodies[b].shape.kind == MPM_SHAPE_MESH);
}

/* Automatic colour range from a sample of frames (percentiles 2 and 98; J centred on 1). */
static int auto_range(render_opts *o, const int *frames, int nf, char *why, size_t cap) {
  if (o->lo < o->hi) return 0;
  if (o->field == FIELD_MATERIAL || o->field == FIELD_BODY) {
    o->lo = 0, o->hi = 1; /* labels map directly */
    return 0;
  }
  double lo = INFINITY, hi = -INFINITY;
  const int samples = nf < 12 ? nf : 12;
  for (int s = 0; s < samples; ++s) {
    const int k = frames[(long)s * (nf - 1) / (samples > 1 ? samples - 1 : 1)];
    char path[4200];
    snprintf(path, sizeof path, "%s/frame_%04d.vtu", o->dir, k);
    mpm_vtu_frame fr;
    mpm_error err;
    mpm_error_clear(&err);
    if (mpm_read_vtu(path, &fr, &err) != MPM_OK) {
      snprintf(why, cap, "%s", err.message);
      return -1;
    }
    float *v = malloc(((size_t)fr.point_count + 1) * sizeof *v);
    if (!v || field_values(&fr, o->field, v, why, cap)) {
      free(v);
      mpm_vtu_frame_free(&fr);
      if (!v) snprintf(why, cap, "out of memory");
      return -1;
    }
    qsort(v, (size_t)fr.point_count, sizeof *v, cmp_float);
    if (fr.point_count > 0) {
      lo = fmin(lo, v[(size_t)(0.02 * (double)(fr.point_count - 1))]);
      hi = fmax(hi, v[(size_t)(0.98 * (double)(fr.point_count - 1))]);
    }
    free(v);
    mpm_vtu_frame_free(&fr);
  }
  if (!isfinite(lo)) lo = 0, hi = 1;
  if (o->field == FIELD_VELOCITY || o->field == FIELD_STRESS) lo = 0;
  if (o->field == FIELD_MELT) lo = 0, hi = 1;
  if (o->field == FIELD_J) {
    const double d = fmax(fmax(fabs(hi - 1), fabs(1 - lo)), 1e-3);
    lo = 1 - d, hi = 1 + d;
  }
  if (!(hi > lo)) hi = lo + 1;
  o->lo = lo, o->hi = hi;
  return 0;
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
  double lo[3], hi[3], floor_y;
  if (auto_range(&o, frames, nf, why, sizeof why)) {
    fprintf(stderr, "mpm render: %s\n", why);
    code = MPM_EXIT_USAGE;
    goto done;
  }
  if (mpm_make_dirs(out, &err) != MPM_OK || mpm_image_init(&img, o.width, o.height, &err) ||
      mpm_image_init(&bg, o.width, o.height, &err)) {
    fprintf(stderr, "mpm render: %s\n", err.message);
    code = MPM_EXIT_FAILURE;
    goto done;
  }
  if (o.grid) {
    if (grid_edges(o.dir, frames[0], &edges, &edge_rgb, &edge_count, why, sizeof why)) {
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
  for (int fi = 0; fi < nf; fi += o.every) {
    const double t0 = now();
    char path[4300];
    snprintf(path, sizeof path, "%s/frame_%04d.vtu", o.dir, frames[fi]);
    if (o.grid && fi > 0) { /* a grid rebuilt during the run has a file per frame */
      free(edges), free(edge_rgb);
      edges = edge_rgb = NULL;
      if (grid_edges(o.dir, frames[fi], &edges, &edge_rgb, &edge_count, why, sizeof why)) {
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
    if (rendered == 0) { /* the frame of the camera: the domain, or the particles' box */
      for (int d = 0; d < 3; ++d) {
        lo[d] = INFINITY, hi[d] = -INFINITY;
        for (size_t i = 0; i < n; ++i) {
          lo[d] = fmin(lo[d], pts->data[3 * i + d]);
          hi[d] = fmax(hi[d], pts->data[3 * i + d]);
        }
        if (have_scene) { /* the domain, but only up to a little above the material */
          const double top = hi[1];
          lo[d] = scene.domain_min[d], hi[d] = scene.domain_max[d];
          if (d == 1) hi[1] = fmin(hi[1], top + 0.3 * (hi[0] - lo[0]));
        }
        if (!(hi[d] > lo[d])) lo[d] -= 0.5, hi[d] += 0.5;
      }
      floor_y = lo[1];
      for (int k = 0; have_scene && k < scene.collider_count; ++k) {
        const mpm_shape_desc *s = &scene.colliders[k].shape;
        if (s->kind == MPM_SHAPE_HALFSPACE && !scene.colliders[k].inside_out && s->axis[1] > 0.99)
          floor_y = fmax(floor_y, s->center[1]);
      }
      cam = mpm_camera_frame_box(lo, hi, o.width, o.height);
      if (have_scene && scene.camera.set) { /* the scene's own view */
        memcpy(cam.eye, scene.camera.eye, sizeof cam.eye);
        memcpy(cam.target, scene.camera.target, sizeof cam.target);
        cam.fov_deg = scene.camera.fov;
        mpm_camera_setup(&cam, o.width, o.height);
      }
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
    if (field_values(&fr, o.field, val, why, sizeof why)) {
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
    /* background: recomputed only when a collider moved */
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
      mpm_render_background(&bg, &cam, floor_y, lo, hi, poses, na);
      bg_key = key;
    }
    const size_t pix = (size_t)o.width * (size_t)o.height;
    memcpy(img.rgb, bg.rgb, 3 * pix * sizeof(float));
    memcpy(img.depth, bg.depth, pix * sizeof(float));
    /* the particle surfaces first; the particles they stand for are then left out */
    int surfaces = 0;
    if (draw_surfaces(o.dir, frames[fi], have_scene ? scene.body_count : 64, &img, &cam, &surfaces,
                      why, sizeof why)) {
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
        if (body && mat && on_surface(&scene, (int)body->data[i], (int)mat->data[i])) continue;
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
    printf("mpm render: %d frames, %.2f s per frame (%dx%d, %s %g..%g, %d threads)\n", rendered,
           total / rendered, o.width, o.height, FIELD_NAMES[o.field], o.lo, o.hi,
           mpm_thread_count());
  if (o.movie) {
    const double fps = (have_scene && scene.fps > 0 ? scene.fps : 24) / o.every;
    code = make_movie(&o, out, fps);
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
