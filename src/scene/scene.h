/* scene.h - the scene description: every input of a simulation, in SI units.
 *
 * A scene is loaded from JSON (scene_json.c, documented key by key in docs/scene-format.md)
 * into these plain descriptor structs; `mpm_scene_default` fills every default so that a
 * loader only overwrites what the file gives. The world (sim.c) is built from a scene and
 * never reads JSON. */
#ifndef MPM_SCENE_SCENE_H
#define MPM_SCENE_SCENE_H

#include "collide/collider_desc.h"
#include "core/error.h"
#include "core/limits.h"
#include "grid/grid.h"
#include "interp/kernel.h"
#include "io/io.h"
#include "material/material_desc.h"
#include "transfer/transfer.h"

#include <stddef.h>
#include <stdint.h>

/* The largest mesh file read unless a shape's max_file_mb says more, MiB: as scenes are. */
#define MPM_MESH_MAX_MB 64

/* Particle domains switched off (Zhu sec. 7): from `time` on, every domain particle of the body
 * inside the box [min, max] continues as a standard material point. */
typedef struct mpm_domain_release {
  double time;           /* s */
  double min[3], max[3]; /* m */
} mpm_domain_release;
#define MPM_MAX_RELEASES 16

typedef struct mpm_body_desc {
  char name[MPM_NAME_MAX];
  mpm_shape_desc shape;
  int material;                   /* index into scene.materials */
  double velocity[3];             /* initial velocity, m/s */
  double angular_velocity[3];     /* initial angular velocity about the body's centre, rad/s */
  double particles_per_cell;      /* along the volume: ppc particles per grid cell (e.g. 8) */
  double jitter;                  /* 0..1 fraction of the lattice spacing */
  unsigned seed;                  /* jitter seed */
  int domains;                    /* 1: particle domains (Zhu et al. 2017 sec. 4); needs jitter 0 */
  double enrichment;              /* domains: enrich where K(F) <= this (Zhu sec. 5); default 0:
                                     never (Zhu: 0.6) */
  double enrichment_exit;         /* domains: an enriched particle stays enriched while K(F) <= this
                                     (hysteresis); default 0.95, or `enrichment` when larger */
  double enrichment_hourglass;    /* domains: also enrich where the hexahedron's hourglass strain
                                     is >= this (domain/enrich.h: bending K(F) does not see);
                                     default 0: never (beyond Zhu) */
  int enrichment_contact;         /* domains: enriched corners meet other material
                                     on the grid (domain/enrich_contact.h); default 0 */
  int enrichment_surface_contact; /* domains: the enriched surface meets other bodies' enriched
                                     surfaces (domain/enrich_surface_contact.h); default 1 */
  int enrichment_self_contact;    /* domains: ... and its own enriched surface elsewhere
                                     (domain/enrich_surface_contact.h); default 1 */
  double enrichment_exit_wait;    /* domains: seconds an enriched particle must stay relaxed (K(F)
                                     above enrichment_exit, and its bend below 1 - exit with a bend
                                     threshold) before it returns to the grid; default 0: at once */
  int enrichment_metric;          /* domains: 0 sigma_min / sigma_max (default), 1 the normalized
                                     Frobenius form 3 / (|F| |F^-1|) (domain/enrich.h) */
  int hourglass;                  /* domains: hourglass control of the particles touching an
                                     enriched corner (0, "enriched", the default) or of every domain
                                     particle (1, "all"; domain/enrich.h) */
  int release_count;
  mpm_domain_release release[MPM_MAX_RELEASES];
  int resample;        /* domain.resample on: its particles split and merge (all bodies unless
                          domain.resample.bodies names some) */
  int has_temperature; /* `temperature` given (else the scene's heat.temperature) */
  double temperature;  /* initial temperature of its particles */
} mpm_body_desc;

/* A body-force region (Zhu Fig. 9: a rabbit sucked up a straw): inside the region (a
 * collider's shape, with its motion and its `active` window; the rule and friction are unused)
 * every DOF gets `acceleration` times the schedule's factor at the step's end, on top of
 * gravity, and a drag that takes `drag` times the factor of its velocity per second. */
typedef struct mpm_force_desc {
  mpm_collider_desc region;
  double acceleration[3]; /* m/s^2 */
  double drag;            /* 1/s, >= 0: dv/dt = -drag v (air drag, a settling bath); 0: none */
  int schedule_count;     /* keyframes (time s, factor), interpolated linearly, held outside;
                             none: factor 1 */
  double schedule[MPM_STRENGTH_KEYS][2];
} mpm_force_desc;

/* Most bodies or materials output.surface names. */
#define MPM_SURFACE_SELECT_MAX 32

/* The filter of a smoothing pass of output.surface (the order of vdb_shim.h's mpm_vdb_filter). */
typedef enum mpm_surface_filter {
  MPM_SURFACE_MEAN_CURVATURE = 0,
  MPM_SURFACE_GAUSSIAN = 1,
  MPM_SURFACE_LAPLACIAN = 2,
} mpm_surface_filter;

/* output.surface: a triangle surface reconstructed per frame from the particles of some bodies
 * (src/surface/surface.h): the union of one sphere per particle as an OpenVDB level set,
 * smoothed, meshed. */
typedef struct mpm_surface_desc {
  int enabled;
  int body_count; /* the bodies named (indices); 0 with material_count 0: every body that has
                     no embedded mesh of its own (a mesh body with domains keeps that one) */
  int bodies[MPM_SURFACE_SELECT_MAX];
  int material_count; /* the materials named (indices): their particles, in any body */
  int materials[MPM_SURFACE_SELECT_MAX];
  double voxel;              /* level-set voxel, cells; 0 (default): the particle spacing, the
                                median cbrt(V) (0.5 cell at 8 particles per cell) */
  double radius;             /* particle sphere radius, cells; 0 (default): from each particle's
                                volume (surface.h) */
  int smoothing;             /* filter passes, default 1 */
  mpm_surface_filter filter; /* default mean curvature */
  int per_body;              /* 1: surface_bB_NNNN.obj per body instead of one surface_NNNN */
} mpm_surface_desc;

/* The names of output.fields, in the order of mpm_output_field; NULL-terminated. */
extern const char *const mpm_output_field_names[MPM_FIELD_COUNT + 1];

typedef struct mpm_output_desc {
  char directory[MPM_PATH_MAX]; /* default "out"; `mpm run -o` overrides */
  int vtu;                      /* per-frame VTU + PVD index */
  int ply;                      /* per-frame PLY points */
  int stats;                    /* stats.csv */
  int checkpoint_every;         /* HDF5 checkpoint every this many frames; 0 = only on a signal */
  mpm_surface_desc surface;     /* surface_NNNN.obj / .ply per frame */
  int vdb;                      /* with a surface: its level set as levelset_NNNN.vdb */
  int vdb_density;              /* and a fog-volume grid "density" beside it */
  int vdb_velocity;             /* and the particles' velocity as a vector grid "vel" */
  /* output.fields: bit (1u << f) per mpm_output_field the VTU frames hold; 0 (the key absent):
   * mpm_output_fields_default */
  unsigned fields;
} mpm_output_desc;

/* The view `mpm render` uses (the renderer frames the domain when the scene has none). */
typedef struct mpm_camera_desc {
  int set;                  /* 1 when the scene gives a camera */
  double eye[3], target[3]; /* m */
  double fov;               /* vertical field of view, degrees, in (1, 170); default 35 */
} mpm_camera_desc;

/* What a step that goes unstable (non-finite state, a particle leaving the domain, a CFL
 * violation, an inversion the model cannot take) does. */
typedef enum mpm_instability_action {
  MPM_INSTABILITY_STOP = 0,  /* stop the run with a diagnostic */
  MPM_INSTABILITY_RETRY = 1, /* redo the step from its start with half the dt */
} mpm_instability_action;

typedef enum mpm_integrator_kind {
  MPM_INTEGRATOR_EXPLICIT = 0, /* symplectic Euler at the elastic CFL step (default) */
  MPM_INTEGRATOR_IMPLICIT = 1, /* backward Euler: Newton + CG on the DOF set (Zhu sec. 6) */
} mpm_integrator_kind;

typedef enum mpm_cg_failure_action {
  MPM_CG_FAILURE_WARN = 0, /* keep the answer CG reached; counted in stats.csv (default) */
  MPM_CG_FAILURE_STOP = 1, /* stop the run naming the step and the residual reached */
} mpm_cg_failure_action;

typedef enum mpm_preconditioner_kind {
  MPM_PRECONDITIONER_JACOBI = 0,   /* the diagonal of M + dt^2 K (Zhu eqs. 17-19; default) */
  MPM_PRECONDITIONER_MULTIGRID = 1 /* a Galerkin multigrid V-cycle (solver/multigrid.h) */
} mpm_preconditioner_kind;

typedef enum mpm_scheme_kind {
  MPM_SCHEME_BACKWARD_EULER = 0, /* positions move by v^{n+1} (Zhu sec. 6; default) */
  MPM_SCHEME_NEWMARK = 1         /* by (v^n + v^{n+1}) / 2: beta 1/2, gamma 1 (solver/implicit.h) */
} mpm_scheme_kind;

typedef struct mpm_solver_desc {
  mpm_kernel_kind kernel;
  mpm_transfer_kind transfer;
  mpm_grid_kind grid;
  double flip_alpha;  /* FLIP ratio, [0, 1], default 0.95 */
  double cfl;         /* (0, 1], default 0.4 */
  double max_dt;      /* s, upper bound on the step (0 = only CFL and frame) */
  double gimp_length; /* uGIMP particle box side L_p, m (0 = dx / cbrt(ppc) of the bodies) */
  mpm_instability_action on_instability; /* stop (default) or retry the step with a smaller dt */
  int max_retries;                       /* halvings of dt tried for one step, default 8 */
  mpm_kernel_kind domain_kernel;         /* corner <-> grid weights: linear (Zhu eq. 2, default),
                                            quadratic or cubic */
  /* time integration */
  mpm_integrator_kind integrator;
  double dt;                           /* implicit: a fixed step, s (0 = CFL on particle speed) */
  int newton_iterations;               /* implicit: 1 = Zhu's linearized step; default 2 */
  double cg_tolerance;                 /* implicit: CG's relative residual; 0 = automatic
                                          (mpm_solver_cg_tolerance) */
  int cg_max_iterations;               /* implicit: default 500 */
  mpm_cg_failure_action on_cg_failure; /* implicit: warn (default) or stop */
  mpm_preconditioner_kind preconditioner; /* implicit: CG's preconditioner */
  mpm_scheme_kind scheme;                 /* implicit: the positions' time integration */
} mpm_solver_desc;

/* Most levels of the multi-level grid (MPM_LEVELS_MAX of adaptive/refinement.h). */
#define MPM_SCENE_LEVELS_MAX 6

/* A static refinement rule of the multi-level grid (Gao et al. sec. 7.1; docs/adaptive-grid.md):
 * the cells it selects are refined until their leaves are of `level`. */
typedef enum mpm_refine_kind {
  MPM_REFINE_BOX,      /* cells meeting the box [min, max] */
  MPM_REFINE_COLLIDER, /* cells within `distance` of collider `collider`'s surface at t = 0 */
  MPM_REFINE_BODY,     /* cells holding body `body`'s material (sampled at the level's spacing),
                          with distance > 0 only those within it of the body's surface; at
                          setup only */
  /* rebuilds only (domain.refine_every), from the particles: */
  MPM_REFINE_SURFACE, /* cells within `distance` of the material's surface (body, or -1: all) */
  MPM_REFINE_TYPES,   /* cells of level q - 1 a particle of type q overlaps, q up to `level` */
  MPM_REFINE_STRAIN,  /* cells within `distance` of particles with ||F - I||_F > strain */
} mpm_refine_kind;

typedef struct mpm_refine_desc {
  mpm_refine_kind kind;
  int level;             /* 1 .. levels - 1 */
  double min[3], max[3]; /* box, or a body rule's `within` (when `within`), m */
  int within;            /* body rules: only the cells whose points lie in [min, max] */
  int collider, body;
  double distance; /* collider (required), body (0: all of it), surface (required), types,
                      strain: m */
  double strain;   /* strain rules: the threshold on ||F - I||_F */
} mpm_refine_desc;

/* Particle resampling on the multi-level grid (Gao et al. sec. 7.2; docs/adaptive-grid.md):
 * particles follow the level of the leaves they are in. A particle of type q in a leaf finer
 * than q splits into 8 of type q + 1; particles of type q whose box of type q - 1, grown by
 * merge_margin cells of level q - 1, meets no leaf finer than q - 1 merge 8 at a time, with their
 * nearest neighbours of their body, material and type in their cell of level q - 1. */
typedef struct mpm_resample_desc {
  int enabled;         /* domain.resample given */
  int split, merge;    /* default both on */
  int every;           /* steps between resamplings, default 1 */
  double merge_margin; /* cells of the merged type's level, default 1 */
  int max_per_cell;    /* a split only into a leaf cell that then holds at most this many
                          particles; default 0: twice the body's particles_per_cell */
  int min_per_cell;    /* a merge only where the cell of level q - 1 holds at least this many
                          of the merging particles; default 0: 4 x the body's particles_per_cell */
  unsigned seed;       /* of the split cubes' random orientations */
} mpm_resample_desc;

typedef struct mpm_scene {
  char path[MPM_PATH_MAX]; /* the scene file, for messages; mesh paths resolve against it */
  uint64_t source_hash;    /* FNV-1a of the scene text: a checkpoint resumes only the same scene */
  char name[MPM_NAME_MAX];
  /* the simulation box (the scene's `domain` key; "domain" in the code means Zhu's particle
   * domains, src/domain/) */
  double box_min[3], box_max[3]; /* m */
  double dx;                     /* grid cell size, m (of level 0 on a multi-level grid) */
  int levels;                    /* domain.levels: 0 = the uniform grid; 1..6 = Gao's
                                    multi-level grid (1: one level, through its path) */
  int refine_count;
  mpm_refine_desc *refine;     /* domain.refine */
  mpm_resample_desc resample;  /* domain.resample */
  int refine_every;            /* domain.refine_every: steps between trees from the rules (0:
                                  the tree of setup stays) */
  double gravity[3];           /* m/s^2, default (0, -9.81, 0) */
  mpm_boundary_rule wall_rule; /* domain walls */
  double wall_friction;
  int wall_cells; /* thickness of the wall band in cells, default 3 */
  /* time */
  double end_time; /* s */
  double fps;      /* frames per second */
  mpm_solver_desc solver;
  int material_count, body_count, collider_count, force_count;
  mpm_material_desc *materials;
  mpm_body_desc *bodies;
  mpm_collider_desc *colliders;
  mpm_force_desc *forces;
  mpm_output_desc output;
  mpm_camera_desc camera;
  /* heat transfer (heat/heat.h): the scene's `heat` object turns it on */
  struct {
    int enabled;
    double temperature; /* the initial temperature of bodies without their own */
    double pic; /* the rate the particles' temperatures relax to the grid's (heat.h), in units of
                   4 alpha / dx^2, [0, 100]; default 1 */
  } heat;
} mpm_scene;

/* The CG tolerance the implicit step uses: solver.cg_tolerance, or when it is 0 (the default)
 * 1e-4 for Zhu's single linearized step (it is only as good as its solve) and 1e-2 with Newton
 * iterations (inexact Newton: the line search and the next iteration correct a loose solve). */
double mpm_solver_cg_tolerance(const mpm_solver_desc *d);

/* A schedule's factor at time t: keyframes (time, factor) with increasing times, linear between
 * them, held before the first and after the last; 1 without keyframes (n = 0). */
double mpm_schedule_at(const double (*keys)[2], int n, double t);
/* A material's strength factor at time t (1 without a schedule). */
double mpm_material_strength(const mpm_material_desc *m, double t);

/* Advice on a valid scene that is likely to misbehave, for the CLI to print as warnings (and a
 * host program to show): one line each into buf (cap bytes, NUL-terminated, lines separated by
 * '\n'); returns how many. Today:
 *   - material points with the linear kernel. Its weight gradient jumps when a particle crosses
 *     a cell face, so the force a particle receives jumps too (the cell-crossing instability,
 *     Bardenhagen and Kober 2004): a stressed elastic body rings, then blows up shortly after its
 *     particles cross into new cells, for every transfer and time step;
 *   - a Drucker-Prager friction angle below 2 degrees: the key takes degrees, and such an angle
 *     is almost always radians given by mistake (0.61 for 35 degrees): sand that flows like a
 *     liquid. */
int mpm_scene_advice(const mpm_scene *scene, char *buf, size_t cap);

/* Fill every default; arrays empty. */
void mpm_scene_default(mpm_scene *scene);
/* Defaults for the parts of a scene (what a loader starts each array entry from). */
mpm_material_desc mpm_material_desc_default(void);
mpm_body_desc mpm_body_desc_default(void);
mpm_collider_desc mpm_collider_desc_default(void);
mpm_force_desc mpm_force_desc_default(void);
/* domain.resample's defaults, off (the loader turns `enabled` on when the key is given). */
mpm_resample_desc mpm_resample_desc_default(void);
/* Free the arrays a scene owns (not the struct). */
void mpm_scene_free(mpm_scene *scene);

/* Load, parse and validate a JSON scene (scene_json.c). Every error names the file and the
 * key path (e.g. "bodies[2].material.E") and says what was expected; nothing else happens. */
mpm_status mpm_scene_load(const char *path, mpm_scene *scene, mpm_error *err);
/* The same, and the text it read and parsed in *text (the caller's: mpm_free it; NULL on
 * failure), so that what is kept of the scene (the output folder's scene.json) is what was run,
 * from one read of the file. */
mpm_status mpm_scene_load_text(const char *path, mpm_scene *scene, char **text, mpm_error *err);
mpm_status mpm_scene_parse(const char *json_text, const char *path_for_messages, mpm_scene *scene,
                           mpm_error *err);
/* The same checks on a JSON tree already built (the scene def's), without its text: the source
 * hash is left 0 for the caller, who holds the text the scene is kept as. */
struct cJSON;
mpm_status mpm_scene_parse_tree(const struct cJSON *root, const char *path_for_messages,
                                mpm_scene *scene, mpm_error *err);

/* A scene built in code (include/mpm/scene_def.h) as one validated scene (scene_def.c): the
 * def's own checks, then the format's on the def's JSON tree, with no text parsed in between.
 * Messages name the scene "<def>" ("BASE_DIR/<def>"), where mesh files resolve. The source hash
 * is that of the tree's exact text, as if the def had been written to a file and read. *tree
 * (when not NULL) receives the tree, for the output folder's copy of the scene (the caller's:
 * cJSON_Delete it); NULL on failure. */
struct mpm_scene_def;
mpm_status mpm_scene_from_def(const struct mpm_scene_def *def, const char *base_dir,
                              mpm_scene *scene, struct cJSON **tree, mpm_error *err);

#endif
