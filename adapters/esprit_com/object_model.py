"""The ESPRIT object model as this adapter reads and writes it: the one table of assumptions.

Member *names* come from DP Technology's public C# add-in tutorials (``Document.PartOperations``,
``ToolPath.ItemCopy(i)``, ``IComArc.U``, ``Document.Segments.Add(p1, p2)`` ...). What those
tutorials do not show -- the numbers behind the enums, how a tool path item says it is a rapid
or which feed it runs at, the units of angles, what ``CloseUndoTransaction(False)`` does -- is
assumed below, each value marked **ASSUMPTION** with what to look at on a real installation.
Everything else in the adapter, the .NET emulation (``csharp/EspritEmulation.cs``, whose enums
must equal :data:`ITEM_TYPES`, :data:`GRAPHIC_OBJECT_TYPES` and :data:`UNIT_TYPES`; a test checks
it) and the Python twin take their numbers from here.

To check on a real ESPRIT: run ``ExaminingToolpathTutorial`` (it prints every item's ``Type``
and ``AuxCode``) on an operation with rapids, plunges and arcs, and compare with the tables;
``ncperf esprit`` itself warns when the feed and rapid lengths it reads disagree with
``PartOperation.LengthOfFeed`` / ``LengthOfRapid`` (the cross-check of :data:`AUX_CODES`).
"""

from __future__ import annotations

import math
from typing import Any

#: A late-bound object of ESPRIT's object model (COM, .NET through pythonnet, or the Python
#: twin): its members are resolved at run time, so it is typed Any.
ComObject = Any

# ----------------------------------------------------------------------------- connection
#: ProgID ESPRIT registers for its Application object (seen in public scripts that call
#: ``Dispatch("Esprit.Application")``). ASSUMPTION: the running ESPRIT is also in the
#: running object table under it, so ``Marshal.GetActiveObject`` finds it.
PROG_ID = "Esprit.Application"

# ----------------------------------------------------------------------------- tool path items
#: ``EspritConstants.espToolPathItemType``: name -> value. ASSUMPTION: the values (not public;
#: here the order the names appear in DP's tutorials, from 0). "2"/"3" are taken as planar (XY)
#: and general 3-D geometry; the adapter reads both alike.
ITEM_TYPES: dict[str, int] = {
    "tpiSTART_POINT": 0,
    "tpiEND_POINT": 1,
    "tpiSEG2": 2,
    "tpiSEG3": 3,
    "tpiARC2": 4,
    "tpiARC3": 5,
}
#: Items whose ``data`` is an IComPoint (no motion: they mark where the path starts and ends).
POINT_ITEMS = frozenset({ITEM_TYPES["tpiSTART_POINT"], ITEM_TYPES["tpiEND_POINT"]})
#: Items whose ``data`` is an IComSegment (``StartPoint``, ``EndPoint``, ``Length``).
SEGMENT_ITEMS = frozenset({ITEM_TYPES["tpiSEG2"], ITEM_TYPES["tpiSEG3"]})
#: Items whose ``data`` is an IComArc (``CenterPoint``, ``Radius``, ``U``, ``V``,
#: ``StartAngle``, ``EndAngle``, ``Length``).
ARC_ITEMS = frozenset({ITEM_TYPES["tpiARC2"], ITEM_TYPES["tpiARC3"]})
ITEM_NAMES: dict[int, str] = {v: k for k, v in ITEM_TYPES.items()}

# ----------------------------------------------------------------------------- feeds
#: How an item says what it runs at: ``ToolPathItem.AuxCode`` -> the ``Technology`` attributes
#: holding its feed (per minute, document units), tried in order; ``None`` marks a rapid.
#: ASSUMPTION (the public tutorials show ``AuxCode`` but not its meaning, and items carry no
#: feed of their own): 0 is a cutting move at the technology's XY feed (``XYFeedratePM`` on
#: milling technologies, ``FeedratePM`` on lathe ones), 1 a rapid, 2 a plunge or ramp at
#: ``ZFeedratePM`` (the XY feed where the technology has none). Any other code is an error
#: naming the item, not a guess. Checked at run time against ``LengthOfFeed``/``LengthOfRapid``.
AUX_CODES: dict[int, tuple[str, ...] | None] = {
    0: ("XYFeedratePM", "FeedratePM"),
    1: None,
    2: ("ZFeedratePM", "XYFeedratePM", "FeedratePM"),
}
AUX_CUT, AUX_RAPID, AUX_PLUNGE = 0, 1, 2

#: ``PartOperation`` lengths ESPRIT computes itself (document units), used to cross-check
#: :data:`AUX_CODES`: the item lengths read as feed and as rapid must add up to them.
LENGTH_OF_FEED = "LengthOfFeed"
LENGTH_OF_RAPID = "LengthOfRapid"

# ----------------------------------------------------------------------------- units
#: ``Document.SystemUnit`` (``EspritConstants.espUnitType``, seen in DP's cycle-time tutorial):
#: value -> (units, mm per document unit). ASSUMPTION: the values. A document without
#: ``SystemUnit``, or with another value, is read as mm, with a warning.
UNIT_TYPES: dict[str, int] = {"espInch": 0, "espMetric": 1}
UNITS: dict[int, tuple[str, float]] = {
    UNIT_TYPES["espInch"]: ("inch", 25.4),
    UNIT_TYPES["espMetric"]: ("mm", 1.0),
}
SYSTEM_UNIT = "SystemUnit"

#: ASSUMPTION: arc angles (``IComArc.StartAngle/EndAngle``, ``Arcs.Add``) are radians; an arc
#: runs counter-clockwise about U x V from StartAngle to EndAngle, the point at angle a being
#: centre + radius (cos a U + sin a V); EndAngle <= StartAngle wraps once (+2 pi).
ANGLE_TO_RAD = 1.0
FULL_TURN = 2.0 * math.pi

# ----------------------------------------------------------------------------- selection
#: ``Document.Group`` is the selection (``Count``, 1-based indexer); an entry is an operation
#: when its ``GraphicObjectType`` is ``espOperation`` (DP's smash tutorial). ASSUMPTION: values.
GRAPHIC_OBJECT_TYPES: dict[str, int] = {
    "espPoint": 1,
    "espSegment": 2,
    "espArc": 3,
    "espOperation": 40,
}
GRAPHIC_OPERATION = GRAPHIC_OBJECT_TYPES["espOperation"]

# ----------------------------------------------------------------------------- drawing
#: The layer the annotations go on; an older one of that name is removed first, inside the
#: same undo transaction (DP's ``GetEmptyLayer`` helper does the same). ASSUMPTION: removing
#: a layer removes what is drawn on it.
LAYER_NAME = "ncperf performance"

#: ASSUMPTION: colours are COLORREF, 0x00BBGGRR (red in the low byte), the order of DP's
#: ``ColorToUInt`` helper; that helper also sets the alpha byte (0xFF << 24), which ESPRIT
#: may ignore -- set it here if a real installation draws nothing or black.
COLOUR_ALPHA = 0x00

#: ASSUMPTION: new graphic objects take ``Document.ActiveColor`` and ``Document.ActiveLayer``
#: (DP's centre-line tutorial sets ``ActiveColor`` before ``Segments.Add``), so the adapter
#: sets them once per class instead of ``.Color``/``.Layer`` on every object.
USE_ACTIVE_STYLE = True

#: ASSUMPTION: ``CloseUndoTransaction(True)`` keeps what was done since ``OpenUndoTransaction()``
#: as one undo step; ``CloseUndoTransaction(False)`` cancels it (DP's undo tutorial shows only
#: True).
UNDO_KEEP, UNDO_CANCEL = True, False

# ----------------------------------------------------------------------------- late binding
#: Members called as methods when the adapter talks to ESPRIT through COM late binding
#: (``IDispatch``); every other member is read or written as a property.
METHODS = frozenset(
    {
        "ItemCopy",
        "Add",
        "Remove",
        "GetPoint",
        "OpenUndoTransaction",
        "CloseUndoTransaction",
        "Refresh",
    }
)
#: COM default member behind ``collection[i]`` (``PartOperations``, ``Group``, ``Layers``).
INDEXER = "Item"
