"""The full G-code interpreter: parameters, expressions, control flow and subprograms of
LinuxCNC (rs274ngc), Fanuc Custom Macro B and Siemens 840D, run on small programs.

Every expected value is worked by hand from the controller's documentation (the comment
beside it shows how):

* LinuxCNC: docs/src/gcode/overview.adoc (parameters, expressions, operators, functions)
  and docs/src/gcode/o-code.adoc (O-words); the LinuxCNC programs were also run through
  LinuxCNC 2.9's own interpreter (benchmarks/lcnc_oracle.py), which gives the same moves
  (where a test says otherwise, it says why);
* Fanuc: Custom Macro B chapter of the Fanuc operator's manuals (variables, vacant #0,
  arithmetic, IF/WHILE/GOTO, M98/M99, G65 argument specification I);
* Siemens: SINUMERIK 840D sl programming manuals (job planning: R parameters, DEF, program
  jumps and loops, subprograms, PROC, priority of the operators).
"""

from __future__ import annotations

import numpy as np
import pytest

from adapters.gcode import read_gcode
from adapters.gcode import run as gcode_run
from adapters.gcode.control import MachineSetup
from core import InputError


def read(text: str, name: str = "t.ngc", **kw):
    return read_gcode(text.encode(), name, **kw)


def ends(tp) -> np.ndarray:
    return np.asarray(tp.end, dtype=float)


def assert_path(tp, lines, points):
    """The moves' source lines (1-based) and end points, in order."""
    assert tp.line.tolist() == list(lines)
    np.testing.assert_allclose(ends(tp), np.array(points, dtype=float), atol=1e-9)


def refusal(text: str, name: str = "t.ngc", **kw) -> InputError:
    with pytest.raises(InputError) as info:
        read(text, name, **kw)
    return info.value


# =============================================================================== LinuxCNC
# One move "G1 X<expression> Y1" from the origin: the move ends at X = the expression's
# value (Y1 keeps the move from being of zero length when the value is 0).
LINUXCNC_EXPRESSIONS = [
    # precedence: ** above * / MOD above + - above comparisons above AND OR XOR
    ("[2+3*4]", 14.0),  # 2 + 12
    ("[2*3**2]", 18.0),  # 2 * 9
    ("[10-4-3]", 3.0),  # same group, left first: [10-4]-3
    ("[2.0/3*1.5-5.5/11.0]", 0.5),  # the docs' example: [[2/3]*1.5] - [5.5/11] = 1 - 0.5
    ("[12/4/3]", 1.0),  # [12/4]/3
    ("[2**3**2]", 64.0),  # same group, left first: [2**3]**2 = 8**2
    ("[-2**2]", 4.0),  # a sign belongs to its number: [-2]**2 (LinuxCNC gives 4)
    ("[7 MOD 3 + 1]", 2.0),  # [7 MOD 3] + 1 = 1 + 1
    ("[-7 MOD 3]", 2.0),  # MOD "always calculates a positive answer": fmod = -1, + 3
    ("[7 MOD -3]", 1.0),  # fmod(7, -3) = 1, already positive: kept (interp_execute.cc)
    ("[1+1 EQ 2]", 1.0),  # [1+1] EQ 2
    ("[1 OR 0 AND 0]", 0.0),  # one group, left first: [1 OR 0] AND 0 = 1 AND 0
    ("[0 AND 1 OR 1]", 1.0),  # [0 AND 1] OR 1 = 0 OR 1
    ("[1 XOR 1]", 0.0),
    ("[1 XOR 0]", 1.0),
    ("[2 AND 3]", 1.0),  # any non-zero is true
    ("[0 OR 0]", 0.0),
    ("[3 GT 2]", 1.0),
    ("[2 GT 2]", 0.0),
    ("[2 GE 2]", 1.0),
    ("[2 LT 2]", 0.0),
    ("[1 LT 2]", 1.0),
    ("[2 LE 2]", 1.0),
    ("[3 LE 2]", 0.0),
    ("[2 EQ 2]", 1.0),
    ("[2 NE 2]", 0.0),
    ("[2 NE 3]", 1.0),
    # "values equal if their absolute difference is less than 1e-6" (overview.adoc,
    # "Equality and floating-point values"; TOLERANCE_EQUAL)
    ("[1 EQ 1.0000001]", 1.0),  # |difference| = 1e-7 < 1e-6: equal
    ("[1 NE 1.0000001]", 0.0),
    # functions (angles in degrees)
    ("[SIN[30]]", 0.5),
    ("[COS[60]]", 0.5),
    ("[TAN[45]]", 1.0),
    ("[ASIN[0.5]]", 30.0),
    ("[ACOS[0.5]]", 60.0),
    ("[ATAN[1]/[1]]", 45.0),
    ("[ATAN[1]/[-1]]", 135.0),  # four quadrants: (x, y) = (-1, 1)
    ("[ATAN[-1]/[-1]]", -135.0),  # (x, y) = (-1, -1): atan2 gives -135
    ("[ABS[-3]]", 3.0),
    ("[EXP[0]]", 1.0),
    ("[LN[EXP[2]]]", 2.0),
    ("[SQRT[16]]", 4.0),
    ("[sqrt[9]+abs[-1]]", 4.0),  # case does not count: 3 + 1
    ("[ROUND[2.5]]", 3.0),  # to the nearest, halves away from zero
    ("[ROUND[-2.5]]", -3.0),
    ("[FIX[2.8]]", 2.0),  # "FIX[2.8] = 2 and FIX[-2.8] = -3" (overview.adoc)
    ("[FIX[-2.8]]", -3.0),
    ("[FUP[2.8]]", 3.0),  # "FUP[2.8] = 3 and FUP[-2.8] = -2"
    ("[FUP[-2.8]]", -2.0),
    ("[EXISTS[#<_nope>]]", 0.0),  # never assigned
]


@pytest.mark.parametrize(
    "expr,value", LINUXCNC_EXPRESSIONS, ids=[e for e, _ in LINUXCNC_EXPRESSIONS]
)
def test_linuxcnc_expression(expr, value):
    tp = read(f"G21\nG90 F600\nG1 X{expr} Y1\nM2\n")
    assert_path(tp, [3], [(value, 1.0, 0.0)])


def test_linuxcnc_parameters_numbered_indirect_and_exists():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#1=5\n"
        "G1 X[#1*2] Y1\n"  # 4: X10
        "#2=3\n"
        "#3=7\n"
        "G1 X##2 Y2\n"  # 7: ##2 = #[#2] = #3 = 7
        "G1 X[#2+2] Y3\n"  # 8: '#' binds first: #2 + 2 = 5 (not #4)
        "#<_here> = 3\n"
        "G1 X[EXISTS[#<_here>]] Y4\n"  # 10: 1
        "#<Mixed Case> = 6\n"
        "G1 X#<mixedcase> Y5\n"  # 12: names lose case and spaces: 6
        "M2\n"
    )
    assert_path(
        tp,
        [4, 7, 8, 10, 12],
        [(10, 1, 0), (7, 2, 0), (5, 3, 0), (1, 4, 0), (6, 5, 0)],
    )


def test_linuxcnc_all_values_are_read_before_any_is_set():
    """overview.adoc: "A parameter setting does not take effect until after all parameter
    values on the same line have been found ... '#3=6 G1 X#3' ... X equals 15"."""
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#3=15\n"
        "#3=6 G1 X#3 Y1\n"  # 4: X15 (the docs' example); #3 is 6 after the line
        "G1 X#3 Y2\n"  # 5: X6
        "#1=1 #2=2\n"
        "#1=[#2] #2=[#1]\n"  # both read first: a swap, #1 = 2, #2 = 1
        "G1 X#1 Y#2\n"  # 8: (2, 1)
        "#4=15 #4=6\n"  # the last setting takes effect
        "G1 X#4 Y3\n"  # 10: X6
        "M2\n"
    )
    assert_path(tp, [4, 5, 8, 10], [(15, 1, 0), (6, 2, 0), (2, 1, 0), (6, 3, 0)])


def test_linuxcnc_named_locals_belong_to_their_subroutine_globals_do_not():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#<a> = 1\n"
        "#<_g> = 1\n"
        "o<s> sub\n"
        "  G1 X[EXISTS[#<a>]+1] Y1\n"  # 6: the caller's local is not visible: 0 + 1
        "  #<a> = 7\n"  # a local of the subroutine
        "  #<_g> = [#<_g> + 10]\n"  # the global, shared
        "  G1 X#<a> Y#<_g>\n"  # 9: (7, 11), then (7, 21)
        "o<s> endsub\n"
        "o<s> call\n"
        "G1 X#<a> Y#<_g>\n"  # 12: the main program's a is still 1; g = 11
        "o<s> call\n"  # the sub's a of the first call has vanished: line 6 gives 1 again
        "G1 X#<a> Y#<_g>\n"  # 14: (1, 21)
        "M2\n"
    )
    assert_path(
        tp,
        [6, 9, 12, 6, 9, 14],
        [(1, 1, 0), (7, 11, 0), (1, 11, 0), (1, 1, 0), (7, 21, 0), (1, 21, 0)],
    )


def test_linuxcnc_local_of_a_subroutine_is_gone_after_it_returns():
    err = refusal(
        "G21\nG90 F600\no<s> sub\n  #<inner> = 5\no<s> endsub\no<s> call\nG1 X#<Inner> Y3\nM2\n"
    )
    assert err.line == 7
    assert "#<inner>" in err.message
    assert str(err).endswith(": G1 X#<Inner> Y3")


def test_linuxcnc_call_arguments_are_local_numbered_1_to_30():
    """#1..#30 hold the arguments (unused ones read 0) and are restored on return; #31 and
    above are global (o-code.adoc, O- Call; overview.adoc, uninitialized parameters)."""
    thirty = " ".join(f"[{k}]" for k in range(1, 30)) + " [7]"
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#1 = 5\n"
        "#31 = 0\n"
        "o<s> sub\n"
        "  G1 X#1 Y#2 Z#30\n"  # 6: (3, 4, 0) then (1, 2, 7)
        "  #1 = 100\n"
        "  #31 = [#31 + 1]\n"
        "o<s> endsub\n"
        "o<s> call [3] [4]\n"
        "G1 X#1 Y#31 Z1\n"  # 11: #1 restored to 5, #31 = 1
        f"o<s> call {thirty}\n"
        "G1 X#1 Y#31 Z2\n"  # 13: (5, 2, 2)
        "M2\n"
    )
    assert_path(tp, [6, 11, 6, 13], [(3, 4, 0), (5, 1, 1), (1, 2, 7), (5, 2, 2)])


def test_linuxcnc_if_elseif_else():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "o100 sub\n"
        "  o110 if [#1 GT 5]\n"
        "    G1 X1 Y#2\n"  # 5
        "  o110 elseif [#1 LT 2]\n"
        "    G1 X2 Y#2\n"  # 7
        "  o110 else\n"
        "    G1 X3 Y#2\n"  # 9
        "  o110 endif\n"
        "o100 endsub\n"
        "o100 call [7] [1]\n"  # 7 > 5: if
        "o100 call [1] [2]\n"  # 1 < 2: elseif
        "o100 call [3] [3]\n"  # neither: else
        "o100 call [5] [4]\n"  # 5 is not > 5: else
        "M2\n"
    )
    assert_path(tp, [5, 7, 9, 9], [(1, 1, 0), (2, 2, 0), (3, 3, 0), (3, 4, 0)])


def test_linuxcnc_while_do_while_and_repeat():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "o120 while [#1 GT 0]\n"  # #1 is 0: the body never runs
        "  G1 X99 Y99\n"
        "o120 endwhile\n"
        "#1 = 0\n"
        "o130 do\n"
        "  #1 = [#1 + 1]\n"
        "  G1 X#1 Y12\n"  # 9: X1, X2, X3 (tested after the body)
        "o130 while [#1 LT 3]\n"
        "o140 do\n"
        "  G1 X0 Y13\n"  # 12: once, though the condition is false
        "o140 while [0]\n"
        "G91\n"
        "o150 repeat [3]\n"
        "  G1 X5\n"  # 16: three times, 5 mm each
        "o150 endrepeat\n"
        "o160 repeat [0]\n"
        "  G1 Y5\n"  # never
        "o160 endrepeat\n"
        "G90\n"
        "M2\n"
    )
    assert_path(
        tp,
        [9, 9, 9, 12, 16, 16, 16],
        [(1, 12, 0), (2, 12, 0), (3, 12, 0), (0, 13, 0), (5, 13, 0), (10, 13, 0), (15, 13, 0)],
    )


def test_linuxcnc_while_counts():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#1 = 1\n"
        "o120 while [#1 LE 3]\n"
        "  G1 X[#1*10] Y10\n"  # 5: #1 = 1, 2, 3
        "  #1 = [#1 + 1]\n"
        "o120 endwhile\n"
        "G1 X0 Y0\n"  # 8
        "M2\n"
    )
    assert_path(tp, [5, 5, 5, 8], [(10, 10, 0), (20, 10, 0), (30, 10, 0), (0, 0, 0)])


def test_linuxcnc_break_and_continue():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#1 = 0\n"
        "o100 while [1]\n"
        "  #1 = [#1 + 1]\n"
        "  o101 if [#1 EQ 2]\n"
        "    o100 continue\n"  # skips the move for #1 = 2
        "  o101 endif\n"
        "  o102 if [#1 GT 3]\n"
        "    o100 break\n"  # leaves at #1 = 4
        "  o102 endif\n"
        "  G1 X#1 Y1\n"  # 12: X1, X3
        "o100 endwhile\n"
        "G1 X0 Y2\n"  # 14
        "M2\n"
    )
    assert_path(tp, [12, 12, 14], [(1, 1, 0), (3, 1, 0), (0, 2, 0)])


def test_linuxcnc_return_and_return_values():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "o<r> sub\n"
        "  o201 if [#1 GT 5]\n"
        "    o<r> return [#1 * 2]\n"  # returns at once: the move below is not made
        "  o201 endif\n"
        "  G1 X#1 Y3\n"  # 7
        "o<r> endsub [#1 + 100]\n"
        "o<r> call [9]\n"  # 9 > 5: returns 18
        "G1 X#<_value> Y4\n"  # 10: X18
        "o<r> call [4]\n"  # the move (4, 3), then endsub returns 104
        "G1 X#<_value> Y5\n"  # 12: X104
        "M2\n"
    )
    assert_path(tp, [10, 7, 12], [(18, 4, 0), (4, 3, 0), (104, 5, 0)])


def test_linuxcnc_recursion():
    tp = read(
        "G21\n"
        "G90 F600\n"
        "o<fact> sub\n"
        "  o401 if [#1 LE 1]\n"
        "    o<fact> return [1]\n"
        "  o401 endif\n"
        "  o<fact> call [#1 - 1]\n"
        "  #<v> = #<_value>\n"
        "o<fact> endsub [#1 * #<v>]\n"
        "o<fact> call [4]\n"
        "G1 X#<_value> Y7\n"  # 11: 4! = 24
        "M2\n"
    )
    assert_path(tp, [11], [(24, 7, 0)])


def test_linuxcnc_o_number_by_expression():
    """o-code.adoc, Indirection: "The o-number may be given by a parameter and/or
    calculation: o[#101+2] call"."""
    tp = read(
        "G21\n"
        "G90 F600\n"
        "#101 = 298\n"
        "o300 sub\n"
        "  G1 X7 Y6\n"  # 5
        "o300 endsub\n"
        "o[#101+2] call\n"  # o300
        "M2\n"
    )
    assert_path(tp, [5], [(7, 6, 0)])


def test_linuxcnc_subroutine_in_a_file_beside_the_program(tmp_path):
    (tmp_path / "helper.ngc").write_text(
        "o<helper> sub\n  G1 X#1 Y#2\n  G1 X[#1+1]\no<helper> endsub\nM2\n"
    )
    main = tmp_path / "main.ngc"
    # o<Helper>: names are lower-cased, the file is helper.ngc (o-code.adoc, Calling Files)
    main.write_text("G21\nG90 F600\no<Helper> call [2] [3]\nG1 X0 Y0\nM2\n")
    tp = read_gcode(main.read_bytes(), str(main))
    # lines 2, 3 of helper.ngc: (2, 3), (3, 3); then line 4 of main.ngc
    assert_path(tp, [2, 3, 4], [(2, 3, 0), (3, 3, 0), (0, 0, 0)])
    assert tp.origin is not None
    assert tp.origin.tolist()[:2] == [0, 0] and tp.origin[2] < 0
    assert tp.origins[0].startswith("main.ngc:3 ")
    assert tp.origin_files[0] == "helper.ngc"


def test_linuxcnc_subroutine_on_the_machine_files_search_path(tmp_path):
    lib = tmp_path / "lib"
    prog = tmp_path / "prog"
    lib.mkdir()
    prog.mkdir()
    (lib / "corner.ngc").write_text("o<corner> sub\n  G1 X#1 Y#1\no<corner> endsub\nM2\n")
    main = prog / "main.ngc"
    main.write_text("G21\nG90 F600\no<corner> call [4]\nG1 X0 Y0\nM2\n")
    # not beside the program: refused, naming the call
    with pytest.raises(InputError) as info:
        read_gcode(main.read_bytes(), str(main))
    assert info.value.line == 3 and "corner" in info.value.message
    tp = read_gcode(main.read_bytes(), str(main), setup=MachineSetup(search=(str(lib),)))
    assert_path(tp, [2, 4], [(4, 4, 0), (0, 0, 0)])  # line 2 of corner.ngc, line 4 of main
    assert tp.origin_files[tp.origin[0]] == "corner.ngc"


def test_linuxcnc_nested_subroutine_definition_is_refused():
    """o-code.adoc: "Subroutine definitions may not be nested ... will produce an error";
    LinuxCNC 2.9 stops at line 4: "Nested subroutine definition"."""
    err = refusal(
        "G21\n"
        "G90 F600\n"
        "o<outer> sub\n"
        "  o100 sub\n"
        "    G1 X1\n"
        "  o100 endsub\n"
        "  o100 call\n"
        "o<outer> endsub\n"
        "o<outer> call\n"
        "M2\n"
    )
    assert err.line == 4
    assert "nested" in err.message.lower()
    assert str(err).endswith(": o100 sub")


# ================================================================================= Fanuc
FANUC_EXPRESSIONS = [
    ("2 + 3 * 4", 14.0),  # * before +
    ("[2 + 3] * 4", 20.0),
    ("7 / 2", 3.5),
    ("SQRT[16]", 4.0),
    ("ABS[-3]", 3.0),
    ("SIN[30]", 0.5),  # degrees
    ("ATAN[1]/[1]", 45.0),
    ("ROUND[2.5]", 3.0),
    ("FIX[3.9]", 3.0),
    ("FUP[3.1]", 4.0),
    # "#1=1.2, #2=-1.2: FUP[#1] = 2.0, FIX[#1] = 1.0, FUP[#2] = -2.0, FIX[#2] = -1.0":
    # FIX drops the fraction, FUP rounds away from zero (Custom Macro B, arithmetic,
    # rounding up and down to an integer)
    ("FIX[-1.2]", -1.0),
    ("FUP[-1.2]", -2.0),
]


@pytest.mark.parametrize("expr,value", FANUC_EXPRESSIONS, ids=[e for e, _ in FANUC_EXPRESSIONS])
def test_fanuc_expression(expr, value):
    tp = read(f"G21 G90 G1 F600\n#1 = {expr}\nG1 X#1 Y1\nM30\n", "t.nc", dialect="fanuc")
    assert_path(tp, [3], [(value, 1.0, 0.0)])


def test_fanuc_locals_commons_and_vacant_variables():
    tp = read(
        "O0001\n"
        "G21 G90 G17\n"
        "G0 X0 Y0 Z0\n"
        "#1 = 2 + 3 * 4\n"  # 14
        "#100 = #1 / 2\n"  # 7
        "#500 = #100 - 1\n"  # 6
        "G1 X#1 Y#100 Z#500 F600\n"  # 7: (14, 7, 6)
        "G1 X0 Y#10\n"  # 8: #10 vacant: the Y word is not there: (0, 7, 6)
        "G1 X5 Y0 Z#0\n"  # 9: #0 is always vacant: (5, 0, 6)
        "#2 = #10\n"  # vacant stays vacant
        "#3 = #10 * 5\n"  # in arithmetic vacant is 0: 0
        "#4 = #10 + #10\n"  # 0
        "IF [#2 EQ #0] GOTO 20\n"  # vacant EQ #0: true
        "G1 X99\n"  # skipped
        "N20 G1 X6 Y#3\n"  # 15: #3 is 0 (not vacant): Y0 -> (6, 0, 6)
        "IF [#3 EQ #0] GOTO 30\n"  # 0 EQ vacant: false
        "G1 X7 Y#4\n"  # 17: (7, 0, 6)
        "N30 IF [#10 NE 0] THEN #5 = 1\n"  # vacant NE 0: true
        "IF [#10 GE #0] THEN #6 = 2\n"  # vacant GE #0: true
        "IF [#10 GT 0] THEN #7 = 3\n"  # vacant GT 0: false, #7 stays vacant
        "IF [#3 EQ 0] THEN #8 = 4\n"  # 0 EQ 0: true
        "G1 X#5 Y#6 Z#8\n"  # 22: (1, 2, 4)
        "G1 Y#7 X8\n"  # 23: Y omitted: (8, 2, 4)
        "M30\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_path(
        tp,
        [7, 8, 9, 15, 17, 22, 23],
        [(14, 7, 6), (0, 7, 6), (5, 0, 6), (6, 0, 6), (7, 0, 6), (1, 2, 4), (8, 2, 4)],
    )


def test_fanuc_if_goto_while_do_end():
    tp = read(
        "O0001\n"
        "G21 G90 G1 F600\n"
        "#1 = 1\n"
        "WHILE [#1 LE 3] DO1\n"
        "#2 = 1\n"
        "WHILE [#2 LE 2] DO2\n"
        "G1 X[#1*10] Y#2\n"  # 7: (10,1) (10,2) (20,1) (20,2) (30,1) (30,2)
        "#2 = #2 + 1\n"
        "END2\n"
        "#1 = #1 + 1\n"
        "END1\n"
        "#3 = 0\n"
        "N10 #3 = #3 + 1\n"
        "G1 X0 Y[#3 * 5]\n"  # 14: Y5, Y10, Y15 (the backward GOTO loops)
        "IF [#3 LT 3] GOTO 10\n"
        "#10 = 40\n"
        "GOTO #10\n"  # the block number from a variable
        "G1 X99\n"  # skipped
        "N40 G1 X1 Y1\n"  # 19
        "M30\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_path(
        tp,
        [7] * 6 + [14] * 3 + [19],
        [(10, 1, 0), (10, 2, 0), (20, 1, 0), (20, 2, 0), (30, 1, 0), (30, 2, 0)]
        + [(0, 5, 0), (0, 10, 0), (0, 15, 0), (1, 1, 0)],
    )


def test_fanuc_m98_repeats_and_m99_in_the_same_file():
    tp = read(
        "O0001\n"
        "G21 G90 G17\n"
        "G0 X0 Y0 Z0\n"
        "G1 F600\n"
        "M98 P1000 L3\n"  # 5: O1000 three times
        "G90 G1 X0 Y10\n"  # 6
        "M98 P31000\n"  # 7: P31000 = three times O1000 (count before the 4-digit number)
        "G90\n"
        "M30\n"
        "O1000\n"
        "G91 G1 X5\n"  # 11: 5 mm each time
        "M99\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_path(
        tp,
        [11, 11, 11, 6, 11, 11, 11],
        [(5, 0, 0), (10, 0, 0), (15, 0, 0), (0, 10, 0), (5, 10, 0), (10, 10, 0), (15, 10, 0)],
    )
    assert tp.origin.tolist() == [0, 0, 0, -1, 1, 1, 1]
    assert tp.origins[0].startswith("t.nc:5 ")
    assert tp.origins[1].startswith("t.nc:7 ")
    assert tp.origin_files == ("", "")  # their lines are in the main file


def test_fanuc_g65_arguments_and_local_levels():
    """G65: A -> #1, B -> #2, I -> #4, K -> #6, X -> #24 in a new level of locals (the
    caller's are back after M99); M98 keeps the caller's level (Custom Macro B)."""
    tp = read(
        "O0001\n"
        "G21 G90 G17 G1 F600\n"
        "#1 = 7\n"
        "#5 = 9\n"
        "G65 P2000 A1 B2 X10 I4 K6\n"  # 5
        "G1 X#1 Y#5 Z0\n"  # 6: the caller's #1 = 7, #5 = 9 untouched
        "G65 P2000 X3\n"  # 7: A, B, I, K absent: vacant, 0 in arithmetic
        "M98 P3000\n"  # 8: same level: sets the caller's #1 and #5
        "G1 X#1 Y#5 Z0\n"  # 9: (8, 10, 0)
        "M30\n"
        "O2000\n"
        "G1 X#24 Y[#1+#2] Z[#4+#6]\n"  # 12: (10, 3, 10); then (3, 0, 0)
        "#5 = 100\n"
        "M99\n"
        "O3000\n"
        "#1 = 8\n"
        "#5 = 10\n"
        "M99\n",
        "t.nc",
        dialect="fanuc",
    )
    assert_path(tp, [12, 6, 12, 9], [(10, 3, 10), (7, 9, 0), (3, 0, 0), (8, 10, 0)])


@pytest.mark.parametrize("file_name", ["O1000", "O1000.nc"])
def test_fanuc_subprogram_in_a_file_beside_the_program(tmp_path, file_name):
    (tmp_path / file_name).write_text("%\nO1000 (SUB)\nG91 G1 X5\nM99\n%\n")
    main = tmp_path / "main.nc"
    main.write_text("O0001\nG21 G90 G1 F600\nM98 P21000\nG90 G1 X0 Y1\nM30\n")
    tp = read_gcode(main.read_bytes(), str(main), dialect="fanuc")
    # twice line 3 of the subprogram's file, 5 mm each; then line 4 of main.nc
    assert_path(tp, [3, 3, 4], [(5, 0, 0), (10, 0, 0), (0, 1, 0)])
    assert tp.origin.tolist() == [0, 0, -1]
    assert tp.origins[0].startswith("main.nc:3 ")
    assert tp.origin_files == (file_name,)


def test_fanuc_vacant_0_cannot_be_assigned():
    err = refusal("G21 G90 G1 F600\nG1 X1\n#0 = 1\nM30\n", "t.nc", dialect="fanuc")
    assert err.line == 3
    assert "#0" in err.message and str(err).endswith(": #0 = 1")


# =============================================================================== Siemens
SIEMENS_EXPRESSIONS = [
    ("2+3*4", 14.0),
    ("(2+3)*4", 20.0),
    ("(7 DIV 2)", 3.0),  # integer division
    ("(7 MOD 3)", 1.0),
    ("SIN(30)", 0.5),
    ("SQRT(16)", 4.0),
    ("POT(3)", 9.0),  # square
    ("TRUNC(2.7)", 2.0),
    ("ABS(-3)", 3.0),
    ("ATAN2(1,-1)", 135.0),  # ATAN2(ordinate, abscissa)
    ("1+1==2", 1.0),  # TRUE
    # comparisons have the lowest priority, below AND (840D "Priority of the operations":
    # 7. AND ... 11. == <> > < >= <=): 2 > (1 AND 0) = 2 > 0 = TRUE
    ("(2>1 AND 0)", 1.0),
]


@pytest.mark.parametrize("expr,value", SIEMENS_EXPRESSIONS, ids=[e for e, _ in SIEMENS_EXPRESSIONS])
def test_siemens_expression(expr, value):
    tp = read(f"G71 G90 G1 F600\nR1={expr}\nG1 X=R1 Y1\nM30\n", "t.mpf")
    assert_path(tp, [3], [(value, 1.0, 0.0)])


def test_siemens_r_parameters_def_gotof_gotob_if_else():
    tp = read(
        "DEF REAL TIEFE=2.5\n"
        "G71 G90 G17\n"
        "R1=5\n"
        "G1 X=R1*2 Y=TIEFE F600\n"  # 4: (10, 2.5)
        "R2=0\n"
        "IF R1>2 GOTOF MARKE1\n"  # 5 > 2: forward
        "G1 X99\n"
        "MARKE1:\n"
        "G1 X1 Y1\n"  # 9
        "ANF: R2=R2+1\n"
        "G1 X=R2*10 Y2\n"  # 11: X10, X20, X30
        "IF R2<3 GOTOB ANF\n"
        "IF R1==5\n"
        "G1 X3 Y3\n"  # 14
        "ELSE\n"
        "G1 X98 Y3\n"
        "ENDIF\n"
        "IF R1<>5\n"
        "G1 X97\n"
        "ELSE\n"
        "G1 X4 Y4\n"  # 21
        "ENDIF\n"
        "M30\n",
        "t.mpf",
    )
    assert_path(
        tp,
        [4, 9, 11, 11, 11, 14, 21],
        [(10, 2.5, 0), (1, 1, 0), (10, 2, 0), (20, 2, 0), (30, 2, 0), (3, 3, 0), (4, 4, 0)],
    )


def test_siemens_loops():
    tp = read(
        "DEF INT ZAEHL\n"
        "G71 G90 G1 F600\n"
        "ZAEHL=0\n"
        "LOOP\n"
        "ZAEHL=ZAEHL+1\n"
        "G1 X=ZAEHL Y5\n"  # 6: X1, X2
        "IF ZAEHL>=2 GOTOF RAUS\n"
        "ENDLOOP\n"
        "RAUS:\n"
        "R3=0\n"
        "WHILE R3<2\n"
        "R3=R3+1\n"
        "G1 X=R3 Y6\n"  # 13: X1, X2
        "ENDWHILE\n"
        "FOR R4=1 TO 3\n"
        "G1 X=R4*10 Y7\n"  # 16: X10, X20, X30
        "ENDFOR\n"
        "R5=10\n"
        "REPEAT\n"
        "G1 X=R5 Y8\n"  # 20: X10, X20 (R5 = 30 > 20 ends it)
        "R5=R5+10\n"
        "UNTIL R5>20\n"
        "REPEAT\n"
        "G1 X0 Y9\n"  # 24: once: the condition is tested after the body
        "UNTIL TRUE\n"
        "G1 X=IC(5)\n"  # 26: incremental in G90: X5
        "G1 X=IC(5) Y=IC(-1)\n"  # 27: (10, 8)
        "M30\n",
        "t.mpf",
    )
    assert_path(
        tp,
        [6, 6, 13, 13, 16, 16, 16, 20, 20, 24, 26, 27],
        [(1, 5, 0), (2, 5, 0), (1, 6, 0), (2, 6, 0), (10, 7, 0), (20, 7, 0), (30, 7, 0)]
        + [(10, 8, 0), (20, 8, 0), (0, 9, 0), (5, 9, 0), (10, 8, 0)],
    )


def test_siemens_subprograms_in_spf_files(tmp_path):
    (tmp_path / "L123.SPF").write_text("G91 G1 X5\nM17\nG1 X999\n")  # after M17: not run
    (tmp_path / "BOHREN.SPF").write_text("PROC BOHREN\nG91 G1 Y2\nRET\n")
    (tmp_path / "KONTUR.SPF").write_text(
        "PROC KONTUR(REAL A, REAL B)\nG90 G1 X=A Y=B\nG1 X=A+B\nM17\n"
    )
    main = tmp_path / "MAIN.MPF"
    main.write_text(
        "EXTERN KONTUR(REAL, REAL)\n"
        "G71 G90 G17 G1 F600\n"
        "G0 X0 Y0 Z0\n"
        "L123 P2\n"  # 4: twice 5 mm in X
        "BOHREN P3\n"  # 5: three times 2 mm in Y
        "G90\n"
        "KONTUR(10, 5)\n"  # 7: A = 10, B = 5: (10, 5) then X15
        "G1 X0 Y0\n"  # 8
        "M30\n"
    )
    tp = read_gcode(main.read_bytes(), str(main))
    assert_path(
        tp,
        [1, 1, 2, 2, 2, 2, 3, 8],
        [(5, 0, 0), (10, 0, 0), (10, 2, 0), (10, 4, 0), (10, 6, 0), (10, 5, 0), (15, 5, 0)]
        + [(0, 0, 0)],
    )
    assert tp.origin.tolist() == [0, 0, 1, 1, 1, 2, 2, -1]
    assert [tp.origins[k].split(" ")[0] for k in range(3)] == [
        "MAIN.MPF:4",
        "MAIN.MPF:5",
        "MAIN.MPF:7",
    ]
    assert tp.origin_files == ("L123.SPF", "BOHREN.SPF", "KONTUR.SPF")


def test_siemens_named_tools_start_operations():
    """T="name" selects a tool by its name (tool management); another name is another
    tool, whatever the length of its name."""
    tp = read(
        "G71 G90 G1 F600\n"
        'T="FRAESER_20"\n'
        "G1 X10 Y0\n"  # 3: first operation
        "G1 X10 Y10\n"  # 4
        'T="FRAESER_10"\n'
        "G1 X0 Y10\n"  # 6: second operation (another tool)
        'T="MILL"\n'
        "G1 X0 Y0\n"  # 8: third operation
        "M30\n",
        "t.mpf",
    )
    assert tp.line.tolist() == [3, 4, 6, 8]
    assert tp.op_offsets.tolist() == [0, 2, 3, 4]


# ========================================================================== faithfulness
def test_moves_in_calls_keep_their_lines_files_and_callers(tmp_path):
    """A subroutine of 40 plain lines (long enough for the vectorised runs) called twice,
    and a call inside a call, each in a file of its own."""
    zig = "o<zig> sub\n" + "".join(f"G1 X{k} Y{k % 2}\n" for k in range(1, 41))
    (tmp_path / "zig.ngc").write_text(zig + "o<zig> endsub\nM2\n")
    (tmp_path / "outer.ngc").write_text(
        "o<outer> sub\n  G1 X-1 Y-1\n  o<inner> call [4]\no<outer> endsub\nM2\n"
    )
    (tmp_path / "inner.ngc").write_text(
        "o<inner> sub\n  G1 X#1 Y-2\n  G1 X[#1+1]\no<inner> endsub\nM2\n"
    )
    main = tmp_path / "main.ngc"
    main.write_text("G21\nG90 F600\no<zig> call\nG1 X0 Y0\no<zig> call\no<outer> call\nM2\n")
    tp = read_gcode(main.read_bytes(), str(main))
    body_lines = list(range(2, 42))  # "G1 X<k> Y<k % 2>" is on line k + 1 of zig.ngc
    body = [(k, k % 2, 0) for k in range(1, 41)]
    assert_path(
        tp,
        body_lines + [4] + body_lines + [2, 2, 3],
        body + [(0, 0, 0)] + body + [(-1, -1, 0), (4, -2, 0), (5, -2, 0)],
    )
    origin = tp.origin.tolist()
    first, second, outer, inner = origin[0], origin[41], origin[81], origin[82]
    assert origin == [first] * 40 + [-1] + [second] * 40 + [outer, inner, inner]
    assert len({first, second, outer, inner}) == 4
    assert tp.origins[first].startswith("main.ngc:3 ")
    assert tp.origins[second].startswith("main.ngc:5 ")
    assert tp.origins[outer].startswith("main.ngc:6 ")
    assert tp.origins[inner].startswith("main.ngc:6 ") and "outer.ngc:3" in tp.origins[inner]
    assert tp.origin_files[first] == tp.origin_files[second] == "zig.ngc"
    assert tp.origin_files[outer] == "outer.ngc"
    assert tp.origin_files[inner] == "inner.ngc"


def test_an_error_inside_a_called_file_names_that_file_and_line(tmp_path):
    (tmp_path / "bad.ngc").write_text("o<bad> sub\n  G1 X1\n  G1 X[1/#1]\no<bad> endsub\nM2\n")
    main = tmp_path / "main.ngc"
    main.write_text("G21\nG90 F600\no<bad> call [0]\nM2\n")
    with pytest.raises(InputError) as info:
        read_gcode(main.read_bytes(), str(main))
    err = info.value
    assert err.source is not None and err.source.endswith("bad.ngc")
    assert err.line == 3
    assert "division by zero" in err.message
    assert str(err).endswith(": G1 X[1/#1]")


ENDLESS = {
    "linuxcnc": ("t.ngc", "G21\nG90 F600\no100 while [1]\nG1 X1\nG1 X2\no100 endwhile\nM2\n"),
    "fanuc": ("t.nc", "G21 G90 F600\nN10 G1 X1\nG1 X2\nGOTO 10\nM30\n"),
    "siemens": ("t.mpf", "G71 G90 F600\nLOOP\nG1 X1\nG1 X2\nENDLOOP\nM30\n"),
}


@pytest.mark.parametrize("dialect", list(ENDLESS))
def test_endless_loop_stops_at_the_block_limit(monkeypatch, dialect):
    monkeypatch.setattr(gcode_run, "MAX_BLOCKS", 100)
    name, text = ENDLESS[dialect]
    err = refusal(text, name, dialect=dialect)
    lines = text.split("\n")
    loop = {"linuxcnc": (3, 4, 5, 6), "fanuc": (2, 3, 4), "siemens": (2, 3, 4, 5)}[dialect]
    assert err.line in loop
    assert "loops without end" in err.message
    assert "\n" not in str(err)
    assert str(err).startswith(f"{name}:{err.line}: ")
    assert str(err).endswith(": " + lines[err.line - 1])


# Each refusal: (name, dialect, program, the first offending line, words of the message).
# The program's faulty construct comes twice: the first one is named, quoted as written.
REFUSALS = [
    (
        "linuxcnc undefined subroutine",
        "t.ngc",
        None,
        "G21\nG1 X1 F600\no<NoThere> call\no<NoThere> call\nM2\n",
        3,
        ["nothere"],
    ),
    (
        "linuxcnc undefined numbered subroutine",
        "t.ngc",
        None,
        "G21\nG1 X1 F600\nO200 Call\nO200 Call\nM2\n",
        3,
        ["o200"],
    ),
    (
        "linuxcnc division by zero",
        "t.ngc",
        None,
        "G21\n#1=0\nG1 X1 F600\nG1 X[2/#1]\nG1 X[3/#1]\nM2\n",
        4,
        ["division by zero"],
    ),
    (
        "linuxcnc missing endwhile",
        "t.ngc",
        None,
        "G21\nG1 X1 F600\no100 While [#1 LT 3]\n#1=[#1+1]\nG1 X#1\nM2\n",
        3,
        ["while"],
    ),
    (
        "linuxcnc return outside a subroutine",
        "t.ngc",
        None,
        "G21\nG1 X1 F600\no100 Return\nG1 X2\nM2\n",
        3,
        ["return"],
    ),
    (
        "linuxcnc undefined named parameter",
        "t.ngc",
        None,
        "G21\nG1 X1 F600\nG1 X#<Nope>\nG1 X#<Nope>\nM2\n",
        3,
        ["#<nope>"],
    ),
    (
        "fanuc goto a missing block number",
        "t.nc",
        "fanuc",
        "G21\nG1 X1 F600\nGoto 50\nGoto 50\nN40 G1 X2\nM30\n",
        3,
        ["goto", "n50"],
    ),
    (
        "fanuc while without its end",
        "t.nc",
        "fanuc",
        "G21\nG1 X1 F600\n#1=0\nWhile [#1 LT 3] Do1\n#1=#1+1\nM30\n",
        4,
        ["while", "do1"],
    ),
    (
        "fanuc undefined subprogram",
        "t.nc",
        "fanuc",
        "G21\nG1 X1 F600\nm98 p4321\nm98 p4321\nM30\n",
        3,
        ["o4321"],
    ),
    (
        "fanuc division by zero",
        "t.nc",
        "fanuc",
        "G21\nG1 X1 F600\n#2 = 5 / #1\n#3 = 5 / #1\nM30\n",
        3,
        ["division by zero"],
    ),
    (
        "siemens gotof a missing label",
        "t.mpf",
        None,
        "G71\nG1 X1 F600\nGotoF Ziel\nGotoF Ziel\nG1 X2\nM30\n",
        3,
        ["gotof", "ziel"],
    ),
    (
        "siemens gotof a label that is only behind",
        "t.mpf",
        None,
        "G71\nG1 X1 F600\nZiel: G1 X2\nR1=1\nIf R1>0 GotoF Ziel\nM30\n",
        5,
        ["gotof", "ziel"],
    ),
    (
        "siemens while without its endwhile",
        "t.mpf",
        None,
        "G71\nG1 X1 F600\nR1=0\nWhile R1<3\nR1=R1+1\nM30\n",
        4,
        ["while"],
    ),
    (
        "siemens undefined subprogram",
        "t.mpf",
        None,
        "G71\nG1 X1 F600\nUnterProg P2\nUnterProg P2\nM30\n",
        3,
        ["unterprog"],
    ),
    (
        "siemens division by zero",
        "t.mpf",
        None,
        "G71\nG1 X1 F600\nR1=0\nR2=5/R1\nR3=5/R1\nM30\n",
        4,
        ["division by zero"],
    ),
]


@pytest.mark.parametrize(
    "name,dialect,text,line,words",
    [r[1:] for r in REFUSALS],
    ids=[r[0] for r in REFUSALS],
)
def test_refusal_names_the_first_offending_line_and_the_construct(
    tmp_path, name, dialect, text, line, words
):
    path = tmp_path / name  # nothing beside it: a subprogram file cannot be found by chance
    with pytest.raises(InputError) as info:
        read_gcode(text.encode(), str(path), dialect=dialect)
    err = info.value
    assert err.line == line
    for w in words:
        assert w in err.message.lower()
    as_written = text.split("\n")[line - 1]
    assert str(err) == f"{path}:{line}: {err.message}: {as_written}"


def test_a_number_beyond_a_double_or_a_function_of_one_is_a_line_error():
    """A literal of 400 digits is inf as a double: refused where it is read, with its line
    (it reached math.sin as inf and crashed with "math domain error" -- fuzzer, Siemens
    dialect). A function whose value is undefined (FIX of inf cannot be an integer) or out
    of range (EXP[1000] = 1.97e434) is refused the same way."""
    big = "9" * 400
    err = refusal(f"G21 G90\n#1=[SIN[{big}]]\nG1 X#1 Y1 F100\n")
    assert err.line == 2 and "(400 digits) is out of range" in str(err)
    err = refusal(f"G21 G90\nX58.4865 Y=SIN(-{big})\n", "t.mpf")
    assert err.line == 2 and "out of range" in str(err)
    err = refusal("G21 G90\n#1=[EXP[1000]]\nG1 X#1 Y1 F100\n")
    assert err.line == 2 and "EXP of 1000" in str(err)
    # in range, the same functions read as before: SIN[30] = 0.5
    tp = read("G21 G90\n#1=[SIN[30]]\nG1 X#1 Y1 F100\n")
    assert_path(tp, [3], [[0.5, 1, 0]])


def test_a_g_word_beyond_a_double_is_refused_without_a_numpy_warning():
    """G followed by 400 nines (inf): the dialect guess cast it to an integer first
    ("RuntimeWarning: invalid value encountered in cast" on stderr, an error under -W error);
    now only the reader's one-line refusal."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        err = refusal("G" + "9" * 400 + " X1\n", "t.nc")
    assert err.line == 1 and "G word out of range" in str(err)


def test_linuxcnc_a_lone_o_name_or_expression_is_read_and_ignored():
    """``o<abc>`` or ``o[#1*2]`` with no keyword on its own line: LinuxCNC's interpreter reads
    the program and ignores the line (checked with lcnc_path_check.py); with a subroutine in
    the file ncperf crashed on it (int() of the name or the expression, found by the fuzzer)."""
    text = "G21\n#1=3\no<pocket> sub\nG1 X#1\no<pocket> endsub\no<abc>\no[#1*2]\nG1 X1 F100\nM2\n"
    tp = read(text)
    assert_path(tp, [8], [(1.0, 0.0, 0.0)])
