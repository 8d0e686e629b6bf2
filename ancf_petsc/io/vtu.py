"""One VTK XML unstructured grid (.vtu) file: points, cells and point data, base64 binary.

The layout is meshio's (``meshio.write`` of the same mesh with ``binary=True``: UInt32 headers,
zlib blocks of 32 KiB when compressed) for the cell types the outputs use; writing it here spares
every run importing meshio (~50 ms of its start-up, before the first Newton iteration).
"""
from __future__ import annotations

import base64
import sys
import zlib

import numpy as np

#: VTK cell type ids of the cell blocks ``vtk.py`` writes
VTK_TYPES = {"vertex": 1, "line": 3, "triangle": 5, "polygon": 7, "quad": 9}
_NUMPY_TO_VTU = {np.dtype(np.float32): "Float32", np.dtype(np.float64): "Float64",
                 np.dtype(np.int32): "Int32", np.dtype(np.int64): "Int64"}
BLOCK = 32768


def _encoded(data: np.ndarray, compress: bool) -> str:
    """The base64 text of one DataArray: a UInt32 byte-count header and the bytes, or with
    ``compress`` the block header and the zlib-compressed 32 KiB blocks."""
    raw = data.tobytes()
    if not compress:
        return base64.b64encode(np.array(len(raw), dtype=np.uint32).tobytes() + raw).decode()
    n = -(-len(raw) // BLOCK)
    blocks = [zlib.compress(raw[i * BLOCK:(i + 1) * BLOCK]) for i in range(n)]
    header = np.array([n, BLOCK, len(raw) - (n - 1) * BLOCK] + [len(b) for b in blocks], dtype=np.uint32)
    return base64.b64encode(header.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()


def _array(name: str, data: np.ndarray, compress: bool) -> str:
    components = f' NumberOfComponents="{data.shape[1]}"' if data.ndim == 2 else ""
    return (f'<DataArray type="{_NUMPY_TO_VTU[data.dtype]}" Name="{name}"{components} format="binary">\n'
            f"{_encoded(data, compress)}\n</DataArray>\n")


def cells_xml(cells: list[tuple[str, np.ndarray]], compress: bool = False) -> str:
    """The ``<Cells>`` element of cell blocks [(type, (k, nodes))]: connectivity, offsets, types."""
    conn = np.concatenate([np.asarray(c).reshape(-1) for _, c in cells])
    offsets = [c.shape[1] * np.arange(1, c.shape[0] + 1, dtype=conn.dtype) for _, c in cells]
    for k in range(1, len(offsets)):
        offsets[k] += offsets[k - 1][-1]
    types = np.concatenate([np.full(len(c), VTK_TYPES[t]) for t, c in cells])
    return ("<Cells>\n" + _array("connectivity", conn, compress)
            + _array("offsets", np.concatenate(offsets), compress) + _array("types", types, compress)
            + "</Cells>\n")


def field_xml(field_data: dict[str, np.ndarray], compress: bool = False) -> str:
    """The ``<FieldData>`` element: one tuple per array (the level's values, e.g. ``stable``)."""
    arrays = "".join(_array(k, np.atleast_1d(v), compress).replace(
        " format=", f' NumberOfTuples="{len(np.atleast_1d(v))}" format=', 1) for k, v in field_data.items())
    return f"<FieldData>\n{arrays}</FieldData>\n"


def write_vtu(path: str, points: np.ndarray, cells: list[tuple[str, np.ndarray]],
              point_data: dict[str, np.ndarray], compress: bool = False,
              cells_text: str | None = None, field_data: dict[str, np.ndarray] | None = None) -> None:
    """Write ``points`` (n, 3), cell blocks [(type, (k, nodes))], ``point_data`` and the grid's
    ``field_data`` (arrays of one tuple) to ``path`` (``cells_text``: ``cells_xml(cells,
    compress)`` if the caller kept it from an earlier file)."""
    points = np.asarray(points)
    n_cells = sum(len(c) for _, c in cells)
    order = "LittleEndian" if sys.byteorder == "little" else "BigEndian"
    compressor = ' compressor="vtkZLibDataCompressor"' if compress else ""
    parts = ['<?xml version="1.0"?>\n',
             f'<VTKFile type="UnstructuredGrid" version="0.1" byte_order="{order}"{compressor}>\n',
             "<!--This file was created by ancf-petsc-->\n<UnstructuredGrid>\n",
             field_xml(field_data, compress) if field_data else "",
             f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{n_cells}">\n',
             "<Points>\n", _array("Points", points, compress), "</Points>\n",
             cells_text if cells_text is not None else cells_xml(cells, compress)]
    if point_data:
        parts += ["<PointData>\n"] + [_array(k, np.asarray(v), compress) for k, v in point_data.items()] \
            + ["</PointData>\n"]
    parts.append("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    with open(path, "w") as fh:
        fh.write("".join(parts))
