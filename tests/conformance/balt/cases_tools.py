"""Tools and offsets, units, cutter radius compensation with a cutter, probing: manual ln 2472-2488,
§5.8.5, §5.8.6, §5.17.5-5.17.7, §5.20, §6.4-6.6."""
import math

from corpus import Case, sweep

# ln 2472-2488: Ttool.offset, the offset active from M06: its length on the axis its record names, added to
# that axis's coordinates (offset 1: Z100; offset 2: X50; offset 10: Z-20 -- "T1.10" is offset 10, not 1);
# "TM6" (no offset number) deactivates the offset.
c = Case("tools_length_offsets", """
; ln 2472-2488 T tool.offset with M06: length along the axis of the record (FI1COR in .tools)
T1.1 M6
G X0 Y0 Z0
T2.2 M6
G X0 Y0 Z0
T1.10 M6
G X0 Y0 Z10
TM6
G X0 Y0 Z10
""", "L2472", tools="%\n1 Z100 K10\n2 X50 K0\n10 Z-20 K5\n%\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.rapid(3, x=0, y=0, z=100)
c.op("tool_select", 4, tool="2")
c.op("tool_change", 4, tool="2", offset=2)
c.rapid(5, x=50, y=0, z=0)
c.op("tool_select", 6, tool="1")
c.op("tool_change", 6, tool="1", offset=10)
c.rapid(7, x=0, y=0, z=-10)
c.op("tool_change", 8, tool="0")
c.rapid(9, z=10)

# §6.6 (ln 8436-8521) tool life: tool 13 is broken (status A) so its alternative 14 with offset 14 goes in;
# TOF declares tool 14 (now on the spindle, status E) out of use. The file is NAME.lib/GE1TOL.
c = Case("tools_life_alternative", """
; ln 8436-8493 tool life management: an alternative for a broken tool; TOF (ln 6740-6762)
T13.13 M6
G X0 Y0 Z0
(TOF,13)
""", "L8436", tools="13 Z100 K10\n14 Z150 K10\n",
    **{"lib/GE1TOL": "VTU,13,T14,[TOOL COMP]14,t60,t2,t0,A\nVTU,14,T14,[TOOL COMP]14,t60,t2,t60,B\n"})
c.units(2)
c.op("tool_select", 2, tool="13")
c.op("tool_change", 2, tool="14", offset=14)
c.rapid(3, x=0, y=0, z=150)
c.op("file_op", 4, what="TOF", args="14")

# ln 6820-6872 RQU: increments added to the offset (in effect from the next M06); 7412 RQU after G74.
c = Case("tools_requalification", """
; ln 6820-6872 RQU / RQP: the offset requalified, active from the next M06
T7.7 M6
G Z0
E41=0.5
(RQU,7,7,Z-0.2,KE41)
G Z10
T7.7 M6
G Z10
""", "L6820", tools="7 Z100 K20\n")
c.units(2)
c.op("tool_select", 2, tool="7")
c.op("tool_change", 2, tool="7", offset=7)
c.rapid(3, z=100)
c.op("tool_data", 5, tool="7", length=99.8, diameter=20.5)
c.rapid(6, z=110)
c.op("tool_select", 7, tool="7")
c.op("tool_change", 7, tool="7", offset=7)
c.rapid(8, z=109.8)

# ln 3266-3281 G70 inch / G71 mm: positions always in mm; the units op when the mode changes.
c = Case("units_inch", """
; ln 3266-3281 G70 inch programming, G71 back to mm
G70
G1 X1 Y2 F10
G71 X10
""", "L3266")
c.units(3, mm=False)
c.lin(3, 254, x=25.4, y=50.8)
c.units(4, mm=True)
c.lin(4, 254, x=10)

# Fig 5.8 (ln 3095-3109): G42, the first element a line, cutter radius 5 (K10). From (-80,15) the start move
# ends at 90 degrees to the line (-50,15)->(-20,45): right of (0.7071,0.7071) is (0.7071,-0.7071):
# (-46.4645, 11.4645); the line's offset end (-16.4645, 41.4645); the G40 exit to (0,45).
k = 5 / math.sqrt(2)
c = Case("cc_first_line_g42", """
; ln 3095-3109 (Fig 5.8) G42 with a linear first element; cutter radius 5
T1.1 M6
G X-80 Y15
G1 G42 X-50 Y15 F200
X-20 Y45
G40 X0 Y45
""", "L3095", tools="1 Z0 K10\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.rapid(3, x=-80, y=15)
c.lin(4, 200, x=-50 + k, y=15 - k)
c.lin(5, 200, x=-20 + k, y=45 - k)
c.lin(6, 200, x=0, y=45)

# Fig 5.9, 5.11 (ln 3111-3155): G42 with an arc as the first element: CW about (0,25) radius 35; right of a
# CW arc is its inside: radius 30. Start move to (0,25) + 30 (-31.622,15)/35; the arc to
# (0,25) + 30 (33.541,10)/35; exit to (50,35).
s = (-31.622, 40 - 25)
e = (33.541, 35 - 25)
rs, re = math.hypot(*s), math.hypot(*e)
c = Case("cc_first_arc_g42", """
; ln 3111-3155 (Fig 5.9) G42 with an arc as the first element; cutter radius 5
T1.1 M6
G X-60 Y40
G1 G42 X-31.622 Y40 F200
G2 X33.541 Y35 I J25
G1 G40 X50 Y35
""", "L3111", tools="1 Z0 K10\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.rapid(3, x=-60, y=40)
p0 = (30 * s[0] / rs, 25 + 30 * s[1] / rs)
p1 = (30 * e[0] / re, 25 + 30 * e[1] / re)
c.lin(4, 200, x=p0[0], y=p0[1])
a0, a1 = math.atan2(s[1], s[0]), math.atan2(e[1], e[0])
c.arc(5, 200, (0, 25), True, math.degrees(a0 - a1), x=p1[0], y=p1[1])
c.lin(6, 200, x=50, y=35)


def offset_line(p, q, rr):
    """The line p->q moved rr to its right: a point and the direction."""
    d = (q[0] - p[0], q[1] - p[1])
    n = math.hypot(*d)
    d = (d[0] / n, d[1] / n)
    right = (d[1], -d[0])
    return (p[0] + rr * right[0], p[1] + rr * right[1]), d


def meet(l1, l2):
    (p, d), (q, e) = l1, l2
    den = d[0] * e[1] - d[1] * e[0]
    t = ((q[0] - p[0]) * e[1] - (q[1] - p[1]) * e[0]) / den
    return (p[0] + t * d[0], p[1] + t * d[1])


# Fig 5.13 (ln 3249-3260) a slot with G42, cutter radius 6 (K12): the contour B (50,18) -> 1 (15,10) ->
# 2 (7,45) -> 3 (77,61) -> 4 (85,26) runs clockwise, so the cutter (on the right) is inside and every
# corner turns toward it: the offset lines meet at their intersections. The start move ends at 90 degrees
# to B->1; the last element ends at 90 degrees at 4; the G40 move goes to B.
pts = [(50, 18), (15, 10), (7, 45), (77, 61), (85, 26)]
lines = [offset_line(pts[i], pts[i + 1], 6) for i in range(4)]
c = Case("cc_slot_g42", """
; ln 3249-3260 (Fig 5.13) a slot with G42, cutter radius 6
N84 (DIS, "END MILL MD D=12")
N85 S1100 F170 T9.9 M6
N86 G X50 Y32 M3
N87 Z-305
N88 G1 G42 X50 Y18 F170
N89 X15 Y10
N90 X7 Y45
N91 X77 Y61
N92 X85 Y26
N93 G40 X50 Y18
N94 G X50 Y32
N95 Z M5
""", "L3249", tools="9 Z0 K12\n")
c.units("N84")
c.op("message", "N84", text="END MILL MD D=12")
c.op("tool_select", "N85", tool="9")
c.op("tool_change", "N85", tool="9", offset=9)
c.spindle("N86", "cw", 1100)
c.rapid("N86", x=50, y=32)
c.rapid("N87", z=-305)
c.lin("N88", 170, x=lines[0][0][0], y=lines[0][0][1])
for n, i in zip(("N89", "N90", "N91"), range(3)):
    x, y = meet(lines[i], lines[i + 1])
    c.lin(n, 170, x=x, y=y)
end4 = (pts[4][0] + 6 * lines[3][1][1], pts[4][1] - 6 * lines[3][1][0])
c.lin("N92", 170, x=end4[0], y=end4[1])
c.lin("N93", 170, x=50, y=18)
c.rapid("N94", x=50, y=32)
c.rapid("N95", z=0)
c.spindle("N95", "stop", 1100)

# ln 3082 "the exact intersection point" at outside corners where an arc meets (balt.md judgement call 50):
# the line-line rule applied to the arcs' tangents at the corner. G41, cutter radius 5 (K10): a CCW arc
# about (0,0) of radius 13 from (5,-12) to (13,0) (the cutter inside it: offset radius 8), the line
# (13,0)->(40,0) (a right turn of 90 degrees, away from the cutter), a CCW arc about (53,0) of radius 13
# from (40,0) to (48,-12) (again a right turn of 90 degrees; the cutter inside). At the first corner the
# arc's tangent (0,1) at (13,0) and the line, both offset 5 to the left, meet at X1; the arc ends at its
# offset end and the tool goes straight to X1. At the second the line's offset meets the arc's tangent (0,-1)
# at (40,0) offset 5 to the left at X2: the line runs on to X2, the tool goes straight to the arc's offset
# start. (The offset elements themselves would meet on the offset circles, at (6.245,5) and (46.755,5).)
c1, c2 = (0, 0), (53, 0)
a1s, a1e, a2s, a2e = (5, -12), (13, 0), (40, 0), (48, -12)
t1 = (-(a1e[1] - c1[1]), a1e[0] - c1[0])  # CCW tangent at the first arc's end: (0,13)
t2 = (-(a2s[1] - c2[1]), a2s[0] - c2[0])  # CCW tangent at the second arc's start: (0,-13)
x1 = meet(offset_line((a1e[0] - t1[0], a1e[1] - t1[1]), a1e, -5), offset_line(a1e, (40, 0), -5))
x2 = meet(offset_line(a1e, (40, 0), -5), offset_line(a2s, (a2s[0] + t2[0], a2s[1] + t2[1]), -5))


def on_offset_circle(c, p, rr):
    """The point of p's radius about c at radius rr."""
    d = math.hypot(p[0] - c[0], p[1] - c[1])
    return (c[0] + rr * (p[0] - c[0]) / d, c[1] + rr * (p[1] - c[1]) / d)


c = Case("cc_outside_arc_corners_g41", """
; ln 3082 outside corners where arcs meet (balt.md judgement call 50); cutter radius 5
T1.1 M6
G X5 Y-30
G1 G41 X5 Y-12 F200
G3 X13 Y0 I0 J0
G1 X40 Y0
G3 X48 Y-12 I53 J0
G1 G40 X60 Y-20
""", "L3082", tools="1 Z0 K10\n")
c.units(2)
c.op("tool_select", 2, tool="1")
c.op("tool_change", 2, tool="1", offset=1)
c.rapid(3, x=5, y=-30)
s1, e1 = on_offset_circle(c1, a1s, 8), on_offset_circle(c1, a1e, 8)
c.lin(4, 200, x=s1[0], y=s1[1])  # the start move ends at 90 degrees to the arc (ln 3088)
c.arc(5, 200, c1, False, sweep(a1s, a1e, c1, False), x=e1[0], y=e1[1])
c.lin(5, 200, x=x1[0], y=x1[1])  # the first corner, straight along the arc's tangent offset
c.lin(6, 200, x=x2[0], y=x2[1])  # the line's offset from X1 on to X2
s2, e2 = on_offset_circle(c2, a2s, 8), on_offset_circle(c2, a2e, 8)
c.lin(6, 200, x=s2[0], y=s2[1])  # the second corner, straight along the arc's tangent offset
c.arc(7, 200, c2, False, sweep(a2s, a2e, c2, False), x=e2[0], y=e2[1])
c.lin(8, 200, x=60, y=-20)  # the G40 move from the arc's offset end (ln 3130)

# ln 3172-3185 the automatic radius between two lines, here without compensation: (0,0)->(100,100), r-1,
# ->(-100,100). The radius rounds the corner on the side it turns (left; the sign is not used for lines
# that meet, a judgement call): centre 1 left of both, (100 - 1 - sqrt 2, 99); it touches the first line at
# (98.2929, 98.2929) and the second at (97.5858, 100); 135 degrees CCW.
cx, cy = 99 - math.sqrt(2), 99
t1 = ((cx + cy) / 2, (cx + cy) / 2)
c = Case("corner_radius_iso", """
; ln 3160-3188 automatic radius r between two lines
N20 G1 X100 Y100 F100
N21 r-1
N22 X-100
""", "L3172")
c.units("N20")
c.lin("N20", 100, x=t1[0], y=t1[1])
c.arc("N21", 100, (cx, cy), False, 135, x=cx, y=100)
c.lin("N22", 100, x=-100, y=100)

# ln 3190-3200 a bevel b5: 5 back from the corner (150,50) along (100,50)/111.803, 5 along the next line.
d = math.hypot(100, 50)
c = Case("corner_bevel_iso", """
; ln 3190-3200 a bevel b between two lines
N10 G1 X50 Y F100
N11 X150 Y50
N12 b5
N13 X100 Y50
""", "L3190")
c.units("N10")
c.lin("N10", 100, x=50, y=0)
c.lin("N11", 100, x=150 - 5 * 100 / d, y=50 - 5 * 50 / d)
c.lin("N12", 100, x=145, y=50)
c.lin("N13", 100, x=100, y=50)

# §5.20 probing (ln 6983-7412). G72 Z-80 with the probe T30.30 (ball diameter K6, radius 3; length 0)
# against a part whose top is at Z-80.2 (NAME.probe): rapid to Qa (10) above the nominal point, probe
# down at Vm 1000 toward Qs (12) below it; the ball touches at Z-80.2, its centre at -77.2; the value
# stored is the touching point, -80.2; back to the start. 80.2 > 80.1: the branch to C2 (ln 7314-7355).
c = Case("probe_g72_depth", """
; ln 7314-7355 checking a plane depth -80 +-0.1 with G72
"C1" N252
N267 T30.30 M6
(DPT,10,12,1000)
N268 GX150 Y35
N269 G72 Z-80 E30
N270 E31=ABS(E30)
N271 (BGT,E31,80.1,C2)
N272 (BLT,E31,79.9,C3)
N273 (DIS,"WORKPIECE IN TOLERANCE")
N2100 M30
"C2" N2101 (DIS,E30)
N2102 M00
N2103 M30
"C3" N2104 (DIS,E30)
""", "L7314", tools="30 Z0 K6\n", probe="box -500 -500 -300 500 500 -80.2\n")
c.units("N267")
c.op("tool_select", "N267", tool="30")
c.op("tool_change", "N267", tool="30", offset=30)
c.rapid("N268", x=150, y=35)
c.rapid("N269", z=-70)
c.probe("N269", 72, 1000, "contact", z=-77.2)
c.rapid("N269", z=0)
c.op("message", '"C2"', text="E30=-80.2")
c.op("stop", "N2102", m=0, optional=False)
c.op("end", "N2103", m=30, shuttle=False)

# ln 7201-7215 G73 from the centre of a hole of nominal radius 50 (a square hole of side 100 centred at
# (180.3, 59.8) in NAME.probe; ball radius 3): four points at +-X, +-Y, each from Qa (10) inside the
# nominal radius to Qs (5) beyond it; the centre (180.3, 59.8) and radius 50 go to E35 E36 E37; RQO moves
# origin 0 by the deviation (0.3, -0.2), which the next move shows.
hx, hy = 180.3, 59.8
c = Case("probe_g73_hole_origin", """
; ln 7201-7215 origin requalified from a hole measured with G73
N201 T11.11 M6
(DPT,10,5,500)
N202 GX180 Y60
N203 Z-130
N204 G73 r50 E35
N205 E35=E35-180
N206 E36=E36-60
N207 (RQO,0,XE35,YE36)
G Z0
G X0 Y0
""", "L7201", tools="11 Z0 K6\n",
    probe="box -1000 -1000 -500 130.3 1000 500\nbox 230.3 -1000 -500 1000 1000 500\n"
          "box -1000 -1000 -500 1000 9.8 500\nbox -1000 109.8 -500 1000 1000 500\n")
c.units("N201")
c.op("tool_select", "N201", tool="11")
c.op("tool_change", "N201", tool="11", offset=11)
c.rapid("N202", x=180, y=60)
c.rapid("N203", z=-130)
for dx, dy, wall in ((1, 0, hx + 50), (-1, 0, hx - 50), (0, 1, hy + 50), (0, -1, hy - 50)):
    c.rapid("N204", x=180 + 40 * dx, y=60 + 40 * dy)
    if dx:
        c.probe("N204", 73, 500, "contact", x=wall - 3 * dx, y=60)
    else:
        c.probe("N204", 73, 500, "contact", x=180, y=wall - 3 * dy)
    c.rapid("N204", x=180, y=60)
c.rapid(10, z=0)
c.rapid(11, x=0.3, y=-0.2)

# ln 7357-7395 G74 with a fixed probe (NAME.probe: its top at Z-49.8): the tool (offset 10: length 0)
# touches 0.2 above the nominal -50: E30 = +0.2, requalifying offset 10's length (RQU).
c = Case("probe_g74_tool_length", """
; ln 7383-7395 tool length requalified with a fixed probe (G74, RQU)
T10.10 M6
(DPT,10,5,500)
N170 G X100 Y100
N180 G74 Z-50 E30
N190 (RQU,10,10,ZE30)
(DIS,E30)
""", "L7383", tools="10 Z0 K8\n", probe="box 90 90 -100 110 110 -49.8\n")
c.units(2)
c.op("tool_select", 2, tool="10")
c.op("tool_change", 2, tool="10", offset=10)
c.rapid("N170", x=100, y=100)
c.rapid("N180", z=-40)
c.probe("N180", 74, 500, "contact", z=-49.8)
c.rapid("N180", z=0)
c.op("tool_data", "N190", tool="10", length=0.2, diameter=8)
c.op("message", 7, text="E30=0.2")

# ln 7495-7516 part presence with ERR=1: no part (no probe model), no contact within Qs 15: IOSTA = 1 and
# the program branches to END.
c = Case("probe_err_iosta", """
; ln 7495-7516 workpiece presence: ERR=1, IOSTA after a measurement without contact
N100 T30.30 M6
N110 (DPT,30,15,500)
N120 G Z50
N130 X80 Y100
N140 ERR=1
N150 G72 Z0 E30
N160 (BEQ,IOSTA,1,END)
N170 ERR=0
N180 M30
"END" N1002 (DIS,"WORKPIECE NOT FOUND")
N1003 M00
""", "L7495", tools="30 Z0 K6\n")
c.units("N100")
c.op("tool_select", "N100", tool="30")
c.op("tool_change", "N100", tool="30", offset=30)
c.rapid("N120", z=50)
c.rapid("N130", x=80, y=100)
c.rapid("N150", z=30)
c.probe("N150", 72, 500, "none", z=-15)
c.rapid("N150", z=50)
c.op("message", '"END"', text="WORKPIECE NOT FOUND")
c.op("stop", "N1003", m=0, optional=False)

# §6.7 (ln 8523-8559) random tool management: FI1RAN (the manual's records, ln 8541-8548, in NAME.lib/FI1RAN)
# puts tool 1 in pocket 1, tool 2 in pocket 2, the special tool 3 in pockets 3-5 and tool 4 in pocket 6; the
# tool change names the pocket of its record. T0 M6 (no tool) puts the special tool away before tool 4 (FILMS4
# 90 otherwise, neg_random_mixed_tool_change). Lengths from FI1COR: offset 2 Z120, offset 4 Z140.
random_file = "0001-----\n0002-----\n9003-----\n9003-----\n9003-----\n0004-----\n"
c = Case("tools_random_pockets", """
; ln 8523-8559 random tool file FI1RAN: the pocket of each tool, a special tool on 3 pockets
T2.2 M6
G X0 Y0 Z0
T3.3 M6
T0 M6
T4.4 M6
G Z0
""", "L8523", tools="2 Z120 K10\n3 Z130 K30\n4 Z140 K10\n", **{"lib/FI1RAN": random_file})
c.units(2)
c.op("tool_select", 2, tool="2")
c.op("tool_change", 2, tool="2", offset=2, socket=2)
c.rapid(3, x=0, y=0, z=120)
c.op("tool_select", 4, tool="3")
c.op("tool_change", 4, tool="3", offset=3, socket=3)
c.op("tool_change", 5, tool="0")
c.op("tool_select", 6, tool="4")
c.op("tool_change", 6, tool="4", offset=4, socket=6)
c.rapid(7, z=140)

