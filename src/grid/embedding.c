/* embedding.c - the embedding operator's storage, schedule, scatter and gather (see
 * embedding.h). */
#include "grid/embedding.h"
#include "core/alloc.h"
#include "core/parallel.h"

#include <string.h>

void mpm_embedding_init(mpm_embedding *E) {
  memset(E, 0, sizeof *E);
}

void mpm_embedding_free(mpm_embedding *E) {
  mpm_free(E->row_start);
  mpm_free(E->row_len);
  mpm_free(E->col);
  mpm_free(E->w);
  mpm_scatter_schedule_free(&E->schedule);
  memset(E, 0, sizeof *E);
}

size_t mpm_embedding_bytes(const mpm_embedding *E) {
  return E->row_capacity * 2 * sizeof(uint32_t) +
         E->entry_capacity * (sizeof(uint32_t) + sizeof(mpm_real)) +
         mpm_scatter_schedule_bytes(&E->schedule);
}

mpm_status mpm_embedding_layout(mpm_embedding *E, size_t rows, const uint32_t *max_len,
                                uint32_t uniform_len) {
  E->schedule.built = 0;
  E->rows = 0;
  size_t rcap = E->row_capacity;
  if (rows + 1 > rcap) {
    size_t c2 = rcap;
    if (mpm_reserve((void **)&E->row_start, &rcap, rows + 1, sizeof(uint32_t)) ||
        mpm_reserve((void **)&E->row_len, &c2, rows + 1, sizeof(uint32_t))) {
      E->row_capacity = 0;
      return MPM_ERR_NOMEM;
    }
    E->row_capacity = rcap < c2 ? rcap : c2;
  }
  size_t total = 0;
  for (size_t a = 0; a < rows; ++a) {
    E->row_start[a] = (uint32_t)total;
    total += max_len ? max_len[a] : uniform_len;
  }
  E->row_start[rows] = (uint32_t)total;
  if (total > UINT32_MAX) return MPM_ERR_INVALID; /* past the 32-bit column index */
  size_t ccap = E->entry_capacity, wcap = E->entry_capacity;
  if (total > E->entry_capacity || !E->col) {
    if (mpm_reserve((void **)&E->col, &ccap, total, sizeof(uint32_t)) ||
        mpm_reserve((void **)&E->w, &wcap, total, sizeof(mpm_real))) {
      E->entry_capacity = 0;
      return MPM_ERR_NOMEM;
    }
    E->entry_capacity = ccap < wcap ? ccap : wcap;
  }
  memset(E->row_len, 0, rows * sizeof(uint32_t));
  E->rows = rows;
  return MPM_OK;
}

mpm_status mpm_embedding_schedule(mpm_embedding *E, const int32_t *key, size_t key_count,
                                  const uint8_t *key_colour) {
  return mpm_scatter_schedule_build(&E->schedule, E->rows, key, key_count, key_colour);
}

/* The first moments of a scatter (NULL: none): per entry a[j][e], per carrier cm[3 k + j][row],
 * added to um[k] (mpm_embedding_scatter_moments). */
typedef struct scatter_moments {
  const mpm_real *const *a, *const *cm;
  mpm_real *const *um;
} scatter_moments;

/* The scatter of row a. The carrier's values are read once into registers: the stores to the
 * DOFs could alias them as far as the compiler knows, and reloading 7 values per entry cost a
 * third of the corner scatter. */
#define SCATTER_LOCAL_FIELDS 8
static inline void scatter_row(const mpm_embedding *E, size_t a, int fields,
                               const mpm_real *const *c, mpm_real *const *u,
                               const scatter_moments *m) {
  const uint32_t e0 = E->row_start[a], e1 = e0 + E->row_len[a];
  if (fields > SCATTER_LOCAL_FIELDS) {
    for (uint32_t e = e0; e < e1; ++e) {
      const uint32_t i = E->col[e];
      const mpm_real w = E->w[e];
      for (int k = 0; k < fields; ++k) u[k][i] += w * c[k][a];
    }
  } else {
    mpm_real ca[SCATTER_LOCAL_FIELDS];
    mpm_real *uk[SCATTER_LOCAL_FIELDS];
    for (int k = 0; k < fields; ++k) ca[k] = c[k][a], uk[k] = u[k];
    for (uint32_t e = e0; e < e1; ++e) {
      const uint32_t i = E->col[e];
      const mpm_real w = E->w[e];
      for (int k = 0; k < fields; ++k) uk[k][i] += w * ca[k];
    }
  }
  if (m) { /* in a second pass over the row's entries, which are in cache */
    mpm_real cm[9];
    for (int k = 0; k < 9; ++k) cm[k] = m->cm[k][a];
    mpm_real *um[3] = {m->um[0], m->um[1], m->um[2]};
    const mpm_real *a0 = m->a[0], *a1 = m->a[1], *a2 = m->a[2];
    for (uint32_t e = e0; e < e1; ++e) {
      const uint32_t i = E->col[e];
      for (int k = 0; k < 3; ++k)
        um[k][i] += a0[e] * cm[3 * k] + a1[e] * cm[3 * k + 1] + a2[e] * cm[3 * k + 2];
    }
  }
}

static void scatter(const mpm_embedding *E, int fields, const mpm_real *const *c,
                    mpm_real *const *u, const scatter_moments *m) {
  const mpm_scatter_schedule *S = &E->schedule;
  if (!S->built) {
    for (size_t a = 0; a < E->rows; ++a) scatter_row(E, a, fields, c, u, m);
    return;
  }
  for (int colour = 0; colour < MPM_SCHEDULE_COLOURS; ++colour) {
    const long g0 = (long)S->colour_start[colour], g1 = (long)S->colour_start[colour + 1];
#pragma omp parallel for schedule(dynamic, 4)
    for (long q = g0; q < g1; ++q)
      for (uint32_t j = S->group_start[q]; j < S->group_start[q + 1]; ++j)
        scatter_row(E, S->group_row[j], fields, c, u, m);
  }
  const long own = (long)S->own_rows;
#pragma omp parallel for schedule(static) if (own >= MPM_PARALLEL_MIN)
  for (long j = 0; j < own; ++j) scatter_row(E, S->own_row[j], fields, c, u, m);
}

void mpm_embedding_scatter(const mpm_embedding *E, int fields, const mpm_real *const *c,
                           mpm_real *const *u) {
  scatter(E, fields, c, u, NULL);
}

void mpm_embedding_scatter_moments(const mpm_embedding *E, int fields, const mpm_real *const *c,
                                   mpm_real *const *u, const mpm_real *const a[3],
                                   const mpm_real *const cm[9], mpm_real *const um[3]) {
  const scatter_moments m = {a, cm, um};
  scatter(E, fields, c, u, &m);
}

void mpm_embedding_gather_moments(const mpm_embedding *E, const mpm_real *const u[3],
                                  const mpm_real *const a[3], mpm_real *const cm[9]) {
  const long rows = (long)E->rows;
#pragma omp parallel for schedule(static)
  for (long r = 0; r < rows; ++r) {
    const uint32_t e0 = E->row_start[r], e1 = e0 + E->row_len[r];
    mpm_real m[9] = {0};
    for (uint32_t e = e0; e < e1; ++e)
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) m[3 * k + j] += u[k][E->col[e]] * a[j][e];
    for (int q = 0; q < 9; ++q) cm[q][r] = m[q];
  }
}

void mpm_embedding_gather(const mpm_embedding *E, int fields, const mpm_real *const *u,
                          mpm_real *const *c) {
  const long rows = (long)E->rows;
#pragma omp parallel for schedule(static)
  for (long a = 0; a < rows; ++a) {
    const uint32_t e0 = E->row_start[a], e1 = e0 + E->row_len[a];
    for (int k = 0; k < fields; ++k) {
      mpm_real s = 0;
      for (uint32_t e = e0; e < e1; ++e) s += E->w[e] * u[k][E->col[e]];
      c[k][a] = s;
    }
  }
}
