"""GTL geometric programming (manual §5.15, ln 4363-5406): element definitions and profiles, with the
manual's four GTL examples. The geometry is worked out here with the textbook formulas: a circle runs with a
line it touches when its centre is its (signed) radius to the line's left; two circles that touch running the
same way have centres |R - r| apart; a radius between two elements is the circle of that radius touching both,
running from the first to the second the shorter way round."""
import math

from corpus import Case, rot


def unit(v):
    n = math.hypot(*v)
    return (v[0] / n, v[1] / n)


def left(d):
    return (-d[1], d[0])


def add(a, b, k=1.0):
    return (a[0] + k * b[0], a[1] + k * b[1])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1]


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def L(p, ang=None, q=None):
    """A line through p at `ang` degrees, or through p and q."""
    d = unit(sub(q, p)) if q is not None else (math.cos(math.radians(ang)), math.sin(math.radians(ang)))
    return ("l", p, d)


def C(c, rr):
    return ("c", c, rr)


def meet_lines(a, b):
    _, p, d = a
    _, q, e = b
    t = cross(sub(q, p), e) / cross(d, e)
    return add(p, d, t)


def line_circle(l, c):
    """The points of line l on circle c in the line's direction (none when they do not meet)."""
    _, p, d = l
    _, cc, rr = c
    rr = abs(rr)
    t0 = dot(sub(cc, p), d)
    foot = add(p, d, t0)
    h = math.hypot(*sub(cc, foot))
    if h > rr + 1e-6:
        return []
    s = math.sqrt(max(0.0, rr * rr - h * h))
    return [add(foot, d, -s), add(foot, d, s)]


def circle_circle(a, b):
    """Left, then right of the line from a's centre to b's."""
    c1, r1, c2, r2 = a[1], abs(a[2]), b[1], abs(b[2])
    d = math.hypot(*sub(c2, c1))
    if d > r1 + r2 + 1e-6 or d < abs(r1 - r2) - 1e-6:
        return []
    u = unit(sub(c2, c1))
    x = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    h = math.sqrt(max(0.0, r1 * r1 - x * x))
    base = add(c1, u, x)
    return [add(base, left(u), h), add(base, left(u), -h)]


def tangent_at(e, pt):
    if e[0] == "l":
        return e[2]
    v = unit(sub(pt, e[1]))
    return (-v[1], v[0]) if e[2] > 0 else (v[1], -v[0])


def touch(circ, e):
    """Where circle circ touches element e (a point: the point)."""
    if e[0] == "p":
        return e[1]
    if e[0] == "l":
        _, p, d = e
        t = dot(sub(circ[1], p), d)
        return add(p, d, t)
    k = e[2] / (e[2] - circ[2])
    return add(e[1], sub(circ[1], e[1]), k)


def ccw_angle(c, a, b, cw):
    a0 = math.atan2(a[1] - c[1], a[0] - c[0])
    a1 = math.atan2(b[1] - c[1], b[0] - c[0])
    s = math.degrees(a1 - a0) % 360
    return (360 - s) % 360 if cw else s


def fillet(a, b, rr):
    """The circle of signed radius rr touching a then b, the shorter way round."""
    def locus(e):
        if e[0] == "l":
            return ("l", add(e[1], left(e[2]), rr), e[2])
        if e[0] == "p":
            return ("c", e[1], abs(rr))
        return ("c", e[1], abs(e[2] - rr))
    la, lb = locus(a), locus(b)
    if la[0] == "l" and lb[0] == "l":
        cands = [meet_lines(la, lb)]
    elif la[0] == "l":
        cands = line_circle(la, lb)
    elif lb[0] == "l":
        cands = line_circle(lb, la)
    else:
        cands = circle_circle(la, lb)
    best = min(cands, key=lambda cc: ccw_angle(cc, touch(C(cc, rr), a), touch(C(cc, rr), b), rr < 0))
    return C(best, rr)


def tangent_line(circ, ang):
    """l = c, a..: touching the circle where it runs at angle `ang` (its centre r to the line's left)."""
    d = (math.cos(math.radians(ang)), math.sin(math.radians(ang)))
    return ("l", add(circ[1], left(d), -circ[2]), d)


def crossings(a, b):
    if a[0] == "l" and b[0] == "l":
        return [meet_lines(a, b)]
    if a[0] == "l":
        return line_circle(a, b)
    if b[0] == "l":
        return line_circle(b, a)
    return circle_circle(a, b)


def radius_between(a, b, rr):
    """ln 5192-5203, with the judgement call for a sign that contradicts every crossing's turn (GTL Example 3
    N23): the radius turns with the corner."""
    turns = [cross(tangent_at(a, p), tangent_at(b, p)) for p in crossings(a, b)]
    turns = [t for t in turns if abs(t) > 1e-9]
    if turns and all((t > 0) != (rr > 0) for t in turns):
        rr = -rr
    return fillet(a, b, rr)


class Profile:
    """Writes a profile's moves into a case (programmed path; offset by `comp` to the right for G42)."""

    def __init__(self, case, f, comp=0.0, side=-1, angle=0.0):
        self.c, self.f, self.comp, self.side, self.angle = case, f, comp, side, angle

    def m(self, p):
        return rot(p[0], p[1], self.angle)

    def off(self, e, p):
        """The compensated point for element e at p (the cutter at 90 degrees, `side` -1 right)."""
        t = tangent_at(e, p)
        n = (-self.side * t[1], self.side * t[0])
        return add(p, n, self.comp)

    def line(self, ln, e, a, b):
        q = self.m(self.off(e, b))
        self.c.lin(ln, self.f, x=q[0], y=q[1])

    def arc(self, ln, e, a, b):
        cw = e[2] < 0
        q = self.m(self.off(e, b))
        cc = self.m(e[1])
        ang = ccw_angle(e[1], a, b, cw)
        self.c.arc(ln, self.f, cc, cw, 360 if ang == 0 else ang, x=q[0], y=q[1])

    def seg(self, ln, e, a, b):
        (self.line if e[0] == "l" else self.arc)(ln, e, a, b)


# ln 4440-4448, 4612-4625, 4959: stored elements, read back through FEP / FEC into positions. p1 = o1 X15
# Y15 with o1 = X30 Y30 a45: (30, 30 + 15 sqrt 2); P5 = o1 X20 Y10 with o1 = X30 Y29 a-20: (52.214, 31.557);
# p2 = m55 a60: (27.5, 47.631); c2 = m70 a30 r15: centre (60.622, 35); c1 = l1, l2, r15 (centre 15 to the
# left of both lines) and p3 = l3, c1, the first point on l3 (the manual's l3 misses this c1: its figure
# gives no numbers; l3 here is the line Y70).
o1 = ((30, 30), 45)
p1 = add(o1[0], rot(15, 15, o1[1]))
q2 = (60, 30)
l1 = L(p1, q=q2)
l2 = L((30, 50), 45)
c1 = fillet(l1, l2, 15)
l3 = L((0, 70), q=(100, 70))
p3 = line_circle(l3, c1)[0]
p5 = add((30, 29), rot(20, 10, -20))
c = Case("gtl_definitions", """
; ln 4440-4448, 4612-4625, 4959 GTL elements stored and read back with FEP / FEC
o1 = X30 Y30 a45
p1 = o1 X15 Y15
p2 = X60 Y30
l1 = p1, p2
l2 = X30 Y50, a45
c1 = l1, l2, r15
l3 = X0 Y70, X100 Y70
p3 = l3, c1
c2 = p3, r8
E30=FEP(1,1)
E31=FEP(1,2)
G XE30 YE31
E30=FEC(1,1)
E31=FEC(1,2)
G XE30 YE31
E30=FEP(3,1)
E31=FEP(3,2)
G XE30 YE31
o1 = X30 Y29 a-20
p5 = o1 X20 Y10
p6 = m55 a60
c7 = m70 a30 r15
E30=FEP(5,1)
E31=FEP(5,2)
G XE30 YE31
E30=FEP(6,1)
E31=FEP(6,2)
G XE30 YE31
E30=FEC(7,1)
E31=FEC(7,2)
E32=FEC(7,3)
G XE30 YE31 ZE32
""", "L4440")
c.units(13)
c.rapid(13, x=p1[0], y=p1[1])
c.rapid(16, x=c1[1][0], y=c1[1][1])
c.rapid(19, x=p3[0], y=p3[1])
c.rapid(26, x=p5[0], y=p5[1])
c.rapid(29, x=27.5, y=55 * math.sin(math.radians(60)))
c.rapid(33, x=70 * math.cos(math.radians(30)), y=35, z=15)

# ln 5078-5092 (Fig 5.84) an open profile along y = 25 with two bumps: from p1 on l1, a radius 3 onto c1
# (CW r14 about (30,25)), c1 to its second crossing with c2 (s2: right of the centre line), c2 (CCW r15 about
# (45,25)) to its second crossing with l1 along l1 (s2), l1 to p2. No cutter radius (no offset data).
l1 = L((0, 25), 0)
c1 = C((30, 25), -14)
c2 = C((45, 25), 15)
f1 = radius_between(l1, c1, 3)
t1, t2 = touch(f1, l1), touch(f1, c1)
x12 = circle_circle(c1, c2)[1]
x2l = line_circle(l1, c2)[1]
c = Case("gtl_open_profile", """
; ln 5078-5092 (Fig 5.84) an open GTL profile with s2 selections and an automatic radius
l1 = X Y25,a
p1 = X-20 Y25
p2 = X90 Y25
c1 = I30 J25 r-14
c2 = I45 J25 r15
F200 T1.1 M6
G X-30 Y25
G21 G42 p1
l1
r3
c1 s2
c2 s2
l1
G20 G40 p2
G X-30
""", "L5078")
c.units(7)
c.op("tool_select", 7, tool="1")
c.op("tool_change", 7, tool="1", offset=1)
c.rapid(8, x=-30, y=25)
c.lin(9, 200, x=-20, y=25)
pr = Profile(c, 200)
pr.seg(10, l1, (-20, 25), t1)
pr.seg(11, f1, t1, t2)
pr.seg(12, c1, t2, x12)
pr.seg(13, c2, x12, x2l)
pr.seg(14, l1, x2l, (90, 25))
c.rapid(16, x=-30)

# ln 5243-5267 (Fig 5.91) GTL Example 1: a closed profile (l2 last, l3 first), radii 3, 3, 5, 5, "c2 s2";
# no cutter radius (no offset data), so the programmed profile.
e1l1 = L((70, 40), 150)
e1l2 = L((8, 8), -95)
e1p1 = meet_lines(e1l1, e1l2)
e1l3 = L((8, 8), q=(70, 15))
e1l4 = L((50, 0), 90)
e1c1 = C((70, 40), -25)
e1c2 = C(e1p1, -20)
start = meet_lines(e1l2, e1l3)
fa = radius_between(e1l3, e1l4, 3)
fb = radius_between(e1l4, e1c1, 3)
fc = radius_between(e1c1, e1l1, 5)
fd = radius_between(e1l1, e1c2, 5)
x_c2_l2 = line_circle(e1l2, e1c2)[1]
c = Case("gtl_example_1", """
; ln 5243-5267 (Fig 5.91) GTL Example 1
N1 (DIS,"EXAMPLE 1")
N2 l1=X70Y40,a150
N3 l2=X8Y8,a-95
N4 p1=l1,l2
N5 l3=X8Y8,X70Y15
N6 l4=X50Y,a90
N7 c1=I70J40 r-25
N8 c2=p1,r-20
N9 F250 S800 T1.1 M6M3M7
N10 GXY
N11 Z-10
N12 G21G42l2
N13 l3
N14 r3
N15 l4
N16 r3
N17 c1
N18 r5
N19 l1
N20 r5
N21 c2 s2
N22 l2
N23 G20 G40 l3
N24 GZ2
N25 XY M30
""", "L5243")
c.units("N1")
c.op("message", "N1", text="EXAMPLE 1")
c.op("tool_select", "N9", tool="1")
c.spindle("N9", "cw", 800)
c.op("coolant", "N9", m=7, mode="mist")
c.op("tool_change", "N9", tool="1", offset=1)
c.touch("x", "y")
c.rapid("N11", z=-10)
c.lin("N12", 250, x=start[0], y=start[1])
pr = Profile(c, 250)
chain = [("N13", e1l3, start, touch(fa, e1l3)), ("N14", fa, touch(fa, e1l3), touch(fa, e1l4)),
         ("N15", e1l4, touch(fa, e1l4), touch(fb, e1l4)), ("N16", fb, touch(fb, e1l4), touch(fb, e1c1)),
         ("N17", e1c1, touch(fb, e1c1), touch(fc, e1c1)), ("N18", fc, touch(fc, e1c1), touch(fc, e1l1)),
         ("N19", e1l1, touch(fc, e1l1), touch(fd, e1l1)), ("N20", fd, touch(fd, e1l1), touch(fd, e1c2)),
         ("N21", e1c2, touch(fd, e1c2), x_c2_l2), ("N22", e1l2, x_c2_l2, start)]
for ln, e, a, b in chain:
    pr.seg(ln, e, a, b)
c.rapid("N24", z=2)
c.rapid("N25", x=0, y=0)
c.op("end", "N25", m=30, shuttle=False)

# ln 5373-5404 (Fig 5.94) GTL Example 4: an open profile cut 8 times rotated by 45 degrees, first with the
# stock allowance UOV=2 (the cutter path 2 to the right: arcs of c1 at 52, the radii 3 at 5 and -3 at 1, the
# lines 2 away), then again through EPP with UOV=0. Every element meets the next through a radius, so the
# offset elements join tangentially; the start and the end points are offset at 90 degrees.
g4c1 = C((0, 0), 50)
g4c2 = C((0, 0), 10)
g4l1 = ("l", add((0, 0), left((-1, 0)), -10), (-1.0, 0.0))  # l1 = c2, a180: centre 10 to its left
g4l3 = L((0, 0), 45)
g4l2 = ("l", add((0, 0), left(unit((1, 1))), -10), unit((1, 1)))  # l2 = c2, a45
g4p1 = (50, 0)
g4p2 = line_circle(g4l3, g4c1)[1]
ra = radius_between(g4c1, g4l1, 3)
rb = radius_between(g4l1, g4l2, -3)
rc = radius_between(g4l2, g4c1, 3)
g4chain = [("N17", g4c1, g4p1, touch(ra, g4c1)), ("N18", ra, touch(ra, g4c1), touch(ra, g4l1)),
           ("N19", g4l1, touch(ra, g4l1), touch(rb, g4l1)), ("N20", rb, touch(rb, g4l1), touch(rb, g4l2)),
           ("N21", g4l2, touch(rb, g4l2), touch(rc, g4l2)), ("N22", rc, touch(rc, g4l2), touch(rc, g4c1)),
           ("N23", g4c1, touch(rc, g4c1), g4p2)]
c = Case("gtl_example_4", """
; ln 5373-5404 (Fig 5.94) GTL Example 4: a profile rotated 8 times, roughed with UOV=2, finished by EPP
N2 F100 S100 T2.2 M6
N3 UOV=2
N4 p1=X50 Y0
N5 c1=I0 J0 r50
N6 c2=I0 J0 r10
N7 l1=c2,a180
N8 l3=X0 Y0,a45
N9 l2=c2,a45
N10 p2=l3,c1,s2
N11 GX60 Y0
N12 Z-20
"START" N13 E25=0
N14 (RPT,8)
N15 (URT,E25)
N16 G21 G42 p1
N17 c1
N18 r3
N19 l1
N20 r-3
N21 l2
N22 r3
N23 c1
N24 G20 G40 p2
N25 E25=E25+45
N26 (ERP)
N27 (URT,0)
"END" N28
N29 UOV=0
N30 (EPP,START,END)
N31 GZ20
N32 XY M30
""", "L5373")
c.units("N2")
c.op("tool_select", "N2", tool="2")
c.op("tool_change", "N2", tool="2", offset=2)
c.rapid("N11", x=60, y=0)
c.rapid("N12", z=-20)
for stock in (2.0, 0.0):
    for k in range(8):
        pr = Profile(c, 100, comp=stock, side=-1, angle=45 * k)
        s = pr.m(pr.off(g4c1, g4p1))
        if math.hypot(s[0] - c.pos["x"], s[1] - c.pos["y"]) > 1e-6:
            c.lin("N16", 100, x=s[0], y=s[1])
        for ln, e, a, b in g4chain:
            if e is g4c1 or e[0] == "c":
                # an arc offset to the right: CCW arcs grow, CW arcs shrink
                cc = pr.m(e[1])
                cw = e[2] < 0
                q = pr.m(pr.off(e, b))
                ang = ccw_angle(e[1], a, b, cw)
                c.arc(ln, 100, cc, cw, ang, x=q[0], y=q[1])
            else:
                pr.line(ln, e, a, b)
c.rapid("N31", z=20)
c.rapid("N32", x=0, y=0)
c.op("end", "N32", m=30, shuttle=False)


# ln 5276-5313 (Fig 5.92) GTL Example 2 (scan fixes: G21G42l7, l6 = X0Y0,X-10Y-20, l7 = X-50Y0,a90,
# G20G40l1): a closed profile re-using l1, l2 and l4; "c2 s2" and "c3 s2" leave the circles at their second
# crossings along the lines; no cutter radius.
e2 = {
    "l1": L((-50, 10), q=(30, 50)), "l2": L((30, 50), q=(70, 10)), "l3": L((70, 0), -90),
    "l4": L((0, -20), 180), "l5": L((10, -20), q=(0, 0)), "l6": L((0, 0), q=(-10, -20)),
    "l7": L((-50, 0), 90), "c1": C((-10, 40), 18), "c2": C((50, 30), -14), "c3": C((40, -20), 10),
}
start = meet_lines(e2["l7"], e2["l1"])
f1 = radius_between(e2["l1"], e2["c1"], -8)
f2 = radius_between(e2["c1"], e2["l1"], -8)
f3 = radius_between(e2["l3"], e2["l4"], -10)
f4 = radius_between(e2["l4"], e2["l5"], -8)
f5 = radius_between(e2["l6"], e2["l4"], -8)
f6 = radius_between(e2["l4"], e2["l7"], -10)
x12 = meet_lines(e2["l1"], e2["l2"])
lc2 = line_circle(e2["l2"], e2["c2"])
x23 = meet_lines(e2["l2"], e2["l3"])
lc3 = line_circle(e2["l4"], e2["c3"])
x56 = meet_lines(e2["l5"], e2["l6"])
c = Case("gtl_example_2", """
; ln 5276-5313 (Fig 5.92) GTL Example 2
N2 l1=X-50Y10,X30Y50
N3 l2=X30Y50,X70Y10
N4 l3=X70Y0,a-90
N5 l4=X0Y-20,a180
N6 l5=X10Y-20,X0Y0
N7 l6=X0Y0,X-10Y-20
N8 l7=X-50Y0,a90
N9 c1=I-10J40r18
N10 c2=I50J30r-14
N11 c3=I40J-20r10
N12 S100 M3 T3.3 M6 F300
N13 G0X-30Y0
N14 Z-10
N15 G21G42l7
N16 l1
N17 r-8
N18 c1
N19 r-8
N20 l1
N21 l2
N22 c2s2
N23 l2
N24 l3
N25 r-10
N26 l4
N27 c3s2
N28 l4
N29 r-8
N30 l5
N31 l6
N32 r-8
N33 l4
N34 r-10
N35 l7
N36 G20G40l1
N37 G0Z0
""", "L5276")
c.units("N12")
c.op("tool_select", "N12", tool="3")
c.spindle("N12", "cw", 100)
c.op("tool_change", "N12", tool="3", offset=3)
c.rapid("N13", x=-30, y=0)
c.rapid("N14", z=-10)
c.lin("N15", 300, x=start[0], y=start[1])
pr = Profile(c, 300)
g = e2
chain = [("N16", g["l1"], start, touch(f1, g["l1"])), ("N17", f1, touch(f1, g["l1"]), touch(f1, g["c1"])),
         ("N18", g["c1"], touch(f1, g["c1"]), touch(f2, g["c1"])), ("N19", f2, touch(f2, g["c1"]), touch(f2, g["l1"])),
         ("N20", g["l1"], touch(f2, g["l1"]), x12), ("N21", g["l2"], x12, lc2[0]), ("N22", g["c2"], lc2[0], lc2[1]),
         ("N23", g["l2"], lc2[1], x23), ("N24", g["l3"], x23, touch(f3, g["l3"])),
         ("N25", f3, touch(f3, g["l3"]), touch(f3, g["l4"])), ("N26", g["l4"], touch(f3, g["l4"]), lc3[0]),
         ("N27", g["c3"], lc3[0], lc3[1]), ("N28", g["l4"], lc3[1], touch(f4, g["l4"])),
         ("N29", f4, touch(f4, g["l4"]), touch(f4, g["l5"])), ("N30", g["l5"], touch(f4, g["l5"]), x56),
         ("N31", g["l6"], x56, touch(f5, g["l6"])), ("N32", f5, touch(f5, g["l6"]), touch(f5, g["l4"])),
         ("N33", g["l4"], touch(f5, g["l4"]), touch(f6, g["l4"])), ("N34", f6, touch(f6, g["l4"]), touch(f6, g["l7"])),
         ("N35", g["l7"], touch(f6, g["l7"]), start)]
for ln, e, a, b in chain:
    pr.seg(ln, e, a, b)
c.rapid("N37", z=0)

# ln 5322-5362 (Fig 5.93) GTL Example 3: origin o1, tangent lines l3 l4 of c6 (they touch it: the profile
# passes from l3 onto c6 and off to l4 at the tangency points), p2 the left crossing of c3 and c4, c2 the
# radius 40 through p3 touching c1; the radius 40 joins l7 and c1, which do not meet; N23 "r5" at a right
# turn is taken as r-5 (a judgement call); no cutter radius.
o1 = ((20, 21), 45)
c6 = C(add(o1[0], rot(-38, -35, 45)), 10)
e3 = {
    "l1": L((0, -60), 180), "l2": L((50, 0), 90), "c6": c6, "l3": tangent_line(c6, 135), "l4": tangent_line(c6, -45),
    "l5": L((0, -50), 180), "l6": L((-50, -65), 60), "l7": L((-25, 0), 90), "c3": C((-65, 0), 55),
    "c4": C((0, 80), 55), "c5": C((55, 80), 13), "l8": L((70, 0), -90),
}
p2 = circle_circle(e3["c3"], e3["c4"])[0]
e3["c1"] = C(p2, -15)
e3["c2"] = fillet(e3["c1"], ("p", (40, 80)), 40)
start = meet_lines(e3["l8"], e3["l1"])
g = e3
fa = radius_between(g["l1"], g["l2"], 5)
fb = radius_between(g["l2"], g["l3"], 12)
fc = radius_between(g["l7"], g["c1"], 40)
fd = radius_between(g["c2"], g["c5"], -5)
fe = radius_between(g["c5"], g["l8"], -5)
t3 = touch(g["c6"], g["l3"])
t4 = touch(g["c6"], g["l4"])
x45 = meet_lines(g["l4"], g["l5"])
x56 = meet_lines(g["l5"], g["l6"])
x67 = meet_lines(g["l6"], g["l7"])
x12c = circle_circle(g["c1"], g["c2"])[0]
c = Case("gtl_example_3", """
; ln 5322-5362 (Fig 5.93) GTL Example 3
N2 S100 F200 T1.1 M6
N3 o1 = X20 Y21 a45
N4 l1 = X0 Y-60a180
N5 l2 = X50 Y0,a90
N6 c6 = o1 I-38 J-35 r10
N7 l3 = c6,a135
N8 l4 = c6,a-45
N9 l5 = X0 Y-50,a180
N10 l6 = X-50 Y-65,a60
N11 l7 = X-25 Y0,a90
N12 c3 = I-65 J0 r55
N13 c4 = I0 J80 r55
N14 p2 = c3,c4
N15 c1 = p2,r-15
N16 p3 = X40 Y80
N17 c2 = c1,p3,r40
N18 c5 = I55 J80 r13
N19 l8 = X70 Y0,a-90
N20 G21 G42 l8
N21 Z-10
N22 l1
N23 r5
N24 l2
N25 r12
N26 l3
N27 c6
N28 l4
N29 l5
N30 l6
N31 l7
N32 r40
N33 c1
N34 c2
N35 r-5
N36 c5
N37 r-5
N38 l8
N39 G20 G40 l1
N40 G Z
N41 X0 Y0 M30
""", "L5322")
c.units("N2")
c.op("tool_select", "N2", tool="1")
c.op("tool_change", "N2", tool="1", offset=1)
c.lin("N20", 200, x=start[0], y=start[1])
c.lin("N21", 200, z=-10)
pr = Profile(c, 200)
chain = [("N22", g["l1"], start, touch(fa, g["l1"])), ("N23", fa, touch(fa, g["l1"]), touch(fa, g["l2"])),
         ("N24", g["l2"], touch(fa, g["l2"]), touch(fb, g["l2"])), ("N25", fb, touch(fb, g["l2"]), touch(fb, g["l3"])),
         ("N26", g["l3"], touch(fb, g["l3"]), t3), ("N27", g["c6"], t3, t4), ("N28", g["l4"], t4, x45),
         ("N29", g["l5"], x45, x56), ("N30", g["l6"], x56, x67), ("N31", g["l7"], x67, touch(fc, g["l7"])),
         ("N32", fc, touch(fc, g["l7"]), touch(fc, g["c1"])), ("N33", g["c1"], touch(fc, g["c1"]), x12c),
         ("N34", g["c2"], x12c, touch(fd, g["c2"])), ("N35", fd, touch(fd, g["c2"]), touch(fd, g["c5"])),
         ("N36", g["c5"], touch(fd, g["c5"]), touch(fe, g["c5"])), ("N37", fe, touch(fe, g["c5"]), touch(fe, g["l8"])),
         ("N38", g["l8"], touch(fe, g["l8"]), start)]
for ln, e, a, b in chain:
    pr.seg(ln, e, a, b)
c.rapid("N40", z=0)
c.rapid("N41", x=0, y=0)
c.op("end", "N41", m=30, shuttle=False)
