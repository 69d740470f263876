# SPDX-License-Identifier: MIT
"""The module under mpirun (issue 31): Renderer(comm=MPI.COMM_WORLD) renders data-parallel, rank
0's image is the one-process image (after set_field too), the other ranks get None; a
communicator that is not the world is refused."""

import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import uvr

SCRIPT = textwrap.dedent("""
    import sys
    import numpy as np
    from mpi4py import MPI
    import uvr
    mesh = uvr.read(sys.argv[1])
    r = uvr.Renderer(mesh, device="cpu", comm=MPI.COMM_WORLD)
    img = r.render(tf="viridis", opacity="0:0,1:0.5", size=(160, 120), azimuth=30,
                   elevation=20, method=sys.argv[3])
    # Sample distances up to the one given at preparation render; larger ones are refused.
    far = uvr.Renderer(mesh, device="cpu", comm=MPI.COMM_WORLD, largest_sample_distance=0.5)
    far.render(size=(32, 24), sample_distance=0.5, method="reference")
    try:
        far.render(size=(32, 24), sample_distance=0.8, method="reference")
        raise SystemExit("a sample distance past the ghosts rendered")
    except uvr.ArgumentError as e:
        assert "expected at most 0.525" in str(e), str(e)
    # Another field's values reach the pieces (nothing geometric rebuilt).
    r.set_field("energy")
    energy = r.render(tf="viridis", opacity="0:0,1:0.5", size=(160, 120), azimuth=30,
                      elevation=20, method=sys.argv[3])
    if MPI.COMM_WORLD.Get_rank() == 0:
        np.save(sys.argv[2], np.asarray(img))
        np.save(sys.argv[2] + ".energy.npy", np.asarray(energy))
        assert len(img.stats["ranks"]) == MPI.COMM_WORLD.Get_size()
    else:
        assert img is None and energy is None
""")


@pytest.mark.parametrize("method", ["adaptive", "exact"])
def test_data_parallel_under_mpirun_equals_one_process(tmp_path, data_dir, method):
    pytest.importorskip("mpi4py")
    if not shutil.which("mpirun"):
        pytest.skip("no mpirun (openmpi-bin)")
    script = tmp_path / "dp.py"
    script.write_text(SCRIPT)
    out = tmp_path / "img.npy"
    env = dict(os.environ)
    r = subprocess.run(["mpirun", "-n", "3", "--oversubscribe", "--allow-run-as-root", "--mca",
                        "btl", "self,vader", "-x", "PYTHONPATH", sys.executable, str(script),
                        str(data_dir / "bluntfin_tets.vtk"), str(out), method],
                       capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    fin = uvr.read(str(data_dir / "bluntfin_tets.vtk"))
    # In 8-bit levels over black, as the PNG holds them (uvr compare's measure).
    def levels(a):
        return np.round(np.clip(np.asarray(a, dtype=np.float64)[..., :3], 0, 1) * 255)
    for field, many in (("density", np.load(out)), ("energy", np.load(str(out) + ".energy.npy"))):
        one = uvr.Renderer(fin, field=field, device="cpu").render(
            tf="viridis", opacity="0:0,1:0.5", size=(160, 120), azimuth=30, elevation=20,
            method=method)
        diff = np.abs(levels(one) - levels(many))
        assert diff.max() <= 2, (field, diff.max())
        assert float(np.asarray(one)[..., 3].max()) > 0.1  # a picture to compare


def test_a_bad_largest_sample_distance_is_refused():
    with pytest.raises(uvr.ArgumentError, match="largest_sample_distance -1"):
        uvr.Renderer(_two_tets(), largest_sample_distance=-1)


def test_a_communicator_that_is_not_mpi4pys_is_refused():
    with pytest.raises(TypeError, match="comm: expected mpi4py's MPI.COMM_WORLD"):
        uvr.Renderer(_two_tets(), comm="world")


def _two_tets():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=np.float32)
    cells = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], dtype=np.int64)
    return uvr.Mesh(points, cells, point_data={"f": np.arange(5, dtype=np.float32)})
