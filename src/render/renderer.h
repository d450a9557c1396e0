/* renderer.h - the renderer of a run folder (mpm/render.h: mpm_renderer; `mpm render`): its
 * state (renderer.c makes it, renderer_draw.c draws a picture), the survey of the frames that
 * fixes the camera, the colour field and its range before any picture is drawn (survey.c), the
 * multi-level grid's edges (grid_edges.c) and the particle surfaces (surfaces.c). */
#ifndef MPM_RENDER_RENDERER_H
#define MPM_RENDER_RENDERER_H

#include "io/io.h"
#include "render/overlay.h"
#include "render/render.h"
#include "scene/scene.h"

#include <stddef.h>

#define MPM_RENDER_FIELDS 8   /* mpm_render_field's values from VELOCITY to MELT */
#define MPM_RENDER_KEY_MAX 10 /* categories in the key: the category map's colours repeat */

/* What the particles are coloured by: one of mpm_render_field's, or a point array of the frames
 * named by mpm_render_options.field_array (field MPM_RENDER_FIELD_ARRAY). */
typedef struct render_field_spec {
  int field;                        /* mpm_render_field; MPM_RENDER_FIELD_AUTO: not chosen yet */
  char array[MPM_VTU_NAME_MAX];     /* ARRAY: the point array read */
  int component;                    /* ARRAY: -1 the value (one component) or the magnitude, else
                                       the component (.x .. .z, .xx .. .zz) */
  char label[MPM_VTU_NAME_MAX + 4]; /* ARRAY: as asked ("pressure", "velocity.y") */
} render_field_spec;

/* Parse mpm_render_options.field_array ("NAME", "NAME.x", "NAME.xy") into spec. MPM_OK, or
 * MPM_ERR_INVALID for an empty or too long name. */
mpm_status mpm_render_field_parse(const char *text, render_field_spec *spec);

/* What a sample of the frames to draw says (survey.c). */
typedef struct render_survey {
  double lo[3], hi[3]; /* the particles' spheres' box over the sample */
  int uniform_speed;   /* in every sampled frame the particles move alike (or rest) */
  int max_material, max_body;
  double field_lo, field_hi; /* the field's 2nd and 98th percentiles over the sample */
  int field_components;      /* ARRAY: the array's components */
  int sampled;               /* frames read */
  double first_time;         /* the simulated time of the first frame drawn, s */
} render_survey;

struct mpm_renderer {
  mpm_render_options opts; /* the caller's, completed with the defaults */
  char *run_dir, *out_dir;
  int *frames; /* the frame numbers of RUN_DIR/frame_NNNN.vtu, sorted */
  int frame_count, pictures;
  mpm_scene scene; /* the domain, the colliders, the names, the camera */
  int have_scene;
  mpm_collider *colliders;
  mpm_collider_pose *poses;
  int collider_count;
  render_survey survey;
  /* the field, map and range chosen, and the legend that shows them */
  render_field_spec spec; /* spec.field == field */
  char title[MPM_VTU_NAME_MAX + 32];
  mpm_render_field field;
  mpm_colormap colormap;
  double lo, hi;
  const char *names[MPM_RENDER_KEY_MAX];
  mpm_legend legend;
  double fps;                  /* the scene's, 0 without one */
  double dom_lo[3], dom_hi[3]; /* the domain (the ground's checkers, the background's scale) */
  mpm_ground ground;           /* the domain's floor, a floor collider or a slope */
  int ground_collider;         /* the scene's collider drawn as the ground, -1: none */
  double view[3];              /* the framing's view direction: the default, or across a slope */
  int own_camera;              /* the scene's camera or the options' eye and target */
  mpm_camera cam; /* the steady camera (all but framing follow, which makes one per picture) */
  mpm_image img, bg;
  double bg_key; /* colliders' poses of the cached background; NAN: none */
  /* --grid: the multi-level grid's cell edges of frame edges_frame (-1: none read) */
  float *edges, *edge_rgb;
  size_t edge_count;
  int edges_frame;
  /* the last picture drawn */
  int drawn_frame; /* -1 before the first */
  double drawn_time;
  size_t drawn_particles, drawn_spheres;
  int drawn_surfaces;
  mpm_error error;
};

/* The field's name in the frames and the colour bar's title. */
extern const char *const MPM_RENDER_FIELD_NAMES[MPM_RENDER_FIELDS];

/* The field's value of every particle of fr (read from `path`), for the colour map;
 * MPM_ERR_INVALID naming the file when it lacks the field's array (and the arrays it has), or
 * for a component the array does not have. */
mpm_status mpm_render_field_values(const mpm_vtu_frame *fr, const char *path,
                                   const render_field_spec *spec, float *out, mpm_error *err);

/* Read a sample of the frames to draw (frames[0], frames[every], ...) of dir into sv: every one
 * of them when they are small, else 12 spread over the run. With spec->field AUTO the speed's
 * range is taken. The status with err on a bad frame or no memory. */
mpm_status mpm_render_survey(const char *dir, const render_field_spec *spec, int every,
                             const int *frames, int nf, render_survey *sv, mpm_error *err);

/* The particles' box of one frame, grown by the largest sphere's radius (0.75 cbrt(volume), as
 * drawn). */
void mpm_render_frame_box(const mpm_vtu_frame *fr, double lo[3], double hi[3]);

/* The edges of the multi-level grid's cells of frame `frame` (grid_edges.c): segments for
 * mpm_render_lines, *n = 0 when the run has none; the status with err on a bad file or no
 * memory. */
mpm_status mpm_render_grid_edges(const char *dir, int frame, float **ab, float **rgb, size_t *n,
                                 mpm_error *err);

/* The particle surfaces of frame k (surfaces.c); *drawn counts them. */
mpm_status mpm_render_draw_surfaces(const char *dir, int k, int bodies, mpm_image *img,
                                    const mpm_camera *cam, int *drawn, mpm_error *err);
/* Whether a particle of body b and material m is drawn by a surface instead. */
int mpm_render_on_surface(const mpm_scene *s, int b, int m);

/* The camera on the box [lo, hi] of the material (renderer.c): down to the ground when the
 * material is not far above it (so its shadow shows), fitted into the picture less the margin,
 * the legend's corner and the strip of the time label that reads `label`, along r->view with
 * the options' field of view. */
mpm_camera mpm_renderer_fit_material(const mpm_renderer *r, const double box_lo[3],
                                     const double box_hi[3], const char *label);
/* The time label's text: the frame's time with as many decimals as the frame rate needs. */
void mpm_renderer_time_text(char *buf, size_t cap, double t, int frame, double fps);

/* Around a public call that runs parallel work (opts.threads, as mpm_sim_threads_enter). */
int mpm_renderer_threads_enter(const mpm_renderer *r);
void mpm_renderer_threads_leave(const mpm_renderer *r, int saved);

#endif
