/* vtu_read.c - read back a particle frame written by vtu.c (VTK XML UnstructuredGrid, raw
 * appended data, UInt64 headers), for tools such as the renderer (render/renderer_draw.c) and
 * the rest-state error.
 *
 * Only this engine's own layout is accepted: the header is scanned for DataArray elements with
 * type, Name, NumberOfComponents and offset attributes, the appended block starts after the
 * `_` that follows <AppendedData encoding="raw">, and each array there is a UInt64 byte count
 * followed by its values. Every array is converted to float (a renderer needs nothing finer).
 * Anything else - another writer's encoding, a truncated file, counts that disagree - is a
 * clear error naming the file and the array. */
#include "io/io.h"
#include "core/alloc.h"
#include "io/input_file.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VTU_HEADER_MAX (1 << 16)

/* Value of attribute `name` inside the element text [tag, end), copied to out. */
static int attr(const char *tag, const char *end, const char *name, char *out, size_t cap) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", name);
  const char *a = strstr(tag, key);
  if (!a || a >= end) return -1;
  a += strlen(key);
  const char *q = memchr(a, '"', (size_t)(end - a));
  if (!q || (size_t)(q - a) >= cap) return -1;
  memcpy(out, a, (size_t)(q - a));
  out[q - a] = 0;
  return 0;
}

static int type_size(const char *t) {
  if (!strcmp(t, "Float32") || !strcmp(t, "Int32") || !strcmp(t, "UInt32")) return 4;
  if (!strcmp(t, "Float64") || !strcmp(t, "Int64") || !strcmp(t, "UInt64")) return 8;
  if (!strcmp(t, "UInt8") || !strcmp(t, "Int8")) return 1;
  return 0;
}

static float to_float(const char *t, const unsigned char *p) {
  if (!strcmp(t, "Float32")) {
    float v;
    memcpy(&v, p, 4);
    return v;
  }
  if (!strcmp(t, "Float64")) {
    double v;
    memcpy(&v, p, 8);
    return (float)v;
  }
  if (!strcmp(t, "Int32")) {
    int32_t v;
    memcpy(&v, p, 4);
    return (float)v;
  }
  if (!strcmp(t, "UInt32")) {
    uint32_t v;
    memcpy(&v, p, 4);
    return (float)v;
  }
  if (!strcmp(t, "Int64")) {
    int64_t v;
    memcpy(&v, p, 8);
    return (float)v;
  }
  if (!strcmp(t, "UInt64")) {
    uint64_t v;
    memcpy(&v, p, 8);
    return (float)v;
  }
  return (float)p[0];
}

void mpm_vtu_frame_free(mpm_vtu_frame *f) {
  for (int k = 0; k < f->array_count; ++k) mpm_free(f->arrays[k].data);
  memset(f, 0, sizeof *f);
}

const mpm_vtu_array *mpm_vtu_frame_array(const mpm_vtu_frame *f, const char *name) {
  for (int k = 0; k < f->array_count; ++k)
    if (!strcmp(f->arrays[k].name, name)) return &f->arrays[k];
  return NULL;
}

mpm_status mpm_read_vtu(const char *path, mpm_vtu_frame *out, mpm_error *err) {
  memset(out, 0, sizeof *out);
  char why[128];
  FILE *fp = mpm_open_input(path, NULL, why, sizeof why);
  if (!fp) return mpm_error_set(err, MPM_ERR_IO, "%s: cannot open: %s", path, why);
  char *head = mpm_alloc(VTU_HEADER_MAX + 1);
  unsigned char *buf = NULL;
  mpm_status st = MPM_OK;
  if (!head) {
    st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory", path);
    goto done;
  }
  const size_t got = fread(head, 1, VTU_HEADER_MAX, fp);
  head[got] = 0;
  const char *app = strstr(head, "<AppendedData encoding=\"raw\">");
  const char *us = app ? strchr(app, '_') : NULL;
  if (strncmp(head, "<?xml", 5) || !strstr(head, "<VTKFile type=\"UnstructuredGrid\"") ||
      !strstr(head, "header_type=\"UInt64\"") || !us) {
    st = mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: not a particle frame written by mpm (expected a VTK XML "
                       "UnstructuredGrid with raw appended data and UInt64 headers)",
                       path);
    goto done;
  }
  const long data_start = (long)(us - head) + 1;
  const char *np = strstr(head, "NumberOfPoints=\"");
  out->point_count = np ? strtol(np + 16, NULL, 10) : -1;
  if (out->point_count < 0) {
    st = mpm_error_set(err, MPM_ERR_PARSE, "%s: no NumberOfPoints in the header", path);
    goto done;
  }
  /* every DataArray before the appended block */
  for (const char *tag = strstr(head, "<DataArray"); tag && tag < app;
       tag = strstr(tag + 1, "<DataArray")) {
    const char *end = strchr(tag, '>');
    if (!end) break;
    char type[32], name[MPM_VTU_NAME_MAX], comps[16] = "1", off[32];
    if (attr(tag, end, "type", type, sizeof type) || attr(tag, end, "Name", name, sizeof name) ||
        attr(tag, end, "offset", off, sizeof off)) {
      st = mpm_error_set(err, MPM_ERR_PARSE, "%s: a DataArray without type, Name or offset", path);
      goto done;
    }
    attr(tag, end, "NumberOfComponents", comps, sizeof comps);
    if (!strcmp(name, "connectivity") || !strcmp(name, "offsets") || !strcmp(name, "types"))
      continue; /* vertex cells: nothing a reader needs */
    const char *cd = strstr(head, "<CellData>"), *cde = cd ? strstr(cd, "</CellData>") : NULL;
    if (cd && tag > cd && tag < cde) continue; /* cell data (grid_cells.vtu's level) */
    const int tsize = type_size(type), nc = atoi(comps);
    if (!tsize || nc < 1 || nc > 9 || out->array_count == MPM_VTU_ARRAYS_MAX) {
      st = mpm_error_set(err, MPM_ERR_PARSE, "%s: array '%s': unsupported type %s or %s components",
                         path, name, type, comps);
      goto done;
    }
    uint64_t nbytes = 0;
    if (fseek(fp, data_start + atol(off), SEEK_SET) || fread(&nbytes, 8, 1, fp) != 1) {
      st = mpm_error_set(err, MPM_ERR_PARSE, "%s: array '%s': truncated file", path, name);
      goto done;
    }
    const uint64_t tuples = nbytes / ((uint64_t)tsize * (uint64_t)nc);
    const int is_field = !strcmp(name, "TIME");
    if (nbytes % ((uint64_t)tsize * (uint64_t)nc) ||
        (!is_field && tuples != (uint64_t)out->point_count) || (is_field && tuples != 1)) {
      st = mpm_error_set(
          err, MPM_ERR_PARSE, "%s: array '%s' holds %llu bytes, expected %ld tuples of %d x %s",
          path, name, (unsigned long long)nbytes, is_field ? 1L : out->point_count, nc, type);
      goto done;
    }
    mpm_free(buf);
    buf = mpm_alloc(nbytes ? nbytes : 1);
    float *data = mpm_alloc((size_t)(tuples * (uint64_t)nc) * sizeof(float) + 1);
    if (!buf || !data) {
      mpm_free(data);
      st = mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory for array '%s'", path, name);
      goto done;
    }
    if (fread(buf, 1, nbytes, fp) != nbytes) {
      mpm_free(data);
      st = mpm_error_set(err, MPM_ERR_PARSE, "%s: array '%s': truncated file", path, name);
      goto done;
    }
    for (uint64_t i = 0; i < tuples * (uint64_t)nc; ++i) data[i] = to_float(type, buf + i * tsize);
    if (is_field) {
      double t;
      if (!strcmp(type, "Float64"))
        memcpy(&t, buf, 8);
      else
        t = data[0];
      out->time = t;
      mpm_free(data);
      continue;
    }
    mpm_vtu_array *a = &out->arrays[out->array_count++];
    snprintf(a->name, sizeof a->name, "%s", name);
    a->components = nc;
    a->data = data;
  }
  if (!mpm_vtu_frame_array(out, "Points"))
    st = mpm_error_set(err, MPM_ERR_PARSE, "%s: no Points array", path);
done:
  mpm_free(buf);
  mpm_free(head);
  fclose(fp);
  if (st != MPM_OK) mpm_vtu_frame_free(out);
  return st;
}
