/* vtu_stream.h - what the VTU writers share (vtu.c: the particles; vtu_domains.c: the particle
 * domains; adaptive/cells_vtu.c: the multi-level grid's leaves): an output stream that keeps its
 * first failure, and the XML around the arrays of a VTK XML UnstructuredGrid with one raw appended
 * block (version 1.0, header_type UInt64: each array there is its UInt64 byte count, then its
 * values).
 *
 * A writer puts: mpm_vtu_begin, its FieldData arrays (mpm_vtu_data_array), mpm_vtu_piece, its
 * sections (mpm_vtu_section around their arrays), mpm_vtu_end_head, then the appended values
 * (mpm_vtu_put_count before each array), and mpm_vtu_finish. */
#ifndef MPM_IO_VTU_STREAM_H
#define MPM_IO_VTU_STREAM_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef struct mpm_vtu_stream {
  FILE *fp;
  int err; /* errno of the first failed write, 0 while fine: a full disk stops the writer */
} mpm_vtu_stream;

void mpm_vtu_put(mpm_vtu_stream *o, const void *p, size_t n);
void mpm_vtu_put_text(mpm_vtu_stream *o, const char *s);
void mpm_vtu_put_count(mpm_vtu_stream *o, uint64_t bytes); /* an array's byte count */

/* The XML declaration, <VTKFile>, <UnstructuredGrid> and <FieldData>. */
void mpm_vtu_begin(mpm_vtu_stream *o);
/* </FieldData> and <Piece> with its counts. */
void mpm_vtu_piece(mpm_vtu_stream *o, size_t points, size_t cells);
/* A section's opening (open = 1) or closing tag at the piece's indent, e.g. "PointData"; attrs
 * (or NULL) go inside the opening tag, e.g. " Scalars=\"stress\"". */
void mpm_vtu_section(mpm_vtu_stream *o, const char *name, int open, const char *attrs);
/* One appended DataArray line, at the depth of a section's arrays (field data: one level less):
 * comps > 1 writes NumberOfComponents, single writes NumberOfTuples="1". */
void mpm_vtu_data_array(mpm_vtu_stream *o, int field, const char *type, const char *name, int comps,
                        int single, uint64_t offset);
/* </Piece>, </UnstructuredGrid> and the opening of the appended block up to its '_'. */
void mpm_vtu_end_head(mpm_vtu_stream *o);
/* The end of the appended block and of the file. */
void mpm_vtu_finish(mpm_vtu_stream *o);

#endif
