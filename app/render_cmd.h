/* render_cmd.h - the parts of `mpm render` (render.c): its options, the survey of a run's
 * frames that fixes the camera, the colour field and its range before any picture is drawn
 * (render_survey.c), the multi-level grid's edges (render_grid.c) and the particle surfaces
 * (render_surfaces.c). */
#ifndef MPM_APP_RENDER_CMD_H
#define MPM_APP_RENDER_CMD_H

#include "io/io.h"
#include "render/render.h"
#include "scene/scene.h"

#include <stddef.h>

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
extern const char *const MPM_RENDER_FIELD_NAMES[FIELDS];

/* How the camera is placed when the scene has no `camera`. */
enum {
  FRAMING_MATERIAL, /* the particles' box over all frames rendered: one steady view */
  FRAMING_FOLLOW,   /* the particles' box of each frame */
  FRAMING_DOMAIN,   /* the domain, up to a little above the material (the old default) */
};

typedef struct render_opts {
  const char *dir, *scene, *out;
  int field; /* -1: velocity, or material where the velocity is uniform (render_survey) */
  int colormap, width, height, every, movie, quiet, grid;
  int particles; /* --particles: draw the particles of bodies that have surfaces too */
  int framing;
  double margin; /* free border around the framed material, a fraction of the height */
  int shadow, legend, time_label;
  double lo, hi; /* colour range; lo > hi: automatic */
} render_opts;

/* What a sample of the frames to render says (render_survey.c). */
typedef struct render_survey {
  double lo[3], hi[3]; /* the particles' spheres' box over the sample */
  int uniform_speed;   /* in every sampled frame the particles move alike (or rest) */
  int max_material, max_body;
  double field_lo, field_hi; /* o->field's 2nd and 98th percentiles over the sample */
  int sampled;               /* frames read */
} render_survey;

/* The field's value of every particle of fr, for the colour map; -1 with `why` when the frames
 * lack it. */
int mpm_render_field_values(const mpm_vtu_frame *fr, int field, float *out, char *why, size_t cap);

/* Read a sample of the frames to render (frames[0], frames[every], ...) into sv: every one of
 * them when they are small, else 12 spread over the run. With o->field < 0 the speed's range
 * is taken. -1 with `why` on a bad frame or no memory. */
int mpm_render_survey(const render_opts *o, const int *frames, int nf, render_survey *sv, char *why,
                      size_t cap);

/* The particles' box of one frame, grown by the largest sphere's radius (0.75 cbrt(volume), as
 * drawn). */
void mpm_render_frame_box(const mpm_vtu_frame *fr, double lo[3], double hi[3]);

/* The edges of the multi-level grid's cells of frame `frame` (render_grid.c): segments for
 * mpm_render_lines, *n = 0 when the run has none; -1 with `why` on a bad file. */
int mpm_render_grid_edges(const char *dir, int frame, float **ab, float **rgb, size_t *n, char *why,
                          size_t cap);

/* The particle surfaces of frame k (render_surfaces.c); *drawn counts them. */
int mpm_render_draw_surfaces(const char *dir, int k, int bodies, mpm_image *img,
                             const mpm_camera *cam, int *drawn, char *why, size_t cap);
/* Whether a particle of body b and material m is drawn by a surface instead. */
int mpm_render_on_surface(const mpm_scene *s, int b, int m);

#endif
