/* multigrid.c - the Galerkin multigrid V-cycle (see multigrid.h). */
#include "solver/multigrid.h"
#include "core/parallel.h"
#include "core/sym_eigen.h"

#include <math.h>
#include <string.h>

/* ---- node coordinates -> rows ---------------------------------------------------------- */

typedef struct coord_table {
  uint64_t *key; /* packed coordinates + 1; 0 empty */
  int32_t *row;
  size_t mask;
} coord_table;

#define COORD_BIAS (1 << 20)

static uint64_t pack(const int32_t c[3]) {
  return ((uint64_t)(uint32_t)(c[0] + COORD_BIAS) << 42) |
         ((uint64_t)(uint32_t)(c[1] + COORD_BIAS) << 21) | (uint64_t)(uint32_t)(c[2] + COORD_BIAS);
}

static size_t slot_of(uint64_t k, size_t mask) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdull;
  k ^= k >> 33;
  return (size_t)k & mask;
}

static int table_init(coord_table *t, mpm_arena *a, size_t n) {
  size_t cap = 16;
  while (cap < 2 * n + 2) cap <<= 1;
  t->mask = cap - 1;
  t->key = mpm_arena_alloc(a, cap * sizeof *t->key);
  t->row = mpm_arena_alloc(a, cap * sizeof *t->row);
  if (!t->key || !t->row) return -1;
  memset(t->key, 0, cap * sizeof *t->key);
  return 0;
}

/* The row of c, or -1; with insert >= 0, c is added as that row when absent (returns it). */
static int32_t table_find(coord_table *t, const int32_t c[3], int32_t insert) {
  const uint64_t k = pack(c) + 1;
  for (size_t s = slot_of(k, t->mask);; s = (s + 1) & t->mask) {
    if (t->key[s] == k) return t->row[s];
    if (t->key[s] == 0) {
      if (insert < 0) return -1;
      t->key[s] = k;
      t->row[s] = insert;
      return insert;
    }
  }
}

/* ---- small blocks ---------------------------------------------------------------------- */

/* y += A x for a 3x3 block */
static inline void block_mul_add(const mpm_real *A, const mpm_real *x, mpm_real *y) {
  y[0] += A[0] * x[0] + A[1] * x[1] + A[2] * x[2];
  y[1] += A[3] * x[0] + A[4] * x[1] + A[5] * x[2];
  y[2] += A[6] * x[0] + A[7] * x[1] + A[8] * x[2];
}

static void sym_to_full(const mpm_real P[6], mpm_real M[9]) {
  M[0] = P[0], M[1] = P[1], M[2] = P[2];
  M[3] = P[1], M[4] = P[3], M[5] = P[4];
  M[6] = P[2], M[7] = P[4], M[8] = P[5];
}

static void mul3(const mpm_real *A, const mpm_real *B, mpm_real *C) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
}

/* The pseudo-inverse of the symmetric part of a 3x3 block: eigenvalues below 1e-5 of the
 * largest (a direction the projection removed, up to the real type's rounding) inverted as 0. */
static void pseudo_inverse(const mpm_real *A, mpm_real *out) {
  double S[9], lam[3], V[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) S[3 * r + c] = 0.5 * ((double)A[3 * r + c] + (double)A[3 * c + r]);
  mpm_sym_eigen(3, S, lam, V);
  const double top = fmax(fabs(lam[0]), fabs(lam[2]));
  double inv[3];
  for (int k = 0; k < 3; ++k) inv[k] = top > 0 && lam[k] > 1e-5 * top ? 1 / lam[k] : 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += V[3 * r + k] * inv[k] * V[3 * c + k];
      out[3 * r + c] = (mpm_real)s;
    }
}

/* The largest stencil span (2 radius + 1) and window the Galerkin products hold on the stack:
   kernels up to the cubic (radius 3). */
#define MG_SPAN_MAX 7

/* ---- the hierarchy --------------------------------------------------------------------- */

static void *arena_zero(mpm_multigrid *mg, size_t bytes) {
  void *p = mpm_arena_alloc(mg->arena, bytes ? bytes : 1);
  if (p) {
    memset(p, 0, bytes);
    mg->bytes += bytes;
  }
  return p;
}

/* Level l's neighbour table, colours and work vectors, from its n and coord. */
static int build_level(mpm_multigrid *mg, mpm_mg_level *L) {
  const size_t n = L->n;
  L->span = 2 * L->radius + 1;
  L->slots = (size_t)L->span * (size_t)L->span * (size_t)L->span;
  coord_table t;
  if (table_init(&t, mg->arena, n)) return -1;
  for (size_t i = 0; i < n; ++i) table_find(&t, L->coord[i], (int32_t)i);
  L->nbr = arena_zero(mg, n * L->slots * sizeof *L->nbr);
  L->val = arena_zero(mg, n * L->slots * 9 * sizeof *L->val);
  L->dinv = arena_zero(mg, n * 9 * sizeof *L->dinv);
  L->x = arena_zero(mg, 3 * (n + 1) * sizeof *L->x); /* node n: zero, for absent neighbours */
  L->b = arena_zero(mg, 3 * n * sizeof *L->b);
  L->r = arena_zero(mg, 3 * n * sizeof *L->r);
  const int m = L->radius + 1; /* colours per axis */
  L->colours = m * m * m;
  L->colour_start = arena_zero(mg, ((size_t)L->colours + 1) * sizeof *L->colour_start);
  L->colour_row = arena_zero(mg, n * sizeof *L->colour_row);
  if (!L->nbr || !L->val || !L->dinv || !L->x || !L->b || !L->r || !L->colour_start ||
      !L->colour_row)
    return -1;
  const int R = L->radius, span = L->span;
  const long nl = (long)n;
#pragma omp parallel for schedule(static) if (nl > 256)
  for (long i = 0; i < nl; ++i) {
    int32_t *row = L->nbr + (size_t)i * L->slots;
    for (int a = -R, k = 0; a <= R; ++a)
      for (int b = -R; b <= R; ++b)
        for (int c = -R; c <= R; ++c, ++k) {
          const int32_t q[3] = {L->coord[i][0] + a, L->coord[i][1] + b, L->coord[i][2] + c};
          row[k] = table_find(&t, q, -1);
        }
  }
  (void)span;
  /* colours: coordinates modulo radius + 1 (a colour's nodes are radius + 1 apart on some axis:
     never in each other's stencil) */
  uint8_t *colour = mpm_arena_alloc(mg->arena, n + 1);
  if (!colour) return -1;
  for (size_t i = 0; i < n; ++i) {
    int c = 0;
    for (int e = 0; e < 3; ++e) c = c * m + (int)(((L->coord[i][e] % m) + m) % m);
    colour[i] = (uint8_t)c;
    L->colour_start[c + 1]++;
  }
  for (int c = 0; c < L->colours; ++c) L->colour_start[c + 1] += L->colour_start[c];
  uint32_t *fill = mpm_arena_alloc(mg->arena, ((size_t)L->colours + 1) * sizeof *fill);
  if (!fill) return -1;
  memcpy(fill, L->colour_start, ((size_t)L->colours + 1) * sizeof *fill);
  for (size_t i = 0; i < n; ++i) L->colour_row[fill[colour[i]]++] = (uint32_t)i;
  return 0;
}

/* The parents of fine coordinate j on one axis: up to 2, with weights. */
static int parents_1d(mpm_mg_prolongation kind, int32_t j, int32_t p[2], mpm_real w[2]) {
  const int32_t h = j >> 1; /* floor(j / 2) */
  if (kind == MPM_MG_QUADRATIC) {
    /* coarse I covers fine 2I - 1 .. 2I + 2 with 1/4, 3/4, 3/4, 1/4 */
    if ((j & 1) == 0) {
      p[0] = h, w[0] = R_(0.75), p[1] = h - 1, w[1] = R_(0.25);
    } else {
      p[0] = h, w[0] = R_(0.75), p[1] = h + 1, w[1] = R_(0.25);
    }
    return 2;
  }
  if ((j & 1) == 0) {
    p[0] = h, w[0] = 1;
    return 1;
  }
  p[0] = h, w[0] = R_(0.5), p[1] = h + 1, w[1] = R_(0.5);
  return 2;
}

/* The next coarser level of level l: its nodes (the parents of l's, numbered in the order they
 * are first met), l's parent table and the coarse level's children lists. */
static int coarsen(mpm_multigrid *mg, int l) {
  mpm_mg_level *F = &mg->level[l], *C = &mg->level[l + 1];
  const size_t n = F->n;
  F->parent = arena_zero(mg, n * 8 * sizeof *F->parent);
  F->pw = arena_zero(mg, n * 8 * sizeof *F->pw);
  C->coord = mpm_arena_alloc(mg->arena, (8 * n + 1) * sizeof *C->coord); /* at most */
  coord_table t;
  if (!F->parent || !F->pw || !C->coord || table_init(&t, mg->arena, 8 * n)) return -1;
  size_t nc = 0;
  for (size_t i = 0; i < n; ++i) {
    int32_t p[3][2];
    mpm_real w[3][2];
    int np[3];
    for (int e = 0; e < 3; ++e) np[e] = parents_1d(mg->prolongation, F->coord[i][e], p[e], w[e]);
    int k = 0;
    for (int a = 0; a < np[0]; ++a)
      for (int b = 0; b < np[1]; ++b)
        for (int c = 0; c < np[2]; ++c, ++k) {
          const int32_t q[3] = {p[0][a], p[1][b], p[2][c]};
          int32_t r = table_find(&t, q, (int32_t)nc);
          if (r == (int32_t)nc) {
            memcpy(C->coord[nc], q, sizeof q);
            ++nc;
          }
          F->parent[8 * i + (size_t)k] = r;
          F->pw[8 * i + (size_t)k] = w[0][a] * w[1][b] * w[2][c];
        }
    for (; k < 8; ++k) F->parent[8 * i + (size_t)k] = -1;
  }
  C->n = nc;
  /* a coarse node couples the nodes whose children lie within the fine radius of each other */
  C->radius = mg->prolongation == MPM_MG_QUADRATIC ? (F->radius + 3) / 2 : (F->radius + 2) / 2;
  /* children: P's columns */
  C->child_start = arena_zero(mg, (nc + 1) * sizeof *C->child_start);
  C->child = mpm_arena_alloc(mg->arena, (8 * n + 1) * sizeof *C->child);
  C->cw = mpm_arena_alloc(mg->arena, (8 * n + 1) * sizeof *C->cw);
  uint32_t *fill = mpm_arena_alloc(mg->arena, (nc + 1) * sizeof *fill);
  if (!C->child_start || !C->child || !C->cw || !fill) return -1;
  for (size_t i = 0; i < 8 * n; ++i)
    if (F->parent[i] >= 0) C->child_start[F->parent[i] + 1]++;
  for (size_t c = 0; c < nc; ++c) C->child_start[c + 1] += C->child_start[c];
  memcpy(fill, C->child_start, (nc + 1) * sizeof *fill);
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 8; ++k) {
      const int32_t r = F->parent[8 * i + (size_t)k];
      if (r < 0) continue;
      C->child[fill[r]] = (uint32_t)i;
      C->cw[fill[r]++] = F->pw[8 * i + (size_t)k];
    }
  return build_level(mg, C);
}

static void window(const mpm_multigrid *mg, int radius, int *lo, int *hi);

mpm_status mpm_multigrid_setup(mpm_multigrid *mg, mpm_arena *arena, size_t n,
                               const int32_t (*coord)[3], int radius,
                               mpm_mg_prolongation prolongation, size_t coarsest) {
  memset(mg, 0, sizeof *mg);
  if (radius < 1 || 2 * radius + 1 > MG_SPAN_MAX) return MPM_ERR_INVALID;
  mg->arena = arena;
  mg->prolongation = prolongation;
  mg->sweeps = 1;
  mpm_mg_level *L0 = &mg->level[0];
  L0->n = n;
  L0->radius = radius;
  L0->coord = mpm_arena_alloc(arena, (n + 1) * sizeof *L0->coord);
  mg->proj_of_row = mpm_arena_alloc(arena, (n + 1) * sizeof *mg->proj_of_row);
  if (!L0->coord || !mg->proj_of_row) return MPM_ERR_NOMEM;
  memcpy(L0->coord, coord, n * sizeof *coord);
  if (build_level(mg, L0)) return MPM_ERR_NOMEM;
  mg->level_count = 1;
  if (coarsest < 8) coarsest = 8;
  while (mg->level[mg->level_count - 1].n > coarsest && mg->level_count < MPM_MG_LEVELS_MAX) {
    if (coarsen(mg, mg->level_count - 1)) return MPM_ERR_NOMEM;
    ++mg->level_count;
  }
  /* the Galerkin products' scratch (A P), one for every level and every rebuild of the values:
     allocated per product, a rebuild grew the arena (fresh pages, slow to fault in) */
  size_t ap = 0;
  for (int l = 0; l + 1 < mg->level_count; ++l) {
    int lo, hi;
    window(mg, mg->level[l].radius, &lo, &hi);
    const size_t ws = (size_t)(hi - lo + 1), need = mg->level[l].n * ws * ws * ws * 9;
    if (need > ap) ap = need;
  }
  mg->ap = mpm_arena_alloc(arena, (ap + 1) * sizeof *mg->ap);
  if (!mg->ap) return MPM_ERR_NOMEM;
  mg->bytes += ap * sizeof *mg->ap;
  const size_t N = 3 * mg->level[mg->level_count - 1].n;
  mg->dense_n = N;
  mg->chol = arena_zero(mg, (N * N + 1) * sizeof *mg->chol);
  mg->null = arena_zero(mg, N + 1);
  mg->dense_x = arena_zero(mg, (N + 1) * sizeof *mg->dense_x);
  return mg->chol && mg->null && mg->dense_x ? MPM_OK : MPM_ERR_NOMEM;
}

void mpm_multigrid_clear(mpm_multigrid *mg) {
  mpm_mg_level *L = &mg->level[0];
  memset(L->val, 0, L->n * L->slots * 9 * sizeof *L->val);
}

void mpm_multigrid_mirror_lower(mpm_multigrid *mg) {
  mpm_mg_level *L = &mg->level[0];
  const size_t S = L->slots, centre = S / 2;
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i)
    for (size_t s = 0; s < centre; ++s) {
      const int32_t j = L->nbr[(size_t)i * S + s];
      if (j < 0) continue;
      const mpm_real *src = L->val + ((size_t)j * S + (S - 1 - s)) * 9;
      mpm_real *dst = L->val + ((size_t)i * S + s) * 9;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) dst[3 * a + b] = src[3 * b + a];
    }
}

/* ---- values: projection, Galerkin products, inverses, the coarse factor -------------- */

/* Pi_i A_ij Pi_j on the finest level, plus c_i (I - Pi_i) on the constrained diagonals. */
static void project_finest(mpm_multigrid *mg) {
  mpm_mg_level *L = &mg->level[0];
  const long n = (long)L->n;
  for (long i = 0; i < n; ++i) mg->proj_of_row[i] = -1;
  for (size_t k = 0; k < mg->constrained; ++k) mg->proj_of_row[mg->proj_row[k]] = (int32_t)k;
  if (!mg->constrained) return;
  mpm_real *trace = L->r; /* work: each constrained row's diagonal trace before the projection */
  for (size_t k = 0; k < mg->constrained; ++k) {
    const mpm_real *D = L->val + ((size_t)mg->proj_row[k] * L->slots + L->slots / 2) * 9;
    trace[mg->proj_row[k]] = D[0] + D[4] + D[8];
  }
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i) {
    const int32_t pi = mg->proj_of_row[i];
    mpm_real Pi[9];
    if (pi >= 0) sym_to_full(mg->proj[pi], Pi);
    for (size_t s = 0; s < L->slots; ++s) {
      const int32_t j = L->nbr[(size_t)i * L->slots + s];
      if (j < 0) continue;
      mpm_real *A = L->val + ((size_t)i * L->slots + s) * 9, T[9];
      const int32_t pj = mg->proj_of_row[j];
      if (pj >= 0) {
        mpm_real Pj[9];
        sym_to_full(mg->proj[pj], Pj);
        mul3(A, Pj, T);
        memcpy(A, T, sizeof T);
      }
      if (pi >= 0) {
        mul3(Pi, A, T);
        memcpy(A, T, sizeof T);
      }
    }
    /* the constrained directions decoupled and given the node's own stiffness, c (I - Pi): the
       matrix is Pi A Pi on the constrained subspace and c there, definite, and its inverse on
       the subspace is (Pi A Pi)^+ exactly; the coarse levels see a constrained direction as
       stiff, which is what holding it means */
    if (pi >= 0) {
      mpm_real *D = L->val + ((size_t)i * L->slots + L->slots / 2) * 9;
      const mpm_real c = (trace[i] > 0 ? trace[i] : 1) / 3;
      for (int e = 0; e < 9; ++e) D[e] += c * ((e % 4 == 0 ? 1 : 0) - Pi[e]);
    }
  }
}

/* The window of coarse offsets J - floor(x_i / 2) that a fine row's A P can reach. */
static void window(const mpm_multigrid *mg, int radius, int *lo, int *hi) {
  const int half = (radius + 1) / 2; /* floor(x_j / 2) - floor(x_i / 2) for |x_j - x_i| <= radius */
  *lo = -half + (mg->prolongation == MPM_MG_QUADRATIC ? -1 : 0);
  *hi = half + 1;
}

/* y += w x over n reals (the Galerkin products' rows of blocks: contiguous, so vectorized) */
static inline void axpy(int n, mpm_real w, const mpm_real *restrict x, mpm_real *restrict y) {
  for (int k = 0; k < n; ++k) y[k] += w * x[k];
}

/* P's rows on one axis for a fine row at coordinate x: for each stencil offset d (index
   d + radius), its parents' window indices J - floor(x / 2) - lo and weights. */
typedef struct axis_weights {
  int n[MG_SPAN_MAX];
  int m[MG_SPAN_MAX][2];
  mpm_real w[MG_SPAN_MAX][2];
} axis_weights;

static void axis_of(mpm_mg_prolongation kind, int32_t x, int radius, int lo, axis_weights *a) {
  const int32_t h = x >> 1;
  for (int d = -radius; d <= radius; ++d) {
    int32_t p[2];
    mpm_real w[2];
    const int np = parents_1d(kind, x + d, p, w);
    a->n[d + radius] = np;
    for (int k = 0; k < np; ++k) {
      a->m[d + radius][k] = (int)(p[k] - h - lo);
      a->w[d + radius][k] = w[k];
    }
  }
}

/* Row i of A P in its window (ws^3 blocks, J - floor(x_i / 2) - lo): the row's blocks form a
 * dense span^3 stencil (absent neighbours' blocks are zero), and P is a tensor product, so the
 * product is three contractions, one axis at a time (z, then y, then x), each over contiguous
 * lines of blocks; about 2,250 multiply-adds an axis for the quadratic kernel where the
 * neighbour-by-parent sum took 9,000 scattered ones. */
static void ap_row(const mpm_multigrid *mg, const mpm_mg_level *F, size_t i, int lo, int ws,
                   mpm_real *restrict out) {
  const int S = F->span, R = F->radius;
  axis_weights ax[3];
  for (int e = 0; e < 3; ++e) axis_of(mg->prolongation, F->coord[i][e], R, lo, &ax[e]);
  const mpm_real *A = F->val + i * F->slots * 9;
  mpm_real T1[MG_SPAN_MAX * MG_SPAN_MAX * MG_SPAN_MAX * 9]; /* [dx][dy][mz] */
  mpm_real T2[MG_SPAN_MAX * MG_SPAN_MAX * MG_SPAN_MAX * 9]; /* [dx][my][mz] */
  const int line = ws * 9, plane = ws * ws * 9;
  memset(T1, 0, (size_t)(S * S * line) * sizeof *T1);
  for (int xy = 0; xy < S * S; ++xy)
    for (int dz = 0; dz < S; ++dz)
      for (int k = 0; k < ax[2].n[dz]; ++k)
        axpy(9, ax[2].w[dz][k], A + (size_t)(xy * S + dz) * 9,
             T1 + (size_t)(xy * ws + ax[2].m[dz][k]) * 9);
  memset(T2, 0, (size_t)(S * plane) * sizeof *T2);
  for (int dx = 0; dx < S; ++dx)
    for (int dy = 0; dy < S; ++dy)
      for (int k = 0; k < ax[1].n[dy]; ++k)
        axpy(line, ax[1].w[dy][k], T1 + (size_t)((dx * S + dy) * line),
             T2 + (size_t)(dx * plane + ax[1].m[dy][k] * line));
  memset(out, 0, (size_t)(ws * plane) * sizeof *out);
  for (int dx = 0; dx < S; ++dx)
    for (int k = 0; k < ax[0].n[dx]; ++k)
      axpy(plane, ax[0].w[dx][k], T2 + (size_t)(dx * plane),
           out + (size_t)(ax[0].m[dx][k] * plane));
}

/* Level l + 1's values: P^T A_l P. */
static void galerkin(mpm_multigrid *mg, int l) {
  mpm_mg_level *F = &mg->level[l], *C = &mg->level[l + 1];
  int lo, hi;
  window(mg, F->radius, &lo, &hi);
  const int ws = hi - lo + 1;
  const size_t wslots = (size_t)ws * (size_t)ws * (size_t)ws;
  mpm_real *AP = mg->ap; /* sized for the largest level at setup */
  const long nf = (long)F->n;
#pragma omp parallel for schedule(static) if (nf > 256)
  for (long i = 0; i < nf; ++i) ap_row(mg, F, (size_t)i, lo, ws, AP + (size_t)i * wslots * 9);
  /* P^T (A P), row by coarse row through its children: a child's window, shifted to the coarse
     row's offsets, lands in the row's stencil as contiguous z lines */
  const long nc = (long)C->n;
  const int Rc = C->radius, sc = C->span;
#pragma omp parallel for schedule(static) if (nc > 64)
  for (long I = 0; I < nc; ++I) {
    mpm_real *row = C->val + (size_t)I * C->slots * 9;
    memset(row, 0, C->slots * 9 * sizeof *row);
    const int32_t *cI = C->coord[I];
    for (uint32_t q = C->child_start[I]; q < C->child_start[I + 1]; ++q) {
      const uint32_t i = C->child[q];
      const mpm_real w = C->cw[q];
      /* window index m is coarse offset o = shift + m */
      int sh[3], m0[3], m1[3];
      for (int e = 0; e < 3; ++e) {
        sh[e] = (int)((F->coord[i][e] >> 1) + lo - cI[e]);
        m0[e] = -Rc - sh[e] > 0 ? -Rc - sh[e] : 0;
        m1[e] = Rc - sh[e] < ws - 1 ? Rc - sh[e] : ws - 1;
      }
      if (m1[2] < m0[2]) continue;
      const mpm_real *src = AP + (size_t)i * wslots * 9;
      for (int a = m0[0]; a <= m1[0]; ++a)
        for (int b = m0[1]; b <= m1[1]; ++b)
          axpy((m1[2] - m0[2] + 1) * 9, w, src + (size_t)((a * ws + b) * ws + m0[2]) * 9,
               row + (size_t)(((a + sh[0] + Rc) * sc + (b + sh[1] + Rc)) * sc +
                              (m0[2] + sh[2] + Rc)) *
                         9);
    }
  }
}

static void diagonal_inverses(mpm_mg_level *L) {
  const size_t centre = L->slots / 2;
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i)
    pseudo_inverse(L->val + ((size_t)i * L->slots + centre) * 9, L->dinv + (size_t)i * 9);
}

/* The coarsest level as a dense matrix, factored L L^T in place (lower triangle); a pivot below
 * 1e-6 of its diagonal entry is a null direction (obstacles hold it): its row and column are
 * left out of the solve. */
static void dense_factor(mpm_multigrid *mg) {
  const mpm_mg_level *L = &mg->level[mg->level_count - 1];
  const size_t N = mg->dense_n;
  double *A = mg->chol;
  memset(A, 0, N * N * sizeof *A);
  for (size_t i = 0; i < L->n; ++i)
    for (size_t s = 0; s < L->slots; ++s) {
      const int32_t j = L->nbr[i * L->slots + s];
      if (j < 0) continue;
      const mpm_real *B = L->val + (i * L->slots + s) * 9;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          A[(3 * i + (size_t)a) * N + 3 * (size_t)j + (size_t)b] = B[3 * a + b];
    }
  for (size_t k = 0; k < N; ++k) {
    const double d0 = A[k * N + k];
    double d = d0;
    for (size_t m = 0; m < k; ++m)
      if (!mg->null[m]) d -= A[k * N + m] * A[k * N + m];
    mg->null[k] = !(d > 1e-6 * fabs(d0)) || !(d0 > 0);
    if (mg->null[k]) {
      A[k * N + k] = 0;
      continue;
    }
    const double s = sqrt(d);
    A[k * N + k] = s;
    for (size_t i = k + 1; i < N; ++i) {
      double v = A[i * N + k];
      for (size_t m = 0; m < k; ++m)
        if (!mg->null[m]) v -= A[i * N + m] * A[k * N + m];
      A[i * N + k] = v / s;
    }
  }
}

static void dense_solve(mpm_multigrid *mg, const mpm_real *b, mpm_real *x) {
  const size_t N = mg->dense_n;
  const double *A = mg->chol;
  double *y = mg->dense_x;
  for (size_t i = 0; i < N; ++i) {
    if (mg->null[i]) {
      y[i] = 0;
      continue;
    }
    double v = b[i];
    for (size_t m = 0; m < i; ++m)
      if (!mg->null[m]) v -= A[i * N + m] * y[m];
    y[i] = v / A[i * N + i];
  }
  for (size_t i = N; i-- > 0;) {
    if (mg->null[i]) continue;
    double v = y[i];
    for (size_t m = i + 1; m < N; ++m)
      if (!mg->null[m]) v -= A[m * N + i] * y[m];
    y[i] = v / A[i * N + i];
  }
  for (size_t i = 0; i < N; ++i) x[i] = (mpm_real)y[i];
}

void mpm_multigrid_factor(mpm_multigrid *mg, size_t count, const uint32_t *row,
                          const mpm_real (*P)[6]) {
  mg->constrained = count;
  mg->proj_row = row;
  mg->proj = P;
  project_finest(mg);
  for (int l = 0; l + 1 < mg->level_count; ++l) galerkin(mg, l);
  for (int l = 0; l + 1 < mg->level_count; ++l) diagonal_inverses(&mg->level[l]);
  dense_factor(mg);
}

/* ---- the cycle ------------------------------------------------------------------------- */

void mpm_multigrid_apply(const mpm_multigrid *mg, int l, const mpm_real *x, mpm_real *y) {
  const mpm_mg_level *L = &mg->level[l];
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i) {
    mpm_real acc[3] = {0, 0, 0};
    const int32_t *nb = L->nbr + (size_t)i * L->slots;
    const mpm_real *A = L->val + (size_t)i * L->slots * 9;
    for (size_t s = 0; s < L->slots; ++s)
      if (nb[s] >= 0) block_mul_add(A + s * 9, x + 3 * (size_t)nb[s], acc);
    for (int e = 0; e < 3; ++e) y[3 * i + e] = acc[e];
  }
}

/* Eight reals: the first eight entries of a 3x3 block, row-major (the ninth is apart). */
typedef mpm_real block8 __attribute__((vector_size(8 * sizeof(mpm_real))));

/* sum_j A_ij x_j over row i, x a level's own vector (its node n, past the last, is zero: an
 * absent neighbour reads it, so the loop has no branch). Each block's first eight entries are
 * multiplied at once by (x0 x1 x2 x0 x1 x2 x0 x1) and summed lane by lane over the row, the
 * ninth apart (GCC's vector extensions, core/lanes.h: one AVX register in float): the sweeps
 * of the smoother, 125 blocks a row, took a third of the rubber bunny's implicit run in scalar
 * code. The sums run in one order, whatever the threads. */
static inline void row_product(const mpm_mg_level *L, size_t i, const mpm_real *restrict x,
                               mpm_real acc[3]) {
  const int32_t *restrict nb = L->nbr + i * L->slots;
  const mpm_real *restrict A = L->val + i * L->slots * 9;
  const int32_t none = (int32_t)L->n;
  block8 sum = {0};
  mpm_real ninth = 0;
  for (size_t s = 0; s < L->slots; ++s) {
    const size_t j = 3 * (size_t)(nb[s] < 0 ? none : nb[s]);
    const mpm_real x0 = x[j], x1 = x[j + 1], x2 = x[j + 2];
    const block8 xs = {x0, x1, x2, x0, x1, x2, x0, x1};
    block8 B;
    memcpy(&B, A + 9 * s, sizeof B); /* 36-byte stride: an unaligned load */
    sum += B * xs;
    ninth += A[9 * s + 8] * x2;
  }
  acc[0] = sum[0] + sum[1] + sum[2];
  acc[1] = sum[3] + sum[4] + sum[5];
  acc[2] = sum[6] + sum[7] + ninth;
}

/* x_i += D_i^+ (b_i - sum_j A_ij x_j) for the rows of colour c (independent of each other), on
 * the threads from 32 rows: a colour of the rubber bunny's finest level has about 270 rows, and
 * with them on one thread (below 256) the other spun idle through half the colours (1 s of the
 * bunny, Newmark, 2 threads, two rounds: 18.2, 16.9 s -> 15.7, 16.1 s, results bitwise equal). */
static void relax_colour(const mpm_multigrid *mg, int l, int c) {
  const mpm_mg_level *L = &mg->level[l];
  const long begin = (long)L->colour_start[c], end = (long)L->colour_start[c + 1];
#pragma omp parallel for schedule(static) if (end - begin > 32)
  for (long q = begin; q < end; ++q) {
    const uint32_t i = L->colour_row[q];
    mpm_real r[3] = {L->b[3 * i], L->b[3 * i + 1], L->b[3 * i + 2]}, acc[3];
    row_product(L, i, L->x, acc);
    for (int e = 0; e < 3; ++e) r[e] -= acc[e];
    mpm_real dx[3] = {0, 0, 0};
    block_mul_add(L->dinv + (size_t)i * 9, r, dx);
    for (int e = 0; e < 3; ++e) L->x[3 * i + e] += dx[e];
  }
}

/* Gauss-Seidel sweeps over the colours, forward (before the coarse correction) or backward
 * (after it): the backward sweep is the forward one's adjoint, which makes the cycle
 * symmetric. */
static void smooth(const mpm_multigrid *mg, int l, int forward) {
  const int nc = mg->level[l].colours;
  if (forward)
    for (int c = 0; c < nc; ++c) relax_colour(mg, l, c);
  else
    for (int c = nc - 1; c >= 0; --c) relax_colour(mg, l, c);
}

static void project_rows(const mpm_multigrid *mg, mpm_real *x) {
  const long n = (long)mg->constrained;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long k = 0; k < n; ++k) {
    mpm_real *v = x + 3 * (size_t)mg->proj_row[k], P[9], t[3] = {0, 0, 0};
    sym_to_full(mg->proj[k], P);
    block_mul_add(P, v, t);
    for (int e = 0; e < 3; ++e) v[e] = t[e];
  }
}

/* The next coarser level's right-hand side: b_c = P^T v (v over level l's nodes). */
static void restrict_to_coarser(mpm_multigrid *mg, int l, const mpm_real *v) {
  mpm_mg_level *C = &mg->level[l + 1];
  const long nc = (long)C->n;
#pragma omp parallel for schedule(static) if (nc > 256)
  for (long I = 0; I < nc; ++I) {
    mpm_real acc[3] = {0, 0, 0};
    for (uint32_t q = C->child_start[I]; q < C->child_start[I + 1]; ++q)
      for (int e = 0; e < 3; ++e) acc[e] += C->cw[q] * v[3 * (size_t)C->child[q] + (size_t)e];
    for (int e = 0; e < 3; ++e) C->b[3 * I + e] = acc[e];
  }
}

/* x = P x_c, or x += P x_c with add, on level l (projected on the finest level). */
static void prolong_from_coarser(mpm_multigrid *mg, int l, int add) {
  mpm_mg_level *L = &mg->level[l];
  const mpm_mg_level *C = &mg->level[l + 1];
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i) {
    mpm_real acc[3];
    for (int e = 0; e < 3; ++e) acc[e] = add ? L->x[3 * i + e] : 0;
    for (int k = 0; k < 8; ++k) {
      const int32_t J = L->parent[8 * (size_t)i + (size_t)k];
      if (J < 0) break;
      const mpm_real w = L->pw[8 * (size_t)i + (size_t)k];
      for (int e = 0; e < 3; ++e) acc[e] += w * C->x[3 * (size_t)J + (size_t)e];
    }
    for (int e = 0; e < 3; ++e) L->x[3 * i + e] = acc[e];
  }
  if (l == 0) project_rows(mg, L->x);
}

static void cycle(mpm_multigrid *mg, int l) {
  mpm_mg_level *L = &mg->level[l];
  if (l == mg->level_count - 1) {
    dense_solve(mg, L->b, L->x);
    return;
  }
  memset(L->x, 0, 3 * L->n * sizeof *L->x);
  for (int s = 0; s < mg->sweeps; ++s) smooth(mg, l, 1);
  /* the residual, restricted: b_c = P^T (b - A x) */
  const long n = (long)L->n;
#pragma omp parallel for schedule(static) if (n > 256)
  for (long i = 0; i < n; ++i) {
    mpm_real acc[3];
    row_product(L, (size_t)i, L->x, acc);
    for (int e = 0; e < 3; ++e) L->r[3 * i + e] = L->b[3 * i + e] - acc[e];
  }
  restrict_to_coarser(mg, l, L->r);
  cycle(mg, l + 1);
  prolong_from_coarser(mg, l, 1); /* x += P x_c */
  for (int s = 0; s < mg->sweeps; ++s) smooth(mg, l, 0);
}

/* The cheap cycle: the coarse correction of b itself (x = 0, so the residual is b: no pass over
 * the level's matrix for it), then one backward sweep; one pass over each level's matrix. */
static void cycle_post(mpm_multigrid *mg, int l) {
  mpm_mg_level *L = &mg->level[l];
  if (l == mg->level_count - 1) {
    dense_solve(mg, L->b, L->x);
    return;
  }
  restrict_to_coarser(mg, l, L->b);
  cycle_post(mg, l + 1);
  prolong_from_coarser(mg, l, 0); /* x = P x_c */
  for (int s = 0; s < mg->sweeps; ++s) smooth(mg, l, 0);
}

void mpm_multigrid_vcycle(mpm_multigrid *mg) {
  if (mg->level_count == 1) {
    dense_solve(mg, mg->level[0].b, mg->level[0].x);
  } else if (mg->cheap) {
    cycle_post(mg, 0);
  } else {
    cycle(mg, 0);
  }
  project_rows(mg, mg->level[0].x);
}
