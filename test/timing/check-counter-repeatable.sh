#!/bin/sh
# check-counter-repeatable.sh COUNTER ARCH PROGRAM ARGS...: runs the program twice under the
# instruction counter; passes when both counts are non-zero and agree within 0.01%. (Exact equality
# is not required: the program under test, a gtest binary, prints elapsed milliseconds, so its own
# formatting work varies by a few dozen instructions between runs.)
set -eu
counter="$1"; shift
a=$("$counter" "$@" 2>&1 >/dev/null | sed -n 's/^insns \([0-9]*\)$/\1/p' | tail -1)
b=$("$counter" "$@" 2>&1 >/dev/null | sed -n 's/^insns \([0-9]*\)$/\1/p' | tail -1)
echo "run 1: ${a:-none} instructions, run 2: ${b:-none} instructions"
[ -n "$a" ] && [ -n "$b" ] && [ "$a" -gt 0 ] || exit 1
diff=$((a > b ? a - b : b - a))
[ $((diff * 10000)) -le "$a" ]
