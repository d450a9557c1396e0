/* render.h - pictures of a run: the frames of an output folder drawn by the software renderer
 * (no GPU, no display), to PNG files or into a buffer the caller owns (`mpm render`).
 *
 * A renderer is made for one run folder (the frame_NNNN.vtu files that `mpm run` or
 * mpm_sim_enable_output writes, and its scene.json for the domain, the colliders, the names and
 * the camera). Making it reads a sample of the frames and fixes what must not change from
 * picture to picture: the field the particles are coloured by, its colour range and the camera.
 * Each picture is then drawn on its own, in any order: the background with the colliders, the
 * ground's shadow, the particle surfaces (output.surface) and the particles as shaded spheres,
 * the multi-level grid's cells when asked, the colour bar and the frame's time.
 *
 *   mpm_render_options o = mpm_render_options_default();
 *   o.width = 640, o.height = 360;
 *   if (mpm_render_run("out", &o, NULL, NULL, err, sizeof err) != MPM_OK) ... // PNGs in out/render
 *
 * or, to show the frames in a program:
 *
 *   mpm_renderer *r;
 *   mpm_renderer_create("out", &o, &r, err, sizeof err);
 *   unsigned char *rgb = malloc(3 * 640 * 360);
 *   mpm_renderer_draw(r, 0);                        // the first picture
 *   mpm_renderer_pixels(r, rgb, 3 * 640 * 360);     // 8-bit sRGB, the PNG's pixels
 *   mpm_renderer_destroy(r);
 *
 * A picture does not depend on the OpenMP thread count. Thread safety: one renderer may be used
 * by one caller thread at a time; different renderers are independent.
 *
 * Included by mpm.h; include <mpm/mpm.h>. */
#ifndef MPM_RENDER_H
#define MPM_RENDER_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/// What the particles are coloured by: a point array of the frames.
typedef enum mpm_render_field {
  MPM_RENDER_FIELD_AUTO = -1,       /* speed, or material (body) where the velocity is uniform */
  MPM_RENDER_FIELD_VELOCITY = 0,    /* "velocity": the speed |v|, m/s */
  MPM_RENDER_FIELD_J = 1,           /* "J": det F, the volume ratio */
  MPM_RENDER_FIELD_STRESS = 2,      /* "stress": von Mises stress, Pa */
  MPM_RENDER_FIELD_PLASTIC = 3,     /* "plastic": the plastic state of the material model */
  MPM_RENDER_FIELD_MATERIAL = 4,    /* "material": the material index, in the scene's names */
  MPM_RENDER_FIELD_BODY = 5,        /* "body": the body index */
  MPM_RENDER_FIELD_TEMPERATURE = 6, /* "temperature": runs with heat (scene `heat`) */
  MPM_RENDER_FIELD_MELT = 7,        /* "melt": the melt fraction, 0 to 1 */
  MPM_RENDER_FIELD_ARRAY = 8,       /* the point array mpm_render_options.field_array names */
} mpm_render_field;

/// Colour maps.
typedef enum mpm_render_colormap {
  MPM_RENDER_COLORMAP_AUTO = -1,    /* category for labels, coolwarm for J, else viridis */
  MPM_RENDER_COLORMAP_VIRIDIS = 0,  /* "viridis": perceptually uniform, for magnitudes */
  MPM_RENDER_COLORMAP_COOLWARM = 1, /* "coolwarm": diverging, for J about 1 */
  MPM_RENDER_COLORMAP_CATEGORY = 2, /* "category": distinct colours for labels (10, repeated) */
} mpm_render_colormap;

/// How the camera is placed when the scene has no `camera`.
typedef enum mpm_render_framing {
  MPM_RENDER_FRAMING_MATERIAL = 0, /* "material": the particles' box over all pictures, steady */
  MPM_RENDER_FRAMING_FOLLOW = 1,   /* "follow": the particles' box of each picture */
  MPM_RENDER_FRAMING_DOMAIN = 2,   /* "domain": the domain, up to a little above the material */
} mpm_render_framing;

/// The names `mpm render` spells them by ("velocity", "viridis", "material", ...): static
/// storage, NULL for a value out of range (AUTO and ARRAY included). _from_name: MPM_ERR_INVALID
/// for an unknown name (*out unchanged).
MPM_API const char *mpm_render_field_name(mpm_render_field field);
MPM_API mpm_status mpm_render_field_from_name(const char *name, mpm_render_field *out);
MPM_API const char *mpm_render_colormap_name(mpm_render_colormap map);
MPM_API mpm_status mpm_render_colormap_from_name(const char *name, mpm_render_colormap *out);
MPM_API const char *mpm_render_framing_name(mpm_render_framing framing);
MPM_API mpm_status mpm_render_framing_from_name(const char *name, mpm_render_framing *out);

/// What to draw and how. Start from mpm_render_options_default(): `size` is then the size of
/// the struct the program was compiled with, and the library reads no member beyond it, so a
/// program built against an older header (fewer members, always added at the end) keeps
/// working with the defaults for the newer ones. The strings stay the caller's.
typedef struct mpm_render_options {
  size_t size;                  /* sizeof(mpm_render_options), set by the default */
  int width, height;            /* pixels, 16 to 8192 each; default 1280 x 720 */
  mpm_render_field field;       /* default MPM_RENDER_FIELD_AUTO */
  mpm_render_colormap colormap; /* default MPM_RENDER_COLORMAP_AUTO */
  /* the colour range of the field; range_lo >= range_hi (the default, 1 and 0): from the frames'
     2nd to 98th percentiles (speed and stress from 0, J centred on 1, melt 0 to 1) */
  double range_lo, range_hi;
  mpm_render_framing framing; /* when the scene has no camera; default material */
  double margin;              /* free border around the framed material, a fraction of the
                                 height, 0 to 0.4; default 0.06 */
  int every;                  /* draw every Nth frame file, >= 1; default 1 */
  int shadow;                 /* the ground's shadow under the particles; default 1 */
  int legend;                 /* the colour bar or key of labels; default 1 */
  int time_label;             /* the frame's time in the top-left corner; default 1 */
  int grid;                   /* the multi-level grid's cells over the particles (the run's
                                 grid_cells*.vtu; a run without them is refused); default 0 */
  int particles;              /* draw the particles of bodies that have surfaces too; default 0 */
  const char *scene;          /* the scene file; default NULL: RUN_DIR/scene.json when there is
                                 one, else the frames alone (no colliders, no names) */
  const char *out_dir;        /* where mpm_render_run writes; default NULL: RUN_DIR/render */
  int threads;                /* OpenMP threads for the calls (0, the default: the caller's
                                 setting), restored after each call as mpm_sim_set_threads does */
  /* any point array the run wrote (output.fields), over `field`: "pressure", "cauchy_stress";
     a vector's or tensor's magnitude, or one component as "velocity.y", "cauchy_stress.xy",
     "F.zz"; a signed range is centred on 0 with the coolwarm map. Default NULL: `field` */
  const char *field_array;
  int first_frame, last_frame; /* draw the frame files numbered first to last (inclusive);
                                  default 0 and -1 (to the last) */
  /* the camera, over the scene's and the framing's: where it is, what it looks at (m) and its
     vertical field of view (degrees, 1 to 170). Default NAN, NAN and 0: the automatic one's;
     an eye alone looks at the automatic target, a target alone is seen from the automatic
     direction and distance, a field of view alone refits the framing */
  double eye[3], target[3];
  double fov;
} mpm_render_options;

/// Fill *opts with the defaults; `size` is sizeof *opts (what mpm_render_options_default passes).
MPM_API void mpm_render_options_init(mpm_render_options *opts, size_t size);

/// The defaults, with `size` set to this header's struct.
static inline mpm_render_options mpm_render_options_default(void) {
  mpm_render_options o;
  mpm_render_options_init(&o, sizeof o);
  return o;
}

typedef struct mpm_renderer mpm_renderer;

/// Make a renderer for the run folder `run_dir`: list its frame_NNNN.vtu files, load the scene,
/// read a sample of the frames (all of them when they are small, else 12 spread over the run)
/// for the field, its range and the camera. On failure *out is NULL and err (of errlen bytes, may
/// be NULL) names the folder or file: MPM_ERR_IO for a folder that is not there or a file that
/// cannot be read, MPM_ERR_PARSE for a frame or scene that is not well formed, MPM_ERR_INVALID
/// for an option out of range (named as mpm_render_options.width etc.), a folder without
/// frames, frames without the field's array, or `grid` on a run without grid cells,
/// MPM_ERR_NOMEM.
MPM_API mpm_status mpm_renderer_create(const char *run_dir, const mpm_render_options *opts,
                                       mpm_renderer **out, char *err, size_t errlen);
/// Destroy a renderer; NULL is fine.
MPM_API void mpm_renderer_destroy(mpm_renderer *r);
/// The message of the renderer's last failure ("" when none). Owned by r.
MPM_API const char *mpm_renderer_last_error(const mpm_renderer *r);

/// What a renderer draws, and the last picture drawn. Fill it with
/// mpm_renderer_get_info(r, &info, sizeof info) (as mpm_sim_get_info: members are only added at
/// the end). The strings are owned by r.
typedef struct mpm_render_info {
  int pictures;                 /* pictures to draw: the frame files, every opts.every-th */
  int width, height;            /* pixels */
  mpm_render_field field;       /* the field chosen (never AUTO) */
  mpm_render_colormap colormap; /* the map chosen (never AUTO) */
  double range_lo, range_hi;    /* the colour range */
  int scene_camera;             /* the scene's `camera` places the view (framing unused) */
  mpm_render_framing framing;
  int every;
  double fps;  /* the scene's frames per second; 0 when drawn without a scene */
  int threads; /* the OpenMP threads the calls run on */
  const char *run_dir;
  const char *out_dir; /* where mpm_render_run writes (opts.out_dir or RUN_DIR/render) */
  /* the last picture drawn by mpm_renderer_draw (frame -1 before the first) */
  int frame;               /* its frame number, of frame_NNNN.vtu */
  double time;             /* its simulated time, s */
  size_t particles;        /* the particles of the frame */
  size_t particles_drawn;  /* drawn as spheres (those a particle surface stands for left out) */
  int surfaces;            /* particle surfaces drawn */
  const char *field_label; /* the field as named: "velocity", or the array as asked */
  /* the camera of the pictures (with framing follow, the steady framing's): pass these back
     as options to keep the view and move it */
  double eye[3], target[3], fov;
  int first_frame, last_frame; /* the frame numbers drawn, first and last */
} mpm_render_info;

MPM_API mpm_status mpm_renderer_get_info(const mpm_renderer *r, mpm_render_info *info, size_t size);

/// Draw picture `index` (0 <= index < info.pictures: the frame files in order, every
/// opts.every-th) into the renderer's image. MPM_ERR_INVALID for an index out of range; the
/// frame's own failures (a file that cannot be read or is not a frame of mpm, a missing array,
/// a bad surface file) as mpm_renderer_create reports them, with mpm_renderer_last_error.
MPM_API mpm_status mpm_renderer_draw(mpm_renderer *r, int index);
/// The last picture drawn as 8-bit sRGB, 3 bytes a pixel, rows from the top, into `rgb` of
/// `cap` >= width * height * 3 bytes (the caller's): the pixels its PNG holds. MPM_ERR_INVALID
/// before the first draw or for a buffer too small.
MPM_API mpm_status mpm_renderer_pixels(const mpm_renderer *r, unsigned char *rgb, size_t cap);
/// Write the last picture drawn as a PNG at `path`, atomically (a temporary file renamed), the
/// folders on the way made when missing. MPM_ERR_IO when it cannot be written.
MPM_API mpm_status mpm_renderer_write_png(mpm_renderer *r, const char *path);

/// After each picture of mpm_render_run: the renderer (for mpm_renderer_get_info), the PNG
/// written and the wall time of the picture, reading and writing included, s.
typedef void (*mpm_render_callback)(void *ctx, const mpm_renderer *r, const char *png_path,
                                    double seconds);

/// Draw every picture of a run folder to OUT_DIR/frame_NNNN.png (opts->out_dir, default
/// RUN_DIR/render; opts NULL: the defaults), calling `callback` (may be NULL) after each. Fails
/// as mpm_renderer_create and mpm_renderer_draw do, and MPM_ERR_IO when a PNG cannot be written;
/// the pictures written before a failure stay.
MPM_API mpm_status mpm_render_run(const char *run_dir, const mpm_render_options *opts,
                                  mpm_render_callback callback, void *ctx, char *err,
                                  size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
