/* checkpoint.c - HDF5 checkpoints (see checkpoint.h for what they hold and why).
 *
 * Layout, all at the root of the file:
 *   attributes  format ("mpm checkpoint"), version, real_bytes, scene_hash, time, last_dt,
 *               max_speed, steps, frame, written_frames, dt_level, threads, particle_count,
 *               records, checksum (FNV-1a over all the others), content_checksum (over
 *               every array and record as read back)
 *   datasets    particle_reals [27][n] (the real arrays in mpm_particles_real_arrays order),
 *               particle_material [n], particle_body [n], particle_id [n],
 *               frame_times [r], frame_files [r][64] (NUL-padded names), stats [r][16];
 *               with particle domains (attributes domain_particles nd, domain_corners nc):
 *               domain_reals [27][nd], domain_material, domain_body, domain_id, domain_active
 *               [nd], domain_corner [8][nd], domain_weights [32][nd] (omega_ap, then g_ap),
 *               corner_reals [9][nc] (reference position, position, velocity)
 * Datasets are chunked with Fletcher-32 checksums. The reader trusts nothing: each attribute
 * must exist with the right class and shape, each dataset must have exactly the dimensions
 * the attributes announce, counts are bounded by the file's size before anything is
 * allocated, and every real must be finite. */
#define _POSIX_C_SOURCE 200809L

#include "io/checkpoint.h"
#include "core/alloc.h"
#include "core/hash.h"
#include "scene/scene.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define FORMAT_NAME "mpm checkpoint"
#define STATS_COLUMNS 16
#define CHUNK_ELEMENTS 65536
#define MAX_RECORDS 10000001

/* HDF5 prints its error stack on stderr by default; our messages say what went wrong. */
static void quiet_hdf5(void) {
  if (!getenv("MPM_HDF5_DEBUG")) H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

static hid_t real_type(void) {
  return sizeof(mpm_real) == sizeof(double) ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT;
}

/* ---- writing -------------------------------------------------------------------------- */

static int put_attr(hid_t file, const char *name, hid_t type, const void *value) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = space < 0 ? -1 : H5Acreate2(file, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  int rc = (a < 0 || H5Awrite(a, type, value) < 0) ? -1 : 0;
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  return rc;
}

static int put_format(hid_t file) {
  hid_t t = H5Tcopy(H5T_C_S1);
  if (t < 0) return -1;
  int rc = H5Tset_size(t, sizeof FORMAT_NAME) < 0 ? -1 : put_attr(file, "format", t, FORMAT_NAME);
  H5Tclose(t);
  return rc;
}

/* A chunked, checksummed dataset of rank 1 or 2 (rows x cols; rank 1 when rows == 0). The data
 * are `rows` separate arrays of `cols` elements (rank 2) or one array (rank 1). */
static int put_dataset(hid_t file, const char *name, hid_t type, hsize_t rows, hsize_t cols,
                       const void *const *row_data) {
  const int rank = rows ? 2 : 1;
  hsize_t dims[2] = {rows ? rows : cols, cols};
  /* equal chunks of at most CHUNK_ELEMENTS: a last chunk that is mostly empty is stored whole */
  const hsize_t pieces = (cols + CHUNK_ELEMENTS - 1) / CHUNK_ELEMENTS;
  hsize_t chunk[2] = {1, cols ? (cols + pieces - 1) / pieces : 1};
  if (rank == 1) chunk[0] = chunk[1];
  hid_t space = H5Screate_simple(rank, dims, NULL);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  int rc = -1;
  hid_t ds = -1;
  if (space < 0 || dcpl < 0 || H5Pset_chunk(dcpl, rank, chunk) < 0 || H5Pset_fletcher32(dcpl) < 0)
    goto done;
  ds = H5Dcreate2(file, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (ds < 0) goto done;
  if (rank == 1) {
    rc =
        (cols == 0 || H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, row_data[0]) >= 0) ? 0 : -1;
    goto done;
  }
  rc = 0;
  for (hsize_t r = 0; r < rows && rc == 0 && cols > 0; ++r) {
    hsize_t start[2] = {r, 0}, count[2] = {1, cols};
    hid_t mem = H5Screate_simple(1, &cols, NULL);
    if (mem < 0 || H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
        H5Dwrite(ds, type, mem, space, H5P_DEFAULT, row_data[r]) < 0)
      rc = -1;
    if (mem >= 0) H5Sclose(mem);
  }
done:
  if (ds >= 0) H5Dclose(ds);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  return rc;
}

static void stats_to_row(const mpm_stats_row *s, double out[STATS_COLUMNS]) {
  const double v[STATS_COLUMNS] = {s->frame,
                                   s->time,
                                   s->dt,
                                   (double)s->steps,
                                   s->kinetic,
                                   s->elastic,
                                   s->momentum[0],
                                   s->momentum[1],
                                   s->momentum[2],
                                   s->angular_momentum[0],
                                   s->angular_momentum[1],
                                   s->angular_momentum[2],
                                   s->mass,
                                   s->wall_seconds,
                                   (double)s->particles,
                                   0};
  memcpy(out, v, sizeof v);
}

static void row_to_stats(const double v[STATS_COLUMNS], mpm_stats_row *s) {
  s->frame = (int)v[0];
  s->time = v[1];
  s->dt = v[2];
  s->steps = (long long)v[3];
  s->kinetic = v[4];
  s->elastic = v[5];
  for (int k = 0; k < 3; ++k) {
    s->momentum[k] = v[6 + k];
    s->angular_momentum[k] = v[9 + k];
  }
  s->mass = v[12];
  s->wall_seconds = v[13];
  s->particles = (size_t)v[14];
}

/* Datasets carry Fletcher-32 checksums; the scalar attributes are covered by this one. */
static uint64_t attributes_checksum(const mpm_checkpoint *c, uint64_t n) {
  const double d[3] = {c->time, c->last_dt, c->max_speed};
  const int64_t i[8] = {c->steps,   c->frame,   c->written_frames, c->dt_level,
                        c->threads, c->records, (int64_t)n,        (int64_t)sizeof(mpm_real)};
  uint64_t h[3] = {c->scene_hash, mpm_fnv1a64(d, sizeof d), mpm_fnv1a64(i, sizeof i)};
  return mpm_fnv1a64(h, sizeof h);
}

/* Every array and record, as the reader will hold them: a chunk index damaged in a way HDF5
 * does not notice (a chunk read back as fill values) shows up here. */
static uint64_t content_checksum(const mpm_checkpoint *c) {
  mpm_particles *p = (mpm_particles *)&c->particles;
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, a);
  const size_t n = p->count;
  uint64_t h = 0x6d706d636b707421ull;
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    h = mpm_hash64_words(*a[k], n * sizeof(mpm_real), h);
  h = mpm_hash64_words(p->material, n * sizeof *p->material, h);
  h = mpm_hash64_words(p->body, n * sizeof *p->body, h);
  h = mpm_hash64_words(p->id, n * sizeof *p->id, h);
  const mpm_domain_set *ds = &c->domains;
  const uint64_t counts[2] = {ds->particles.count, ds->corner_count};
  h = mpm_hash64_words(counts, sizeof counts, h);
  if (ds->particles.count) {
    const size_t nd = ds->particles.count, nc = ds->corner_count;
    mpm_real **da[MPM_PARTICLE_REAL_ARRAYS];
    mpm_particles_real_arrays((mpm_particles *)&ds->particles, da);
    for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
      h = mpm_hash64_words(*da[k], nd * sizeof(mpm_real), h);
    h = mpm_hash64_words(ds->particles.material, nd * 4, h);
    h = mpm_hash64_words(ds->particles.body, nd * 4, h);
    h = mpm_hash64_words(ds->particles.id, nd * 4, h);
    h = mpm_hash64_words(ds->corner, nd * sizeof *ds->corner, h);
    h = mpm_hash64_words(ds->w, nd * sizeof *ds->w, h);
    h = mpm_hash64_words(ds->g, nd * sizeof *ds->g, h);
    h = mpm_hash64_words(ds->active, nd, h);
    for (int d = 0; d < 3; ++d) {
      h = mpm_hash64_words(ds->cX[d], nc * sizeof(mpm_real), h);
      h = mpm_hash64_words(ds->cx[d], nc * sizeof(mpm_real), h);
      h = mpm_hash64_words(ds->cv[d], nc * sizeof(mpm_real), h);
    }
  }
  const size_t r = (size_t)c->records;
  h = mpm_hash64_words(c->frame_times, r * sizeof *c->frame_times, h);
  h = mpm_hash64_words(c->frame_files, r * sizeof *c->frame_files, h);
  for (size_t i = 0; i < r; ++i) {
    double row[STATS_COLUMNS];
    stats_to_row(&c->stats[i], row);
    h = mpm_hash64_words(row, sizeof row, h);
  }
  return h;
}

/* Rows of a domain set's per-particle tables, structure of arrays for the file: corner slot a
 * of every particle (8 rows), omega_ap (8 rows) then g_ap (24 rows). */
#define DOMAIN_WEIGHT_ROWS 32
#define CORNER_REAL_ROWS 9

static int write_domains(hid_t f, const mpm_domain_set *s) {
  const uint64_t nd = s->particles.count, nc = s->corner_count;
  if (put_attr(f, "domain_particles", H5T_NATIVE_UINT64, &nd) ||
      put_attr(f, "domain_corners", H5T_NATIVE_UINT64, &nc))
    return -1;
  if (!nd) return 0;
  mpm_real **da[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays((mpm_particles *)&s->particles, da);
  const void *rows[MPM_PARTICLE_REAL_ARRAYS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *da[k];
  const void *material = s->particles.material, *body = s->particles.body, *id = s->particles.id,
             *active = s->active;
  uint32_t *corner = malloc(nd * MPM_HEX_CORNERS * sizeof *corner);
  mpm_real *weights = malloc(nd * DOMAIN_WEIGHT_ROWS * sizeof *weights);
  int rc = -1;
  if (corner && weights) {
    const void *crows[MPM_HEX_CORNERS], *wrows[DOMAIN_WEIGHT_ROWS];
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) crows[a] = corner + a * nd;
    for (int k = 0; k < DOMAIN_WEIGHT_ROWS; ++k) wrows[k] = weights + k * nd;
    for (uint64_t i = 0; i < nd; ++i)
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
        corner[a * nd + i] = s->corner[i][a];
        weights[a * nd + i] = s->w[i][a];
        for (int d = 0; d < 3; ++d) weights[(8 + 3 * a + d) * nd + i] = s->g[i][a][d];
      }
    const void *cr[CORNER_REAL_ROWS] = {s->cX[0], s->cX[1], s->cX[2], s->cx[0], s->cx[1],
                                        s->cx[2], s->cv[0], s->cv[1], s->cv[2]};
    rc = put_dataset(f, "domain_reals", real_type(), MPM_PARTICLE_REAL_ARRAYS, nd, rows) ||
                 put_dataset(f, "domain_material", H5T_NATIVE_INT32, 0, nd, &material) ||
                 put_dataset(f, "domain_body", H5T_NATIVE_INT32, 0, nd, &body) ||
                 put_dataset(f, "domain_id", H5T_NATIVE_UINT32, 0, nd, &id) ||
                 put_dataset(f, "domain_active", H5T_NATIVE_UINT8, 0, nd, &active) ||
                 put_dataset(f, "domain_corner", H5T_NATIVE_UINT32, MPM_HEX_CORNERS, nd, crows) ||
                 put_dataset(f, "domain_weights", real_type(), DOMAIN_WEIGHT_ROWS, nd, wrows) ||
                 put_dataset(f, "corner_reals", real_type(), CORNER_REAL_ROWS, nc, cr)
             ? -1
             : 0;
  }
  free(corner);
  free(weights);
  return rc;
}

static int write_contents(hid_t f, const mpm_checkpoint *c) {
  const int version = MPM_CHECKPOINT_VERSION, real_bytes = (int)sizeof(mpm_real);
  const uint64_t n = c->particles.count;
  if (put_format(f) || put_attr(f, "version", H5T_NATIVE_INT, &version) ||
      put_attr(f, "real_bytes", H5T_NATIVE_INT, &real_bytes) ||
      put_attr(f, "scene_hash", H5T_NATIVE_UINT64, &c->scene_hash) ||
      put_attr(f, "time", H5T_NATIVE_DOUBLE, &c->time) ||
      put_attr(f, "last_dt", H5T_NATIVE_DOUBLE, &c->last_dt) ||
      put_attr(f, "max_speed", H5T_NATIVE_DOUBLE, &c->max_speed) ||
      put_attr(f, "steps", H5T_NATIVE_INT64, &c->steps) ||
      put_attr(f, "frame", H5T_NATIVE_INT, &c->frame) ||
      put_attr(f, "written_frames", H5T_NATIVE_INT, &c->written_frames) ||
      put_attr(f, "dt_level", H5T_NATIVE_INT, &c->dt_level) ||
      put_attr(f, "threads", H5T_NATIVE_INT, &c->threads) ||
      put_attr(f, "particle_count", H5T_NATIVE_UINT64, &n) ||
      put_attr(f, "records", H5T_NATIVE_INT, &c->records))
    return -1;
  const uint64_t sum = attributes_checksum(c, n), content = content_checksum(c);
  if (put_attr(f, "checksum", H5T_NATIVE_UINT64, &sum) ||
      put_attr(f, "content_checksum", H5T_NATIVE_UINT64, &content))
    return -1;
  mpm_particles *p = (mpm_particles *)&c->particles; /* the array table only reads pointers */
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  const void *rows[MPM_PARTICLE_REAL_ARRAYS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *arrays[k];
  const void *material = p->material, *body = p->body, *id = p->id;
  if (put_dataset(f, "particle_reals", real_type(), MPM_PARTICLE_REAL_ARRAYS, n, rows) ||
      put_dataset(f, "particle_material", H5T_NATIVE_INT32, 0, n, &material) ||
      put_dataset(f, "particle_body", H5T_NATIVE_INT32, 0, n, &body) ||
      put_dataset(f, "particle_id", H5T_NATIVE_UINT32, 0, n, &id) || write_domains(f, &c->domains))
    return -1;
  const hsize_t r = (hsize_t)c->records;
  double *stats = malloc((r ? r : 1) * STATS_COLUMNS * sizeof *stats);
  const void **srows = malloc((r ? r : 1) * sizeof *srows);
  const void **frows = malloc((r ? r : 1) * sizeof *frows);
  int rc = -1;
  if (stats && srows && frows) {
    for (hsize_t i = 0; i < r; ++i) {
      stats_to_row(&c->stats[i], stats + i * STATS_COLUMNS);
      srows[i] = stats + i * STATS_COLUMNS;
      frows[i] = c->frame_files[i];
    }
    const void *times = c->frame_times;
    rc = put_dataset(f, "frame_times", H5T_NATIVE_DOUBLE, 0, r, &times);
    if (!rc && r)
      rc = put_dataset(f, "frame_files", H5T_NATIVE_UINT8, r, MPM_FRAME_NAME_MAX, frows);
    if (!rc && r) rc = put_dataset(f, "stats", H5T_NATIVE_DOUBLE, r, STATS_COLUMNS, srows);
  }
  free(stats);
  free(srows);
  free(frows);
  return rc;
}

/* ---- the guard header -----------------------------------------------------------------
 * The first HEADER_BYTES of the file are HDF5's user block, which HDF5 leaves to the
 * application: the magic, the format version, the file's size and a digest of everything
 * after the header, little-endian. The reader checks them before HDF5 parses a byte, so a
 * truncated or damaged file is refused by this code rather than handed to the HDF5 parser
 * (HDF5 1.10 can crash on a damaged file). */
#define HEADER_BYTES 512
static const char MAGIC[8] = {'M', 'P', 'M', 'C', 'K', 'P', 'T', '\n'};

static void put_u64(unsigned char *b, uint64_t v) {
  for (int i = 0; i < 8; ++i) b[i] = (unsigned char)(v >> (8 * i));
}
static uint64_t get_u64(const unsigned char *b) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= (uint64_t)b[i] << (8 * i);
  return v;
}
static uint64_t image_digest(const unsigned char *image, size_t size) {
  return mpm_hash64_words(image + HEADER_BYTES, size - HEADER_BYTES, 0x636b707464696721ull);
}
static uint64_t mix64(uint64_t h) {
  h ^= h >> 31;
  h *= 0x7fb5d329728ea185ull;
  h ^= h >> 27;
  h *= 0x81dadef4bc2dd44dull;
  return h ^ (h >> 33);
}

static void put_header(unsigned char *b, size_t size) {
  memset(b, 0, HEADER_BYTES);
  memcpy(b, MAGIC, 8);
  put_u64(b + 8, MPM_CHECKPOINT_VERSION);
  put_u64(b + 16, size);
  put_u64(b + 24, image_digest(b, size));
}

/* The file is built in memory (HDF5's core driver, no backing store) and then written with the
 * engine's atomic writer: HDF5 never touches the disk on this path, so a full disk or a file
 * size limit is one checked stdio error that leaves the old checkpoint in place, and never an
 * HDF5 file handle left half-closed. */
mpm_status mpm_checkpoint_write(const char *path, const mpm_checkpoint *c, mpm_error *err) {
  quiet_hdf5();
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0 || H5Pset_fapl_core(fapl, (size_t)1 << 20, 0) < 0) {
    if (fapl >= 0) H5Pclose(fapl);
    return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write checkpoint '%s': HDF5 set-up failed",
                         path);
  }
  hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
  if (fcpl < 0 || H5Pset_userblock(fcpl, HEADER_BYTES) < 0) {
    if (fcpl >= 0) H5Pclose(fcpl);
    H5Pclose(fapl);
    return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write checkpoint '%s': HDF5 set-up failed",
                         path);
  }
  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, fcpl, fapl);
  H5Pclose(fcpl);
  H5Pclose(fapl);
  if (f < 0)
    return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write checkpoint '%s': HDF5 create failed",
                         path);
  int failed = write_contents(f, c) || H5Fflush(f, H5F_SCOPE_GLOBAL) < 0;
  /* the image HDF5 hands out leaves the user block out: it goes in front of it */
  const ssize_t hdf5_size = failed ? -1 : H5Fget_file_image(f, NULL, 0);
  const ssize_t size = hdf5_size > 0 ? hdf5_size + HEADER_BYTES : -1;
  unsigned char *image = size > 0 ? malloc((size_t)size) : NULL;
  if (!image || H5Fget_file_image(f, image + HEADER_BYTES, (size_t)hdf5_size) != hdf5_size)
    failed = 1;
  H5Fclose(f);
  if (failed) {
    free(image);
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "cannot write checkpoint '%s': out of memory building it; the previous "
                         "checkpoint is kept",
                         path);
  }
  put_header(image, (size_t)size);
  mpm_atomic_file af;
  mpm_status st = mpm_atomic_open(&af, path, err);
  if (st == MPM_OK) {
    /* a short write sets the stream's error flag, which the commit reports */
    const size_t wrote = fwrite(image, 1, (size_t)size, af.fp);
    (void)wrote;
    st = mpm_atomic_commit(&af, err);
  }
  free(image);
  if (st != MPM_OK && err) {
    char msg[sizeof err->message];
    snprintf(msg, sizeof msg, "%s", err->message);
    mpm_error_set(err, st, "%s; the previous checkpoint is kept", msg);
  }
  return st;
}

/* ---- reading -------------------------------------------------------------------------- */

typedef struct reader {
  const char *path;
  hid_t file;
  hsize_t file_bytes;
  mpm_error *err;
} reader;

static int bad(reader *r, const char *fmt, const char *name) {
  char what[256];
  snprintf(what, sizeof what, fmt, name);
  mpm_error_set(r->err, MPM_ERR_PARSE, "%s: not a usable mpm checkpoint: %s", r->path, what);
  return -1;
}

/* A scalar attribute of the given class, read as `mem_type`. */
static int get_attr(reader *r, const char *name, H5T_class_t cls, hid_t mem_type, void *out) {
  if (H5Aexists(r->file, name) <= 0) return bad(r, "attribute '%s' is missing", name);
  hid_t a = H5Aopen(r->file, name, H5P_DEFAULT);
  if (a < 0) return bad(r, "attribute '%s' cannot be opened", name);
  hid_t space = H5Aget_space(a), type = H5Aget_type(a);
  int rc = 0;
  if (space < 0 || type < 0 || H5Sget_simple_extent_type(space) != H5S_SCALAR ||
      H5Tget_class(type) != cls)
    rc = bad(r, "attribute '%s' has the wrong type or shape", name);
  else if (H5Aread(a, mem_type, out) < 0)
    rc = bad(r, "attribute '%s' cannot be read", name);
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  return rc;
}

static int check_format(reader *r) {
  if (H5Aexists(r->file, "format") <= 0) return bad(r, "attribute '%s' is missing", "format");
  hid_t a = H5Aopen(r->file, "format", H5P_DEFAULT);
  if (a < 0) return bad(r, "attribute '%s' cannot be opened", "format");
  hid_t type = H5Aget_type(a), space = H5Aget_space(a);
  int rc = -1;
  char text[sizeof FORMAT_NAME] = {0};
  if (type >= 0 && space >= 0 && H5Tget_class(type) == H5T_STRING &&
      H5Tis_variable_str(type) == 0 && H5Tget_size(type) == sizeof FORMAT_NAME &&
      H5Sget_simple_extent_type(space) == H5S_SCALAR) {
    hid_t mem = H5Tcopy(H5T_C_S1);
    if (mem >= 0 && H5Tset_size(mem, sizeof FORMAT_NAME) >= 0 && H5Aread(a, mem, text) >= 0 &&
        memcmp(text, FORMAT_NAME, sizeof FORMAT_NAME) == 0)
      rc = 0;
    if (mem >= 0) H5Tclose(mem);
  }
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  return rc ? bad(r, "%s", "the 'format' attribute does not say \"" FORMAT_NAME "\"") : 0;
}

/* Open dataset `name`, check its class, element size, rank and dimensions (rows == 0: rank 1
 * of cols), and read it row by row into row_data[] as mem_type. */
static int get_dataset(reader *r, const char *name, H5T_class_t cls, size_t elem, hid_t mem_type,
                       hsize_t rows, hsize_t cols, void *const *row_data) {
  if (H5Lexists(r->file, name, H5P_DEFAULT) <= 0) return bad(r, "dataset '%s' is missing", name);
  hid_t ds = H5Dopen2(r->file, name, H5P_DEFAULT);
  if (ds < 0) return bad(r, "dataset '%s' cannot be opened", name);
  hid_t type = H5Dget_type(ds), space = H5Dget_space(ds);
  int rc = 0;
  hsize_t dims[2] = {0, 0};
  const int rank = rows ? 2 : 1;
  if (type < 0 || space < 0 || H5Tget_class(type) != cls || H5Tget_size(type) != elem ||
      H5Sget_simple_extent_ndims(space) != rank ||
      H5Sget_simple_extent_dims(space, dims, NULL) != rank || dims[0] != (rows ? rows : cols) ||
      (rank == 2 && dims[1] != cols)) {
    rc = bad(r, "dataset '%s' has the wrong type or dimensions", name);
    goto done;
  }
  /* the storage as the writer makes it: chunks of at most CHUNK_ELEMENTS with the Fletcher-32
   * filter alone (HDF5 would allocate whatever chunk size a damaged file declares) */
  hid_t dcpl = H5Dget_create_plist(ds);
  hsize_t cdims[2] = {0, 0};
  int storage_ok = dcpl >= 0 && H5Pget_layout(dcpl) == H5D_CHUNKED &&
                   H5Pget_chunk(dcpl, 2, cdims) == rank && H5Pget_nfilters(dcpl) == 1;
  if (storage_ok) {
    unsigned flags = 0, config = 0;
    size_t nelmts = 0;
    storage_ok =
        H5Pget_filter2(dcpl, 0, &flags, &nelmts, NULL, 0, NULL, &config) == H5Z_FILTER_FLETCHER32 &&
        cdims[0] >= 1 && cdims[0] <= CHUNK_ELEMENTS &&
        (rank == 1 || (cdims[1] >= 1 && cdims[1] <= CHUNK_ELEMENTS && cdims[0] == 1));
  }
  if (dcpl >= 0) H5Pclose(dcpl);
  /* every stored chunk no larger than its data and its checksum, and inside the file */
  hsize_t nchunks = 0;
  if (storage_ok && H5Dget_num_chunks(ds, space, &nchunks) < 0) storage_ok = 0;
  const hsize_t chunk_bytes = cdims[0] * (rank == 2 ? cdims[1] : 1) * elem + 4;
  for (hsize_t i = 0; storage_ok && i < nchunks; ++i) {
    hsize_t offset[2];
    unsigned mask = 0;
    haddr_t addr = 0;
    hsize_t bytes = 0;
    if (H5Dget_chunk_info(ds, space, i, offset, &mask, &addr, &bytes) < 0 || bytes > chunk_bytes ||
        addr > r->file_bytes || bytes > r->file_bytes - addr) {
      storage_ok = 0;
    }
  }
  if (!storage_ok) {
    rc = bad(r, "dataset '%s' is not stored as a checkpoint stores it", name);
    goto done;
  }
  for (hsize_t i = 0; i < (rows ? rows : 1) && cols > 0; ++i) {
    hsize_t start[2] = {i, 0}, count[2] = {1, cols};
    hid_t mem = H5Screate_simple(1, &cols, NULL);
    const int sel =
        rank == 1 ? 0 : H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL);
    const int ok =
        mem >= 0 && sel >= 0 &&
        H5Dread(ds, mem_type, mem, rank == 1 ? H5S_ALL : space, H5P_DEFAULT, row_data[i]) >= 0;
    if (mem >= 0) H5Sclose(mem);
    if (!ok) {
      rc = bad(r, "dataset '%s' cannot be read (damaged: its checksum does not match?)", name);
      break;
    }
  }
done:
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Dclose(ds);
  return rc;
}

/* The particle domains, when the checkpoint has them. */
static int read_domains(reader *r, mpm_checkpoint *c) {
  uint64_t nd = 0, nc = 0;
  if (get_attr(r, "domain_particles", H5T_INTEGER, H5T_NATIVE_UINT64, &nd) ||
      get_attr(r, "domain_corners", H5T_INTEGER, H5T_NATIVE_UINT64, &nc))
    return -1;
  if (!nd && !nc) return 0;
  if (nd > UINT32_MAX || nc > MPM_HEX_CORNERS * nd ||
      nd * MPM_PARTICLE_REAL_ARRAYS * sizeof(mpm_real) > r->file_bytes ||
      nc * CORNER_REAL_ROWS * sizeof(mpm_real) > r->file_bytes)
    return bad(r, "%s", "'domain_particles' or 'domain_corners' is larger than the file can hold");
  mpm_domain_set *s = &c->domains;
  uint32_t *corner = malloc(nd * MPM_HEX_CORNERS * sizeof *corner);
  mpm_real *weights = malloc(nd * DOMAIN_WEIGHT_ROWS * sizeof *weights);
  int rc = -1;
  if (!corner || !weights || mpm_domain_set_alloc(s, (size_t)nd, (size_t)nc)) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %llu particle domains", r->path,
                  (unsigned long long)nd);
    goto done;
  }
  mpm_real **da[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(&s->particles, da);
  void *rows[MPM_PARTICLE_REAL_ARRAYS], *crows[MPM_HEX_CORNERS], *wrows[DOMAIN_WEIGHT_ROWS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *da[k];
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) crows[a] = corner + a * nd;
  for (int k = 0; k < DOMAIN_WEIGHT_ROWS; ++k) wrows[k] = weights + k * nd;
  void *material = s->particles.material, *body = s->particles.body, *id = s->particles.id,
       *active = s->active;
  void *cr[CORNER_REAL_ROWS] = {s->cX[0], s->cX[1], s->cX[2], s->cx[0], s->cx[1],
                                s->cx[2], s->cv[0], s->cv[1], s->cv[2]};
  const size_t R = sizeof(mpm_real);
  if (get_dataset(r, "domain_reals", H5T_FLOAT, R, real_type(), MPM_PARTICLE_REAL_ARRAYS, nd,
                  rows) ||
      get_dataset(r, "domain_material", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, nd, &material) ||
      get_dataset(r, "domain_body", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, nd, &body) ||
      get_dataset(r, "domain_id", H5T_INTEGER, 4, H5T_NATIVE_UINT32, 0, nd, &id) ||
      get_dataset(r, "domain_active", H5T_INTEGER, 1, H5T_NATIVE_UINT8, 0, nd, &active) ||
      get_dataset(r, "domain_corner", H5T_INTEGER, 4, H5T_NATIVE_UINT32, MPM_HEX_CORNERS, nd,
                  crows) ||
      get_dataset(r, "domain_weights", H5T_FLOAT, R, real_type(), DOMAIN_WEIGHT_ROWS, nd, wrows) ||
      get_dataset(r, "corner_reals", H5T_FLOAT, R, real_type(), CORNER_REAL_ROWS, nc, cr))
    goto done;
  s->active_count = 0;
  for (uint64_t i = 0; i < nd; ++i) {
    if (s->active[i] > 1) {
      bad(r, "%s", "a domain's active flag is neither 0 nor 1");
      goto done;
    }
    s->active_count += s->active[i];
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
      s->corner[i][a] = corner[a * nd + i];
      if (s->corner[i][a] >= nc) {
        bad(r, "%s", "a domain names a corner that does not exist");
        goto done;
      }
      s->w[i][a] = weights[a * nd + i];
      for (int d = 0; d < 3; ++d) s->g[i][a][d] = weights[(8 + 3 * a + d) * nd + i];
    }
  }
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    for (uint64_t i = 0; i < nd; ++i)
      if (!isfinite((*da[k])[i])) {
        bad(r, "%s", "a domain particle value is not finite");
        goto done;
      }
  for (uint64_t i = 0; i < nd * DOMAIN_WEIGHT_ROWS; ++i)
    if (!isfinite(weights[i])) {
      bad(r, "%s", "a domain weight is not finite");
      goto done;
    }
  for (int k = 0; k < CORNER_REAL_ROWS; ++k)
    for (uint64_t i = 0; i < nc; ++i)
      if (!isfinite(((mpm_real *)cr[k])[i])) {
        bad(r, "%s", "a corner value is not finite");
        goto done;
      }
  if (mpm_domain_set_rebuild(s)) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for the domain corners", r->path);
    goto done;
  }
  rc = 0;
done:
  free(corner);
  free(weights);
  return rc;
}

static int read_contents(reader *r, mpm_checkpoint *c) {
  if (check_format(r)) return -1;
  int version = 0, real_bytes = 0;
  if (get_attr(r, "version", H5T_INTEGER, H5T_NATIVE_INT, &version)) return -1;
  if (version != MPM_CHECKPOINT_VERSION) {
    mpm_error_set(r->err, MPM_ERR_PARSE,
                  "%s: checkpoint format version %d; this build reads version %d", r->path, version,
                  MPM_CHECKPOINT_VERSION);
    return -1;
  }
  if (get_attr(r, "real_bytes", H5T_INTEGER, H5T_NATIVE_INT, &real_bytes)) return -1;
  if (real_bytes != (int)sizeof(mpm_real)) {
    mpm_error_set(r->err, MPM_ERR_INVALID,
                  "%s: the checkpoint was written by a %s build and this is a %s build; resume "
                  "it with the same build",
                  r->path,
                  real_bytes == 8   ? "double"
                  : real_bytes == 4 ? "float"
                                    : "foreign",
                  sizeof(mpm_real) == 8 ? "double" : "float");
    return -1;
  }
  uint64_t n = 0;
  if (get_attr(r, "scene_hash", H5T_INTEGER, H5T_NATIVE_UINT64, &c->scene_hash) ||
      get_attr(r, "time", H5T_FLOAT, H5T_NATIVE_DOUBLE, &c->time) ||
      get_attr(r, "last_dt", H5T_FLOAT, H5T_NATIVE_DOUBLE, &c->last_dt) ||
      get_attr(r, "max_speed", H5T_FLOAT, H5T_NATIVE_DOUBLE, &c->max_speed) ||
      get_attr(r, "steps", H5T_INTEGER, H5T_NATIVE_INT64, &c->steps) ||
      get_attr(r, "frame", H5T_INTEGER, H5T_NATIVE_INT, &c->frame) ||
      get_attr(r, "written_frames", H5T_INTEGER, H5T_NATIVE_INT, &c->written_frames) ||
      get_attr(r, "dt_level", H5T_INTEGER, H5T_NATIVE_INT, &c->dt_level) ||
      get_attr(r, "threads", H5T_INTEGER, H5T_NATIVE_INT, &c->threads) ||
      get_attr(r, "particle_count", H5T_INTEGER, H5T_NATIVE_UINT64, &n) ||
      get_attr(r, "records", H5T_INTEGER, H5T_NATIVE_INT, &c->records))
    return -1;
  uint64_t sum = 0, content = 0;
  if (get_attr(r, "checksum", H5T_INTEGER, H5T_NATIVE_UINT64, &sum) ||
      get_attr(r, "content_checksum", H5T_INTEGER, H5T_NATIVE_UINT64, &content))
    return -1;
  if (sum != attributes_checksum(c, n))
    return bad(r, "%s", "the attributes do not match their checksum (damaged)");
  if (!isfinite(c->time) || c->time < 0 || !isfinite(c->last_dt) || c->last_dt < 0 ||
      !isfinite(c->max_speed) || c->max_speed < 0 || c->steps < 0 || c->frame < 0 ||
      c->written_frames < 0 || c->dt_level < 0 || c->dt_level > 64)
    return bad(r, "%s", "time, step or frame counters out of range");
  /* every particle takes at least its reals in the file: a larger count is a lie */
  if (n > UINT32_MAX || n * MPM_PARTICLE_REAL_ARRAYS * sizeof(mpm_real) > r->file_bytes)
    return bad(r, "%s", "'particle_count' is larger than the file can hold");
  if (c->records < 0 || c->records >= MAX_RECORDS ||
      (uint64_t)c->records * (STATS_COLUMNS + 1) * sizeof(double) > r->file_bytes ||
      c->written_frames != c->records)
    return bad(r, "%s", "'records' is out of range or differs from 'written_frames'");

  if (mpm_particles_init(&c->particles, (size_t)n)) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %llu particles", r->path,
                  (unsigned long long)n);
    return -1;
  }
  mpm_particles *p = &c->particles;
  p->count = (size_t)n;
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  void *rows[MPM_PARTICLE_REAL_ARRAYS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *arrays[k];
  void *material = p->material, *body = p->body, *id = p->id;
  if (get_dataset(r, "particle_reals", H5T_FLOAT, sizeof(mpm_real), real_type(),
                  MPM_PARTICLE_REAL_ARRAYS, n, rows) ||
      get_dataset(r, "particle_material", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, n, &material) ||
      get_dataset(r, "particle_body", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, n, &body) ||
      get_dataset(r, "particle_id", H5T_INTEGER, 4, H5T_NATIVE_UINT32, 0, n, &id))
    return -1;
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    for (size_t i = 0; i < p->count; ++i)
      if (!isfinite((*arrays[k])[i])) return bad(r, "%s", "a particle value is not finite");
  if (read_domains(r, c)) return -1;

  const size_t rc = (size_t)(c->records ? c->records : 1);
  c->frame_times = calloc(rc, sizeof *c->frame_times);
  c->frame_files = calloc(rc, sizeof *c->frame_files);
  c->stats = calloc(rc, sizeof *c->stats);
  double *stats = malloc(rc * STATS_COLUMNS * sizeof *stats);
  void **srows = malloc(rc * sizeof *srows), **frows = malloc(rc * sizeof *frows);
  int status = -1;
  if (!c->frame_times || !c->frame_files || !c->stats || !stats || !srows || !frows) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %d frame records", r->path,
                  c->records);
    goto done;
  }
  for (int i = 0; i < c->records; ++i) {
    srows[i] = stats + (size_t)i * STATS_COLUMNS;
    frows[i] = c->frame_files[i];
  }
  void *times = c->frame_times;
  if (get_dataset(r, "frame_times", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, 0, (hsize_t)c->records,
                  &times))
    goto done;
  if (c->records && (get_dataset(r, "frame_files", H5T_INTEGER, 1, H5T_NATIVE_UINT8,
                                 (hsize_t)c->records, MPM_FRAME_NAME_MAX, frows) ||
                     get_dataset(r, "stats", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, (hsize_t)c->records,
                                 STATS_COLUMNS, srows)))
    goto done;
  for (int i = 0; i < c->records; ++i) {
    c->frame_files[i][MPM_FRAME_NAME_MAX - 1] = '\0';
    for (int k = 0; k < STATS_COLUMNS; ++k)
      if (!isfinite(stats[(size_t)i * STATS_COLUMNS + k])) {
        bad(r, "%s", "a stats record is not finite");
        goto done;
      }
    /* the integer columns must fit their types before they are converted */
    const double *row = stats + (size_t)i * STATS_COLUMNS;
    if (!(row[0] >= 0 && row[0] < MAX_RECORDS && row[3] >= 0 && row[3] < 9e18 && row[14] >= 0 &&
          row[14] <= 4294967295.0)) {
      bad(r, "%s", "a stats record is out of range");
      goto done;
    }
    row_to_stats(row, &c->stats[i]);
    if (!isfinite(c->frame_times[i])) {
      bad(r, "%s", "a frame time is not finite");
      goto done;
    }
  }
  if (content != content_checksum(c)) {
    bad(r, "%s", "the data do not match their checksum (damaged)");
    goto done;
  }
  status = 0;
done:
  free(stats);
  free(srows);
  free(frows);
  return status;
}

/* The whole file; NULL with err set when it cannot be read. */
static unsigned char *read_file(const char *path, size_t *size, mpm_error *err) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the checkpoint", path);
    return NULL;
  }
  long end = -1;
  if (fseek(f, 0, SEEK_END) == 0) end = ftell(f);
  unsigned char *image = NULL;
  if (end < 0 || fseek(f, 0, SEEK_SET) != 0) {
    mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the checkpoint (not a regular file?)", path);
  } else if (!(image = malloc(end > 0 ? (size_t)end : 1))) {
    mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory reading %ld bytes", path, end);
  } else if (fread(image, 1, (size_t)end, f) != (size_t)end) {
    mpm_error_set(err, MPM_ERR_IO, "%s: read error", path);
    free(image);
    image = NULL;
  }
  fclose(f);
  *size = image ? (size_t)end : 0;
  return image;
}

/* The guard header against the bytes: 0, or -1 with err set. */
static int check_header(const unsigned char *b, size_t size, const char *path, mpm_error *err) {
  if (size < 8 || memcmp(b, MAGIC, 8) != 0) {
    mpm_error_set(err, MPM_ERR_PARSE, "%s: not an mpm checkpoint (%s)", path,
                  size >= 4 && !memcmp(b, "\x89HDF", 4) ? "an HDF5 file without the mpm header"
                                                        : "no mpm checkpoint header");
    return -1;
  }
  if (size < HEADER_BYTES || get_u64(b + 8) != MPM_CHECKPOINT_VERSION) {
    mpm_error_set(
        err, MPM_ERR_PARSE, "%s: checkpoint format version %llu; this build reads version %d", path,
        size < HEADER_BYTES ? 0ull : (unsigned long long)get_u64(b + 8), MPM_CHECKPOINT_VERSION);
    return -1;
  }
  if ((uint64_t)size != get_u64(b + 16)) {
    mpm_error_set(err, MPM_ERR_PARSE,
                  "%s: the checkpoint is %zu bytes but its header says %llu (truncated or "
                  "appended to)",
                  path, size, (unsigned long long)get_u64(b + 16));
    return -1;
  }
  /* compared through a bijective mix, so that a fuzzer's comparison tracing cannot simply
   * copy the expected digest into the header (fuzz/fuzz_checkpoint.c) */
  if (mix64(image_digest(b, size)) != mix64(get_u64(b + 24))) {
    mpm_error_set(err, MPM_ERR_PARSE, "%s: the checkpoint is damaged (its checksum does not match)",
                  path);
    return -1;
  }
  return 0;
}

void mpm_checkpoint_seal(void *image, size_t size) {
  if (size >= HEADER_BYTES) put_header(image, size);
}

mpm_status mpm_checkpoint_parse(const void *data, size_t size, const char *path, mpm_checkpoint *c,
                                mpm_error *err) {
  quiet_hdf5();
  memset(c, 0, sizeof *c);
  mpm_error local;
  if (!err) err = &local;
  if (check_header(data, size, path, err)) return err->status;
  /* HDF5 opens the image from memory (core driver, which copies it) */
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  const int ok = fapl >= 0 && H5Pset_fapl_core(fapl, (size_t)1 << 20, 0) >= 0 &&
                 H5Pset_file_image(fapl, (void *)data, size) >= 0;
  reader r = {path, -1, (hsize_t)size, err};
  /* the core driver refuses a name that exists on disk when it opens an image */
  if (ok) r.file = H5Fopen("/proc/self/mpm-checkpoint-image", H5F_ACC_RDONLY, fapl);
  if (fapl >= 0) H5Pclose(fapl);
  if (r.file < 0)
    return mpm_error_set(err, MPM_ERR_PARSE, "%s: HDF5 cannot open the checkpoint", path);
  const int failed = read_contents(&r, c);
  H5Fclose(r.file);
  if (failed) {
    const mpm_status st = err->status;
    mpm_checkpoint_free(c);
    return st != MPM_OK ? st : MPM_ERR_PARSE;
  }
  return MPM_OK;
}

mpm_status mpm_checkpoint_read(const char *path, mpm_checkpoint *c, mpm_error *err) {
  memset(c, 0, sizeof *c);
  mpm_error local;
  if (!err) err = &local;
  size_t size = 0;
  unsigned char *image = read_file(path, &size, err);
  if (!image) return err->status;
  const mpm_status st = mpm_checkpoint_parse(image, size, path, c, err);
  free(image);
  return st;
}

void mpm_checkpoint_free(mpm_checkpoint *c) {
  mpm_particles_free(&c->particles);
  mpm_domain_set_free(&c->domains);
  free(c->frame_times);
  free(c->frame_files);
  free(c->stats);
  memset(c, 0, sizeof *c);
}
