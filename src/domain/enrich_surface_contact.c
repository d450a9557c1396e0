/* enrich_surface_contact.c - enriched parts meet enriched parts (see enrich_surface_contact.h). */
#include "domain/enrich_surface_contact.h"
#include "core/parallel.h"
#include "core/tile_batches.h"
#include "domain/enrich.h"
#include "domain/hex.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* a face of its own body nearer than this many lattice spacings (reference centre to the
   corner's reference position) is the corner's neighbourhood, not a contact: a corner of the
   face's own hexahedron is 0.5-1.2 spacings from its centre, one of the next hexahedron's
   1.1-1.9 */
#define SELF_REACH 2.5
/* the skin a contact stops at, and the depth past which a corner is taken as through the face
   already (not pushed back), in lattice spacings */
#define SKIN 0.02
#define DEPTH 0.5
/* how far off a face a corner behind it may project and still be pushed back out, in lattice
   spacings */
#define LATERAL_BEHIND 0.5
/* the share of its depth below the skin a corner is moved out by in a step (a corner that
   slid in across an edge or a turning face comes back out over a few steps instead of staying
   there; Baumgarte's stabilization) */
#define RECOVERY 0.2
/* contacts kept per corner (the nearest; a corner at an edge or a vertex touches 2 or 3 faces),
   Gauss-Seidel sweeps over them */
#define PER_CORNER 4
#define SWEEPS 4

int mpm_surface_contact_on(const mpm_domain_set *s) {
  const mpm_domain_enrichment *e = &s->enrich;
  if (!e->count) return 0;
  for (int b = 0; b < e->body_count; ++b)
    if (e->body[b].surface_contact) return 1;
  return 0;
}

typedef struct face {
  uint32_t particle;
  uint32_t corner[4]; /* in cyclic order around the face */
  int32_t body;
  float centre[3];    /* its particle's hexahedron's centre (outward is away from it) */
  float lo[3], hi[3]; /* its box over the step */
} face;

typedef struct contact {
  uint32_t dof, fdof[3];
  double beta[3], n[3], gap;
} contact;

typedef struct hash_entry {
  uint64_t key;
  uint32_t face;
} hash_entry;

/* corner k (0..3, cyclic) of face f (0..5: axis f / 2, side f % 2) of a hexahedron (hex.h) */
static int face_corner(int f, int k) {
  const int d = f >> 1, u = (d + 1) % 3, v = (d + 2) % 3;
  static const int iu[4] = {0, 1, 1, 0}, iv[4] = {0, 0, 1, 1};
  return ((f & 1) << d) | (iu[k] << u) | (iv[k] << v);
}

static int uses(const mpm_domain_set *s, uint32_t q, uint32_t c) {
  for (int a = 0; a < MPM_HEX_CORNERS; ++a)
    if (s->corner[q][a] == c) return 1;
  return 0;
}

/* Whether face f of particle p is on the surface (no other active particle has its corners)
 * with its four corners enriched (users: each corner's active particles, at most 8). */
static int surface_face(const mpm_domain_set *s, const uint8_t *users, uint32_t p, int f,
                        uint32_t k[4]) {
  const uint8_t *en = s->enrich.enriched;
  for (int j = 0; j < 4; ++j) { /* a corner of 8 active particles is inside the body */
    k[j] = s->corner[p][face_corner(f, j)];
    if (!en[k[j]] || users[k[j]] >= MPM_HEX_CORNERS) return 0;
  }
  for (uint32_t a = s->adj_start[k[0]]; a < s->adj_start[k[0] + 1]; ++a) {
    const uint32_t q = s->adj[a] / MPM_HEX_CORNERS;
    if (q != p && s->active[q] && uses(s, q, k[1]) && uses(s, q, k[2]) && uses(s, q, k[3]))
      return 0;
  }
  return 1;
}

static uint64_t cell_key(const int64_t c[3]) {
  const int64_t bias = (int64_t)1 << 20, mask = ((int64_t)1 << 21) - 1;
  return ((uint64_t)((c[0] + bias) & mask) << 42) | ((uint64_t)((c[1] + bias) & mask) << 21) |
         (uint64_t)((c[2] + bias) & mask);
}

static int entry_order(const void *a, const void *b) {
  const hash_entry *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return (x->face > y->face) - (x->face < y->face);
}

/* the cells [lo, hi] of the box [a, b] on cells of side H */
static void cell_range(const double a[3], const double b[3], double H, int64_t lo[3],
                       int64_t hi[3]) {
  for (int d = 0; d < 3; ++d) {
    lo[d] = (int64_t)floor(a[d] / H);
    hi[d] = (int64_t)floor(b[d] / H);
  }
}

static void vsub(const double a[3], const double b[3], double r[3]) {
  for (int d = 0; d < 3; ++d) r[d] = a[d] - b[d];
}
static double vdot(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The closest point of triangle (a, b, c) to x, as barycentric weights w (Ericson, Real-Time
 * Collision Detection, sec. 5.1.5: the Voronoi regions of the vertices, edges and face). */
static void closest_on_triangle(const double x[3], const double a[3], const double b[3],
                                const double c[3], double w[3]) {
  double ab[3], ac[3], ax[3], bx[3], cx[3];
  vsub(b, a, ab), vsub(c, a, ac), vsub(x, a, ax);
  const double d1 = vdot(ab, ax), d2 = vdot(ac, ax);
  if (d1 <= 0 && d2 <= 0) {
    w[0] = 1, w[1] = w[2] = 0;
    return;
  }
  vsub(x, b, bx);
  const double d3 = vdot(ab, bx), d4 = vdot(ac, bx);
  if (d3 >= 0 && d4 <= d3) {
    w[1] = 1, w[0] = w[2] = 0;
    return;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    w[0] = 1 - t, w[1] = t, w[2] = 0;
    return;
  }
  vsub(x, c, cx);
  const double d5 = vdot(ab, cx), d6 = vdot(ac, cx);
  if (d6 >= 0 && d5 <= d6) {
    w[2] = 1, w[0] = w[1] = 0;
    return;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    w[0] = 1 - t, w[2] = t, w[1] = 0;
    return;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w[1] = 1 - t, w[2] = t, w[0] = 0;
    return;
  }
  const double den = 1 / (va + vb + vc);
  w[1] = vb * den, w[2] = vc * den, w[0] = 1 - w[1] - w[2];
}

typedef struct ctx {
  const mpm_domain_set *s;
  const mpm_grid_values *dofs;
  double dt;
  const face *faces;
  const hash_entry *hash;
  size_t hash_count;
  double H;
  const int32_t *body; /* per corner */
} ctx;

static uint32_t dof_of(const mpm_domain_set *s, uint32_t c) {
  return (uint32_t)(s->enrich.dof_begin + s->enrich.slot[c]);
}

static uint32_t corner_of(const mpm_domain_set *s, uint32_t dof) {
  return s->enrich.corner[dof - s->enrich.dof_begin];
}

static void corner_x(const mpm_domain_set *s, uint32_t c, double x[3]) {
  for (int d = 0; d < 3; ++d) x[d] = (double)s->cx[d][c];
}

static void dof_v(const mpm_grid_values *g, uint32_t i, double v[3]) {
  for (int d = 0; d < 3; ++d) v[d] = (double)g->v[d][i];
}

/* corner c against face f: a contact into *out (1), or none (0) */
static int touch(const ctx *x, uint32_t c, const double xc[3], const double vc[3], uint32_t f,
                 contact *out) {
  const mpm_domain_set *s = x->s;
  const face *F = &x->faces[f];
  const int bc = x->body[c];
  const double h = (double)s->enrich.body[bc].spacing;
  if (F->body == bc) {
    if (!s->enrich.body[bc].self_contact) return 0;
    double r[3] = {0, 0, 0};
    for (int j = 0; j < 4; ++j)
      for (int d = 0; d < 3; ++d) r[d] += 0.25 * (double)s->cX[d][F->corner[j]];
    for (int d = 0; d < 3; ++d) r[d] -= (double)s->cX[d][c];
    if (vdot(r, r) <= SELF_REACH * SELF_REACH * h * h) return 0;
  }
  double q[4][3];
  for (int j = 0; j < 4; ++j) corner_x(s, F->corner[j], q[j]);
  /* the nearer of the face's two triangles (0 1 2) and (0 2 3) */
  static const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
  double best = INFINITY, w[3] = {0}, p[3] = {0};
  int t = 0;
  for (int k = 0; k < 2; ++k) {
    double wk[3], pk[3] = {0, 0, 0}, r[3];
    closest_on_triangle(xc, q[tri[k][0]], q[tri[k][1]], q[tri[k][2]], wk);
    for (int j = 0; j < 3; ++j)
      for (int d = 0; d < 3; ++d) pk[d] += wk[j] * q[tri[k][j]][d];
    vsub(xc, pk, r);
    const double dist = vdot(r, r);
    if (dist < best) {
      best = dist, t = k;
      memcpy(w, wk, sizeof w);
      memcpy(p, pk, sizeof p);
    }
  }
  /* the triangle's normal, outward from its particle's centre */
  double e1[3], e2[3], n[3];
  vsub(q[tri[t][1]], q[tri[t][0]], e1);
  vsub(q[tri[t][2]], q[tri[t][0]], e2);
  n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double nn = sqrt(vdot(n, n));
  if (!(nn > 0)) return 0;
  const double centre[3] = {F->centre[0], F->centre[1], F->centre[2]};
  double out_dir[3];
  vsub(p, centre, out_dir);
  const double sign = vdot(out_dir, n) < 0 ? -1 : 1;
  for (int d = 0; d < 3; ++d) n[d] *= sign / nn;
  /* in front of the face: the gap is the distance to the closest point, along the line to it
     (a corner above an edge or a crease between faces meets the edge); behind it, the depth
     along the face's normal where the corner projects onto the face */
  double r[3];
  vsub(xc, p, r);
  const double side = vdot(r, n), dist = sqrt(vdot(r, r));
  double gap;
  if (side > 0 && dist > 1e-6 * h) {
    gap = dist;
    for (int d = 0; d < 3; ++d) n[d] = r[d] / dist;
  } else {
    /* behind a face of its own body a corner is mostly in the body's own inside: a thin part
       crushed to less than DEPTH spacings puts one side's corners behind the other side's
       faces, and a hexahedron turned inside out turns its faces' normals; pushing those out
       tore Zhu's tunnel bunny and rolled bunny (their rest-state errors 4.3e-4 and 2.0e-3,
       against 2.7e-6 and 2.9e-5 from the front only). A corner meets its own body's faces
       from the front only */
    if (F->body == bc) return 0;
    gap = side;
    double lateral[3];
    for (int d = 0; d < 3; ++d) lateral[d] = r[d] - side * n[d];
    if (vdot(lateral, lateral) > LATERAL_BEHIND * LATERAL_BEHIND * h * h) return 0;
    if (gap <= -DEPTH * h) return 0;
  }
  /* the relative normal velocity and the gap at the step's end */
  double vn = vdot(vc, n);
  for (int j = 0; j < 3; ++j) {
    double vk[3];
    dof_v(x->dofs, dof_of(s, F->corner[tri[t][j]]), vk);
    vn -= w[j] * vdot(vk, n);
  }
  if (!(gap + x->dt * vn < SKIN * h)) return 0;
  out->dof = dof_of(s, c);
  for (int j = 0; j < 3; ++j) {
    out->fdof[j] = dof_of(s, F->corner[tri[t][j]]);
    out->beta[j] = w[j];
  }
  memcpy(out->n, n, sizeof out->n);
  out->gap = gap - SKIN * h; /* the gap to the skin */
  return 1;
}

/* corner c's contacts into out[0 .. PER_CORNER) (the nearest at the step's end first); their
 * count */
static int corner_contacts(const ctx *x, uint32_t c, contact *out) {
  const mpm_domain_set *s = x->s;
  double xc[3], vc[3], a[3], b[3];
  corner_x(s, c, xc);
  dof_v(x->dofs, dof_of(s, c), vc);
  const double h = (double)s->enrich.body[x->body[c]].spacing, pad = (SKIN + LATERAL_BEHIND) * h;
  for (int d = 0; d < 3; ++d) {
    const double e = xc[d] + x->dt * vc[d];
    a[d] = fmin(xc[d], e) - pad;
    b[d] = fmax(xc[d], e) + pad;
  }
  int64_t lo[3], hi[3];
  cell_range(a, b, x->H, lo, hi);
  int n = 0;
  double end_gap[PER_CORNER];
  int64_t cc[3];
  for (cc[0] = lo[0]; cc[0] <= hi[0]; ++cc[0])
    for (cc[1] = lo[1]; cc[1] <= hi[1]; ++cc[1])
      for (cc[2] = lo[2]; cc[2] <= hi[2]; ++cc[2]) {
        const uint64_t key = cell_key(cc);
        size_t l = 0, r = x->hash_count;
        while (l < r) { /* the first entry of the cell */
          const size_t m = l + (r - l) / 2;
          if (x->hash[m].key < key)
            l = m + 1;
          else
            r = m;
        }
        for (; l < x->hash_count && x->hash[l].key == key; ++l) {
          const uint32_t f = x->hash[l].face;
          const face *F = &x->faces[f];
          if (F->lo[0] > b[0] || F->hi[0] < a[0] || F->lo[1] > b[1] || F->hi[1] < a[1] ||
              F->lo[2] > b[2] || F->hi[2] < a[2])
            continue; /* their boxes apart */
          /* the face is in every cell its box touches: taken in the first cell that both
             boxes touch only */
          int first = 1;
          for (int d = 0; d < 3 && first; ++d) {
            const int64_t from = (int64_t)floor((double)F->lo[d] / x->H);
            first = cc[d] == (from > lo[d] ? from : lo[d]);
          }
          if (!first) continue;
          contact k;
          if (!touch(x, c, xc, vc, f, &k)) continue;
          double vn = vdot(vc, k.n);
          for (int j = 0; j < 3; ++j) {
            double vk[3];
            dof_v(x->dofs, k.fdof[j], vk);
            vn -= k.beta[j] * vdot(vk, k.n);
          }
          const double g = k.gap + x->dt * vn;
          /* insert by the gap at the step's end (ties: the face's order, as found) */
          int at = n < PER_CORNER ? n : PER_CORNER;
          while (at > 0 && end_gap[at - 1] > g) --at;
          if (at >= PER_CORNER) continue;
          const int last = n < PER_CORNER ? n : PER_CORNER - 1;
          for (int j = last; j > at; --j) {
            out[j] = out[j - 1];
            end_gap[j] = end_gap[j - 1];
          }
          out[at] = k;
          end_gap[at] = g;
          if (n < PER_CORNER) ++n;
        }
      }
  return n;
}

/* The impulse of contact k at the current velocities (enrich_surface_contact.h); 1 when it
 * took one. */
static int resolve(const contact *k, const mpm_grid_values *g, double dt) {
  double vn = 0;
  for (int d = 0; d < 3; ++d) vn += (double)g->v[d][k->dof] * k->n[d];
  double inv = 1 / (double)g->mass[k->dof];
  for (int j = 0; j < 3; ++j) {
    const uint32_t i = k->fdof[j];
    for (int d = 0; d < 3; ++d) vn -= k->beta[j] * (double)g->v[d][i] * k->n[d];
    inv += k->beta[j] * k->beta[j] / (double)g->mass[i];
  }
  /* to the skin, or out of it by RECOVERY of the depth this step */
  const double target = k->gap > 0 ? -k->gap / dt : -RECOVERY * k->gap / dt;
  if (!(vn < target)) return 0;
  const double j = (target - vn) / inv;
  const double mc = (double)g->mass[k->dof];
  for (int d = 0; d < 3; ++d) {
    g->v[d][k->dof] = (mpm_real)((double)g->v[d][k->dof] + j / mc * k->n[d]);
    for (int q = 0; q < 3; ++q) {
      const uint32_t i = k->fdof[q];
      g->v[d][i] = (mpm_real)((double)g->v[d][i] - j * k->beta[q] / (double)g->mass[i] * k->n[d]);
    }
  }
  return 1;
}

mpm_status mpm_surface_contact(const mpm_domain_set *s, const mpm_grid_values *dofs, double dt,
                               mpm_arena *scratch, mpm_surface_contact_stats *stats) {
  memset(stats, 0, sizeof *stats);
  if (!mpm_surface_contact_on(s) || !(dt > 0)) return MPM_OK;
  const mpm_domain_enrichment *e = &s->enrich;
  const size_t np = s->particles.count, nc = s->corner_count;
  /* the surface faces, particle by particle */
  uint8_t *mask = mpm_arena_alloc(scratch, np + 1);
  uint32_t *start = mpm_arena_alloc(scratch, (np + 1) * sizeof *start);
  int32_t *body = mpm_arena_alloc(scratch, (nc + 1) * sizeof *body);
  if (!mask || !start || !body) return MPM_ERR_NOMEM;
  uint8_t *users = mpm_arena_alloc(scratch, nc + 1);
  if (!users) return MPM_ERR_NOMEM;
  const long ncl = (long)nc;
#pragma omp parallel for schedule(static) if (ncl > MPM_PARALLEL_MIN)
  for (long c = 0; c < ncl; ++c) {
    const uint32_t a0 = s->adj_start[c], a1 = s->adj_start[c + 1];
    body[c] = mpm_domain_corner_body(s, (size_t)c);
    int n = 0;
    for (uint32_t a = a0; a < a1; ++a) n += s->active[s->adj[a] / MPM_HEX_CORNERS] != 0;
    users[c] = (uint8_t)n;
  }
  const long npl = (long)np;
#pragma omp parallel for schedule(static) if (npl > MPM_PARALLEL_MIN)
  for (long p = 0; p < npl; ++p) {
    mask[p] = 0;
    const int b = s->particles.body[p];
    if (!s->active[p] || b < 0 || b >= e->body_count || !e->body[b].surface_contact) continue;
    uint32_t k[4];
    for (int f = 0; f < 6; ++f)
      if (surface_face(s, users, (uint32_t)p, f, k)) mask[p] |= (uint8_t)(1u << f);
  }
  size_t nf = 0;
  for (size_t p = 0; p < np; ++p) {
    start[p] = (uint32_t)nf;
    nf += (size_t)__builtin_popcount(mask[p]);
  }
  start[np] = (uint32_t)nf;
  stats->faces = nf;
  if (!nf) return MPM_OK;
  face *faces = mpm_arena_alloc(scratch, nf * sizeof *faces);
  uint32_t *cells = mpm_arena_alloc(scratch, (nf + 1) * sizeof *cells);
  uint8_t *on_surface = mpm_arena_alloc(scratch, nc + 1);
  if (!faces || !cells || !on_surface) return MPM_ERR_NOMEM;
  /* the hash's cells: twice the largest lattice spacing of the bodies in contact */
  double hmax = 0;
  for (int b = 0; b < e->body_count; ++b)
    if (e->body[b].surface_contact) hmax = fmax(hmax, (double)e->body[b].spacing);
  const double H = 2 * hmax;
#pragma omp parallel for schedule(static) if (npl > MPM_PARALLEL_MIN)
  for (long p = 0; p < npl; ++p) {
    uint32_t at = start[p];
    for (int f = 0; f < 6; ++f) {
      if (!(mask[p] >> f & 1)) continue;
      face *F = &faces[at];
      F->particle = (uint32_t)p;
      F->body = s->particles.body[p];
      for (int j = 0; j < 4; ++j) F->corner[j] = s->corner[p][face_corner(f, j)];
      double centre[3] = {0, 0, 0};
      for (int k = 0; k < MPM_HEX_CORNERS; ++k)
        for (int d = 0; d < 3; ++d) centre[d] += (double)s->cx[d][s->corner[p][k]];
      /* its box over the step */
      double a[3] = {INFINITY, INFINITY, INFINITY}, b[3] = {-INFINITY, -INFINITY, -INFINITY};
      for (int j = 0; j < 4; ++j) {
        double x[3], v[3];
        corner_x(s, F->corner[j], x);
        dof_v(dofs, dof_of(s, F->corner[j]), v);
        for (int d = 0; d < 3; ++d) {
          const double y = x[d] + dt * v[d];
          a[d] = fmin(a[d], fmin(x[d], y));
          b[d] = fmax(b[d], fmax(x[d], y));
        }
      }
      for (int d = 0; d < 3; ++d) {
        F->centre[d] = (float)(centre[d] / MPM_HEX_CORNERS);
        F->lo[d] = (float)a[d];
        F->hi[d] = (float)b[d];
        a[d] = F->lo[d]; /* the cells of the box as kept (the hash's fill reads these) */
        b[d] = F->hi[d];
      }
      int64_t lo[3], hi[3];
      cell_range(a, b, H, lo, hi);
      cells[at] = (uint32_t)((hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1));
      ++at;
    }
  }
  /* the hash: (cell, face) entries sorted */
  size_t ne = 0;
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t k = cells[f];
    cells[f] = (uint32_t)ne;
    ne += k;
  }
  hash_entry *hash = mpm_arena_alloc(scratch, (ne + 1) * sizeof *hash);
  if (!hash) return MPM_ERR_NOMEM;
  const long nfl = (long)nf;
#pragma omp parallel for schedule(static) if (nfl > MPM_PARALLEL_MIN / 8)
  for (long f = 0; f < nfl; ++f) {
    const face *F = &faces[f];
    const double a[3] = {F->lo[0], F->lo[1], F->lo[2]}, b[3] = {F->hi[0], F->hi[1], F->hi[2]};
    int64_t lo[3], hi[3], c[3];
    cell_range(a, b, H, lo, hi);
    size_t at = cells[f];
    for (c[0] = lo[0]; c[0] <= hi[0]; ++c[0])
      for (c[1] = lo[1]; c[1] <= hi[1]; ++c[1])
        for (c[2] = lo[2]; c[2] <= hi[2]; ++c[2])
          hash[at++] = (hash_entry){cell_key(c), (uint32_t)f};
  }
  qsort(hash, ne, sizeof *hash, entry_order);
  /* the enriched corners on the surface, in corner order */
  memset(on_surface, 0, nc);
  for (size_t f = 0; f < nf; ++f)
    for (int j = 0; j < 4; ++j) on_surface[faces[f].corner[j]] = 1;
  size_t ns = 0;
  for (size_t c = 0; c < nc; ++c) ns += on_surface[c];
  stats->corners = ns;
  uint32_t *corner = mpm_arena_alloc(scratch, (ns + 1) * sizeof *corner);
  contact *found = mpm_arena_alloc(scratch, (ns * PER_CORNER + 1) * sizeof *found);
  uint8_t *count = mpm_arena_alloc(scratch, ns + 1);
  if (!corner || !found || !count) return MPM_ERR_NOMEM;
  for (size_t c = 0, k = 0; c < nc; ++c)
    if (on_surface[c]) corner[k++] = (uint32_t)c;
  const ctx x = {s, dofs, dt, faces, hash, ne, H, body};
  const long nsl = (long)ns;
  /* a corner's search (its hash cells, each face there) costs some hundred times an
     element-wise loop's item: parallel from far fewer corners */
#pragma omp parallel for schedule(dynamic, 64) if (nsl > MPM_PARALLEL_MIN / 64)
  for (long k = 0; k < nsl; ++k) {
    const uint32_t c = corner[k];
    const int b = body[c];
    count[k] = 0;
    if (b < 0 || b >= e->body_count || !e->body[b].surface_contact) continue;
    count[k] = (uint8_t)corner_contacts(&x, c, found + (size_t)k * PER_CORNER);
  }
  size_t nk = 0;
  for (size_t k = 0; k < ns; ++k)
    for (int j = 0; j < count[k]; ++j) found[nk++] = found[k * PER_CORNER + (size_t)j];
  if (!nk) return MPM_OK;
  /* the impulses: a few Gauss-Seidel sweeps, in parallel by tiles (core/tile_batches.h). A
     contact touches its corner and its face's corners, all within `reach` of the corner along
     each axis; tiles of twice that side keep one colour's tiles' contacts apart */
  uint8_t *took = mpm_arena_alloc(scratch, nk + 1);
  int32_t(*tile)[3] = mpm_arena_alloc(scratch, (nk + 1) * sizeof *tile);
  if (!took || !tile) return MPM_ERR_NOMEM;
  memset(took, 0, nk + 1);
  double reach = 0;
  for (size_t k = 0; k < nk; ++k) {
    double xc[3];
    corner_x(s, corner_of(s, found[k].dof), xc);
    for (int j = 0; j < 3; ++j) {
      double xf[3];
      corner_x(s, corner_of(s, found[k].fdof[j]), xf);
      for (int d = 0; d < 3; ++d) reach = fmax(reach, fabs(xf[d] - xc[d]));
    }
  }
  const double side = 2.001 * reach + 1e-3 * hmax;
  for (size_t k = 0; k < nk; ++k) {
    double xc[3];
    corner_x(s, corner_of(s, found[k].dof), xc);
    for (int d = 0; d < 3; ++d) tile[k][d] = (int32_t)fmax(-1e9, fmin(1e9, floor(xc[d] / side)));
  }
  mpm_tile_batches batch;
  if (mpm_tile_batches_build(nk, (const int32_t(*)[3])tile, scratch, &batch)) return MPM_ERR_NOMEM;
  for (int sweep = 0; sweep < SWEEPS; ++sweep)
    for (int colour = 0; colour < MPM_TILE_COLOURS; ++colour) {
      const long t0 = (long)batch.colour_start[colour], t1 = (long)batch.colour_start[colour + 1];
#pragma omp parallel for schedule(dynamic, 4) if (t1 - t0 > 1)
      for (long t = t0; t < t1; ++t)
        for (size_t i = batch.tile_start[t]; i < batch.tile_start[t + 1]; ++i) {
          const uint32_t k = batch.item[i];
          took[k] |= (uint8_t)resolve(&found[k], dofs, dt);
        }
    }
  for (size_t k = 0; k < nk; ++k) stats->contacts += took[k];
  return MPM_OK;
}
