#define _POSIX_C_SOURCE 200809L
#include "client/term.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

bool term_is_tty(FILE *f)
{
    return isatty(fileno(f)) == 1;
}

bool term_color(FILE *f)
{
    const char *no = getenv("NO_COLOR"), *term = getenv("TERM");
    return term_is_tty(f) && !(no && *no) && !(term && !strcmp(term, "dumb"));
}
