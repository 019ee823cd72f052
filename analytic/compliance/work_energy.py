"""The work–energy balance of the compliance loops: named offsets and the output columns.

Both compliance loops keep five running work totals [kJ] (the Newmark loop in its workspace
array ``W``, trapezoidal over each step; the adaptive loop as extra ODE components, the slice
``y[2 n_dof:]`` of its state, integrated from the powers): the offsets ``W_*`` name them. The
output columns :data:`deckpound.models.columns.ENERGY_COLUMNS` follow from them and from the
energies stored at the committed state (:func:`energy_columns`); the offsets ``E_*`` name
those columns in their order.
"""

from __future__ import annotations

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.models.columns import ENERGY_COLUMNS

__all__ = [
    "E_CONTACT_DISSIPATED",
    "E_CONTACT_STORED",
    "E_ERROR",
    "E_FRICTION",
    "E_HYSTERETIC",
    "E_INPUT",
    "E_KINETIC",
    "E_STRAIN",
    "E_VISCOUS",
    "N_ENERGY",
    "N_WORK",
    "W_CONTACT",
    "W_FRICTION",
    "W_INPUT",
    "W_SPRINGS",
    "W_VISCOUS",
    "energy_columns",
    "stick_spring_energy",
]

#: Running work totals [kJ]: work of the support reactions (plus the initial mechanical
#: energy), of the spring restoring forces ∫ f_s dd, of the viscous forces (Rayleigh and
#: dashpots), of the normal contact forces −∫ λ_N dg and of friction −∫ λ_T ds.
W_INPUT, W_SPRINGS, W_VISCOUS, W_CONTACT, W_FRICTION = range(5)
N_WORK = 5

#: Offsets of the energy output columns (the order of ENERGY_COLUMNS).
(
    E_INPUT,
    E_KINETIC,
    E_STRAIN,
    E_VISCOUS,
    E_HYSTERETIC,
    E_CONTACT_STORED,
    E_CONTACT_DISSIPATED,
    E_FRICTION,
    E_ERROR,
) = (
    ENERGY_COLUMNS.index(f"energy_{name}")
    for name in (
        "input",
        "kinetic",
        "strain",
        "viscous",
        "hysteretic",
        "contact_stored",
        "contact_dissipated",
        "friction",
        "error",
    )
)
N_ENERGY = len(ENERGY_COLUMNS)


@kernel(inline="always")
def stick_spring_energy(cp, cs):
    """Energy stored in the tangential stick springs of the corners, Σ ½ λ_T² / k_t [kJ] (the
    part of :func:`deckpound.analytic.kernels.contact_laws.contact_stored_energy` that friction, not
    the normal law, stores)."""
    efs = 0.0
    for c in range(cs.shape[0]):
        if cl.has_stick_spring(cp[c, cl.P_FMODE]) and cs[c, cl.S_CFT] != 0.0:
            efs += 0.5 * cs[c, cl.S_CFT] ** 2 / cp[c, cl.P_KT]
    return efs


@kernel(inline="always")
def energy_columns(out, base, W, ke, es, ec, efs):
    """The energy columns into ``out[base + E_*]`` from the work totals ``W`` (offsets
    ``W_*``) and the energies at the committed state: kinetic ``ke``, recoverable spring
    energy ``es``, contact stored ``ec`` (stick springs included) and its stick-spring part
    ``efs`` [kJ]. Hysteretic = spring work − recoverable; dissipated by contact = contact work
    − normal-law stored energy; friction = friction work − stick-spring energy; error = input −
    all the others."""
    out[base + E_INPUT] = W[W_INPUT]
    out[base + E_KINETIC] = ke
    out[base + E_STRAIN] = es
    out[base + E_VISCOUS] = W[W_VISCOUS]
    out[base + E_HYSTERETIC] = W[W_SPRINGS] - es
    out[base + E_CONTACT_STORED] = ec
    out[base + E_CONTACT_DISSIPATED] = W[W_CONTACT] - (ec - efs)
    out[base + E_FRICTION] = W[W_FRICTION] - efs
    out[base + E_ERROR] = W[W_INPUT] - (
        ke + W[W_SPRINGS] + W[W_VISCOUS] + W[W_CONTACT] + W[W_FRICTION]
    )
