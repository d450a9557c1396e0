/* json_check.h - typed, checked access to a parsed JSON tree for the scene loader.
 *
 * Every getter knows the key path of the value it reads (kept in the context as the loader
 * descends: "bodies[2].shape.center") and, on a mistake, writes one message of the form
 *   "<file>: <key path>: expected <what>, got <what was found>"
 * and returns -1. Unknown keys are reported with a did-you-mean suggestion chosen by edit
 * distance, or with the list of allowed keys. Nothing here depends on the C locale: numbers
 * are printed with '.' whatever LC_NUMERIC says, and names are compared byte by byte.
 * Internal to src/scene; not part of the public API. */
#ifndef MPM_SCENE_JSON_CHECK_H
#define MPM_SCENE_JSON_CHECK_H

#include "core/error.h"

#include <cjson/cJSON.h>
#include <stddef.h>

/* Where the loader is: the file named in messages, the error to fill and the key path. */
typedef struct mpm_json_ctx {
  const char *file;
  mpm_error *err;
  char path[512];
  size_t len;
} mpm_json_ctx;

/* A closed/open interval for a number, printed in messages as "> 0", "in (0, 1]" or
 * "in [2, 16]". lo_kind is '(' (exclusive), '[' (inclusive) or 0 (unbounded); hi_kind is ')',
 * ']' or 0. note (may be NULL) is printed in parentheses after the range: the unit, and
 * anything else the reader needs ("m, at most dx"). */
typedef struct mpm_json_range {
  char lo_kind, hi_kind;
  double lo, hi;
  const char *note;
} mpm_json_range;

static inline mpm_json_range mpm_json_any(const char *note) {
  mpm_json_range r = {0, 0, 0.0, 0.0, note};
  return r;
}
static inline mpm_json_range mpm_json_gt(double lo, const char *note) {
  mpm_json_range r = {'(', 0, lo, 0.0, note};
  return r;
}
static inline mpm_json_range mpm_json_ge(double lo, const char *note) {
  mpm_json_range r = {'[', 0, lo, 0.0, note};
  return r;
}
static inline mpm_json_range mpm_json_in(char lo_kind, double lo, double hi, char hi_kind,
                                         const char *note) {
  mpm_json_range r = {lo_kind, hi_kind, lo, hi, note};
  return r;
}

void mpm_json_ctx_init(mpm_json_ctx *c, const char *file, mpm_error *err);

/* Descend into ".key" or "[index]"; each returns the previous length for mpm_json_pop. */
size_t mpm_json_push_key(mpm_json_ctx *c, const char *key);
size_t mpm_json_push_index(mpm_json_ctx *c, int index);
void mpm_json_pop(mpm_json_ctx *c, size_t old_len);

/* Write "<file>: <path>: <message>" (just "<file>: <message>" at the top level) with the
 * given status; returns -1. The _at variant names `key` below the current path. */
int mpm_json_fail(mpm_json_ctx *c, mpm_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int mpm_json_fail_at(mpm_json_ctx *c, const char *key, mpm_status status, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* "a string ('abc')", "a number (5)", "true", "null", "an array of 2 elements", ... */
const char *mpm_json_describe(const cJSON *node, char *buf, size_t cap);
/* Shortest text that reads back as v, always with '.' as the decimal point. */
const char *mpm_json_format_number(double v, char *buf, size_t cap);
/* The same with at most 10 significant digits, for derived values (0.15, not
 * 0.15000000000000002); range bounds are printed this way. */
const char *mpm_json_format_short(double v, char *buf, size_t cap);
/* "a number > 0 (Pa)" or "an integer in [2, 16]". */
const char *mpm_json_describe_range(const mpm_json_range *r, int integer, char *buf, size_t cap);
int mpm_json_in_range(const mpm_json_range *r, double v);

/* Edit distance (insertions, deletions, substitutions, adjacent transpositions; ASCII case
 * differences cost nothing) and the closest name of a NULL-terminated list, or NULL when
 * none is close enough to be a plausible typo. */
int mpm_json_edit_distance(const char *a, const char *b);
const char *mpm_json_suggest(const char *word, const char *const *names);

/* The first member of obj named exactly `key` (case-sensitive), or NULL. */
const cJSON *mpm_json_get(const cJSON *obj, const char *key);

/* Reject duplicate keys and keys outside `allowed` (NULL-terminated) in the object at the
 * current path. `what` (may be NULL) qualifies "unknown key" ("for a box shape"). */
int mpm_json_check_keys(mpm_json_ctx *c, const cJSON *obj, const char *const *allowed,
                        const char *what);

/* The node at the current path must be an object; `what` names it ("a material object"). */
int mpm_json_expect_object(mpm_json_ctx *c, const cJSON *node, const char *what);

/* Typed getters for obj[key]. They return 1 when the key was present and valid (the value
 * written to *out), 0 when it is absent and not required (*out untouched), -1 on a mistake
 * (message written), including a missing required key. */
int mpm_json_number(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                    mpm_json_range range, double *out);
int mpm_json_integer(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                     mpm_json_range range, long long *out);
int mpm_json_bool(mpm_json_ctx *c, const cJSON *obj, const char *key, int required, int *out);
/* A non-empty string of at most cap - 1 bytes. */
int mpm_json_string(mpm_json_ctx *c, const cJSON *obj, const char *key, int required, char *out,
                    size_t cap);
/* One of the NULL-terminated `names`; *out is its index. */
int mpm_json_enum(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                  const char *const *names, int *out);
/* An array of exactly 3 finite numbers, each in `range`. */
int mpm_json_vec3(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                  mpm_json_range range, double out[3]);
/* A nonzero 3-vector, normalised. */
int mpm_json_direction(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                       double out[3]);

/* Check text[0, len) against the strict JSON grammar (json_syntax.c). On a mistake write
 * "line L, column C: JSON syntax error near 'x': expected ..." with a hint for the usual slips
 * (trailing or missing comma, comments, single quotes), status MPM_ERR_PARSE, and return -1. */
int mpm_json_check_syntax(mpm_json_ctx *c, const char *text, size_t len);
/* The same for text that cJSON refused at `at` (its return_parse_end; NULL: the end). */
void mpm_json_syntax_error(mpm_json_ctx *c, const char *text, size_t len, const char *at);

/* The tree as JSON text (indented when `formatted`) with every number in its shortest exact form:
 * cJSON's own printer writes 15 digits and accepts them within an epsilon, which can be one bit
 * off, so a scene printed by it could run differently from the one it was printed from. A
 * non-finite number is written as null. The text is cJSON's (free it with cJSON_free); NULL when
 * out of memory. */
char *mpm_json_print_exact(const cJSON *root, int formatted);

/* "missing required key 'key'" at the current path; returns -1. */
int mpm_json_missing(mpm_json_ctx *c, const char *key);

#endif
