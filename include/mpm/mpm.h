/* mpm.h - public API of the mpm Material Point Method engine.
 *
 * A simulation is an opaque handle created from a JSON scene (see docs/scene-format.md) and
 * advanced frame by frame; results are read through bulk read-only views or written by the
 * frame writers. Functions that can fail return an mpm_status; the message that names the
 * file, key path, step or particle is available from mpm_sim_last_error or is written into
 * the caller's buffer. No function of the library exits the process.
 *
 * Thread safety: one mpm_sim may be used by one caller thread at a time; the engine itself
 * runs its transfers on OpenMP threads.
 *
 * Linking: libmpm.so exports the functions of this header only (MPM_API); libmpm.a holds the
 * same objects. See README "Using mpm as a library" (pkg-config mpm, find_package(mpm)). */
#ifndef MPM_MPM_H
#define MPM_MPM_H

#include <stddef.h>
#include <stdint.h>

/* The functions of the public API: exported from the shared library, which is compiled with
 * -fvisibility=hidden (everything else stays inside it). */
#if defined(__GNUC__) || defined(__clang__)
#define MPM_API __attribute__((visibility("default")))
#else
#define MPM_API
#endif

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
  MPM_ERR_EXTERNAL = 7,    /* a program the call runs is missing or failed (gnuplot) */
} mpm_status;

/// Human-readable name of a status ("ok", "parse error", ...). Static storage.
MPM_API const char *mpm_status_string(mpm_status s);

/// Version string of the library, "MAJOR.MINOR.PATCH". Static storage.
MPM_API const char *mpm_version(void);

/// Name of the real type this library was built with: "float" or "double".
MPM_API const char *mpm_real_type(void);

/// Bytes the library holds now for its large arrays (particles, grids, the steps' scratch), over
/// every simulation of the process: what a leak check compares before and after.
MPM_API size_t mpm_live_bytes(void);

/// An embedding program's allocator for the library's memory (a pool, a tracking allocator):
/// alloc returns `bytes` aligned to `alignment` (a power of two, at least 64) or NULL when out
/// of memory; free takes back what alloc gave. `user` is passed to both.
typedef struct mpm_allocator {
  void *(*alloc)(size_t bytes, size_t alignment, void *user);
  void (*free)(void *p, void *user);
  void *user;
} mpm_allocator;

/// Every later allocation of the library goes through `a` (NULL: back to the C library's
/// aligned_alloc and free, and anonymous mappings for the particle storage), the particle
/// storage included (it then grows by a copy instead of moving its pages). Set it while the
/// library holds no memory (mpm_live_bytes() == 0: before the first simulation, or after the
/// last is destroyed), from one thread; MPM_ERR_INVALID otherwise, or when a has only one of its
/// two functions. What the scene parser (cJSON) and OpenVDB allocate for their own work does
/// not go through it.
MPM_API mpm_status mpm_set_allocator(const mpm_allocator *a);

typedef struct mpm_sim mpm_sim;

/// Load and validate a JSON scene and build the simulation (particles sampled, colliders set).
/// On failure *out is NULL and err (of errlen bytes, may be NULL) holds the message.
MPM_API mpm_status mpm_sim_create_from_file(const char *scene_path, mpm_sim **out, char *err,
                                            size_t errlen);

/// The same from the scene's JSON text (a NUL-terminated string, the keys of a scene file).
/// Relative mesh files resolve against `base_dir` (NULL: the current directory), and messages
/// name the scene "<json>" (inside base_dir when given). The text is not kept. On failure *out
/// is NULL and err (of errlen bytes, may be NULL) holds the message.
MPM_API mpm_status mpm_sim_create_from_json(const char *json_text, const char *base_dir,
                                            mpm_sim **out, char *err, size_t errlen);

/// Destroy a simulation; NULL is fine.
MPM_API void mpm_sim_destroy(mpm_sim *sim);

/// Advance the simulation to the end of the frame in progress (the steps it still needs, which
/// may be none after mpm_sim_step calls) and complete the frame: the frame count goes up and,
/// with output on, the frame is written (and a checkpoint when output.checkpoint_every says).
/// MPM_ERR_INVALID once every frame is done (the end time reached).
///
/// A step that fails with MPM_ERR_UNSTABLE or MPM_ERR_NOMEM loses the state: from then on
/// mpm_sim_advance_frame, mpm_sim_step and mpm_sim_write_checkpoint return that status, naming
/// the step that failed, and change nothing; destroy the simulation (or create it again and
/// resume from a checkpoint). MPM_ERR_INTERRUPTED loses nothing: the next call goes on.
MPM_API mpm_status mpm_sim_advance_frame(mpm_sim *sim);

/// Advance by one time step of at most max_dt seconds (0: no bound of the caller's; the CFL
/// bound applies too), never past the time of the frame in progress: the step is shortened to
/// land on it, and then the frame is completed as mpm_sim_advance_frame completes it. Steps and
/// frames may be mixed freely; time only goes forward. MPM_ERR_INVALID past the end time.
MPM_API mpm_status mpm_sim_step(mpm_sim *sim, double max_dt);

/// The message of the last failure of this simulation ("" when none). Owned by sim.
MPM_API const char *mpm_sim_last_error(const mpm_sim *sim);

/// The OpenMP threads this simulation's calls run on (advance, step, enable_output, particles),
/// at least 1; 0 (the default) leaves the caller's OpenMP setting (OMP_NUM_THREADS,
/// omp_set_num_threads). The count is set for the duration of each call and the caller's restored
/// after it, so that a host's own parallel regions keep theirs. Results do not depend on the count.
/// Returns MPM_ERR_INVALID for a negative count; in a build without OpenMP the count is accepted
/// and every call runs on one thread.
MPM_API mpm_status mpm_sim_set_threads(mpm_sim *sim, int threads);

/// Simulated time in seconds, steps taken, and frames completed.
MPM_API double mpm_sim_time(const mpm_sim *sim);
MPM_API int64_t mpm_sim_steps(const mpm_sim *sim);
MPM_API int mpm_sim_frame(const mpm_sim *sim);
MPM_API int mpm_sim_frame_count(const mpm_sim *sim);

/// An output folder holds one run. What mpm_sim_open_output does with a folder that holds the
/// files of an earlier run (frames, checkpoints, stats.csv, the PVD indexes, scene.json, the
/// surfaces and level sets, and their temporaries, recognised by their exact names):
typedef enum mpm_output_mode {
  /// refuse it (MPM_ERR_INVALID, naming some of the files); nothing is touched
  MPM_OUTPUT_NEW = 0,
  /// remove exactly those files first, and nothing else: never a folder, a symbolic link, a
  /// file of another name, nor this simulation's scene file or meshes. Every one is checked
  /// before any is removed: a folder or a link bearing such a name refuses the whole (MPM_ERR_IO)
  MPM_OUTPUT_OVERWRITE = 1,
} mpm_output_mode;

/// Turn per-frame output on into `dir` (created if missing; NULL: the scene's output.directory;
/// the scene's `output` keys choose the files) and write frame 0. Checkpoints need it:
/// mpm_sim_write_checkpoint writes into `dir`. The folder is locked for this simulation until
/// it is destroyed (a lock file `.mpm.lock` in it, flock): another simulation, in this process
/// or another, that opens or resumes output there gets MPM_ERR_IO naming the folder and the
/// process that holds it.
MPM_API mpm_status mpm_sim_open_output(mpm_sim *sim, const char *dir, mpm_output_mode mode);
/// mpm_sim_open_output with MPM_OUTPUT_NEW.
MPM_API mpm_status mpm_sim_enable_output(mpm_sim *sim, const char *dir);
/// Write the current state, once, as a frame's files into `dir` (created if missing), apart from
/// any run's records: the files the scene's `output` keys choose for a frame (frame_NNNN.vtu and
/// .ply, domains_NNNN.vtu, the embedded and particle surfaces, the level sets), numbered with
/// mpm_sim_frame (the frames completed; the files carry the time), without the PVD indexes,
/// stats.csv or a checkpoint, and without counting a frame. Works with output on or off, between
/// any two steps. The files are written into a private folder inside `dir` and moved in together
/// once all are written: with MPM_OUTPUT_NEW a name that already exists there refuses the whole
/// (MPM_ERR_INVALID naming it; nothing is written), with MPM_OUTPUT_OVERWRITE the same-named
/// regular files are replaced (nothing else is touched; a folder or link of such a name refuses).
/// `dir` is locked for the call as a run's folder is (a folder a running simulation holds is
/// refused, MPM_ERR_IO), and this simulation's own output folder is refused (its frames are the
/// run's record). The names written go to `written` (cap bytes, may be NULL), one per line.
MPM_API mpm_status mpm_sim_write_frame_to(mpm_sim *sim, const char *dir, mpm_output_mode mode,
                                          char *written, size_t cap);

/// Checkpoints (HDF5, see docs/scene-format.md "Checkpoints"). Write the complete state into
/// the output directory as checkpoint_<steps>.h5, atomically, keeping the two newest; the
/// path written is copied to `path` (of `cap` bytes, may be NULL). Needs output enabled.
MPM_API mpm_status mpm_sim_write_checkpoint(mpm_sim *sim, char *path, size_t cap);
/// Replace the state of a freshly created simulation with the newest valid checkpoint in
/// `dir` (older ones are tried when the newest is damaged) and continue writing frames there.
/// The scene must be the one the checkpoint was written from. The checkpoint used is copied
/// to `path` (may be NULL). The run then continues bit-identically to an uninterrupted one.
/// The folder is locked as mpm_sim_open_output locks it, and the temporaries a killed run
/// left there (.NAME.tmp.PID) are removed.
MPM_API mpm_status mpm_sim_resume(mpm_sim *sim, const char *dir, char *path, size_t cap);
/// Stop between two steps when *flag becomes nonzero (set it from a signal handler):
/// mpm_sim_advance_frame then returns MPM_ERR_INTERRUPTED with the state consistent, ready
/// for mpm_sim_write_checkpoint. NULL removes the flag.
MPM_API void mpm_sim_set_interrupt(mpm_sim *sim, const volatile int *flag);

/// Set the velocity of the particles with the stable ids ids[0 .. count) (the view's `id`) to
/// v[3 k .. 3 k + 2] (m/s), now, between two steps: the next step's P2G carries m v to the grid
/// (the APIC affine moment is kept). Material points only: a particle whose domain is on moves
/// with its domain's corners (release the domain first). MPM_ERR_INVALID, naming the id or the
/// value, for an id not simulated now, a particle with its domain on, a value not finite;
/// nothing is changed then.
MPM_API mpm_status mpm_sim_set_velocities(mpm_sim *sim, size_t count, const uint32_t *ids,
                                          const double *v);
/// The same for positions x[3 k .. 3 k + 2] (m), which must lie inside the scene's domain: the
/// particles jump there (nothing of their motion is implied: set their velocities too).
MPM_API mpm_status mpm_sim_set_positions(mpm_sim *sim, size_t count, const uint32_t *ids,
                                         const double *x);

/// Move collider `index` (the scene's `colliders`, in order) by a script: it ends the next step
/// at this pose (centre in m; rotation row-major, local -> world; NULL keeps its rotation),
/// moving there at a constant velocity and angular velocity over the step, its pose change over
/// dt, which the boundary rule gives the material it touches; after that step it stands still
/// there until set again. From the first call the collider follows the script, not its scene
/// motion. Checkpoints carry the script's state, so a resumed run that sets the same poses
/// continues bit-identically. MPM_ERR_INVALID, with the message, for an index out of range, a
/// value not finite, a matrix that is not a rotation (|R R^T - I| > 1e-6 or det <= 0).
MPM_API mpm_status mpm_sim_set_collider_pose(mpm_sim *sim, int index, const double center[3],
                                             const double rotation[9]);

/// Add a body now, between steps: `body_json` is one entry of a scene's `bodies` list (its
/// shape, a material of the scene by name, velocity, particles per cell, ...; relative mesh files
/// against `base_dir`, NULL: the working directory), checked as the scene's own bodies are
/// (messages name its key path, bodies[N]) and sampled into material points with new ids; the
/// number made goes to *count (may be NULL). The scene then has the body: checkpoints name that
/// scene, and with output open the folder's scene.json is rewritten with it, which is the scene
/// a resume takes. Not with particle domains, an inline material, nor on the multi-level grid
/// (MPM_ERR_INVALID, saying so). Nothing changes when it fails.
MPM_API mpm_status mpm_sim_add_body(mpm_sim *sim, const char *body_json, const char *base_dir,
                                    size_t *count);

/// Particle domains (Zhu et al. 2017): switch off the domains of every domain particle inside
/// the box [lo, hi] (m), now; they continue as standard material points (for topology change
/// such as melting or cutting). The number switched off goes to *count (may be NULL).
MPM_API mpm_status mpm_sim_release_domains(mpm_sim *sim, const double lo[3], const double hi[3],
                                           size_t *count);

/// Read-only view of every particle, valid until the next call that advances sim or asks for
/// the view again: the standard material points, then the particles with domains (Zhu et al.)
/// whose domains are on. Without domains the state arrays are the simulation's own; with them,
/// a copy the simulation owns. Components are separate arrays (structure of arrays) of `count`
/// entries each, in the engine's real type (float or double, see real_size). J and stress are
/// computed by each call (one stress evaluation per particle, in parallel): ask once per frame,
/// not once per particle. Members are only ever added at the end, so a program compiled against
/// an older header keeps working. An empty view (count 0) when out of memory.
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
  /* temperature in the scene's unit (K or degrees C, scene `heat`); NULL when heat is off */
  const void *temperature;
  /* the plastic state of the particle's material model: snow's J_p (plastic volume change,
   * 1 at rest), Drucker-Prager's accumulated log volume correction (0 at rest); 1 and unused
   * for the other models */
  const void *plastic;
  const void *J;         /* det F, the volume ratio (elastic part for the plastic models) */
  const void *stress[9]; /* Cauchy stress sigma = P F^T / J, row-major, Pa */
  /* Bytes from one component to the next of x, v and F: x[d] is (const char *)x[0] + d *
   * component_stride, F[c] is (const char *)F[0] + c * component_stride, so that a vector
   * field is one strided array (particle i's x[d] at i * real_size + d * component_stride:
   * numpy's strides (real_size, component_stride) for an n x 3 array, no copy) */
  size_t component_stride;
  size_t stress_stride; /* the same for stress[c] (0 in mpm_sim_particle_state's view) */
} mpm_particle_view;

MPM_API mpm_particle_view mpm_sim_particles(const mpm_sim *sim);

/// The same view without J and stress (NULL there): no stress is evaluated, so it costs reading
/// the pointers (with particle domains, copying the particles into one set). For a program that
/// reads the state every step.
MPM_API mpm_particle_view mpm_sim_particle_state(const mpm_sim *sim);

/// The particle domains (Zhu et al. 2017) of a view: their corners, shared by neighbouring
/// domains, and each active domain particle's eight. Valid as mpm_sim_particles' view is (until
/// the next call that advances sim or asks for a view again: a step may number the corners
/// anew, the hexahedra staying the same); counts 0 without domains (and when out of memory).
typedef struct mpm_domain_view {
  size_t corners;   /* corner count */
  size_t real_size; /* sizeof the real type */
  const void *x[3]; /* each corner's position, m */
  const void *v[3]; /* velocity, m/s */
  const void *X[3]; /* reference position (the lattice at rest), m */
  /* per corner: 1 where the corner was a DOF of its own (enriched, Zhu sec. 5) in the step the
     marks are of; NULL when no marks are current (before the first step, after a release) */
  const uint8_t *enriched;
  size_t particles; /* the active domain particles */
  size_t first;     /* the first one's index in mpm_sim_particles' view (after the material
                       points) */
  /* 8 per particle, row by row: its hexahedron's corners, corner a = i + 2 j + 4 k at the
     reference cube's (2i - 1, 2j - 1, 2k - 1) (VTK's voxel order) */
  const uint32_t *corner;
} mpm_domain_view;

MPM_API mpm_domain_view mpm_sim_domain_view(const mpm_sim *sim);

/// For a binding that hands the view's arrays to garbage-collected code (the Python module's
/// numpy arrays): delta +1 holds them, -1 releases a hold. While any hold is on, the arrays
/// the simulation would free (when it adds particles and grows its arrays, or replaces the
/// view's buffers) stay allocated, and are freed when the last hold is released: a pointer
/// from an earlier view then reads stale values (the particles are reordered every step), never
/// freed memory. mpm_sim_destroy frees everything whatever the holds.
MPM_API void mpm_sim_hold_particle_arrays(mpm_sim *sim, int delta);

/// A collider of the scene (its `colliders` list, in order) at the simulation's current time.
typedef struct mpm_collider_state {
  const char *name;           /* the scene's name for it; owned by sim */
  double center[3];           /* the shape's centre now, m */
  double rotation[9];         /* its rotation now (local -> world), row-major */
  double velocity[3];         /* of the centre, m/s */
  double angular_velocity[3]; /* rad/s */
  int active;                 /* it acts now (inside its `active` time window) */
} mpm_collider_state;

/// The number of colliders of the scene.
MPM_API int mpm_sim_collider_count(const mpm_sim *sim);
/// The pose of collider `index` (0 <= index < mpm_sim_collider_count) at mpm_sim_time, into
/// *out; MPM_ERR_INVALID for an index out of range.
MPM_API mpm_status mpm_sim_collider_pose(const mpm_sim *sim, int index, mpm_collider_state *out);

/// The particles simulated now: the standard material points and the particles whose domains
/// are on (the count of mpm_sim_particles' view, without building it).
MPM_API size_t mpm_sim_particle_count(const mpm_sim *sim);

/// Run at most `frames` frames (1 .. the scene's end time times fps): mpm_sim_frame_count then
/// returns it, and a loop `while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))` stops there
/// (`mpm run --frames N`). Once output is enabled the count may only be lowered (the output's
/// per-frame records are sized for it). MPM_ERR_INVALID otherwise, with the message.
MPM_API mpm_status mpm_sim_set_frame_limit(mpm_sim *sim, int frames);

/// Called after every step that mpm_sim_advance_frame takes, with `ctx` and the simulation
/// (whose getters it may call; it must not advance it): progress within a long frame. NULL
/// removes it.
typedef void (*mpm_step_callback)(void *ctx, const mpm_sim *sim);
MPM_API void mpm_sim_set_step_callback(mpm_sim *sim, mpm_step_callback callback, void *ctx);

/// What is likely a mistake in the scene though not an error, one line each (no trailing
/// newline) into `buf` (of `cap` bytes, may be NULL with cap 0): a kernel known to go unstable
/// on the scene's bodies and, before the first step, bodies that overlap each other (they
/// would be doubly dense) or start inside a collider. Returns the number of warnings.
MPM_API int mpm_sim_warnings(const mpm_sim *sim, char *buf, size_t cap);

/// The time step the next mpm_sim_step would take before clipping to a frame's end: the CFL
/// bound on the current state (the enrichment's too, Zhu et al. 2017 sec. 5) or the implicit
/// solver's fixed solver.dt, into *dt, without advancing. A frame then needs about
/// 1 / (fps * dt) steps (`mpm check` prints it). It computes the step's enrichment marks,
/// which the next step would compute the same way.
MPM_API mpm_status mpm_sim_next_dt(mpm_sim *sim, double *dt);

/// What a program reports about a simulation: its size, its output and the figures of the
/// last frame. Fill it with mpm_sim_get_info(sim, &info, sizeof info): members are only ever
/// added at the end, and the library writes no more than `size` bytes, so a program built
/// against an older header keeps working. The strings are owned by sim and valid until the
/// next call that changes it.
typedef struct mpm_sim_info {
  size_t particles;        /* simulated now (mpm_sim_particle_count) */
  size_t domain_particles; /* of them, those whose domains are on (Zhu et al. 2017) */
  int bodies, materials, colliders;
  double dx;              /* the grid's cell size (the coarsest level's on a multi-level grid), m */
  double finest_dx;       /* the finest level's, m (dx on a uniform grid) */
  double fps, frame_dt;   /* frames per second and 1 / fps, s */
  double end_time;        /* the scene's, s */
  int frame_count;        /* frames to run: the scene's or mpm_sim_set_frame_limit's */
  int implicit;           /* solver.integrator is "implicit" */
  int fixed_dt;           /* the step is the scene's solver.dt (implicit), not a CFL bound */
  int threads;            /* the OpenMP threads its calls run on (mpm_sim_set_threads) */
  double memory_bytes;    /* the memory the scene needs for its particles (the estimate that
                             creation checks against MPM_MEMORY_LIMIT or the machine's) */
  int output_enabled;     /* mpm_sim_enable_output was called (or mpm_sim_resume) */
  const char *output_dir; /* where frames go (the scene's output.directory until then) */
  int written_frames;     /* frame files written, frame 0 included */
  const char *last_checkpoint; /* the path of the newest checkpoint written, "" when none */
  /* the implicit solver over the last frame completed (0 steps when explicit) */
  long long solver_steps, cg_iterations, newton_iterations, cg_unconverged;
  int cg_max;             /* most CG iterations of one step */
  double cg_residual_max; /* largest final relative CG residual of one step */
  /* output.surface: the last frame's particle surfaces, and all frames of this process */
  int surfaces;             /* output.surface is on */
  double surface_seconds;   /* the last frame's wall time for them, s */
  size_t surface_triangles; /* its triangles */
  double surface_seconds_total;
  int surface_frames;
  /* Gao et al. 2017: the multi-level grid's rebuilds (domain.refine_every) and the particle
     split and merge (resample), since creation */
  int refining;
  long long refinements;
  double refinement_seconds;
  int resampling;
  long long splits, merges;
  double angular_momentum_change[3]; /* what the resampling changed, kg m^2/s */
  /* heat (scene `heat`): domain particles melted off their domains since creation, and the
     last step's conduction substeps */
  int heat;
  size_t melted_domains;
  int conduction_substeps;
  long long refinements_unchanged; /* of refinements: trees equal to the one in use, which was
                                      kept (its caches stay valid) */
  /* a run on MPI ranks (mpm_sim_join_mpi_world): this process's rank and the run's ranks, and
     the particles of every rank (`particles` above is this rank's); one process: 0, 1 and
     `particles` */
  int rank, ranks;
  size_t run_particles;
} mpm_sim_info;

MPM_API mpm_status mpm_sim_get_info(const mpm_sim *sim, mpm_sim_info *info, size_t size);

/// Runs on MPI ranks (docs/distributed.md; a library built with -DMPM_MPI=ON). Make `sim`
/// this process's part of a run over every process of MPI_COMM_WORLD: every process made its
/// simulation from the same scene and calls this first (no step taken, output not opened; the
/// caller initialises MPI before and finalises it after destroying the simulation). Each
/// process then keeps the particles of its part of the domain and its steps exchange with the
/// others. From then on every process makes the same calls in the same order (they are
/// collective): mpm_sim_open_output (rank 0 locks and claims the folder, which every rank must
/// see at the same path), mpm_sim_advance_frame, mpm_sim_step. Frames are written as one piece
/// per rank, frame_NNNN_pRRRR.vtu (and .ply), with frame_NNNN.pvtu listing them, frames.pvd,
/// run.pvd and stats.csv (figures over every rank) by rank 0. Not yet on ranks: checkpoints
/// (mpm_sim_write_checkpoint and mpm_sim_resume refused, output.checkpoint_every ignored). A
/// failure of the steps or the frames comes back on every rank alike (mpm_sim_ranks_agree
/// picks one message for all). Collective. MPM_ERR_INVALID on every rank, the message naming it,
/// for what does not run on ranks yet (the implicit step, the multi-level grid, particle
/// domains, heat, the dense grid, particle surfaces) and in a library built without MPI;
/// MPM_ERR_NOMEM.
MPM_API mpm_status mpm_sim_join_mpi_world(mpm_sim *sim);

/// After a call that every rank of a run on MPI ranks made (mpm_sim_join_mpi_world, and a
/// call that may have failed on some ranks only): `st` is this rank's result. Returns the
/// largest status of every rank's, and where it is a failure, every rank's mpm_sim_last_error
/// becomes the message of the rank where the failure began (the others' messages only point
/// at it), so that one rank can print it for all. Collective. A simulation that is not a rank's
/// part of a run (one process, or the join refused): st, nothing else.
MPM_API mpm_status mpm_sim_ranks_agree(mpm_sim *sim, mpm_status st);

/// What a scene will need, from its description alone: its bodies are not sampled, so a scene
/// of 10^8 particles is answered in a moment and without its memory (`mpm check` on a large
/// scene). Filled by mpm_scene_estimate_file; members are only added at the end, as
/// mpm_sim_info's.
typedef struct mpm_scene_estimate {
  double particles;       /* expected: each body's volume (a mesh's enclosed volume) over its
                             particle spacing cubed, and on a multi-level grid the refined leaves'
                             particles; sampling gives a count within a few percent of it */
  double memory_bytes;    /* what the run is admitted by: the estimate of mpm_sim_info */
  double available_bytes; /* what this machine offers: MPM_MEMORY_LIMIT, else MemAvailable */
  double first_dt;        /* the first step's bound, s: the stiffest material's CFL step with the
                             bodies' initial speeds (explicit), the particle speed's or solver.dt
                             (implicit); solver.max_dt caps it */
  double frame_dt, dx, finest_dx;
  int bodies, materials, colliders, frame_count;
  int implicit; /* solver.integrator "implicit" */
} mpm_scene_estimate;

/// Read and check the scene file at `path` as mpm_sim_create_from_file does, up to sampling
/// its bodies: every key, the meshes (read and checked closed), the memory against what the
/// machine has (MPM_ERR_NOMEM when it is short, as mpm_sim_create_from_file refuses it), the
/// steps a frame takes. What sampling alone finds (a body outside the domain, overlapping
/// bodies, a body inside a collider, shells of a mesh that overlap) is not checked. Fills
/// `size` bytes of *out (pass sizeof *out). On failure err (of errlen bytes, may be NULL) holds
/// the message, as mpm_sim_create_from_file's.
MPM_API mpm_status mpm_scene_estimate_file(const char *path, mpm_scene_estimate *out, size_t size,
                                           char *err, size_t errlen);

/// The rest-state error of Zhu et al. 2017 (sec. 7, their Table 1) between two frame files of
/// a run (frame_NNNN.vtu, with the id array; `mpm error`): particles matched by id, the rigid
/// motion removed by shape matching (mass-weighted where the frames have masses), distances
/// over the rest shape's bounding-box diagonal. body >= 0 keeps that body's particles only.
typedef struct mpm_rest_error_result {
  double mean, max;        /* mean and largest distance after the rigid motion, / diagonal */
  double diagonal;         /* the rest shape's bounding-box diagonal, m */
  size_t matched;          /* particles in both frames */
  size_t rest_particles;   /* particles of the rest frame (of the body) */
  double rotation[9];      /* the rotation removed, row-major */
  double rotation_degrees; /* its angle */
  double translation[3];   /* and the translation, m */
} mpm_rest_error_result;

/// MPM_ERR_IO or MPM_ERR_PARSE for a file that cannot be read or is not a frame of mpm,
/// MPM_ERR_INVALID when no particle is in both, with the file named in err (may be NULL).
MPM_API mpm_status mpm_rest_error_frames(const char *rest_vtu, const char *final_vtu, int body,
                                         mpm_rest_error_result *out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
/* a scene built in code (description structs), on the declarations above */
#include "scene_def.h"
/* pictures of a run's output folder (the software renderer) and plots of its stats.csv */
#include "render.h"
#include "plot.h"
#endif
