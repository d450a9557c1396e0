/* checkpoint_read.c - reading a checkpoint back (layout: checkpoint.c): the guard header
 * first, then HDF5 from the image in memory, with every attribute, dataset, storage layout,
 * count and value checked before it is used. */
#define _POSIX_C_SOURCE 200809L

#include "domain/enrich.h"
#include "core/alloc.h"
#include "io/input_file.h"
#include "io/checkpoint_format.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
  char text[sizeof MPM_CKPT_FORMAT_NAME] = {0};
  if (type >= 0 && space >= 0 && H5Tget_class(type) == H5T_STRING &&
      H5Tis_variable_str(type) == 0 && H5Tget_size(type) == sizeof MPM_CKPT_FORMAT_NAME &&
      H5Sget_simple_extent_type(space) == H5S_SCALAR) {
    hid_t mem = H5Tcopy(H5T_C_S1);
    if (mem >= 0 && H5Tset_size(mem, sizeof MPM_CKPT_FORMAT_NAME) >= 0 &&
        H5Aread(a, mem, text) >= 0 &&
        memcmp(text, MPM_CKPT_FORMAT_NAME, sizeof MPM_CKPT_FORMAT_NAME) == 0)
      rc = 0;
    if (mem >= 0) H5Tclose(mem);
  }
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  return rc ? bad(r, "%s", "the 'format' attribute does not say \"" MPM_CKPT_FORMAT_NAME "\"") : 0;
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
  /* the storage as the writer makes it: chunks of at most MPM_CKPT_CHUNK_ELEMENTS with the
   * Fletcher-32 filter alone (HDF5 would allocate whatever chunk size a damaged file declares) */
  hid_t dcpl = H5Dget_create_plist(ds);
  hsize_t cdims[2] = {0, 0};
  int storage_ok = dcpl >= 0 && H5Pget_layout(dcpl) == H5D_CHUNKED &&
                   H5Pget_chunk(dcpl, 2, cdims) == rank && H5Pget_nfilters(dcpl) == 1;
  if (storage_ok) {
    unsigned flags = 0, config = 0;
    size_t nelmts = 0;
    storage_ok =
        H5Pget_filter2(dcpl, 0, &flags, &nelmts, NULL, 0, NULL, &config) == H5Z_FILTER_FLETCHER32 &&
        cdims[0] >= 1 && cdims[0] <= MPM_CKPT_CHUNK_ELEMENTS &&
        (rank == 1 || (cdims[1] >= 1 && cdims[1] <= MPM_CKPT_CHUNK_ELEMENTS && cdims[0] == 1));
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
      nc * MPM_CKPT_CORNER_REAL_ROWS * sizeof(mpm_real) > r->file_bytes)
    return bad(r, "%s", "'domain_particles' or 'domain_corners' is larger than the file can hold");
  mpm_domain_set *s = &c->domains;
  uint32_t *corner = mpm_alloc(nd * MPM_HEX_CORNERS * sizeof *corner);
  mpm_real *weights = mpm_alloc(nd * MPM_CKPT_DOMAIN_WEIGHT_ROWS * sizeof *weights);
  int rc = -1;
  if (!corner || !weights || mpm_domain_set_alloc(s, (size_t)nd, (size_t)nc)) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %llu particle domains", r->path,
                  (unsigned long long)nd);
    goto done;
  }
  mpm_real **da[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(&s->particles, da);
  void *rows[MPM_PARTICLE_REAL_ARRAYS], *crows[MPM_HEX_CORNERS],
      *wrows[MPM_CKPT_DOMAIN_WEIGHT_ROWS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *da[k];
  for (int a = 0; a < MPM_HEX_CORNERS; ++a) crows[a] = corner + a * nd;
  for (int k = 0; k < MPM_CKPT_DOMAIN_WEIGHT_ROWS; ++k) wrows[k] = weights + k * nd;
  if (mpm_enrichment_reserve(&s->enrich, (size_t)nd + 1, (size_t)nc + 1)) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %llu particle domains", r->path,
                  (unsigned long long)nd);
    goto done;
  }
  void *material = s->particles.material, *body = s->particles.body, *id = s->particles.id,
       *active = s->active, *flags = s->enrich.flag;
  void *cr[MPM_CKPT_CORNER_REAL_ROWS] = {
      s->cX[0], s->cX[1], s->cX[2],  s->cx[0],  s->cx[1],  s->cx[2], s->cv[0],
      s->cv[1], s->cv[2], s->cxc[0], s->cxc[1], s->cxc[2], s->cB[0], s->cB[1],
      s->cB[2], s->cB[3], s->cB[4],  s->cB[5],  s->cB[6],  s->cB[7], s->cB[8]};
  const size_t R = sizeof(mpm_real);
  if (get_dataset(r, "domain_reals", H5T_FLOAT, R, mpm_ckpt_real_type(), MPM_PARTICLE_REAL_ARRAYS,
                  nd, rows) ||
      get_dataset(r, "domain_material", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, nd, &material) ||
      get_dataset(r, "domain_body", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, nd, &body) ||
      get_dataset(r, "domain_id", H5T_INTEGER, 4, H5T_NATIVE_UINT32, 0, nd, &id) ||
      get_dataset(r, "domain_active", H5T_INTEGER, 1, H5T_NATIVE_UINT8, 0, nd, &active) ||
      get_dataset(r, "domain_enriched", H5T_INTEGER, 1, H5T_NATIVE_UINT8, 0, nd, &flags) ||
      get_dataset(r, "domain_corner", H5T_INTEGER, 4, H5T_NATIVE_UINT32, MPM_HEX_CORNERS, nd,
                  crows) ||
      get_dataset(r, "domain_weights", H5T_FLOAT, R, mpm_ckpt_real_type(),
                  MPM_CKPT_DOMAIN_WEIGHT_ROWS, nd, wrows) ||
      get_dataset(r, "corner_reals", H5T_FLOAT, R, mpm_ckpt_real_type(), MPM_CKPT_CORNER_REAL_ROWS,
                  nc, cr))
    goto done;
  s->active_count = 0;
  for (uint64_t i = 0; i < nd; ++i) {
    if (s->active[i] > 1) { /* (an enriched flag counts its relaxed steps: any byte) */
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
  for (uint64_t i = 0; i < nd * MPM_CKPT_DOMAIN_WEIGHT_ROWS; ++i)
    if (!isfinite(weights[i])) {
      bad(r, "%s", "a domain weight is not finite");
      goto done;
    }
  for (int k = 0; k < MPM_CKPT_CORNER_REAL_ROWS; ++k)
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
  mpm_free(corner);
  mpm_free(weights);
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
      get_attr(r, "next_id", H5T_INTEGER, H5T_NATIVE_UINT32, &c->next_id) ||
      get_attr(r, "particle_count", H5T_INTEGER, H5T_NATIVE_UINT64, &n) ||
      get_attr(r, "records", H5T_INTEGER, H5T_NATIVE_INT, &c->records))
    return -1;
  for (int k = 0; k < MPM_CKPT_SOLVER_FIGURES; ++k)
    if (get_attr(r, mpm_ckpt_solver_figure_names[k], H5T_FLOAT, H5T_NATIVE_DOUBLE,
                 &c->solver_figures[k]))
      return -1;
  for (int k = 0; k < MPM_CKPT_SOLVER_FIGURES; ++k)
    if (!isfinite(c->solver_figures[k]) || c->solver_figures[k] < 0)
      return bad(r, "attribute '%s' is not a finite count", mpm_ckpt_solver_figure_names[k]);
  uint64_t sum = 0, content = 0;
  if (get_attr(r, "checksum", H5T_INTEGER, H5T_NATIVE_UINT64, &sum) ||
      get_attr(r, "content_checksum", H5T_INTEGER, H5T_NATIVE_UINT64, &content))
    return -1;
  if (sum != mpm_ckpt_attributes_checksum(c, n))
    return bad(r, "%s", "the attributes do not match their checksum (damaged)");
  if (!isfinite(c->time) || c->time < 0 || !isfinite(c->last_dt) || c->last_dt < 0 ||
      !isfinite(c->max_speed) || c->max_speed < 0 || c->steps < 0 || c->frame < 0 ||
      c->written_frames < 0 || c->dt_level < 0 || c->dt_level > 64)
    return bad(r, "%s", "time, step or frame counters out of range");
  /* every particle takes at least its reals in the file: a larger count is a lie */
  if (n > UINT32_MAX || n * MPM_PARTICLE_REAL_ARRAYS * sizeof(mpm_real) > r->file_bytes)
    return bad(r, "%s", "'particle_count' is larger than the file can hold");
  if (c->records < 0 || c->records >= MPM_CKPT_MAX_RECORDS ||
      (uint64_t)c->records * (MPM_CKPT_STATS_COLUMNS + 1) * sizeof(double) > r->file_bytes ||
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
  void *material = p->material, *body = p->body, *level = p->level, *id = p->id;
  if (get_dataset(r, "particle_reals", H5T_FLOAT, sizeof(mpm_real), mpm_ckpt_real_type(),
                  MPM_PARTICLE_REAL_ARRAYS, n, rows) ||
      get_dataset(r, "particle_material", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, n, &material) ||
      get_dataset(r, "particle_body", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, n, &body) ||
      get_dataset(r, "particle_level", H5T_INTEGER, 4, H5T_NATIVE_INT32, 0, n, &level) ||
      get_dataset(r, "particle_id", H5T_INTEGER, 4, H5T_NATIVE_UINT32, 0, n, &id))
    return -1;
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    for (size_t i = 0; i < p->count; ++i)
      if (!isfinite((*arrays[k])[i])) return bad(r, "%s", "a particle value is not finite");
  if (read_domains(r, c)) return -1;
  if (get_attr(r, "refined_cells", H5T_INTEGER, H5T_NATIVE_UINT64, &c->tree_count)) return -1;
  if (c->tree_count) {
    if (c->tree_count * 4 * sizeof(int32_t) > r->file_bytes)
      return bad(r, "%s", "'refined_cells' is larger than the file can hold");
    void *tree_rows[4];
    for (int k = 0; k < 4; ++k)
      if (!(tree_rows[k] = c->tree[k] = mpm_alloc(c->tree_count * sizeof(int32_t)))) {
        mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %llu refined cells", r->path,
                      (unsigned long long)c->tree_count);
        return -1;
      }
    if (get_dataset(r, "refined_cells", H5T_INTEGER, 4, H5T_NATIVE_INT32, 4, c->tree_count,
                    tree_rows))
      return -1;
  }
  /* domain particles transfer through their corners, on the coarsest level */
  if (c->domains.particles.count)
    memset(c->domains.particles.level, 0, c->domains.particles.count * sizeof(int32_t));

  const size_t rc = (size_t)(c->records ? c->records : 1);
  c->frame_times = mpm_calloc(rc, sizeof *c->frame_times);
  c->frame_files = mpm_calloc(rc, sizeof *c->frame_files);
  c->stats = mpm_calloc(rc, sizeof *c->stats);
  double *stats = mpm_alloc(rc * MPM_CKPT_STATS_COLUMNS * sizeof *stats);
  void **srows = mpm_alloc(rc * sizeof *srows), **frows = mpm_alloc(rc * sizeof *frows);
  int status = -1;
  if (!c->frame_times || !c->frame_files || !c->stats || !stats || !srows || !frows) {
    mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for %d frame records", r->path,
                  c->records);
    goto done;
  }
  for (int i = 0; i < c->records; ++i) {
    srows[i] = stats + (size_t)i * MPM_CKPT_STATS_COLUMNS;
    frows[i] = c->frame_files[i];
  }
  void *times = c->frame_times;
  if (get_dataset(r, "frame_times", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, 0, (hsize_t)c->records,
                  &times))
    goto done;
  if (c->records && (get_dataset(r, "frame_files", H5T_INTEGER, 1, H5T_NATIVE_UINT8,
                                 (hsize_t)c->records, MPM_FRAME_NAME_MAX, frows) ||
                     get_dataset(r, "stats", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, (hsize_t)c->records,
                                 MPM_CKPT_STATS_COLUMNS, srows)))
    goto done;
  for (int i = 0; i < c->records; ++i) {
    c->frame_files[i][MPM_FRAME_NAME_MAX - 1] = '\0';
    for (int k = 0; k < MPM_CKPT_STATS_COLUMNS; ++k)
      if (!isfinite(stats[(size_t)i * MPM_CKPT_STATS_COLUMNS + k])) {
        bad(r, "%s", "a stats record is not finite");
        goto done;
      }
    /* the integer columns must fit their types before they are converted */
    const double *row = stats + (size_t)i * MPM_CKPT_STATS_COLUMNS;
    if (!(row[0] >= 0 && row[0] < MPM_CKPT_MAX_RECORDS && row[3] >= 0 && row[3] < 9e18 &&
          row[14] >= 0 && row[14] <= 4294967295.0)) {
      bad(r, "%s", "a stats record is out of range");
      goto done;
    }
    mpm_ckpt_row_to_stats(row, &c->stats[i]);
    if (!isfinite(c->frame_times[i])) {
      bad(r, "%s", "a frame time is not finite");
      goto done;
    }
  }
  if (H5Aexists(r->file, "colliders") > 0) { /* the colliders' force columns */
    if (get_attr(r, "colliders", H5T_INTEGER, H5T_NATIVE_INT, &c->colliders)) goto done;
    const size_t nf = ((size_t)c->records + 1) * 3 * (size_t)(c->colliders > 0 ? c->colliders : 0);
    if (c->colliders <= 0 || c->colliders > 1000000 || nf * sizeof(double) > r->file_bytes) {
      c->colliders = 0;
      bad(r, "%s", "the 'colliders' attribute is out of range");
      goto done;
    }
    void *forces = c->collider_forces = mpm_alloc(nf * sizeof *c->collider_forces);
    if (!forces) {
      mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for the collider forces", r->path);
      goto done;
    }
    if (get_dataset(r, "collider_forces", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, 0, (hsize_t)nf, &forces))
      goto done;
    for (size_t k = 0; k < nf; ++k)
      if (!isfinite(c->collider_forces[k])) {
        bad(r, "%s", "a collider force is not finite");
        goto done;
      }
  }
  if (c->colliders > 0 && H5Lexists(r->file, "collider_scripts", H5P_DEFAULT) > 0) {
    const size_t ns = MPM_CKPT_SCRIPT_DOUBLES * (size_t)c->colliders;
    void *scripts = c->collider_scripts = mpm_alloc(ns * sizeof(double));
    if (!scripts) {
      mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for the collider scripts", r->path);
      goto done;
    }
    if (get_dataset(r, "collider_scripts", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, 0, (hsize_t)ns,
                    &scripts))
      goto done;
    for (size_t k = 0; k < ns; ++k)
      if (!isfinite(c->collider_scripts[k])) {
        bad(r, "%s", "a collider script's pose is not finite");
        goto done;
      }
  }
  if (H5Aexists(r->file, "meshes") > 0) { /* the mesh files' digests */
    if (get_attr(r, "meshes", H5T_INTEGER, H5T_NATIVE_INT, &c->mesh_count)) goto done;
    if (c->mesh_count <= 0 || c->mesh_count > 1000000 ||
        (size_t)c->mesh_count * sizeof(uint64_t) > r->file_bytes) {
      c->mesh_count = 0;
      bad(r, "%s", "the 'meshes' attribute is out of range");
      goto done;
    }
    void *digests = c->mesh_digests = mpm_alloc((size_t)c->mesh_count * sizeof *c->mesh_digests);
    if (!digests) {
      mpm_error_set(r->err, MPM_ERR_NOMEM, "%s: out of memory for the mesh digests", r->path);
      goto done;
    }
    if (get_dataset(r, "mesh_digests", H5T_INTEGER, 8, H5T_NATIVE_UINT64, 0, (hsize_t)c->mesh_count,
                    &digests))
      goto done;
  }
  if (content != mpm_ckpt_content_checksum(c)) {
    bad(r, "%s", "the data do not match their checksum (damaged)");
    goto done;
  }
  status = 0;
done:
  mpm_free(stats);
  mpm_free(srows);
  mpm_free(frows);
  return status;
}

/* The whole file; NULL with err set when it cannot be read. */
static unsigned char *read_file(const char *path, size_t *size, mpm_error *err) {
  char why[128];
  FILE *f = mpm_open_input(path, NULL, why, sizeof why);
  if (!f) {
    mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the checkpoint: %s", path, why);
    return NULL;
  }
  long end = -1;
  if (fseek(f, 0, SEEK_END) == 0) end = ftell(f);
  unsigned char *image = NULL;
  if (end < 0 || fseek(f, 0, SEEK_SET) != 0) {
    mpm_error_set(err, MPM_ERR_IO, "%s: cannot read the checkpoint (not a regular file?)", path);
  } else if (!(image = mpm_alloc(end > 0 ? (size_t)end : 1))) {
    mpm_error_set(err, MPM_ERR_NOMEM, "%s: out of memory reading %ld bytes", path, end);
  } else if (fread(image, 1, (size_t)end, f) != (size_t)end) {
    mpm_error_set(err, MPM_ERR_IO, "%s: read error", path);
    mpm_free(image);
    image = NULL;
  }
  fclose(f);
  *size = image ? (size_t)end : 0;
  return image;
}

/* The guard header against the bytes: 0, or -1 with err set. */
static int check_header(const unsigned char *b, size_t size, const char *path, mpm_error *err) {
  if (size < 8 || memcmp(b, mpm_ckpt_magic, 8) != 0) {
    mpm_error_set(err, MPM_ERR_PARSE, "%s: not an mpm checkpoint (%s)", path,
                  size >= 4 && !memcmp(b, "\x89HDF", 4) ? "an HDF5 file without the mpm header"
                                                        : "no mpm checkpoint header");
    return -1;
  }
  if (size < MPM_CKPT_HEADER_BYTES || mpm_ckpt_get_u64(b + 8) != MPM_CHECKPOINT_VERSION) {
    mpm_error_set(err, MPM_ERR_PARSE,
                  "%s: checkpoint format version %llu; this build reads version %d", path,
                  size < MPM_CKPT_HEADER_BYTES ? 0ull : (unsigned long long)mpm_ckpt_get_u64(b + 8),
                  MPM_CHECKPOINT_VERSION);
    return -1;
  }
  if ((uint64_t)size != mpm_ckpt_get_u64(b + 16)) {
    mpm_error_set(err, MPM_ERR_PARSE,
                  "%s: the checkpoint is %zu bytes but its header says %llu (truncated or "
                  "appended to)",
                  path, size, (unsigned long long)mpm_ckpt_get_u64(b + 16));
    return -1;
  }
  /* compared through a bijective mix, so that a fuzzer's comparison tracing cannot simply
   * copy the expected digest into the header (fuzz/fuzz_checkpoint.c) */
  if (mpm_ckpt_mix64(mpm_ckpt_image_digest(b, size)) != mpm_ckpt_mix64(mpm_ckpt_get_u64(b + 24))) {
    mpm_error_set(err, MPM_ERR_PARSE, "%s: the checkpoint is damaged (its checksum does not match)",
                  path);
    return -1;
  }
  return 0;
}

mpm_status mpm_checkpoint_parse(const void *data, size_t size, const char *path, mpm_checkpoint *c,
                                mpm_error *err) {
  mpm_ckpt_quiet_hdf5();
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
  mpm_free(image);
  return st;
}
