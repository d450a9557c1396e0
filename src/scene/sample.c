/* sample.c - filling a body with particles on a grid-aligned lattice (see sample.h).
 *
 * The lattice points are box_min + (k + 1/2) h with h = dx / cbrt(ppc): the usual MPM
 * initialisation of Gao et al. 2017 (sec. 7) and Zhu et al. 2017 (sec. 8), particles evenly
 * spaced inside each cell, each carrying V_p^0 = h^3 and m_p = rho h^3.
 *
 * Mesh bodies are filled a lattice column at a time: the triangles are bucketed once over
 * the (y, z) lattice columns they may cover, and each column's ray along +x is intersected
 * with its bucket. The crossings are decided with an exact 2D orientation predicate
 * (Shewchuk's orient2d with a floating-point filter and an exact expansion fallback) and
 * simulation of simplicity (Edelsbrunner and Muecke 1990): the column point is perturbed by
 * (eps, eps^2) in (y, z), so a ray through a shared edge or vertex crosses exactly one of the
 * triangles around it and the crossing count of a closed mesh is always even. Points between
 * crossings 2m and 2m+1 are inside. A column with an odd count (the mesh has holes) falls back
 * to the generalized winding number of each of its points (O(triangles) per point). Cost:
 * O(triangles x columns each covers + particles) instead of O(triangles x particles). */
#include "scene/sample.h"
#include "core/alloc.h"
#include "scene/mesh.h"

#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- exact orientation in the (y, z) plane ---------------------------------------------- */

/* Knuth's two-sum and the FMA two-product: a + b = s + e and a b = p + e exactly. */
static inline void two_sum(double a, double b, double *s, double *e) {
  double x = a + b, bv = x - a, av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

/* Sign of a sum of 12 doubles, exactly (Shewchuk's grow-expansion with zero elimination). */
static int exact_sign(const double *terms, int n) {
  double e[16];
  int m = 0;
  for (int t = 0; t < n; ++t) {
    double q = terms[t];
    int k = 0;
    for (int i = 0; i < m; ++i) {
      double s, r;
      two_sum(q, e[i], &s, &r);
      if (r != 0) e[k++] = r;
      q = s;
    }
    if (q != 0 || k == 0) e[k++] = q;
    m = k;
  }
  double top = e[m - 1];
  return (top > 0) - (top < 0);
}

/* Sign of (b - a) x (q - a) = orient2d(a, b, q): > 0 when q is left of a->b. */
static int orient2d(const double a[2], const double b[2], const double q[2]) {
  double left = (a[0] - q[0]) * (b[1] - q[1]);
  double right = (a[1] - q[1]) * (b[0] - q[0]);
  double det = left - right;
  double bound = 3.3306690738754716e-16 * (fabs(left) + fabs(right)); /* (3 + 16 eps) eps */
  if (det > bound) return 1;
  if (-det > bound) return -1;
  /* exact: a0 b1 - a1 b0 - a0 q1 + a1 q0 + b0 q1 - b1 q0, as 6 exact products */
  const double f[6][2] = {{a[0], b[1]}, {-a[1], b[0]}, {-a[0], q[1]},
                          {a[1], q[0]}, {b[0], q[1]},  {-b[1], q[0]}};
  double terms[12];
  for (int k = 0; k < 6; ++k) {
    double p = f[k][0] * f[k][1];
    terms[2 * k] = p;
    terms[2 * k + 1] = fma(f[k][0], f[k][1], -p);
  }
  return exact_sign(terms, 12);
}

/* orient2d at q + (eps, eps^2): never 0 unless a == b. */
static int orient2d_sos(const double a[2], const double b[2], const double q[2]) {
  int s = orient2d(a, b, q);
  if (s) return s;
  if (a[1] != b[1]) return a[1] > b[1] ? 1 : -1; /* d/dq0 = -(b1 - a1) */
  if (a[0] != b[0]) return b[0] > a[0] ? 1 : -1; /* d/dq1 = b0 - a0 */
  return 0;
}

/* ---- the mesh column caster -------------------------------------------------------------- */

/* A crossing of a column's ray: where, which triangle, and which way it faces (the sign of its
 * normal's x: the ray leaves a correctly wound shell through +1 and enters it through -1). */
typedef struct column_hit {
  double x;
  int t, side;
} column_hit;

typedef struct mesh_columns {
  const mpm_mesh *mesh;
  double y0, z0, h; /* position of column (0, 0) and the spacing */
  long nj, nk;      /* columns along y and z */
  size_t *start;    /* CSR: triangles of column (j, k) are tri[start[c] .. start[c + 1]) */
  int *tri;
  struct column_hit *hits; /* scratch for one column's crossings */
} mesh_columns;

static void columns_free(mesh_columns *mc) {
  mpm_free(mc->start);
  mpm_free(mc->tri);
  mpm_free(mc->hits);
  memset(mc, 0, sizeof *mc);
}

/* Range of column indices whose coordinate may lie in [lo, hi] (one column of slack: the
 * exact test decides). */
static void column_range(double lo, double hi, double o, double h, long n, long *a, long *b) {
  *a = (long)ceil((lo - o) / h) - 1;
  *b = (long)floor((hi - o) / h) + 1;
  if (*a < 0) *a = 0;
  if (*b > n - 1) *b = n - 1;
}

static int columns_build(mesh_columns *mc, const mpm_mesh *m, double y0, double z0, double h,
                         long nj, long nk) {
  memset(mc, 0, sizeof *mc);
  mc->mesh = m;
  mc->y0 = y0, mc->z0 = z0, mc->h = h, mc->nj = nj, mc->nk = nk;
  const size_t ncol = (size_t)nj * (size_t)nk;
  mc->start = mpm_calloc(ncol + 1, sizeof *mc->start);
  if (!mc->start) return -1;
  for (int pass = 0; pass < 2; ++pass) {
    for (int t = 0; t < m->triangle_count; ++t) {
      const int *v = &m->triangles[3 * t];
      double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
      for (int c = 0; c < 3; ++c)
        for (int d = 0; d < 2; ++d) {
          double x = m->vertices[3 * v[c] + 1 + d];
          lo[d] = fmin(lo[d], x);
          hi[d] = fmax(hi[d], x);
        }
      long ja, jb, ka, kb;
      column_range(lo[0], hi[0], y0, h, nj, &ja, &jb);
      column_range(lo[1], hi[1], z0, h, nk, &ka, &kb);
      for (long k = ka; k <= kb; ++k)
        for (long j = ja; j <= jb; ++j) {
          size_t c = (size_t)k * (size_t)nj + (size_t)j;
          if (pass == 0)
            mc->start[c + 1]++;
          else
            mc->tri[mc->start[c]++] = t;
        }
    }
    if (pass == 0) {
      size_t maxcount = 0;
      for (size_t c = 0; c < ncol; ++c) {
        if (mc->start[c + 1] > maxcount) maxcount = mc->start[c + 1];
        mc->start[c + 1] += mc->start[c];
      }
      mc->tri = mpm_alloc((mc->start[ncol] ? mc->start[ncol] : 1) * sizeof *mc->tri);
      mc->hits = mpm_alloc((maxcount ? maxcount : 1) * sizeof *mc->hits);
      if (!mc->tri || !mc->hits) return -1;
    }
  }
  /* the fill pass advanced start[c] to the end of column c: shift back by one column */
  for (size_t c = ncol; c > 0; --c) mc->start[c] = mc->start[c - 1];
  mc->start[0] = 0;
  return 0;
}

static int cmp_hit(const void *a, const void *b) {
  const column_hit *p = a, *q = b;
  return (p->x > q->x) - (p->x < q->x);
}

/* Where the +x ray through q = (y, z) crosses triangle t, or NAN when it does not; *side is
 * the triangle's facing seen along the ray (the exact sign of its projected orientation). */
static double ray_cross(const mpm_mesh *m, int t, const double q[2], int *side) {
  const int *v = &m->triangles[3 * t];
  const double *A = &m->vertices[3 * v[0]], *B = &m->vertices[3 * v[1]],
               *C = &m->vertices[3 * v[2]];
  const double a[2] = {A[1], A[2]}, b[2] = {B[1], B[2]}, c[2] = {C[1], C[2]};
  int s0 = orient2d_sos(b, c, q), s1 = orient2d_sos(c, a, q), s2 = orient2d_sos(a, b, q);
  if (s0 == 0 || s0 != s1 || s1 != s2) return NAN;
  *side = s0;
  /* barycentric weights from the (inexact) sub-areas, for the crossing's x only */
  double w0 = (b[0] - q[0]) * (c[1] - q[1]) - (b[1] - q[1]) * (c[0] - q[0]);
  double w1 = (c[0] - q[0]) * (a[1] - q[1]) - (c[1] - q[1]) * (a[0] - q[0]);
  double w2 = (a[0] - q[0]) * (b[1] - q[1]) - (a[1] - q[1]) * (b[0] - q[0]);
  double sum = w0 + w1 + w2;
  double x = sum != 0 ? (w0 * A[0] + w1 * B[0] + w2 * C[0]) / sum : (A[0] + B[0] + C[0]) / 3;
  double lo = fmin(A[0], fmin(B[0], C[0])), hi = fmax(A[0], fmax(B[0], C[0]));
  return fmin(fmax(x, lo), hi);
}

/* inside[i] for the lattice points x0 + i h, i < ni, of column (j, k). Returns -1, or the
 * crossing where the ray enters a second shell while inside one (shells that overlap, or a shell
 * through itself: parity would leave the overlap hollow, so the caller refuses the mesh), with
 * *at its x. Nested shells wound opposite ways (a hollow body) never do: their windings
 * cancel. */
static int columns_fill(mesh_columns *mc, long j, long k, double x0, long ni, unsigned char *inside,
                        double *at) {
  const mpm_mesh *m = mc->mesh;
  const double q[2] = {mc->y0 + (double)j * mc->h, mc->z0 + (double)k * mc->h};
  const size_t c = (size_t)k * (size_t)mc->nj + (size_t)j;
  size_t nh = 0;
  for (size_t e = mc->start[c]; e < mc->start[c + 1]; ++e) {
    int side = 0;
    const double x = ray_cross(m, mc->tri[e], q, &side);
    if (!isnan(x)) mc->hits[nh++] = (column_hit){x, mc->tri[e], side};
  }
  memset(inside, 0, (size_t)ni);
  if (nh == 0) return -1;
  qsort(mc->hits, nh, sizeof *mc->hits, cmp_hit);
  /* the winding number after each crossing; crossings at one x (two shells that touch along a
     face) count together, so that leaving one and entering the other is not an overlap */
  int winding = 0;
  for (size_t h2 = 0; h2 < nh; ++h2) {
    winding += mc->hits[h2].side;
    if (h2 + 1 < nh && mc->hits[h2 + 1].x == mc->hits[h2].x) continue;
    if (winding > 1 || winding < -1) {
      *at = mc->hits[h2].x;
      return mc->hits[h2].t;
    }
  }
  if (nh % 2 == 0) {
    for (size_t h2 = 0; h2 < nh; h2 += 2) {
      double xa = mc->hits[h2].x, xb = mc->hits[h2 + 1].x;
      long ia = (long)ceil((xa - x0) / mc->h) - 1, ib = (long)floor((xb - x0) / mc->h) + 1;
      for (long i = ia < 0 ? 0 : ia; i <= ib && i < ni; ++i) {
        double x = x0 + (double)i * mc->h;
        if (x > xa && x < xb) inside[i] = 1;
      }
    }
    return -1;
  }
  /* Odd count: the ray passes a hole, and parity means nothing on this column. Each point
   * gets the generalized winding number (the value jumps across a hole too, so one value per
   * run between crossings would not do). Points are independent: threads cannot change the
   * result. */
#pragma omp parallel for schedule(dynamic, 4)
  for (long i = 0; i < ni; ++i) {
    const double p[3] = {x0 + (double)i * mc->h, q[0], q[1]};
    inside[i] = (unsigned char)mpm_mesh_inside(m, p);
  }
  return -1;
}

/* ---- shapes --------------------------------------------------------------------------- */

/* The refusal of a mesh whose shells overlap: where the ray found it and the face's line. */
static mpm_status overlapping_shells(const mpm_scene *scene, int bi, const mpm_mesh *mesh, int t,
                                     double x, double y, double z, mpm_error *err) {
  const mpm_body_desc *body = &scene->bodies[bi];
  char face[96] = "";
  if (mesh->triangle_source)
    snprintf(face, sizeof face, " (the face at %s %d)",
             mesh->source_is_line ? "line" : "face element", mesh->triangle_source[t]);
  return mpm_error_set(err, MPM_ERR_INVALID,
                       "%s: bodies[%d].shape.file: mesh file '%s' has shells that overlap (or a "
                       "shell that passes through itself): the point (%g, %g, %g) is inside two "
                       "of them%s, and inside and outside are ambiguous there; join overlapping "
                       "shells into one closed surface (a boolean union), and wind a shell inside "
                       "another the other way round to leave it hollow",
                       scene->path[0] ? scene->path : "scene", bi, body->shape.mesh_path, x, y, z,
                       face);
}

typedef struct shape_ctx {
  const mpm_shape_desc *s;
  double axis[3]; /* cylinder: normalised axis */
  mpm_mesh mesh;  /* mesh: transformed to world coordinates */
  mesh_columns columns;
} shape_ctx;

static int analytic_inside(const shape_ctx *sc, const double x[3]) {
  const mpm_shape_desc *s = sc->s;
  double d[3] = {x[0] - s->center[0], x[1] - s->center[1], x[2] - s->center[2]};
  switch (s->kind) {
  case MPM_SHAPE_BOX:
    return fabs(d[0]) <= s->half_extent[0] && fabs(d[1]) <= s->half_extent[1] &&
           fabs(d[2]) <= s->half_extent[2];
  case MPM_SHAPE_SPHERE:
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= s->radius * s->radius;
  case MPM_SHAPE_CYLINDER: {
    const double *a = sc->axis;
    double t = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    double r[3] = {d[0] - t * a[0], d[1] - t * a[1], d[2] - t * a[2]};
    return fabs(t) <= s->half_height &&
           r[0] * r[0] + r[1] * r[1] + r[2] * r[2] <= s->radius * s->radius;
  }
  default:
    return 0;
  }
}

void mpm_scene_mesh_file(const mpm_scene *scene, const char *mesh_path, char *out, size_t size) {
  snprintf(out, size, "%s", mesh_path);
  if (mesh_path[0] == '/') return;
  const char *slash = strrchr(scene->path, '/');
  if (!slash) return;
  char candidate[2 * MPM_PATH_MAX];
  snprintf(candidate, sizeof candidate, "%.*s/%s", (int)(slash - scene->path), scene->path,
           mesh_path);
  if (access(candidate, F_OK) == 0) /* not opened: a FIFO there would block */
    snprintf(out, size, "%s", candidate);
}

/* Check the shape, compute its bounds and prepare what the inside test needs. */
static mpm_status shape_prepare(const mpm_scene *scene, int bi, shape_ctx *sc, double lo[3],
                                double hi[3], mpm_error *err) {
  const mpm_shape_desc *s = sc->s;
  const char *file = scene->path[0] ? scene->path : "scene";
  switch (s->kind) {
  case MPM_SHAPE_BOX:
    for (int d = 0; d < 3; ++d) {
      if (!(s->half_extent[d] > 0))
        return mpm_error_set(err, MPM_ERR_INVALID,
                             "%s: bodies[%d].shape.half_extent[%d] is %g, expected > 0", file, bi,
                             d, s->half_extent[d]);
      lo[d] = s->center[d] - s->half_extent[d];
      hi[d] = s->center[d] + s->half_extent[d];
    }
    return MPM_OK;
  case MPM_SHAPE_SPHERE:
  case MPM_SHAPE_CYLINDER: {
    if (!(s->radius > 0))
      return mpm_error_set(err, MPM_ERR_INVALID, "%s: bodies[%d].shape.radius is %g, expected > 0",
                           file, bi, s->radius);
    double ext[3] = {s->radius, s->radius, s->radius};
    if (s->kind == MPM_SHAPE_CYLINDER) {
      double n = sqrt(s->axis[0] * s->axis[0] + s->axis[1] * s->axis[1] + s->axis[2] * s->axis[2]);
      if (!(n > 0) || !isfinite(n))
        return mpm_error_set(err, MPM_ERR_INVALID,
                             "%s: bodies[%d].shape.axis has zero length, expected a unit vector",
                             file, bi);
      if (!(s->half_height > 0) || !isfinite(s->half_height))
        return mpm_error_set(err, MPM_ERR_INVALID,
                             "%s: bodies[%d].shape.half_height is %g, a body's cylinder must be "
                             "capped (half_height > 0)",
                             file, bi, s->half_height);
      for (int d = 0; d < 3; ++d) sc->axis[d] = s->axis[d] / n;
      for (int d = 0; d < 3; ++d)
        ext[d] = s->half_height * fabs(sc->axis[d]) +
                 s->radius * sqrt(fmax(0, 1 - sc->axis[d] * sc->axis[d]));
    }
    for (int d = 0; d < 3; ++d) {
      lo[d] = s->center[d] - ext[d];
      hi[d] = s->center[d] + ext[d];
    }
    return MPM_OK;
  }
  case MPM_SHAPE_MESH: {
    if (!s->mesh_path[0])
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "%s: bodies[%d].shape.mesh_path is empty, expected an .obj or .ply "
                           "file",
                           file, bi);
    if (!(s->mesh_scale > 0) || !isfinite(s->mesh_scale))
      return mpm_error_set(err, MPM_ERR_INVALID,
                           "%s: bodies[%d].shape.mesh_scale is %g, expected > 0", file, bi,
                           s->mesh_scale);
    char path[2 * MPM_PATH_MAX];
    mpm_scene_mesh_file(scene, s->mesh_path, path, sizeof path);
    mpm_error merr;
    mpm_error_clear(&merr);
    const double max_mb = s->mesh_max_mb > 0 ? s->mesh_max_mb : MPM_MESH_MAX_MB;
    mpm_status st = mpm_mesh_load_max(path, max_mb * 1024 * 1024, &sc->mesh, &merr);
    if (st != MPM_OK)
      return mpm_error_set(err, st, "%s: bodies[%d].shape.mesh_path: %s", file, bi, merr.message);
    double mlo[3], mhi[3];
    mpm_mesh_bounds(&sc->mesh, mlo, mhi);
    for (int i = 0; i < sc->mesh.vertex_count; ++i)
      for (int d = 0; d < 3; ++d) {
        double *x = &sc->mesh.vertices[3 * i + d];
        *x = (*x - 0.5 * (mlo[d] + mhi[d])) * s->mesh_scale + s->center[d];
      }
    mpm_mesh_bounds(&sc->mesh, lo, hi);
    return MPM_OK;
  }
  default:
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: bodies[%d].shape: a half-space cannot be a body, expected box, "
                         "sphere, cylinder or mesh",
                         file, bi);
  }
}

mpm_status mpm_sample_body_mesh(const mpm_scene *scene, int bi, mpm_mesh *out, mpm_error *err) {
  memset(out, 0, sizeof *out);
  shape_ctx sc;
  memset(&sc, 0, sizeof sc);
  sc.s = &scene->bodies[bi].shape;
  if (sc.s->kind != MPM_SHAPE_MESH)
    return mpm_error_set(err, MPM_ERR_INVALID, "bodies[%d] is not made from a mesh", bi);
  double lo[3], hi[3];
  mpm_status st = shape_prepare(scene, bi, &sc, lo, hi, err);
  if (st != MPM_OK) {
    mpm_mesh_free(&sc.mesh);
    return st;
  }
  *out = sc.mesh;
  return MPM_OK;
}

/* ---- sampling ------------------------------------------------------------------------- */

/* splitmix64 (Steele, Lea and Flood 2014): uniform in [0, 1). */
static double next_uniform(uint64_t *state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

double mpm_sample_spacing(const mpm_scene *scene, int body_index) {
  return scene->dx / cbrt(scene->bodies[body_index].particles_per_cell);
}

mpm_status mpm_sample_body(const mpm_scene *scene, int bi, mpm_particles *p, mpm_error *err) {
  const size_t start = p->count;
  const mpm_status st = mpm_sample_body_kept(scene, bi, 1, NULL, NULL, p, err);
  if (st == MPM_OK) mpm_sample_spin(scene, bi, p, start);
  return st;
}

void mpm_sample_spin(const mpm_scene *scene, int bi, mpm_particles *p, size_t start) {
  const mpm_body_desc *body = &scene->bodies[bi];
  const size_t count = p->count - start;
  /* rigid rotation about the centroid of the particles as stored: sum (x - c) = 0, so the
   * rotation adds no net linear momentum */
  const double *w = body->angular_velocity;
  if (!count || (w[0] == 0 && w[1] == 0 && w[2] == 0)) return;
  double c[3] = {0, 0, 0};
  for (size_t q = start; q < p->count; ++q)
    for (int d = 0; d < 3; ++d) c[d] += (double)p->x[d][q];
  for (int d = 0; d < 3; ++d) c[d] /= (double)count;
  for (size_t q = start; q < p->count; ++q) {
    double r[3] = {(double)p->x[0][q] - c[0], (double)p->x[1][q] - c[1], (double)p->x[2][q] - c[2]};
    p->v[0][q] = (mpm_real)(body->velocity[0] + w[1] * r[2] - w[2] * r[1]);
    p->v[1][q] = (mpm_real)(body->velocity[1] + w[2] * r[0] - w[0] * r[2]);
    p->v[2][q] = (mpm_real)(body->velocity[2] + w[0] * r[1] - w[1] * r[0]);
  }
}

mpm_status mpm_sample_body_kept(const mpm_scene *scene, int bi, double scale,
                                mpm_sample_keep_fn keep, const void *ctx, mpm_particles *p,
                                mpm_error *err) {
  assert(bi >= 0 && bi < scene->body_count);
  const mpm_body_desc *body = &scene->bodies[bi];
  const char *file = scene->path[0] ? scene->path : "scene";
  if (!(scene->dx > 0))
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: dx is %g, expected > 0", file, scene->dx);
  if (!(body->particles_per_cell > 0) || !isfinite(body->particles_per_cell))
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: bodies[%d].particles_per_cell is %g, expected > 0", file, bi,
                         body->particles_per_cell);
  if (body->material < 0 || body->material >= scene->material_count)
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: bodies[%d].material is %d, expected 0..%d",
                         file, bi, body->material, scene->material_count - 1);
  if (!(body->jitter >= 0 && body->jitter <= 1))
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: bodies[%d].jitter is %g, expected 0..1", file,
                         bi, body->jitter);
  const double density = scene->materials[body->material].density;
  const double h = mpm_sample_spacing(scene, bi) * scale;
  const double *dmin = scene->box_min, *dmax = scene->box_max;

  shape_ctx sc;
  memset(&sc, 0, sizeof sc);
  sc.s = &body->shape;
  const size_t start = p->count;
  unsigned char *inside = NULL;
  double lo[3], hi[3];
  mpm_status st = shape_prepare(scene, bi, &sc, lo, hi, err);
  if (st != MPM_OK) goto done;

  /* lattice indices (absolute, k: dmin + (k + 1/2) h) covering the shape's bounds */
  long i0[3], n[3];
  double points = 1;
  for (int d = 0; d < 3; ++d) {
    double a = ceil((lo[d] - dmin[d]) / h - 0.5) - 1, b = floor((hi[d] - dmin[d]) / h - 0.5) + 1;
    if (!(b - a < 1e9)) a = b = 0, points = INFINITY;
    i0[d] = (long)a;
    n[d] = (long)(b - a) + 1;
    points *= (double)n[d];
  }
  if (points > 4e9) {
    st = mpm_error_set(err, MPM_ERR_INVALID,
                       "%s: bodies[%d]: the shape's bounds hold %.3g lattice points (spacing %g "
                       "m), too many; use a larger dx or fewer particles_per_cell",
                       file, bi, points, h);
    goto done;
  }
  inside = mpm_alloc((size_t)n[0]);
  if (!inside) goto oom;
  const int is_mesh = body->shape.kind == MPM_SHAPE_MESH;
  if (is_mesh && columns_build(&sc.columns, &sc.mesh, dmin[1] + ((double)i0[1] + 0.5) * h,
                               dmin[2] + ((double)i0[2] + 0.5) * h, h, n[1], n[2]))
    goto oom;

  uint64_t rng = body->seed;
  const double jit = body->jitter * h;
  const mpm_real m = (mpm_real)(density * h * h * h), vol = (mpm_real)(h * h * h);
  mpm_real v0[3];
  for (int d = 0; d < 3; ++d) v0[d] = (mpm_real)body->velocity[d];
  for (long k = 0; k < n[2]; ++k)
    for (long j = 0; j < n[1]; ++j) {
      double x[3];
      x[1] = dmin[1] + ((double)(i0[1] + j) + 0.5) * h;
      x[2] = dmin[2] + ((double)(i0[2] + k) + 0.5) * h;
      const double x0 = dmin[0] + ((double)i0[0] + 0.5) * h;
      if (is_mesh) {
        double at = 0;
        const int t = columns_fill(&sc.columns, j, k, x0, n[0], inside, &at);
        if (t >= 0) {
          st = overlapping_shells(scene, bi, &sc.mesh, t, at, x[1], x[2], err);
          goto done;
        }
      } else {
        for (long i = 0; i < n[0]; ++i) {
          x[0] = dmin[0] + ((double)(i0[0] + i) + 0.5) * h;
          inside[i] = (unsigned char)analytic_inside(&sc, x);
        }
      }
      for (long i = 0; i < n[0]; ++i) {
        if (!inside[i]) continue;
        x[0] = dmin[0] + ((double)(i0[0] + i) + 0.5) * h;
        if (keep && !keep(ctx, x)) continue;
        const long idx[3] = {i0[0] + i, i0[1] + j, i0[2] + k};
        for (int d = 0; d < 3; ++d)
          if (idx[d] < 0 || dmin[d] + (double)(idx[d] + 1) * h > dmax[d] + 1e-9 * h) {
            st = mpm_error_set(err, MPM_ERR_INVALID,
                               "%s: bodies[%d]: particle at (%g, %g, %g) lies outside the "
                               "domain [%g, %g] x [%g, %g] x [%g, %g]; move or shrink the body",
                               file, bi, x[0], x[1], x[2], dmin[0], dmax[0], dmin[1], dmax[1],
                               dmin[2], dmax[2]);
            goto done;
          }
        mpm_real xr[3];
        for (int d = 0; d < 3; ++d) {
          double off = jit > 0 ? (next_uniform(&rng) - 0.5) * jit : 0;
          xr[d] = (mpm_real)(x[d] + off);
        }
        const long pj = mpm_particles_push(p, xr, v0, m, vol, body->material, bi);
        if (pj < 0) goto oom;
        p->temperature[pj] = (mpm_real)body->temperature;
      }
    }

  if (p->count == start && !keep) {
    st = mpm_error_set(err, MPM_ERR_INVALID,
                       "%s: bodies[%d] (\"%s\"): no particle lies inside the shape at lattice "
                       "spacing %g m; use a smaller dx or more particles_per_cell",
                       file, bi, body->name, h);
    goto done;
  }
  goto done;
oom:
  st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: bodies[%d]: out of memory while sampling", file, bi);
done:
  if (st != MPM_OK) p->count = start;
  mpm_free(inside);
  columns_free(&sc.columns);
  mpm_mesh_free(&sc.mesh);
  return st;
}
