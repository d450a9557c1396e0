/* test_surface.c - particle surfaces (src/surface, issue 14) against independent truths: the
 * surface of a sampled sphere lies within half a voxel of the analytic sphere, is closed and
 * consistently oriented (every edge shared by exactly two triangles, once each way), and
 * encloses (divergence theorem) the sphere's volume; the .vdb written reads back with its name,
 * class, voxel size and signs; output.surface's mistakes name their key path; a short run with
 * output.surface writes the files of every frame. */
#include "support.h"
#include "scene_json_support.h"
#include "scene/mesh.h"
#include "sim/sim.h"
#include "surface/surface.h"

#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#define PI 3.14159265358979323846

/* The particles of a sphere (centre c, radius R) on a lattice of spacing s, each of volume
 * s^3, as a body sampled at 8 particles per cell would hold them (cell = 2 s). */
static size_t sphere_particles(const double c[3], double R, double s, double **xyz, double **vol) {
  const int m = (int)ceil(R / s) + 1;
  const size_t cap = (size_t)(2 * m) * (size_t)(2 * m) * (size_t)(2 * m);
  *xyz = malloc(3 * cap * sizeof **xyz);
  *vol = malloc(cap * sizeof **vol);
  assert_non_null(*xyz);
  assert_non_null(*vol);
  size_t n = 0;
  for (int i = -m; i < m; ++i)
    for (int j = -m; j < m; ++j)
      for (int k = -m; k < m; ++k) {
        const double p[3] = {(i + 0.5) * s, (j + 0.5) * s, (k + 0.5) * s};
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] >= R * R) continue;
        for (int d = 0; d < 3; ++d) (*xyz)[3 * n + (size_t)d] = c[d] + p[d];
        (*vol)[n++] = s * s * s;
      }
  return n;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Every directed edge once and its reverse once: closed, manifold along edges, consistently
 * oriented. Returns the number of directed edges that break this. */
static long bad_edges(const mpm_surface_mesh *m) {
  const size_t e = 3 * m->triangle_count;
  uint64_t *key = malloc((e + 1) * sizeof *key);
  assert_non_null(key);
  for (size_t t = 0; t < m->triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = m->triangles[3 * t + (size_t)k],
                     b = m->triangles[3 * t + (size_t)(k + 1) % 3];
      key[3 * t + (size_t)k] = a << 32 | b;
    }
  qsort(key, e, sizeof *key, cmp_u64);
  long bad = 0;
  for (size_t i = 0; i < e; ++i) {
    if (i + 1 < e && key[i + 1] == key[i]) ++bad; /* a directed edge twice */
    const uint64_t rev = (key[i] & 0xffffffffu) << 32 | key[i] >> 32;
    if (!bsearch(&rev, key, e, sizeof *key, cmp_u64)) ++bad; /* no neighbour across it */
  }
  free(key);
  return bad;
}

/* Enclosed volume by the divergence theorem: sum over triangles of a . (b x c) / 6. */
static double mesh_volume(const mpm_surface_mesh *m) {
  double v = 0;
  for (size_t t = 0; t < m->triangle_count; ++t) {
    const float *a = m->vertices + 3 * m->triangles[3 * t],
                *b = m->vertices + 3 * m->triangles[3 * t + 1],
                *c = m->vertices + 3 * m->triangles[3 * t + 2];
    v += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
          (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
          (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) /
         6;
  }
  return v;
}

static void check_sphere(const double c[3], double R, double s, int smoothing) {
  double *xyz, *vol;
  const size_t n = sphere_particles(c, R, s, &xyz, &vol);
  mpm_surface_params p = mpm_surface_params_default();
  p.smoothing = smoothing;
  mpm_surface_mesh mesh;
  mpm_surface_figures fig;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_surface_build(xyz, vol, n, &p, &mesh, NULL, &fig, &err) != MPM_OK)
    fail_msg("%s", err.message);
  assert_close(fig.voxel, s, 1e-12); /* the default voxel: the particle spacing */
  assert_true(mesh.triangle_count > 1000);
  double mean = 0, max = 0;
  for (size_t i = 0; i < mesh.vertex_count; ++i) {
    double r2 = 0;
    for (int d = 0; d < 3; ++d) {
      const double x = (double)mesh.vertices[3 * i + (size_t)d] - c[d];
      r2 += x * x;
    }
    const double dist = fabs(sqrt(r2) - R);
    mean += dist;
    max = fmax(max, dist);
  }
  mean /= (double)mesh.vertex_count;
  const double v = mesh_volume(&mesh), v_true = 4.0 / 3.0 * PI * R * R * R;
  const double v_particles = (double)n * s * s * s;
  printf("sphere R/s = %g, %d passes: %zu particles, %zu triangles, distance mean %.3f max %.3f "
         "voxels, volume %+.2f%% (particles %+.2f%%)\n",
         R / s, smoothing, n, mesh.triangle_count, mean / fig.voxel, max / fig.voxel,
         100 * (v / v_true - 1), 100 * (v_particles / v_true - 1));
  assert_true(mean < 0.5 * fig.voxel);
  assert_true(max < 0.5 * fig.voxel);
  assert_int_equal(bad_edges(&mesh), 0);
  assert_true(v > 0); /* outward normals */
  assert_true(fabs(v / v_true - 1) < 0.03);
  mpm_surface_mesh_free(&mesh);
  free(xyz);
  free(vol);
}

static void test_sphere_surface(void **state) {
  (void)state;
  /* R = 15 and 20 particle spacings, the lattice at different offsets to the voxels */
  const double c1[3] = {0.31, 0.52, 0.47}, c2[3] = {0.5, 0.5, 0.5}, c3[3] = {0.137, 0.271, 0.05};
  check_sphere(c1, 0.3, 0.02, 1);
  check_sphere(c2, 0.3, 0.02, 1);
  check_sphere(c3, 0.4, 0.02, 2);
}

/* The height of a flat face: at r = s/2 the spheres of the top layer just touch; within the
 * disc of radius r about a particle the surface is its cap, outside it (the corners of the
 * particle's square) nothing reaches above -r (the union's value there is taken as -r, the
 * centre plane less r). The mean over the unit square is then the hemisphere's volume
 * 2 pi r^3 / 3 = pi / 12 less r times the corners' area 1 - pi / 4. */
static void test_face_height(void **state) {
  (void)state;
  const double r = 0.5;
  assert_close(mpm_surface_face_height(r, 1), PI / 12 - r * (1 - PI / 4), 2e-3);
  /* a face of spheres of radius s: between r - (s - sqrt(s^2 - s^2/2)) and r; and it scales */
  const double h = mpm_surface_face_height(1.0, 1);
  assert_true(h > sqrt(0.5) && h < 1);
  assert_close(mpm_surface_face_height(0.02, 0.02), 0.02 * h, 1e-12);
}

static int dir_has_temp(const char *dir) {
  DIR *d = opendir(dir);
  int temp = 0;
  for (struct dirent *e; d && (e = readdir(d));) temp |= strstr(e->d_name, ".tmp.") != NULL;
  if (d) closedir(d);
  return temp;
}

static void test_vdb_round_trip(void **state) {
  (void)state;
  const double c[3] = {0.5, 0.5, 0.5}, R = 0.2, s = 0.02;
  double *xyz, *vol;
  const size_t n = sphere_particles(c, R, s, &xyz, &vol);
  mpm_surface_params p = mpm_surface_params_default();
  mpm_surface_mesh mesh;
  mpm_vdb_grid *grid = NULL;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_surface_build(xyz, vol, n, &p, &mesh, &grid, NULL, &err) != MPM_OK)
    fail_msg("%s", err.message);
  assert_non_null(grid);
  const char *dir = test_temp_dir("surface-vdb");
  char path[600];
  snprintf(path, sizeof path, "%s/levelset_0003.vdb", dir);
  assert_int_equal(mpm_surface_write_vdb(path, grid, 1, NULL, &err), MPM_OK);
  mpm_vdb_grid_destroy(grid);
  assert_false(dir_has_temp(dir));
  mpm_vdb_grid *back = NULL;
  char msg[600];
  if (mpm_vdb_read(path, "surface", &back, msg, sizeof msg) != MPM_VDB_OK) fail_msg("%s", msg);
  char name[64];
  mpm_vdb_class cls;
  double voxel;
  mpm_vdb_grid_info(back, name, sizeof name, &cls, &voxel);
  assert_string_equal(name, "surface");
  assert_int_equal(cls, MPM_VDB_CLASS_LEVEL_SET);
  assert_close(voxel, s, 1e-9);
  const double inside[3] = {c[0] + 0.5 * R, c[1], c[2]};
  const double near_in[3] = {c[0], c[1] + R - 2 * s, c[2]};
  const double near_out[3] = {c[0], c[1], c[2] - R - 2 * s};
  const double outside[3] = {c[0] + 3 * R, c[1], c[2]};
  assert_true(mpm_vdb_sample(back, c) < 0);
  assert_true(mpm_vdb_sample(back, inside) < 0);
  /* near the surface the value is the signed distance to it (R - 2 s from the centre: 2 s
     inside; within a voxel of reconstruction error) */
  assert_close(mpm_vdb_sample(back, near_in), -2 * s, s);
  assert_close(mpm_vdb_sample(back, near_out), 2 * s, s);
  assert_true(mpm_vdb_sample(back, outside) > 0);
  mpm_vdb_grid_destroy(back);
  /* the density grid beside it: a fog volume, 0 outside and positive inside */
  if (mpm_vdb_read(path, "density", &back, msg, sizeof msg) != MPM_VDB_OK) fail_msg("%s", msg);
  mpm_vdb_grid_info(back, name, sizeof name, &cls, &voxel);
  assert_int_equal(cls, MPM_VDB_CLASS_FOG_VOLUME);
  assert_true(mpm_vdb_sample(back, c) > 0.99);
  assert_true(mpm_vdb_sample(back, outside) == 0);
  mpm_vdb_grid_destroy(back);
  /* a grid the file does not have: named, with those it has */
  assert_int_equal(mpm_vdb_read(path, "velocity", &back, msg, sizeof msg), MPM_VDB_FAIL);
  assert_null(back);
  assert_non_null(strstr(msg, "velocity"));
  if (!strstr(msg, "surface") || !strstr(msg, "density")) fail_msg("%s", msg);
  mpm_surface_mesh_free(&mesh);
  free(xyz);
  free(vol);
}

/* The velocity grid of a spinning, drifting sphere: v = u + w x (x - c) is linear, and on the
 * particles' lattice (spacing = voxel, particles at cell centres) each interior voxel averages
 * eight particles placed symmetrically about it, so the mass-weighted trilinear P2G gives the
 * field exactly there, and trilinear sampling between voxels keeps it exact. Read back from the
 * .vdb: name "vel", the field inside to float round-off, zero far outside. */
static void test_vdb_velocity(void **state) {
  (void)state;
  const double c[3] = {0.5, 0.5, 0.5}, R = 0.2, s = 0.02;
  const double u[3] = {1, -2, 0.5}, w[3] = {0.3, 2, -1};
  double *xyz, *vol;
  const size_t n = sphere_particles(c, R, s, &xyz, &vol);
  double *vel = malloc(3 * n * sizeof *vel), *mass = malloc(n * sizeof *mass);
  assert_non_null(vel);
  assert_non_null(mass);
  for (size_t i = 0; i < n; ++i) {
    const double r[3] = {xyz[3 * i] - c[0], xyz[3 * i + 1] - c[1], xyz[3 * i + 2] - c[2]};
    vel[3 * i] = u[0] + w[1] * r[2] - w[2] * r[1];
    vel[3 * i + 1] = u[1] + w[2] * r[0] - w[0] * r[2];
    vel[3 * i + 2] = u[2] + w[0] * r[1] - w[1] * r[0];
    mass[i] = 1000 * vol[i];
  }
  mpm_surface_params p = mpm_surface_params_default();
  p.voxel = s;
  mpm_surface_mesh mesh;
  mpm_vdb_grid *grid = NULL;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_surface_build(xyz, vol, n, &p, &mesh, &grid, NULL, &err) != MPM_OK)
    fail_msg("%s", err.message);
  mpm_vdb_vector_grid *v = NULL;
  char msg[600];
  if (mpm_vdb_velocity_from_particles(xyz, vel, mass, n, s, &v, msg, sizeof msg) != MPM_VDB_OK)
    fail_msg("%s", msg);
  const char *dir = test_temp_dir("surface-vdb-velocity");
  char path[600];
  snprintf(path, sizeof path, "%s/levelset_0000.vdb", dir);
  assert_int_equal(mpm_surface_write_vdb(path, grid, 0, v, &err), MPM_OK);
  mpm_vdb_vector_grid_destroy(v);
  mpm_vdb_grid_destroy(grid);
  mpm_vdb_vector_grid *back = NULL;
  if (mpm_vdb_read_vector(path, "vel", &back, msg, sizeof msg) != MPM_VDB_OK) fail_msg("%s", msg);
  char name[64];
  mpm_vdb_vector_name(back, name, sizeof name);
  assert_string_equal(name, "vel");
  /* every voxel within one voxel of a particle: at least the particles' count */
  assert_true(mpm_vdb_vector_active_voxels(back) >= n);
  double worst = 0;
  int checked = 0;
  for (int k = 0; k < 200; ++k) { /* points spread through the ball of radius R - 2 s */
    const double a = 2.39996 * k, z = 1 - 2 * (k + 0.5) / 200, rho = sqrt(1 - z * z);
    const double rad = (R - 2 * s) * cbrt((k % 10 + 0.5) / 10);
    const double r[3] = {rad * rho * cos(a), rad * rho * sin(a), rad * z};
    const double x[3] = {c[0] + r[0], c[1] + r[1], c[2] + r[2]};
    const double want[3] = {u[0] + w[1] * r[2] - w[2] * r[1], u[1] + w[2] * r[0] - w[0] * r[2],
                            u[2] + w[0] * r[1] - w[1] * r[0]};
    double got[3];
    mpm_vdb_vector_sample(back, x, got);
    for (int d = 0; d < 3; ++d) worst = fmax(worst, fabs(got[d] - want[d]));
    ++checked;
  }
  print_message("velocity grid: %d points inside, worst error %.2e m/s\n", checked, worst);
  assert_true(worst < 1e-5); /* |v| ~ 2 m/s in float */
  const double far[3] = {c[0] + 2 * R, c[1], c[2]};
  double got[3];
  mpm_vdb_vector_sample(back, far, got);
  assert_true(got[0] == 0 && got[1] == 0 && got[2] == 0);
  mpm_vdb_vector_grid_destroy(back);
  /* the level set is not a vector grid: the type is named */
  assert_int_equal(mpm_vdb_read_vector(path, "surface", &back, msg, sizeof msg), MPM_VDB_FAIL);
  if (!strstr(msg, "surface") || !strstr(msg, "vector")) fail_msg("%s", msg);
  mpm_surface_mesh_free(&mesh);
  free(xyz);
  free(vol);
  free(vel);
  free(mass);
}

static void test_surface_keys(void **state) {
  (void)state;
  expect_error(SCENE_WITH(", 'output': {'surface': {'voxle': 1}}"), MPM_ERR_INVALID,
               "output.surface", "voxle", "voxel", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'smoothing': 'two'}}"), MPM_ERR_INVALID,
               "output.surface.smoothing", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'smoothing': 50}}"), MPM_ERR_INVALID,
               "output.surface.smoothing", "[0, 20]", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'voxel': -1}}"), MPM_ERR_INVALID,
               "output.surface.voxel", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'bodies': ['jelly']}}"), MPM_ERR_INVALID,
               "output.surface.bodies[0]", "jelly", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'bodies': [3]}}"), MPM_ERR_INVALID,
               "output.surface.bodies[0]", "index", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'bodies': 'some'}}"), MPM_ERR_INVALID,
               "output.surface.bodies", "all", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'materials': ['steel', 'steel']}}"),
               MPM_ERR_INVALID, "output.surface.materials[1]", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': {'filter': 'median'}}"), MPM_ERR_INVALID,
               "output.surface.filter", "gaussian", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': 3}"), MPM_ERR_INVALID, "output.surface", NULL);
  expect_error(SCENE_WITH(", 'output': {'vdb': true}"), MPM_ERR_INVALID, "output.vdb",
               "output.surface", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': true, 'vdb': 1}"), MPM_ERR_INVALID, "output.vdb",
               NULL);
  expect_error(SCENE_WITH(", 'output': {'vdb_velocity': true}"), MPM_ERR_INVALID,
               "output.vdb_velocity", "output.surface", NULL);
  expect_error(SCENE_WITH(", 'output': {'surface': true, 'vdb_velocity': 'yes'}"), MPM_ERR_INVALID,
               "output.vdb_velocity", NULL);
  /* and the valid forms */
  mpm_scene s;
  parse_ok(SCENE_WITH(", 'output': {'surface': {'materials': ['jello'], 'voxel': 0.25, "
                      "'radius': 0.3, 'smoothing': 2, 'filter': 'gaussian'}, 'vdb': true}"),
           &s);
  assert_true(s.output.surface.enabled && s.output.vdb);
  assert_int_equal(s.output.surface.material_count, 1);
  assert_int_equal(s.output.surface.materials[0], 0);
  assert_close(s.output.surface.voxel, 0.25, 0);
  assert_close(s.output.surface.radius, 0.3, 0);
  assert_int_equal(s.output.surface.smoothing, 2);
  assert_int_equal(s.output.surface.filter, MPM_SURFACE_GAUSSIAN);
  mpm_scene_free(&s);
  parse_ok(SCENE_WITH(", 'output': {'surface': true}"), &s);
  assert_true(s.output.surface.enabled && !s.output.vdb && !s.output.vdb_velocity);
  assert_int_equal(s.output.surface.smoothing, 1);
  assert_int_equal(s.output.surface.filter, MPM_SURFACE_MEAN_CURVATURE);
  mpm_scene_free(&s);
  /* the velocity grid asks for the .vdb it goes into */
  parse_ok(SCENE_WITH(", 'output': {'surface': true, 'vdb_velocity': true}"), &s);
  assert_true(s.output.vdb && s.output.vdb_velocity && !s.output.vdb_density);
  mpm_scene_free(&s);
}

static int has_file(const char *dir, const char *name) {
  char path[700];
  struct stat sb;
  snprintf(path, sizeof path, "%s/%s", dir, name);
  return stat(path, &sb) == 0 && sb.st_size > 0;
}

/* Two boxes, one surface each (per_body): frames 0 and 1 have their OBJ, PLY and VDB files, and
 * the PLY read back by the mesh loader is closed and spans its box. */
static void test_run_writes_surfaces(void **state) {
  (void)state;
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"gravity\": [0,0,0],"
      " \"time\": {\"end\": 0.02, \"fps\": 50},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3, "
      "\"density\": 1000}],"
      " \"bodies\": [{\"name\": \"a\", \"shape\": {\"type\": \"box\", \"center\": [0.3,0.5,0.5], "
      "\"half_extent\": [0.1,0.1,0.1]}, \"material\": \"m\", \"velocity\": [0.5, 0, 0]},"
      " {\"name\": \"b\", \"shape\": {\"type\": \"sphere\", \"center\": [0.7,0.5,0.5], "
      "\"radius\": 0.12}, \"material\": \"m\"}],"
      " \"output\": {\"surface\": {\"bodies\": \"all\", \"per_body\": true}, \"vdb_velocity\": "
      "true}}",
      "surface run");
  const char *dir = test_temp_dir("surface-run");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  assert_int_equal(mpm_sim_frame_count(sim), 1);
  assert_true(sim->out.surface_triangles > 0);
  mpm_sim_destroy(sim);
  const char *names[] = {"surface_b0_0000.obj", "surface_b0_0000.ply", "levelset_b0_0000.vdb",
                         "surface_b1_0001.obj", "surface_b1_0001.ply", "levelset_b1_0001.vdb"};
  for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k)
    if (!has_file(dir, names[k])) fail_msg("%s/%s was not written", dir, names[k]);
  assert_false(has_file(dir, "surface_0000.obj")); /* per body: no combined file */
  /* the drifting box's level set file holds its velocity, the resting sphere's zero */
  for (int b = 0; b < 2; ++b) {
    char vdb[700], msg[600];
    snprintf(vdb, sizeof vdb, "%s/levelset_b%d_0000.vdb", dir, b);
    mpm_vdb_vector_grid *v = NULL;
    if (mpm_vdb_read_vector(vdb, "vel", &v, msg, sizeof msg) != MPM_VDB_OK) fail_msg("%s", msg);
    const double centre[3] = {b ? 0.7 : 0.3, 0.5, 0.5};
    double got[3];
    mpm_vdb_vector_sample(v, centre, got);
    assert_close(got[0], b ? 0 : 0.5, 1e-6);
    assert_close(got[1], 0, 1e-6);
    assert_close(got[2], 0, 1e-6);
    mpm_vdb_vector_grid_destroy(v);
  }
  assert_false(dir_has_temp(dir));
  char path[700];
  snprintf(path, sizeof path, "%s/surface_b0_0000.ply", dir);
  mpm_mesh mesh;
  mpm_error err;
  mpm_error_clear(&err);
  if (mpm_mesh_load(path, &mesh, &err) != MPM_OK) fail_msg("%s", err.message);
  assert_int_equal(mpm_mesh_boundary_edges(&mesh), 0);
  double lo[3], hi[3];
  mpm_mesh_bounds(&mesh, lo, hi);
  const double box_lo[3] = {0.2, 0.4, 0.4}, box_hi[3] = {0.4, 0.6, 0.6};
  for (int d = 0; d < 3; ++d) { /* the box's faces, within a particle spacing (dx / 2) */
    assert_close(lo[d], box_lo[d], 0.025);
    assert_close(hi[d], box_hi[d], 0.025);
  }
  mpm_mesh_free(&mesh);
}

static char printed[65536]; /* what the last mpm command printed */

/* Run the mpm program (MPM_BIN) with args, stderr merged into `printed`; its exit code. */
static int mpm(const char *args) {
  const char *bin = test_mpm_bin();
  if (!bin) fail_msg("MPM_BIN is not set (run through ctest)");
  char cmd[3000];
  snprintf(cmd, sizeof cmd, "'%s' %s 2>&1", bin, args);
  FILE *f = popen(cmd, "r");
  assert_non_null(f);
  const size_t n = fread(printed, 1, sizeof printed - 1, f);
  printed[n] = 0;
  const int status = pclose(f);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static void expect_output(const char *needle) {
  if (!strstr(printed, needle)) fail_msg("expected '%s' in the output:\n%s", needle, printed);
}

/* `mpm run` with output.surface: the files of every frame and the progress line's surface
 * figures; a folder holding only a level set of another run is refused, and --overwrite removes
 * it; `mpm render` draws the surface in place of the particles. */
static void test_cli_surfaces(void **state) {
  (void)state;
  const char *tmp = test_temp_dir("surface-cli");
  char scene[600], out[600], other[600], args[2400], path[700];
  snprintf(scene, sizeof scene, "%s/goo.json", tmp);
  snprintf(out, sizeof out, "%s/out", tmp);
  snprintf(other, sizeof other, "%s/other", tmp);
  write_file(scene, q("{'domain': {'min': [0,0,0], 'max': [1,1,1], 'dx': 0.05},"
                      " 'time': {'end': 0.04, 'fps': 50},"
                      " 'materials': [{'name': 'goo', 'model': 'neo_hookean', 'E': 1e4, 'nu': 0.3,"
                      " 'density': 1000}],"
                      " 'bodies': [{'name': 'ball', 'shape': {'type': 'sphere', 'center': "
                      "[0.5,0.4,0.5], 'radius': 0.15}, 'material': 'goo'}],"
                      " 'output': {'surface': {'bodies': ['ball']}, 'vdb': true}}"));
  snprintf(args, sizeof args, "run '%s' -o '%s'", scene, out);
  assert_int_equal(mpm(args), 0);
  expect_output("surface ");
  expect_output("triangles)");
  expect_output("mpm: surfaces: "); /* the closing note's share */
  expect_output("s per frame (3 frames)");
  for (int f = 0; f <= 2; ++f) {
    const char *kinds[] = {"surface_%04d.obj", "surface_%04d.ply", "levelset_%04d.vdb"};
    for (int k = 0; k < 3; ++k) {
      char name[64];
      snprintf(name, sizeof name, kinds[k], f);
      if (!has_file(out, name)) fail_msg("%s/%s was not written", out, name);
    }
  }
  snprintf(args, sizeof args, "render '%s' --size 160x90", out);
  assert_int_equal(mpm(args), 0);
  expect_output("0 particles, 1 surface");
  /* an output folder holding a level set of another run */
  assert_int_equal(mkdir(other, 0777), 0);
  snprintf(path, sizeof path, "%s/levelset_0007.vdb", other);
  write_file(path, "not a vdb");
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet", scene, other);
  assert_int_equal(mpm(args), 2);
  expect_output("levelset_0007.vdb");
  snprintf(args, sizeof args, "run '%s' -o '%s' --quiet --overwrite", scene, other);
  assert_int_equal(mpm(args), 0);
  assert_false(has_file(other, "levelset_0007.vdb"));
  assert_true(has_file(other, "levelset_0002.vdb"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sphere_surface), cmocka_unit_test(test_face_height),
      cmocka_unit_test(test_vdb_round_trip), cmocka_unit_test(test_vdb_velocity),
      cmocka_unit_test(test_surface_keys),   cmocka_unit_test(test_run_writes_surfaces),
      cmocka_unit_test(test_cli_surfaces),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
