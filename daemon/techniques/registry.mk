# The technique registry: one line per technique, in the order /v1/info
# lists them. Each names a folder daemon/techniques/NAME/ whose local.mk
# adds its sources and shaders to the build; its GL-free half defines
# NAME_info, its GL half technique_NAME. build-aux/gen-registry.sh reads
# these lines into the C registry (registered.h), so nothing else names a
# technique.
include $(srcdir)/daemon/techniques/forward/local.mk
include $(srcdir)/daemon/techniques/unlit/local.mk
include $(srcdir)/daemon/techniques/osl/local.mk
include $(srcdir)/daemon/techniques/deferred/local.mk
include $(srcdir)/daemon/techniques/tiled_deferred/local.mk
include $(srcdir)/daemon/techniques/forward_plus/local.mk
include $(srcdir)/daemon/techniques/clustered_forward/local.mk
include $(srcdir)/daemon/techniques/clustered_deferred/local.mk
include $(srcdir)/daemon/techniques/visibility_buffer/local.mk
