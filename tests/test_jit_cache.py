"""numba's on-disk cache of the analytic kernels is keyed by their sources (analytic/_jit.py).

numba validates a cached function against its own file only; the kernels it inlines from other
modules are not checked. The package therefore places the cache in a directory named by a hash
of all its sources and of the compile-time switches; a user's NUMBA_CACHE_DIR wins.
"""

import os
import subprocess
import sys

SNIPPET = "import deckpound.analytic, numba; print(numba.config.CACHE_DIR)"


def _cache_dir(env_updates: dict[str, str], drop=("NUMBA_CACHE_DIR",)) -> str:
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(env_updates)
    out = subprocess.run(
        [sys.executable, "-c", SNIPPET], env=env, capture_output=True, text=True, check=True
    )
    return out.stdout.strip().splitlines()[-1]


def test_cache_directory_is_keyed_by_sources_and_switches(tmp_path):
    a = _cache_dir({"XDG_CACHE_HOME": str(tmp_path)})
    assert a.startswith(str(tmp_path / "deckpound" / "numba")), a
    assert _cache_dir({"XDG_CACHE_HOME": str(tmp_path)}) == a  # deterministic
    # a switch frozen into the kernels at compile time gives another cache
    b = _cache_dir({"XDG_CACHE_HOME": str(tmp_path), "DECKPOUND_TAKEDA_SHORTCUT": "0"})
    assert b != a and b.startswith(str(tmp_path / "deckpound" / "numba"))


def test_user_numba_cache_dir_wins(tmp_path):
    mine = str(tmp_path / "mine")
    assert _cache_dir({"NUMBA_CACHE_DIR": mine}, drop=()) == mine
