/* sim.h - the simulation object behind the public mpm_sim handle: it owns the scene, the
 * particles, materials, colliders, the grid and every per-step buffer. One object, no global
 * mutable state. */
#ifndef MPM_SIM_SIM_H
#define MPM_SIM_SIM_H

#include "heat/heat.h"
#include "collide/body_force.h"
#include "collide/collider.h"
#include "domain/domain.h"
#include "core/alloc.h"
#include "core/clock.h"
#include "core/particles.h"
#include "domain/embed.h"
#include "grid/grid.h"
#include "interp/kernel.h"
#include "io/io.h"
#include "material/material.h"
#include "scene/memory_estimate.h"
#include "scene/scene.h"
#include "grid/dofs.h"
#include "sim/thread_tuner.h"
#include "transfer/transfer.h"

#include <stdint.h>

/* Time spent in the stages of the step (step.c), seconds, accumulated since creation
 * (benchmarks read it): sort = activation and DOF layout, grid = the update on the DOF set. */
typedef struct mpm_stage_times {
  double sort, p2g, grid, heat, g2p, total;
} mpm_stage_times;

/* The implicit solver's figures, summed over the steps of the current frame (stats.csv). */
typedef struct mpm_solver_figures {
  long long steps, cg_iterations, newton_iterations, cg_unconverged;
  int cg_max;               /* most CG iterations of one step */
  double residual_max;      /* largest final relative CG residual of one step */
  int last_cg, last_newton; /* the last step's (progress line) */
  double last_residual;
  double mg_setup_seconds, mg_cycle_seconds; /* multigrid: its build and its V-cycles */
  size_t mg_bytes;                           /* multigrid: the largest hierarchy of a step */
} mpm_solver_figures;

/* The steps of the current frame (stats.csv's dt columns). A frame's last step or two are
 * shortened so that the steps land on the frame's time; `full` counts the others, whose mean
 * is the frame's typical step. min and max are 0 before the frame's first step. */
typedef struct mpm_step_figures {
  long long steps, full_steps;
  double sum, full_sum; /* s */
  double min, max;      /* s */
} mpm_step_figures;

/* The output folder and its bookkeeping (sim_output.c, frame_files.c, sim_surface.c). */
typedef struct mpm_sim_output {
  int enabled;
  char dir[MPM_PATH_MAX];
  int lock; /* the descriptor holding dir's lock (io/run_folder.h), -1: none */
  int written_frames;
  double *frame_times;
  char (*frame_files)[64];
  mpm_stats_row *stats;
  double *stats_forces; /* per stats row, 3 per collider: the mean force on each collider over
                           the frame, N (stats.csv's last columns) */
  double frame_wall_start;
  /* output.surface (sim_surface.c): the last frame's reconstruction, for the progress line */
  double surface_seconds;       /* wall time of the frame's surfaces, files included */
  size_t surface_triangles;     /* triangles over all its surfaces */
  double surface_seconds_total; /* over the frames written by this process */
  int surface_frames;
  char last_checkpoint[MPM_PATH_MAX + 32];
} mpm_sim_output;

/* What a retried step needs (guard.c, sim_checkpoint.c). */
typedef struct mpm_sim_retry {
  int dt_level;                /* dt is halved this many times after an unstable step */
  long long retries;           /* steps redone with a smaller dt, over the run */
  mpm_particles backup;        /* the particles at the start of a step (retry mode) */
  mpm_particles domain_backup; /* the domain particles and corners at the start of a step */
  mpm_real *corner_backup[18];
  size_t corner_backup_capacity;
} mpm_sim_retry;

/* The copies behind the public views (sim_view.c). */
typedef struct mpm_sim_views {
  mpm_particles particles; /* mpm_sim_particles' copy of every particle when there are domains */
  mpm_real *derived;       /* the view's J and Cauchy stress: 10 arrays of capacity */
  size_t capacity;
  uint32_t *corner; /* mpm_sim_domain_view's corner indices (8 per active particle) */
  size_t corner_capacity;
  mpm_keep keep; /* arrays replaced while a binding holds views (mpm_sim_hold_particle_arrays) */
} mpm_sim_views;

struct mpm_sim {
  mpm_scene scene;
  mpm_particles particles;
  mpm_material *materials;      /* as they are this step (strength schedules applied) */
  mpm_material *base_materials; /* as the scene gives them */
  int has_strength;             /* some material has a strength schedule */
  int material_count;
  mpm_collider *colliders;
  mpm_collider_pose *poses;
  int collider_count;
  /* the momentum each collider took from the DOFs (stats.csv's collider force columns), 3 per
   * collider, kg m/s: in the step under way (step.c), and summed over this frame's steps
   * (frame.c); measured only while stats.csv is written */
  double *collider_step, *collider_frame;
  mpm_collider *force_colliders;   /* body-force regions: their level sets and motion */
  mpm_force_region *force_regions; /* those acting this step (step.c) */
  int force_count;
  mpm_kernel kernel;
  /* Zhu's particle domains: the domain particles, their corners, and the corner kernel */
  mpm_domain_set domains;
  mpm_kernel domain_kernel;
  mpm_embedded_surface *surfaces; /* meshes of mesh bodies with domains (Zhu sec. 4.1) */
  int surface_count;
  mpm_real origin[3];
  int cells[3];  /* grid cells per axis over the domain */
  mpm_grid grid; /* the uniform grid level (sparse or dense) */
  /* the grids the step transfers on (grid_stack.h): the uniform level, or Gao's multi-level
   * grid (scene.levels > 0) in place of `grid`, whose state is `adaptive` (else NULL) */
  const struct mpm_grid_stack_ops *stack;
  struct mpm_adaptive *adaptive;
  /* the state of a stack that wraps another (a rank's part of a distributed run, src/dist/:
   * the ranks' halo exchange around the uniform stack's stages), else NULL */
  void *stack_data;
  mpm_dofs dofs; /* the unknowns of the step: the values at the grid's nodes */
  /* the step's global reductions over the processes of a run (core/reduce.h), NULL for one
   * process; the DOF set's reductions use the same (mpm_sim_set_reduction) */
  const mpm_reduction *reduction;
  mpm_heat heat;         /* heat transfer's scratch and figures (scene `heat`) */
  size_t melted_domains; /* domain particles switched off by melting so far */
  mpm_arena step_arena;  /* the step's scratch, taken back when the next step begins */
  uint32_t *iscratch;    /* per-particle integers for the periodic reorder (the reals reorder
                            within their own storage: core/particles.h) */
  size_t scratch_capacity;
  int reorder_interval;     /* physically reorder particles every this many steps */
  mpm_thread_tuner threads; /* the step's thread count, measured (sim/thread_tuner.h) */
  int thread_request;       /* mpm_sim_set_threads' count for the public calls; 0: the caller's */
  /* time */
  double time, frame_dt, last_dt;
  int64_t steps;
  uint32_t next_id; /* the id of the next particle a split makes (ids are never reused) */
  int frame, frame_count;
  mpm_real max_speed, wave_speed;
  mpm_stage_times times;
  mpm_solver_figures solver_figures;       /* implicit steps of this frame */
  mpm_solver_figures last_frame_solver;    /* the same for the last frame completed (progress) */
  mpm_step_figures step_figures;           /* the steps of this frame (frame.c) */
  long long implicit_steps, cg_iterations; /* implicit steps and their CG iterations since
                                              creation (benchmarks) */
  long long enriched_contacts; /* enriched corners' contacts with the grid's material since
                                  creation (domain/enrich_contact.h) */
  long long surface_contacts;  /* enriched corners' contacts with enriched faces since creation
                                  (domain/enrich_surface_contact.h) */
  /* outputs */
  const struct mpm_frame_writer *writer; /* where frames and checkpoints go (frame_writer.h) */
  mpm_sim_output out;
  mpm_sim_retry retry; /* robustness (guard.c, sim_checkpoint.c) */
  const volatile int *interrupt;
  /* a step that lost the state (MPM_ERR_UNSTABLE, MPM_ERR_NOMEM; frame.c): its status and
   * message, MPM_OK while the state is whole */
  mpm_status failed;
  char failed_message[sizeof(((mpm_error *)0)->message)];
  /* called after every step inside mpm_sim_advance_frame (the CLI's progress within a frame) */
  void (*on_step)(void *ctx, const mpm_sim *sim);
  void *on_step_ctx;
  mpm_sim_views views; /* the public views' copies (sim_view.c) */
  /* the scene's JSON, mesh paths made absolute, for the output folder's scene.json (made when
   * created from a file or JSON text; NULL when created from a scene struct) */
  char *scene_copy;
  /* a digest of each body's mesh file as sampled (io/input_file.h), 0 for a body without one;
   * NULL when no body is a mesh (sim_checkpoint.c: a checkpoint resumes with the same meshes) */
  uint64_t *mesh_digests;
  /* the particles the memory check expected, from the bodies' volumes (and the refined
   * leaves'), before any was sampled */
  double expected_particles;
  mpm_error error;
};

/* Build a simulation from a validated scene (takes ownership of the scene's arrays: the
 * caller's struct is emptied). */
mpm_status mpm_sim_create_from_scene(mpm_scene *scene, mpm_sim **out, mpm_error *err);
/* The same up to the sampling of the bodies, which is left out: every check of the scene but
 * the bodies' placement, the memory check on the expected particles, no particle
 * (mpm_scene_estimate_file: `mpm check` on a scene too large to sample quickly). The result is
 * only for reading its figures (expected_particles, wave_speed and max_speed from the bodies'
 * initial motion); it is not stepped. */
mpm_status mpm_sim_create_unsampled(mpm_scene *scene, mpm_sim **out, mpm_error *err);

/* mpm_sim_enable_output (per-frame writing into `dir`, frame 0 written) is public: mpm/mpm.h. */

/* Around a public call that runs parallel work (mpm_sim_set_threads): enter sets the
 * simulation's thread count, when one was set, and returns the caller's, which leave restores. */
int mpm_sim_threads_enter(const mpm_sim *sim);
void mpm_sim_threads_leave(const mpm_sim *sim, int saved);

/* The standard and the active domain particles in one set (`all`: zeroed, or a set this made
 * before, whose arrays it reuses): for the frame files and the public particle view. MPM_OK, or
 * MPM_ERR_NOMEM when out of memory. */
mpm_status mpm_sim_all_particles(const mpm_sim *sim, mpm_particles *all);

/* Particle i of p (sim's particles or a copy of them): its Kirchhoff stress tau = P F^T = J sigma
 * with the moduli the step uses (the material hardened by its plastic state, softened by
 * melting), for the frame files and the view; returns J = det F. */
mpm_real mpm_sim_kirchhoff(const mpm_sim *sim, const mpm_particles *p, size_t i, mpm_real tau[9]);

/* Whether the step moves its n particles into their sorted order (mpm_reorder_due with the
 * simulation's steps and reorder_interval). */
int mpm_sim_wants_reorder(const mpm_sim *sim, size_t breaks, size_t n);

/* Room for the periodic reorder's per-particle buffers. MPM_OK, or MPM_ERR_NOMEM when out of
 * memory. */
mpm_status mpm_sim_ensure_scratch(mpm_sim *sim);

/* What the bodies start in that is likely a mistake (placement.c): bodies overlapping each other
 * and bodies inside a collider, one line each in out (cap bytes). The number of findings. */
int mpm_sim_placement_report(const mpm_sim *sim, char *out, size_t cap);

/* The cell size the CFL condition uses: dx, or the finest level's spacing on a multi-level grid. */
double mpm_sim_finest_dx(const mpm_sim *sim);

/* The time step the CFL condition allows now (before clipping to the frame end). */
double mpm_sim_cfl_dt(const mpm_sim *sim);

/* Diagnostics over the particles (double accumulation, fixed order => deterministic). */
typedef struct mpm_diagnostics {
  double mass, kinetic, elastic;
  double gravitational;                    /* -sum m g.x: zero at the origin, J */
  double momentum[3], angular_momentum[3]; /* about the origin; APIC affine part included */
} mpm_diagnostics;
mpm_diagnostics mpm_sim_diagnostics(const mpm_sim *sim);

/* The global reductions of the simulation's steps (core/reduce.h: every process of a
 * distributed run fills one; NULL, the default, for a single process), for the step and its
 * DOF set alike. */
void mpm_sim_set_reduction(mpm_sim *sim, const mpm_reduction *reduction);
/* Where the simulation's frames and checkpoints go (frame_writer.h; mpm_frame_files, the
 * default, when NULL). */
void mpm_sim_set_writer(mpm_sim *sim, const struct mpm_frame_writer *writer);

/* One step, three layers: mpm_sim_step (frame.c, public) runs the work between steps, then the
 * guarded step; mpm_sim_guarded_step (guard.c) runs the raw step, then a scan for non-finite
 * values, particles leaving the domain, CFL violations and inversions the model cannot take,
 * and with solver.on_instability = "retry" undoes an unstable step and redoes it with half the
 * dt, up to solver.max_retries times; mpm_sim_raw_step (step.c) runs the stages of one step. */
mpm_status mpm_sim_guarded_step(mpm_sim *sim, double max_dt);
mpm_status mpm_sim_raw_step(mpm_sim *sim, double max_dt);
/* The work between steps (frame.c): domain releases. */
mpm_status mpm_sim_between_steps(mpm_sim *sim);
/* The guards' scan alone, for the state after a step of dt: MPM_ERR_UNSTABLE with the
 * diagnostic in sim->error, or MPM_OK. */
mpm_status mpm_sim_guard_check(mpm_sim *sim, double dt);

/* Tests and benchmarks: the stages of a step of dt up to the solve (sort, layout, P2G, with the
 * force apart), and the step's implicit system in *s (its scratch is the step arena's, valid
 * until the next step). Time and particles are not advanced (the sort may reorder the particle
 * arrays, as a step does). */
struct mpm_implicit;
mpm_status mpm_sim_implicit_system(mpm_sim *sim, double dt, struct mpm_implicit *s);

/* Zhu Algorithm 1 line 2: the enrichment marks (domain/enrich.h) of the step about to be taken,
 * from the state at its start; they bound an explicit step's dt, so the frame loop asks before
 * it plans a step, and every step asks before anything touches the grid. Computed once per
 * step (a function of the state: a resumed run gets the same marks). */
mpm_status mpm_sim_mark_enrichment(mpm_sim *sim);

/* Scale the materials' moduli by their strength schedules at time t (sim.c); a no-op without
 * schedules. */
void mpm_sim_apply_strength(mpm_sim *sim, double t);

/* Take the lock of the output folder `dir` for this simulation (releasing the one it held) and
 * make the folder ready: how == MPM_RUN_CLAIM_NEW refuses a folder holding a run's files,
 * OVERWRITE removes them, RESUME removes stale temporaries; the scene file and its meshes are
 * never touched. The folder must exist. On failure the lock held before is kept. */
mpm_status mpm_sim_claim_output(mpm_sim *sim, const char *dir, int how);

/* sim->mesh_digests from the scene's mesh files (sim_checkpoint.c); MPM_ERR_IO naming the key
 * and file when one cannot be read. */
mpm_status mpm_sim_digest_meshes(mpm_sim *sim, mpm_error *err);

/* Output bookkeeping for frame_count + 1 records (sim_output.c). */
mpm_status mpm_sim_alloc_output(mpm_sim *sim, int records);

/* Switch off the domains the scene's domain_release boxes name for the current time (sim.c);
 * a stage of mpm_sim_between_steps. */
mpm_status mpm_sim_apply_domain_releases(mpm_sim *sim);

/* Write the current state as the next frame (VTU, PLY, PVD, stats) into the output dir. */
mpm_status mpm_sim_write_frame(mpm_sim *sim);
/* output.surface of one frame: surface_NNNN.obj and .ply (or surface_bB_NNNN per body), and
 * with output.vdb levelset_NNNN.vdb, into dir, from the particles p (all of them, domains
 * included), in order of p's bodies (sim_surface.c). With `records` the run's surface figures
 * (time, triangles) count the frame. */
mpm_status mpm_sim_write_surfaces(mpm_sim *sim, const mpm_particles *p, const char *dir, int frame,
                                  int records);

/* The output folder's copy of the scene (sim_scene_copy.c): the JSON tree (the def's) or text
 * (the scene file's) printed with its numbers exact and the mesh bodies' files made absolute
 * (the tree is changed so), NULL when it cannot be read or is out of memory; and writing
 * sim->scene_copy as output_dir/scene.json (nothing without one). */
struct cJSON;
char *mpm_scene_copy_tree(struct cJSON *root, const mpm_scene *scene);
char *mpm_scene_copy_text(const char *json_text, const mpm_scene *scene);
mpm_status mpm_sim_write_scene_copy(mpm_sim *sim);

#endif
