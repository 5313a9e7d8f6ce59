"""ROS ``map_server`` maps (a YAML file and a PGM or PNG image) to obstacles.

A map is an occupancy grid: each pixel is a cell of ``resolution`` metres, and the pixel's
shade says whether the cell is occupied, free or unknown, as ``map_server`` reads it:

* the shade ``c`` (0-255; the mean of the channels of a colour image, a 16-bit image
  scaled to 255) gives the probability of occupancy ``p = (255 - c) / 255``, or
  ``c / 255`` with ``negate: 1``;
* ``mode: trinary`` (the default) and ``scale``: occupied where ``p > occupied_thresh``;
  ``raw``: the pixel is the occupancy itself, 0-100, occupied above
  ``100 occupied_thresh``;
* free and unknown cells are not obstacles: the robot may drive through unknown space,
  as a planner that treats it as free would.

The occupied cells become polygons with holes, their outlines: runs of occupied cells
along each row, runs repeated on the rows below merged into rectangles, the rectangles
joined (``shapely.union_all``) and the outlines simplified (Douglas-Peucker, keeping the
topology) within ``tolerance`` metres, one cell by default: every point of the result
lies within ``tolerance`` of the cells' staircase outline, and every corner of it within
``tolerance`` of the result. All of it is array work: a 4000 x 4000 building map loads
in a few seconds.

The image's first row is the map's top (largest y); ``origin`` is the pose of the
lower-left corner of the lower-left pixel, ``[x, y, yaw]``, yaw counter-clockwise.

>>> import numpy as np
>>> occupied = np.zeros((4, 6), dtype=bool)
>>> occupied[1:3, 1:5] = True                 # a 4 x 2 cell block
>>> plan = outline(occupied, 0.5, (10.0, 0.0, 0.0))
>>> plan.geom_type, plan.area, plan.bounds
('MultiPolygon', 2.0, (10.5, 0.5, 12.5, 1.5))
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mdle.core.errors import WorldError
from mdle.sim.interruptible import call_interruptibly
from mdle.sim.shapes import Parts

if TYPE_CHECKING:
    from shapely.geometry.base import BaseGeometry

__all__ = ["MAP_MODES", "MAX_MAP_CELLS", "FloorPlan", "MapInfo", "load_map", "occupied_cells",
           "outline", "outline_parts", "read_image", "read_map_info"]

#: Cells in one numpy pass over a map: about 10 ms of CPU. A pass over a whole 3000 x
#: 3000 map took 0.15 s in which Ctrl-C waited; between two bands a signal is acted on.
BAND_CELLS = 1 << 20


def _bands(rows: int, columns: int) -> list[slice]:
    """Return the slices of rows that cut a (rows, columns) map into passes of ~BAND_CELLS."""
    step = max(1, BAND_CELLS // max(1, columns))
    return [slice(top, min(rows, top + step)) for top in range(0, rows, step)]

#: How a map's pixels are read (``map_server``'s ``mode``).
MAP_MODES = ("trinary", "scale", "raw")
#: The largest map read, in cells (a 10,000 x 10,000 image).
MAX_MAP_CELLS = 100_000_000
_MAP_KEYS = ("image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate",
             "mode")


@dataclass(frozen=True, eq=False)
class FloorPlan:
    """Solid polygons with holes as one obstacle (a shape of :mod:`sim.shapes`): a map.

    ``geom`` is a shapely MultiPolygon, metres; ``source`` the file it came from.
    """

    geom: BaseGeometry
    name: str = ""
    source: str = ""
    kind = "floorplan"

    def geometry(self) -> BaseGeometry:
        """Return the shapely MultiPolygon."""
        return self.geom

    def parts(self) -> Parts:
        """Return every ring's faces at once (:func:`outline_parts`)."""
        return outline_parts(self.geom)


@dataclass(frozen=True)
class MapInfo:
    """A ``map_server`` map's YAML: where the image is, and how to read it.

    Attributes
    ----------
    image : str
        The image's path (relative paths resolved against the YAML file's folder).
    resolution : float
        Metres per pixel.
    origin : (x, y, yaw)
        Metres and radians: the pose of the image's lower-left corner.
    occupied_thresh, free_thresh : float
        Probabilities: above the first a cell is occupied, below the second free.
    negate : bool
        Whether white is occupied (``negate: 1``).
    mode : str
        One of :data:`MAP_MODES`.
    """

    image: str
    resolution: float
    origin: tuple[float, float, float]
    occupied_thresh: float = 0.65
    free_thresh: float = 0.196
    negate: bool = False
    mode: str = "trinary"


def read_map_info(path: str | os.PathLike[str]) -> MapInfo:
    """Read and check a ``map_server`` YAML file.

    Raises
    ------
    WorldError
        Unreadable, not YAML, a missing or unknown key, or a bad value (file, line, key).
    """
    from mdle.core.userfile import UserFileError, read_user_file
    from mdle.sim.yaml_doc import _Doc, _yaml_value
    from mdle.sim.yaml_values import _mapping, _number, _show, _string

    file = str(path)
    try:
        text = read_user_file(path).decode("utf-8")
    except UserFileError as err:
        raise WorldError(f"cannot read map file {file}: {err.reason}") from None
    except UnicodeDecodeError:
        raise WorldError(f"cannot read map file {file}: not UTF-8 text") from None
    doc = _Doc(file, text)
    data = _yaml_value(doc)
    top = _mapping(doc, "", {} if data is None else data, _MAP_KEYS, "a map_server map")
    for key in ("image", "resolution", "origin"):
        if key not in top:
            raise doc.fail("", f"missing key `{key}` (a map needs image, resolution, origin)")
    image = _string(doc, "image", top["image"])
    if not image:
        raise doc.fail("image", "expected the image's file name, got nothing")
    resolution = _number(doc, "resolution", top["resolution"], size=True)
    raw_origin = top["origin"]
    if not isinstance(raw_origin, list) or len(raw_origin) != 3:
        raise doc.fail("origin", f"expected [x, y, yaw] (metres, radians), got "
                       f"{_show(raw_origin)}")
    ox, oy = (_number(doc, f"origin[{i}]", raw_origin[i], coordinate=True) for i in range(2))
    yaw = _number(doc, "origin[2]", raw_origin[2], unit="rad")
    occ = _number(doc, "occupied_thresh", top.get("occupied_thresh", 0.65))
    free = _number(doc, "free_thresh", top.get("free_thresh", 0.196))
    for key, value in (("occupied_thresh", occ), ("free_thresh", free)):
        if not 0.0 <= value <= 1.0:
            raise doc.fail(key, f"a probability is between 0 and 1, got {value:g}")
    if free > occ:
        raise doc.fail("free_thresh", f"must not exceed occupied_thresh ({occ:g}), got "
                       f"{free:g}")
    negate = top.get("negate", 0)
    if isinstance(negate, bool) or negate not in (0, 1):
        raise doc.fail("negate", f"expected 0 or 1, got {_show(negate)}")
    mode = _string(doc, "mode", top.get("mode", "trinary"))
    if mode not in MAP_MODES:
        raise doc.fail("mode", f"unknown mode {mode!r}; one of: {', '.join(MAP_MODES)}")
    where = Path(file).parent
    full = Path(image) if Path(image).is_absolute() else where / image
    return MapInfo(str(full), resolution, (ox, oy, yaw), occ, free, bool(negate), mode)


def read_image(path: str | os.PathLike[str]) -> np.ndarray:
    """Read a map image as shades 0-255 (float32, rows top first).

    PGM (binary ``P5`` or text ``P2``, 8 or 16 bits) is read here; other formats (PNG,
    BMP, ...) through Pillow, which matplotlib already installs. A colour image's shade
    is the mean of its colour channels (alpha ignored).

    Raises
    ------
    WorldError
        Unreadable, not an image, or larger than :data:`MAX_MAP_CELLS`.
    """
    from mdle.core.userfile import UserFileError, read_user_file

    try:
        data = read_user_file(path)
    except UserFileError as err:
        raise WorldError(f"cannot read map image {path}: {err.reason}") from None
    if data[:2] in (b"P5", b"P2"):
        return _pgm(data, str(path))
    return _pillow(data, str(path))


def _pgm(data: bytes, file: str) -> np.ndarray:
    """Decode a PGM (P5 binary or P2 text) into shades 0-255."""
    fields: list[int] = []
    i = 2
    while len(fields) < 3:                # width, height, maxval; '#' starts a comment
        while i < len(data) and data[i:i + 1].isspace():
            i += 1
        if data[i:i + 1] == b"#":
            while i < len(data) and data[i:i + 1] not in (b"\n", b"\r"):
                i += 1
            continue
        j = i
        while j < len(data) and data[j:j + 1].isdigit():
            j += 1
        if j == i:
            raise WorldError(f"{file}: not a PGM image (its header needs width, height and "
                             "the largest shade)")
        fields.append(int(data[i:j]))
        i = j
    width, height, maxval = fields
    if width < 1 or height < 1 or not 1 <= maxval <= 65535:
        raise WorldError(f"{file}: a PGM of {width} x {height} pixels, shades up to "
                         f"{maxval}: nothing to read")
    if width * height > MAX_MAP_CELLS:
        raise WorldError(f"{file}: {width} x {height} pixels is more than the "
                         f"{MAX_MAP_CELLS:,} cells a map may have")
    n = width * height
    if data[:2] == b"P5":
        i += 1                             # one whitespace byte ends the header
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        need = n * dtype.itemsize
        if len(data) - i < need:
            raise WorldError(f"{file}: the PGM says {width} x {height} pixels but holds "
                             f"{max(0, len(data) - i)} bytes of the {need} they need")
        pixels = np.frombuffer(data, dtype=dtype, count=n, offset=i)
    else:
        try:
            pixels = np.array(data[i:].split()[:n], dtype=np.int64)
        except ValueError:
            raise WorldError(f"{file}: a text PGM whose pixels are not all numbers") from None
        if pixels.shape[0] < n:
            raise WorldError(f"{file}: the PGM says {width} x {height} pixels but holds "
                             f"{pixels.shape[0]}")
    grid = pixels.reshape(height, width)
    shades = np.empty((height, width), dtype=np.float32)
    for band in _bands(height, width):
        shades[band] = grid[band]
        if maxval != 255:
            shades[band] *= np.float32(255.0 / maxval)
    return shades


def _pillow(data: bytes, file: str) -> np.ndarray:
    """Decode any image Pillow reads into shades 0-255."""
    import io

    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as img:
            if img.width * img.height > MAX_MAP_CELLS:
                raise WorldError(f"{file}: {img.width} x {img.height} pixels is more than the "
                                 f"{MAX_MAP_CELLS:,} cells a map may have")
            if img.mode in ("I;16", "I;16B", "I"):
                arr = np.asarray(img, dtype=np.float32) * np.float32(255.0 / 65535.0)
            else:
                arr = np.asarray(img.convert("RGBA" if "A" in img.getbands() else "RGB"),
                                 dtype=np.float32)[..., :3].mean(axis=2)
    except (UnidentifiedImageError, OSError, ValueError) as err:
        raise WorldError(f"{file}: not an image mdle can read ({err})") from None
    return np.asarray(arr, dtype=np.float32)


def occupied_cells(shades: np.ndarray, info: MapInfo) -> np.ndarray:
    """Return where the map is occupied (bool, the image's shape), as ``map_server`` reads it."""
    occupied = np.empty(shades.shape, dtype=bool)
    for band in _bands(*shades.shape):
        c = shades[band]
        if info.mode == "raw":
            occupied[band] = (c <= 100.0) & (c > 100.0 * info.occupied_thresh)
            continue
        p = c / np.float32(255.0) if info.negate else (np.float32(255.0) - c) / 255.0
        occupied[band] = p > info.occupied_thresh
    return occupied


def outline(occupied: np.ndarray, resolution: float, origin: tuple[float, float, float],
            tolerance: float | None = None) -> BaseGeometry:
    """Return the occupied cells' outlines as a shapely MultiPolygon (with holes), metres.

    ``occupied``: (rows, columns) bool, the first row the map's top. ``tolerance``: how
    far the simplified outline may stray from the cells' (metres; default one cell;
    0 keeps every corner).
    """
    import shapely
    from shapely import affinity

    tol = resolution if tolerance is None else float(tolerance)
    if not (math.isfinite(tol) and tol >= 0):
        raise ValueError(f"a tolerance is a length of 0 or more, not {tolerance!r}")
    occupied = np.asarray(occupied, dtype=bool)
    rows = occupied.shape[0]
    # Runs along each row: where a run starts (0 -> 1) and ends (1 -> 0), band by band.
    starts_r, starts_c, ends_c = [], [], []
    for band in _bands(*occupied.shape):
        edges = np.diff(occupied[band].astype(np.int8), axis=1, prepend=0, append=0)
        r_band, c_band = np.nonzero(edges == 1)
        starts_r.append(r_band + band.start)
        starts_c.append(c_band)
        ends_c.append(np.nonzero(edges == -1)[1])  # row-major, so paired with the starts
    r_start = np.concatenate(starts_r) if starts_r else np.zeros(0, dtype=np.intp)
    c_start = np.concatenate(starts_c) if starts_c else np.zeros(0, dtype=np.intp)
    c_end = np.concatenate(ends_c) if ends_c else np.zeros(0, dtype=np.intp)
    # The same run on the next row down continues a rectangle: group by (start, end, row).
    order = np.lexsort((r_start, c_end, c_start))
    r, a, b = r_start[order], c_start[order], c_end[order]
    new = np.ones(r.shape[0], dtype=bool)
    new[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1]) | (r[1:] != r[:-1] + 1)
    first = np.flatnonzero(new)
    if first.shape[0] == 0:
        return shapely.MultiPolygon()
    top, bottom = r[first], np.maximum.reduceat(r, first)
    x0, y0, yaw = origin
    boxes = shapely.box(x0 + a[first] * resolution, y0 + (rows - 1 - bottom) * resolution,
                        x0 + b[first] * resolution, y0 + (rows - top) * resolution)
    # Simplified even at 0: that drops the corners the union leaves on straight edges.
    # Seconds in GEOS for a large map: run so that Ctrl-C still cuts it.
    merged = call_interruptibly(
        lambda: shapely.simplify(shapely.union_all(boxes), tol, preserve_topology=True))
    if yaw != 0.0:
        merged = affinity.rotate(merged, yaw, origin=(x0, y0), use_radians=True)
    parts = [g for g in shapely.get_parts(merged) if g.geom_type == "Polygon" and g.area > 0]
    return shapely.MultiPolygon(parts)


def load_map(path: str | os.PathLike[str], tolerance: float | None = None,
             name: str = "") -> FloorPlan:
    """Read a ``map_server`` map into one :class:`FloorPlan` obstacle.

    Raises
    ------
    WorldError
        A bad YAML file or image (:func:`read_map_info`, :func:`read_image`), or a map
        with no occupied cell.
    """
    info = read_map_info(path)
    shades = read_image(info.image)
    occupied = occupied_cells(shades, info)
    geom = outline(occupied, info.resolution, info.origin, tolerance)
    if geom.is_empty:
        raise WorldError(f"{path}: the map has no occupied cell (occupied_thresh "
                         f"{info.occupied_thresh:g}, negate {int(info.negate)}, mode "
                         f"{info.mode}): nothing to make obstacles of")
    return FloorPlan(geom, name or Path(path).stem, str(path))



def outline_parts(geom: BaseGeometry) -> Parts:
    """Return the faces of every ring of a (Multi)Polygon at once, solid on the right.

    Exteriors run clockwise and holes counter-clockwise (the solid is then on the right),
    as :func:`sim.shapes.polygon_parts` orients them, with array operations over all the
    rings instead of a loop over polygons; the faces are flat (curvature 0): a map's
    outline is a simplified staircase, not a sampled curve.
    """
    import shapely


    polys = shapely.get_parts(geom)
    if polys.shape[0] == 0:
        return Parts.make()
    rings = shapely.get_rings(polys)
    # get_rings lists each polygon's exterior, then its holes.
    per = shapely.get_num_interior_rings(polys) + 1
    exterior = np.zeros(rings.shape[0], dtype=bool)
    exterior[np.cumsum(per) - per] = True
    flip = shapely.is_ccw(rings) == exterior
    xy, ring = shapely.get_coordinates(rings, return_index=True)
    same = ring[1:] == ring[:-1]               # a ring's last point closes it: no wrap
    s0, s1 = xy[:-1][same], xy[1:][same]
    turn = flip[ring[:-1][same]][:, None]
    return Parts.make((np.where(turn, s1, s0), np.where(turn, s0, s1), np.zeros(s0.shape[0])))
