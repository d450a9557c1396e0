/* vtu.c - one frame of particles as a VTK XML UnstructuredGrid (.vtu), binary appended.
 *
 * Format: VTK XML file formats, version 1.0 with header_type UInt64 (Kitware, "VTK File
 * Formats", XML section). Each particle is one VTK_VERTEX cell. The XML header names every
 * array with an `offset` into a single `<AppendedData encoding="raw">` block that starts after
 * a `_`; each array there is a UInt64 byte count followed by the raw little-endian values.
 *
 * Particles are stored as structure of arrays while VTK wants interleaved tuples (x y z), so
 * every array is produced by a fill function into one fixed 32 KiB buffer and streamed a chunk
 * at a time: a million particles need no more memory than that.
 *
 * Arrays: FieldData TIME (Float64); Points; PointData, those of fields->fields (the scene's
 * output.fields; by default id, velocity, mass, volume (= V0 J, the current volume), J, stress
 * (von Mises, Pa), plastic (the model's plastic state: snow J_p, Drucker-Prager's volume
 * correction), material, body, level, enrichment, and with heat temperature and melt (the
 * melt fraction, 0 solid to 1 melted); on request cauchy_stress (9 components, a VTK tensor,
 * Pa), pressure (Pa) and F (9 components)); Cells connectivity, offsets, types. Tensors are
 * row-major, as ParaView names the components (XX, XY, XZ, YX, ...). Reals are Float32 or
 * Float64 as the build's mpm_real. When fields->J is NULL, J is det F of each particle; when
 * fields->stress (cauchy, pressure) is NULL, that array is written as zero. */
#include "io/io.h"
#include "io/vtu_stream.h"
#include "core/alloc.h"

#include <errno.h>
#include <stdint.h>
#include <string.h>

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "vtu.c writes native byte order and declares LittleEndian; add byte swapping first"
#endif

#define VTU_REAL_TYPE (sizeof(mpm_real) == 8 ? "Float64" : "Float32")
#define VTU_CHUNK_BYTES (1 << 15)

/* Fill `n` tuples starting at particle `first` into out (interleaved components). */
typedef void (*vtu_fill_fn)(const mpm_frame_fields *f, size_t first, size_t n, void *out);

typedef struct vtu_array {
  const char *section; /* "field", "point", "points", "cells": where the header lists it */
  const char *name;
  const char *type;  /* VTK type name */
  size_t comp_bytes; /* bytes of one component */
  int comps;
  int per_particle; /* 1: count tuples, 0: a single tuple (TIME) */
  int field;        /* the mpm_output_field that selects it; -1: always written */
  vtu_fill_fn fill;
} vtu_array;

static void fill_time(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  (void)first;
  (void)n;
  memcpy(out, &f->time, sizeof f->time);
}

static void fill_xyz(mpm_real *const *c, size_t first, size_t n, mpm_real *o) {
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) o[3 * i + d] = c[d][first + i];
}

static void fill_points(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  fill_xyz(f->particles->x, first, n, out);
}

static void fill_velocity(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  fill_xyz(f->particles->v, first, n, out);
}

static void fill_id(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->id + first, n * sizeof(uint32_t));
}

static void fill_mass(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->mass + first, n * sizeof(mpm_real));
}

/* det F, for callers that pass no J */
static mpm_real det_f(const mpm_particles *p, size_t i) {
  mpm_real *const *F = p->F;
  return F[0][i] * (F[4][i] * F[8][i] - F[5][i] * F[7][i]) -
         F[1][i] * (F[3][i] * F[8][i] - F[5][i] * F[6][i]) +
         F[2][i] * (F[3][i] * F[7][i] - F[4][i] * F[6][i]);
}

static void fill_J(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  mpm_real *o = out;
  if (f->J)
    memcpy(o, f->J + first, n * sizeof(mpm_real));
  else
    for (size_t i = 0; i < n; ++i) o[i] = det_f(f->particles, first + i);
}

static void fill_volume(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  mpm_real *o = out;
  fill_J(f, first, n, o);
  const mpm_real *vol0 = f->particles->vol0 + first;
  for (size_t i = 0; i < n; ++i) o[i] *= vol0[i];
}

static void fill_stress(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  if (f->stress)
    memcpy(out, f->stress + first, n * sizeof(mpm_real));
  else
    memset(out, 0, n * sizeof(mpm_real));
}

static void fill_plastic(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->plastic + first, n * sizeof(mpm_real));
}

static void fill_material(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->material + first, n * sizeof(int32_t));
}

static void fill_body(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->body + first, n * sizeof(int32_t));
}

static void fill_level(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->level + first, n * sizeof(int32_t));
}

static void fill_enrichment(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  int32_t *o = out;
  for (size_t i = 0; i < n; ++i) o[i] = f->enrichment ? f->enrichment[first + i] : -1;
}

static void fill_temperature(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  memcpy(out, f->particles->temperature + first, n * sizeof(mpm_real));
}

static void fill_melt(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  if (f->melt)
    memcpy(out, f->melt + first, n * sizeof(mpm_real));
  else
    memset(out, 0, n * sizeof(mpm_real));
}

static void fill_cauchy(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  if (f->cauchy)
    memcpy(out, f->cauchy + 9 * first, 9 * n * sizeof(mpm_real));
  else
    memset(out, 0, 9 * n * sizeof(mpm_real));
}

static void fill_pressure(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  if (f->pressure)
    memcpy(out, f->pressure + first, n * sizeof(mpm_real));
  else
    memset(out, 0, n * sizeof(mpm_real));
}

/* F is stored as nine arrays, one per row-major component; VTK wants the nine of a particle
 * together. */
static void fill_F(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  mpm_real *o = out;
  mpm_real *const *F = f->particles->F;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 9; ++c) o[9 * i + c] = F[c][first + i];
}

static void fill_connectivity(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  (void)f;
  int64_t *o = out;
  for (size_t i = 0; i < n; ++i) o[i] = (int64_t)(first + i);
}

static void fill_offsets(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  (void)f;
  int64_t *o = out;
  for (size_t i = 0; i < n; ++i) o[i] = (int64_t)(first + i + 1);
}

static void fill_types(const mpm_frame_fields *f, size_t first, size_t n, void *out) {
  (void)f;
  (void)first;
  memset(out, 1, n); /* VTK_VERTEX = 1 */
}

/* In order of appearance in the appended block; the header groups them by section. */
#define VTU_ARRAYS 21
static const vtu_array vtu_arrays[VTU_ARRAYS] = {
    {"field", "TIME", "Float64", sizeof(double), 1, 0, -1, fill_time},
    {"points", "Points", NULL, sizeof(mpm_real), 3, 1, -1, fill_points},
    {"point", "id", "UInt32", sizeof(uint32_t), 1, 1, MPM_FIELD_ID, fill_id},
    {"point", "velocity", NULL, sizeof(mpm_real), 3, 1, MPM_FIELD_VELOCITY, fill_velocity},
    {"point", "mass", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_MASS, fill_mass},
    {"point", "volume", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_VOLUME, fill_volume},
    {"point", "J", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_J, fill_J},
    {"point", "stress", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_STRESS, fill_stress},
    {"point", "plastic", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_PLASTIC, fill_plastic},
    {"point", "material", "Int32", sizeof(int32_t), 1, 1, MPM_FIELD_MATERIAL, fill_material},
    {"point", "body", "Int32", sizeof(int32_t), 1, 1, MPM_FIELD_BODY, fill_body},
    {"point", "level", "Int32", sizeof(int32_t), 1, 1, MPM_FIELD_LEVEL, fill_level},
    {"point", "enrichment", "Int32", sizeof(int32_t), 1, 1, MPM_FIELD_ENRICHMENT, fill_enrichment},
    {"point", "temperature", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_TEMPERATURE, fill_temperature},
    {"point", "melt", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_MELT, fill_melt},
    {"point", "cauchy_stress", NULL, sizeof(mpm_real), 9, 1, MPM_FIELD_CAUCHY_STRESS, fill_cauchy},
    {"point", "pressure", NULL, sizeof(mpm_real), 1, 1, MPM_FIELD_PRESSURE, fill_pressure},
    {"point", "F", NULL, sizeof(mpm_real), 9, 1, MPM_FIELD_F, fill_F},
    {"cells", "connectivity", "Int64", sizeof(int64_t), 1, 1, -1, fill_connectivity},
    {"cells", "offsets", "Int64", sizeof(int64_t), 1, 1, -1, fill_offsets},
    {"cells", "types", "UInt8", sizeof(uint8_t), 1, 1, -1, fill_types},
};

/* Whether array a is written under the selection `fields` (bits of mpm_output_field). */
static int written(const vtu_array *a, unsigned fields) {
  return a->field < 0 || (fields >> a->field & 1u);
}

static uint64_t array_bytes(const vtu_array *a, size_t count) {
  return (uint64_t)(a->per_particle ? count : 1) * (uint64_t)a->comps * a->comp_bytes;
}

/* Header lines of every array of one section. */
static void header_section(mpm_vtu_stream *o, const char *section, const uint64_t *offsets,
                           unsigned fields) {
  for (int k = 0; k < VTU_ARRAYS; ++k) {
    const vtu_array *a = &vtu_arrays[k];
    if (strcmp(a->section, section) != 0 || !written(a, fields)) continue;
    mpm_vtu_data_array(o, !strcmp(section, "field"), a->type ? a->type : VTU_REAL_TYPE, a->name,
                       a->comps, !a->per_particle, offsets[k]);
  }
}

static void write_header(mpm_vtu_stream *o, size_t count, const uint64_t *offsets,
                         unsigned fields) {
  mpm_vtu_begin(o);
  header_section(o, "field", offsets, fields);
  mpm_vtu_piece(o, count, count);
  /* the active attributes ParaView colours and glyphs by, where they are written */
  char attrs[128];
  snprintf(attrs, sizeof attrs, "%s%s%s",
           fields >> MPM_FIELD_STRESS & 1u ? " Scalars=\"stress\"" : "",
           fields >> MPM_FIELD_VELOCITY & 1u ? " Vectors=\"velocity\"" : "",
           fields >> MPM_FIELD_CAUCHY_STRESS & 1u ? " Tensors=\"cauchy_stress\"" : "");
  const char *const sections[3][2] = {
      {"PointData", "point"}, {"Points", "points"}, {"Cells", "cells"}};
  for (int k = 0; k < 3; ++k) {
    mpm_vtu_section(o, sections[k][0], 1, k == 0 ? attrs : NULL);
    header_section(o, sections[k][1], offsets, fields);
    mpm_vtu_section(o, sections[k][0], 0, NULL);
  }
  mpm_vtu_end_head(o);
}

/* Byte count, then the values a chunk of tuples at a time through buf (VTU_CHUNK_BYTES). */
static void write_array(mpm_vtu_stream *o, const vtu_array *a, const mpm_frame_fields *f,
                        size_t count, void *buf) {
  mpm_vtu_put_count(o, array_bytes(a, count));
  const size_t tuples = a->per_particle ? count : 1;
  const size_t tuple_bytes = (size_t)a->comps * a->comp_bytes;
  const size_t chunk = VTU_CHUNK_BYTES / tuple_bytes;
  for (size_t first = 0; first < tuples && !o->err; first += chunk) {
    const size_t n = tuples - first < chunk ? tuples - first : chunk;
    a->fill(f, first, n, buf);
    mpm_vtu_put(o, buf, n * tuple_bytes);
  }
}

mpm_status mpm_write_vtu(const char *path, const mpm_frame_fields *f, mpm_error *err) {
  const size_t count = f->particles->count;
  const unsigned fields = f->fields ? f->fields : mpm_output_fields_default(f->heat);
  uint64_t offsets[VTU_ARRAYS], at = 0;
  for (int k = 0; k < VTU_ARRAYS; ++k) {
    offsets[k] = at;
    if (written(&vtu_arrays[k], fields))
      at += sizeof(uint64_t) + array_bytes(&vtu_arrays[k], count);
  }

  /* heap, not stack: the fill functions store reals and integers into it */
  void *buf = mpm_alloc(VTU_CHUNK_BYTES);
  if (!buf) return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write '%s': out of memory", path);
  mpm_atomic_file af;
  mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) {
    mpm_free(buf);
    return st;
  }
  mpm_vtu_stream o = {af.fp, 0};
  write_header(&o, count, offsets, fields);
  for (int k = 0; k < VTU_ARRAYS && !o.err; ++k)
    if (written(&vtu_arrays[k], fields)) write_array(&o, &vtu_arrays[k], f, count, buf);
  mpm_vtu_finish(&o);
  mpm_free(buf);
  if (o.err) {
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&af, err);
}

/* ---- the index of a frame written in pieces (a run on ranks) ---- */

/* VTK XML PUnstructuredGrid (Kitware, "VTK File Formats", Parallel File Formats): the PPoints
 * and PPointData elements name the type, name and components of each array of the pieces
 * without their values, and one <Piece Source=".."/> per piece file. ParaView's reader checks
 * the pieces' arrays against these, so they come from the table mpm_write_vtu writes from. The
 * cells need no entry (PUnstructuredGrid has no PCells), nor the TIME field data (each piece
 * carries its own, and the PVD index gives the time). */
mpm_status mpm_write_pvtu(const char *path, const mpm_frame_fields *f, int pieces,
                          const char *const *sources, mpm_error *err) {
  const unsigned fields = f->fields ? f->fields : mpm_output_fields_default(f->heat);
  mpm_atomic_file af;
  mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) return st;
  mpm_vtu_stream o = {af.fp, 0};
  char line[512];
  mpm_vtu_put_text(&o, "<?xml version=\"1.0\"?>\n"
                       "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" "
                       "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                       "  <PUnstructuredGrid GhostLevel=\"0\">\n");
  /* the same active attributes as the pieces' PointData */
  snprintf(line, sizeof line, "    <PPointData%s%s%s>\n",
           fields >> MPM_FIELD_STRESS & 1u ? " Scalars=\"stress\"" : "",
           fields >> MPM_FIELD_VELOCITY & 1u ? " Vectors=\"velocity\"" : "",
           fields >> MPM_FIELD_CAUCHY_STRESS & 1u ? " Tensors=\"cauchy_stress\"" : "");
  mpm_vtu_put_text(&o, line);
  const char *const sections[2][2] = {{"point", "PPointData"}, {"points", "PPoints"}};
  for (int s = 0; s < 2; ++s) {
    if (s == 1) mpm_vtu_put_text(&o, "    <PPoints>\n");
    for (int k = 0; k < VTU_ARRAYS; ++k) {
      const vtu_array *a = &vtu_arrays[k];
      if (strcmp(a->section, sections[s][0]) != 0 || !written(a, fields)) continue;
      char comps[48] = "";
      if (a->comps > 1) snprintf(comps, sizeof comps, " NumberOfComponents=\"%d\"", a->comps);
      snprintf(line, sizeof line, "      <PDataArray type=\"%s\" Name=\"%s\"%s/>\n",
               a->type ? a->type : VTU_REAL_TYPE, a->name, comps);
      mpm_vtu_put_text(&o, line);
    }
    snprintf(line, sizeof line, "    </%s>\n", sections[s][1]);
    mpm_vtu_put_text(&o, line);
  }
  for (int k = 0; k < pieces; ++k) { /* the sources are the writer's own names: no escaping */
    snprintf(line, sizeof line, "    <Piece Source=\"%s\"/>\n", sources[k]);
    mpm_vtu_put_text(&o, line);
  }
  mpm_vtu_put_text(&o, "  </PUnstructuredGrid>\n</VTKFile>\n");
  if (o.err) {
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&af, err);
}

/* ---- the per-particle arrays for another file's CellData (vtu_domains.c) ---- */

/* Whether array a is one of the per-particle ones `fields` selects. */
static int particle_array(const vtu_array *a, unsigned fields) {
  return !strcmp(a->section, "point") && a->field >= 0 && (fields >> a->field & 1u);
}

uint64_t mpm_vtu_particle_arrays_bytes(const mpm_frame_fields *f, unsigned fields) {
  uint64_t at = 0;
  for (int k = 0; k < VTU_ARRAYS; ++k)
    if (particle_array(&vtu_arrays[k], fields))
      at += sizeof(uint64_t) + array_bytes(&vtu_arrays[k], f->particles->count);
  return at;
}

void mpm_vtu_particle_arrays_header(mpm_vtu_stream *o, const mpm_frame_fields *f, unsigned fields,
                                    uint64_t base) {
  uint64_t offsets[VTU_ARRAYS] = {0}, at = base;
  for (int k = 0; k < VTU_ARRAYS; ++k)
    if (particle_array(&vtu_arrays[k], fields)) {
      offsets[k] = at;
      at += sizeof(uint64_t) + array_bytes(&vtu_arrays[k], f->particles->count);
    }
  /* header_section writes the always-written ones too; there are none among "point" */
  header_section(o, "point", offsets, fields);
}

void mpm_vtu_particle_arrays_data(mpm_vtu_stream *o, const mpm_frame_fields *f, unsigned fields) {
  void *buf = mpm_alloc(VTU_CHUNK_BYTES);
  if (!buf) {
    if (!o->err) o->err = ENOMEM;
    return;
  }
  for (int k = 0; k < VTU_ARRAYS && !o->err; ++k)
    if (particle_array(&vtu_arrays[k], fields))
      write_array(o, &vtu_arrays[k], f, f->particles->count, buf);
  mpm_free(buf);
}
