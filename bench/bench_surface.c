/* bench_surface.c - `mpm bench surface`: the cost of one frame's particle surface
 * (output.surface, src/surface) for about N particles (default 1M) on a lattice of spacing
 * 1 cm (8 per cell of 2 cm), shaped as a cube and as a sphere with 10% jitter: seconds for the
 * level set (ParticlesToLevelSet), the filter (rebuild, smoothing, offset), the mesh
 * (volumeToMesh), the OBJ + PLY writers and the velocity grid of output.vdb_velocity (serial), per
 * thread count. Figures printed, never asserted. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */

#include "bench.h"
#include "bench_util.h"
#include "core/parallel.h"
#include "surface/surface.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* About n particles of spacing s in a cube (sphere = 0) or a ball (1), jittered by `jitter` s. */
static size_t sample(int sphere, size_t n, double s, double jitter, double **xyz, double **vol) {
  const double side = cbrt((double)n * (sphere ? 6 / 3.14159265358979323846 : 1));
  const int m = (int)ceil(side / 2) + 1;
  const size_t cap = (size_t)(2 * m) * (size_t)(2 * m) * (size_t)(2 * m);
  *xyz = malloc(3 * cap * sizeof **xyz);
  *vol = malloc(cap * sizeof **vol);
  if (!*xyz || !*vol) return 0;
  uint64_t state = 0x9e3779b97f4a7c15ull;
  size_t k = 0;
  const double R = side / 2;
  for (int i = -m; i < m; ++i)
    for (int j = -m; j < m; ++j)
      for (int l = -m; l < m; ++l) {
        const double p[3] = {i + 0.5, j + 0.5, l + 0.5};
        if (sphere ? p[0] * p[0] + p[1] * p[1] + p[2] * p[2] >= R * R
                   : fabs(p[0]) > R || fabs(p[1]) > R || fabs(p[2]) > R)
          continue;
        for (int d = 0; d < 3; ++d) {
          state ^= state >> 12, state ^= state << 25, state ^= state >> 27;
          const double u = (double)((state * 0x2545f4914f6cdd1dull) >> 11) / 9007199254740992.0;
          (*xyz)[3 * k + (size_t)d] = s * (p[d] + jitter * (u - 0.5));
        }
        (*vol)[k++] = s * s * s;
      }
  return k;
}

int mpm_bench_surface(int argc, char **argv) {
  long n = 1000000;
  int threads[16] = {0}, nthreads = 0, smoothing = 1;
  for (int i = 0; i < argc; ++i) {
    if (!strcmp(argv[i], "--particles") && i + 1 < argc) {
      n = atol(argv[++i]);
      if (n < 1000 || n > 100000000) {
        fprintf(stderr, "mpm bench surface: --particles expects 1000 .. 1e8\n");
        return 2;
      }
    } else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      nthreads = bench_parse_threads(argv[++i], threads, 16);
      if (nthreads < 0) {
        fprintf(stderr, "mpm bench: --threads expects a list like 1,2\n");
        return 2;
      }
    } else if (!strcmp(argv[i], "--smoothing") && i + 1 < argc) {
      smoothing = atoi(argv[++i]);
    } else {
      fprintf(stderr,
              "mpm bench surface: unknown option '%s' (--particles N, --threads LIST, "
              "--smoothing PASSES)\n",
              argv[i]);
      return 2;
    }
  }
  if (nthreads <= 0) threads[0] = mpm_thread_count(), nthreads = 1;
  bench_print_machine();
  const double s = 0.01;
  printf("surface benchmark: about %ld particles, spacing %g m, voxel = spacing, radius = %g "
         "spacing, %d mean-curvature pass%s\n",
         n, s, MPM_SURFACE_RADIUS_SCALE, smoothing, smoothing == 1 ? "" : "es");
  char dir[] = "/tmp/mpm-bench-surface-XXXXXX";
  const int have_dir = mkdtemp(dir) != NULL;
  for (int shape = 0; shape < 2; ++shape) {
    double *xyz = NULL, *vol = NULL;
    const size_t count = sample(shape, (size_t)n, s, shape ? 0.1 : 0, &xyz, &vol);
    if (!count) {
      fprintf(stderr, "mpm bench surface: out of memory for %ld particles\n", n);
      free(xyz), free(vol);
      return 1;
    }
    /* a spin about the vertical axis, for the velocity grid */
    double *vel = malloc(3 * count * sizeof *vel), *mass = malloc(count * sizeof *mass);
    if (!vel || !mass) {
      fprintf(stderr, "mpm bench surface: out of memory for %zu velocities\n", count);
      free(xyz), free(vol), free(vel), free(mass);
      return 1;
    }
    for (size_t i = 0; i < count; ++i) {
      vel[3 * i] = -xyz[3 * i + 2], vel[3 * i + 1] = 0, vel[3 * i + 2] = xyz[3 * i];
      mass[i] = 1000 * vol[i];
    }
    for (int t = 0; t < nthreads; ++t) {
      mpm_surface_params p = mpm_surface_params_default();
      p.smoothing = smoothing;
      p.threads = threads[t];
      mpm_surface_mesh mesh;
      mpm_surface_figures f;
      mpm_error err;
      mpm_error_clear(&err);
      const double t0 = now();
      if (mpm_surface_build(xyz, vol, count, &p, &mesh, NULL, &f, &err) != MPM_OK) {
        fprintf(stderr, "mpm bench surface: %s\n", err.message);
        free(xyz), free(vol);
        return 1;
      }
      const double built = now() - t0;
      double write = 0;
      if (have_dir) {
        char path[128];
        const double w0 = now();
        snprintf(path, sizeof path, "%s/surface.obj", dir);
        const mpm_triangle_mesh view = mpm_surface_mesh_view(&mesh);
        mpm_write_mesh_obj(path, &view, &err);
        snprintf(path, sizeof path, "%s/surface.ply", dir);
        mpm_write_mesh_ply(path, &view, &err);
        write = now() - w0;
        unlink(path);
        snprintf(path, sizeof path, "%s/surface.obj", dir);
        unlink(path);
      }
      const double v0 = now();
      mpm_vdb_vector_grid *velocity = NULL;
      char msg[512];
      if (mpm_vdb_velocity_from_particles(xyz, vel, mass, count, f.voxel, &velocity, msg,
                                          sizeof msg) != MPM_VDB_OK) {
        fprintf(stderr, "mpm bench surface: %s\n", msg);
        mpm_surface_mesh_free(&mesh);
        free(xyz), free(vol), free(vel), free(mass);
        return 1;
      }
      const double velocity_seconds = now() - v0;
      const unsigned long long velocity_voxels = mpm_vdb_vector_active_voxels(velocity);
      mpm_vdb_vector_grid_destroy(velocity);
      printf("%-6s %zu particles, %d threads: level set %.2f s, filter %.2f s, mesh %.2f s "
             "(%.2f s in all; %llu voxels, %zu triangles); OBJ + PLY %.2f s; velocity grid "
             "%.2f s (%llu voxels)\n",
             shape ? "sphere" : "cube", count, threads[t], f.levelset_seconds, f.filter_seconds,
             f.mesh_seconds, built, (unsigned long long)f.voxels, mesh.triangle_count, write,
             velocity_seconds, velocity_voxels);
      mpm_surface_mesh_free(&mesh);
    }
    free(xyz);
    free(vol);
    free(vel);
    free(mass);
  }
  if (have_dir) rmdir(dir);
  printf("peak memory: %.1f MiB (resident set)\n", bench_peak_rss_mib());
  return 0;
}
