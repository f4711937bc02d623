# bloom: bright pass, Gaussian blur (separable or 2d, optionally over a mip
# chain), added back to the colour.
libsb_effects_a_SOURCES += %reldir%/bloom_info.c %reldir%/bloom_info.h
EFFECT_GL_SOURCES += %reldir%/bloom.c
GLSL_FILES += \
	%reldir%/bloom_sample.frag \
	%reldir%/bloom_blur.frag \
	%reldir%/bloom_up.frag
