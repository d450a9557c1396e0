/* checkpoint.c - HDF5 checkpoints (see checkpoint.h for what they hold and why).
 *
 * Layout, all at the root of the file:
 *   attributes  format ("mpm checkpoint"), version, real_bytes, scene_hash, time, last_dt,
 *               max_speed, steps, frame, written_frames, dt_level, threads, next_id,
 *               particle_count, records, refined_cells, checksum (FNV-1a over all the
 *               others), content_checksum (over every array and record as read back)
 *   datasets    particle_reals [31][n] (the real arrays in mpm_particles_real_arrays order),
 *               particle_material [n], particle_body [n], particle_level [n], particle_id [n],
 *               frame_times [r], frame_files [r][64] (NUL-padded names), stats [r][25];
 *               with particle domains (attributes domain_particles nd, domain_corners nc):
 *               domain_reals [31][nd], domain_material, domain_body, domain_id, domain_active,
 *               domain_enriched (the enrichment flags: state, for their hysteresis)
 *               [nd], domain_corner [8][nd], domain_weights [32][nd] (omega_ap, then g_ap),
 *               corner_reals [21][nc] (reference position, position, velocity, position
 *               compensation, APIC affine moment); with a multi-level grid rebuilt during
 *               the run (refined_cells t > 0), refined_cells [4][t] (level, i, j, k); with
 *               colliders (attribute colliders nc) collider_forces [(r + 1) 3 nc], and with
 *               colliders moved by a script collider_scripts [32 nc]; with mesh
 *               bodies (attribute meshes b, the scene's body count) mesh_digests [b]
 * Datasets are chunked with Fletcher-32 checksums. The reader trusts nothing: each attribute
 * must exist with the right class and shape, each dataset must have exactly the dimensions
 * the attributes announce, counts are bounded by the file's size before anything is
 * allocated, and every real must be finite. */
#define _POSIX_C_SOURCE 200809L

#include "io/checkpoint_format.h"
#include "core/alloc.h"

#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
  int rc = H5Tset_size(t, sizeof MPM_CKPT_FORMAT_NAME) < 0
               ? -1
               : put_attr(file, "format", t, MPM_CKPT_FORMAT_NAME);
  H5Tclose(t);
  return rc;
}

/* A chunked, checksummed dataset of rank 1 or 2 (rows x cols; rank 1 when rows == 0). The data
 * are `rows` separate arrays of `cols` elements (rank 2) or one array (rank 1). */
static int put_dataset(hid_t file, const char *name, hid_t type, hsize_t rows, hsize_t cols,
                       const void *const *row_data) {
  const int rank = rows ? 2 : 1;
  hsize_t dims[2] = {rows ? rows : cols, cols};
  /* equal chunks of at most MPM_CKPT_CHUNK_ELEMENTS: a last chunk that is mostly empty is stored
   * whole */
  const hsize_t pieces = (cols + MPM_CKPT_CHUNK_ELEMENTS - 1) / MPM_CKPT_CHUNK_ELEMENTS;
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
  uint32_t *corner = mpm_alloc(nd * MPM_HEX_CORNERS * sizeof *corner);
  mpm_real *weights = mpm_alloc(nd * MPM_CKPT_DOMAIN_WEIGHT_ROWS * sizeof *weights);
  uint8_t *flag = mpm_calloc(nd + 1, 1); /* the enrichment flags (state: their hysteresis) */
  int rc = -1;
  if (corner && weights && flag) {
    if (s->enrich.flag && s->enrich.particle_capacity >= nd) memcpy(flag, s->enrich.flag, nd);
    const void *flags = flag;
    const void *crows[MPM_HEX_CORNERS], *wrows[MPM_CKPT_DOMAIN_WEIGHT_ROWS];
    for (int a = 0; a < MPM_HEX_CORNERS; ++a) crows[a] = corner + a * nd;
    for (int k = 0; k < MPM_CKPT_DOMAIN_WEIGHT_ROWS; ++k) wrows[k] = weights + k * nd;
    for (uint64_t i = 0; i < nd; ++i)
      for (int a = 0; a < MPM_HEX_CORNERS; ++a) {
        corner[a * nd + i] = s->corner[i][a];
        weights[a * nd + i] = s->w[i][a];
        for (int d = 0; d < 3; ++d) weights[(8 + 3 * a + d) * nd + i] = s->g[i][a][d];
      }
    const void *cr[MPM_CKPT_CORNER_REAL_ROWS] = {
        s->cX[0], s->cX[1], s->cX[2],  s->cx[0],  s->cx[1],  s->cx[2], s->cv[0],
        s->cv[1], s->cv[2], s->cxc[0], s->cxc[1], s->cxc[2], s->cB[0], s->cB[1],
        s->cB[2], s->cB[3], s->cB[4],  s->cB[5],  s->cB[6],  s->cB[7], s->cB[8]};
    rc = put_dataset(f, "domain_reals", mpm_ckpt_real_type(), MPM_PARTICLE_REAL_ARRAYS, nd, rows) ||
                 put_dataset(f, "domain_material", H5T_NATIVE_INT32, 0, nd, &material) ||
                 put_dataset(f, "domain_body", H5T_NATIVE_INT32, 0, nd, &body) ||
                 put_dataset(f, "domain_id", H5T_NATIVE_UINT32, 0, nd, &id) ||
                 put_dataset(f, "domain_active", H5T_NATIVE_UINT8, 0, nd, &active) ||
                 put_dataset(f, "domain_enriched", H5T_NATIVE_UINT8, 0, nd, &flags) ||
                 put_dataset(f, "domain_corner", H5T_NATIVE_UINT32, MPM_HEX_CORNERS, nd, crows) ||
                 put_dataset(f, "domain_weights", mpm_ckpt_real_type(), MPM_CKPT_DOMAIN_WEIGHT_ROWS,
                             nd, wrows) ||
                 put_dataset(f, "corner_reals", mpm_ckpt_real_type(), MPM_CKPT_CORNER_REAL_ROWS, nc,
                             cr)
             ? -1
             : 0;
  }
  mpm_free(corner);
  mpm_free(weights);
  mpm_free(flag);
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
      put_attr(f, "next_id", H5T_NATIVE_UINT32, &c->next_id) ||
      put_attr(f, "particle_count", H5T_NATIVE_UINT64, &n) ||
      put_attr(f, "records", H5T_NATIVE_INT, &c->records))
    return -1;
  for (int k = 0; k < MPM_CKPT_SOLVER_FIGURES; ++k)
    if (put_attr(f, mpm_ckpt_solver_figure_names[k], H5T_NATIVE_DOUBLE, &c->solver_figures[k]))
      return -1;
  const uint64_t sum = mpm_ckpt_attributes_checksum(c, n), content = mpm_ckpt_content_checksum(c);
  if (put_attr(f, "checksum", H5T_NATIVE_UINT64, &sum) ||
      put_attr(f, "content_checksum", H5T_NATIVE_UINT64, &content))
    return -1;
  mpm_particles *p = (mpm_particles *)&c->particles; /* the array table only reads pointers */
  mpm_real **arrays[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, arrays);
  const void *rows[MPM_PARTICLE_REAL_ARRAYS];
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k) rows[k] = *arrays[k];
  const void *material = p->material, *body = p->body, *level = p->level, *id = p->id;
  if (put_dataset(f, "particle_reals", mpm_ckpt_real_type(), MPM_PARTICLE_REAL_ARRAYS, n, rows) ||
      put_dataset(f, "particle_material", H5T_NATIVE_INT32, 0, n, &material) ||
      put_dataset(f, "particle_body", H5T_NATIVE_INT32, 0, n, &body) ||
      put_dataset(f, "particle_level", H5T_NATIVE_INT32, 0, n, &level) ||
      put_dataset(f, "particle_id", H5T_NATIVE_UINT32, 0, n, &id) || write_domains(f, &c->domains))
    return -1;
  const void *tree[4] = {c->tree[0], c->tree[1], c->tree[2], c->tree[3]};
  if (put_attr(f, "refined_cells", H5T_NATIVE_UINT64, &c->tree_count) ||
      (c->tree_count && put_dataset(f, "refined_cells", H5T_NATIVE_INT32, 4, c->tree_count, tree)))
    return -1;
  const hsize_t r = (hsize_t)c->records;
  double *stats = mpm_alloc((r ? r : 1) * MPM_CKPT_STATS_COLUMNS * sizeof *stats);
  const void **srows = mpm_alloc((r ? r : 1) * sizeof *srows);
  const void **frows = mpm_alloc((r ? r : 1) * sizeof *frows);
  int rc = -1;
  if (stats && srows && frows) {
    for (hsize_t i = 0; i < r; ++i) {
      mpm_ckpt_stats_to_row(&c->stats[i], stats + i * MPM_CKPT_STATS_COLUMNS);
      srows[i] = stats + i * MPM_CKPT_STATS_COLUMNS;
      frows[i] = c->frame_files[i];
    }
    const void *times = c->frame_times;
    rc = put_dataset(f, "frame_times", H5T_NATIVE_DOUBLE, 0, r, &times);
    if (!rc && r)
      rc = put_dataset(f, "frame_files", H5T_NATIVE_UINT8, r, MPM_FRAME_NAME_MAX, frows);
    if (!rc && r) rc = put_dataset(f, "stats", H5T_NATIVE_DOUBLE, r, MPM_CKPT_STATS_COLUMNS, srows);
    /* only with colliders: a file without them is what it was before the columns */
    const void *forces = c->collider_forces;
    if (!rc && c->colliders > 0)
      rc = put_attr(f, "colliders", H5T_NATIVE_INT, &c->colliders) ||
           put_dataset(f, "collider_forces", H5T_NATIVE_DOUBLE, 0,
                       (r + 1) * 3 * (hsize_t)c->colliders, &forces);
    /* only with scripted colliders, likewise */
    const void *scripts = c->collider_scripts;
    if (!rc && c->colliders > 0 && c->collider_scripts)
      rc = put_dataset(f, "collider_scripts", H5T_NATIVE_DOUBLE, 0,
                       (hsize_t)MPM_CKPT_SCRIPT_DOUBLES * (hsize_t)c->colliders, &scripts);
    /* only with mesh bodies, likewise */
    const void *digests = c->mesh_digests;
    if (!rc && c->mesh_count > 0)
      rc = put_attr(f, "meshes", H5T_NATIVE_INT, &c->mesh_count) ||
           put_dataset(f, "mesh_digests", H5T_NATIVE_UINT64, 0, (hsize_t)c->mesh_count, &digests);
  }
  mpm_free(stats);
  mpm_free(srows);
  mpm_free(frows);
  return rc;
}

/* The file is built in memory (HDF5's core driver, no backing store) and then written with the
 * engine's atomic writer: HDF5 never touches the disk on this path, so a full disk or a file
 * size limit is one checked stdio error that leaves the old checkpoint in place, and never an
 * HDF5 file handle left half-closed. */
mpm_status mpm_checkpoint_write(const char *path, const mpm_checkpoint *c, mpm_error *err) {
  mpm_ckpt_quiet_hdf5();
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0 || H5Pset_fapl_core(fapl, (size_t)1 << 20, 0) < 0) {
    if (fapl >= 0) H5Pclose(fapl);
    return mpm_error_set(err, MPM_ERR_NOMEM, "cannot write checkpoint '%s': HDF5 set-up failed",
                         path);
  }
  hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
  if (fcpl < 0 || H5Pset_userblock(fcpl, MPM_CKPT_HEADER_BYTES) < 0) {
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
  const ssize_t size = hdf5_size > 0 ? hdf5_size + MPM_CKPT_HEADER_BYTES : -1;
  unsigned char *image = size > 0 ? mpm_alloc((size_t)size) : NULL;
  if (!image || H5Fget_file_image(f, image + MPM_CKPT_HEADER_BYTES, (size_t)hdf5_size) != hdf5_size)
    failed = 1;
  H5Fclose(f);
  if (failed) {
    mpm_free(image);
    return mpm_error_set(err, MPM_ERR_NOMEM,
                         "cannot write checkpoint '%s': out of memory building it; the previous "
                         "checkpoint is kept",
                         path);
  }
  mpm_ckpt_put_header(image, (size_t)size);
  mpm_atomic_file af;
  mpm_status st = mpm_atomic_open(&af, path, err);
  if (st == MPM_OK) {
    /* a short write sets the stream's error flag, which the commit reports */
    const size_t wrote = fwrite(image, 1, (size_t)size, af.fp);
    (void)wrote;
    st = mpm_atomic_commit(&af, err);
  }
  mpm_free(image);
  if (st != MPM_OK && err) {
    char msg[sizeof err->message];
    snprintf(msg, sizeof msg, "%s", err->message);
    mpm_error_set(err, st, "%s; the previous checkpoint is kept", msg);
  }
  return st;
}
