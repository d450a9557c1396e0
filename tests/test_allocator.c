/* test_allocator.c - mpm_set_allocator (mpm.h): an embedding program's allocator takes every
 * allocation of the library, the particle storage included, and gets every block back. */
#include "support.h"
#include "core/alloc.h"
#include "mpm/mpm.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* An embedding program's allocator: counts what it gives and takes back, and checks the
 * alignment the library asks for. */
typedef struct counting_allocator {
  size_t calls, frees, live, peak, min_alignment;
  int misaligned;
} counting_allocator;

static void *counting_alloc(size_t bytes, size_t alignment, void *user) {
  counting_allocator *c = user;
  if (alignment < 64 || (alignment & (alignment - 1))) c->misaligned = 1;
  if (!c->min_alignment || alignment < c->min_alignment) c->min_alignment = alignment;
  /* a header of one alignment in front, holding the size */
  unsigned char *raw =
      aligned_alloc(alignment, (bytes + 2 * alignment - 1) / alignment * alignment);
  if (!raw) return NULL;
  memcpy(raw, &bytes, sizeof bytes);
  memcpy(raw + sizeof bytes, &alignment, sizeof alignment);
  unsigned char *p = raw + alignment;
  memcpy(p - sizeof raw, &raw, sizeof raw);
  c->calls++;
  c->live += bytes;
  if (c->live > c->peak) c->peak = c->live;
  return p;
}

static void counting_free(void *p, void *user) {
  counting_allocator *c = user;
  unsigned char *raw;
  memcpy(&raw, (unsigned char *)p - sizeof raw, sizeof raw);
  size_t bytes;
  memcpy(&bytes, raw, sizeof bytes);
  c->frees++;
  c->live -= bytes;
  free(raw);
}

static void test_allocator_hook(void **state) {
  (void)state;
  assert_int_equal(mpm_live_bytes(), 0); /* nothing of earlier tests left */
  counting_allocator c = {0};
  const mpm_allocator half = {counting_alloc, NULL, &c};
  assert_int_equal(mpm_set_allocator(&half), MPM_ERR_INVALID);
  /* the same run with the library's allocator and with the program's: the same state */
  void *x[2] = {NULL, NULL};
  size_t n[2] = {0, 0}; /* bytes of each component */
  for (int k = 0; k < 2; ++k) {
    const mpm_allocator a = {counting_alloc, counting_free, &c};
    if (k) assert_int_equal(mpm_set_allocator(&a), MPM_OK);
    mpm_sim *sim = NULL;
    char err[1024];
    assert_int_equal(mpm_sim_create_from_json(test_block_json, NULL, &sim, err, sizeof err),
                     MPM_OK);
    /* no change of allocator while the library holds memory */
    assert_int_equal(mpm_set_allocator(k ? NULL : &a), MPM_ERR_INVALID);
    assert_int_equal(mpm_sim_advance_frame(sim), MPM_OK);
    const mpm_particle_view v = mpm_sim_particles(sim);
    n[k] = v.count * v.real_size;
    x[k] = malloc(3 * n[k]);
    for (int d = 0; d < 3; ++d) memcpy((char *)x[k] + d * n[k], v.x[d], n[k]);
    mpm_sim_destroy(sim);
  }
  assert_int_equal(mpm_live_bytes(), 0);
  assert_int_equal(mpm_set_allocator(NULL), MPM_OK);
  assert_int_equal(n[0], n[1]);
  assert_memory_equal(x[0], x[1], 3 * n[0]);
  free(x[0]);
  free(x[1]);
  print_message("the program's allocator: %zu allocations, %zu frees, peak %.1f KiB, smallest "
                "alignment %zu\n",
                c.calls, c.frees, (double)c.peak / 1024, c.min_alignment);
  assert_true(c.calls > 10);
  assert_int_equal(c.calls, c.frees); /* everything taken back */
  assert_int_equal(c.live, 0);
  assert_false(c.misaligned);
}

/* mpm_free of what mpm_alloc did not make stops the program with a message (in a child process
 * here) instead of miscounting the live bytes and freeing a wrong address (a benchmark's scene
 * arrays from calloc were freed so, silently). A pointer inside a block stands for it: a block
 * of another allocator would be read before its start, which the sanitizer build reports on its
 * own. */
static void test_foreign_free_stops(void **state) {
  (void)state;
  fflush(stdout);
  const pid_t child = fork();
  assert_true(child >= 0);
  if (child == 0) {
    unsigned char *p = mpm_alloc(256);
    mpm_free(p + 128); /* no header there */
    _exit(0);          /* not reached */
  }
  int status = 0;
  assert_int_equal(waitpid(child, &status, 0), child);
  assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_allocator_hook),
                                     cmocka_unit_test(test_foreign_free_stops)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
