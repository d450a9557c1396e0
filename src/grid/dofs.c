/* dofs.c - the DOF set: layout, fields, solver vectors and deterministic reductions (see
 * dofs.h). */
#include "grid/dofs.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <math.h>
#include <string.h>

/* The fixed chunks of the parallel passes and reductions: their count, and chunk q's DOFs
 * lo .. hi. Fixed, not per thread, so that sums do not depend on the thread count. */
static long chunk_count(const mpm_dofs *d) {
  return (long)((d->count + MPM_DOF_CHUNK - 1) / MPM_DOF_CHUNK);
}
static void chunk_range(const mpm_dofs *d, long q, size_t *lo, size_t *hi) {
  *lo = (size_t)q * MPM_DOF_CHUNK;
  *hi = d->count - *lo < MPM_DOF_CHUNK ? d->count : *lo + MPM_DOF_CHUNK;
}

void mpm_dofs_init(mpm_dofs *d) {
  memset(d, 0, sizeof *d);
}

/* The field arrays in a fixed order, with the bit of each. */
static void field_arrays(mpm_dofs *d, mpm_real **a[10], unsigned bit[10]) {
  a[0] = &d->mass;
  bit[0] = MPM_DOF_MASS;
  for (int c = 0; c < 3; ++c) {
    a[1 + c] = &d->v0[c];
    bit[1 + c] = MPM_DOF_V0;
    a[4 + c] = &d->v[c];
    bit[4 + c] = MPM_DOF_V;
    a[7 + c] = &d->f[c];
    bit[7 + c] = MPM_DOF_F;
  }
}

void mpm_dofs_free(mpm_dofs *d) {
  mpm_real **a[10];
  unsigned bit[10];
  field_arrays(d, a, bit);
  for (int k = 0; k < 10; ++k) mpm_free(*a[k]);
  for (int k = 0; k < d->vector_count; ++k)
    for (int c = 0; c < 3; ++c) mpm_free(d->vector[k].c[c]);
  mpm_free(d->partial);
  memset(d, 0, sizeof *d);
}

void mpm_dofs_begin_layout(mpm_dofs *d) {
  d->segment_count = 0;
  d->count = 0;
  for (int c = 0; c < 3; ++c) d->vm[c] = NULL;
}

static mpm_dof_segment *push_segment(mpm_dofs *d, size_t count) {
  if (d->segment_count == MPM_DOF_MAX_SEGMENTS) return NULL;
  mpm_dof_segment *s = &d->segment[d->segment_count++];
  memset(s, 0, sizeof *s);
  s->begin = d->count;
  s->count = count;
  d->count += count;
  return s;
}

mpm_status mpm_dofs_add_grid(mpm_dofs *d, mpm_grid *g) {
  mpm_dof_segment *s = push_segment(d, g->ops->node_count(g));
  if (!s) return MPM_ERR_INVALID;
  s->kind = MPM_DOF_GRID_NODE;
  s->level = g->level;
  s->grid = g;
  s->boundary_depth = R_(0.5) * g->dx;
  g->dof_begin = s->begin;
  return MPM_OK;
}

mpm_status mpm_dofs_add_corners(mpm_dofs *d, size_t count, const mpm_real *const x[3]) {
  mpm_dof_segment *s = push_segment(d, count);
  if (!s) return MPM_ERR_INVALID;
  s->kind = MPM_DOF_CORNER;
  s->level = -1;
  for (int c = 0; c < 3; ++c) s->x[c] = x[c];
  return MPM_OK;
}

mpm_status mpm_dofs_end_layout(mpm_dofs *d, unsigned fields) {
  mpm_real **a[10];
  unsigned bit[10];
  field_arrays(d, a, bit);
  const int grow = d->count > d->capacity;
  if (grow) /* room for some growth of the material between steps */
    d->capacity = d->count + d->count / 8 + MPM_BLOCK_NODES;
  for (int k = 0; k < 10; ++k) {
    if (!(fields & bit[k]) || grow) { /* nothing to keep: values are per step */
      mpm_free(*a[k]);
      *a[k] = NULL;
    }
  }
  for (int k = 0; k < 10; ++k)
    if ((fields & bit[k]) && !*a[k] && !(*a[k] = mpm_alloc((d->capacity + 1) * sizeof(mpm_real))))
      goto oom;
  d->fields = fields;
  if (grow) {
    for (int v = 0; v < d->vector_count; ++v)
      for (int c = 0; c < 3; ++c) {
        mpm_free(d->vector[v].c[c]);
        if (!(d->vector[v].c[c] = mpm_calloc(d->capacity + 1, sizeof(mpm_real)))) goto oom;
      }
    mpm_free(d->partial);
    if (!(d->partial = mpm_alloc((d->capacity / MPM_DOF_CHUNK + 2) * sizeof(double)))) goto oom;
  }
  return MPM_OK;
oom:
  for (int k = 0; k < 10; ++k) {
    mpm_free(*a[k]);
    *a[k] = NULL;
  }
  d->fields = 0;
  d->capacity = 0;
  return MPM_ERR_NOMEM;
}

void mpm_dofs_clear(mpm_dofs *d, unsigned fields) {
  mpm_real **a[10];
  unsigned bit[10];
  field_arrays(d, a, bit);
  const long chunks = chunk_count(d);
#pragma omp parallel for schedule(static)
  for (long q = 0; q < chunks; ++q) {
    size_t lo, hi;
    chunk_range(d, q, &lo, &hi);
    for (int k = 0; k < 10; ++k)
      if ((fields & bit[k]) && *a[k]) memset(*a[k] + lo, 0, (hi - lo) * sizeof(mpm_real));
  }
}

static mpm_grid_values values_from(const mpm_dofs *d, size_t o) {
  mpm_grid_values v;
  v.mass = d->mass ? d->mass + o : NULL;
  for (int c = 0; c < 3; ++c) {
    v.v0[c] = d->v0[c] ? d->v0[c] + o : NULL;
    v.v[c] = d->v[c] ? d->v[c] + o : NULL;
    v.f[c] = d->f[c] ? d->f[c] + o : NULL;
    v.vm[c] = d->vm[c] ? d->vm[c] + o : NULL;
  }
  return v;
}

mpm_grid_values mpm_dofs_values(const mpm_dofs *d) {
  return values_from(d, 0);
}

mpm_grid_values mpm_dofs_grid_values(const mpm_dofs *d, const mpm_grid *g) {
  return values_from(d, g->dof_begin);
}

const mpm_dof_segment *mpm_dofs_segment_of(const mpm_dofs *d, size_t i) {
  int lo = 0, hi = d->segment_count - 1;
  if (hi < 0 || i >= d->count) return NULL;
  while (lo < hi) { /* the last segment whose begin <= i */
    const int mid = (lo + hi + 1) / 2;
    if (d->segment[mid].begin <= i)
      lo = mid;
    else
      hi = mid - 1;
  }
  return &d->segment[lo];
}

void mpm_dofs_position(const mpm_dofs *d, size_t i, mpm_real x[3]) {
  const mpm_dof_segment *s = mpm_dofs_segment_of(d, i);
  const size_t k = i - s->begin;
  if (s->kind == MPM_DOF_CORNER) {
    for (int c = 0; c < 3; ++c) x[c] = s->x[c][k];
    return;
  }
  /* the box holding node k: boxes cover the level in order of their first node */
  const mpm_grid *g = s->grid;
  size_t lo = 0, hi = g->ops->box_count(g) - 1;
  while (lo < hi) {
    const size_t mid = (lo + hi + 1) / 2;
    if (g->ops->box(g, mid).first <= k)
      lo = mid;
    else
      hi = mid - 1;
  }
  const mpm_node_box b = g->ops->box(g, lo);
  const size_t r = k - b.first, plane = (size_t)b.n[1] * (size_t)b.n[2];
  const int32_t idx[3] = {b.lo[0] + (int32_t)(r / plane), b.lo[1] + (int32_t)(r % plane / b.n[2]),
                          b.lo[2] + (int32_t)(r % b.n[2])};
  mpm_grid_node_position(g, idx, x);
}

mpm_real **mpm_dofs_vector(mpm_dofs *d, const char *name) {
  for (int v = 0; v < d->vector_count; ++v)
    if (!strncmp(d->vector[v].name, name, MPM_DOF_VECTOR_NAME)) return d->vector[v].c;
  if (d->vector_count == MPM_DOF_MAX_VECTORS) return NULL;
  mpm_dof_vector *v = &d->vector[d->vector_count];
  memset(v, 0, sizeof *v);
  strncpy(v->name, name, MPM_DOF_VECTOR_NAME - 1);
  for (int c = 0; c < 3; ++c)
    if (!(v->c[c] = mpm_calloc(d->capacity + 1, sizeof(mpm_real)))) {
      for (int e = 0; e < c; ++e) mpm_free(v->c[e]);
      return NULL;
    }
  d->vector_count++;
  return v->c;
}

/* Sum of the chunk sums in chunk order. */
static double sum_partials(const mpm_dofs *d, long chunks) {
  double s = 0;
  for (long q = 0; q < chunks; ++q) s += d->partial[q];
  return s;
}

double mpm_dofs_dot(const mpm_dofs *d, const mpm_real *w, mpm_real *const a[3],
                    mpm_real *const b[3]) {
  const long chunks = chunk_count(d);
  double *partial = d->partial;
#pragma omp parallel for schedule(static) if (chunks > 1)
  for (long q = 0; q < chunks; ++q) {
    size_t lo, hi;
    chunk_range(d, q, &lo, &hi);
    double s = 0;
    for (size_t i = lo; i < hi; ++i) {
      const double ab =
          (double)a[0][i] * b[0][i] + (double)a[1][i] * b[1][i] + (double)a[2][i] * b[2][i];
      s += w ? (double)w[i] * ab : ab;
    }
    partial[q] = s;
  }
  double sum = sum_partials(d, chunks);
  mpm_reduce_all(d->reduction, MPM_REDUCE_SUM, &sum, 1);
  return sum;
}

double mpm_dofs_max_abs(const mpm_dofs *d, mpm_real *const a[3]) {
  const long chunks = chunk_count(d);
  double *partial = d->partial;
#pragma omp parallel for schedule(static) if (chunks > 1)
  for (long q = 0; q < chunks; ++q) {
    size_t lo, hi;
    chunk_range(d, q, &lo, &hi);
    double m = 0;
    for (size_t i = lo; i < hi; ++i)
      for (int c = 0; c < 3; ++c) {
        const double v = fabs((double)a[c][i]);
        m = v > m || v != v ? v : m; /* a NaN wins, so that it is seen */
      }
    partial[q] = m;
  }
  double m = 0;
  for (long q = 0; q < chunks; ++q) m = partial[q] > m || partial[q] != partial[q] ? partial[q] : m;
  mpm_reduce_all(d->reduction, MPM_REDUCE_MAX, &m, 1);
  return m;
}

void mpm_dofs_axpy(const mpm_dofs *d, mpm_real alpha, mpm_real *const x[3], mpm_real *const y[3]) {
  const long n = (long)d->count;
#pragma omp parallel if (n > MPM_PARALLEL_MIN)
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict xc = x[c];
    mpm_real *restrict yc = y[c];
#pragma omp for simd schedule(static) nowait
    for (long i = 0; i < n; ++i) yc[i] += alpha * xc[i];
  }
}

void mpm_dofs_xpby(const mpm_dofs *d, mpm_real *const x[3], mpm_real beta, mpm_real *const y[3]) {
  const long n = (long)d->count;
#pragma omp parallel if (n > MPM_PARALLEL_MIN)
  for (int c = 0; c < 3; ++c) {
    const mpm_real *restrict xc = x[c];
    mpm_real *restrict yc = y[c];
#pragma omp for simd schedule(static) nowait
    for (long i = 0; i < n; ++i) yc[i] = xc[i] + beta * yc[i];
  }
}

void mpm_dofs_copy(const mpm_dofs *d, mpm_real *const x[3], mpm_real *const y[3]) {
  for (int c = 0; c < 3; ++c) memcpy(y[c], x[c], d->count * sizeof(mpm_real));
}
