/* test_outputs.c - what the per-frame output files report (issue 17, "outputs people
 * expect"): the step columns of stats.csv (dt is the frame's typical step, not its last one,
 * which is cut short to land on the frame time; dt_min and dt_max its range), its energies
 * (gravitational and total: a body falling freely keeps the total), the PLY point fields
 * (pscale, material, body) and the run index run.pvd that names every file of a frame. */
#define _POSIX_C_SOURCE 200809L /* io_support.h lists directories */

#include "support.h"
#include "io_support.h"
#include "sim/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The column `name` of stats.csv's header, 0-based, or -1. */
static int stats_column(const char *header, const char *name) {
  const size_t n = strlen(name);
  int k = 0;
  for (const char *p = header;; ++k) {
    const char *end = p + strcspn(p, ",\n");
    if ((size_t)(end - p) == n && strncmp(p, name, n) == 0) return k;
    if (*end != ',') return -1;
    p = end + 1;
  }
}

/* Field `k` (0-based) of a CSV line, as a number. */
static double csv_field(const char *line, int k) {
  const char *p = line;
  for (int i = 0; i < k; ++i) {
    p = strchr(p, ',');
    assert_non_null(p);
    ++p;
  }
  return strtod(p, NULL);
}

/* ---- stats.csv: the frame's steps ------------------------------------------------------ */

/* The step is solver.max_dt (the CFL step of this soft block at rest is longer), and a frame
 * of 25 ms is 22.7 of them: 21 whole steps, then the loop halves the remaining 1.9 ms into two
 * of 0.95 ms so that the last one does not come out tiny. The frame's last step, which the
 * dt column used to show, is 0.95 ms; its typical one is max_dt. */
static void test_stats_dt_columns(void **state) {
  (void)state;
  const double max_dt = 1.1e-3, frame_dt = 0.025;
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.05}, \"gravity\": [0,0,0],"
      " \"time\": {\"end\": 0.1, \"fps\": 40}, \"solver\": {\"max_dt\": 1.1e-3},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, \"nu\": 0.3, "
      "\"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,0.5,0.5], \"half_extent\": "
      "[0.1,0.1,0.1]}, \"material\": \"m\"}]}",
      "dt columns");
  assert_true(mpm_sim_cfl_dt(sim) == max_dt); /* the premise: max_dt sets the step */
  const char *dir = test_temp_dir("outputs-dt");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  const int frames = mpm_sim_frame_count(sim);
  assert_int_equal(frames, 4);
  /* frame 0 had no steps */
  assert_true(sim->out.stats[0].dt == 0 && sim->out.stats[0].dt_min == 0 &&
              sim->out.stats[0].dt_max == 0);
  for (int f = 1; f <= frames; ++f) {
    const mpm_stats_row *r = &sim->out.stats[f];
    assert_int_equal(r->steps - sim->out.stats[f - 1].steps, 23);
    assert_close(r->dt, max_dt, 1e-12);
    assert_close(r->dt_max, max_dt, 1e-12);
    assert_close(r->dt_min, 0.5 * (frame_dt - 21 * max_dt), 1e-12);
    assert_true(r->dt_min < r->dt && r->dt <= r->dt_max);
    /* the mean of all the frame's steps would be 1.087 ms: the typical step is not that */
    assert_true(r->dt > frame_dt / 23 * (1 + 1e-3));
  }
  /* the file: the same figures under their names, dt where it always was (4th column) */
  char path[700], header[1024], line[1024];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  FILE *fp = fopen(path, "r");
  assert_non_null(fp);
  assert_non_null(fgets(header, sizeof header, fp));
  const int c_dt = stats_column(header, "dt"), c_min = stats_column(header, "dt_min"),
            c_max = stats_column(header, "dt_max");
  assert_int_equal(c_dt, 3);
  assert_int_equal(stats_column(header, "enriched_percent"), 20);
  assert_true(c_min > 20 && c_max > 20);
  for (int f = 0; f <= frames; ++f) {
    assert_non_null(fgets(line, sizeof line, fp));
    const mpm_stats_row *r = &sim->out.stats[f];
    assert_close(csv_field(line, c_dt), r->dt, 1e-8 * max_dt);
    assert_close(csv_field(line, c_min), r->dt_min, 1e-8 * max_dt);
    assert_close(csv_field(line, c_max), r->dt_max, 1e-8 * max_dt);
  }
  fclose(fp);
  mpm_sim_destroy(sim);
}

/* The CFL step of a falling body shrinks as it gathers speed: the typical step lies in the
 * frame's range, and a frame that does not hold a whole number of steps shows its shortened
 * step as the minimum. */
static void test_stats_dt_range_cfl(void **state) {
  (void)state;
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,2,1], \"dx\": 0.05}, \"gravity\": [0,-9.81,0],"
      " \"time\": {\"end\": 0.2, \"fps\": 30},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3, "
      "\"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,1.6,0.5], \"half_extent\": "
      "[0.1,0.1,0.1]}, \"material\": \"m\"}]}",
      "dt range");
  const double dt0 = mpm_sim_cfl_dt(sim);
  const char *dir = test_temp_dir("outputs-dt-cfl");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  int shortened = 0;
  for (int f = 1; f <= mpm_sim_frame_count(sim); ++f) {
    const mpm_stats_row *r = &sim->out.stats[f];
    assert_true(r->dt_min > 0 && r->dt_min <= r->dt && r->dt <= r->dt_max);
    assert_true(r->dt_max <= dt0 * (1 + 1e-12)); /* faster particles only shorten it */
    if (r->dt_min < 0.9 * r->dt) ++shortened;
  }
  print_message("CFL step at rest %.6g s; frame 1: typical %.6g, %.6g..%.6g s\n", dt0,
                sim->out.stats[1].dt, sim->out.stats[1].dt_min, sim->out.stats[1].dt_max);
  assert_true(shortened > 0);
  assert_close(sim->out.stats[1].dt, dt0,
               2e-2 * dt0); /* the step of the first frame, barely moving */
  mpm_sim_destroy(sim);
}

/* ---- stats.csv: energies ---------------------------------------------------------------- */

/* A block falling freely (nothing in its way during the run, no particle domains) trades
 * gravitational for kinetic energy: their sum with the elastic energy stays constant. The
 * steps are symplectic Euler (v += g dt, then x += v dt), whose energy drifts by
 * -m |g|^2 dt / 2 per unit of time: a fraction dt / t of the kinetic energy gained by t
 * (max_dt keeps it under 1e-3 of the total here). */
static void test_stats_energy_free_fall(void **state) {
  (void)state;
  mpm_sim *sim = test_sim_from_json(
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,2,1], \"dx\": 0.05}, \"gravity\": [0,-9.81,0],"
      " \"time\": {\"end\": 0.3, \"fps\": 20}, \"solver\": {\"max_dt\": 2.5e-4},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3, "
      "\"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.5,1.6,0.5], \"half_extent\": "
      "[0.1,0.1,0.1]}, \"material\": \"m\"}]}",
      "free fall energy");
  const char *dir = test_temp_dir("outputs-energy");
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  const int frames = mpm_sim_frame_count(sim);
  const mpm_stats_row *s = sim->out.stats;
  /* the reference: zero at the origin, so the block starts at m g y0 */
  assert_close(s[0].gravitational, s[0].mass * 9.81 * 1.6, 1e-4 * s[0].mass * 9.81 * 1.6);
  assert_true(s[0].kinetic == 0);
  const double e0 = s[0].total_energy;
  for (int f = 1; f <= frames; ++f) {
    assert_true(s[f].kinetic > s[f - 1].kinetic);
    assert_true(s[f].gravitational < s[f - 1].gravitational);
    assert_close(s[f].total_energy, s[f].kinetic + s[f].elastic + s[f].gravitational,
                 1e-12 * fabs(e0));
    const double drift = fabs(s[f].total_energy - e0), gained = s[f].kinetic;
    const double bound = 0.5 * s[f].mass * 9.81 * 9.81 * s[f].time * s[f].dt_max;
    print_message("frame %d: kinetic %.6g J, total %.9g J, drift %.3g J (%.2g of kinetic; "
                  "symplectic Euler %.3g J)\n",
                  f, gained, s[f].total_energy, drift, drift / gained, bound);
    if (drift > 1.5 * bound + TOL(1e-6, 1e-10) * fabs(e0) || drift > 1e-3 * fabs(e0))
      fail_msg("frame %d: total energy %.9g J, %.3g J from the start's %.9g J (kinetic %.6g J)", f,
               s[f].total_energy, drift, e0, gained);
  }
  /* it did fall: the kinetic energy is that of v = g t, and the drift is a small part of it */
  const double t = s[frames].time, v = 9.81 * t;
  assert_true(fabs(s[frames].total_energy - e0) < 1e-2 * s[frames].kinetic);
  assert_close(s[frames].kinetic, 0.5 * s[frames].mass * v * v, 2e-2 * s[frames].kinetic);
  mpm_sim_destroy(sim);
}

/* ---- run.pvd ------------------------------------------------------------------------------ */

typedef struct pvd_entry {
  double time;
  int part;
  char name[64], file[128];
} pvd_entry;

/* The DataSets of a .pvd as this project writes it (one per line); returns their count. */
static int read_pvd(const char *path, pvd_entry *out, int max) {
  FILE *fp = fopen(path, "r");
  if (!fp) fail_msg("cannot open %s", path);
  char line[512];
  int n = 0;
  while (fgets(line, sizeof line, fp)) {
    const char *d = strstr(line, "<DataSet ");
    if (!d) continue;
    assert_true(n < max);
    pvd_entry *e = &out[n++];
    memset(e, 0, sizeof *e);
    const char *t = strstr(d, "timestep=\""), *p = strstr(d, "part=\""), *f = strstr(d, "file=\"");
    const char *nm = strstr(d, "name=\"");
    assert_non_null(t);
    assert_non_null(p);
    assert_non_null(f);
    e->time = strtod(t + 10, NULL);
    e->part = atoi(p + 6);
    if (nm) sscanf(nm + 6, "%63[^\"]", e->name);
    assert_int_equal(sscanf(f + 6, "%127[^\"]", e->file), 1);
  }
  fclose(fp);
  return n;
}

/* A mesh body with particle domains writes, per frame, its particles, its domains and its
 * embedded surface; run.pvd names all three for every frame (part 0, 1, 2, in that order),
 * each file exists and is VTK XML of the kind ParaView needs (UnstructuredGrid for the
 * particles and domains, PolyData for the surface); frames.pvd still lists the particle
 * frames alone. tests/vtk/check_output.py reads them with VTK's readers. */
static void test_run_pvd_names_every_file(void **state) {
  (void)state;
  const char *dir = test_temp_dir("outputs-run-pvd");
  char text[2048];
  snprintf(
      text, sizeof text,
      "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.04}, \"gravity\": [0,0,0],"
      " \"time\": {\"end\": 0.02, \"fps\": 100},"
      " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e4, "
      "\"nu\": 0.3, \"density\": 1000}],"
      " \"bodies\": [{\"shape\": {\"type\": \"mesh\", \"file\": \"%s/examples/meshes/torus.obj\","
      " \"center\": [0.5, 0.5, 0.5], \"scale\": 0.15}, \"material\": \"m\", \"domains\": true,"
      " \"velocity\": [0.5, 0, 0]}]}",
      MPM_SOURCE_DIR);
  mpm_sim *sim = test_sim_from_json(text, "torus.json");
  assert_int_equal(sim->surface_count, 1);
  assert_int_equal(mpm_sim_enable_output(sim, dir), MPM_OK);
  while (mpm_sim_frame(sim) < mpm_sim_frame_count(sim))
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
  const int frames = mpm_sim_frame_count(sim) + 1;
  assert_int_equal(frames, 3);
  char path[800];
  snprintf(path, sizeof path, "%s/run.pvd", dir);
  pvd_entry e[16];
  assert_int_equal(read_pvd(path, e, 16), 3 * frames);
  static const char *const part_name[3] = {"particles", "domains", "surface_body0"};
  static const char *const part_file[3] = {"frame_%04d.vtu", "domains_%04d.vtu",
                                           "surface_body0_%04d.vtp"};
  static const char *const part_type[3] = {"UnstructuredGrid", "UnstructuredGrid", "PolyData"};
  for (int f = 0; f < frames; ++f)
    for (int k = 0; k < 3; ++k) {
      const pvd_entry *d = &e[3 * f + k];
      char want[64];
      snprintf(want, sizeof want, part_file[k], f);
      assert_string_equal(d->file, want);
      assert_string_equal(d->name, part_name[k]);
      assert_int_equal(d->part, k);
      assert_close(d->time, sim->out.frame_times[f], 1e-8 * (1 + sim->out.frame_times[f]));
      snprintf(path, sizeof path, "%s/%s", dir, d->file);
      size_t len = 0;
      char *body = (char *)slurp(path, &len);
      if (!body) fail_msg("run.pvd names %s, which cannot be read", path);
      char type[64];
      snprintf(type, sizeof type, "<VTKFile type=\"%s\"", part_type[k]);
      if (!strstr(body, type)) fail_msg("%s is not a VTK %s file", path, part_type[k]);
      free(body);
    }
  /* the surface's points are the embedded surface's, as the OBJ has them */
  snprintf(path, sizeof path, "%s/surface_body0_0002.vtp", dir);
  size_t len = 0;
  char *vtp = (char *)slurp(path, &len);
  assert_non_null(vtp);
  char tag[128];
  snprintf(tag, sizeof tag, "NumberOfPoints=\"%d\"", sim->surfaces[0].vertex_count);
  assert_non_null(strstr(vtp, tag));
  snprintf(tag, sizeof tag, "NumberOfPolys=\"%d\"", sim->surfaces[0].triangle_count);
  assert_non_null(strstr(vtp, tag));
  free(vtp);
  /* frames.pvd: the particle frames only, as before */
  snprintf(path, sizeof path, "%s/frames.pvd", dir);
  const int n = read_pvd(path, e, 16);
  assert_int_equal(n, frames);
  for (int f = 0; f < n; ++f) assert_int_equal(e[f].part, 0);
  mpm_sim_destroy(sim);
}

/* A frame without a part (NULL) has no DataSet for it; names are escaped as XML attributes. */
static void test_pvd_parts(void **state) {
  (void)state;
  const char *dir = test_temp_dir("outputs-pvd-parts");
  char path[700];
  snprintf(path, sizeof path, "%s/run.pvd", dir);
  const double times[2] = {0, 0.5};
  const char *names[2] = {"a&b", "c"};
  const char *files[4] = {"f0.vtu", NULL, "f1.vtu", "g\"1.vtp"};
  mpm_error err = {0};
  assert_int_equal(mpm_write_pvd_parts(path, 2, 2, times, names, files, &err), MPM_OK);
  assert_file_text(path,
                   "<?xml version=\"1.0\"?>\n"
                   "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                   "  <Collection>\n"
                   "    <DataSet timestep=\"0\" group=\"\" part=\"0\" name=\"a&amp;b\" "
                   "file=\"f0.vtu\"/>\n"
                   "    <DataSet timestep=\"0.5\" group=\"\" part=\"0\" name=\"a&amp;b\" "
                   "file=\"f1.vtu\"/>\n"
                   "    <DataSet timestep=\"0.5\" group=\"\" part=\"1\" name=\"c\" "
                   "file=\"g&quot;1.vtp\"/>\n"
                   "  </Collection>\n</VTKFile>\n");
  assert_int_equal(mpm_write_pvd_parts(path, 1, 0, times, names, files, &err), MPM_ERR_INVALID);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_stats_dt_columns),
      cmocka_unit_test(test_stats_dt_range_cfl),
      cmocka_unit_test(test_stats_energy_free_fall),
      cmocka_unit_test(test_run_pvd_names_every_file),
      cmocka_unit_test(test_pvd_parts),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
