# taa: temporal anti-aliasing (jittered projection, motion vectors, a
# clamped history).
libsb_effects_a_SOURCES += %reldir%/taa_info.c %reldir%/taa_info.h
EFFECT_GL_SOURCES += %reldir%/taa.c
GLSL_FILES += %reldir%/taa.frag
