"""The README's Python example, run as written in a scratch directory that holds the
repository's scenes (needs the package installed, as `.ci/run` does)."""

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_python_blocks():
    blocks, block = [], None
    for line in (ROOT / "README.md").read_text().splitlines():
        stripped = line.strip()
        if block is None and stripped == "```python":
            block = []
        elif block is not None and stripped == "```":
            blocks.append("\n".join(block))
            block = None
        elif block is not None:
            block.append(line)
    return blocks


def test_the_readme_python_example_runs(tmp_path, monkeypatch):
    blocks = readme_python_blocks()
    assert blocks, "the README has a Python example"
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        # Each block is indented as the README's list item it sits in.
        lines = block.splitlines()
        indent = min(len(l) - len(l.lstrip()) for l in lines if l.strip())
        namespace = {}
        exec("\n".join(l[indent:] for l in lines), namespace)
    assert (tmp_path / "out" / "py" / "summary.json").is_file()
    assert os.path.getsize(tmp_path / "out" / "py" / "trajectory.csv") > 0
