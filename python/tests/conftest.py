# SPDX-License-Identifier: MIT
"""Fixtures of the Python tests: the shared real meshes, the CLI, a work folder."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def data_dir():
    """../shared/data (UVR_SHARED_DATA_DIR); tests using it are skipped when it is absent."""
    d = pathlib.Path(os.environ.get("UVR_SHARED_DATA_DIR", ROOT.parent / "shared" / "data"))
    if not (d / "spx.vtk").exists():
        pytest.skip(f"no shared data in {d}")
    return d


@pytest.fixture(scope="session")
def cli():
    """A function running the `uvr` command line (UVR_CLI) and returning its result."""
    exe = os.environ.get("UVR_CLI")
    if not exe or not os.path.exists(exe):
        pytest.skip("UVR_CLI does not name the uvr executable")

    def run(*args, check=True):
        r = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
        if check and r.returncode != 0:
            raise AssertionError(f"uvr {' '.join(map(str, args))}: {r.stderr}")
        return r

    return run


@pytest.fixture
def small_tets():
    """Two tetrahedra sharing a face, a point field and a cell field, as numpy arrays."""
    import numpy as np

    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float32)
    cells = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], dtype=np.uint32)
    return points, cells
