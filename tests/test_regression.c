/* test_regression.c - the explicit path's results stay bitwise what they were.
 *
 * A refactor of the step (the DOF set, the grid interface, the embedding operator, the stages)
 * must change no result. This test runs a few example scenes (and two inline ones for the
 * dense grid and for domain releases) for a few frames and compares a digest of the whole
 * simulation state - every particle array in id order, the domain particles and their corners,
 * the time and the step count - with the digests in tests/regression/state_<real>.txt, which
 * were written by this same test against main before the refactor (commit 8b62097).
 * One intended change since: the domain walls act on domain corners as the colliders do
 * (collide/boundary.h), which changes tunnel_squeeze (its ball lands on the floor wall); its
 * digests were rewritten with that commit, all others are main's.
 * Dynamic enrichment (Zhu sec. 5) changes the domain scenes: they run here with every body's
 * enrichment set to 0, which gave main's digests bitwise when
 * enrichment came in (e38c670: the unenriched path untouched), and enriched (the *_enriched
 * cases: Zhu's 0.6, or the scene's own 1). The next commit, the compensated summation of the
 * corners' moves (the float drift of issue 13), changed every domain scene on purpose; the domain
 * digests were rewritten with it, the others are main's.
 *
 * Reordering the particles when their order has come apart (step.c, mpm_sim_wants_reorder, issue
 * 17: a moving body was 12% slower between the reorders every 16 steps) changes the order of the
 * transfers' sums in every scene whose material moves; those digests were rewritten with it.
 *
 * The corners' transfers through pads of nodes on the sparse grid (domain/corner_pads.h, issue 13:
 * the domain step's speed) take their corners as SIMD lanes, which sums the same terms in
 * another order: the explicit domain scenes on the sparse grid were rewritten with it (the
 * enriched release, whose every corner is its own DOF, and every other scene are unchanged).
 *
 * The domain particles' stresses come from the models' pk1_batch (vectorized logarithm and SVD),
 * which rounds differently from pk1: the six domain scenes were rewritten with it.
 * The material points' moves are summed with compensation (particles.h, xc; issue 13: a body
 * drifting slowly moved up to 29% farther than its velocity said in float): every scene's
 * positions round differently since, and all digests were rewritten with it.
 * A lattice domain's weights are stored as the cube's exact pattern (w = 1/8, g = +-1/(4h)),
 * no longer as the quadrature's rounding of it: the float digests are unchanged (the same
 * values), the double build's domain scenes were rewritten with it.
 *
 * The domain step's speed (issue 13, 2026-12-05): the corner -> grid scatter sums each batch's
 * terms lane by lane and the lanes once per node, and the corners are renumbered into the order
 * of the grid blocks their transfers go by (mpm_domain_order_corners), which changes the order
 * of the sums over a corner's particles and a cell's corners: the five domain scenes were
 * rewritten with it (the others are unchanged).
 * The hourglass stiffness (issue 13, 2026-12-05): kappa from mu h / 80 to E h / 48, the
 * linear-elastic cost of a bent domain (domain/enrich.h): the two enriched scenes were
 * rewritten with it (the others are unchanged).
 * Lattice fragments (issue 13, 2026-12-05): a mesh body's particles that touch the rest only
 * along an edge or at a corner are dropped when its domains are made (domain.h,
 * MPM_DOMAIN_MIN_FRAGMENT): the two bunny scenes were rewritten with it.
 * The multi-level grid (issue 16, 2026-12-05): level_crossing, levels_contact and levels_sand
 * were added with the paired transfers (mpm_kernel_paired); for them the labels include the
 * particles' types and the clock the refined cells.
 * APIC across levels in the lanes (issue 42, 2026-12-06): the boundary particles' D_p, C_p and
 * B corrections are computed inside the P2G and G2P lanes from the lanes' own weights (float,
 * where a scalar pass recomputed them in double) and from the divisor the lanes use, and the
 * ghosts' affine moments are summed per cell entry, then per ghost: the three multi-level scenes
 * were rewritten with it (level_crossing's kinetic energy and angular momentum over 4 frames
 * agree with the old results to 2e-7 relative; the others unchanged).
 * Lanes of one register in the double build (core/lanes.h, 2026-12-07: 4 doubles where 8 made
 * GCC build the transfers' vectors through the stack; the explicit step 2.9-3.4 times faster):
 * a cell's particles are summed 4 at a time, then the batches, in another order: every double
 * digest was rewritten with it (the float build is unchanged). sand_pile, jello_cubes and the
 * explicit cantilever agree with the old build in kinetic, elastic and total energy to every
 * printed digit and in momentum and angular momentum to 1e-11 relative.
 * A mismatch names the scene and the quantity (x, v, F, B, plastic, ...) that differs.
 * Regenerate the files only for an intended change of results, and say so in the commit:
 *   MPM_REGRESSION_WRITE=tests/regression/state_float.txt build/test_regression
 * (and the same from build-double for state_double.txt). The digests are of IEEE bits: they
 * hold for any thread count (the engine is deterministic) and any optimization level (the
 * build is ISO C: no FMA contraction), on the x86-64 machines this project runs on. */
#include "support.h"
#include "core/hash.h"
#include "adaptive/adaptive.h"
#include "sim/sim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define STATE_QUANTITIES 9
static const char *const quantity_name[STATE_QUANTITIES] = {
    "clock", "x", "v", "F", "B", "plastic", "mass_vol0", "labels", "corners"};

typedef struct state_digest {
  uint64_t h[STATE_QUANTITIES];
} state_digest;

/* Digest of count values of `size` bytes gathered in the order `order` (NULL: natural). */
static uint64_t digest_gather(uint64_t h, const void *data, size_t size, size_t count,
                              const size_t *order) {
  unsigned char buf[8];
  const unsigned char *b = data;
  for (size_t k = 0; k < count; ++k) {
    const size_t i = order ? order[k] : k;
    memcpy(buf, b + i * size, size);
    h = mpm_hash64_words(buf, size, h);
  }
  return h;
}

static void digest_particles(const mpm_particles *p, const size_t *order, state_digest *s) {
  const size_t n = p->count, r = sizeof(mpm_real);
  for (int d = 0; d < 3; ++d) {
    s->h[1] = digest_gather(s->h[1], p->x[d], r, n, order);
    s->h[2] = digest_gather(s->h[2], p->v[d], r, n, order);
  }
  for (int c = 0; c < 9; ++c) {
    s->h[3] = digest_gather(s->h[3], p->F[c], r, n, order);
    s->h[4] = digest_gather(s->h[4], p->B[c], r, n, order);
  }
  s->h[5] = digest_gather(s->h[5], p->plastic, r, n, order);
  s->h[6] = digest_gather(s->h[6], p->mass, r, n, order);
  s->h[6] = digest_gather(s->h[6], p->vol0, r, n, order);
  s->h[7] = digest_gather(s->h[7], p->material, sizeof(int32_t), n, order);
  s->h[7] = digest_gather(s->h[7], p->body, sizeof(int32_t), n, order);
  s->h[7] = digest_gather(s->h[7], p->id, sizeof(uint32_t), n, order);
}

static int by_cell(const void *a, const void *b) {
  const int32_t *x = a, *y = b;
  for (int k = 0; k < 4; ++k)
    if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
  return 0;
}

static state_digest digest_sim(const mpm_sim *sim) {
  state_digest s;
  for (int q = 0; q < STATE_QUANTITIES; ++q) s.h[q] = 0x5eed0000u + (uint64_t)q;
  const int64_t steps = sim->steps;
  const double t = sim->time;
  s.h[0] = mpm_hash64_words(&steps, sizeof steps, s.h[0]);
  s.h[0] = mpm_hash64_words(&t, sizeof t, s.h[0]);
  s.h[0] = mpm_hash64_words(&sim->last_dt, sizeof sim->last_dt, s.h[0]);
  /* standard particles in id order: their memory order is an implementation detail */
  const mpm_particles *p = &sim->particles;
  size_t *order = malloc((p->count + 1) * sizeof *order);
  uint32_t max_id = 0;
  for (size_t i = 0; i < p->count; ++i)
    if (p->id[i] > max_id) max_id = p->id[i];
  size_t *slot = malloc(((size_t)max_id + 2) * sizeof *slot);
  for (size_t i = 0; i <= max_id; ++i) slot[i] = SIZE_MAX;
  for (size_t i = 0; i < p->count; ++i) slot[p->id[i]] = i;
  size_t k = 0;
  for (size_t i = 0; i <= max_id; ++i)
    if (slot[i] != SIZE_MAX) order[k++] = slot[i];
  assert_int_equal(k, p->count);
  digest_particles(p, order, &s);
  if (sim->adaptive) { /* the multi-level grid: the particles' types and the tree */
    s.h[7] = digest_gather(s.h[7], p->level, sizeof *p->level, p->count, order);
    size_t cells = 0;
    int32_t(*tree)[4] = mpm_adaptive_tree_cells(sim->adaptive, &cells);
    assert_non_null(tree);
    qsort(tree, cells, sizeof *tree, by_cell); /* the order of a hash table's slots: not ours */
    s.h[0] = mpm_hash64_words(tree, cells * sizeof *tree, s.h[0]);
    mpm_free(tree);
  }
  free(slot);
  free(order);
  /* domain particles are never reordered; their corners neither */
  const mpm_domain_set *ds = &sim->domains;
  digest_particles(&ds->particles, NULL, &s);
  s.h[7] = digest_gather(s.h[7], ds->active, 1, ds->particles.count, NULL);
  for (int d = 0; d < 3; ++d) {
    s.h[8] = digest_gather(s.h[8], ds->cx[d], sizeof(mpm_real), ds->corner_count, NULL);
    s.h[8] = digest_gather(s.h[8], ds->cv[d], sizeof(mpm_real), ds->corner_count, NULL);
  }
  return s;
}

/* A small dense-grid scene: cubic B-spline, FLIP, two materials, a sphere collider. */
static const char dense_scene[] =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.03},"
    " \"time\": {\"end\": 1, \"fps\": 24},"
    " \"solver\": {\"kernel\": \"cubic\", \"transfer\": \"flip\", \"flip_alpha\": 0.9,"
    "              \"grid\": \"dense\", \"cfl\": 0.4},"
    " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 3e4, \"nu\": 0.3,"
    "                  \"density\": 1000},"
    "                 {\"name\": \"s\", \"model\": \"drucker_prager\", \"E\": 2e5, \"nu\": 0.3,"
    "                  \"density\": 1500, \"friction_angle\": 30}],"
    " \"colliders\": [{\"shape\": {\"type\": \"sphere\", \"center\": [0.3,0.12,0.3], \"radius\": "
    "0.08}, \"rule\": \"slip\"}],"
    " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.3,0.35,0.3], \"half_extent\": "
    "[0.08,0.05,0.08]}, \"material\": \"j\", \"velocity\": [0.5,-1,0]},"
    "              {\"shape\": {\"type\": \"sphere\", \"center\": [0.3,0.44,0.3], \"radius\": "
    "0.05}, \"material\": \"s\"}]}";

/* Domains switched off by a release box half-way: released particles continue as material
 * points under FLIP with the quadratic corner kernel. */
#define RELEASE_SCENE(enrichment)                                                                  \
  "{\"domain\": {\"min\": [0,0,0], \"max\": [0.5,0.5,0.5], \"dx\": 0.025},"                        \
  " \"time\": {\"end\": 1, \"fps\": 24},"                                                          \
  " \"solver\": {\"kernel\": \"quadratic\", \"transfer\": \"flip\", \"flip_alpha\": 0.95,"         \
  "              \"domain_kernel\": \"quadratic\", \"cfl\": 0.4},"                                 \
  " \"materials\": [{\"name\": \"r\", \"model\": \"neo_hookean\", \"E\": 5e4, \"nu\": 0.3,"        \
  "                  \"density\": 1000, \"min_stretch\": 0.1}],"                                   \
  " \"colliders\": [{\"shape\": {\"type\": \"halfspace\", \"point\": [0,0.1,0], \"normal\": "      \
  "[0,1,0]}, \"rule\": \"sticky\"}],"                                                              \
  " \"bodies\": [{\"shape\": {\"type\": \"box\", \"center\": [0.25,0.2,0.25], \"half_extent\": "   \
  "[0.1,0.05,0.05]}, \"material\": \"r\", \"jitter\": 0, \"domains\": true," enrichment            \
  "              \"velocity\": [0,-1,0],"                                                          \
  "              \"domain_release\": [{\"time\": 0.04, \"min\": [0.25,0,0], \"max\": "             \
  "[1,1,1]}]}]}"
static const char release_scene[] = RELEASE_SCENE("");
/* the same with every domain enriched from the start (epsilon = 1) */
static const char release_scene_enriched[] = RELEASE_SCENE(" \"enrichment\": 1,");

/* Two jellos meeting on 3 levels (examples/gao/jello_collision_256_contact.json, small): fine
 * only where they meet (a body rule's within), the grid following the particle types every 2
 * steps, middle particles on the fine grid with paired transfers; and sand on 2 levels whose
 * band follows its free surface, its particles split and merged to follow the band. */
static const char levels_contact_scene[] =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [1,1,1], \"dx\": 0.0625, \"levels\": 3,"
    " \"refine_every\": 2, \"refine\": ["
    "  {\"level\": 1, \"body\": \"l\", \"distance\": 0.08, \"within\": {\"min\": [0.3,0,0],"
    " \"max\": [1,1,1]}},"
    "  {\"level\": 2, \"body\": \"l\", \"distance\": 0.03, \"within\": {\"min\": [0.42,0,0],"
    " \"max\": [1,1,1]}},"
    "  {\"level\": 1, \"body\": \"r\", \"distance\": 0.08, \"within\": {\"min\": [0,0,0],"
    " \"max\": [0.7,1,1]}},"
    "  {\"level\": 2, \"body\": \"r\", \"distance\": 0.03, \"within\": {\"min\": [0,0,0],"
    " \"max\": [0.58,1,1]}},"
    "  {\"level\": 2, \"types\": true, \"distance\": 0.015}]},"
    " \"gravity\": [0,0,0], \"time\": {\"end\": 1, \"fps\": 24},"
    " \"solver\": {\"transfer\": \"apic\", \"cfl\": 0.5},"
    " \"materials\": [{\"name\": \"j\", \"model\": \"fixed_corotated\", \"E\": 2e4, \"nu\": 0.3,"
    " \"density\": 1000}],"
    " \"bodies\": [{\"name\": \"l\", \"shape\": {\"type\": \"box\", \"center\": [0.35,0.5,0.5],"
    " \"half_extent\": [0.09,0.09,0.09]}, \"material\": \"j\", \"velocity\": [1.5,0,0],"
    " \"jitter\": 0},"
    "  {\"name\": \"r\", \"shape\": {\"type\": \"box\", \"center\": [0.65,0.53,0.5],"
    " \"half_extent\": [0.09,0.09,0.09]}, \"material\": \"j\", \"velocity\": [-1.5,0,0],"
    " \"jitter\": 0}]}";
static const char levels_sand_scene[] =
    "{\"domain\": {\"min\": [0,0,0], \"max\": [0.6,0.6,0.6], \"dx\": 0.05, \"levels\": 2,"
    " \"refine_every\": 2, \"refine\": [{\"level\": 1, \"body\": \"s\", \"distance\": 0.05},"
    " {\"level\": 1, \"surface\": 0.04}], \"resample\": {\"merge_margin\": 0.25,"
    " \"min_per_cell\": 8}},"
    " \"time\": {\"end\": 1, \"fps\": 24},"
    " \"solver\": {\"transfer\": \"apic\", \"cfl\": 0.5},"
    " \"materials\": [{\"name\": \"d\", \"model\": \"drucker_prager\", \"E\": 3e5, \"nu\": 0.3,"
    " \"density\": 1600, \"friction_angle\": 30}],"
    " \"bodies\": [{\"name\": \"s\", \"shape\": {\"type\": \"box\", \"center\": [0.3,0.3,0.3],"
    " \"half_extent\": [0.12,0.12,0.12]}, \"material\": \"d\", \"velocity\": [0,-1,0]}]}";

typedef struct regression_case {
  const char *name; /* as in the digest file */
  const char *path; /* an example scene, or NULL for json */
  const char *json; /* an inline scene */
  int frames;
  double enrichment; /* >= 0: every body's enrichment set to this; < 0: as the scene says */
} regression_case;

static const regression_case cases[] = {
    {"jello_cubes", "examples/jello_cubes.json", NULL, 3, -1},
    {"bunny_drop", "examples/bunny_drop.json", NULL, 2, -1},
    {"sand_pile", "examples/sand_pile.json", NULL, 2, -1},
    {"snowball", "examples/snowball.json", NULL, 1, -1},
    {"goo_slits", "examples/goo_slits.json", NULL, 1, -1},
    {"block_on_cylinder", "examples/block_on_cylinder.json", NULL, 3, -1},
    {"bar_stretch", "examples/bar_stretch.json", NULL, 4, 0},
    {"ball_bunny", "examples/ball_bunny.json", NULL, 2, 0},
    {"tunnel_squeeze", "examples/tunnel_squeeze.json", NULL, 6, 0},
    {"dense_flip_cubic", NULL, dense_scene, 3, -1},
    {"domain_release", NULL, release_scene, 3, 0},
    {"ball_bunny_enriched", "examples/ball_bunny.json", NULL, 2, 0.6},
    {"domain_release_enriched", NULL, release_scene_enriched, 3, -1},
    {"level_crossing", "examples/gao/level_crossing.json", NULL, 2, -1},
    {"levels_contact", NULL, levels_contact_scene, 2, -1},
    {"levels_sand", NULL, levels_sand_scene, 2, -1},
};
#define CASE_COUNT (sizeof cases / sizeof cases[0])

static mpm_sim *make_sim(const regression_case *c) {
  mpm_sim *sim = NULL;
  mpm_scene scene;
  mpm_error e;
  mpm_error_clear(&e);
  if (c->path ? mpm_scene_load(c->path, &scene, &e) != MPM_OK
              : mpm_scene_parse(c->json, c->name, &scene, &e) != MPM_OK)
    fail_msg("%s: %s", c->name, e.message);
  for (int b = 0; b < scene.body_count && c->enrichment >= 0; ++b)
    if (scene.bodies[b].domains) scene.bodies[b].enrichment = c->enrichment;
  if (mpm_sim_create_from_scene(&scene, &sim, &e) != MPM_OK) fail_msg("%s: %s", c->name, e.message);
  mpm_scene_free(&scene);
  return sim;
}

static state_digest run_case(const regression_case *c) {
  mpm_sim *sim = make_sim(c);
  for (int f = 0; f < c->frames; ++f)
    if (mpm_sim_advance_frame(sim) != MPM_OK)
      fail_msg("%s frame %d: %s", c->name, f + 1, mpm_sim_last_error(sim));
  state_digest s = digest_sim(sim);
  mpm_sim_destroy(sim);
  return s;
}

static const char *digest_file(void) {
  return "tests/regression/state_" MPM_REAL_NAME ".txt";
}

/* Find "name quantity hex" in the digest file. Returns 1 and the digest, or 0. */
static int lookup(const char *name, const char *quantity, uint64_t *out) {
  FILE *f = fopen(digest_file(), "r");
  if (!f) fail_msg("cannot open %s", digest_file());
  char line[256], n[128], q[64];
  unsigned long long h;
  int found = 0;
  while (fgets(line, sizeof line, f))
    if (line[0] != '#' && sscanf(line, "%127s %63s %llx", n, q, &h) == 3 && !strcmp(n, name) &&
        !strcmp(q, quantity)) {
      *out = (uint64_t)h;
      found = 1;
    }
  fclose(f);
  return found;
}

static void test_state_unchanged(void **state) {
  (void)state;
  const char *write = getenv("MPM_REGRESSION_WRITE");
  FILE *out = NULL;
  if (write && *write) {
    out = fopen(write, "w");
    if (!out) fail_msg("cannot write %s", write);
    fprintf(out, "# test_regression digests (%s build): scene quantity digest\n", MPM_REAL_NAME);
  }
  int mismatches = 0;
  for (size_t i = 0; i < CASE_COUNT; ++i) {
    const state_digest s = run_case(&cases[i]);
    for (int q = 0; q < STATE_QUANTITIES; ++q) {
      if (out) {
        fprintf(out, "%s %s %016llx\n", cases[i].name, quantity_name[q],
                (unsigned long long)s.h[q]);
        continue;
      }
      uint64_t want = 0;
      if (!lookup(cases[i].name, quantity_name[q], &want))
        fail_msg("%s: no digest for %s %s", digest_file(), cases[i].name, quantity_name[q]);
      if (want != s.h[q]) {
        print_error("%s after %d frames: %s differs from the digest of main before the refactor "
                    "(%016llx, expected %016llx)\n",
                    cases[i].name, cases[i].frames, quantity_name[q], (unsigned long long)s.h[q],
                    (unsigned long long)want);
        ++mismatches;
      }
    }
  }
  if (out) fclose(out);
  assert_int_equal(mismatches, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_state_unchanged)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
