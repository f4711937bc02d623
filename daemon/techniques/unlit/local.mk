# unlit: forward's geometry and passes without lighting, the cost floor.
libsb_techinfo_a_SOURCES += %reldir%/unlit_info.c
TECHNIQUE_GL_SOURCES += %reldir%/unlit.c
GLSL_FILES += %reldir%/unlit.frag
