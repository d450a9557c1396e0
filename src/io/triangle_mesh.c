/* triangle_mesh.c - OBJ, PLY and VTP writers of triangle meshes (see triangle_mesh.h). */
#include "io/triangle_mesh.h"
#include "io/io.h"

#include <stdio.h>

/* Vertex v's coordinate d as a double, from whichever array the view has. */
static double coord(const mpm_triangle_mesh *m, size_t v, int d) {
  return m->xd ? m->xd[3 * v + (size_t)d] : (double)m->xf[3 * v + (size_t)d];
}

mpm_status mpm_write_mesh_obj(const char *path, const mpm_triangle_mesh *m, mpm_error *err) {
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st != MPM_OK) return st;
  fprintf(f.fp, "# %s\n", m->title);
  for (size_t v = 0; v < m->vertex_count; ++v)
    fprintf(f.fp, "v %.9g %.9g %.9g\n", coord(m, v, 0), coord(m, v, 1), coord(m, v, 2));
  for (size_t t = 0; t < m->triangle_count; ++t)
    fprintf(f.fp, "f %u %u %u\n", (unsigned)m->triangles[3 * t] + 1,
            (unsigned)m->triangles[3 * t + 1] + 1, (unsigned)m->triangles[3 * t + 2] + 1);
  return mpm_atomic_commit(&f, err); /* a short write shows up as the stream's error here */
}

mpm_status mpm_write_mesh_ply(const char *path, const mpm_triangle_mesh *m, mpm_error *err) {
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st != MPM_OK) return st;
  fprintf(f.fp,
          "ply\nformat binary_little_endian 1.0\ncomment %s\n"
          "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
          "element face %zu\nproperty list uchar int vertex_indices\nend_header\n",
          m->title, m->vertex_count, m->triangle_count);
  /* the records byte by byte, little endian whatever the machine */
  for (size_t v = 0; v < m->vertex_count; ++v) {
    unsigned char rec[12];
    for (int d = 0; d < 3; ++d) {
      const float c = (float)coord(m, v, d);
      uint32_t bits;
      __builtin_memcpy(&bits, &c, sizeof bits);
      for (int b = 0; b < 4; ++b) rec[4 * d + b] = (unsigned char)(bits >> (8 * b));
    }
    fwrite(rec, 1, sizeof rec, f.fp);
  }
  unsigned char rec[13];
  rec[0] = 3;
  for (size_t t = 0; t < m->triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m->triangles[3 * t + (size_t)k];
      for (int b = 0; b < 4; ++b) rec[1 + 4 * k + b] = (unsigned char)(v >> (8 * b));
    }
    fwrite(rec, 1, sizeof rec, f.fp);
  }
  return mpm_atomic_commit(&f, err);
}

mpm_status mpm_write_mesh_vtp(const char *path, const mpm_triangle_mesh *m, double time,
                              mpm_error *err) {
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st != MPM_OK) return st;
  fprintf(f.fp,
          "<?xml version=\"1.0\"?>\n"
          "<!-- %s -->\n"
          "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n"
          "  <PolyData>\n"
          "    <FieldData>\n"
          "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" "
          "format=\"ascii\">%.17g</DataArray>\n"
          "    </FieldData>\n"
          "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" NumberOfLines=\"0\" "
          "NumberOfStrips=\"0\" NumberOfPolys=\"%zu\">\n"
          "      <Points>\n"
          "        <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n",
          m->title, time, m->vertex_count, m->triangle_count);
  for (size_t v = 0; v < m->vertex_count; ++v)
    fprintf(f.fp, "%.9g %.9g %.9g\n", (double)(float)coord(m, v, 0), (double)(float)coord(m, v, 1),
            (double)(float)coord(m, v, 2));
  fputs("        </DataArray>\n      </Points>\n      <Polys>\n"
        "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n",
        f.fp);
  for (size_t t = 0; t < m->triangle_count; ++t)
    fprintf(f.fp, "%u %u %u\n", (unsigned)m->triangles[3 * t], (unsigned)m->triangles[3 * t + 1],
            (unsigned)m->triangles[3 * t + 2]);
  fputs("        </DataArray>\n"
        "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n",
        f.fp);
  for (size_t t = 0; t < m->triangle_count; ++t) fprintf(f.fp, "%zu\n", 3 * (t + 1));
  fputs("        </DataArray>\n      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n", f.fp);
  return mpm_atomic_commit(&f, err);
}
