/* main.c - the `mpm` command line program: dispatch to run, check, bench, render and plot. */
#define _POSIX_C_SOURCE 200809L /* setenv, execv */
#include "cli.h"
#include "mpm/mpm.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The usage of each subcommand: `mpm --help` prints them all, `mpm CMD --help` its own. */
typedef struct usage_section {
  const char *cmd, *text;
} usage_section;

static const usage_section SECTIONS[] = {
    {"run",
     "  mpm run SCENE.json [-o DIR [--overwrite] | --resume DIR] [--threads N] [--frames N]\n"
     "          [--render] [--quiet]\n"
     "      simulate the scene, writing frames (VTU + PVD, PLY, stats.csv), checkpoints\n"
     "      (checkpoint_*.h5) and a copy of the scene (scene.json) to DIR (default: the\n"
     "      scene's output.directory); a DIR holding another run's files is refused unless\n"
     "      --overwrite (which removes them first); --resume continues the run in DIR from\n"
     "      its newest checkpoint; --threads sets the OpenMP threads; --frames stops after N "
     "frames;\n"
     "      --render then runs `mpm render DIR`; --quiet prints no progress;\n"
     "      Ctrl-C or SIGTERM writes a checkpoint and stops (exit 130 or 143)\n"},
    {"check", "  mpm check SCENE.json [--sample]\n"
              "      validate a scene only: nothing is simulated or written; a scene of more\n"
              "      than 5 million particles is answered from the bodies' volumes without\n"
              "      sampling them (--sample: sample them too, checking their placement)\n"},
    {"bench", "  mpm bench transfer [--threads LIST] [--repeats N] [--kernel K] [--grid G]\n"
              "                     [--spacing-scale S] [--levels N]\n"
              "      Gao et al. 2017 Table 1 transfer benchmark (P2G and G2P ns per particle);\n"
              "      --levels N: the block on N levels, fine near its surface, beside uniform\n"
              "  mpm bench step [--particles N] [--threads LIST] [--steps N] [--repeats N]\n"
              "                 [--levels N]\n"
              "      full explicit steps of a falling neo-Hookean block (ns per particle-step);\n"
              "      --levels N: the block on N levels, fine near its surface, beside the\n"
              "      uniform sparse grid, with the ratio per particle-step\n"
              "  mpm bench stress [--particles N] [--threads LIST] [--repeats N]\n"
              "      each material model's batch stress and return map (ns per particle), and\n"
              "      ns per 3x3 SVD (mpm_svd3)\n"
              "  mpm bench checkpoint [--particles N] [--repeats N] [--dir DIR]\n"
              "      checkpoint write/read/resume seconds and MB/s, cost of the guards per step\n"
              "  mpm bench domains [--particles N] [--threads LIST] [--steps N] [--repeats N]\n"
              "      ns per particle-step with particle domains against material points, and\n"
              "      where the time goes (activation and layout, P2G, grid update, G2P)\n"
              "  mpm bench implicit [--particles N] [--drop-particles N] [--threads LIST]\n"
              "                     [--repeats N] [--only action|drop|resolution]\n"
              "                     [--case block5e6|block1e9|bunny] [--preconditioner "
              "jacobi|multigrid]\n"
              "                     [--ladder all|fixed|cfl] [--scheme backward_euler|newmark]\n"
              "      the Hessian action against explicit P2G + G2P, CG iterations with and\n"
              "      without the preconditioner, time to simulate 1 s explicit and implicit\n"
              "      (a dropped block of two moduli, the rubber bunny; implicit at the CFL\n"
              "      rate of the motion and at fixed steps), CG iterations of one step at\n"
              "      three resolutions with Jacobi and multigrid\n"
              "  mpm bench surface [--particles N] [--threads LIST] [--smoothing PASSES]\n"
              "      seconds of one frame's particle surface (output.surface) for a 1M-particle\n"
              "      cube and ball: level set, filter, mesh, OBJ + PLY\n"
              "  mpm bench contact [--threads LIST] [--repeats N]\n"
              "      the enriched surfaces' contact pass alone on two blocks of enriched\n"
              "      domains at three sizes: ms a pass, ns per enriched corner\n"},
    {"render",
     "  mpm render OUTDIR [--field velocity|J|stress|plastic|material|body|temperature|melt|\n"
     "                             ARRAY[.x|.xx]]\n"
     "                    [--size WxH] [--colormap viridis|coolwarm|category] [--range LO:HI]\n"
     "                    [--every N] [--frames FIRST:LAST] [--frame material|follow|domain]\n"
     "                    [--margin F] [--eye X,Y,Z] [--target X,Y,Z] [--fov DEG]\n"
     "                    [--no-shadow] [--no-legend] [--no-time]\n"
     "                    [--scene SCENE.json] [--out DIR] [--movie] [--grid] [--particles]\n"
     "                    [--quiet]\n"
     "      draw each frame of a run to OUTDIR/render/frame_NNNN.png (no GPU needed):\n"
     "      particles coloured by --field (default velocity, or material (body when they\n"
     "      share one) where every particle moves alike, e.g. a run at rest; temperature\n"
     "      and melt, the melt fraction, in runs with heat; or any array the run wrote\n"
     "      (output.fields), e.g. pressure, a vector's or tensor's magnitude, or one\n"
     "      component: velocity.y, cauchy_stress.xy) with --colormap over --range\n"
     "      (default: percentiles of the run; a signed array centred on 0), every N-th\n"
     "      frame of --frames FIRST:LAST (FIRST:, :LAST, or N alone; default all), the\n"
     "      colliders of --scene (default OUTDIR/scene.json), to --out, at --size\n"
     "      (default 1280x720);\n"
     "      --frame: the camera frames the material over all frames rendered (material,\n"
     "      the default: one steady view), in each frame (follow) or the domain (domain),\n"
     "      leaving --margin F of the height free at the edges (default 0.06), seen across\n"
     "      a slope (a tilted half-space is the ground); the scene's `camera` overrides it,\n"
     "      and --eye, --target (m) and --fov (vertical, degrees) override both, each alone\n"
     "      keeping the rest of the automatic view (the last line printed gives the camera\n"
     "      used); a soft shadow under the material on the ground\n"
     "      (--no-shadow: none), a colour bar with the field's name, units and range (or\n"
     "      the key of materials or bodies; --no-legend: none) and the time and frame\n"
     "      number (--no-time: none); --movie also makes movie.mp4 with ffmpeg; --grid\n"
     "      draws the multi-level grid's fine cells over them; a run's particle surfaces\n"
     "      (output.surface) are drawn as shaded triangles in place of their particles\n"
     "      (--particles: the particles too); --quiet prints nothing but errors\n"},
    {"plot", "  mpm plot OUTDIR [--out DIR] [--quiet]\n"
             "      plot OUTDIR/stats.csv (energies, momenta, dt, steps and wall time per frame,\n"
             "      enriched particles, the colliders' reaction forces) to OUTDIR/plots/*.png\n"
             "      (or --out DIR) with gnuplot\n"},
    {"error", "  mpm error REST.vtu FINAL.vtu [--body N]\n"
              "  mpm error OUTDIR REST_FRAME FINAL_FRAME [--body N]\n"
              "      the rest-state error (Zhu et al. 2017): particles matched by id, rigid\n"
              "      motion removed by shape matching, mean and max distance over the rest\n"
              "      shape's bounding-box diagonal; --body N: the particles of body N only\n"},
};
#define SECTION_COUNT (sizeof SECTIONS / sizeof SECTIONS[0])

/* The whole usage (cmd NULL) or one subcommand's. Returns 0, -1 for an unknown cmd. */
static int usage_of(FILE *out, const char *cmd) {
  int known = !cmd;
  for (size_t k = 0; k < SECTION_COUNT; ++k) known |= cmd && !strcmp(cmd, SECTIONS[k].cmd);
  if (!known) return -1;
  fprintf(out, "mpm %s - Material Point Method simulation engine (%s build)\n\n", mpm_version(),
          mpm_real_type());
  if (!cmd) fputs("usage:\n", out);
  for (size_t k = 0; k < SECTION_COUNT; ++k)
    if (!cmd)
      fputs(SECTIONS[k].text, out);
    else if (!strcmp(cmd, SECTIONS[k].cmd)) /* "usage: mpm CMD ..." on its first line */
      fprintf(out, "usage: %s", SECTIONS[k].text + 2);
  if (!cmd) fputs("  mpm --help | CMD --help | --version\n", out);
  fputs("\nexit codes: 0 success, 1 simulation failure, 2 usage or input error,\n"
        "            128 + N stopped by signal N after writing a checkpoint\n",
        out);
  return 0;
}

static void usage(FILE *out) {
  usage_of(out, NULL);
}

/* Edit distance of a and b with adjacent transpositions counted as one edit ("rnu" is one from
 * "run"; optimal string alignment); words over 63 characters count as far. */
static int edit_distance(const char *a, const char *b) {
  const int la = (int)strlen(a), lb = (int)strlen(b);
  if (la > 63 || lb > 63) return 64;
  int d[64][64];
  for (int i = 0; i <= la; ++i) d[i][0] = i;
  for (int j = 0; j <= lb; ++j) d[0][j] = j;
  for (int i = 1; i <= la; ++i)
    for (int j = 1; j <= lb; ++j) {
      int best = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
      if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
          d[i - 2][j - 2] + 1 < best)
        best = d[i - 2][j - 2] + 1;
      d[i][j] = best;
    }
  return d[la][lb];
}

const char *mpm_cli_suggest(const char *word, const char *const *known) {
  const char *best = NULL;
  int best_d = 3;
  for (int k = 0; known[k]; ++k) {
    const int d = edit_distance(word, known[k]);
    if (d < best_d && 2 * d < (int)strlen(word)) {
      best_d = d;
      best = known[k];
    }
  }
  return best;
}

void mpm_cli_unknown_option(const char *cmd, const char *option, const char *const *known) {
  const char *near = mpm_cli_suggest(option, known);
  if (near)
    fprintf(stderr, "mpm %s: unknown option '%s': did you mean '%s'? (mpm %s --help lists them)\n",
            cmd, option, near, cmd);
  else
    fprintf(stderr, "mpm %s: unknown option '%s' (mpm %s --help lists them)\n", cmd, option, cmd);
}

int mpm_cli_parse_int(const char *opt, const char *value, int lo, int hi, int *out) {
  if (!value) {
    fprintf(stderr, "mpm: %s needs a value (an integer from %d to %d)\n", opt, lo, hi);
    return -1;
  }
  char *end;
  errno = 0;
  long v = strtol(value, &end, 10);
  if (errno || *end || end == value || v < lo || v > hi) {
    fprintf(stderr, "mpm: %s expects an integer from %d to %d, got '%s'\n", opt, lo, hi, value);
    return -1;
  }
  *out = (int)v;
  return 0;
}

/* The spin count the program asks of libgomp's threads (GOMP_SPINCOUNT): how long a thread that
 * ends its share of a parallel loop spins before it sleeps. The implicit step runs thousands of
 * short loops a second (the multigrid's colours, level by level), and a sleeping thread takes
 * long to wake on this project's VM: 0.5 s of jello_cubes (2 threads, idle machine) took 2.58 s
 * with passive threads (they sleep at once), 1.04-1.10 s spinning 10,000 times or for ever;
 * 0.35 s of the implicit rubber bunny 15.1 s with 1,000 or 2,000 spins, 12.8 s with 5,000,
 * 11.9 s with 10,000, 11.7 s with 50,000, 12.2 s active. Bounded, the spin costs a busy
 * machine little: beside five busy loops the jello took 5.5-6.5 s against passive threads'
 * 5.4-5.7 (threads that spin for ever: 17.6-19.7 s against 4.8-5.0, an earlier sitting), beside
 * one 1.9-2.2 s against 2.3-2.7. */
#define SPIN_COUNT "10000"

/* The OpenMP runtime reads its wait policy once, when it is loaded, so the program runs itself
 * again with GOMP_SPINCOUNT set (SPIN_COUNT) unless the environment chose a policy
 * (OMP_WAIT_POLICY) or a spin count of its own. GOMP_SPINCOUNT is read by GCC's runtime (libgomp,
 * in the gcc builds); LLVM's (the ThreadSanitizer build's) keeps its own KMP_BLOCKTIME. */
static void prefer_bounded_spin(char **argv) {
  if (getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT") || !argv[0]) return;
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return; /* no /proc: go on with the policy the runtime has */
  self[n] = 0;
  /* only when this process is the program itself, not a tool running it (valgrind's
   * /proc/self/exe is valgrind's) */
  const char *a = strrchr(argv[0], '/'), *b = strrchr(self, '/');
  if (strcmp(a ? a + 1 : argv[0], b ? b + 1 : self)) return;
  if (setenv("GOMP_SPINCOUNT", SPIN_COUNT, 0)) return;
  execv(self, argv);
}

int main(int argc, char **argv) {
  prefer_bounded_spin(argv);
  if (argc < 2) {
    usage(stderr);
    return MPM_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    usage(stdout);
    return MPM_EXIT_OK;
  }
  if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V")) {
    const char *policy = getenv("OMP_WAIT_POLICY"), *spin = getenv("GOMP_SPINCOUNT");
    if (policy)
      printf("mpm %s (%s; OpenMP threads wait %s)\n", mpm_version(), mpm_real_type(), policy);
    else if (spin)
      printf("mpm %s (%s; OpenMP threads spin %s times, then sleep)\n", mpm_version(),
             mpm_real_type(), spin);
    else
      printf("mpm %s (%s; OpenMP threads wait as the runtime chooses)\n", mpm_version(),
             mpm_real_type());
    return MPM_EXIT_OK;
  }
  /* `mpm CMD --help` (anywhere among CMD's arguments): CMD's usage, exit 0 */
  for (int k = 2; k < argc; ++k)
    if (!strcmp(argv[k], "--help") || !strcmp(argv[k], "-h")) {
      if (usage_of(stdout, cmd) == 0) return MPM_EXIT_OK;
      break;
    }
  if (!strcmp(cmd, "run")) return mpm_cmd_run(argc - 2, argv + 2);
  if (!strcmp(cmd, "check")) return mpm_cmd_check(argc - 2, argv + 2);
  if (!strcmp(cmd, "bench")) return mpm_cmd_bench(argc - 2, argv + 2);
  if (!strcmp(cmd, "render")) return mpm_cmd_render(argc - 2, argv + 2);
  if (!strcmp(cmd, "plot")) return mpm_cmd_plot(argc - 2, argv + 2);
  if (!strcmp(cmd, "error")) return mpm_cmd_error(argc - 2, argv + 2);
  static const char *const commands[] = {"run",   "check",  "bench",     "render", "plot",
                                         "error", "--help", "--version", NULL};
  const char *near = mpm_cli_suggest(cmd, commands);
  if (near)
    fprintf(stderr, "mpm: unknown command '%s': did you mean '%s'? (try 'mpm --help')\n", cmd,
            near);
  else
    fprintf(stderr, "mpm: unknown command '%s' (try 'mpm --help')\n", cmd);
  return MPM_EXIT_USAGE;
}
