"""The Python twin of the .NET ESPRIT emulation (``csharp/EspritEmulation.cs``).

Same classes, members and behaviour, member for member, for fast tests and machines without
Mono; the adapter tests run against both. The enums are built from
:mod:`~adapters.esprit_com.object_model`. As in the C# file, the ESPRIT-like classes hold only
ESPRIT members; filling documents and reading back what was drawn is in :class:`Emulation`.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import overload

import numpy as np
from numpy.typing import NDArray

from adapters.esprit_com import object_model as om


# The enums spelled out member by member (mypy cannot see the members of a functional IntEnum),
# in the tables' order and with the tables' values.
class espToolPathItemType(IntEnum):
    tpiSTART_POINT = om.ITEM_TYPES["tpiSTART_POINT"]
    tpiEND_POINT = om.ITEM_TYPES["tpiEND_POINT"]
    tpiSEG2 = om.ITEM_TYPES["tpiSEG2"]
    tpiSEG3 = om.ITEM_TYPES["tpiSEG3"]
    tpiARC2 = om.ITEM_TYPES["tpiARC2"]
    tpiARC3 = om.ITEM_TYPES["tpiARC3"]


class espGraphicObjectType(IntEnum):
    espPoint = om.GRAPHIC_OBJECT_TYPES["espPoint"]
    espSegment = om.GRAPHIC_OBJECT_TYPES["espSegment"]
    espArc = om.GRAPHIC_OBJECT_TYPES["espArc"]
    espOperation = om.GRAPHIC_OBJECT_TYPES["espOperation"]


class espUnitType(IntEnum):
    espInch = om.UNIT_TYPES["espInch"]
    espMetric = om.UNIT_TYPES["espMetric"]


T = espToolPathItemType


class _List:
    """A 1-based ESPRIT collection."""

    _what = "items"

    def __init__(self) -> None:
        self.items: list = []

    @property
    def Count(self) -> int:
        return len(self.items)

    def __getitem__(self, i: int):
        if not 1 <= i <= len(self.items):
            raise IndexError(f"{self._what} are numbered 1..{len(self.items)}, got {i}")
        return self.items[i - 1]

    def __iter__(self):
        return iter(list(self.items))


def _finite(value: float, what: str) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{what} must be finite, got {value}")
    return value


# ------------------------------------------------------------------ tool path geometry
class ComPoint:
    def __init__(self, x: float, y: float, z: float) -> None:
        self.X, self.Y, self.Z = float(x), float(y), float(z)


ComVector = ComPoint


class ComSegment:
    def __init__(self, start: ComPoint, end: ComPoint) -> None:
        self.StartPoint, self.EndPoint = start, end

    @property
    def Length(self) -> float:
        s, e = self.StartPoint, self.EndPoint
        return math.dist((s.X, s.Y, s.Z), (e.X, e.Y, e.Z))


class ComArc:
    def __init__(self, centre, radius, u, v, start, end) -> None:
        self.CenterPoint, self.Radius, self.U, self.V = centre, float(radius), u, v
        self.StartAngle, self.EndAngle = float(start), float(end)

    @property
    def Length(self) -> float:
        sweep = self.EndAngle - self.StartAngle
        return self.Radius * (sweep if sweep > 0 else sweep + 2 * math.pi)


@overload
def _copy(data: ComPoint) -> ComPoint: ...
@overload
def _copy(data: object) -> object: ...
def _copy(data: object) -> object:
    if isinstance(data, ComSegment):
        return ComSegment(_copy(data.StartPoint), _copy(data.EndPoint))
    if isinstance(data, ComArc):
        d = data
        return ComArc(
            _copy(d.CenterPoint), d.Radius, _copy(d.U), _copy(d.V), d.StartAngle, d.EndAngle
        )
    if isinstance(data, ComPoint):
        return ComPoint(data.X, data.Y, data.Z)
    return data


class ToolPathItem:
    def __init__(self, type_: int, aux: int, data: object) -> None:
        # An int not in the enum stays an int, as a C# enum holds any value.
        self.Type = T(type_) if type_ in T._value2member_map_ else int(type_)
        self.AuxCode = int(aux)
        self.data = data


class ToolPath:
    def __init__(self) -> None:
        self.items: list[ToolPathItem] = []

    @property
    def Count(self) -> int:
        return len(self.items)

    def ItemCopy(self, i: int) -> ToolPathItem:
        """Item ``i`` (1-based), a copy."""
        if not 1 <= i <= len(self.items):
            raise IndexError(f"tool path items are numbered 1..{len(self.items)}, got {i}")
        it = self.items[i - 1]
        return ToolPathItem(it.Type, it.AuxCode, _copy(it.data))


class TechMill3DFinish:
    def __init__(self, xy: float, z: float) -> None:
        self.XYFeedratePM, self.ZFeedratePM = float(xy), float(z)


class PartOperation:
    GraphicObjectType = espGraphicObjectType.espOperation

    def __init__(self, name: str, key: int, tech: object, tool_path: ToolPath | None) -> None:
        self.Name, self.Key, self.Technology, self.ToolPath = name, key, tech, tool_path
        self.LengthOfFeed = self.LengthOfRapid = 0.0
        self.Suppress = False


class PartOperations(_List):
    _what = "operations"


class Group(_List):
    _what = "group entries"


# ------------------------------------------------------------------ drawing
class Layer:
    def __init__(self, name: str) -> None:
        self.Name, self.Visible = name, True


class Point:
    GraphicObjectType = espGraphicObjectType.espPoint

    def __init__(self, x: float, y: float, z: float, colour: int = 0, layer=None) -> None:
        self.X, self.Y, self.Z = (_finite(c, a) for c, a in ((x, "x"), (y, "y"), (z, "z")))
        self.Color, self.Layer = colour, layer


class Segment:
    GraphicObjectType = espGraphicObjectType.espSegment

    def __init__(self, p1: Point, p2: Point, colour: int, layer: Layer) -> None:
        self.StartPoint, self.EndPoint, self.Color, self.Layer = p1, p2, colour, layer


class Arc:
    GraphicObjectType = espGraphicObjectType.espArc

    def __init__(self, centre, radius, start, end, colour, layer) -> None:
        self.CenterPoint, self.Radius = centre, radius
        self.StartAngle, self.EndAngle = start, end
        self.Ux, self.Uy, self.Uz, self.Vx, self.Vy, self.Vz = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0
        self.Color, self.Layer = colour, layer


class Layers(_List):
    _what = "layers"

    def __init__(self, doc: Document) -> None:
        super().__init__()
        self._doc = doc

    def Add(self, name: str) -> Layer:
        if not name:
            raise ValueError("a layer needs a name")
        if any(layer.Name == name for layer in self.items):
            raise ValueError(f"layer '{name}' exists")
        layer = Layer(name)
        self.items.append(layer)
        return layer

    def Remove(self, name: str) -> None:
        """Remove the layer and what is drawn on it."""
        found = next((layer for layer in self.items if layer.Name == name), None)
        if found is None:
            raise ValueError(f"no layer '{name}'")
        if found is self._doc._active_layer:
            raise RuntimeError("cannot remove the active layer")
        self.items.remove(found)
        for coll in (self._doc.Segments, self._doc.Arcs, self._doc.Points):
            coll.items = [o for o in coll.items if o.Layer is not found]


class Segments(_List):
    def __init__(self, doc: Document) -> None:
        super().__init__()
        self._doc = doc

    def Add(self, p1: Point, p2: Point) -> Segment:
        if p1 is None or p2 is None:
            raise ValueError("a segment needs two points")
        s = Segment(p1, p2, self._doc.ActiveColor, self._doc._active_layer)
        self.items.append(s)
        return s


class Arcs(_List):
    def __init__(self, doc: Document) -> None:
        super().__init__()
        self._doc = doc

    def Add(self, centre: Point, radius: float, start: float, end: float) -> Arc:
        if centre is None:
            raise ValueError("an arc needs a centre")
        radius = _finite(radius, "radius")
        start, end = _finite(start, "start angle"), _finite(end, "end angle")
        if radius <= 0:
            raise ValueError(f"arc radius must be positive, got {radius:g}")
        a = Arc(centre, radius, start, end, self._doc.ActiveColor, self._doc._active_layer)
        self.items.append(a)
        return a


class Points(_List):
    def __init__(self, doc: Document) -> None:
        super().__init__()
        self._doc = doc

    def Add(self, x: float, y: float, z: float) -> Point:
        p = Point(x, y, z, self._doc.ActiveColor, self._doc._active_layer)
        self.items.append(p)
        return p


# ------------------------------------------------------------------ document, application
class Document:
    def __init__(self, name: str) -> None:
        self.Name = name
        self.SystemUnit = espUnitType.espMetric
        self.PartOperations = PartOperations()
        self.Group = Group()
        self.Layers = Layers(self)
        self.Segments = Segments(self)
        self.Arcs = Arcs(self)
        self.Points = Points(self)
        self.ActiveColor = 0
        self._active_layer = self.Layers.Add("Default")
        self._transaction: tuple | None = None
        self._undo_steps = self._cancelled = self._refreshes = 0

    @property
    def ActiveLayer(self) -> Layer:
        return self._active_layer

    @ActiveLayer.setter
    def ActiveLayer(self, layer: Layer) -> None:
        if not any(layer is x for x in self.Layers.items):
            raise ValueError("the active layer must be a layer of this document")
        self._active_layer = layer

    def GetPoint(self, x: float, y: float, z: float) -> Point:
        return Point(x, y, z)

    def OpenUndoTransaction(self) -> None:
        if self._transaction is not None:
            raise RuntimeError("an undo transaction is already open")
        self._transaction = (
            list(self.Layers.items),
            list(self.Segments.items),
            list(self.Arcs.items),
            list(self.Points.items),
            self._active_layer,
            self.ActiveColor,
        )

    def CloseUndoTransaction(self, keep: bool) -> None:
        if self._transaction is None:
            raise RuntimeError("no undo transaction is open")
        if keep:
            self._undo_steps += 1
        else:
            (
                self.Layers.items,
                self.Segments.items,
                self.Arcs.items,
                self.Points.items,
                self._active_layer,
                self.ActiveColor,
            ) = self._transaction
            self._cancelled += 1
        self._transaction = None

    def Refresh(self) -> None:
        self._refreshes += 1


class Application:
    Name = "ESPRIT (ncperf Python twin)"

    def __init__(self, document_name: str) -> None:
        self.Document = Document(document_name)


# ------------------------------------------------------------------ not ESPRIT
class Emulation:
    """Filling documents and reading back what was drawn: the C# ``Emulation`` class."""

    ItemStride = 12

    @staticmethod
    def AddOperation(doc, name, xy_feed, z_feed, with_tool_path) -> PartOperation:
        op = PartOperation(
            name,
            doc.PartOperations.Count + 1,
            TechMill3DFinish(xy_feed, z_feed),
            ToolPath() if with_tool_path else None,
        )
        doc.PartOperations.items.append(op)
        return op

    @staticmethod
    def AddItems(op, types, aux, data, rapid_aux) -> None:
        if op.ToolPath is None:
            raise RuntimeError("operation has no tool path")
        data = np.asarray(data, dtype=np.float64).reshape(-1, Emulation.ItemStride)
        for t, a, d in zip(
            np.asarray(types).tolist(), np.asarray(aux).tolist(), data.tolist(), strict=True
        ):
            length = 0.0
            obj: ComPoint | ComSegment | ComArc | None = None
            if t in (T.tpiSTART_POINT, T.tpiEND_POINT):
                obj = ComPoint(*d[0:3])
            elif t in (T.tpiSEG2, T.tpiSEG3):
                obj = ComSegment(ComPoint(*d[0:3]), ComPoint(*d[3:6]))
                length = obj.Length
            elif t in (T.tpiARC2, T.tpiARC3):
                obj = ComArc(
                    ComPoint(*d[0:3]), d[3], ComPoint(*d[4:7]), ComPoint(*d[7:10]), d[10], d[11]
                )
                length = obj.Length
            op.ToolPath.items.append(ToolPathItem(t, a, obj))
            if a == rapid_aux:
                op.LengthOfRapid += length
            else:
                op.LengthOfFeed += length

    @staticmethod
    def SetLengths(op, feed: float, rapid: float) -> None:
        op.LengthOfFeed, op.LengthOfRapid = float(feed), float(rapid)

    @staticmethod
    def Select(doc, obj) -> None:
        doc.Group.items.append(obj)

    @staticmethod
    def LayerNames(doc) -> list[str]:
        return [layer.Name for layer in doc.Layers.items]

    @staticmethod
    def _layer(doc, layer) -> int:
        return next(i for i, x in enumerate(doc.Layers.items) if x is layer)

    @staticmethod
    def SegmentRecords(doc) -> NDArray[np.float64]:
        rows = [
            (s.StartPoint.X, s.StartPoint.Y, s.StartPoint.Z, s.EndPoint.X, s.EndPoint.Y,
             s.EndPoint.Z, s.Color, Emulation._layer(doc, s.Layer))
            for s in doc.Segments.items
        ]  # fmt: skip
        return np.asarray(rows, dtype=np.float64).reshape(-1)

    @staticmethod
    def ArcRecords(doc) -> NDArray[np.float64]:
        rows = [
            (a.CenterPoint.X, a.CenterPoint.Y, a.CenterPoint.Z, a.Radius, a.Ux, a.Uy, a.Uz,
             a.Vx, a.Vy, a.Vz, a.StartAngle, a.EndAngle, a.Color, Emulation._layer(doc, a.Layer))
            for a in doc.Arcs.items
        ]  # fmt: skip
        return np.asarray(rows, dtype=np.float64).reshape(-1)

    @staticmethod
    def PointRecords(doc) -> NDArray[np.float64]:
        rows = [(p.X, p.Y, p.Z, p.Color, Emulation._layer(doc, p.Layer)) for p in doc.Points.items]
        return np.asarray(rows, dtype=np.float64).reshape(-1)

    @staticmethod
    def UndoSteps(doc) -> int:
        return doc._undo_steps

    @staticmethod
    def Cancelled(doc) -> int:
        return doc._cancelled

    @staticmethod
    def Refreshes(doc) -> int:
        return doc._refreshes

    @staticmethod
    def TransactionOpen(doc) -> bool:
        return doc._transaction is not None
