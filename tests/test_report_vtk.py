"""The paper job's report and figures, `compare`, and the ParaView export (issue 6)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pandas as pd
import pytest

from deckpound.cli import main
from deckpound.compare.paper import run_paper
from deckpound.models.scene_io import load_scene

TINY = ["excitation.duration=1.0", "run.output_dt=0.01", "opensees.dt=0.001",
        "compliance.dt=0.001", "nonsmooth.h=0.001", "sequence.pgas=[0.5, 1.0]"]


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    scene = load_scene("saiidi-4span", TINY)
    md = run_paper(scene, out, quick=True, workers=2, studies=("stiffness", "friction"),
                   progress=False)
    return out, md


def test_report_and_every_figure_written(report):
    out, md = report
    text = md.read_text()
    for heading in ("What was run", "Headline", "Engines against OpenSees", "Study: Contact "
                    "stiffness", "Inputs that are assumptions"):
        assert heading in text
    assert "ASSUMPTION" in text and "PAPER" in text
    html = (out / "report.html").read_text()
    assert html.startswith("<!doctype html>") and "<table" in html
    figs = out / "figures"
    expected = ["peak_rotation_vs_pga", "run1_histories", "run2_histories",
                "contact_forces_strongest", "bent_hysteresis_strongest", "plan_at_peak_rotation",
                "stiffness", "friction"]
    for name in expected:
        for ext in ("png", "pdf"):
            assert (figs / f"{name}.{ext}").stat().st_size > 1000, name
    # every image the report links exists
    for line in text.splitlines():
        if line.startswith("!["):
            assert (out / line.split("](")[1][:-1]).is_file()


def test_report_tables(report):
    out, _ = report
    seq = pd.read_csv(out / "tables" / "sequence.csv")
    assert set(seq["engine"]) >= {"opensees", "compliance", "nonsmooth"}
    assert len(seq) == 2 * 6  # two runs, three engines, two friction assumptions
    assert (seq["status"] == "success").all()
    long = pd.read_parquet(out / "tables" / "run2" / "aligned_long.parquet")
    assert list(long.columns) == ["engine", "t", "quantity", "value"]
    m = pd.read_csv(out / "tables" / "metrics_vs_opensees.csv")
    clone = m[(m["engine"] == "compliance") & (m["quantity"] == "deck_theta")]
    assert (clone["nrmse"] < 1e-6).all()  # the clone is OpenSees to round-off


def test_compare_then_vtk_series_readable(tmp_path, capsys):
    out = tmp_path / "cmp"
    args = ["compare", "saiidi-4span", "--engines", "compliance,nonsmooth", "-o", str(out),
            "--no-progress", "--workers", "1"] + sum((["--set", o] for o in TINY[:5]), [])
    assert main(args) == 0
    assert (out / "metrics.csv").is_file() and (out / "figures" / "histories.png").is_file()
    vtk = tmp_path / "vtk"
    assert main(["export-vtk", str(out), "-o", str(vtk), "--every", "10"]) == 0
    for engine in ("compliance", "nonsmooth"):
        root = ET.parse(vtk / f"{engine}.pvd").getroot()
        sets = root.findall("./Collection/DataSet")
        assert len(sets) == 11
        times = [float(s.get("timestep")) for s in sets]
        assert times == sorted(times) and times[-1] == pytest.approx(1.0)
        mesh = meshio.read(vtk / sets[-1].get("file"))
        assert mesh.points.shape == (12, 3)  # deck + two seats, 4 corners each
        assert len(mesh.cells[0].data) == 3
        d = mesh.point_data["displacement"]
        assert np.all(np.isfinite(d)) and np.abs(d).max() > 0
