/* surface.c - particles to a closed triangle surface through OpenVDB (surface.h), and the
 * surface's writers. */
#define _POSIX_C_SOURCE 200809L

#include "surface/surface.h"
#include "core/alloc.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* The band's half-width in voxels when the spheres are drawn: the zero crossing needs only the
 * voxels next to it, and each particle costs (2 (r + band) + 1)^3 voxels; the band is rebuilt
 * 3 voxels wide for the filters (vdb_shim.h). */
#define SURFACE_HALF_WIDTH 2.0
/* Particles whose spacing is sampled for the median */
#define SPACING_SAMPLES 4096

static double seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

mpm_surface_params mpm_surface_params_default(void) {
  mpm_surface_params p;
  memset(&p, 0, sizeof p);
  p.smoothing = 1;
  p.filter = MPM_VDB_FILTER_MEAN_CURVATURE;
  return p;
}

void mpm_surface_mesh_free(mpm_surface_mesh *m) {
  mpm_free(m->vertices);
  mpm_free(m->triangles);
  memset(m, 0, sizeof *m);
}

double mpm_surface_face_height(double r, double s) {
  /* the face z = 0 through the outermost layer of a lattice of spacing s; the height of the
     union of the spheres of that layer and of the one below, sampled over the square
     [0, s)^2 that one particle of the face covers */
  enum { SAMPLES = 48 };
  double sum = 0;
  for (int a = 0; a < SAMPLES; ++a)
    for (int b = 0; b < SAMPLES; ++b) {
      const double x = (a + 0.5) / SAMPLES * s, y = (b + 0.5) / SAMPLES * s;
      double h = -r;
      for (int i = -2; i <= 2; ++i)
        for (int j = -2; j <= 2; ++j)
          for (int k = 0; k >= -1; --k) {
            const double dx = x - i * s, dy = y - j * s, q = r * r - dx * dx - dy * dy;
            if (q > 0) h = fmax(h, k * s + sqrt(q));
          }
      sum += h;
    }
  return sum / (SAMPLES * SAMPLES);
}

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

/* The median of cbrt(V) over an even sample of the particles. */
static double median_spacing(const double *volume, size_t n) {
  const size_t m = n < SPACING_SAMPLES ? n : SPACING_SAMPLES;
  double v[SPACING_SAMPLES];
  for (size_t k = 0; k < m; ++k) v[k] = cbrt(fmax(volume[k * n / m], 0));
  qsort(v, m, sizeof *v, cmp_double);
  return v[m / 2];
}

mpm_status mpm_surface_build(const double *xyz, const double *volume, size_t n,
                             const mpm_surface_params *p, mpm_surface_mesh *mesh,
                             mpm_vdb_grid **grid_out, mpm_surface_figures *figures,
                             mpm_error *err) {
  memset(mesh, 0, sizeof *mesh);
  if (grid_out) *grid_out = NULL;
  mpm_surface_figures fig;
  memset(&fig, 0, sizeof fig);
  fig.particles = n;
  if (figures) *figures = fig;
  if (n == 0) return MPM_OK;
  const double spacing = median_spacing(volume, n);
  const double voxel = p->voxel > 0 ? p->voxel : spacing;
  if (!(voxel > 0) || !isfinite(voxel))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "surface: the particles have no volume (median spacing %g m)", spacing);
  double *radius = mpm_alloc(n * sizeof *radius);
  if (!radius) return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory for %zu radii", n);
  double rsum = 0;
  for (size_t i = 0; i < n; ++i) {
    radius[i] = p->radius > 0 ? p->radius : MPM_SURFACE_RADIUS_SCALE * cbrt(fmax(volume[i], 0));
    rsum += radius[i];
  }
  fig.voxel = voxel;
  fig.radius_mean = rsum / (double)n;
  const double r_face = p->radius > 0 ? p->radius : MPM_SURFACE_RADIUS_SCALE * spacing;
  fig.offset = fmax(mpm_surface_face_height(r_face, spacing) - 0.5 * spacing, 0);
  char msg[512];
  mpm_vdb_grid *grid = NULL;
  mpm_status st = MPM_OK;
  double t = seconds();
  if (mpm_vdb_levelset_from_spheres(xyz, radius, n, voxel, SURFACE_HALF_WIDTH, p->threads, &grid,
                                    msg, sizeof msg) != MPM_VDB_OK) {
    st = mpm_error_set(err, MPM_ERR_INVALID, "surface: %s", msg);
    goto done;
  }
  fig.levelset_seconds = seconds() - t;
  t = seconds();
  if (mpm_vdb_smooth(grid, p->smoothing, p->filter, fig.offset, p->threads, msg, sizeof msg) !=
      MPM_VDB_OK) {
    st = mpm_error_set(err, MPM_ERR_INVALID, "surface: %s", msg);
    goto done;
  }
  fig.filter_seconds = seconds() - t;
  fig.voxels = mpm_vdb_active_voxels(grid);
  t = seconds();
  if (mpm_vdb_mesh(grid, p->threads, &mesh->vertices, &mesh->vertex_count, &mesh->triangles,
                   &mesh->triangle_count, msg, sizeof msg) != MPM_VDB_OK) {
    st = mpm_error_set(err, MPM_ERR_NOMEM, "surface: %s", msg);
    goto done;
  }
  fig.mesh_seconds = seconds() - t;
done:
  mpm_free(radius);
  if (st == MPM_OK && grid_out)
    *grid_out = grid;
  else
    mpm_vdb_grid_destroy(grid);
  if (st != MPM_OK) mpm_surface_mesh_free(mesh);
  if (figures) *figures = fig;
  return st;
}

mpm_triangle_mesh mpm_surface_mesh_view(const mpm_surface_mesh *m) {
  mpm_triangle_mesh v = {m->vertex_count, m->triangle_count, NULL,
                         m->vertices,     m->triangles,      "mpm particle surface"};
  return v;
}

mpm_status mpm_surface_write_vdb(const char *path, const mpm_vdb_grid *grid, int density,
                                 const mpm_vdb_vector_grid *velocity, mpm_error *err) {
  /* OpenVDB opens the file it writes by name: it gets a new temporary beside the final path,
     made as the atomic writers make theirs (never a planted file or link), and reaches it
     through this process's descriptor of it where /proc has one, so that the name cannot be
     swapped in between; the temporary is renamed into place on success */
  char temp[1100];
  const int fd = mpm_temp_create(path, temp, sizeof temp, err);
  if (fd < 0) return MPM_ERR_IO;
  char by_fd[64];
  snprintf(by_fd, sizeof by_fd, "/proc/self/fd/%d", fd);
  const char *target = access(by_fd, W_OK) == 0 ? by_fd : temp;
  char msg[600];
  const int wrote = mpm_vdb_write(grid, target, density, velocity, msg, sizeof msg);
  close(fd);
  if (wrote != MPM_VDB_OK) {
    remove(temp);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s' (through its temporary %s): %s", path,
                         temp, msg);
  }
  if (rename(temp, path) != 0) {
    remove(temp);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': rename failed", path);
  }
  return MPM_OK;
}
