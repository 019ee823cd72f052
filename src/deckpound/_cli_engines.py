"""CLI: ``run``, ``export``, ``modes`` and ``verify``."""

from __future__ import annotations

import argparse

from deckpound.models.errors import DoubtfulResult, EngineFailure

from ._cli_args import add_scene_args, check_output_folder, int_in
from ._terminal import terminal_text


def register(sub: argparse._SubParsersAction) -> None:
    from deckpound.compare.engines import ENGINES

    p = sub.add_parser("run", help="run one engine on a scene and write DIR/<engine>.csv/.json")
    add_scene_args(p)
    p.add_argument("--engine", required=True, metavar="NAME", help=f"one of: {', '.join(ENGINES)}")
    p.add_argument("-o", "--output", required=True, metavar="DIR")
    p.set_defaults(func=_run)

    p = sub.add_parser(
        "export",
        help="write a standalone OpenSees script of a scene (plus its "
        "data folder <stem>_data/ with the records and manifest.json)",
    )
    add_scene_args(p)
    p.add_argument("--format", required=True, choices=("tcl", "py"))
    p.add_argument("-o", "--output", required=True, metavar="FILE")
    p.set_defaults(func=_export)

    p = sub.add_parser("modes", help="periods and mode shapes of the contact-free model")
    add_scene_args(p)
    p.add_argument(
        "--engine",
        default="opensees",
        choices=("opensees", "analytic"),
        help="OpenSees eigen (default) or the 7-DOF matrices",
    )
    p.set_defaults(func=_modes)

    p = sub.add_parser("verify", help="cross-verify the clone against OpenSees")
    vsub = p.add_subparsers(dest="verify_command", metavar="WHAT")
    vsub.required = True
    q = vsub.add_parser("takeda", help="Hysteretic clone vs OpenSees on random strain histories")
    q.add_argument("--states", type=int_in(1, 10_000_000), default=20000)
    q.add_argument("--seed", type=int_in(0, 2**63 - 1), default=0)
    q.set_defaults(func=_verify_takeda)
    q = vsub.add_parser(
        "clone",
        help="compliance newmark vs OpenSees rigid: the matrix of "
        "contact laws x friction x skew x damping (one case with --set)",
    )
    add_scene_args(q)
    q.add_argument(
        "--quick", action="store_true", help="a small subset of the matrix over the first 5 s"
    )
    q.set_defaults(func=_verify_clone)
    q = vsub.add_parser(
        "impact-law",
        help="nonsmooth engine: Newton's impact law vs the "
        "energy-safe variant on a scene, without and with friction",
    )
    add_scene_args(q)
    q.set_defaults(func=_verify_impact_law)
    q = vsub.add_parser(
        "contact-step",
        help="the default step of the penalty engines at contact stiffnesses 1e6-1e8 kN/m: "
        "energy created and peak rotation against a tenth of the step",
    )
    add_scene_args(q)
    q.set_defaults(func=_verify_contact_step)


def _peak_rotations(result) -> str:
    """'peak θ_d 3.622 mrad', or each deck segment's: 'peak θ frame1 1.2, frame2 0.8 mrad'."""
    if "deck_theta" in result.columns:
        return f"peak θ_d {1e3 * result.peak('deck_theta'):.3f} mrad"
    names = [c for c in result.columns if c.endswith("_theta") and not c.startswith("seat")]
    each = ", ".join(
        f"{terminal_text(c[: -len('_theta')])} {1e3 * result.peak(c):.3f}" for c in names
    )
    return f"peak θ {each} mrad"


def _run(args) -> int:
    from deckpound.compare.engines import get_engine, run_engine
    from deckpound.models import plausibility
    from deckpound.models.excitation import support_motion
    from deckpound.models.file_io import output_folder
    from deckpound.models.record_checks import scaling_summary
    from deckpound.models.scene_io import load_scene

    get_engine(args.engine)  # refuse an unknown name before any work
    check_output_folder(args.output)
    scene = load_scene(args.scene, args.overrides)
    motion = support_motion(scene)
    plausibility.enforce(scene, motion, engines=(get_engine(args.engine),))
    result = run_engine(args.engine, scene, motion)
    with output_folder(args.output, f"run {args.engine}") as out:
        csv_path, _ = result.write(out)
    m = result.meta
    scaled = scaling_summary(m.get("record"))  # any scaling of a user's record is said
    scaled = f"; {scaled}" if scaled else ""
    given = get_engine(args.engine).step_of(get_engine(args.engine).settings_of(scene))
    if m.get("dt") is not None and m["dt"] < given:  # the contact-step rule shortened it
        scaled += f"; step {m['dt']:.4g} s (contact-step rule; {given:g} s given)"
    if result.unseated:  # the answer of the run: which corner lost its seat, and when
        scaled += f"; {m['message'] if m['status'] == 'unseated' else 'a corner unseated'}"
    print(
        f"{args.engine}: {m['status']} in {m.get('wall_time', 0):.2f} s, {m.get('steps', 0)} steps, "
        f"{m.get('gap_closures', 0)} gap closures, {_peak_rotations(result)}{scaled}; "
        f"wrote {terminal_text(csv_path)}"
    )
    if result.doubtful:
        if scene.run.accept_doubtful:
            return 0
        raise DoubtfulResult(
            f"{m['message']} (the result is written; --set run.accept_doubtful=true accepts it)"
        )
    if m["status"] == "unseated":
        # unseating is an answer (the deck lost its seat), not an engine failure: exit 0
        return 0
    if not result.ok:
        raise EngineFailure(m.get("message", "run failed"))
    return 0


def _export(args) -> int:
    from deckpound.models import plausibility
    from deckpound.models.excitation import support_motion
    from deckpound.models.file_io import check_parent, check_target, claim_folder_of
    from deckpound.models.scene_io import load_scene
    from deckpound.opensees_build.engine import OpenSeesEngine
    from deckpound.opensees_build.export import export_script

    out = check_target(args.output, stream=False)  # a folder, link or device: refused
    check_parent(out)
    claim_folder_of(out)
    scene = load_scene(args.scene, args.overrides)
    motion = support_motion(scene)
    plausibility.enforce(scene, motion, engines=(OpenSeesEngine(),))
    written = export_script(scene, args.format, out, motion)  # all files or none
    print(
        f"wrote {terminal_text(written)} and "
        f"{terminal_text(written.parent / (written.stem + '_data'))}/ (support records, "
        f"manifest.json); recorder files go to {terminal_text(written.stem)}_results/ "
        "when it runs"
    )
    return 0


def _modes(args) -> int:
    import numpy as np

    from deckpound.models.mechanics import energy_groups, mode_labels, natural_modes
    from deckpound.models.plan import plan_of
    from deckpound.models.scene_io import load_scene

    scene = load_scene(args.scene, args.overrides)
    if args.engine == "opensees":
        from deckpound.opensees_build.modes import opensees_modes

        periods, shapes = opensees_modes(scene)
    else:
        modes = natural_modes(scene)
        periods, shapes = modes.periods, modes.shapes
    # named by what moves: the kinetic-energy shares (deck x, y, θ; the seats)
    plan = plan_of(scene)
    labels = mode_labels(shapes, np.diag(plan.mass_matrix), energy_groups(plan))
    print("mode  period [s]  freq [Hz]  kinetic energy by part")
    for i, T in enumerate(periods):
        print(f"{i + 1:4d}  {T:10.5f}  {1 / T:9.4f}  {labels[i]}")
    return 0


def _verify_takeda(args) -> int:
    from deckpound.compare.verify.takeda import verify_takeda

    report = verify_takeda(n_states=args.states, seed=args.seed)
    print(
        f"Hysteretic clone vs OpenSees: {report['n_states']} states, "
        f"{report['n_exact']} bit-identical; max relative deviation stress "
        f"{report['max_rel_stress']:.3g}, tangent {report['max_rel_tangent']:.3g}"
    )
    return 0 if report["max_rel_stress"] <= 1e-12 and report["max_rel_tangent"] <= 1e-12 else 1


def _verify_clone(args) -> int:
    """One line per case (compare/verify/matrix.py); exit 1 when a case exceeds its tolerance.
    With --set: one case, the scene as given, with its column-by-column deviations (exit 1
    when the two runs end differently, :func:`~deckpound.compare.verify.matrix.ended_alike`)."""

    from deckpound.compare.verify import matrix as verify_matrix
    from deckpound.models.scene_io import load_scene

    scene = load_scene(args.scene, args.overrides)
    if args.overrides:
        return _verify_single(scene, verify_matrix)
    return verify_matrix.main(
        scene, pinned=False, quick=args.quick, log=lambda t: print(t, flush=True)
    )


def _verify_single(scene, verify_matrix) -> int:
    from deckpound.compare.verify.clone import verify_clone

    twin_scale = verify_matrix.BACKWARD_TOLERANCE
    report = verify_clone(scene, twin=True, twin_scale=twin_scale)
    for note in report["notes"]:
        print(f"note: {note}")
    for col, dev in sorted(report["deviation"].items(), key=lambda kv: -kv[1]):
        print(f"{col:16s} {dev:.3e}")
    col, worst = report["worst"]
    vcol, vworst = report["worst_velocity"]
    us = report["us_per_step"]
    print(
        f"largest deviation (relative to the column peak): {worst:.3e} in {col} "
        f"(velocities: {vworst:.3e} in {vcol}); "
        f"Newton iterations OpenSees {report['iterations']['opensees']}, clone "
        f"{report['iterations']['compliance']}"
    )
    print(
        f"speed: OpenSees {us['opensees']:.1f} us/step, clone {us['compliance']:.2f} us/step "
        f"(per-step ratio {us['opensees'] / us['compliance']:.1f}); whole-run wall-time ratio "
        f"{report['speed_ratio']:.1f}"
    )
    if not verify_matrix.ended_alike(report):
        raise EngineFailure(f"the runs ended differently: {verify_matrix.ended_text(report)}")
    if verify_matrix.ended_text(report) != "success":  # compared up to where both stopped
        print(f"the runs ended alike: {verify_matrix.ended_text(report)}")
    tol = verify_matrix.TOLERANCE
    tcol, tworst = report["twin_worst"]
    print(
        f"the clone's own sensitivity: the support motion scaled by 1 + {twin_scale:g} moves it "
        f"by {tworst:.3e} of the column's peak (in {tcol})"
    )
    if max(worst, vworst) <= tol:
        print(f"PASS: every column within {tol:g} of its peak")
        return 0
    backward = verify_matrix.backward_error(report)
    print(
        f"backward error: the clone moves as far as the engines are apart on the record "
        f"changed by {backward:.1e} of itself"
    )
    if verify_matrix.within_tolerance(max(worst, vworst), backward):
        print(
            f"PASS: deviation above {tol:g} of the column's peak but within "
            f"{verify_matrix.FORWARD_CAP:g}, at a backward error within "
            f"{verify_matrix.BACKWARD_TOLERANCE:g} (the response amplifies round-off: the "
            "engines differ by what a change of the record in its tenth digit makes)"
        )
        return 0
    print(f"FAIL: deviation above {tol:g} of the column's peak")
    if tworst > tol:
        print(
            f"the scene's response itself is not determined to {tol:g}: a change of "
            f"{twin_scale:g} in the record moves the clone beyond it (stiff contact: Newton "
            "iteration counts flip on round-off and the impacts amplify it)"
        )
    return 1


def _verify_contact_step(args) -> int:
    from deckpound.compare.studies.contact_step import contact_step_table, failures, format_table
    from deckpound.models.scene_io import load_scene

    rows = contact_step_table(load_scene(args.scene, args.overrides))
    print(format_table(rows))
    bad = failures(rows)
    if bad:
        print("FAIL: " + "; ".join(bad))
        return 1
    print("PASS: every default step within its stated error")
    return 0


def _verify_impact_law(args) -> int:
    from deckpound.compare.studies.impact_law import format_table, impact_law_table
    from deckpound.models.scene_io import load_scene

    rows = impact_law_table(load_scene(args.scene, args.overrides))
    print(format_table(rows))
    if any(r["status"] != "success" for r in rows):
        raise EngineFailure(
            "a run failed: "
            + ", ".join(f"{r['friction']}/{r['impact_law']}: {r['status']}" for r in rows)
        )
    return 0
