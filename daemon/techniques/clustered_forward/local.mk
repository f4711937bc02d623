# clustered_forward: froxel light lists, a depth pre-pass, forward shading
# over each cluster's lights (seed 004); its work is
# daemon/techniques/shared/culled.c.
libsb_techinfo_a_SOURCES += %reldir%/clustered_forward_info.c %reldir%/clustered_forward_info.h
TECHNIQUE_GL_SOURCES += %reldir%/clustered_forward.c
