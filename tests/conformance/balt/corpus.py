"""The Balt-System corpus framework: a case is the program (NAME.balt), the canonical commands expected from it
(NAME.expected) and, for the negative corpus, its diagnostic (NAME.diag); derive.py writes them all."""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
AXES = "xyzabcuvw"
CASES = []


def r(v):
    return round(v, 6)


class Case:
    def __init__(self, name, program, cite, **files):
        self.name, self.cite = name, cite
        self.program = program.strip("\n") + "\n"
        self.files = files  # suffix -> text (".tools", ".params", ".probe", ".args", "lib/NAME")
        self.ops, self.used, self.diag = [], set(), None
        self.pos = {a: 0.0 for a in AXES}
        # Feed moves stop at their end unless the case is in G28: G27 (the power-up mode, ln 2979) decelerates
        # to 0 at each block end with ERF=0 (ln 4317), G29 always (ln 2971). A G28 case sets this False.
        self.exact_default = True
        CASES.append(self)

    def line_of(self, text):
        """1-based line of the first program line starting with `text`."""
        for i, l in enumerate(self.program.split("\n")):
            if l.startswith(text):
                return i + 1
        raise KeyError(f"{self.name}: no line starts with {text!r}")

    def op(self, op, line, **kw):
        d = {"op": op, "line": line if isinstance(line, int) else self.line_of(line)}
        d.update(kw)
        self.ops.append(d)

    def units(self, line, mm=True):
        self.op("units", line, length="mm" if mm else "inch", x_mode="radius")

    def touch(self, *axes):
        self.used.update(axes)

    def _target(self, d, ax, travel):
        for a, v in ax.items():
            self.pos[a] = v
            self.used.add(a)
        for a in AXES:
            if a in self.used:
                d[a] = r(self.pos[a] % 360 if a in "abc" else self.pos[a])
        for a, v in (travel or {}).items():
            d[a + "_travel"] = v

    def rapid(self, line, travel=None, **ax):
        d = {"op": "rapid", "line": line if isinstance(line, int) else self.line_of(line)}
        self._target(d, ax, travel)
        self.ops.append(d)

    def lin(self, line, f, exact=None, mode=None, travel=None, **ax):
        d = {"op": "linear", "line": line if isinstance(line, int) else self.line_of(line)}
        self._target(d, ax, travel)
        d["f"] = f
        if mode:
            d["f_mode"] = mode
        if self.exact_default if exact is None else exact:
            d["exact_stop"] = True
        self.ops.append(d)

    def arc(self, line, f, center, cw, angle, plane="xy", exact=None, **ax):
        d = {"op": "arc", "line": line if isinstance(line, int) else self.line_of(line)}
        z = self.pos["z"]
        self._target(d, ax, None)
        d["f"] = f
        if self.exact_default if exact is None else exact:
            d["exact_stop"] = True
        c = list(center) + [z] * (3 - len(center))
        d["center"] = [r(v) for v in c]
        d["dir"] = "cw" if cw else "ccw"
        d["plane"] = plane
        d["angle"] = r(angle)
        self.ops.append(d)

    def thread(self, line, lead, start=0.0, change=0.0, **ax):
        d = {"op": "thread", "line": line if isinstance(line, int) else self.line_of(line)}
        self._target(d, ax, None)
        d["lead"] = lead
        if change:
            d["lead_change"] = change
        d["start_angle"] = start
        self.ops.append(d)

    def probe(self, line, g, f, result, **ax):
        d = {"op": "probe", "line": line if isinstance(line, int) else self.line_of(line), "g": g}
        self._target(d, ax, None)
        d["f"] = f
        d["result"] = result
        self.ops.append(d)

    def spindle(self, line, d, s, **kw):
        self.op("spindle", line, dir=d, s=s, **kw)

    def error(self, line, col, code, text):
        self.diag = f"{self.name}.balt:{line}:{col}: error: [FILMS4 {code:02d}] {text}"

    def write(self):
        base = os.path.join(HERE, self.name)
        with open(base + ".balt", "w") as f:
            f.write(self.program)
        with open(base + ".expected", "w") as f:
            for o in self.ops:
                f.write(json.dumps(o, separators=(",", ":")) + "\n")
        if self.diag:
            with open(base + ".diag", "w") as f:
                f.write(self.diag + "\n")
        for suffix, text in self.files.items():
            path = base + "." + suffix if not suffix.startswith("lib/") else base + ".lib/" + suffix[4:]
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w") as f:
                f.write(text)


def sweep(start, end, c, cw):
    a0 = math.atan2(start[1] - c[1], start[0] - c[0])
    a1 = math.atan2(end[1] - c[1], end[0] - c[0])
    ccw = math.degrees(a1 - a0) % 360
    if abs(end[0] - start[0]) < 1e-9 and abs(end[1] - start[1]) < 1e-9:
        return 360.0
    return (360 - ccw) % 360 if cw else ccw


def rot(x, y, deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return x * c - y * s, x * s + y * c


