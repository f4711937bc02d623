# Tests: their programs, lists and check targets (included by Makefile.am).
#   make check                      everything (tools/check runs it in build/)
#   make check TESTS=tests/e2e/e2e_http.py     one test; its log is
#                                   tests/e2e/e2e_http.log, ending in its time
#   make check-sanitizers           SANITIZER_TESTS, in a build configured
#                                   with --enable-sanitizers (build-asan/)
#   make distcheck-quick            the tarball is complete and builds
#   make fuzz [FUZZ_SECONDS=300]    each libFuzzer target (tests/fuzz/run.sh)
#   make fuzz-long [FUZZ_LONG_SECONDS=1800]   the converter, routes, jobs, sweeps

# GL-free unit tests in C, end-to-end tests in Python 3 (standard library
# only) against a real daemon on a free loopback port.
UNIT_TESTS = \
	tests/unit/test_job \
	tests/unit/test_options \
	tests/unit/test_stats \
	tests/unit/test_scene \
	tests/unit/test_scene_asset \
	tests/unit/test_scene_view \
	tests/unit/test_osl \
	tests/unit/test_metrics \
	tests/unit/test_flicker \
	tests/unit/test_sweep \
	tests/unit/test_interference \
	tests/unit/test_records \
	tests/unit/test_store \
	tests/unit/test_png \
	tests/unit/test_gate \
	tests/unit/test_client \
	tests/unit/test_job_filter \
	tests/unit/test_http \
	tests/unit/test_routes \
	tests/unit/test_charts \
	tests/unit/test_history \
	tests/unit/test_fleet \
	tests/unit/test_culling \
	tests/unit/test_effects \
	tests/unit/test_pbr \
	tests/unit/test_teapot \
	tests/unit/test_lighting \
	tests/unit/test_asset \
	tests/unit/test_uv_charts \
	tests/unit/test_uv_overlap \
	tests/unit/test_convert_matrices \
	tests/unit/test_convert_checks \
	tests/unit/test_light_shape \
	tests/unit/test_temporal \
	tests/unit/test_fidelity \
	tests/unit/test_tile_plan \
	tests/unit/test_devices \
	tests/unit/test_gpu_memory
check_PROGRAMS = $(UNIT_TESTS) tests/tools/png-tool \
	tests/fuzz/replay-job tests/fuzz/replay-sweep tests/fuzz/replay-png_metrics \
	tests/fuzz/replay-route tests/fuzz/replay-asset_cache tests/fuzz/replay-asset_convert \
	tests/fuzz/replay-env_convert
tests_unit_test_job_LDADD = $(CORE_LIBS)
tests_unit_test_options_LDADD = libsb-common.a $(JANSSON_LIBS) $(LIBS)
tests_unit_test_store_LDADD = $(CORE_LIBS)
tests_unit_test_stats_LDADD = $(CORE_LIBS)
tests_unit_test_scene_LDADD = $(CORE_LIBS)
tests_unit_test_scene_asset_LDADD = $(CORE_LIBS) -lm
tests_unit_test_scene_view_LDADD = $(CORE_LIBS) -lm
tests_unit_test_osl_LDADD = $(CORE_LIBS)
tests_unit_test_light_shape_LDADD = $(CORE_LIBS)
tests_unit_test_metrics_LDADD = $(CORE_LIBS)
tests_unit_test_flicker_LDADD = $(CORE_LIBS)
tests_unit_test_sweep_LDADD = $(CORE_LIBS)
tests_unit_test_effects_LDADD = $(CORE_LIBS)
tests_unit_test_temporal_LDADD = $(CORE_LIBS)
tests_unit_test_records_LDADD = $(CORE_LIBS)
tests_unit_test_interference_LDADD = libsb-status.a $(CORE_LIBS)
tests_unit_test_fidelity_LDADD = $(CORE_LIBS) -lm
# The measuring run's tiles: GL-free logic in the GL toolkit's folder.
tests_unit_test_tile_plan_SOURCES = tests/unit/test_tile_plan.c daemon/gpu/tile_plan.c \
	daemon/gpu/tile_plan.h
tests_unit_test_tile_plan_LDADD = -lm
tests_unit_test_png_LDADD = $(CORE_LIBS)
# The GPU's names and the scheduler's choice, over fake sysfs trees.
tests_unit_test_devices_SOURCES = tests/unit/test_devices.c $(GPU_DEVICE_SOURCES)
tests_unit_test_devices_LDADD = $(CORE_LIBS)
tests_unit_test_gpu_memory_SOURCES = tests/unit/test_gpu_memory.c daemon/gpu/gpu_memory.c \
	daemon/gpu/gpu_memory.h
tests_unit_test_gpu_memory_LDADD = $(CORE_LIBS)
tests_unit_test_gate_SOURCES = tests/unit/test_gate.c $(CLIENT_PURE)
tests_unit_test_gate_LDADD = $(CORE_LIBS) -lm
tests_unit_test_client_SOURCES = tests/unit/test_client.c $(CLIENT_PURE)
tests_unit_test_client_LDADD = $(CORE_LIBS) -lm
tests_unit_test_job_filter_SOURCES = tests/unit/test_job_filter.c daemon/api/job_filter.c \
	daemon/api/job_filter.h
tests_unit_test_job_filter_LDADD = $(CORE_LIBS)
tests_unit_test_charts_SOURCES = tests/unit/test_charts.c
tests_unit_test_charts_LDADD = $(REPORT_LIBS)
tests_unit_test_history_SOURCES = tests/unit/test_history.c
tests_unit_test_history_LDADD = $(REPORT_LIBS)
# The fleet's device view, with the client's CSV and the reports it reads.
tests_unit_test_fleet_SOURCES = tests/unit/test_fleet.c client/fleet_view.c
tests_unit_test_fleet_LDADD = $(REPORT_LIBS)
tests_unit_test_culling_LDADD = $(CORE_LIBS) -lm
tests_unit_test_pbr_LDADD = $(CORE_LIBS) -lm
tests_unit_test_teapot_LDADD = $(CORE_LIBS) -lm
tests_unit_test_lighting_LDADD = $(CORE_LIBS) -lm
tests_unit_test_asset_LDADD = $(CORE_LIBS) -lm
tests_unit_test_uv_charts_SOURCES = tests/unit/test_uv_charts.c daemon/assets/uv_charts.c \
	daemon/assets/uv_charts.h
tests_unit_test_uv_charts_LDADD = -lm
tests_unit_test_uv_overlap_SOURCES = tests/unit/test_uv_overlap.c daemon/assets/uv_overlap.c \
	daemon/assets/uv_overlap.h
tests_unit_test_uv_overlap_LDADD = -lm
tests_unit_test_convert_matrices_SOURCES = tests/unit/test_convert_matrices.c \
	daemon/assets/convert_matrices.c daemon/assets/convert_internal.h
tests_unit_test_convert_matrices_LDADD = $(JANSSON_LIBS) -lm
# The converter's checks, on documents of up to a million nodes.
tests_unit_test_convert_checks_SOURCES = tests/unit/test_convert_checks.c $(ASSET_CONVERT_SOURCES)
tests_unit_test_convert_checks_CFLAGS = $(AM_CFLAGS) $(ASSIMP_CFLAGS) $(JPEG_CFLAGS)
tests_unit_test_convert_checks_LDADD = $(CORE_LIBS) $(ASSIMP_LIBS) $(JPEG_LIBS) -lm
tests_tools_png_tool_SOURCES = tests/tools/png_tool.c
tests_tools_png_tool_LDADD = $(CORE_LIBS)
noinst_HEADERS = tests/unit/check.h tests/unit/catalog_fixture.h tests/fuzz/fuzz.h
tests_unit_test_routes_SOURCES = tests/unit/test_routes.c daemon/api/routes.c daemon/api/routes.h
tests_unit_test_routes_LDADD = $(CORE_LIBS)
# The HTTP layer without GL: the API's sources, the store and the real
# catalogue, with the test as the render thread.
tests_unit_test_http_SOURCES = tests/unit/test_http.c $(API_SOURCES) \
	daemon/jobs/sweeps.c daemon/jobs/sweeps.h
nodist_tests_unit_test_http_SOURCES = daemon/api/ui_files.c
tests_unit_test_http_LDADD = $(API_LIBS) $(MHD_LIBS)
# The fuzz targets, replayed over their corpora in make check (tests/fuzz/run.sh
# builds them with clang and libFuzzer instead).
tests_fuzz_replay_job_SOURCES = tests/fuzz/fuzz_job.c tests/fuzz/replay.c
tests_fuzz_replay_job_LDADD = $(CORE_LIBS)
tests_fuzz_replay_sweep_SOURCES = tests/fuzz/fuzz_sweep.c tests/fuzz/replay.c
tests_fuzz_replay_sweep_LDADD = $(CORE_LIBS)
tests_fuzz_replay_png_metrics_SOURCES = tests/fuzz/fuzz_png_metrics.c tests/fuzz/replay.c
tests_fuzz_replay_png_metrics_LDADD = $(CORE_LIBS)
tests_fuzz_replay_route_SOURCES = tests/fuzz/fuzz_route.c tests/fuzz/replay.c daemon/api/routes.c
tests_fuzz_replay_route_LDADD = $(CORE_LIBS)
tests_fuzz_replay_asset_cache_SOURCES = tests/fuzz/fuzz_asset_cache.c tests/fuzz/replay.c
tests_fuzz_replay_asset_cache_LDADD = $(CORE_LIBS)
tests_fuzz_replay_asset_convert_SOURCES = tests/fuzz/fuzz_asset_convert.c tests/fuzz/replay.c \
	$(ASSET_CONVERT_SOURCES)
tests_fuzz_replay_asset_convert_CFLAGS = $(AM_CFLAGS) $(ASSIMP_CFLAGS) $(JPEG_CFLAGS)
tests_fuzz_replay_asset_convert_LDADD = $(CORE_LIBS) $(ASSIMP_LIBS) $(JPEG_LIBS) -lm
tests_fuzz_replay_env_convert_SOURCES = tests/fuzz/fuzz_env_convert.c tests/fuzz/replay.c \
	$(ENV_CONVERT_SOURCES)
tests_fuzz_replay_env_convert_CFLAGS = $(AM_CFLAGS) $(STB_CFLAGS) $(OPENEXR_CFLAGS)
tests_fuzz_replay_env_convert_LDADD = $(CORE_LIBS) $(STB_LIBS) $(OPENEXR_LIBS) -lm
if HAVE_SECCOMP
check_PROGRAMS += tests/tools/sandbox-run
tests_tools_sandbox_run_SOURCES = tests/tools/sandbox_run.c
tests_tools_sandbox_run_CFLAGS = $(AM_CFLAGS) $(SECCOMP_CFLAGS)
tests_tools_sandbox_run_LDADD = $(SECCOMP_LIBS)
endif

# Longest first (tools/check prints each test's time; re-ordered from the
# run of 2026-11-27 after the wave-5 trims), and the ones that mostly wait
# (e2e_fleet, e2e_timing_rule) early: make -j starts them in this order, so
# the short ones fill in beside the long ones instead of one long test
# running alone at the end.
E2E_TESTS = \
	tests/e2e/e2e_osl.py \
	tests/e2e/e2e_msaa.py \
	tests/e2e/e2e_fleet.py \
	tests/e2e/e2e_many_lights.py \
	tests/e2e/e2e_ab.py \
	tests/e2e/e2e_fidelity.py \
	tests/e2e/e2e_timing_rule.py \
	tests/e2e/e2e_hardening.py \
	tests/e2e/e2e_sweep.py \
	tests/e2e/e2e_report.py \
	tests/e2e/e2e_techniques.py \
	tests/e2e/e2e_gate.py \
	tests/e2e/e2e_runaway.py \
	tests/e2e/e2e_post.py \
	tests/e2e/e2e_reference_temporal.py \
	tests/e2e/e2e_taa.py \
	tests/e2e/e2e_light_types.py \
	tests/e2e/e2e_faults.py \
	tests/e2e/e2e_scene.py \
	tests/e2e/e2e_integrity.py \
	tests/e2e/e2e_store.py \
	tests/e2e/e2e_guardrails.py \
	tests/e2e/e2e_timing_settle.py \
	tests/e2e/e2e_records.py \
	tests/e2e/e2e_textured.py \
	tests/e2e/e2e_charts.py \
	tests/e2e/e2e_visibility.py \
	tests/e2e/e2e_metrics.py \
	tests/e2e/e2e_verdicts.py \
	tests/e2e/e2e_load.py \
	tests/e2e/e2e_asset_pins.py \
	tests/e2e/e2e_client.py \
	tests/e2e/e2e_dashboard.py \
	tests/e2e/e2e_cancel_drain.py \
	tests/e2e/e2e_pass_times.py \
	tests/e2e/e2e_client_verdicts.py \
	tests/e2e/systemd_sandbox.py \
	tests/e2e/e2e_http.py \
	tests/e2e/e2e_crash_report.py \
	tests/e2e/e2e_history.py \
	tests/e2e/e2e_scene_view.py \
	tests/e2e/e2e_persist.py \
	tests/e2e/e2e_full_disk.py \
	tests/e2e/e2e_asset_import.py \
	tests/e2e/e2e_asset_convert.py \
	tests/e2e/e2e_gpu.py \
	tests/e2e/e2e_osl_assets.py \
	tests/e2e/e2e_asset_render.py \
	tests/e2e/e2e_assets.py \
	tests/e2e/e2e_upload_slots.py \
	tests/e2e/e2e_pbr.py \
	tests/e2e/e2e_badinput.py \
	tests/e2e/e2e_demo.py \
	tests/e2e/ssim_skimage.py \
	tests/e2e/e2e_orphans.py \
	tests/e2e/e2e_compare_alpha.py \
	tests/e2e/systemd_unit.sh

# The folders' layers (docs/architecture.md), read from the includes.
STATIC_TESTS = tests/layers.py

TESTS = $(UNIT_TESTS) \
	$(STATIC_TESTS) \
	tests/fuzz/replay.sh \
	$(E2E_TESTS)

# Under the sanitizers (tools/check: build-asan/): the unit tests, the fuzz
# corpora, and the end-to-end tests of the daemon's own memory handling:
# HTTP, bad input, hardening and load, persistence and records. Not every
# rendering test again: under ASan, llvmpipe's allocations alone make them
# several times slower, and the rendering paths they add are the driver's.
SANITIZER_TESTS = $(UNIT_TESTS) \
	tests/fuzz/replay.sh \
	tests/e2e/e2e_faults.py \
	tests/e2e/e2e_hardening.py \
	tests/e2e/e2e_records.py \
	tests/e2e/e2e_store.py \
	tests/e2e/e2e_load.py \
	tests/e2e/e2e_http.py \
	tests/e2e/e2e_assets.py \
	tests/e2e/e2e_persist.py \
	tests/e2e/e2e_badinput.py \
	tests/e2e/e2e_asset_convert.py \
	tests/e2e/e2e_compare_alpha.py \
	tests/e2e/e2e_asset_pins.py \
	tests/e2e/e2e_full_disk.py \
	tests/e2e/e2e_upload_slots.py \
	tests/e2e/e2e_gpu.py
check-sanitizers:
if SANITIZERS
	$(MAKE) $(AM_MAKEFLAGS) check TESTS='$(SANITIZER_TESTS)'
else
	@echo "check-sanitizers: configure with --enable-sanitizers (tools/check: build-asan/)" >&2; exit 1
endif

# tools/check runs the whole suite in the build tree, and SANITIZER_TESTS
# under the sanitizers; the distribution check proves the tarball is
# complete and builds, with the unit tests and one end-to-end test, so that
# CI does not run every end-to-end test a third time.
DISTCHECK_TESTS = $(UNIT_TESTS) tests/e2e/e2e_http.py
# Built at -O0: it proves the tarball complete and buildable, which the
# optimiser adds nothing to (the build tree's -O2 build has its warnings),
# in under half the compile time.
distcheck-quick:
	$(MAKE) $(AM_MAKEFLAGS) distcheck TESTS='$(DISTCHECK_TESTS)' DISTCHECK_CONFIGURE_FLAGS='CFLAGS="-g -O0"'

# Each libFuzzer target for FUZZ_SECONDS (tools/check runs them for
# FUZZ_SECONDS=25, two at a time).
FUZZ_SECONDS = 300
fuzz:
	$(SHELL) $(srcdir)/tests/fuzz/run.sh $(FUZZ_SECONDS)
# The longer run (issue 34): the converter's checks, the HTTP routing and
# the job and sweep parsers, FUZZ_LONG_SECONDS each (default 30 minutes,
# two at a time: an hour), for a quiet machine, not CI.
FUZZ_LONG_SECONDS = 1800
fuzz-long:
	$(SHELL) $(srcdir)/tests/fuzz/run.sh $(FUZZ_LONG_SECONDS) asset_convert route job sweep
.PHONY: check-sanitizers distcheck-quick fuzz fuzz-long
# Under --enable-sanitizers every test (and the daemons the end-to-end tests
# start) stops at the first error; leaks inside the GL driver, LLVM and
# fontconfig, which the daemon cannot free, are suppressed by name.
if SANITIZERS
AM_TESTS_ENVIRONMENT_SAN = \
	ASAN_OPTIONS='detect_leaks=1:halt_on_error=1:strict_string_checks=1:malloc_context_size=4:quarantine_size_mb=16'; \
	LSAN_OPTIONS='suppressions=$(abs_top_srcdir)/tests/sanitizers/lsan.supp:print_suppressions=0'; \
	UBSAN_OPTIONS='print_stacktrace=1:halt_on_error=1'; \
	SHADEBENCH_SANITIZERS=1; \
	export ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS SHADEBENCH_SANITIZERS;
else
AM_TESTS_ENVIRONMENT_SAN =
endif
# Each log ends with the test's wall and CPU seconds (tests/run-timed).
TEST_EXTENSIONS = .py .sh
LOG_COMPILER = $(SHELL) $(srcdir)/tests/run-timed
PY_LOG_COMPILER = $(SHELL) $(srcdir)/tests/run-timed $(PYTHON)
SH_LOG_COMPILER = $(SHELL) $(srcdir)/tests/run-timed $(SHELL)
AM_TESTS_ENVIRONMENT = \
	SHADEBENCHD='$(abs_top_builddir)/shadebenchd'; \
	PNG_TOOL='$(abs_top_builddir)/tests/tools/png-tool'; \
	SHADEBENCH_COMPARE='$(abs_top_builddir)/shadebench-compare'; \
	SHADEBENCH_CLIENT='$(abs_top_builddir)/shadebench'; \
	SHADEBENCH_UNIT='$(abs_top_builddir)/systemd/shadebenchd.service'; \
	FUZZ_REPLAY_DIR='$(abs_top_builddir)/tests/fuzz'; \
	SANDBOX_RUN='$(abs_top_builddir)/tests/tools/sandbox-run'; \
	SHADEBENCH_ASSET='$(abs_top_builddir)/shadebench-asset'; \
	export SHADEBENCHD PNG_TOOL SHADEBENCH_COMPARE SHADEBENCH_CLIENT SHADEBENCH_UNIT FUZZ_REPLAY_DIR \
	SANDBOX_RUN SHADEBENCH_ASSET; \
	$(AM_TESTS_ENVIRONMENT_SAN)

