"""Python-side views of the contact-law kernels of :mod:`deckpound.analytic.kernels.contact_laws`.

:func:`law_parameters` names one corner's packed parameters as the table's ``force``
functions do (:mod:`deckpound.models.contact_laws_table`, which the kernels are tested
against); :func:`check_kernel_branches` refuses, before a run, a law or friction code the
kernels have no branch for.
"""

from __future__ import annotations

import types

import numpy as np
from numba.extending import is_jitted

from deckpound.analytic.kernels import contact_laws
from deckpound.analytic.kernels.contact_laws import (
    N_CS,
    P_C,
    P_D,
    P_DY,
    P_E,
    P_FMODE,
    P_K,
    P_K2,
    P_KT,
    P_LAW,
    P_MU,
    P_N,
    P_V0,
    S_CGD,
    V_IMPACT_MIN,
    friction_law,
    normal_law,
)

__all__ = ["check_kernel_branches", "law_parameters", "python_source_kernels"]


def law_parameters(cp_row, cs_row) -> dict:
    """The packed parameters of one corner by the names the table's ``force`` functions use
    (:mod:`deckpound.models.contact_laws_table`); ``v_impact``: the committed approach
    velocity −ġ."""
    return {
        "k": cp_row[P_K],
        "n": cp_row[P_N],
        "c": cp_row[P_C],
        "hc": cp_row[P_D],
        "k2": cp_row[P_K2],
        "dy": cp_row[P_DY],
        "e": cp_row[P_E],
        "mu": cp_row[P_MU],
        "kt": cp_row[P_KT],
        "v0": cp_row[P_V0],
        "v_min": V_IMPACT_MIN,
        "v_impact": -cs_row[S_CGD],
    }


def python_source_kernels(module) -> dict:
    """The numba kernels of ``module`` as plain Python functions, by name: each kernel's
    Python source (``py_func``) with the module's other kernels it calls bound to their
    Python source too, so a dispatcher such as :func:`normal_law` runs the law kernels it
    inlines without compiling or loading any of them."""
    namespace = dict(vars(module))
    pure = {}
    for name, value in vars(module).items():
        if is_jitted(value):
            fn = value.py_func
            pure[name] = types.FunctionType(
                fn.__code__, namespace, fn.__name__, fn.__defaults__, fn.__closure__
            )
    namespace.update(pure)  # the functions' globals: calls between kernels stay in Python
    return pure


_PYTHON_LAWS = python_source_kernels(contact_laws)


def check_kernel_branches(cp) -> None:
    """Raise NotImplementedError if a corner's law or friction code has no kernel branch.

    Probes :func:`normal_law` and :func:`friction_law` on a scratch state at a closed state;
    the final branch of each gives a non-finite force. The probe runs their Python source
    (:func:`python_source_kernels`: the branches numba compiles, no compiled code needed):
    calling the compiled kernels from Python would load them from numba's cache in every
    fresh process (``tests/test_contact_law_table.py`` checks the compiled kernels' branches).
    """
    normal, friction = _PYTHON_LAWS[normal_law.__name__], _PYTHON_LAWS[friction_law.__name__]
    for row in cp:
        cs = np.zeros(N_CS)
        closed, lam, dg, _ = normal(row, cs, -1.0e-3, 0.0)
        if not (closed and np.isfinite(lam) and np.isfinite(dg)):
            raise NotImplementedError(
                f"contact law code {int(row[P_LAW])} has no branch in "
                "deckpound.analytic.kernels.contact_laws.normal_law (table: "
                "deckpound.models.contact_laws_table)"
            )
        _, lt, *_ = friction(row, cs, 1.0, 0.0, 0.0)
        if not np.isfinite(lt):
            raise NotImplementedError(
                f"friction code {int(row[P_FMODE])} has no branch in "
                "deckpound.analytic.kernels.contact_laws.friction_law (table: "
                "deckpound.models.contact_laws_table)"
            )
