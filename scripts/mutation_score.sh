#!/usr/bin/env bash
# Mutation testing of one part of the code against the tests that guard it (mutmut 3).
#
#   scripts/mutation_score.sh src/choreo/finishing/ "tests/test_beat_lock.py tests/test_foot_lock.py" [SECONDS]
#
# Give a folder (a package), not a single file: mutmut 3 then cannot import the mutated module.
# Works on a throw-away clone in /tmp (mutmut rewrites the sources it mutates), with this
# checkout's .venv (mutmut is installed into it if missing). Prints killed / survived / timeout /
# untested counts and the surviving mutants; `mutmut show NAME` in the clone shows one.
set -euo pipefail
paths=${1:?"the folder to mutate, e.g. src/choreo/finishing/"}
tests=${2:?"the test files that guard it, space-separated"}
limit=${3:-1800}
repo=$(cd "$(dirname "$0")/.." && pwd)
python=$repo/.venv/bin/python
"$python" -m pip show mutmut >/dev/null 2>&1 || "$python" -m pip install --quiet mutmut
work=$(mktemp -d /tmp/choreo-mutants.XXXXXX)
git clone --quiet "$repo" "$work"
cd "$work"
{
  echo; echo "[tool.mutmut]"
  echo "paths_to_mutate = [\"$paths\"]"
  printf 'tests_dir = [%s]\n' "$(printf '"%s", ' $tests | sed 's/, $//')"
  echo 'pytest_add_cli_args = ["-x", "-q", "-p", "no:cacheprovider"]'
} >> pyproject.toml
export PYTHONPATH=$work/src:$work/generators
timeout "$limit" "$repo/.venv/bin/mutmut" run --max-children 1 >/dev/null 2>&1 || true
"$repo/.venv/bin/mutmut" results 2>/dev/null > results.txt || true
for status in killed survived timeout "no tests" suspicious; do
  printf '%-10s %s\n' "$status" "$(grep -c ": $status" results.txt || true)"
done
echo "surviving mutants:"; grep ": survived" results.txt || true
echo "(clone kept in $work)"
