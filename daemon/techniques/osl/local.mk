# osl: object space lighting (the thesis's OSLProg), with its async schedule
# and shading atlas (GL-free, unit-tested) and its shaders.
libsb_techinfo_a_SOURCES += \
	%reldir%/osl_info.c %reldir%/osl_info.h \
	%reldir%/osl_schedule.c %reldir%/osl_schedule.h \
	%reldir%/osl_atlas.c %reldir%/osl_atlas.h
TECHNIQUE_GL_SOURCES += %reldir%/osl.c %reldir%/osl_gl.h %reldir%/osl_texgen.c \
	%reldir%/osl_seen.c %reldir%/osl_describe.c
GLSL_FILES += \
	%reldir%/osl_texgen.vert \
	%reldir%/osl_texgen.frag \
	%reldir%/osl_light.comp \
	%reldir%/osl_select.comp \
	%reldir%/osl_draw.vert \
	%reldir%/osl_draw.frag
