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
#include "domain/domain.h"
#include "scene/scene.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define REAL_TYPE (sizeof(mpm_real) == 8 ? "Float64" : "Float32")

typedef struct out {
  FILE *fp;
  int err;
} out;

static void put(out *o, const void *p, size_t n) {
  if (o->err || !n) return;
  errno = 0;
  if (fwrite(p, 1, n, o->fp) != n) o->err = errno ? errno : EIO;
}

static void put_count(out *o, uint64_t bytes) {
  put(o, &bytes, sizeof bytes);
}

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
  out o = {f.fp, 0};
  char head[4096];
  snprintf(
      head, sizeof head,
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <FieldData>\n"
      "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" "
      "format=\"appended\" offset=\"%llu\"/>\n"
      "    </FieldData>\n"
      "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
      "      <Points>\n"
      "        <DataArray type=\"%s\" Name=\"Points\" NumberOfComponents=\"3\" "
      "format=\"appended\" offset=\"%llu\"/>\n"
      "      </Points>\n"
      "      <PointData>\n"
      "        <DataArray type=\"%s\" Name=\"velocity\" NumberOfComponents=\"3\" "
      "format=\"appended\" offset=\"%llu\"/>\n"
      "      </PointData>\n"
      "      <CellData>\n"
      "        <DataArray type=\"UInt32\" Name=\"id\" format=\"appended\" offset=\"%llu\"/>\n"
      "        <DataArray type=\"%s\" Name=\"J\" format=\"appended\" offset=\"%llu\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"material\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"body\" format=\"appended\" offset=\"%llu\"/>\n"
      "        <DataArray type=\"Int32\" Name=\"enrichment\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "      </CellData>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" "
      "offset=\"%llu\"/>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"%llu\"/>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "  <AppendedData encoding=\"raw\">\n_",
      (unsigned long long)off[0], nc, ncell, REAL_TYPE, (unsigned long long)off[1], REAL_TYPE,
      (unsigned long long)off[2], (unsigned long long)off[3], REAL_TYPE, (unsigned long long)off[4],
      (unsigned long long)off[5], (unsigned long long)off[6], (unsigned long long)off[10],
      (unsigned long long)off[7], (unsigned long long)off[8], (unsigned long long)off[9]);
  /* the header in two parts, the selected arrays' lines between them: the CellData's end */
  char *cell_end = strstr(head, "      </CellData>");
  put(&o, head, (size_t)(cell_end - head));
  if (extra && !o.err) o.err = mpm_vtu_particle_arrays_header(f.fp, cells, extra, at, "        ");
  put(&o, cell_end, strlen(cell_end));
  put_count(&o, sizes[0]);
  put(&o, &time, sizeof time);
  /* corner positions and velocities, interleaved */
  for (int which = 0; which < 2; ++which) {
    mpm_real *const *c = which == 0 ? s->cx : s->cv;
    put_count(&o, sizes[1 + which]);
    for (size_t i = 0; i < nc; ++i) {
      const mpm_real t[3] = {c[0][i], c[1][i], c[2][i]};
      put(&o, t, sizeof t);
    }
  }
  const mpm_particles *p = &s->particles;
  put_count(&o, sizes[3]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) put(&o, &p->id[i], 4);
  put_count(&o, sizes[4]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) {
      mpm_real *const *F = p->F;
      const mpm_real J = F[0][i] * (F[4][i] * F[8][i] - F[5][i] * F[7][i]) -
                         F[1][i] * (F[3][i] * F[8][i] - F[5][i] * F[6][i]) +
                         F[2][i] * (F[3][i] * F[7][i] - F[4][i] * F[6][i]);
      put(&o, &J, sizeof J);
    }
  put_count(&o, sizes[5]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) put(&o, &p->material[i], 4);
  put_count(&o, sizes[6]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) put(&o, &p->body[i], 4);
  put_count(&o, sizes[7]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i])
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
        const int64_t c = s->corner[i][MPM_HEX_VTK_ORDER[a]];
        put(&o, &c, sizeof c);
      }
  put_count(&o, sizes[8]);
  for (size_t k = 1; k <= ncell; ++k) {
    const int64_t end = (int64_t)(8 * k);
    put(&o, &end, sizeof end);
  }
  put_count(&o, sizes[9]);
  const uint8_t hex = 12; /* VTK_HEXAHEDRON */
  for (size_t k = 0; k < ncell; ++k) put(&o, &hex, 1);
  /* the enrichment category of each domain (Zhu sec. 5.2: 0 unenriched, 1 transitional, 2
   * enriched), from the marks of the set's current F (domain/enrich.h) */
  put_count(&o, sizes[10]);
  for (size_t i = 0; i < p->count; ++i)
    if (s->active[i]) {
      const int32_t cat = s->enrich.category ? s->enrich.category[i] : 0;
      put(&o, &cat, sizeof cat);
    }
  if (extra && !o.err) o.err = mpm_vtu_particle_arrays_data(f.fp, cells, extra);
  put(&o, "\n  </AppendedData>\n</VTKFile>\n", strlen("\n  </AppendedData>\n</VTKFile>\n"));
  if (o.err) {
    mpm_atomic_abort(&f);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&f, err);
}
