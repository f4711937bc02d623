#ifndef SHADEBENCH_SHADERS_H
#define SHADEBENCH_SHADERS_H

/* GLSL sources embedded at build time from shaders/ (see build-aux/embed-glsl.sh). */
struct shader_file {
    const char *name;
    const char *source;
};

extern const struct shader_file shader_files[];

#endif
