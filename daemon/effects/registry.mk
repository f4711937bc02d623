# The effect registry: one line per post effect, in the order /v1/info
# lists them. Each names a folder daemon/effects/NAME/ whose local.mk adds
# its sources and shaders to the build; its GL-free half defines NAME_info,
# its GL half effect_NAME. build-aux/gen-registry.sh reads these lines into
# the C registry (registered.h), so nothing else names an effect.
include $(srcdir)/daemon/effects/bloom/local.mk
include $(srcdir)/daemon/effects/toon/local.mk
include $(srcdir)/daemon/effects/ssao/local.mk
include $(srcdir)/daemon/effects/taa/local.mk
