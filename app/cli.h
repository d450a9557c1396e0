/* cli.h - the `mpm` program's commands. Exit codes: 0 success, 1 simulation failure,
 * 2 usage or input error. */
#ifndef MPM_APP_CLI_H
#define MPM_APP_CLI_H

enum { MPM_EXIT_OK = 0, MPM_EXIT_FAILURE = 1, MPM_EXIT_USAGE = 2 };

int mpm_cmd_run(int argc, char **argv);
int mpm_cmd_check(int argc, char **argv);
int mpm_cmd_bench(int argc, char **argv);
int mpm_cmd_render(int argc, char **argv); /* render.c */
int mpm_cmd_plot(int argc, char **argv);   /* plot.c */
int mpm_cmd_error(int argc, char **argv);  /* error.c */

/* The word of `known` (NULL-terminated) closest to `word` by edit distance, when it is close
 * enough to be a typing slip (at most 2 edits, and fewer than half the word); NULL otherwise.
 * For "did you mean" on mistyped options and commands. */
const char *mpm_cli_suggest(const char *word, const char *const *known);

/* "unknown option 'X'" for `cmd`, with "did you mean 'Y'?" when one of `known` is close. */
void mpm_cli_unknown_option(const char *cmd, const char *option, const char *const *known);

/* Parse a positive integer option value; prints an error naming the option on failure. */
int mpm_cli_parse_int(const char *opt, const char *value, int lo, int hi, int *out);

#endif
