"""The negative corpus: the manual's machining messages FILMS4 nn (Table 8.6, ln 9794-9914; conditions
ln 9916-10221). A run stops at its first error; what it produced before stays (DESIGN §4)."""
from corpus import Case


def neg(name, program, line, col, code, text, cite, ops=(), **files):
    c = Case(name, program, cite, **files)
    for o in ops:
        o(c)
    c.error(line, col, code, text)
    return c


def units(line):
    return lambda c: c.units(line)


# FILMS4 11 SYNTAX ERROR (ln 9950-9956): illegal character, a G after other words (ln 2595), a missing
# closing bracket.
neg("neg_syntax_illegal_character", "; ln 9950\nG1 X10 ? F100\n", 2, 8, 11, "SYNTAX ERROR: illegal character '?'", "L9950")
neg("neg_syntax_g_after_words", "; ln 2595\nX10 G1 F100\n", 2, 5, 11,
    "SYNTAX ERROR: G functions must come before the other words of the block", "L2595")
neg("neg_syntax_bracket_missing", "; ln 9956\n(URT,45\n", 2, 1, 11, "SYNTAX ERROR: closing bracket missing", "L9956")
# FILMS4 12 DATA MISSING: a circle with neither I J nor R.
neg("neg_arc_without_centre", "; ln 2750\nG2 X10 Y10 F100\n", 2, 1, 12,
    "DATA MISSING: a circle needs I and J (or R)", "L2750")
# FILMS4 13 FORMAT ERROR: a byte parameter out of 0-255 (Table 5.8).
neg("neg_byte_parameter_overflow", "; ln 5417 E0-E9 are bytes\nE1=300\n", 2, 1, 13,
    "FORMAT ERROR: E1 is a byte (0 to 255): 300", "L5417")
# FILMS4 16 a block of 128 characters or more (ln 2326).
neg("neg_block_too_long", "; ln 2326\nG1 X10 Y10 F100" + " " * 120 + "\n", 2, 128, 16,
    "STRING TOO LONG: a block has fewer than 128 characters", "L2326")
# FILMS4 17 a G code that does not exist (ln 2593), a function that does not exist.
neg("neg_nonexistent_g", "; ln 2593\nG45 X10\n", 2, 1, 17, "NON EXISTENT FUNCTION: G45 does not exist on this control", "L2593")
neg("neg_nonexistent_function", "; ln 5437-5466\nE30=SINH(1)\n", 2, 5, 17,
    "NON EXISTENT FUNCTION: SINH is not a function", "L5437")
# FILMS4 19 PARAMETER OVERFLOW: division by zero (ln 9975).
neg("neg_division_by_zero", "; ln 9975\nE31=0\nE30=10/E31\n", 3, 7, 19, "PARAMETER OVERFLOW: division by zero", "L9975")
# FILMS4 21 more than 8 G functions (ln 9979).
neg("neg_too_many_g", "; ln 9979\nG1 G90 G94 G97 G17 G27 G71 G40 G80\n", 2, 32, 21,
    "ILLEGAL NUMBER OF OPERATORS: more than 8 G functions in the block", "L9979")
# FILMS4 23: more than 3 axes (ln 2699), more than 4 M (ln 9992).
neg("neg_four_axes", "; ln 2699\nG X10 Y10 Z10 A5\n", 2, 15, 23,
    "ILLEGAL NUMBER OF OPERANDS: more than 3 axes in a block", "L2699")
neg("neg_five_m", "; ln 2706, 9992\nS100 M3 M7 M8 M10 M11\n", 2, 19, 23,
    "ILLEGAL NUMBER OF OPERANDS: more than 4 M functions in a block", "L9992")
# FILMS4 25 BLOCK DOES NOT MATCH: G17 not alone (ln 2956), G00 with G01 (Table 5.5), a second cycle
# without G80 (ln 3331), a fixed cycle with compensation (ln 3208), the start of compensation on an arc
# (ln 3088), GTL in G91 (ln 4369).
neg("neg_g17_not_alone", "; ln 2956\nG17 X10\n", 2, 1, 25, "BLOCK DOES NOT MATCH: G17 must be alone in its block", "L2956")
neg("neg_g00_with_g01", "; Table 5.5 ln 2620\nG0 G1 X10\n", 2, 4, 25,
    "BLOCK DOES NOT MATCH: G00 and G01 in one block (Table 5.5)", "L2620")
neg("neg_cycle_without_g80", "; ln 3331\nG81 R2 Z-10 F100\nG82 R2 Z-5\n", 3, 1, 25,
    "BLOCK DOES NOT MATCH: G81 is active: close it with G80 first (ln 3331)", "L3331")
# FILMS4 13 (a judgement call): a G83 whose increment shrinks (K < 1, no J) to no more than the 1 mm of
# "R1 = R1 + I - 1" (ln 3395) can never reach Z. R2 Z-30 I5 K.5, worked by hand: peck 1 to 2 - 5 = -3,
# R1 = -2, I = 2.5; peck 2 to -4.5, R1 = -3.5, I = 1.25; peck 3 to -4.75, R1 = -3.75, I = .625 <= 1: refused
# when the hole is reached, before any cut (the positioning rapids to X10 Y10 and to R1 have run); the column
# is the block's first axis word, X10.
neg("neg_g83_increment_too_small", "; ln 3389-3402\nS1000 F80 M3\nG83 R2 Z-30 I5 K.5\nN4 X10 Y10\n", 4, 4, 13,
    "FORMAT ERROR: G83: the increment falls to 0.625 mm, not more than the 1 mm re-approach of R1 = R1 + I - 1: "
    "Z is never reached (ln 3395-3402)", "L3395",
    ops=(units(2), lambda c: c.spindle(2, "cw", 1000), lambda c: c.rapid(4, x=10, y=10),
         lambda c: c.rapid(4, z=2)))
# E(n) = ... (ln 5429-5435): a number index names an E parameter that must exist (E0-E999 configured by
# default, E_PARAMETERS): FILMS4 18 INDEX OUT OF RANGE; an E-parameter index must be byte or integer
# (E0-E19, Table 5.8 ln 5417-5418): E30 is long real, FILMS4 13 FORMAT ERROR.
neg("neg_e_number_index_out_of_range", "; ln 5435\nE(1000)=1\n", 2, 1, 18,
    "INDEX OUT OF RANGE: E1000 (E parameters are E0-E999)", "L5435")
neg("neg_e_index_parameter_real", "; ln 5435\nE30=5\nE(E30)=1\n", 3, 1, 13,
    "FORMAT ERROR: E(E30): the index parameter must be E0-E19", "L5435")
neg("neg_cycle_with_compensation", "; ln 3208\nG1 G41 X10 Y0 F100\nG81 R2 Z-10\n", 3, 1, 25,
    "BLOCK DOES NOT MATCH: fixed cycles with cutter compensation on", "L3208", ops=(units(2),))
neg("neg_compensation_starts_on_arc", "; ln 3088\nG41\nG2 X20 Y0 I10 J0 F100\n", 3, 1, 25,
    "BLOCK DOES NOT MATCH: the G41 start move must be linear (G00/G01)", "L3088", ops=(units(3),))
neg("neg_gtl_incremental", "; ln 4369\nl1=X0 Y0,a0\nG91 F100\nG21 l1\n", 4, 1, 25,
    "BLOCK DOES NOT MATCH: GTL works in G90 only (ln 4369)", "L4369")
# FILMS4 30 probing without DPT (ln 7520).
neg("neg_probe_without_dpt", "; ln 7520\nG72 Z-10 E30\n", 2, 1, 30,
    "PROBING PARAMETERS UNDEFINED: program (DPT,Qa,Qs,Vm) first", "L7520")
# FILMS4 08 no contact within Qs with ERR=0 (ln 7528): the probe move is out, then the error.
c = neg("neg_probe_no_contact", "; ln 7528, 9941\n(DPT,10,5,500)\nG72 Z-10 E30\n", 3, 1, 8,
        "MEASUREMENT MISMATCH: no contact within the safety distance Qs", "L7528")
c.units(3)
c.rapid(3, z=0)
c.ops.pop()
c.touch("z")
c.probe(3, 72, 500, "none", z=-15)
c.rapid(3, z=0)
# FILMS4 31 ERP without RPT, a fourth RPT level (ln 5930).
neg("neg_erp_without_rpt", "; ln 10029\n(ERP)\n", 2, 1, 31, "RPT NEST >3 OR ERP WITHOUT RPT: ERP without RPT", "L10029")
neg("neg_rpt_four_levels", "; ln 5930\n(RPT,2)\n(RPT,2)\n(RPT,2)\n(RPT,2)\n", 5, 1, 31,
    "RPT NEST >3 OR ERP WITHOUT RPT: a fourth RPT level", "L5930")
# FILMS4 32 a third call level (ln 5944): MAIN -> A -> B -> C.
neg("neg_subroutine_third_level", "; ln 5944\n(CLS,SUBA)\n", 2, 1, 32,
    "SUBROUTINE NEST >2: (CLS,SUBC) is a third call level (in SUBB line 1)", "L5944",
    **{"lib/SUBA": "(CLS,SUBB)\n", "lib/SUBB": "(CLS,SUBC)\n", "lib/SUBC": "G X1\n"})
# FILMS4 33 EPP inside EPP (ln 6082).
neg("neg_epp_nested", '; ln 6082\n"A" N1\n(EPP,C,D)\n"B" N3\n"C" N4\n"D" N5\n(EPP,A,B)\n', 3, 1, 33,
    "EPP NEST >1: EPP inside EPP", "L6082")
# FILMS4 34 / 37 labels (ln 10035-10049).
neg("neg_undefined_label", "; ln 10035\n(BNC,LAB9)\n", 2, 6, 34, 'UNDEFINED LABEL: "LAB9"', "L10035")
neg("neg_duplicated_label", '; ln 10043\n"L1" N1\n"L1" N2\n(BNC,L1)\n', 4, 6, 37, 'DUPLICATED LABEL: "L1"', "L10043")
# FILMS4 35 RPT not closed at the end (ln 10038).
neg("neg_rpt_not_closed", "; ln 10038\n(RPT,2)\nG X1\n", 3, 1, 35,
    "RPT OR EPP CYCLE NOT CLOSED: RPT without ERP at the end of the program", "L10038",
    ops=(units(3), lambda c: c.rapid(3, x=1)))
# FILMS4 36 a subroutine that does not exist (ln 10040).
neg("neg_subroutine_missing", "; ln 10040\n(CLS,NOSUB)\n", 2, 6, 36, "WRONG DATA SET: program NOSUB not found", "L10040")
# FILMS4 44 an offset not in the offsets file (ln 10058).
neg("neg_offset_not_in_file", "; ln 10058\nT5.5 M6\n", 2, 1, 44, "OFFSET NON EXISTENT: offset 5 is not in FI1COR", "L10058",
    ops=(units(2), lambda c: c.op("tool_select", 2, tool="5")), tools="1 Z100 K10\n")
# FILMS4 48 spindle on without S; FILMS4 49 M06 without T (ln 10064-10069).
neg("neg_spindle_without_s", "; ln 10064\nM3\n", 2, 1, 48, "S NOT DEFINED: M03 without S", "L10064")
neg("neg_m06_without_t", "; ln 10069\nM6\n", 2, 1, 49, "T NOT DEFINED: M06 without T", "L10069")
# FILMS4 59 a keyboard-only variable in a program (Table 4.3).
neg("neg_keyboard_only_variable", "; ln 2171 UAS is keyboard only\nUAS=1\n", 2, 1, 59,
    "BLOCK NOT ALLOWED: UAS is set from the keyboard only", "L2171")
# FILMS4 72 mutually alternative tools (ln 10115), FILMS4 82 a tool not in the tool life file (ln 10142).
neg("neg_tool_monitoring_loop", "; ln 10115\nT1.1 M6\n", 2, 1, 72, "TOOL MONITORING LOOP: tool 1 and its alternatives", "L10115",
    ops=(units(2), lambda c: c.op("tool_select", 2, tool="1")),
    **{"lib/GE1TOL": "VTU,1,T2,[TOOL COMP]2,t60,t2,t0,D\nVTU,2,T1,[TOOL COMP]1,t60,t2,t0,D\n"})
neg("neg_tool_not_allowed", "; ln 10142\nT3.3 M6\n", 2, 1, 82, "T NOT ALLOWED: tool 3 is not in the tool life file", "L10142",
    ops=(units(2), lambda c: c.op("tool_select", 2, tool="3")),
    **{"lib/GE1TOL": "VTU,1,T1,[TOOL COMP]1,t60,t2,t60,B\n"})
# FILMS4 03 beyond the DLO limits, FILMS4 84 into a protected area: refused before the move (ln 6633-6664,
# 6874-6914).
neg("neg_dlo_limit", "; ln 6652\n(DLO,X300 X-300)\nG X200\nG X350\n", 4, 3, 3, "OUT OF OPERATING LIMITS: X outside -300.000 .. 300.000 (DLO)",
    "L6652", ops=(units(3), lambda c: c.rapid(3, x=200)))
neg("neg_protected_area", "; ln 6900-6911\nN1 (DSA,1,X-300 X-100,Y-100 Y100)\nN3 (ASC,1)\nG X-50 Y0\nG X-400\n", 5, 3, 84,
    "VIOLATION OF PROTECTED AREA: the move enters protected area 1", "L6900",
    ops=(units(4), lambda c: c.rapid(4, x=-50, y=0)))
# FILMS4 77 UNDEFINED PROFILE: GTL elements that do not meet; a radius larger than an inside arc with
# compensation (ln 3211).
neg("neg_gtl_no_intersection", "; ln 10125\nl1=X0 Y0,a0\nl2=X0 Y10,a0\np1=l1,l2\n", 4, 4, 77,
    "UNDEFINED PROFILE: the elements do not intersect", "L10125")
# FILMS4 86 a feed move without F (ln 10150); FILMS4 88 a cycle on an axis that is not a spindle
# (ln 10154); FILMS4 94 the end of the text with a cycle open (ln 10168); FILMS4 96 a helix without its
# axis (ln 10171).
neg("neg_feed_not_programmed", "; ln 10150\nG1 X10\n", 2, 4, 86, "FEEDRATE NOT PROGRAMMED: no F programmed", "L10150")
neg("neg_cycle_axis", "; ln 10154\nG81 R2 U-10 F100\n", 2, 8, 88, "UNDEFINED CANNED CYCLE: U is not a spindle axis", "L10154")
neg("neg_incomplete_program", "; ln 10168\nG81 R2 Z-10 F100\n", 2, 1, 94,
    "INCOMPLETE PROGRAM: fixed cycle G81 still active (G80 missing)", "L10168")
neg("neg_helix_without_axis", "; ln 10171\nG3 X10 Y0 I5 J0 K2 F100\n", 2, 17, 96,
    "AXIS NOT BELONGING TO WORK PLANE: a helix needs the axis perpendicular to the plane", "L10171")
# FILMS4 103 the lathe configuration (CTL,T) (ln 6666-6679), virtual axes (UAV).
neg("neg_lathe_configuration", "; ln 6673\n(CTL,T)\n", 2, 1, 103,
    "FUNCTION NOT CONFIGURED: the lathe configuration (CTL,T) is not characterized here", "L6673")
# K14 @ (ln 4195-4205): only a SYVAR string runs (FILMS4 24 at the operand); an error in the text is reported
# at the @ operand with the text; a SYVAR never written holds no text (FILMS4 22).
neg("neg_exec_not_syvar", "; ln 4203\n@ SK5.4CH\n", 2, 3, 24, "OPERAND NOT ALLOWED: @ executes a SYVAR string", "L4203")
neg("neg_exec_bad_text", "; ln 4203\nSYVAR0.5CH=\"G45X1\"\n@ SYVAR0.5CH\n", 3, 3, 17,
    "NON EXISTENT FUNCTION: in \"G45X1\": G45 does not exist on this control", "L4203")
neg("neg_exec_empty", "; ln 4203\n@ SYVAR40.CH\n", 2, 3, 22, "OPERAND NOT PROVIDED: SYVAR40 holds no text", "L4203")
# Table 4.3 switches the cell cannot honour (judgement call 41): UVR=1, URL=1, UEP=0 are FILMS4 103; RAP=1 is
# the control's own FILMS4 05. The column is the value's.
neg("neg_uvr_rapid_test", "; ln 2166\nUVR=1\n", 2, 5, 103,
    "FUNCTION NOT CONFIGURED: UVR=1 (feed moves at rapid for testing): not on the cell", "L2166")
neg("neg_url_jog_rapid", "; ln 2167\nURL=1\n", 2, 5, 103,
    "FUNCTION NOT CONFIGURED: URL=1 (rapid under the JOG selector): the cell has no JOG", "L2167")
neg("neg_rap_auto_return", "; ln 2170\nRAP=1\n", 2, 5, 5,
    "AUTO RETURN TO PROFILE ILLEGAL: RAP=1: a feed hold on the cell stays on the profile, there is no jog to "
    "return from", "L2170")
neg("neg_uep_off", "; ln 2177\nUEP=0\n", 2, 5, 103,
    "FUNCTION NOT CONFIGURED: UEP=0: the servo always checks the following error", "L2177")
# SA / SK (ln 4108-4138): the A and K buffers are the interface logic's (the machine builder's signals, "data
# area 2 Siprom system", not in the manual). A machine without it (INTERFACE_LOGIC=0, BS01) refuses writes and
# reads with FILMS4 103; ABTVU, K bit 340 (ln 8520), asks for a tool life count the cell cannot make
# (judgement call 52).
neg("neg_sa_no_interface_logic", "; ln 4132-4136 SA128=1 sets signal 128 of the A buffer\nSA128=1\n", 2, 1, 103,
    "FUNCTION NOT CONFIGURED: SA: the machine has no interface logic for the A and K buffers (INTERFACE_LOGIC=0)",
    "L4132", params="INTERFACE_LOGIC=0\n")
neg("neg_sk_read_no_interface_logic", "; ln 5486 E2=SK396 reads byte 396 of the K buffer\nE2=SK396\n", 2, 4,
    103, "FUNCTION NOT CONFIGURED: SK: the machine has no interface logic for the A and K buffers "
    "(INTERFACE_LOGIC=0)", "L5486", params="INTERFACE_LOGIC=0\n")
neg("neg_sk_abtvu", "; ln 8520 ABTVU: SK340.BL=1 counts tool life without cutting\nSK340.BL=1\n", 2, 1, 103,
    "FUNCTION NOT CONFIGURED: SK340.BL=1 (ABTVU): the cell counts tool life only while the tool cuts", "L8520")
neg("neg_erf_negative", "; ln 4317-4329 ERF is a form error in mm\nERF=-.1\n", 2, 5, 13,
    "FORMAT ERROR: ERF (a form error) is not negative", "L4319")
neg("neg_mcd_range", "; ln 4333 MCD is 0 to 2\nMCD=2.5\n", 2, 5, 13, "FORMAT ERROR: MCD is 0-2", "L4333")
# DTL (ln 6606-6630): a tolerance other than 0 (judgement call 42), and DTL with compensation (ln 6627-6630).
neg("neg_dtl_tolerance", "; ln 6619\n(DTL,X.1,Y.05)\n", 2, 6, 103,
    "FUNCTION NOT CONFIGURED: a positioning tolerance other than 0 (the configured one)", "L6619")
neg("neg_dtl_with_compensation", "; ln 6627-6630\nT1.1 M6\nG41 G1 X10 Y10 F100\n(DTL,X0)\n", 4, 1, 25,
    "BLOCK DOES NOT MATCH: DTL is not allowed in a GTL profile or with compensation", "L6627",
    ops=[units(2), lambda c: c.op("tool_select", 2, tool="1"), lambda c: c.op("tool_change", 2, tool="1", offset=1)],
    tools="1 Z100 K10\n")
# FILMS4 51 UNKNOWN M OR H CODES (ln 10065): M and H codes are the machine builder's (ln 2500, 420-422).
# Offline the machine has Table 5.3's M10-M12 and M40-M45 (ln 2555-2589) and every H code; M50 is none of
# them. A station lists its own (M_CODES, H_CODES; BS01: none, judgement call 45).
neg("neg_m_code_unknown", "; ln 2555-2589, 10065\nS100 M3\nG1 X10 F100 M50\n", 3, 13, 51,
    "UNKNOWN M OR H CODES: M50 is not a function of this machine (M_CODES)", "L10065",
    ops=[units(2), lambda c: c.spindle(2, "cw", 100), lambda c: c.lin(3, 100, x=10)])
neg("neg_m_code_not_on_machine", "; ln 2569, 10065 (M_CODES=NONE, as BS01)\nG1 X10 F100 M10\n", 2, 13, 51,
    "UNKNOWN M OR H CODES: M10 is not a function of this machine (M_CODES)", "L2569", params="M_CODES=NONE\n")
neg("neg_h_code_not_on_machine", "; ln 420-422, 10065 (H_CODES=NONE, as BS01)\nG1 X10 F100 H5\n", 2, 13, 51,
    "UNKNOWN M OR H CODES: H05 is not a function of this machine (H_CODES)", "L420", params="H_CODES=NONE\n")
# FILMS4 103 for the console functions the cell does not have (judgement call 44): graphics (ln 6772-6818),
# the ASSET screen and keyboard (ln 1022-1040, 7711), multi-process (ln 2264-2266), table files (ln 1004-1017),
# virtual axes (ln 7588-7762).
for name, prog, cite, why in (
        ("neg_graphics_ucg", "(UCG,1,X0 X100,Y0 Y100)", "L6772", "is graphics: the cell has no CNC screen"),
        ("neg_graphics_clg", "(CLG)", "L6806", "is graphics: the cell has no CNC screen"),
        ("neg_asset_inp", "(INP,\"DEPTH\",E30)", "L7711",
         "is the ASSET operator screen and keyboard, which the cell does not have"),
        ("neg_asset_scr", "(SCR,ON)", "L1031", "is the ASSET operator screen and keyboard, which the cell does not have"),
        ("neg_process_wai", "(WAI,2)", "L2264", "is multi-process: the station runs one process"),
        ("neg_process_snd", "(SND,2)", "L2265", "is multi-process: the station runs one process"),
        ("neg_process_exe", "(EXE,2,PROG1)", "L2266", "is multi-process: the station runs one process"),
        ("neg_table_file_opn", "(OPN,TAB1)", "L1004", "is an ASSET table file, which the cell does not have"),
        ("neg_virtual_axes_uav", "(UAV,2,B,Y,50)", "L7588", "is virtual or dual axes, which no Balt-System station has"),
):
    mne = prog[1:4]
    neg(name, f"; ln {cite[1:]}\n{prog}\n", 2, 1, 103, f"FUNCTION NOT CONFIGURED: ({mne}) {why} (see docs/dialects/balt.md)",
        cite)
# Keyboard-only commands (Tables 1.7/4.4, ln 1141-1166, 2184-2217: ORA, CAO, VOA, SPG, REL, PTM, EVA, ...) are
# not part-program commands: FILMS4 17 at the bracket.
neg("neg_keyboard_command", "; ln 2184-2217 SPG is a keyboard command\n(SPG,PROG1)\n", 2, 1, 17,
    "NON EXISTENT FUNCTION: (SPG,...) is not a command of this control", "L2184")

# Random tool management (§6.7, ln 8523-8559; judgement call 47): a T the file FI1RAN does not hold is FILMS4
# 82; RANDOM_TOOLS=1 without the file FILMS4 83 (ln 10144-10145); a standard tool programmed while a special
# tool is on the spindle FILMS4 90 (ln 10158-10160).
random_file = "0001-----\n0002-----\n9003-----\n9003-----\n9003-----\n0004-----\n"
neg("neg_random_tool_not_in_file", "; ln 8551-8553, 10142\nT5.5 M6\n", 2, 1, 82,
    "T NOT ALLOWED: tool 5 is not in the random tool file", "L8551",
    **{"lib/FI1RAN": random_file})
neg("neg_random_file_missing", "; ln 10144-10145 (RANDOM_TOOLS=1)\nT1.1 M6\n", 2, 1, 83,
    "RANDOM TOOL FILE NOT FOUND: T1: FI1RAN is not on MP0 (RANDOM_TOOLS=1)", "L10144",
    params="RANDOM_TOOLS=1\n")
neg("neg_random_mixed_tool_change", "; ln 10158-10160\nT3.3 M6\nT1.1 M6\n", 3, 1, 90,
    "MIXED TOOL CHANGE: standard tool 1 while special tool 3 is on the spindle", "L10158",
    ops=(units(2), lambda c: c.op("tool_select", 2, tool="3"),
         lambda c: c.op("tool_change", 2, tool="3", offset=3, socket=3)),
    tools="1 Z100 K10\n3 Z130 K30\n", **{"lib/FI1RAN": random_file})

