#!/usr/bin/env bash
# Mutation testing with mutmut (a benchmark, not run in CI): prints the kill rate and survivors.
#
# Usage: tools/mutation.sh [--max-children N] [FILE_OR_DIR ...]
#   default targets: composer/environment.py composer/observation/ mjcf/physics.py mjcf/binding.py
#
# Works on a copy of the tracked files under .cache/mutation/tree, with mutmut in its own
# venv (.cache/mutation/venv), so the working tree and its venv are left alone. mutmut runs,
# for each mutant, the tests that exercise the mutated function. Prints mutmut's summary,
# the surviving mutants (inspect one with `cd .cache/mutation/tree && ../venv/bin/mutmut
# show NAME`), and the kill rate: killed / (killed + survived), timeouts counted as killed.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
work="$repo/.cache/mutation"
children=2
if [ "${1:-}" = "--max-children" ]; then
  children=$2
  shift 2
fi
targets=("$@")
if [ "${#targets[@]}" -eq 0 ]; then
  targets=(composer/environment.py composer/observation/ mjcf/physics.py mjcf/binding.py)
fi

if [ ! -x "$work/venv/bin/mutmut" ]; then
  python3 -m venv "$work/venv"
  "$work/venv/bin/pip" install -q -e ".[test]" "mutmut==3.8.1"
  # The tests must import the mutated copy, not this checkout: keep only the dependencies.
  "$work/venv/bin/pip" uninstall -q -y mujoco-composer
fi

rm -rf "$work/tree"
mkdir -p "$work/tree"
git ls-files -z | xargs -0 cp --parents -t "$work/tree"
# Lists in mutmut's setup.cfg section are one item per (indented) line. mutmut runs the tests
# inside mutants/, which holds only what it is told to copy: all of the tree.
paths=$(printf '\n    %s' "${targets[@]}")
copied=$(git ls-files | cut -d/ -f1 | sort -u | sed 's/^/    /')
cat > "$work/tree/setup.cfg" <<CFG
[mutmut]
source_paths=$paths
also_copy=
$copied
CFG

cd "$work/tree"
export MUJOCO_GL=egl
"$work/venv/bin/mutmut" run --max-children "$children" || true
"$work/venv/bin/mutmut" results || true
"$work/venv/bin/mutmut" export-cicd-stats >/dev/null
python3 - <<'PY'
import json

stats = json.load(open("mutants/mutmut-cicd-stats.json"))
killed = stats["killed"] + stats.get("timeout", 0)
survived = stats["survived"]
print(json.dumps(stats))
total = killed + survived
if total:
    print(f"kill rate: {killed}/{total} = {100 * killed / total:.1f}%")
PY
