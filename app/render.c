/* render.c - `mpm render OUTDIR`: draw every frame of a finished (or running) run to PNG with
 * the library's renderer (mpm/render.h: what it fixes before drawing and what a picture holds
 * are said there and in src/render/renderer.c), print a line per picture, and optionally
 * assemble a movie with ffmpeg. On the public API alone. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include "cli.h"
#include "mpm/mpm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The command line: the run folder, the renderer's options and what the command does itself. */
typedef struct render_cli {
  const char *dir;
  mpm_render_options o;
  int movie, quiet;
} render_cli;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int usage(void) {
  fprintf(stderr, "usage: mpm render OUTDIR [--field velocity|J|stress|plastic|material|body|\n"
                  "                                     temperature|melt|ARRAY[.x|.xy]]\n"
                  "                  [--size WxH] [--colormap viridis|coolwarm|category]\n"
                  "                  [--range LO:HI] [--every N] [--frames FIRST:LAST]\n"
                  "                  [--scene SCENE.json] [--out DIR]\n"
                  "                  [--frame material|follow|domain] [--margin F]\n"
                  "                  [--eye X,Y,Z] [--target X,Y,Z] [--fov DEG]\n"
                  "                  [--no-shadow] [--no-legend] [--no-time]\n"
                  "                  [--movie] [--grid] [--particles] [--quiet]\n"
                  "(mpm render --help says what each does)\n");
  return MPM_EXIT_USAGE;
}

/* "X,Y,Z" into p: three finite numbers. */
static int parse_point(const char *opt, const char *v, double p[3]) {
  char tail;
  if (!v || sscanf(v, "%lf,%lf,%lf%c", &p[0], &p[1], &p[2], &tail) != 3 ||
      !isfinite(p[0] + p[1] + p[2])) {
    fprintf(stderr, "mpm render: %s expects X,Y,Z (metres, three numbers), got '%s'\n", opt,
            v ? v : "");
    return -1;
  }
  return 0;
}

/* "FIRST:LAST", "FIRST:", ":LAST" or "N" (that frame alone) into the options' frame range. */
static int parse_frames(const char *v, mpm_render_options *o) {
  int a = 0, b = -1, n = 0;
  char tail;
  const char *colon = v ? strchr(v, ':') : NULL;
  int ok = v && *v;
  if (ok && !colon) {
    ok = sscanf(v, "%d%c", &a, &tail) == 1;
    b = a;
  } else if (ok) {
    if (colon != v) ok = sscanf(v, "%d%n", &a, &n) == 1 && v + n == colon;
    if (ok && colon[1]) ok = sscanf(colon + 1, "%d%c", &b, &tail) == 1;
  }
  if (!ok || a < 0 || b < -1 || (b >= 0 && b < a)) {
    fprintf(stderr,
            "mpm render: --frames expects FIRST:LAST frame numbers with 0 <= FIRST <= LAST "
            "(FIRST: or :LAST for open ends, N for one frame), got '%s'\n",
            v ? v : "");
    return -1;
  }
  o->first_frame = a, o->last_frame = b;
  return 0;
}

static int parse_args(int argc, char **argv, render_cli *c) {
  memset(c, 0, sizeof *c);
  c->o = mpm_render_options_default();
  mpm_render_options *o = &c->o;
  for (int i = 0; i < argc; ++i) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--field") && v) {
      /* a field of its own, or any point array the frames hold (the renderer checks it) */
      if (mpm_render_field_from_name(v, &o->field) != MPM_OK) o->field_array = v;
      ++i;
    } else if (!strcmp(a, "--eye") || !strcmp(a, "--target")) {
      if (parse_point(a, v, a[2] == 'e' ? o->eye : o->target)) return -1;
      ++i;
    } else if (!strcmp(a, "--fov")) {
      char *end = NULL;
      o->fov = v ? strtod(v, &end) : 0;
      if (!v || *end || end == v || !(o->fov >= 1 && o->fov <= 170)) {
        fprintf(stderr,
                "mpm render: --fov expects the vertical field of view, 1 to 170 degrees, "
                "got '%s'\n",
                v ? v : "");
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--frames")) {
      if (parse_frames(v, o)) return -1;
      ++i;
    } else if (!strcmp(a, "--colormap") && v) {
      if (mpm_render_colormap_from_name(v, &o->colormap) != MPM_OK) {
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
      if (sscanf(v, "%lf:%lf", &o->range_lo, &o->range_hi) != 2 || !(o->range_lo < o->range_hi)) {
        fprintf(stderr, "mpm render: --range expects LO:HI with LO < HI, got '%s'\n", v);
        return -1;
      }
      ++i;
    } else if (!strcmp(a, "--frame") && v) {
      if (mpm_render_framing_from_name(v, &o->framing) != MPM_OK) {
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
      o->out_dir = argv[++i];
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
      c->movie = 1;
    } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q")) {
      c->quiet = 1;
    } else if (a[0] == '-') {
      static const char *const known[] = {
          "--field",     "--colormap", "--size",  "--range", "--frame",     "--margin",
          "--every",     "--scene",    "--out",   "--grid",  "--particles", "--no-shadow",
          "--no-legend", "--no-time",  "--movie", "--quiet", "--eye",       "--target",
          "--fov",       "--frames",   NULL};
      const char *near = mpm_cli_suggest(a, known);
      if (near && strcmp(near, a))
        fprintf(stderr, "mpm render: unknown option '%s': did you mean '%s'?\n", a, near);
      else
        fprintf(stderr, "mpm render: unknown option or missing value '%s'\n", a);
      return -1;
    } else if (!c->dir) {
      c->dir = a;
    } else {
      fprintf(stderr, "mpm render: more than one folder given ('%s' and '%s')\n", c->dir, a);
      return -1;
    }
  }
  return c->dir ? 0 : -1;
}

static int make_movie(int quiet, const char *out, double fps) {
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
  if (!quiet) printf("%s/movie.mp4\n", out);
  return MPM_EXIT_OK;
}

/* A failure of the renderer: input (the run's files, the options) is a usage error, exit 2;
 * no memory or no place to write is a failure, exit 1. */
static int failed(mpm_status st, const char *message, int input) {
  fprintf(stderr, "mpm render: %s\n", message);
  return input && st != MPM_ERR_NOMEM ? MPM_EXIT_USAGE : MPM_EXIT_FAILURE;
}

int mpm_cmd_render(int argc, char **argv) {
  render_cli c;
  if (parse_args(argc, argv, &c)) return usage();
  char err[4400];
  mpm_renderer *r;
  mpm_status st = mpm_renderer_create(c.dir, &c.o, &r, err, sizeof err);
  if (st != MPM_OK) return failed(st, err, 1);
  mpm_render_info info;
  mpm_renderer_get_info(r, &info, sizeof info);
  int code = MPM_EXIT_OK, rendered = 0;
  double total = 0;
  for (int i = 0; i < info.pictures; ++i) {
    const double t0 = now();
    if ((st = mpm_renderer_draw(r, i)) != MPM_OK) {
      code = failed(st, mpm_renderer_last_error(r), 1);
      break;
    }
    mpm_render_info fi;
    mpm_renderer_get_info(r, &fi, sizeof fi);
    char png[4400];
    snprintf(png, sizeof png, "%s/frame_%04d.png", info.out_dir, fi.frame);
    if ((st = mpm_renderer_write_png(r, png)) != MPM_OK) {
      code = failed(st, mpm_renderer_last_error(r), 0);
      break;
    }
    const double dt = now() - t0;
    total += dt;
    ++rendered;
    if (!c.quiet) {
      if (fi.surfaces)
        printf("%s (%zu particles, %d surface%s, %.2f s)\n", png, fi.particles_drawn, fi.surfaces,
               fi.surfaces > 1 ? "s" : "", dt);
      else
        printf("%s (%zu particles, %.2f s)\n", png, fi.particles, dt);
    }
  }
  if (code == MPM_EXIT_OK && !c.quiet) {
    printf("mpm render: %d frames, %.2f s per frame (%dx%d, %s %g..%g, %s, %d threads)\n", rendered,
           total / rendered, info.width, info.height, info.field_label, info.range_lo,
           info.range_hi,
           info.scene_camera ? "the scene's or the given camera"
                             : mpm_render_framing_name(info.framing),
           info.threads);
    printf("mpm render: camera --eye %.6g,%.6g,%.6g --target %.6g,%.6g,%.6g --fov %.6g\n",
           info.eye[0], info.eye[1], info.eye[2], info.target[0], info.target[1], info.target[2],
           info.fov);
  }
  if (code == MPM_EXIT_OK && c.movie)
    code = make_movie(c.quiet, info.out_dir, (info.fps > 0 ? info.fps : 24) / info.every);
  mpm_renderer_destroy(r);
  return code;
}
