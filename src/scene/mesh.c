/* mesh.c - OBJ and PLY readers for triangle meshes (see mesh.h; what a mesh is asked once read,
 * its bounds, edges and inside test, is in mesh_query.c).
 *
 * Both readers take the whole file into memory and fan-triangulate polygons (v0, vi, vi+1),
 * and keep each triangle's source (the OBJ line or the PLY face element) for messages.
 * Messages follow the engine's rule: they name the file, then the line (OBJ, PLY header,
 * ascii PLY data) or the element and its ordinal (binary PLY), then what was expected. */
#include "scene/mesh.h"
#include "io/input_file.h"
#include "core/alloc.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- small growable arrays ------------------------------------------------------------ */

typedef struct int_buf {
  int *data;
  size_t count, capacity;
} int_buf;

static int int_buf_push(int_buf *b, int v) {
  if (b->count == b->capacity) {
    size_t cap = b->capacity ? 2 * b->capacity : 256;
    int *q = mpm_alloc(cap * sizeof *q);
    if (!q) return -1;
    if (b->count) memcpy(q, b->data, b->count * sizeof *q);
    mpm_free(b->data);
    b->data = q;
    b->capacity = cap;
  }
  b->data[b->count++] = v;
  return 0;
}

/* The source (line or face index) of a polygon's n triangles. */
static int push_sources(int_buf *sources, int source, int n) {
  for (int k = 0; k < n; ++k)
    if (int_buf_push(sources, source)) return -1;
  return 0;
}

/* Fan-triangulate a polygon of n >= 3 vertex indices into tris. */
static int push_fan(int_buf *tris, const int *poly, int n) {
  for (int k = 1; k + 1 < n; ++k)
    if (int_buf_push(tris, poly[0]) || int_buf_push(tris, poly[k]) ||
        int_buf_push(tris, poly[k + 1]))
      return -1;
  return 0;
}

static mpm_status oom(mpm_error *err, const char *path) {
  return mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory reading the mesh", path);
}

/* Whole file, NUL-terminated, allocated with mpm_alloc; refused when over max_bytes. */
static mpm_status read_whole_file(const char *path, double max_bytes, char **out, size_t *len,
                                  mpm_error *err) {
  char why[128];
  FILE *f = mpm_open_input(path, NULL, why, sizeof why);
  if (!f) return mpm_error_set(err, MPM_ERR_IO, "%s: cannot open mesh: %s", path, why);
  char *buf = NULL;
  long size = -1;
  if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
  if (size < 0 || fseek(f, 0, SEEK_SET) != 0) {
    fclose(f);
    return mpm_error_set(err, MPM_ERR_IO, "%s: cannot determine the file size", path);
  }
  if ((double)size > max_bytes) {
    fclose(f);
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: the file is %.1f MiB, more than the %g MiB a mesh file may be "
                         "(it is read whole into memory); raise the shape's max_file_mb to "
                         "read it",
                         path, (double)size / (1024.0 * 1024.0), max_bytes / (1024.0 * 1024.0));
  }
  buf = mpm_alloc((size_t)size + 1);
  if (!buf) {
    fclose(f);
    return oom(err, path);
  }
  size_t got = fread(buf, 1, (size_t)size, f);
  fclose(f);
  if (got != (size_t)size) {
    mpm_free(buf);
    return mpm_error_set(err, MPM_ERR_IO, "%s: read %zu of %ld bytes", path, got, size);
  }
  buf[size] = '\0';
  *out = buf;
  *len = (size_t)size;
  return MPM_OK;
}

static int is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
static int is_end(char c) {
  return c == '\0' || is_space(c);
}
static const char *skip_space(const char *s) {
  while (is_space(*s)) ++s;
  return s;
}
static int token_len(const char *s) {
  int n = 0;
  while (!is_end(s[n]) && n < 40) ++n;
  return n;
}

/* ---- OBJ -------------------------------------------------------------------------------- */

/* Two passes over the lines: the first counts `v` records so that positive face indices are
 * checked against the final vertex count (the error says the valid range); the second
 * parses. Negative indices count back from the vertices read so far (OBJ rule). */
static mpm_status obj_parse(const char *path, char *text, size_t len, mpm_mesh *m, mpm_error *err) {
  const char *name = path; /* messages name the file as the caller gave it */
  /* text, not binary: the counting pass splits lines at '\n' only and the parsing pass also
     at a NUL, so a NUL byte would let the second find more vertices than the first counted */
  const char *nul = memchr(text, '\0', len);
  if (nul) {
    long line = 1;
    for (const char *q = text; q < nul; ++q) line += *q == '\n';
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s:%ld: expected OBJ text, got a NUL byte (is this a binary file?)", name,
                         line);
  }
  long total_v = 0;
  for (char *line = text; line < text + len;) {
    char *nl = memchr(line, '\n', (size_t)(text + len - line));
    char *end = nl ? nl : text + len;
    *end = '\0';
    const char *s = skip_space(line);
    if (s[0] == 'v' && is_space(s[1])) ++total_v;
    line = end + 1;
  }
  if (total_v > INT_MAX / 3)
    return mpm_error_set(err, MPM_ERR_PARSE, "%s: too many vertices", name);
  m->vertices = mpm_alloc((size_t)(total_v ? total_v : 1) * 3 * sizeof(double));
  if (!m->vertices) return oom(err, name);

  int_buf tris = {0}, poly = {0}, sources = {0};
  mpm_status st = MPM_OK;
  long nv = 0, lineno = 0;
  for (char *line = text; line < text + len; line += strlen(line) + 1) {
    ++lineno;
    const char *s = skip_space(line);
    if (s[0] == 'v' && is_space(s[1])) {
      s += 1;
      for (int d = 0; d < 3; ++d) {
        s = skip_space(s);
        char *e;
        double x = strtod(s, &e);
        if (e == s || !is_end(*e)) {
          st = mpm_error_set(err, MPM_ERR_PARSE,
                             "%s:%ld: vertex needs 3 numbers (x y z), coordinate %d is '%.*s'",
                             name, lineno, d + 1, token_len(s), s);
          goto done;
        }
        if (!isfinite(x)) {
          st = mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: vertex coordinate %d is not finite", name,
                             lineno, d + 1);
          goto done;
        }
        m->vertices[3 * nv + d] = x;
        s = e;
      }
      ++nv; /* further numbers (w, or vertex colours) are ignored */
    } else if (s[0] == 'f' && is_space(s[1])) {
      s += 1;
      poly.count = 0;
      for (;;) {
        s = skip_space(s);
        if (*s == '\0') break;
        char *e;
        errno = 0;
        long n = strtol(s, &e, 10);
        if (e == s || !(is_end(*e) || *e == '/')) {
          st = mpm_error_set(err, MPM_ERR_PARSE,
                             "%s:%ld: face vertex '%.*s' is not an index (expected i, i/t, "
                             "i//n or i/t/n)",
                             name, lineno, token_len(s), s);
          goto done;
        }
        long idx;
        if (n > 0 && errno == 0 && n <= total_v) {
          idx = n - 1;
        } else if (n < 0 && errno == 0 && n >= -nv) { /* not -n: n may be LONG_MIN */
          idx = nv + n;
        } else if (n == 0) {
          st = mpm_error_set(err, MPM_ERR_PARSE,
                             "%s:%ld: face index 0 is not valid (OBJ indices start at 1)", name,
                             lineno);
          goto done;
        } else if (n > 0) {
          st = mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: face index %.*s out of range (1..%ld)",
                             name, lineno, token_len(s), s, total_v);
          goto done;
        } else {
          st = mpm_error_set(err, MPM_ERR_PARSE,
                             "%s:%ld: face index %ld out of range (-%ld..-1, %ld vertices read "
                             "so far)",
                             name, lineno, n, nv, nv);
          goto done;
        }
        if (int_buf_push(&poly, (int)idx)) {
          st = oom(err, name);
          goto done;
        }
        while (!is_end(*e)) ++e; /* texture and normal indices */
        s = e;
      }
      if (poly.count < 3) {
        st = mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: face has %zu vertices, expected at least 3",
                           name, lineno, poly.count);
        goto done;
      }
      if (push_fan(&tris, poly.data, (int)poly.count) ||
          push_sources(&sources, (int)lineno, (int)poly.count - 2)) {
        st = oom(err, name);
        goto done;
      }
    }
    /* vt, vn, vp, g, o, s, l, usemtl, mtllib, comments: ignored */
  }
  if (tris.count == 0) {
    st = mpm_error_set(err, MPM_ERR_PARSE, "%s: no faces ('f' records), expected a triangle mesh",
                       name);
    goto done;
  }
  if (tris.count / 3 > (size_t)INT_MAX) {
    st = mpm_error_set(err, MPM_ERR_PARSE, "%s: too many triangles", name);
    goto done;
  }
  m->vertex_count = (int)nv;
  m->triangle_count = (int)(tris.count / 3);
  m->triangles = tris.data;
  m->triangle_source = sources.data;
  m->source_is_line = 1;
  tris.data = sources.data = NULL;
done:
  mpm_free(tris.data);
  mpm_free(sources.data);
  mpm_free(poly.data);
  return st;
}

/* ---- PLY -------------------------------------------------------------------------------- */

typedef enum ply_type {
  PLY_NONE = 0,
  PLY_I8,
  PLY_U8,
  PLY_I16,
  PLY_U16,
  PLY_I32,
  PLY_U32,
  PLY_F32,
  PLY_F64
} ply_type;

static const struct {
  const char *name;
  ply_type type;
} ply_type_names[] = {
    {"char", PLY_I8},   {"int8", PLY_I8},     {"uchar", PLY_U8},   {"uint8", PLY_U8},
    {"short", PLY_I16}, {"int16", PLY_I16},   {"ushort", PLY_U16}, {"uint16", PLY_U16},
    {"int", PLY_I32},   {"int32", PLY_I32},   {"uint", PLY_U32},   {"uint32", PLY_U32},
    {"float", PLY_F32}, {"float32", PLY_F32}, {"double", PLY_F64}, {"float64", PLY_F64},
};

static const int ply_type_size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

static ply_type ply_type_of(const char *s) {
  for (size_t k = 0; k < sizeof ply_type_names / sizeof ply_type_names[0]; ++k)
    if (strcmp(s, ply_type_names[k].name) == 0) return ply_type_names[k].type;
  return PLY_NONE;
}

#define PLY_MAX_ELEMENTS 32
#define PLY_MAX_PROPS 64

typedef struct ply_prop {
  char name[64];
  ply_type type;       /* scalar type, or the item type of a list */
  ply_type count_type; /* PLY_NONE for scalars */
} ply_prop;

typedef struct ply_element {
  char name[64];
  long count;
  int prop_count;
  ply_prop props[PLY_MAX_PROPS];
} ply_element;

enum { PLY_ASCII, PLY_LE, PLY_BE };
static const char *ply_format_name[] = {"ascii", "binary_little_endian", "binary_big_endian"};

typedef struct ply_reader {
  const char *name;
  const char *p, *end;
  int format;
  long line; /* ascii only */
} ply_reader;

/* One value of type t. Returns 0, or -1 at the end of the data, -2 for a malformed number
 * (ascii only). */
static int ply_read(ply_reader *r, ply_type t, double *out) {
  if (r->format == PLY_ASCII) {
    while (r->p < r->end && (is_space(*r->p) || *r->p == '\n')) {
      if (*r->p == '\n') ++r->line;
      ++r->p;
    }
    if (r->p >= r->end) return -1;
    char *e;
    double x = strtod(r->p, &e);
    if (e == r->p || !(is_end(*e) || *e == '\n') || !isfinite(x)) return -2;
    if (t != PLY_F32 && t != PLY_F64 && x != floor(x)) return -2;
    r->p = e;
    *out = x;
    return 0;
  }
  int n = ply_type_size[t];
  if (r->end - r->p < n) return -1;
  unsigned char b[8];
  memcpy(b, r->p, (size_t)n);
  r->p += n;
  const uint16_t one = 1;
  const int host_le = *(const unsigned char *)&one == 1;
  if ((r->format == PLY_LE) != host_le)
    for (int k = 0; k < n / 2; ++k) {
      unsigned char c = b[k];
      b[k] = b[n - 1 - k];
      b[n - 1 - k] = c;
    }
  switch (t) {
  case PLY_I8: {
    int8_t v;
    memcpy(&v, b, 1);
    *out = v;
  } break;
  case PLY_U8: {
    uint8_t v;
    memcpy(&v, b, 1);
    *out = v;
  } break;
  case PLY_I16: {
    int16_t v;
    memcpy(&v, b, 2);
    *out = v;
  } break;
  case PLY_U16: {
    uint16_t v;
    memcpy(&v, b, 2);
    *out = v;
  } break;
  case PLY_I32: {
    int32_t v;
    memcpy(&v, b, 4);
    *out = v;
  } break;
  case PLY_U32: {
    uint32_t v;
    memcpy(&v, b, 4);
    *out = v;
  } break;
  case PLY_F32: {
    float v;
    memcpy(&v, b, 4);
    *out = v;
  } break;
  case PLY_F64: {
    double v;
    memcpy(&v, b, 8);
    *out = v;
  } break;
  default:
    return -2;
  }
  if (!isfinite(*out)) return -2;
  return 0;
}

/* "file:LINE: " for ascii data, "file: " for binary data. */
static const char *ply_where(const ply_reader *r, char *buf, size_t size) {
  if (r->format == PLY_ASCII)
    snprintf(buf, size, "%s:%ld", r->name, r->line);
  else
    snprintf(buf, size, "%s", r->name);
  return buf;
}

static mpm_status ply_data_error(ply_reader *r, int code, const ply_element *el, long i,
                                 const ply_prop *pr, mpm_error *err) {
  char where[600];
  ply_where(r, where, sizeof where);
  if (code == -1)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: unexpected end of data in element '%s' %ld (the header declares "
                         "%ld, %s)",
                         where, el->name, i, el->count, ply_format_name[r->format]);
  if (r->format != PLY_ASCII)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: element '%s' %ld: property '%s' is not a finite number", where,
                         el->name, i, pr->name);
  return mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: element '%s' %ld: property '%s' is '%.*s', expected a finite %s", where,
                       el->name, i, pr->name, token_len(r->p), r->p,
                       (pr->type == PLY_F32 || pr->type == PLY_F64) ? "number" : "integer");
}

/* Parse the header into elements; *data is set to the first byte after end_header. */
static mpm_status ply_header(const char *name, char *text, size_t len, ply_element *els,
                             int *el_count, int *format, long *lines, const char **data,
                             mpm_error *err) {
  char *line = text;
  long lineno = 0;
  *el_count = 0;
  *format = -1;
  for (;;) {
    if (line >= text + len)
      return mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: header ends without 'end_header'", name,
                           lineno);
    char *nl = memchr(line, '\n', (size_t)(text + len - line));
    char *next = nl ? nl + 1 : text + len;
    char buf[512];
    size_t n = (size_t)((nl ? nl : text + len) - line);
    if (n >= sizeof buf) n = sizeof buf - 1;
    memcpy(buf, line, n);
    buf[n] = '\0';
    ++lineno;
    line = next;
    char *tok[6] = {0};
    int nt = 0;
    for (char *s = buf; nt < 6;) { /* split on blanks, in place */
      while (is_space(*s)) *s++ = '\0';
      if (*s == '\0') break;
      tok[nt++] = s;
      while (!is_end(*s)) ++s;
    }
    if (lineno == 1) {
      if (nt != 1 || strcmp(tok[0], "ply") != 0)
        return mpm_error_set(err, MPM_ERR_PARSE, "%s:1: expected 'ply' (the PLY magic line)", name);
      continue;
    }
    if (nt == 0 || !strcmp(tok[0], "comment") || !strcmp(tok[0], "obj_info")) continue;
    if (!strcmp(tok[0], "format")) {
      if (nt < 2) goto bad_format;
      for (int f = 0; f < 3; ++f)
        if (!strcmp(tok[1], ply_format_name[f])) *format = f;
      if (*format < 0) goto bad_format;
    } else if (!strcmp(tok[0], "element")) {
      char *e = NULL;
      long count = nt == 3 ? strtol(tok[2], &e, 10) : -1;
      if (nt != 3 || *e != '\0' || count < 0)
        return mpm_error_set(err, MPM_ERR_PARSE,
                             "%s:%ld: expected 'element NAME COUNT' with COUNT >= 0", name, lineno);
      if (*el_count == PLY_MAX_ELEMENTS)
        return mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: more than %d elements", name, lineno,
                             PLY_MAX_ELEMENTS);
      ply_element *el = &els[(*el_count)++];
      snprintf(el->name, sizeof el->name, "%s", tok[1]);
      el->count = count;
      el->prop_count = 0;
    } else if (!strcmp(tok[0], "property")) {
      if (*el_count == 0)
        return mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: 'property' before any 'element'", name,
                             lineno);
      ply_element *el = &els[*el_count - 1];
      if (el->prop_count == PLY_MAX_PROPS)
        return mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: more than %d properties", name, lineno,
                             PLY_MAX_PROPS);
      ply_prop *pr = &el->props[el->prop_count];
      if (nt >= 2 && !strcmp(tok[1], "list")) {
        if (nt != 5 || !(pr->count_type = ply_type_of(tok[2])) || !(pr->type = ply_type_of(tok[3])))
          return mpm_error_set(err, MPM_ERR_PARSE,
                               "%s:%ld: expected 'property list COUNT_TYPE ITEM_TYPE NAME' with "
                               "types among char uchar short ushort int uint float double",
                               name, lineno);
        if (pr->count_type == PLY_F32 || pr->count_type == PLY_F64)
          return mpm_error_set(err, MPM_ERR_PARSE,
                               "%s:%ld: a list count must have an integer type, not '%s'", name,
                               lineno, tok[2]);
        snprintf(pr->name, sizeof pr->name, "%s", tok[4]);
      } else {
        if (nt != 3 || !(pr->type = ply_type_of(tok[1])))
          return mpm_error_set(err, MPM_ERR_PARSE,
                               "%s:%ld: expected 'property TYPE NAME' with TYPE among char uchar "
                               "short ushort int uint float double (or their sized names)",
                               name, lineno);
        pr->count_type = PLY_NONE;
        snprintf(pr->name, sizeof pr->name, "%s", tok[2]);
      }
      el->prop_count++;
    } else if (!strcmp(tok[0], "end_header")) {
      if (*format < 0)
        return mpm_error_set(err, MPM_ERR_PARSE, "%s:%ld: 'end_header' before any 'format' line",
                             name, lineno);
      for (int k = 0; k < *el_count; ++k) /* items without properties carry nothing to read */
        if (els[k].prop_count == 0 && els[k].count > 0)
          return mpm_error_set(err, MPM_ERR_PARSE,
                               "%s: element '%s' declares %ld items but no properties", name,
                               els[k].name, els[k].count);
      *data = line;
      *lines = lineno;
      return MPM_OK;
    } else {
      return mpm_error_set(err, MPM_ERR_PARSE,
                           "%s:%ld: unknown header keyword '%s' (expected format, comment, "
                           "obj_info, element, property or end_header)",
                           name, lineno, tok[0]);
    }
    continue;
  bad_format:
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s:%ld: expected 'format ascii|binary_little_endian|binary_big_endian "
                         "1.0'",
                         name, lineno);
  }
}

static mpm_status ply_parse(const char *path, char *text, size_t len, mpm_mesh *m, mpm_error *err) {
  const char *name = path; /* messages name the file as the caller gave it */
  ply_element els[PLY_MAX_ELEMENTS];
  int el_count = 0, format = 0;
  long lines = 0;
  const char *data = NULL;
  mpm_status st = ply_header(name, text, len, els, &el_count, &format, &lines, &data, err);
  if (st != MPM_OK) return st;

  /* the vertex element and its x y z, the face element and its index list */
  int ev = -1, ef = -1, px[3] = {-1, -1, -1}, pf = -1;
  for (int e = 0; e < el_count; ++e) {
    if (!strcmp(els[e].name, "vertex")) ev = e;
    if (!strcmp(els[e].name, "face")) ef = e;
  }
  if (ev < 0) return mpm_error_set(err, MPM_ERR_PARSE, "%s: header has no 'element vertex'", name);
  if (ef < 0)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: header has no 'element face', expected a triangle mesh", name);
  for (int k = 0; k < els[ev].prop_count; ++k)
    for (int d = 0; d < 3; ++d)
      if (els[ev].props[k].name[0] == "xyz"[d] && els[ev].props[k].name[1] == '\0' &&
          els[ev].props[k].count_type == PLY_NONE)
        px[d] = k;
  for (int d = 0; d < 3; ++d)
    if (px[d] < 0)
      return mpm_error_set(err, MPM_ERR_PARSE,
                           "%s: element 'vertex' has no scalar property '%c' (expected x, y, z)",
                           name, "xyz"[d]);
  for (int k = 0; k < els[ef].prop_count && pf < 0; ++k)
    if (els[ef].props[k].count_type != PLY_NONE &&
        (!strcmp(els[ef].props[k].name, "vertex_indices") ||
         !strcmp(els[ef].props[k].name, "vertex_index")))
      pf = k;
  for (int k = 0; k < els[ef].prop_count && pf < 0; ++k)
    if (els[ef].props[k].count_type != PLY_NONE) pf = k;
  if (pf < 0)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: element 'face' has no list property (expected 'property list "
                         "uchar int vertex_indices')",
                         name);
  const long nv = els[ev].count;
  const size_t avail = (size_t)(text + len - data);
  if ((size_t)nv > avail || nv > INT_MAX / 3)
    return mpm_error_set(err, MPM_ERR_PARSE,
                         "%s: element 'vertex' declares %ld vertices but only %zu bytes of data "
                         "follow the header",
                         name, nv, avail);

  m->vertices = mpm_alloc((size_t)(nv ? nv : 1) * 3 * sizeof(double));
  if (!m->vertices) return oom(err, name);
  int_buf tris = {0}, poly = {0}, sources = {0};
  ply_reader r = {name, data, text + len, format, lines + 1};
  char where[600];
  for (int e = 0; e < el_count; ++e) {
    const ply_element *el = &els[e];
    for (long i = 0; i < el->count; ++i) {
      for (int k = 0; k < el->prop_count; ++k) {
        const ply_prop *pr = &el->props[k];
        double x;
        int rc;
        if (pr->count_type == PLY_NONE) {
          if ((rc = ply_read(&r, pr->type, &x))) {
            st = ply_data_error(&r, rc, el, i, pr, err);
            goto done;
          }
          if (e == ev)
            for (int d = 0; d < 3; ++d)
              if (k == px[d]) m->vertices[3 * i + d] = x;
          continue;
        }
        double cnt;
        if ((rc = ply_read(&r, pr->count_type, &cnt))) {
          st = ply_data_error(&r, rc, el, i, pr, err);
          goto done;
        }
        const int is_face = (e == ef && k == pf);
        if (cnt < 0 || (is_face && cnt < 3) || cnt > 1e9) {
          st = mpm_error_set(err, MPM_ERR_PARSE,
                             "%s: element '%s' %ld: list '%s' has %.0f entries, expected %s",
                             ply_where(&r, where, sizeof where), el->name, i, pr->name, cnt,
                             is_face ? "at least 3 (a polygon)" : "a count >= 0");
          goto done;
        }
        if (is_face) poly.count = 0;
        for (long c = 0; c < (long)cnt; ++c) {
          if ((rc = ply_read(&r, pr->type, &x))) {
            st = ply_data_error(&r, rc, el, i, pr, err);
            goto done;
          }
          if (!is_face) continue;
          if (!(x >= 0 && x < (double)nv && x == floor(x))) {
            st = mpm_error_set(err, MPM_ERR_PARSE,
                               "%s: face %ld: vertex index %.17g out of range (0..%ld)",
                               ply_where(&r, where, sizeof where), i, x, nv - 1);
            goto done;
          }
          if (int_buf_push(&poly, (int)x)) {
            st = oom(err, name);
            goto done;
          }
        }
        if (is_face && (push_fan(&tris, poly.data, (int)poly.count) ||
                        push_sources(&sources, (int)i, (int)poly.count - 2))) {
          st = oom(err, name);
          goto done;
        }
      }
    }
  }
  if (tris.count == 0) {
    st = mpm_error_set(err, MPM_ERR_PARSE,
                       "%s: no faces (element 'face' is empty), expected a "
                       "triangle mesh",
                       name);
    goto done;
  }
  if (tris.count / 3 > (size_t)INT_MAX) {
    st = mpm_error_set(err, MPM_ERR_PARSE, "%s: too many triangles", name);
    goto done;
  }
  m->vertex_count = (int)nv;
  m->triangle_count = (int)(tris.count / 3);
  m->triangles = tris.data;
  m->triangle_source = sources.data;
  m->source_is_line = 0;
  tris.data = sources.data = NULL;
done:
  mpm_free(tris.data);
  mpm_free(sources.data);
  mpm_free(poly.data);
  return st;
}

/* ---- public --------------------------------------------------------------------------- */

static int ends_with_ci(const char *s, const char *suffix) {
  size_t n = strlen(s), k = strlen(suffix);
  if (k > n) return 0;
  for (size_t i = 0; i < k; ++i)
    if (tolower((unsigned char)s[n - k + i]) != tolower((unsigned char)suffix[i])) return 0;
  return 1;
}

/* Parse text[0, len) (NUL at text[len]; the parsers write into it) and free it. */
static mpm_status parse_text(char *text, size_t len, mpm_mesh_format format, const char *name,
                             mpm_mesh *mesh, mpm_error *err) {
  mpm_status st = format == MPM_MESH_OBJ ? obj_parse(name, text, len, mesh, err)
                                         : ply_parse(name, text, len, mesh, err);
  mpm_free(text);
  if (st != MPM_OK) mpm_mesh_free(mesh);
  return st;
}

mpm_status mpm_mesh_load(const char *path, mpm_mesh *mesh, mpm_error *err) {
  return mpm_mesh_load_max(path, INFINITY, mesh, err);
}

mpm_status mpm_mesh_load_max(const char *path, double max_bytes, mpm_mesh *mesh, mpm_error *err) {
  memset(mesh, 0, sizeof *mesh);
  int is_obj = ends_with_ci(path, ".obj"), is_ply = ends_with_ci(path, ".ply");
  if (!is_obj && !is_ply)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "%s: unknown mesh format, expected a file ending in .obj or .ply", path);
  char *text = NULL;
  size_t len = 0;
  mpm_status st = read_whole_file(path, max_bytes, &text, &len, err);
  if (st != MPM_OK) return st;
  return parse_text(text, len, is_obj ? MPM_MESH_OBJ : MPM_MESH_PLY, path, mesh, err);
}

mpm_status mpm_mesh_parse(const char *data, size_t len, mpm_mesh_format format,
                          const char *path_for_messages, mpm_mesh *mesh, mpm_error *err) {
  const char *name = path_for_messages ? path_for_messages : "<mesh>";
  memset(mesh, 0, sizeof *mesh);
  if (format != MPM_MESH_OBJ && format != MPM_MESH_PLY)
    return mpm_error_set(err, MPM_ERR_INVALID, "%s: unknown mesh format %d", name, (int)format);
  if (len == SIZE_MAX) return oom(err, name);
  char *text = mpm_alloc(len + 1);
  if (!text) return oom(err, name);
  if (len) memcpy(text, data, len);
  text[len] = '\0';
  return parse_text(text, len, format, name, mesh, err);
}

void mpm_mesh_free(mpm_mesh *mesh) {
  if (!mesh) return;
  mpm_free(mesh->vertices);
  mpm_free(mesh->triangles);
  mpm_free(mesh->triangle_source);
  memset(mesh, 0, sizeof *mesh);
}
