/* test_io.c - the frame writers read back by an independent parser.
 *
 * VTU: the XML header is parsed for every DataArray (type, components, offset), the raw
 * appended block after `_` is walked (UInt64 byte count + payload per array, contiguous from
 * offset 0 to `</AppendedData>`), tags are checked to balance, and every value (points,
 * velocity, id, mass, volume = V0 J, J, stress, material, body, cells, TIME) is compared with
 * what was written, for several chunks' worth of particles, for zero particles, and with
 * J/stress left to their defaults. PVD, PLY (header and binary records) and the stats CSV are
 * read back the same way. Atomic files and the writers' failures are tested in
 * test_io_atomic.c. */
#define _POSIX_C_SOURCE 200809L

#include "support.h"
#include "io_support.h"
#include "core/alloc.h"
#include "io/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- VTU parser */

typedef struct parsed_array {
  char section[16]; /* FieldData, PointData, Points, Cells */
  char name[32];
  char type[16];
  int comps;
  uint64_t offset;
  uint64_t nbytes;
  const unsigned char *data;
} parsed_array;

typedef struct parsed_vtu {
  unsigned char *buf;
  size_t len;
  long points, cells;
  int narrays;
  parsed_array arrays[32];
} parsed_vtu;

/* Value of attribute `name` inside the element text [begin, end); 0 if absent. */
static int attr(const char *begin, const char *end, const char *name, char *out, size_t cap) {
  char key[64];
  snprintf(key, sizeof key, " %s=\"", name);
  const size_t klen = strlen(key);
  for (const char *s = begin; s + klen < end; ++s) {
    if (strncmp(s, key, klen) != 0) continue;
    const char *v = s + klen, *q = memchr(v, '"', (size_t)(end - v));
    assert_non_null(q);
    assert_true((size_t)(q - v) < cap);
    memcpy(out, v, (size_t)(q - v));
    out[q - v] = '\0';
    return 1;
  }
  return 0;
}

/* Tags in [s, end) open and close in order; `stack` carries open tags across calls. */
static void check_tags(const char *s, const char *end, char stack[][32], int *depth) {
  while ((s = memchr(s, '<', (size_t)(end - s)))) {
    const char *gt = memchr(s, '>', (size_t)(end - s));
    assert_non_null(gt);
    if (s[1] == '?') {
      assert_true(gt[-1] == '?');
    } else if (s[1] == '/') {
      assert_true(*depth > 0);
      const size_t n = strlen(stack[*depth - 1]);
      assert_true(strncmp(s + 2, stack[*depth - 1], n) == 0 && s[2 + n] == '>');
      --*depth;
    } else if (gt[-1] != '/') {
      size_t n = strcspn(s + 1, " >");
      assert_true(n < 32 && *depth < 16);
      memcpy(stack[*depth], s + 1, n);
      stack[(*depth)++][n] = '\0';
    }
    s = gt + 1;
  }
}

static const char *skip_space(const char *s) {
  while (*s == ' ' || *s == '\n' || *s == '\r' || *s == '\t') ++s;
  return s;
}

static int by_offset(const void *a, const void *b) {
  const uint64_t x = ((const parsed_array *)a)->offset, y = ((const parsed_array *)b)->offset;
  return (x > y) - (x < y);
}

static void parse_vtu(const char *path, parsed_vtu *v) {
  memset(v, 0, sizeof *v);
  v->buf = slurp(path, &v->len);
  assert_non_null(v->buf);
  const char *text = (const char *)v->buf, *file_end = text + v->len;
  assert_int_equal(strncmp(text, "<?xml", 5), 0);

  /* the XML header ends where the raw data begins */
  const char *app = strstr(text, "<AppendedData encoding=\"raw\">");
  assert_non_null(app);
  const char *underscore = skip_space(strchr(app, '>') + 1);
  assert_int_equal(*underscore, '_');
  const unsigned char *base = (const unsigned char *)underscore + 1;

  char vtkfile[256] = "";
  const char *vf = strstr(text, "<VTKFile");
  assert_non_null(vf);
  const char *vf_end = strchr(vf, '>');
  assert_true(attr(vf, vf_end, "type", vtkfile, sizeof vtkfile));
  assert_string_equal(vtkfile, "UnstructuredGrid");
  assert_true(attr(vf, vf_end, "version", vtkfile, sizeof vtkfile));
  assert_string_equal(vtkfile, "1.0");
  assert_true(attr(vf, vf_end, "header_type", vtkfile, sizeof vtkfile));
  assert_string_equal(vtkfile, "UInt64");
  assert_true(attr(vf, vf_end, "byte_order", vtkfile, sizeof vtkfile));
  assert_string_equal(vtkfile, "LittleEndian");

  const char *piece = strstr(text, "<Piece");
  assert_true(piece && piece < app);
  char num[64];
  assert_true(attr(piece, strchr(piece, '>'), "NumberOfPoints", num, sizeof num));
  v->points = atol(num);
  assert_true(attr(piece, strchr(piece, '>'), "NumberOfCells", num, sizeof num));
  v->cells = atol(num);

  static const char *sections[] = {"<FieldData", "<PointData", "<Points", "<Cells"};
  for (const char *s = text; (s = strstr(s, "<DataArray")) && s < app; ++s) {
    assert_true(v->narrays < 32);
    parsed_array *a = &v->arrays[v->narrays++];
    const char *e = strchr(s, '>');
    char fmt[32] = "";
    assert_true(attr(s, e, "Name", a->name, sizeof a->name));
    assert_true(attr(s, e, "type", a->type, sizeof a->type));
    assert_true(attr(s, e, "format", fmt, sizeof fmt));
    assert_string_equal(fmt, "appended");
    assert_true(attr(s, e, "offset", num, sizeof num));
    a->offset = strtoull(num, NULL, 10);
    a->comps = attr(s, e, "NumberOfComponents", num, sizeof num) ? atoi(num) : 1;
    /* the section is the last one opened before this array */
    const char *best = NULL;
    for (int k = 0; k < 4; ++k)
      for (const char *t = text; (t = strstr(t, sections[k])) && t < s; ++t)
        if (!best || t > best) {
          best = t;
          snprintf(a->section, sizeof a->section, "%s", sections[k] + 1);
        }
    assert_non_null(best);
    /* its payload: UInt64 byte count, then the values */
    assert_true(base + a->offset + 8 <= (const unsigned char *)file_end);
    memcpy(&a->nbytes, base + a->offset, 8);
    a->data = base + a->offset + 8;
    assert_true(a->data + a->nbytes <= (const unsigned char *)file_end);
  }

  /* the arrays tile the appended block exactly, from offset 0 to its end */
  parsed_array sorted[32];
  memcpy(sorted, v->arrays, sizeof sorted);
  qsort(sorted, (size_t)v->narrays, sizeof *sorted, by_offset);
  uint64_t at = 0;
  for (int k = 0; k < v->narrays; ++k) {
    assert_int_equal(sorted[k].offset, at);
    at += 8 + sorted[k].nbytes;
  }
  const char *tail = (const char *)base + at;
  assert_int_equal(strncmp(skip_space(tail), "</AppendedData>", 15), 0);

  /* tags balance over the header and the tail; the file ends with </VTKFile> */
  char stack[16][32];
  int depth = 0;
  check_tags(text, underscore, stack, &depth);
  check_tags(tail, file_end, stack, &depth);
  assert_int_equal(depth, 0);
  const char *last = file_end;
  while (last > tail && (last[-1] == '\n' || last[-1] == ' ')) --last;
  assert_true(last - tail >= 10);
  assert_int_equal(strncmp(last - 10, "</VTKFile>", 10), 0);
}

static const parsed_array *find_array(const parsed_vtu *v, const char *name, const char *section,
                                      const char *type, int comps, size_t tuples,
                                      size_t comp_bytes) {
  for (int k = 0; k < v->narrays; ++k) {
    const parsed_array *a = &v->arrays[k];
    if (strcmp(a->name, name) != 0) continue;
    assert_string_equal(a->section, section);
    assert_string_equal(a->type, type);
    assert_int_equal(a->comps, comps);
    assert_int_equal(a->nbytes, (uint64_t)tuples * (uint64_t)comps * comp_bytes);
    return a;
  }
  fail_msg("array %s missing from the VTU", name);
  return NULL;
}

static const char *real_type(void) {
  return sizeof(mpm_real) == 8 ? "Float64" : "Float32";
}

static mpm_real real_at(const parsed_array *a, size_t i) {
  mpm_real r;
  memcpy(&r, a->data + i * sizeof r, sizeof r);
  return r;
}

static int64_t i64_at(const parsed_array *a, size_t i) {
  int64_t r;
  memcpy(&r, a->data + i * sizeof r, sizeof r);
  return r;
}

static int32_t i32_at(const parsed_array *a, size_t i) {
  int32_t r;
  memcpy(&r, a->data + i * sizeof r, sizeof r);
  return r;
}

/* Every array of a written VTU against the particles and fields it came from. */
static void check_vtu(const char *path, const mpm_particles *p, const mpm_real *J,
                      const mpm_real *stress, double time) {
  parsed_vtu v;
  parse_vtu(path, &v);
  const size_t n = p->count;
  const size_t rs = sizeof(mpm_real);
  assert_int_equal(v.points, (long)n);
  assert_int_equal(v.cells, (long)n);
  assert_int_equal(v.narrays, 16);

  const parsed_array *t = find_array(&v, "TIME", "FieldData", "Float64", 1, 1, 8);
  double tv;
  memcpy(&tv, t->data, 8);
  assert_true(tv == time);

  const parsed_array *pts = find_array(&v, "Points", "Points", real_type(), 3, n, rs);
  const parsed_array *vel = find_array(&v, "velocity", "PointData", real_type(), 3, n, rs);
  const parsed_array *id = find_array(&v, "id", "PointData", "UInt32", 1, n, 4);
  const parsed_array *mass = find_array(&v, "mass", "PointData", real_type(), 1, n, rs);
  const parsed_array *vol = find_array(&v, "volume", "PointData", real_type(), 1, n, rs);
  const parsed_array *jj = find_array(&v, "J", "PointData", real_type(), 1, n, rs);
  const parsed_array *sig = find_array(&v, "stress", "PointData", real_type(), 1, n, rs);
  const parsed_array *pl = find_array(&v, "plastic", "PointData", real_type(), 1, n, rs);
  const parsed_array *mat = find_array(&v, "material", "PointData", "Int32", 1, n, 4);
  const parsed_array *body = find_array(&v, "body", "PointData", "Int32", 1, n, 4);
  const parsed_array *lvl = find_array(&v, "level", "PointData", "Int32", 1, n, 4);
  const parsed_array *enr = find_array(&v, "enrichment", "PointData", "Int32", 1, n, 4);
  const parsed_array *conn = find_array(&v, "connectivity", "Cells", "Int64", 1, n, 8);
  const parsed_array *offs = find_array(&v, "offsets", "Cells", "Int64", 1, n, 8);
  const parsed_array *types = find_array(&v, "types", "Cells", "UInt8", 1, n, 1);

  for (size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      assert_true(real_at(pts, 3 * i + (size_t)d) == p->x[d][i]);
      assert_true(real_at(vel, 3 * i + (size_t)d) == p->v[d][i]);
    }
    uint32_t idv;
    memcpy(&idv, id->data + 4 * i, 4);
    assert_int_equal(idv, p->id[i]);
    assert_true(real_at(mass, i) == p->mass[i]);
    if (J) assert_true(real_at(jj, i) == J[i]);
    assert_close_msg(real_at(vol, i), (double)p->vol0[i] * real_at(jj, i),
                     TOL(1e-6, 1e-14) * (double)p->vol0[i], "volume = V0 J");
    assert_true(real_at(sig, i) == (stress ? stress[i] : 0));
    assert_true(real_at(pl, i) == p->plastic[i]);
    assert_int_equal(i32_at(mat, i), p->material[i]);
    assert_int_equal(i32_at(body, i), p->body[i]);
    assert_int_equal(i32_at(lvl, i), p->level[i]);
    assert_int_equal(i32_at(enr, i), -1); /* no categories given: material points */
    assert_int_equal(i64_at(conn, i), (int64_t)i);
    assert_int_equal(i64_at(offs, i), (int64_t)i + 1);
    assert_int_equal(types->data[i], 1);
  }
  free(v.buf);
}

/* ---------------------------------------------------------------- VTU tests */

static void test_vtu_roundtrip(void **state) {
  (void)state;
  const size_t n = 3000; /* more than one 32 KiB chunk for every array */
  mpm_particles p;
  mpm_real *J = malloc(n * sizeof *J), *stress = malloc(n * sizeof *stress);
  make_particles(&p, n, J, stress);
  const char *dir = test_temp_dir("io-vtu");
  char path[600];
  join(path, sizeof path, dir, "frame_0003.vtu");
  mpm_frame_fields ff = {&p, J, stress, 0.041666666666666664, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error err = {0};
  assert_int_equal(mpm_write_vtu(path, &ff, &err), MPM_OK);
  check_vtu(path, &p, J, stress, ff.time);
  assert_int_equal(dir_entries(dir), 1);
  mpm_particles_free(&p);
  free(J);
  free(stress);
}

static void test_vtu_empty(void **state) {
  (void)state;
  mpm_particles p;
  assert_int_equal(mpm_particles_init(&p, 0), MPM_OK);
  const char *dir = test_temp_dir("io-vtu-empty");
  char path[600];
  join(path, sizeof path, dir, "empty.vtu");
  mpm_frame_fields ff = {&p, NULL, NULL, 2.5, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error err = {0};
  assert_int_equal(mpm_write_vtu(path, &ff, &err), MPM_OK);
  check_vtu(path, &p, NULL, NULL, 2.5);
  mpm_particles_free(&p);
}

/* J left NULL is det F; stress left NULL is zero. */
static void test_vtu_default_fields(void **state) {
  (void)state;
  const size_t n = 17;
  mpm_particles p;
  mpm_real J[17];
  make_particles(&p, n, J, NULL);
  const char *dir = test_temp_dir("io-vtu-default");
  char path[600];
  join(path, sizeof path, dir, "f.vtu");
  mpm_frame_fields ff = {&p, NULL, NULL, 0.0, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error err = {0};
  assert_int_equal(mpm_write_vtu(path, &ff, &err), MPM_OK);
  check_vtu(path, &p, NULL, NULL, 0.0);
  parsed_vtu v;
  parse_vtu(path, &v);
  const parsed_array *jj = find_array(&v, "J", "PointData", real_type(), 1, n, sizeof(mpm_real));
  for (size_t i = 0; i < n; ++i) assert_close(real_at(jj, i), J[i], TOL(1e-5, 1e-13));
  free(v.buf);
  mpm_particles_free(&p);
}

/* Streaming: the writer's memory does not grow with the particle count. */
static void test_vtu_small_buffer(void **state) {
  (void)state;
  const size_t n = 40000;
  mpm_particles p;
  make_particles(&p, n, NULL, NULL);
  const char *dir = test_temp_dir("io-vtu-mem");
  char path[600];
  join(path, sizeof path, dir, "big.vtu");
  mpm_frame_fields ff = {&p, NULL, NULL, 1.0, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error err = {0};
  const size_t live = mpm_alloc_live_bytes();
  mpm_alloc_reset_peak();
  assert_int_equal(mpm_write_vtu(path, &ff, &err), MPM_OK);
  assert_true(mpm_alloc_peak_bytes() - live <= 64 * 1024);
  join(path, sizeof path, dir, "big.ply");
  mpm_alloc_reset_peak();
  assert_int_equal(mpm_write_ply_points(path, &ff, &err), MPM_OK);
  assert_true(mpm_alloc_peak_bytes() - live <= 64 * 1024);
  assert_int_equal(mpm_alloc_live_bytes(), live);
  mpm_particles_free(&p);
}

/* ---------------------------------------------------------------- PVD, PLY, CSV */

static void test_pvd(void **state) {
  (void)state;
  const char *dir = test_temp_dir("io-pvd");
  char path[600];
  join(path, sizeof path, dir, "frames.pvd");
  const double times[3] = {0.0, 0.041666666666666664, 1e-3};
  const char *files[3] = {"frame_0000.vtu", "frame_0001.vtu", "a&b.vtu"};
  const char *expect_files[3] = {"frame_0000.vtu", "frame_0001.vtu", "a&amp;b.vtu"};
  mpm_error err = {0};
  assert_int_equal(mpm_write_pvd(path, 3, times, files, &err), MPM_OK);

  size_t len = 0;
  char *text = (char *)slurp(path, &len);
  assert_non_null(text);
  assert_int_equal(strncmp(text, "<?xml", 5), 0);
  assert_non_null(strstr(text, "<VTKFile type=\"Collection\" version=\"0.1\""));
  int k = 0;
  for (const char *s = text; (s = strstr(s, "<DataSet")); ++s, ++k) {
    assert_true(k < 3);
    const char *e = strchr(s, '>');
    char val[64];
    assert_true(attr(s, e, "timestep", val, sizeof val));
    assert_close(strtod(val, NULL), times[k], 1e-9 * (times[k] + 1e-30));
    assert_true(attr(s, e, "file", val, sizeof val));
    assert_string_equal(val, expect_files[k]);
    assert_true(attr(s, e, "part", val, sizeof val));
    assert_string_equal(val, "0");
    assert_true(attr(s, e, "group", val, sizeof val));
    assert_string_equal(val, "");
  }
  assert_int_equal(k, 3);
  char stack[16][32];
  int depth = 0;
  check_tags(text, text + len, stack, &depth);
  assert_int_equal(depth, 0);
  assert_non_null(strstr(text, "</Collection>\n</VTKFile>"));
  free(text);

  /* rewriting with one more frame replaces the file */
  assert_int_equal(mpm_write_pvd(path, 1, times, files, &err), MPM_OK);
  text = (char *)slurp(path, &len);
  assert_null(strstr(text, "frame_0001"));
  free(text);
  assert_int_equal(dir_entries(dir), 1);
}

static void test_ply(void **state) {
  (void)state;
  const size_t n = 2500; /* more than one chunk of records */
  mpm_particles p;
  make_particles(&p, n, NULL, NULL);
  const char *dir = test_temp_dir("io-ply");
  char path[600];
  join(path, sizeof path, dir, "frame_0000.ply");
  mpm_frame_fields ff = {&p, NULL, NULL, 0.25, NULL, 0, NULL, 0, NULL, NULL};
  mpm_error err = {0};
  assert_int_equal(mpm_write_ply_points(path, &ff, &err), MPM_OK);

  size_t len = 0;
  unsigned char *buf = slurp(path, &len);
  assert_non_null(buf);
  const char *t = sizeof(mpm_real) == 8 ? "double" : "float";
  char header[512];
  snprintf(header, sizeof header,
           "ply\nformat binary_little_endian 1.0\ncomment mpm particles, time 0.25 s\n"
           "element vertex %zu\nproperty %s x\nproperty %s y\nproperty %s z\n"
           "property %s vx\nproperty %s vy\nproperty %s vz\nproperty %s pscale\n"
           "property uint id\nproperty int material\nproperty int body\nend_header\n",
           n, t, t, t, t, t, t, t);
  const size_t hl = strlen(header);
  assert_true(len > hl);
  assert_memory_equal(buf, header, hl);
  const size_t rs = sizeof(mpm_real), rec = 7 * rs + 12;
  assert_int_equal(len, hl + n * rec);
  for (size_t i = 0; i < n; ++i) {
    const unsigned char *r = buf + hl + i * rec;
    mpm_real val;
    for (int d = 0; d < 3; ++d) {
      memcpy(&val, r + (size_t)d * rs, rs);
      assert_true(val == p.x[d][i]);
      memcpy(&val, r + (size_t)(3 + d) * rs, rs);
      assert_true(val == p.v[d][i]);
    }
    /* pscale: the sphere of the current volume V0 det F (det F from F: no J given) */
    memcpy(&val, r + 6 * rs, rs);
    double F[9];
    for (int c = 0; c < 9; ++c) F[c] = p.F[c][i];
    const double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                     F[2] * (F[3] * F[7] - F[4] * F[6]);
    const double radius = cbrt(3 * J * p.vol0[i] / (4 * 3.14159265358979324));
    assert_close(val, radius, TOL(1e-6, 1e-14) * radius);
    uint32_t id;
    memcpy(&id, r + 7 * rs, 4);
    assert_int_equal(id, p.id[i]);
    int32_t material, body;
    memcpy(&material, r + 7 * rs + 4, 4);
    memcpy(&body, r + 7 * rs + 8, 4);
    assert_int_equal(material, p.material[i]);
    assert_int_equal(body, p.body[i]);
  }
  free(buf);

  /* zero particles: header only */
  p.count = 0;
  assert_int_equal(mpm_write_ply_points(path, &ff, &err), MPM_OK);
  buf = slurp(path, &len);
  assert_non_null(strstr((char *)buf, "element vertex 0\n"));
  assert_int_equal(len, strlen((char *)buf));
  assert_int_equal(strcmp((char *)buf + len - 11, "end_header\n"), 0);
  free(buf);
  mpm_particles_free(&p);
}

static const char csv_header[] =
    "frame,time,steps,dt,kinetic_energy,elastic_energy,momentum_x,momentum_y,momentum_z,"
    "angular_momentum_x,angular_momentum_y,angular_momentum_z,mass,particles,wall_seconds,"
    "cg_iterations_mean,cg_iterations_max,cg_residual_max,newton_iterations_mean,cg_unconverged,"
    "enriched_percent,dt_min,dt_max,gravitational_energy,total_energy";

static void test_stats_csv(void **state) {
  (void)state;
  enum { ROWS = 4 };
  mpm_stats_row rows[ROWS];
  uint64_t rng = 99;
  for (int i = 0; i < ROWS; ++i) {
    mpm_stats_row *r = &rows[i];
    r->frame = i;
    r->time = i / 24.0;
    r->dt = 1e-4 / 3.0;
    r->steps = 1250LL * i + 3000000000LL;
    r->kinetic = test_rand(&rng, 0, 1e3);
    r->elastic = test_rand(&rng, 0, 1e3);
    for (int d = 0; d < 3; ++d) {
      r->momentum[d] = test_rand(&rng, -1, 1) * 1e-3;
      r->angular_momentum[d] = test_rand(&rng, -1, 1);
    }
    r->mass = 1.0 / 3.0 + i;
    r->wall_seconds = test_rand(&rng, 0, 10);
    r->particles = (size_t)5000000000ULL + (size_t)i;
    r->cg_iterations_mean = 12.5 + i;
    r->cg_iterations_max = 30 + i;
    r->cg_residual_max = 1e-5 * (i + 1);
    r->newton_iterations_mean = 1.5;
    r->cg_unconverged = i;
    r->enriched_percent = 12.5 * i;
    r->dt_min = 1e-5 / 7.0;
    r->dt_max = 1e-4 / 2.9;
    r->gravitational = test_rand(&rng, -1e3, 1e3);
    r->total_energy = r->kinetic + r->elastic + r->gravitational;
  }
  const char *dir = test_temp_dir("io-csv");
  char path[600];
  join(path, sizeof path, dir, "stats.csv");
  mpm_error err = {0};
  assert_int_equal(mpm_write_stats_csv(path, ROWS, rows, &err), MPM_OK);

  size_t len = 0;
  char *text = (char *)slurp(path, &len);
  assert_non_null(text);
  char *save = NULL;
  char *line = strtok_r(text, "\n", &save);
  assert_non_null(line);
  assert_string_equal(line, csv_header);
  int k = 0;
  while ((line = strtok_r(NULL, "\n", &save))) {
    assert_true(k < ROWS);
    const mpm_stats_row *r = &rows[k++];
    double f[25];
    int nf = 0;
    char *save2 = NULL;
    for (char *c = strtok_r(line, ",", &save2); c; c = strtok_r(NULL, ",", &save2)) {
      assert_true(nf < 25);
      f[nf++] = strtod(c, NULL);
      if (nf == 3) assert_int_equal(strtoll(c, NULL, 10), r->steps);
      if (nf == 14) assert_int_equal(strtoull(c, NULL, 10), r->particles);
    }
    assert_int_equal(nf, 25);
    assert_int_equal((int)f[0], r->frame);
    const double rel = 1e-8;
    assert_close(f[1], r->time, rel * r->time);
    assert_close(f[3], r->dt, rel * r->dt);
    assert_close(f[4], r->kinetic, rel * r->kinetic);
    assert_close(f[5], r->elastic, rel * r->elastic);
    for (int d = 0; d < 3; ++d) { /* %.17g reads back the exact double */
      assert_true(f[6 + d] == r->momentum[d]);
      assert_true(f[9 + d] == r->angular_momentum[d]);
    }
    assert_true(f[12] == r->mass);
    assert_close(f[14], r->wall_seconds, rel * r->wall_seconds);
    assert_close(f[15], r->cg_iterations_mean, 1e-5 * r->cg_iterations_mean);
    assert_int_equal((int)f[16], r->cg_iterations_max);
    assert_close(f[17], r->cg_residual_max, 1e-5 * r->cg_residual_max);
    assert_close(f[18], r->newton_iterations_mean, 1e-5);
    assert_int_equal((long long)f[19], r->cg_unconverged);
    assert_close(f[20], r->enriched_percent, 1e-9);
    /* the columns added at the end of the row */
    assert_close(f[21], r->dt_min, rel * r->dt_min);
    assert_close(f[22], r->dt_max, rel * r->dt_max);
    assert_close(f[23], r->gravitational, rel * fabs(r->gravitational));
    assert_close(f[24], r->total_energy, rel * fabs(r->total_energy));
  }
  assert_int_equal(k, ROWS);
  free(text);

  /* no rows: the header alone */
  assert_int_equal(mpm_write_stats_csv(path, 0, rows, &err), MPM_OK);
  char expect[sizeof csv_header + 1];
  snprintf(expect, sizeof expect, "%s\n", csv_header);
  assert_file_text(path, expect);
  assert_int_equal(dir_entries(dir), 1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_vtu_roundtrip),
      cmocka_unit_test(test_vtu_empty),
      cmocka_unit_test(test_vtu_default_fields),
      cmocka_unit_test(test_vtu_small_buffer),
      cmocka_unit_test(test_pvd),
      cmocka_unit_test(test_ply),
      cmocka_unit_test(test_stats_csv),
  };
  const int failed = cmocka_run_group_tests(tests, NULL, NULL);
  remove_io_temp_dirs(failed);
  return test_cleanup(failed);
}
