/* mpm.h - public API of the mpm Material Point Method engine.
 *
 * A simulation is an opaque handle created from a JSON scene (see docs/scene-format.md) and
 * advanced frame by frame; results are read through bulk read-only views or written by the
 * frame writers. Functions that can fail return an mpm_status; the message that names the
 * file, key path, step or particle is available from mpm_sim_last_error or is written into
 * the caller's buffer. No function of the library exits the process.
 *
 * Thread safety: one mpm_sim may be used by one caller thread at a time; the engine itself
 * runs its transfers on OpenMP threads. */
#ifndef MPM_MPM_H
#define MPM_MPM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mpm_status {
  MPM_OK = 0,
  MPM_ERR_IO = 1,          /* a file could not be read or written */
  MPM_ERR_PARSE = 2,       /* a file is not well formed (JSON, OBJ, PLY) */
  MPM_ERR_INVALID = 3,     /* a value is out of range or a key is unknown */
  MPM_ERR_NOMEM = 4,       /* an allocation failed */
  MPM_ERR_UNSTABLE = 5,    /* the simulation produced a non-finite or runaway value */
  MPM_ERR_INTERRUPTED = 6, /* the caller's interrupt flag was raised (between two steps) */
} mpm_status;

/// Human-readable name of a status ("ok", "parse error", ...). Static storage.
const char *mpm_status_string(mpm_status s);

/// Version string of the library, "MAJOR.MINOR.PATCH". Static storage.
const char *mpm_version(void);

/// Name of the real type this library was built with: "float" or "double".
const char *mpm_real_type(void);

typedef struct mpm_sim mpm_sim;

/// Load and validate a JSON scene and build the simulation (particles sampled, colliders set).
/// On failure *out is NULL and err (of errlen bytes, may be NULL) holds the message.
mpm_status mpm_sim_create_from_file(const char *scene_path, mpm_sim **out, char *err,
                                    size_t errlen);

/// Destroy a simulation; NULL is fine.
void mpm_sim_destroy(mpm_sim *sim);

/// Advance the simulation to the end of the next frame (several substeps).
mpm_status mpm_sim_advance_frame(mpm_sim *sim);

/// Advance by exactly one time step of at most max_dt seconds (the CFL bound applies too).
mpm_status mpm_sim_step(mpm_sim *sim, double max_dt);

/// The message of the last failure of this simulation ("" when none). Owned by sim.
const char *mpm_sim_last_error(const mpm_sim *sim);

/// Simulated time in seconds, steps taken, and frames completed.
double mpm_sim_time(const mpm_sim *sim);
int64_t mpm_sim_steps(const mpm_sim *sim);
int mpm_sim_frame(const mpm_sim *sim);
int mpm_sim_frame_count(const mpm_sim *sim);

/// Turn per-frame output on into `dir` (created if missing; the scene's `output` keys choose the
/// files) and write frame 0. Checkpoints need it: mpm_sim_write_checkpoint writes into `dir`.
mpm_status mpm_sim_enable_output(mpm_sim *sim, const char *dir);

/// Checkpoints (HDF5, see docs/scene-format.md "Checkpoints"). Write the complete state into
/// the output directory as checkpoint_<steps>.h5, atomically, keeping the two newest; the
/// path written is copied to `path` (of `cap` bytes, may be NULL). Needs output enabled.
mpm_status mpm_sim_write_checkpoint(mpm_sim *sim, char *path, size_t cap);
/// Replace the state of a freshly created simulation with the newest valid checkpoint in
/// `dir` (older ones are tried when the newest is damaged) and continue writing frames there.
/// The scene must be the one the checkpoint was written from. The checkpoint used is copied
/// to `path` (may be NULL). The run then continues bit-identically to an uninterrupted one.
mpm_status mpm_sim_resume(mpm_sim *sim, const char *dir, char *path, size_t cap);
/// Stop between two steps when *flag becomes nonzero (set it from a signal handler):
/// mpm_sim_advance_frame then returns MPM_ERR_INTERRUPTED with the state consistent, ready
/// for mpm_sim_write_checkpoint. NULL removes the flag.
void mpm_sim_set_interrupt(mpm_sim *sim, const volatile int *flag);

/// Particle domains (Zhu et al. 2017): switch off the domains of every domain particle inside
/// the box [lo, hi] (m), now; they continue as standard material points (for topology change
/// such as melting or cutting). The number switched off goes to *count (may be NULL).
mpm_status mpm_sim_release_domains(mpm_sim *sim, const double lo[3], const double hi[3],
                                   size_t *count);

/// Read-only view of every particle, valid until the next call that advances sim or asks for
/// the view again: the standard material points, then the particles with domains (Zhu et al.)
/// whose domains are on. Without domains the arrays are the simulation's own; with them, a
/// copy the simulation owns. Components are separate arrays (structure of arrays) of `count`
/// entries each, in the engine's real type (float or double, see real_size).
typedef struct mpm_particle_view {
  size_t count;
  size_t real_size;    /* sizeof the real type: 4 or 8 */
  const void *x[3];    /* position, m */
  const void *v[3];    /* velocity, m/s */
  const void *F[9];    /* deformation gradient, row-major */
  const void *mass;    /* kg */
  const void *volume0; /* initial volume, m^3 */
  const int32_t *material;
  const int32_t *body;
  const uint32_t *id; /* stable particle id */
} mpm_particle_view;

mpm_particle_view mpm_sim_particles(const mpm_sim *sim);

#ifdef __cplusplus
}
#endif
#endif
