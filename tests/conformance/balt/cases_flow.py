"""Fixed cycles, reference systems, parametric programming and control flow: manual §5.8.7, §5.16, §5.17."""
import math

from corpus import Case, rot


def hole(c, line, x, y, r1, depth, f, ret=None, z_before=None, **kw):
    """G81: rapid to the hole, rapid to R1 (when not there), feed to the depth, rapid to R2 / R1."""
    c.rapid(line, x=x, y=y)
    if abs(c.pos["z"] - r1) > 1e-9:
        c.rapid(line, z=r1)
    else:
        c.touch("z")
    c.lin(line, f, exact=True, z=depth)
    c.rapid(line, z=r1 if ret is None else ret)


# L3349-3356 (Fig 5.14): the declaration block N33 moves nothing; holes at (15,15), (15,60), (80,60),
# (80,15): rapid to R3, F95 to Z-15, rapid back to R3; G80 Z50 moves in G00.
c = Case("p5_8_7_g81_drilling", """
; L3349-3356 G81 drilling (Fig 5.14)
N32 S1100 F95 T3.3 M6
N33 G81 R 3 Z-15 M3
N34 X15 Y15
N35 Y60
N36 X80
N37 Y15
N38 G80 Z50 M5
""", "L3349")
c.units("N32")
c.op("tool_select", "N32", tool="3")
c.op("tool_change", "N32", tool="3", offset=3)
c.spindle("N33", "cw", 1100)
for n, (x, y) in zip(("N34", "N35", "N36", "N37"), ((15, 15), (15, 60), (80, 60), (80, 15))):
    hole(c, n, x, y, 3, -15, 95)
c.rapid("N38", z=50)
c.spindle("N38", "stop", 1100)

# ln 2494-2496 (G95: F per revolution, judgement call 18) with ln 3349-3356 (G81): a cycle declared in G95
# feeds per revolution. Found by the LinuxCNC differential (tests/oracle): the cycle's feed moves were output
# per minute (F0.2 as 0.2 mm/min). Hole at (10, 20) from Z0: rapid to the hole, rapid to R1 = 2, F0.2 mm/rev
# to Z-10, rapid back to R1 = 2.
c = Case("cycle_g81_per_rev", """
; ln 2494-2496 G95 feed per revolution, ln 3349-3356 G81: the cycle feeds 0.2 mm/rev
N1 S1000 M3
N2 G95
N3 G81 R2 Z-10 F0.2
N4 X10 Y20
N5 G80
""", "ln 2494")
c.units("N1")
c.spindle("N1", "cw", 1000)
c.rapid("N4", x=10, y=20)
c.rapid("N4", z=2)
c.lin("N4", 0.2, exact=True, mode="per_rev", z=-10)
c.rapid("N4", z=2)

# L3362-3368: G82 dwells TMR (2 s) at the bottom. (The manual's N34 has M13 without any S: S600 F80 are
# given before it.)
c = Case("p5_8_7_g82_spotface", """
; L3362-3368 G82 spot-facing with TMR=2 at the bottom
N32 S600 F80
N33 TMR=2
N34 G82 R-3 Z-5 T6 M13
N35 X35 Y150
N36 G80 Z50 M5
""", "L3362")
c.units("N34")
c.op("tool_select", "N34", tool="6")
c.spindle("N34", "cw", 600)
c.op("coolant", "N34", m=13, mode="flood")
c.rapid("N35", x=35, y=150)
c.rapid("N35", z=-3)
c.lin("N35", 80, exact=True, z=-5)
c.op("dwell", "N35", seconds=2)
c.rapid("N35", z=-3)
c.rapid("N36", z=50)
c.spindle("N36", "stop", 600)
c.op("coolant", "N36", m=5, mode="off")

# L3372-3428: G83 with I K J (chip discharge), R1 = 3 ("M3" in the scan read as R3), Z-55, I20 K.8 J6.
# The manual's steps (ln 3389-3400): b. rapid to R1, c. feed to R1 + I, d. rapid back to R1 (the initial one,
# ln 3400), e. R1 = R1 + I - 1, f. I = I*K (at least J). I is taken in the drilling direction (-Z), so
# "R1 + I" is R1 - I here and "- 1" is 1 mm back up. Worked by hand, per hole:
#   peck 1: rapid Z3, feed to 3 - 20 = -17, rapid Z3;          R1 = -17 + 1 = -16,     I = 20 * .8 = 16
#   peck 2: rapid Z-16, feed to -16 - 16 = -32, rapid Z3;      R1 = -32 + 1 = -31,     I = 12.8
#   peck 3: rapid Z-31, feed to -31 - 12.8 = -43.8, rapid Z3;  R1 = -43.8 + 1 = -42.8, I = 10.24
#   peck 4: rapid Z-42.8, feed to -42.8 - 10.24 = -53.04, rapid Z3; R1 = -52.04,       I = 8.192
#   peck 5: rapid Z-52.04, -52.04 - 8.192 = -60.232 is past Z-55: feed to -55, rapid Z3 (no R2).
# (Feeding I from the last bottom instead, the old defect, gave -17, -33, -45.8, -55: 1 mm deeper a peck.)
c = Case("p5_8_7_g83_deep_drilling", """
; L3422-3428 G83 deep drilling with chip discharge (I20 K.8 J6)
N66 S930 F65 T6.6 M6
N67 G83 R3 Z-55 I20 K.8 J6 M13
N68 X-15.81 Y-22.2
N69 X23
N70 X9 Y35.8
N71 G80 Z50 M5
""", "L3422")
c.units("N66")
c.op("tool_select", "N66", tool="6")
c.op("tool_change", "N66", tool="6", offset=6)
c.spindle("N67", "cw", 930)
c.op("coolant", "N67", m=13, mode="flood")
for n, (x, y) in zip(("N68", "N69", "N70"), ((-15.81, -22.2), (23, -22.2), (9, 35.8))):
    c.rapid(n, x=x, y=y)
    if n == "N68":  # later holes are already at R1 = 3 (the last discharge): no move (DESIGN §4)
        c.rapid(n, z=3)
    c.lin(n, 65, exact=True, z=-17)
    c.rapid(n, z=3)
    c.rapid(n, z=-16)
    c.lin(n, 65, exact=True, z=-32)
    c.rapid(n, z=3)
    c.rapid(n, z=-31)
    c.lin(n, 65, exact=True, z=-43.8)
    c.rapid(n, z=3)
    c.rapid(n, z=-42.8)
    c.lin(n, 65, exact=True, z=-53.04)
    c.rapid(n, z=3)
    c.rapid(n, z=-52.04)
    c.lin(n, 65, exact=True, z=-55)
    c.rapid(n, z=3)
c.rapid("N71", z=50)
c.spindle("N71", "stop", 930)
c.op("coolant", "N71", m=5, mode="off")

# L3389-3402: a constant peck (K1, no J: "to keep I invariable ... program K=1 and omit J", ln 3402) with R2
# ("R2 only serves for the last discharge", ln 3400). R1 = 2, R2 = 10, Z-30, I10. Worked by hand:
#   peck 1: rapid Z2, feed to 2 - 10 = -8, rapid Z2;      R1 = -8 + 1 = -7
#   peck 2: rapid Z-7, feed to -7 - 10 = -17, rapid Z2;   R1 = -16
#   peck 3: rapid Z-16, feed to -16 - 10 = -26, rapid Z2; R1 = -25
#   peck 4: rapid Z-25, -25 - 10 = -35 is past Z-30: feed to -30, then the last discharge rapid to R2 = 10.
# The second hole starts from Z10 (R2): rapid to the point, rapid to R1 = 2, the same pecks.
c = Case("p5_8_7_g83_constant_peck", """
; L3389-3402 G83 chip discharge with a constant peck (K1, J omitted) and R2 for the last discharge
N1 S1000 F80 M3
N2 G83 R2 R10 Z-30 I10 K1
N3 X20 Y20
N4 X40
N5 G80 Z50 M5
""", "L3389")
c.units("N1")
c.spindle("N1", "cw", 1000)
for n, x in (("N3", 20), ("N4", 40)):
    c.rapid(n, x=x, y=20)
    c.rapid(n, z=2)
    c.lin(n, 80, exact=True, z=-8)
    c.rapid(n, z=2)
    c.rapid(n, z=-7)
    c.lin(n, 80, exact=True, z=-17)
    c.rapid(n, z=2)
    c.rapid(n, z=-16)
    c.lin(n, 80, exact=True, z=-26)
    c.rapid(n, z=2)
    c.rapid(n, z=-25)
    c.lin(n, 80, exact=True, z=-30)
    c.rapid(n, z=10)
c.rapid("N5", z=50)
c.spindle("N5", "stop", 1000)

# L3432-3476: G84 without a spindle transducer: F = S x pitch x 0.9 = 315 given; in at F, the spindle
# reverses at the bottom, out to R1 at F (RMS 100 %), the spindle turns forward again. Holes on a
# diameter 120 bolt circle.
c = Case("p5_8_7_g84_tapping", """
; L3470-3476 G84 tapping (F = 280 x 1.25 x 0.9 = 315)
N91 S280 F315 T8.8 M6 M13
N92 G84 R-7 Z-15
N93 X-51.96 Y-30
N94 X51.96
N95 X Y60
N96 G80 Z50 M5
""", "L3470")
c.units("N91")
c.op("tool_select", "N91", tool="8")
c.spindle("N91", "cw", 280)
c.op("coolant", "N91", m=13, mode="flood")
c.op("tool_change", "N91", tool="8", offset=8)
for n, (x, y) in zip(("N93", "N94", "N95"), ((-51.96, -30), (51.96, -30), (0, 60))):
    c.rapid(n, x=x, y=y)
    if c.pos["z"] != -7 or "z" not in c.used:
        c.rapid(n, z=-7)
    c.lin(n, 315, exact=True, z=-15)
    c.spindle(n, "ccw", 280)
    c.lin(n, 315, exact=True, z=-7)
    c.spindle(n, "cw", 280)
c.rapid("N96", z=50)
c.spindle("N96", "stop", 280)
c.op("coolant", "N96", m=5, mode="off")

# L3484-3508: with a spindle transducer K gives the pitch and F = K x rpm = 1 x 280.
c = Case("p5_8_7_g84_pitch", """
; L3502-3508 G84 with the pitch K: F = K x S = 280
N91 S280 T8.8 M6 M3
N92 G84 R 7 Z-15 K1
N93 X-51.96 Y-30
N96 G80 Z M5
""", "L3502")
c.units("N91")
c.op("tool_select", "N91", tool="8")
c.spindle("N91", "cw", 280)
c.op("tool_change", "N91", tool="8", offset=8)
c.rapid("N93", x=-51.96, y=-30)
c.rapid("N93", z=7)
c.lin("N93", 280, exact=True, z=-15)
c.spindle("N93", "ccw", 280)
c.lin("N93", 280, exact=True, z=7)
c.spindle("N93", "cw", 280)
c.rapid("N96", z=0)
c.spindle("N96", "stop", 280)

# L3531-3558 (Fig 5.22): "X Y R": to the point, R updated, then drilled: hole 3 at (65,85) from R-13.
c = Case("p5_8_7_update_r", """
; L3551-3558 a lower plane without G80: "Y85 R-13" moves, updates R1, drills
N36 S1000 F100 T4.4 M6
N37 G81 R3 Z-42 M3
N38 X15 Y15
N39 X65
N40 Y85 R-13
N41 X15
N42 G80 Z50 M5
""", "L3551")
c.units("N36")
c.op("tool_select", "N36", tool="4")
c.op("tool_change", "N36", tool="4", offset=4)
c.spindle("N37", "cw", 1000)
hole(c, "N38", 15, 15, 3, -42, 100)
hole(c, "N39", 65, 15, 3, -42, 100)
hole(c, "N40", 65, 85, -13, -42, 100)
hole(c, "N41", 15, 85, -13, -42, 100)
c.rapid("N42", z=50)
c.spindle("N42", "stop", 1000)

# L3560-3588: "X Y R1 R2" drills with the values in force, then takes R1 R2 and goes to the new R2 (a
# higher plane); the next "X Y R" starts from there. (The scan's N47 is damaged: the higher plane here is
# R1 -3, R2 +2.)
c = Case("p5_8_7_r1_r2", """
; L3560-3588 to a higher plane with "X Y R1 R2" (after Fig 5.23)
N43 S850 F100 T5.5 M6
N44 G81 R-18 Z-46 M13
N45 X25 Y25
N46 X60 R-18 R2
N47 Y75 R-3
N48 X95
N50 G80 Z50 M5
""", "L3560")
c.units("N43")
c.op("tool_select", "N43", tool="5")
c.op("tool_change", "N43", tool="5", offset=5)
c.spindle("N44", "cw", 850)
c.op("coolant", "N44", m=13, mode="flood")
hole(c, "N45", 25, 25, -18, -46, 100)
hole(c, "N46", 60, 25, -18, -46, 100)
c.rapid("N46", z=2)
hole(c, "N47", 60, 75, -3, -46, 100, ret=2)
hole(c, "N48", 95, 75, -3, -46, 100, ret=2)
c.rapid("N50", z=50)
c.spindle("N50", "stop", 850)
c.op("coolant", "N50", m=5, mode="off")

# L5544-5663 origins from the origin file FILEOR (NAME.lib/FILEOR): UAO per axis, UOT = absolute origin +
# shift, UIO cumulative: (20,20) -> (20,-20) -> (-25,-20) -> (-25,15).
c = Case("p5_17_origins", """
; L5544-5663 UAO, UOT, UIO with the origin file FILEOR
G X0 Y0 Z0
(UAO,1)
G X0 Y0 Z0
(UAO,2,X,Y)
(UAO,3,Z)
G X0 Y0 Z0
(UAO,0)
G X Y Z
(UOT,0,X100,Y100)
G X0 Y0
(UOT,1,X-250,Y50)
G X0 Y0
(UAO,0)
N65 (UIO,X20,Y20)
G X Y
N121 (UIO,Y-40)
G X Y
N180 (UIO,X-45)
G X Y
N230 (UIO,Y35)
G X Y
N300 (UAO,0)
G X Y
""", "L5544", **{"lib/FILEOR": "%\n0 X0 Y0 Z0\n1 X100 Y200 Z-50\n2 X300 Y400\n3 Z-100\n%\n"})
c.units(4)
c.touch("x", "y", "z")
c.rapid(4, x=100, y=200, z=-50)
c.rapid(7, x=300, y=400, z=-100)
c.rapid(9, x=0, y=0, z=0)
c.rapid(11, x=100, y=100)
c.rapid(13, x=-150, y=250)
c.rapid(16, x=20, y=20)
c.rapid(18, x=20, y=-20)
c.rapid(20, x=-25, y=-20)
c.rapid(22, x=-25, y=15)
c.rapid(24, x=0, y=0)

# L5800-5815 (Fig 5.99) RPT with MIR: pass 1 as written, pass 2 mirrored in X from the first X move: the
# CW half circle about (40,40) becomes CCW about (-40,40) on the machine.
c = Case("p5_17_mirror_repeat", """
; L5800-5815 mirror machining in a repeat (Fig 5.99)
N200 S1500 T8.8 M6 M3
N201 (RPT,2)
N202 G X90 Y20
N203 Z2
N204 G1 Z-8 F150
N205 X40 F200
N206 G2 Y60 I40 J40
N207 G1 X90
N208 G Z-100
N209 (MIR,X)
N210 (ERP)
N211 (MIR)
N212 G Z50
""", "L5800")
c.units("N200")
c.op("tool_select", "N200", tool="8")
c.spindle("N200", "cw", 1500)
c.op("tool_change", "N200", tool="8", offset=8)
for sx in (1, -1):
    c.rapid("N202", x=90 * sx, y=20)
    c.rapid("N203", z=2)
    c.lin("N204", 150, z=-8)
    c.lin("N205", 200, x=40 * sx)
    c.arc("N206", 200, (40 * sx, 40), sx > 0, 180, x=40 * sx, y=60)
    c.lin("N207", 200, x=90 * sx)
    c.rapid("N208", z=-100)
c.rapid("N212", z=50)

# L5825-5840 (Fig 5.100) drilling under (UOT,0,X30,Y22) and (URT,20): each hole (x, y) is at
# (30,22) + (x cos 20 - y sin 20, x sin 20 + y cos 20): (44.942,54.043), (64.168,45.078),
# (78.263,50.208), (87.228,69.434).
c = Case("p5_17_rotation_drilling", """
; L5825-5840 holes in a plane rotated by URT (Fig 5.100)
N100 S2000 F200 T3.3 M6
N101 (UOT,0,X30,Y22)
N102 (URT,20)
N103 G81 R3 Z-25 M3
N104 X25 Y25
N105 X40 Y10
N106 X55
N107 X70 Y25
N108 G80 Z20
N109 (UAO,0)
N110 (URT,0)
N111 G X0 Y0
""", "L5825")
c.units("N100")
c.op("tool_select", "N100", tool="3")
c.op("tool_change", "N100", tool="3", offset=3)
c.spindle("N103", "cw", 2000)
for n, (x, y) in zip(("N104", "N105", "N106", "N107"), ((25, 25), (40, 10), (55, 10), (70, 25))):
    rx, ry = rot(x, y, 20)
    hole(c, n, 30 + rx, 22 + ry, 3, -25, 200)
c.rapid("N108", z=20)
c.rapid("N111", x=0, y=0)

# L5847-5864 (Fig 5.101) eight radial slots from radius 40 to 80 at 0, 45, ... 315 degrees, two depths.
c = Case("p5_17_rotation_slots", """
; L5847-5864 URT with RPT: 8 radial slots (Fig 5.101)
N149 S1500 T5.5 M6 M3
N150 E25=0
N151 (RPT,8)
N152 (URT,E25)
N153 G X40 Y
N154 Z2
N155 G29 G1 Z-6 F150
N156 X80 F200
N157 Z-12 F150
N158 X40 F200
N159 G Z20
N160 E25=E25+45
N161 (ERP)
N162 (URT,0)
""", "L5847")
c.units("N149")
c.op("tool_select", "N149", tool="5")
c.spindle("N149", "cw", 1500)
c.op("tool_change", "N149", tool="5", offset=5)
for k in range(8):
    a = 45 * k
    x1, y1 = rot(40, 0, a)
    x2, y2 = rot(80, 0, a)
    c.rapid("N153", x=x1, y=y1)
    c.rapid("N154", z=2)
    c.lin("N155", 150, exact=True, z=-6)
    c.lin("N156", 200, exact=True, x=x2, y=y2)
    c.lin("N157", 150, exact=True, z=-12)
    c.lin("N158", 200, exact=True, x=x1, y=y1)
    c.rapid("N159", z=20)

# L5971-5997 (Fig 5.104) the subroutine S600 (NAME.lib/S600) called under three temporary origins: 12
# holes; ops of a subroutine carry the line of its CLS.
c = Case("p5_17_subroutine_s600", """
; L5971-5997 subroutine S600 called three times (Fig 5.104); R and Z given as R2 Z-10
N20 S2000 F180 T2.2 M6
N21 (UOT,0,X-20,Y-25)
N22 (CLS,S600)
N23 (UOT,0,X-15,Y50)
N24 (CLS,S600)
N25 (UOT,0,X60,Y20)
N26 (CLS,S600)
N27 Z50
""", "L5971", **{"lib/S600": "N501 G81 R2 Z-10\nN502 XY\nN503 Y-15\nN504 X30\nN505 Y\nN506 G80\n"})
c.units("N20")
c.op("tool_select", "N20", tool="2")
c.op("tool_change", "N20", tool="2", offset=2)
for n, (ox, oy) in zip(("N22", "N24", "N26"), ((-20, -25), (-15, 50), (60, 20))):
    for (x, y) in ((0, 0), (0, -15), (30, -15), (30, 0)):
        hole(c, n, ox + x, oy + y, 2, -10, 180)
c.rapid("N27", z=50)

# L6004-6047 (Fig 5.105) parametric subroutine SUB800: 6 holes on radius 30 about (50,50) from 45 degrees
# every 45: (71.213,71.213), (50,80), (28.787,71.213), (20,50), (28.787,28.787), (50,20); GE2 is G81.
c = Case("p5_17_parametric_grid", """
; L6004-6047 circular grid by the parametric subroutine SUB800 (Fig 5.105)
N44 T2.2 M6 S900 F70 M3
N45 E30=50
N46 E31=50
N47 E32=30
N48 E33=45
N49 E34=45
N50 E1=6
N51 E36=2
N52 E37=-10
N53 E2=81
N54 (CLS,SUB800)
N55 G Z20 M5
""", "L6004", **{"lib/SUB800": """N799 (DIS,"CIRCULAR GRIDS")
N800 (UOT,0,XE30,YE31)
N801 E25=E33
N802 (RPT,E1)
N803 (URT,E25)
N804 GE2 RE36 ZE37
N805 XE32 Y
N806 E25=E25+E34
N807 G80
N808 (ERP)
N809 (UAO,0)
N810 (URT,0)
"""})
c.units("N44")
c.op("tool_select", "N44", tool="2")
c.spindle("N44", "cw", 900)
c.op("tool_change", "N44", tool="2", offset=2)
c.op("message", "N54", text="CIRCULAR GRIDS")
for k in range(6):
    x, y = rot(30, 0, 45 + 45 * k)
    hole(c, "N54", 50 + x, 50 + y, 2, -10, 70)
c.rapid("N55", z=20)
c.spindle("N55", "stop", 900)

# L6051-6074, L6417-6449 (Fig 5.113): EPP re-runs labelled ranges: the centre holes D6 ... D10 and D10 ...
# END again at Z-22 and Z-24, each op with the line of the block in the range.
c = Case("p5_17_epp_holes", """
; L6417-6449 EPP in point-to-point work (Fig 5.113)
N2 F300 S200 T1.1 M3 M6
N3 G81 R0 Z-4
"D6" N4
N5 X100 Y100
N6 X-100
N7 Y-100
N8 X100
"D10" N9
N10 X40 Y40
N11 X-40
N12 Y-40
N13 X40
"END" N14
N15 G80
N17 F200 S1800 T2.2 M3 M6
N18 G81 R Z-22
N19 (EPP,D6,D10)
N20 G80
N22 F220 S1600 T3.3 M3 M6
N23 G81 R Z-24
N24 (EPP,D10,END)
N25 G80
""", "L6417")
c.units("N2")
c.op("tool_select", "N2", tool="1")
c.spindle("N2", "cw", 200)
c.op("tool_change", "N2", tool="1", offset=1)
first4 = (("N5", 100, 100), ("N6", -100, 100), ("N7", -100, -100), ("N8", 100, -100))
last4 = (("N10", 40, 40), ("N11", -40, 40), ("N12", -40, -40), ("N13", 40, -40))
for n, x, y in first4 + last4:
    hole(c, n, x, y, 0, -4, 300)
c.spindle("N17", "cw", 1800)
c.op("tool_select", "N17", tool="2")
c.op("tool_change", "N17", tool="2", offset=2)
for n, x, y in first4:
    hole(c, n, x, y, 0, -22, 200)
c.spindle("N22", "cw", 1600)
c.op("tool_select", "N22", tool="3")
c.op("tool_change", "N22", tool="3", offset=3)
for n, x, y in last4:
    hole(c, n, x, y, 0, -24, 220)

# L6120-6131: a branch loop comparing against a threshold: 0.015 + 4 x 0.0015 = 0.021.
c = Case("p5_17_branch_threshold", """
; L6123-6131 conditional branching with a threshold
E42=0.021
E41=0.015
E47=0.0015
E43=0.0001
"LAB2" E41=E41+E47
E44=ABS(E42-E41)
(BLT,E44,E43,LAB1)
(BNC,LAB2)
"LAB1" (DIS,E41)
""", "L6123")
c.units(10)
c.op("message", 10, text="E41=0.021")

# L6136-6161 (Fig 5.106) nested RPT: three grooves, each a 40x30 rectangle at two depths (G91 Z-8 from Z2:
# -6, then -14), shifted by (UIO,X80,Y20): origins (0,0), (80,20), (160,40). T6.6 has no offset data here:
# G41 with radius 0 follows the programmed path.
c = Case("p5_17_nested_repeat", """
; L6136-6161 three grooves with nested RPT and UIO (Fig 5.106)
N1 S600 T6.6 M6 M3
N2 (RPT,3)
N3 X40 Y35
N4 Z2
N5 (RPT,2)
N6 G91 Z-8
N7 G90 G1 G41 X40 Y20 F300
N8 X60
N9 Y50
N10 X20
N11 Y20
N12 G40 X40
N13 Y35 F1000
N14 (ERP)
N15 G Z2
N16 (UIO,X80,Y20)
N17 (ERP)
N18 (UAO,0)
N19 Z20
N20 XYM30
""", "L6136")
c.units("N1")
c.op("tool_select", "N1", tool="6")
c.spindle("N1", "cw", 600)
c.op("tool_change", "N1", tool="6", offset=6)
for k in range(3):
    ox, oy = 80 * k, 20 * k
    c.rapid("N3", x=ox + 40, y=oy + 35)
    if c.pos["z"] != 2:
        c.rapid("N4", z=2)
    for p in range(2):
        if p == 0:
            c.rapid("N6", z=c.pos["z"] - 8)
        else:
            c.lin("N6", 1000, z=c.pos["z"] - 8)
        c.lin("N7", 300, x=ox + 40, y=oy + 20)
        c.lin("N8", 300, x=ox + 60)
        c.lin("N9", 300, y=oy + 50)
        c.lin("N10", 300, x=ox + 20)
        c.lin("N11", 300, y=oy + 20)
        c.lin("N12", 300, x=ox + 40)
        c.lin("N13", 1000, y=oy + 35)
    c.rapid("N15", z=2)
c.rapid("N19", z=20)
c.rapid("N20", x=0, y=0)
c.op("end", "N20", m=30, shuttle=False)

# L6167-6213 (Fig 5.107) equidistant holes: row Y10 X10 ... X80 (the G91 X10 of the loop), N7 "Y40" is
# incremental: (80,50), then back to X10; 16 holes; N11 G90 XY to the origin.
c = Case("p5_17_equidistant_holes", """
; L6167-6213 equidistant holes with RPT (Fig 5.107)
N1 F200 S900 T1.1 M6
N2 G81 R5 Z-10 M3
N3 X10 Y10
N4 (RPT,7)
N5 G91 X10
N6 (ERP)
N7 Y40
N8 (RPT,7)
N9 X-10
N10 (ERP)
N11 G80 G90 XY M5
""", "L6167")
c.units("N1")
c.op("tool_select", "N1", tool="1")
c.op("tool_change", "N1", tool="1", offset=1)
c.spindle("N2", "cw", 900)
hole(c, "N3", 10, 10, 5, -10, 200)
for k in range(7):
    hole(c, "N5", 20 + 10 * k, 10, 5, -10, 200)
hole(c, "N7", 80, 50, 5, -10, 200)
for k in range(7):
    hole(c, "N9", 70 - 10 * k, 50, 5, -10, 200)
c.rapid("N11", x=0, y=0)
c.spindle("N11", "stop", 900)

# L6219-6240 (Fig 5.108) roughing with the stock allowance UOV=0.5, finishing with 0: G41 (left) on a CCW
# contour of two half circles r60 joined by a line. T6.6 has no offset data: radius = 0 + UOV. Pass 1: the
# start move ends at 90 degrees to the first arc, (60, 59.5); the arcs at radius 59.5 (inside), the line at
# Y-59.5; the exit from (100,59.5) to (60,60). Pass 2 the programmed path.
c = Case("p5_17_stock_allowance", """
; L6219-6240 roughing with UOV=0.5 and finishing (Fig 5.108)
N1 S350 T6.6 M6
N2 X60 Y M3
N3 Z-50
N4 UOV=0.5
N5 (RPT,2)
N6 G1 G41 X60 Y60 F500
N7 G3 Y-60 I60 J
N8 G1 X100
N9 G3 Y60 I100 J
N10 G1 G40 X60
N11 G Y
N12 UOV=0
N13 (ERP)
N14 Z M5
N15 X Y M30
""", "L6219")
c.units("N1")
c.op("tool_select", "N1", tool="6")
c.op("tool_change", "N1", tool="6", offset=6)
c.spindle("N2", "cw", 350)
c.rapid("N2", x=60, y=0)
c.rapid("N3", z=-50)
for rr in (0.5, 0.0):
    c.lin("N6", 500, x=60, y=60 - rr)
    c.arc("N7", 500, (60, 0), False, 180, x=60, y=-60 + rr)
    c.lin("N8", 500, x=100, y=-60 + rr)
    c.arc("N9", 500, (100, 0), False, 180, x=100, y=60 - rr)
    c.lin("N10", 500, x=60, y=60)
    c.rapid("N11", y=0)
c.rapid("N14", z=0)
c.spindle("N14", "stop", 350)
c.rapid("N15", x=0, y=0)
c.op("end", "N15", m=30, shuttle=False)

# L6244-6281 (Fig 5.109) milling-boring SUB500: E35 = 62.5 - 25 = 37.5; in to (25,37.5), a CCW quarter
# r25 about (0,37.5) to (0,62.5) at F160, the full circle r62.5 (I J without axes), the exit quarter to
# (-25,37.5), back to the centre; under (UOT,0,X65,Y48). Cutter radius 0 (no offset data).
c = Case("p5_17_milling_boring", """
; L6244-6281 milling-boring with a full circle (Fig 5.109)
N129 S330 T12.12 M6
N130 (UOT,0,X65,Y48)
N131 G X Y M3
N132 E30=62.5
N133 E31=25
N134 E25=160
N135 (CLS,SUB500)
N136 (UAO,0)
N137 G Z
""", "L6244", **{"lib/SUB500": """N500 E35=E30-E31
N501 G1 G41 X E31 YE35 F2000
N502 G3 X YE30 I JE35 FE25
N503 I J
N504 E31=NEG(E31)
N505 G40 XE31 YE35 I JE35
N506 G1 X Y F2000
"""})
c.units("N129")
c.op("tool_select", "N129", tool="12")
c.op("tool_change", "N129", tool="12", offset=12)
c.spindle("N131", "cw", 330)
c.rapid("N131", x=65, y=48)
c.lin("N135", 2000, x=65 + 25, y=48 + 37.5)
c.arc("N135", 160, (65, 48 + 37.5), False, 90, x=65, y=48 + 62.5)
c.arc("N135", 160, (65, 48), False, 360, x=65, y=48 + 62.5)
c.arc("N135", 160, (65, 48 + 37.5), False, 90, x=65 - 25, y=48 + 37.5)
c.lin("N135", 2000, x=65, y=48)

# L6285-6333 (Fig 5.110) linear grid SUB600 ("(RPT,E3" in the scan closed): 9 holes from (12,12) every 20
# along 30 degrees: (12 + 17.3205 k, 12 + 10 k); centre-drilled to Z-3, then drilled to Z-20.
c = Case("p5_17_linear_grid", """
; L6285-6333 linear grid by the parametric subroutine SUB600 (Fig 5.110)
N30 S1000 F60 T4.4 M6 M3
N31 E25=30
N32 E30=12
N33 E31=12
N34 E32=20
N35 E1=9
N36 E34=2
N37 E35=-3
N38 E2=81
N39 (CLS,SUB600)
N40 (DIS,"TWIST DRILL D=9")
N41 S880 F100 T5.5 M6 M3
N42 E35=-20
N43 (CLS,SUB600)
""", "L6285", **{"lib/SUB600": """N600 (UOT,0,XE30,YE31)
N601 (URT,E25)
N602 E3=E1-1
N603 GE2 RE34 ZE35
N604 XY
N605 (RPT,E3)
N606 G91 XE32
N607 (ERP)
N608 G90
N609 G80
N610 (UAO,0)
N611 (URT,0)
"""})
c.units("N30")
c.op("tool_select", "N30", tool="4")
c.spindle("N30", "cw", 1000)
c.op("tool_change", "N30", tool="4", offset=4)
for k in range(9):
    x, y = rot(20 * k, 0, 30)
    hole(c, "N39", 12 + x, 12 + y, 2, -3, 60)
c.op("message", "N40", text="TWIST DRILL D=9")
c.spindle("N41", "cw", 880)
c.op("tool_select", "N41", tool="5")
c.op("tool_change", "N41", tool="5", offset=5)
for k in range(9):
    x, y = rot(20 * k, 0, 30)
    hole(c, "N43", 12 + x, 12 + y, 2, -20, 100)

# L6498-6526 (Fig 5.115) a slot by depth: passes at -3.5 ... -21 while E31 > E32 = -24, then E31 = -25
# through EPP: 7 passes. G42 with cutter radius 0 (no offset data).
c = Case("p5_17_slot_by_depth", """
; L6498-6526 conditional branching and EPP: a slot in depth steps (Fig 5.115)
N2 F500 S2000 T1.1 M6 M3
N3 E31=-3.5
N4 E32=-24
"START" N5
N6 G X Y-10
N7 Z E31
N8 G1 G42 X Y-20
N9 X-30
N10 Y20
N11 X30
N12 Y-20
N13 G40 X
N14 Y-10
"END" N15
N16 E31=E31-3.5
N17 (BGT,E31,E32,START)
N18 E31=-25
N19 (EPP,START,END)
N20 G Z10
N21 X Y
""", "L6498")
c.units("N2")
c.op("tool_select", "N2", tool="1")
c.spindle("N2", "cw", 2000)
c.op("tool_change", "N2", tool="1", offset=1)
for depth in (-3.5, -7, -10.5, -14, -17.5, -21, -25):
    if c.pos["y"] != -10 or "y" not in c.used:
        c.rapid("N6", x=0, y=-10)
    c.rapid("N7", z=depth)
    c.lin("N8", 500, x=0, y=-20)
    c.lin("N9", 500, x=-30)
    c.lin("N10", 500, y=20)
    c.lin("N11", 500, x=30)
    c.lin("N12", 500, y=-20)
    c.lin("N13", 500, x=0)
    c.lin("N14", 500, y=-10)
c.rapid("N20", z=10)
c.rapid("N21", x=0, y=0)

# L6528-6567 (Fig 5.116) a thread by a branch loop: passes at U = 56.8 + 0.5 k while U <= 60 (seven), the
# finishing pass at U60; each G33 Z5 -> Z-45 with pitch 3, U (diameter axis) back to 50 between. ("Y5.5" in
# N2 is the scan's T5.5.)
c = Case("p5_17_thread_loop", """
; L6528-6567 a cylindrical thread in passes by a branch loop (Fig 5.116)
N1 (DIS,"THREAD DIA 60")
N2 S150 T5.5 M6
N3 G X66 Y98 Z5 M3
N4 E30=56.8
N5 E31=0.5
N6 E32=50
N7 E33=60
"I" N8
N9 G Z5
N10 UE30
N11 G33 Z-45 K3
N12 GUE32
N13 E30=E30+E31
N14 (BGT,E30,E33,F)
N15 (BNC,I)
"F" N16
N17 GUE32
N18 Z5
N19 UE33
N20 G33 Z-45 K3
N21 GUE32
N22 Z20
""", "L6528")
c.units("N1")
c.op("message", "N1", text="THREAD DIA 60")
c.op("tool_select", "N2", tool="5")
c.op("tool_change", "N2", tool="5", offset=5)
c.spindle("N3", "cw", 150)
c.rapid("N3", x=66, y=98, z=5)
u = 56.8
while u <= 60 + 1e-9:
    if c.pos["z"] != 5:
        c.rapid("N9", z=5)
    c.rapid("N10", u=round(u, 6))
    c.thread("N11", 3, z=-45)
    c.rapid("N12", u=50)
    u += 0.5
c.rapid("N18", z=5)
c.rapid("N19", u=60)
c.thread("N20", 3, z=-45)
c.rapid("N21", u=50)
c.rapid("N22", z=20)

# K14 (ln 4195-4205): "@ SYVARn.mCH" runs the ISO text held in a SYVAR string as a block; the manual's two
# examples, the second with no count (`@ SYVAR12.CH` runs the 8 characters stored there, judgement call 40).
# N4 is G1 X30 Z20 F100 from X50 Y20 Z10 C90 (G27: exact stop); N5 is G0 X0 C0 Z0; N7 runs "X5Y5" in the
# modal G0 of N5.
c = Case("p5_14_syvar_iso_blocks", """
; ln 4195-4205 @ SYVARn.mCH runs the ISO blocks held in SYVAR (the manual's examples)
N1 G X50 Y20 C90
N2 Z10
N3 SYVAR0.12CH="G1X30Z20F100"
N4 SYVAR12.8CH="G0X0C0Z0"
N5 @ SYVAR0.12CH
N6 @ SYVAR12.CH
N7 SYVAR20.4CH="X5Y5"
N8 @ SYVAR20.4CH
""", "L4195")
c.units("N1")
c.rapid("N1", travel={"c": 90.0}, x=50, y=20, c=90)  # C from 0 to 90: travel +90
c.rapid("N2", z=10)
c.lin("N5", 100, x=30, z=20)
c.rapid("N6", travel={"c": -90.0}, x=0, c=0, z=0)  # C back by 90
c.rapid("N8", x=5, y=5)

# Table 4.3 (ln 2159-2177) and DTL (ln 6606-6630): the values the cell runs with are accepted and read back
# (judgement calls 38, 41-43): ERF=.05 (G27 still stops at every block end: no form error), MCD=1 (90
# degrees), UVR=0 (programmed feed), URL=0, RAP=0, UEP=1, DTL 0 = the configured tolerance. E30=ERF*100 = 5,
# E31=MCD = 1, E0=UVR+URL+RAP+UEP = 1; N11 feeds to X10 at F100 with exact stop.
c = Case("p5_14_panel_switches", """
; ln 2159-2177 ERF MCD UVR URL RAP UEP, ln 6606-6630 DTL with the configured tolerance
N1 ERF=.05
N2 MCD=1
N3 UVR=0
N4 URL=0
N5 RAP=0
N6 UEP=1
N7 (DTL,X0,Y0)
N8 E30=ERF*100
N9 E31=MCD
N10 E0=UVR+URL+RAP+UEP
N11 (DIS,E30)
N12 (DIS,E31)
N13 (DIS,E0)
N14 G1 X10 F100
""", "L2159")
c.units("N11")
c.op("message", "N11", text="E30=5")
c.op("message", "N12", text="E31=1")
c.op("message", "N13", text="E0=1")
c.lin("N14", 100, x=10)

# Table 5.3 machine-logic M codes (ln 2569-2586) and H functions (ln 420-422, 2502) go to the machine logic as
# `aux` / `output` ops, in the block's order: M10 (lock the axes not involved) and M41 (gear range 1) at the
# start of the motion, M40 (cancel the gear range) at its end; H5 before the motion.
c = Case("p5_07_machine_logic", """
; ln 2569-2586 M10 M11 M40 M41, ln 420-422 H functions
N1 G1 X10 F100 M10 M41 H5
N2 Y10 M11 M40
""", "L2569")
c.units("N1")
c.op("aux", "N1", m=10)
c.op("aux", "N1", m=41)
c.op("output", "N1", spec="H05")
c.lin("N1", 100, x=10)
c.op("aux", "N2", m=11)
c.lin("N2", 100, y=10)
c.op("aux", "N2", m=40)

# Globals and functions not shown elsewhere (ln 4245-4315, 2157-2158, 6712-6732, 6084-6131, 5460-5462, 5510):
# TIM1=5 and TOT2=1.5 (RE) display as set; RTA=.5 RTO=-.25 mm; (DLY,2) is a 2 s dwell; E30=LOG(1000) = 3,
# E31=MOD(17,5) = 2; l1 through X0 Y0 at 30 degrees: FEL(1,1) = sin 30 = 0.5; the branches: 3 <> 2 (BNE taken,
# skips N13), 2 >= 2 (BGE taken, skips N15), 2 <= 3 (BLE taken, skips N17); E1=1 then GE1 X5 is G01 X5 at
# F100. A DIS list is shown as one text, its items side by side (ln 6700-6710, `(DIS,"RTA=",E40,...)`).
c = Case("p5_14_timers_functions", """
; ln 4245-4315 TIM TOT, ln 2157 RTA RTO, ln 6712 DLY, ln 5460-5462 LOG MOD FEL, ln 6084-6131 BNE BGE BLE, ln 5510 GE1
N1 TIM1=5
N2 TOT2=1.5
N3 RTA=.5
N4 RTO=-.25
N5 (DIS,TIM1,TOT2,RTA,RTO)
N6 #(DLY,2)
N7 E30=LOG(1000)
N8 E31=MOD(17,5)
N9 l1=X0Y0,a30
N10 E32=FEL(1,1)
N11 (DIS,E30,E31,E32)
N12 (BNE,E30,E31,A)
N13 (DIS,"NOT HERE")
"A" N14 (BGE,E31,2,B)
N15 (DIS,"NOT HERE")
"B" N16 (BLE,E31,E30,C)
N17 (DIS,"NOT HERE")
"C" N18 E1=1
N19 GE1 X5 F100
""", "L4245")
c.units("N5")
c.op("message", "N5", text="TIM1=5TOT2=1.5RTA=0.5RTO=-0.25")
c.op("dwell", "N6", seconds=2)
c.op("message", "N11", text="E30=3E31=2E32=0.5")
c.lin("N19", 100, x=5)
