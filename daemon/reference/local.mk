# The Khronos reference (issue 32; docs/assets.md, "Fidelity against the
# Khronos viewer"): shadebench-reference, the child that drives headless
# Chromium. The daemon's side: a fidelity job's spec in daemon/spec/
# (fidelity_spec), the worker that runs this child and
# compares in daemon/jobs/fidelity, the render thread's channels in
# daemon/harness/fidelity_render.

# The viewer's files, its request and its patch, shared by the child and
# the daemon's spec (GL-free).
libsb_reference_a_SOURCES = \
	daemon/reference/reference_files.c daemon/reference/reference_files.h

bin_PROGRAMS += shadebench-reference
shadebench_reference_SOURCES = daemon/reference/reference_main.c \
	daemon/reference/cdp.c daemon/reference/cdp.h
shadebench_reference_LDADD = libsb-reference.a libsb-common.a $(JANSSON_LIBS) $(PNG_LIBS) -lm

# The page the viewer runs in, and the viewer itself: tools/setup unpacks
# @khronosgroup/gltf-viewer into build/reference-viewer (npm pack; nothing
# is fetched at run time); make install copies it when it is there.
referencedir = $(pkgdatadir)/reference
dist_reference_DATA = daemon/reference/page.html daemon/reference/page.js
install-data-hook:
	if test -f reference-viewer/gltf-viewer.module.js; then \
	  $(MKDIR_P) '$(DESTDIR)$(pkgdatadir)/reference-viewer/libs' && \
	  $(INSTALL_DATA) reference-viewer/gltf-viewer.module.js reference-viewer/LICENSE.md \
	    '$(DESTDIR)$(pkgdatadir)/reference-viewer/' && \
	  $(INSTALL_DATA) reference-viewer/libs/* '$(DESTDIR)$(pkgdatadir)/reference-viewer/libs/'; \
	else echo "make install: no reference-viewer/ here (tools/setup vendors it): the Khronos reference is not installed"; fi
uninstall-hook:
	rm -rf '$(DESTDIR)$(pkgdatadir)/reference-viewer'
