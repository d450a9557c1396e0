/* sample.h - filling a body's shape with material points on a grid-aligned lattice.
 *
 * Particles of a body sit on a regular lattice of spacing h = dx / cbrt(particles_per_cell)
 * whose points are box_min + (k + 1/2) h, so that with an integer cube root every grid cell
 * holds the same number of points. Points inside the shape (box, sphere, capped cylinder,
 * closed triangle mesh) are kept; each carries volume h^3 and mass density h^3. */
#ifndef MPM_SCENE_SAMPLE_H
#define MPM_SCENE_SAMPLE_H

#include "core/error.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "core/particles.h"

/// Lattice spacing of bodies[body_index]: scene->dx / cbrt(particles_per_cell), m.
double mpm_sample_spacing(const mpm_scene *scene, int body_index);

/// Append the particles of scene->bodies[body_index] to p.
///
/// A lattice point is kept when it lies inside the shape (before jitter; boundaries count as
/// inside for the analytic shapes). Mesh shapes: shape.mesh_path is read (a relative path is
/// tried against the scene file's folder first, then as given), scaled by shape.mesh_scale
/// about its bounding-box centre and moved so that centre is at shape.center; inside means odd
/// parity of exact crossings along the lattice column (x ray), with a generalized winding
/// number fallback on columns whose crossing count is odd (meshes with holes).
/// With body.jitter > 0 each point moves by a uniform offset in [-jitter h/2, jitter h/2]^3
/// drawn from a generator seeded by body.seed alone (same seed, same particles).
/// Per particle: vol0 = h^3, mass = density h^3, F = I, C = 0,
/// v = body.velocity + angular_velocity x (x - c) with c the centroid of the body's particles,
/// material = body.material, body = body_index.
///
/// Errors (nothing is appended): no point inside the shape (MPM_ERR_INVALID, names bodies[i]
/// and suggests a smaller dx or more particles_per_cell), a kept point whose lattice cell is
/// outside the domain (MPM_ERR_INVALID), invalid shape parameters, and mesh loading errors
/// (MPM_ERR_IO / MPM_ERR_PARSE, naming the mesh file and line). body_index must be valid.
mpm_status mpm_sample_body(const mpm_scene *scene, int body_index, mpm_particles *p,
                           mpm_error *err);

/* Which lattice points a sampling keeps: keep(ctx, x) on a point's position before jitter. */
typedef int (*mpm_sample_keep_fn)(const void *ctx, const double x[3]);

/* mpm_sample_body on the lattice of spacing `scale` times the body's (mass and volume per
 * particle scaled with it), keeping the points `keep` accepts: the multi-level grid samples each
 * level's leaves at that level's spacing (Gao et al. sec. 7.1). No point kept is not an error
 * here, and the body's angular velocity is not applied (mpm_sample_spin does it over all the
 * levels' particles). */
mpm_status mpm_sample_body_kept(const mpm_scene *scene, int body_index, double scale,
                                mpm_sample_keep_fn keep, const void *ctx, mpm_particles *p,
                                mpm_error *err);

/* The body's rigid rotation (bodies[].angular_velocity) about the centroid of particles
 * start .. p->count, added to their velocities. */
void mpm_sample_spin(const mpm_scene *scene, int body_index, mpm_particles *p, size_t start);

/// The triangle mesh of a mesh body, in world coordinates (scaled and placed as the sampler
/// places it). The caller frees it with mpm_mesh_free.
mpm_status mpm_sample_body_mesh(const mpm_scene *scene, int body_index, mpm_mesh *mesh,
                                mpm_error *err);

/* The file a mesh body reads: an absolute mesh_path as given; a relative one against the scene
 * file's folder when a file is there, else as given (against the working directory). */
void mpm_scene_mesh_file(const mpm_scene *scene, const char *mesh_path, char *out, size_t size);

#endif
