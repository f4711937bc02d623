#ifndef SHADEBENCH_SINGLE_PASS_H
#define SHADEBENCH_SINGLE_PASS_H

/* The hooks of a technique that draws every object once with scene.vert and
 * one fragment shader, in its one declared pass (the fragment shader says
 * how it shades). Render thread only. */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "daemon/techniques/technique.h"

/* Builds scene.vert with frag (the look's defines applied); label names the
 * program in errors and debug captures. */
bool single_pass_create(const struct technique_env *env, const char *label, const char *frag,
                        void **state, char *err, size_t errlen);
bool single_pass_render(void *state, const struct technique_env *env, int64_t frame, char *err,
                        size_t errlen);
void single_pass_destroy(void *state);

#endif
