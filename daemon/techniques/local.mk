# The techniques. Each is a folder daemon/techniques/NAME/ registered by one
# line of registry.mk; its local.mk adds its GL-free half to
# libsb-techinfo.a, its GL half to TECHNIQUE_GL_SOURCES (linked by the
# daemon) and its own shaders to GLSL_FILES. Here: the contract, the
# catalogue, the registry and what several techniques share.

# The GL-free halves: catalogue, options, passes, descriptions.
libsb_techinfo_a_SOURCES = \
	%reldir%/technique_info.h \
	%reldir%/catalog.c %reldir%/catalog.h \
	%reldir%/shared/culling_info.c %reldir%/shared/culling_info.h
nodist_libsb_techinfo_a_SOURCES = %reldir%/registered.h

# The GL halves, behind technique.h.
TECHNIQUE_GL_SOURCES = \
	%reldir%/technique.h \
	%reldir%/registry.c \
	%reldir%/shared/single_pass.c %reldir%/shared/single_pass.h \
	%reldir%/shared/gbuffer.c %reldir%/shared/gbuffer.h \
	%reldir%/shared/depth_prepass.c %reldir%/shared/depth_prepass.h \
	%reldir%/shared/heat.c %reldir%/shared/heat.h \
	%reldir%/shared/light_grid.c %reldir%/shared/light_grid.h \
	%reldir%/shared/culled.c %reldir%/shared/culled.h

include $(srcdir)/daemon/techniques/registry.mk
