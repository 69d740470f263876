# SPDX-License-Identifier: MIT
"""The example notebook runs: every code cell in order, in one namespace."""

import json
import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_example_notebook_runs(data_dir, tmp_path, monkeypatch):
    notebook = ROOT / "examples" / "python" / "uvr_tour.ipynb"
    cells = json.loads(notebook.read_text())["cells"]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("UVR_SHARED_DATA_DIR", str(data_dir))
    namespace = {"__name__": "__notebook__"}
    code = [c for c in cells if c["cell_type"] == "code"]
    assert code
    for i, cell in enumerate(code):
        source = "".join(cell["source"])
        exec(compile(source, f"{notebook.name} cell {i}", "exec"), namespace)
    assert namespace["img"]._repr_png_().startswith(b"\x89PNG")
