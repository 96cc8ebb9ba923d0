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
    """The points of line l on circle c in the line's direction."""
    _, p, d = l
    _, cc, rr = c
    t0 = dot(sub(cc, p), d)
    foot = add(p, d, t0)
    h = math.hypot(*sub(cc, foot))
    s = math.sqrt(max(0.0, rr * rr - h * h))
    return [add(foot, d, -s), add(foot, d, s)]


def circle_circle(a, b):
    """Left, then right of the line from a's centre to b's."""
    c1, r1, c2, r2 = a[1], abs(a[2]), b[1], abs(b[2])
    d = math.hypot(*sub(c2, c1))
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
    """Where circle circ touches element e."""
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
