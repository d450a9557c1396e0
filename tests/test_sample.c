/* test_sample.c - mesh readers (OBJ, PLY ascii and binary; files and buffers), the
 * point-in-mesh test and body sampling: volumes against analytic values, masses, lattice
 * alignment, jitter, rigid rotation, mesh bodies against the equivalent box, the bunny, and
 * error messages. */
#include "support.h"

#include "scene/mesh.h"
#include "scene/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* ---- helpers ------------------------------------------------------------------------- */

typedef struct fixture {
  mpm_scene scene;
  mpm_body_desc body;
  mpm_material_desc material;
  mpm_particles p;
  mpm_error err;
} fixture;

/* Domain [0,1]^3, dx 0.05, one material of density 1000, one body of 8 ppc (h = 0.025). */
static void fixture_init(fixture *f) {
  memset(f, 0, sizeof *f);
  for (int d = 0; d < 3; ++d) f->scene.box_max[d] = 1;
  f->scene.dx = 0.05;
  f->material.density = 1000;
  f->scene.material_count = 1;
  f->scene.materials = &f->material;
  f->scene.body_count = 1;
  f->scene.bodies = &f->body;
  f->body.particles_per_cell = 8;
  f->body.shape.mesh_scale = 1;
  for (int d = 0; d < 3; ++d) f->body.shape.center[d] = 0.5;
  assert_int_equal(mpm_particles_init(&f->p, 16), MPM_OK);
  mpm_error_clear(&f->err);
}

static void fixture_free(fixture *f) {
  mpm_particles_free(&f->p);
}

static void sample_ok(fixture *f) {
  mpm_status st = mpm_sample_body(&f->scene, 0, &f->p, &f->err);
  if (st != MPM_OK) fail_msg("sampling failed: %s", f->err.message);
}

static void write_text(const char *path, const char *text) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
}

static void assert_contains(const char *haystack, const char *needle) {
  if (!strstr(haystack, needle)) fail_msg("'%s' does not contain '%s'", haystack, needle);
}

static double signed_volume(const mpm_mesh *m) {
  double v = 0;
  for (int t = 0; t < m->triangle_count; ++t) {
    const double *a = &m->vertices[3 * m->triangles[3 * t]];
    const double *b = &m->vertices[3 * m->triangles[3 * t + 1]];
    const double *c = &m->vertices[3 * m->triangles[3 * t + 2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6;
  }
  return v;
}

/* The unit cube [0,1]^3 as six outward quads. */
static const double cube_v[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
static const int cube_f[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                 {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3}};

/* OBJ with comments, normals and texture coordinates, every face-vertex form and negative
 * indices; `skip_face` >= 0 leaves that face out (an open box). */
static void write_cube_obj(const char *path, int skip_face) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fprintf(fp, "# unit cube\r\nmtllib none.mtl\no cube\n");
  for (int i = 0; i < 8; ++i) fprintf(fp, "v %g %g %g\n", cube_v[i][0], cube_v[i][1], cube_v[i][2]);
  fprintf(fp, "vt 0 0\nvn 0 0 1\ns off\n\n");
  for (int f = 0; f < 6; ++f) {
    if (f == skip_face) continue;
    const int *q = cube_f[f];
    switch (f % 4) {
    case 0:
      fprintf(fp, "f %d %d %d %d\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
      break;
    case 1:
      fprintf(fp, "f %d/1 %d/1 %d/1 %d/1\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
      break;
    case 2:
      fprintf(fp, "f %d//1 %d//1 %d//1 %d//1\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
      break;
    default: /* negative: -1 is the last vertex (index 7) */
      fprintf(fp, "f\t%d/1/1 %d/1/1 %d/1/1 %d/1/1\n", q[0] - 8, q[1] - 8, q[2] - 8, q[3] - 8);
    }
  }
  fclose(fp);
}

static void write_cube_ply_ascii(const char *path) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fprintf(fp, "ply\nformat ascii 1.0\ncomment unit cube\nelement vertex 8\n"
              "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
              "element face 6\nproperty list uchar int vertex_indices\nproperty int flag\n"
              "end_header\n");
  for (int i = 0; i < 8; ++i)
    fprintf(fp, "%g %g %g 255\n", cube_v[i][0], cube_v[i][1], cube_v[i][2]);
  for (int f = 0; f < 6; ++f)
    fprintf(fp, "4 %d %d %d %d 7\n", cube_f[f][0], cube_f[f][1], cube_f[f][2], cube_f[f][3]);
  fclose(fp);
}

static void put_bytes(FILE *fp, const void *v, int n, int big) {
  const unsigned char *b = v;
  const unsigned short one = 1;
  int host_le = *(const unsigned char *)&one == 1;
  for (int k = 0; k < n; ++k) fputc(b[(big == host_le) ? n - 1 - k : k], fp);
}

/* Binary PLY with double positions, extra properties of several types before, between and
 * after x y z, an extra element, and a uint index list. `truncate` drops the last bytes. */
static void write_cube_ply_binary(const char *path, int big, int truncate) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  fprintf(fp,
          "ply\nformat %s 1.0\nelement vertex 8\nproperty short id\nproperty double x\n"
          "property double y\nproperty float nx\nproperty double z\nproperty uchar alpha\n"
          "element material 1\nproperty list uchar float rgb\n"
          "element face 6\nproperty list int uint vertex_index\nend_header\n",
          big ? "binary_big_endian" : "binary_little_endian");
  for (int i = 0; i < 8; ++i) {
    short id = (short)i;
    float nx = 0.5f;
    unsigned char alpha = 9;
    put_bytes(fp, &id, 2, big);
    put_bytes(fp, &cube_v[i][0], 8, big);
    put_bytes(fp, &cube_v[i][1], 8, big);
    put_bytes(fp, &nx, 4, big);
    put_bytes(fp, &cube_v[i][2], 8, big);
    put_bytes(fp, &alpha, 1, big);
  }
  unsigned char three = 3;
  float rgb[3] = {1, 2, 3};
  put_bytes(fp, &three, 1, big);
  for (int k = 0; k < 3; ++k) put_bytes(fp, &rgb[k], 4, big);
  for (int f = 0; f < 6; ++f) {
    int n = 4;
    put_bytes(fp, &n, 4, big);
    int last = (f == 5 && truncate) ? 4 - truncate : 4;
    for (int k = 0; k < last; ++k) {
      unsigned int idx = (unsigned int)cube_f[f][k];
      put_bytes(fp, &idx, 4, big);
    }
  }
  fclose(fp);
}

/* ---- analytic shapes ------------------------------------------------------------------ */

static void test_box_counts_mass_alignment(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.body.shape.kind = MPM_SHAPE_BOX;
  f.body.shape.half_extent[0] = 0.2; /* [0.3, 0.7] x [0.35, 0.65] x [0.4, 0.6] */
  f.body.shape.half_extent[1] = 0.15;
  f.body.shape.half_extent[2] = 0.1;
  sample_ok(&f);
  const double h = mpm_sample_spacing(&f.scene, 0);
  assert_close(h, 0.025, 1e-15);
  /* the faces fall halfway between lattice points: exactly 16 x 12 x 8 points */
  assert_int_equal(f.p.count, 16 * 12 * 8);
  assert_close(f.p.count * h * h * h, 0.4 * 0.3 * 0.2, 1e-12);
  const mpm_real m = (mpm_real)(1000 * h * h * h), vol = (mpm_real)(h * h * h);
  double total = 0;
  for (size_t i = 0; i < f.p.count; ++i) {
    assert_true(f.p.mass[i] == m);
    assert_true(f.p.vol0[i] == vol);
    assert_int_equal(f.p.material[i], 0);
    assert_int_equal(f.p.body[i], 0);
    total += f.p.mass[i];
    for (int d = 0; d < 3; ++d) {
      double x = f.p.x[d][i];
      assert_true(fabs(x - 0.5) <= f.body.shape.half_extent[d]);
      double k = x / h - 0.5; /* lattice: box_min + (k + 1/2) h */
      assert_close(k, round(k), TOL(1e-4, 1e-9));
      assert_true(f.p.v[d][i] == 0);
    }
    for (int c = 0; c < 9; ++c) assert_true(f.p.F[c][i] == ((c % 4 == 0) ? 1 : 0));
  }
  assert_close(total, 1000.0 * (double)f.p.count * h * h * h, TOL(1e-6, 1e-12) * total);
  assert_close(total, (double)m * (double)f.p.count, TOL(1e-6, 1e-12) * total);
  fixture_free(&f);
}

static void test_box_unaligned_volume(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.body.shape.kind = MPM_SHAPE_BOX;
  f.body.shape.center[0] = 0.4137;
  f.body.shape.half_extent[0] = 0.2113;
  f.body.shape.half_extent[1] = 0.1771;
  f.body.shape.half_extent[2] = 0.1499;
  sample_ok(&f);
  const double h = 0.025, exact = 8 * 0.2113 * 0.1771 * 0.1499;
  assert_close(f.p.count * h * h * h, exact, 0.06 * exact);
  fixture_free(&f);
}

static void test_sphere_volume_inside(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.body.particles_per_cell = 27; /* h = dx / 3 */
  f.body.shape.kind = MPM_SHAPE_SPHERE;
  f.body.shape.radius = 0.3;
  sample_ok(&f);
  const double h = mpm_sample_spacing(&f.scene, 0);
  assert_close(h, 0.05 / 3, 1e-12);
  const double exact = 4.0 / 3.0 * PI * 0.027;
  assert_close(f.p.count * h * h * h, exact, 0.02 * exact);
  for (size_t i = 0; i < f.p.count; ++i) {
    double r2 = 0;
    for (int d = 0; d < 3; ++d) r2 += (f.p.x[d][i] - 0.5) * (f.p.x[d][i] - 0.5);
    assert_true(sqrt(r2) <= 0.3 + TOL(1e-6, 1e-12));
  }
  fixture_free(&f);
}

static void test_cylinder_tilted_axis(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.scene.dx = 0.02; /* h = 0.01 */
  f.body.shape.kind = MPM_SHAPE_CYLINDER;
  f.body.shape.radius = 0.12;
  f.body.shape.half_height = 0.25;
  const double a[3] = {1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)};
  for (int d = 0; d < 3; ++d) f.body.shape.axis[d] = a[d];
  sample_ok(&f);
  const double h = 0.01, exact = PI * 0.12 * 0.12 * 0.5;
  assert_close(f.p.count * h * h * h, exact, 0.03 * exact);
  for (size_t i = 0; i < f.p.count; ++i) {
    double dd[3], t = 0, r2 = 0;
    for (int d = 0; d < 3; ++d) dd[d] = f.p.x[d][i] - 0.5, t += dd[d] * a[d];
    for (int d = 0; d < 3; ++d) r2 += (dd[d] - t * a[d]) * (dd[d] - t * a[d]);
    assert_true(fabs(t) <= 0.25 + 1e-6);
    assert_true(sqrt(r2) <= 0.12 + 1e-6);
  }
  fixture_free(&f);
}

static void test_jitter_bounds_and_determinism(void **state) {
  (void)state;
  fixture a, b, c;
  fixture_init(&a);
  fixture_init(&b);
  fixture_init(&c);
  a.body.shape.kind = b.body.shape.kind = c.body.shape.kind = MPM_SHAPE_SPHERE;
  a.body.shape.radius = b.body.shape.radius = c.body.shape.radius = 0.2;
  b.body.jitter = c.body.jitter = 0.8;
  b.body.seed = c.body.seed = 42;
  sample_ok(&a);
  sample_ok(&b);
  sample_ok(&c);
  assert_int_equal(a.p.count, b.p.count);
  const double half = 0.8 * 0.025 / 2;
  double maxoff = 0, mean = 0;
  for (size_t i = 0; i < a.p.count; ++i)
    for (int d = 0; d < 3; ++d) {
      double off = (double)b.p.x[d][i] - (double)a.p.x[d][i];
      assert_true(fabs(off) <= half + TOL(1e-6, 1e-14));
      assert_true(b.p.x[d][i] == c.p.x[d][i]); /* same seed, same particles */
      maxoff = fmax(maxoff, fabs(off));
      mean += off;
    }
  mean /= 3.0 * (double)a.p.count;
  assert_true(maxoff > 0.9 * half); /* the offsets fill the range */
  assert_true(fabs(mean) < 0.05 * half);
  /* another seed moves the points differently */
  fixture_free(&c);
  fixture_init(&c);
  c.body = b.body;
  c.body.seed = 43;
  sample_ok(&c);
  int differ = 0;
  for (size_t i = 0; i < c.p.count; ++i) differ += c.p.x[0][i] != b.p.x[0][i];
  assert_true(differ > (int)c.p.count / 2);
  fixture_free(&a);
  fixture_free(&b);
  fixture_free(&c);
}

static void test_angular_velocity(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.body.shape.kind = MPM_SHAPE_CYLINDER;
  f.body.shape.center[0] = 0.47;
  f.body.shape.radius = 0.2;
  f.body.shape.half_height = 0.1;
  f.body.shape.axis[2] = 1;
  f.body.jitter = 0.5;
  f.body.seed = 7;
  const double v0[3] = {1, -2, 0.5}, w[3] = {0.3, -0.2, 4};
  for (int d = 0; d < 3; ++d) f.body.velocity[d] = v0[d], f.body.angular_velocity[d] = w[d];
  sample_ok(&f);
  const size_t n = f.p.count;
  double c[3] = {0, 0, 0}, mom[3] = {0, 0, 0}, mass = 0, L = 0;
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) c[d] += f.p.x[d][i] / (double)n;
  for (size_t i = 0; i < n; ++i) {
    double r[3] = {f.p.x[0][i] - c[0], f.p.x[1][i] - c[1], f.p.x[2][i] - c[2]};
    double wr[3] = {w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2],
                    w[0] * r[1] - w[1] * r[0]};
    for (int d = 0; d < 3; ++d) {
      assert_close(f.p.v[d][i], v0[d] + wr[d], TOL(2e-6, 1e-12));
      mom[d] += f.p.mass[i] * f.p.v[d][i];
    }
    mass += f.p.mass[i];
    L += f.p.mass[i] * (r[0] * f.p.v[1][i] - r[1] * f.p.v[0][i]); /* z angular momentum */
  }
  /* the rotation adds no net linear momentum */
  for (int d = 0; d < 3; ++d) assert_close(mom[d] / mass, v0[d], TOL(1e-5, 1e-12));
  assert_true(L > 0); /* w_z > 0 spins counter-clockwise */
  fixture_free(&f);
}

static void test_sampling_errors(void **state) {
  (void)state;
  fixture f;
  fixture_init(&f);
  f.scene.path[0] = '\0';
  snprintf(f.scene.path, sizeof f.scene.path, "scenes/tiny.json");
  f.body.shape.kind = MPM_SHAPE_SPHERE;
  f.body.shape.radius = 0.004; /* between lattice points (h = 0.025) */
  f.body.shape.center[0] = f.body.shape.center[1] = f.body.shape.center[2] = 0.5;
  assert_int_equal(mpm_sample_body(&f.scene, 0, &f.p, &f.err), MPM_ERR_INVALID);
  assert_contains(f.err.message, "bodies[0]");
  assert_contains(f.err.message, "smaller dx");
  assert_contains(f.err.message, "particles_per_cell");
  assert_contains(f.err.message, "tiny.json");
  assert_int_equal(f.p.count, 0);

  /* partly outside the domain: an error, and nothing appended */
  f.body.shape.radius = 0.2;
  f.body.shape.center[1] = 0.9;
  assert_int_equal(mpm_sample_body(&f.scene, 0, &f.p, &f.err), MPM_ERR_INVALID);
  assert_contains(f.err.message, "bodies[0]");
  assert_contains(f.err.message, "outside the domain");
  assert_int_equal(f.p.count, 0);

  /* an infinite cylinder cannot be a body */
  f.body.shape.kind = MPM_SHAPE_CYLINDER;
  f.body.shape.center[1] = 0.5;
  f.body.shape.axis[0] = 1;
  f.body.shape.half_height = 0;
  assert_int_equal(mpm_sample_body(&f.scene, 0, &f.p, &f.err), MPM_ERR_INVALID);
  assert_contains(f.err.message, "bodies[0].shape.half_height");

  /* a missing mesh file */
  f.body.shape.kind = MPM_SHAPE_MESH;
  snprintf(f.body.shape.mesh_path, sizeof f.body.shape.mesh_path, "/nonexistent/x.obj");
  assert_int_equal(mpm_sample_body(&f.scene, 0, &f.p, &f.err), MPM_ERR_IO);
  assert_contains(f.err.message, "x.obj");
  assert_int_equal(f.p.count, 0);
  fixture_free(&f);
}

/* ---- meshes --------------------------------------------------------------------------- */

/* Loads `file` as the unit cube and checks it samples exactly like the box it describes. */
static void check_cube_mesh(const char *dir, const char *file) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  mpm_mesh mesh;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_mesh_load(path, &mesh, &err) != MPM_OK) fail_msg("%s", err.message);
  assert_int_equal(mesh.vertex_count, 8);
  assert_int_equal(mesh.triangle_count, 12);
  assert_int_equal(mpm_mesh_boundary_edges(&mesh), 0);
  assert_close(signed_volume(&mesh), 1, 1e-12);
  double lo[3], hi[3];
  mpm_mesh_bounds(&mesh, lo, hi);
  for (int d = 0; d < 3; ++d) assert_true(lo[d] == 0 && hi[d] == 1);
  const double in[3] = {0.5, 0.25, 0.75}, out[3] = {1.5, 0.5, 0.5};
  assert_true(mpm_mesh_inside(&mesh, in));
  assert_false(mpm_mesh_inside(&mesh, out));
  mpm_mesh_free(&mesh);

  fixture box, cube;
  fixture_init(&box);
  fixture_init(&cube);
  box.body.shape.kind = MPM_SHAPE_BOX;
  for (int d = 0; d < 3; ++d) box.body.shape.half_extent[d] = 0.3;
  cube.body.shape.kind = MPM_SHAPE_MESH;
  cube.body.shape.mesh_scale = 0.6; /* [0,1]^3 -> [0.2, 0.8]^3 */
  snprintf(cube.scene.path, sizeof cube.scene.path, "%s/scene.json", dir);
  snprintf(cube.body.shape.mesh_path, sizeof cube.body.shape.mesh_path, "%s", file);
  sample_ok(&box);
  sample_ok(&cube);
  assert_int_equal(box.p.count, 24 * 24 * 24);
  assert_int_equal(cube.p.count, box.p.count);
  for (size_t i = 0; i < box.p.count; ++i)
    for (int d = 0; d < 3; ++d) assert_true(box.p.x[d][i] == cube.p.x[d][i]);
  fixture_free(&box);
  fixture_free(&cube);
}

static void test_cube_obj_and_ply(void **state) {
  (void)state;
  const char *dir = test_temp_dir("sample-cube");
  char path[600];
  snprintf(path, sizeof path, "%s/cube.obj", dir);
  write_cube_obj(path, -1);
  check_cube_mesh(dir, "cube.obj");
  snprintf(path, sizeof path, "%s/CUBE.OBJ", dir); /* the extension is case-insensitive */
  write_cube_obj(path, -1);
  check_cube_mesh(dir, "CUBE.OBJ");
  snprintf(path, sizeof path, "%s/cube_ascii.ply", dir);
  write_cube_ply_ascii(path);
  check_cube_mesh(dir, "cube_ascii.ply");
  snprintf(path, sizeof path, "%s/cube_le.ply", dir);
  write_cube_ply_binary(path, 0, 0);
  check_cube_mesh(dir, "cube_le.ply");
  snprintf(path, sizeof path, "%s/cube_be.Ply", dir);
  write_cube_ply_binary(path, 1, 0);
  check_cube_mesh(dir, "cube_be.Ply");
}

/* A box with its +x face missing: the x rays through the hole cross once, so those columns
 * are decided by the winding number, which still gives exactly the box. */
static void test_open_cube_falls_back_to_winding_number(void **state) {
  (void)state;
  const char *dir = test_temp_dir("sample-open");
  char path[600];
  snprintf(path, sizeof path, "%s/open.obj", dir);
  write_cube_obj(path, 4);
  mpm_mesh mesh;
  mpm_error err;
  assert_int_equal(mpm_mesh_load(path, &mesh, &err), MPM_OK);
  assert_int_equal(mesh.triangle_count, 10);
  assert_int_equal(mpm_mesh_boundary_edges(&mesh), 4);
  mpm_mesh_free(&mesh);
  fixture box, open;
  fixture_init(&box);
  fixture_init(&open);
  box.body.shape.kind = MPM_SHAPE_BOX;
  for (int d = 0; d < 3; ++d) box.body.shape.half_extent[d] = 0.3;
  open.body.shape.kind = MPM_SHAPE_MESH;
  open.body.shape.mesh_scale = 0.6;
  snprintf(open.body.shape.mesh_path, sizeof open.body.shape.mesh_path, "%s", path);
  sample_ok(&box);
  sample_ok(&open);
  assert_int_equal(open.p.count, box.p.count);
  for (size_t i = 0; i < box.p.count; ++i)
    for (int d = 0; d < 3; ++d) assert_true(box.p.x[d][i] == open.p.x[d][i]);
  fixture_free(&box);
  fixture_free(&open);
}

/* Boxes (centre, half side) as one OBJ, each as 12 triangles wound outwards, or inwards where
 * reversed[k]. */
static void write_boxes_obj(const char *path, int count, const double (*c)[4],
                            const int *reversed) {
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  for (int k = 0; k < count; ++k)
    for (int i = 0; i < 8; ++i)
      fprintf(fp, "v %.17g %.17g %.17g\n", c[k][0] + (cube_v[i][0] - 0.5) * 2 * c[k][3],
              c[k][1] + (cube_v[i][1] - 0.5) * 2 * c[k][3],
              c[k][2] + (cube_v[i][2] - 0.5) * 2 * c[k][3]);
  for (int k = 0; k < count; ++k)
    for (int f = 0; f < 6; ++f) {
      const int *q = cube_f[f], o = 8 * k + 1;
      if (reversed[k])
        fprintf(fp, "f %d %d %d %d\n", q[3] + o, q[2] + o, q[1] + o, q[0] + o);
      else
        fprintf(fp, "f %d %d %d %d\n", q[0] + o, q[1] + o, q[2] + o, q[3] + o);
    }
  fclose(fp);
}

/* Particles of a mesh body (file path, scale 1, centred at the origin of the file): the count,
 * or -1 with the message in msg. */
static long mesh_particles(const char *path, char *msg, size_t cap) {
  fixture f;
  fixture_init(&f);
  f.body.shape.kind = MPM_SHAPE_MESH;
  for (int d = 0; d < 3; ++d) f.body.shape.center[d] = 0.5;
  snprintf(f.body.shape.mesh_path, sizeof f.body.shape.mesh_path, "%s", path);
  const mpm_status st = mpm_sample_body(&f.scene, 0, &f.p, &f.err);
  snprintf(msg, cap, "%s", f.err.message);
  const long n = st == MPM_OK ? (long)f.p.count : -1;
  fixture_free(&f);
  return n;
}

/* Several shells in one mesh. Two boxes that overlap (or one inside another wound the same way)
 * were sampled by parity, leaving the overlap hollow: they are refused, naming the face. A box
 * inside another wound the other way is a hollow body: the outer box's particles less the
 * inner's. Two boxes that touch along a face are both filled. */
static void test_mesh_shells(void **state) {
  (void)state;
  const char *dir = test_temp_dir("sample-shells");
  char path[600], msg[1024];
  const double one[1][4] = {{0, 0, 0, 0.2}}, inner[1][4] = {{0, 0, 0, 0.1}};
  const int fwd[2] = {0, 0}, hollow_rev[2] = {0, 1};
  snprintf(path, sizeof path, "%s/one.obj", dir);
  write_boxes_obj(path, 1, one, fwd);
  const long n_outer = mesh_particles(path, msg, sizeof msg);
  write_boxes_obj(path, 1, inner, fwd);
  const long n_inner = mesh_particles(path, msg, sizeof msg);
  assert_true(n_outer > 0 && n_inner > 0);
  const double nested[2][4] = {{0, 0, 0, 0.2}, {0, 0, 0, 0.1}};
  snprintf(path, sizeof path, "%s/hollow.obj", dir);
  write_boxes_obj(path, 2, nested, hollow_rev);
  const long n_hollow = mesh_particles(path, msg, sizeof msg);
  print_message("outer %ld, inner %ld, hollow %ld particles\n", n_outer, n_inner, n_hollow);
  assert_int_equal(n_hollow, n_outer - n_inner);
  snprintf(path, sizeof path, "%s/nested_same.obj", dir);
  write_boxes_obj(path, 2, nested, fwd);
  assert_int_equal(mesh_particles(path, msg, sizeof msg), -1);
  assert_contains(msg, "has shells that overlap");
  const double overlap[2][4] = {{0, 0, 0, 0.2}, {0.1, 0.07, 0.05, 0.2}};
  snprintf(path, sizeof path, "%s/overlap.obj", dir);
  write_boxes_obj(path, 2, overlap, fwd);
  assert_int_equal(mesh_particles(path, msg, sizeof msg), -1);
  print_message("%s\n", msg);
  assert_contains(msg, "overlap.obj' has shells that overlap");
  assert_contains(msg, "is inside two of them (the face at line ");
  const double touch[2][4] = {{-0.2, 0, 0, 0.2}, {0.2, 0, 0, 0.2}};
  snprintf(path, sizeof path, "%s/touch.obj", dir);
  write_boxes_obj(path, 2, touch, fwd);
  const long n_touch = mesh_particles(path, msg, sizeof msg);
  if (n_touch < 0) fail_msg("touching boxes refused: %s", msg);
  assert_int_equal(n_touch, 2 * n_outer);
}

static void test_torus_inside(void **state) {
  (void)state;
  mpm_mesh mesh;
  mpm_error err;
  if (mpm_mesh_load(MPM_SOURCE_DIR "/examples/meshes/torus.obj", &mesh, &err) != MPM_OK)
    fail_msg("%s", err.message);
  assert_int_equal(mesh.triangle_count, 1600);
  assert_int_equal(mpm_mesh_boundary_edges(&mesh), 0);
  const double hole[3] = {0, 0, 0}, above_hole[3] = {0, 0, 0.3}, tube[3] = {1, 0, 0},
               tube2[3] = {0, -1.2, 0.1}, beyond[3] = {1.6, 0, 0}, over_tube[3] = {1, 0, 0.5};
  assert_false(mpm_mesh_inside(&mesh, hole));
  assert_false(mpm_mesh_inside(&mesh, above_hole));
  assert_true(mpm_mesh_inside(&mesh, tube));
  assert_true(mpm_mesh_inside(&mesh, tube2));
  assert_false(mpm_mesh_inside(&mesh, beyond));
  assert_false(mpm_mesh_inside(&mesh, over_tube));
  assert_close(mpm_mesh_winding_number(&mesh, tube), 1, 1e-9);
  assert_close(mpm_mesh_winding_number(&mesh, hole), 0, 1e-9);

  /* sampled at scale 0.25 about (0.5, 0.5, 0.5): the volume of the polyhedron, and the
   * particles (every 11th) agree with the winding-number test */
  fixture f;
  fixture_init(&f);
  f.scene.dx = 0.02; /* h = 0.01 */
  f.body.shape.kind = MPM_SHAPE_MESH;
  f.body.shape.mesh_scale = 0.25;
  snprintf(f.body.shape.mesh_path, sizeof f.body.shape.mesh_path, "%s",
           MPM_SOURCE_DIR "/examples/meshes/torus.obj");
  sample_ok(&f);
  const double h = 0.01, exact = signed_volume(&mesh) * 0.25 * 0.25 * 0.25;
  assert_close(f.p.count * h * h * h, exact, 0.03 * exact);
  for (size_t i = 0; i < f.p.count; i += 11) {
    double p[3] = {(f.p.x[0][i] - 0.5) / 0.25, (f.p.x[1][i] - 0.5) / 0.25,
                   (f.p.x[2][i] - 0.5) / 0.25};
    assert_true(mpm_mesh_inside(&mesh, p));
  }
  fixture_free(&f);
  mpm_mesh_free(&mesh);
}

static void test_bunny(void **state) {
  (void)state;
  const char *path = MPM_SOURCE_DIR "/examples/meshes/bunny.obj";
  mpm_mesh mesh;
  mpm_error err;
  if (mpm_mesh_load(path, &mesh, &err) != MPM_OK) fail_msg("%s", err.message);
  assert_int_equal(mesh.vertex_count, 1839);
  assert_int_equal(mesh.triangle_count, 3674);
  assert_int_equal(mpm_mesh_boundary_edges(&mesh), 0); /* closed */
  const double vol = signed_volume(&mesh);
  assert_true(vol > 0); /* outward-facing */
  double lo[3], hi[3];
  mpm_mesh_bounds(&mesh, lo, hi);

  fixture f;
  fixture_init(&f);
  f.scene.dx = 0.02; /* h = 0.01: about 24k particles */
  f.body.shape.kind = MPM_SHAPE_MESH;
  f.body.shape.mesh_scale = 0.06;
  f.body.shape.center[1] = 0.4;
  snprintf(f.body.shape.mesh_path, sizeof f.body.shape.mesh_path, "%s", path);
  sample_ok(&f);
  const double s = 0.06, h = 0.01, exact = vol * s * s * s;
  assert_true(f.p.count > 1000);
  assert_close(f.p.count * h * h * h, exact, 0.03 * exact);
  const double c[3] = {0.5, 0.4, 0.5};
  for (size_t i = 0; i < f.p.count; ++i) {
    double p[3];
    for (int d = 0; d < 3; ++d) {
      double x = f.p.x[d][i];
      assert_true(x >= c[d] + s * (lo[d] - 0.5 * (lo[d] + hi[d])) - 1e-6);
      assert_true(x <= c[d] + s * (hi[d] - 0.5 * (lo[d] + hi[d])) + 1e-6);
      p[d] = (x - c[d]) / s + 0.5 * (lo[d] + hi[d]);
    }
    if (i % 29 == 0) assert_true(mpm_mesh_inside(&mesh, p));
  }
  fixture_free(&f);
  mpm_mesh_free(&mesh);
}

/* ---- malformed files ------------------------------------------------------------------ */

static void expect_parse_error(const char *dir, const char *file, const char *text,
                               const char *where, const char *what) {
  char path[600];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  if (text) write_text(path, text);
  mpm_mesh mesh;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_mesh_load(path, &mesh, &err);
  if (st != MPM_ERR_PARSE) fail_msg("%s: status %d, message '%s'", file, (int)st, err.message);
  assert_contains(err.message, where);
  assert_contains(err.message, what);
  assert_null(mesh.vertices);
  assert_null(mesh.triangles);
  assert_int_equal(mesh.triangle_count, 0);
}

static void test_malformed_files(void **state) {
  (void)state;
  const char *dir = test_temp_dir("sample-bad");
  expect_parse_error(dir, "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 9000\n",
                     "range.obj:5:", "face index 9000 out of range (1..3)");
  expect_parse_error(dir, "neg.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
                     "neg.obj:3:", "out of range");
  expect_parse_error(dir, "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
                     "zero.obj:4:", "index 0");
  expect_parse_error(dir, "short.obj", "# a\nv 0 0 0\nv 1 zero 0\n",
                     "short.obj:3:", "vertex needs 3 numbers");
  expect_parse_error(dir, "two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
                     "two.obj:4:", "at least 3");
  expect_parse_error(dir, "word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
                     "word.obj:4:", "'x' is not an index");
  expect_parse_error(dir, "empty.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "empty.obj", "no faces");
  /* found by fuzz_obj: -LONG_MIN overflowed in the range check (UBSan) */
  expect_parse_error(dir, "min.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
                     "min.obj:4:", "face index -9223372036854775808 out of range (-3..-1");

  const char *head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                     "property float y\nproperty float z\nelement face 1\n"
                     "property list uchar int vertex_indices\nend_header\n";
  char text[1024];
  snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", head);
  expect_parse_error(dir, "range.ply", text, "range.ply:13:", "vertex index 7 out of range (0..2)");
  snprintf(text, sizeof text, "%s0 0 0\n1 oops 0\n0 1 0\n3 0 1 2\n", head);
  expect_parse_error(dir, "num.ply", text, "num.ply:11:", "'oops'");
  snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 1 0\n", head);
  expect_parse_error(dir, "eof.ply", text, "eof.ply", "unexpected end of data in element 'face'");
  expect_parse_error(dir, "magic.ply", "plx\n", "magic.ply:1:", "'ply'");
  expect_parse_error(dir, "kw.ply", "ply\nformat ascii 1.0\nelemnt vertex 3\n",
                     "kw.ply:3:", "unknown header keyword 'elemnt'");
  expect_parse_error(dir, "fmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
                     "fmt.ply:2:", "format");
  expect_parse_error(dir, "noface.ply",
                     "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                     "property float y\nproperty float z\nend_header\n0 0 0\n",
                     "noface.ply", "no 'element face'");
  char path[600];
  snprintf(path, sizeof path, "%s/trunc.ply", dir);
  write_cube_ply_binary(path, 0, 2);
  expect_parse_error(dir, "trunc.ply", NULL, "trunc.ply", "element 'face' 5");

  /* not a parse error: unknown extension and a missing file */
  mpm_mesh mesh;
  mpm_error err;
  assert_int_equal(mpm_mesh_load("cube.stl", &mesh, &err), MPM_ERR_INVALID);
  assert_contains(err.message, ".obj or .ply");
  assert_int_equal(mpm_mesh_load("/nonexistent/cube.obj", &mesh, &err), MPM_ERR_IO);
  assert_contains(err.message, "/nonexistent/cube.obj");
}

/* Allocate exactly n bytes holding text (no NUL after them), so that AddressSanitizer sees a
 * parser that reads past the end of its input. */
static char *exact_copy(const char *text, size_t n) {
  char *p = malloc(n ? n : 1);
  assert_non_null(p);
  memcpy(p, text, n);
  return p;
}

/* mpm_mesh_parse: the in-memory reader behind mpm_mesh_load (and the fuzz targets). */
static void test_parse_from_memory(void **state) {
  (void)state;
  mpm_mesh mesh, ref;
  mpm_error err;
  /* an OBJ without a final newline or NUL: one triangle */
  const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3";
  char *buf = exact_copy(obj, sizeof obj - 1);
  assert_int_equal(mpm_mesh_parse(buf, sizeof obj - 1, MPM_MESH_OBJ, "mem.obj", &mesh, &err),
                   MPM_OK);
  assert_int_equal(mesh.vertex_count, 3);
  assert_int_equal(mesh.triangle_count, 1);
  assert_true(mesh.vertices[3] == 1 && mesh.triangles[2] == 2);
  mpm_mesh_free(&mesh);
  free(buf);

  /* a binary PLY file's bytes give the mesh mpm_mesh_load reads from the file */
  const char *dir = test_temp_dir("sample-memory");
  char path[600];
  snprintf(path, sizeof path, "%s/cube_be.ply", dir);
  write_cube_ply_binary(path, 1, 0);
  FILE *fp = fopen(path, "rb");
  assert_non_null(fp);
  char bytes[4096];
  size_t n = fread(bytes, 1, sizeof bytes, fp);
  fclose(fp);
  assert_true(n > 0 && n < sizeof bytes);
  buf = exact_copy(bytes, n);
  assert_int_equal(mpm_mesh_parse(buf, n, MPM_MESH_PLY, NULL, &mesh, &err), MPM_OK);
  free(buf);
  assert_int_equal(mpm_mesh_load(path, &ref, &err), MPM_OK);
  assert_int_equal(mesh.vertex_count, ref.vertex_count);
  assert_int_equal(mesh.triangle_count, ref.triangle_count);
  assert_memory_equal(mesh.vertices, ref.vertices, 3 * sizeof(double) * (size_t)ref.vertex_count);
  assert_memory_equal(mesh.triangles, ref.triangles, 3 * sizeof(int) * (size_t)ref.triangle_count);
  mpm_mesh_free(&mesh);
  mpm_mesh_free(&ref);

  /* messages name path_for_messages, or "<mesh>" */
  const char bad[] = "v 0 0 0\nf 1 1 9\n";
  assert_int_equal(mpm_mesh_parse(bad, sizeof bad - 1, MPM_MESH_OBJ, "mem.obj", &mesh, &err),
                   MPM_ERR_PARSE);
  assert_contains(err.message, "mem.obj:2: face index 9 out of range (1..1)");
  assert_null(mesh.vertices);
  assert_int_equal(mpm_mesh_parse(bad, sizeof bad - 1, MPM_MESH_OBJ, NULL, &mesh, &err),
                   MPM_ERR_PARSE);
  assert_contains(err.message, "<mesh>:2:");
  assert_int_equal(mpm_mesh_parse("", 0, MPM_MESH_PLY, "mem.ply", &mesh, &err), MPM_ERR_PARSE);
  assert_contains(err.message, "mem.ply:0: header ends without 'end_header'");

  /* found by fuzz_obj: a NUL byte made the parsing pass see more vertices than the counting
     pass had allocated for (a heap overflow); OBJ is text, so a NUL is refused */
  const char nul[] = "v 0 0 0\n\0v 1 0 0\n\0v 0 1 0\n\0v 0 0 1\n\0v 1 1 1\nf 1 2 3\n";
  assert_int_equal(mpm_mesh_parse(nul, sizeof nul - 1, MPM_MESH_OBJ, "nul.obj", &mesh, &err),
                   MPM_ERR_PARSE);
  assert_contains(err.message, "nul.obj:2: expected OBJ text, got a NUL byte");
  assert_null(mesh.vertices);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_counts_mass_alignment),
      cmocka_unit_test(test_box_unaligned_volume),
      cmocka_unit_test(test_sphere_volume_inside),
      cmocka_unit_test(test_cylinder_tilted_axis),
      cmocka_unit_test(test_jitter_bounds_and_determinism),
      cmocka_unit_test(test_angular_velocity),
      cmocka_unit_test(test_sampling_errors),
      cmocka_unit_test(test_cube_obj_and_ply),
      cmocka_unit_test(test_open_cube_falls_back_to_winding_number),
      cmocka_unit_test(test_mesh_shells),
      cmocka_unit_test(test_torus_inside),
      cmocka_unit_test(test_bunny),
      cmocka_unit_test(test_malformed_files),
      cmocka_unit_test(test_parse_from_memory),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
