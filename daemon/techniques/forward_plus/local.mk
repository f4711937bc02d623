# forward_plus: a depth pre-pass, per-tile light lists, forward shading over
# each tile's lights; its work is daemon/techniques/shared/culled.c.
libsb_techinfo_a_SOURCES += %reldir%/forward_plus_info.c %reldir%/forward_plus_info.h
TECHNIQUE_GL_SOURCES += %reldir%/forward_plus.c
