# forward: one pass, every light for every fragment; the baseline. Its
# fragment shader lives in shaders/common/ since the light probes use it too.
libsb_techinfo_a_SOURCES += %reldir%/forward_info.c
TECHNIQUE_GL_SOURCES += %reldir%/forward.c
