#!/usr/bin/env python3
"""Writes the Balt-System conformance corpus: each case's program (NAME.balt, the manual's example with its
lines cited), the canonical commands expected from it (NAME.expected) and, for the negative corpus, the
diagnostic (NAME.diag). The expected values are worked out in cases_*.py from the manual's stated geometry
with plain arithmetic, independently of the interpreter; the comments say where each number comes from.
Run it after changing a case: python3 tests/conformance/balt/derive.py"""
import cases_flow  # noqa: F401  (each module adds its cases)
import cases_gtl  # noqa: F401
import cases_motion  # noqa: F401
import cases_negative  # noqa: F401
import cases_tools  # noqa: F401
from corpus import CASES

if __name__ == "__main__":
    names = set()
    for c in CASES:
        assert c.name not in names, c.name
        names.add(c.name)
        c.write()
    print(f"{len(CASES)} cases written")
