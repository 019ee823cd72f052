"""Issue 31: a contact table per joint (``joints[k].contact``), in every engine.

A joint gives the contact fields in which it differs from the scene's ``contact`` table (law,
stiffness, restitution, friction, ...) and takes the others from it. The checks:

* the scene: the joint's table is the scene's with the given fields in their place, a
  ``--set contact.X`` reaches every joint that does not give X, bad values are refused naming
  the joint's field, and the scene file keeps the joint's table (round trip);
* the engines apply it corner by corner: the packed per-corner laws, Newton's impact law at
  the joint with the joint's restitution (nonsmooth, the closed form of
  ``tests/test_segment_oracles.py``), the joint's Kelvin–Voigt law while the abutments keep
  the linear law (compliance, that closed form with the face restitution), and the clone equal
  to OpenSees with the joint's own stiffness and friction;
* an engine refuses, naming the joint's field, what it cannot express, and warns about the
  joint's fields it does not read. (OpenSees with friction at the joint alone, its corners
  zeroLengthContact2D and the abutments' gap materials, and its Python export:
  ``tests/test_opensees_segments.py``, variant ``joint-friction``.)
"""

from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest
from _segment_scenes import velocities
from test_segment_oracles import (
    FRAME,
    M1,
    ROUND_OFF,
    V1,
    V2,
    face_contact,
    newton_pair,
    two_body,
)

import deckpound as dp
from deckpound.analytic.kernels.contact_laws import (
    P_C,
    P_E,
    P_K,
    P_LAW,
    P_MU,
    pack_contact,
)
from deckpound.compare.engines import get_engine
from deckpound.models.contact_laws_table import LAW_CODES
from deckpound.models.contact_params import corner_contacts
from deckpound.models.errors import SceneError
from deckpound.models.magnitudes import magnitude_findings
from deckpound.models.plan import plan_of
from deckpound.models.scene_io import load_scene, parse_toml, scene_from_mapping, scene_to_toml

HAS_OPENSEES = importlib.util.find_spec("openseespy") is not None

pytestmark = [
    pytest.mark.filterwarnings("ignore:compliance engine. penetration"),
    pytest.mark.filterwarnings("ignore:nonsmooth engine. penetration"),
    pytest.mark.filterwarnings("ignore:opensees engine. penetration"),
]


def test_a_joint_gives_its_fields_and_takes_the_rest_from_the_scene():
    sc = load_scene(
        "two-frame",
        ["joints[0].contact.restitution=0.2", "joints[0].contact.stiffness=5e6"],
    )
    joint = sc.joint_contact(0)
    assert (joint.restitution, joint.stiffness) == (0.2, 5e6)
    assert (joint.law, joint.friction, joint.geometry) == (
        sc.contact.law,
        sc.contact.friction,
        sc.contact.geometry,
    )
    # a change of the scene's table reaches the fields the joint does not give
    changed = sc.replace({"contact.law": "hertz", "contact.restitution": 0.9})
    assert changed.joint_contact(0).law == "hertz"
    assert changed.joint_contact(0).restitution == 0.2
    # the scene file keeps the joint's own fields, and only those
    text = scene_to_toml(sc)
    assert scene_from_mapping(parse_toml(text)) == sc
    assert parse_toml(text)["joints"][0]["contact"] == {"stiffness": 5e6, "restitution": 0.2}
    # no joint table: the scene's, the same object
    plain = load_scene("two-frame")
    assert plain.joint_contact(0) is plain.contact
    assert [w for w, _ in sc.contact_tables()] == ["contact", "joints[0].contact"]
    assert "; joints[0]: stiffness 5e+06, restitution 0.2" in repr(sc)  # the summary says it


@pytest.mark.parametrize(
    "override, field",
    [
        ("joints[0].contact.restitution=1.5", "joints[0].contact.restitution"),
        ("joints[0].contact.law=bogus", "joints[0].contact.law"),
        ("joints[0].contact.geometry=nonlinear", "joints[0].contact.geometry"),
    ],
)
def test_a_bad_joint_field_is_refused_by_its_name(override, field):
    with pytest.raises(SceneError) as err:
        load_scene("two-frame", [override])
    assert err.value.field == field, str(err.value)


def test_the_plausibility_checks_read_the_joint_fields_given():
    """A joint's friction beyond any surface is an error at its own field; a field the joint
    does not give is the scene's, checked (once) there."""
    sc = load_scene("two-frame", ["joints[0].contact.friction=40", "contact.stiffness=2e11"])
    found = {(level, field) for level, field, _ in magnitude_findings(sc)}
    assert ("error", "joints[0].contact.friction") in found
    assert ("warning", "contact.stiffness") in found
    assert not any(f == "joints[0].contact.stiffness" for _, f in found)


def test_a_law_refusal_names_the_joint():
    """flores needs e > 0: a joint that asks for it with the scene's e = 0 is refused at the
    joint's restitution, the value it takes."""
    with pytest.raises(SceneError) as err:
        load_scene("two-frame", ["contact.restitution=0.0", "joints[0].contact.law=flores"])
    assert err.value.field == "joints[0].contact.restitution"
    assert "flores" in str(err.value)


def test_every_corner_is_packed_with_its_tables_values():
    sc = load_scene(
        "two-frame",
        [
            "contact.friction=0.3",
            "contact.friction_mode=stick",
            "joints[0].contact.law=kelvin-voigt",
            "joints[0].contact.stiffness=4e6",
            "joints[0].contact.restitution=0.3",
            "joints[0].contact.friction=0.6",
        ],
    )
    plan = plan_of(sc)
    cp = pack_contact(sc, plan)
    tables = corner_contacts(sc, plan)
    for corner, row, ct in zip(plan.corners, cp, tables, strict=True):
        at_joint = corner.joint >= 0
        assert ct == (sc.joint_contact(corner.joint) if at_joint else sc.contact)
        law = "kelvin-voigt" if at_joint else sc.contact.law
        assert row[P_LAW] == LAW_CODES[law], corner.name
        assert (row[P_K], row[P_E], row[P_MU]) == (
            (4e6, 0.3, 0.6) if at_joint else (sc.contact.stiffness, sc.contact.restitution, 0.3)
        )
        assert row[P_C] > 0.0  # the dashpot of every corner's own e and k
    assert {c.name for c in plan.corners if c.joint >= 0} == {"j1_c1", "j1_c2"}


def test_nonsmooth_impact_at_a_joint_takes_the_joints_restitution():
    """Two free segments meet at the joint (the abutments 1 m away never close): Newton's
    closed form with the joint's e = 0.3, not the scene's 0.9."""
    sc = two_body(1.0, 0.9, 0.05, {"nonsmooth.h": 1e-4, "joints[0].contact.restitution": 0.3})
    v = velocities(dp.run(sc, engine="nonsmooth"), sc)
    np.testing.assert_allclose(
        v[:, 0], newton_pair(M1, M1, V1, V2, 0.3), rtol=0, atol=ROUND_OFF * abs(V2)
    )


def test_compliance_joint_law_differs_from_the_abutments():
    """The scene's law is the linear gap (elastic: e_face = 1 at the joint if it were used);
    the joint's own Kelvin–Voigt law with e = 0.5 gives the face restitution of that law's
    calibration (``face_contact``), to the adaptive integrator's error control."""
    e = 0.5
    e_face, _, _ = face_contact(e, M1, M1, FRAME)
    sc = two_body(
        1.0,
        e,
        0.05,
        {
            "contact.law": "linear",
            "joints[0].contact.law": "kelvin-voigt",
            "compliance.integrator": "adaptive",
            "compliance.rtol": 1e-10,
        },
    )
    v = velocities(dp.run(sc, engine="compliance"), sc)
    np.testing.assert_allclose(v[:, 0], newton_pair(M1, M1, V1, V2, e_face), atol=1e-6 * (V1 - V2))
    assert abs(e_face - 1.0) > 0.5  # the scene's law would have bounced elastically


def test_an_engine_warns_about_the_joint_fields_it_does_not_read():
    sc = load_scene("two-frame", ["joints[0].contact.stiffness=5e6", "run.duration=0.01"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        msgs = get_engine("nonsmooth").validate(sc)
    assert any(m.startswith("joints[0].contact.stiffness = 5000000.0 does nothing") for m in msgs)
    assert any("joints[0].contact.stiffness" in str(w.message) for w in caught)
    assert not any("joints[0]" in m for m in get_engine("compliance").validate(sc, warn=False))


def test_an_engine_refuses_a_joint_table_it_cannot_express():
    adaptive_contact2d = load_scene(
        "two-frame",
        [
            "compliance.integrator=adaptive",
            "joints[0].contact.friction=0.3",
            "joints[0].contact.friction_mode=contact2d",
        ],
    )
    with pytest.raises(SceneError) as err:
        get_engine("compliance").validate(adaptive_contact2d, warn=False)
    assert err.value.field == "compliance.integrator" and "joints[0].contact" in str(err.value)
    if HAS_OPENSEES:
        flores = load_scene("two-frame", ["joints[0].contact.law=flores"])
        with pytest.raises(SceneError) as err:
            get_engine("opensees").validate(flores, warn=False)
        assert err.value.field == "joints[0].contact.law"


@pytest.mark.skipif(not HAS_OPENSEES, reason="no openseespy")
@pytest.mark.parametrize(
    "overrides",
    [
        ["joints[0].contact.stiffness=3e6"],
        ["joints[0].contact.law=kelvin-voigt", "joints[0].contact.restitution=0.4"],
        [
            "contact.friction=0.2",
            "contact.friction_mode=contact2d",
            "joints[0].contact.friction=0.5",
            "joints[0].contact.stiffness=2e6",
            "joints[0].contact.tangential_stiffness=3e5",
        ],
    ],
    ids=["stiffness", "kelvin-voigt", "friction"],
)
def test_clone_equals_opensees_with_a_joint_table_of_its_own(overrides):
    """The matrix's criterion over the first 8 s of two-frame, where the joint pounds."""
    from deckpound.compare.verify import matrix as vm
    from deckpound.compare.verify.clone import verify_clone

    sc = load_scene("two-frame", [*overrides, "run.duration=8.0"])
    rep = verify_clone(sc)
    assert rep["status"] == {"opensees": "success", "compliance": "success"}
    assert max(rep["worst"][1], rep["worst_velocity"][1]) <= vm.TOLERANCE, rep["worst"]
    assert rep["peaks"]["fn_j1_c1"] > 0.0
