"""Run the experiment's test sequence with an engine, carrying gap and stiffness between runs.

The carry rule lives in :mod:`deckpound.models.sequence`; this module only drives engines
through it. Runs of one engine are sequential (each needs the previous result); different
engines run in parallel. Every run is cached under its full description.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from deckpound.compare.cases import case_key, interrupted, map_parallel, run_case, surface_warnings
from deckpound.compare.progress import Progress
from deckpound.compare.result_cache import ResultCache
from deckpound.models.errors import SceneError
from deckpound.models.result import Result
from deckpound.models.scene import Scene
from deckpound.models.sequence import SpecimenState, initial_state, next_state, scene_for_run


@dataclass
class SequenceRun:
    """One run of a sequence: its PGA label, the state it started from, its scene and result."""

    index: int
    pga: float
    state: SpecimenState
    scene: Scene
    result: Result
    cached: bool = False  # the result came from the result cache (not computed now)


def run_sequence(
    scene: Scene,
    engine: str,
    cache_folder: str | Path | None = None,
    start: SpecimenState | None = None,
    runs: int | None = None,
) -> list[SequenceRun]:
    """The runs of ``scene.sequence`` with one engine (the first ``runs`` of them, default
    all); stops after a failed run."""
    cache = ResultCache(cache_folder) if cache_folder is not None else None
    state = start if start is not None else initial_state(scene)
    done: list[SequenceRun] = []
    pgas = scene.sequence.pgas if runs is None else scene.sequence.pgas[:runs]
    for i, pga in enumerate(pgas):
        run_scene = scene_for_run(scene, pga, state)
        key = case_key(engine, run_scene)
        result = cache.get(key, engine) if cache is not None else None
        cached = result is not None
        if result is None:
            result = run_case(engine, run_scene)
            if cache is not None and result.finished:
                cache.put(key, result)
        done.append(SequenceRun(i + 1, pga, state, run_scene, result, cached))
        if not result.ok:
            break
        # the bent deformations come from the result's columns: no excitation is rebuilt
        state = next_state(scene, state, run_scene, result, None)
    return done


def strongest_run(scene: Scene) -> int:
    """The sequence's strongest run (1-based): the largest PGA, the last of equal ones."""
    pgas = scene.sequence.pgas
    return max(range(len(pgas)), key=lambda i: (pgas[i], i)) + 1


def state_before(
    scene: Scene, run: int, engine: str, cache_folder: str | Path | None = None
) -> tuple[SpecimenState, Scene]:
    """The state the specimen carries into run ``run`` (1-based) of the sequence driven by
    ``engine`` (runs 1 … run − 1 are run or read from the cache), and that run's scene."""
    n = len(scene.sequence.pgas)
    if not 1 <= run <= n:
        raise SceneError("--state", f"names run {run}, but the sequence has runs 1 to {n}")
    state = initial_state(scene)
    if run > 1:
        runs = run_sequence(scene, engine, cache_folder, runs=run - 1)
        last = runs[-1]
        if len(runs) < run - 1 or not last.result.ok:
            raise SceneError(
                "--state",
                f"run {last.index} of the {engine} sequence failed "
                f"({last.result.meta.get('message', '')}), so no state reaches "
                f"run {run}",
            )
        state = next_state(scene, last.state, last.scene, last.result, None)
    return state, scene_for_run(scene, scene.sequence.pgas[run - 1], state)


def run_sequences(
    scene: Scene,
    engines: list[str],
    cache_folder: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> dict[str, list[SequenceRun]]:
    """The sequence for several engines, one engine per worker."""
    out: dict[str, list[SequenceRun]] = {}
    bar = Progress(len(engines), "sequence", progress)

    def done(engine, runs):
        out[engine] = runs
        bar.advance()

    try:
        map_parallel(
            engines, lambda e: (scene, e, cache_folder), run_sequence, done, workers, scheduler
        )
    except KeyboardInterrupt as err:  # each finished run is cached: say so (issue 14)
        bar.close()
        raise interrupted(
            err, "sequence", len(out), len(engines), cache_folder, "engines' sequences", "run"
        ) from None
    finally:
        bar.close()  # its log thread ends with it, whatever ended the sequences
    surface_warnings(r.result for runs in out.values() for r in runs)
    return {e: out[e] for e in engines}
