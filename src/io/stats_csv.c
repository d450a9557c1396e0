/* stats_csv.c - per-frame diagnostics (energies, momenta, mass, timing) as a CSV table.
 *
 * One header line and one row per frame, comma separated, no quoting needed (all fields are
 * numbers). Times and energies use %.9g; mass and the linear and angular momenta use %.17g so
 * that conservation checks read back the exact doubles. The caller keeps the rows and the
 * whole file is rewritten atomically after each frame.
 *
 * Columns are only ever added at the end of the row (readers such as `mpm plot` find the
 * older ones at their old places): dt_min, dt_max, gravitational_energy and total_energy came
 * after enriched_percent, and the colliders' forces (three per collider, as many as the scene
 * has: none, and the file is what it was) after total_energy. */
#include "io/io.h"

#include <errno.h>
#include <string.h>

static const char stats_header[] =
    "frame,time,steps,dt,kinetic_energy,elastic_energy,momentum_x,momentum_y,momentum_z,"
    "angular_momentum_x,angular_momentum_y,angular_momentum_z,mass,particles,wall_seconds,"
    "cg_iterations_mean,cg_iterations_max,cg_residual_max,newton_iterations_mean,"
    "cg_unconverged,enriched_percent,dt_min,dt_max,gravitational_energy,total_energy";

/* The collider columns of the header, or of one row, then the line's end. */
static int put_colliders(FILE *fp, int colliders, const double *forces) {
  static const char axis[3] = {'x', 'y', 'z'};
  for (int c = 0; c < colliders; ++c)
    for (int e = 0; e < 3; ++e)
      if ((forces ? fprintf(fp, ",%.9g", forces[3 * c + e])
                  : fprintf(fp, ",collider%d_f%c", c, axis[e])) < 0)
        return -1;
  return fputc('\n', fp) == EOF ? -1 : 0;
}

mpm_status mpm_write_stats_csv(const char *path, int count, const mpm_stats_row *rows,
                               mpm_error *err) {
  return mpm_write_stats_csv_forces(path, count, rows, 0, NULL, err);
}

mpm_status mpm_write_stats_csv_forces(const char *path, int count, const mpm_stats_row *rows,
                                      int colliders, const double *forces, mpm_error *err) {
  if (count < 0)
    return mpm_error_set(err, MPM_ERR_INVALID, "cannot write '%s': negative row count %d", path,
                         count);
  mpm_atomic_file af;
  const mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) return st;
  int werr = 0;
  errno = 0;
  if (fputs(stats_header, af.fp) == EOF || put_colliders(af.fp, colliders, NULL))
    werr = errno ? errno : EIO;
  for (int i = 0; i < count && !werr; ++i) {
    const mpm_stats_row *r = &rows[i];
    errno = 0;
    if (fprintf(af.fp,
                "%d,%.9g,%lld,%.9g,%.9g,%.9g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%zu,"
                "%.9g,%.6g,%d,%.6g,%.6g,%lld,%.6g,%.9g,%.9g,%.9g,%.9g",
                r->frame, r->time, r->steps, r->dt, r->kinetic, r->elastic, r->momentum[0],
                r->momentum[1], r->momentum[2], r->angular_momentum[0], r->angular_momentum[1],
                r->angular_momentum[2], r->mass, r->particles, r->wall_seconds,
                r->cg_iterations_mean, r->cg_iterations_max, r->cg_residual_max,
                r->newton_iterations_mean, r->cg_unconverged, r->enriched_percent, r->dt_min,
                r->dt_max, r->gravitational, r->total_energy) < 0 ||
        put_colliders(af.fp, colliders, forces ? forces + 3 * (size_t)i * (size_t)colliders : NULL))
      werr = errno ? errno : EIO;
  }
  if (werr) {
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(werr));
  }
  return mpm_atomic_commit(&af, err);
}
