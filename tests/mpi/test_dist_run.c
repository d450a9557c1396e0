/* test_dist_run.c - a run on ranks through the public calls `mpm run` makes under mpirun
 * (mpm_sim_join_mpi_world, mpm_sim_open_output, mpm_sim_advance_frame, mpm_sim_ranks_agree),
 * its files against the same scene run by one process (rank 0, the default writer):
 *   - each frame's frame_NNNN.pvtu lists one piece per rank, frame_NNNN_pRRRR.vtu in rank order,
 *     with the pieces' arrays as its PPointData; every piece reads back; their particles add up
 *     to the scene's, and together (by id) they are the single process's frame, within 1e-6 of
 *     the body's extent (float32 files: a few units in the last place; on one rank the piece is
 *     the single process's file, byte for byte);
 *     frames.pvd and run.pvd name the .pvtu of every frame; a .ply piece per rank;
 *   - stats.csv, written once, holds the figures over every rank: the particles and the mass as
 *     one process has them, the energies and momenta within rounding;
 *   - no checkpoint is written (output.checkpoint_every ignored), and asking for one or a resume
 *     is refused on every rank, naming why;
 *   - a scene the ranks cannot run (implicit) is refused on every rank with the same message;
 *   - a folder holding a file of a run's name is refused on every rank, nothing in it touched;
 *     with MPM_OUTPUT_OVERWRITE the earlier run's files go, a user's other file stays;
 *   - a piece that cannot be written on the last rank stops every rank in the same frame, each
 *     with that rank's message. */
#define _XOPEN_SOURCE 700 /* nftw */
#include "io/io.h"
#include "mpi_check.h"

#include <ftw.h>
#include <math.h>
#include <mpm/plot.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *const scene =
    "{\"domain\": {\"min\": [0, 0, 0], \"max\": [1, 1, 1], \"dx\": 0.025},"
    " \"time\": {\"end\": 0.02, \"fps\": 100},"
    " \"output\": {\"vtu\": true, \"ply\": true, \"stats\": true, \"checkpoint_every\": 1},"
    " \"materials\": [{\"name\": \"m\", \"model\": \"neo_hookean\", \"E\": 1e5, \"nu\": 0.3,"
    "  \"density\": 1000}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.45, 0.2, 0.5],"
    "  \"half_extent\": [0.15, 0.1, 0.12]}, \"material\": \"m\","
    "  \"velocity\": [1.5, -0.5, 0.3], \"angular_velocity\": [0, 0, 4]}],"
    " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0, 0.08, 0],"
    "  \"normal\": [0, 1, 0]}, \"rule\": \"slip\"}]}";

enum { FRAMES = 2 };

static char root[256]; /* the test's folder, rank 0's name for all */

static void path_of(char *out, size_t cap, const char *dir, const char *name) {
  snprintf(out, cap, "%s/%s/%s", root, dir, name);
}

/* A simulation of json as this rank's part of the run, or of one process (join 0). */
static mpm_sim *made(const char *json, int join) {
  mpm_sim *sim = mpi_check_sim(json);
  if (join) CHECK(mpm_sim_join_mpi_world(sim) == MPM_OK, "join: %s", mpm_sim_last_error(sim));
  return sim;
}

/* Every frame of the scene into root/dir. */
static void run(mpm_sim *sim, const char *dir) {
  char out[512];
  snprintf(out, sizeof out, "%s/%s", root, dir);
  mpm_status st = mpm_sim_ranks_agree(sim, mpm_sim_open_output(sim, out, MPM_OUTPUT_NEW));
  CHECK(st == MPM_OK, "open %s: %s", out, mpm_sim_last_error(sim));
  while (st == MPM_OK && mpm_sim_frame(sim) < mpm_sim_frame_count(sim)) {
    st = mpm_sim_ranks_agree(sim, mpm_sim_advance_frame(sim));
    CHECK(st == MPM_OK, "frame %d: %s", mpm_sim_frame(sim), mpm_sim_last_error(sim));
  }
}

static char *slurp(const char *path, long *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  const long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *text = malloc((size_t)n + 1);
  const size_t got = fread(text, 1, (size_t)n, f);
  text[got] = '\0';
  fclose(f);
  if (len) *len = (long)got;
  return text;
}

static int exists(const char *path) {
  return access(path, F_OK) == 0;
}

/* One particle of a frame: its id and position. */
typedef struct point {
  double id, x[3];
} point;

static int by_id(const void *a, const void *b) {
  const double x = ((const point *)a)->id, y = ((const point *)b)->id;
  return x < y ? -1 : x > y;
}

/* Append the particles of a VTU file to *pts (count *n). 0 when it does not read. */
static int read_points(const char *path, point **pts, long *n, mpm_vtu_frame *keep) {
  mpm_vtu_frame f;
  mpm_error err;
  if (mpm_read_vtu(path, &f, &err) != MPM_OK) {
    CHECK(0, "%s", err.message);
    return 0;
  }
  const mpm_vtu_array *x = mpm_vtu_frame_array(&f, "Points"), *id = mpm_vtu_frame_array(&f, "id");
  CHECK(x && id, "%s: no Points or id", path);
  if (x && id) {
    *pts = realloc(*pts, (size_t)(*n + f.point_count + 1) * sizeof **pts);
    for (long i = 0; i < f.point_count; ++i) {
      point *p = &(*pts)[*n + i];
      p->id = id->data[i];
      for (int d = 0; d < 3; ++d) p->x[d] = x->data[3 * i + d];
    }
    *n += f.point_count;
  }
  if (keep)
    *keep = f;
  else
    mpm_vtu_frame_free(&f);
  return 1;
}

/* The .pvtu of frame k: one piece per rank in rank order, the pieces' point arrays declared. */
static void check_pvtu(int k, const mpm_vtu_frame *piece0) {
  char path[512], name[64];
  snprintf(name, sizeof name, "frame_%04d.pvtu", k);
  path_of(path, sizeof path, "ranks", name);
  char *text = slurp(path, NULL);
  CHECK(text != NULL, "%s missing", path);
  if (!text) return;
  CHECK(strstr(text, "<VTKFile type=\"PUnstructuredGrid\""), "%s: not a PUnstructuredGrid", path);
  int pieces = 0;
  for (const char *s = text; (s = strstr(s, "<Piece Source=\"")); ++s, ++pieces) {
    char want[64];
    snprintf(want, sizeof want, "<Piece Source=\"frame_%04d_p%04d.vtu\"/>", k, pieces);
    CHECK(!strncmp(s, want, strlen(want)), "%s: piece %d is not %s", path, pieces, want);
  }
  CHECK(pieces == size, "%s lists %d pieces on %d ranks", path, pieces, size);
  /* every point array of a piece is declared (PPointData), and no other */
  int declared = 0;
  for (const char *s = text; (s = strstr(s, "<PDataArray ")); ++s) ++declared;
  for (int a = 0; piece0 && a < piece0->array_count; ++a) {
    char want[96];
    snprintf(want, sizeof want, "Name=\"%s\"", piece0->arrays[a].name);
    CHECK(strstr(text, want), "%s does not declare the pieces' array %s", path, want);
  }
  if (piece0)
    CHECK(declared == piece0->array_count, "%s declares %d arrays, a piece has %d", path, declared,
          piece0->array_count);
  free(text);
}

/* Frame k of the ranks against one process's. */
static void check_frame(int k) {
  char path[512], name[64];
  point *one = NULL, *all = NULL;
  long n_one = 0, n_all = 0;
  snprintf(name, sizeof name, "frame_%04d.vtu", k);
  path_of(path, sizeof path, "one", name);
  read_points(path, &one, &n_one, NULL);
  mpm_vtu_frame piece0;
  memset(&piece0, 0, sizeof piece0);
  for (int r = 0; r < size; ++r) {
    snprintf(name, sizeof name, "frame_%04d_p%04d.vtu", k, r);
    path_of(path, sizeof path, "ranks", name);
    read_points(path, &all, &n_all, r == 0 ? &piece0 : NULL);
    snprintf(name, sizeof name, "frame_%04d_p%04d.ply", k, r);
    path_of(path, sizeof path, "ranks", name);
    CHECK(exists(path), "%s missing", path);
  }
  check_pvtu(k, &piece0);
  mpm_vtu_frame_free(&piece0);
  CHECK(n_all == n_one, "frame %d: the pieces hold %ld particles, one process %ld", k, n_all,
        n_one);
  if (n_all == n_one && n_one > 0) {
    qsort(one, (size_t)n_one, sizeof *one, by_id);
    qsort(all, (size_t)n_all, sizeof *all, by_id);
    double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30}, dx = 0;
    int ids = 1;
    for (long i = 0; i < n_one; ++i) {
      ids &= one[i].id == all[i].id;
      for (int d = 0; d < 3; ++d) {
        lo[d] = fmin(lo[d], one[i].x[d]);
        hi[d] = fmax(hi[d], one[i].x[d]);
        dx = fmax(dx, fabs(one[i].x[d] - all[i].x[d]));
      }
    }
    const double extent = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    CHECK(ids, "frame %d: the pieces' ids are not one process's", k);
    /* (the files hold float32: 1e-6 of this extent is a few units in the last place; a node's
       sums added in another order on the ranks move a particle by about one) */
    CHECK(dx <= 1e-6 * extent, "frame %d: a position differs by %.3g of the extent", k,
          dx / extent);
    printf("%d ranks, frame %d: %ld particles in %d pieces, largest difference from one process "
           "%.3g of the extent\n",
           size, k, n_all, size, dx / extent);
  }
  free(one);
  free(all);
  if (size == 1) { /* one rank writes one process's file */
    char a[512], b[512];
    long la = 0, lb = 0;
    snprintf(name, sizeof name, "frame_%04d.vtu", k);
    path_of(a, sizeof a, "one", name);
    snprintf(name, sizeof name, "frame_%04d_p0000.vtu", k);
    path_of(b, sizeof b, "ranks", name);
    char *ta = slurp(a, &la), *tb = slurp(b, &lb);
    CHECK(ta && tb && la == lb && !memcmp(ta, tb, (size_t)la), "one rank's piece differs from %s",
          a);
    free(ta);
    free(tb);
  }
}

static void check_indexes(void) {
  char path[512];
  for (int k = 0; k < 2; ++k) {
    path_of(path, sizeof path, "ranks", k ? "run.pvd" : "frames.pvd");
    char *text = slurp(path, NULL);
    CHECK(text != NULL, "%s missing", path);
    for (int f = 0; text && f <= FRAMES; ++f) {
      char want[64];
      snprintf(want, sizeof want, "file=\"frame_%04d.pvtu\"", f);
      CHECK(strstr(text, want), "%s does not name %s", path, want);
    }
    free(text);
  }
  path_of(path, sizeof path, "ranks", "frame_0001.vtu");
  CHECK(!exists(path), "a single process's frame file on ranks");
  char cmd[600];
  snprintf(cmd, sizeof cmd, "ls %s/ranks | grep -q '^checkpoint_'", root);
  CHECK(system(cmd) != 0, "a checkpoint was written on ranks");
}

static void check_stats(void) {
  char a[512], b[512], err[512];
  path_of(a, sizeof a, "one", "stats.csv");
  path_of(b, sizeof b, "ranks", "stats.csv");
  mpm_stats_table one, all;
  memset(&one, 0, sizeof one);
  memset(&all, 0, sizeof all);
  CHECK(mpm_stats_read(a, &one, err, sizeof err) == MPM_OK, "%s", err);
  CHECK(mpm_stats_read(b, &all, err, sizeof err) == MPM_OK, "%s", err);
  CHECK(all.rows == FRAMES + 1 && one.rows == all.rows, "stats.csv: %zu rows, one process %zu",
        all.rows, one.rows);
  for (size_t r = 0; r < all.rows && r < one.rows; ++r) {
    const double *x = all.values + r * (size_t)all.stride, *y = one.values + r * (size_t)one.stride;
    CHECK(x[MPM_STATS_PARTICLES] == y[MPM_STATS_PARTICLES], "row %zu: %g particles, one process %g",
          r, x[MPM_STATS_PARTICLES], y[MPM_STATS_PARTICLES]);
    CHECK(fabs(x[MPM_STATS_MASS] - y[MPM_STATS_MASS]) <= 1e-12 * y[MPM_STATS_MASS],
          "row %zu: mass %.17g, one process %.17g", r, x[MPM_STATS_MASS], y[MPM_STATS_MASS]);
    CHECK(x[MPM_STATS_STEPS] == y[MPM_STATS_STEPS], "row %zu: other steps", r);
    const double energy = fabs(y[MPM_STATS_KINETIC_ENERGY]) + fabs(y[MPM_STATS_ELASTIC_ENERGY]);
    for (int c = MPM_STATS_KINETIC_ENERGY; c <= MPM_STATS_ELASTIC_ENERGY; ++c)
      CHECK(fabs(x[c] - y[c]) <= 1e-5 * energy, "row %zu: %s %.9g, one process %.9g", r,
            mpm_stats_column_name(c), x[c], y[c]);
    const double p = sqrt(2 * y[MPM_STATS_MASS] * y[MPM_STATS_KINETIC_ENERGY]);
    for (int c = MPM_STATS_MOMENTUM_X; c <= MPM_STATS_MOMENTUM_Z; ++c)
      CHECK(fabs(x[c] - y[c]) <= 1e-5 * p, "row %zu: %s %.9g, one process %.9g", r,
            mpm_stats_column_name(c), x[c], y[c]);
    for (int c = 0; c < all.colliders * 3 && all.colliders == one.colliders; ++c) {
      const double fx = all.forces[r * (size_t)all.colliders * 3 + (size_t)c],
                   fy = one.forces[r * (size_t)one.colliders * 3 + (size_t)c];
      CHECK(fabs(fx - fy) <= 1e-4 * (fabs(fy) + 1e-9), "row %zu: collider force %.9g, one %.9g", r,
            fx, fy);
    }
  }
  mpm_stats_free(&one);
  mpm_stats_free(&all);
}

/* The same text on every rank (rank 0's compared). */
static int same_on_every_rank(const char *text) {
  char first[1024];
  snprintf(first, sizeof first, "%s", text);
  MPI_Bcast(first, sizeof first, MPI_CHAR, 0, MPI_COMM_WORLD);
  int same = !strcmp(first, text), all = 0;
  MPI_Allreduce(&same, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all;
}

static void test_refusals(void) {
  /* the implicit step: refused by the join, on every rank, alike */
  char json[4096];
  snprintf(json, sizeof json, "{\"solver\": {\"integrator\": \"implicit\"}, %s", scene + 1);
  mpm_sim *sim = mpi_check_sim(json);
  const mpm_status st = mpm_sim_join_mpi_world(sim);
  CHECK(st == MPM_ERR_INVALID, "implicit scene joined: %d", st);
  CHECK(strstr(mpm_sim_last_error(sim), "implicit"), "message: %s", mpm_sim_last_error(sim));
  CHECK(same_on_every_rank(mpm_sim_last_error(sim)), "the ranks' messages differ");
  mpm_sim_destroy(sim);

  /* checkpoints and resumes */
  sim = made(scene, 1);
  char out[512];
  snprintf(out, sizeof out, "%s/ranks", root);
  CHECK(mpm_sim_resume(sim, out, NULL, 0) == MPM_ERR_INVALID, "resume on ranks");
  CHECK(strstr(mpm_sim_last_error(sim), "checkpoints are not written on ranks"), "message: %s",
        mpm_sim_last_error(sim));
  CHECK(mpm_sim_write_checkpoint(sim, NULL, 0) == MPM_ERR_INVALID, "checkpoint on ranks");
  mpm_sim_destroy(sim);

  /* a folder with a file of a run's name that the user made: nothing touched */
  char dir[512], user[512], notes[512];
  snprintf(dir, sizeof dir, "%s/user", root);
  path_of(user, sizeof user, "user", "stats.csv");
  path_of(notes, sizeof notes, "user", "notes.txt");
  if (rank == 0) {
    mkdir(dir, 0755);
    FILE *f = fopen(user, "w");
    fputs("my own numbers\n", f);
    fclose(f);
    f = fopen(notes, "w");
    fputs("keep me\n", f);
    fclose(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  sim = made(scene, 1);
  mpm_status o = mpm_sim_ranks_agree(sim, mpm_sim_open_output(sim, dir, MPM_OUTPUT_NEW));
  CHECK(o == MPM_ERR_INVALID, "a folder with a run's file was taken: %d", o);
  CHECK(strstr(mpm_sim_last_error(sim), "stats.csv"), "message: %s", mpm_sim_last_error(sim));
  CHECK(same_on_every_rank(mpm_sim_last_error(sim)), "the ranks' messages differ");
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0) {
    char *text = slurp(user, NULL);
    CHECK(text && !strcmp(text, "my own numbers\n"), "the user's stats.csv changed");
    free(text);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "test $(ls -A %s | grep -v '^.mpm.lock$' | wc -l) -eq 2", dir);
    CHECK(system(cmd) == 0, "a file was added to %s", dir);
  }
  mpm_sim_destroy(sim);
  /* with MPM_OUTPUT_OVERWRITE the run's name goes, the user's notes stay */
  sim = made(scene, 1);
  o = mpm_sim_ranks_agree(sim, mpm_sim_open_output(sim, dir, MPM_OUTPUT_OVERWRITE));
  CHECK(o == MPM_OK, "overwrite: %s", mpm_sim_last_error(sim));
  mpm_sim_destroy(sim);
  if (rank == 0) {
    char *text = slurp(notes, NULL);
    CHECK(text && !strcmp(text, "keep me\n"), "the user's notes.txt was touched");
    free(text);
    char piece[512];
    path_of(piece, sizeof piece, "user", "frame_0000.pvtu");
    CHECK(exists(piece), "no frame 0 after the overwrite");
  }
}

/* A piece the last rank cannot write (a folder stands at its name) stops every rank. */
static void test_failed_piece(void) {
  mpm_sim *sim = made(scene, 1);
  char out[512], piece[512], name[64];
  snprintf(out, sizeof out, "%s/failing", root);
  mpm_status st = mpm_sim_ranks_agree(sim, mpm_sim_open_output(sim, out, MPM_OUTPUT_NEW));
  CHECK(st == MPM_OK, "open: %s", mpm_sim_last_error(sim));
  snprintf(name, sizeof name, "frame_0001_p%04d.vtu", size - 1);
  path_of(piece, sizeof piece, "failing", name);
  if (rank == size - 1) mkdir(piece, 0755);
  MPI_Barrier(MPI_COMM_WORLD);
  st = mpm_sim_ranks_agree(sim, mpm_sim_advance_frame(sim));
  CHECK(st == MPM_ERR_IO, "a piece that cannot be written: %d (%s)", st, mpm_sim_last_error(sim));
  CHECK(strstr(mpm_sim_last_error(sim), name), "the message does not name %s: %s", name,
        mpm_sim_last_error(sim));
  CHECK(same_on_every_rank(mpm_sim_last_error(sim)), "the ranks' messages differ");
  char index[512];
  path_of(index, sizeof index, "failing", "frame_0001.pvtu");
  CHECK(!exists(index), "an index names a piece that is not there");
  mpm_sim_destroy(sim);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  return remove(path);
}

int main(int argc, char **argv) {
  mpi_check_start(&argc, &argv);
  if (rank == 0) {
    snprintf(root, sizeof root, "/tmp/mpm_test_dist_run_%ld", (long)getpid());
    mkdir(root, 0755);
  }
  MPI_Bcast(root, sizeof root, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank == 0) { /* one process's run, the reference */
    mpm_sim *one = made(scene, 0);
    run(one, "one");
    mpm_sim_destroy(one);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  mpm_sim *sim = made(scene, 1);
  mpm_sim_info in;
  mpm_sim_get_info(sim, &in, sizeof in);
  CHECK(in.rank == rank && in.ranks == size, "info: rank %d of %d", in.rank, in.ranks);
  run(sim, "ranks");
  mpm_sim_get_info(sim, &in, sizeof in);
  long mine = (long)in.particles, total = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  CHECK((long)in.run_particles == total, "info: %zu particles of the run, %ld on the ranks",
        in.run_particles, total);
  mpm_sim_destroy(sim);
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0) {
    for (int k = 0; k <= FRAMES; ++k) check_frame(k);
    check_indexes();
    check_stats();
  }
  test_refusals();
  test_failed_piece();
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0 && !failures) nftw(root, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
  return mpi_check_finish("test_dist_run");
}
