/* checkpoint_format.h - what the checkpoint writer (checkpoint.c) and reader
 * (checkpoint_read.c) share: the file's constants, the stats row layout, the checksums and the
 * guard header. Private to src/io. */
#ifndef MPM_IO_CHECKPOINT_FORMAT_H
#define MPM_IO_CHECKPOINT_FORMAT_H

#include "io/checkpoint.h"

#include <hdf5.h>
#include <stddef.h>
#include <stdint.h>

#define MPM_CKPT_FORMAT_NAME "mpm checkpoint"
#define MPM_CKPT_STATS_COLUMNS 25
/* a scripted collider's state (collide/collider.h: MPM_COLLIDER_SCRIPT_DOUBLES) */
#define MPM_CKPT_SCRIPT_DOUBLES 32
#define MPM_CKPT_CHUNK_ELEMENTS 65536
#define MPM_CKPT_MAX_RECORDS 10000001
/* Rows of a domain set's per-particle tables, structure of arrays for the file: corner slot a
 * of every particle (8 rows), omega_ap (8 rows) then g_ap (24 rows); the corners' reference
 * position, position, velocity, position compensation (12 rows) and APIC affine moment (9). */
#define MPM_CKPT_DOMAIN_WEIGHT_ROWS 32
#define MPM_CKPT_CORNER_REAL_ROWS 21
/* The guard header: the first bytes of the file, HDF5's user block (checkpoint_format.c). */
#define MPM_CKPT_HEADER_BYTES 512
extern const char mpm_ckpt_magic[8];

/* The attribute names of mpm_checkpoint.solver_figures. */
extern const char *const mpm_ckpt_solver_figure_names[MPM_CKPT_SOLVER_FIGURES];

/* HDF5 prints its error stack on stderr by default; our messages say what went wrong
 * (MPM_HDF5_DEBUG=1 keeps HDF5's). */
void mpm_ckpt_quiet_hdf5(void);
/* The HDF5 type of mpm_real. */
hid_t mpm_ckpt_real_type(void);

void mpm_ckpt_stats_to_row(const mpm_stats_row *s, double out[MPM_CKPT_STATS_COLUMNS]);
void mpm_ckpt_row_to_stats(const double v[MPM_CKPT_STATS_COLUMNS], mpm_stats_row *s);

/* Checksums of the scalar attributes (n particles) and of every array and record. */
uint64_t mpm_ckpt_attributes_checksum(const mpm_checkpoint *c, uint64_t n);
uint64_t mpm_ckpt_content_checksum(const mpm_checkpoint *c);

/* Little-endian fields of the guard header, the digest of an image after its header, and the
 * bijective mix the digest is compared through. */
void mpm_ckpt_put_u64(unsigned char *b, uint64_t v);
uint64_t mpm_ckpt_get_u64(const unsigned char *b);
uint64_t mpm_ckpt_image_digest(const unsigned char *image, size_t size);
uint64_t mpm_ckpt_mix64(uint64_t h);
/* Write the header into the first MPM_CKPT_HEADER_BYTES of an image of `size` bytes. */
void mpm_ckpt_put_header(unsigned char *b, size_t size);

#endif
