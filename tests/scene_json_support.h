/* scene_json_support.h - shared helpers of the JSON scene loader tests (test_scene_json,
 * test_scene_json_material, test_scene_json_shape): a valid scene in pieces to splice mistakes
 * into, and parse-and-expect helpers. Header only: each test program links support.c alone. */
#ifndef MPM_TEST_SCENE_JSON_SUPPORT_H
#define MPM_TEST_SCENE_JSON_SUPPORT_H

#include "support.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

/* Scenes are written with single quotes for readability; q() turns them into JSON. */
static inline char *q(const char *s) {
  static char buf[8192];
  size_t n = strlen(s);
  assert_true(n < sizeof buf);
  for (size_t i = 0; i <= n; ++i) buf[i] = s[i] == '\'' ? '"' : s[i];
  return buf;
}

#define DOMAIN "'domain': {'min': [0, 0, 0], 'max': [1, 1, 1], 'dx': 0.05}"
#define TIME "'time': {'end': 1}"
#define JELLO "{'name': 'jello', 'model': 'fixed_corotated', 'E': 1e5, 'nu': 0.3, 'density': 1000}"
#define STEEL "{'name': 'steel', 'model': 'neo_hookean', 'E': 2e11, 'nu': 0.28, 'density': 7800}"
#define MATS "'materials': [" JELLO ", " STEEL "]"
#define SPHERE "{'type': 'sphere', 'center': [0.5, 0.5, 0.5], 'radius': 0.1}"
#define BODY "{'shape': " SPHERE ", 'material': 'jello'}"
#define BODIES "'bodies': [" BODY "]"
/* A valid scene with one extra top-level member X spliced in (X starts with a comma). */
#define SCENE_WITH(X) "{" DOMAIN ", " TIME ", " MATS ", " BODIES X "}"

static const char *FILE_NAME = "scenes/x.json";

/* Parse and expect failure with `status`; every NULL-terminated needle must be in the
 * message, as must the file name. The scene must be left empty. */
static inline void expect_error(const char *json_single_quoted, mpm_status status, ...) {
  mpm_scene s;
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_scene_parse(q(json_single_quoted), FILE_NAME, &s, &err);
  if (st != status)
    fail_msg("status %d, expected %d; message: %s; input: %s", st, status, err.message,
             json_single_quoted);
  assert_int_equal(err.status, status);
  if (strncmp(err.message, "scenes/x.json: ", 15) != 0)
    fail_msg("message does not start with the file: %s", err.message);
  va_list ap;
  va_start(ap, status);
  for (const char *needle = va_arg(ap, const char *); needle; needle = va_arg(ap, const char *))
    if (!strstr(err.message, needle)) fail_msg("'%s' not in message: %s", needle, err.message);
  va_end(ap);
  assert_null(s.materials);
  assert_null(s.bodies);
  assert_null(s.colliders);
  assert_int_equal(s.material_count + s.body_count + s.collider_count, 0);
}

static inline void parse_ok(const char *json_single_quoted, mpm_scene *s) {
  mpm_error err;
  mpm_error_clear(&err);
  mpm_status st = mpm_scene_parse(q(json_single_quoted), FILE_NAME, s, &err);
  if (st != MPM_OK) fail_msg("unexpected error: %s", err.message);
}

static inline void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

#endif
