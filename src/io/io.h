/* io.h - per-frame writers: VTU (binary, appended) + PVD index, PLY points, stats CSV.
 *
 * Every file is written atomically: to a temporary name in the same directory, then renamed,
 * so a crash never leaves a half-written frame and an existing file is never truncated. */
#ifndef MPM_IO_IO_H
#define MPM_IO_IO_H

#include "core/error.h"
#include "core/real.h"
#include "core/particles.h"

#include <stdio.h>

/* The point arrays of frame_NNNN.vtu that output.fields selects, in the order the file lists
 * them (src/io/vtu.c; docs/scene-format.md "output.fields" says what each holds). */
typedef enum mpm_output_field {
  MPM_FIELD_ID = 0,
  MPM_FIELD_VELOCITY,
  MPM_FIELD_MASS,
  MPM_FIELD_VOLUME,
  MPM_FIELD_J,
  MPM_FIELD_STRESS, /* von Mises equivalent of the Cauchy stress */
  MPM_FIELD_PLASTIC,
  MPM_FIELD_MATERIAL,
  MPM_FIELD_BODY,
  MPM_FIELD_LEVEL,
  MPM_FIELD_ENRICHMENT,
  MPM_FIELD_TEMPERATURE,
  MPM_FIELD_MELT,
  MPM_FIELD_CAUCHY_STRESS, /* the full tensor sigma = P F^T / J */
  MPM_FIELD_PRESSURE,      /* -tr(sigma) / 3 */
  MPM_FIELD_F,             /* the deformation gradient */
  MPM_FIELD_COUNT
} mpm_output_field;

/* The arrays written when output.fields is not given: those of the files before the key
 * existed (id .. enrichment), with temperature and melt when the run has heat. */
unsigned mpm_output_fields_default(int heat);

/* ---- atomic files ---- */
typedef struct mpm_atomic_file {
  FILE *fp;
  char final_path[1024];
  char temp_path[1040];
} mpm_atomic_file;

mpm_status mpm_atomic_open(mpm_atomic_file *f, const char *path, mpm_error *err);
/* Create a new temporary beside `path` (`.name.tmp.PID`, another suffix when that name is
 * taken) without following links or opening an existing file: its name goes to temp (cap
 * bytes), its descriptor is returned for writing; -1 with the message on failure. For writers
 * that need the file itself rather than a stream (the OpenVDB shim). */
int mpm_temp_create(const char *path, char *temp, size_t cap, mpm_error *err);
/* flush, fsync-free close, rename over the final path */
mpm_status mpm_atomic_commit(mpm_atomic_file *f, mpm_error *err);
/* close and remove the temporary (after a failure); the final path is untouched */
void mpm_atomic_abort(mpm_atomic_file *f);

/* Create a directory and its parents (mkdir -p). */
mpm_status mpm_make_dirs(const char *path, mpm_error *err);

/* ---- per-particle fields written with a frame ---- */
typedef struct mpm_frame_fields {
  const mpm_particles *particles;
  const mpm_real *J;         /* det F per particle */
  const mpm_real *stress;    /* von Mises stress per particle, Pa */
  double time;               /* s */
  const int32_t *enrichment; /* Zhu sec. 5.2 category per particle: 0 unenriched, 1
                                transitional, 2 enriched, -1 a material point; NULL: all -1 */
  int heat;                  /* the run has heat: write temperature and melt */
  const mpm_real *melt;      /* melt fraction per particle (material.h), NULL: 0 */
  unsigned fields;          /* the point arrays written, bit (1u << f) per mpm_output_field (below);
                               0: mpm_output_fields_default(heat) */
  const mpm_real *cauchy;   /* Cauchy stress per particle, 9 row-major values each, Pa; NULL
                               with cauchy_stress selected: zero */
  const mpm_real *pressure; /* -tr(sigma) / 3 per particle, Pa; NULL: zero */
} mpm_frame_fields;

/* VTK UnstructuredGrid, one vertex cell per particle, binary appended raw data with
 * Float32/Float64 per the real type: points; the point data f->fields selects (by default id,
 * velocity, mass, volume (current, V0 J), J, stress, plastic (the model's plastic state),
 * material, body, level, enrichment, and temperature and melt with heat). */
mpm_status mpm_write_vtu(const char *path, const mpm_frame_fields *f, mpm_error *err);

/* The index of a frame written as pieces (one a process of a run on ranks, each written by
 * mpm_write_vtu): a VTK XML PUnstructuredGrid whose PPointData lists the arrays that f->fields
 * (f->heat) selects, as the pieces have them, and whose pieces are sources[0 .. pieces) (names
 * relative to the file's folder). f's particles are not read. */
mpm_status mpm_write_pvtu(const char *path, const mpm_frame_fields *f, int pieces,
                          const char *const *sources, mpm_error *err);

/* ParaView collection listing the frame files written so far (file names relative to the
 * PVD's directory). */
mpm_status mpm_write_pvd(const char *path, int count, const double *times, const char *const *files,
                         mpm_error *err);
/* The same with `parts` files per frame: files[i * parts + k] is frame i's part k (NULL: the
 * frame has none), each written with part="k" and, when names is not NULL, name="names[k]". */
mpm_status mpm_write_pvd_parts(const char *path, int count, int parts, const double *times,
                               const char *const *names, const char *const *files, mpm_error *err);

/* Binary little-endian PLY point cloud: x y z, vx vy vz, pscale (the radius of the sphere of
 * the particle's current volume), id, material and body. */
mpm_status mpm_write_ply_points(const char *path, const mpm_frame_fields *f, mpm_error *err);

/* The per-particle arrays of frame_NNNN.vtu that `fields` selects (bits of mpm_output_field),
 * of f's particles, for the CellData of another file (vtu.c): their appended bytes (byte counts
 * included); their header lines, offsets from `base`; and their appended data. A failed write
 * (or no memory) is kept in o's err (io/vtu_stream.h). */
struct mpm_vtu_stream;
uint64_t mpm_vtu_particle_arrays_bytes(const mpm_frame_fields *f, unsigned fields);
void mpm_vtu_particle_arrays_header(struct mpm_vtu_stream *o, const mpm_frame_fields *f,
                                    unsigned fields, uint64_t base);
void mpm_vtu_particle_arrays_data(struct mpm_vtu_stream *o, const mpm_frame_fields *f,
                                  unsigned fields);

/* The particle domains of a frame as hexahedral cells over their corners (vtu_domains.c).
 * `cells` (may be NULL): the active domain particles in the set's order, whose arrays that
 * cells->fields selects beyond the file's own (id, J, material, body, enrichment) are added to
 * the CellData (output.fields). */
struct mpm_domain_set;
mpm_status mpm_write_domain_vtu(const char *path, const struct mpm_domain_set *s, double time,
                                const mpm_frame_fields *cells, mpm_error *err);

/* ---- stats CSV ---- */
typedef struct mpm_stats_row {
  int frame;
  double time;
  /* the frame's steps, s: dt is the typical one, the mean of those the frame's end did not
   * shorten (of all of them when it shortened every one); dt_min and dt_max the shortest and
   * longest (the shortest is usually a step cut short to land on the frame time). All 0 for a
   * frame without steps (frame 0). */
  double dt, dt_min, dt_max;
  long long steps;
  double kinetic, elastic;    /* J */
  double gravitational;       /* -sum m g.x, zero at the origin, J */
  double total_energy;        /* kinetic + elastic + gravitational, J */
  double momentum[3];         /* kg m/s */
  double angular_momentum[3]; /* kg m^2/s about the origin */
  double mass;                /* kg */
  double wall_seconds;        /* wall time spent on this frame */
  size_t particles;
  /* implicit integration, over the frame's steps (0 for explicit runs) */
  double cg_iterations_mean, newton_iterations_mean;
  int cg_iterations_max;
  double cg_residual_max;   /* largest final relative CG residual */
  long long cg_unconverged; /* steps whose CG stopped short of the tolerance */
  /* dynamic enrichment (Zhu Figs. 6, 10): enriched domain particles at the frame's time, in
   * percent of the active domain particles (0 without domains) */
  double enriched_percent;
} mpm_stats_row;

/* Rewrites the whole CSV (header + rows) atomically; rows are kept by the caller. */
mpm_status mpm_write_stats_csv(const char *path, int count, const mpm_stats_row *rows,
                               mpm_error *err);
/* The same with the force each of `colliders` colliders felt from the material, three columns
 * per collider after all the others (collider<c>_fx, _fy, _fz, N): row r's are
 * forces[3 (r colliders + c) + e]. forces may be NULL when colliders is 0. */
mpm_status mpm_write_stats_csv_forces(const char *path, int count, const mpm_stats_row *rows,
                                      int colliders, const double *forces, mpm_error *err);

/* ---- reading frames back (vtu_read.c) ------------------------------------------------- */

#define MPM_VTU_NAME_MAX 32
#define MPM_VTU_ARRAYS_MAX 24

/* One array of a frame, converted to float: point_count tuples of `components` values. */
typedef struct mpm_vtu_array {
  char name[MPM_VTU_NAME_MAX];
  int components;
  float *data;
} mpm_vtu_array;

typedef struct mpm_vtu_frame {
  long point_count;
  double time; /* the TIME field, s */
  int array_count;
  mpm_vtu_array arrays[MPM_VTU_ARRAYS_MAX]; /* "Points" and the point data by name */
} mpm_vtu_frame;

/* Read a frame written by mpm_write_vtu. Errors name the file and the array. */
mpm_status mpm_read_vtu(const char *path, mpm_vtu_frame *out, mpm_error *err);
/* The array called `name`, or NULL. */
const mpm_vtu_array *mpm_vtu_frame_array(const mpm_vtu_frame *f, const char *name);
void mpm_vtu_frame_free(mpm_vtu_frame *f);

#endif
