"""What each G-code, M-code and keyword means to ncperf, per dialect.

G-codes are keyed by ``round(10 * number)``: G1 -> 10, G91.1 -> 911, G642 -> 6420.
Sources: LinuxCNC 2.9 G-code reference, Fanuc 0i/30i-MB operator's manuals,
SINUMERIK 840D sl programming manual (fundamentals) -- facts only.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

DIALECTS = ("fanuc", "siemens", "linuxcnc")


class Group(IntEnum):
    """Modal groups ncperf tracks (plus the non-modal codes it acts on)."""

    MOTION = 0
    PLANE = 1
    DISTANCE = 2
    ARC_DISTANCE = 3
    UNITS = 4
    FEED_MODE = 5
    PATH_MODE = 6
    WORK_OFFSET = 7
    DWELL = 8  # G4, non-modal
    EXACT_STOP_BLOCK = 9  # G9, non-modal
    HOME = 10  # G28 / G30, non-modal
    MACHINE_COORDS = 11  # G53, non-modal
    PASS = 12  # recognised, no effect on the path


N_GROUPS = len(Group)


@dataclass(frozen=True)
class GCode:
    group: Group | None  # None: an error
    message: str = ""  # the error, or a notice for PASS codes that deserve one


def _c(x: float) -> int:
    return round(x * 10)


# Codes every dialect reads the same way.
COMMON: dict[int, GCode] = {
    _c(0): GCode(Group.MOTION),
    _c(1): GCode(Group.MOTION),
    _c(2): GCode(Group.MOTION),
    _c(3): GCode(Group.MOTION),
    _c(4): GCode(Group.DWELL),
    _c(9): GCode(Group.EXACT_STOP_BLOCK),
    _c(17): GCode(Group.PLANE),
    _c(18): GCode(Group.PLANE),
    _c(19): GCode(Group.PLANE),
    _c(20): GCode(Group.UNITS),
    _c(21): GCode(Group.UNITS),
    _c(28): GCode(Group.HOME),
    _c(30): GCode(Group.HOME),
    _c(40): GCode(Group.PASS),  # cutter compensation off
    _c(43): GCode(Group.PASS),  # tool length offset: shifts Z uniformly, shape unchanged
    _c(44): GCode(Group.PASS),
    _c(49): GCode(Group.PASS),
    _c(53): GCode(Group.MACHINE_COORDS),
    _c(54): GCode(Group.WORK_OFFSET),
    _c(55): GCode(Group.WORK_OFFSET),
    _c(56): GCode(Group.WORK_OFFSET),
    _c(57): GCode(Group.WORK_OFFSET),
    _c(58): GCode(Group.WORK_OFFSET),
    _c(59): GCode(Group.WORK_OFFSET),
    _c(61): GCode(Group.PATH_MODE),
    _c(64): GCode(Group.PATH_MODE),
    _c(69): GCode(Group.PASS),  # cancel coordinate rotation
    _c(90): GCode(Group.DISTANCE),
    _c(91): GCode(Group.DISTANCE),
    _c(90.1): GCode(Group.ARC_DISTANCE),
    _c(91.1): GCode(Group.ARC_DISTANCE),
    _c(93): GCode(Group.FEED_MODE),
    _c(94): GCode(Group.FEED_MODE),
    _c(95): GCode(Group.FEED_MODE),
    _c(96): GCode(Group.PASS),  # spindle speed modes do not move the tool
    _c(97): GCode(Group.PASS),
    _c(98): GCode(Group.PASS),  # canned-cycle return level, no cycle follows unless G8x
    _c(99): GCode(Group.PASS),
    # Errors: each would move the tool in a way ncperf cannot follow.
    _c(10): GCode(None, "G10 (setting offsets or tool data) is not supported"),
    _c(41): GCode(None, "cutter compensation G41 is not supported (the path would be offset)"),
    _c(42): GCode(None, "cutter compensation G42 is not supported (the path would be offset)"),
    _c(41.1): GCode(None, "cutter compensation G41.1 is not supported"),
    _c(42.1): GCode(None, "cutter compensation G42.1 is not supported"),
    _c(52): GCode(None, "G52 local coordinate system is not supported"),
    _c(68): GCode(None, "G68 coordinate rotation is not supported"),
    _c(92): GCode(None, "G92 coordinate offset is not supported"),
    _c(92.1): GCode(None, "G92.1 is not supported"),
    _c(92.2): GCode(None, "G92.2 is not supported"),
    _c(92.3): GCode(None, "G92.3 is not supported"),
    _c(15): GCode(None, "G15/G16 polar coordinates are not supported"),
    _c(16): GCode(None, "G15/G16 polar coordinates are not supported"),
    _c(12): GCode(None, "G12/G13 circle cycles are not supported"),
    _c(13): GCode(None, "G12/G13 circle cycles are not supported"),
    _c(33): GCode(None, "G33 threading is not supported"),
    _c(50.1): GCode(None, "G50.1/G51.1 mirroring is not supported"),
    _c(51.1): GCode(None, "G50.1/G51.1 mirroring is not supported"),
    _c(51): GCode(None, "G51 scaling is not supported"),
}
for _code in (73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89):
    COMMON[_c(_code)] = GCode(None, f"canned cycle G{_code} is not supported")
for _probe in (38.2, 38.3, 38.4, 38.5):
    COMMON[_c(_probe)] = GCode(None, f"probing G{_probe} is not supported")

FANUC: dict[int, GCode] = {
    **COMMON,
    _c(80): GCode(Group.PASS),  # cancel canned cycle (its own modal group on Fanuc)
    _c(5): GCode(
        Group.PASS,
        "G05 high-speed machining mode: the controller's look-ahead differs from the machine model",
    ),
    _c(5.1): GCode(
        Group.PASS,
        "G05.1 AI contour control: the controller's look-ahead differs from the machine model",
    ),
    _c(8): GCode(
        Group.PASS,
        "G08 look-ahead control: the controller's look-ahead differs from the machine model",
    ),
    _c(50): GCode(Group.PASS),  # cancel scaling
    _c(54.1): GCode(Group.WORK_OFFSET),
    _c(61.1): GCode(Group.PATH_MODE),
    _c(70): GCode(Group.UNITS),  # older Fanuc systems: G70 inch / G71 metric
    _c(71): GCode(Group.UNITS),
    _c(60): GCode(None, "G60 single-direction positioning is not supported"),
    _c(47): GCode(None, "G47 text engraving (Haas) is not supported"),
}

SIEMENS: dict[int, GCode] = {
    **COMMON,
    _c(80): GCode(Group.PASS),  # cancel canned cycle
    _c(60): GCode(Group.PATH_MODE),  # exact stop, modal
    _c(641): GCode(Group.PATH_MODE),  # continuous path with smoothing (ADIS)
    _c(642): GCode(Group.PATH_MODE),
    _c(643): GCode(Group.PATH_MODE),
    _c(644): GCode(Group.PATH_MODE),
    _c(645): GCode(Group.PATH_MODE),
    _c(601): GCode(Group.PASS),  # exact-stop windows
    _c(602): GCode(Group.PASS),
    _c(603): GCode(Group.PASS),
    _c(70): GCode(Group.UNITS),
    _c(71): GCode(Group.UNITS),
    _c(700): GCode(Group.UNITS),
    _c(710): GCode(Group.UNITS),
    _c(500): GCode(Group.WORK_OFFSET),
    _c(153): GCode(Group.MACHINE_COORDS),
    _c(40): GCode(Group.PASS),
    _c(450): GCode(Group.PASS),  # corner behaviour of cutter compensation
    _c(451): GCode(Group.PASS),
    _c(5): GCode(None, "Siemens G5 oblique plunge is not supported"),
    _c(25): GCode(Group.PASS),  # working-area limitation
    _c(26): GCode(Group.PASS),
}
for _code in range(505, 600):
    SIEMENS[_c(_code)] = GCode(Group.WORK_OFFSET)

LINUXCNC: dict[int, GCode] = {
    **COMMON,
    _c(80): GCode(Group.MOTION),  # modal group 1 in LinuxCNC: no motion mode afterwards
    _c(61.1): GCode(Group.PATH_MODE),
    _c(59.1): GCode(Group.WORK_OFFSET),
    _c(59.2): GCode(Group.WORK_OFFSET),
    _c(59.3): GCode(Group.WORK_OFFSET),
    _c(43.1): GCode(Group.PASS),
    _c(43.2): GCode(Group.PASS),
    _c(28.1): GCode(None, "G28.1 (store home position) is not supported"),
    _c(30.1): GCode(None, "G30.1 (store home position) is not supported"),
    _c(5): GCode(None, "cubic spline G5 is not supported"),
    _c(5.1): GCode(None, "quadratic spline G5.1 is not supported"),
    _c(5.2): GCode(None, "NURBS G5.2 is not supported"),
    _c(5.3): GCode(Group.PASS),
    _c(7): GCode(None, "lathe diameter mode G7 is not supported"),
    _c(8): GCode(Group.PASS),  # lathe radius mode (the default)
    _c(70): GCode(None, "G70 is a lathe cycle in LinuxCNC and is not supported"),
    _c(71): GCode(None, "G71 is a lathe cycle in LinuxCNC and is not supported"),
    _c(72): GCode(None, "G72 is a lathe cycle in LinuxCNC and is not supported"),
    _c(76): GCode(None, "G76 threading cycle is not supported"),
}

TABLES = {"fanuc": FANUC, "siemens": SIEMENS, "linuxcnc": LINUXCNC}

# Codes of each group ncperf distinguishes (by round(10 * number)).
MOTION_RAPID, MOTION_LINE, MOTION_CW, MOTION_CCW, MOTION_NONE = 0, 10, 20, 30, 800
PLANE_NORMAL = {170: (0.0, 0.0, 1.0), 180: (0.0, 1.0, 0.0), 190: (1.0, 0.0, 0.0)}
EXACT_STOP_CODES = (610, 611, 600)
#: LinuxCNC's G61 is *exact path*, not exact stop (its G61.1): no blending, so the machine
#: stops at a corner, but it runs on through joints that are tangent -- measured in LinuxCNC
#: 2.9's planner (full speed through collinear G1 joints under G61, 0 under G61.1). Read as a
#: continuous path of tolerance 0: model 1 then stops at every corner and nowhere else.
EXACT_PATH = 610


def exact_stop_codes(dialect: str) -> tuple[int, ...]:
    """The path-mode codes that stop at every block end in ``dialect``."""
    return (611,) if dialect == "linuxcnc" else EXACT_STOP_CODES


#: units code -> (geometry in inch, feed in inch/min). Siemens G70/G71 change the
#: geometry only; feeds stay in the basic system (assumed metric), G700/G710 change both.
UNITS = {
    200: (True, True),
    210: (False, False),
    700: (True, False),
    710: (False, False),
    7000: (True, True),
    7100: (False, False),
}

# M-codes (integer numbers).
M_STOP = {0, 1}  # program stop, optional stop: the machine comes to rest
M_END = {2, 30}


def path_mode_note(dialect: str, default_path_mode: str | None) -> str | None:
    """What a program that sets no path mode (G61/G64/G60/G641...) runs in, when it
    matters: the machine's default exact stop, or a Siemens program on a machine file
    that does not say."""
    if default_path_mode == "exact_stop":
        return (
            "no path mode in the program (G64...): exact stop at every block end, the "
            "machine's default (default_path_mode in the machine file)"
        )
    if dialect == "siemens" and default_path_mode is None:
        return (
            "no G64/G641..G645: continuous path assumed (an 840D powers on in exact stop "
            "G60; default_path_mode in the machine file says which)"
        )
    return None


M_TOOL_CHANGE = 6
M_ERRORS = {
    98: "subprogram call M98 is not supported",
    99: "M99 (subprogram return / loop) is not supported",
    198: "subprogram call M198 is not supported",
}

# Siemens keywords that do not change the path.
PASS_KEYWORDS = {
    "SOFT": "",
    "BRISK": "",
    "SOFTA": "",
    "BRISKA": "",
    "DRIVE": "",
    "DRIVEA": "",
    "FFWON": "",
    "FFWOF": "",
    "CFC": "",
    "CFTCP": "",
    "CFIN": "",
    "CUT2D": "",
    "CUT2DF": "",
    "CUT3DC": "",
    "TRAFOOF": "",
    "UPATH": "",
    "SPATH": "",
    "FNORM": "",
    "STOPRE": "",
    "DIAMOF": "",
    "MSG": "",
    "WAITM": "",
    "COMPON": "the controller's compressor may merge short blocks into splines; "
    "ncperf predicts without compression",
    "COMPCURV": "the controller's compressor may merge short blocks into splines; "
    "ncperf predicts without compression",
    "COMPCAD": "the controller's compressor may merge short blocks into splines; "
    "ncperf predicts without compression",
    "COMPSURF": "the controller's compressor may merge short blocks into splines; "
    "ncperf predicts without compression",
    "COMPOF": "",
    "FLIN": "feed profile FLIN/FCUB changes the feed inside blocks; not modelled",
    "FCUB": "feed profile FLIN/FCUB changes the feed inside blocks; not modelled",
    "TRAORI": "5-axis transformation TRAORI: the 3-axis models read X, Y, Z only",
}
# Keyword families that change the path in ways ncperf cannot follow.
ERROR_KEYWORDS = {
    "CIP": "Siemens circle through intermediate point CIP is not supported",
    "CT": "Siemens tangential circle CT is not supported",
    "ASPLINE": "Siemens spline interpolation is not supported",
    "BSPLINE": "Siemens spline interpolation is not supported",
    "CSPLINE": "Siemens spline interpolation is not supported",
    "POLY": "Siemens polynomial interpolation POLY is not supported",
    "TRANS": "Siemens frame TRANS is not supported",
    "ATRANS": "Siemens frame ATRANS is not supported",
    "ROT": "Siemens frame ROT is not supported",
    "AROT": "Siemens frame AROT is not supported",
    "SCALE": "Siemens frame SCALE is not supported",
    "ASCALE": "Siemens frame ASCALE is not supported",
    "MIRROR": "Siemens frame MIRROR is not supported",
    "AMIRROR": "Siemens frame AMIRROR is not supported",
    "G41": "cutter compensation is not supported",
}
CONTROL_FLOW = (
    "IF",
    "ELSE",
    "ENDIF",
    "WHILE",
    "ENDWHILE",
    "DO",
    "REPEAT",
    "UNTIL",
    "LOOP",
    "ENDLOOP",
    "FOR",
    "ENDFOR",
    "GOTO",
    "GOTOF",
    "GOTOB",
    "GOTOC",
    "CALL",
    "PCALL",
    "MCALL",
    "DEF",
    "PROC",
    "RET",
    "SUB",
    "ENDSUB",
    "RETURN",
    "CASE",
    "BREAK",
    "CONTINUE",
)
#: Siemens assignments that do not change the path (smoothing distances, tolerances).
#: Siemens settings that ncperf reads: CTOL, the contour tolerance of G642/G645 smoothing
#: and compressors, is the path tolerance of the blocks that follow (like LinuxCNC G64 P).
SETTINGS = {"CTOL"}
PASS_ASSIGNMENTS = {"ADIS": "", "ADISPOS": "", "CTOL": "", "OTOL": "", "ATOL": "", "SD": ""}


# ----------------------------------------------------------------------------- full interpreter
def _full(table: dict[int, GCode], dialect: str) -> dict[int, GCode]:
    """The codes the full interpreter (adapters.gcode.run) runs: the table, with the codes
    it executes made valid (their group is only a marker there)."""
    out = dict(table)
    ok = GCode(Group.PASS)
    for code in (100, 410, 420, 411, 421, 520, 680, 690, 920, 921, 922, 923, 120, 130, 800):
        out[code] = ok
    if dialect != "siemens":
        for code in (730, 810, 820, 830, 840, 850, 860, 870, 880, 890):
            out[code] = ok
        out[740] = ok
        out[510] = ok
        out[501] = ok
        out[511] = ok
        out[500] = ok
        if dialect == "fanuc":
            out[760] = ok
    for code in (382, 383, 384, 385):
        out[code] = ok
    if dialect == "fanuc":
        out[930] = ok
    out[280] = ok
    out[300] = ok
    out[530] = ok
    out[310] = ok  # Mach3/Fanuc skip (probe) G31
    if dialect == "linuxcnc":
        out[330] = ok  # spindle-synchronised motion
        out[331] = ok  # rigid tapping
        out[930] = ok  # inverse-time feed
        out[52] = GCode(None, "NURBS G5.2 is not supported")
        out[62] = GCode(None, "NURBS G6.2 is not supported")
        out[281] = GCode(None, "G28.1 (store home position) is not supported")
        out[301] = GCode(None, "G30.1 (store home position) is not supported")
    return out


FULL_TABLES = {d: _full(t, d) for d, t in TABLES.items()}
