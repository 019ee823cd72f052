#!/usr/bin/env bash
# deckpound bootstrap: sets up everything on a fresh Linux machine, then runs a job.
#   ./run.sh paper [-o DIR]   the main job on the built-in benchmark
#   ./run.sh test [ARGS]      the test suite (ARGS go to pytest, e.g. -m slow)
#   ./run.sh <any deckpound command>
# Idempotent: a re-run only reinstalls when pyproject.toml changed, and only recompiles the
# numba kernels when their sources changed.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
venv="${DECKPOUND_VENV:-$here/.venv}"

# 1. the one system library openseespy needs (Debian/Ubuntu: libblas3)
if ! ldconfig -p 2>/dev/null | grep -q 'libblas\.so\.3'; then
  echo "run.sh: installing libblas3 (needed by openseespy)" >&2
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq && $sudo_cmd apt-get install -y -qq libblas3 >/dev/null
fi

# 2. a virtual environment with deckpound installed (editable)
py="${PYTHON:-python3}"
"$py" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else 1)' \
  || { echo "run.sh: Python >= 3.11 is required ($py is $("$py" -V 2>&1))" >&2; exit 2; }
[ -x "$venv/bin/python" ] || "$py" -m venv "$venv"
stamp="$venv/.deckpound-installed"
want="$(sha256sum pyproject.toml | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  "$venv/bin/python" -m pip install -q --upgrade pip >/dev/null
  "$venv/bin/python" -m pip install -q -e ".[test]"
  echo "$want" > "$stamp"
fi

# 3. the numba kernels, compiled once (deckpound compile): the stamp holds a hash of the
#    kernels' sources (content, path, mtime), the compile-time switches and the install, and the
#    cache folder it filled; a change of any of them (or a removed cache) compiles again. DECKPOUND_SKIP_COMPILE=1 skips.
if [ "${DECKPOUND_SKIP_COMPILE:-0}" != "1" ]; then
  cstamp="$venv/.deckpound-compiled"
  ckey="$( { cat "$stamp"; echo "${DECKPOUND_TAKEDA_SHORTCUT:-1} ${NUMBA_CACHE_DIR:-} ${XDG_CACHE_HOME:-$HOME/.cache}";
            echo "$here"; kernels="$(find analytic -name '*.py' | LC_ALL=C sort)"
            stat -c '%n %Y' $kernels;   # numba's index checks path and mtime (every subpackage)
            for f in $kernels; do echo "$f"; cat "$f"; done; } | sha256sum | cut -d' ' -f1)"
  cdir="$(sed -n 2p "$cstamp" 2>/dev/null || true)"
  if [ "$(head -n 1 "$cstamp" 2>/dev/null || true)" != "$ckey" ] || [ ! -d "$cdir" ]; then
    echo "run.sh: compiling the numba kernels once (deckpound compile; a few minutes)" >&2
    "$venv/bin/deckpound" compile --stamp "$cstamp" --key "$ckey" >&2 \
      || echo "run.sh: warning: deckpound compile failed; kernels compile on first use" >&2
  fi
fi

# 3b. Python's bytecode of the package, kept up to date after any edit (about 30 ms when nothing
#     changed): Python reads it even where PYTHONDONTWRITEBYTECODE is set, which otherwise makes
#     every process compile deckpound's modules from source again (deckpound.compare.warmup.byte_compile)
"$venv/bin/python" -m compileall -q src/deckpound models opensees_build analytic compare >/dev/null \
  || echo "run.sh: warning: could not write Python's bytecode cache; processes start slower" >&2

# 4. the job
cmd="${1:-paper}"; shift || true
case "$cmd" in
  test) # one pytest worker per core (pytest-xdist, at most 4; none on one core); a file's tests
        # stay on one worker so its module fixtures are built once. "-n 0" in ARGS runs serially.
        workers="$(nproc 2>/dev/null || echo 1)"; [ "$workers" -gt 4 ] && workers=4
        [ "$workers" -le 1 ] && workers=0
        exec "$venv/bin/python" -m pytest -q -p no:cacheprovider -n "$workers" --dist loadfile "$@" ;;
  *)    exec "$venv/bin/deckpound" "$cmd" "$@" ;;
esac
