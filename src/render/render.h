/* render.h - a software renderer for particle frames: no GPU, no display.
 *
 * A frame is drawn in three passes into a float RGB image with a depth buffer:
 *   1. the background: a vertical sky gradient, a checkered ground plane (the domain floor, a
 *      floor collider or a slope: mpm_ground),
 *      and the scene's colliders found by sphere tracing their level sets (collide/collider.h);
 *      containers (inside-out colliders) show their far wall, so what they hold stays visible;
 *   1b. the ground's shadow under the particles (shadow.c), on the pixels that show the ground;
 *   2. the particles as shaded sphere impostors (a disc per particle whose depth and normal
 *      are those of the sphere), depth-tested against each other and the background;
 *   3. tone mapping to 8-bit sRGB and a PNG written atomically with libpng (render_png.c).
 * Between 2 and 3 the particle surfaces may be drawn as shaded triangles (mpm_render_triangles)
 * and an overlay of line segments (mpm_render_lines: the multi-level grid's cells); before 3
 * the colour bar and labels of overlay.h.
 * Particles are spread over threads, each with its own colour and depth buffer, merged by
 * depth at the end, so the image does not depend on the thread count. */
#ifndef MPM_RENDER_RENDER_H
#define MPM_RENDER_RENDER_H

#include "collide/collider.h"
#include "core/error.h"

#include <stddef.h>
#include <stdint.h>

typedef struct mpm_image {
  int width, height;
  float *rgb;   /* width * height * 3, linear */
  float *depth; /* distance along the view axis; INFINITY where nothing is */
} mpm_image;

mpm_status mpm_image_init(mpm_image *img, int width, int height, mpm_error *err);
void mpm_image_free(mpm_image *img);

/* img as 8-bit sRGB, 3 bytes a pixel, rows from the top, into rgb (width * height * 3 bytes):
 * the pixels mpm_image_write_png writes. */
void mpm_image_to_srgb8(const mpm_image *img, unsigned char *rgb);

/* Write img as an 8-bit sRGB PNG, atomically (a temporary file renamed). */
mpm_status mpm_image_write_png(const mpm_image *img, const char *path, mpm_error *err);

/* Pinhole camera looking from eye to target with +y up (unless the view is vertical). */
typedef struct mpm_camera {
  double eye[3], target[3];
  double fov_deg; /* vertical field of view */
  /* derived by mpm_camera_setup */
  double right[3], up[3], forward[3];
  double focal; /* pixels per unit at distance 1 */
  int width, height;
} mpm_camera;

void mpm_camera_setup(mpm_camera *cam, int width, int height);

/* A camera that frames the box [lo, hi] from the front-right and above. */
mpm_camera mpm_camera_frame_box(const double lo[3], const double hi[3], int width, int height);

/* The view direction (from the target towards the eye) of mpm_camera_frame_box and
 * mpm_camera_fit_box: front right, above. */
void mpm_camera_default_view(double view[3]);

/* A camera looking along -view (NULL: the default view) with a vertical field of view of
 * fov_deg (0: 35 degrees) that is as near the box [lo, hi] as lets all of its corners project
 * into the pixel rectangle rect = {x0, y0, x1, y1}, centred in it. */
mpm_camera mpm_camera_fit_box(const double lo[3], const double hi[3], int width, int height,
                              const int rect[4], const double view[3], double fov_deg);

/* The ground: the plane the material stands on (ground.c). A level floor at height y, or any
 * plane whose normal points up (a slope: a tilted half-space collider). */
typedef struct mpm_ground {
  double point[3], normal[3]; /* a point of the plane; its unit normal, upwards */
  double e1[3], e2[3];        /* unit tangents: x and z on a level floor */
  int level;                  /* the normal is +y exactly */
} mpm_ground;

void mpm_ground_make(mpm_ground *g, const double point[3], const double normal[3]);
void mpm_ground_level(mpm_ground *g, double y);
/* Signed height of x over the plane, along its normal. */
double mpm_ground_height(const mpm_ground *g, const double x[3]);
/* The plane's height at (x, z) (normal[1] > 0). */
double mpm_ground_y_at(const mpm_ground *g, double x, double z);
/* Distance along the unit ray eye + t dir to the plane seen from above, or INFINITY. */
double mpm_ground_hit(const mpm_ground *g, const double eye[3], const double dir[3]);
/* x's coordinates along e1 and e2 (x and z on a level floor), and back to the plane's point. */
void mpm_ground_coords(const mpm_ground *g, const double x[3], double *u, double *w);
void mpm_ground_point(const mpm_ground *g, double u, double w, double x[3]);

/* Colour maps: t in [0, 1] (clamped) to linear RGB. */
typedef enum mpm_colormap {
  MPM_CMAP_VIRIDIS = 0, /* perceptually uniform, for magnitudes */
  MPM_CMAP_COOLWARM,    /* diverging, for signed quantities such as J - 1 */
  MPM_CMAP_CATEGORY,    /* distinct colours for integer labels (material, body) */
} mpm_colormap;

void mpm_colormap_eval(mpm_colormap map, double t, float rgb[3]);
/* The map of a name (viridis, coolwarm, category); -1 for an unknown one. */
int mpm_colormap_of(const char *name);

/* Pass 1. ground: the plane drawn checkered (the checkers lighter over the domain's x and z
 * span); colliders may be NULL; the collider ground_collider (-1: none) is the ground itself and
 * is not traced. */
void mpm_render_background(mpm_image *img, const mpm_camera *cam, const mpm_ground *ground,
                           const double domain_lo[3], const double domain_hi[3],
                           const mpm_collider_pose *colliders, int collider_count,
                           int ground_collider);

/* Pass 2. Particle i at xyz[3i..3i+2] with radius radius[i] (or `radius_all` when radius is
 * NULL) and linear colour rgb[3i..3i+2]. */
mpm_status mpm_render_particles(mpm_image *img, const mpm_camera *cam, size_t n, const float *xyz,
                                const float *radius, float radius_all, const float *rgb,
                                mpm_error *err);

/* Pass 2b, an overlay: the segments from ab[6 s] to ab[6 s + 3] (s < n) blended with alpha over
 * the image in colour rgb[3 s..], hidden where something nearer is drawn (the depth buffer is
 * read, not written). */
void mpm_render_lines(mpm_image *img, const mpm_camera *cam, size_t n, const float *ab,
                      const float *rgb, float alpha);

/* Pass 2c: a triangle mesh (vertices xyz[3v..], triangles tri[3t..] of vertex indices) shaded
 * in linear colour rgb with smooth vertex normals, depth-tested against and written into the
 * image (triangles.c). */
mpm_status mpm_render_triangles(mpm_image *img, const mpm_camera *cam, size_t vertex_count,
                                const float *xyz, size_t triangle_count, const uint32_t *tri,
                                const float rgb[3], mpm_error *err);

/* Pass 1b, the ground's shadow: the n particles at xyz (radius[i], or radius_all when radius is
 * NULL) darken the ground plane below them (along its normal), sharply where they touch it and
 * more softly the higher they are (shadow.c). Only pixels that show the ground are changed. */
mpm_status mpm_render_ground_shadow(mpm_image *img, const mpm_camera *cam, const mpm_ground *ground,
                                    size_t n, const float *xyz, const float *radius,
                                    float radius_all, mpm_error *err);

#endif
