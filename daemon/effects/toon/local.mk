# toon: a colour ramp of a few levels plus outlines from depth and normal
# edges.
libsb_effects_a_SOURCES += %reldir%/toon_info.c %reldir%/toon_info.h
EFFECT_GL_SOURCES += %reldir%/toon.c
GLSL_FILES += %reldir%/toon.frag
