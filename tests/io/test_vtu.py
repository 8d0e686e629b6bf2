"""io/vtu.py (issue 40): the VTU files are meshio's, line for line (the comment naming the writer
aside), compressed or not, and meshio reads them back."""
import meshio
import numpy as np
import pytest

from ancf_petsc.io.vtu import write_vtu


@pytest.mark.parametrize("compress", [False, True])
def test_same_file_as_meshio(tmp_path, compress):
    rng = np.random.default_rng(0)
    pts = rng.random((40000, 3)).astype(np.float32)       # > 32 KiB: several zlib blocks
    cells = [("quad", rng.integers(0, 40000, (300, 4))), ("polygon", np.arange(7)[None, :]),
             ("polygon", np.arange(9)[None, :])]
    data = {"displacement": rng.random((40000, 3)).astype(np.float32),
            "J": rng.random(40000).astype(np.float32)}
    a, b = tmp_path / "meshio.vtu", tmp_path / "ours.vtu"
    meshio.write(a, meshio.Mesh(pts, cells, point_data=data), binary=True,
                 compression="zlib" if compress else None)
    write_vtu(str(b), pts, cells, data, compress)
    la, lb = a.read_text().split("\n"), b.read_text().split("\n")
    assert len(la) == len(lb)
    assert [i for i, (x, y) in enumerate(zip(la, lb)) if x != y] == [2]     # the comment
    back = meshio.read(b)
    assert np.array_equal(back.points, pts) and np.array_equal(back.point_data["J"], data["J"])
    assert [c.type for c in back.cells] == ["quad", "polygon", "polygon"]
