# visibility_buffer: triangle and instance ids and depth per pixel, then
# one shading pass that fetches the triangle's vertices, rebuilds its
# attributes and their screen derivatives and shades with the lighting
# library (Burns and Hunt 2013).
libsb_techinfo_a_SOURCES += %reldir%/visibility_buffer_info.c %reldir%/visibility_buffer_info.h
TECHNIQUE_GL_SOURCES += %reldir%/visibility_buffer.c
GLSL_FILES += \
	%reldir%/vis_ids.frag \
	%reldir%/vis_key.vert \
	%reldir%/vis_fetch.glsl \
	%reldir%/vis_edges.frag \
	%reldir%/vis_classify.frag \
	%reldir%/vis_shade.frag
