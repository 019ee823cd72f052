"""The contact-law table drives every dispatch (issue 11 item 4): every row has a kernel branch
that computes its equation, an unknown code fails loudly instead of running another law, and
the engines' reads, the OpenSees refusals and the law study come from the table."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest
from _compliance_helpers import base_scene, with_contact, with_run

from deckpound.analytic.compliance import pack as compliance_pack
from deckpound.analytic.kernels import contact_law_checks as clc
from deckpound.analytic.kernels import contact_laws as cl
from deckpound.compare.engines import get_engine, run_engine
from deckpound.models.contact_laws_table import CONTACT_LAW_TABLE, FRICTION_MODEL_TABLE, contact_law
from deckpound.models.errors import SceneError
from deckpound.models.scene import CONTACT_LAWS, FRICTION_MODES

LAWS = [law.name for law in CONTACT_LAW_TABLE]
MODELS = [m.name for m in FRICTION_MODEL_TABLE]


def _packed(law: str, **contact):
    sc = with_contact(base_scene(), law=law, **contact)
    return sc, cl.pack_contact(sc)


def test_scene_choices_are_the_table():
    assert tuple(LAWS) == CONTACT_LAWS
    assert tuple(MODELS) == FRICTION_MODES
    assert [law.code for law in CONTACT_LAW_TABLE] == list(range(len(LAWS)))


@pytest.mark.parametrize("law", LAWS)
def test_every_law_has_a_kernel_branch_computing_its_equation(law):
    """First loading of a virgin corner (committed open, approach velocity v) at several
    penetrations and rates: the compiled branch gives the table's force, open gives zero."""
    _, cp = _packed(law, stiffness=2.0e6, restitution=0.7)
    clc.check_kernel_branches(cp)
    row = cp[0]
    for delta in (1e-5, 4e-4, 3e-3):  # below and above the bilinear yield (1 mm)
        for rate in (0.0, 0.05, -0.02):
            cs = cl.new_contact_state(np.full(4, 0.01))[0]
            cs[cl.S_CGD] = -0.3  # committed approach velocity 0.3 m/s
            closed, lam, dg, dgd = cl.normal_law(row, cs, -delta, -rate)
            want = contact_law(law).force(delta, rate, clc.law_parameters(row, cs))
            assert closed, (law, delta)
            assert lam == pytest.approx(want, rel=1e-12, abs=1e-9), (law, delta, rate)
            assert np.isfinite(dg) and np.isfinite(dgd)
        cs = cl.new_contact_state(np.full(4, 0.01))[0]
        closed, lam, _, _ = cl.normal_law(row, cs, +delta, 0.0)
        assert not closed and lam == 0.0, law


@pytest.mark.parametrize("mode", MODELS)
def test_every_friction_model_has_a_kernel_branch_computing_its_equation(mode):
    _, cp = _packed("linear", friction=0.3, friction_mode=mode, tangential_stiffness=1e5)
    row = cp[0]
    for lam_n, ds, ut in ((100.0, 1e-5, 0.01), (100.0, -1e-3, -0.5), (0.0, 1e-4, 0.1)):
        cs = np.zeros(cl.N_CS)
        _, lt, *_ = cl.friction_law(row, cs, lam_n, ds, ut)
        model = FRICTION_MODEL_TABLE[int(row[cl.P_FMODE])]
        want = model.force(lam_n, ds, ut, clc.law_parameters(row, cs)) if lam_n > 0 else 0.0
        assert lt == pytest.approx(want, rel=1e-12, abs=1e-12), (mode, lam_n, ds, ut)


def test_unknown_codes_fail_loudly():
    """A code without a branch gives a non-finite force (never another law's) and is refused
    before a run with the kernel named."""
    _, cp = _packed("bilinear")
    bad = cp.copy()
    bad[:, cl.P_LAW] = len(LAWS)
    cs = np.zeros(cl.N_CS)
    closed, lam, dg, _ = cl.normal_law(bad[0], cs, -1e-3, 0.0)
    assert closed and np.isnan(lam) and np.isnan(dg)
    with pytest.raises(NotImplementedError, match="normal_law"):
        clc.check_kernel_branches(bad)
    bad = cp.copy()
    bad[:, cl.P_FMODE] = len(MODELS)
    with pytest.raises(NotImplementedError, match="friction_law"):
        clc.check_kernel_branches(bad)


def test_a_run_with_an_unknown_code_is_refused(monkeypatch):
    pack = cl.pack_contact

    def broken(scene, **kw):
        cp = pack(scene, **kw)
        cp[:, cl.P_LAW] = 99
        return cp

    monkeypatch.setattr(cl, "pack_contact", broken)
    monkeypatch.setattr(compliance_pack, "MODELS_KEPT", 0)  # packed now, not kept from before
    with pytest.raises(NotImplementedError, match="code 99 has no branch"):
        run_engine("compliance", with_run(base_scene(), duration=0.05))


@pytest.mark.parametrize("law", LAWS)
def test_reads_and_refusals_follow_the_table(law):
    row = contact_law(law)
    sc = with_contact(base_scene(), law=law)
    read = get_engine("compliance").reads(sc, sc.compliance)
    assert set(row.params) <= read and "contact.law" in read
    ns_read = get_engine("nonsmooth").reads(sc, sc.nonsmooth)
    assert ("contact.law" in ns_read) == row.nonsmooth
    opensees = get_engine("opensees")
    if law == "bilinear":  # ImpactMaterial runs only with fine sub-steps (issue 12)
        with pytest.raises(SceneError, match="opensees.substeps >= 1000"):
            opensees.refuse(sc, sc.opensees)
        sc = sc.replace(opensees=dataclasses.replace(sc.opensees, substeps=1000))
    if row.opensees is None:
        with pytest.raises(SceneError, match="OpenSees cannot express"):
            opensees.refuse(sc, sc.opensees)
    else:
        opensees.refuse(sc, sc.opensees)


def test_law_study_has_one_case_per_row():
    from deckpound.compare.studies.sensitivity import law_cases

    assert [c.params["law"] for c in law_cases(base_scene())] == LAWS


def test_the_opensees_refusals_name_the_laws_opensees_expresses():
    """The refusal texts list, in words, the laws that have an OpenSees material: the same set
    as the table's ``opensees`` column."""
    expressed = {law.name for law in CONTACT_LAW_TABLE if law.opensees}
    for law in CONTACT_LAW_TABLE:
        if law.opensees_refusal and "; use " in law.opensees_refusal:
            listed = law.opensees_refusal.rsplit("; use ", 1)[1]
            named = {w.strip(" ,") for w in listed.replace(" or ", ", ").split(",")}
            assert named == expressed, law.name


def _trial_path():
    """A corner's trials through an impact: approach, loading, a repeated (zero-increment)
    trial, unloading, tension-side rates, separation, with commits between steps."""
    return [(+2e-4, -0.3), (-1e-4, -0.3), (-4e-4, -0.2), (-4e-4, -0.2), (-1.5e-3, -0.1),
            (-9e-4, 0.2), (-2e-4, 0.5), (-1e-5, 0.6), (+1e-4, 0.6), (-3e-4, -0.4)]  # fmt: skip


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("variant", ["default", "opensees"])
def test_the_python_source_of_the_law_kernels_is_the_compiled_law(law, variant):
    """check_kernel_branches probes the laws' Python source (no compiled code); along an
    impact's loading and unloading trials it gives bitwise the compiled kernels' forces,
    derivatives and state writes, for the law's default and OpenSees variants."""
    opensees = variant == "opensees"
    sc = with_contact(base_scene(), law=law, stiffness=2.0e6, restitution=0.7)
    cp = cl.pack_contact(sc, kv_clip=not opensees, impact_opensees=opensees)
    cp[:, cl.P_OTAN] = 1.0 if opensees else 0.0
    python_law = clc.python_source_kernels(cl)["normal_law"]
    row = cp[0]
    cs_c, cs_p = cl.new_contact_state(np.full(4, 0.01)), cl.new_contact_state(np.full(4, 0.01))
    for g, gd in _trial_path():
        for trial in (1.0, 0.5):  # two Newton trials, then commit the second
            got = cl.normal_law(row, cs_c[0], trial * g, gd)
            want = python_law(row, cs_p[0], trial * g, gd)
            assert got == want, (law, variant, g, gd)
            np.testing.assert_array_equal(cs_c, cs_p)
        gg = np.full(4, g / 2)
        cl.contact_commit(cs_c, gg, np.full(4, gd), np.ones(4, dtype=np.bool_))
        cl.contact_commit(cs_p, gg, np.full(4, gd), np.ones(4, dtype=np.bool_))


def test_the_branch_check_compiles_no_kernel():
    """check_kernel_branches runs before every compliance run: it loads no compiled kernel."""
    code = (
        "import numba\n"
        "from deckpound.analytic.kernels import contact_laws as cl, contact_law_checks as clc\n"
        "from deckpound.api import load_scene\n"
        "from deckpound.models.contact_laws_table import LAW_CODES\n"
        "for law in LAW_CODES:\n"
        "    clc.check_kernel_branches(cl.pack_contact(load_scene('saiidi-4span', "
        "set={'contact.law': law})))\n"
        "print([n for n, v in vars(cl).items() if numba.extending.is_jitted(v) and "
        "v.signatures])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
