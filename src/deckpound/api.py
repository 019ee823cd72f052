"""The Python API behind ``import deckpound as dp`` (see the package docstring).

Four verbs: :func:`load_scene`, :func:`run`, :func:`compare`, :func:`available_engines`. They are thin:
scenes come from :mod:`deckpound.models.scene_io`, engines from the registry
(:mod:`deckpound.compare.engines`), alignment and metrics from :mod:`deckpound.compare`.
"""

from __future__ import annotations

import functools
import html
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from deckpound.models.errors import SceneError
from deckpound.models.html_table import short_text
from deckpound.models.result import Result

__all__ = [
    "Comparison",
    "available_engines",
    "builtin_scenes",
    "compare",
    "load_scene",
    "run",
    "run_batch",
    "run_many",
]

#: the quantities :func:`compare` aligns and scores unless told otherwise (relative
#: displacements: what the gaps and springs see)
DEFAULT_QUANTITIES = (
    "deck_theta",
    "deck_y_rel",
    "deck_x_rel",
    "seat1_x_rel",
    "seat2_x_rel",
    "gap_c1",
    "gap_c3",
)


def caller_warnings(func: Callable) -> Callable:
    """Attribute the warnings ``func`` issues (OptionIgnored, QualityWarning, RecordWarning,
    PlausibilityWarning, ...) to the line that called it, not to deckpound's source.

    The warnings are collected while ``func`` runs (all of them: the caller's filters decide
    later) and issued again, in order, with ``stacklevel`` pointing at the caller, so the
    caller's filters (``"error"``, ``"ignore"``, once per line) and a notebook show them at
    the user's line. Python 3.12's ``skip_file_prefixes`` would do this too, but the package
    supports 3.11. They are issued again also when ``func`` raises.
    """

    @functools.wraps(func)
    def attributed(*args: Any, **kwargs: Any):
        pending: list[warnings.WarningMessage] = []
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                try:
                    return func(*args, **kwargs)
                finally:
                    pending = list(caught)
        finally:
            level = _caller_stacklevel(sys._getframe(1)) if pending else 2
            for w in pending:
                warnings.warn(w.message, w.category, stacklevel=level)

    return attributed


#: deckpound's packages: frames in their folders are not the caller's
_PACKAGES = (
    "deckpound",
    "deckpound.models",
    "deckpound.compare",
    "deckpound.analytic",
    "deckpound.opensees_build",
)


def _package_folders() -> tuple[str, ...]:
    """The folders of deckpound's packages (found without importing the subpackages)."""
    import importlib.util

    folders = []
    for name in _PACKAGES:
        spec = importlib.util.find_spec(name)
        folders += list(spec.submodule_search_locations or []) if spec else []
    return tuple(os.path.join(os.path.realpath(f), "") for f in folders)


def _caller_stacklevel(frame) -> int:
    """``stacklevel`` for a ``warnings.warn`` in the function that ``frame`` called: 2 is
    ``frame`` itself, one more for every frame inside deckpound's packages (``dp.compare``
    reached through the callable ``deckpound.compare`` module, an API function calling
    another), so the warning names the first line outside the package."""
    folders = _package_folders()
    level = 2
    while frame is not None and frame.f_back is not None:
        if not os.path.realpath(frame.f_code.co_filename).startswith(folders):
            break
        frame = frame.f_back
        level += 1
    return level


def _overrides(set_: Mapping[str, Any] | Iterable[str] | None) -> list[str]:
    """``{"contact.friction": 0.2}`` or ``["contact.friction=0.2"]`` → override strings."""
    if set_ is None:
        return []
    if isinstance(set_, Mapping):
        import json

        out = []
        for k, v in set_.items():
            # TOML values: strings quoted, booleans lower-case, numbers and lists as JSON
            out.append(f"{k}={json.dumps(v)}")
        return out
    return [str(s) for s in set_]


@caller_warnings
def load_scene(
    ref: str | Path = "saiidi-4span", set: Mapping[str, Any] | Iterable[str] | None = None
):
    """A scene by built-in name or TOML path, with field overrides.

    ``set`` maps dotted paths to values (``{"contact.stiffness": 2e6, "bents[1].y.beta": 0.3}``)
    or is a list of ``"path=value"`` strings, as ``--set`` on the command line.
    """
    from deckpound.models.scene_io import load_scene as _load

    return _load(ref, _overrides(set))


def builtin_scenes() -> list[str]:
    """Names of the scenes shipped with deckpound."""
    from deckpound.models.scene_io import builtin_scene_names

    return builtin_scene_names()


def available_engines() -> dict[str, str]:
    """Registered engines: name → one-line title."""
    from deckpound.compare.engines import engine_names, get_engine

    return {name: get_engine(name).title for name in engine_names()}


@caller_warnings
def run(
    scene,
    engine: str = "compliance",
    *,
    settings: Any = None,
    motion=None,
    raise_on_failure: bool = False,
    **options: Any,
):
    """Run one engine on a scene and return its :class:`~deckpound.models.result.Result`.

    ``settings`` replaces the engine's settings table of the scene (an instance of the engine's
    ``Settings`` class); ``options`` are the engine's extra keywords (e.g. ``initial_state``),
    and ``summary_only=True`` gives a result without histories (peaks, closures, seat margins,
    energy check and status only: what a sweep keeps of each case).
    """
    from deckpound.compare.engines import run_engine

    return run_engine(
        engine, scene, motion, settings=settings, raise_on_failure=raise_on_failure, **options
    )


@caller_warnings
def run_batch(
    scenes: Iterable,
    engine: str = "compliance",
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    cache: str | Path | None = None,
    progress: bool = False,
    summary_only: bool = False,
) -> list:
    """Run one engine on many scenes; the results in the order of ``scenes``.

    The cases run on ``workers`` local processes (default: one per core; 1: in this process)
    or on the Dask cluster at ``scheduler``; each worker loads the compiled kernels once for
    the whole batch (:mod:`deckpound.compare.pool`). ``cache`` is a result-cache folder:
    finished cases are never recomputed, so an interrupted batch resumes. Failed runs are
    returned as failed results (``result.ok`` is False), not raised. ``summary_only``: results
    without histories (peaks, closures, seat margins, energy check, status: :func:`run`), what
    a sweep of thousands of cases keeps.
    """
    from deckpound.compare.cases import Case, run_cases
    from deckpound.compare.engines import get_engine
    from deckpound.compare.pool import pool_scope
    from deckpound.compare.result_cache import ResultCache

    get_engine(engine)  # an unknown name is refused with the list of valid ones
    scenes = list(scenes)
    cases = [Case(f"{i}", engine, sc) for i, sc in enumerate(scenes)]
    store = ResultCache(cache) if cache is not None else None
    with pool_scope():
        results = run_cases(
            cases,
            cache=store,
            workers=workers,
            scheduler=scheduler,
            progress=progress,
            title=f"{engine} batch",
            summary_only=summary_only,
        )
    return [results[c.label] for c in cases]


#: ``dp.run_many`` is :func:`run_batch`
run_many = run_batch


@dataclass
class Comparison:
    """Several engines on one scene: results, the aligned frames and metrics.

    Attributes
    ----------
    results : engine name → Result (each on its own output time base).
    aligned : engine name → pandas DataFrame on the common time base (``t`` column).
    metrics : one row per (engine, quantity) against ``reference``: peaks, peak ratio, NRMSE,
        correlation, residuals (:func:`deckpound.compare.metrics.compare_pair`).
    reference : the engine the others are compared with.
    """

    results: dict[str, Any]
    aligned: dict[str, Any]
    metrics: Any
    reference: str
    quantities: tuple[str, ...] = field(default=DEFAULT_QUANTITIES)

    # -- figures ---------------------------------------------------------------------
    def plot(self, kind: str = "histories", quantities: Iterable[str] | None = None):
        """A matplotlib figure of the comparison (returned, not shown; not registered with
        pyplot).

        ``kind = "histories"``: one panel per quantity, every engine's history on its own
        output time base overlaid (:meth:`Result.plot`) in the engines' line styles (the
        paper figures' styles, :func:`deckpound.compare.engines.engine_style`). ``kind = "peaks"``:
        one panel per quantity, a bar per engine: its peak (:meth:`Result.peak`, over every
        step; for a gap its smallest value). Lengths in mm, angles in mrad (:func:`deckpound.models.result.display_unit`).
        ``quantities`` default to :attr:`quantities`.
        """
        from matplotlib.figure import Figure

        from deckpound.compare.engines import engine_style
        from deckpound.models.columns import column_unit
        from deckpound.models.result import display_unit

        kinds = ("histories", "peaks")
        if kind not in kinds:
            raise ValueError(f"kind must be one of {', '.join(kinds)}, got {kind!r}")
        names = tuple(self.quantities if quantities is None else quantities)
        missing = [q for q in names if not all(q in r.columns for r in self.results.values())]
        if not names or missing:
            raise ValueError(
                f"quantities {missing or '()'} are not in every result; compared: "
                + ", ".join(self.quantities)
            )
        fig = Figure(figsize=(7.0, 0.6 + 2.0 * len(names)), layout="constrained")
        axes = fig.subplots(len(names), 1, sharex=kind == "histories", squeeze=False)[:, 0]
        engines = list(self.results)
        for ax, q in zip(axes, names, strict=True):
            scale, unit = display_unit(column_unit(q))
            if kind == "histories":
                for name, res in self.results.items():
                    style = engine_style(name)
                    res.plot((q,), ax=ax, label=style.pop("label"), **style)
            else:
                peaks = [scale * self.results[e].peak(q) for e in engines]
                colors = [engine_style(e)["color"] for e in engines]
                ax.bar(range(len(engines)), peaks, color=colors)
                ax.set_xticks(range(len(engines)), engines)
                ax.grid(True, axis="y", alpha=0.3)
            # a gap's peak is its smallest value (the deepest penetration, Result.peak)
            what = "smallest" if q.startswith("gap_") else "peak"
            ax.set_ylabel(f"{q} [{unit}]" if kind == "histories" else f"{what} {q} [{unit}]")
        if kind == "histories":
            axes[-1].set_xlabel("time [s]")
        return fig

    # -- short text for consoles and notebooks ---------------------------------------
    def engine_rows(self) -> list[dict[str, str]]:
        """One row of short texts per engine: status, peak deck rotation θ_d [rad], gap
        closures, and against the reference its θ_d peak ratio and NRMSE (from
        :attr:`metrics`)."""
        rows = []
        for name, res in self.results.items():
            row = {"engine": name, "status": str(res.meta.get("status"))}
            row["peak θ_d [rad]"] = (
                f"{res.peak('deck_theta'):.4g}" if "deck_theta" in res.columns else ""
            )
            row["gap closures"] = f"{res.gap_closures}"
            for col, head in (("peak_ratio", "θ_d peak ratio"), ("nrmse", "θ_d NRMSE")):
                row[head] = self._theta_metric(name, col)
            rows.append(row)
        return rows

    def _theta_metric(self, engine: str, column: str) -> str:
        m = self.metrics
        if m is None or column not in getattr(m, "columns", ()):
            return ""
        hit = m[(m["engine"] == engine) & (m["quantity"] == "deck_theta")]
        return f"{float(hit[column].iloc[0]):.3g}" if len(hit) else ""

    def __repr__(self) -> str:
        engines = ", ".join(short_text(n, 30) for n in self.results)
        return (
            f"Comparison(reference {short_text(self.reference, 30)!r}, engines [{engines}], "
            f"{len(self.quantities)} quantities, {len(self.metrics)} metric rows)"
        )

    def _repr_html_(self) -> str:
        """An HTML table, one row per engine (:meth:`engine_rows`), every text escaped."""
        rows = self.engine_rows()
        heads = list(rows[0]) if rows else []
        head = "".join(f"<th>{html.escape(h)}</th>" for h in heads)
        body = "".join(
            "<tr>" + "".join(f"<td>{html.escape(r[h])}</td>" for h in heads) + "</tr>" for r in rows
        )
        title = html.escape(f"Comparison against {self.reference}")
        return f"<b>{title}</b><table><tr>{head}</tr>{body}</table>"


@caller_warnings
def compare(
    scene,
    engines: Iterable[str] | None = None,
    *,
    reference: str | None = None,
    quantities: Iterable[str] = DEFAULT_QUANTITIES,
    dt: float | None = None,
    cache: str | Path | None = None,
    workers: int | None = 1,
    results: Mapping[str, Result] | None = None,
) -> Comparison:
    """Run ``engines`` (default: every registered engine) on ``scene``, align and score them
    against ``reference`` (default :data:`deckpound.compare.engines.DEFAULT_REFERENCE`, or the first
    engine when that one is not run). ``cache`` is a result-cache folder (finished cases are
    never recomputed); ``workers`` local processes (1: in this process). ``results``: engine →
    :class:`Result` the caller already has (e.g. from :func:`run` of the same scene): those
    engines are not run again; a result of another scene (its physics hash differs) is
    refused."""
    from deckpound.compare.align import align
    from deckpound.compare.cases import Case, run_cases
    from deckpound.compare.engines import DEFAULT_REFERENCE, engine_names, get_engine
    from deckpound.compare.metrics import metrics_against
    from deckpound.compare.result_cache import ResultCache
    from deckpound.models.result import physics_hash

    given = dict(results or {})
    names = list(engines) if engines is not None else list(engine_names())
    names += [n for n in given if n not in names]
    for n in names:
        get_engine(n)  # unknown names are refused with the list of valid ones
    for n, r in given.items():
        if not r.has_histories:
            raise SceneError(
                f"results[{n!r}]",
                "is a summary-only result (no histories to align): run it without summary_only",
            )
        if r.meta.get("physics_hash") != physics_hash(scene):
            raise SceneError(
                f"results[{n!r}]",
                "was run on another scene (its physics hash differs from this scene's): "
                "run it again on this scene or leave it out",
            )
    ref = reference or (DEFAULT_REFERENCE if DEFAULT_REFERENCE in names else names[0])
    if ref not in names:
        names.insert(0, ref)
    store = ResultCache(cache) if cache is not None else None
    run = [n for n in names if n not in given]
    ran = run_cases([Case(n, n, scene) for n in run], cache=store, workers=workers, progress=False)
    results = {n: given[n] if n in given else ran[n] for n in names}
    qs = tuple(q for q in quantities if all(q in r.columns for r in results.values()))
    aligned = align(results, dt=dt, columns=list(qs))
    metrics = metrics_against(results, aligned, ref, list(qs))
    return Comparison(
        results=results, aligned=aligned, metrics=metrics, reference=ref, quantities=qs
    )
