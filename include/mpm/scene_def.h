/* scene_def.h - a scene built in code: plain description structs that mirror the JSON scene
 * format (docs/scene-format.md) key by key, Box2D-style.
 *
 * Start every struct from its _default() function, which fills each field with the default the
 * scene format gives the key it mirrors, change what the scene needs and hand the scene to
 * mpm_sim_create_from_def:
 *
 *   mpm_material_def jelly = mpm_material_def_default();
 *   jelly.name = "jelly";
 *   mpm_body_def cube = mpm_body_def_default();
 *   cube.shape.center[0] = cube.shape.center[1] = cube.shape.center[2] = 0.5;
 *   cube.shape.half_extent[0] = cube.shape.half_extent[1] = cube.shape.half_extent[2] = 0.1;
 *   mpm_scene_def def = mpm_scene_def_default();
 *   def.materials = &jelly, def.material_count = 1;
 *   def.bodies = &cube, def.body_count = 1;
 *   mpm_sim_create_from_def(&def, NULL, &sim, err, sizeof err);
 *
 * The def is turned into the scene's JSON text and loaded as mpm_sim_create_from_json loads it,
 * so every check of the scene format applies, and its messages name the field by the same path
 * as the key: "<def>: bodies[0].shape.radius: expected a number > 0 (m), got 0" is the def's
 * bodies[0].shape.radius. Fields whose JSON key is required have no default there; the def
 * either starts them from a value that makes a valid scene (said at the field) or leaves them
 * 0, which the check refuses, naming the field.
 *
 * Every quantity is a double in SI units whatever real type the library was built with. The
 * strings and arrays stay the caller's: they are read during the call only. A `const char *`
 * that is NULL leaves the key out (the format's default applies). A number that is not finite
 * is written as null, which the check reports as "got null" at the field. An object that the
 * format turns on by being there (heat, camera, output.surface, domain.resample) has an `enabled`
 * field, and its other fields must keep their defaults while it is 0; lists of bodies or
 * materials hold indices into the def's arrays. Members are only ever added at the end of a
 * struct, and a program that starts from _default() keeps working.
 *
 * Included by mpm.h; include <mpm/mpm.h>. */
#ifndef MPM_SCENE_DEF_H
#define MPM_SCENE_DEF_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Material models (materials[].model), as the format spells them.
typedef enum mpm_def_model {
  MPM_DEF_FIXED_COROTATED = 0, /* "fixed_corotated" (the default) */
  MPM_DEF_NEO_HOOKEAN = 1,     /* "neo_hookean" */
  MPM_DEF_HENCKY_STVK = 2,     /* "hencky_stvk" */
  MPM_DEF_DRUCKER_PRAGER = 3,  /* "drucker_prager": sand */
  MPM_DEF_VON_MISES = 4,       /* "von_mises": metal-like plasticity */
  MPM_DEF_SNOW = 5,            /* "snow" */
} mpm_def_model;

/// Boundary rules of walls and colliders (domain.walls.rule, colliders[].rule).
typedef enum mpm_def_rule {
  MPM_DEF_STICKY = 0,   /* "sticky": relative velocity set to zero */
  MPM_DEF_SLIP = 1,     /* "slip": normal relative velocity removed (the default) */
  MPM_DEF_SEPARATE = 2, /* "separate": removed only while approaching */
} mpm_def_rule;

/// Shapes (bodies[].shape.type, colliders[].shape.type).
typedef enum mpm_def_shape_type {
  MPM_DEF_BOX = 0,       /* "box": center, half_extent */
  MPM_DEF_SPHERE = 1,    /* "sphere": center, radius */
  MPM_DEF_CYLINDER = 2,  /* "cylinder": center, radius, axis, half_height */
  MPM_DEF_MESH = 3,      /* "mesh": file, center, scale (bodies only) */
  MPM_DEF_HALFSPACE = 4, /* "halfspace": point, normal (colliders only) */
  MPM_DEF_REVOLVE = 5,   /* "revolve": center, axis, profile (colliders and force regions) */
} mpm_def_shape_type;

/// solver.kernel
typedef enum mpm_def_kernel {
  MPM_DEF_KERNEL_LINEAR = 0,
  MPM_DEF_KERNEL_QUADRATIC = 1, /* the default */
  MPM_DEF_KERNEL_CUBIC = 2,
  MPM_DEF_KERNEL_UGIMP = 3,
} mpm_def_kernel;

/// solver.transfer
typedef enum mpm_def_transfer {
  MPM_DEF_APIC = 0, /* the default */
  MPM_DEF_FLIP = 1, /* PIC/FLIP blend with solver.flip_alpha */
} mpm_def_transfer;

/// solver.integrator
typedef enum mpm_def_integrator {
  MPM_DEF_EXPLICIT = 0, /* the default */
  MPM_DEF_IMPLICIT = 1, /* backward Euler (Zhu et al. 2017 sec. 6) */
} mpm_def_integrator;

/// solver.grid
typedef enum mpm_def_grid {
  MPM_DEF_GRID_SPARSE = 0, /* "sparse": paged blocks near the material (the default) */
  MPM_DEF_GRID_DENSE = 1,  /* "dense": every node of the domain (the reference) */
} mpm_def_grid;

/// solver.on_instability
typedef enum mpm_def_instability {
  MPM_DEF_INSTABILITY_STOP = 0,  /* "stop": the run stops with a diagnostic (the default) */
  MPM_DEF_INSTABILITY_RETRY = 1, /* "retry": the step is redone with half the dt */
} mpm_def_instability;

/// solver.on_cg_failure (implicit)
typedef enum mpm_def_cg_failure {
  MPM_DEF_CG_WARN = 0, /* "warn": keep what CG reached, counted in stats.csv (the default) */
  MPM_DEF_CG_STOP = 1, /* "stop" */
} mpm_def_cg_failure;

/// solver.preconditioner (implicit)
typedef enum mpm_def_preconditioner {
  MPM_DEF_PRECONDITIONER_JACOBI = 0,   /* "jacobi": the diagonal (the default) */
  MPM_DEF_PRECONDITIONER_MULTIGRID = 1 /* "multigrid": a Galerkin multigrid V-cycle */
} mpm_def_preconditioner;

/// solver.scheme (implicit)
typedef enum mpm_def_scheme {
  MPM_DEF_SCHEME_BACKWARD_EULER = 0, /* "backward_euler": positions by v^{n+1} (the default) */
  MPM_DEF_SCHEME_NEWMARK = 1         /* "newmark": by (v^n + v^{n+1}) / 2 (beta 1/2, gamma 1) */
} mpm_def_scheme;

/// bodies[].enrichment_metric
typedef enum mpm_def_enrichment_metric {
  MPM_DEF_METRIC_CONDITION = 0, /* "condition": sigma_min / sigma_max (the default) */
  MPM_DEF_METRIC_FROBENIUS = 1, /* "frobenius": 3 / (|F| |F^-1|) */
} mpm_def_enrichment_metric;

/// bodies[].hourglass
typedef enum mpm_def_hourglass {
  MPM_DEF_HOURGLASS_ENRICHED = 0, /* "enriched": particles touching an enriched corner (default) */
  MPM_DEF_HOURGLASS_ALL = 1,      /* "all": every domain particle */
} mpm_def_hourglass;

/// output.surface.filter
typedef enum mpm_def_surface_filter {
  MPM_DEF_FILTER_MEAN_CURVATURE = 0, /* "mean_curvature" (the default) */
  MPM_DEF_FILTER_GAUSSIAN = 1,       /* "gaussian" */
  MPM_DEF_FILTER_LAPLACIAN = 2,      /* "laplacian" */
} mpm_def_surface_filter;

/// The rule kinds of domain.refine[]: which key of the rule selects its cells.
typedef enum mpm_def_refine_kind {
  MPM_DEF_REFINE_BOX = 0,      /* "box": cells meeting box.min .. box.max */
  MPM_DEF_REFINE_COLLIDER = 1, /* "collider": cells within distance of a collider at t = 0 */
  MPM_DEF_REFINE_BODY = 2,     /* "body": cells of a body's material (distance: near its surface) */
  MPM_DEF_REFINE_SURFACE = 3,  /* "surface": rebuilds only; within `surface` of the material's
                                  surface (of `body`, or of all) */
  MPM_DEF_REFINE_TYPES = 4,    /* "types": rebuilds only; the grid follows the particle types */
  MPM_DEF_REFINE_STRAIN = 5,   /* "strain": rebuilds only; around particles strained past it */
} mpm_def_refine_kind;

/// A shape: the fields of its `type` are written, the others must keep their defaults (a box
/// given a radius is refused rather than the radius ignored).
typedef struct mpm_shape_def {
  mpm_def_shape_type type; /* shape.type; default MPM_DEF_BOX */
  double center[3];        /* shape.center, m (box, sphere, cylinder, mesh); required: default 0 */
  double half_extent[3];   /* shape.half_extent, m (box); required, > 0: default 0 (refused) */
  double radius;           /* shape.radius, m (sphere, cylinder); required, > 0: default 0 */
  double axis[3];          /* shape.axis (cylinder), any length; default +y {0, 1, 0} */
  double half_height;      /* shape.half_height, m (cylinder); bodies: required, > 0; colliders:
                              0 = infinite; default 0 */
  const char *file;        /* shape.file (mesh): OBJ or PLY, relative to base_dir; default NULL */
  double scale;            /* shape.scale (mesh), factor; default 1 */
  double point[3];         /* shape.point, m (halfspace); required key: default 0 */
  double normal[3];        /* shape.normal, outward (halfspace), any length; required key: the
                              def starts from +y {0, 1, 0} */
  /* shape.profile (revolve; `center` and `axis` too): profile_count points [radius, height
     along the axis from the centre], m, from the axis (radius 0) back to it, a simple outline
     of 3..32 points; the caller's array; required: default NULL, 0 (refused) */
  const double (*profile)[2];
  int profile_count;
  double max_file_mb; /* shape.max_file_mb (mesh): the largest mesh file read, MiB, (0, 2^20];
                         default 64 */
} mpm_shape_def;

/// A material (materials[i]). The keys of one model only (friction_angle...) are written for
/// that model; on another model they must keep their defaults (the format refuses a key that
/// would have no effect, and so does the def).
typedef struct mpm_material_def {
  const char *name;    /* materials[].name, 1..63 bytes; default NULL: "material<i>" */
  mpm_def_model model; /* materials[].model; default MPM_DEF_FIXED_COROTATED */
  /* E, nu and density are required keys: the def starts from the values of the format's
     smallest scene, so that a default material is valid */
  double E;              /* Young's modulus, Pa, > 0; default 1e5 */
  double nu;             /* Poisson's ratio, (-1, 0.5); default 0.3 */
  double density;        /* kg/m^3, > 0; default 1000 */
  double min_stretch;    /* neo_hookean: singular values clamped below it, (0, 1]; default 0.2 */
  double friction_angle; /* drucker_prager: degrees, [0, 90); default 30 */
  double cohesion;       /* drucker_prager: Pa, >= 0; default 0 */
  double yield_stress;   /* von_mises: Pa, > 0, required: default 0 (refused for von_mises) */
  double theta_c;        /* snow: critical compression, (0, 1); default 0.025 */
  double theta_s;        /* snow: critical stretch, > 0; default 0.0075 */
  double hardening;      /* snow: hardening coefficient, >= 0; default 10 */
  /* heat (the scene's heat.enabled; without it these must keep their defaults) */
  double specific_heat; /* materials[].specific_heat, J/(kg K), > 0; default 1000 */
  double conductivity;  /* materials[].conductivity, W/(m K), >= 0; default 0 (none) */
  int melting;          /* write materials[].melting (elastic models only); default 0 */
  double melt_point;    /* melting.point, the scene's temperature unit; default 0 */
  double melt_range;    /* melting.range, degrees over which the moduli fall, >= 0; default 0 */
  double melt_shear;    /* melting.shear, the melted shear modulus's share, [0, 1]; default 0.01 */
  double melt_bulk;     /* melting.bulk, the melted lambda's share, (0, 1]; default 1 */
  /* materials[].strength (Zhu Fig. 5): strength_count keyframes [time s, factor >= 0] that
     scale the moduli, linear between them and held outside; 1..16, times increasing; the
     caller's array; default NULL, 0: factor 1 */
  const double (*strength)[2];
  int strength_count;
} mpm_material_def;

/// A particle-domain release of a body (bodies[].domain_release[i]): from `time` on, its domain
/// particles inside the box continue as standard material points.
typedef struct mpm_release_def {
  double time;   /* domain_release[].time, s, >= 0; required key: default 0 */
  double min[3]; /* domain_release[].min, m; required key: default 0 */
  double max[3]; /* domain_release[].max, m, > min; required key: default 0 (refused) */
} mpm_release_def;

/// A body (bodies[i]): a shape filled with particles of one material.
typedef struct mpm_body_def {
  const char *name;    /* bodies[].name, 1..63 bytes; default NULL: "body<i>" */
  mpm_shape_def shape; /* bodies[].shape: box, sphere, cylinder or mesh */
  int material;        /* bodies[].material: index into the scene def's materials; default 0 */
  const char *material_name;  /* or by name (bodies[].material's string), when not NULL; it
                                 wins over `material`; default NULL */
  double velocity[3];         /* bodies[].velocity, m/s; default 0 */
  double angular_velocity[3]; /* bodies[].angular_velocity about the shape's centre, rad/s;
                                 default 0 */
  double particles_per_cell;  /* bodies[].particles_per_cell, (0, 1000]; default 8 */
  double jitter;              /* bodies[].jitter, fraction of the spacing, [0, 1]; default 0 */
  uint32_t seed;              /* bodies[].seed of the jitter; default 1 */
  int domains; /* bodies[].domains: particle domains (Zhu et al. 2017), needs jitter 0; 0 or 1;
                  default 0 */
  int has_temperature; /* write bodies[].temperature (needs heat); default 0: heat.temperature */
  double temperature;  /* bodies[].temperature, its particles' initial one; default 0 */
  /* particle domains' own keys (written only with domains 1; without it they must keep their
     defaults) */
  double enrichment;      /* bodies[].enrichment, K(F) at or below which a particle is enriched
                             (Zhu sec. 5; Zhu uses 0.6), [0, 1]; default 0: never */
  double enrichment_exit; /* bodies[].enrichment_exit, [enrichment, 1]; default 0: not written
                             (the format's 0.95, or enrichment when larger) */
  mpm_def_enrichment_metric enrichment_metric; /* default MPM_DEF_METRIC_CONDITION */
  const mpm_release_def *domain_release;       /* bodies[].domain_release, at most 16; the
                                                  caller's array; default NULL */
  int domain_release_count;
  mpm_def_hourglass hourglass;    /* bodies[].hourglass; default MPM_DEF_HOURGLASS_ENRICHED */
  double enrichment_hourglass;    /* bodies[].enrichment_hourglass, hourglass strain at or above
                                     which a particle is enriched (beyond Zhu), [0, 1]; default 0:
                                     never */
  int enrichment_contact;         /* bodies[].enrichment_contact: its enriched corners meet other
                                     material on the grid (beyond Zhu); 0 or 1; default 0 */
  int enrichment_surface_contact; /* bodies[].enrichment_surface_contact: its enriched surface
                                     meets enriched surfaces, other bodies' and its own (beyond
                                     Zhu); 0 or 1; default 1 */
  int enrichment_self_contact;    /* bodies[].enrichment_self_contact: its enriched surface meets
                                     its own elsewhere (beyond Zhu); 0 or 1; default 1 */
  double enrichment_exit_wait;    /* bodies[].enrichment_exit_wait: seconds an enriched particle
                                     stays relaxed before it returns to the grid (beyond Zhu),
                                     >= 0; default 0: at once */
} mpm_body_def;

/// A pose of a keyframed motion (motion.keyframes[i]).
typedef struct mpm_keyframe_def {
  double time;           /* keyframes[].time, s, >= 0, after the previous one's; required key:
                            default 0 */
  double translation[3]; /* keyframes[].translation from the rest position, m; default 0 */
  double angle;          /* keyframes[].angle about motion.axis through the centre, rad;
                            default 0 */
} mpm_keyframe_def;

/// A collider's motion (colliders[].motion, forces[].motion): constant velocity and spin, or
/// keyframes (then velocity and angular_speed must keep their defaults: the pose follows the
/// keyframes alone, linear between them and held outside).
typedef struct mpm_motion_def {
  double velocity[3];   /* motion.velocity, m/s; default 0 */
  double axis[3];       /* motion.axis of the spin through the centre, any length; default +z */
  double angular_speed; /* motion.angular_speed about axis, rad/s; default 0 */
  const mpm_keyframe_def *keyframes; /* motion.keyframes; the caller's array; default NULL */
  int keyframe_count;
} mpm_motion_def;

/// A collider (colliders[i]): a kinematic obstacle.
typedef struct mpm_collider_def {
  const char *name;      /* colliders[].name, 1..63 bytes; default NULL: "collider<i>" */
  mpm_shape_def shape;   /* colliders[].shape: box, sphere, cylinder, halfspace or revolve;
                            default MPM_DEF_HALFSPACE */
  int inside_out;        /* colliders[].inside_out: material kept inside (a container); 0 or 1;
                            default 0 */
  mpm_def_rule rule;     /* colliders[].rule; default MPM_DEF_SLIP */
  double friction;       /* colliders[].friction, Coulomb coefficient >= 0; default 0 */
  mpm_motion_def motion; /* colliders[].motion; default at rest */
  int heat_source;       /* write colliders[].temperature (needs heat): the grid nodes inside
                            its solid are held at `temperature`; default 0 */
  double temperature;    /* colliders[].temperature; default 0 */
  double active[2];      /* colliders[].active [start, end), s: it acts while start <= t < end
                            (a grip that lets go); default {0, HUGE_VAL}: always, the key left
                            out (the format has no open end: give another end a finite one) */
} mpm_collider_def;

/// A body-force region (forces[i], Zhu Fig. 9): inside the shape, which moves as a collider's
/// does and acts in its `active` window, every grid node gets `acceleration` times the
/// schedule's factor on top of gravity, and a drag of `drag` times the factor.
typedef struct mpm_force_def {
  const char *name;            /* forces[].name, 1..63 bytes; default NULL: "force<i>" */
  mpm_shape_def shape;         /* forces[].shape: box, sphere, cylinder, halfspace or revolve;
                                  default MPM_DEF_BOX */
  int inside_out;              /* forces[].inside_out: the region is outside the shape; default 0 */
  mpm_motion_def motion;       /* forces[].motion; default at rest */
  double active[2];            /* forces[].active, s, as a collider's; default {0, HUGE_VAL} */
  double acceleration[3];      /* forces[].acceleration, m/s^2; default 0 */
  const double (*schedule)[2]; /* forces[].schedule: schedule_count keyframes [time s, factor],
                                  1..16, as a material's strength; default NULL, 0: factor 1 */
  int schedule_count;
  double drag; /* forces[].drag, 1/s, [0, 1e6]: dv/dt = -drag v inside; default 0, not written */
} mpm_force_def;

/// domain.walls
typedef struct mpm_walls_def {
  mpm_def_rule rule; /* walls.rule; default MPM_DEF_SLIP */
  double friction;   /* walls.friction, >= 0; default 0 */
  int cells;         /* walls.cells, band depth in cells, 2..16; default 3 */
} mpm_walls_def;

/// A refinement rule of the multi-level grid (domain.refine[i]; docs/adaptive-grid.md). The
/// fields of its kind are written, the others must keep their defaults.
typedef struct mpm_refine_def {
  mpm_def_refine_kind kind; /* the rule's selecting key; default MPM_DEF_REFINE_BOX */
  int level;                /* refine[].level, 1 .. levels - 1; required key: default 1 */
  struct {
    double min[3], max[3];   /* box.min, box.max, m, max > min; default 0 (refused) */
  } box;                     /* box; a body rule's within (default 0: all of the body) */
  int collider;              /* collider: index into the def's colliders; default -1: none (a
                                collider rule needs it or collider_name) */
  const char *collider_name; /* collider, by name (wins over the index); default NULL */
  int body;                  /* body (body rule, required) or surface rule's body: index into
                                the def's bodies; default -1: none (a surface rule: all) */
  const char *body_name;     /* body, by name (wins over the index); default NULL */
  double distance;           /* distance, m: collider (>= 0), body (> 0; 0: not written, all
                                of it), types and strain (>= 0); default 0 */
  double surface;            /* surface: the band on both sides of the surface, m, > 0;
                                default 0 (refused for a surface rule) */
  double strain;             /* strain: the threshold on ||F - I||, > 0; default 0 (refused) */
} mpm_refine_def;

/// Particle resampling on the multi-level grid (domain.resample; Gao et al. 2017 sec. 7.2).
typedef struct mpm_resample_def {
  int enabled;         /* write domain.resample (needs levels >= 2); default 0 */
  int split;           /* resample.split; default 1 */
  int merge;           /* resample.merge; default 1 */
  int every;           /* resample.every, steps, 1..1e6; default 1 */
  double merge_margin; /* resample.merge_margin, cells of the merged type's level, [0, 8];
                          default 1 */
  int max_per_cell;    /* resample.max_per_cell (0: 2 x particles_per_cell); default 0 */
  int min_per_cell;    /* resample.min_per_cell (0: 4 x particles_per_cell); default 0 */
  const int *bodies;   /* resample.bodies: indices into the def's bodies; the caller's array;
                          default NULL, 0: every body */
  int body_count;
  uint32_t seed; /* resample.seed of the split cubes' orientations; default 0 */
} mpm_resample_def;

/// domain (the box and the grid). min, max and dx are required keys: the def starts from the
/// unit box at 64 cells, so that a default domain is valid.
typedef struct mpm_domain_def {
  double min[3];       /* domain.min, m; default 0 */
  double max[3];       /* domain.max, m, > min + 8 dx; default {1, 1, 1} */
  double dx;           /* domain.dx, the cell size, m, > 0; default 1/64 */
  mpm_walls_def walls; /* domain.walls */
  int resolution;      /* domain.resolution, cells along the longest axis, written instead of
                          dx (which must then keep its default); default 0: dx */
  /* the multi-level grid (Gao et al. 2017; docs/adaptive-grid.md): it needs solver.kernel
     MPM_DEF_KERNEL_UGIMP (the format's default there, but the def's kernel is always written) */
  int levels;                   /* domain.levels, 1..6; default 0: the uniform grid */
  const mpm_refine_def *refine; /* domain.refine; the caller's array; default NULL */
  int refine_count;
  mpm_resample_def resample; /* domain.resample */
  int refine_every;          /* domain.refine_every, steps between rebuilds (0: none); default 0 */
} mpm_domain_def;

/// time
typedef struct mpm_time_def {
  double end; /* time.end, s, > 0; required key: default 1 */
  double fps; /* time.fps, frames per second, > 0; default 24 */
} mpm_time_def;

/// solver (the keys of the implicit integrator are written only with MPM_DEF_IMPLICIT; with the
/// explicit one they must keep their defaults)
typedef struct mpm_solver_def {
  mpm_def_integrator integrator;      /* solver.integrator; default MPM_DEF_EXPLICIT */
  mpm_def_kernel kernel;              /* solver.kernel; default MPM_DEF_KERNEL_QUADRATIC */
  mpm_def_transfer transfer;          /* solver.transfer; default MPM_DEF_APIC */
  double flip_alpha;                  /* solver.flip_alpha, FLIP share, [0, 1]; default 0.95 */
  double cfl;                         /* solver.cfl, (0, 1]; default 0.4 */
  double max_dt;                      /* solver.max_dt, s, >= 0 (0: no bound); default 0 */
  double dt;                          /* implicit: solver.dt, a fixed step, s (0: CFL); default 0 */
  int newton_iterations;              /* implicit: solver.newton_iterations, 1..100; default 2 */
  mpm_def_grid grid;                  /* solver.grid; default MPM_DEF_GRID_SPARSE */
  double gimp_length;                 /* solver.gimp_length, uGIMP's particle box side, m, [0, 2 dx]
                                         (0: automatic); default 0 */
  mpm_def_instability on_instability; /* solver.on_instability; default MPM_DEF_INSTABILITY_STOP */
  int max_retries;                    /* solver.max_retries, halvings of dt, 1..30; default 8 */
  mpm_def_kernel domain_kernel;       /* solver.domain_kernel, corner weights of particle domains:
                                         linear, quadratic or cubic; default linear */
  double cg_tolerance;   /* implicit: solver.cg_tolerance, (0, 1); default 0: automatic, the
                            key left out */
  int cg_max_iterations; /* implicit: solver.cg_max_iterations, 1..100000; default 500 */
  mpm_def_cg_failure on_cg_failure; /* implicit: solver.on_cg_failure; default MPM_DEF_CG_WARN */
  mpm_def_preconditioner preconditioner; /* implicit: solver.preconditioner; default
                                            MPM_DEF_PRECONDITIONER_JACOBI */
  mpm_def_scheme scheme; /* implicit: solver.scheme; default MPM_DEF_SCHEME_BACKWARD_EULER */
} mpm_solver_def;

/// The point arrays of frame_NNNN.vtu (output.fields, docs/scene-format.md): bit (1u << f) of
/// mpm_output_def.fields for each one written.
typedef enum mpm_def_field {
  MPM_DEF_FIELD_ID = 0,
  MPM_DEF_FIELD_VELOCITY = 1,
  MPM_DEF_FIELD_MASS = 2,
  MPM_DEF_FIELD_VOLUME = 3,
  MPM_DEF_FIELD_J = 4,
  MPM_DEF_FIELD_STRESS = 5, /* von Mises equivalent stress */
  MPM_DEF_FIELD_PLASTIC = 6,
  MPM_DEF_FIELD_MATERIAL = 7,
  MPM_DEF_FIELD_BODY = 8,
  MPM_DEF_FIELD_LEVEL = 9,
  MPM_DEF_FIELD_ENRICHMENT = 10,
  MPM_DEF_FIELD_TEMPERATURE = 11, /* needs heat */
  MPM_DEF_FIELD_MELT = 12,        /* needs heat */
  MPM_DEF_FIELD_CAUCHY_STRESS = 13,
  MPM_DEF_FIELD_PRESSURE = 14,
  MPM_DEF_FIELD_F = 15,
} mpm_def_field;

/// heat (heat transfer and melting; docs/scene-format.md "heat")
typedef struct mpm_heat_def {
  int enabled;        /* write the scene's heat object: heat transfer on; default 0 */
  double temperature; /* heat.temperature, the bodies' initial one where they give none;
                         default 0 */
  double pic;         /* heat.pic, the rate at which the particles' temperatures relax to the
                         grid's, in units of 4 alpha / dx^2, [0, 100]; default 1 */
} mpm_heat_def;

/// output.surface: a triangle surface per frame from the particles of some bodies or materials
/// (needs OpenVDB when it is written). Bodies and materials are given by index.
typedef struct mpm_surface_def {
  int enabled;          /* write output.surface; default 0 */
  const int *bodies;    /* surface.bodies: indices into the def's bodies; the caller's array;
                           default NULL, 0: every body */
  int body_count;       /* at most 32 */
  const int *materials; /* surface.materials: indices into the def's materials (not with
                           bodies); default NULL, 0 */
  int material_count;   /* at most 32 */
  double voxel;         /* surface.voxel, cells, 0 or [0.05, 4] (0: the particle spacing);
                           default 0 */
  double radius;        /* surface.radius, cells, [0, 8] (0: from the volume); default 0 */
  int smoothing;        /* surface.smoothing, filter passes, 0..20; default 1 */
  mpm_def_surface_filter filter; /* surface.filter; default MPM_DEF_FILTER_MEAN_CURVATURE */
  int per_body;                  /* surface.per_body: one file per body; default 0 */
} mpm_surface_def;

/// output (what mpm_sim_enable_output writes)
typedef struct mpm_output_def {
  const char *directory;   /* output.directory; default "out" */
  int vtu;                 /* output.vtu: frame_NNNN.vtu and frames.pvd; default 1 */
  int ply;                 /* output.ply: frame_NNNN.ply points; default 0 */
  int stats;               /* output.stats: stats.csv; default 1 */
  int checkpoint_every;    /* output.checkpoint_every, frames (0: only on a signal); default 10 */
  unsigned fields;         /* output.fields: bit (1u << mpm_def_field) per array; default 0, the
                              format's default set (id .. enrichment, with heat temperature and
                              melt) */
  mpm_surface_def surface; /* output.surface */
  int vdb;                 /* output.vdb: the surface's level set as .vdb (needs surface);
                              default 0 */
  int vdb_density;         /* output.vdb_density: a density grid beside it (needs surface);
                              default 0 */
  int vdb_velocity;        /* output.vdb_velocity: a velocity grid beside it (needs surface);
                              default 0 */
} mpm_output_def;

/// camera (the view of `mpm render`; without it the renderer frames the domain)
typedef struct mpm_camera_def {
  int enabled;      /* write camera; default 0 */
  double eye[3];    /* camera.eye, m; required key: default 0 */
  double target[3]; /* camera.target, m, not the eye; required key: default 0 (refused) */
  double fov;       /* camera.fov, vertical, degrees, (1, 170); default 35 */
} mpm_camera_def;

/// A whole scene. The arrays are the caller's (read during the call only); a count of 0 with a
/// NULL array is an empty list. A scene needs at least one body.
typedef struct mpm_scene_def {
  const char *name; /* name, 1..63 bytes; default NULL: the scene is named "<json>" as
                       mpm_sim_create_from_json names it */
  mpm_domain_def domain;
  double gravity[3]; /* gravity, m/s^2; default {0, -9.81, 0} */
  mpm_time_def time;
  mpm_solver_def solver;
  const mpm_material_def *materials; /* materials */
  int material_count;
  const mpm_body_def *bodies; /* bodies */
  int body_count;
  const mpm_collider_def *colliders; /* colliders */
  int collider_count;
  mpm_output_def output;
  mpm_heat_def heat;
  const mpm_force_def *forces; /* forces: body-force regions */
  int force_count;
  mpm_camera_def camera;
} mpm_scene_def;

/// The defaults of each struct (the scene format's defaults for the keys they mirror).
MPM_API mpm_scene_def mpm_scene_def_default(void);
MPM_API mpm_material_def mpm_material_def_default(void);
MPM_API mpm_body_def mpm_body_def_default(void);
MPM_API mpm_collider_def mpm_collider_def_default(void);
MPM_API mpm_force_def mpm_force_def_default(void);
MPM_API mpm_keyframe_def mpm_keyframe_def_default(void);
MPM_API mpm_release_def mpm_release_def_default(void);
MPM_API mpm_refine_def mpm_refine_def_default(void);
/// A shape's defaults are those of the body's (MPM_DEF_BOX) and the collider's
/// (MPM_DEF_HALFSPACE) _default(); this gives them for any type.
MPM_API mpm_shape_def mpm_shape_def_default(mpm_def_shape_type type);

/// Build the simulation of a def: the same scene, checks and simulation as mpm_sim_create_from_json
/// makes from the def's JSON text (mpm_scene_def_to_json), with no text parsed on the way (the
/// def's JSON tree is checked as a file's is): mesh files resolve against `base_dir` (NULL: the
/// current directory), and messages name the scene "<def>" (inside base_dir when given) and the
/// field by its path. The def is not kept. On failure *out is NULL and err (of errlen bytes, may be
/// NULL) holds the message: MPM_ERR_INVALID for a NULL def, a NULL array with a nonzero count, a
/// negative count, an enum value out of range, a material index out of range, a name longer
/// than 63 bytes, a field that would have no effect (said at each struct) or an `active` window
/// with an open end, and the format's own status for everything the scene check refuses.
MPM_API mpm_status mpm_sim_create_from_def(const mpm_scene_def *def, const char *base_dir,
                                           mpm_sim **out, char *err, size_t errlen);

/// The def as the text of a scene file (JSON, indented), to save it or to read it back with
/// mpm_sim_create_from_file or mpm_sim_create_from_json. Only the def's own checks run here
/// (those listed at mpm_sim_create_from_def before "and the format's"), not the scene check.
/// On success *json_out is a NUL-terminated string the caller frees with mpm_free_string; on
/// failure it is NULL and err holds the message.
MPM_API mpm_status mpm_scene_def_to_json(const mpm_scene_def *def, char **json_out, char *err,
                                         size_t errlen);

/// Free a string the library allocated for the caller (mpm_scene_def_to_json's); NULL is fine.
MPM_API void mpm_free_string(char *s);

#ifdef __cplusplus
}
#endif
#endif
