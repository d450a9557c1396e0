/* ply_points.c - one frame of particles as a binary little-endian PLY point cloud.
 *
 * Format: PLY (Turk, 1994), `format binary_little_endian 1.0`, one `vertex` element per
 * particle with properties x y z vx vy vz pscale (float or double, the build's mpm_real), id
 * (uint), material and body (int), packed without padding. Meant for renderers and
 * point-cloud tools (Houdini, Blender, CloudCompare), hence the names: vx vy vz the velocity's
 * components (docs/houdini-blender.md says how to join them into Houdini's v) and pscale
 * Houdini's per-point radius, which it instances and renders spheres with. pscale is the radius of
 * the sphere of the particle's current volume, V0 det F (the VTU's `volume`): compressed particles
 * get smaller, and at rest the spheres of a body fill its volume. Records are interleaved from the
 * structure-of-arrays particles a chunk at a time through one fixed buffer, and the file is written
 * atomically. */
#include "io/io.h"
#include "core/alloc.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "ply_points.c writes native byte order and declares little endian; add byte swapping"
#endif

#define PLY_RECORD_BYTES (7 * sizeof(mpm_real) + sizeof(uint32_t) + 2 * sizeof(int32_t))
/* the buffer stays under the writers' 64 KiB bound (test_io) in a double build too */
#define PLY_CHUNK_RECORDS 512

typedef struct ply_out {
  FILE *fp;
  int err; /* errno of the first failed write */
} ply_out;

static void out_bytes(ply_out *o, const void *p, size_t n) {
  if (o->err || n == 0) return;
  errno = 0;
  if (fwrite(p, 1, n, o->fp) != n) o->err = errno ? errno : EIO;
}

static void write_header(ply_out *o, const mpm_frame_fields *f) {
  const char *t = sizeof(mpm_real) == 8 ? "double" : "float";
  char head[512];
  const int n = snprintf(head, sizeof head,
                         "ply\n"
                         "format binary_little_endian 1.0\n"
                         "comment mpm particles, time %.9g s\n"
                         "element vertex %zu\n"
                         "property %s x\nproperty %s y\nproperty %s z\n"
                         "property %s vx\nproperty %s vy\nproperty %s vz\n"
                         "property %s pscale\n"
                         "property uint id\nproperty int material\nproperty int body\n"
                         "end_header\n",
                         f->time, f->particles->count, t, t, t, t, t, t, t);
  out_bytes(o, head, (size_t)n);
}

/* The radius of the sphere of particle j's current volume V0 J, with J = det F as the frame
 * gives it (or from F), the way the VTU's volume is made. */
static mpm_real pscale(const mpm_frame_fields *f, size_t j) {
  const mpm_particles *p = f->particles;
  mpm_real J;
  if (f->J) {
    J = f->J[j];
  } else {
    mpm_real *const *F = p->F;
    J = F[0][j] * (F[4][j] * F[8][j] - F[5][j] * F[7][j]) -
        F[1][j] * (F[3][j] * F[8][j] - F[5][j] * F[6][j]) +
        F[2][j] * (F[3][j] * F[7][j] - F[4][j] * F[6][j]);
  }
  const mpm_real volume = J * p->vol0[j];
  /* an inverted particle (J <= 0, which the guards stop) gets radius 0, not a NaN */
  const double sphere = 4.18879020478639098; /* 4 pi / 3: ISO C has no M_PI */
  return volume > 0 ? (mpm_real)cbrt((double)volume / sphere) : 0;
}

/* Pack records [first, first + n) into buf: x y z vx vy vz pscale id material body,
 * unaligned, via memcpy. */
static void pack(const mpm_frame_fields *f, size_t first, size_t n, unsigned char *buf) {
  const mpm_particles *p = f->particles;
  const size_t rs = sizeof(mpm_real);
  for (size_t i = 0; i < n; ++i) {
    unsigned char *r = buf + i * PLY_RECORD_BYTES;
    const size_t j = first + i;
    for (int d = 0; d < 3; ++d) {
      memcpy(r + d * rs, &p->x[d][j], rs);
      memcpy(r + (3 + d) * rs, &p->v[d][j], rs);
    }
    const mpm_real radius = pscale(f, j);
    memcpy(r + 6 * rs, &radius, rs);
    memcpy(r + 7 * rs, &p->id[j], sizeof(uint32_t));
    memcpy(r + 7 * rs + 4, &p->material[j], sizeof(int32_t));
    memcpy(r + 7 * rs + 8, &p->body[j], sizeof(int32_t));
  }
}

mpm_status mpm_write_ply_points(const char *path, const mpm_frame_fields *f, mpm_error *err) {
  const mpm_particles *p = f->particles;
  unsigned char *buf = mpm_alloc(PLY_CHUNK_RECORDS * PLY_RECORD_BYTES);
  if (!buf) return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write '%s': out of memory", path);
  mpm_atomic_file af;
  const mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) {
    mpm_free(buf);
    return st;
  }
  ply_out o = {af.fp, 0};
  write_header(&o, f);
  for (size_t first = 0; first < p->count && !o.err; first += PLY_CHUNK_RECORDS) {
    const size_t n = p->count - first < PLY_CHUNK_RECORDS ? p->count - first : PLY_CHUNK_RECORDS;
    pack(f, first, n, buf);
    out_bytes(&o, buf, n * PLY_RECORD_BYTES);
  }
  mpm_free(buf);
  if (o.err) {
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&af, err);
}
