#ifndef SHADEBENCH_TERM_H
#define SHADEBENCH_TERM_H

/* What the client's log may do on the stream it writes to: a progress bar
 * that redraws its line on a terminal only, and verdicts in colour on a
 * terminal unless NO_COLOR is set (https://no-color.org) or TERM is
 * "dumb". Pipes and files (a CI log) get plain lines. Single-threaded. */

#include <stdbool.h>
#include <stdio.h>

bool term_is_tty(FILE *f);
bool term_color(FILE *f);

/* ANSI colours for a verdict word. */
#define TERM_GREEN "\033[1;32m"
#define TERM_RED "\033[1;31m"
#define TERM_YELLOW "\033[1;33m"
#define TERM_RESET "\033[0m"
/* Back to the line's start and clear it: a bar leaves nothing behind. */
#define TERM_CLEAR_LINE "\r\033[K"

#endif
