# deferred: a g-buffer, then each light added over the pixels its bound
# covers (seed 001).
libsb_techinfo_a_SOURCES += %reldir%/deferred_info.c %reldir%/deferred_info.h
TECHNIQUE_GL_SOURCES += %reldir%/deferred.c
GLSL_FILES += \
	%reldir%/deferred_ambient.frag \
	%reldir%/deferred_light.vert \
	%reldir%/deferred_light.frag
