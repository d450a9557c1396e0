/* json_syntax.c - where and why a JSON text is malformed, for the scene loader's messages.
 *
 * cJSON builds the tree, but it is lenient (it takes raw newlines inside strings and leading
 * zeros) and its error pointer is only roughly at a mistake (often one byte past it) and says
 * nothing about what was expected. So the text is first read by a small strict
 * recursive-descent checker of the JSON grammar (RFC 8259) that stops at the first offending
 * byte and knows what it wanted there ("',' or '}' after an object member"). The message
 * gives line and column (1-based, columns in bytes), the token found and, for the usual
 * slips, a hint: trailing or missing commas, comments, single quotes, raw newlines in
 * strings, unescaped backslashes. If cJSON still fails on text the checker accepted (it ran
 * out of memory, say), cJSON's own position is reported. */
#include "scene/json_check.h"

#include <stdio.h>
#include <string.h>

#define MAX_DEPTH 1000 /* cJSON's CJSON_NESTING_LIMIT */

typedef struct scan {
  const char *s;
  size_t len, pos;
  const char *expect; /* what was wanted at pos when the scan failed */
  const char *hint;   /* a likely cause, or "" */
  int depth;
} scan;

static int fail(scan *sc, const char *expect, const char *hint) {
  sc->expect = expect;
  sc->hint = hint ? hint : "";
  return -1;
}

static int is_ws(char ch) {
  return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r';
}
static int is_digit(char ch) {
  return ch >= '0' && ch <= '9';
}
static int is_hex(char ch) {
  return is_digit(ch) || (ch >= 'a' && ch <= 'f') || (ch >= 'A' && ch <= 'F');
}

static void skip_ws(scan *sc) {
  while (sc->pos < sc->len && is_ws(sc->s[sc->pos])) ++sc->pos;
}

static char peek(const scan *sc) {
  return sc->pos < sc->len ? sc->s[sc->pos] : '\0';
}

static int scan_value(scan *sc);

static int scan_string(scan *sc) {
  ++sc->pos; /* opening quote */
  for (;;) {
    if (sc->pos >= sc->len) return fail(sc, "a closing '\"' of the string", NULL);
    char ch = sc->s[sc->pos];
    if (ch == '"') {
      ++sc->pos;
      return 0;
    }
    if ((unsigned char)ch < 0x20)
      return fail(sc, "a closing '\"' before the end of the line",
                  " (strings cannot span lines; write \\n for a newline)");
    if (ch == '\\') {
      ++sc->pos;
      char e = peek(sc);
      if (e == 'u') {
        for (int k = 1; k <= 4; ++k)
          if (sc->pos + (size_t)k >= sc->len || !is_hex(sc->s[sc->pos + (size_t)k])) {
            sc->pos += (size_t)k;
            return fail(sc, "four hex digits after \\u", NULL);
          }
        if (!strncmp(sc->s + sc->pos + 1, "0000", 4)) /* cJSON would cut the string there */
          return fail(sc, "a character other than \\u0000 (NUL)",
                      " (strings cannot contain NUL; it would silently cut them short)");
        sc->pos += 5;
        continue;
      }
      if (!e || !strchr("\"\\/bfnrt", e))
        return fail(sc, "an escape: one of \\\" \\\\ \\/ \\b \\f \\n \\r \\t \\uXXXX",
                    " (write \\\\ for a backslash, e.g. in Windows paths)");
    }
    ++sc->pos;
  }
}

static int scan_number(scan *sc) {
  if (peek(sc) == '-') ++sc->pos;
  if (peek(sc) == '0') {
    ++sc->pos;
    if (is_digit(peek(sc))) return fail(sc, "no leading zeros in a number", NULL);
  } else if (is_digit(peek(sc))) {
    while (is_digit(peek(sc))) ++sc->pos;
  } else {
    return fail(sc, "a digit", NULL);
  }
  if (peek(sc) == '.') {
    ++sc->pos;
    if (!is_digit(peek(sc))) return fail(sc, "a digit after the decimal point", NULL);
    while (is_digit(peek(sc))) ++sc->pos;
  }
  if (peek(sc) == 'e' || peek(sc) == 'E') {
    ++sc->pos;
    if (peek(sc) == '+' || peek(sc) == '-') ++sc->pos;
    if (!is_digit(peek(sc))) return fail(sc, "a digit in the exponent", NULL);
    while (is_digit(peek(sc))) ++sc->pos;
  }
  return 0;
}

static int scan_literal(scan *sc, const char *word) {
  size_t n = strlen(word);
  if (sc->len - sc->pos < n || memcmp(sc->s + sc->pos, word, n) != 0)
    return fail(sc, "a value (a string, number, object, array, true, false or null)", NULL);
  sc->pos += n;
  return 0;
}

/* A comma was just passed when `after_comma`; a closing bracket then is a trailing comma. */
static int scan_object(scan *sc) {
  ++sc->pos;
  skip_ws(sc);
  if (peek(sc) == '}') {
    ++sc->pos;
    return 0;
  }
  int after_comma = 0;
  for (;;) {
    skip_ws(sc);
    char ch = peek(sc);
    if (ch != '"') {
      const char *hint = ch == '}' && after_comma ? " (a trailing comma before it?)"
                         : ch == '\''             ? " (JSON strings use double quotes)"
                         : ch == '/'              ? " (JSON does not allow comments)"
                                                  : " (keys must be quoted)";
      return fail(sc, "a key in double quotes", hint);
    }
    if (scan_string(sc) < 0) return -1;
    skip_ws(sc);
    if (peek(sc) != ':') return fail(sc, "':' after the key", NULL);
    ++sc->pos;
    if (scan_value(sc) < 0) return -1;
    skip_ws(sc);
    ch = peek(sc);
    if (ch == ',') {
      ++sc->pos;
      after_comma = 1;
      continue;
    }
    if (ch == '}') {
      ++sc->pos;
      return 0;
    }
    return fail(sc, "',' or '}' after an object member",
                ch == '"'   ? " (a missing comma before it?)"
                : ch == '/' ? " (JSON does not allow comments)"
                            : NULL);
  }
}

static int scan_array(scan *sc) {
  ++sc->pos;
  skip_ws(sc);
  if (peek(sc) == ']') {
    ++sc->pos;
    return 0;
  }
  for (;;) {
    if (scan_value(sc) < 0) return -1;
    skip_ws(sc);
    char ch = peek(sc);
    if (ch == ',') {
      ++sc->pos;
      skip_ws(sc);
      if (peek(sc) == ']') return fail(sc, "a value", " (a trailing comma before it?)");
      continue;
    }
    if (ch == ']') {
      ++sc->pos;
      return 0;
    }
    return fail(sc, "',' or ']' after an array element",
                (ch == '"' || ch == '-' || is_digit(ch) || ch == '{' || ch == '[')
                    ? " (a missing comma before it?)"
                    : NULL);
  }
}

static int scan_value(scan *sc) {
  skip_ws(sc);
  char ch = peek(sc);
  if (sc->pos >= sc->len) return fail(sc, "a value", NULL);
  int r;
  switch (ch) {
  case '{':
  case '[':
    if (++sc->depth > MAX_DEPTH) return fail(sc, "at most 1000 levels of nesting", NULL);
    r = ch == '{' ? scan_object(sc) : scan_array(sc);
    --sc->depth;
    return r;
  case '"':
    return scan_string(sc);
  case 't':
    return scan_literal(sc, "true");
  case 'f':
    return scan_literal(sc, "false");
  case 'n':
    return scan_literal(sc, "null");
  default:
    if (ch == '-' || is_digit(ch)) return scan_number(sc);
    return fail(sc, "a value (a string, number, object, array, true, false or null)",
                ch == '\''                 ? " (JSON strings use double quotes)"
                : ch == '/'                ? " (JSON does not allow comments)"
                : (ch == ']' || ch == '}') ? " (a trailing comma before it?)"
                                           : NULL);
  }
}

/* 0 when the whole text is one JSON value; otherwise -1 with sc->pos at the mistake. */
static int scan_text(scan *sc) {
  if (sc->len >= 3 && (unsigned char)sc->s[0] == 0xEF && (unsigned char)sc->s[1] == 0xBB &&
      (unsigned char)sc->s[2] == 0xBF)
    sc->pos = 3; /* UTF-8 byte order mark, skipped by cJSON too */
  if (scan_value(sc) < 0) return -1;
  skip_ws(sc);
  if (sc->pos < sc->len)
    return fail(sc, "the end of the file after the top-level value",
                peek(sc) == ',' || peek(sc) == '{' || peek(sc) == '"'
                    ? " (the whole scene must be one object)"
                    : NULL);
  return 0;
}

/* "line L, column C: JSON syntax error near 'x': expected ... (hint)" for the byte at pos. */
static int report(mpm_json_ctx *c, const char *text, size_t len, size_t pos, const char *expect,
                  const char *hint) {
  int line = 1, col = 1;
  for (size_t i = 0; i < pos && i < len; ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  char want[200] = "";
  if (expect) snprintf(want, sizeof want, ": expected %s", expect);
  if (pos >= len)
    return mpm_json_fail(c, MPM_ERR_PARSE,
                         "line %d, column %d: JSON syntax error: unexpected end of the file%s%s",
                         line, col, want, expect ? " (a missing '}' or ']'?)" : "");
  /* the token at the mistake: a word, or one character */
  char near[48];
  size_t n = 0;
  for (size_t i = pos; i < len && n + 1 < sizeof near; ++i) {
    char ch = text[i];
    int word = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || is_digit(ch) || ch == '_' ||
               ch == '-' || ch == '+' || ch == '.';
    if (n > 0 && !word) break;
    near[n++] = ch;
    if (!word) break;
  }
  near[n] = '\0';
  char where[64];
  if (text[pos] == '\n' || text[pos] == '\r')
    snprintf(where, sizeof where, "at the end of the line");
  else if ((unsigned char)text[pos] < 0x20)
    snprintf(where, sizeof where, "at control character %d", (int)(unsigned char)text[pos]);
  else
    snprintf(where, sizeof where, "near '%s'", near);
  return mpm_json_fail(c, MPM_ERR_PARSE, "line %d, column %d: JSON syntax error %s%s%s", line, col,
                       where, want, hint ? hint : "");
}

static int is_blank(const char *text, size_t len) {
  for (size_t i = 0; i < len; ++i)
    if (!is_ws(text[i])) return 0;
  return 1;
}

int mpm_json_check_syntax(mpm_json_ctx *c, const char *text, size_t len) {
  if (is_blank(text, len))
    return mpm_json_fail(c, MPM_ERR_PARSE, "the file is empty; expected a JSON object");
  scan sc = {text, len, 0, NULL, "", 0};
  if (scan_text(&sc) == 0) return 0;
  return report(c, text, len, sc.pos, sc.expect, sc.hint);
}

void mpm_json_syntax_error(mpm_json_ctx *c, const char *text, size_t len, const char *at) {
  if (mpm_json_check_syntax(c, text, len) < 0) return;
  size_t pos = (at && at >= text && (size_t)(at - text) <= len) ? (size_t)(at - text) : len;
  report(c, text, len, pos, NULL, NULL);
}
