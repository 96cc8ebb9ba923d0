"""Program format and motion: manual §5.3-5.13 (seeds/balt-system-nc110-nc210.txt)."""
import math

from corpus import Case, r, rot, sweep

# L2408-2417: the skeleton program: tape delimiters, a message, the tool change in the first block, rapid
# positioning with M13 (spindle CW + coolant, before the move), M5 (spindle and the M13 coolant off, after
# it), M30.
c = Case("p5_06_skeleton", """
; L2408-2417 skeleton program
%
N1 (DIS,"TWIST DRILL D6")
N2 T1.1 M6 S800
N3 G X80 Y80 M13
N236 G X250 Y50 M5
N237 M30
%
""", "L2408")
c.units("N1")
c.op("message", "N1", text="TWIST DRILL D6")
c.op("tool_select", "N2", tool="1")
c.op("tool_change", "N2", tool="1", offset=1)
c.spindle("N3", "cw", 800)
c.op("coolant", "N3", m=13, mode="flood")
c.rapid("N3", x=80, y=80)
c.rapid("N236", x=250, y=50)
c.spindle("N236", "stop", 800)
c.op("coolant", "N236", m=5, mode="off")
c.op("end", "N237", m=30, shuttle=False)

# L2728-2729 (Fig 5.2): "N79 X10 Y10" in the power-up G00, then a line at F200 mm/min.
c = Case("p5_08_linear", """
; L2728-2729 linear interpolation (Fig 5.2)
N79      X10 Y10
N80 G01 X90 Y40 F200
M30
""", "L2728")
c.units("N79")
c.rapid("N79", x=10, y=10)
c.lin("N80", 200, x=90, y=40)
c.op("end", "M30", m=30, shuttle=False)

# L2762-2766: I J are the centre, absolute in G90. N20: CCW quarter about (-40,60) from (-20,60) to
# (-40,80); N40: CW quarter about (-45,90) from (-45,80) to (-55,90). "N50 G1 Y..." given a value, 100.
c = Case("p5_08_arcs_absolute", """
; L2762-2766 circular interpolation with centre coordinates (G90)
N10 G1 X-20 Y60 F200
N20 G3 X-40 Y80 I-40 J60
N30 G1 X-45
N40 G2 X-55 Y90 I-45J90
N50 G1 Y100
""", "L2762")
c.units("N10")
c.lin("N10", 200, x=-20, y=60)
c.arc("N20", 200, (-40, 60), False, 90, x=-40, y=80)
c.lin("N30", 200, x=-45)
c.arc("N40", 200, (-45, 90), True, 90, x=-55, y=90)
c.lin("N50", 200, y=100)

# L2770-2781: the same path in G91: I J relative to the arc's start (a judgement call, the manual's only
# evidence): N20 from (-20,60) by (-20,20), centre (-20-20, 60+0); N40 from (-45,80), centre (-45+0, 80+10).
c = Case("p5_08_arcs_incremental", """
; L2770-2781 the same path with G91 (I J relative to the start of the arc)
N10 G1 X-20 Y60 F200
N20 G3 G91 X-20 Y20 I-20 J0
N30 G1 X-5
N40 G2 X-10 Y10 I0J10
N50 G1 Y10
""", "L2770")
c.units("N10")
c.lin("N10", 200, x=-20, y=60)
c.arc("N20", 200, (-40, 60), False, 90, x=-40, y=80)
c.lin("N30", 200, x=-45)
c.arc("N40", 200, (-45, 90), True, 90, x=-55, y=90)
c.lin("N50", 200, y=100)

# L2743-2756: R is the radius, positive up to 180 degrees, negative from 180. From (0,0) CW to (20,20)
# with R20: the centres are (20,0) (90 degrees) and (0,20) (270); R+ takes (20,0). From (20,20) CW to
# (40,0) with R-20: (20,0) gives 90 degrees, (40,20) gives 270: R- takes (40,20).
c = Case("p5_08_arc_radius", """
; L2743-2756 circular interpolation with the radius R (+ up to 180 degrees, - from 180)
G2 X20 Y20 R20 F100
G2 X40 Y0 R-20
""", "L2743")
c.units(2)
c.arc(2, 100, (20, 0), True, 90, x=20, y=20)
c.arc(3, 100, (40, 20), True, 270, x=40, y=0)

# L2790-2836: a helix of depth n K programs the arc of n's fraction: Z-27 with K10 is n = 2.7, so a 252
# degree arc (360 x 0.7) and two full turns: 972 degrees. End (10 cos 252, 10 sin 252). Then a full circle
# (no plane axes, I J) with Z down 20 at K10: n = 2, 720 degrees.
e = (10 * math.cos(math.radians(252)), 10 * math.sin(math.radians(252)))
c = Case("p5_08_helix", f"""
; L2790-2836 helical interpolation: depth n K, the arc of the fraction of n
G X10 Y0 Z0
G3 X{e[0]:.4f} Y{e[1]:.4f} Z-27 I0 J0 K10 F100
G2 I0 J0 Z-47 K10
""", "L2790")
c.units(2)
c.rapid(2, x=10, y=0, z=0)
c.arc(3, 100, (0, 0), False, 972, x=round(e[0], 4), y=round(e[1], 4), z=-27)
c.arc(4, 100, (0, 0), True, 720, z=-47)

# L2866-2929: G33 threads (K pitch, I pitch change per turn, R start angle): cylindrical, conical with the
# diameter axis U, decreasing pitch checked against I <= K^2 / 2L (100 / 100 = 1: allowed), three starts.
c = Case("p5_08_threads", """
; L2866-2929 G33 threads: cylindrical, conical (U), variable pitch, three starts (R)
S200 M3
G X0 Y0 Z5
N15 G33 Z-100 K2
G Z5
N22 G33 Z-80 U40 K3
G Z5 U0
N24 G33 Z-45 K10 I-1
G Z5
N37 G33 Z-30 K6
G Z5
N41 G33 Z-30 K6 R120
G Z5
N45 G33 Z-30 K6 R240
""", "L2866")
c.units(2)
c.spindle(2, "cw", 200)
c.rapid(3, x=0, y=0, z=5)
c.thread("N15", 2, z=-100)
c.rapid(5, z=5)
c.thread("N22", 3, z=-80, u=40)
c.rapid(7, z=5, u=0)
c.thread("N24", 10, change=-1, z=-45)
c.rapid(9, z=5)
c.thread("N37", 6, z=-30)
c.rapid(11, z=5)
c.thread("N41", 6, start=120, z=-30)
c.rapid(13, z=5)
c.thread("N45", 6, start=240, z=-30)

# L3016-3033: point-to-point G29: every feed move stops exactly; M and S inside the profile; G4 dwells TMR
# at the end of its block. N15 CCW about (0,0) from (75,0) to (-70.477,25.651) (radius 74.9997).
a15 = math.degrees(math.atan2(25.651, -70.477))
c = Case("p5_08_point_to_point", """
; L3016-3033 point-to-point mode G29 with M and S inside the profile, G4 with TMR
N10 S800 T4.4 M6
N11 G29 G X-235 Y-230 M13
N12 Z-10
N13 G1 X75 F500 M5
N14 Y S1200 M13
N15 G3 X-70.477 Y25.651 I J
N16 TMR=2
N17 G1 G4 X-187 Y-295
N18 G Z5 M5
""", "L3016")
c.units("N10")
c.op("tool_select", "N10", tool="4")
c.op("tool_change", "N10", tool="4", offset=4)
c.spindle("N11", "cw", 800)
c.op("coolant", "N11", m=13, mode="flood")
c.rapid("N11", x=-235, y=-230)
c.rapid("N12", z=-10)
c.lin("N13", 500, exact=True, x=75)
c.spindle("N13", "stop", 800)
c.op("coolant", "N13", m=5, mode="off")
c.spindle("N14", "cw", 1200)
c.op("coolant", "N14", m=13, mode="flood")
c.lin("N14", 500, exact=True, y=0)
c.arc("N15", 500, (0, 0), False, a15, exact=True, x=-70.477, y=25.651)
c.lin("N17", 500, exact=True, x=-187, y=-295)
c.op("dwell", "N17", seconds=2)
c.rapid("N18", z=5)
c.spindle("N18", "stop", 1200)
c.op("coolant", "N18", m=5, mode="off")

# ln 2958-2983, 4317: G27 and G28 differ at the corners. The canonical commands carry only `exact_stop`
# (docs/canonical-commands.md): G27, the power-up mode (ln 2979), decelerates "to 0 at the end of each block"
# with the default ERF=0 (ln 4317): every feed move has exact_stop; G28 "without automatic deceleration on
# corners ... output speed equal to the programmed speed" (ln 2969): the feed moves blend (no exact_stop).
# With ERF=.05 G27 still stops (the canon has no form-error bound; a judgement call, balt.md). The profile is
# the manual's continuous-mode example (ln 2991-3005): N13 (75,-230), N14 Y0, N15 CCW about I0 J0 = (0,0)
# from (75,0) to (-70.477,25.651), N16 (-187,-295); the G00 blocks always stop (ln 2977).
a15 = math.degrees(math.atan2(25.651, -70.477))
c = Case("p5_08_g27_g28_corners", """
; ln 2958-2983, 4317 G27 (ERF=0: exact stop at each block end) against G28 (blended corners)
N10 S800 T4.4 M6
N11 G X-235 Y-230 M13
N12 Z-10
N13 G1 X75 F500
N14 Y
N15 G3 X-70.477 Y25.651 I J
N16 G1 X-187 Y-295
N17 G Z5 M5
N20 G28 G X-235 Y-230 M13
N21 Z-10
N22 G1 X75 F500
N23 Y
N24 G3 X-70.477 Y25.651 I J
N25 G1 X-187 Y-295
N26 ERF=.05
N27 G27 X75 Y-230
N28 G Z5 M5
""", "L2958")
c.units("N10")
c.op("tool_select", "N10", tool="4")
c.op("tool_change", "N10", tool="4", offset=4)
for n in ("N11", "N20"):
    c.spindle(n, "cw", 800)
    c.op("coolant", n, m=13, mode="flood")
    c.rapid(n, x=-235, y=-230)
    k = int(n[1:])
    c.rapid(f"N{k + 1}", z=-10)
    c.exact_default = n == "N11"  # G27 first, G28 from N20
    c.lin(f"N{k + 2}", 500, x=75)
    c.lin(f"N{k + 3}", 500, y=0)
    c.arc(f"N{k + 4}", 500, (0, 0), False, a15, x=-70.477, y=25.651)
    c.lin(f"N{k + 5}", 500, x=-187, y=-295)
    if n == "N11":
        c.rapid("N17", z=5)
        c.spindle("N17", "stop", 800)
        c.op("coolant", "N17", m=5, mode="off")
c.lin("N27", 500, exact=True, x=75, y=-230)
c.rapid("N28", z=5)
c.spindle("N28", "stop", 800)
c.op("coolant", "N28", m=5, mode="off")

# L3616-3621 (Fig 5.24) under a temporary origin (100,200): N1 to the origin, N2 P1 (30,40), N3-N4 G91 to
# P2 (80,65) and P3 (9,77), N5 G90 P4 (110,35), N6 G79 P5 at machine (70,55), not shifted.
c = Case("p5_08_absolute_incremental_g79", """
; L3616-3621 G90 / G91 / G79 (Fig 5.24), under (UOT,0,X100,Y200)
(UOT,0,X100,Y200)
N1 G X Y
N2 X30 Y40
N3 G91 X50 Y25
N4 X-71 Y12
N5 G90 X110 Y35
N6 G79 X70 Y55
N7 X0 Y0
""", "L3616")
c.units("N1")
c.rapid("N1", x=100, y=200)
c.rapid("N2", x=130, y=240)
c.rapid("N3", x=180, y=265)
c.rapid("N4", x=109, y=277)
c.rapid("N5", x=210, y=235)
c.rapid("N6", x=70, y=55)
c.rapid("N7", x=100, y=200)

# L3711-3720: G93: F is blocks per minute and is valid in its block only.
c = Case("p5_08_inverse_time", """
; L3711-3720 G93 inverse time feed: X100 F1 takes 1 min, X200 F10 6 s
G93 G1 X100 F1
X200 F10
""", "L3711")
c.units(2)
c.lin(2, 1, mode="inverse_time", x=100)
c.lin(3, 10, mode="inverse_time", x=200)

# L3743-3756 back spot-facing: M19 orients before the block's motion; TMR=2 dwell with G4.
c = Case("p5_09_m19_back_spotface", """
; L3743-3756 back spot-facing with M19 (before any motion of its block) and G4 / TMR
N33 S115 F20 T7.7 M6
N34 G X250 Y-12 M19
N35 Z-306
N36 Y M3
N37 TMR=2
N38 G1 G4 Z-300
N39 G Z-302 M5
N40 Y-12 M19
N41 Z
""", "L3743")
c.units("N33")
c.op("tool_select", "N33", tool="7")
c.op("tool_change", "N33", tool="7", offset=7)
c.spindle("N34", "orient", 115, angle=0)
c.rapid("N34", x=250, y=-12)
c.rapid("N35", z=-306)
c.spindle("N36", "cw", 115)
c.rapid("N36", y=0)
c.lin("N38", 20, z=-300)
c.op("dwell", "N38", seconds=2)
c.rapid("N39", z=-302)
c.spindle("N39", "stop", 115)
c.spindle("N40", "orient", 115, angle=0)
c.rapid("N40", y=-12)
c.rapid("N41", z=0)

# L3842-3877 paraxial factors with a cutter of radius 5 (offset 1 K10): final = programmed + 5 x factor on
# X (u), Y (v), Z (w), in the block only. (b) Y = 10 - 5, X = 40 + 5; (c) the inside of the 40 square at
# +-15; (d) the outside at +-25.
c = Case("p5_11_paraxial", """
; L3842-3877 paraxial compensation u v w, examples (b), (c), (d); cutter radius 5 (K10)
T1.1 M6
N13 G X Y
N14 Y10 v-1
N15 X40 u1
N16 Y30
N17 G X0 Y0
N14 G1 Z-10 F100
N15 X-20 Y-20 u1 v1
N16 X20 u-1
N17 Y20 v-1
N18 X-20 u1
N19 Y-20 v1
N20 G X-35 Y-35
N15 G1 X-20 Y-20 u-1 v-1
N16 X20 u1
N17 Y20 v1
N18 X-20 u-1
N19 Y-20 v-1
""", "L3842", tools="1 Z0 K10\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.touch("x", "y")
c.rapid(4, y=5)
c.rapid(5, x=45)
c.rapid(6, y=30)
c.rapid(7, x=0, y=0)
c.lin(8, 100, z=-10)
c.lin(9, 100, x=-15, y=-15)
c.lin(10, 100, x=15)
c.lin(11, 100, y=15)
c.lin(12, 100, x=-15)
c.lin(13, 100, y=-15)
c.rapid(14, x=-35, y=-35)
c.lin(15, 100, x=-25, y=-25)
c.lin(16, 100, x=25)
c.lin(17, 100, y=25)
c.lin(18, 100, x=-25)
c.lin(19, 100, y=-25)

# L3901-3905 (f): paraxial with the rotary B turning: X = 30 + 5, then 25 + 5 while B turns 360 degrees.
c = Case("p5_11_paraxial_rotary", """
; L3901-3905 paraxial factor with a rotary axis (f); cutter radius 5
T1.1 M6
N12 G X40 Y B0
N13 G1 X30 u1 F200
N14 X25 B360 u1
N15 G X40
""", "L3901", tools="1 Z0 K10\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.rapid(3, x=40, y=0, b=0)
c.lin(4, 200, x=35)
# B turns with X (ln 3961-3976): F200 is the rate along the vector (5 mm, 360 degrees), X runs at
# 200 * 5 / sqrt(5^2 + 360^2).
c.lin(5, r(200 * 5 / math.hypot(5, 360)), travel={"b": 360}, x=30, b=360)
c.rapid(6, x=40)

# ln 3961-3976: rotary axes moving with linear ones in G94, F = A * sqrt(X^2 + Y^2 + Z^2 + B^2 + C^2) / L with
# the travels in mm and degrees: F is the rate along that vector, so the tool point (X Y Z) runs at F times
# its share of it (judgement call 21). X30 Y40 is 50 mm, B120 120 degrees: the vector is 130, so F1300 moves
# X Y at 1300 * 50 / 130 = 500 mm/min. In G70 the travels still count in mm: X1 (25.4 mm) with turning
# -25.4 degrees at F10 in/min (254 mm/min) runs at 254 / sqrt(2) mm/min. In G93 F stays the block's inverse
# time (F = A / L); a rotary move alone is in deg/min (p5_07_feed_modes).
c = Case("p5_13_rotary_with_linear", """
; ln 3961-3976 rotary axes with linear axes: F is the rate along the vector of mm and degrees
G1 X30 Y40 B120 F1300
G70 G91 X1 A-25.4 F10
G93 G71 Y-40 B-120 F2
""", "L3961")
c.units(2)
c.lin(2, 500, travel={"b": 120}, x=30, y=40, b=120)
c.units(3, mm=False)
c.lin(3, r(254 / math.sqrt(2)), travel={"a": -25.4}, x=30 + 25.4, a=-25.4)
c.units(4)
c.lin(4, 2, mode="inverse_time", travel={"b": -120}, y=0, b=0)

# L3909-3938 indexing table: B takes a number of indexes (INDEX_B=5: 5 degrees each), absolute or
# incremental; the table turns before the other axes of its block.
c = Case("p5_12_indexing_table", """
; L3909-3938 indexing table B (5 degrees per index: INDEX_B in .params)
N24 B10
N41 G91 B2
N80 G90 B0 X10
""", "L3909", params="INDEX_B=5\n")
c.units("N24")
c.rapid("N24", travel={"b": 50}, b=50)
c.rapid("N41", travel={"b": 10}, b=60)
c.rapid("N80", travel={"b": -60}, b=0)
c.rapid("N80", x=10)

# L3988-4031 rollover B (ROLLOVER=B): G90 goes to the angle modulo 360 the way its sign says; G91 by the
# increment. From 90, B45 turns +315; B-0 turns -90; from 0, G91 B765 turns 765 and shows 45.
c = Case("p5_13_rollover", """
; L3988-4031 rollover rotary axis B (ROLLOVER=B in .params)
B90
B45
B90
B-0
G91 B765
""", "L3988", params="ROLLOVER=B\n")
c.units(2)
c.rapid(2, travel={"b": 90}, b=90)
c.rapid(3, travel={"b": 315}, b=45)
c.rapid(4, travel={"b": 45}, b=90)
c.rapid(5, travel={"b": -90}, b=0)
c.rapid(6, travel={"b": 765}, b=45)

# L3984: t is the block's time in seconds: F = length / t = 100 mm / 0.1 min = 1000 mm/min.
c = Case("p5_13_block_time", """
; L3984 block time t: G1 Y100 B20 t6 runs 6 s
G1 Y100 B20 t6
""", "L3984")
c.units(2)
c.lin(2, 1000, travel={"b": 20}, y=100, b=20)

# L4052-4138 global variables: TMR (the G04 dwell), UOV shown with DIS, SA / SK writes go to the machine
# logic as outputs, a character read back.
c = Case("p5_14_global_variables", """
; L4052-4138 TMR, UOV, RMS, SA / SK assignments
TMR = 12.5
G4
E32 = 13.4
TMR = E32
G4
UOV = 0.5
(DIS,UOV)
RMS = 110
(DIS,RMS)
SA128=1
SK7="RIF"
SA3.BY=255
(DIS,SK7.3CH)
""", "L4052")
c.units(3)
c.op("dwell", 3, seconds=12.5)
c.op("dwell", 6, seconds=13.4)
c.op("message", 8, text="UOV=0.5")
c.op("message", 10, text="RMS=110")
c.op("output", 11, spec="SA128=1")
c.op("output", 12, spec='SK7="RIF"')
c.op("output", 13, spec="SA3.BY=255")
c.op("message", 14, text="SK7.3CH=RIF")

# L2216, L5476-5495: expressions with the usual precedence, degree trigonometry, E(En) (K14).
# E37 = (2 sin 30 + 123.4567) / 4 = 31.114175; E51 = 4.99999876; tan 35 = 0.7002075382;
# SQR(144)+20/2 = 22 and (SQR(144)+20)/2 = 16 (EVA, L2216); E(E3) with E3=17 sets E17.
c = Case("p5_16_expressions", """
; L2216, L5476-5495 expressions, functions, E(En)
E30=30
E31=2
N1 E37=(E31*SIN(E30)+123.4567)/SQR(16)
"LAB1"E51=-0.00000124+5
E40=TAN(35)
E41=SQR(144)+20/2
E42=(SQR(144)+20)/2
Nm1 E3=17
E(E3)=10
E25=E25+30
(DIS,E37)
(DIS,E51)
(DIS,E40)
(DIS,E41)
(DIS,E42)
(DIS,"E17=",E17)
(DIS,E25)
""".replace("Nm1 ", ""), "L5476")
c.units(12)
c.op("message", 12, text="E37=31.114175")
c.op("message", 13, text="E51=4.99999876")
c.op("message", 14, text="E40=0.7002075382")
c.op("message", 15, text="E41=22")
c.op("message", 16, text="E42=16")
c.op("message", 17, text="E17=10")
c.op("message", 18, text="E25=30")

# L5429-5435: "E(En) = <expression> ... n can be a number or an E parameter (of either byte or integer type)".
# E(31)=12.5 is E31 = 12.5; E3=32 then E(E3)=E(31)*2 sets E32 = 12.5 * 2 = 25; E(14)=7 sets the integer E14.
# E50=E(E3)-E(14) = E32 - E14 = 25 - 7 = 18. The move reads them back, E(32) also as an address value:
# X = E31 = 12.5, Y = E(32) = 25, Z = E50 = 18 (no origin or tool offsets: positions as programmed).
c = Case("p5_16_e_number_index", """
; L5429-5435 E(n) = <expression> with n a number or an E parameter (K14)
E(31)=12.5
E3=32
E(E3)=E(31)*2
E(14)=7
E50=E(E3)-E(14)
G1 XE31 YE(32) ZE50 F100
(DIS,"E14=",E14)
""", "L5429")
c.units(7)
c.lin(7, 100, x=12.5, y=25, z=18)
c.op("message", 8, text="E14=7")

# ln 2936-2956 G18 (abscissa Z, ordinate X) with I J as the plane's abscissa and ordinate (ln 2454): from
# (X0 Z0) CW about (Z20, X0) to (Z20, X20): 90 degrees. G19 (Y, Z): from (Y0 Z20) CCW about (Y0 Z30) to
# (Y10 Z30): 90 degrees. DPI makes another pair the plane (ln 6578-6604): (DPI,X,Z), from (X20 Z30) CW
# about (X20 Z10), radius 20, to (X40 Z10): in the (abscissa, ordinate) frame from 90 to 0 degrees, 90 swept.
c = Case("p5_08_planes", """
; ln 2936-2956 G18 / G19 and DPI planes; I J are the plane's abscissa and ordinate
G1 X0 Y0 Z0 F100
G18
G2 Z20 X20 I20 J0
G19
G3 Y10 Z30 I0 J30
G17
(DPI,X,Z)
G2 X40 Z10 I20 J10
(DPI,X,Y)
""", "L2936")
c.units(4)
c.touch("x", "y", "z")
c.arc(4, 100, (0, 0, 20), True, 90, plane="zx", x=20, z=20)
c.arc(6, 100, (20, 0, 30), False, 90, plane="yz", y=10, z=30)
c.arc(9, 100, (20, 10, 10), True, 90, plane="xz", x=40, z=10)

# ln 5730-5765 SCF: factor 2 on every axis, then 3 on X only (the others unscaled), then none.
c = Case("p5_17_scale", """
; ln 5730-5765 scale factors SCF
(SCF,2)
G1 X10 Y10 F100
(SCF,3,X)
X10 Y10
(SCF)
X10 Y10
""", "L5730")
c.units(3)
c.lin(3, 100, x=20, y=20)
c.lin(5, 100, x=30, y=10)
c.lin(7, 100, x=10, y=10)

# ln 5730-5765 SCF scales the programmed axes' dimensions; ln 2790-2836 a helix's depth is n K. K is a length
# on the perpendicular axis and scales with it (judgement call 48, found by the transforms property of
# tests/oracle): (SCF,2) makes X10 20, the centre I0 J0 stays 0 0, the depth Z6 12 and K3 6, so n = 12 / 6 = 2
# whole circles = 720 degrees (K unscaled would give n = 12 / 3 = 4, 1440 degrees: twice the turns).
c = Case("p5_17_scale_helix_pitch", """
; ln 5730-5765 SCF scales the helix pitch K with the depth (ln 2790-2836, judgement call 48)
(SCF,2)
G X10 Y0 Z0
G3 X10 Y0 Z6 I0 J0 K3 F100
(SCF)
G X10 Y0 Z6
""", "L5730")
c.units(3)
c.rapid(3, x=20, y=0, z=0)
c.arc(4, 100, (0, 0), False, 720, x=20, y=0, z=12)
c.rapid(6, x=10, y=0, z=6)

# ln 2326-2333, 2165: a slashed block is a comment while USB=0 (the default), executed with USB=1.
c = Case("p5_04_slashed_blocks", """
; ln 2326-2333 slashed blocks and USB
/N100 G00 X100
USB=1
/N101 G00 X50
""", "L2326")
c.units(4)
c.rapid(4, x=50)

# ln 2560, 2168 M01 is a stop only with USO=1 (a judgement call: Table 2.1 says the opposite).
c = Case("p5_07_optional_stop", """
; ln 2560, 2168 M01 and USO
M01
USO=1
M01
M60
S100 M3 M10
""", "L2560")
c.units(4)
c.op("stop", 4, m=1, optional=True)
c.op("pallet", 5, m=60)
c.spindle(6, "cw", 100)
c.op("aux", 6, m=10)

# ln 7647-7667: a tape may hold several programs, each "%:NAME" ... "%": the first runs; CLS finds the
# others by name (a judgement call, docs/dialects/balt.md).
c = Case("p5_04_programs_in_one_file", """
; ln 7647-7667 %:NAME programs in one file; CLS finds SUBA in it
%:MAIN
G X10
(CLS,SUBA)
G X0
M30
%
%:SUBA
G Y10
%
""", "L7647")
c.units(3)
c.rapid(3, x=10)
c.rapid(4, y=10)
c.rapid(5, x=0)
c.op("end", 6, m=30, shuttle=False)

# ln 2490-2496, 3940-3949: G95 feed per revolution; a rotary axis alone in G94 moves in degrees per minute;
# G96 S is a cutting speed in m/min.
c = Case("p5_07_feed_modes", """
; ln 2490-2496, 3940-3949 feed per revolution, rotary feed in degrees per minute, constant cutting speed
S500 M3
G95 G1 X10 F0.2
G94 B90 F100
G96 S120
""", "L2490")
c.units(2)
c.spindle(2, "cw", 500)
c.lin(3, 0.2, mode="per_rev", x=10)
c.lin(4, 100, mode="deg_per_min", travel={"b": 90}, b=90)
c.spindle(5, "cw", 0, css=120)

# G09 (ln 3643-3644; Table 5.2 ln 2545 says "acceleration", judgement call 19): in G28 (blended) the G09 block
# alone decelerates to 0 at its end; the blocks around it stay blended.
c = Case("p5_08_g09_block_stop", """
; ln 3643-3644 G09 decelerates to 0 at the end of its block only (here in G28)
N1 G28 G1 X10 F100
N2 G9 X20
N3 X30
""", "L3643")
c.units("N1")
c.lin("N1", 100, exact=False, x=10)
c.lin("N2", 100, exact=True, x=20)
c.lin("N3", 100, exact=False, x=30)

# Table 5.6 (ln 3300-3313): G85 feeds in and feeds out to R1, then rapids to R2 (here R1 2, R2 10); G86 stops
# the spindle at the bottom and rapids out to R1 (the spindle turns again for the next hole); G89 dwells TMR
# (1 s) at the bottom and feeds out. Each hole: rapid to X Y, rapid to R1, feed to Z-10 at F100 (G27: exact).
c = Case("p5_8_7_g85_g86_g89", """
; ln 3300-3313 Table 5.6 G85 reaming, G86 boring with spindle stop, G89 boring with dwell
N1 S500 F100 M3
N2 TMR=1
N3 G85 R2 R10 Z-10
N4 X10 Y10
N5 G80
N6 G86 R2 Z-10
N7 X20
N8 G80
N9 G89 R2 Z-10
N10 X30
N11 G80 Z50 M5
""", "L3300")
c.units("N1")
c.spindle("N1", "cw", 500)
c.rapid("N4", x=10, y=10)
c.rapid("N4", z=2)
c.lin("N4", 100, z=-10)
c.lin("N4", 100, z=2)
c.rapid("N4", z=10)
c.rapid("N7", x=20)
c.rapid("N7", z=2)
c.lin("N7", 100, z=-10)
c.spindle("N7", "stop", 500)
c.rapid("N7", z=2)
c.spindle("N7", "cw", 500)
c.rapid("N10", x=30)  # G86 left the spindle at R1 (z 2): no approach move for G89's hole
c.lin("N10", 100, z=-10)
c.op("dwell", "N10", seconds=1)
c.lin("N10", 100, z=2)
c.rapid("N11", z=50)
c.spindle("N11", "stop", 500)

# Table 5.3 (ln 2561-2578): M04 spindle CCW at the start of its block, M08 coolant at the start, M09 coolant
# off at the end, M14 spindle CCW + coolant (the spindle already turns CCW: only the coolant changes), M02 end
# of program without rewind.
c = Case("p5_07_m04_m14_m02", """
; ln 2561-2578 M04 M08 M09 M14 M02
N1 S300 M4
N2 G1 X10 F100 M8
N3 M9
N4 M14
N5 M2
""", "L2561")
c.units("N1")
c.spindle("N1", "ccw", 300)
c.op("coolant", "N2", m=8, mode="flood")
c.lin("N2", 100, x=10)
c.op("coolant", "N3", m=9, mode="off")
c.op("coolant", "N4", m=14, mode="flood")
c.op("end", "N5", m=2, shuttle=False)

# A stored GTL point gives the plane's abscissa and ordinate of an ISO move (ln 2701): p1 = X5 Y5, then G1 p1
# feeds from X10 Y20 to X5 Y5.
c = Case("p5_08_point_as_coordinates", """
; ln 2701 a stored point gives the coordinates of a G01 move
N1 G1 X10 Y20 F100
N2 p1=X5Y5
N3 G1 p1
""", "L2701")
c.units("N1")
c.lin("N1", 100, x=10, y=20)
c.lin("N3", 100, x=5, y=5)
