# clustered_deferred: froxel light lists, a g-buffer, one lighting pass over
# each cluster's lights (seed 004); its work is
# daemon/techniques/shared/culled.c.
libsb_techinfo_a_SOURCES += %reldir%/clustered_deferred_info.c %reldir%/clustered_deferred_info.h
TECHNIQUE_GL_SOURCES += %reldir%/clustered_deferred.c
