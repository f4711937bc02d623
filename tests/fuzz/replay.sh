#!/bin/sh
# Part of make check: every seed and every input that once broke a fuzz
# target (tests/fuzz/regressions/TARGET) replayed through that target, built
# with the normal compiler and without libFuzzer. tests/fuzz/run.sh fuzzes.
bin=${FUZZ_REPLAY_DIR:-tests/fuzz}
src=${srcdir:-.}/tests/fuzz
failed=0
for t in job sweep png_metrics route asset_cache asset_convert env_convert; do
    if "$bin/replay-$t" "$src/corpus/$t" "$src/regressions/$t"; then
        echo "PASS: replay $t"
    else
        echo "FAIL: replay $t"
        failed=1
    fi
done
exit $failed
