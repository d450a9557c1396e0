/* checkpoint_format.c - the parts of the checkpoint format that the writer and the reader
 * share (see checkpoint_format.h and, for the layout, checkpoint.c). */
#include "io/checkpoint_format.h"
#include "core/alloc.h"
#include "core/hash.h"

#include <stdlib.h>
#include <string.h>

const char *const mpm_ckpt_solver_figure_names[MPM_CKPT_SOLVER_FIGURES] = {
    "solver_steps",          "solver_cg_iterations", "solver_newton_iterations",
    "solver_cg_unconverged", "solver_cg_max",        "solver_residual_max",
    "frame_steps",           "frame_full_steps",     "frame_dt_sum",
    "frame_full_dt_sum",     "frame_dt_min",         "frame_dt_max"};

/* HDF5 prints its error stack on stderr by default; our messages say what went wrong. */
void mpm_ckpt_quiet_hdf5(void) {
  if (!getenv("MPM_HDF5_DEBUG")) H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

hid_t mpm_ckpt_real_type(void) {
  return sizeof(mpm_real) == sizeof(double) ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT;
}

void mpm_ckpt_stats_to_row(const mpm_stats_row *s, double out[MPM_CKPT_STATS_COLUMNS]) {
  const double v[MPM_CKPT_STATS_COLUMNS] = {s->frame,
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
                                            s->cg_iterations_mean,
                                            s->cg_iterations_max,
                                            s->cg_residual_max,
                                            s->newton_iterations_mean,
                                            (double)s->cg_unconverged,
                                            s->enriched_percent,
                                            s->dt_min,
                                            s->dt_max,
                                            s->gravitational,
                                            s->total_energy};
  memcpy(out, v, sizeof v);
}

void mpm_ckpt_row_to_stats(const double v[MPM_CKPT_STATS_COLUMNS], mpm_stats_row *s) {
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
  s->cg_iterations_mean = v[15];
  s->cg_iterations_max = (int)v[16];
  s->cg_residual_max = v[17];
  s->newton_iterations_mean = v[18];
  s->cg_unconverged = (long long)v[19];
  s->enriched_percent = v[20];
  s->dt_min = v[21];
  s->dt_max = v[22];
  s->gravitational = v[23];
  s->total_energy = v[24];
}

/* Datasets carry Fletcher-32 checksums; the scalar attributes are covered by this one. */
uint64_t mpm_ckpt_attributes_checksum(const mpm_checkpoint *c, uint64_t n) {
  double d[3 + MPM_CKPT_SOLVER_FIGURES] = {c->time, c->last_dt, c->max_speed};
  memcpy(d + 3, c->solver_figures, sizeof c->solver_figures);
  const int64_t i[9] = {
      c->steps,   c->frame,   c->written_frames,         c->dt_level,        c->threads,
      c->records, (int64_t)n, (int64_t)sizeof(mpm_real), (int64_t)c->next_id};
  uint64_t h[3] = {c->scene_hash, mpm_fnv1a64(d, sizeof d), mpm_fnv1a64(i, sizeof i)};
  return mpm_fnv1a64(h, sizeof h);
}

/* Every array and record, as the reader will hold them: a chunk index damaged in a way HDF5
 * does not notice (a chunk read back as fill values) shows up here. */
uint64_t mpm_ckpt_content_checksum(const mpm_checkpoint *c) {
  mpm_particles *p = (mpm_particles *)&c->particles;
  mpm_real **a[MPM_PARTICLE_REAL_ARRAYS];
  mpm_particles_real_arrays(p, a);
  const size_t n = p->count;
  uint64_t h = 0x6d706d636b707421ull;
  for (int k = 0; k < MPM_PARTICLE_REAL_ARRAYS; ++k)
    h = mpm_hash64_words(*a[k], n * sizeof(mpm_real), h);
  h = mpm_hash64_words(p->material, n * sizeof *p->material, h);
  h = mpm_hash64_words(p->body, n * sizeof *p->body, h);
  h = mpm_hash64_words(p->level, n * sizeof *p->level, h);
  h = mpm_hash64_words(p->id, n * sizeof *p->id, h);
  h = mpm_hash64_words(&c->tree_count, sizeof c->tree_count, h);
  for (int k = 0; k < 4 && c->tree_count; ++k)
    h = mpm_hash64_words(c->tree[k], c->tree_count * sizeof(int32_t), h);
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
    for (int e = 0; e < 9; ++e) h = mpm_hash64_words(ds->cB[e], nc * sizeof(mpm_real), h);
  }
  const size_t r = (size_t)c->records;
  h = mpm_hash64_words(c->frame_times, r * sizeof *c->frame_times, h);
  h = mpm_hash64_words(c->frame_files, r * sizeof *c->frame_files, h);
  for (size_t i = 0; i < r; ++i) {
    double row[MPM_CKPT_STATS_COLUMNS];
    mpm_ckpt_stats_to_row(&c->stats[i], row);
    h = mpm_hash64_words(row, sizeof row, h);
  }
  if (c->colliders > 0) /* files without colliders keep the checksum they had */
    h = mpm_hash64_words(c->collider_forces,
                         (r + 1) * 3 * (size_t)c->colliders * sizeof *c->collider_forces, h);
  if (c->colliders > 0 && c->collider_scripts) /* likewise without scripts */
    h = mpm_hash64_words(c->collider_scripts,
                         MPM_CKPT_SCRIPT_DOUBLES * (size_t)c->colliders * sizeof(double), h);
  return h;
}

/* ---- the guard header -----------------------------------------------------------------
 * The first MPM_CKPT_HEADER_BYTES of the file are HDF5's user block, which HDF5 leaves to the
 * application: the magic, the format version, the file's size and a digest of everything
 * after the header, little-endian. The reader checks them before HDF5 parses a byte, so a
 * truncated or damaged file is refused by this code rather than handed to the HDF5 parser
 * (HDF5 1.10 can crash on a damaged file). */
const char mpm_ckpt_magic[8] = {'M', 'P', 'M', 'C', 'K', 'P', 'T', '\n'};

void mpm_ckpt_put_u64(unsigned char *b, uint64_t v) {
  for (int i = 0; i < 8; ++i) b[i] = (unsigned char)(v >> (8 * i));
}
uint64_t mpm_ckpt_get_u64(const unsigned char *b) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= (uint64_t)b[i] << (8 * i);
  return v;
}
uint64_t mpm_ckpt_image_digest(const unsigned char *image, size_t size) {
  return mpm_hash64_words(image + MPM_CKPT_HEADER_BYTES, size - MPM_CKPT_HEADER_BYTES,
                          0x636b707464696721ull);
}
uint64_t mpm_ckpt_mix64(uint64_t h) {
  h ^= h >> 31;
  h *= 0x7fb5d329728ea185ull;
  h ^= h >> 27;
  h *= 0x81dadef4bc2dd44dull;
  return h ^ (h >> 33);
}

void mpm_ckpt_put_header(unsigned char *b, size_t size) {
  memset(b, 0, MPM_CKPT_HEADER_BYTES);
  memcpy(b, mpm_ckpt_magic, 8);
  mpm_ckpt_put_u64(b + 8, MPM_CHECKPOINT_VERSION);
  mpm_ckpt_put_u64(b + 16, size);
  mpm_ckpt_put_u64(b + 24, mpm_ckpt_image_digest(b, size));
}

void mpm_checkpoint_seal(void *image, size_t size) {
  if (size >= MPM_CKPT_HEADER_BYTES) mpm_ckpt_put_header(image, size);
}

void mpm_checkpoint_free(mpm_checkpoint *c) {
  mpm_particles_free(&c->particles);
  mpm_domain_set_free(&c->domains);
  for (int k = 0; k < 4; ++k) mpm_free(c->tree[k]);
  mpm_free(c->frame_times);
  mpm_free(c->frame_files);
  mpm_free(c->stats);
  mpm_free(c->collider_forces);
  mpm_free(c->collider_scripts);
  mpm_free(c->mesh_digests);
  memset(c, 0, sizeof *c);
}
