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

/* Parse a positive integer option value; prints an error naming the option on failure. */
int mpm_cli_parse_int(const char *opt, const char *value, int lo, int hi, int *out);

#endif
