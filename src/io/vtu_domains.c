/* vtu_domains.c - the particle domains of one frame as a VTK UnstructuredGrid of hexahedra
 * (domains_NNNN.vtu): the corners are the points, each active domain particle is one
 * VTK_HEXAHEDRON cell over its 8 corners, so ParaView shows the deformed domains as a mesh.
 *
 * Same layout as vtu.c (XML header, UInt64 byte counts, one raw appended block): FieldData
 * TIME; Points (corner positions); PointData velocity (corner velocities); CellData id, J
 * (det F), material, body, enrichment, then the per-particle arrays output.fields lists beyond
 * those (the domain particle's velocity, stress tensor, pressure, F, ...: vtu.c writes them);
 * Cells connectivity (VTK's hexahedron order, domain/hex.h), offsets, types. Without
 * output.fields the file is what it was before the key existed. */
#include "io/io.h"
#include "io/vtu_stream.h"
#include "domain/domain.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define REAL_TYPE (sizeof(mpm_real) == 8 ? "Float64" : "Float32")

/* The fields the domain file writes of its own, whatever output.fields says. */
#define OWN_FIELDS                                                                                 \
  (1u << MPM_FIELD_ID | 1u << MPM_FIELD_J | 1u << MPM_FIELD_MATERIAL | 1u << MPM_FIELD_BODY |      \
   1u << MPM_FIELD_ENRICHMENT)

mpm_status mpm_write_domain_vtu(const char *path, const mpm_domain_set *s, double time,
                                const mpm_frame_fields *cells, mpm_error *err) {
  const size_t nc = s->corner_count;
  size_t ncell = 0;
  for (size_t i = 0; i < s->particles.count; ++i) ncell += s->active[i] != 0;
  const size_t R = sizeof(mpm_real);
  /* byte sizes of the arrays, in appended order, and their offsets */
  const uint64_t sizes[11] = {sizeof(double), 3 * nc * R, 3 * nc * R, ncell * 4,
                              ncell * R,      ncell * 4,  ncell * 4,  8 * ncell * 8,
                              ncell * 8,      ncell,      ncell * 4};
  uint64_t off[11], at = 0;
  for (int k = 0; k < 11; ++k) {
    off[k] = at;
    at += 8 + sizes[k];
  }
  /* output.fields' arrays, after the file's own */
  const unsigned extra = cells && cells->fields ? cells->fields & ~OWN_FIELDS : 0;
  if (extra && cells->particles->count != ncell)
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: %zu cell values for %zu domains", path,
                         cells->particles->count, ncell);
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st != MPM_OK) return st;
  mpm_vtu_stream o = {f.fp, 0};
  mpm_vtu_begin(&o);
  mpm_vtu_data_array(&o, 1, "Float64", "TIME", 1, 1, off[0]);
  mpm_vtu_piece(&o, nc, ncell);
  mpm_vtu_section(&o, "Points", 1, NULL);
  mpm_vtu_data_array(&o, 0, REAL_TYPE, "Points", 3, 0, off[1]);
  mpm_vtu_section(&o, "Points", 0, NULL);
  mpm_vtu_section(&o, "PointData", 1, NULL);
  mpm_vtu_data_array(&o, 0, REAL_TYPE, "velocity", 3, 0, off[2]);
  mpm_vtu_section(&o, "PointData", 0, NULL);
  mpm_vtu_section(&o, "CellData", 1, NULL);
  mpm_vtu_data_array(&o, 0, "UInt32", "id", 1, 0, off[3]);
  mpm_vtu_data_array(&o, 0, REAL_TYPE, "J", 1, 0, off[4]);
  mpm_vtu_data_array(&o, 0, "Int32", "material", 1, 0, off[5]);
  mpm_vtu_data_array(&o, 0, "Int32", "body", 1, 0, off[6]);
  mpm_vtu_data_array(&o, 0, "Int32", "enrichment", 1, 0, off[10]);
  if (extra) mpm_vtu_particle_arrays_header(&o, cells, extra, at);
  mpm_vtu_section(&o, "CellData", 0, NULL);
  mpm_vtu_section(&o, "Cells", 1, NULL);
  mpm_vtu_data_array(&o, 0, "Int64", "connectivity", 1, 0, off[7]);
  mpm_vtu_data_array(&o, 0, "Int64", "offsets", 1, 0, off[8]);
  mpm_vtu_data_array(&o, 0, "UInt8", "types", 1, 0, off[9]);
  mpm_vtu_section(&o, "Cells", 0, NULL);
  mpm_vtu_end_head(&o);
  mpm_vtu_put_count(&o, sizes[0]);
  mpm_vtu_put(&o, &time, sizeof time);
  /* corner positions and velocities, interleaved */
  for (int which = 0; which < 2; ++which) {
    mpm_real *const *c = which == 0 ? s->cx : s->cv;
    mpm_vtu_put_count(&o, sizes[1 + which]);
    for (size_t i = 0; i < nc; ++i) {
      const mpm_real t[3] = {c[0][i], c[1][i], c[2][i]};
      mpm_vtu_put(&o, t, sizeof t);
    }
  }
  const mpm_particles *p = &s->particles;
  mpm_vtu_put_count(&o, sizes[3]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) mpm_vtu_put(&o, &p->id[i], 4);
  mpm_vtu_put_count(&o, sizes[4]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) {
      mpm_real *const *F = p->F;
      const mpm_real J = F[0][i] * (F[4][i] * F[8][i] - F[5][i] * F[7][i]) -
                         F[1][i] * (F[3][i] * F[8][i] - F[5][i] * F[6][i]) +
                         F[2][i] * (F[3][i] * F[7][i] - F[4][i] * F[6][i]);
      mpm_vtu_put(&o, &J, sizeof J);
    }
  mpm_vtu_put_count(&o, sizes[5]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) mpm_vtu_put(&o, &p->material[i], 4);
  mpm_vtu_put_count(&o, sizes[6]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) mpm_vtu_put(&o, &p->body[i], 4);
  mpm_vtu_put_count(&o, sizes[7]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i])
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
        const int64_t c = s->corner[i][MPM_HEX_VTK_ORDER[a]];
        mpm_vtu_put(&o, &c, sizeof c);
      }
  mpm_vtu_put_count(&o, sizes[8]);
  for (size_t k = 1; k <= ncell; ++k) {
    const int64_t end = (int64_t)(8 * k);
    mpm_vtu_put(&o, &end, sizeof end);
  }
  mpm_vtu_put_count(&o, sizes[9]);
  const uint8_t hex = 12; /* VTK_HEXAHEDRON */
  for (size_t k = 0; k < ncell; ++k) mpm_vtu_put(&o, &hex, 1);
  /* the enrichment category of each domain (Zhu sec. 5.2: 0 unenriched, 1 transitional, 2
   * enriched), from the marks of the set's current F (domain/enrich.h) */
  mpm_vtu_put_count(&o, sizes[10]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) {
      const int32_t cat = s->enrich.category ? s->enrich.category[i] : 0;
      mpm_vtu_put(&o, &cat, sizeof cat);
    }
  if (extra) mpm_vtu_particle_arrays_data(&o, cells, extra);
  mpm_vtu_finish(&o);
  if (o.err) {
    mpm_atomic_abort(&f);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&f, err);
}
