/* vtu_stream.c - the VTU writers' stream and XML (see vtu_stream.h). */
#include "io/vtu_stream.h"

#include <errno.h>
#include <string.h>

void mpm_vtu_put(mpm_vtu_stream *o, const void *p, size_t n) {
  if (o->err || n == 0) return;
  errno = 0;
  if (fwrite(p, 1, n, o->fp) != n) o->err = errno ? errno : EIO;
}

void mpm_vtu_put_text(mpm_vtu_stream *o, const char *s) {
  mpm_vtu_put(o, s, strlen(s));
}

void mpm_vtu_put_count(mpm_vtu_stream *o, uint64_t bytes) {
  mpm_vtu_put(o, &bytes, sizeof bytes);
}

void mpm_vtu_begin(mpm_vtu_stream *o) {
  mpm_vtu_put_text(o, "<?xml version=\"1.0\"?>\n"
                      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                      "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                      "  <UnstructuredGrid>\n"
                      "    <FieldData>\n");
}

void mpm_vtu_piece(mpm_vtu_stream *o, size_t points, size_t cells) {
  char line[128];
  snprintf(line, sizeof line,
           "    </FieldData>\n    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n", points,
           cells);
  mpm_vtu_put_text(o, line);
}

void mpm_vtu_section(mpm_vtu_stream *o, const char *name, int open, const char *attrs) {
  char line[256];
  snprintf(line, sizeof line, "      <%s%s%s>\n", open ? "" : "/", name,
           open && attrs ? attrs : "");
  mpm_vtu_put_text(o, line);
}

void mpm_vtu_data_array(mpm_vtu_stream *o, int field, const char *type, const char *name, int comps,
                        int single, uint64_t offset) {
  char count[48] = "", line[320];
  if (comps > 1) snprintf(count, sizeof count, " NumberOfComponents=\"%d\"", comps);
  if (single) snprintf(count, sizeof count, " NumberOfTuples=\"1\"");
  snprintf(line, sizeof line,
           "%s<DataArray type=\"%s\" Name=\"%s\"%s format=\"appended\" offset=\"%llu\"/>\n",
           field ? "      " : "        ", type, name, count, (unsigned long long)offset);
  mpm_vtu_put_text(o, line);
}

void mpm_vtu_end_head(mpm_vtu_stream *o) {
  mpm_vtu_put_text(o, "    </Piece>\n"
                      "  </UnstructuredGrid>\n"
                      "  <AppendedData encoding=\"raw\">\n"
                      "   _");
}

void mpm_vtu_finish(mpm_vtu_stream *o) {
  mpm_vtu_put_text(o, "\n  </AppendedData>\n</VTKFile>\n");
}
