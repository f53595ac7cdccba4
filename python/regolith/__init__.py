"""regolith from Python: load, run and step scenes; read runs into numpy arrays.

    import regolith
    scene = regolith.load_scene("scenes/impact_tipped_coarse.ron", overrides=["time.end=0.1"])
    run = regolith.run(scene, out="out/impact")          # as `regolith run`, files and all
    run.trajectory["intruder_y"]                          # numpy arrays by column

    sim = regolith.Simulation(scene)                      # or step it yourself
    sim.run_until(0.05)
    sim.points("bed")["pressure"]

Scenes, overrides and outputs are those of the command line (docs/scenes.md); errors are
raised as `regolith.SceneError` (a ValueError) carrying the same `file:line:col: ...` line,
and a run that stops on a fault raises `regolith.RunError` after writing its files.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from ._regolith import (
    RunError,
    Scene,
    SceneError,
    Simulation,
    __version__,
    load_scene,
    run_to_dir,
)
from .vtk import read_vtu, read_vti, read_collection

__all__ = [
    "Run",
    "RunError",
    "Scene",
    "SceneError",
    "Simulation",
    "__version__",
    "load_scene",
    "read_collection",
    "read_run",
    "read_vti",
    "read_vtu",
    "run",
]


def run(scene, out, overrides=None, checkpoint_every=None) -> "Run":
    """Runs a scene (a `Scene`, or a path with `overrides`) to its end, writing `out` as
    `regolith run --out` does, and returns the run read back."""
    if not isinstance(scene, Scene):
        scene = load_scene(os.fspath(scene), overrides)
    elif overrides:
        raise ValueError("overrides go to load_scene (or give a path instead of a Scene)")
    run_to_dir(scene, os.fspath(out), checkpoint_every)
    return read_run(out)


def _table(path: Path) -> dict[str, np.ndarray]:
    """A CSV with a header as one float array per column (empty cells are NaN; text
    columns, like the snapshots' body names, stay strings)."""
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
    columns = {}
    for k, name in enumerate(header):
        cells = [r[k] if k < len(r) else "" for r in rows]
        try:
            columns[name] = np.array([float(c) if c else np.nan for c in cells])
        except ValueError:
            columns[name] = np.array(cells)
    return columns


class Run:
    """A run directory read into Python: `summary` (dict), `trajectory` (columns as numpy
    arrays), `snapshots` (one dict of columns per snapshot file, in order) and the VTK
    frames (`vtk_frames()`, read on demand: they can be large)."""

    def __init__(self, path):
        self.path = Path(path)
        summary = self.path / "summary.json"
        if not summary.exists():
            raise FileNotFoundError(f"{self.path}: no summary.json (not a regolith run directory)")
        self.summary = json.loads(summary.read_text())
        # a run still going (or killed) has only the streamed part
        found = [p for p in ("trajectory.csv", "trajectory.csv.part") if (self.path / p).exists()]
        self.trajectory = _table(self.path / found[0]) if found else {}
        self.snapshots = [_table(p) for p in sorted((self.path / "snapshots").glob("snapshot_*.csv"))]

    @property
    def status(self) -> str:
        """completed, failed or interrupted (a failed run keeps every file it wrote)."""
        return self.summary["status"]

    def vtk_frames(self, grid: bool = False) -> list[tuple[float, dict[str, dict]]]:
        """The frames of the run's Vtk output: (time, {body: arrays}) per frame, in time
        order; `grid=True` gives the nodal fields instead of the points."""
        name = "grid.pvd" if grid else "points.pvd"
        collection = self.path / "vtk" / name
        if not collection.exists():
            raise FileNotFoundError(f"{collection}: the run has no Vtk output")
        reader = read_vti if grid else read_vtu
        bodies = {b["name"]: k for k, b in enumerate(self.summary.get("bodies", []))}
        names = {k: n for n, k in bodies.items()}
        frames: dict[float, dict] = {}
        for time, part, file in read_collection(collection):
            frames.setdefault(time, {})[names.get(part, str(part))] = reader(collection.parent / file)
        return sorted(frames.items())

    def __repr__(self):
        return f"<regolith.Run {self.path} {self.status}>"


def read_run(path) -> Run:
    """Reads a run directory written by `regolith run` (or `run`)."""
    return Run(path)
