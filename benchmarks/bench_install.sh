#!/usr/bin/env bash
# The install's time, two ways, in fresh venvs: the Makefile's own `make install` (pip --no-compile;
# Python then compiles and caches what the tests and notebooks import, on first import) vs pip
# byte-compiling all of it as it installs (one core). Prints seconds and the .pyc count of each. Alternates the two
# ROUNDS times; run it with nothing else on the machine.
#     bash benchmarks/bench_install.sh [ROUNDS]
set -uo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-2}
venv=$(mktemp -d)/venv
for ((i = 0; i < rounds; i++)); do
  for mode in compile-after pip-compiles; do
    rm -rf "$venv"
    py="$venv/bin/python"
    start=$(date +%s.%N)
    if [ "$mode" = pip-compiles ]; then
      python3 -m venv "$venv"
      "$py" -m pip install --disable-pip-version-check -q "$(grep -E '^torch==' environment.txt)" 2>/dev/null
      "$py" -m pip install --disable-pip-version-check -q -r environment.txt 2>/dev/null
      "$py" -m pip install --disable-pip-version-check -q --no-deps -e . 2>/dev/null
    else
      make -s install VENV="$venv" > /dev/null 2>&1
    fi
    end=$(date +%s.%N)
    printf '%-14s %6.1f s  %d .pyc  load %s\n' "$mode" "$(echo "$end - $start" | bc)" \
      "$(find "$venv" -name '*.pyc' | wc -l)" "$(cut -d' ' -f1-3 /proc/loadavg)"
  done
done
rm -rf "$(dirname "$venv")"
