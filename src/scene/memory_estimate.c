/* memory_estimate.c - how much memory a scene will need, and whether the machine has it, so
 * that a scene too large for the machine is refused before anything is allocated. */
#include "scene/memory_estimate.h"

#include "grid/dofs.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Bytes per particle: the particle arrays (x, its compensation xc, v, F, B: 27 reals; mass,
 * vol0, plastic, temperature: 4 reals; material, body, level, id: 4 x 4 bytes), the sort's
 * permutation, keys and scratch (about 16 bytes), and the sparse grid blocks the particles
 * occupy (about 20% on top for 8 particles per cell). Measured: 157 bytes per particle in the
 * float build before xc and temperature (docs/performance.md, `mpm bench step`). */
#define BYTES_PER_PARTICLE (1.2 * (31.0 * (double)sizeof(mpm_real) + 16 + 16))

/* The implicit step's scratch per particle: the factored stress derivative (30 reals), F at the
 * displacement (9), the gathered gradients and the diagonal's quadratic forms (18); and per DOF
 * (about 0.2 per particle at 8 particles per cell) the solver's ten 3-vectors, positions and
 * wall depths (34 reals). */
#define IMPLICIT_BYTES_PER_PARTICLE ((57.0 + 0.2 * 34.0) * (double)sizeof(mpm_real))

/* Expected particle count of one body: its volume over the lattice cell. Meshes count the
 * volume they enclose (the loader measured it; half their bounding box when it did not);
 * analytic shapes their exact volume. */
static double body_particles(const mpm_scene *s, int b) {
  const mpm_body_desc *body = &s->bodies[b];
  const mpm_shape_desc *sh = &body->shape;
  const double pi = 3.14159265358979323846;
  double v = 0;
  switch (sh->kind) {
  case MPM_SHAPE_BOX:
    v = 8 * sh->half_extent[0] * sh->half_extent[1] * sh->half_extent[2];
    break;
  case MPM_SHAPE_SPHERE:
    v = 4.0 / 3.0 * pi * sh->radius * sh->radius * sh->radius;
    break;
  case MPM_SHAPE_CYLINDER:
    v = pi * sh->radius * sh->radius * 2 * sh->half_height;
    break;
  default:
    v = sh->mesh_volume > 0
            ? sh->mesh_volume
            : 0.5 * (sh->bounds_hi[0] - sh->bounds_lo[0]) * (sh->bounds_hi[1] - sh->bounds_lo[1]) *
                  (sh->bounds_hi[2] - sh->bounds_lo[2]);
    break;
  }
  return v / (s->dx * s->dx * s->dx) * body->particles_per_cell;
}

/* Reals per DOF with every field of the DOF set (mass, v0, v, f). */
#define DOF_REALS 10

/* Nodes of the dense reference grid (solver.grid = dense), 0 for the sparse grid. */
static double dense_nodes(const mpm_scene *s) {
  if (s->solver.grid != MPM_GRID_DENSE) return 0;
  double n = 1;
  for (int d = 0; d < 3; ++d) n *= (s->box_max[d] - s->box_min[d]) / s->dx + 4;
  return n;
}

static double bytes_per_particle(const mpm_scene *s) {
  return BYTES_PER_PARTICLE +
         (s->solver.integrator == MPM_INTEGRATOR_IMPLICIT ? IMPLICIT_BYTES_PER_PARTICLE : 0);
}

double mpm_scene_memory_for(const mpm_scene *s, double particles) {
  return particles * bytes_per_particle(s) + dense_nodes(s) * DOF_REALS * sizeof(mpm_real) +
         64.0 * 1024 * 1024; /* plus the program itself */
}

double mpm_scene_memory_estimate(const mpm_scene *s, double *particles) {
  double n = 0;
  for (int b = 0; b < s->body_count; ++b) n += body_particles(s, b);
  if (particles) *particles = n;
  return mpm_scene_memory_for(s, n);
}

/* MPM_MEMORY_LIMIT's value in bytes: a positive number with an optional K, M or G suffix
 * (powers of 1024); -1 when it is anything else. */
static double parse_limit(const char *env) {
  char *end;
  double v = strtod(env, &end);
  if (end == env || !(v > 0) || !isfinite(v)) return -1;
  const char u = *end;
  if (u == 'K' || u == 'k')
    v *= 1024, ++end;
  else if (u == 'M' || u == 'm')
    v *= 1024.0 * 1024, ++end;
  else if (u == 'G' || u == 'g')
    v *= 1024.0 * 1024 * 1024, ++end;
  if (*end == 'B' || *end == 'b') ++end; /* 20MB, 4GB */
  return *end ? -1 : v;
}

/* MPM_MEMORY_LIMIT (bytes, with an optional K, M or G suffix) if set, else MemAvailable from
 * /proc/meminfo, else the physical memory; 0 when none is known (a malformed variable counts
 * as unset here: mpm_scene_check_memory reports it). */
double mpm_available_memory(void) {
  const char *env = getenv("MPM_MEMORY_LIMIT");
  if (env && *env) {
    const double v = parse_limit(env);
    if (v > 0) return v;
  }
  FILE *f = fopen("/proc/meminfo", "r");
  if (f) {
    char line[256];
    double kb = 0;
    while (fgets(line, sizeof line, f))
      if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1) break;
    fclose(f);
    if (kb > 0) return kb * 1024;
  }
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
  return pages > 0 && size > 0 ? (double)pages * (double)size : 0;
}

/* bytes as "20 MiB", "1.5 GiB" (three significant digits, never rounded to 0) */
static const char *human_bytes(double b, char *buf, size_t cap) {
  static const char *const unit[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024 && u < 4) b /= 1024, ++u;
  snprintf(buf, cap, "%.3g %s", b, unit[u]);
  return buf;
}

mpm_status mpm_scene_check_memory(const mpm_scene *s, mpm_error *err) {
  double n;
  mpm_scene_memory_estimate(s, &n);
  return mpm_scene_check_memory_for(s, n, err);
}

mpm_status mpm_scene_check_memory_for(const mpm_scene *s, double n, mpm_error *err) {
  const char *env = getenv("MPM_MEMORY_LIMIT");
  if (env && *env && parse_limit(env) < 0)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "MPM_MEMORY_LIMIT: expected a positive number of bytes with an optional "
                         "K, M or G suffix (e.g. 512M, 4G), got '%.64s'",
                         env);
  const double need = mpm_scene_memory_for(s, n), have = mpm_available_memory();
  if (have > 0 && need > have) {
    const double dense = dense_nodes(s);
    char grid[160] = "", need_s[32], have_s[32], dense_s[32];
    if (dense > 0)
      snprintf(grid, sizeof grid, ", and a dense grid (solver.grid) of %.3g nodes: %s", dense,
               human_bytes(dense * DOF_REALS * sizeof(mpm_real), dense_s, sizeof dense_s));
    const int limited = env && *env;
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: the scene needs about %s (%.3g particles at about %.0f bytes "
                         "each%s) but %s %s; use a larger dx, fewer particles_per_cell, "
                         "smaller bodies%s%s",
                         s->path[0] ? s->path : "scene", human_bytes(need, need_s, sizeof need_s),
                         n, bytes_per_particle(s), grid,
                         limited ? "MPM_MEMORY_LIMIT allows" : "this machine has available",
                         human_bytes(have, have_s, sizeof have_s),
                         s->levels > 1 ? ", fewer refined cells" : "",
                         dense > 0 ? ", or the sparse grid" : "");
  }
  return MPM_OK;
}
