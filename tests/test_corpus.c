/* test_corpus.c - the malformed-input corpus: every bad scene and mesh under tests/corpus/,
 * listed with its expected exit code and message in tests/corpus/manifest.txt (the format is
 * described at the top of that file), goes through `mpm check FILE` and
 * `mpm run FILE -o DIR --frames 1 --quiet`. Each command must exit with the listed code (2:
 * input error), within a time limit (no hang), with a message that names the scene file and
 * contains the expected text (the key path, or the mesh file and line), and `mpm run` must
 * not create its output folder. Cases flagged known_bug are real bugs not fixed yet: they are
 * printed as KNOWN BUG and do not fail the test. One summary line ends the run. */
#include "support.h"
#include "cli_support.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__SANITIZE_ADDRESS__)
#define CORPUS_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CORPUS_ASAN 1
#endif
#endif
#ifndef CORPUS_ASAN
#define CORPUS_ASAN 0
#endif

#define CORPUS_DIR "tests/corpus"
#define MANIFEST CORPUS_DIR "/manifest.txt"
#define MAX_CASES 400
#define MIN_CASES 50
/* Seconds a command may run before it counts as a hang (a bad input is refused in
 * milliseconds); known bugs include hangs, so they get less. */
#define TIMEOUT_S 60
#define TIMEOUT_KNOWN_BUG_S 5
/* Address-space limit (KiB) for cases flagged heavy, so that a regression that allocates
 * without bound fails fast instead of exhausting the machine. */
#define HEAVY_ULIMIT_KB 1000000

typedef struct corpus_case {
  int line;             /* in the manifest */
  char file[256];       /* relative to CORPUS_DIR, or absolute */
  int exit_code;        /* of both commands */
  char expected[600];   /* pieces separated by " ... ", in order */
  int known_bug, heavy; /* flags */
  char note[600];       /* what goes wrong today, for known bugs */
} corpus_case;

static corpus_case cases[MAX_CASES];
static int case_count;

/* ---- the manifest --------------------------------------------------------------------- */

static void copy_field(char *dst, size_t cap, const char *src, const char *what, int line) {
  if (strlen(src) >= cap)
    fail_msg("%s:%d: %s is longer than %zu bytes", MANIFEST, line, what, cap - 1);
  snprintf(dst, cap, "%s", src);
}

static void parse_flags(corpus_case *c, const char *flags) {
  char buf[128];
  snprintf(buf, sizeof buf, "%s", flags);
  for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
    if (!strcmp(tok, "known_bug"))
      c->known_bug = 1;
    else if (!strcmp(tok, "heavy"))
      c->heavy = 1;
    else if (tok[0] && strcmp(tok, "-") != 0)
      fail_msg("%s:%d: unknown flag '%s' (known_bug, heavy)", MANIFEST, c->line, tok);
  }
}

static void read_manifest(void) {
  FILE *f = fopen(MANIFEST, "r");
  if (!f) fail_msg("cannot open %s (run from the source directory)", MANIFEST);
  char buf[2400];
  int line = 0;
  case_count = 0;
  while (fgets(buf, sizeof buf, f)) {
    ++line;
    size_t n = strlen(buf);
    if (n + 1 == sizeof buf) fail_msg("%s:%d: line too long", MANIFEST, line);
    while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == '\r')) buf[--n] = '\0';
    if (n == 0 || buf[0] == '#') continue;
    char *field[5] = {NULL, NULL, NULL, NULL, NULL};
    int nf = 0;
    for (char *s = buf; s && nf < 5; ++nf) {
      field[nf] = s;
      s = strchr(s, '\t');
      if (s) *s++ = '\0';
    }
    if (nf < 3 || !field[0][0] || !field[2][0])
      fail_msg("%s:%d: expected FILE<TAB>EXIT<TAB>EXPECTED[<TAB>FLAGS[<TAB>NOTE]]", MANIFEST, line);
    if (case_count == MAX_CASES) fail_msg("%s: more than %d cases", MANIFEST, MAX_CASES);
    corpus_case *c = &cases[case_count++];
    memset(c, 0, sizeof *c);
    c->line = line;
    copy_field(c->file, sizeof c->file, field[0], "FILE", line);
    char *end;
    long code = strtol(field[1], &end, 10);
    if (end == field[1] || *end || code < 0 || code > 255)
      fail_msg("%s:%d: EXIT '%s' is not an exit code", MANIFEST, line, field[1]);
    c->exit_code = (int)code;
    copy_field(c->expected, sizeof c->expected, field[2], "EXPECTED", line);
    if (field[3]) parse_flags(c, field[3]);
    if (field[4]) copy_field(c->note, sizeof c->note, field[4], "NOTE", line);
    for (int k = 0; k < case_count - 1; ++k)
      if (!strcmp(cases[k].file, c->file))
        fail_msg("%s:%d: %s is listed twice (also line %d)", MANIFEST, line, c->file,
                 cases[k].line);
  }
  fclose(f);
}

/* Every scene in the corpus folder must have its line in the manifest. */
static void check_all_listed(void) {
  DIR *d = opendir(CORPUS_DIR);
  if (!d) fail_msg("cannot open %s", CORPUS_DIR);
  struct dirent *e;
  while ((e = readdir(d))) {
    size_t n = strlen(e->d_name);
    if (n < 5 || strcmp(e->d_name + n - 5, ".json") != 0) continue;
    int listed = 0;
    for (int k = 0; k < case_count && !listed; ++k) listed = !strcmp(cases[k].file, e->d_name);
    if (!listed) fail_msg("%s/%s is not listed in %s", CORPUS_DIR, e->d_name, MANIFEST);
  }
  closedir(d);
}

/* ---- one case ------------------------------------------------------------------------- */

/* Does text contain the pieces of pattern (separated by " ... "), in this order? */
static int contains_in_order(const char *text, const char *pattern) {
  static const char sep[] = " ... ";
  const char *at = text;
  for (const char *p = pattern;;) {
    const char *next = strstr(p, sep);
    size_t len = next ? (size_t)(next - p) : strlen(p);
    char piece[sizeof cases[0].expected];
    memcpy(piece, p, len);
    piece[len] = '\0';
    const char *hit = strstr(at, piece);
    if (!hit) return 0;
    at = hit + len;
    if (!next) return 1;
    p = next + sizeof sep - 1;
  }
}

/* The first line of the output that says something (not a sanitizer's "====" rule),
 * shortened, for reports. */
static const char *output_head(void) {
  static char head[400];
  const char *line = output;
  while (*line == '=' || *line == '\n') line += strspn(line, "=\n");
  size_t n = strcspn(line, "\n");
  if (n > sizeof head - 8) n = sizeof head - 8;
  memcpy(head, line, n);
  snprintf(head + n, sizeof head - n, "%s", line[n] && line[n + 1] ? " [...]" : "");
  return n ? head : "(no output)";
}

/* Run `mpm ARGS` for case c under its time limit, and heavy cases under a memory limit.
 * MPM_MEMORY_LIMIT makes the program's own memory check (scene/memory_estimate.c) answer
 * the same on every machine. */
static int run_case_command(const corpus_case *c, const char *args) {
  const int limit = c->known_bug ? TIMEOUT_KNOWN_BUG_S : TIMEOUT_S;
  char env[200];
  if (c->heavy)
    snprintf(env, sizeof env, "ulimit -v %d; MPM_MEMORY_LIMIT=4G timeout %d", HEAVY_ULIMIT_KB,
             limit);
  else
    snprintf(env, sizeof env, "MPM_MEMORY_LIMIT=4G timeout %d", limit);
  return mpm_env(env, args);
}

/* What the last command got wrong, written to why; 0 when it did what c expects. */
static int judge(const corpus_case *c, const char *path, const char *cmd, int rc, char *why,
                 size_t cap) {
  if (rc == 124)
    snprintf(why, cap, "mpm %s did not finish within %d s (a hang?)", cmd,
             c->known_bug ? TIMEOUT_KNOWN_BUG_S : TIMEOUT_S);
  else if (rc > 128 && rc != c->exit_code)
    snprintf(why, cap, "mpm %s died of signal %d (a crash?), expected exit %d: %s", cmd, rc - 128,
             c->exit_code, output_head());
  else if (rc != c->exit_code)
    snprintf(why, cap, "mpm %s exited with %d, expected %d: %s", cmd, rc, c->exit_code,
             output_head());
  else if (!contains_in_order(output, c->expected))
    snprintf(why, cap, "mpm %s: expected '%s' in: %s", cmd, c->expected, output_head());
  else if (!strstr(output, path))
    snprintf(why, cap, "mpm %s: the message does not name the file %s: %s", cmd, path,
             output_head());
  else
    return 0;
  return -1;
}

/* Number of entries in a folder other than . and .., or -1 when it cannot be opened. */
static int folder_entries(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) ++n;
  closedir(d);
  return n;
}

/* 0 when case c behaves as listed, else -1 with the first problem in why. */
static int run_case(const corpus_case *c, int index, const char *tmp, char *why, size_t cap) {
  char path[600], out[700], args[1600];
  if (c->file[0] == '/')
    snprintf(path, sizeof path, "%s", c->file);
  else
    snprintf(path, sizeof path, "%s/%s", CORPUS_DIR, c->file);
  snprintf(args, sizeof args, "check '%s'", path);
  if (judge(c, path, "check", run_case_command(c, args), why, cap) < 0) return -1;
  snprintf(out, sizeof out, "%s/out%03d", tmp, index);
  snprintf(args, sizeof args, "run '%s' -o '%s' --frames 1 --quiet", path, out);
  if (judge(c, path, "run", run_case_command(c, args), why, cap) < 0) return -1;
  if (exists(out)) {
    int n = folder_entries(out);
    snprintf(why, cap, "mpm run created its output folder %s%s", out,
             n > 0 ? " and wrote into it" : " (empty) before refusing the scene");
    return -1;
  }
  return 0;
}

/* ---- the test ------------------------------------------------------------------------- */

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_corpus(void **state) {
  (void)state;
  const double t0 = now_s();
  read_manifest();
  check_all_listed();
  if (case_count < MIN_CASES)
    fail_msg("%s lists %d cases, expected at least %d", MANIFEST, case_count, MIN_CASES);
  const char *tmp = test_temp_dir("corpus");
  int passed = 0, known = 0, skipped = 0, failed = 0, fixed = 0;
  char why[1500];
  for (int i = 0; i < case_count; ++i) {
    const corpus_case *c = &cases[i];
    if (c->heavy && CORPUS_ASAN) { /* ulimit -v and AddressSanitizer's shadow memory clash */
      printf("SKIP       %s (heavy; not under AddressSanitizer)\n", c->file);
      ++skipped;
      continue;
    }
    if (run_case(c, i, tmp, why, sizeof why) == 0) {
      ++passed;
      if (c->known_bug) {
        printf("FIXED?     %s passes now: remove known_bug from %s:%d\n", c->file, MANIFEST,
               c->line);
        ++fixed;
      }
    } else if (c->known_bug) {
      printf("KNOWN BUG  %s: %s\n           now: %s\n", c->file, c->note, why);
      ++known;
    } else {
      printf("FAIL       %s (%s:%d): %s\n", c->file, MANIFEST, c->line, why);
      ++failed;
    }
  }
  printf("test_corpus: %d cases, %d passed, %d known bugs, %d skipped, %d failed (%.1f s)\n",
         case_count, passed, known, skipped, failed, now_s() - t0);
  if (fixed) printf("test_corpus: %d known bugs pass now; update the manifest\n", fixed);
  fflush(stdout);
  if (failed) fail_msg("%d corpus cases failed (see FAIL above)", failed);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_corpus),
  };
  return test_cleanup(cmocka_run_group_tests(tests, NULL, NULL));
}
