"""``deckpound compile`` warms every kernel a user's run reaches (src/deckpound/warmup.py)."""

import warnings

from deckpound import cli
from deckpound.compare import warmup
from deckpound.compare.engines import run_engine
from deckpound.models.scene_io import load_scene


def test_compile_command_reports_a_line_per_item_and_the_cache(capsys, tmp_path):
    stamp = tmp_path / "stamp"
    assert cli.main(["compile", "--engines", "nonsmooth", "--stamp", str(stamp), "--key", "k"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("deckpound compile: Python bytecode of ")
    out = out[1:]
    assert out[0].startswith("deckpound compile: kernels are cached in ")
    items = [i for i in warmup.ITEMS if i.engine == "nonsmooth"]
    lines = [ln for ln in out if ln.startswith("[")]
    assert len(lines) == len(items)
    for ln, item in zip(lines, items):
        assert item.label in ln and " s (" in ln and "success" in ln
    where = out[0].rsplit(" ", 1)[-1]
    assert stamp.read_text().splitlines() == ["k", where]
    # a second run finds everything in the cache
    assert cli.main(["compile", "--engines", "nonsmooth"]) == 0
    assert "0 kernels compiled (all loaded from the cache)" in capsys.readouterr().out


def test_byte_compile_writes_a_valid_pyc_for_every_module():
    """The set-up writes the bytecode cache that Python reads even under
    PYTHONDONTWRITEBYTECODE: after it, every module of every deckpound package has a .pyc whose
    header matches its source (a missing one is rewritten)."""
    import importlib
    import importlib.util
    from pathlib import Path

    errors = importlib.import_module("deckpound.models.errors").__file__
    Path(importlib.util.cache_from_source(errors)).unlink(missing_ok=True)
    assert errors in warmup.stale_bytecode()
    n = warmup.byte_compile()
    assert n > 100
    assert warmup.stale_bytecode() == []


def test_compile_goes_on_when_the_bytecode_cannot_be_written(monkeypatch, capsys):
    """A read-only install: the kernels are still compiled, the bytecode is a warning."""

    def refuse():
        raise OSError("could not byte-compile the modules in /usr/lib/deckpound")

    monkeypatch.setattr(warmup, "byte_compile", refuse)
    monkeypatch.setattr(warmup, "ITEMS", (warmup.Item("takeda", "material"),))
    assert cli.main(["compile"]) == 0
    out, err = capsys.readouterr()
    assert "could not byte-compile the modules in /usr/lib/deckpound" in err
    assert "kernels are cached in" in out


def test_stale_bytecode_sees_a_changed_source(tmp_path, monkeypatch):
    """A .pyc whose recorded source mtime or size differs from the source's is stale."""
    import compileall
    import os

    src = tmp_path / "mod.py"
    src.write_text("x = 1\n")
    compileall.compile_dir(str(tmp_path), quiet=1)
    monkeypatch.setattr(warmup, "_package_folders", lambda: [tmp_path])
    assert warmup.stale_bytecode() == []
    st = src.stat()
    os.utime(src, (st.st_atime, st.st_mtime + 5))
    assert warmup.stale_bytecode() == [str(src)]


def test_unknown_engine_refused(capsys):
    assert cli.main(["compile", "--engines", "nope"]) == 2
    assert "unknown engine 'nope'" in capsys.readouterr().err


def test_after_warm_up_user_variants_compile_nothing():
    """Runs with other laws, options, records and initial states than the warm-up items reuse
    the warmed kernels: the items cover the type specialisations, not the values."""
    warmup.warm()
    variants = [
        (
            "compliance",
            [
                "contact.law=hertz-damp",
                "contact.friction=0.3",
                "contact.friction_mode=slip",
                "contact.geometry=nonlinear",
            ],
            {},
        ),
        ("compliance", ["contact.law=bilinear", "compliance.integrator=adaptive"], {}),
        ("compliance", ["excitation.kind=pulse"], {"initial_state": ([0.0] * 7, [0.001] * 7)}),
        ("compliance", [], {"channels": ["energy_input"], "kv_clip": True}),
        ("nonsmooth", ["nonsmooth.theta=0.7", "contact.restitution=0.0"], {}),
    ]
    with warmup._CompileCounter() as counter, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for engine, overrides, options in variants:
            scene = load_scene("saiidi-4span", ["run.duration=0.02", *overrides])
            assert run_engine(engine, scene, **options).ok
    assert counter.compiled == set()


def test_numba_caching_warnings_are_reported(monkeypatch, capsys):
    """A kernel numba cannot cache (e.g. an unwritable cache folder) compiles in every
    process: the set-up says so instead of reporting success silently."""
    from numba.core.errors import NumbaWarning

    def warn_like_numba():
        warnings.warn(
            "Cannot cache compiled function 'k' as it uses dynamic globals",
            NumbaWarning,
            stacklevel=1,
        )

    monkeypatch.setattr(warmup, "_warm_takeda", warn_like_numba)
    res = warmup.warm_item(warmup.Item("takeda", "material"))
    assert res.notes == ["Cannot cache compiled function 'k' as it uses dynamic globals"]
    monkeypatch.setattr(warmup, "ITEMS", (warmup.Item("takeda", "material"),))
    assert cli.main(["compile"]) == 0
    err = capsys.readouterr().err
    assert "deckpound: warning: Cannot cache compiled function 'k'" in err
