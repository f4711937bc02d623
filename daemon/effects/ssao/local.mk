# ssao: screen-space ambient occlusion, blurred, multiplied into the colour.
libsb_effects_a_SOURCES += %reldir%/ssao_info.c %reldir%/ssao_info.h
EFFECT_GL_SOURCES += %reldir%/ssao.c
GLSL_FILES += \
	%reldir%/ssao.frag \
	%reldir%/ssao_apply.frag
