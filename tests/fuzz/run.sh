#!/bin/sh
# Builds the libFuzzer targets with clang (AddressSanitizer and
# UndefinedBehaviorSanitizer) in build-fuzz/ and runs each for SECONDS,
# FUZZ_JOBS of them at a time (default 2):
#   tests/fuzz/run.sh SECONDS [TARGET...]     (targets: job sweep png_metrics route
#                                              asset_cache asset_convert env_convert)
#   make fuzz FUZZ_SECONDS=600                 (the same, from a build folder)
# tools/check runs them for 25 s, two at a time. Each starts from its seed
# corpus (tests/fuzz/corpus/TARGET) and the inputs that once broke it
# (tests/fuzz/regressions/TARGET); new inputs go to build-fuzz/corpus/TARGET,
# a crash to build-fuzz/crashes/TARGET/ (copy it to
# tests/fuzz/regressions/TARGET/ once fixed: make check replays those).
# Prints "PASS: fuzz_TARGET ..." or "FAIL: ..." per target, then
# "fuzz: N passed, N failed"; exits non-zero when any failed.
set -u
cd "$(dirname "$0")/../.."
seconds=${1:-60}
[ $# -gt 0 ] && shift
targets=${*:-job sweep png_metrics route asset_cache asset_convert env_convert}
jobs=${FUZZ_JOBS:-2}
out=${FUZZ_BUILD:-build-fuzz}
cc=${FUZZ_CC:-clang}
mkdir -p "$out/obj"

if ! command -v "$cc" >/dev/null 2>&1; then
    echo "FAIL: fuzz: $cc is not installed (apt-get install clang)"
    echo "fuzz: 0 passed, 1 failed"
    exit 1
fi
flags="-g -O1 -std=c11 -I. -I$out/gen -fno-omit-frame-pointer -fsanitize=address,undefined
  -fno-sanitize-recover=undefined $(pkg-config --cflags jansson libpng sqlite3 nettle)"
libs="$(pkg-config --libs jansson libpng sqlite3 nettle) -lm -pthread"
# The registries' lists for C, as the build generates them (rewritten only
# when they change, so that what includes them is not rebuilt every run).
for registry in daemon/techniques/registry.mk daemon/effects/registry.mk; do
    gen="$out/gen/$(dirname "$registry")/registered.h"
    mkdir -p "$(dirname "$gen")"
    sh build-aux/gen-registry.sh "$registry" >"$gen.tmp" || { echo "FAIL: fuzz: $registry"; exit 1; }
    if cmp -s "$gen.tmp" "$gen"; then rm "$gen.tmp"; else mv "$gen.tmp" "$gen"; fi
done
# The GL-free libraries, read from Makefile.am and the fragments it may
# include (*.mk, where %reldir% and %D% stand for the fragment's folder),
# so that this list cannot fall behind the build; all but libsb-reports (the
# charts and reports, with cairo), which no target reaches.
fragments=$(find . \( -name '.git' -o -name 'build*' -o -name 'shadebench-*' \) -prune -o \
    -name '*.mk' -type f -print | sed 's|^\./||' | sort)
sources=$(for f in Makefile.am $fragments; do
    awk -v dir="$(dirname "$f")" '/^libsb_[a-z]*_a_SOURCES *\+?=/ && !/^libsb_reports_/ { on = 1 }
        on { for (i = 1; i <= NF; i++) if ($i ~ /\.c$/) {
                 s = $i; gsub(/%reldir%|%D%/, dir, s); sub(/^\.\//, "", s); print s } }
        on && !/\\$/ { on = 0 }' "$f"
done)
[ -n "$sources" ] || { echo "FAIL: fuzz: no library sources found in Makefile.am"; exit 1; }
sources="$sources daemon/api/routes.c" # the route target's only GL-free part of the API layer

# Objects, FUZZ_JOBS compilers at a time; a header newer than an object
# rebuilds it.
objs=""
stale=""
for src in $sources; do
    obj="$out/obj/$(echo "$src" | tr / _ | sed 's/\.c$/.o/')"
    if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find "$(dirname "$src")" common "$out/gen" -name '*.h' -newer "$obj" 2>/dev/null | head -n1)" ]; then
        stale="$stale $src:$obj"
    fi
    objs="$objs $obj"
done
if [ -n "$stale" ]; then
    # shellcheck disable=SC2086
    if ! printf '%s\n' $stale | xargs -P "$jobs" -n 1 sh -c \
        'src=${1%%:*}; obj=${1#*:}; '"$cc"' $0 -fsanitize=fuzzer-no-link -c "$src" -o "$obj.tmp" && mv "$obj.tmp" "$obj" || { echo "FAIL: fuzz: cannot build $src"; exit 255; }' \
        "$(echo $flags)"; then
        echo "fuzz: 0 passed, 1 failed"
        exit 1
    fi
fi

# One target: build, run for $seconds, print one PASS or FAIL line.
fuzz_one() {
    t=$1
    bin="$out/fuzz_$t"
    # The converter's target adds its core and the libraries only the
    # converter links (assimp, libjpeg), not instrumented themselves.
    extra=""
    if [ "$t" = asset_convert ]; then
        extra="daemon/assets/asset_convert.c daemon/assets/convert_*.c daemon/assets/uv_charts.c daemon/assets/uv_overlap.c $(pkg-config --cflags --libs assimp libjpeg)"
    fi
    if [ "$t" = env_convert ]; then
        extra="daemon/assets/env_convert.c daemon/assets/env_exr.c $(pkg-config --cflags --libs stb OpenEXR)"
    fi
    # shellcheck disable=SC2086
    if ! "$cc" $flags -fsanitize=fuzzer "tests/fuzz/fuzz_$t.c" $extra $objs $libs -o "$bin" 2>"$out/$t.build.log"; then
        echo "FAIL: fuzz_$t (does not build)"
        tail -n 20 "$out/$t.build.log"
        return
    fi
    mkdir -p "$out/corpus/$t" "$out/crashes/$t"
    dict=""
    [ -f "tests/fuzz/$t.dict" ] && dict="-dict=tests/fuzz/$t.dict"
    seeds="tests/fuzz/corpus/$t"
    [ -d "tests/fuzz/regressions/$t" ] && seeds="$seeds tests/fuzz/regressions/$t"
    start=$(date +%s)
    # Leaks are checked too (LSan, part of ASan): each input must free what it
    # takes, apart from the libraries' own (tests/sanitizers/lsan.supp).
    # shellcheck disable=SC2086
    ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 \
    LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp" \
    "$bin" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2560 -max_len=65536 \
        -artifact_prefix="$out/crashes/$t/" -print_final_stats=1 $dict \
        "$out/corpus/$t" $seeds >"$out/$t.log" 2>&1
    rc=$?
    took=$(( $(date +%s) - start ))
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$out/$t.log" | tail -n1)
    if [ "$rc" -eq 0 ]; then
        echo "PASS: fuzz_$t (${runs:-?} inputs in ${took} s)"
    else
        echo "FAIL: fuzz_$t (exit $rc after ${took} s; see $out/$t.log, input in $out/crashes/$t/)"
        grep -m1 -A12 "ERROR\|invariant broken" "$out/$t.log"
    fi
}

# FUZZ_JOBS lanes side by side, each running its share of the targets in
# turn; the results are printed in the targets' order.
for t in $targets; do rm -f "$out/$t.result"; done
lane=0
while [ "$lane" -lt "$jobs" ]; do
    (
        i=0
        for t in $targets; do
            [ $((i % jobs)) -eq "$lane" ] && fuzz_one "$t" >"$out/$t.result"
            i=$((i + 1))
        done
    ) &
    lane=$((lane + 1))
done
wait

pass=0
fail=0
for t in $targets; do
    if [ -f "$out/$t.result" ]; then
        cat "$out/$t.result"
        grep -q '^PASS: ' "$out/$t.result" && pass=$((pass + 1)) || fail=$((fail + 1))
        rm -f "$out/$t.result"
    else
        echo "FAIL: fuzz_$t (no result)"
        fail=$((fail + 1))
    fi
done
echo "fuzz: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
