# The post effects. Each is a folder daemon/effects/NAME/ registered by one
# line of registry.mk; its local.mk adds its GL-free half to
# libsb-effects.a, its GL half to EFFECT_GL_SOURCES (linked by the daemon)
# and its own shaders to GLSL_FILES. Here: the contract, look.post, the
# chain and the registry.

# The GL-free halves: the registry's infos, look.post.
libsb_effects_a_SOURCES = \
	%reldir%/effect_info.c %reldir%/effect_info.h \
	%reldir%/post_spec.c %reldir%/post_spec.h
nodist_libsb_effects_a_SOURCES = %reldir%/registered.h

# The GL halves, behind effect.h, and the chain that runs them.
EFFECT_GL_SOURCES = \
	%reldir%/effect.h \
	%reldir%/registry.c \
	%reldir%/post_chain.c %reldir%/post_chain.h

include $(srcdir)/daemon/effects/registry.mk
