"""What the CL data reader does with each APT major word.

Four kinds of words: the ones :mod:`adapters.cl_data.interp` reads (GOTO,
CIRCLE, FEDRAT...), the ones passed over because they cannot move the tool
(:data:`PASSIVE`, one summary notice), the ones that move the tool in a way
ncperf cannot reproduce (:data:`ERRORS`, an error naming the line), and the
rest: words ncperf does not know, passed over with a notice naming each.
"""

from __future__ import annotations

#: Words whose text runs to the end of the line: a "$" or "$$" inside is text.
LITERAL = frozenset({"PARTNO", "PPRINT", "INSERT"})

#: Words that cannot move the tool, with what they are (for the summary notice).
PASSIVE: dict[str, str] = {
    "PARTNO": "part name",
    "PPRINT": "operator message",
    "PAINT": "display colour",
    "TLDATA": "tool geometry",
    "CUTTER": "tool geometry",
    "SELECT": "tool preselection",
    "SPINDL": "spindle",
    "COOLNT": "coolant",
    "MACHIN": "post-processor name",
    "CLRSRF": "clearance surface",
    "INTOL": "tolerance",
    "OUTTOL": "tolerance",
    "TOLER": "tolerance",
    "LINTOL": "tolerance",
    "DISPLY": "display",
    "OPSKIP": "block-skip switch",
    "AUXFUN": "auxiliary function",
    "PREFUN": "preparatory function",
    "SEQNO": "block numbering",
    "OPNAME": "operation name",
    "TOOLNO": "tool number for the post",
    "SET": "post-processor setting",
}

#: Words that set the post's coordinate system; the CL points are already written in it.
FRAMES = frozenset({"MSYS", "CSYS", "TRNTYP"})

#: Words that move the tool in a way ncperf cannot reproduce: word -> why.
ERRORS: dict[str, str] = {
    "NURBS": (
        "NURBS/ spline motion is not supported; output the tool path with linear "
        "(GOTO) or circular (CIRCLE) motion"
    ),
    "KNOT": "KNOT/ belongs to a NURBS/ spline, which is not supported",
    "CNTRL": "CNTRL/ belongs to a NURBS/ spline, which is not supported",
    "BSPLIN": "B-spline motion is not supported",
    "SPLINE": "spline motion is not supported",
    "CYCLE": (
        "canned cycles (CYCLE/) are not supported: the controller generates their "
        "moves, which the CL data does not contain"
    ),
    "COPY": "COPY/ repeats motion (a transformation); not supported",
    "INDEX": "INDEX/ marks motion for COPY/ (a transformation); not supported",
    "TRACUT": "TRACUT/ transforms the cutter path; not supported",
    "REFSYS": "REFSYS/ transforms the cutter path; not supported",
    "TRANS": "TRANS/ translates the cutter path; not supported",
    "ORIGIN": "ORIGIN/ moves the origin of the cutter path; not supported",
    "LOOPST": "loops (LOOPST/LOOPND) are not supported",
    "LOOPND": "loops (LOOPST/LOOPND) are not supported",
    "JUMPTO": "jumps (JUMPTO) are not supported",
    "CALL": "macro calls are not supported",
    "MACRO": "macros are not supported",
    "TERMAC": "macros are not supported",
    "IF": "conditional statements are not supported",
    "THREAD": "thread cutting (THREAD/) is not supported",
}

#: APT part-program motion: an APT processor computes the cutter path from surfaces.
PART_PROGRAM = frozenset(
    {
        "GO",
        "GOFWD",
        "GOLFT",
        "GORGT",
        "GOBACK",
        "GOUP",
        "GODOWN",
        "INDIRV",
        "INDIRP",
        "TLON",
        "TLLFT",
        "TLRGT",
        "TLOFPS",
        "TLONPS",
        "PSIS",
        "AUTOPS",
        "THICK",
        "CUT",
        "DNTCUT",
    }
)

#: Feed-rate units of FEDRAT, in mm/min per unit.
FEED_UNITS = {"MMPM": 1.0, "IPM": 25.4}
#: Feed per revolution and inverse time: the CL data does not give the spindle speed ncperf needs.
FEED_UNSUPPORTED = {
    "MMPR": "feed per revolution (MMPR)",
    "IPR": "feed per revolution (IPR)",
    "INVERS": "inverse-time feed (INVERS)",
}

#: UNITS/UNIT arguments -> mm per unit.
LENGTH_UNITS = {"MM": 1.0, "MILLIMETERS": 1.0, "METRIC": 1.0, "INCHES": 25.4, "INCH": 25.4}
