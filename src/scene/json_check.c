/* json_check.c - typed, checked access to a parsed JSON tree, with messages that name the
 * file and key path, say what was expected and what was found, and suggest the intended key
 * for a typo (edit distance with adjacent transpositions, "optimal string alignment").
 *
 * Locale: numbers are printed through snprintf and the decimal separator of whatever locale
 * is active is then replaced by '.', so messages read the same everywhere; all character
 * tests are plain ASCII comparisons (no <ctype.h>). See json_check.h for the contract. */
#include "scene/json_check.h"
#include "core/real.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- context and key path ------------------------------------------------------------- */

void mpm_json_ctx_init(mpm_json_ctx *c, const char *file, mpm_error *err) {
  c->file = file;
  c->err = err;
  c->path[0] = '\0';
  c->len = 0;
}

static void path_append(mpm_json_ctx *c, const char *text) {
  for (const char *s = text; *s && c->len + 1 < sizeof c->path; ++s) {
    unsigned char ch = (unsigned char)*s;
    c->path[c->len++] = (ch < 0x20 || ch == 0x7f) ? '?' : (char)ch;
  }
  c->path[c->len] = '\0';
}

size_t mpm_json_push_key(mpm_json_ctx *c, const char *key) {
  size_t old = c->len;
  if (c->len > 0) path_append(c, ".");
  path_append(c, key);
  return old;
}

size_t mpm_json_push_index(mpm_json_ctx *c, int index) {
  size_t old = c->len;
  char buf[24];
  snprintf(buf, sizeof buf, "[%d]", index);
  path_append(c, buf);
  return old;
}

void mpm_json_pop(mpm_json_ctx *c, size_t old_len) {
  c->len = old_len;
  c->path[old_len] = '\0';
}

static int vfail(mpm_json_ctx *c, mpm_status status, const char *fmt, va_list ap) {
  char msg[900];
  vsnprintf(msg, sizeof msg, fmt, ap);
  if (c->len > 0)
    mpm_error_set(c->err, status, "%s: %s: %s", c->file, c->path, msg);
  else
    mpm_error_set(c->err, status, "%s: %s", c->file, msg);
  return -1;
}

int mpm_json_fail(mpm_json_ctx *c, mpm_status status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(c, status, fmt, ap);
  va_end(ap);
  return -1;
}

int mpm_json_fail_at(mpm_json_ctx *c, const char *key, mpm_status status, const char *fmt, ...) {
  size_t old = mpm_json_push_key(c, key);
  va_list ap;
  va_start(ap, fmt);
  vfail(c, status, fmt, ap);
  va_end(ap);
  mpm_json_pop(c, old);
  return -1;
}

int mpm_json_missing(mpm_json_ctx *c, const char *key) {
  return mpm_json_fail(c, MPM_ERR_INVALID, "missing required key '%s'", key);
}

/* ---- describing values ---------------------------------------------------------------- */

static int is_digit(char ch) {
  return ch >= '0' && ch <= '9';
}

/* Shortest of "%.6g" .. "%.<max_prec>g" that reads back as v, with '.' as separator. */
static const char *format_prec(double v, int max_prec, char *buf, size_t cap) {
  if (isnan(v)) {
    snprintf(buf, cap, "nan");
    return buf;
  }
  if (isinf(v)) {
    snprintf(buf, cap, v > 0 ? "infinity" : "-infinity");
    return buf;
  }
  char tmp[64];
  for (int prec = 6; prec <= max_prec; ++prec) {
    snprintf(tmp, sizeof tmp, "%.*g", prec, v);
    if (strtod(tmp, NULL) == v) break; /* same locale as snprintf, so this round-trips */
  }
  /* Copy, turning the locale's decimal separator (whatever sits between the digits of the
     mantissa and is not a sign or exponent) into '.'. */
  size_t o = 0;
  int in_sep = 0;
  for (const char *s = tmp; *s && o + 1 < cap; ++s) {
    char ch = *s;
    if (is_digit(ch) || ch == '-' || ch == '+' || ch == 'e') {
      buf[o++] = ch;
      in_sep = 0;
    } else if (!in_sep) {
      buf[o++] = '.';
      in_sep = 1;
    }
  }
  buf[o] = '\0';
  return buf;
}

const char *mpm_json_format_number(double v, char *buf, size_t cap) {
  return format_prec(v, 17, buf, cap);
}

/* Every number node of a tree that is the caller's becomes a raw node holding its exact text. */
static int numbers_to_raw(cJSON *node) {
  for (; node; node = node->next) {
    if (cJSON_IsNumber(node)) {
      char buf[64];
      if (isfinite(node->valuedouble))
        mpm_json_format_number(node->valuedouble, buf, sizeof buf);
      else
        snprintf(buf, sizeof buf, "null");
      const size_t n = strlen(buf) + 1;
      char *text = cJSON_malloc(n);
      if (!text) return -1;
      memcpy(text, buf, n);
      node->type = cJSON_Raw;
      node->valuestring = text; /* cJSON_Delete frees it */
    } else if (numbers_to_raw(node->child) < 0) {
      return -1;
    }
  }
  return 0;
}

char *mpm_json_print_exact(const cJSON *root, int formatted) {
  cJSON *copy = cJSON_Duplicate(root, 1);
  if (!copy) return NULL;
  char *text = NULL;
  if (numbers_to_raw(copy) == 0)
    text = formatted ? cJSON_Print(copy) : cJSON_PrintUnformatted(copy);
  cJSON_Delete(copy);
  return text;
}

const char *mpm_json_format_short(double v, char *buf, size_t cap) {
  return format_prec(v, 10, buf, cap);
}

const char *mpm_json_describe(const cJSON *node, char *buf, size_t cap) {
  char num[48];
  if (!node) {
    snprintf(buf, cap, "nothing");
  } else if (cJSON_IsFalse(node)) {
    snprintf(buf, cap, "false");
  } else if (cJSON_IsTrue(node)) {
    snprintf(buf, cap, "true");
  } else if (cJSON_IsNull(node)) {
    snprintf(buf, cap, "null");
  } else if (cJSON_IsNumber(node)) {
    snprintf(buf, cap, "a number (%s)", mpm_json_format_number(node->valuedouble, num, sizeof num));
  } else if (cJSON_IsString(node)) {
    const char *s = node->valuestring ? node->valuestring : "";
    size_t n = strlen(s);
    if (n > 40)
      snprintf(buf, cap, "a string ('%.40s...')", s);
    else
      snprintf(buf, cap, "a string ('%s')", s);
  } else if (cJSON_IsArray(node)) {
    int n = cJSON_GetArraySize(node);
    if (n == 0)
      snprintf(buf, cap, "an empty array");
    else
      snprintf(buf, cap, "an array of %d element%s", n, n == 1 ? "" : "s");
  } else if (cJSON_IsObject(node)) {
    snprintf(buf, cap, "an object");
  } else {
    snprintf(buf, cap, "an unreadable value");
  }
  return buf;
}

/* " > 0 (Pa)", " in [2, 16]", or just " (m)". */
static const char *range_tail(const mpm_json_range *r, char *buf, size_t cap) {
  char lo[48], hi[48];
  mpm_json_format_short(r->lo, lo, sizeof lo);
  mpm_json_format_short(r->hi, hi, sizeof hi);
  char body[128] = "";
  if (r->lo_kind && r->hi_kind)
    snprintf(body, sizeof body, " in %c%s, %s%c", r->lo_kind, lo, hi, r->hi_kind);
  else if (r->lo_kind)
    snprintf(body, sizeof body, " %s %s", r->lo_kind == '(' ? ">" : ">=", lo);
  else if (r->hi_kind)
    snprintf(body, sizeof body, " %s %s", r->hi_kind == ')' ? "<" : "<=", hi);
  if (r->note)
    snprintf(buf, cap, "%s (%s)", body, r->note);
  else
    snprintf(buf, cap, "%s", body);
  return buf;
}

const char *mpm_json_describe_range(const mpm_json_range *r, int integer, char *buf, size_t cap) {
  char tail[256];
  snprintf(buf, cap, "%s%s", integer ? "an integer" : "a number", range_tail(r, tail, sizeof tail));
  return buf;
}

int mpm_json_in_range(const mpm_json_range *r, double v) {
  if (r->lo_kind == '(' && !(v > r->lo)) return 0;
  if (r->lo_kind == '[' && !(v >= r->lo)) return 0;
  if (r->hi_kind == ')' && !(v < r->hi)) return 0;
  if (r->hi_kind == ']' && !(v <= r->hi)) return 0;
  return 1;
}

/* ---- did you mean --------------------------------------------------------------------- */

static char lower(char ch) {
  return (ch >= 'A' && ch <= 'Z') ? (char)(ch - 'A' + 'a') : ch;
}

int mpm_json_edit_distance(const char *a, const char *b) {
  enum { N = 64 };
  size_t n = strlen(a), m = strlen(b);
  if (n >= N) n = N - 1;
  if (m >= N) m = N - 1;
  int d[N][N];
  for (size_t i = 0; i <= n; ++i) d[i][0] = (int)i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = (int)j;
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      int cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      int best = d[i - 1][j - 1] + cost;
      if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1]) && d[i - 2][j - 2] + 1 < best)
        best = d[i - 2][j - 2] + 1;
      d[i][j] = best;
    }
  }
  return d[n][m];
}

const char *mpm_json_suggest(const char *word, const char *const *names) {
  size_t len = strlen(word);
  /* how many edits still look like a typo of a word this long */
  int limit = len <= 2 ? 1 : len <= 5 ? 1 : len <= 12 ? 2 : 3;
  const char *best = NULL;
  int best_d = limit + 1;
  for (const char *const *n = names; *n; ++n) {
    int d = mpm_json_edit_distance(word, *n);
    if (d < best_d && (size_t)d < (len > strlen(*n) ? len : strlen(*n))) {
      best_d = d;
      best = *n;
    }
  }
  return best;
}

static void join_names(const char *const *names, char *buf, size_t cap) {
  size_t o = 0;
  buf[0] = '\0';
  for (const char *const *n = names; *n; ++n) {
    int w = snprintf(buf + o, cap - o, "%s%s", n == names ? "" : ", ", *n);
    if (w < 0 || (size_t)w >= cap - o) break;
    o += (size_t)w;
  }
}

/* ---- objects and keys ----------------------------------------------------------------- */

const cJSON *mpm_json_get(const cJSON *obj, const char *key) {
  if (!obj) return NULL;
  for (const cJSON *ch = obj->child; ch; ch = ch->next)
    if (ch->string && strcmp(ch->string, key) == 0) return ch;
  return NULL;
}

int mpm_json_check_keys(mpm_json_ctx *c, const cJSON *obj, const char *const *allowed,
                        const char *what) {
  for (const cJSON *ch = obj->child; ch; ch = ch->next) {
    const char *key = ch->string ? ch->string : "";
    int known = 0;
    for (const char *const *a = allowed; *a; ++a)
      if (strcmp(*a, key) == 0) known = 1;
    if (!known) {
      const char *hint = mpm_json_suggest(key, allowed);
      const char *sep = what ? " " : "";
      const char *qual = what ? what : "";
      if (hint)
        return mpm_json_fail_at(
            c, key, MPM_ERR_INVALID, "unknown key%s%s; did you mean '%s'?%s", sep, qual, hint,
            mpm_json_edit_distance(key, hint) == 0 ? " (keys are case-sensitive)" : "");
      char list[600];
      join_names(allowed, list, sizeof list);
      return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "unknown key%s%s; allowed keys: %s", sep,
                              qual, list);
    }
    for (const cJSON *prev = obj->child; prev != ch; prev = prev->next)
      if (prev->string && strcmp(prev->string, key) == 0)
        return mpm_json_fail_at(c, key, MPM_ERR_INVALID,
                                "duplicate key; each key may appear only once in an object");
  }
  return 0;
}

int mpm_json_expect_object(mpm_json_ctx *c, const cJSON *node, const char *what) {
  if (cJSON_IsObject(node)) return 0;
  char got[96];
  return mpm_json_fail(c, MPM_ERR_INVALID, "expected %s, got %s", what,
                       mpm_json_describe(node, got, sizeof got));
}

/* ---- typed getters -------------------------------------------------------------------- */

/* Check the node at the current path against a range; integer: must be a whole number. */
static int check_number(mpm_json_ctx *c, const cJSON *node, const mpm_json_range *r, int integer,
                        double *out) {
  char want[300], got[96];
  mpm_json_describe_range(r, integer, want, sizeof want);
  if (!cJSON_IsNumber(node))
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected %s, got %s", want,
                         mpm_json_describe(node, got, sizeof got));
  double v = node->valuedouble;
  if (!isfinite(v))
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected %s, got a number too large to represent (it overflows to %s)",
                         want, v > 0 ? "infinity" : "-infinity");
  if (integer && (v != floor(v) || fabs(v) > 9007199254740992.0))
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected %s, got %s", want,
                         mpm_json_format_number(v, got, sizeof got));
  if (!mpm_json_in_range(r, v))
    return mpm_json_fail(c, MPM_ERR_INVALID, "expected %s, got %s", want,
                         mpm_json_format_number(v, got, sizeof got));
  /* the float build's particles and grid hold values up to FLT_MAX: a density, velocity or
     temperature past it is infinite from the first frame on */
  if (sizeof(mpm_real) == 4 && fabs(v) > FLT_MAX)
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected %s, got %s: past the largest number of the float build "
                         "(3.4e38; the double build, make build-double, holds it)",
                         want, mpm_json_format_number(v, got, sizeof got));
  *out = v;
  return 0;
}

int mpm_json_number(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                    mpm_json_range range, double *out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  size_t old = mpm_json_push_key(c, key);
  int r = check_number(c, n, &range, 0, out);
  mpm_json_pop(c, old);
  return r < 0 ? -1 : 1;
}

int mpm_json_integer(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                     mpm_json_range range, long long *out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  size_t old = mpm_json_push_key(c, key);
  double v = 0;
  int r = check_number(c, n, &range, 1, &v);
  mpm_json_pop(c, old);
  if (r < 0) return -1;
  *out = (long long)v;
  return 1;
}

int mpm_json_bool(mpm_json_ctx *c, const cJSON *obj, const char *key, int required, int *out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  if (!cJSON_IsBool(n)) {
    char got[96];
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected true or false, got %s",
                            mpm_json_describe(n, got, sizeof got));
  }
  *out = cJSON_IsTrue(n) ? 1 : 0;
  return 1;
}

int mpm_json_string(mpm_json_ctx *c, const cJSON *obj, const char *key, int required, char *out,
                    size_t cap) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  char got[96];
  if (!cJSON_IsString(n) || !n->valuestring)
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected a string, got %s",
                            mpm_json_describe(n, got, sizeof got));
  size_t len = strlen(n->valuestring);
  if (len == 0)
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected a non-empty string, got ''");
  if (len >= cap)
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID,
                            "expected a string of at most %zu bytes, got one of %zu bytes", cap - 1,
                            len);
  memcpy(out, n->valuestring, len + 1);
  return 1;
}

int mpm_json_enum(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                  const char *const *names, int *out) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  char list[300], got[96];
  join_names(names, list, sizeof list);
  if (!cJSON_IsString(n) || !n->valuestring)
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected one of %s, got %s", list,
                            mpm_json_describe(n, got, sizeof got));
  for (int i = 0; names[i]; ++i)
    if (strcmp(names[i], n->valuestring) == 0) {
      *out = i;
      return 1;
    }
  const char *hint = mpm_json_suggest(n->valuestring, names);
  char suffix[96] = "";
  if (hint) snprintf(suffix, sizeof suffix, "; did you mean '%s'?", hint);
  return mpm_json_fail_at(c, key, MPM_ERR_INVALID, "expected one of %s, got '%.60s'%s", list,
                          n->valuestring, suffix);
}

int mpm_json_vec3(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                  mpm_json_range range, double out[3]) {
  const cJSON *n = mpm_json_get(obj, key);
  if (!n) return required ? mpm_json_missing(c, key) : 0;
  size_t old = mpm_json_push_key(c, key);
  char tail[256], got[96];
  if (!cJSON_IsArray(n) || cJSON_GetArraySize(n) != 3) {
    mpm_json_fail(c, MPM_ERR_INVALID, "expected an array of 3 numbers%s, got %s",
                  range_tail(&range, tail, sizeof tail), mpm_json_describe(n, got, sizeof got));
    mpm_json_pop(c, old);
    return -1;
  }
  double v[3];
  int i = 0;
  for (const cJSON *e = n->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    int r = check_number(c, e, &range, 0, &v[i]);
    mpm_json_pop(c, o2);
    if (r < 0) {
      mpm_json_pop(c, old);
      return -1;
    }
  }
  mpm_json_pop(c, old);
  for (int d = 0; d < 3; ++d) out[d] = v[d];
  return 1;
}

int mpm_json_direction(mpm_json_ctx *c, const cJSON *obj, const char *key, int required,
                       double out[3]) {
  double v[3];
  int r = mpm_json_vec3(c, obj, key, required, mpm_json_any(NULL), v);
  if (r <= 0) return r;
  double s = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
  if (!(s > 0) || !isfinite(s))
    return mpm_json_fail_at(c, key, MPM_ERR_INVALID,
                            "expected a nonzero direction vector, got [0, 0, 0]");
  double u[3] = {v[0] / s, v[1] / s, v[2] / s};
  double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (int d = 0; d < 3; ++d) out[d] = u[d] / len;
  return 1;
}
