#!/usr/bin/env bash
# pimodel quick start: sets up a virtual environment (.venv) with everything, then
#   bash quickstart.sh demo [ARGS...]   runs the main job (pimodel demo)
#   bash quickstart.sh test             runs lint and the whole test suite (docs build included)
#   bash quickstart.sh quick            lint and the quick tier: the tests not marked slow
#                                       (day-to-day work; CI runs the whole suite)
# Needs only Python >= 3.10, a C compiler and pip access to PyPI.
set -euo pipefail
cd "$(dirname "$0")"

PY=${PYTHON:-}
if [ -z "$PY" ]; then
    for cand in python3.11 python3 python; do
        if command -v "$cand" >/dev/null 2>&1; then PY=$cand; break; fi
    done
fi
[ -n "$PY" ] || { echo "quickstart: no python3 found on PATH" >&2; exit 1; }

if [ ! -x .venv/bin/python ]; then
    echo "quickstart: creating .venv with $PY"
    "$PY" -m venv .venv
    # the build backend too, so that a rebuild with --no-build-isolation works (docs/DEVELOPING.md)
    .venv/bin/python -m pip install -q --upgrade pip "setuptools>=77" wheel
fi

cmd=${1:-demo}
shift || true
extras="test"
[ "$cmd" = test ] || [ "$cmd" = quick ] && extras="test,docs"   # the docs build (Sphinx) is tested
echo "quickstart: installing pimodel[$extras] into .venv (compiles the C core)"
.venv/bin/python -m pip install -q -e ".[$extras]"

case "$cmd" in
    demo)
        exec .venv/bin/pimodel demo "$@" ;;
    test|quick)
        .venv/bin/ruff check .
        # one pytest worker per core, at most 4 (pytest-xdist); a test file stays on one worker
        # so its module fixtures are built once. PIMODEL_TEST_WORKERS=0 runs in this process.
        workers=${PIMODEL_TEST_WORKERS:-$(nproc 2>/dev/null || echo 1)}
        case $workers in
            ''|*[!0-9]*) echo "quickstart: PIMODEL_TEST_WORKERS: expected a whole number >= 0" \
                              "(0: one process), got '$workers'" >&2; exit 2 ;;
        esac
        [ "$workers" -gt 4 ] && workers=4
        tier=()
        [ "$cmd" = quick ] && tier=(-m "not slow")
        # the 25 slowest tests listed at the end: where the suite's time goes (CI's budget)
        exec .venv/bin/python -m pytest -q -n "$workers" --dist loadfile --durations=25 \
            "${tier[@]}" "$@" ;;
    *)
        echo "usage: bash quickstart.sh {demo|test|quick} [args...]" >&2; exit 2 ;;
esac
