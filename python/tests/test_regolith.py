"""The Python package against the command line and an independent VTK reader.

Needs the package installed (`pip install ./python`) and the command built
(`cargo build --release`, or the workspace's tests, which build it); REGOLITH names
another binary. `.ci/run` does all three.
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import regolith

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "impact_tipped_coarse.ron"
# 0.03 s of the coarse impact: about 900 steps, the intruder well into the bed.
SHORT = ["time.end=0.03"]
OUTPUTS = "outputs=[Impact(body: \"intruder\", surface: 0.6825), Snapshots(every: 0.01), Vtk(every: 0.01, grid: true)]"


def command():
    binary = Path(os.environ.get("REGOLITH", ROOT / "target" / "release" / "regolith"))
    if not binary.exists():
        pytest.fail(f"{binary} not found: build it with `cargo build --release` (or set REGOLITH)")
    return binary


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """The short impact run by the command line, with every file output."""
    out = tmp_path_factory.mktemp("cli")
    sets = [a for s in SHORT + [OUTPUTS] for a in ("--set", s)]
    subprocess.run([command(), "run", SCENE, "--out", out, "-q", *sets], check=True)
    return out


def hashes(summary):
    return {b["name"]: b["state_hash"] for b in summary["bodies"]}


def test_stepping_from_python_reaches_the_command_lines_state(cli_run):
    cli = json.loads((cli_run / "summary.json").read_text())
    sim = regolith.Simulation(regolith.load_scene(SCENE, overrides=SHORT))
    taken = 0
    while not sim.finished:
        taken += sim.step(100)
    assert taken == sim.steps == cli["steps"]
    assert dict(sim.state_hash()) == hashes(cli)
    summary = sim.summary()
    assert summary["status"] == "completed"
    assert hashes(summary) == hashes(cli)


def test_points_are_numpy_arrays_of_the_bodys_state():
    sim = regolith.Simulation(regolith.load_scene(SCENE, overrides=SHORT))
    sim.run_until(0.01)
    assert sim.time >= 0.01
    bed = sim.points("bed")
    n = len(bed["mass"])
    assert bed["position"].shape == (n, 2) and bed["stress"].shape == (n, 4)
    assert bed["phase"].dtype == np.uint8
    # pressure is minus the mean of the three normal stresses
    xx, yy, zz = bed["stress"][:, 0], bed["stress"][:, 1], bed["stress"][:, 3]
    np.testing.assert_allclose(bed["pressure"], -(xx + yy + zz) / 3, rtol=1e-12, atol=1e-9)
    with pytest.raises(KeyError, match="no body called \"ghost\""):
        sim.points("ghost")


def test_a_bad_scene_raises_the_located_error(tmp_path):
    text = SCENE.read_text().replace("outputs:", "outptus:", 1)
    bad = tmp_path / "bad.ron"
    bad.write_text(text)
    line = next(k for k, l in enumerate(text.splitlines(), 1) if "outptus" in l)
    with pytest.raises(regolith.SceneError) as raised:
        regolith.load_scene(bad)
    message = str(raised.value)
    assert message.startswith(f"{bad}:{line}:"), message
    assert "outptus" in message
    # the command line says the same
    cli = subprocess.run([command(), "check", bad], capture_output=True, text=True)
    assert cli.returncode != 0 and message in cli.stderr


def test_a_run_from_python_equals_the_command_lines_and_reads_back(cli_run, tmp_path):
    run = regolith.run(SCENE, tmp_path / "py", overrides=SHORT + [OUTPUTS])
    cli = regolith.read_run(cli_run)
    assert run.status == cli.status == "completed"
    assert hashes(run.summary) == hashes(cli.summary)
    for column in cli.trajectory:
        np.testing.assert_array_equal(run.trajectory[column], cli.trajectory[column])
    # what read_run gives is what the files hold
    assert len(cli.snapshots) == 4  # t = 0, 0.01, 0.02, 0.03
    last = cli.snapshots[-1]
    assert set(last["body"]) == {"bed", "intruder"}
    final = cli.trajectory["t"][-1]
    assert last["t"][0] == pytest.approx(final, abs=0)


def test_vtk_frames_match_the_snapshots(cli_run):
    run = regolith.read_run(cli_run)
    frames = run.vtk_frames()
    assert len(frames) == len(run.snapshots)
    for (time, bodies), snapshot in zip(frames, run.snapshots):
        assert time == snapshot["t"][0]
        for name, points in bodies.items():
            rows = snapshot["body"] == name
            assert points["time"] == time
            np.testing.assert_array_equal(points["position"][:, 0], snapshot["x"][rows])
            np.testing.assert_array_equal(points["position"][:, 1], snapshot["y"][rows])
            np.testing.assert_allclose(points["pressure"], snapshot["pressure"][rows], rtol=1e-15)
            np.testing.assert_array_equal(points["phase"], snapshot["phase"][rows])
    grid = run.vtk_frames(grid=True)
    assert [t for t, _ in grid] == [t for t, _ in frames]
    intruder = grid[-1][1]["intruder"]
    mass = run.summary["bodies"][1]["mass"]
    assert intruder["mass"].sum() == pytest.approx(mass, rel=1e-12)


def test_an_independent_vtk_reader_reads_the_same_frames(cli_run):
    from vtkmodules import vtkIOXML as vtkxml
    from vtkmodules.util.numpy_support import vtk_to_numpy

    run = regolith.read_run(cli_run)
    collection = regolith.read_collection(cli_run / "vtk" / "points.pvd")
    times = sorted({t for t, _, _ in collection})
    assert times == [s["t"][0] for s in run.snapshots]
    for time, part, file in collection:
        reader = vtkxml.vtkXMLUnstructuredGridReader()
        reader.SetFileName(str(cli_run / "vtk" / file))
        reader.Update()
        grid = reader.GetOutput()
        snapshot = run.snapshots[times.index(time)]
        name = run.summary["bodies"][part]["name"]
        rows = snapshot["body"] == name
        assert grid.GetNumberOfPoints() == grid.GetNumberOfCells() == rows.sum()
        xyz = vtk_to_numpy(grid.GetPoints().GetData())
        np.testing.assert_array_equal(xyz[:, 0], snapshot["x"][rows])
        np.testing.assert_array_equal(xyz[:, 2], 0.0)
        pressure = vtk_to_numpy(grid.GetPointData().GetArray("pressure"))
        np.testing.assert_allclose(pressure, snapshot["pressure"][rows], rtol=1e-15)
        stress = vtk_to_numpy(grid.GetPointData().GetArray("stress"))
        np.testing.assert_allclose(-np.trace(stress.reshape(-1, 3, 3), axis1=1, axis2=2) / 3,
                                   pressure, rtol=1e-12, atol=1e-9)
        assert vtk_to_numpy(grid.GetFieldData().GetArray("TimeValue"))[0] == time
    image = vtkxml.vtkXMLImageDataReader()
    file = next(f for t, p, f in regolith.read_collection(cli_run / "vtk" / "grid.pvd") if p == 1)
    image.SetFileName(str(cli_run / "vtk" / file))
    image.Update()
    ours = regolith.read_vti(cli_run / "vtk" / file)
    nx, ny, _ = image.GetOutput().GetDimensions()
    assert ours["mass"].shape == (ny, nx)
    np.testing.assert_array_equal(
        vtk_to_numpy(image.GetOutput().GetPointData().GetArray("mass")).reshape(ny, nx), ours["mass"])
