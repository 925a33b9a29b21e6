#!/usr/bin/env bash
# Mutation testing with mutmut (a benchmark, not run in CI): prints the kill rate and survivors.
#
# Usage: tools/mutation.sh [--max-children N] [--name NAME] [--tests PATH ...] [--only PATTERN ...]
#                         [FILE_OR_DIR ...]
#   default targets: composer/environment.py composer/observation/ mjcf/physics.py mjcf/binding.py
#   --tests: the test files or folders to draw on (default: all of tests/); a folder of
#     tests that drive the targets directly keeps a run on a small machine to hours.
#   --only: run just the mutants whose names match (fnmatch patterns, e.g. the survivors of
#     an earlier run, or 'composer.environment.*'); the kill rate then counts only those.
#
# Works on a copy of the files git tracks or would track (untracked and not ignored) under
# .cache/mutation/NAME (default "tree"), with mutmut in its own venv (.cache/mutation/venv),
# so the working tree and its venv are left alone. mutmut runs, for each mutant, the
# selected tests that exercise the mutated function. Prints mutmut's summary, the surviving
# mutants (inspect one with `cd .cache/mutation/NAME && ../venv/bin/mutmut show MUTANT`;
# rerun them after adding tests with `--only MUTANT ...`, which copies the current tree
# afresh), and the kill rate: killed / (killed + survived), timeouts counted as killed.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
work="$repo/.cache/mutation"
children=2
name=tree
tests=()
only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --max-children) children=$2; shift 2 ;;
    --name) name=$2; shift 2 ;;
    --tests) tests+=("$2"); shift 2 ;;
    --only) only+=("$2"); shift 2 ;;
    *) break ;;
  esac
done
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

tree="$work/$name"
rm -rf "$tree"
mkdir -p "$tree"
git ls-files -z --cached --others --exclude-standard | xargs -0 cp --parents -t "$tree"
# Lists in mutmut's setup.cfg section are one item per (indented) line. mutmut runs the tests
# inside mutants/, which holds only what it is told to copy: all of the tree.
paths=$(printf '\n    %s' "${targets[@]}")
copied=$(git ls-files --cached --others --exclude-standard | cut -d/ -f1 | sort -u | sed 's/^/    /')
# Tests that run this project in a Python subprocess of their own cannot see mutmut's copy.
ignored=$(grep -l "sys.executable" tests -r --include "test_*.py" \
  | grep -v -e test_determinism.py -e test_bad_input.py | sed 's/^/    --ignore=/')
# A warning attributed to its caller's line (warnings.warn's stacklevel) points into
# mutmut's trampoline, one frame deeper, in the mutated copy: that check cannot pass there.
ignored+=$'\n    --deselect=tests/composer/test_environment.py::test_the_time_limit_warning_points_at_the_line_that_built_the_environment'
selection=""
if [ "${#tests[@]}" -gt 0 ]; then
  selection=$(printf '\n    %s' "${tests[@]}")
fi
# Workers fork from a server that has only collected the tests: forked from mutmut's main
# process, which has rendered with EGL while collecting stats, a worker that renders hangs,
# and the hang would be counted as a kill (a timeout).
cat > "$tree/setup.cfg" <<CFG
[mutmut]
source_paths=$paths
also_copy=
$copied
pytest_add_cli_args=
$ignored
pytest_add_cli_args_test_selection=$selection
timeout_multiplier=2
timeout_constant=3
process_isolation=forkserver
CFG

cd "$tree"
export MUJOCO_GL=egl
# The copy is not a repository of its own: without this, mutmut would read this checkout's
# git history, and a commit made during the run would make it drop its test associations.
export GIT_CEILING_DIRECTORIES="$work"
"$work/venv/bin/mutmut" run --max-children "$children" "${only[@]}" || true
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
