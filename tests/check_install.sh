#!/usr/bin/env bash
# `cmake --install` into a fresh prefix, then the installed command and (when
# the module is built) the installed Python package are run from outside the
# source and build trees: what is installed must stand on its own.
#   check_install.sh BUILD_DIR SCENE [PYTHON PYTHON_INSTALL_DIR]
# SCENE is copied under the prefix, as a user's own scene file would be.
set -euo pipefail
build="$1"
scene="$2"
python="${3:-}"
pydir="${4:-}"
prefix="$(mktemp -d)"
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build" --prefix "$prefix" >/dev/null
cp "$scene" "$prefix/scene.toml"
cd "$prefix"   # nothing of the project's trees on any path from here

test -x bin/emdae || { echo "check_install: no bin/emdae under the prefix" >&2; exit 1; }
bin/emdae --version
bin/emdae run scene.toml --t-end 0.2 --out run -q
grep -q '"status": "ok"' run/summary.json ||
  { echo "check_install: the installed emdae's run did not complete" >&2; exit 1; }

if [ -n "$python" ]; then
  test -f "$pydir/emdae/__init__.py" ||
    { echo "check_install: no $pydir/emdae/__init__.py under the prefix" >&2; exit 1; }
  PYTHONPATH="$prefix/$pydir" "$python" - "$prefix" <<'PY'
import os, sys
import emdae
prefix = sys.argv[1]
assert os.path.realpath(emdae.__file__).startswith(os.path.realpath(prefix)), emdae.__file__
result = emdae.run(emdae.load(overrides={"time.t_end": 0.2}))
assert result.summary["status"] == "ok", result.summary["status"]
print("installed module:", os.path.relpath(emdae.__file__, prefix), "ran", result.summary["steps"], "steps")
PY
fi
