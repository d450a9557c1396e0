/* collider_desc.h - shapes, boundary rules, kinematic motion and colliders as a scene describes
 * them (collider.h and motion.h build the runtime colliders; bodies take the shapes too). */
#ifndef MPM_COLLIDE_COLLIDER_DESC_H
#define MPM_COLLIDE_COLLIDER_DESC_H

#include "core/limits.h"

#include <stddef.h>

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

#endif
