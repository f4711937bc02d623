# tiled_deferred: a g-buffer, per-tile light lists, one lighting pass over
# each tile's lights (seed 003); its work is daemon/techniques/shared/culled.c.
libsb_techinfo_a_SOURCES += %reldir%/tiled_deferred_info.c %reldir%/tiled_deferred_info.h
TECHNIQUE_GL_SOURCES += %reldir%/tiled_deferred.c
