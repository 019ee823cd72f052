"""Engine registry and the contract every engine fulfils.

An engine is a function ``run(scene, motion=None, *, raise_on_failure=False) -> Result``:

1. It reads only the scene (including its own settings table: ``scene.opensees``,
   ``scene.compliance`` or ``scene.nonsmooth``) and the support motion; when ``motion`` is
   None it builds it with :func:`deckpound.models.excitation.support_motion`.
2. It runs for :func:`deckpound.models.excitation.analysis_duration` seconds and stores output
   every ``scene.run.output_dt`` (rounded to a whole number of its own steps, see
   :func:`output_stride`), starting with t = 0.
3. It returns a :class:`deckpound.models.result.Result` with every column of
   :func:`deckpound.models.result.standard_columns` (SI units with tonnes; ``fn`` ≥ 0 is
   compression) and metadata ``wall_time`` [s], ``steps``, ``iterations``,
   ``contact_events`` (gap closures), ``failures``, ``status``, ``message`` and, on failure,
   ``failed_time`` [s] and ``failed_step``.
4. A failure (non-convergence, unsolved contact problem, non-finite state) never returns
   NaN silently: the result holds the output up to the failure with ``status = "failed"``;
   with ``raise_on_failure=True`` it raises :class:`deckpound.models.errors.EngineFailure`.
5. It warns (``warnings.warn``) about scene options it ignores.

Engines are looked up by name in :data:`ENGINES`; the modules are imported lazily, so that
OpenSees is loaded only when its engine runs.
"""

from __future__ import annotations

import importlib
from typing import Callable

from deckpound.models.errors import SceneError

ENGINES: dict[str, str] = {
    "opensees": "deckpound.opensees_build.engine:run_opensees",
    "compliance": "deckpound.analytic.compliance:run_compliance",
    "nonsmooth": "deckpound.analytic.nonsmooth:run_nonsmooth",
}


def get_engine(name: str) -> Callable:
    """The run function of engine ``name`` (unknown names list the valid ones)."""
    if name not in ENGINES:
        raise SceneError("engine", f"unknown engine {name!r}; valid engines: {', '.join(ENGINES)}")
    module, func = ENGINES[name].split(":")
    return getattr(importlib.import_module(module), func)


def output_stride(dt: float, output_dt: float) -> int:
    """Steps between stored outputs: round(output_dt / dt), at least 1."""
    return max(1, int(round(output_dt / dt)))


def run_engine(name: str, scene, motion=None, **kwargs):
    """Run engine ``name`` on ``scene`` and attach the full scene to the result's metadata
    (so a result folder is self-describing: VTK export and re-runs need nothing else)."""
    from deckpound.models._fields import to_mapping

    result = get_engine(name)(scene, motion, **kwargs)
    result.meta["scene"] = to_mapping(scene)
    return result
