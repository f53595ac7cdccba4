"""Reads the VTK files of regolith's Vtk output with numpy alone.

They are VTK XML with one appended raw block (little-endian, a UInt64 byte count before
each array); this reader knows just that layout, so reading a run needs no VTK install.
The tests check it against the `vtk` package's own readers.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


def _split(path: Path) -> tuple[ET.Element, bytes]:
    data = Path(path).read_bytes()
    start = data.find(b"<AppendedData")
    if start < 0:
        raise ValueError(f"{path}: no appended data (not a regolith VTK file)")
    block = data.index(b"_", start) + 1
    header = data[:start] + b"</VTKFile>"
    if b'header_type="UInt64"' not in header or b'encoding="raw"' not in data[start:block]:
        raise ValueError(f"{path}: expected raw appended data with UInt64 headers")
    return ET.fromstring(header), data[block:]


def _array(tag: ET.Element, block: bytes) -> np.ndarray:
    offset = int(tag.get("offset"))
    size = int(np.frombuffer(block, "<u8", 1, offset)[0])
    dtype = np.dtype(_TYPES[tag.get("type")])
    values = np.frombuffer(block, dtype, size // dtype.itemsize, offset + 8)
    components = int(tag.get("NumberOfComponents", "1"))
    return values.reshape(-1, components) if components > 1 else values.copy()


def _field_data(root: ET.Element) -> dict[str, np.ndarray]:
    return {
        array.get("Name"): np.array([float(v) for v in array.text.split()])
        for block in root.iter("FieldData")
        for array in block.findall("DataArray")
    }


def read_vtu(path) -> dict[str, np.ndarray]:
    """A body's points: `position` (n x 2) and every point array of the file, plus `time`."""
    root, block = _split(path)
    piece = root.find("UnstructuredGrid/Piece")
    arrays = {a.get("Name"): _array(a, block) for a in piece.find("PointData")}
    arrays["position"] = _array(piece.find("Points/DataArray"), block)[:, :2]
    arrays["time"] = _field_data(root)["TimeValue"][0]
    return arrays


def read_vti(path) -> dict[str, np.ndarray]:
    """A body's nodal field: each array shaped (ny, nx[, components]), `origin`, `spacing`,
    the body's total `contact_force` and `time`."""
    root, block = _split(path)
    image = root.find("ImageData")
    extent = [int(v) for v in image.get("WholeExtent").split()]
    nx, ny = extent[1] + 1, extent[3] + 1
    arrays = {}
    for tag in image.find("Piece/PointData"):
        values = _array(tag, block)
        arrays[tag.get("Name")] = values.reshape((ny, nx) + values.shape[1:])
    fields = _field_data(root)
    arrays["origin"] = np.array([float(v) for v in image.get("Origin").split()[:2]])
    arrays["spacing"] = float(image.get("Spacing").split()[0])
    arrays["contact_force"] = fields["contact_force"][:2]
    arrays["time"] = fields["TimeValue"][0]
    return arrays


def read_collection(path) -> list[tuple[float, int, str]]:
    """A .pvd's entries: (time, part = body index, file relative to the .pvd)."""
    root = ET.parse(path).getroot()
    return [
        (float(d.get("timestep")), int(d.get("part")), d.get("file"))
        for d in root.iter("DataSet")
    ]
