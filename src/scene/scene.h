/* scene.h - the scene description: every input of a simulation, in SI units.
 *
 * A scene is loaded from JSON (scene_json.c, documented key by key in docs/scene-format.md)
 * into these plain descriptor structs; `mpm_scene_default` fills every default so that a
 * loader only overwrites what the file gives. The world (sim.c) is built from a scene and
 * never reads JSON. */
#ifndef MPM_SCENE_SCENE_H
#define MPM_SCENE_SCENE_H

#include "core/error.h"

#include <stddef.h>
#include <stdint.h>

#define MPM_NAME_MAX 64
/* The largest mesh file read unless a shape's max_file_mb says more, MiB: as scenes are. */
#define MPM_MESH_MAX_MB 64
#define MPM_PATH_MAX 1024

typedef enum mpm_kernel_kind {
  MPM_KERNEL_LINEAR = 0,      /* trilinear hat (Gao eq. 2) */
  MPM_KERNEL_QUADRATIC = 1,   /* quadratic B-spline (Stomakhin et al. 2013) */
  MPM_KERNEL_CUBIC = 2,       /* cubic B-spline */
  MPM_KERNEL_UGIMP = 3,       /* undeformed GIMP, closed form (Gao eqs. 5-6, sec. 6.2) */
  MPM_KERNEL_UGIMP_WIDE = 4,  /* internal, no scene name: the uGIMP kernel mpm_kernel_make builds
                                for boxes wider than dx (4 nodes per axis) */
  MPM_KERNEL_UGIMP_PAIRED = 5 /* internal: uGIMP (box <= dx) from the even node at or below the
                                 base, 4 nodes per axis (mpm_kernel_paired) */
} mpm_kernel_kind;

typedef enum mpm_transfer_kind {
  MPM_TRANSFER_APIC = 0, /* affine PIC (Jiang et al. 2015) */
  MPM_TRANSFER_FLIP = 1, /* PIC/FLIP blend with ratio flip_alpha (Gao sec. 3.2 step 6) */
} mpm_transfer_kind;

typedef enum mpm_grid_kind {
  MPM_GRID_SPARSE = 0, /* paged blocks activated from particles (the production grid) */
  MPM_GRID_DENSE = 1,  /* full box of nodes (reference implementation and baseline) */
} mpm_grid_kind;

typedef enum mpm_model_kind {
  MPM_MODEL_FIXED_COROTATED = 0, /* Stomakhin et al. 2012; Gao sec. 4.1 */
  MPM_MODEL_NEO_HOOKEAN = 1,     /* compressible neo-Hookean with clamped singular values
                                    (Zhu sec. 5.3 and 7, Irving et al. 2004) */
  MPM_MODEL_HENCKY_STVK = 2,     /* St. Venant-Kirchhoff in Hencky strain (Gao eq. 7) */
  MPM_MODEL_DRUCKER_PRAGER = 3,  /* Hencky elasticity + Drucker-Prager sand (Klar et al. 2016,
                                    volume correction of Tampubolon et al. 2017; Gao 4.2.1) */
  MPM_MODEL_VON_MISES = 4,       /* Hencky elasticity + von Mises plasticity (Gao 4.2.2) */
  MPM_MODEL_SNOW = 5,            /* fixed-corotated + snow plasticity (Stomakhin et al. 2013) */
  MPM_MODEL_COUNT
} mpm_model_kind;

typedef enum mpm_boundary_rule {
  MPM_BOUNDARY_STICKY = 0,   /* relative velocity set to zero */
  MPM_BOUNDARY_SLIP = 1,     /* normal relative velocity removed */
  MPM_BOUNDARY_SEPARATE = 2, /* normal relative velocity removed only when approaching */
} mpm_boundary_rule;

typedef enum mpm_shape_kind {
  MPM_SHAPE_BOX = 0,
  MPM_SHAPE_SPHERE = 1,
  MPM_SHAPE_CYLINDER = 2,
  MPM_SHAPE_MESH = 3,      /* closed triangle mesh (bodies only) */
  MPM_SHAPE_HALFSPACE = 4, /* colliders only */
  MPM_SHAPE_REVOLVE = 5,   /* solid of revolution of a profile polyline (colliders only) */
} mpm_shape_kind;

/* Most points of a revolve profile. */
#define MPM_PROFILE_MAX 32

#define MPM_STRENGTH_KEYS 16

typedef struct mpm_material_desc {
  char name[MPM_NAME_MAX];
  mpm_model_kind model;
  double E;              /* Young's modulus, Pa (> 0) */
  double nu;             /* Poisson's ratio, (-1, 0.5) */
  double density;        /* kg/m^3 (> 0) */
  double min_stretch;    /* neo-Hookean: singular values clamped below this (Zhu 5.3); (0, 1] */
  double friction_angle; /* Drucker-Prager: degrees, [0, 90); default 30 */
  double cohesion;       /* Drucker-Prager: Pa, >= 0; default 0 (dry sand) */
  double yield_stress;   /* von Mises: Pa, > 0 */
  double theta_c;        /* snow: critical compression, (0, 1); default 2.5e-2 */
  double theta_s;        /* snow: critical stretch, > 0; default 7.5e-3 */
  double hardening;      /* snow: hardening coefficient xi, >= 0; default 10 */
  /* strength schedule (Zhu Fig. 5): the moduli scaled by a factor interpolated linearly between
   * keyframes (time s, factor >= 0), held before the first and after the last; none: 1 */
  int strength_count;
  double strength[MPM_STRENGTH_KEYS][2];
  /* heat (scene `heat`; heat/heat.h) */
  double specific_heat; /* c, J/(kg K), > 0; default 1000 */
  double conductivity;  /* k, W/(m K), >= 0; default 0 (no conduction) */
  /* melting (Zhu Fig. 11, a simplified Stomakhin et al. 2014): from `melt_point` on, the shear
   * modulus falls linearly over `melt_range` degrees to melt_shear times its value, and the
   * bulk part (lambda) to melt_bulk times its value; domain particles leave their domains when
   * they pass melt_point. melting 0: none */
  int melting;
  double melt_point, melt_range, melt_shear, melt_bulk;
  int heat_keys; /* the scene gave one of the heat keys (they need `heat`) */
} mpm_material_desc;

/* A solid shape in world coordinates. Boxes and cylinders may be rotated about `axis`-free
 * Euler angles later; for now a box is axis-aligned and a cylinder's axis is any unit vector. */
typedef struct mpm_shape_desc {
  mpm_shape_kind kind;
  double center[3];      /* m */
  double half_extent[3]; /* box half sizes, m */
  double radius;         /* sphere and cylinder, m */
  double axis[3];        /* cylinder or revolve axis (unit), or half-space outward normal */
  double half_height;    /* cylinder half length along axis, m; <= 0 means infinite */
  /* mesh bodies: the file, then scale about the mesh's bounding-box centre and a translation
     that puts that centre at `center` */
  char mesh_path[MPM_PATH_MAX];
  double mesh_scale;
  double mesh_max_mb; /* the largest mesh file read, MiB (key max_file_mb; default 64) */
  double mesh_volume; /* the volume the mesh encloses once scaled, m^3 (set by the loader;
                         0: unknown) */
  double bounds_lo[3], bounds_hi[3]; /* bodies: the shape's bounding box, set by the loader */
  /* revolve: points (radius, height along axis from center), m, from the axis back to the
     axis (first and last radius 0); the solid is the region the polyline encloses with the
     axis, turned about it */
  double profile[MPM_PROFILE_MAX][2];
  int profile_count;
} mpm_shape_desc;

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
  int material;                /* index into scene.materials */
  double velocity[3];          /* initial velocity, m/s */
  double angular_velocity[3];  /* initial angular velocity about the body's centre, rad/s */
  double particles_per_cell;   /* along the volume: ppc particles per grid cell (e.g. 8) */
  double jitter;               /* 0..1 fraction of the lattice spacing */
  unsigned seed;               /* jitter seed */
  int domains;                 /* 1: particle domains (Zhu et al. 2017 sec. 4); needs jitter 0 */
  double enrichment;           /* domains: enrich where K(F) <= this (Zhu sec. 5); default 0:
                                  never (Zhu: 0.6) */
  double enrichment_exit;      /* domains: an enriched particle stays enriched while K(F) <= this
                                  (hysteresis); default 0.95, or `enrichment` when larger */
  double enrichment_hourglass; /* domains: also enrich where the hexahedron's hourglass strain
                                  is >= this (domain/enrich.h: bending K(F) does not see);
                                  default 0: never (beyond Zhu) */
  int enrichment_contact;      /* domains: enriched corners meet other material
                                  on the grid (domain/enrich_contact.h); default 0 */
  int enrichment_metric;       /* domains: 0 sigma_min / sigma_max (default), 1 the normalized
                                  Frobenius form 3 / (|F| |F^-1|) (domain/enrich.h) */
  int hourglass;               /* domains: hourglass control of the particles touching an
                                  enriched corner (0, "enriched", the default) or of every domain
                                  particle (1, "all"; domain/enrich.h) */
  int release_count;
  mpm_domain_release release[MPM_MAX_RELEASES];
  int resample;        /* domain.resample on: its particles split and merge (all bodies unless
                          domain.resample.bodies names some) */
  int has_temperature; /* `temperature` given (else the scene's heat.temperature) */
  double temperature;  /* initial temperature of its particles */
} mpm_body_desc;

typedef struct mpm_keyframe {
  double time;           /* s */
  double translation[3]; /* offset of the collider from its rest position, m */
  double angle;          /* rotation about motion.axis through the collider's centre, rad */
} mpm_keyframe;

/* Kinematic motion: pose(t) = translation(t) then rotation by angle(t) about `axis` through
 * the (moving) centre. Without keyframes translation(t) = velocity * t and
 * angle(t) = angular_speed * t. With keyframes both are piecewise linear and held constant
 * outside the keyframe span. */
typedef struct mpm_motion_desc {
  double velocity[3];   /* m/s */
  double axis[3];       /* unit rotation axis */
  double angular_speed; /* rad/s */
  int keyframe_count;
  mpm_keyframe *keyframes; /* owned by the scene; times strictly increasing */
} mpm_motion_desc;

typedef struct mpm_collider_desc {
  char name[MPM_NAME_MAX];
  mpm_shape_desc shape; /* box, sphere, cylinder or half-space (not mesh) */
  int inside_out;       /* 1: the material is kept inside the shape (containers) */
  mpm_boundary_rule rule;
  double friction; /* Coulomb coefficient >= 0 (slip and separate) */
  mpm_motion_desc motion;
  double active[2];   /* s: the collider acts while active[0] <= t < active[1] (a grip that lets
                         go); default [0, infinity) */
  int heat_source;    /* `temperature` given: grid nodes inside the solid are held at it */
  double temperature; /* a heat source's temperature (a hot plate) */
} mpm_collider_desc;

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

/* The names of output.fields, in the order of mpm_output_field; NULL-terminated. */
extern const char *const mpm_output_field_names[MPM_FIELD_COUNT + 1];

/* The arrays written when output.fields is not given: those of the files before the key
 * existed (id .. enrichment), with temperature and melt when the run has heat. */
unsigned mpm_output_fields_default(int heat);

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
mpm_status mpm_scene_parse(const char *json_text, const char *path_for_messages, mpm_scene *scene,
                           mpm_error *err);

/* Lamé parameters from E and nu. */
void mpm_lame(double E, double nu, double *mu, double *lambda);

#endif
