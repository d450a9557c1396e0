/* pvd.c - ParaView collection files (.pvd) that list a run's files with their times.
 *
 * Format: VTK XML "Collection" (ParaView data file, version 0.1): one
 * `<DataSet timestep="T" group="" part="P" file="F"/>` per file, T written with %.9g and F
 * relative to the .pvd's directory. frames.pvd has one part, the particles; run.pvd one part
 * per kind of file a frame has (particles, domains, each embedded surface), with a `name`
 * attribute saying which: ParaView's PVD reader makes each timestep a multiblock data set of
 * its parts, so one file opens everything of a run. The whole file is rewritten atomically
 * after each frame, so ParaView can reload it at any moment. */
#include "io/io.h"

#include <errno.h>
#include <string.h>

typedef struct pvd_out {
  FILE *fp;
  int err; /* errno of the first failed write */
} pvd_out;

static void out_text(pvd_out *o, const char *s) {
  const size_t n = strlen(s);
  if (o->err || n == 0) return;
  errno = 0;
  if (fwrite(s, 1, n, o->fp) != n) o->err = errno ? errno : EIO;
}

/* A file name as an XML attribute value (quotes, ampersands and angle brackets escaped). */
static void out_attr(pvd_out *o, const char *s) {
  for (; *s; ++s) {
    const char c = *s;
    const char one[2] = {c, '\0'};
    out_text(o, c == '&'   ? "&amp;"
                : c == '<' ? "&lt;"
                : c == '>' ? "&gt;"
                : c == '"' ? "&quot;"
                           : one);
  }
}

mpm_status mpm_write_pvd(const char *path, int count, const double *times, const char *const *files,
                         mpm_error *err) {
  return mpm_write_pvd_parts(path, count, 1, times, NULL, files, err);
}

mpm_status mpm_write_pvd_parts(const char *path, int count, int parts, const double *times,
                               const char *const *names, const char *const *files, mpm_error *err) {
  if (count < 0 || parts < 1)
    return mpm_error_set(err, MPM_ERR_INVALID,
                         "cannot write '%s': negative frame count %d or no parts (%d)", path, count,
                         parts);
  mpm_atomic_file af;
  const mpm_status st = mpm_atomic_open(&af, path, err);
  if (st != MPM_OK) return st;
  pvd_out o = {af.fp, 0};
  out_text(&o, "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
               "  <Collection>\n");
  for (int i = 0; i < count && !o.err; ++i)
    for (int k = 0; k < parts; ++k) {
      const char *file = files[(size_t)i * (size_t)parts + (size_t)k];
      if (!file) continue; /* a part this frame does not have */
      char line[128];
      snprintf(line, sizeof line, "    <DataSet timestep=\"%.9g\" group=\"\" part=\"%d\" ",
               times[i], k);
      out_text(&o, line);
      if (names) {
        out_text(&o, "name=\"");
        out_attr(&o, names[k]);
        out_text(&o, "\" ");
      }
      out_text(&o, "file=\"");
      out_attr(&o, file);
      out_text(&o, "\"/>\n");
    }
  out_text(&o, "  </Collection>\n</VTKFile>\n");
  if (o.err) {
    mpm_atomic_abort(&af);
    return mpm_error_set(err, MPM_ERR_IO, "cannot write '%s': %s", path, strerror(o.err));
  }
  return mpm_atomic_commit(&af, err);
}
